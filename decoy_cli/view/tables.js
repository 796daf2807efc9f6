// tables.js: the run's tables, the player-round list, the legend, and the page's start.
const LEGEND = [ // what the map draws, each with the colour it is drawn in
  ["ring", COLOUR.T, "real T (ring, dashed trail of 4 s)"],
  ["dot", COLOUR.CT, "replayed CT (dot, solid trail); the tick: where a player looks"],
  ["line", COLOUR.join, "a player's real and replayed positions joined"],
  ["dashed", COLOUR.kill, "a real kill, attacker to victim, for 3 s"],
  ["line", COLOUR.kill, "a kill in the replay"],
  ["cross", COLOUR.deathReal, "a real death (in the replay: the side's colour)"],
  ["square", COLOUR.bomb, "the bomb: hollow real, filled replay, dashed inferred by a rule"],
  ["bar", COLOUR.hpReal, "HP under the name: real above (dark grey), replay below (side colour)"],
  ["disc", COLOUR.smoke, "a smoke (the data's)"],
  ["disc", COLOUR.fire, "a fire (the data's)"],
];

function legend() {
  const list = $("legend");
  for (const [shape, colour, text] of LEGEND) {
    const item = el("li");
    const mark = el("span", null, "key " + shape);
    mark.dataset.colour = colour;
    if (shape === "line" || shape === "dashed") mark.style.borderTopColor = colour;
    else if (shape === "ring" || shape === "square" || shape === "cross") mark.style.borderColor = colour;
    else mark.style.background = colour;
    item.append(mark, document.createTextNode(text));
    list.appendChild(item);
  }
}

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
  const labels = spec.labels || spec.columns;
  let sortColumn = -1, descending = false, chosen = -1;
  const buttons = [];
  spec.columns.forEach((c, j) => {
    const th = el("th");
    const button = el("button", labels[j]);
    button.type = "button";
    button.title = c;
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
      buttons.forEach((other, k) => {
        other.textContent = labels[k] + (k === j ? (descending ? " ▼" : " ▲") : "");
        head.cells[k].removeAttribute("aria-sort");
      });
      th.setAttribute("aria-sort", descending ? "descending" : "ascending");
      fill();
    });
    buttons.push(button);
    th.appendChild(button);
    head.appendChild(th);
  });
  const body = table.tBodies[0];
  function fill() {
    const rows = order.map((i) => {
      const tr = document.createElement("tr");
      tr.tabIndex = 0;
      tr.dataset.row = String(i);
      if (i === chosen) tr.className = "chosen";
      for (const v of spec.rows[i]) tr.appendChild(el("td", fmt(v)));
      return tr;
    });
    body.replaceChildren(...rows);
  }
  function choose(tr) {
    const i = Number(tr.dataset.row);
    const round = spec.round[i], player = spec.player[i];
    if (round === null || round === undefined || !DATA.rounds[round]) return;
    chosen = i;
    for (const other of body.rows) other.classList.toggle("chosen", other === tr);
    setPlaying(false);
    const p = DATA.rounds[round].players[player];
    openRound(round, p && p.worst_s !== null ? p.worst_s : undefined, player);
    $("round").scrollIntoView();
  }
  body.addEventListener("click", (e) => { const tr = e.target.closest("tr"); if (tr) choose(tr); });
  body.addEventListener("keydown", (e) => {
    if (e.key === "Enter") { const tr = e.target.closest("tr"); if (tr) choose(tr); }
  });
  fill();
}

// The round is drawn first; the tables (thousands of rows in a large run) are filled after.
function start() {
  document.title = DATA.title;
  $("title").textContent = DATA.title;
  $("subtitle").textContent = DATA.subtitle;
  legend();
  if (!DATA.heat) $("heat").disabled = true;
  DATA.rounds.forEach((r, i) => roundSelect.appendChild(new Option(r.label, String(i))));
  const asked = fromFragment();
  if (asked) openRound(asked.index, asked.t);
  else if (DATA.rounds.length) openRound(DATA.initial || 0);
  else $("round-info").textContent = "no round to show";
  setTimeout(() => {
    const tables = $("tables");
    for (const spec of DATA.tables) tables.appendChild(tableOf(spec));
    playerTable();
    document.body.dataset.ready = "1";
  }, 0);
}
start();
