"""Time of the view page's round trace (`round_trace`) of the 8-frames/s CS2 round after its
replay: python benchmarks/bench/view_trace_time.py. A one-off figure of this machine; compare two
code trees by running it with each on PYTHONPATH, one after the other.
"""

from __future__ import annotations

import time
from pathlib import Path

from decoy_cli.esta import read_match
from decoy_cli.replay.replayer import ReplayOptions, replay_round
from decoy_cli.replay.view_trace import round_trace
from decoy_cli.waypoints.build import builtin_graph

ROUND = (
    Path(__file__).resolve().parents[3]
    / "shared/data/cs2_dust2_both/spirit-vs-falcons-m2-dust2-8hz-r02.json.xz"
)
REPEATS = 5


def main() -> None:
    round_ = read_match(ROUND).rounds[0]
    result = replay_round(round_, builtin_graph(), ReplayOptions(combat=False, bomb=False))
    round_trace(round_, result)  # compiles or loads the compiled kernels
    started = time.perf_counter()
    for _ in range(REPEATS):
        round_trace(round_, result)
    print(f"round_trace: {(time.perf_counter() - started) / REPEATS:.4f} s per call")


if __name__ == "__main__":
    main()
