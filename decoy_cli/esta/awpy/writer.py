"""Write a match in awpy's layouts, an awpy 2 zip or a folder of awpy 3 tables, with awpy's
column names and types (parquet through pyarrow): CS2 tables of rounds the project has (the
synthetic sample) with what the real CS2 rounds lack (weapons, armour, the carrier, steamids,
bomb events with players, damages, full-rate ticks), for the tests and the reader's benchmark.

Names are awpy's (decoy_cli/esta/awpy/names.py): awpy 2 ticks spell weapons as demoparser2
shows them ("M4A1-S"), events and awpy 3 snapshots as the game's items ("m4a1_silencer"). Each
round's start lies 15 s of freeze time before its freeze end. `every` ticks between rows
interpolates positions between frames (full-rate tables); the other columns hold the frame's.
"""

from __future__ import annotations

import json
import zipfile
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.esta.awpy.names import WEAPON_SPELLINGS
from decoy_cli.esta.reader import Match, Round

DISPLAY = {esta: shown[0] for esta, (shown, _) in WEAPON_SPELLINGS.items() if shown}
ITEM = {esta: items[0] for esta, (_, items) in WEAPON_SPELLINGS.items() if items}
HIT_GROUPS = {
    "Generic": "generic",
    "Head": "head",
    "Chest": "chest",
    "Stomach": "stomach",
    "LeftArm": "left_arm",
    "RightArm": "right_arm",
    "LeftLeg": "left_leg",
    "RightLeg": "right_leg",
    "Neck": "neck",
}
HIT_GROUP_CODES = {name: code for code, name in enumerate(HIT_GROUPS.values())}
REASONS2 = {
    "TargetBombed": "bomb_exploded",
    "BombDefused": "bomb_defused",
    "CTWin": "t_killed",
    "TerroristsWin": "ct_killed",
    "TargetSaved": "time_ran_out",
}
REASONS3 = {"TargetBombed": 1, "BombDefused": 7, "CTWin": 8, "TerroristsWin": 9, "TargetSaved": 12}
REASON_NAMES3 = {1: "target_bombed", 7: "bomb_defused", 8: "ct_win", 9: "terrorists_win"}
REASON_NAMES3[12] = "target_saved"
BOMB2 = {"plant": "plant", "defuse": "defuse", "explode": "detonate"}
BOMB3 = {"plant_begin": "start_plant", "plant": "finish_plant", "defuse": "defuse"}
SIDE2 = {"T": "t", "CT": "ct"}
SIDE3 = {"T": "terrorist", "CT": "counter-terrorist"}
FREEZE_TICKS = 15 * 128
"""Ticks of freeze time before each round's freeze end in the written round windows."""


def _write(table: dict[str, pa.Array]) -> bytes:
    sink = pa.BufferOutputStream()
    pq.write_table(pa.table(table), sink, compression="zstd")
    return sink.getvalue().to_pybytes()


def _tick_rows(rounds: list[Round], *, every: int = 0) -> dict[str, np.ndarray]:
    """One row per player present per kept tick (each frame's, or with `every` one every
    `every` ticks from the round's start, freeze time included as awpy's tick tables hold it,
    positions interpolated between frames): the long form both layouts share."""
    out: dict[str, list[np.ndarray]] = {k: [] for k in ("tick", "player", "round", "frame")}
    xyz: list[np.ndarray] = []
    for r_index, round_ in enumerate(rounds):
        ticks = round_.frame_ticks
        if every:
            start = int(round_.clock.zero_tick) - FREEZE_TICKS if round_.clock else ticks[0]
            fine = np.arange(start, ticks[-1] + 1, every, dtype=np.int64)
            frame = np.clip(np.searchsorted(ticks, fine, side="right") - 1, 0, len(ticks) - 1)
        else:
            fine, frame = ticks, np.arange(len(ticks))
        for p in range(round_.num_players):
            present = round_.present[p, frame]
            where = np.flatnonzero(present)
            if every:
                position = np.stack(
                    [
                        np.interp(fine, ticks, round_.position[p, :, axis] / HAMMER_TO_M)
                        for axis in range(3)
                    ],
                    axis=1,
                )
            else:
                position = round_.position[p] / HAMMER_TO_M
            out["tick"].append(fine[where])
            out["player"].append(np.full(where.size, p))
            out["round"].append(np.full(where.size, r_index))
            out["frame"].append(frame[where])
            xyz.append(position[where])
    rows = {k: np.concatenate(v) for k, v in out.items()}
    rows["xyz"] = np.concatenate(xyz)
    order = np.lexsort((rows["player"], rows["tick"]))
    return {k: v[order] for k, v in rows.items()}


def _players_columns(rounds: list[Round], rows: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Per row: name, steamid, side, health, armour, flags, yaw, weapon (ESTA name)."""

    def take(field: str) -> np.ndarray:
        """The (player, frame) entry of each row's round's `field`, round by round (a row at a
        time in Python took seconds on a full-rate match)."""
        arrays = [np.asarray(getattr(round_, field)) for round_ in rounds]
        out = np.empty(len(rows["round"]), dtype=np.result_type(*arrays))
        for r_index, values in enumerate(arrays):
            mine = rows["round"] == r_index
            out[mine] = values[rows["player"][mine], rows["frame"][mine]]
        return out

    players = [[(pl.name, pl.steam_id, pl.side) for pl in r.players] for r in rounds]
    info = [players[r][p] for r, p in zip(rows["round"], rows["player"], strict=True)]
    defusing = np.zeros(len(rows["tick"]), dtype=bool)
    for r_index, round_ in enumerate(rounds):
        events = round_.bomb_events
        starts = events[events["bombAction"] == "defuse_start"]
        ends = events[events["bombAction"] == "defuse"]
        for start, end in zip(starts.itertuples(), ends.itertuples(), strict=False):
            p = next(i for i, pl in enumerate(round_.players) if pl.name == start.playerName)
            defusing |= (
                (rows["round"] == r_index)
                & (rows["player"] == p)
                & (rows["tick"] >= start.tick)
                & (rows["tick"] <= end.tick)
            )
    return {
        "is_defusing": defusing,
        "name": np.array([i[0] for i in info], dtype=object),
        "steamid": np.array([i[1] or 0 for i in info], dtype=np.uint64),
        "side": np.array([i[2] for i in info], dtype=object),
        "health": take("hp").astype(np.int32),
        "armor": take("armor").astype(np.int32),
        "has_helmet": take("helmet").astype(bool),
        "has_defuser": take("has_defuser").astype(bool),
        "has_bomb": take("has_bomb").astype(bool),
        "is_alive": take("alive").astype(bool),
        "yaw": take("yaw").astype(np.float32),
        "weapon": take("weapon").astype(object),
    }


def _event_players(
    round_: Round, table: str, who: str, sides: dict[str, str], upper: bool
) -> dict[str, list]:
    """An event table's columns of one player, awpy style (`who` the ESTA prefix, also awpy's)."""
    frame = getattr(round_, table)
    steam = frame[f"{who}SteamID"]
    columns: dict[str, list] = {
        f"{who}_name": [None if v is None or v != v else v for v in frame[f"{who}Name"]],
        f"{who}_steamid": [0 if v is None or v != v else int(v) for v in steam.astype(object)],
        f"{who}_side": [sides.get(v) if isinstance(v, str) else None for v in frame[f"{who}Side"]],
    }
    for axis in "XYZ":
        columns[f"{who}_{axis if upper else axis.lower()}"] = frame[f"{who}{axis}"].tolist()
    return columns


def _round_row(round_: Round, layout: int) -> dict[str, object]:
    """The round's row of awpy's rounds table; a round without a clock, an end, a winner or an
    end reason awpy would know cannot have one (ValueError)."""
    clock, end, winner, reason = (
        round_.clock,
        round_.end_tick,
        round_.winning_side,
        round_.end_reason,
    )
    if clock is None or end is None or winner is None or reason not in REASONS2:
        raise ValueError(f"round {round_.round_num}: no clock, end, winner or known end reason")
    freeze_end = int(clock.zero_tick)
    if layout == 2:
        site = next((str(s) for s in round_.bombsite if s), "")
        return {
            "round_num": round_.round_num,
            "start": freeze_end - FREEZE_TICKS,
            "freeze_end": freeze_end,
            "end": end,
            "official_end": end,
            "winner": SIDE2[winner],
            "reason": REASONS2[reason],
            "bomb_plant": round_.bomb_plant_tick,
            "bomb_site": f"bombsite_{site.lower()}" if site else "not_planted",
        }
    return {
        "round_num": round_.round_num,
        "start_tick": freeze_end - FREEZE_TICKS,
        "freeze_end_tick": freeze_end,
        "end_tick": end,
        "official_end_tick": end,
        "winner": 2 if winner == "T" else 3,
        "winner_side": SIDE3[winner],
        "reason": REASONS3[reason],
        "reason_name": REASON_NAMES3[REASONS3[reason]],
    }


def _rounds_and_events(match: Match, layout: int) -> dict[str, bytes]:
    """The rounds, kills, damages and bomb tables of one layout (2 or 3)."""
    rounds = match.rounds
    upper = layout == 2
    side = SIDE2 if layout == 2 else SIDE3
    tables: dict[str, dict[str, list]] = {"kills": {}, "damages": {}, "bomb": {}}
    round_rows: dict[str, list] = {}
    for round_ in rounds:
        row = _round_row(round_, layout)
        for key, value in row.items():
            round_rows.setdefault(key, []).append(value)
        kills, damages, bomb = round_.kills, round_.damages, round_.bomb_events
        for name, frame in (("kills", kills), ("damages", damages)):
            table = tables[name]
            for who in ("attacker", "victim"):
                for key, column in _event_players(round_, name, who, side, upper).items():
                    table.setdefault(key, []).extend(column)
            table.setdefault("tick", []).extend(frame["tick"].astype(int).tolist())
            table.setdefault("weapon", []).extend(ITEM.get(w, w) for w in frame["weapon"])
            if layout == 2:
                table.setdefault("round_num", []).extend([round_.round_num] * len(frame))
        tables["kills"].setdefault("headshot", []).extend(bool(h) for h in kills["isHeadshot"])
        groups = [HIT_GROUPS[g] for g in damages["hitGroup"]]
        if layout == 2:
            tables["damages"].setdefault("hitgroup", []).extend(groups)
            tables["damages"].setdefault("dmg_health", []).extend(damages["hpDamage"].astype(int))
            tables["damages"].setdefault("dmg_health_real", []).extend(
                damages["hpDamageTaken"].astype(int)
            )
            tables["damages"].setdefault("dmg_armor", []).extend(damages["armorDamage"].astype(int))
        else:
            tables["damages"].setdefault("hitgroup", []).extend(HIT_GROUP_CODES[g] for g in groups)
            tables["damages"].setdefault("hitgroup_name", []).extend(groups)
            tables["damages"].setdefault("dmg_health", []).extend(damages["hpDamage"].astype(int))
            taken = damages["hpDamageTaken"].astype(int).to_numpy()
            tables["damages"].setdefault("health_pre", []).extend([100] * len(taken))
            tables["damages"].setdefault("health_post", []).extend((100 - taken).tolist())
            tables["damages"].setdefault("dmg_armor", []).extend(damages["armorDamage"].astype(int))
        events = BOMB2 if layout == 2 else BOMB3
        for event in bomb.itertuples():
            if event.bombAction not in events:
                continue
            table = tables["bomb"]
            table.setdefault("tick", []).append(int(event.tick))
            table.setdefault("event", []).append(events[event.bombAction])
            table.setdefault("name", []).append(event.playerName)
            table.setdefault("steamid", []).append(int(event.playerSteamID))
            for axis in "XYZ":
                key = axis if upper else axis.lower()
                table.setdefault(key, []).append(float(getattr(event, f"player{axis}")))
            site = event.bombSite or ""
            table.setdefault("bombsite", []).append(
                (f"Bombsite{site}" if layout == 2 else site) if site else None
            )
            if layout == 2:
                table.setdefault("round_num", []).append(round_.round_num)
    out = {"rounds": _write({k: pa.array(v) for k, v in round_rows.items()})}
    for name, columns in tables.items():
        typed = {}
        for key, values in columns.items():
            kind = pa.int32() if key in ("tick", "health_pre", "health_post") else None
            if key.endswith(("_x", "_y", "_z", "_X", "_Y", "_Z")) or key in "XYZxyz":
                kind = pa.float32()
            if key.endswith("steamid"):
                kind = pa.uint64()
            typed[key] = pa.array([_plain(v) for v in values], kind)
        out[name] = _write(typed)
    return out


def _plain(value: object) -> object:
    return value.item() if isinstance(value, np.generic) else value


def _utility(match: Match, layout: int) -> dict[str, bytes]:
    """The smokes and fires tables (`infernos` in awpy 2), and awpy 3's blinds."""
    upper = layout == 2
    sides = SIDE2 if upper else SIDE3
    out = {}
    for name, field in (("smokes", "smokes"), ("infernos" if upper else "fires", "fires")):
        rows = pd.concat([getattr(r, field) for r in match.rounds], ignore_index=True)
        table = {
            "start_tick": pa.array(rows["start_tick"].astype("int64"), pa.int64()),
            "end_tick": pa.array(rows["end_tick"].astype("Int64"), pa.int64()),
            **{
                (a.upper() if upper else a): pa.array(rows[f"{a}_m"] / HAMMER_TO_M, pa.float64())
                for a in "xyz"
            },
            "thrower_name": pa.array(rows["thrower_name"].astype(object), pa.large_string()),
            "thrower_side": pa.array(
                [sides.get(s) for s in rows["thrower_side"]], pa.large_string()
            ),
            "thrower_steamid": pa.array(rows["thrower_steamid"].astype("Int64"), pa.uint64()),
        }
        out[name] = _write(table)
    if not upper:
        flashes = pd.concat([r.flashes for r in match.rounds], ignore_index=True)
        table = {"tick": pa.array(flashes["tick"].astype("int64"), pa.int32())}
        for who, esta in (("attacker", "attacker"), ("victim", "player")):
            table[f"{who}_name"] = pa.array(
                flashes[f"{esta}Name"].astype(object), pa.large_string()
            )
            table[f"{who}_side"] = pa.array(
                [sides.get(s) for s in flashes[f"{esta}Side"]], pa.large_string()
            )
            for axis in "xyz":
                table[f"{who}_{axis}"] = pa.array(flashes[f"{esta}{axis.upper()}"], pa.float32())
        table["duration"] = pa.array(flashes["flashDuration"], pa.float32())
        out["blinds"] = _write(table)
    return out


def _tick_columns(match: Match, every: int, layout: int) -> dict[str, pa.Array]:
    """The tick table of a layout (2: awpy 2's `ticks`; 3: awpy 3's `snapshots`)."""
    rows = _tick_rows(match.rounds, every=every)
    cols = _players_columns(match.rounds, rows)
    upper, sides = (True, SIDE2) if layout == 2 else (False, SIDE3)
    table: dict[str, pa.Array] = {
        "tick": pa.array(rows["tick"], pa.int32()),
        "steamid": pa.array(cols["steamid"], pa.uint64()),
        "name": pa.array(cols["name"], pa.large_string()),
        "side": pa.array([sides[s] for s in cols["side"]], pa.large_string()),
        **{
            (axis.upper() if upper else axis): pa.array(rows["xyz"][:, k], pa.float32())
            for k, axis in enumerate("xyz")
        },
        "yaw": pa.array(cols["yaw"], pa.float32()),
        "health": pa.array(cols["health"], pa.int32()),
        "armor": pa.array(cols["armor"], pa.int32()),
        "has_helmet": pa.array(cols["has_helmet"]),
        "has_defuser": pa.array(cols["has_defuser"]),
    }
    if layout == 2:
        table["round_num"] = pa.array(
            [match.rounds[r].round_num for r in rows["round"]], pa.uint32()
        )
        table["is_alive"] = pa.array(cols["is_alive"])
        table["active_weapon_name"] = pa.array(
            [DISPLAY.get(w) if w else None for w in cols["weapon"]], pa.large_string()
        )
        table["inventory"] = pa.array(
            [
                ([DISPLAY[w]] if w else []) + ["C4 Explosive"] * int(bomb)
                for w, bomb in zip(cols["weapon"], cols["has_bomb"], strict=True)
            ],
            pa.list_(pa.large_string()),
        )
    else:
        table["pitch"] = pa.array(np.zeros(len(rows["tick"])), pa.float32())
        table["has_bomb"] = pa.array(cols["has_bomb"])
        table["is_defusing"] = pa.array(cols["is_defusing"])
        table["active_weapon"] = pa.array(
            [ITEM.get(w) if w else None for w in cols["weapon"]], pa.large_string()
        )
    return table


def write_awpy2_zip(match: Match, path: Path, *, every: int = 0) -> Path:
    """The match as `awpy parse --player-props` writes it (a zip of parquet tables)."""
    tables = {
        "ticks": _write(_tick_columns(match, every, 2)),
        **_rounds_and_events(match, 2),
        **_utility(match, 2),
    }
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        for name, data in tables.items():
            archive.writestr(f"{name}.parquet", data)
        archive.writestr("header.json", json.dumps({"map_name": match.map_name}))
    return path


def write_awpy3_folder(match: Match, folder: Path, *, every: int = 0) -> Path:
    """The match as awpy 3's datasets in this project's folder of tables."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "snapshots.parquet").write_bytes(_write(_tick_columns(match, every, 3)))
    for name, data in {**_rounds_and_events(match, 3), **_utility(match, 3)}.items():
        (folder / f"{name}.parquet").write_bytes(data)
    header = {"map_name": match.map_name, "playback_ticks": match.tick_rate * 100}
    header["playback_time"] = 100.0
    (folder / "header.json").write_text(json.dumps(header))
    return folder
