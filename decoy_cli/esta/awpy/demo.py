"""A CS2 demo (`.dem`) read through awpy 3 (`pip install 'decoy[cs2]'`): its datasets are the
tables of an awpy 3 folder, the snapshots taken every `tick rate / rate` ticks, so a match's
memory is the frames the replay keeps."""

from __future__ import annotations

from pathlib import Path

import pyarrow as pa

from decoy_cli.errors import EstaError
from decoy_cli.esta.awpy.tables import TableSource
from decoy_cli.files import json_object

TABLES = ("rounds", "kills", "damages", "bomb", "smokes", "fires", "blinds", "grenades", "shots")
"""awpy 3's datasets the reader may open (its snapshots aside)."""


def demo_source(path: Path, rate: float) -> TableSource:
    """The demo's tables as awpy 3 gives them; a demo awpy 3 cannot read raises EstaError."""
    try:
        from awpy import Demo
    except ImportError:
        raise EstaError(
            f"{path}: reading a demo needs awpy 3 (pip install 'decoy[cs2]'), or its tables "
            "written as docs/cs2.md shows"
        ) from None
    try:
        demo = Demo(path)
        header = json_object(dict(demo.header))
        every = max(1, round(float(demo.tick_rate) / rate))
    except Exception as error:  # awpy's InvalidDemoError and whatever its parser raises
        raise EstaError(f"{path}: awpy 3 cannot read this demo ({error})") from None
    opened: dict[str, pa.Table] = {}

    def open_table(name: str) -> pa.Table | None:
        if name not in opened:
            if name != "snapshots" and name not in TABLES:
                return None
            try:
                data = demo.snapshots(every=every) if name == "snapshots" else getattr(demo, name)
                opened[name] = data.to_arrow()
            except Exception as error:  # the parser's own errors, whatever their type
                raise EstaError(f"{path}: awpy 3 cannot read its {name} ({error})") from None
        return opened[name]

    return TableSource(path, "awpy 3", header, open_table)
