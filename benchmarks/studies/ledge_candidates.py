"""Walled sides over a lower floor: would a player step off there?
python benchmarks/studies/ledge_candidates.py [--mesh MESH.tri] [--rounds PATH ...]
(defaults: ../shared/data/meshes/de_dust2_moh-maps.tri; the real rounds of
../shared/data/esta_dust2_tside (T side, CS:GO) and of
../shared/data/cs2_dust2_both/spirit-vs-falcons-m2-dust2-r01-12.json.xz (both sides, CS2))

The world builder walls every stretch of a nav-area side with no area near beyond it
(`open_stretches` with `other` -1). The rule in question would open such a stretch as a ledge
where a lower floor lies beyond it or reaches under it: a *candidate* is a sample point of a
walled stretch (every `SAMPLE_U` along it) whose landing spot (`LAND_U` beyond the side, or
just inside a lower area that starts within `LEDGE_REACH_U` of it) lies on another nav area
whose floor there is lower than the side by more than a crouch-jump (`JUMP_U`) and at most the
deepest drop the waypoint builder links (`MAX_DROP_M`, 620 u: a fall a player at full health
survives by the game's fall rule, `decoy_cli.csgo.fall_damage`), with no area near the upper
floor's level there. Consecutive candidate samples of one side over one lower area make one
candidate stretch.

1. **Every map**: the candidate stretches, and how many of them the nav mesh's own connections
   link (upper area to lower area, the generator's drop links).
2. **de_dust2's brush geometry** (`--mesh`, awpy-style .tri in Hammer units, read by
   `read_mesh`): from each sample a walker goes out across the side over the mesh's floors
   (`walk_off`: rays at knee to above-head heights for each stride, a ray down for the floor at
   its end, steps and stairs walked, falls fallen) and ends *open* (it stands on the lower
   floor), *low barrier* (the same, over a barrier low enough to jump), *blocked* (a railing
   or wall), *floor continues* (no lower floor within `WALK_U`: the mesh's floor goes on at the
   upper level, or the lower area lies under a slab) or *no floor*. A stretch is open if a run
   of open samples at least a player hull wide (`HULL_U`) exists; the same for a low barrier;
   else the commonest sample verdict names it. Missing from the mesh (see its README): clip
   brushes (invisible walls) and most props, so "open" is an upper bound.
   The control: the same probe over the ledges the world already makes (a lower area within
   `LEDGE_REACH_U` beyond a side, at most `MAX_SHARED_STEP_U` lower), which should mostly be open.
3. **Real movement** (`--rounds`): consecutive frames (one or two frames apart) of a living
   player who goes from a candidate's upper area to its lower area while the straight path
   between the two positions crosses the side's line within the stretch (± `HULL_U`), falling
   by more than `JUMP_U`; and the drop edges of the shipped de_dust2 graph that cross it.

The decision rule (stated before measuring): open such stretches on every map only if at least
`ADOPT_SHARE` of de_dust2's candidate stretches are open in the brush geometry.
"""

from __future__ import annotations

import argparse
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from decoy_cli.csgo import HAMMER_TO_M, MAP_NAMES, MAX_DROP_M, SAFE_DROP_M
from decoy_cli.esta import iter_match_files, read_match
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.waypoints.graph import EdgeKind
from decoy_cli.world.meshfile import read_mesh
from decoy_cli.world.nav_data import NavMesh, load_navmesh
from decoy_cli.world.nav_geometry import (
    JUMP_U,
    LEDGE_REACH_U,
    STEP_U,
    floor_corner_heights,
    open_stretches,
)
from decoy_cli.world.physics import PhysicsWorld

SAMPLE_U = 8.0
"""Spacing of the sample points along a walled stretch."""
LAND_U = 32.0
"""Where a player stepping off lands, beyond the side: past the wall push (16 u) by a hull
radius (16 u)."""
INSET_U = 16.0
"""The walk off a side starts this far inside it (on the upper floor)."""
STRIDE_U = 8.0
"""The walk's stride."""
WALK_U = 128.0
"""The walk goes on up to this far beyond the side (`LEDGE_REACH_U`)."""
LOWER_MATCH_U = 48.0
"""The walker has reached the lower floor when it stands this close above its nav height."""
RAY_HEIGHTS_U = (20.0, 40.0, 60.0, 80.0, 100.0, 120.0)
"""Above the upper floor: knee (above the 18 u step), waist, chest, then the space a player
jumping over a low barrier needs (72 u hull over a barrier of up to `JUMP_OVER_U`)."""
JUMP_OVER_U = 56.0
"""A barrier lower than this a player clears by jumping (crouch-jump of about 64 u)."""
HULL_U = 32.0
"""A player's hull width: the narrowest opening a player passes."""
ADOPT_SHARE = 0.8
"""The decision rule: adopt if at least this share of de_dust2's candidates are open."""
MAX_DROP_U = MAX_DROP_M / HAMMER_TO_M
SAFE_DROP_U = SAFE_DROP_M / HAMMER_TO_M
ROUNDS = [
    Path("../shared/data/esta_dust2_tside"),
    Path("../shared/data/cs2_dust2_both/spirit-vs-falcons-m2-dust2-r01-12.json.xz"),
]


@dataclass
class Candidate:
    """A walled stretch over one lower area: its samples (Hammer units) and their verdicts."""

    upper: int
    lower: int
    side: str
    starts: list  # (x, y, z) on the side, at the upper floor's height
    lands: list  # (x, y, z) of the landing spot on the lower floor
    outward: tuple[float, float]
    verdicts: list[str]


def bilinear(nav: NavMesh, zx: np.ndarray, zy: np.ndarray, area: int, x: float, y: float):
    """The fitted floor height of an area at a point of its rectangle (clamped)."""
    u = np.clip((x - nav.x_min[area]) / (nav.x_max[area] - nav.x_min[area]), 0, 1)
    v = np.clip((y - nav.y_min[area]) / (nav.y_max[area] - nav.y_min[area]), 0, 1)
    z00, z10, z01, z11 = nav.z_at_min[area], zx[area], zy[area], nav.z_at_max[area]
    return float(z00 * (1 - u) * (1 - v) + z10 * u * (1 - v) + z01 * (1 - u) * v + z11 * u * v)


def candidates(nav: NavMesh, ledges: bool = False) -> list[Candidate]:
    """The candidate stretches of a map (module docstring), or with `ledges` the same over the
    stretches the world already makes ledges (the control)."""
    zx, zy = floor_corner_heights(nav)
    found: list[Candidate] = []
    for side, part in open_stretches(nav):
        if (part.other >= 0) != ledges:
            continue
        n = max(1, int((part.hi - part.lo) // SAMPLE_U))
        current: Candidate | None = None
        for along in part.lo + (np.arange(n) + 0.5) * (part.hi - part.lo) / n:
            x, y = side.point(along, side.coord)
            z_up = bilinear(nav, zx, zy, side.area, x, y)
            # the landing spot on each area beyond: LAND_U out, or just inside a farther area
            lands = {}
            beyond = (side.t_lo <= along) & (along <= side.t_hi)
            beyond &= (side.gap <= LEDGE_REACH_U) & (
                side.gap + (side.near_hi - side.near_lo) >= LAND_U
            )
            beyond[side.area] = False
            for b in np.nonzero(beyond)[0]:
                out = max(LAND_U, float(side.gap[b]) + INSET_U)
                lx, ly = side.point(along, side.coord + side.sign * out)
                lands[int(b)] = (lx, ly, bilinear(nav, zx, zy, int(b), lx, ly))
            below = {b: q for b, q in lands.items() if q[2] < z_up - JUMP_U}
            lower = max(below, key=lambda b: below[b][2]) if below else -1
            level = any(abs(q[2] - z_up) <= JUMP_U for q in lands.values())
            if lower < 0 or level or z_up - below[lower][2] > MAX_DROP_U:
                current = None
                continue
            if current is None or current.lower != lower:
                name = ("-x", "+x", "-y", "+y")[side.axis * 2 + int(side.sign > 0)]
                outward = (side.sign, 0.0) if side.axis == 0 else (0.0, side.sign)
                current = Candidate(side.area, lower, name, [], [], outward, [])
                found.append(current)
            current.starts.append((x, y, z_up))
            current.lands.append(below[lower])
    return found


def linked(nav: NavMesh) -> set[tuple[int, int]]:
    return {(int(a), int(b)) for a, b in nav.connections}


def judge_in_mesh(physics: PhysicsWorld, found: list[Candidate]) -> None:
    """Fill each candidate's sample verdicts by walking off the side in the brush mesh."""
    if not found:
        return
    start = np.concatenate([np.asarray(c.starts) for c in found])
    lower_z = np.concatenate([np.asarray(c.lands)[:, 2] for c in found])
    out = np.concatenate([np.tile([*c.outward, 0.0], (len(c.starts), 1)) for c in found])
    verdicts = walk_off(physics, start, out, lower_z)
    k = 0
    for c in found:
        c.verdicts, k = verdicts[k : k + len(c.starts)], k + len(c.starts)


def walk_off(physics: PhysicsWorld, start: np.ndarray, out: np.ndarray, lower_z: np.ndarray):
    """Walk each sample outward in `STRIDE_U` strides from `INSET_U` inside its side, up to
    `WALK_U` beyond it (Hammer units): a stride is blocked by a hit of the rays at
    `RAY_HEIGHTS_U` (a hit only below `JUMP_OVER_U` is a low barrier, jumped over); the walker
    then stands on the first floor below the stride's end (from a step up); it has reached the
    lower floor when it stands within `LOWER_MATCH_U` of it (by stairs or by a fall)."""
    m = HAMMER_TO_M
    n = len(start)
    pos = start - INSET_U * out
    floor, _ = physics.first_floor_below((pos + np.array([0.0, 0.0, 40.0])) * m, 120 * m)
    pos[:, 2] = np.where(np.isfinite(floor), floor / m, start[:, 2])
    verdict = np.full(n, "", dtype=object)
    barrier = np.zeros(n, dtype=bool)
    heights = np.array(RAY_HEIGHTS_U)
    for _ in range(int((WALK_U + INSET_U) // STRIDE_U)):
        going = np.nonzero(verdict == "")[0]
        if not len(going):
            break
        a, b = pos[going], pos[going] + STRIDE_U * out[going]
        hit = []
        for h in heights:
            lift = np.array([0.0, 0.0, h])
            hit.append(np.isfinite(physics.ray_test((a + lift) * m, (b + lift) * m)[0]))
        hits = np.array(hit)
        blocked = hits[heights >= JUMP_OVER_U].any(axis=0)
        verdict[going[blocked]] = "blocked"
        barrier[going] |= hits.any(axis=0)
        depth = a[:, 2] + STEP_U - lower_z[going] + 2 * LOWER_MATCH_U
        z, _ = physics.first_floor_below((b + np.array([0.0, 0.0, STEP_U])) * m, depth * m)
        z = z / m
        walking = going[~blocked]
        z = z[~blocked]
        pos[walking, :2] = b[~blocked, :2]
        verdict[walking[np.isnan(z)]] = "no floor"
        pos[walking, 2] = np.where(np.isnan(z), pos[walking, 2], z)
        reached = ~np.isnan(z) & (z <= lower_z[walking] + LOWER_MATCH_U)
        verdict[walking[reached]] = np.where(barrier[walking[reached]], "low barrier", "open")
    verdict[verdict == ""] = "floor continues"
    return verdict.tolist()


def stretch_verdict(c: Candidate) -> str:
    """Open if a hull-wide run of open samples exists, then low barrier, else the commonest."""
    need = max(1, int(np.ceil(HULL_U / SAMPLE_U)) + 1)
    need = min(need, len(c.verdicts))
    for kind, ok in (("open", {"open"}), ("low barrier", {"open", "low barrier"})):
        run = 0
        for v in c.verdicts:
            run = run + 1 if v in ok else 0
            if run >= need:
                return kind
    counts = Counter(v for v in c.verdicts if v not in ("open", "low barrier"))
    return counts.most_common(1)[0][0] if counts else "blocked"


def crossings(nav: NavMesh, found: list[Candidate], folder: Path) -> Counter:
    """Real crossings per candidate index (module docstring, 3.)."""
    by_pair: dict[tuple[int, int], list[int]] = {}
    for k, c in enumerate(found):
        by_pair.setdefault((c.upper, c.lower), []).append(k)
    seen: Counter = Counter()
    for path in iter_match_files(folder):
        for round_ in read_match(path, implausible="warn").rounds:
            pos = round_.position / HAMMER_TO_M
            ok = round_.alive & round_.present & np.isfinite(pos).all(axis=-1)
            for p in range(pos.shape[0]):
                area = np.full(pos.shape[1], -1)
                area[ok[p]] = nav.area_of(round_.position[p][ok[p]])
                for f in range(pos.shape[1] - 1):
                    for g in (f + 1, f + 2):
                        if g >= pos.shape[1] or area[f] < 0 or area[g] < 0:
                            continue
                        for k in by_pair.get((int(area[f]), int(area[g])), []):
                            if pos[p, f, 2] - pos[p, g, 2] > JUMP_U and crosses(
                                found[k], pos[p, f], pos[p, g]
                            ):
                                seen[k] += 1
    return seen


def crosses(c: Candidate, a: np.ndarray, b: np.ndarray) -> bool:
    """Whether the segment a-b crosses the candidate's side line within its stretch ± a hull."""
    axis = 0 if c.outward[0] else 1
    line = c.starts[0][axis]
    if (a[axis] - line) * (b[axis] - line) > 0:
        return False
    t = (line - a[axis]) / (b[axis] - a[axis]) if b[axis] != a[axis] else 0.0
    along = a[1 - axis] + t * (b[1 - axis] - a[1 - axis])
    ends = [s[1 - axis] for s in c.starts]
    return min(ends) - HULL_U <= along <= max(ends) + HULL_U


def graph_drops(found: list[Candidate]) -> Counter:
    """Drop edges of the shipped de_dust2 graph across each stretch (source near its upper
    floor, target near its lower one)."""
    graph = builtin_graph("de_dust2")
    drop = graph.edge_kind == EdgeKind.DROP
    src = graph.positions[graph.edge_source[drop]] / HAMMER_TO_M
    dst = graph.positions[graph.edge_target[drop]] / HAMMER_TO_M
    counts: Counter = Counter()
    for k, c in enumerate(found):
        top, bottom = np.median(np.asarray(c.starts)[:, 2]), np.median(np.asarray(c.lands)[:, 2])
        near = (np.abs(src[:, 2] - top) <= LOWER_MATCH_U) & (np.abs(dst[:, 2] - bottom) <= JUMP_U)
        counts[k] = sum(crosses(c, a, b) for a, b in zip(src[near], dst[near], strict=True))
    return counts


def describe(nav: NavMesh, c: Candidate) -> str:
    s = np.asarray(c.starts)
    drop = float(np.median(s[:, 2] - np.asarray(c.lands)[:, 2]))
    mid = s[len(s) // 2]
    return (
        f"{nav.place[c.upper] or '-'} -> {nav.place[c.lower] or '-'} ({c.side} side of area "
        f"{nav.area_id[c.upper]}, {len(s) * SAMPLE_U:.0f} u long at ({mid[0]:.0f}, {mid[1]:.0f}), "
        f"drop {drop:.0f} u)"
    )


def report(
    nav: NavMesh, found: list[Candidate], rounds: list[Path], title: str, detail: bool
) -> float:
    """Print the verdicts and real crossings of a set of stretches; the open share."""
    print(f"\n2. de_dust2, {title}, in the brush mesh")
    verdicts = [stretch_verdict(c) for c in found]
    drops = graph_drops(found)
    seen: Counter = Counter()
    for path in rounds:
        seen += crossings(nav, found, path) if path.exists() else Counter()
    for c, v, k in zip(found, verdicts, range(len(found)), strict=True):
        if detail or v != "open":
            samples = dict(Counter(c.verdicts))
            print(
                f"  {v:15s} crossings {seen[k]:3d} graph drops {drops[k]:2d}  "
                f"{describe(nav, c)}  samples {samples}"
            )
    tally = Counter(verdicts)
    share = tally["open"] / max(1, len(found))
    print(f"  stretches: {len(found)}; {dict(tally)}; open share {share:.0%}")
    print(f"3. real crossings: {sum(seen.values())} over {len(seen)} stretches")
    for v in sorted(tally):
        n = sum(seen[k] for k in range(len(found)) if verdicts[k] == v)
        e = sum(drops[k] for k in range(len(found)) if verdicts[k] == v)
        print(f"  over {v} stretches: {n} real crossings, {e} drop edges of the shipped graph")
    return share


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mesh", default="../shared/data/meshes/de_dust2_moh-maps.tri")
    parser.add_argument("--rounds", nargs="*", type=Path, default=ROUNDS)
    args = parser.parse_args()

    print(
        "1. candidate stretches per map (linked: by the nav mesh's own connections; by drop: "
        f"up to the safe fall {SAFE_DROP_U:.0f} u, up to 320 u, deeper)"
    )
    for map_name in MAP_NAMES:
        nav = load_navmesh(map_name)
        found = candidates(nav)
        links = linked(nav)
        n_linked = sum((c.upper, c.lower) in links for c in found)
        length = sum(len(c.starts) for c in found) * SAMPLE_U
        drop = np.array([np.median(np.subtract(c.starts, c.lands)[:, 2]) for c in found])
        bands = [
            int((drop <= SAFE_DROP_U).sum()),
            int(((drop > SAFE_DROP_U) & (drop <= 320)).sum()),
        ]
        bands.append(len(found) - sum(bands))
        print(
            f"  {map_name:12s} {len(found):3d} stretches, {length:6.0f} u, linked {n_linked}, "
            f"by drop {bands}"
        )

    nav = load_navmesh("de_dust2")
    shares = {}
    with PhysicsWorld(read_mesh(args.mesh)) as physics:
        for ledges, title in ((False, "candidates"), (True, "control: the world's ledges")):
            found = candidates(nav, ledges)
            judge_in_mesh(physics, found)
            shares[ledges] = report(nav, found, args.rounds, title, detail=not ledges)
    adopt = shares[False] >= ADOPT_SHARE
    print(
        f"\ndecision (adopt if open share >= {ADOPT_SHARE:.0%}): {'adopt' if adopt else 'reject'}"
    )


if __name__ == "__main__":
    main()
