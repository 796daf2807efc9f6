"""Fingerprints of replays, to show two code trees replay real rounds identically.

    python benchmarks/studies/replay_fingerprints.py OUT.json [--files N] [--every N]
    PYTHONPATH=/path/to/other/tree python benchmarks/studies/replay_fingerprints.py OTHER.json
    python benchmarks/studies/replay_fingerprints.py --compare OUT.json OTHER.json
    python benchmarks/studies/replay_fingerprints.py --cs2-forms [--float32]

Replays every EVERY-th round (default 4) of the first FILES match files (default 15) of
../shared/data/esta_dust2_tside under four settings (movement only; the bomb; the bomb with the
physics mover; shooting with the shipped models and the bomb), and every real CS2 round in each
of its three forms (the ESTA-shaped file of ../shared/data/cs2_dust2_both, the awpy 2 zip and
the awpy 3 folder of ../shared/data/cs2_dust2_awpy) under four more (the game's damage rules with
`--deaths data`, with simulated deaths, the shipped models, the physics mover), and writes, per
replay, a SHA-256 of its recording (ticks, positions, yaw, HP, alive), its events and its
outcome, with the time taken. `--compare` counts the replays whose fingerprints differ.

`--cs2-forms` prints, per CS2 round, whether its three forms replay alike with the damage rules
under both death protocols.
`--float32` first rounds the ESTA-shaped file's positions to float32, as awpy stores them: the
one difference between the forms of the 1 Hz rounds (the file holds decimals of 0.1 u that
float32 cannot).
"""

from __future__ import annotations

import argparse
import hashlib
import json
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


CS2_STEMS = ("spirit-vs-falcons-m2-dust2-r01-12", "spirit-vs-falcons-m2-dust2-8hz-r02")


def cs2_replays(float32: bool = False, only: tuple[str, ...] = ()) -> dict[str, str]:
    """Fingerprints of the CS2 rounds, keyed setting:stem:round:form (module docstring), under
    the settings named in `only` (all when empty)."""
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
    rules = load_damage_model("rules")
    settings = {
        "data": ReplayOptions(combat=True, bomb=True, damage_model=rules, deaths="data", seed=0),
        "simulated": ReplayOptions(combat=True, bomb=True, damage_model=rules, seed=0),
        "shipped": ReplayOptions(damage_model=load_damage_model("shipped"), seed=0),
        "physics": ReplayOptions(combat=False, bomb=True, mover="physics"),
    }
    settings = {k: v for k, v in settings.items() if not only or k in only}
    out = {}
    with PhysicsWorld(nav_world()) as physics:
        for stem in CS2_STEMS:
            forms = {
                "esta": read_match(shared / "cs2_dust2_both" / f"{stem}.json.xz"),
                "awpy2": read_match(shared / "cs2_dust2_awpy" / "awpy2" / f"{stem}.zip"),
                "awpy3": read_match(shared / "cs2_dust2_awpy" / "awpy3" / stem),
            }
            for num in forms["esta"].round_numbers:
                for name, options in settings.items():
                    for form, match in forms.items():
                        round_ = match.round(num)
                        if float32 and form == "esta":
                            exact = round_.position / HAMMER_TO_M
                            stored = exact.astype(np.float32).astype(np.float64) * HAMMER_TO_M
                            round_ = replace(round_, position=stored)
                        result = replay_round(round_, graph, options, physics=physics)
                        out[f"{name}:{stem}:{num}:{form}"] = replay_digest(result)
    return out


def print_cs2_forms(float32: bool) -> None:
    """Print whether each CS2 round replays alike from its three forms, with the game's damage
    rules under both death protocols."""
    by_replay: dict[str, set[str]] = {}
    for key, digest in cs2_replays(float32, only=("data", "simulated")).items():
        by_replay.setdefault(key.rsplit(":", 1)[0], set()).add(digest)
    differ = [key for key, digests in by_replay.items() if len(digests) > 1]
    for key, digests in by_replay.items():
        print(f"{key}: {'same' if len(digests) == 1 else 'differ'}")
    print(f"{len(by_replay)} replays of three forms; {len(differ)} differ")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("out", nargs="?", type=Path, help="where to write the fingerprints")
    parser.add_argument("--files", type=int, default=15, help="T-side match files")
    parser.add_argument("--every", type=int, default=4, help="every N-th round of each")
    parser.add_argument("--compare", nargs=2, type=Path, metavar=("A", "B"))
    parser.add_argument("--cs2-forms", action="store_true", help="do the three forms agree")
    parser.add_argument("--float32", action="store_true", help="with --cs2-forms (docstring)")
    args = parser.parse_args()
    if args.cs2_forms:
        print_cs2_forms(args.float32)
        return
    if args.compare:
        a, b = (json.loads(p.read_text())["replays"] for p in args.compare)
        differ = sorted(k for k in a.keys() | b.keys() if a.get(k) != b.get(k))
        print(f"{len(a)} and {len(b)} replays; {len(differ)} differ {differ[:10]}")
        return
    if args.out is None:
        parser.error("give OUT.json, --compare A B or --cs2-forms")
    began = time.perf_counter()
    replays = {**fingerprints(args.files, args.every), **cs2_replays()}
    seconds = time.perf_counter() - began
    args.out.write_text(json.dumps({"seconds": seconds, "replays": replays}, indent=1))
    print(f"{len(replays)} replays in {seconds:.1f} s -> {args.out}")


if __name__ == "__main__":
    main()
