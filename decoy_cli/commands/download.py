"""`decoy download ID...`: fetch ESTA match files of one map by id, verified, into a folder."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.progress import (
    BarColumn,
    DownloadColumn,
    Progress,
    TaskID,
    TextColumn,
    TimeRemainingColumn,
    TransferSpeedColumn,
)

from decoy_cli.commands._console import make_console
from decoy_cli.commands._options import MAPS_HELP
from decoy_cli.errors import DecoyError, DownloadError
from decoy_cli.esta.download import (
    DEFAULT_DEST,
    ESTA_BASE_URL,
    Downloaded,
    download_match,
    parse_match_id,
    parse_sha256,
)
from decoy_cli.files import check_folder_writable
from decoy_cli.waypoints.build import canonical_map


def download(
    ids: list[str] = typer.Argument(
        ...,
        metavar="ID...",
        help="ESTA match ids: the uuid of the file name (looked up in data/lan/, then "
        "data/online/), or lan/<uuid> or online/<uuid>.",
    ),
    dest: Path = typer.Option(
        DEFAULT_DEST,
        "--dest",
        help="Folder for the verified <uuid>.json.xz files; point `decoy evaluate` at it.",
    ),
    base_url: str = typer.Option(
        ESTA_BASE_URL,
        "--base-url",
        help="URL above the lan/ and online/ folders: the ESTA repository's raw files (default), "
        "a pinned commit (.../pnxenopoulos/esta/<commit>/data), a mirror or a file:// folder.",
    ),
    sha256: list[str] = typer.Option(
        [],
        "--sha256",
        metavar="ID=HEX",
        help="Expected sha256 of a match file (repeatable). ESTA publishes no checksums; the "
        "sha256 of every verified file is printed so that it can be pinned.",
    ),
    timeout: float = typer.Option(
        60.0, "--timeout", min=0.1, help="Seconds to wait for a connection or for more data."
    ),
    map_name: str = typer.Option(
        "dust2",
        "--map",
        help=f"The map the matches must be on ({MAPS_HELP}); a match of another is not kept.",
    ),
) -> None:
    """Download ESTA match files of one map by id, verified, into a folder.

    Each file is verified (complete, xz, readable as ESTA, on the map) before it is renamed
    into the folder; a verified file already there is kept. A failure is one line per id, the
    other ids go on, and the exit code is 1 if any failed."""
    console = make_console()
    errors = make_console(stderr=True)
    expected = _parse_checksums(sha256, ids)
    map_id = canonical_map(map_name)
    check_folder_writable(dest)  # one error line, not one per id
    failed = 0
    with Progress(
        TextColumn("{task.description}", markup=False),
        BarColumn(),
        DownloadColumn(),
        TransferSpeedColumn(),
        TimeRemainingColumn(),
        console=errors,
        transient=True,
    ) as progress:
        for match_id in dict.fromkeys(ids):
            task = progress.add_task(match_id, total=None)

            def advance(done: int, total: int | None, task: TaskID = task) -> None:
                progress.update(task, completed=done, total=total)

            try:
                result = download_match(
                    match_id,
                    dest,
                    base_url=base_url,
                    sha256=expected.get(match_id),
                    timeout=timeout,
                    on_progress=advance,
                    map_name=map_id,
                )
            except DecoyError as error:
                failed += 1
                errors.print(f"error: {error}", highlight=False, soft_wrap=True)
            else:
                console.print(_describe(result), highlight=False, soft_wrap=True)
            finally:
                progress.remove_task(task)
    if failed:
        errors.print(f"{failed} of {len(dict.fromkeys(ids))} ids failed", highlight=False)
        raise typer.Exit(1)


def _parse_checksums(options: list[str], ids: list[str]) -> dict[str, str]:
    """`--sha256 ID=HEX` values by id; a malformed one, or one for no given id, is an error."""
    checksums: dict[str, str] = {}
    for option in options:
        match_id, equals, digest = option.partition("=")
        if not equals:
            raise DownloadError(f"--sha256 {option!r}: expected ID=HEX")
        parse_match_id(match_id)
        if match_id not in ids:
            raise DownloadError(f"--sha256 {option!r}: {match_id} is not among the ids to fetch")
        checksums[match_id] = parse_sha256(digest)
    return checksums


def _describe(result: Downloaded) -> str:
    """One line: what happened, the file, its size, rounds and sha256."""
    verb = {"downloaded": "downloaded", "present": "already present", "replaced": "replaced"}
    text = (
        f"{result.match_id}: {verb[result.status]} {result.path} "
        f"({result.size / 1e6:.2f} MB, {result.rounds} rounds, sha256 {result.sha256})"
    )
    if result.note:
        text += f"; {result.note}"
    return text
