"""Reading the files decoy is given: regular files only, bounded in size; JSON bounded in depth,
its numbers finite and in range.

Every file a user can hand decoy or edit (a run's `summary.json`, a model folder's `dip.json`,
`dog.json`, `rules.json` and calibration, a match file) is anyone's file:

* `open_regular` opens a file only when it is a regular file: a FIFO named like a match would
  block `open` forever, a device would never end; a folder, a FIFO, a socket or a device is one
  error naming the file and what it is, and nothing is opened that is not a regular file (the
  open itself does not block: it checks the opened file again, so a file swapped in between
  fails the same way);
* `read_limited` reads at most a given number of bytes of it, `read_csv_table` a CSV table of
  at most a given size (with the columns named as text read as text);
* `load_json` and `parse_json` read JSON as Python's `json` does, but refuse a document nested
  deeper than `MAX_JSON_DEPTH` (which would end in a RecursionError), a number that is not
  finite (`NaN`, `Infinity` or one beyond the float range, which strict JSON, and decoy's own
  writer, never writes) and an integer beyond 64 bits, naming where in the document it is.

Each failure is one error of the caller's `DecoyError` class, naming the file.
"""

from __future__ import annotations

import json
import math
import os
import stat
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, BinaryIO, TypeAlias

from decoy_cli.errors import DecoyError
from decoy_cli.text import shortened, visible

if TYPE_CHECKING:
    import pandas as pd

JsonValue: TypeAlias = "str | int | float | bool | list[JsonValue] | dict[str, JsonValue] | None"
"""What a JSON file holds, as `json.loads` returns it."""

JsonObject: TypeAlias = "dict[str, JsonValue]"
"""A JSON object: what the outputs' JSON files are."""

MAX_JSON_MB = 64
"""Largest JSON file decoy reads besides match files (which have their own limit,
decoy_cli/esta/source.py): the largest it writes (a run's summary.json) holds a few kB a round."""

MAX_JSON_DEPTH = 64
"""Deepest nesting of arrays and objects a JSON file may have; decoy writes at most 5 levels."""

MAX_JSON_INT = 2**63
"""Integers in JSON must be smaller than this in magnitude (64 bits, what every reader of JSON
takes), so that none overflows a float or an array later."""

_KINDS = (
    (stat.S_ISDIR, "a folder"),
    (stat.S_ISFIFO, "a FIFO"),
    (stat.S_ISSOCK, "a socket"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
)


def _not_regular(path: Path, mode: int) -> str | None:
    """Why `path`, of `mode`, is not read: None for a regular file."""
    if stat.S_ISREG(mode):
        return None
    if stat.S_ISDIR(mode):
        return f"{path}: is a folder, not a file"
    kind = next((name for test, name in _KINDS if test(mode)), "not a file")
    return f"{path}: not a regular file ({kind})"


def open_regular(path: str | Path, error: type[DecoyError] = DecoyError) -> BinaryIO:
    """`path` opened for reading in binary, when it is a regular file (module doc); else
    `error` naming the file and what it is, or why it cannot be opened."""
    path = Path(path)
    try:
        why = _not_regular(path, os.stat(path).st_mode)
        if why is not None:
            raise error(why)
        flags = os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC | getattr(os, "O_NOCTTY", 0)
        fd = os.open(path, flags)
    except FileNotFoundError:
        raise error(f"{path}: no such file") from None
    except OSError as failure:
        raise error(f"{path}: cannot read the file ({failure.strerror or failure})") from None
    try:
        why = _not_regular(path, os.fstat(fd).st_mode)
        if why is not None:
            raise error(why)
        os.set_blocking(fd, True)
        return os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise


def read_limited(path: str | Path, limit: int, error: type[DecoyError] = DecoyError) -> bytes:
    """The bytes of the regular file `path`, at most `limit` of them; a larger file is an
    `error` saying so (nothing more than `limit` + 1 bytes is read)."""
    with open_regular(path, error) as handle:
        try:
            data = handle.read(limit + 1)
        except OSError as failure:
            raise error(f"{path}: cannot read the file ({failure.strerror or failure})") from None
    if len(data) > limit:
        raise error(f"{path}: larger than {limit / 1e6:g} MB, more than decoy reads of it")
    return data


def read_csv_table(
    path: str | Path,
    error: type[DecoyError] = DecoyError,
    *,
    limit_mb: float,
    text: Sequence[str] = (),
) -> pd.DataFrame:
    """The CSV table of the regular file `path` (at most `limit_mb` MB), the columns `text` read
    as text whatever they hold; a missing, unreadable or larger file is one `error` naming
    it."""
    path = Path(path)
    if not path.exists():
        raise error(f"{path}: not found (is {path.parent} an output folder of decoy?)")
    import pandas as pd

    with open_regular(path, error) as handle:
        if os.fstat(handle.fileno()).st_size > limit_mb * 1e6:
            raise error(f"{path}: larger than {limit_mb:g} MB, not a table decoy wrote")
        try:
            return pd.read_csv(handle, dtype=dict.fromkeys(text, "str"))
        except (pd.errors.ParserError, pd.errors.EmptyDataError, ValueError, OSError) as e:
            raise error(f"{path}: not a readable CSV ({str(e).splitlines()[0]})") from None


def load_json(
    path: str | Path, error: type[DecoyError] = DecoyError, *, limit_mb: float = MAX_JSON_MB
) -> JsonValue:
    """The JSON document of the regular file `path`, checked (module doc); any problem is one
    `error` naming the file."""
    return parse_json(read_limited(path, int(limit_mb * 1e6), error), str(path), error)


def parse_json(data: bytes | str, where: str, error: type[DecoyError] = DecoyError) -> JsonValue:
    """The JSON document `data` (UTF-8 when bytes), checked (module doc); any problem is one
    `error` beginning with `where`."""
    try:
        text = data.decode("utf-8") if isinstance(data, bytes) else data
        document = json.loads(
            text, parse_constant=_Refused.constant, parse_float=_float, parse_int=_int
        )
    except json.JSONDecodeError as failure:
        raise error(f"{where}: not readable JSON ({failure.msg}, line {failure.lineno})") from None
    except UnicodeDecodeError:
        raise error(f"{where}: not readable JSON (not UTF-8 text)") from None
    except RecursionError:
        raise error(f"{where}: JSON nested deeper than {MAX_JSON_DEPTH} levels") from None
    except ValueError as failure:  # an integer of more digits than Python converts
        first = str(failure).splitlines()[0] if str(failure) else "a bad value"
        raise error(f"{where}: not readable JSON ({first})") from None
    problem = _first_problem(document)
    if problem is not None:
        raise error(f"{where}: {problem}")
    return document


class _Refused:
    """A number `json` read that the document may not hold (module doc): where it stood."""

    def __init__(self, text: str, why: str) -> None:
        self.text = shortened(text, 24)
        self.why = why

    @classmethod
    def constant(cls, name: str) -> _Refused:
        return cls(name, "not a finite number (strict JSON has no NaN or Infinity)")


def _float(text: str) -> float | _Refused:
    value = float(text)
    if math.isfinite(value):
        return value
    return _Refused(text, "beyond the range of a float")


def _int(text: str) -> int | _Refused:
    value = int(text)
    if -MAX_JSON_INT < value < MAX_JSON_INT:
        return value
    return _Refused(text, "an integer beyond 64 bits")


def _first_problem(document: object) -> str | None:
    """A refused number (with its place in the document) or a nesting deeper than
    `MAX_JSON_DEPTH`, walking the document without recursion; None when there is neither."""
    if not isinstance(document, dict | list | _Refused):
        return None
    stack: list[tuple[object, tuple[str | int, ...]]] = [(document, ())]
    while stack:
        value, trail = stack.pop()
        if isinstance(value, _Refused):
            return f"{_place(trail)}: {value.text} is {value.why}"
        if len(trail) >= MAX_JSON_DEPTH:
            return f"JSON nested deeper than {MAX_JSON_DEPTH} levels"
        items = value.items() if isinstance(value, dict) else enumerate(value)  # type: ignore[arg-type]
        stack.extend(
            (child, (*trail, key))
            for key, child in items
            if isinstance(child, dict | list | _Refused)
        )
    return None


def _place(trail: tuple[str | int, ...]) -> str:
    """Where a value stands in a document: `bullets.counts.AK-47[3]`."""
    if not trail:
        return "the document"
    parts = [f"[{k}]" if isinstance(k, int) else f".{visible(shortened(k, 40))}" for k in trail]
    return "".join(parts).removeprefix(".")
