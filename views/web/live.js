// The live page of leakmon: polls /api/trend (new trend points since the last poll and the
// newest status) and /api/events (events since the last seen), draws with uPlot, and posts
// acknowledgements to /ack. No framework, no external resource (the page's CSP forbids both).
"use strict";

const POLL_TREND_MS = 1000;
const POLL_EVENTS_MS = 2000;
const MAX_EVENT_ROWS = 50;

const view = {
  since: 0,          // newest trend time received [unix s]
  capacity: 14400,   // points the daemon keeps; the page keeps no more
  actuators: new Map(),  // name -> {card, charts, data}
  loop: null,        // {chart, data} for the first group's latency
  eventsAfter: 0,
  tokenRequired: false,
};

function $(id) { return document.getElementById(id); }

function el(tag, className, text) {
  const e = document.createElement(tag);
  if (className) e.className = className;
  if (text !== undefined) e.textContent = text;
  return e;
}

function fmt(value, digits, unit) {
  if (value === null || value === undefined || !Number.isFinite(value)) return "–";
  return value.toFixed(digits) + (unit ? " " + unit : "");
}

// JSON null (the daemon has no value yet) stays null through a change of unit.
function scaled(value, divisor) { return typeof value === "number" ? value / divisor : null; }

// The newest finite value of a trend column, or null. The status's own value is null while the
// newest wavelet window holds a gap (a missed cycle), which on a loaded machine is much of the
// time: the tile then shows what the chart shows, the newest value there is.
function newestFinite(column) {
  for (let i = column.length - 1; i >= 0; --i) {
    if (Number.isFinite(column[i])) return column[i];
  }
  return null;
}

function current(value, column) { return Number.isFinite(value) ? value : newestFinite(column); }

function stateClass(state) {
  if (state === "normal") return "ok";
  if (state === "active_acknowledged") return "warn";
  return "bad";
}

function statusClass(status) { return status === "ok" ? "ok" : status === "failure" ? "bad" : "warn"; }

// uPlot wants column arrays; the page appends the daemon's new columns and trims the oldest.
function appendColumns(columns, incoming, names) {
  for (const name of names) {
    const add = incoming[name] || [];
    for (const v of add) columns[name].push(v);
    const excess = columns[name].length - view.capacity;
    if (excess > 0) columns[name].splice(0, excess);
  }
}

function makeChart(container, title, series, data, extra) {
  const box = el("div", "chart");
  box.appendChild(el("h3", null, title));
  container.appendChild(box);
  const opts = Object.assign({
    width: 300,  // resize() fits it to its cell once laid out
    height: 180,
    series: [{}].concat(series),
    axes: [{}, { size: 60 }],
    legend: { live: true },
    cursor: { drag: { x: true, y: false } },
  }, extra || {});
  const chart = new uPlot(opts, data, box);
  return { box, chart };
}

function windowRange(times) {
  const seconds = Number($("window").value);
  if (!times.length) return null;
  const last = times[times.length - 1];
  if (seconds > 0) return { min: last - seconds, max: last };
  return { min: times[0], max: last };
}

// The vocabulary of /status and /api/trend (docs/daemon.md "Vocabulary").
const TREND_COLUMNS = ["time", "index_p1_pa", "index_p2_pa", "score", "raise_threshold",
  "leak_lpm_per_mpa", "leak_lpm_per_mpa_ci95", "p1_pa", "p2_pa", "oil_temperature_c",
  "alarm_state_code"];

function tile(label) {
  const t = el("div", "tile");
  t.appendChild(el("div", "label", label));
  const value = el("div", "value", "–");
  t.appendChild(value);
  return { tile: t, value };
}

function createActuator(a) {
  const card = el("section", "actuator");
  card.id = "actuator-" + a.name;
  card.dataset.actuator = a.name;
  card.dataset.points = "0";
  const title = el("div", "title");
  title.appendChild(el("h2", null, a.name));
  const alarm = el("span", "badge alarm-state", "");
  const learning = el("span", "badge", "learning");
  const suspended = el("span", "badge warn", "decision held: sensor fault");
  // A pressure-only detector on a rig whose hydraulic mode did not show while it learned: it
  // cannot raise a leak alarm, which must not look like a healthy rig.
  const blind = el("span", "badge warn blind", "blind: no hydraulic mode in the pressures");
  blind.title = "The pressure-only detector sees a leak through the hydraulic mode, which " +
    "hardly showed above the transducer noise while it learned (seal friction, much air). " +
    "No leak alarm can come from it; acquire the valve command and the position.";
  // The detector cannot see a leak now (a hold, a sine block, loads it never learned): a quiet
  // alarm then says nothing about the rig.
  const notJudged = el("span", "badge warn not-judged", "not judging");
  const ack = el("button", "ack", "Acknowledge");
  ack.type = "button";
  ack.addEventListener("click", () => acknowledge(a.name, result));
  const result = el("span", "ack-result", "");
  title.append(alarm, learning, suspended, blind, notJudged, ack, result);
  card.appendChild(title);

  const tiles = el("div", "tiles");
  const t = {
    index: tile("index p1 / p2 [kPa]"),
    score: tile("score / raise threshold"),
    leak: tile("leak size [l/min/MPa], 95 %"),
    pressure: tile("chamber pressures p1 / p2 [MPa]"),
    temperature: tile("oil temperature [°C]"),
    sensors: tile("sensors (NE 107)"),
    decisions: tile("decisions"),
  };
  for (const k of Object.keys(t)) tiles.appendChild(t[k].tile);
  t.leak.value.classList.add("leak");
  t.sensors.value.classList.add("sensors");
  card.appendChild(tiles);

  const charts = el("div", "charts");
  card.appendChild(charts);
  $("actuators").appendChild(card);

  const data = {};
  for (const name of TREND_COLUMNS) data[name] = [];
  const kpa = (v) => scaled(v, 1e3);
  const mpa = (v) => scaled(v, 1e6);
  const entry = {
    card, alarm, learning, suspended, blind, notJudged, ack, result, tiles: t, data, charts: [],
  };
  entry.build = [
    () => [data.time, data.index_p1_pa.map(kpa), data.index_p2_pa.map(kpa)],
    () => [data.time, data.score, data.raise_threshold],
    () => [data.time, data.leak_lpm_per_mpa,
      data.leak_lpm_per_mpa.map((v, i) => (v === null || data.leak_lpm_per_mpa_ci95[i] === null
        ? null : v + data.leak_lpm_per_mpa_ci95[i])),
      data.leak_lpm_per_mpa.map((v, i) => (v === null || data.leak_lpm_per_mpa_ci95[i] === null
        ? null : v - data.leak_lpm_per_mpa_ci95[i]))],
    () => [data.time, data.p1_pa.map(mpa), data.p2_pa.map(mpa), data.oil_temperature_c],
  ];
  const empty = (n) => [[]].concat(Array.from({ length: n }, () => []));
  entry.charts.push(makeChart(charts, "wavelet index [kPa]", [
    { label: "p1", stroke: "#1f77b4" }, { label: "p2", stroke: "#9467bd" }], empty(2)));
  entry.charts.push(makeChart(charts, "detector score against its threshold", [
    { label: "score", stroke: "#d62728", width: 2 },
    { label: "raise threshold", stroke: "#555", dash: [6, 4] }], empty(2)));
  entry.charts.push(makeChart(charts, "leak size [l/min/MPa] with 95 % interval", [
    { label: "leak", stroke: "#2ca02c", width: 2 },
    { label: "upper", stroke: "rgba(44,160,44,0.4)" },
    { label: "lower", stroke: "rgba(44,160,44,0.4)" }], empty(3),
    { bands: [{ series: [2, 3], fill: "rgba(44,160,44,0.15)" }] }));
  entry.charts.push(makeChart(charts, "chamber pressures [MPa], oil temperature [°C]", [
    { label: "p1", stroke: "#1f77b4" }, { label: "p2", stroke: "#ff7f0e" },
    { label: "oil", stroke: "#8c564b", scale: "degC" }], empty(3),
    { axes: [{}, { size: 60 }, { side: 1, scale: "degC", grid: { show: false } }],
      scales: { degC: {} } }));
  view.actuators.set(a.name, entry);
  requestAnimationFrame(resize);
  return entry;
}

function updateActuator(a) {
  const entry = view.actuators.get(a.name) || createActuator(a);
  const { card, tiles } = entry;
  entry.alarm.textContent = a.alarm + ": " + a.alarm_state;
  entry.alarm.className = "badge alarm-state " + stateClass(a.alarm_state);
  card.dataset.alarmState = a.alarm_state;
  card.classList.toggle("alarmed", a.alarm_state !== "normal");
  entry.learning.hidden = !a.learning;
  entry.suspended.hidden = !a.suspended;
  entry.blind.hidden = !a.detection_blind;
  // Learning has its own badge; a status without `judged` (an older daemon) shows none.
  entry.notJudged.hidden = a.judged !== false || a.learning;
  entry.notJudged.textContent = "not judging: " + (a.not_judged_reason || "") +
    (Number.isFinite(a.not_judged_since) ? " since t " + a.not_judged_since.toFixed(0) + " s" : "");
  card.dataset.judged = String(a.judged);
  entry.ack.disabled = a.alarm_state === "normal";
  if (a.trend) appendColumns(entry.data, a.trend, TREND_COLUMNS);
  const data = entry.data;
  tiles.index.value.textContent = fmt(scaled(current(a.index_p1_pa, data.index_p1_pa), 1e3), 2) +
    " / " + fmt(scaled(current(a.index_p2_pa, data.index_p2_pa), 1e3), 2);
  tiles.score.value.textContent = fmt(a.score, 3) + " / " + fmt(a.raise_threshold, 3);
  tiles.leak.value.textContent = Number.isFinite(a.leak_lpm_per_mpa)
    ? fmt(a.leak_lpm_per_mpa, 3) + " ± " + fmt(a.leak_lpm_per_mpa_ci95, 3) : "–";
  tiles.pressure.value.textContent = fmt(scaled(current(a.p1_pa, data.p1_pa), 1e6), 2) + " / " +
    fmt(scaled(current(a.p2_pa, data.p2_pa), 1e6), 2);
  tiles.temperature.value.textContent =
    a.oil_temperature_c === null ? "not acquired" : fmt(a.oil_temperature_c, 1);
  tiles.decisions.value.textContent = String(a.decisions);
  const sensors = tiles.sensors.value;
  sensors.replaceChildren();
  for (const c of a.sensors) {
    const b = el("span", "badge " + statusClass(c.status),
      c.channel + ": " + c.status + (c.fault !== null ? " (" + c.fault + ")" : ""));
    b.dataset.channel = c.channel;
    sensors.appendChild(b);
    sensors.appendChild(document.createTextNode(" "));
  }
  if (a.trend) {
    card.dataset.points = String(entry.data.time.length);
    const range = windowRange(entry.data.time);
    entry.charts.forEach((c, i) => {
      c.chart.setData(entry.build[i](), false);
      if (range) c.chart.setScale("x", range);
    });
  }
}

function updateLoops(trend) {
  const body = $("loops").tBodies[0];
  body.replaceChildren();
  for (const g of trend.groups) {
    const row = el("tr");
    row.dataset.group = g.name;
    for (const text of [g.name, g.realtime ? "SCHED_FIFO" : "normal", String(g.cycles),
      fmt(g.wakeup_latency_mean_us, 1) + " / " + fmt(g.wakeup_latency_p99_us, 0) + " / " +
        fmt(g.wakeup_latency_max_us, 0),
      String(g.overruns), String(g.missed_cycles), String(g.ring_drops),
      g.ring_high_water + " / " + g.ring_capacity]) {
      row.appendChild(el("td", null, text));
    }
    body.appendChild(row);
  }
  $("worker").textContent = "worker: " + trend.samples_processed + " samples processed, " +
    trend.events + " events, decision latency p99 " + fmt(trend.decision_latency_p99_us, 0, "µs");
  const g = trend.groups[0];
  if (!g || !g.trend) return;
  if (!view.loop) {
    const data = { time: [], wakeup_latency_mean_us: [], overruns: [] };
    const chart = makeChart($("loop-chart"), "group " + g.name +
      ": mean wake-up latency [µs] per interval, overruns", [
      { label: "latency", stroke: "#1f77b4" },
      { label: "overruns", stroke: "#d62728", scale: "count" }], [[], [], []],
    { axes: [{}, { size: 60 }, { side: 1, scale: "count", grid: { show: false } }],
      scales: { count: {} } });
    view.loop = { data, chart };
    requestAnimationFrame(resize);
  }
  appendColumns(view.loop.data, g.trend, ["time", "wakeup_latency_mean_us", "overruns"]);
  const d = view.loop.data;
  view.loop.chart.chart.setData([d.time, d.wakeup_latency_mean_us, d.overruns], false);
  const range = windowRange(d.time);
  if (range) view.loop.chart.chart.setScale("x", range);
}

function setConnection(ok, text) {
  const c = $("connection");
  c.textContent = text;
  c.className = "badge " + (ok ? "ok" : "bad");
}

async function pollTrend() {
  try {
    const response = await fetch("api/trend?since=" + view.since, { cache: "no-store" });
    if (!response.ok) throw new Error("HTTP " + response.status);
    const trend = await response.json();
    view.capacity = trend.capacity;
    view.tokenRequired = trend.ack_token_required;
    $("token-box").hidden = !trend.ack_token_required;
    for (const a of trend.actuators) updateActuator(a);
    updateLoops(trend);
    if (trend.now) view.since = Math.max(view.since, trend.now);
    $("updated").textContent = "updated " + new Date(trend.now * 1000).toLocaleTimeString();
    setConnection(true, "live");
  } catch (e) {
    setConnection(false, "daemon not answering (" + e.message + ")");
  }
  setTimeout(pollTrend, POLL_TREND_MS);
}

function eventDetail(e) {
  const parts = [];
  if (e.channel) parts.push(e.channel);
  if (e.fault) parts.push(e.fault);
  if (e.leak_lpm_per_mpa !== undefined) {
    parts.push("leak " + fmt(e.leak_lpm_per_mpa, 3) +
      (e.leak_lpm_per_mpa_ci95 !== undefined ? " ± " + fmt(e.leak_lpm_per_mpa_ci95, 3) : "") +
      " l/min/MPa");
  }
  if (e.score !== undefined) parts.push("score " + fmt(e.score, 3));
  if (e.message) parts.push(e.message);
  return parts.join(", ");
}

// Events that repeat while nothing else happens (a loaded machine's overruns, once a second at
// most) fold into the newest row with a count, so that they cannot push an alarm out of sight.
const FOLDED_EVENTS = new Set(["overrun"]);

function eventRow(e, seq) {
  const row = el("tr", e.event);
  row.dataset.seq = String(seq);
  row.dataset.count = "1";
  const when = e.time ? new Date(e.time).toLocaleTimeString() : "";
  for (const text of [when, e.event, e.actuator || "", e.alarm || "", eventDetail(e)]) {
    row.appendChild(el("td", null, text));
  }
  return row;
}

// Folds `e` into `row` (the newest row, of the same kind and channel): newest time and detail,
// the count beside the event's name, the first time in the row's tooltip.
function foldInto(row, e, seq) {
  const count = Number(row.dataset.count) + 1;
  row.dataset.count = String(count);
  row.dataset.seq = String(seq);
  const cells = row.cells;
  if (!row.title) row.title = "first at " + cells[0].textContent;
  cells[0].textContent = e.time ? new Date(e.time).toLocaleTimeString() : "";
  cells[1].textContent = e.event + " ×" + count;
  cells[4].textContent = eventDetail(e);
}

async function pollEvents() {
  try {
    const response = await fetch("api/events?after=" + view.eventsAfter, { cache: "no-store" });
    if (!response.ok) throw new Error("HTTP " + response.status);
    const answer = await response.json();
    const body = $("events").tBodies[0];
    for (const item of answer.events) {
      const e = item.event;
      const newest = body.rows[0];
      if (FOLDED_EVENTS.has(e.event) && newest && newest.classList.contains(e.event) &&
          newest.dataset.channel === (e.channel || "")) {
        foldInto(newest, e, item.seq);
      } else {
        const row = eventRow(e, item.seq);
        row.dataset.channel = e.channel || "";
        body.insertBefore(row, body.firstChild);
      }
      view.eventsAfter = Math.max(view.eventsAfter, item.seq);
    }
    while (body.rows.length > MAX_EVENT_ROWS) body.deleteRow(body.rows.length - 1);
  } catch (e) {
    setConnection(false, "daemon not answering (" + e.message + ")");
  }
  setTimeout(pollEvents, POLL_EVENTS_MS);
}

async function acknowledge(actuator, result) {
  let target = "ack?actuator=" + encodeURIComponent(actuator);
  const headers = {};
  const token = $("token").value;
  if (token) {
    target += "&token=" + encodeURIComponent(token);
    headers.Authorization = "Bearer " + token;
  }
  try {
    const response = await fetch(target, { method: "POST", headers, cache: "no-store" });
    result.textContent = (await response.text()).trim();
  } catch (e) {
    result.textContent = "not sent: " + e.message;
  }
}

function resize() {
  for (const entry of view.actuators.values()) {
    for (const c of entry.charts) c.chart.setSize({ width: c.box.clientWidth, height: 180 });
  }
  if (view.loop) {
    const c = view.loop.chart;
    c.chart.setSize({ width: c.box.clientWidth, height: 180 });
  }
}

window.addEventListener("resize", resize);
$("window").addEventListener("change", () => {
  for (const entry of view.actuators.values()) {
    const range = windowRange(entry.data.time);
    if (range) for (const c of entry.charts) c.chart.setScale("x", range);
  }
  if (view.loop) {
    const range = windowRange(view.loop.data.time);
    if (range) view.loop.chart.chart.setScale("x", range);
  }
});
pollTrend();
pollEvents();
