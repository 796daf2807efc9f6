"""awpy's tables on disk, read column by column: an awpy 2 zip, a folder of awpy 3 tables, or a
demo parsed by awpy 3 (installed with the `cs2` extra).

Only the columns the reader uses are read, by name (awpy 2 orders its prop columns differently
from run to run), with pyarrow, and each is checked to hold the kind of value it should (a
number, text, a flag); strings arrive dictionary-encoded, so a full-rate tick table of millions
of rows takes a few bytes a cell. A source that cannot be read is one EstaError naming the file
and, where it lies there, the table and the column: a zip or folder without a table, a file that
is not parquet, a column of the wrong type, more data than the reader's limit.
"""

from __future__ import annotations

import io
import json
import zipfile
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import pyarrow as pa
import pyarrow.parquet as pq

from decoy_cli.errors import EstaError
from decoy_cli.esta.source import max_match_bytes
from decoy_cli.files import JsonObject

Kind = Literal["int", "float", "str", "bool", "list"]
"""What a column holds; integers may arrive as floats where awpy writes nulls."""

HEADER = "header.json"
DEMO_SUFFIX = ".dem"
ZIP_SUFFIX = ".zip"
MAX_HEADER_BYTES = 1 << 20
"""Largest `header.json` read: a real one holds a dozen short keys."""

_CHECKS: dict[Kind, Callable[[pa.DataType], bool]] = {
    "int": lambda t: pa.types.is_integer(t) or pa.types.is_floating(t) or pa.types.is_null(t),
    "float": lambda t: pa.types.is_integer(t) or pa.types.is_floating(t) or pa.types.is_null(t),
    "str": lambda t: (
        pa.types.is_string(t)
        or pa.types.is_large_string(t)
        or pa.types.is_null(t)
        or (pa.types.is_dictionary(t) and pa.types.is_string(t.value_type))
    ),
    "bool": lambda t: pa.types.is_boolean(t) or pa.types.is_null(t),
    "list": lambda t: (
        (
            (pa.types.is_list(t) or pa.types.is_large_list(t))
            and (pa.types.is_string(t.value_type) or pa.types.is_large_string(t.value_type))
        )
        or pa.types.is_null(t)
    ),
}


@dataclass(frozen=True, eq=False)
class TableSource:
    """Where a source's tables are and how to open each: `open_table(name)` gives a parquet
    file's bytes (or an Arrow table for a demo) and None for a table the source does not hold."""

    path: Path
    layout: Literal["awpy 2", "awpy 3"]
    header: JsonObject
    open_table: Callable[[str], pa.Table | bytes | Path | None]


def is_awpy_source(path: Path) -> bool:
    """Whether `path` names awpy data: a `.zip`, a `.dem`, or a folder holding `header.json`
    beside parquet files."""
    if path.suffix.lower() in (ZIP_SUFFIX, DEMO_SUFFIX):
        return True
    return path.is_dir() and (path / HEADER).is_file()


def open_source(path: Path, rate: float) -> TableSource:
    """The tables of an awpy 2 zip, an awpy 3 folder or a demo (whose snapshots are taken at
    `rate` frames a second); an unreadable one raises."""
    if path.is_dir():
        return _folder(path)
    if not path.is_file():
        raise EstaError(f"{path}: not a regular file")
    if path.suffix.lower() == DEMO_SUFFIX:
        from decoy_cli.esta.awpy.demo import demo_source

        return demo_source(path, rate)
    return _zip(path)


def read_table(
    source: TableSource, table: str, columns: Mapping[str, Kind], required: tuple[str, ...]
) -> pa.Table:
    """The columns of `table` the source has (all of `required`, or EstaError), type-checked."""
    where = f"{source.path}: {table}"
    found = source.open_table(table)
    if found is None:
        raise EstaError(f"{source.path}: no {table} table (awpy writes one; is this awpy data?)")
    try:
        if isinstance(found, pa.Table):
            schema = found.schema
            names = [c for c in columns if c in schema.names]
            data = found.select(names)
        else:
            handle = pq.ParquetFile(io.BytesIO(found) if isinstance(found, bytes) else found)
            schema = handle.schema_arrow
            names = [c for c in columns if c in schema.names]
            data = handle.read(columns=names, use_threads=False)
    except (pa.ArrowException, OSError, ValueError) as error:
        raise EstaError(f"{where}: not a readable parquet table ({error})") from None
    missing = [c for c in required if c not in names]
    if missing:
        raise EstaError(f"{where}: no column {', '.join(missing)}")
    for name in names:
        kind = columns[name]
        if not _CHECKS[kind](data.schema.field(name).type):
            raise EstaError(
                f"{where}: column {name} holds {data.schema.field(name).type}, not {kind} values"
            )
    return data


def stream_table(
    source: TableSource,
    table: str,
    columns: Mapping[str, Kind],
    required: tuple[str, ...],
    keep: Callable[[pa.RecordBatch], pa.Array],
) -> pa.Table:
    """Like `read_table`, but read in batches and only the rows `keep` marks are held: a tick
    table of millions of rows takes the memory of the rows kept."""
    found = source.open_table(table)
    if found is None or isinstance(found, pa.Table):
        whole = read_table(source, table, columns, required)
        return whole.filter(keep(whole.to_batches()[0])) if whole.num_rows else whole
    where = f"{source.path}: {table}"
    head = read_table(source, table, columns, required).slice(0, 0)  # checks names and types
    try:
        handle = pq.ParquetFile(io.BytesIO(found) if isinstance(found, bytes) else found)
        parts = [
            batch.filter(keep(batch))
            for batch in handle.iter_batches(columns=head.schema.names, use_threads=False)
        ]
    except (pa.ArrowException, OSError, ValueError) as error:
        raise EstaError(f"{where}: not a readable parquet table ({error})") from None
    return pa.Table.from_batches(parts, schema=head.schema) if parts else head


def table_rows(source: TableSource, table: str) -> int | None:
    """How many rows a parquet table holds, from its footer (None for a demo's tables)."""
    found = source.open_table(table)
    if found is None or isinstance(found, pa.Table):
        return None if found is None else found.num_rows
    try:
        handle = pq.ParquetFile(io.BytesIO(found) if isinstance(found, bytes) else found)
    except (pa.ArrowException, OSError, ValueError) as error:
        raise EstaError(f"{source.path}: {table}: not a readable parquet table ({error})") from None
    return int(handle.metadata.num_rows)


def _folder(path: Path) -> TableSource:
    """An awpy 3 folder: one `<dataset>.parquet` per table beside `header.json`."""
    header = _header(path / HEADER, _read_limited(path / HEADER, MAX_HEADER_BYTES))
    total = sum(p.stat().st_size for p in path.glob("*.parquet") if p.is_file())
    _check_size(path, total)

    def open_table(name: str) -> Path | None:
        file = path / f"{name}.parquet"
        if not file.exists():
            return None
        if not file.is_file():
            raise EstaError(f"{file}: not a regular file")
        return file

    return TableSource(path, "awpy 3", header, open_table)


def _zip(path: Path) -> TableSource:
    """An awpy 2 zip: `<table>.parquet` members and `header.json`."""
    try:
        archive = zipfile.ZipFile(path)
        members = {info.filename: info for info in archive.infolist()}
    except (zipfile.BadZipFile, OSError, ValueError) as error:
        raise EstaError(f"{path}: not a readable zip file ({error})") from None
    _check_size(path, sum(info.file_size for info in members.values()))

    def member(name: str) -> bytes | None:
        if name not in members:
            return None
        try:
            return archive.read(name)
        except (zipfile.BadZipFile, OSError, ValueError, EOFError) as error:
            raise EstaError(f"{path}: {name} is corrupt ({error})") from None

    raw_header = member(HEADER)
    if raw_header is None:
        raise EstaError(f"{path}: no {HEADER} (awpy 2 writes one into its zip)")
    header = _header(path, raw_header)
    return TableSource(path, "awpy 2", header, lambda name: member(f"{name}.parquet"))


def _check_size(path: Path, size: int) -> None:
    limit = max_match_bytes()
    if size > limit:
        raise EstaError(
            f"{path}: {size / 1e6:,.0f} MB of tables, more than {limit / 1e6:g} MB "
            "(set DECOY_MAX_MATCH_MB to allow more)"
        )


def _read_limited(path: Path, limit: int) -> bytes:
    try:
        with path.open("rb") as handle:
            data = handle.read(limit + 1)
    except OSError as error:
        raise EstaError(f"{path}: cannot read the file ({error.strerror or error})") from None
    if len(data) > limit:
        raise EstaError(f"{path}: larger than {limit:,} bytes (not an awpy header)")
    return data


def _header(where: Path, raw: bytes) -> JsonObject:
    """`header.json` as an object; anything else raises."""
    if len(raw) > MAX_HEADER_BYTES:
        raise EstaError(f"{where}: {HEADER} is larger than {MAX_HEADER_BYTES:,} bytes")
    try:
        header = json.loads(raw)
    except (ValueError, RecursionError) as error:
        raise EstaError(f"{where}: {HEADER} is not JSON ({error})") from None
    if not isinstance(header, dict):
        raise EstaError(f"{where}: {HEADER} is not a JSON object")
    return header
