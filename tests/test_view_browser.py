"""The view page in a headless Chromium, issue 52: keys that work whatever control has focus,
the legend's colours against the picture, a crisp canvas at any device pixel ratio, the map's
aspect and the controls' place from 390 px to 1024 x 768, the URL's fragment, the player-round
list (sort marker, readable columns, a chosen row's player), the slider's end, zoom and pan, the
heatmap layer, clickable events; and the trace's HP, heading and weapon against the round.

One `decoy evaluate` of the shipped sample (tests/conftest.py) serves the module and test_view.py.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from browser import Browser, find_chromium
from test_view import _clock, _set_slider, needs_browser, page_data, shown_players

from decoy_cli.replay.view_trace import HEADING_STEP, decode_path
from decoy_cli.view.page import winner_info

pytestmark = needs_browser


@pytest.fixture(scope="module")
def chromium() -> Iterator[Browser]:
    executable = find_chromium()
    assert executable is not None
    with Browser(executable) as browser:
        yield browser


def _window(browser: Browser, width: int, height: int, ratio: float = 1) -> None:
    browser.call(
        "Emulation.setDeviceMetricsOverride",
        {"width": width, "height": height, "deviceScaleFactor": ratio, "mobile": width < 600},
        session=True,
    )


@pytest.fixture
def browser(chromium: Browser) -> Browser:
    _window(chromium, 1300, 1000)
    return chromium


def _box(browser: Browser, selector: str) -> dict[str, float]:
    return browser.evaluate(
        f"(() => {{ const r = document.querySelector({json.dumps(selector)})"
        ".getBoundingClientRect(); return {x: r.x, y: r.y, w: r.width, h: r.height}; })()"
    )


def _colours(browser: Browser) -> set[tuple[int, int, int]]:
    """The opaque colours of the map's pixels."""
    pixels = browser.evaluate(
        "(() => { const c = document.getElementById('map'); "
        "return Array.from(c.getContext('2d').getImageData(0, 0, c.width, c.height).data); })()"
    )
    rgba = np.asarray(pixels, np.uint8).reshape(-1, 4)
    return {tuple(p[:3]) for p in rgba[rgba[:, 3] == 255].tolist()}


def _hex(colour: str) -> tuple[int, int, int]:
    return (int(colour[1:3], 16), int(colour[3:5], 16), int(colour[5:7], 16))


def _pick_round(browser: Browser, index: int) -> None:
    browser.evaluate(
        "(() => { const s = document.getElementById('round-select'); s.focus(); "
        f"s.value = '{index}'; s.dispatchEvent(new Event('change')); }})()"
    )


RIGHT = ("ArrowRight", "ArrowRight", 39)


# ---- keys ---------------------------------------------------------------------------------------


def test_keys_work_after_picking_a_round_in_the_dropdown(browser: Browser, run: Path) -> None:
    browser.open(run / "view.html")
    _pick_round(browser, 2)
    assert browser.evaluate("document.activeElement.id") == "round-select"
    browser.key(*RIGHT)
    assert browser.evaluate("document.getElementById('round-select').value") == "2"
    assert _clock(browser) == pytest.approx(0.5)
    browser.key(" ", "Space", 32)
    assert browser.evaluate("document.getElementById('play').textContent") == "pause"
    browser.key(" ", "Space", 32)
    assert browser.evaluate("document.getElementById('play').textContent") == "play"
    browser.key("n", "KeyN", 78)
    assert browser.evaluate("document.getElementById('round-select').value") == "3"
    browser.key("p", "KeyP", 80)
    browser.key("p", "KeyP", 80)
    assert browser.evaluate("document.getElementById('round-select').value") == "1"
    assert browser.console_errors() == []


def test_keys_work_after_dragging_the_slider(browser: Browser, run: Path) -> None:
    browser.open(run / "view.html")
    browser.evaluate("document.getElementById('time').focus()")
    _set_slider(browser, 10)
    browser.key(*RIGHT)
    assert _clock(browser) == pytest.approx(10.5)  # a frame, not the slider's 0.1 s
    browser.key(*RIGHT, shift=True)
    assert _clock(browser) == pytest.approx(15.5)
    browser.key("]", "BracketRight", 221)
    assert browser.evaluate("document.getElementById('speed').value") == "4"
    browser.key("[", "BracketLeft", 219)
    browser.key("[", "BracketLeft", 219)
    assert browser.evaluate("document.getElementById('speed').value") == "1"


# ---- the picture --------------------------------------------------------------------------------


def test_the_legend_s_colours_are_those_drawn(browser: Browser, run: Path) -> None:
    browser.open(run / "view.html")
    legend = browser.evaluate(
        "Array.from(document.querySelectorAll('#legend [data-colour]'))"
        ".map((m) => [m.parentNode.textContent, m.dataset.colour])"
    )
    colours = {text: colour for text, colour in legend}
    kill = next(c for text, c in colours.items() if text.startswith("a real kill"))
    joined = next(c for text, c in colours.items() if "joined" in text)
    assert kill != joined
    data = page_data(run / "view.html")
    first = min(e[0] for e in data["rounds"][0]["events"] if e[1:3] == ["data", "kill"]) / 100
    _set_slider(browser, first - 1)
    before = _colours(browser)
    _set_slider(browser, first + 0.5)
    after = _colours(browser)
    assert _hex(kill) not in before and _hex(kill) in after  # kills are drawn in their colour
    assert _hex(colours[next(t for t in colours if t.startswith("real T"))]) in before


def test_the_canvas_is_crisp_at_any_device_pixel_ratio(chromium: Browser, run: Path) -> None:
    for ratio in (1, 2, 1.5):
        _window(chromium, 1300, 1000, ratio)
        chromium.open(run / "view.html")
        width, height, css = chromium.evaluate(
            "(() => { const c = document.getElementById('map'); "
            "return [c.width, c.height, c.getBoundingClientRect().width]; })()"
        )
        assert width == height == round(css * ratio), ratio


@pytest.mark.parametrize(("width", "height"), [(390, 844), (1024, 768), (360, 640), (3840, 2160)])
def test_the_map_stays_square_and_the_controls_in_reach(
    chromium: Browser, run: Path, width: int, height: int
) -> None:
    _window(chromium, width, height)
    chromium.open(run / "view.html")
    chromium.evaluate("document.getElementById('round').scrollIntoView()")
    canvas, play, slider = (_box(chromium, s) for s in ("#map", "#play", "#time"))
    assert abs(canvas["w"] - canvas["h"]) <= 1 and canvas["w"] >= min(width, height) * 0.8
    assert canvas["x"] >= 0 and canvas["x"] + canvas["w"] <= width
    if width < 760:  # narrow: the controls under the map
        assert play["y"] >= canvas["y"] + canvas["h"]
    else:  # wide: beside it, map and controls in the window at once
        assert play["x"] >= canvas["x"] + canvas["w"]
        assert canvas["y"] + canvas["h"] <= height and slider["y"] + slider["h"] <= height
    assert chromium.console_errors() == []


def test_zoom_pan_and_reset(browser: Browser, run: Path) -> None:
    browser.open(run / "view.html")
    _set_slider(browser, 20)
    whole = browser.screenshot()
    box = _box(browser, "#map")
    centre = {"x": box["x"] + box["w"] / 2, "y": box["y"] + box["h"] / 2}
    browser.call(
        "Input.dispatchMouseEvent",
        {"type": "mouseWheel", **centre, "deltaX": 0, "deltaY": -400},
        session=True,
    )
    zoomed = browser.screenshot()
    assert zoomed != whole
    for kind, dx in (("mousePressed", 0), ("mouseMoved", 60), ("mouseReleased", 60)):
        point = {"x": centre["x"] + dx, "y": centre["y"]}
        browser.call(
            "Input.dispatchMouseEvent",
            {
                "type": kind,
                **point,
                "button": "left",
                "buttons": 1 if kind != "mouseReleased" else 0,
                "clickCount": 1,
            },
            session=True,
        )
    assert browser.screenshot() not in (whole, zoomed)
    browser.evaluate("document.activeElement.blur()")
    browser.key("0", "Digit0", 48)
    assert browser.screenshot() == whole


def test_hovering_a_player_names_him_his_weapon_and_hp(browser: Browser, run: Path) -> None:
    data = page_data(run / "view.html")
    browser.open(run / "view.html")
    _set_slider(browser, 20)
    assert browser.evaluate("document.getElementById('hover').textContent") == ""
    box = _box(browser, "#map")
    text = ""
    for y in np.linspace(box["y"] + 5, box["y"] + box["h"] - 5, 40):  # until a player is hit
        for x in np.linspace(box["x"] + 5, box["x"] + box["w"] - 5, 40):
            browser.call(
                "Input.dispatchMouseEvent",
                {"type": "mouseMoved", "x": float(x), "y": float(y)},
                session=True,
            )
            text = browser.evaluate("document.getElementById('hover').textContent")
            if text:
                break
        if text:
            break
    names = {p["name"] for shown in data["rounds"] for p in shown["players"]}
    name = text.split(" (")[0]
    assert name in names, text
    weapon = text.split(" · weapon ")[1].split(" · ")[0]
    assert weapon and weapon != "–" and " · HP real " in text, text


def test_the_heatmap_layer(browser: Browser, run: Path) -> None:
    browser.open(run / "view.html")
    _set_slider(browser, 20)
    shots = []
    for layer in ("none", "real", "replay", "difference", "none"):
        browser.evaluate(
            "(() => { const s = document.getElementById('heat'); "
            f"s.value = '{layer}'; s.dispatchEvent(new Event('change')); }})()"
        )
        shots.append(browser.screenshot())
    assert len(set(shots[:4])) == 4 and shots[4] == shots[0]
    heat = page_data(run / "view.html")["heat"]
    assert sum(heat["real"][1::2]) > 0 and sum(heat["replay"][1::2]) > 0


# ---- time, events, the URL ----------------------------------------------------------------------


def test_the_slider_ends_at_the_data_s_last_frame(browser: Browser, run: Path) -> None:
    data = page_data(run / "view.html")
    browser.open(run / "view.html")
    for index, shown in enumerate(data["rounds"]):
        _pick_round(browser, index)
        assert float(browser.evaluate("document.getElementById('time').max")) == shown["end"] / 100
    late = [e for e in data["rounds"][0]["events"] if e[0] > data["rounds"][0]["end"]]
    assert late  # the sample's first round has events after its last frame: listed, not reached
    _pick_round(browser, 0)
    texts = browser.evaluate(
        "Array.from(document.querySelectorAll('#events li')).map((li) => li.textContent)"
    )
    assert sum("(after the last frame)" in text for text in texts) == len(late)


def test_an_event_or_its_mark_seeks_to_it(browser: Browser, run: Path) -> None:
    data = page_data(run / "view.html")
    browser.open(run / "view.html")
    kills = [
        e
        for e in data["rounds"][0]["events"]
        if e[2] == "kill" and e[0] <= data["rounds"][0]["end"]
    ]
    index = data["rounds"][0]["events"].index(kills[1])
    browser.evaluate(f"document.querySelectorAll('#events li button')[{index}].click()")
    assert _clock(browser) == pytest.approx(kills[1][0] / 100, abs=0.05)
    marks = browser.evaluate("document.querySelectorAll('#marks .mark').length")
    assert marks == sum(e[2] != "carry" for e in data["rounds"][0]["events"])
    browser.evaluate("document.querySelector('#marks .mark').click()")
    assert _clock(browser) == pytest.approx(kills[0][0] / 100, abs=0.05)


def test_the_fragment_opens_a_round_at_a_time(browser: Browser, run: Path) -> None:
    data = page_data(run / "view.html")
    label = data["rounds"][3]["label"]
    url = (run / "view.html").resolve().as_uri() + f"#round={label}&t=25"
    browser.call("Page.navigate", {"url": "about:blank"}, session=True)
    browser.call("Page.navigate", {"url": url}, session=True)
    browser.wait_for("document.body && document.body.dataset.ready === '1'")
    assert browser.evaluate("document.getElementById('round-select').value") == "3"
    assert _clock(browser) == pytest.approx(25.0)
    _set_slider(browser, 30)  # and the fragment follows the round and time shown
    browser.wait_for(
        f"decodeURIComponent(location.hash) === {json.dumps(f'#round={label}&t=30.0')}"
    )


# ---- the player-round list ----------------------------------------------------------------------


def test_the_list_s_sort_marker_names_and_chosen_row(browser: Browser, run: Path) -> None:
    browser.open(run / "view.html")
    heads = browser.evaluate(
        "Array.from(document.querySelectorAll('#player-table thead button'))"
        ".map((b) => b.textContent)"
    )
    assert "mean distance (m)" in heads and "mean_dist" not in heads
    column = heads.index("largest distance (m)")
    button = f"document.querySelectorAll('#player-table thead button')[{column}]"
    browser.evaluate(f"{button}.click()")
    assert browser.evaluate(f"{button}.textContent") == "largest distance (m) ▼"
    browser.evaluate(f"{button}.click()")
    assert browser.evaluate(f"{button}.textContent") == "largest distance (m) ▲"
    row = "document.querySelectorAll('#player-table tbody tr')[3]"
    browser.evaluate(f"{row}.click()")
    plain = browser.screenshot()
    assert browser.evaluate(f"{row}.className") == "chosen"
    player = int(browser.evaluate(f"Number({row}.dataset.row)"))
    t = _clock(browser)
    data = page_data(run / "view.html")
    focused = browser.evaluate(
        "Array.from(document.querySelectorAll('#at-cursor tbody tr'))"
        ".findIndex((r) => r.className === 'focus')"
    )
    assert focused == data["players"]["player"][player]
    browser.evaluate(
        "(() => { const s = document.getElementById('round-select'); "
        "s.dispatchEvent(new Event('change')); })()"
    )  # the same round opened again: nobody highlighted
    _set_slider(browser, t)
    assert browser.screenshot() != plain


def test_dead_in_both_is_said(browser: Browser, run: Path) -> None:
    data = page_data(run / "view.html")
    browser.open(run / "view.html")
    _set_slider(browser, data["rounds"][0]["end"] / 100)
    cells = browser.evaluate(
        "Array.from(document.querySelectorAll('#at-cursor tbody tr'))"
        ".map((r) => r.cells[3].textContent)"
    )
    assert "–" not in cells and "dead in both" in cells


def test_the_winner_is_said_in_words() -> None:
    said = winner_info(None, None, None, None, {"T"})
    assert "–" not in said and said.startswith("winner data: none, replay: none")
    assert "only the T side" in said
    assert winner_info("CT", "BombDefused", "T", None, {"T", "CT"}) == (
        "winner data: CT (BombDefused), replay: T"
    )


def test_the_title_names_what_was_evaluated(run: Path) -> None:
    assert page_data(run / "view.html")["title"] == "decoy evaluate: sample"


# ---- the trace's HP, heading and weapon ---------------------------------------------------------


def _changes_at(changes: list[int], seconds: np.ndarray) -> list[Any]:
    times, values = changes[0::2], changes[1::2]
    return [values[max(np.searchsorted(times, round(t * 100), "right") - 1, 0)] for t in seconds]


def test_the_trace_s_hp_weapon_and_heading_follow_the_round(run: Path) -> None:
    for shown, round_, seconds, p, player, alive in shown_players(run):
        hp = _changes_at(player["hp_original"], seconds)
        assert np.array_equal(np.where(alive, round_.hp[p], 0), hp)
        held = [
            shown["weapons"][i] if i >= 0 else "" for i in _changes_at(player["weapon"], seconds)
        ]
        assert [w if a else "" for w, a in zip(round_.weapon[p], alive, strict=True)] == held
        for segment in player["original"]:
            kept = decode_path(segment)
            frames = np.searchsorted(seconds, kept[:, 0] - 1e-6)
            turn = np.abs((kept[:, 4] - round_.yaw[p, frames] + 180) % 360 - 180)
            assert turn.max() <= HEADING_STEP / 2 + 1e-6


def test_an_older_trace_without_hp_still_draws(
    chromium: Browser, run: Path, tmp_path: Path
) -> None:
    shutil.copytree(run, tmp_path / "run")  # its page rewritten without the new fields
    page = tmp_path / "run" / "view.html"
    html = page.read_text(encoding="utf-8")
    for field in ("hp_original", "hp_replay", "weapon"):
        html = html.replace(f'"{field}":', f'"old_{field}":')
    page.write_text(html, encoding="utf-8")
    _window(chromium, 1300, 1000)
    chromium.open(page)
    _set_slider(chromium, 30)
    assert chromium.console_errors() == []
