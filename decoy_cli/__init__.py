"""decoy: replay real CS:GO rounds on waypoint graphs of eight maps and measure replay fidelity."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("decoy")
except PackageNotFoundError:  # running from a source tree that was never installed
    __version__ = "0.0.0+unknown"
