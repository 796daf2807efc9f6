"""Extract the de_dust2 slice of the CS:GO navigation mesh from the awpy 1.3.1 sdist.

Run once by a maintainer (the project never imports awpy):

    pip download awpy==1.3.1 --no-deps -d /tmp/awpy
    python scripts/extract_awpy_nav.py /tmp/awpy/awpy-1.3.1.tar.gz

Writes `assets/de_dust2/nav_areas.csv` (one row per nav area: id, place name and the
two corner points awpy kept, in Hammer units), `nav_connections.csv` (directed area pairs) and
`map.json` (radar transform and attribution). awpy names the corners "northWest" and "southEast",
but in its data the first corner is always the minimum x and minimum y: the files here use
`x_min, y_min, z_at_min` and `x_max, y_max, z_at_max` so nobody has to remember that.
"""

from __future__ import annotations

import csv
import io
import json
import sys
import tarfile
from pathlib import Path

AWPY_VERSION = "1.3.1"
MAP = "de_dust2"
OUT = Path(__file__).resolve().parents[1] / "assets" / MAP


def _member(archive: tarfile.TarFile, suffix: str) -> str:
    names = [m.name for m in archive.getmembers() if m.name.endswith(suffix)]
    if len(names) != 1:
        raise SystemExit(f"expected one {suffix} in the sdist, found {names}")
    file = archive.extractfile(names[0])
    assert file is not None
    return file.read().decode("utf-8")


def main(sdist: Path) -> None:
    with tarfile.open(sdist) as archive:
        nav_info = _member(archive, "awpy/data/nav/nav_info.csv")
        connections = _member(archive, f"awpy/data/nav/{MAP}.txt")
        map_data = json.loads(_member(archive, "awpy/data/map/map_data.json"))[MAP]

    rows = [r for r in csv.DictReader(io.StringIO(nav_info)) if r["mapName"] == MAP]
    rows.sort(key=lambda r: int(r["areaId"]))
    for r in rows:
        if not (float(r["northWestX"]) < float(r["southEastX"])):
            raise SystemExit(f"area {r['areaId']}: corner order differs from the documented one")
        if not (float(r["northWestY"]) < float(r["southEastY"])):
            raise SystemExit(f"area {r['areaId']}: corner order differs from the documented one")
    OUT.mkdir(parents=True, exist_ok=True)
    with open(OUT / "nav_areas.csv", "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["area_id", "place", "x_min", "y_min", "z_at_min", "x_max", "y_max", "z_at_max"])
        for r in rows:
            w.writerow(
                [
                    int(r["areaId"]),
                    r["areaName"],
                    r["northWestX"],
                    r["northWestY"],
                    r["northWestZ"],
                    r["southEastX"],
                    r["southEastY"],
                    r["southEastZ"],
                ]
            )
    pairs = sorted({tuple(int(v) for v in line.split(",")) for line in connections.split()})
    with open(OUT / "nav_connections.csv", "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["from_area", "to_area"])
        w.writerows(pairs)
    meta = {
        "map": MAP,
        "source": f"awpy=={AWPY_VERSION} (PyPI sdist), awpy/data/nav and awpy/data/map",
        "license": "MIT, Copyright (c) 2020-2023 Peter Xenopoulos",
        "units": "Hammer units (1 u = 0.01905 m), x east, y north, z up",
        "radar": {
            "pos_x": map_data["pos_x"],
            "pos_y": map_data["pos_y"],
            "scale": map_data["scale"],
        },
        "areas": len(rows),
        "connections": len(pairs),
    }
    (OUT / "map.json").write_text(json.dumps(meta, indent=2) + "\n")
    print(f"wrote {len(rows)} areas and {len(pairs)} connections to {OUT}")


if __name__ == "__main__":
    main(Path(sys.argv[1]))
