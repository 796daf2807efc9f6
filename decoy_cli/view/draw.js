// draw.js: the map. The canvas's backing store is its CSS size times the device pixel ratio, and
// everything is drawn in CSS pixels through that scale, so lines and text are crisp at any ratio.
// The floor (nav areas, the run's heatmap, the places' names) is drawn once per view into a
// second canvas and copied; players, trails, kills, the bomb and smokes are drawn over it.
const COLOUR = {
  T: "#d35400", CT: "#1f5fa8", other: "#555555",
  join: "#9a9a9a", // the line joining a player's real and replayed positions
  kill: "#8e24aa", // attacker to victim, 3 s after the kill: dashed real, solid replay
  deathReal: "#7f8c8d", // the replay's deaths are crosses in the side's colour
  bomb: "#b7950b", bombFill: "#f4d03f", defused: "#1e8449", defusedFill: "#58d68d",
  smoke: "rgba(128, 128, 128, 0.45)", fire: "rgba(230, 110, 20, 0.35)",
  hpReal: "#444444", hpBack: "#e0e0e0", focus: "rgba(255, 190, 0, 0.75)", place: "rgba(60, 50, 40, 0.7)",
};
const sideColour = (side) => COLOUR[side === "T" || side === "CT" ? side : "other"];

const canvas = $("map");
const ctx = canvas.getContext("2d");
const floor = document.createElement("canvas");
const view = { size: 1, ratio: 1, scale0: 1, k: 1, cx: 0, cy: 0, bounds: null, floorKey: "" };
const MAX_ZOOM = 16;

function mapBounds() {
  const a = DATA.map.areas;
  let x0 = Infinity, y0 = Infinity, x1 = -Infinity, y1 = -Infinity;
  for (let i = 0; i < a.length; i += 5) {
    x0 = Math.min(x0, a[i]); y0 = Math.min(y0, a[i + 1]);
    x1 = Math.max(x1, a[i + 2]); y1 = Math.max(y1, a[i + 3]);
  }
  if (!isFinite(x0)) return [-10, -10, 10, 10];
  return [x0 / 10, y0 / 10, x1 / 10, y1 / 10];
}

// The backing store's size follows the canvas's CSS size and the device pixel ratio.
function fitCanvas() {
  const size = Math.max(canvas.getBoundingClientRect().width, 1), ratio = window.devicePixelRatio || 1;
  const backing = Math.round(size * ratio);
  if (canvas.width !== backing || canvas.height !== backing) {
    canvas.width = backing; canvas.height = backing;
  }
  if (!view.bounds) { view.bounds = mapBounds(); resetZoom(); }
  view.size = size; view.ratio = backing / size;
  const b = view.bounds, margin = Math.min(20, size / 20);
  view.scale0 = (size - 2 * margin) / Math.max(b[2] - b[0], b[3] - b[1], 1);
}

function resetZoom() {
  const b = view.bounds || mapBounds();
  view.k = 1; view.cx = (b[0] + b[2]) / 2; view.cy = (b[1] + b[3]) / 2;
}

// Zoom by `factor` keeping the map point under (sx, sy) (CSS pixels) where it is.
function zoomAt(factor, sx, sy) {
  const k = Math.min(Math.max(view.k * factor, 1), MAX_ZOOM);
  const x = wx(sx), y = wy(sy);
  view.k = k;
  view.cx = x - (sx - view.size / 2) / (view.scale0 * k);
  view.cy = y + (sy - view.size / 2) / (view.scale0 * k);
}

function pan(dx, dy) {
  view.cx -= dx / (view.scale0 * view.k); view.cy += dy / (view.scale0 * view.k);
}

const px = (x) => view.size / 2 + (x - view.cx) * view.scale0 * view.k;
const py = (y) => view.size / 2 - (y - view.cy) * view.scale0 * view.k;
const wx = (sx) => view.cx + (sx - view.size / 2) / (view.scale0 * view.k);
const wy = (sy) => view.cy - (sy - view.size / 2) / (view.scale0 * view.k);

// ---- the floor, the heatmap, the places ---------------------------------------------------------
function drawFloor() {
  const key = [canvas.width, view.k, view.cx, view.cy, state.heat].join();
  if (key === view.floorKey) return;
  view.floorKey = key;
  floor.width = canvas.width; floor.height = canvas.height;
  const g = floor.getContext("2d");
  g.setTransform(view.ratio, 0, 0, view.ratio, 0, 0);
  const a = DATA.map.areas;
  let z0 = Infinity, z1 = -Infinity;
  for (let i = 4; i < a.length; i += 5) { z0 = Math.min(z0, a[i]); z1 = Math.max(z1, a[i]); }
  const zs = z1 > z0 ? z1 - z0 : 1;
  g.fillStyle = "#ffffff"; g.fillRect(0, 0, view.size, view.size);
  g.lineWidth = 0.5;
  for (let i = 0; i < a.length; i += 5) { // sorted by height: upper floors drawn over lower
    const light = Math.round(56 + 36 * (a[i + 4] - z0) / zs);
    g.fillStyle = "hsl(35, 18%, " + light + "%)";
    g.strokeStyle = "hsl(35, 18%, " + (light - 14) + "%)";
    const x = px(a[i] / 10), y = py(a[i + 3] / 10);
    const w = px(a[i + 2] / 10) - x, h = py(a[i + 1] / 10) - y;
    g.fillRect(x, y, w, h);
    g.strokeRect(x, y, w, h);
  }
  if (state.heat !== "none") drawHeat(g, state.heat);
  g.fillStyle = COLOUR.place; g.textAlign = "center"; g.textBaseline = "middle";
  g.font = (view.size < 500 ? 8 : 10) + "px system-ui, sans-serif";
  for (const [x, y, name] of DATA.map.places || []) g.fillText(name, px(x / 10), py(y / 10));
}

// Shares of the position samples per cell, of the data ("real"), of the replay, or their
// difference (replay − real: red where the replay is more often, blue where less).
function heatShares(which) {
  const h = DATA.heat, out = new Map();
  const add = (list, sign) => {
    let total = 0;
    for (let i = 1; i < list.length; i += 2) total += list[i];
    for (let i = 0; i + 1 < list.length; i += 2) {
      out.set(list[i], (out.get(list[i]) || 0) + sign * list[i + 1] / Math.max(total, 1));
    }
  };
  if (which !== "replay") add(h.real, which === "difference" ? -1 : 1);
  if (which !== "real") add(h.replay, 1);
  return out;
}

function drawHeat(g, which) {
  if (!DATA.heat) return;
  const h = DATA.heat, shares = heatShares(which);
  let top = 0;
  for (const v of shares.values()) top = Math.max(top, Math.abs(v));
  if (top <= 0) return;
  const cell = h.cell / 10;
  for (const [index, v] of shares) {
    const i = index % h.nx, j = Math.floor(index / h.nx);
    const x = h.x0 / 10 + i * cell, y = h.y0 / 10 + j * cell;
    const strength = Math.sqrt(Math.abs(v) / top);
    if (strength < 0.02) continue;
    const hue = which === "difference" ? (v > 0 ? "200, 30, 30" : "30, 70, 200") : "200, 30, 30";
    g.fillStyle = "rgba(" + hue + ", " + (0.15 + 0.7 * strength).toFixed(3) + ")";
    const sx = px(x), sy = py(y + cell);
    g.fillRect(sx, sy, px(x + cell) - sx, py(y) - sy);
  }
}

// ---- the round at the current time -----------------------------------------------------------
function line(points, colour, width, dash) {
  if (points.length < 2) return;
  ctx.strokeStyle = colour; ctx.lineWidth = width;
  ctx.setLineDash(dash);
  ctx.beginPath();
  ctx.moveTo(px(points[0][0]), py(points[0][1]));
  for (let i = 1; i < points.length; i++) ctx.lineTo(px(points[i][0]), py(points[i][1]));
  ctx.stroke();
  ctx.setLineDash([]);
}

function cross(x, y, colour, size) {
  ctx.strokeStyle = colour; ctx.lineWidth = 2.5;
  ctx.beginPath();
  ctx.moveTo(px(x) - size, py(y) - size); ctx.lineTo(px(x) + size, py(y) + size);
  ctx.moveTo(px(x) + size, py(y) - size); ctx.lineTo(px(x) - size, py(y) + size);
  ctx.stroke();
}

// The heading as a short tick from a position (0 = +x, counter-clockwise).
function tick(pos, colour, from) {
  if (pos[3] === null || pos[3] === undefined) return;
  const a = pos[3] * Math.PI / 180, x = px(pos[0]), y = py(pos[1]);
  ctx.strokeStyle = colour; ctx.lineWidth = 2;
  ctx.beginPath();
  ctx.moveTo(x + from * Math.cos(a), y - from * Math.sin(a));
  ctx.lineTo(x + (from + 7) * Math.cos(a), y - (from + 7) * Math.sin(a));
  ctx.stroke();
}

function bombAt(r, source, t, where) {
  let bomb = null, inferred = false;
  for (const e of r.events) {
    if (e.source !== source || e.t > t + 1e-6 || e.kind === "kill") continue;
    inferred = Boolean(e.inferred);
    if (e.kind === "carry") bomb = { carrier: e.player };
    else if (e.x === null) bomb = null; // where is not known
    else if (e.kind === "drop") bomb = { x: e.x, y: e.y };
    else if (e.kind === "plant" || e.kind === "explode") bomb = { x: e.x, y: e.y, planted: true };
    else if (e.kind === "defuse") bomb = { x: e.x, y: e.y, defused: true };
  }
  if (!bomb) return null;
  bomb.inferred = inferred;
  if (bomb.carrier !== undefined) {
    const p = where[bomb.carrier];
    const pos = p && (source === "data" ? p.real : p.replay);
    if (!pos) return null;
    bomb.x = pos[0]; bomb.y = pos[1];
  }
  return bomb;
}

function drawBomb(bomb, hollow) {
  if (!bomb) return;
  const s = bomb.planted || bomb.defused ? 8 : 5, off = bomb.carrier !== undefined ? 7 : 0;
  ctx.save();
  ctx.translate(px(bomb.x) + off, py(bomb.y) - off);
  ctx.rotate(Math.PI / 4);
  ctx.lineWidth = 2;
  ctx.strokeStyle = bomb.defused ? COLOUR.defused : COLOUR.bomb;
  ctx.fillStyle = bomb.defused ? COLOUR.defusedFill : COLOUR.bombFill;
  if (bomb.inferred) ctx.setLineDash([2, 2]);
  if (!hollow) ctx.fillRect(-s / 2, -s / 2, s, s);
  ctx.strokeRect(-s / 2, -s / 2, s, s);
  ctx.restore();
}

function drawUtility(r, t) {
  for (const u of r.utility) {
    if (t < u.start || t >= u.end) continue;
    ctx.beginPath();
    ctx.arc(px(u.x), py(u.y), Math.abs(px(u.x + u.r) - px(u.x)), 0, 2 * Math.PI);
    ctx.fillStyle = u.kind === "smoke" ? COLOUR.smoke : COLOUR.fire;
    ctx.fill();
  }
}

function drawKills(r, t, where, show) {
  for (const e of r.events) { // deaths so far; kills of the last seconds as lines
    if (e.kind !== "kill" || e.t > t) continue;
    const victim = r.players[e.other], isReal = e.source === "data";
    if (!victim || !visible(e.other, victim) || !show[e.source] || e.x === null) continue;
    cross(e.x, e.y, isReal ? COLOUR.deathReal : sideColour(victim.side), 5);
    if (t - e.t > KILL_SHOWN_S || e.player < 0 || !where[e.player]) continue;
    const from = at(isReal ? r.players[e.player].real : r.players[e.player].replay, e.t);
    if (from) line([from, [e.x, e.y]], COLOUR.kill, 2, isReal ? [5, 3] : []);
  }
}

// Name, then the HP bars (real above, replay below), placed where no earlier label is.
function label(placed, x, y, text, hp) {
  const w = ctx.measureText(text).width + 2, h = 19;
  const tries = [[8, -14], [8, 6], [-8 - w, -14], [-8 - w, 6], [8, -32], [8, 24]];
  let box = null;
  for (const [dx, dy] of tries) {
    const b = [x + dx, y + dy, w, h];
    if (!placed.some((o) => b[0] < o[0] + o[2] && o[0] < b[0] + b[2] && b[1] < o[1] + o[3] && o[1] < b[1] + b[3])) {
      box = b; break;
    }
  }
  box = box || [x + 8, y - 14, w, h];
  placed.push(box);
  ctx.fillStyle = "#111";
  ctx.fillText(text, box[0], box[1] + 10);
  hp.forEach((bar, k) => {
    if (bar.value === null || bar.value < 0) return; // not known
    const by = box[1] + 13 + 3 * k, bw = 20;
    ctx.fillStyle = COLOUR.hpBack; ctx.fillRect(box[0], by, bw, 2);
    ctx.fillStyle = bar.colour;
    ctx.fillRect(box[0], by, bw * Math.min(Math.max(bar.value, 0), 100) / 100, 2);
  });
}

function draw() {
  if (state.round < 0) return;
  fitCanvas();
  drawFloor();
  const r = decodeRound(DATA.rounds[state.round]);
  const t = state.t;
  const show = { data: $("show-real").checked, replay: $("show-replay").checked };
  ctx.setTransform(1, 0, 0, 1, 0, 0);
  ctx.drawImage(floor, 0, 0);
  ctx.setTransform(view.ratio, 0, 0, view.ratio, 0, 0);
  drawUtility(r, t);
  const where = positionsAt(r, t);
  r.players.forEach((p, i) => {
    if (!visible(i, p)) return;
    if (show.data) line(trail(p.real, t - TRAIL_S, t), sideColour(p.side), 1.5, [4, 3]);
    if (show.replay) line(trail(p.replay, t - TRAIL_S, t), sideColour(p.side), 1.5, []);
  });
  drawKills(r, t, where, show);
  const placed = [];
  ctx.font = "11px system-ui, sans-serif";
  r.players.forEach((p, i) => {
    if (!visible(i, p)) return;
    const colour = sideColour(p.side);
    const a = show.data ? where[i].real : null, b = show.replay ? where[i].replay : null;
    if (i === state.focus) {
      for (const pos of [a, b]) {
        if (!pos) continue;
        ctx.strokeStyle = COLOUR.focus; ctx.lineWidth = 5;
        ctx.beginPath(); ctx.arc(px(pos[0]), py(pos[1]), 11, 0, 2 * Math.PI); ctx.stroke();
      }
    }
    if (a && b) line([a, b], COLOUR.join, 1, []);
    if (a) {
      ctx.strokeStyle = colour; ctx.lineWidth = 2;
      ctx.beginPath(); ctx.arc(px(a[0]), py(a[1]), 6, 0, 2 * Math.PI); ctx.stroke();
      tick(a, colour, 6);
    }
    if (b) {
      ctx.fillStyle = colour;
      ctx.beginPath(); ctx.arc(px(b[0]), py(b[1]), 4.5, 0, 2 * Math.PI); ctx.fill();
      tick(b, colour, 4.5);
    }
    const at = b || a;
    if (at) {
      label(placed, px(at[0]), py(at[1]), p.name, [
        { value: a ? valueAt(p.hpReal, t) : null, colour: COLOUR.hpReal },
        { value: b ? valueAt(p.hpReplay, t) : null, colour: colour },
      ]);
    }
  });
  if (show.data) drawBomb(bombAt(r, "data", t, where), true);
  if (show.replay) drawBomb(bombAt(r, "replay", t, where), false);
  updatePanel(r, where);
}
