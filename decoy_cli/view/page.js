"use strict";
// The view page of decoy: plain ES2017, no library, nothing fetched. Every text from the data
// is shown through textContent or the canvas, never as markup.
(function () {
  const errors = [];
  window.addEventListener("error", (e) => {
    errors.push(String(e.message));
    const box = document.getElementById("errors");
    box.hidden = false;
    box.textContent = "error: " + errors.join("; ");
  });

  const DATA = JSON.parse(document.getElementById("data").textContent);
  const SIDE_COLOUR = { T: "#d35400", CT: "#1f5fa8" };
  const TRAIL_S = 4;
  const KILL_SHOWN_S = 3;
  const $ = (id) => document.getElementById(id);

  function el(tag, text, cls) {
    const node = document.createElement(tag);
    if (text !== undefined && text !== null) node.textContent = String(text);
    if (cls) node.className = cls;
    return node;
  }

  function fmt(value) {
    if (value === null || value === undefined) return "–";
    if (typeof value === "number") {
      if (Number.isInteger(value)) return String(value);
      const size = Math.abs(value);
      return value.toFixed(size >= 100 ? 1 : size >= 1 ? 2 : 3);
    }
    return String(value);
  }

  // ---- decoding -----------------------------------------------------------------------------
  function decodeSegment(flat) {
    const out = [];
    let t = 0, x = 0, y = 0, z = 0;
    for (let i = 0; i < flat.length; i += 4) {
      t += flat[i]; x += flat[i + 1]; y += flat[i + 2]; z += flat[i + 3];
      out.push([t / 100, x / 10, y / 10, z / 10]);
    }
    return out;
  }

  function decodeRound(round) {
    if (round.decoded) return round.decoded;
    const players = round.players.map((p) => ({
      name: p.name, side: p.side, worst_s: p.worst_s, worst_m: p.worst_m,
      real: p.original.map(decodeSegment), replay: p.replay.map(decodeSegment),
    }));
    const events = round.events.map((e) => ({
      t: e[0] / 100, source: e[1], kind: e[2], player: e[3], other: e[4],
      x: e[5] === null ? null : e[5] / 10, y: e[6] === null ? null : e[6] / 10,
      inferred: e[7] || null,
    }));
    let end = round.end / 100;
    for (const e of events) end = Math.max(end, e.t);
    const utility = (round.utility || []).map((u) => ({
      start: u[0] / 100, end: u[1] / 100, kind: u[2], x: u[3] / 10, y: u[4] / 10, r: u[5] / 10,
    }));
    round.decoded = { players, events, utility, start: round.start / 100, end };
    return round.decoded;
  }

  // Position of a path at time t (linear between kept frames), or null where not alive.
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
      return [a[1] + w * (b[1] - a[1]), a[2] + w * (b[2] - a[2]), a[3] + w * (b[3] - a[3])];
    }
    return null;
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

  // ---- the map ------------------------------------------------------------------------------
  const canvas = $("map");
  const ctx = canvas.getContext("2d");
  const view = { x0: 0, y0: 0, scale: 1, size: canvas.width };
  const floor = document.createElement("canvas");

  function fitMap() {
    const a = DATA.map.areas;
    let x0 = Infinity, y0 = Infinity, x1 = -Infinity, y1 = -Infinity;
    for (let i = 0; i < a.length; i += 5) {
      x0 = Math.min(x0, a[i]); y0 = Math.min(y0, a[i + 1]);
      x1 = Math.max(x1, a[i + 2]); y1 = Math.max(y1, a[i + 3]);
    }
    if (!isFinite(x0)) { x0 = -100; y0 = -100; x1 = 100; y1 = 100; }
    const margin = 20;
    view.scale = (view.size - 2 * margin) / (Math.max(x1 - x0, y1 - y0) / 10);
    view.x0 = x0 / 10 - margin / view.scale;
    view.y1 = y1 / 10 + margin / view.scale;
  }
  const px = (x) => (x - view.x0) * view.scale;
  const py = (y) => (view.y1 - y) * view.scale;

  function drawFloor() {
    floor.width = canvas.width; floor.height = canvas.height;
    const g = floor.getContext("2d");
    const a = DATA.map.areas;
    let z0 = Infinity, z1 = -Infinity;
    for (let i = 4; i < a.length; i += 5) { z0 = Math.min(z0, a[i]); z1 = Math.max(z1, a[i]); }
    const zs = z1 > z0 ? z1 - z0 : 1;
    g.fillStyle = "#ffffff"; g.fillRect(0, 0, floor.width, floor.height);
    for (let i = 0; i < a.length; i += 5) { // sorted by height: upper floors drawn over lower
      const level = (a[i + 4] - z0) / zs;
      const light = Math.round(56 + 36 * level);
      g.fillStyle = "hsl(35, 18%, " + light + "%)";
      g.strokeStyle = "hsl(35, 18%, " + (light - 14) + "%)";
      g.lineWidth = 0.5;
      const x = px(a[i] / 10), y = py(a[i + 3] / 10);
      const w = (a[i + 2] - a[i]) / 10 * view.scale, h = (a[i + 3] - a[i + 1]) / 10 * view.scale;
      g.fillRect(x, y, w, h);
      g.strokeRect(x, y, w, h);
    }
  }

  // ---- state --------------------------------------------------------------------------------
  const state = { round: -1, t: 0, playing: false, speed: 2, hidden: new Set(), sides: new Set(["T", "CT"]) };
  const roundSelect = $("round-select"), slider = $("time"), playButton = $("play");

  function visible(p, player) {
    return state.sides.has(player.side) && !state.hidden.has(p);
  }

  function drawPath(points, colour, dashed) {
    if (points.length < 2) return;
    ctx.strokeStyle = colour;
    ctx.setLineDash(dashed ? [4, 3] : []);
    ctx.beginPath();
    ctx.moveTo(px(points[0][0]), py(points[0][1]));
    for (const q of points.slice(1)) ctx.lineTo(px(q[0]), py(q[1]));
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

  function positionsAt(r, t) {
    return r.players.map((p) => ({ real: at(p.real, t), replay: at(p.replay, t) }));
  }

  function bombAt(r, source, t, where) {
    let bomb = null;
    for (const e of r.events) {
      if (e.source !== source || e.t > t + 1e-6) continue;
      if (e.kind === "carry") bomb = { carrier: e.player };
      else if (e.x === null) bomb = null; // where is not known
      else if (e.kind === "drop") bomb = { x: e.x, y: e.y, label: "dropped" };
      else if (e.kind === "plant") bomb = { x: e.x, y: e.y, label: "planted", planted: true };
      else if (e.kind === "defuse") bomb = { x: e.x, y: e.y, label: "defused", defused: true };
      else if (e.kind === "explode") bomb = { x: e.x, y: e.y, label: "exploded", planted: true };
    }
    if (bomb) bomb.inferred = latestInferred(r, source, t);
    if (bomb && bomb.carrier !== undefined) {
      const p = where[bomb.carrier];
      const pos = p && (source === "data" ? p.real : p.replay);
      if (!pos) return null;
      bomb.x = pos[0]; bomb.y = pos[1];
    }
    return bomb;
  }

  // The data's smokes and fires active at time t: grey and orange discs of their sizes.
  function drawUtility(r, t) {
    for (const u of r.utility) {
      if (t < u.start || t >= u.end) continue;
      ctx.beginPath();
      ctx.arc(px(u.x), py(u.y), Math.abs(px(u.x + u.r) - px(u.x)), 0, 2 * Math.PI);
      ctx.fillStyle = u.kind === "smoke" ? "rgba(128, 128, 128, 0.45)" : "rgba(230, 110, 20, 0.35)";
      ctx.fill();
    }
  }

  // Whether the bomb's latest event of a source up to time t was inferred by a rule.
  function latestInferred(r, source, t) {
    let inferred = false;
    for (const e of r.events) {
      if (e.source === source && e.t <= t + 1e-6 && e.kind !== "kill") inferred = Boolean(e.inferred);
    }
    return inferred;
  }

  function drawBomb(bomb, hollow) {
    if (!bomb) return;
    const x = px(bomb.x), y = py(bomb.y), s = bomb.planted || bomb.defused ? 8 : 5;
    ctx.save();
    ctx.translate(x + (bomb.carrier !== undefined ? 7 : 0), y - (bomb.carrier !== undefined ? 7 : 0));
    ctx.rotate(Math.PI / 4);
    ctx.lineWidth = 2;
    ctx.strokeStyle = bomb.defused ? "#1e8449" : "#b7950b";
    ctx.fillStyle = bomb.defused ? "#58d68d" : "#f4d03f";
    if (bomb.inferred) ctx.setLineDash([2, 2]);
    if (hollow) ctx.strokeRect(-s / 2, -s / 2, s, s);
    else { ctx.fillRect(-s / 2, -s / 2, s, s); ctx.strokeRect(-s / 2, -s / 2, s, s); }
    ctx.restore();
  }

  function draw() {
    if (state.round < 0) return;
    const r = decodeRound(DATA.rounds[state.round]);
    const t = state.t;
    const showReal = $("show-real").checked, showReplay = $("show-replay").checked;
    ctx.drawImage(floor, 0, 0);
    drawUtility(r, t);
    const where = positionsAt(r, t);
    ctx.lineWidth = 1.5;
    r.players.forEach((p, i) => {
      if (!visible(i, p)) return;
      const colour = SIDE_COLOUR[p.side] || "#555";
      if (showReal) drawPath(trail(p.real, t - TRAIL_S, t), colour, true);
      if (showReplay) drawPath(trail(p.replay, t - TRAIL_S, t), colour, false);
    });
    for (const e of r.events) { // deaths so far; kills of the last seconds as arrows
      if (e.kind !== "kill" || e.t > t) continue;
      const victim = r.players[e.other];
      const isReal = e.source === "data";
      if (!victim || !visible(e.other, victim) || (isReal ? !showReal : !showReplay)) continue;
      if (e.x === null) continue; // where is not known
      cross(e.x, e.y, isReal ? "#888" : (SIDE_COLOUR[victim.side] || "#555"), 5);
      if (t - e.t <= KILL_SHOWN_S && e.player >= 0 && where[e.player]) {
        const from = isReal ? at(r.players[e.player].real, e.t) : at(r.players[e.player].replay, e.t);
        if (from) {
          ctx.strokeStyle = isReal ? "rgba(80,80,80,0.8)" : "rgba(0,0,0,0.9)";
          ctx.lineWidth = 1.5;
          ctx.setLineDash(isReal ? [4, 3] : []);
          ctx.beginPath(); ctx.moveTo(px(from[0]), py(from[1])); ctx.lineTo(px(e.x), py(e.y)); ctx.stroke();
          ctx.setLineDash([]);
        }
      }
    }
    r.players.forEach((p, i) => {
      if (!visible(i, p)) return;
      const colour = SIDE_COLOUR[p.side] || "#555";
      const a = where[i].real, b = where[i].replay;
      if (showReal && showReplay && a && b) {
        ctx.strokeStyle = "rgba(0,0,0,0.35)"; ctx.lineWidth = 1;
        ctx.beginPath(); ctx.moveTo(px(a[0]), py(a[1])); ctx.lineTo(px(b[0]), py(b[1])); ctx.stroke();
      }
      if (showReal && a) {
        ctx.strokeStyle = colour; ctx.lineWidth = 2;
        ctx.beginPath(); ctx.arc(px(a[0]), py(a[1]), 6, 0, 2 * Math.PI); ctx.stroke();
      }
      if (showReplay && b) {
        ctx.fillStyle = colour;
        ctx.beginPath(); ctx.arc(px(b[0]), py(b[1]), 4.5, 0, 2 * Math.PI); ctx.fill();
      }
      const label = b && showReplay ? b : (a && showReal ? a : null);
      if (label) {
        ctx.fillStyle = "#111"; ctx.font = "11px system-ui, sans-serif";
        ctx.fillText(p.name, px(label[0]) + 8, py(label[1]) - 6);
      }
    });
    if (showReal) drawBomb(bombAt(r, "data", t, where), true);
    if (showReplay) drawBomb(bombAt(r, "replay", t, where), false);
    updatePanel(r, where);
  }

  // ---- the panel beside the map -------------------------------------------------------------
  function errorOf(w) {
    if (!w.real || !w.replay) return null;
    return Math.hypot(w.real[0] - w.replay[0], w.real[1] - w.replay[1], w.real[2] - w.replay[2]);
  }

  function updatePanel(r, where) {
    const clock = state.t.toFixed(1) + " s";
    $("clock").textContent = clock;
    $("cursor-time").textContent = clock;
    slider.value = String(state.t);
    const rows = $("at-cursor").tBodies[0].rows;
    r.players.forEach((p, i) => {
      const w = where[i];
      const error = errorOf(w);
      let text = error === null ? "–" : error.toFixed(2);
      if (error === null && (w.real || w.replay)) text = w.real ? "dead in replay" : "dead in data";
      rows[i].cells[3].textContent = text;
    });
    for (const li of $("events").children) {
      li.className = Number(li.dataset.t) > state.t + 1e-6 ? "future" : "";
    }
  }

  function eventText(r, e) {
    const name = (i) => (i >= 0 && r.players[i] ? r.players[i].name : "?");
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
    return e.t.toFixed(1) + " s · " + who + " · " + (words[e.kind] ? words[e.kind]() : e.kind) + rule;
  }

  function openRound(index, t) {
    state.round = index;
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
      const box = el("input"); box.type = "checkbox"; box.checked = true;
      box.setAttribute("aria-label", "show " + p.name);
      box.dataset.player = String(i);
      box.addEventListener("change", () => {
        if (box.checked) state.hidden.delete(i); else state.hidden.add(i);
        draw();
      });
      const show = el("td"); show.appendChild(box);
      const name = el("td");
      const swatch = el("span", null, "swatch"); swatch.style.background = SIDE_COLOUR[p.side] || "#555";
      name.append(swatch, document.createTextNode(p.name));
      row.append(show, name, el("td", p.side, p.side), el("td", "–"));
      body.appendChild(row);
    });
    const list = $("events");
    list.replaceChildren();
    for (const e of r.events) {
      const li = el("li", eventText(r, e));
      li.dataset.t = String(e.t);
      list.appendChild(li);
    }
    setTime(t === undefined ? r.start : t);
  }

  function setTime(t) {
    if (state.round < 0) return;
    const r = decodeRound(DATA.rounds[state.round]);
    state.t = Math.min(Math.max(t, r.start), r.end);
    draw();
  }

  // ---- playing ------------------------------------------------------------------------------
  let last = null;
  function tick(now) {
    if (!state.playing) { last = null; return; }
    if (last !== null) {
      const r = decodeRound(DATA.rounds[state.round]);
      setTime(state.t + (now - last) / 1000 * state.speed);
      if (state.t >= r.end) setPlaying(false);
    }
    last = now;
    if (state.playing) requestAnimationFrame(tick);
  }

  function setPlaying(on) {
    state.playing = on && state.round >= 0;
    playButton.textContent = state.playing ? "pause" : "play";
    if (state.playing) {
      const r = decodeRound(DATA.rounds[state.round]);
      if (state.t >= r.end) setTime(r.start);
      requestAnimationFrame(tick);
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

  document.addEventListener("keydown", (e) => {
    const target = e.target;
    const typing = target instanceof HTMLSelectElement || (target instanceof HTMLInputElement && target.type === "range");
    // Space plays and pauses, except on a control that Space works itself (a button, a box)
    const control = target instanceof HTMLButtonElement || target instanceof HTMLSelectElement ||
      (target instanceof HTMLInputElement && target.type !== "range");
    if (e.key === " " && !control) {
      e.preventDefault(); setPlaying(!state.playing);
    } else if (typing || e.altKey || e.ctrlKey || e.metaKey) {
      return;
    } else if (e.key === "ArrowRight" || e.key === "ArrowLeft") {
      e.preventDefault();
      step((e.key === "ArrowRight" ? 1 : -1) * (e.shiftKey ? 5 : 0.5));
    } else if (e.key === "Home" || e.key === "End") {
      if (state.round < 0) return;
      e.preventDefault();
      const r = decodeRound(DATA.rounds[state.round]);
      step(0); setTime(e.key === "Home" ? r.start : r.end);
    } else if (e.key === "[" || e.key === "]") {
      changeSpeed(e.key === "]" ? 1 : -1);
    }
  });

  playButton.addEventListener("click", () => setPlaying(!state.playing));
  $("speed").addEventListener("change", () => { state.speed = Number($("speed").value); });
  slider.addEventListener("input", () => { setPlaying(false); setTime(Number(slider.value)); });
  roundSelect.addEventListener("change", () => { setPlaying(false); openRound(Number(roundSelect.value)); });
  for (const box of document.querySelectorAll("input.side")) {
    box.addEventListener("change", () => {
      if (box.checked) state.sides.add(box.value); else state.sides.delete(box.value);
      draw();
    });
  }
  $("show-real").addEventListener("change", draw);
  $("show-replay").addEventListener("change", draw);

  canvas.addEventListener("mousemove", (e) => {
    if (state.round < 0) return;
    const box = canvas.getBoundingClientRect();
    const x = (e.clientX - box.left) * canvas.width / box.width;
    const y = (e.clientY - box.top) * canvas.height / box.height;
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
    const error = errorOf(where[best]);
    $("hover").textContent = r.players[best].name + " (" + r.players[best].side + "): " +
      (error === null ? "not alive in both" : error.toFixed(2) + " m between real and replay");
  });

  // ---- the tables ---------------------------------------------------------------------------
  function tableOf(spec) {
    const table = el("table");
    if (spec.title) table.appendChild(el("caption", spec.title));
    const head = table.createTHead().insertRow();
    for (const c of spec.columns) head.appendChild(el("th", c));
    const body = table.createTBody();
    for (const row of spec.rows) {
      const tr = body.insertRow();
      for (const v of row) tr.appendChild(el("td", fmt(v)));
    }
    return table;
  }

  function playerTable() {
    const spec = DATA.players;
    const table = $("player-table");
    const head = table.tHead.insertRow();
    const order = spec.rows.map((_, i) => i);
    let sortColumn = -1, descending = false;
    spec.columns.forEach((c, j) => {
      const th = el("th");
      const button = el("button", c);
      button.type = "button";
      button.addEventListener("click", () => {
        descending = sortColumn === j ? !descending : spec.rows.length > 0 && typeof spec.rows[0][j] === "number";
        sortColumn = j;
        const sign = descending ? -1 : 1;
        order.sort((a, b) => {
          const x = spec.rows[a][j], y = spec.rows[b][j];
          if (x === y) return a - b;
          if (x === null) return 1;
          if (y === null) return -1;
          return (x < y ? -1 : 1) * sign;
        });
        for (const th2 of head.cells) th2.removeAttribute("aria-sort");
        th.setAttribute("aria-sort", descending ? "descending" : "ascending");
        fill();
      });
      th.appendChild(button);
      head.appendChild(th);
    });
    const body = table.tBodies[0];
    function fill() {
      const rows = order.map((i) => {
        const tr = document.createElement("tr");
        tr.tabIndex = 0;
        tr.dataset.row = String(i);
        for (const v of spec.rows[i]) tr.appendChild(el("td", fmt(v)));
        return tr;
      });
      body.replaceChildren(...rows);
    }
    function choose(tr) {
      const i = Number(tr.dataset.row);
      const round = spec.round[i], player = spec.player[i];
      if (round === null || round === undefined || !DATA.rounds[round]) return;
      setPlaying(false);
      const p = DATA.rounds[round].players[player];
      openRound(round, p && p.worst_s !== null ? p.worst_s : undefined);
      $("round").scrollIntoView();
    }
    body.addEventListener("click", (e) => { const tr = e.target.closest("tr"); if (tr) choose(tr); });
    body.addEventListener("keydown", (e) => {
      if (e.key === "Enter") { const tr = e.target.closest("tr"); if (tr) choose(tr); }
    });
    fill();
  }

  function start() {
    document.title = DATA.title;
    $("title").textContent = DATA.title;
    $("subtitle").textContent = DATA.subtitle;
    fitMap();
    drawFloor();
    DATA.rounds.forEach((r, i) => roundSelect.appendChild(new Option(r.label, String(i))));
    const tables = $("tables");
    for (const spec of DATA.tables) tables.appendChild(tableOf(spec));
    playerTable();
    if (DATA.rounds.length) openRound(DATA.initial || 0);
    else $("round-info").textContent = "no round to show";
    document.body.dataset.ready = "1";
  }
  start();
})();
