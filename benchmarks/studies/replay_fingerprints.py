"""Fingerprints of replays, to show two code trees replay real rounds identically.

    python benchmarks/studies/replay_fingerprints.py OUT.json [FILES] [EVERY]
    PYTHONPATH=/path/to/other/tree python benchmarks/studies/replay_fingerprints.py OTHER.json
    python benchmarks/studies/replay_fingerprints.py --compare OUT.json OTHER.json
    python benchmarks/studies/replay_fingerprints.py --cs2 [--float32]

Replays every EVERY-th round (default 4) of the first FILES match files (default 15) of
../shared/data/esta_dust2_tside under four settings (movement only; the bomb; the bomb with the
physics mover; shooting with the shipped models and the bomb) and writes, per replay, a SHA-256
of its recording (ticks, positions, yaw, HP, alive), its events and its outcome, with the time
taken. `--compare` counts the replays whose fingerprints differ.

`--cs2` replays the real CS2 rounds read from each of their three forms (the ESTA-shaped file
of ../shared/data/cs2_dust2_both, the awpy 2 zip and the awpy 3 folder of
../shared/data/cs2_dust2_awpy) under `--deaths data` and simulated deaths (shipped models, seed
0) and prints, per round and setting, whether the three fingerprints agree. `--float32` first
rounds the ESTA-shaped file's positions to float32, as awpy stores them: the one difference
between the forms of the 1 Hz rounds (the file holds decimals of 0.1 u that float32 cannot).
"""

from __future__ import annotations

import hashlib
import json
import sys
import time
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "esta_dust2_tside"


def fingerprints(files: int, every: int) -> dict[str, str]:
    from decoy_cli.damage import load_damage_model
    from decoy_cli.esta import read_match
    from decoy_cli.replay import ReplayOptions, replay_round
    from decoy_cli.waypoints.build import builtin_graph
    from decoy_cli.world.navmesh import nav_world
    from decoy_cli.world.physics import PhysicsWorld

    graph = builtin_graph()
    settings = {
        "move": ReplayOptions(combat=False, bomb=False),
        "bomb": ReplayOptions(combat=False, bomb=True),
        "physics": ReplayOptions(combat=False, bomb=True, mover="physics"),
        "combat": ReplayOptions(combat=True, bomb=True, damage_model=load_damage_model("shipped")),
    }
    out = {}
    with PhysicsWorld(nav_world()) as physics:
        for name, options in settings.items():
            for path in sorted(DATA.glob("*.json.xz"))[:files]:
                for round_ in read_match(path).rounds[::every]:
                    key = f"{name}:{path.name}:{round_.round_num}"
                    result = replay_round(round_, graph, options, physics=physics)
                    out[key] = replay_digest(result)
    return out


def replay_digest(result: object) -> str:
    """A SHA-256 of a replay's recording, events and outcome."""
    digest = hashlib.sha256()
    rec = result.recording  # type: ignore[attr-defined]
    for array in (rec.ticks, rec.position, rec.yaw, rec.hp, rec.alive):
        digest.update(np.ascontiguousarray(array).tobytes())
    events = [(e.tick, e.kind, e.agent, e.other, sorted(e.data.items()))
              for e in result.events]  # type: ignore[attr-defined]  # fmt: skip
    digest.update(repr((events, result.outcome)).encode())  # type: ignore[attr-defined]
    return digest.hexdigest()


def cs2_fingerprints(float32: bool) -> None:
    """Print whether each CS2 round replays alike from its three forms (module docstring)."""
    from dataclasses import replace

    from decoy_cli.csgo import HAMMER_TO_M
    from decoy_cli.damage import load_damage_model
    from decoy_cli.esta import read_match
    from decoy_cli.replay import ReplayOptions, replay_round
    from decoy_cli.waypoints.build import builtin_graph
    from decoy_cli.world.navmesh import nav_world
    from decoy_cli.world.physics import PhysicsWorld

    shared = DATA.parent
    graph = builtin_graph()
    model = load_damage_model("rules")
    settings = {
        "data": ReplayOptions(combat=True, bomb=True, damage_model=model, deaths="data", seed=0),
        "simulated": ReplayOptions(combat=True, bomb=True, damage_model=model, seed=0),
    }
    stems = ["spirit-vs-falcons-m2-dust2-r01-12", "spirit-vs-falcons-m2-dust2-8hz-r02"]
    differ = total = 0
    with PhysicsWorld(nav_world()) as physics:
        for stem in stems:
            forms = {
                "esta": read_match(shared / "cs2_dust2_both" / f"{stem}.json.xz"),
                "awpy2": read_match(shared / "cs2_dust2_awpy" / "awpy2" / f"{stem}.zip"),
                "awpy3": read_match(shared / "cs2_dust2_awpy" / "awpy3" / stem),
            }
            for num in forms["esta"].round_numbers:
                for name, options in settings.items():
                    digests = {}
                    for form, match in forms.items():
                        round_ = match.round(num)
                        if float32 and form == "esta":
                            exact = round_.position / HAMMER_TO_M
                            stored = exact.astype(np.float32).astype(np.float64) * HAMMER_TO_M
                            round_ = replace(round_, position=stored)
                        digests[form] = replay_digest(
                            replay_round(round_, graph, options, physics=physics)
                        )
                    same = len(set(digests.values())) == 1
                    total += 1
                    differ += not same
                    print(f"{stem}:{num} {name}: {'same' if same else digests}")
    print(f"{total} replays of three forms; {differ} differ")


def main() -> None:
    if sys.argv[1:2] == ["--cs2"]:
        cs2_fingerprints("--float32" in sys.argv)
        return
    if sys.argv[1:2] == ["--compare"]:
        a, b = (json.loads(Path(p).read_text())["replays"] for p in sys.argv[2:4])
        differ = sorted(k for k in a.keys() | b.keys() if a.get(k) != b.get(k))
        print(f"{len(a)} and {len(b)} replays; {len(differ)} differ {differ[:10]}")
        return
    files = int(sys.argv[2]) if len(sys.argv) > 2 else 15
    every = int(sys.argv[3]) if len(sys.argv) > 3 else 4
    began = time.perf_counter()
    replays = fingerprints(files, every)
    seconds = time.perf_counter() - began
    Path(sys.argv[1]).write_text(json.dumps({"seconds": seconds, "replays": replays}, indent=1))
    print(f"{len(replays)} replays in {seconds:.1f} s -> {sys.argv[1]}")


if __name__ == "__main__":
    main()
