// fricctl device view: the page's script (plain JS, uPlot for the plots).
//
// The server sends one JSON batch per 100 ms over the WebSocket: rows with
// the CLI's keys (kind "estimate", "control" or "status"), the device's
// state and events. The page keeps the last WINDOW_S seconds, at most
// MAX_ROWS rows of each kind, and redraws at most every REDRAW_MS: its
// memory is bounded whatever the stream's rate.
"use strict";

const WINDOW_S = 60;
const MAX_ROWS = 20000;
const REDRAW_MS = 200;
const MAX_MESSAGES = 200;

let columns = [];
let readOnly = false;
let state = {};
const rows = { estimate: [], status: [] };
let received = 0;
let lostBatches = 0;
let droppedRows = 0;
let dirty = false;

const $ = (id) => document.getElementById(id);

// ---- plots ------------------------------------------------------------

const um = (x) => (x == null ? null : x * 1e6);

// Each plot: title, source rows, y-axis label(s), and its series.
const PLOTS = [
  {
    id: "mu", title: "μ (estimates) with ± std error band", src: "estimate",
    y: "μ (–)",
    series: [
      { label: "μ", stroke: "#1f4e9c", width: 1.5, get: (r) => r.mu },
      { label: "μ + σ", stroke: "#9bb3dd", get: (r) => (r.mu == null ? null : r.mu + (r.std_error || 0)) },
      { label: "μ − σ", stroke: "#9bb3dd", get: (r) => (r.mu == null ? null : r.mu - (r.std_error || 0)) },
      { label: "μ* (loop)", stroke: "#d17a00", dash: [6, 4], get: (r) => r.target_mu },
    ],
    bands: [{ series: [2, 3], fill: "rgba(31,78,156,0.18)" }],
  },
  {
    id: "amp", title: "Δu_z and Δu_x: measured against set", src: "status",
    y: "amplitude (µm)",
    series: [
      { label: "Δu_z set", stroke: "#1f4e9c", dash: [6, 4], get: (r) => um(r.duz) },
      { label: "Δu_z measured", stroke: "#1f4e9c", width: 1.5, get: (r) => um(r.amp_z_measured_m) },
      { label: "Δu_x set", stroke: "#2a8a3e", dash: [6, 4], get: (r) => um(r.dux) },
      { label: "Δu_x measured", stroke: "#2a8a3e", width: 1.5, get: (r) => um(r.amp_x_measured_m) },
    ],
  },
  {
    id: "phi", title: "φ: measured against set", src: "status",
    y: "φ (deg)",
    series: [
      { label: "φ set", stroke: "#7a3e9d", dash: [6, 4], get: (r) => r.phi_deg },
      { label: "φ measured", stroke: "#7a3e9d", width: 1.5, get: (r) => r.phase_measured_deg },
    ],
  },
  {
    id: "freq", title: "drive frequency and tracking error", src: "status",
    y: "frequency (Hz)", y2: "tracking error (Hz)",
    series: [
      { label: "drive frequency", stroke: "#1f4e9c", width: 1.5, get: (r) => r.frequency_hz },
      { label: "tracking error", stroke: "#c0392b", scale: "y2", get: (r) => r.tracking_error_hz },
    ],
  },
  {
    id: "liftoff", title: "lift-off margin: peak Δu_z against the limit", src: "status",
    y: "amplitude (µm)",
    series: [
      { label: "peak Δu_z (amp_z_peak_m)", stroke: "#1f4e9c", width: 1.5, get: (r) => um(r.amp_z_peak_m) },
      { label: "guard (1 − margin)·u_z0", stroke: "#d17a00", dash: [6, 4], get: (r) => um(r.liftoff_limit_m) },
      { label: "u_z0 (contact opens)", stroke: "#b00020", dash: [2, 3], get: (r) => um(r.uz0) },
    ],
  },
];

function makePlot(p) {
  const box = document.createElement("div");
  box.className = "plot";
  box.id = "plot-" + p.id;
  const h = document.createElement("h3");
  h.textContent = p.title;
  box.appendChild(h);
  $("plots").appendChild(box);
  // Tick labels with as many digits as the tick spacing needs (μ varies
  // by 1e-4 around 0.13: uPlot's default three decimals repeat one value).
  const ticks = (u, splits, axis, space, incr) => {
    let d = 0;
    while (incr > 0 && d < 12 && Math.abs(incr * 10 ** d - Math.round(incr * 10 ** d)) > 1e-6 * incr * 10 ** d) d++;
    return splits.map((v) => (v == null ? "" : Math.abs(v) >= 1e5 || (v !== 0 && Math.abs(v) < 1e-4)
      ? v.toExponential(Math.max(1, d - 1 + Math.floor(Math.log10(Math.abs(v))))) : v.toFixed(d)));
  };
  const axes = [
    { label: "time (s)", stroke: "#333", values: ticks },
    { label: p.y, stroke: "#333", size: 80, values: ticks },
  ];
  // A flat series (a constant frequency) gets a narrow range around it,
  // not uPlot's default that reaches down to 0.
  const pad = (u, min, max) => {
    if (min == null || max == null) return [0, 1];
    const span = max - min;
    const d = span > 0 ? span * 0.08 : Math.max(Math.abs(max) * 1e-4, 1e-12);
    return [min - d, max + d];
  };
  const scales = { x: { time: false }, y: { range: pad } };
  if (p.y2) {
    axes.push({ label: p.y2, scale: "y2", side: 1, stroke: "#c0392b", size: 70, grid: { show: false }, values: ticks });
    scales.y2 = { range: pad };
  }
  const opts = {
    width: 560, height: 230,
    scales, axes,
    series: [{ label: "t (s)" }].concat(p.series.map((s) => ({
      label: s.label, stroke: s.stroke, width: s.width || 1, dash: s.dash,
      scale: s.scale || "y", spanGaps: false, points: { show: false },
    }))),
    legend: { live: false },
  };
  if (p.bands) opts.bands = p.bands;
  const empty = [[]].concat(p.series.map(() => []));
  p.u = new uPlot(opts, empty, box);
  p.points = 0;
}

function redraw() {
  if (!dirty) return;
  dirty = false;
  const width = Math.max(300, Math.floor(($("plots").clientWidth - 10) / 2) - 12);
  for (const p of PLOTS) {
    const src = rows[p.src];
    const t = new Array(src.length);
    const cols = p.series.map(() => new Array(src.length));
    for (let i = 0; i < src.length; i++) {
      const r = src[i];
      t[i] = r.t_s;
      for (let k = 0; k < p.series.length; k++) {
        const v = p.series[k].get(r);
        cols[k][i] = v == null ? null : v;
      }
    }
    if (p.u.width !== width) p.u.setSize({ width, height: 230 });
    p.u.setData([t].concat(cols));
    p.points = src.length;
    $("plot-" + p.id).dataset.points = String(src.length);
  }
}

// ---- rows and state ----------------------------------------------------

function keep(list, now) {
  let cut = 0;
  while (cut < list.length && list[cut].t_s < now - WINDOW_S) cut++;
  if (list.length - cut > MAX_ROWS) cut = list.length - MAX_ROWS;
  if (cut > 0) list.splice(0, cut);
}

function onBatch(b) {
  let now = state.t_s || 0;
  for (const r of b.rows) {
    received++;
    // Control updates share the μ plot with the estimates.
    const list = r.kind === "status" ? rows.status : rows.estimate;
    list.push(r);
    now = Math.max(now, r.t_s);
  }
  keep(rows.estimate, now);
  keep(rows.status, now);
  droppedRows += b.dropped_rows || 0;
  state = b.state || state;
  for (const e of b.events || []) message(e.text, bad(e.text));
  showState();
  dirty = true;
}

// An event the page shows in red: a fault, a lost link, a refused command.
function bad(t) {
  return /fault latched|^device:|recording stopped/.test(t) || (/^fricctl /.test(t) && !/: done$/.test(t));
}

function text(id, v) { $(id).textContent = v; }

function fmt(x, unit, digits) {
  if (x == null) return "–";
  return Number(x).toPrecision(digits || 5) + (unit ? " " + unit : "");
}

function showState() {
  const s = state;
  const run = $("run-state");
  run.textContent = s.running ? "running" : "stopped";
  run.className = s.running ? "running" : "stopped";
  text("mode", s.drive_mode ? (s.drive_mode === "open_loop" ? "voltage (open loop)" : "displacement") + (s.track && s.track !== "none" ? ", tracking " + s.track : "") : "–");
  text("locked", s.locked == null ? "–" : s.locked ? "yes" : "no");
  const f = $("faults");
  const faults = s.faults || [];
  f.textContent = faults.length ? faults.join(", ") : "none";
  f.className = faults.length ? "fault" : "";
  const id = s.identified;
  text("ident", id ? `z: f_r ${fmt(id.resonance_z_hz, "Hz", 6)}, Q ${fmt(id.q_z, "", 4)}; x: f_r ${fmt(id.resonance_x_hz, "Hz", 6)}, Q ${fmt(id.q_x, "", 4)}` : "none (voltage mode only)");
  text("cpu", s.cpu_load_pct == null ? "not reported by this device" : `${fmt(s.cpu_load_pct, "%", 3)} (max ${fmt(s.cpu_load_max_pct, "%", 3)})`);
  const c = s.control;
  text("loop", c && c.on ? `on: μ* ${c.target_mu} at v₀ ${c.v0} m/s` : "off");
  text("phi-set", fmt(s.phi_deg, "deg", 5));
  const last = rows.status[rows.status.length - 1];
  text("phi-measured", fmt(last && last.phase_measured_deg, "deg", 5));
  text("stream", (s.streaming ? `estimates every ${s.periods} periods` : s.loop_on ? "the μ loop's updates" : "off") + (s.link_error ? " — " + s.link_error : ""));
  text("recording", s.recording ? "to " + s.recording : "off (--record FILE)");
  text("rows", `${received} rows received` + (lostBatches ? `, ${lostBatches} batches lost` : "") + (droppedRows ? `, ${droppedRows} rows thinned` : ""));
  $("rows").dataset.received = String(received);
}

function message(t, isErr) {
  const m = $("messages");
  const line = document.createElement("div");
  line.textContent = new Date().toISOString().slice(11, 19) + "  " + t;
  if (isErr) line.className = "err";
  m.appendChild(line);
  while (m.childNodes.length > MAX_MESSAGES) m.removeChild(m.firstChild);
  m.scrollTop = m.scrollHeight;
}

// ---- controls: the CLI's commands -------------------------------------

const metres = (umValue) => String(Number((Number(umValue) * 1e-6).toPrecision(9)));

async function run(words) {
  if (readOnly) { message("read-only view (--read-only): the controls are off", true); return; }
  message("$ fricctl device " + words.join(" "));
  try {
    const r = await fetch("/api/action", {
      method: "POST", headers: { "content-type": "application/json" },
      body: JSON.stringify({ words }),
    });
    const a = await r.json();
    // A refusal (422) reaches every page as an event of the batch; the
    // answer of a command done, and the server's own refusals, only here.
    if (r.status !== 422) {
      for (const line of String(a.message).trim().split("\n")) message(line, !a.ok);
    }
  } catch (e) {
    message("no answer from the view's server: " + e, true);
  }
}

function field(id, flag) {
  const v = $(id).value.trim();
  if (v === "") throw new Error(flag + ": empty");
  return v;
}

function driveWords(track) {
  const s = state;
  const w = ["drive", "set", "--freq", String(s.freq),
    "--amp-z", metres(field("amp-z", "--amp-z")), "--amp-x", metres(field("amp-x", "--amp-x")),
    "--offset-z", metres(field("offset", "--offset-z")), "--phase-deg", field("phase", "--phase-deg")];
  if (s.drive_mode === "open_loop" && track === undefined) {
    w.push("--open-loop");
  } else {
    w.push("--track", track === undefined ? (s.track || "none") : track);
    if (s.drive_mode !== "open_loop" && s.headroom != null) w.push("--headroom", String(s.headroom));
  }
  return w;
}

function loadCurrent() {
  const s = state;
  if (s.duz == null) return;
  $("amp-z").value = Number((s.duz * 1e6).toPrecision(9));
  $("amp-x").value = Number((s.dux * 1e6).toPrecision(9));
  $("offset").value = Number((s.uz0 * 1e6).toPrecision(9));
  $("phase").value = s.phi_deg;
}

function guarded(f) {
  return () => { try { f(); } catch (e) { message(e.message, true); } };
}

function download() {
  const all = rows.estimate.concat(rows.status).sort((a, b) => a.t_s - b.t_s);
  const cell = (v) => v == null ? "" : Array.isArray(v) ? v.join(" ") : String(v);
  const lines = [columns.join(",")].concat(all.map((r) => columns.map((k) => cell(r[k])).join(",")));
  const blob = new Blob([lines.join("\n") + "\n"], { type: "text/csv" });
  const a = document.createElement("a");
  a.href = URL.createObjectURL(blob);
  a.download = "fricctl-view-" + new Date().toISOString().replace(/[:.]/g, "-") + ".csv";
  a.click();
  setTimeout(() => URL.revokeObjectURL(a.href), 1000);
  message(`recorded ${all.length} rows (what is shown) to ${a.download}`);
}

function wire() {
  $("start").onclick = () => run(["start"]);
  $("stop").onclick = () => run(["stop"]);
  $("reset-faults").onclick = () => run(["reset-faults"]);
  $("apply").onclick = guarded(() => run(driveWords()));
  $("load").onclick = loadCurrent;
  $("track-on").onclick = guarded(() => run(driveWords("z")));
  $("track-off").onclick = guarded(() => run(driveWords("none")));
  $("loop-on").onclick = guarded(() => run(["control", "--target-mu", field("target-mu", "--target-mu"), "--v0", field("v0", "--v0")]));
  $("loop-off").onclick = () => run(["control", "off"]);
  $("record").onclick = download;
}

function setReadOnly(ro) {
  readOnly = ro;
  $("readonly").style.display = ro ? "inline" : "none";
  for (const b of $("controls").querySelectorAll("button")) if (b.id !== "record") b.disabled = ro;
}

// ---- connection -------------------------------------------------------

let loaded = false;

function connect() {
  const ws = new WebSocket((location.protocol === "https:" ? "wss://" : "ws://") + location.host + "/ws");
  ws.onopen = () => text("conn", "connected");
  ws.onclose = () => { text("conn", "disconnected — retrying"); setTimeout(connect, 1000); };
  ws.onmessage = (ev) => {
    const m = JSON.parse(ev.data);
    if (m.type === "hello") {
      columns = m.columns;
      setReadOnly(m.read_only);
      text("link", m.link);
    } else if (m.type === "batch") {
      onBatch(m);
      if (!loaded && state.duz != null) { loadCurrent(); loaded = true; }
    } else if (m.type === "lagged") {
      lostBatches += m.batches;
    }
  };
}

for (const p of PLOTS) makePlot(p);
wire();
connect();
setInterval(redraw, REDRAW_MS);
