"""CS:GO's damage rules against real hits:
python benchmarks/studies/damage_rules_check.py [EVENTS...]

For every firearm hit in the ESTA files' `damages` (default: ../shared/data/esta_dust2_events),
the rules of decoy_cli/damage/rules.py predict the health damage from weapon, hit group, distance
and armour; per weapon it prints the share reproduced exactly and within 1 HP, and the base damage
the hits imply (median and 10th-90th percentile), next to the table's value.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pandas as pd
from _damage_rules import check_rules

from decoy_cli.esta import collect_match_files, read_match

DEFAULT = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "esta_dust2_events"


def main() -> None:
    inputs = [Path(a) for a in sys.argv[1:]] or [DEFAULT]
    files, _ = collect_match_files(inputs)
    tables = [r.damages for f in files for r in read_match(f).rounds]
    damages = pd.concat(tables, ignore_index=True)
    table, left_out = check_rules(damages)
    print(f"{len(damages)} damage rows in {len(files)} files; left out: {left_out}")
    with pd.option_context("display.width", 160):
        print(table.round(3).to_string(index=False))
    hits = table["hits"].sum()
    exact = (table["exact_share"] * table["hits"]).sum() / hits
    within = (table["within_1hp_share"] * table["hits"]).sum() / hits
    print(f"all {hits} firearm hits: {exact:.1%} reproduced exactly, {within:.1%} within 1 HP")


if __name__ == "__main__":
    main()
