"""The view page (issue 36): its data against players.csv, the cache and the round's own
frames; bad folders; hostile names; and the page itself in a headless Chromium (skipped, with
the reason, where there is none): it loads without a console error, lists every player-round,
draws another picture when the round or the time changes, hides a player, answers the keys,
opens a row's round at its largest error, and works copied alone into another folder.

One `decoy evaluate` of the shipped sample serves the module (about 15 s).
"""

from __future__ import annotations

import base64
import hashlib
import json
import re
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import msgspec
import numpy as np
import pandas as pd
import pytest
from browser import Browser, find_chromium
from esta_fixtures import make_match, write_match
from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.esta import read_match
from decoy_cli.evaluate.cache import RunCache
from decoy_cli.evaluate.runner import round_id
from decoy_cli.replay.view_trace import THIN_M, decode_path, thin
from decoy_cli.view.page import embedded_json

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = ROOT / "examples" / "sample"
runner = CliRunner()
HOSTILE = "</script><img src=x onerror=alert(1)>"
CHROMIUM = find_chromium()
needs_browser = pytest.mark.skipif(
    CHROMIUM is None,
    reason="no Chromium to drive (install Debian's `chromium`, or name one in DECOY_CHROMIUM)",
)


def page_data(path: Path) -> dict[str, Any]:
    html = path.read_text(encoding="utf-8")
    found = re.search(r'<script type="application/json" id="data">(.*?)</script>', html, re.S)
    assert found is not None
    return json.loads(found.group(1))


def one_error(result: Any) -> str:
    """The `error:` line of a failed command (and nothing else on it)."""
    assert result.exit_code == 1, result.output
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.output
    assert "Traceback" not in result.output
    return lines[0]


@pytest.fixture(scope="module")
def browser() -> Iterator[Browser]:
    assert CHROMIUM is not None
    with Browser(CHROMIUM) as chromium:
        chromium.call(
            "Emulation.setDeviceMetricsOverride",
            {"width": 1300, "height": 1000, "deviceScaleFactor": 1, "mobile": False},
            session=True,
        )
        yield chromium


# ---- the data ---------------------------------------------------------------------------------


def test_the_page_holds_every_player_round_of_players_csv(run: Path) -> None:
    data = page_data(run / "view.html")
    players = pd.read_csv(run / "players.csv")
    rounds = pd.read_csv(run / "rounds.csv")
    assert len(data["rounds"]) == len(rounds)
    assert [r["label"] for r in data["rounds"]] == [
        f"{m}:{n}" for m, n in rounds[["match", "round"]].values
    ]
    table = data["players"]
    assert len(table["rows"]) == len(players)
    shown = pd.DataFrame(table["rows"], columns=table["columns"])
    for column in ("match", "player", "side"):
        assert shown[column].tolist() == players[column].astype(str).tolist()
    for column in ("round", "mean_dist", "max_dist", "dtw", "paper_dtw"):
        assert np.allclose(shown[column], players[column], rtol=1e-3, equal_nan=True), column
    for row, (r, p) in enumerate(zip(table["round"], table["player"], strict=True)):
        player = data["rounds"][r]["players"][p]
        assert player["name"] == players["player"][row]
        # the moment a row opens on is the largest error the metrics measured
        assert player["worst_m"] == pytest.approx(players["max_dist"][row], abs=1e-9)
        # and its deaths are the kills drawn, it the victim: at its death time, or (a death
        # the frames did not record) not before the round's last frame
        shown_round = data["rounds"][r]
        for source, name in (("data", "original"), ("replay", "replay")):
            kills = [
                e[0] / 100
                for e in shown_round["events"]
                if e[1:3] == [source, "kill"] and e[4] == p
            ]
            if players[f"died_{name}"][row]:
                assert kills == [pytest.approx(players[f"death_time_{name}_s"][row], abs=0.01)]
            else:
                assert all(t >= shown_round["end"] / 100 - 1e-9 for t in kills), (row, source)


def test_the_page_holds_the_cached_trace_of_every_round(run: Path) -> None:
    data = page_data(run / "view.html")
    keys = json.loads((run / "summary.json").read_text())["cache_keys"]
    rounds = pd.read_csv(run / "rounds.csv")
    cache = RunCache(run)
    for shown, row in zip(data["rounds"], rounds.itertuples(), strict=True):
        record = cache.load_round(keys[round_id(row.file_sha, row.round)])
        assert record is not None
        expected = json.loads(embedded_json(msgspec.to_builtins(record.trace)))
        assert {k: v for k, v in shown.items() if k not in ("label", "info")} == expected


def shown_players(
    run: Path,
) -> Iterator[tuple[dict[str, Any], Any, np.ndarray, int, dict[str, Any], np.ndarray]]:
    """Each player the run's page shows, beside his round in the sample: (what the page holds
    of the round, the round, its frames' seconds, his row, what the page holds of him, his
    alive-and-present frames)."""
    data = page_data(run / "view.html")
    match = read_match(next(SAMPLE.glob("*.json.xz")))
    for shown in data["rounds"]:
        round_ = match.round(int(shown["label"].rsplit(":", 1)[1]))
        seconds = np.asarray(round_.frame_seconds)
        for p, player in enumerate(shown["players"]):
            alive = np.asarray(round_.alive[p]) & np.asarray(round_.present[p])
            yield shown, round_, seconds, p, player, alive


def test_the_thinned_paths_follow_the_round_s_frames(run: Path) -> None:
    for _, round_, seconds, p, player, alive in shown_players(run):
        points = np.concatenate([decode_path(s) for s in player["original"]] or [np.zeros((0, 5))])
        assert len(points) <= alive.sum()
        frames = np.flatnonzero(alive)
        if not len(frames):
            continue
        # every alive frame lies on the thinned path: within the tolerance and the rounding
        t = seconds[frames]
        inside = (t >= points[0, 0] - 1e-9) & (t <= points[-1, 0] + 1e-9)
        for axis in (1, 2, 3):
            guess = np.interp(t[inside], points[:, 0], points[:, axis])
            error = np.abs(guess - round_.position[p, frames[inside], axis - 1])
            assert error.max() <= THIN_M + 0.1, (round_.round_num, player["name"], axis)


def test_thinning_keeps_what_interpolation_would_miss() -> None:
    rng = np.random.default_rng(3)
    t = np.arange(400) * 0.5
    walk = np.cumsum(rng.normal(0, 0.4, (400, 3)), axis=0)
    walk[100:200] = walk[100]  # standing still: two frames are enough
    kept = thin(t, walk)
    assert kept[0] == 0 and kept[-1] == 399 and len(kept) < 400
    assert ((kept > 101) & (kept < 199)).sum() == 0
    for axis in range(3):
        assert np.abs(np.interp(t, t[kept], walk[kept, axis]) - walk[:, axis]).max() <= THIN_M


def test_no_view_leaves_the_page_out(run: Path, tmp_path: Path) -> None:
    copy = tmp_path / "copy"
    shutil.copytree(run, copy)
    result = runner.invoke(
        app,
        [
            "evaluate",
            str(SAMPLE),
            "--out",
            str(copy),
            "--workers",
            "1",
            "--no-view",
            "--no-figures",
        ],
    )
    assert result.exit_code == 0, result.output
    assert not (copy / "view.html").exists()  # the earlier run's page goes with its tables
    assert (copy / "report.md").is_file()


def test_view_writes_where_asked_and_opens_on_the_round_asked(run: Path, tmp_path: Path) -> None:
    rounds = pd.read_csv(run / "rounds.csv")
    label = f"{rounds['match'][3]}:{rounds['round'][3]}"
    out = tmp_path / "pages" / "r.html"
    result = runner.invoke(app, ["view", str(run), "--round", label, "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert page_data(out)["initial"] == 3
    assert f"no round {label}x" in one_error(
        runner.invoke(app, ["view", str(run), "--round", f"{label}x", "--out", str(out)])
    )


# ---- bad folders ------------------------------------------------------------------------------


def _broken(run: Path, tmp_path: Path, how: str) -> Path:
    folder = tmp_path / how
    shutil.copytree(run, folder)
    if how == "no players":
        (folder / "players.csv").unlink()
    elif how == "older":
        summary = json.loads((folder / "summary.json").read_text())
        del summary["cache_keys"]
        (folder / "summary.json").write_text(json.dumps(summary))
    elif how == "no cache":
        shutil.rmtree(folder / "cache")
    elif how == "edited players":
        players = pd.read_csv(folder / "players.csv")
        players.iloc[:-1].to_csv(folder / "players.csv", index=False)
    elif how == "bad summary":
        (folder / "summary.json").write_text("[1, 2")
    elif how == "no tables":
        shutil.rmtree(folder / "tables")
    return folder


@pytest.mark.parametrize(
    ("how", "said"),
    [
        ("no players", "players.csv: not found"),
        ("older", "older decoy"),
        ("no cache", "cached result of round"),
        ("edited players", "players.csv"),
        ("bad summary", "summary.json: not readable JSON"),
        ("no tables", "an incomplete"),
    ],
)
def test_a_broken_run_is_one_error_line(run: Path, tmp_path: Path, how: str, said: str) -> None:
    folder = _broken(run, tmp_path, how)
    before = sorted(p.name for p in folder.iterdir())
    assert said in one_error(runner.invoke(app, ["view", str(folder)]))
    assert sorted(p.name for p in folder.iterdir()) == before  # nothing written


def test_not_a_run_is_one_error_line(tmp_path: Path) -> None:
    assert "no such folder" in one_error(runner.invoke(app, ["view", str(tmp_path / "none")]))
    assert "decoy evaluate" in one_error(runner.invoke(app, ["view", str(tmp_path)]))
    (tmp_path / "replay.csv").write_text("frame\n")
    assert "summary.json: not found" in one_error(runner.invoke(app, ["view", str(tmp_path)]))


@pytest.fixture(scope="module")
def replay_folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("replay") / "replay"
    file = next(SAMPLE.glob("*.json.xz"))
    result = runner.invoke(app, ["replay", f"{file}:2", "--models", "none", "--out", str(out)])
    assert result.exit_code == 0, result.output
    return out


def test_a_replay_folder_gets_its_page(replay_folder: Path, tmp_path: Path) -> None:
    out = tmp_path / "replay"
    shutil.copytree(replay_folder, out)
    result = runner.invoke(app, ["view", str(out)])
    assert result.exit_code == 0, result.output
    data = page_data(out / "view.html")
    players = pd.read_csv(out / "players.csv")
    assert len(data["rounds"]) == 1 and len(data["players"]["rows"]) == len(players)
    assert [p["name"] for p in data["rounds"][0]["players"]] == players["player"].tolist()
    (out / "trace.json").unlink()  # as an older decoy left it
    assert "older decoy" in one_error(runner.invoke(app, ["view", str(out)]))


@pytest.fixture(scope="module")
def empty_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A run whose every round failed: its page has no round."""
    folder = tmp_path_factory.mktemp("empty")
    (folder / "in").mkdir()
    (folder / "in" / "broken.json").write_text("{")
    out = folder / "evaluate"
    result = runner.invoke(app, ["evaluate", str(folder / "in"), "--no-figures", "--out", str(out)])
    assert result.exit_code == 1, result.output  # the failure is recorded
    return out


def test_a_run_without_a_round_still_gets_its_page(empty_run: Path) -> None:
    data = page_data(empty_run / "view.html")
    assert data["rounds"] == [] and data["players"]["rows"] == []


@needs_browser
def test_a_page_without_a_round_opens(browser: Browser, empty_run: Path) -> None:
    browser.open(empty_run / "view.html")
    assert browser.console_errors() == []
    assert browser.evaluate("document.getElementById('round-info').textContent") == (
        "no round to show"
    )


@needs_browser
def test_a_replay_folder_s_page_opens(browser: Browser, replay_folder: Path) -> None:
    result = runner.invoke(app, ["view", str(replay_folder)])
    assert result.exit_code == 0, result.output
    browser.open(replay_folder / "view.html")
    _set_slider(browser, 30)
    assert browser.console_errors() == []
    rows = browser.evaluate("document.querySelectorAll('#at-cursor tbody tr').length")
    assert rows == len(pd.read_csv(replay_folder / "players.csv"))


# ---- hostile names ----------------------------------------------------------------------------


@pytest.fixture(scope="module")
def hostile(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("hostile")
    document = make_match()
    document["matchID"] = "<b>m</b>\u2028"
    for game_round in document["gameRounds"]:
        for frame in game_round.get("frames") or []:
            for player in frame["t"]["players"]:
                if player["name"] == "t1":
                    player["name"] = HOSTILE
    write_match(folder / "m.json", document)
    out = folder / "evaluate"
    args = ["evaluate", str(folder), "--no-combat", "--no-figures", "--out", str(out)]
    result = runner.invoke(app, args)
    assert (out / "view.html").is_file(), result.output
    return out / "view.html"


def test_names_in_the_page_cannot_end_its_script(hostile: Path) -> None:
    html = hostile.read_text(encoding="utf-8")
    assert html.count("</script>") == 2  # the page's own two script elements
    assert "<img" not in html and "<b>" not in html and "\u2028" not in html
    names = [p["name"] for r in page_data(hostile)["rounds"] for p in r["players"]]
    assert HOSTILE in names  # shown as it is, as text


@needs_browser
def test_names_in_the_page_are_shown_as_text(browser: Browser, hostile: Path) -> None:
    browser.open(hostile)
    assert browser.console_errors() == []
    assert browser.evaluate("document.querySelectorAll('img, b').length") == 0
    assert HOSTILE in browser.evaluate("document.getElementById('at-cursor').textContent")


# ---- in the browser ---------------------------------------------------------------------------


def _set_slider(browser: Browser, seconds: float) -> None:
    browser.evaluate(
        "(() => { const s = document.getElementById('time'); "
        f"s.value = '{seconds}'; s.dispatchEvent(new Event('input')); }})()"
    )


def _clock(browser: Browser) -> float:
    return float(browser.evaluate("document.getElementById('clock').textContent").split()[0])


@needs_browser
def test_the_page_loads_and_lists_every_player_round(browser: Browser, run: Path) -> None:
    browser.open(run / "view.html")
    assert browser.console_errors() == []
    rows = browser.evaluate("document.querySelectorAll('#player-table tbody tr').length")
    assert rows == len(pd.read_csv(run / "players.csv"))
    options = browser.evaluate("document.getElementById('round-select').options.length")
    assert options == len(pd.read_csv(run / "rounds.csv"))
    assert browser.evaluate("document.querySelectorAll('#tables table').length") >= 4


@needs_browser
def test_round_and_time_change_the_picture(browser: Browser, run: Path) -> None:
    browser.open(run / "view.html")
    _set_slider(browser, 20)
    first = browser.screenshot()
    _set_slider(browser, 45)
    later = browser.screenshot()
    assert later != first
    browser.evaluate(
        "(() => { const s = document.getElementById('round-select'); s.value = '2'; "
        "s.dispatchEvent(new Event('change')); })()"
    )
    _set_slider(browser, 45)
    assert browser.screenshot() not in (first, later)
    _set_slider(browser, 20)
    browser.evaluate(
        "(() => { const s = document.getElementById('round-select'); s.value = '0'; "
        "s.dispatchEvent(new Event('change')); })()"
    )
    _set_slider(browser, 20)
    assert browser.screenshot() == first  # the same round and time: the same picture
    assert browser.console_errors() == []


@needs_browser
def test_a_hidden_player_disappears(browser: Browser, run: Path) -> None:
    browser.open(run / "view.html")
    _set_slider(browser, 30)
    shown = browser.screenshot()
    toggle = "document.querySelector('#at-cursor input[data-player=\"{}\"]').click()"
    browser.evaluate(toggle.format(0))
    assert browser.screenshot() != shown
    browser.evaluate(toggle.format(0))
    assert browser.screenshot() == shown
    # everyone else hidden, then him too: exactly the picture of nobody shown
    count = browser.evaluate("document.querySelectorAll('#at-cursor input').length")
    for p in range(1, count):
        browser.evaluate(toggle.format(p))
    alone = browser.screenshot()
    browser.evaluate(toggle.format(0))
    nobody = browser.screenshot()
    assert alone != nobody
    for side in ("T", "CT"):
        browser.evaluate(f"document.querySelector('input.side[value=\"{side}\"]').click()")
    assert browser.screenshot() == nobody


@needs_browser
def test_keys_play_pause_and_step(browser: Browser, run: Path) -> None:
    browser.open(run / "view.html")
    _set_slider(browser, 10)
    browser.evaluate("document.activeElement.blur()")
    browser.key("ArrowRight", "ArrowRight", 39)
    assert _clock(browser) == pytest.approx(10.5)
    browser.key("ArrowRight", "ArrowRight", 39, shift=True)
    assert _clock(browser) == pytest.approx(15.5)
    browser.key("ArrowLeft", "ArrowLeft", 37)
    assert _clock(browser) == pytest.approx(15.0)
    browser.key(" ", "Space", 32)
    assert browser.evaluate("document.getElementById('play').textContent") == "pause"
    browser.wait_for("parseFloat(document.getElementById('clock').textContent) > 15.2")
    browser.key(" ", "Space", 32)
    assert browser.evaluate("document.getElementById('play').textContent") == "play"
    # on a check box Space is the box's: it hides the player, and nothing plays
    browser.evaluate("document.querySelector('#at-cursor input').focus()")
    browser.key(" ", "Space", 32)
    assert browser.evaluate("document.querySelector('#at-cursor input').checked") is False
    assert browser.evaluate("document.getElementById('play').textContent") == "play"
    assert browser.console_errors() == []


@needs_browser
def test_a_row_opens_its_round_at_its_largest_error(browser: Browser, run: Path) -> None:
    browser.open(run / "view.html")
    data = page_data(run / "view.html")
    # sort by max_dist, largest first, and open the top row
    column = data["players"]["columns"].index("max_dist")
    browser.evaluate(f"document.querySelectorAll('#player-table thead button')[{column}].click()")
    row = int(browser.evaluate("document.querySelector('#player-table tbody tr').dataset.row"))
    values = [r[column] for r in data["players"]["rows"]]
    assert values[row] == max(values)
    browser.evaluate("document.querySelector('#player-table tbody tr').click()")
    r, p = data["players"]["round"][row], data["players"]["player"][row]
    assert browser.evaluate("document.getElementById('round-select').value") == str(r)
    worst = data["rounds"][r]["players"][p]["worst_s"]
    assert _clock(browser) == pytest.approx(worst, abs=0.05)


@needs_browser
def test_the_page_works_copied_alone_elsewhere(browser: Browser, run: Path, tmp_path: Path) -> None:
    html = (run / "view.html").read_text(encoding="utf-8")
    assert not re.search(r"""(src|href)\s*=\s*["'](?!#)""", html)  # nothing but its own anchors
    alone = tmp_path / "elsewhere" / "page.html"
    alone.parent.mkdir()
    shutil.copy(run / "view.html", alone)
    browser.open(alone)
    _set_slider(browser, 25)
    assert browser.console_errors() == []
    assert _clock(browser) == pytest.approx(25.0)


def test_a_rounds_smokes_and_fires_are_in_its_trace(tmp_path: Path) -> None:
    from dataclasses import replace

    from decoy_cli.replay import ReplayOptions, replay_round
    from decoy_cli.replay.view_trace import round_trace
    from decoy_cli.sim.utility import SMOKE_RADIUS_M
    from decoy_cli.waypoints.build import builtin_graph

    round_ = read_match(next(SAMPLE.glob("*.json.xz"))).rounds[0]
    smoke = pd.DataFrame(
        {"start_tick": [0.0], "end_tick": [1.0], "start_s": [5.0], "end_s": [20.0],
         "x_m": [10.0], "y_m": [20.0], "z_m": [0.0], "thrower_name": ["T-1"],
         "thrower_side": ["T"], "thrower_steamid": pd.array([11], dtype="Int64")}
    )  # fmt: skip
    smoked = replace(round_, smokes=smoke)
    result = replay_round(smoked, builtin_graph(), ReplayOptions(combat=False, bomb=False))
    trace = round_trace(smoked, result)
    assert trace.utility == [[500, 2000, "smoke", 100, 200, round(SMOKE_RADIUS_M * 10)]]


@needs_browser
def test_an_active_smoke_is_drawn(browser: Browser, replay_folder: Path, tmp_path: Path) -> None:
    pictures = []
    for utility in ([], [[2000, 4000, "smoke", 0, 0, 316]]):
        out = tmp_path / f"replay{len(utility)}"
        shutil.copytree(replay_folder, out)
        trace = json.loads((out / "trace.json").read_text())
        trace["utility"] = utility
        (out / "trace.json").write_text(json.dumps(trace))
        assert runner.invoke(app, ["view", str(out)]).exit_code == 0
        browser.open(out / "view.html")
        shots = []
        for seconds in (10, 30):  # before the smoke, and while it is there
            _set_slider(browser, seconds)
            shots.append(browser.screenshot())
        assert browser.console_errors() == []
        pictures.append(shots)
    assert pictures[1][0] == pictures[0][0]  # not yet: the same picture
    assert pictures[1][1] != pictures[0][1]  # active: drawn


CS2_ROUNDS = ROOT.parent / "shared" / "data" / "cs2_dust2_both"


@pytest.mark.skipif(
    not CS2_ROUNDS.is_dir(), reason="../shared/data/cs2_dust2_both is absent (real CS2 rounds)"
)
def test_inferred_bomb_events_are_marked_with_their_rule() -> None:
    from decoy_cli.replay import ReplayOptions, replay_round
    from decoy_cli.replay.view_trace import round_trace
    from decoy_cli.waypoints.build import builtin_graph

    round_ = read_match(CS2_ROUNDS / "spirit-vs-falcons-m2-dust2-r01-12.json.xz").round(3)
    result = replay_round(round_, builtin_graph(), ReplayOptions(combat=False))
    events = [e for e in round_trace(round_, result).events if e.source == "data"]
    marked = {e.kind: e.inferred for e in events if e.kind in ("carry", "plant", "defuse")}
    assert marked["plant"] is not None and marked["plant"].startswith("bomb carrier and planter")
    assert marked["defuse"] is not None and marked["defuse"].startswith("defuse (")
    assert all(e.inferred is None for e in events if e.kind == "kill")  # recorded


def test_recorded_bomb_events_are_not_marked(replay_folder: Path) -> None:
    trace = json.loads((replay_folder / "trace.json").read_text())
    data = [e for e in trace["events"] if e[1] == "data" and e[2] in ("carry", "plant")]
    assert data and all(len(e) < 8 or e[7] is None for e in data)


@needs_browser
@pytest.mark.skipif(
    not CS2_ROUNDS.is_dir(), reason="../shared/data/cs2_dust2_both is absent (real CS2 rounds)"
)
def test_the_page_lists_inferred_events_apart(browser: Browser, tmp_path: Path) -> None:
    file = CS2_ROUNDS / "spirit-vs-falcons-m2-dust2-r01-12.json.xz"
    out = tmp_path / "round3"
    result = runner.invoke(app, ["replay", f"{file}:3", "--models", "none", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert runner.invoke(app, ["view", str(out)]).exit_code == 0
    browser.open(out / "view.html")
    listed = browser.evaluate(
        "Array.from(document.getElementById('events').children).map((li) => li.textContent)"
    )
    assert any(" · inferred · " in text and "plants (bomb carrier" in text for text in listed)
    assert not any(" · real · " in text and "plants" in text for text in listed)
    assert browser.console_errors() == []


# ---- the page's Content-Security-Policy (issue 51) --------------------------------------------


def _policy(html: str) -> dict[str, list[str]]:
    found = re.search(r'<meta http-equiv="Content-Security-Policy" content="([^"]*)">', html)
    assert found is not None
    directives = [part.split() for part in found.group(1).split(";") if part.strip()]
    return {name: values for name, *values in directives}


def _inline(html: str, tag: str) -> list[str]:
    """The contents of the page's inline elements `tag` (scripts that run, or styles)."""
    return re.findall(rf"<{tag}>(.*?)</{tag}>", html, re.S)


def _digest(text: str) -> str:
    return "'sha256-" + base64.b64encode(hashlib.sha256(text.encode()).digest()).decode() + "'"


def test_the_policy_names_the_page_s_script_and_style_by_hash(hostile: Path) -> None:
    html = hostile.read_text(encoding="utf-8")
    policy = _policy(html)
    assert "'unsafe-inline'" not in str(policy) and "'unsafe-eval'" not in str(policy)
    assert policy["default-src"] == ["'none'"]
    assert policy["script-src"] == [_digest(s) for s in _inline(html, "script")]
    assert policy["style-src"] == [_digest(s) for s in _inline(html, "style")]
    assert len(policy["script-src"]) == len(policy["style-src"]) == 1
    assert not re.search(r"<[^>]+\son[a-z]+\s*=", html, re.I)  # no inline handler
    assert not re.search(r"<[^>]+\sstyle\s*=", html, re.I)  # no inline style attribute


@needs_browser
def test_an_injected_handler_or_script_does_not_run(browser: Browser, hostile: Path) -> None:
    browser.open(hostile)
    assert browser.evaluate("document.body.dataset.ready") == "1"  # the page's own script ran
    background = "getComputedStyle(document.body).backgroundColor"
    assert browser.evaluate(background) == "rgb(250, 250, 250)"  # and its own style applies
    browser.evaluate(
        "(() => { window.ran = []; "
        "document.body.insertAdjacentHTML('beforeend', "
        '\'<img src="data:," onerror="window.ran.push(1)">'
        '<button id=b onclick="window.ran.push(2)">b</button>\'); '
        "const s = document.createElement('script'); s.textContent = 'window.ran.push(3)'; "
        "document.body.appendChild(s); document.getElementById('b').click(); })()"
    )
    browser.wait_for("document.images.length > 0 && document.images[0].complete")
    assert browser.evaluate("window.ran.length") == 0


def test_no_figures_leaves_them_out_and_the_tables_as_they_were(run: Path, tmp_path: Path) -> None:
    copy = tmp_path / "copy"
    shutil.copytree(run, copy)
    again = ["evaluate", str(SAMPLE), "--out", str(copy), "--workers", "0"]
    assert runner.invoke(app, again).exit_code == 0  # every round from the cache; figures drawn
    assert len(list((copy / "figures").glob("*.png"))) == 5
    result = runner.invoke(app, [*again, "--no-figures"])
    assert result.exit_code == 0, result.output
    assert not (copy / "figures").exists()  # the earlier run's figures go with its tables
    report = (copy / "report.md").read_text()
    assert "Not drawn (`--no-figures`)" in report and "![" not in report
    assert "| place | original | replay |" in report  # the table by place stays
    for table in ("players.csv", "rounds.csv", "tables/places.csv"):
        assert (copy / table).read_bytes() == (run / table).read_bytes()
