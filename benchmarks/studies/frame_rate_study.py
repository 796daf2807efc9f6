"""What the frame rate read from awpy's ticks trades: fidelity of the replayed paths against
the real ones, and the cost of a replay, at `--rate` 8, 4, 2 and 1 frames a second.

    python benchmarks/studies/frame_rate_study.py [ZIP_OR_FOLDER]

Fidelity: the real 8 Hz round (../shared/data/cs2_dust2_awpy/awpy2/...-8hz-r02.zip by default)
is read at each rate and replayed (movement only, the kinematic mover: the paths alone); the
replay is recorded at every real 8 Hz frame and compared with the real positions there, so a
lower rate is judged on the moments it did not see: per player the mean and the largest
distance, as `mean_dist` and `max_dist` (docs/metrics.md) on the 8 Hz frames. Cost: seconds to
read and replay the round at each rate, and its frames. Rates above the data's 8 Hz cannot be
judged on this data (no real round here is recorded faster): their cost is measured on the
synthetic sample's first two rounds written with 64 tick rows a second
(decoy_cli/esta/awpy/writer.py), read and replayed at 32, 16, 8 and 4 frames a second.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "cs2_dust2_awpy"
ROUND_8HZ = DATA / "awpy2" / "spirit-vs-falcons-m2-dust2-8hz-r02.zip"
RATES = (8.0, 4.0, 2.0, 1.0)
COST_RATES = (32.0, 16.0, 8.0, 4.0)


def main() -> None:
    from decoy_cli.csgo import tick_at
    from decoy_cli.esta import read_match
    from decoy_cli.replay import ReplayOptions, replay_round
    from decoy_cli.sim.setup import open_round
    from decoy_cli.waypoints.build import builtin_graph
    from decoy_cli.world.navmesh import nav_world
    from decoy_cli.world.physics import PhysicsWorld

    path = Path(sys.argv[1]) if len(sys.argv) > 1 else ROUND_8HZ
    graph = builtin_graph()
    truth = read_match(path, rate=8.0).rounds[0]
    seconds = truth.frame_seconds
    sim_ticks = np.array([tick_at(s) for s in seconds])
    options = ReplayOptions(combat=False, bomb=False)
    extra = tuple(int(t) for t in sim_ticks)

    def recording_more(*args, record_ticks=(), **kwargs):  # type: ignore[no-untyped-def]
        """The simulator, recording at the real 8 Hz frames too."""
        return open_round(*args, record_ticks=(*record_ticks, *extra), **kwargs)

    print(f"{path.name} round {truth.round_num}: {truth.num_frames} real frames at 8 Hz")
    print("rate  frames  mean_dist median (T, CT)  max_dist p90 (T, CT)  read+replay s")
    with PhysicsWorld(nav_world()) as physics:
        for rate in RATES:
            started = time.perf_counter()
            round_ = read_match(path, rate=rate).rounds[0]
            result = replay_round(round_, graph, options, physics=physics, open_sim=recording_more)
            cost = time.perf_counter() - started
            rec = result.recording
            at = np.searchsorted(rec.ticks, sim_ticks)
            replayed = rec.position[at]  # (F, P, 3) at the real frames
            rows = {"T": ([], []), "CT": ([], [])}
            for p, player in enumerate(truth.players):
                both = truth.alive[p] & rec.alive[at, p]
                gap = np.linalg.norm(replayed[both, p] - truth.position[p, both], axis=1)
                if gap.size:
                    rows[player.side][0].append(gap.mean())
                    rows[player.side][1].append(gap.max())
            means = [np.median(rows[s][0]) for s in ("T", "CT")]
            p90 = [np.percentile(rows[s][1], 90) for s in ("T", "CT")]
            print(
                f"{rate:4g}  {round_.num_frames:6d}  {means[0]:.3f}, {means[1]:.3f} m"
                f"{'':16}{p90[0]:.2f}, {p90[1]:.2f} m{'':10}{cost:.2f}"
            )


def cost_at_full_rate() -> None:
    """Read-and-replay seconds of full-rate synthetic rounds at rates above the real data's."""
    import tempfile
    from dataclasses import replace

    from decoy_cli.esta import read_match
    from decoy_cli.esta.awpy.writer import write_awpy3_folder
    from decoy_cli.replay import ReplayOptions, replay_round
    from decoy_cli.synth.sample import SAMPLE_DIR
    from decoy_cli.waypoints.build import builtin_graph
    from decoy_cli.world.navmesh import nav_world
    from decoy_cli.world.physics import PhysicsWorld

    sample = read_match(next(SAMPLE_DIR.glob("*.json.xz")))
    graph = builtin_graph()
    options = ReplayOptions(combat=False, bomb=False)
    print("synthetic sample, rounds 1-2 at 64 tick rows a second: rate  frames  read+replay s")
    with tempfile.TemporaryDirectory() as folder, PhysicsWorld(nav_world()) as physics:
        path = write_awpy3_folder(
            replace(sample, rounds=sample.rounds[:2]), Path(folder) / "full", every=2
        )
        for rate in COST_RATES:
            started = time.perf_counter()
            frames = 0
            for round_ in read_match(path, rate=rate).rounds:
                replay_round(round_, graph, options, physics=physics)
                frames += round_.num_frames
            print(f"{rate:4g}  {frames:6d}  {time.perf_counter() - started:.2f}")


if __name__ == "__main__":
    main()
    cost_at_full_rate()
