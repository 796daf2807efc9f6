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
import lzma
import zipfile
import zlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import pyarrow as pa
import pyarrow.parquet as pq

from decoy_cli.errors import EstaError
from decoy_cli.esta.source import max_match_bytes
from decoy_cli.files import JsonObject
from decoy_cli.reading import read_limited

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
        or (
            pa.types.is_dictionary(t)
            and (pa.types.is_string(t.value_type) or pa.types.is_large_string(t.value_type))
        )
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
    found, names = _opened(source, table, columns, required)
    if isinstance(found, pa.Table):
        return found.select(names)
    try:
        return found.read(columns=names, use_threads=False)
    except (pa.ArrowException, OSError, ValueError) as error:
        raise EstaError(f"{source.path}: {table}: not a readable parquet table ({error})") from None


def stream_table(
    source: TableSource,
    table: str,
    columns: Mapping[str, Kind],
    required: tuple[str, ...],
    keep: Callable[[pa.RecordBatch | pa.Table], pa.Array],
) -> pa.Table:
    """Like `read_table`, but read in batches and only the rows `keep` marks are held: a tick
    table of millions of rows takes the memory of the rows kept."""
    found, names = _opened(source, table, columns, required)
    if isinstance(found, pa.Table):
        whole = found.select(names)
        return whole.filter(keep(whole))
    try:
        parts = [
            batch.filter(keep(batch))
            for batch in found.iter_batches(columns=names, use_threads=False)
        ]
        schema = found.schema_arrow
    except (pa.ArrowException, OSError, ValueError) as error:
        raise EstaError(f"{source.path}: {table}: not a readable parquet table ({error})") from None
    empty = pa.schema([schema.field(name) for name in names])
    return pa.Table.from_batches(parts, schema=empty) if parts else empty.empty_table()


def _opened(
    source: TableSource, table: str, columns: Mapping[str, Kind], required: tuple[str, ...]
) -> tuple[pq.ParquetFile | pa.Table, list[str]]:
    """The table, opened (its data not yet read), and the names of the columns it has of
    `columns`, checked: every required one there, each of the kind it should hold."""
    where = f"{source.path}: {table}"
    found = source.open_table(table)
    if found is None:
        raise EstaError(f"{source.path}: no {table} table (awpy writes one; is this awpy data?)")
    try:
        schema = found.schema if isinstance(found, pa.Table) else _parquet(found).schema_arrow
    except (pa.ArrowException, OSError, ValueError) as error:
        raise EstaError(f"{where}: not a readable parquet table ({error})") from None
    names = [c for c in columns if c in schema.names]
    missing = [c for c in required if c not in names]
    if missing:
        raise EstaError(f"{where}: no column {', '.join(missing)}")
    for name in names:
        kind, held = columns[name], schema.field(name).type
        if not _CHECKS[kind](held):
            raise EstaError(f"{where}: column {name} holds {held}, not {kind} values")
    if isinstance(found, pa.Table):
        return found, names
    text = [c for c in names if columns[c] == "str" and not pa.types.is_null(schema.field(c).type)]
    try:
        return _parquet(found, text), names  # each distinct text held once, however many rows
    except (pa.ArrowException, OSError, ValueError) as error:
        raise EstaError(f"{where}: not a readable parquet table ({error})") from None


def _parquet(found: bytes | Path, text: list[str] | None = None) -> pq.ParquetFile:
    """A parquet file opened, its `text` columns to be read dictionary-encoded."""
    return pq.ParquetFile(
        io.BytesIO(found) if isinstance(found, bytes) else found, read_dictionary=text
    )


def table_rows(source: TableSource, table: str) -> int:
    """How many rows a table holds (a parquet file's from its footer)."""
    opened, _ = _opened(source, table, {}, ())
    return opened.num_rows if isinstance(opened, pa.Table) else int(opened.metadata.num_rows)


def _folder(path: Path) -> TableSource:
    """An awpy 3 folder: one `<dataset>.parquet` per table beside `header.json`."""
    header = _header(path / HEADER, read_limited(path / HEADER, MAX_HEADER_BYTES, EstaError))
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
        listed = archive.infolist()
    except (zipfile.BadZipFile, OSError, ValueError) as error:
        raise EstaError(f"{path}: not a readable zip file ({error})") from None
    members = {info.filename: info for info in listed}
    if len(members) != len(listed):
        twice = sorted(
            {i.filename for i in listed if [j.filename for j in listed].count(i.filename) > 1}
        )
        raise EstaError(f"{path}: the zip holds {twice[0]} twice (which is the table?)")
    _check_size(path, sum(info.file_size for info in members.values()))

    def member(name: str) -> bytes | None:
        if name not in members:
            return None
        try:  # read by the declared size, so a member that lies about it cannot inflate on
            with archive.open(members[name]) as handle:
                data = handle.read(members[name].file_size + 1)
        except _MEMBER_ERRORS as error:
            raise EstaError(f"{path}: {name} cannot be read ({error})") from None
        if len(data) != members[name].file_size:
            raise EstaError(
                f"{path}: {name} holds {len(data):,} bytes, its entry says "
                f"{members[name].file_size:,} (a damaged zip)"
            )
        return data

    raw_header = member(HEADER)
    if raw_header is None:
        raise EstaError(f"{path}: no {HEADER} (awpy 2 writes one into its zip)")
    header = _header(path, raw_header)
    return TableSource(path, "awpy 2", header, lambda name: member(f"{name}.parquet"))


_MEMBER_ERRORS = (
    zipfile.BadZipFile,
    OSError,
    ValueError,
    EOFError,
    RuntimeError,  # an encrypted member
    NotImplementedError,  # a compression method Python lacks
    zlib.error,
    lzma.LZMAError,
)
"""What reading a damaged or unusual zip member can raise."""


def _check_size(path: Path, size: int) -> None:
    limit = max_match_bytes()
    if size > limit:
        raise EstaError(
            f"{path}: {size / 1e6:,.0f} MB of tables, more than {limit / 1e6:g} MB "
            "(set DECOY_MAX_MATCH_MB to allow more)"
        )


def _header(where: Path, raw: bytes) -> JsonObject:
    """`header.json` as an object; anything else raises."""
    if len(raw) > MAX_HEADER_BYTES:
        raise EstaError(f"{where}: {HEADER} is larger than {MAX_HEADER_BYTES:,} bytes")
    try:
        header = json.loads(raw, object_pairs_hook=_no_repeated_keys)
    except (ValueError, RecursionError) as error:
        raise EstaError(f"{where}: {HEADER} is not JSON ({error})") from None
    if not isinstance(header, dict):
        raise EstaError(f"{where}: {HEADER} is not a JSON object")
    return header


def _no_repeated_keys(pairs: list[tuple[str, object]]) -> dict[str, object]:
    """A JSON object; a key given twice raises (which value would be the header's?)."""
    keys = [key for key, _ in pairs]
    if len(set(keys)) != len(keys):
        raise ValueError(f"the key {next(k for k in keys if keys.count(k) > 1)!r} is given twice")
    return dict(pairs)
