"""awpy 2's and awpy 3's table layouts: which table and column holds what the reader uses, under
one set of names (awpy 3's lower-case ones) and kinds.

awpy 2 (`awpy parse`, a zip): `ticks` with demoparser2's prop names (`X`, `armor`, `is_alive`,
`active_weapon_name` when the user asked for them with `--player-props`), `<player>_X` in events,
sides `t`/`ct`, reasons by name, a `round_num` in every table. awpy 3 (`Demo`, a folder this
project defines): `snapshots` (`x`, `armor`, `has_bomb`, `active_weapon`), sides
`terrorist`/`counter-terrorist`, `rounds.winner` 2/3 and `reason` by number, no round numbers on
events. What is optional may be absent; what is required raises when absent.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from decoy_cli.esta.awpy.names import Spelling
from decoy_cli.esta.awpy.tables import Kind

LayoutName = Literal["awpy 2", "awpy 3"]


@dataclass(frozen=True)
class TableLayout:
    """One table of a layout: its file name and its columns, source name -> (name, kind)."""

    name: str
    columns: dict[str, tuple[str, Kind]]
    required: tuple[str, ...]

    @property
    def kinds(self) -> dict[str, Kind]:
        """Source column -> kind, as `read_table` takes them."""
        return {source: kind for source, (_, kind) in self.columns.items()}

    @property
    def renames(self) -> dict[str, str]:
        """Source column -> the reader's name."""
        return {source: name for source, (name, _) in self.columns.items()}


@dataclass(frozen=True)
class Layout:
    """Where each of the reader's tables lies in one awpy layout."""

    name: LayoutName
    rounds: TableLayout
    ticks: TableLayout
    kills: TableLayout
    damages: TableLayout
    bomb: TableLayout
    smokes: TableLayout
    fires: TableLayout
    blinds: TableLayout | None
    """awpy 2 has no blinds table."""
    tick_weapons: Spelling
    """How the tick table spells a weapon in hand."""


def _player(prefix: str, upper_xyz: bool, *, view: bool = False) -> dict[str, tuple[str, Kind]]:
    """An event's player columns: `<prefix>_name`, `_steamid`, `_side`, position (and view)."""
    columns: dict[str, tuple[str, Kind]] = {
        f"{prefix}_name": (f"{prefix}_name", "str"),
        f"{prefix}_steamid": (f"{prefix}_steamid", "int"),
        f"{prefix}_side": (f"{prefix}_side", "str"),
    }
    for axis in "xyz":
        source = f"{prefix}_{axis.upper() if upper_xyz else axis}"
        columns[source] = (f"{prefix}_{axis}", "float")
    if view:
        columns[f"{prefix}_yaw"] = (f"{prefix}_yaw", "float")
        columns[f"{prefix}_pitch"] = (f"{prefix}_pitch", "float")
    return columns


def _same(kinds: dict[str, Kind]) -> dict[str, tuple[str, Kind]]:
    return {name: (name, kind) for name, kind in kinds.items()}


def _utility(name: str, upper_xyz: bool) -> TableLayout:
    """A smokes or fires table: its window, where it burst, who threw it."""
    xyz: dict[str, tuple[str, Kind]] = {
        (a.upper() if upper_xyz else a): (a, "float") for a in "xyz"
    }
    thrower: dict[str, Kind] = {
        "thrower_name": "str",
        "thrower_steamid": "int",
        "thrower_side": "str",
    }
    columns = {**_same({"start_tick": "int", "end_tick": "int"}), **xyz, **_same(thrower)}
    return TableLayout(name, {**columns, "part": ("part", "int")}, ("start_tick", "end_tick", *xyz))


_EVENT_KILL: dict[str, Kind] = {
    "tick": "int",
    "weapon": "str",
    "headshot": "bool",
    "thrusmoke": "bool",
    "noscope": "bool",
    "penetrated": "int",
    "attackerblind": "bool",
    "distance": "float",
}
_TICK_COMMON: dict[str, Kind] = {
    "tick": "int",
    "name": "str",
    "steamid": "int",
    "side": "str",
    "health": "int",
    "yaw": "float",
    "pitch": "float",
    "armor": "int",
    "has_helmet": "bool",
    "has_defuser": "bool",
    "is_defusing": "bool",
}

AWPY2 = Layout(
    name="awpy 2",
    rounds=TableLayout(
        "rounds",
        _same(
            {
                "round_num": "int",
                "start": "int",
                "freeze_end": "int",
                "end": "int",
                "official_end": "int",
                "winner": "str",
                "reason": "str",
                "bomb_plant": "int",
                "bomb_site": "str",
            }
        ),
        ("round_num", "start", "freeze_end", "end", "winner", "reason"),
    ),
    ticks=TableLayout(
        "ticks",
        {
            **_same(_TICK_COMMON),
            "X": ("x", "float"),
            "Y": ("y", "float"),
            "Z": ("z", "float"),
            "armor_value": ("armor", "int"),
            "is_alive": ("is_alive", "bool"),
            "active_weapon_name": ("weapon", "str"),
            "velocity_Z": ("velocity_z", "float"),
            "inventory": ("inventory", "list"),
        },
        ("tick", "name", "side", "X", "Y", "Z", "health"),
    ),
    kills=TableLayout(
        "kills",
        {
            **_same(_EVENT_KILL | {"hitgroup": "str"}),
            **_player("attacker", True, view=True),
            **_player("victim", True, view=True),
            **_player("assister", True),
        },
        ("tick", "victim_name", "weapon"),
    ),
    damages=TableLayout(
        "damages",
        {
            **_same({"tick": "int", "weapon": "str", "dmg_health": "int", "dmg_armor": "int"}),
            "dmg_health_real": ("dmg_health_taken", "int"),
            "hitgroup": ("hitgroup", "str"),
            **_player("attacker", True, view=True),
            **_player("victim", True, view=True),
        },
        ("tick", "victim_name", "dmg_health"),
    ),
    bomb=TableLayout(
        "bomb",
        {
            **_same({"tick": "int", "event": "str", "name": "str", "steamid": "int"}),
            "X": ("x", "float"),
            "Y": ("y", "float"),
            "Z": ("z", "float"),
            "bombsite": ("site", "str"),
        },
        ("tick", "event"),
    ),
    smokes=_utility("smokes", True),
    fires=_utility("infernos", True),
    blinds=None,
    tick_weapons="display",
)

AWPY3 = Layout(
    name="awpy 3",
    rounds=TableLayout(
        "rounds",
        {
            "round_num": ("round_num", "int"),
            "start_tick": ("start", "int"),
            "freeze_end_tick": ("freeze_end", "int"),
            "end_tick": ("end", "int"),
            "official_end_tick": ("official_end", "int"),
            "winner": ("winner", "int"),
            "reason": ("reason", "int"),
        },
        ("round_num", "start_tick", "freeze_end_tick", "end_tick", "winner", "reason"),
    ),
    ticks=TableLayout(
        "snapshots",
        {
            **_same(_TICK_COMMON),
            "x": ("x", "float"),
            "y": ("y", "float"),
            "z": ("z", "float"),
            "has_bomb": ("has_bomb", "bool"),
            "active_weapon": ("weapon", "str"),
            "velocity_z": ("velocity_z", "float"),
            "part": ("part", "int"),
        },
        ("tick", "name", "side", "x", "y", "z", "health"),
    ),
    kills=TableLayout(
        "kills",
        {
            **_same(_EVENT_KILL),
            "hitgroup_name": ("hitgroup", "str"),
            **_player("attacker", False),
            **_player("victim", False),
            **_player("assister", False),
            "part": ("part", "int"),
        },
        ("tick", "victim_name", "weapon"),
    ),
    damages=TableLayout(
        "damages",
        {
            **_same(
                {
                    "tick": "int",
                    "weapon": "str",
                    "dmg_health": "int",
                    "dmg_armor": "int",
                    "health_pre": "int",
                    "health_post": "int",
                    "armor_pre": "int",
                    "armor_post": "int",
                }
            ),
            "hitgroup_name": ("hitgroup", "str"),
            **_player("attacker", False),
            **_player("victim", False),
            "part": ("part", "int"),
        },
        ("tick", "victim_name", "dmg_health"),
    ),
    bomb=TableLayout(
        "bomb",
        {
            **_same({"tick": "int", "event": "str", "name": "str", "steamid": "int"}),
            "x": ("x", "float"),
            "y": ("y", "float"),
            "z": ("z", "float"),
            "bombsite": ("site", "str"),
            "part": ("part", "int"),
        },
        ("tick", "event"),
    ),
    smokes=_utility("smokes", False),
    fires=_utility("fires", False),
    blinds=TableLayout(
        "blinds",
        {
            "tick": ("tick", "int"),
            "duration": ("duration", "float"),
            **_player("attacker", False),
            **_player("victim", False),
            "part": ("part", "int"),
        },
        ("tick", "duration", "victim_name"),
    ),
    tick_weapons="item",
)

LAYOUTS: dict[LayoutName, Layout] = {"awpy 2": AWPY2, "awpy 3": AWPY3}
