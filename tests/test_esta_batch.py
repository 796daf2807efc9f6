"""The one round iterator: rounds in order, and every file or round that fails as a failure."""

from __future__ import annotations

from pathlib import Path

import pytest
from esta_fixtures import make_match, write_match

from decoy_cli.errors import DecoyError, EstaError
from decoy_cli.esta import (
    Round,
    RoundFailure,
    collect_match_files,
    each_round,
    failure_from,
    iter_rounds,
)


def _kinds(items: list) -> list[tuple[str, int | None, str]]:
    return [(Path(x.file).name, x.round_num, x.kind) for x in items if isinstance(x, RoundFailure)]


def test_rounds_in_file_then_round_order_with_failures_in_place(tmp_path: Path) -> None:
    good = write_match(tmp_path / "a.json.xz")
    broken = make_match()
    broken["gameRounds"][1]["frames"] = "not a list"
    bad_round = write_match(tmp_path / "b.json", broken)
    corrupt = tmp_path / "c.json.xz"
    corrupt.write_bytes(b"\xfd7zXZ\x00 truncated")
    other = make_match()
    other["mapName"] = "de_mirage"
    other_map = write_match(tmp_path / "d.json", other)

    items = list(iter_rounds([good, bad_round, corrupt, other_map], map_name="de_dust2"))

    rounds = [(Path(x.path).name, x.round_num) for x in items if not isinstance(x, RoundFailure)]
    assert rounds == [
        ("a.json.xz", 1),
        ("a.json.xz", 2),
        ("a.json.xz", 3),
        ("b.json", 1),
        ("b.json", 3),
    ]
    assert _kinds(items) == [
        ("b.json", 2, "broken round"),
        ("c.json.xz", None, "unreadable file"),
        ("d.json", None, "other map"),
    ]
    assert items.index(next(x for x in items if isinstance(x, RoundFailure))) == 4


def test_any_map_when_none_is_asked(tmp_path: Path) -> None:
    other = make_match()
    other["mapName"] = "de_mirage"
    file = write_match(tmp_path / "d.json", other)
    assert [r.map_name for r in iter_rounds([file])] == ["de_mirage"] * 3


def test_collect_match_files_each_once_and_ignored(tmp_path: Path) -> None:
    a = write_match(tmp_path / "a.json.xz")
    (tmp_path / "notes.txt").write_text("x")
    files, ignored = collect_match_files([tmp_path, a])
    assert files == [a.resolve()]
    assert [p.name for p in ignored] == ["notes.txt"]
    with pytest.raises(EstaError, match="no such file or folder"):
        collect_match_files([tmp_path / "missing"])


def test_failure_from_keeps_a_bad_input_line_and_names_a_bug() -> None:
    bad = failure_from(EstaError("x.json: round 3: broken"), "x.json", 3, "replay error")
    assert (bad.kind, bad.message) == ("replay error", "x.json: round 3: broken")
    try:
        [][1]
    except IndexError as error:
        bug = failure_from(error, "x.json", 3, "replay error")
    assert bug.kind == "internal error"
    assert bug.message.startswith("IndexError: list index out of range (at test_esta_batch.py:")


def test_dangling_and_looping_links_are_failures_not_silence(tmp_path: Path) -> None:
    good = write_match(tmp_path / "a.json.xz")
    (tmp_path / "dangling.json.xz").symlink_to(tmp_path / "nowhere.json.xz")
    (tmp_path / "loop.json").symlink_to(tmp_path / "loop.json")
    files, ignored = collect_match_files([tmp_path])
    assert [f.name for f in files] == ["a.json.xz", "dangling.json.xz", "loop.json"]
    assert ignored == []
    items = list(iter_rounds(files))
    failures = [x for x in items if isinstance(x, RoundFailure)]
    assert [(Path(f.file).name, f.kind) for f in failures] == [
        ("dangling.json.xz", "unreadable file"),
        ("loop.json", "unreadable file"),
    ]
    assert "no such file" in failures[0].message
    assert "cannot read the file" in failures[1].message
    assert len(items) - len(failures) == 3 and good.exists()


def test_each_round_works_or_records_and_goes_on(tmp_path: Path) -> None:
    broken = make_match()
    broken["gameRounds"][1]["frames"] = "not a list"
    path = write_match(tmp_path / "b.json", broken)

    def work(round_: Round) -> int:
        if round_.round_num == 3:
            raise DecoyError("round three is refused")
        return round_.round_num * 10

    items = list(each_round(iter_rounds([path]), work, "my work"))
    done = [
        (r.round_num, made) for r, made in (x for x in items if not isinstance(x, RoundFailure))
    ]
    assert done == [(1, 10)]
    assert _kinds(items) == [("b.json", 2, "broken round"), ("b.json", 3, "my work")]
    assert isinstance(items[2], RoundFailure) and items[2].message == "round three is refused"

    def buggy(round_: Round) -> int:
        raise KeyError("oops")

    bugs = [x for x in each_round(iter_rounds([path]), buggy, "w") if isinstance(x, RoundFailure)]
    assert [b.kind for b in bugs] == ["internal error", "broken round", "internal error"]
    with pytest.raises(KeyError):  # outside `catch`: not caught
        list(each_round(iter_rounds([path]), buggy, "w", catch=DecoyError))
