"""The machine a benchmark ran on: cores, CPU model, memory, and the versions that matter.

Versions are read from the installed package metadata, so torch is not imported here.
"""

from __future__ import annotations

import importlib.metadata
import os
import platform
import resource
import sys
from pathlib import Path

from decoy_cli.bench.records import MachineInfo

PACKAGES = ("decoy", "numpy", "torch", "pybullet", "numba", "scipy", "pandas", "msgspec")


def cpu_model(cpuinfo: Path = Path("/proc/cpuinfo")) -> str:
    """The CPU's model name from /proc/cpuinfo, else what `platform` knows."""
    try:
        for line in cpuinfo.read_text(errors="replace").splitlines():
            key, _, value = line.partition(":")
            if key.strip() == "model name" and value.strip():
                return value.strip()
    except OSError:
        pass
    return platform.processor() or platform.machine() or "unknown"


def memory_gb(meminfo: Path = Path("/proc/meminfo")) -> float | None:
    """Total memory in GB (10^9 bytes) from /proc/meminfo; None where there is none."""
    try:
        for line in meminfo.read_text().splitlines():
            if line.startswith("MemTotal:"):
                return int(line.split()[1]) * 1024 / 1e9
    except (OSError, ValueError, IndexError):
        pass
    return None


def package_version(name: str) -> str | None:
    """The installed version of a distribution, None when it is not installed."""
    try:
        return importlib.metadata.version(name)
    except importlib.metadata.PackageNotFoundError:
        return None


def usable_cores() -> int:
    """Cores this process may run on (the affinity mask where the platform has one)."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


def ru_maxrss_mb() -> float:
    """getrusage's ru_maxrss in MB (KiB on Linux, bytes on macOS). On Linux a process started
    by fork + exec (a spawned worker) inherits its parent's RSS at the fork into this value."""
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak / 1e6 if sys.platform == "darwin" else peak * 1024 / 1e6


def peak_rss_mb(status: Path = Path("/proc/self/status")) -> float:
    """This process's own peak resident memory in MB: VmHWM (the high-water mark of this
    program image, reset by exec) where /proc has it, else `ru_maxrss_mb()`."""
    try:
        for line in status.read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) * 1024 / 1e6
    except (OSError, ValueError, IndexError):
        pass
    return ru_maxrss_mb()


def load_average() -> list[float] | None:
    """The 1, 5 and 15 minute load averages: other work on a shared machine slows a benchmark."""
    try:
        return [round(value, 2) for value in os.getloadavg()]
    except (AttributeError, OSError):
        return None


def machine_line() -> str:
    """The machine in one line, for a report: cores, CPU, Python and decoy versions."""
    return (
        f"{usable_cores()} cores ({cpu_model()}), Python {platform.python_version()}, "
        f"decoy {package_version('decoy')}"
    )


def machine_info() -> MachineInfo:
    """Cores, CPU, memory, load, OS and the versions of Python and the packages that matter."""
    return {
        "cores": os.cpu_count(),
        "usable_cores": usable_cores(),
        "cpu": cpu_model(),
        "memory_gb": memory_gb(),
        "load_average": load_average(),
        "os": platform.platform(),
        "python": platform.python_version(),
        "packages": {name: package_version(name) for name in PACKAGES},
    }
