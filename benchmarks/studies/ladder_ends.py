"""Where the floors at the shipped ladders' ends lie: python benchmarks/studies/ladder_ends.py

For every ladder of every built-in map, the floor nearest its top and its bottom found by the
builder's probes (`decoy_cli.waypoints.ladders.end_floor`), once in the builder's height bands
and once in a wide band (2 m below to 1 m above), with the height of that floor relative to the
end and how far from it the probe found it. What `TOP_BAND_M`, `BOTTOM_BAND_M` and
`LADDER_REACH` were chosen by.
"""

from __future__ import annotations

from decoy_cli.csgo import HAMMER_TO_M, MAP_NAMES
from decoy_cli.waypoints.ladders import BOTTOM_BAND_M, TOP_BAND_M, end_floor
from decoy_cli.waypoints.lattice_params import LatticeParams
from decoy_cli.world.navmesh import load_navmesh, nav_world
from decoy_cli.world.physics import PhysicsWorld

WIDE_BAND_M = (-2.0, 1.0)


def described(found) -> str:
    return "none" if found is None else f"{found[2]:+.2f} m at {found[1]:.2f} m"


def main() -> None:
    params = LatticeParams()
    print("map, ladder, end: floor in the builder's band | in the wide band (height, distance)")
    for map_name in MAP_NAMES:
        ladders = load_navmesh(map_name).ladders * HAMMER_TO_M
        if not len(ladders):
            continue
        with PhysicsWorld(nav_world(map_name)) as physics:
            for k, ladder in enumerate(ladders):
                for name, end, band in (
                    ("top", ladder[:3], TOP_BAND_M),
                    ("bottom", ladder[3:], BOTTOM_BAND_M),
                ):
                    row = []
                    for b in (band, WIDE_BAND_M):
                        found = end_floor(physics, end, b, params)
                        row.append(
                            described(None if found is None else (*found, found[0][2] - end[2]))
                        )
                    print(f"{map_name} {k} {name:6s} {row[0]:18s} | {row[1]}")


if __name__ == "__main__":
    main()
