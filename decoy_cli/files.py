"""Writing output files safely: to a temporary file beside the target, then a rename; and the
one JSON writer (strict JSON: no bare NaN).

A crash, a full disk or an interrupt never leaves a half-written graph, mesh, table or picture
under the real name; every failure is one OutputError line. And the one CSV writer.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import shutil
import tempfile
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path

import numpy as np
import pandas as pd

from decoy_cli.errors import DecoyError, OutputError
from decoy_cli.reading import JsonObject, JsonValue, load_json  # the JSON types: read there
from decoy_cli.text import csv_inert


def write_atomic(path: str | Path, payload: bytes | Callable[[Path], None]) -> Path:
    """Write `payload` (bytes, or a function that writes the given temporary path) to `path`."""
    path = Path(path)
    fd, tmp = _temporary_beside(path, ".tmp")
    try:
        if callable(payload):
            os.close(fd)
            payload(tmp)
        else:
            with os.fdopen(fd, "wb") as out:
                out.write(payload)
        os.chmod(tmp, 0o644)  # mkstemp makes the file private; outputs are ordinary files
        os.replace(tmp, path)
    except OSError as error:
        tmp.unlink(missing_ok=True)
        raise OutputError(f"cannot write {path}: {error.strerror or error}") from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path


def write_csv(path: str | Path, frame: pd.DataFrame) -> Path:
    """Write `frame` as CSV, atomically, its text cells inert (`decoy_cli.text.csv_inert`: no
    formula a spreadsheet would run, no control character): the one CSV writer of every
    output."""
    return write_atomic(path, csv_inert(frame).to_csv(index=False).encode())


@contextlib.contextmanager
def staged(folder: str | Path) -> Iterator[Path]:
    """A staging folder inside `folder` for a set of files (and folders) that replace the
    previous ones together: written there, then moved into place by renames (which a full disk
    does not stop; a folder replaces the previous folder of its name whole). On any error while
    writing, the stage is removed and the previous files stay as they were; the error passes
    on."""
    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise OutputError(f"cannot create {folder}: {error.strerror or error}") from None
    stage = folder / f".staging-{os.getpid()}"
    shutil.rmtree(stage, ignore_errors=True)
    try:
        stage.mkdir()
        yield stage
    except BaseException:
        shutil.rmtree(stage, ignore_errors=True)
        raise
    try:
        for entry in sorted(stage.iterdir()):
            target = folder / entry.name
            if entry.is_dir() and target.is_dir() and not target.is_symlink():
                shutil.rmtree(target)
            os.replace(entry, target)
        stage.rmdir()
    except OSError as error:
        raise OutputError(
            f"cannot move the outputs into {folder}: {error.strerror or error}"
        ) from None


def json_ready(value: object) -> JsonValue:
    """`value` as strict JSON data: NaN and infinities as null (strict JSON has neither), numpy
    scalars and arrays as Python numbers and lists, paths as strings, tuples as lists."""
    if isinstance(value, np.ndarray):
        return json_ready(value.tolist())
    if isinstance(value, np.generic):
        return json_ready(value.item())
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {str(k): json_ready(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_ready(v) for v in value]
    if isinstance(value, Path):
        return str(value)
    if value is None or isinstance(value, str | int | float):
        return value
    raise TypeError(f"not JSON data: {type(value).__name__}")


def json_object(value: Mapping[str, object]) -> JsonObject:
    """`json_ready` of a mapping: a JSON object."""
    return {str(k): json_ready(v) for k, v in value.items()}


def object_at(data: JsonObject, key: str) -> JsonObject:
    """The JSON object under `key` of `data`; an empty one when there is none."""
    value = data.get(key)
    return value if isinstance(value, dict) else {}


def objects_in(value: JsonValue) -> list[JsonObject]:
    """The JSON objects in `value` when it is a list (none otherwise)."""
    return [item for item in value if isinstance(item, dict)] if isinstance(value, list) else []


def json_text(data: object, *, sort_keys: bool = True) -> str:
    """Pretty strict JSON of `data` (see `json_ready`), ending in a newline."""
    return json.dumps(json_ready(data), indent=2, sort_keys=sort_keys, allow_nan=False) + "\n"


def write_json(path: str | Path, data: object, *, sort_keys: bool = True) -> Path:
    """Write `data` as pretty strict JSON, atomically: the one JSON writer of every output."""
    return write_atomic(path, json_text(data, sort_keys=sort_keys).encode())


def read_json_object(path: Path, written_by: str) -> JsonObject:
    """The JSON object a command wrote to `path` (`written_by`: "`decoy replay`", ...), read
    through the checked loader (`decoy_cli.reading.load_json`: bounded size and depth, finite
    numbers); a missing, unreadable or other file is one DecoyError line saying so."""
    if not path.exists():
        raise DecoyError(f"{path}: not found (is {path.parent} a {written_by} output?)")
    data = load_json(path)
    if not isinstance(data, dict):
        raise DecoyError(f"{path}: not written by {written_by}")
    return data


def check_writable(path: str | Path) -> Path:
    """An OutputError now, before any long work, when `path` (a file to write later) cannot be
    written: its folder cannot be made, or a file cannot be created there."""
    path = Path(path)
    fd, tmp = _temporary_beside(path, ".check")
    os.close(fd)
    tmp.unlink(missing_ok=True)
    return path


def check_folder_writable(folder: str | Path) -> Path:
    """An OutputError now, before any long work, when files cannot be written in `folder`: it
    is a file, or it (or a missing parent) cannot be made, or a file cannot be created in it."""
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise OutputError(f"cannot write into {folder}: it is a file, not a folder")
    made = [part for part in (folder, *folder.parents) if not part.exists()]
    try:
        check_writable(folder / "check")
    finally:  # the check leaves no folder behind: a failing command writes nothing
        for part in made:
            with contextlib.suppress(OSError):
                part.rmdir()
    return folder


def _temporary_beside(path: Path, suffix: str) -> tuple[int, Path]:
    """A new private file in `path`'s folder (made if needed): (descriptor, its path)."""
    if path.is_dir():
        raise OutputError(f"cannot write {path}: it is a directory")
    parent = path.parent if str(path.parent) else Path(".")
    try:
        parent.mkdir(parents=True, exist_ok=True)
        fd, name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=suffix, dir=parent)
    except OSError as error:
        raise OutputError(f"cannot write {path}: {error.strerror or error}") from None
    return fd, Path(name)
