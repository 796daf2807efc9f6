// data.js: the page's data and the decoding of a round's trace (decoy_cli/replay/view_trace.py).
// Plain ES2017, no library, nothing fetched. Every text from the data is shown through
// textContent or the canvas, never as markup.
const errors = [];
window.addEventListener("error", (e) => {
  errors.push(String(e.message));
  const box = document.getElementById("errors");
  box.hidden = false;
  box.textContent = "error: " + errors.join("; ");
});

const DATA = JSON.parse(document.getElementById("data").textContent);
const $ = (id) => document.getElementById(id);
const NONE = "–"; // the one meaning of the dash on the page: no value (not recorded, not defined)
const TRAIL_S = 4;
const KILL_SHOWN_S = 3;
const HEADING_STEP = 10; // degrees per step of a kept heading
const ROW = 5; // integers per kept frame: t, x, y, z (differences), heading

function el(tag, text, cls) {
  const node = document.createElement(tag);
  if (text !== undefined && text !== null) node.textContent = String(text);
  if (cls) node.className = cls;
  return node;
}

function fmt(value) {
  if (value === null || value === undefined) return NONE;
  if (typeof value === "number") {
    if (Number.isInteger(value)) return String(value);
    const size = Math.abs(value);
    return value.toFixed(size >= 100 ? 1 : size >= 1 ? 2 : 3);
  }
  return String(value);
}

// One segment of a path: [t (s), x, y, z (m), heading (degrees, null not known)] per kept frame.
function decodeSegment(flat) {
  const out = [];
  let t = 0, x = 0, y = 0, z = 0;
  for (let i = 0; i + ROW <= flat.length; i += ROW) {
    t += flat[i]; x += flat[i + 1]; y += flat[i + 2]; z += flat[i + 3];
    const h = flat[i + 4];
    out.push([t / 100, x / 10, y / 10, z / 10, h >= 0 ? h * HEADING_STEP : null]);
  }
  return out;
}

// A list of changes [t (cs), value, ...] as [[t (s), value], ...].
function decodeChanges(flat) {
  const out = [];
  for (let i = 0; i + 1 < (flat || []).length; i += 2) out.push([flat[i] / 100, flat[i + 1]]);
  return out;
}

function decodeRound(round) {
  if (round.decoded) return round.decoded;
  const weapons = round.weapons || [];
  const players = round.players.map((p) => ({
    name: p.name, side: p.side, worst_s: p.worst_s, worst_m: p.worst_m,
    real: p.original.map(decodeSegment), replay: p.replay.map(decodeSegment),
    hpReal: decodeChanges(p.hp_original), hpReplay: decodeChanges(p.hp_replay),
    weapon: decodeChanges(p.weapon).map((c) => [c[0], c[1] >= 0 ? weapons[c[1]] : null]),
  }));
  const events = round.events.map((e) => ({
    t: e[0] / 100, source: e[1], kind: e[2], player: e[3], other: e[4],
    x: e[5] === null ? null : e[5] / 10, y: e[6] === null ? null : e[6] / 10,
    inferred: e[7] || null,
  }));
  const utility = (round.utility || []).map((u) => ({
    start: u[0] / 100, end: u[1] / 100, kind: u[2], x: u[3] / 10, y: u[4] / 10, r: u[5] / 10,
  }));
  round.decoded = { players, events, utility, start: round.start / 100, end: round.end / 100 };
  return round.decoded;
}

// Position and heading of a path at time t (linear between kept frames; the heading of the
// kept frame before), or null where not alive.
function at(path, t) {
  for (const seg of path) {
    if (t < seg[0][0] - 1e-6 || t > seg[seg.length - 1][0] + 1e-6) continue;
    let lo = 0, hi = seg.length - 1;
    while (hi - lo > 1) {
      const mid = (lo + hi) >> 1;
      if (seg[mid][0] <= t) lo = mid; else hi = mid;
    }
    const a = seg[lo], b = seg[hi];
    const span = b[0] - a[0];
    const w = span > 0 ? Math.min(Math.max((t - a[0]) / span, 0), 1) : 0;
    const heading = w >= 1 ? b[4] : a[4];
    return [a[1] + w * (b[1] - a[1]), a[2] + w * (b[2] - a[2]), a[3] + w * (b[3] - a[3]), heading];
  }
  return null;
}

// The value of a list of changes at time t (null before the first).
function valueAt(changes, t) {
  let value = null;
  for (const c of changes) {
    if (c[0] > t + 1e-6) break;
    value = c[1];
  }
  return value;
}

function trail(path, t0, t1) {
  const points = [];
  for (const seg of path) {
    if (seg[seg.length - 1][0] < t0 || seg[0][0] > t1) continue;
    const start = at([seg], Math.max(t0, seg[0][0]));
    if (start) points.push(start);
    for (const p of seg) if (p[0] > t0 && p[0] < t1) points.push([p[1], p[2], p[3]]);
    const end = at([seg], Math.min(t1, seg[seg.length - 1][0]));
    if (end) points.push(end);
  }
  return points;
}

function positionsAt(r, t) {
  return r.players.map((p) => ({ real: at(p.real, t), replay: at(p.replay, t) }));
}

function errorOf(w) {
  if (!w.real || !w.replay) return null;
  return Math.hypot(w.real[0] - w.replay[0], w.real[1] - w.replay[1], w.real[2] - w.replay[2]);
}
