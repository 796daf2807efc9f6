"""Hand-made `decoy evaluate` run folders for the tests of the readers of runs (`decoy compare`):
players.csv, rounds.csv and tables/places.csv, every metric of every player-round the same
value unless told otherwise.

Usage from another test module: `from run_fixtures import write_run`.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from decoy_cli.metrics import METRIC_NAMES

ROUNDS = 6
PLAYERS = ("p1", "p2")


def write_run(folder: Path, value: float = 1.0, values: dict[str, float] | None = None) -> Path:
    """A run folder whose metrics are `value` (or `values[metric]`) in every player-round."""
    rows = []
    for r in range(1, ROUNDS + 1):
        for p in PLAYERS:
            row: dict[str, object] = {"match": "m", "round": r, "player": p, "side": "T"}
            row |= {"reason": None} | {m: (values or {}).get(m, value) for m in METRIC_NAMES}
            rows.append(row)
    (folder / "tables").mkdir(parents=True)
    pd.DataFrame(rows).to_csv(folder / "players.csv", index=False)
    rounds = pd.DataFrame({"match": "m", "round": range(1, ROUNDS + 1), "file_sha": "abc"})
    rounds.to_csv(folder / "rounds.csv", index=False)
    places = pd.DataFrame({"place": ["LongA", "Mid"], "mean_error_m": [value, value]})
    places.to_csv(folder / "tables" / "places.csv", index=False)
    return folder
