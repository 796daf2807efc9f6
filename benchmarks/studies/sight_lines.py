"""How often the simulator's world lets a real shot through: line of sight along real firing lines.

Every firearm damage event (attacker known, not friendly fire) and every firearm kill that was not
a wallbang of the given ESTA files is a line a player really saw along (a shot through smoke
still had the geometry clear). The script puts a standing eye over both ends (the event's
position; a kill without a height takes the frame's) and tests the line in the map's built-in
world, the geometry the simulator's line of sight uses by default, and with `--mesh` in a map's
own geometry (awpy's `.tri` or an `.obj`), then prints the share clear by source. A crouching
player's eye is lower, so both figures are bounds of a kind, comparable with each other.

    python benchmarks/studies/sight_lines.py [FILES_OR_FOLDERS ...] [--map dust2]
        [--mesh ../shared/data/meshes/de_dust2_moh-maps.tri]

Default inputs: `../shared/data/esta_dust2_events` and the 12 rounds of `cs2_dust2_both`.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from decoy_cli.esta import Round, RoundFailure, collect_match_files, iter_rounds
from decoy_cli.geometry import eye_point
from decoy_cli.waypoints.build import canonical_map
from decoy_cli.weapons import FIREARMS
from decoy_cli.world.meshfile import read_mesh
from decoy_cli.world.navmesh import nav_world
from decoy_cli.world.occlusion import OcclusionScene

DATA = Path(__file__).resolve().parents[2].parent / "shared" / "data"
DEFAULT_INPUTS = [
    DATA / "esta_dust2_events",
    DATA / "cs2_dust2_both" / "spirit-vs-falcons-m2-dust2-r01-12.json.xz",
]
ENDS = ["attackerX_m", "attackerY_m", "attackerZ_m", "victimX_m", "victimY_m", "victimZ_m"]


def firing_lines(round_: Round) -> dict[str, np.ndarray]:
    """(K, 6) attacker and victim feet (metres) of the round's damage events and kills."""
    lines = {}
    damages = round_.damages
    if len(damages):
        shots = damages[damages.weapon.isin(FIREARMS) & damages.attackerX_m.notna()]
        if "isFriendlyFire" in shots:
            shots = shots[~shots.isFriendlyFire.fillna(False).astype(bool)]
        lines["damage events"] = shots[ENDS].to_numpy(dtype=np.float64)
    kills = round_.kills
    if len(kills):
        kills = kills[kills.weapon.isin(FIREARMS) & kills.attackerX_m.notna()]
        if "isWallbang" in kills:
            kills = kills[~kills.isWallbang.fillna(False).astype(bool)]
        ends = kills[ENDS].to_numpy(dtype=np.float64, copy=True)
        rows = {str(p.name): i for i, p in enumerate(round_.players)}
        names = zip(kills.attackerName, kills.victimName, kills.seconds, strict=True)
        for k, (attacker, victim, seconds) in enumerate(names):
            frame = int(np.searchsorted(round_.frame_seconds, seconds, "right")) - 1
            for column, name in ((2, attacker), (5, victim)):
                if not np.isfinite(ends[k, column]) and name in rows and frame >= 0:
                    ends[k, column] = round_.position[rows[name], frame, 2]
        lines["kills (no wallbang)"] = ends
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("inputs", nargs="*", type=Path, default=DEFAULT_INPUTS)
    parser.add_argument("--map", default="dust2")
    parser.add_argument("--mesh", type=Path, default=None)
    args = parser.parse_args()
    map_name = canonical_map(args.map)
    files, _ = collect_match_files(args.inputs)
    by_source: dict[str, list[np.ndarray]] = {}
    for item in iter_rounds(files, map_name=map_name):
        if isinstance(item, RoundFailure):
            print(f"skipped: {item.file} round {item.round_num}: {item.message}")
            continue
        for kind, ends in firing_lines(item).items():
            by_source.setdefault(f"{Path(item.path).name}: {kind}", []).append(ends)
    scenes = {"built-in world": OcclusionScene(nav_world(map_name))}
    if args.mesh is not None:
        scenes[f"mesh {args.mesh.name}"] = OcclusionScene(read_mesh(args.mesh))
    width = max(len(source) for source in by_source) + 2 if by_source else 10
    print(f"{'source':<{width}}{'lines':>7}" + "".join(f"  {name:>28}" for name in scenes))
    for source, parts in by_source.items():
        ends = np.concatenate(parts)
        ends = ends[np.isfinite(ends).all(axis=1)]
        starts, stops = eye_point(ends[:, :3]), eye_point(ends[:, 3:])
        shares = [scene.clear(starts, stops).mean() for scene in scenes.values()]
        print(f"{source:<{width}}{len(ends):>7}" + "".join(f"  {share:>28.3f}" for share in shares))


if __name__ == "__main__":
    main()
