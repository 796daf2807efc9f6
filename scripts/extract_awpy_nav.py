"""Extract the navigation meshes of the eight ESTA maps from the awpy 1.3.1 sdist.

Run once by a maintainer (the project never imports awpy):

    pip download awpy==1.3.1 --no-deps -d /tmp/awpy
    python scripts/extract_awpy_nav.py /tmp/awpy/awpy-1.3.1.tar.gz

awpy 1.3.1 ships nav meshes (`awpy/data/nav/<map>.txt` and rows of `nav_info.csv`) for all eight
maps ESTA covers (de_ancient, de_dust2, de_inferno, de_mirage, de_nuke, de_overpass, de_train,
de_vertigo) and for 16 maps ESTA does not cover (cs_assault, cs_italy, cs_office, de_anubis,
de_bank, de_cache, de_canals, de_cbble, de_grind, de_lake, de_mocha, de_safehouse, de_shortdust,
de_shortnuke, de_stmarc, de_sugarcane): only the eight are extracted.

For each map, writes `assets/<map>/nav_areas.csv` (one row per nav area: id, place name and the
two corner points awpy kept, in Hammer units), `nav_connections.csv` (directed area pairs) and
`map.json` (radar transform, the nav places that make each region, attribution). awpy names the
corners "northWest" and "southEast", but in its data the first corner is always the minimum x and
minimum y: the files here use `x_min, y_min, z_at_min` and `x_max, y_max, z_at_max` so nobody has
to remember that. An existing `world_patches.csv` is kept; a map without one gets an empty one.
"""

from __future__ import annotations

import csv
import io
import json
import sys
import tarfile
from pathlib import Path

from decoy_cli.csgo import MAP_NAMES

AWPY_VERSION = "1.3.1"
ASSETS = Path(__file__).resolve().parents[1] / "assets"
STANDARD_REGIONS = {
    "t_spawn": ["TSpawn"],
    "ct_spawn": ["CTSpawn"],
    "bombsite_a": ["BombsiteA"],
    "bombsite_b": ["BombsiteB"],
}
REGION_EXCEPTIONS = {
    # de_overpass's nav mesh names no CTSpawn: the CT start is the two-level hall at the north end
    # of the radar picture, above A site, whose areas awpy names StorageRoom and Lobby.
    "de_overpass": {"ct_spawn": ["StorageRoom", "Lobby"]},
}
PATCH_HEADER = "x_min,y_min,x_max,y_max,z_top,z_bottom,what\n"


def _member(archive: tarfile.TarFile, suffix: str) -> str:
    names = [m.name for m in archive.getmembers() if m.name.endswith(suffix)]
    if len(names) != 1:
        raise SystemExit(f"expected one {suffix} in the sdist, found {names}")
    file = archive.extractfile(names[0])
    assert file is not None
    return file.read().decode("utf-8")


def _write_csv(path: Path, header: list[str], rows: list[list[object]]) -> None:
    with open(path, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(header)
        w.writerows(rows)


def extract(map_name: str, nav_rows: list[dict[str, str]], links: str, radar: dict) -> None:
    rows = sorted((r for r in nav_rows if r["mapName"] == map_name), key=lambda r: int(r["areaId"]))
    for r in rows:
        if not float(r["northWestX"]) < float(r["southEastX"]):
            raise SystemExit(f"{map_name} area {r['areaId']}: corner order differs")
        if not float(r["northWestY"]) < float(r["southEastY"]):
            raise SystemExit(f"{map_name} area {r['areaId']}: corner order differs")
    regions = {**STANDARD_REGIONS, **REGION_EXCEPTIONS.get(map_name, {})}
    places = {r["areaName"] for r in rows}
    for region, names in regions.items():
        if not set(names) <= places:
            raise SystemExit(f"{map_name}: region {region} names places the nav mesh lacks")
    out = ASSETS / map_name
    out.mkdir(parents=True, exist_ok=True)
    corners = ("northWestX", "northWestY", "northWestZ", "southEastX", "southEastY", "southEastZ")
    _write_csv(
        out / "nav_areas.csv",
        ["area_id", "place", "x_min", "y_min", "z_at_min", "x_max", "y_max", "z_at_max"],
        [[int(r["areaId"]), r["areaName"], *(r[k] for k in corners)] for r in rows],
    )
    pairs = sorted({tuple(int(v) for v in line.split(",")) for line in links.split()})
    _write_csv(out / "nav_connections.csv", ["from_area", "to_area"], [list(p) for p in pairs])
    meta = {
        "map": map_name,
        "source": f"awpy=={AWPY_VERSION} (PyPI sdist), awpy/data/nav and awpy/data/map",
        "license": "MIT, Copyright (c) 2020-2023 Peter Xenopoulos",
        "units": "Hammer units (1 u = 0.01905 m), x east, y north, z up",
        "radar": {k: radar[k] for k in ("pos_x", "pos_y", "scale")},
        "regions": regions,
        "areas": len(rows),
        "connections": len(pairs),
    }
    (out / "map.json").write_text(json.dumps(meta, indent=2) + "\n")
    if not (out / "world_patches.csv").is_file():
        (out / "world_patches.csv").write_text(PATCH_HEADER)
    print(f"{map_name}: {len(rows)} areas, {len(pairs)} connections -> {out}")


def main(sdist: Path) -> None:
    with tarfile.open(sdist) as archive:
        nav_rows = list(csv.DictReader(io.StringIO(_member(archive, "awpy/data/nav/nav_info.csv"))))
        map_data = json.loads(_member(archive, "awpy/data/map/map_data.json"))
        links = {m: _member(archive, f"awpy/data/nav/{m}.txt") for m in MAP_NAMES}
    for map_name in MAP_NAMES:
        extract(map_name, nav_rows, links[map_name], map_data[map_name])


if __name__ == "__main__":
    main(Path(sys.argv[1]))
