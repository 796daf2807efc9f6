"""Read ESTA match files (awpy 1.x JSON, `.json.xz` or `.json`) into rounds of numpy arrays.

Units: positions are converted from Hammer units to metres here, once (x east, y north, z up);
yaw stays in degrees (awpy `viewX`: 0 = +x, counter-clockwise); time is seconds since freeze-time
end. Event tables keep awpy's Hammer columns and add metre columns (see decoy_cli/esta/events.py).

Tolerated, because real files have them: nulls anywhere, ints written as floats, unknown keys
(ignored), players missing from some frames or in a different order in each frame (they are keyed
by steamID, else name), fewer than five players on a side, an empty side, rounds without frames.
A null round number falls back to the round's position in `gameRounds` (1-based), a null
matchID to the file name, a null mapName to "".

Errors are EstaError with one line naming the file. Where a problem lies decides what fails:
* file level -> `read_match` raises: unreadable, corrupt or truncated xz, invalid JSON, not an
  ESTA match (not an object, no `gameRounds` list, a bad `tickRate`, `mapName` or `matchID`),
  two rounds with the same number;
* round level -> only that round fails: a wrong type inside it, a frame without a tick, ticks
  going backwards, a NaN or off-map position (named by round, frame and player), an unknown
  weapon, a player twice in one frame. `read_match` still returns the match: the round is left
  out of `Match.rounds`, its error is kept in `Match.round_errors`, and `Match.round(num)` raises
  it, so a batch over many rounds can record per-round failures and go on.
All rounds are built when the match is read (`decoy bench --sections reader` measures how fast),
so the decoded JSON is dropped at once and errors show up front. JSON is decoded with msgspec
straight into typed structs (decoy_cli/esta/schema.py): faster than orjson into dicts
(benchmarks/studies/json_decoders.py), and its type errors carry the JSON path.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import cast

import numpy as np
import pandas as pd

from decoy_cli.errors import EstaError
from decoy_cli.esta.awpy.tables import is_awpy_source
from decoy_cli.esta.events import build_table
from decoy_cli.esta.frames import FrameArrays, PlayerInfo, RoundClock, Side, build_frames
from decoy_cli.esta.plausibility import Implausible, check_frames, round_order_problems
from decoy_cli.esta.schema import (
    BOMB_EVENT_COLUMNS,
    DAMAGE_COLUMNS,
    FLASH_COLUMNS,
    KILL_COLUMNS,
    Invalid,
    RoundState,
)
from decoy_cli.esta.source import decode_round, parse, read_bytes, round_number_hint
from decoy_cli.files import JsonObject, JsonValue

MAX_MATCH_PLAYER_FRAMES = 4_000_000
"""Most player-frames (players × frames, summed over rounds) a match file may hold: about 140
times the most in a real file in ../shared/data (28,365, T side only; twice that with both
teams). With the per-round limits of decoy_cli/esta/frames.py it bounds the memory a hostile
file can take."""

UTILITY_COLUMNS = (
    "start_tick",
    "end_tick",
    "start_s",
    "end_s",
    "x_m",
    "y_m",
    "z_m",
    "thrower_name",
    "thrower_side",
    "thrower_steamid",
)
"""A smoke's or fire's row: ticks (`end_tick` NaN where the data shows no end), seconds on the
round's clock, where it burst in metres, and who threw it."""


def empty_utility() -> pd.DataFrame:
    """A smokes or fires table without rows."""
    return pd.DataFrame({column: pd.Series(dtype=_UTILITY_DTYPES.get(column, "float64"))
                         for column in UTILITY_COLUMNS})  # fmt: skip


_UTILITY_DTYPES = {"thrower_name": "object", "thrower_side": "object", "thrower_steamid": "Int64"}


MATCH_SUFFIXES = (".json.xz", ".json", ".zip", ".dem")
"""File names `iter_match_files` picks up in a folder: ESTA files, awpy 2 zips and demos (a
folder of awpy 3 tables is picked up by its `header.json`)."""


@dataclass(frozen=True, eq=False)
class Round:
    """One round as arrays: P players (T first, then CT) by F frames, positions in metres.

    Per-player arrays have shape (P, F): `position` (P, F, 3) metres and `yaw` degrees (NaN where
    absent), `hp` and `armor` int16 (-1 where absent or null), `helmet`, `has_defuser`, `alive`,
    `present`, `has_bomb` bool (False where absent), `weapon` str ("" where none or absent).
    Per-frame: `frame_ticks` int64, `frame_seconds` float64 (the game's clock: seconds since
    freeze-time end counted in ticks at `tick_rate`, `clock`; events' `seconds` are on the same
    clock when the round has one), `bomb_position` (F, 3) metres (NaN
    when null), `bomb_planted` bool, `bombsite` str. Events: `damages`, `kills`, `bomb_events`,
    `flashes` (attacker = the thrower, player = the flashed player).
    `start_tick`/`end_tick` fall back to the first/last frame tick when null (None if no frames).
    """

    match_id: str
    path: Path
    round_num: int
    map_name: str
    tick_rate: int
    frame_ticks: np.ndarray
    frame_seconds: np.ndarray
    players: list[PlayerInfo]
    position: np.ndarray
    yaw: np.ndarray
    hp: np.ndarray
    armor: np.ndarray
    helmet: np.ndarray
    has_defuser: np.ndarray
    weapon: np.ndarray
    alive: np.ndarray
    present: np.ndarray
    has_bomb: np.ndarray
    vertical_speed: np.ndarray
    """(P, F) float64 awpy's `velocityZ` in m/s: 0 on the ground, NaN where absent or null."""
    bomb_position: np.ndarray
    bomb_planted: np.ndarray
    bombsite: np.ndarray
    damages: pd.DataFrame
    kills: pd.DataFrame
    bomb_events: pd.DataFrame
    flashes: pd.DataFrame
    winning_side: Side | None
    end_reason: str | None
    bomb_plant_tick: int | None
    start_tick: int | None
    end_tick: int | None
    clock: RoundClock | None = None
    """None only for a round without frames whose file gives neither `freezeTimeEndTick` nor
    `startTick`."""
    warnings: tuple[str, ...] = ()
    """Implausible data kept under the "warn" policy (decoy_cli/esta/plausibility.py)."""
    buy_types: dict[str, str] = field(default_factory=dict)
    """awpy's buy type of each side that has one ("Full Eco", "Semi Eco", "Semi Buy",
    "Full Buy"), from `tBuyType` and `ctBuyType`; what armour a side could afford."""
    source: str = "ESTA"
    """The data the round was read from: "ESTA" (awpy 1.x JSON), "awpy 2" or "awpy 3"."""
    not_recorded: tuple[str, ...] = ()
    """What awpy's tables do not record for this round (decoy_cli/esta/awpy/rounds.py): held
    as absent, and filled by the replay's rules where the game needs it."""
    smokes: pd.DataFrame = field(default_factory=lambda: empty_utility())
    """Smokes from detonation to expiry (`UTILITY_COLUMNS`; awpy's tables, none in ESTA's)."""
    fires: pd.DataFrame = field(default_factory=lambda: empty_utility())
    """Fires (molotov, incendiary) from their first to their last flame, as `smokes`."""

    @property
    def num_frames(self) -> int:
        """F, the number of frames."""
        return int(self.frame_ticks.shape[0])

    @property
    def num_players(self) -> int:
        """P, the number of players seen in any frame."""
        return len(self.players)

    def side_indices(self, side: Side) -> np.ndarray:
        """Row indices of the players of one side ("T" or "CT"), in row order."""
        if side not in ("T", "CT"):
            raise ValueError(f"side must be 'T' or 'CT', not {side!r}")
        return np.array([i for i, p in enumerate(self.players) if p.side == side], dtype=np.int64)


@dataclass(frozen=True, eq=False)
class Match:
    """One match file: metadata, the rounds that could be built, and the errors of the others.

    `meta` holds every top-level key except matchID, mapName, tickRate and gameRounds (e.g.
    clientName, parserParameters, serverVars, provenance).
    """

    match_id: str
    path: Path
    map_name: str
    tick_rate: int
    meta: JsonObject
    rounds: list[Round]
    round_errors: dict[int, EstaError] = field(default_factory=dict)

    @property
    def round_numbers(self) -> list[int]:
        """Every round number in the file, built or failed, ascending."""
        return sorted([r.round_num for r in self.rounds] + list(self.round_errors))

    def round(self, num: int) -> Round:
        """The round numbered `num`; its own error if it failed, or one naming the range."""
        for candidate in self.rounds:
            if candidate.round_num == num:
                return candidate
        if num in self.round_errors:
            raise self.round_errors[num]
        raise EstaError(f"{self.path}: no round {num} ({_describe_numbers(self.round_numbers)})")


def read_match(
    path: str | Path, *, implausible: Implausible = "fail", rate: float | None = None
) -> Match:
    """Read and validate one match: an ESTA file, or awpy's tables (an awpy 2 zip, a folder of
    awpy 3 tables, a demo: decoy_cli/esta/awpy/reader.py, `rate` frames a second from full-rate
    ticks, its default when None); file-level problems raise EstaError (module doc).
    `implausible` says whether a round with implausible data fails or keeps warnings
    (decoy_cli/esta/plausibility.py)."""
    path = Path(path)
    if is_awpy_source(path):
        from decoy_cli.esta.awpy.reader import read_awpy_match
        from decoy_cli.esta.awpy.rounds import DEFAULT_RATE

        return read_awpy_match(
            path, rate=DEFAULT_RATE if rate is None else rate, implausible=implausible
        )
    document = parse(path, read_bytes(path))
    top = document.top
    tick_rate = _tick_rate(path, top.get("tickRate"))
    map_name = top.get("mapName")
    if map_name is not None and not isinstance(map_name, str):
        raise EstaError(f"{path}: not an ESTA match file (mapName {map_name!r} is not a string)")
    match_id = _match_id(path, top.get("matchID"))
    meta = {k: v for k, v in top.items() if k not in ("matchID", "mapName", "tickRate")}
    rounds: list[Round] = []
    errors: dict[int, EstaError] = {}
    position_of: dict[int, int] = {}
    player_frames = 0
    for i, source in enumerate(document.rounds):
        try:
            state = decode_round(source)
            num = _round_number(state.roundNum, i)
        except Invalid as problem:
            num = _round_number_or_position(round_number_hint(source), i)
            _claim(path, position_of, num, i)
            errors[num] = EstaError(f"{path}: round {num}: {problem}")
            continue
        _claim(path, position_of, num, i)
        try:
            rounds.append(
                _build_round(
                    state,
                    num,
                    match_id=match_id,
                    path=path,
                    map_name=map_name or "",
                    tick_rate=tick_rate,
                    implausible=implausible,
                )
            )
        except Invalid as problem:
            errors[num] = EstaError(f"{path}: round {num}: {problem}")
            continue
        player_frames += rounds[-1].num_players * rounds[-1].num_frames
        if player_frames > MAX_MATCH_PLAYER_FRAMES:
            raise EstaError(
                f"{path}: more than {MAX_MATCH_PLAYER_FRAMES:,} player-frames by round {num} "
                "(not a real match; the limit bounds the reader's memory)"
            )
    rounds = _in_clock_order(path, sorted(rounds, key=lambda r: r.round_num), errors, implausible)
    return Match(
        match_id=match_id,
        path=path,
        map_name=map_name or "",
        tick_rate=tick_rate,
        meta=meta,
        rounds=rounds,
        round_errors=dict(sorted(errors.items())),
    )


def parse_round_address(address: str) -> tuple[Path, int]:
    """Split "FILE:ROUND" at the last colon; ROUND must be a non-negative integer."""
    file, colon, number = address.rpartition(":")
    if not colon or not file or not (number.isascii() and number.isdigit()):
        raise EstaError(
            f"{address}: not a round address (expected FILE:ROUND, e.g. match.json.xz:3)"
        )
    return Path(file), int(number)


def iter_match_files(path: str | Path) -> list[Path]:
    """The match file itself, or the `.json.xz` and `.json` entries of a folder, sorted. An entry
    with a match-file name that is not a readable file (a dangling or looping link) is listed
    too, so that reading it fails with its reason instead of vanishing."""
    path = Path(path)
    if path.is_file() or is_awpy_source(path):
        return [path]
    if not path.is_dir():
        raise EstaError(f"{path}: no such file or folder")
    files = sorted(
        p
        for p in path.iterdir()
        if (p.name.endswith(MATCH_SUFFIXES) and not p.is_dir()) or is_awpy_source(p)
    )
    if not files:
        raise EstaError(
            f"{path}: no match files in this folder (.json.xz, .json, awpy's .zip or .dem, or "
            "folders of awpy 3 tables)"
        )
    return files


def load_round(
    address: str, *, implausible: Implausible = "fail", rate: float | None = None
) -> Round:
    """The round at "FILE:ROUND" (reads the whole file: for many rounds, read_match once)."""
    file, num = parse_round_address(address)
    return read_match(file, implausible=implausible, rate=rate).round(num)


def _build_round(
    state: RoundState,
    num: int,
    *,
    match_id: str,
    path: Path,
    map_name: str,
    tick_rate: int,
    implausible: Implausible,
) -> Round:
    """One decoded round as arrays and tables; a problem raises Invalid."""
    start_tick = _optional_int(state.startTick, "startTick")
    end_tick = _optional_int(state.endTick, "endTick")
    arrays = build_frames(
        state.frames or [],
        tick_rate,
        _optional_int(state.freezeTimeEndTick, "freezeTimeEndTick"),
        start_tick,
    )
    warnings = check_frames(arrays, implausible)
    ticks = arrays.ticks
    clock = arrays.clock
    if ticks.size:
        start_tick = int(ticks[0]) if start_tick is None else start_tick
        end_tick = int(ticks[-1]) if end_tick is None else end_tick
    winning_side = state.winningSide or None
    if winning_side not in (None, "T", "CT"):
        raise Invalid(f"winningSide {winning_side!r} is not T or CT")
    winner = cast("Side | None", winning_side)  # checked just above
    return round_from_frames(
        arrays,
        match_id=match_id,
        path=path,
        round_num=num,
        map_name=map_name,
        tick_rate=tick_rate,
        damages=build_table("damages", state.damages, DAMAGE_COLUMNS, ticks, clock),
        kills=build_table("kills", state.kills, KILL_COLUMNS, ticks, clock),
        bomb_events=build_table("bomb_events", state.bombEvents, BOMB_EVENT_COLUMNS, ticks, clock),
        flashes=build_table("flashes", state.flashes, FLASH_COLUMNS, ticks, clock),
        winning_side=winner,
        end_reason=state.roundEndReason or None,
        bomb_plant_tick=_optional_int(state.bombPlantTick, "bombPlantTick"),
        start_tick=start_tick,
        end_tick=end_tick,
        clock=clock,
        warnings=warnings,
        buy_types={
            side: value
            for side, value in (("T", state.tBuyType), ("CT", state.ctBuyType))
            if isinstance(value, str) and value
        },
    )


def round_from_frames(frames: FrameArrays, **fields: object) -> Round:
    """A `Round` of the frames' arrays (ticks, seconds, players, and every per-player and
    per-frame array) and the other `fields` (the round's facts and events)."""
    return Round(
        frame_ticks=frames.ticks,
        frame_seconds=frames.seconds,
        players=frames.players,
        position=frames.position,
        yaw=frames.yaw,
        hp=frames.hp,
        armor=frames.armor,
        helmet=frames.helmet,
        has_defuser=frames.has_defuser,
        weapon=frames.weapon,
        alive=frames.alive,
        present=frames.present,
        has_bomb=frames.has_bomb,
        vertical_speed=frames.vertical_speed,
        bomb_position=frames.bomb_position,
        bomb_planted=frames.bomb_planted,
        bombsite=frames.bombsite,
        **fields,  # type: ignore[arg-type]
    )


def _in_clock_order(
    path: Path, rounds: list[Round], errors: dict[int, EstaError], implausible: Implausible
) -> list[Round]:
    """`rounds` less those that start before the round before them ended (their failure goes
    into `errors`), or with that as a warning under "warn" (plausibility.round_order_problems)."""
    spans = [
        (r.round_num, r.start_tick, r.end_tick)
        for r in rounds
        if r.start_tick is not None and r.end_tick is not None
    ]
    problems = round_order_problems(spans)
    if not problems:
        return rounds
    kept = []
    for round_ in rounds:
        problem = problems.get(round_.round_num)
        if problem is None:
            kept.append(round_)
        elif implausible == "warn":
            kept.append(replace(round_, warnings=(*round_.warnings, problem)))
        else:
            errors[round_.round_num] = EstaError(f"{path}: round {round_.round_num}: {problem}")
    return kept


def _optional_int(value: float | None, name: str) -> int | None:
    """An integral number as int; None stays None; anything else raises Invalid."""
    if value is None:
        return None
    if not (math.isfinite(value) and value == round(value) and abs(value) < 2.0**53):
        raise Invalid(f"{name} {value!r} is not an integer")
    return int(value)


def _round_number(value: float | None, position: int) -> int:
    """`roundNum`, or the 1-based position in gameRounds when null."""
    num = _optional_int(value, "roundNum")
    if num is None:
        return position + 1
    if num < 0:
        raise Invalid(f"roundNum {num} is negative")
    return num


def _round_number_or_position(value: float | None, position: int) -> int:
    """Like `_round_number`, but the position when `roundNum` itself is bad."""
    try:
        return _round_number(value, position)
    except Invalid:
        return position + 1


def _claim(path: Path, position_of: dict[int, int], num: int, position: int) -> None:
    """Record that gameRounds[position] is round `num`; a second claim is a file-level error."""
    if num in position_of:
        raise EstaError(
            f"{path}: round {num} appears twice (gameRounds[{position_of[num]}] and [{position}])"
        )
    position_of[num] = position


def _tick_rate(path: Path, value: JsonValue) -> int:
    """`tickRate` as a positive int (128 or 64 in ESTA)."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise EstaError(f"{path}: not an ESTA match file (tickRate {value!r} is not a number)")
    if not (math.isfinite(value) and value == round(value) and 0 < value < 100_000):
        raise EstaError(f"{path}: tickRate {value!r} is not a positive integer")
    return int(value)


def _match_id(path: Path, value: JsonValue) -> str:
    """`matchID` as a string; the file name without its suffixes when null or empty."""
    if value is None or value == "":
        name = path.name
        for suffix in MATCH_SUFFIXES:
            name = name.removesuffix(suffix)
        return name
    if isinstance(value, bool) or not isinstance(value, str | int):
        raise EstaError(f"{path}: not an ESTA match file (matchID {value!r} is not a string)")
    return str(value)


def _describe_numbers(numbers: list[int]) -> str:
    """'rounds 1-28', 'rounds 1, 3, 7' or 'the file has no rounds'."""
    if not numbers:
        return "the file has no rounds"
    if numbers == list(range(numbers[0], numbers[-1] + 1)):
        return f"rounds {numbers[0]}-{numbers[-1]}"
    return "rounds " + ", ".join(map(str, numbers))
