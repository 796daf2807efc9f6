"""`decoy bench`: how fast the simulator, the replay, the metrics and the reader run.

* simspeed.py: the DECOY paper's Table 1 (physics ticks per second by agent count);
* combat.py: the cost of one combat step (line of sight, batch, damage model, damage);
* metrics.py: fidelity-metric throughput on synthetic player-rounds;
* data.py: reader and replay throughput on match files (real data, or the synthetic sample);
* awpy.py: the awpy readers on a full-rate match;
* portable.py: the sections measured by one file on any version's code (the kinematic core,
  the environment, the combat step at any agent count, the metrics and their kernels);
* machine.py: the machine and versions, and peak memory;
* runner.py: the sections, their sizes, one spawned process each, and the JSON report;
* baseline.py: the sections on this code and on a baseline, alternating, as ratios.

Some scripts in benchmarks/ (profiles and studies) reuse these functions. Nothing here prints.
"""

from decoy_cli.bench.data import BenchData, find_data
from decoy_cli.bench.machine import machine_info, peak_rss_mb
from decoy_cli.bench.runner import (
    SECTIONS,
    BenchConfig,
    ModelStatus,
    check_damage_model,
    failed_sections,
    report,
    run_isolated,
    run_section,
)

__all__ = [
    "SECTIONS",
    "BenchConfig",
    "BenchData",
    "ModelStatus",
    "check_damage_model",
    "failed_sections",
    "find_data",
    "machine_info",
    "peak_rss_mb",
    "report",
    "run_isolated",
    "run_section",
]
