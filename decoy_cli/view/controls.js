// controls.js: the round player's state, its panel, the keys, zoom and pan, and the URL's
// fragment (#round=MATCH:ROUND&t=SECONDS opens that round at that time).
const state = {
  round: -1, t: 0, playing: false, speed: 2, hidden: new Set(), sides: new Set(["T", "CT"]),
  focus: -1, heat: "none",
};
const roundSelect = $("round-select"), slider = $("time"), playButton = $("play");
const HEAT_LAYERS = ["none", "real", "replay", "difference"];

function visible(i, player) {
  return state.sides.has(player.side) && !state.hidden.has(i);
}

function updatePanel(r, where) {
  const clock = state.t.toFixed(1) + " s";
  $("clock").textContent = clock;
  $("cursor-time").textContent = clock;
  slider.value = String(state.t);
  const rows = $("at-cursor").tBodies[0].rows;
  r.players.forEach((p, i) => {
    const w = where[i], error = errorOf(w);
    let text = error === null ? "dead in both" : error.toFixed(2);
    if (error === null && (w.real || w.replay)) text = w.real ? "dead in replay" : "dead in data";
    rows[i].cells[3].textContent = text;
  });
  for (const li of $("events").children) {
    li.classList.toggle("future", Number(li.dataset.t) > state.t + 1e-6);
  }
}

function eventText(r, e) {
  const name = (i) => (i >= 0 && r.players[i] ? r.players[i].name : "unknown");
  const who = e.source === "data" ? (e.inferred ? "inferred" : "real") : "replay";
  const words = {
    kill: () => (e.player >= 0 ? name(e.player) + " → " + name(e.other) : name(e.other) + " dies" +
      (e.source === "replay" ? " (as the data says)" : "")),
    carry: () => name(e.player) + " carries the bomb",
    drop: () => "bomb dropped",
    plant: () => name(e.player) + " plants",
    defuse: () => name(e.player) + " defuses",
    explode: () => "bomb explodes",
  };
  const rule = e.inferred ? " (" + e.inferred + ")" : "";
  const after = e.t > r.end + 1e-6 ? " (after the last frame)" : "";
  return e.t.toFixed(1) + " s · " + who + " · " + (words[e.kind] ? words[e.kind]() : e.kind) + rule + after;
}

// The events as a list of buttons and as marks on the time line; either seeks to its event.
function listEvents(r) {
  const list = $("events"), marks = $("marks");
  list.replaceChildren(); marks.replaceChildren();
  const span = Math.max(r.end - r.start, 1e-6);
  for (const e of r.events) {
    const t = Math.min(e.t, r.end);
    const li = el("li"), button = el("button", eventText(r, e));
    button.type = "button";
    button.addEventListener("click", () => { setPlaying(false); setTime(t); });
    li.dataset.t = String(e.t);
    li.className = e.source === "data" ? (e.inferred ? "inferred" : "real") : "replay";
    li.appendChild(button);
    list.appendChild(li);
    if (e.kind === "carry") continue;
    const mark = el("span", null, "mark " + li.className + " " + e.kind);
    mark.title = button.textContent;
    mark.style.left = (100 * (t - r.start) / span).toFixed(3) + "%";
    mark.addEventListener("click", () => { setPlaying(false); setTime(t); });
    marks.appendChild(mark);
  }
}

function openRound(index, t, focus) {
  state.round = index;
  state.focus = focus === undefined ? -1 : focus;
  roundSelect.value = String(index);
  const round = DATA.rounds[index];
  const r = decodeRound(round);
  state.hidden = new Set();
  $("round-info").textContent = round.info;
  slider.min = String(r.start); slider.max = String(r.end);
  const body = $("at-cursor").tBodies[0];
  body.replaceChildren();
  r.players.forEach((p, i) => {
    const row = document.createElement("tr");
    if (i === state.focus) row.className = "focus";
    const box = el("input"); box.type = "checkbox"; box.checked = true;
    box.setAttribute("aria-label", "show " + p.name);
    box.dataset.player = String(i);
    box.addEventListener("change", () => {
      if (box.checked) state.hidden.delete(i); else state.hidden.add(i);
      draw();
    });
    const show = el("td"); show.appendChild(box);
    const name = el("td");
    const swatch = el("span", null, "swatch"); swatch.style.background = sideColour(p.side);
    name.append(swatch, document.createTextNode(p.name));
    row.append(show, name, el("td", p.side, p.side), el("td", NONE));
    body.appendChild(row);
  });
  listEvents(r);
  setTime(t === undefined ? r.start : t);
}

function setTime(t) {
  if (state.round < 0) return;
  const r = decodeRound(DATA.rounds[state.round]);
  state.t = Math.min(Math.max(t, r.start), r.end);
  draw();
  if (!state.playing) remember();
}

// The round and time in the URL's fragment, without a new history entry; a quarter of a second
// after the last change (a browser's history call costs more than a draw).
let remembering = 0;
function remember() {
  clearTimeout(remembering);
  remembering = setTimeout(rememberNow, 250);
}

function rememberNow() {
  if (state.round < 0) return;
  const fragment = "#round=" + encodeURIComponent(DATA.rounds[state.round].label) + "&t=" + state.t.toFixed(1);
  if (location.hash !== fragment) history.replaceState(null, "", fragment);
}

// The round and time a fragment names (null when it names none of the page's rounds).
function fromFragment() {
  const asked = new URLSearchParams(location.hash.slice(1));
  const label = asked.get("round");
  const index = DATA.rounds.findIndex((r) => r.label === label);
  if (index < 0) return null;
  const t = Number(asked.get("t"));
  return { index, t: asked.has("t") && isFinite(t) ? t : undefined };
}

// ---- playing --------------------------------------------------------------------------------
let last = null;
function frame(now) {
  if (!state.playing) { last = null; return; }
  if (last !== null) {
    const r = decodeRound(DATA.rounds[state.round]);
    setTime(state.t + (now - last) / 1000 * state.speed);
    if (state.t >= r.end) setPlaying(false);
  }
  last = now;
  if (state.playing) requestAnimationFrame(frame);
}

function setPlaying(on) {
  state.playing = on && state.round >= 0;
  playButton.textContent = state.playing ? "pause" : "play";
  if (state.playing) {
    const r = decodeRound(DATA.rounds[state.round]);
    if (state.t >= r.end) setTime(r.start);
    requestAnimationFrame(frame);
  } else if (state.round >= 0) {
    remember();
  }
}

function step(seconds) {
  setPlaying(false);
  setTime(state.t + seconds);
}

const SPEEDS = ["0.5", "1", "2", "4", "8"];
function changeSpeed(by) {
  const speed = $("speed");
  const i = Math.min(Math.max(SPEEDS.indexOf(speed.value) + by, 0), SPEEDS.length - 1);
  speed.value = SPEEDS[i];
  state.speed = Number(speed.value);
}

function changeRound(by) {
  const n = DATA.rounds.length;
  if (!n) return;
  setPlaying(false);
  openRound((state.round + by + n) % n);
}

function setHeat(layer) {
  state.heat = layer;
  $("heat").value = layer;
  draw();
}

function zoomKey(factor) {
  zoomAt(factor, view.size / 2, view.size / 2);
  draw();
}

// ---- keys: on the page whatever control has focus, except while typing in a text field, and
// Space on a button or a check box (which Space presses). Listened to before the control does.
const KEYS = {
  " ": () => setPlaying(!state.playing),
  ArrowRight: (e) => step(e.shiftKey ? 5 : 0.5),
  ArrowLeft: (e) => step(e.shiftKey ? -5 : -0.5),
  Home: () => step(-Infinity),
  End: () => step(Infinity),
  "[": () => changeSpeed(-1),
  "]": () => changeSpeed(1),
  n: () => changeRound(1),
  p: () => changeRound(-1),
  PageDown: () => changeRound(1),
  PageUp: () => changeRound(-1),
  "+": () => zoomKey(1.5),
  "=": () => zoomKey(1.5),
  "-": () => zoomKey(1 / 1.5),
  "0": () => { resetZoom(); draw(); },
  h: () => setHeat(HEAT_LAYERS[(HEAT_LAYERS.indexOf(state.heat) + 1) % HEAT_LAYERS.length]),
};

function typing(target) {
  if (target instanceof HTMLTextAreaElement || (target && target.isContentEditable)) return true;
  return target instanceof HTMLInputElement &&
    !["range", "checkbox", "radio", "button", "submit", "reset"].includes(target.type);
}

window.addEventListener("keydown", (e) => {
  const target = e.target, action = KEYS[e.key];
  if (!action || typing(target) || e.altKey || e.ctrlKey || e.metaKey) return;
  const presses = target instanceof HTMLButtonElement ||
    (target instanceof HTMLInputElement && ["checkbox", "radio"].includes(target.type));
  if (e.key === " " && presses) return;
  if (state.round < 0) return;
  e.preventDefault();
  e.stopPropagation();
  action(e);
}, true);

playButton.addEventListener("click", () => setPlaying(!state.playing));
$("speed").addEventListener("change", () => { state.speed = Number($("speed").value); });
slider.addEventListener("input", () => { setPlaying(false); setTime(Number(slider.value)); });
roundSelect.addEventListener("change", () => { setPlaying(false); openRound(Number(roundSelect.value)); });
$("heat").addEventListener("change", () => setHeat($("heat").value));
for (const box of document.querySelectorAll("input.side")) {
  box.addEventListener("change", () => {
    if (box.checked) state.sides.add(box.value); else state.sides.delete(box.value);
    draw();
  });
}
$("show-real").addEventListener("change", draw);
$("show-replay").addEventListener("change", draw);
$("reset-zoom").addEventListener("click", () => { resetZoom(); draw(); });
window.addEventListener("hashchange", () => {
  const asked = fromFragment();
  if (asked) { setPlaying(false); openRound(asked.index, asked.t); }
});
new ResizeObserver(() => draw()).observe(canvas);

// ---- the mouse on the map: the wheel zooms, a drag pans, hovering names the nearest player ----
canvas.addEventListener("wheel", (e) => {
  e.preventDefault();
  const box = canvas.getBoundingClientRect();
  zoomAt(Math.pow(1.0015, -e.deltaY), e.clientX - box.left, e.clientY - box.top);
  draw();
}, { passive: false });

let drag = null;
canvas.addEventListener("pointerdown", (e) => {
  drag = { x: e.clientX, y: e.clientY };
  canvas.setPointerCapture(e.pointerId);
});
canvas.addEventListener("pointerup", () => { drag = null; });
canvas.addEventListener("pointermove", (e) => {
  if (drag) {
    pan(e.clientX - drag.x, e.clientY - drag.y);
    drag = { x: e.clientX, y: e.clientY };
    draw();
    return;
  }
  hover(e);
});

function hover(e) {
  if (state.round < 0) return;
  const box = canvas.getBoundingClientRect();
  const x = e.clientX - box.left, y = e.clientY - box.top;
  const r = decodeRound(DATA.rounds[state.round]);
  const where = positionsAt(r, state.t);
  let best = null, bestD = 15;
  r.players.forEach((p, i) => {
    if (!visible(i, p)) return;
    for (const pos of [where[i].real, where[i].replay]) {
      if (!pos) continue;
      const d = Math.hypot(px(pos[0]) - x, py(pos[1]) - y);
      if (d < bestD) { best = i; bestD = d; }
    }
  });
  if (best === null) { $("hover").textContent = ""; return; }
  const p = r.players[best], error = errorOf(where[best]);
  const weapon = valueAt(p.weapon, state.t);
  const hp = (changes) => { const v = valueAt(changes, state.t); return v === null || v < 0 ? NONE : String(v); };
  $("hover").textContent = p.name + " (" + p.side + "): " +
    (error === null ? "not alive in both" : error.toFixed(2) + " m between real and replay") +
    " · weapon " + (weapon === null ? NONE : weapon) + " · HP real " + hp(p.hpReal) + ", replay " + hp(p.hpReplay);
}
