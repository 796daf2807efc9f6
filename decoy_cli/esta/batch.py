"""Every round of a set of match files, or why it could not be had: the one batch loop.

Work over many rounds (evaluate, the snap and replay studies, the benchmark, training) goes
through this module. A file that cannot be read, a match of another map and a round that fails
validation each become a `RoundFailure` with its reason, and the batch goes on; work done on a
round that then fails is recorded with `failure_from` under the same rules: a `DecoyError` is a
bad input and keeps its own one-line message, anything else is a bug ("internal error") named
with the place it was raised.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TypeVar

from decoy_cli.errors import DecoyError, EstaError, describe_bug
from decoy_cli.esta.awpy.tables import is_awpy_source
from decoy_cli.esta.reader import MATCH_SUFFIXES, Match, Round, iter_match_files, read_match

Result = TypeVar("Result")

UNREADABLE_FILE = "unreadable file"
OTHER_MAP = "other map"
BROKEN_ROUND = "broken round"
INTERNAL_ERROR = "internal error"


@dataclass(frozen=True)
class RoundFailure:
    """A file (`round_num` None) or one round that produced no result, and why, in one line.

    `kind` is a short category (`UNREADABLE_FILE`, `OTHER_MAP`, `BROKEN_ROUND`, or what the
    work on the round calls its own failures, e.g. "replay error"); `message` is one line.
    """

    file: str
    round_num: int | None
    kind: str
    message: str

    @property
    def where(self) -> str:
        """ "FILE" for a whole file, "FILE:ROUND" for a round."""
        return self.file if self.round_num is None else f"{self.file}:{self.round_num}"

    def row(self) -> dict[str, str | int | None]:
        """The failure as a table row: file, round, kind, message."""
        return {
            "file": self.file,
            "round": self.round_num,
            "kind": self.kind,
            "message": self.message,
        }


def failure_from(
    error: BaseException, file: str | Path, round_num: int | None, kind: str
) -> RoundFailure:
    """The failure of work that raised `error`: its own line for a `DecoyError`, else a bug."""
    if isinstance(error, DecoyError):
        return RoundFailure(str(file), round_num, kind, str(error))
    summary, where = describe_bug(error)
    at = f" (at {where})" if where else ""
    return RoundFailure(str(file), round_num, INTERNAL_ERROR, summary + at)


def each_round(
    rounds: Iterable[Round | RoundFailure],
    work: Callable[[Round], Result],
    kind: str,
    *,
    catch: type[BaseException] | tuple[type[BaseException], ...] = Exception,
) -> Iterator[tuple[Round, Result] | RoundFailure]:
    """(round, what `work` made of it) for every round of `rounds` (`iter_rounds`,
    `match_rounds`), or the failure that stands for it: a round the reader could not build, or
    one whose work raised one of `catch`, recorded by `failure_from` under `kind`. The batch
    goes on; an exception outside `catch` (a benchmark's bug) is not caught."""
    for item in rounds:
        if isinstance(item, RoundFailure):
            yield item
            continue
        try:
            result = work(item)
        except catch as error:
            yield failure_from(error, item.path, item.round_num, kind)
            continue
        yield item, result


def collect_match_files(inputs: Sequence[str | Path]) -> tuple[list[Path], list[Path]]:
    """The match files of the inputs (files or folders; absolute, in input order, each once)
    and the other files found in the folders (not read). A missing input is an EstaError."""
    files: list[Path] = []
    ignored: list[Path] = []
    seen: set[Path] = set()
    for item in inputs:
        path = Path(item)
        if not path.exists():
            raise EstaError(f"{path}: no such file or folder")
        if path.is_dir() and not is_awpy_source(path):  # a folder of matches
            ignored.extend(
                sorted(
                    p for p in path.iterdir() if p.is_file() and not p.name.endswith(MATCH_SUFFIXES)
                )
            )
        for file in iter_match_files(path):
            # workers may run elsewhere: absolute paths; a dangling or looping link keeps its
            # own name, and reading it says what is wrong
            resolved = file.resolve() if file.exists() else file.absolute()
            if resolved not in seen:
                seen.add(resolved)
                files.append(resolved)
    return files, ignored


def map_failure(
    file: str | Path, file_map: str, rounds: int, map_name: str | None
) -> RoundFailure | None:
    """The failure of a whole file of `rounds` rounds played on `file_map` when the work is on
    `map_name` (None, or a file that names no map: no failure)."""
    if map_name is None or not file_map or file_map == map_name:
        return None
    return RoundFailure(
        str(file),
        None,
        OTHER_MAP,
        f"{file}: a {file_map} match ({rounds} rounds skipped); this work is on {map_name}",
    )


def match_rounds(match: Match) -> Iterator[Round | RoundFailure]:
    """The rounds of a match in round-number order, a broken one as its failure."""
    built = {r.round_num: r for r in match.rounds}
    for num in match.round_numbers:
        if num in built:
            yield built[num]
        else:
            error = match.round_errors[num]
            yield RoundFailure(str(match.path), num, BROKEN_ROUND, str(error))


def iter_matches(
    files: Iterable[str | Path], *, map_name: str | None = None, rate: float | None = None
) -> Iterator[Match | RoundFailure]:
    """Each readable match of `files` on `map_name` (None: any), else the file's failure;
    awpy's full-rate ticks read at `rate` frames a second (None: the reader's default)."""
    for file in files:
        try:
            match = read_match(file, rate=rate)
        except DecoyError as error:
            yield failure_from(error, file, None, UNREADABLE_FILE)
            continue
        other = map_failure(match.path, match.map_name, len(match.round_numbers), map_name)
        yield match if other is None else other


def iter_rounds(
    files: Iterable[str | Path], *, map_name: str | None = None, rate: float | None = None
) -> Iterator[Round | RoundFailure]:
    """Every round of `files` in file then round order, or the failure that stands for it."""
    for item in iter_matches(files, map_name=map_name, rate=rate):
        if isinstance(item, RoundFailure):
            yield item
        else:
            yield from match_rounds(item)
