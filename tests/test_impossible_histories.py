"""Histories no CS:GO round can have (issue 35): alive after dead, HP rising, one player on both
sides, a file's clock running backwards across rounds. What may look like them and is not:
a player missing from a frame, a frame with HP unknown, a round ending on the tick the next
starts. The real rounds in ../shared/data trip none of them."""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

import pandas as pd
import pytest
from esta_fixtures import make_match, write_match
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from decoy_cli.errors import EstaError
from decoy_cli.esta import iter_match_files, read_match
from decoy_cli.esta.plausibility import round_order_problems

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"


def _ct1(document: dict[str, Any], frame: int) -> dict[str, Any]:
    players = document["gameRounds"][0]["frames"][frame]["ct"]["players"]
    return next(p for p in players if p["name"] == "ct1")


def _warnings(tmp_path: Path, document: dict[str, Any]) -> tuple[str, ...]:
    match = read_match(write_match(tmp_path / "m.json", document), implausible="warn")
    return match.round(1).warnings


def test_what_only_looks_impossible_is_no_warning(tmp_path: Path) -> None:
    document = make_match()
    _ct1(document, 1)["hp"] = None  # HP unknown in one frame: 100, ?, 100 does not rise
    _ct1(document, 2)["hp"] = 70  # a fall: HP goes down and stays
    _ct1(document, 3)["hp"] = 70
    frames = document["gameRounds"][0]["frames"]
    dead = next(p for p in frames[2]["t"]["players"] if p["name"] == "t2")
    dead.update(hp=0, isAlive=False)
    for frame in frames[3:]:  # dead, then no longer listed: not a revival
        frame["t"]["players"].remove(next(p for p in frame["t"]["players"] if p["name"] == "t2"))
    assert _warnings(tmp_path, document) == ()


def test_a_player_missing_between_death_and_life_is_still_revived(tmp_path: Path) -> None:
    document = make_match()
    _ct1(document, 0).update(hp=0, isAlive=False)
    frame = document["gameRounds"][0]["frames"][1]["ct"]
    frame["players"] = [p for p in frame["players"] if p["name"] != "ct1"]
    warnings = _warnings(tmp_path, document)
    assert warnings[0].startswith("frame 2 (tick 1128): ct1 is alive again after being dead")
    assert "HP rose to 100 from 0 in frame 0" in warnings[1]


def test_every_impossible_history_of_a_round_is_one_warning_each(tmp_path: Path) -> None:
    document = make_match()
    _ct1(document, 1).update(hp=0, isAlive=False)  # dead, alive again in frame 2
    frames = document["gameRounds"][0]["frames"]
    t1 = next(p for p in frames[3]["t"]["players"] if p["name"] == "t1")
    frames[3]["ct"]["players"].append(t1)  # t1 listed for both sides in frame 3
    frames[3]["t"]["players"].remove(t1)
    warnings = _warnings(tmp_path, document)
    assert len(warnings) == 3, warnings
    assert "ct1 is alive again" in warnings[0] and "ct1's HP rose" in warnings[1]
    assert "t1 plays for CT after playing for T since frame 0" in warnings[2]
    with pytest.raises(EstaError, match="ct1 is alive again"):
        read_match(tmp_path / "m.json").round(1)


def test_round_order() -> None:
    assert round_order_problems([(1, 0, 10), (2, 10, 20), (3, 30, 40)]) == {}
    problems = round_order_problems([(3, 15, 40), (1, 0, 10), (2, 12, 20)])
    assert problems == {
        3: "starts at tick 15, before round 2 has ended (tick 20): the file's clock runs backwards"
    }


def test_a_round_numbered_out_of_clock_order_fails_alone(tmp_path: Path) -> None:
    document = make_match()
    document["gameRounds"][2]["roundNum"] = 0  # round 3's ticks (8000-12000) come after round 2
    match = read_match(write_match(tmp_path / "m.json", document))
    assert [r.round_num for r in match.rounds] == [0, 2]
    assert "round 1: starts at tick 900, before round 0 has ended (tick 12000)" in str(
        match.round_errors[1]
    )
    warned = read_match(tmp_path / "m.json", implausible="warn")
    assert [r.round_num for r in warned.rounds] == [0, 1, 2]
    assert warned.round(1).warnings == (
        "starts at tick 900, before round 0 has ended (tick 12000): the file's clock runs "
        "backwards",
    )


@pytest.mark.parametrize(
    "folder", ["esta_dust2_tside", "cs2_dust2_both", "esta_dust2_events", "events_ancient"]
)
def test_real_rounds_have_possible_histories(folder: str) -> None:
    if not (DATA / folder).is_dir():
        pytest.skip(f"real data not found at {DATA / folder} (../shared/data next to the repo)")
    for path in iter_match_files(DATA / folder):
        match = read_match(path, implausible="warn")
        assert not match.round_errors, match.round_errors
        assert [w for r in match.rounds for w in r.warnings] == []


# ---- property: any history of one player over the four frames ------------------------------------

FRAME_STATE = st.one_of(
    st.none(),  # not listed in the frame
    st.tuples(st.sampled_from([None, 0, 40, 100]), st.booleans()),  # (hp, isAlive)
)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(history=st.lists(FRAME_STATE, min_size=4, max_size=4))
def test_revival_and_rising_hp_are_found_exactly_when_they_happen(
    tmp_path_factory: pytest.TempPathFactory, history: list[tuple[int | None, bool] | None]
) -> None:
    document = make_match()
    frames = document["gameRounds"][0]["frames"]
    for frame, state in zip(frames, history, strict=True):
        players = frame["ct"]["players"]
        if state is None:
            players.remove(next(p for p in players if p["name"] == "ct1"))
        else:
            next(p for p in players if p["name"] == "ct1").update(hp=state[0], isAlive=state[1])
    listed = [s for s in history if s is not None]
    revived = any(not a[1] and b[1] for i, a in enumerate(listed) for b in listed[i + 1 :])
    known = [hp for hp, _ in listed if hp is not None]
    rose = any(b > a for a, b in itertools.pairwise(known))
    warnings = " ".join(_warnings(tmp_path_factory.mktemp("h"), document))
    assert ("ct1 is alive again" in warnings) == revived, (history, warnings)
    assert ("ct1's HP rose" in warnings) == rose, (history, warnings)


def test_evaluate_replays_a_player_on_both_sides_as_one_agent_per_side(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from decoy_cli.cli import app

    document = make_match()
    for frame in document["gameRounds"][0]["frames"][2:]:  # ct2 plays for T from frame 2
        ct2 = next(p for p in frame["ct"]["players"] if p["name"] == "ct2")
        frame["ct"]["players"].remove(ct2)
        frame["t"]["players"] = [p for p in frame["t"]["players"] if p["name"] != "t1"]
        frame["t"]["players"].append(ct2)
    file = write_match(tmp_path / "m.json", document)
    out = tmp_path / "out"
    args = ["evaluate", str(file), "--no-combat", "--implausible", "warn", "--no-figures"]
    args += ["--out", str(out)]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 1, result.output  # round 3 has no frames: its failure
    assert "Traceback" not in result.output
    rounds = pd.read_csv(out / "rounds.csv").set_index("round")
    assert "ct2 plays for T after playing for CT since frame 0" in rounds.loc[1, "warnings"]
    players = pd.read_csv(out / "players.csv")
    ct2 = players[(players["round"] == 1) & (players["player"] == "ct2")]
    assert sorted(ct2["side"]) == ["CT", "T"]
