// mi-brdfs explore: the page. Controls are generated from GET /api/models;
// every change is sent over the websocket (plots, render, walk). Each column
// keeps at most one request of each kind in flight: a change made meanwhile
// is sent when the answer comes (the newest state only, never a queue), so
// that a dragged slider's plots follow it at the speed the server answers.
// Only the answer to the newest request of each kind is shown.
"use strict";

const CHANNELS = [["R", "#d62728"], ["G", "#2ca02c"], ["B", "#1f77b4"]];
const DEFAULTS = {
  left: {type: "cook_torrance", distribution: "ggx", geometry: "smith", alpha: 0.3, k: 0.2,
         diffuse_reflectance: [0.6, 0.12, 0.05]},
  right: {type: "roughconductor", material: "Au", distribution: "ggx", alpha: 0.3},
};
const SLIDER_MAX = 1e4;    // an unbounded or huge range: the slider stops here (type more)
const PLOT_CONFIG = {displayModeBar: false, responsive: true};
const FONT = {family: "system-ui, sans-serif", size: 11};

const page = {models: {}, ws: null, nextId: 1, columns: {}};

// ---------------------------------------------------------------- numbers and colours
const toLinear = c => (c <= 0.04045 ? c / 12.92 : ((c + 0.055) / 1.055) ** 2.4);
const toSrgb = c => (c <= 0.0031308 ? 12.92 * c : 1.055 * c ** (1 / 2.4) - 0.055);
const hexOf = rgb => "#" + rgb.map(c => Math.round(255 * Math.min(1, Math.max(0, toSrgb(c))))
  .toString(16).padStart(2, "0")).join("");
const rgbOf = hex => [1, 3, 5].map(i => toLinear(parseInt(hex.slice(i, i + 2), 16) / 255));
const shown = v => (Array.isArray(v) ? v.map(c => +c.toFixed(3)).join(", ") : String(+(+v).toPrecision(4)));

function parsed(text, colour) {
  // a number, a list of three for a colour, or the text itself (the server explains why not)
  const parts = text.split(",").map(s => s.trim());
  const nums = parts.map(Number);
  if (parts.every(s => s !== "") && nums.every(Number.isFinite)) {
    if (nums.length === 1) return nums[0];
    if (colour && nums.length === 3) return nums;
  }
  return text;
}

// A slider position in [0, 1000] and a value: linear, or logarithmic for a
// shape parameter whose range spans more than a decade (an exponent).
function scale(p) {
  const lo = p.lo ?? -1, hi = Math.min(p.upper ?? 1, SLIDER_MAX);
  if (p.role === "shape" && lo === 0 && hi > 10) {
    const top = Math.log1p(hi);
    return {toValue: t => Math.expm1(t / 1000 * top), toSlider: v => 1000 * Math.log1p(Math.max(v, 0)) / top};
  }
  return {toValue: t => lo + (hi - lo) * t / 1000, toSlider: v => 1000 * (v - lo) / (hi - lo)};
}

// ---------------------------------------------------------------- the connection
function send(column, op, extra) {
  if (!page.ws || page.ws.readyState !== WebSocket.OPEN) return;
  const id = page.nextId++;
  column.latest[op] = id;
  page.ws.send(JSON.stringify({op, id, side: column.side, ...extra}));
  trace("sent", column, op, id);
}

// What each throttled operation sends: the column's state when it is sent.
const REQUESTS = {
  plots: column => ({material: column.material, theta_i: theta()}),
  render: column => ({material: column.material, res: +document.getElementById("res").value}),
  walk: column => ({material: column.material}),
};

// Ask for `op` with the column's current state: now if none of its kind is in
// flight, else once the one in flight answers (a render: its first pass). The
// walk (NumPy on the server's other thread, a second or so) also waits for
// the plots and the render's first pass: it would take CPU from them.
function request(column, op) {
  if (column.inflight[op] || (op === "walk" && (column.inflight.plots || column.inflight.render))) {
    column.wanted[op] = true;
    return;
  }
  column.wanted[op] = false;
  send(column, op, REQUESTS[op](column));
  column.inflight[op] = column.latest[op];
}

function answered(column, op, id) {
  if (column.inflight[op] !== id) return;
  column.inflight[op] = null;
  if (column.wanted[op]) request(column, op);
  if (op !== "walk" && column.wanted.walk) request(column, "walk");
}

// Timings for a page that measures itself (mi_brdfs/tools/explore/latency.py):
// an "explore" event on the document for every request sent and answer shown.
function trace(what, column, op, id, extra) {
  document.dispatchEvent(new CustomEvent("explore", {detail: {
    what, side: column.side, op, id, t: performance.now(), ...extra}}));
}

function connect() {
  return new Promise(resolve => {
    const ws = new WebSocket(`ws://${location.host}/ws`);
    ws.onopen = () => resolve(ws);
    ws.onmessage = event => receive(JSON.parse(event.data));
    ws.onclose = () => status("disconnected: the server stopped (reload the page when it runs)");
    page.ws = ws;
  });
}

function status(text) {
  document.getElementById("status").textContent = text;
}

function receive(msg) {
  const column = page.columns[msg.side];
  if (!column || msg.id !== column.latest[msg.op]) return;       // superseded
  msg.received = performance.now();
  // the next request first: the server computes it while this answer is drawn
  if (msg.op in REQUESTS) answered(column, msg.op, msg.id);
  show(column, msg);
  if (msg.op === "render") draw3dSoon(column);
}

function show(column, msg) {
  if (msg.error) {
    if (msg.op === "fit") status("fit failed: " + msg.error);
    else if (msg.op !== "walk") column.el.querySelector(".error").textContent = msg.error;
    return;
  }
  if (msg.op === "plots") drawPlots(column, msg);
  else if (msg.op === "render") showImage(column, msg);
  else if (msg.op === "walk") { column.walk = msg.E ? msg : null; drawAlbedo(column); }
  else if (msg.op === "material") showCopied(column, msg);
  else if (msg.op === "fit") fitted(msg);
  if (msg.op in REQUESTS) trace("shown", column, msg.op, msg.id, {spp: msg.spp, received: msg.received});
}

// ---------------------------------------------------------------- a column
function makeColumn(section, material, choices) {
  section.append(document.getElementById("column").content.cloneNode(true));
  const column = {side: section.dataset.side, el: section, latest: {}, inflight: {},
                  wanted: {}, material: null, walk: null, plots: null, pending: false};
  page.columns[column.side] = column;
  const select = section.querySelector(".model");
  for (const m of Object.values(page.models).filter(choices)) {
    select.add(new Option(`${m.name}${m.source === "mitsuba" ? " (Mitsuba)" : ""}`, m.name));
  }
  select.onchange = () => setMaterial(column, {type: select.value, mode: column.material.mode});
  section.querySelector(".mode").onchange = e => change(column, "mode", e.target.value);
  for (const as of ["xml", "python"]) {
    section.querySelector(`.copy-${as}`).onclick = () => {
      column.copyAs = as;
      send(column, "material", {material: column.material});
    };
  }
  setMaterial(column, material);
  return column;
}

function setMaterial(column, material) {
  // the material completed with its model's defaults, and controls for it
  const model = page.models[material.type];
  const m = {type: model.name, mode: material.mode ?? "hdr"};
  for (const o of model.options) if (o.name !== "mode") m[o.name] = material[o.name] ?? o.default;
  for (const p of model.params) if (controlled(p, m)) m[p.name] = material[p.name] ?? p.default;
  column.material = m;
  column.walk = null;
  const el = column.el;
  el.querySelector(".model").value = model.name;
  el.querySelector(".mode").value = m.mode;
  el.querySelector(".title").textContent = model.title;
  buildOptions(column, model);
  buildParams(column, model);
  update(column);
}

// A parameter has a control while the configuration exposes it: with the
// model's defaults (p.control), or with a choice of an option (p.when:
// option -> the choices that expose it, e.g. cook_torrance's eta and kappa
// with fresnel "conductor").
function controlled(p, m) {
  if (p.control && !p.optional) return true;
  return Object.entries(p.when ?? {}).some(([option, choices]) => choices.includes(m[option]));
}

// Another choice of an option: the controls it exposes appear (their
// defaults), the ones it no longer exposes go.
function changeOption(column, name, value) {
  const model = page.models[column.material.type];
  const m = {...column.material, [name]: value};
  for (const p of model.params) if (p.when && !controlled(p, m)) delete m[p.name];
  setMaterial(column, m);
}

function row(container, label, doc, ...inputs) {
  const name = document.createElement("label");
  name.textContent = label;
  name.title = doc;
  container.append(name, ...inputs);
}

function buildOptions(column, model) {
  const box = column.el.querySelector(".options");
  box.replaceChildren();
  for (const o of model.options) {
    if (o.name === "mode") continue;
    let input;
    if (o.type === "bool") {
      input = Object.assign(document.createElement("input"), {type: "checkbox", checked: column.material[o.name]});
      input.onchange = () => changeOption(column, o.name, input.checked);
    } else if (o.type === "int") {
      input = Object.assign(document.createElement("input"), {type: "number", min: o.lo, max: o.hi, value: column.material[o.name]});
      input.onchange = () => changeOption(column, o.name, parseInt(input.value, 10));
    } else {
      input = document.createElement("select");
      for (const c of o.choices) input.add(new Option(c, c));
      input.value = column.material[o.name];
      input.onchange = () => changeOption(column, o.name, input.value);
    }
    input.dataset.name = o.name;
    row(box, o.name, o.doc, input, document.createElement("span"));
  }
}

function buildParams(column, model) {
  const box = column.el.querySelector(".params");
  box.replaceChildren();
  for (const p of model.params) {
    if (!(p.name in column.material)) continue;
    const text = Object.assign(document.createElement("input"), {type: "text", value: shown(column.material[p.name])});
    text.dataset.name = p.name;
    let control;
    if (p.kind === "spectrum") {
      const v = column.material[p.name];
      control = Object.assign(document.createElement("input"), {type: "color", value: hexOf(Array.isArray(v) ? v : [v, v, v])});
      control.oninput = () => {
        const rgb = rgbOf(control.value);
        text.value = shown(rgb);
        change(column, p.name, rgb, MOVING);
      };
      control.onchange = () => update(column, ["walk"]);
      text.onchange = () => {
        const v = parsed(text.value, true);
        if (Array.isArray(v) || typeof v === "number") control.value = hexOf(Array.isArray(v) ? v : [v, v, v]);
        change(column, p.name, v);
      };
    } else {
      const s = scale(p);
      control = Object.assign(document.createElement("input"), {type: "range", min: 0, max: 1000, step: 1,
                                                                  value: s.toSlider(column.material[p.name])});
      control.oninput = () => {
        const v = +s.toValue(+control.value).toPrecision(4);
        text.value = shown(v);
        change(column, p.name, v, MOVING);
      };
      control.onchange = () => update(column, ["walk"]);      // released
      text.onchange = () => {
        const v = parsed(text.value, false);
        if (typeof v === "number") control.value = s.toSlider(v);
        change(column, p.name, v);
      };
    }
    control.dataset.name = p.name;
    row(box, p.name, p.doc, control, text);
  }
}

// While a slider or a colour picker moves, the plots and the render follow
// it; the random walk (a second or so of NumPy on the server's other thread,
// taking CPU from the plots) waits until it is released, its dots hidden.
const MOVING = ["plots", "render"];

function change(column, name, value, ops) {
  column.material[name] = value;
  if (ops && !ops.includes("walk")) column.walk = null;    // its dots were of another value
  update(column, ops);
}

// Coalesce changes to one request of each kind per animation frame.
function update(column, ops = ["plots", "render", "walk"]) {
  column.ops = new Set([...(column.ops ?? []), ...ops]);
  if (column.pending) return;
  column.pending = true;
  requestAnimationFrame(() => {
    column.pending = false;
    const wanted = column.ops;
    column.ops = null;
    if (wanted.has("render")) column.el.querySelector(".preview").dataset.spp = "0";   // until the new render's first pass
    for (const op of wanted) request(column, op);
  });
}

const theta = () => +document.getElementById("theta").value;

// ---------------------------------------------------------------- the views
// R, G and B differ in dash and width too: a grey material's three curves
// coincide, and each stays visible.
const LINES = [{dash: "solid", width: 3}, {dash: "dash", width: 2}, {dash: "dot", width: 1.5}];
const RADIUS = "f·cos θo (1/sr)";

function drawPlots(column, msg) {
  column.el.querySelector(".error").textContent = "";
  column.plots = msg;
  column.lobeTop = Math.max(1e-6, ...msg.lobe.rgb.flat());
  // both columns' lobes on one radial scale: they are compared side by side
  const top = Math.max(...Object.values(page.columns).filter(c => c.plots).map(c => c.lobeTop));
  for (const c of Object.values(page.columns)) {
    if (c === column) drawLobe(c, top);
    else if (c.plots && c.drawnTop !== top) drawLobe(c, top);
  }
  drawAlbedo(column);
  column.el.dataset.plots = String(msg.id);
  // The 3-D lobe (WebGL, in software on a machine without a GPU: the slowest
  // view by far) later, the newest only: once the render's first pass is
  // shown if one is on its way, so that it holds up neither that image nor
  // the other views.
  column.lobe3dWanted = msg;
  if (!column.inflight.render) draw3dSoon(column);
}

const LOBE3D_MS = 400;

function draw3dSoon(column) {
  if (column.lobe3dPending || !column.lobe3dWanted) return;
  column.lobe3dPending = true;
  requestAnimationFrame(() => setTimeout(() => {
    column.lobe3dPending = false;
    // a newer answer is coming (a drag): drawn at most every LOBE3D_MS, the
    // newest drawn when the answers stop
    if (column.inflight.plots && performance.now() - (column.lobe3dAt ?? 0) < LOBE3D_MS) return;
    column.lobe3dAt = performance.now();
    const newest = column.lobe3dWanted;
    column.lobe3dWanted = null;
    drawLobe3d(column, newest);
    column.el.dataset.lobe3d = String(newest.id);
    trace("shown", column, "lobe3d", newest.id, {received: newest.received});
  }));
}

function drawLobe(column, top) {
  // the lobe: plotted angle 90° - θo puts the normal up and the mirror side right
  const msg = column.plots;
  column.drawnTop = top;
  const angle = msg.lobe.theta.map(t => 90 - t);
  const traces = msg.lobe.rgb.map((r, c) => ({type: "scatterpolar", mode: "lines", r, theta: angle,
                                              name: CHANNELS[c][0],
                                              line: {color: CHANNELS[c][1], ...LINES[c]}}));
  traces.push({type: "scatterpolar", mode: "lines", r: [0, top], theta: [90 + msg.theta_i, 90 + msg.theta_i],
               name: "viewer", line: {color: "#888", dash: "dot"}});
  Plotly.react(column.el.querySelector(".lobe"), traces, {
    title: {text: "eval = f·cos θo in the plane of incidence<br>radius: " + RADIUS
                  + ", one scale for both columns", font: FONT},
    font: FONT, margin: {l: 35, r: 35, t: 50, b: 10}, showlegend: true,
    legend: {orientation: "h", x: 0.5, xanchor: "center", y: 0.02, yanchor: "bottom"},
    polar: {sector: [0, 180], domain: {y: [0.14, 1]},
            radialaxis: {range: [0, top * 1.05], angle: 0, tickangle: 0, nticks: 4,
                         title: {text: "1/sr", font: FONT}},
            angularaxis: {tickvals: [0, 30, 60, 90, 120, 150, 180],
                          ticktext: ["90°", "60°", "30°", "0°", "-30°", "-60°", "-90°"]}},
  }, PLOT_CONFIG);
}

function drawLobe3d(column, msg) {
  // A fixed box, the same for every lobe: [-R, R]² × [0, R] with R the
  // largest radius (the lobe's or the viewer's arrow), seen from a fixed
  // camera, so that no lobe however long or tilted leaves the panel.
  const v = msg.lobe3d;
  const flat = a => a.flat().map(Math.abs);
  const r = Math.max(1e-6, ...flat(v.x), ...flat(v.y), ...flat(v.z));
  const t = msg.theta_i * Math.PI / 180;
  const axis = (title, range) => ({title: {text: title}, range, autorange: false,
                                   showticklabels: false, zeroline: false});
  Plotly.react(column.el.querySelector(".lobe3d"), [
    {type: "surface", x: v.x, y: v.y, z: v.z, showscale: false, colorscale: "Viridis"},
    {type: "scatter3d", mode: "lines", x: [0, -Math.sin(t) * r], y: [0, 0], z: [0, Math.cos(t) * r],
     line: {color: "#444", width: 4}, name: "viewer"},
  ], {title: {text: "the lobe over the hemisphere (channel mean)", font: FONT}, font: FONT,
      margin: {l: 0, r: 0, t: 30, b: 0}, showlegend: false,
      scene: {aspectmode: "manual", aspectratio: {x: 1, y: 1, z: 0.5},
              camera: {eye: {x: 0.25, y: -1.7, z: 0.8}, center: {x: 0, y: 0, z: -0.1}},
              xaxis: axis("x", [-r, r]), yaxis: axis("y", [-r, r]), zaxis: axis("n", [0, r])}},
  PLOT_CONFIG);
}

function drawAlbedo(column) {
  const msg = column.plots;
  if (!msg) return;
  const dashes = ["solid", "dash", "dot"];
  const traces = msg.albedo.curves.map((c, i) => ({type: "scatter", mode: "lines", x: msg.albedo.theta, y: c.E,
                                                   name: c.label, line: {dash: dashes[i % 3]}}));
  if (column.walk) {
    traces.push({type: "scatter", mode: "markers", x: column.walk.theta, y: column.walk.E,
                 name: "white, random walk", marker: {color: "#000", size: 5}});
  }
  const f = msg.furnace;
  const title = f ? `white furnace: ${f.mean.toFixed(3)} (E up to ${f.max.toFixed(3)} at ${f.at}°)` : "";
  Plotly.react(column.el.querySelector(".albedo"), traces, {
    title: {text: "directional albedo E(θi)<br>" + title, font: FONT}, font: FONT,
    // the legend at the foot of the panel, under the axis title: never over it
    margin: {l: 50, r: 10, t: 45, b: 40 + 19 * traces.length},
    legend: {orientation: "h", x: 0, xanchor: "left", yref: "container", y: 0, yanchor: "bottom",
             font: {size: 10}},
    xaxis: {title: {text: "θi (degrees)", standoff: 4}, range: [0, 90]},
    yaxis: {title: {text: "E (fraction reflected)", standoff: 4}, rangemode: "tozero"},
  }, PLOT_CONFIG);
}

function showImage(column, msg) {
  column.el.querySelector(".error").textContent = "";
  const img = column.el.querySelector(".preview");
  img.src = msg.image;
  img.dataset.spp = String(msg.spp);
  column.el.querySelector(".spp").textContent = `${msg.res}², ${msg.spp} spp${msg.final ? "" : " …"}`;
}

async function showCopied(column, msg) {
  const text = column.copyAs === "python" ? msg.python : msg.xml;
  const pre = column.el.querySelector(".copied");
  pre.textContent = text;
  pre.hidden = false;
  try {
    await navigator.clipboard.writeText(text);
    status(`${column.copyAs === "python" ? "Python" : "XML"} copied`);
  } catch {
    status("the clipboard is not available: copy the text below the buttons");
  }
}

function fitted(msg) {
  const error = msg.brdf_error === null ? "not finite" : msg.brdf_error.toFixed(3);
  status(`fitted: BRDF error ${error} (0 identical, 1 as far as black)`);
  setMaterial(page.columns.left, msg.material);
}

// ---------------------------------------------------------------- start
async function main() {
  status("loading…");
  for (const m of await (await fetch("/api/models")).json()) page.models[m.name] = m;
  await connect();
  status("");
  const [left, right] = document.querySelectorAll(".column");
  makeColumn(left, DEFAULTS.left, m => m.source === "mi_brdfs");
  makeColumn(right, DEFAULTS.right, () => true);
  const slider = document.getElementById("theta");
  slider.oninput = () => {
    document.getElementById("theta-out").textContent = `${slider.value}°`;
    for (const c of Object.values(page.columns)) update(c, ["plots"]);
  };
  document.getElementById("res").onchange = () => Object.values(page.columns).forEach(update);
  document.getElementById("fit").onclick = () => {
    status("fitting…");
    send(page.columns.left, "fit", {left: page.columns.left.material, right: page.columns.right.material});
  };
}

main();
