// rtaw-view's page: replays one or two executed episodes (rtaw_marl.viz.episode_data).
// Positions are rebuilt from move codes: a keyframe every KEY timesteps is computed on
// load, any timestep is at most KEY - 1 rows of moves from one.
"use strict";
window.rtawErrors = [];
window.addEventListener("error", (e) => window.rtawErrors.push(String(e.message)));
window.addEventListener("unhandledrejection", (e) => window.rtawErrors.push(String(e.reason)));

const KEY = 64;
const DX = [0, 1, -1, 0, 0];
const DY = [0, 0, 0, 1, -1];
const IDLE = 0, TO_PICKUP = 1, CARRYING = 2;
const STATE_NAMES = ["idle", "to pickup", "carrying"];
const QUEUED_COLOR = "#5a5a5a";
const STATE_COLORS = ["#8c8c8c", "#1f6fd1", "#e8710a"];
const CELL_COLORS = [[242, 242, 242], [58, 63, 75], [204, 236, 204], [252, 222, 190]];
// Below this many pixels per cell, robots are drawn as pixels of a grid-sized image.
const PIXEL_MODE = 4;
const rgba32 = (hex) => { const v = parseInt(hex.slice(1), 16); return (0xff << 24 | (v & 0xff) << 16 | (v & 0xff00) | (v >> 16)) >>> 0; };
const STATE_PIXELS = Uint32Array.from(STATE_COLORS, rgba32);
const TYPES = { uint8: Uint8Array, uint16: Uint16Array, uint32: Uint32Array, int32: Int32Array };

async function decode(a) {
  const text = atob(a.data);
  const bytes = new Uint8Array(text.length);
  for (let i = 0; i < text.length; i++) bytes[i] = text.charCodeAt(i);
  const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("deflate"));
  return new TYPES[a.dtype](await new Response(stream).arrayBuffer());
}

// One episode: positions at any timestep, robot states, tasks by robot. Moves come
// robot by robot: robot m's move from s to s + 1 is moves[m * T + s].
class Episode {
  constructor(meta, arrays) {
    this.name = meta.name;
    this.summary = meta.summary;
    this.M = meta.robots;
    this.T = meta.steps;
    this.binSize = meta.bin_size;
    Object.assign(this, arrays);
    this.K = this.tasks.length / 9;
    this.buildKeyframes();
    this.indexTasks();
    this.pos = new Int16Array(2 * this.M);
    this.state = new Uint8Array(this.M);
    this.task = new Int32Array(this.M);
    this.at = -1;
    this.finishedBefore = new Int32Array(this.T + 2);
    for (let t = 0; t <= this.T; t++) this.finishedBefore[t + 1] = this.finishedBefore[t] + this.delivered[t];
  }
  buildKeyframes() {
    const M = this.M, pos = new Int16Array(2 * M);
    for (let i = 0; i < 2 * M; i++) pos[i] = this.start[i];
    this.keys = [];
    for (let t = 0; t <= this.T; t++) {
      if (t % KEY === 0) this.keys.push(pos.slice());
      if (t === this.T) break;
      const T = this.T;
      for (let m = 0; m < M; m++) {
        const c = this.moves[m * T + t];
        if (c) { pos[2 * m] += DX[c]; pos[2 * m + 1] += DY[c]; }
      }
    }
  }
  indexTasks() {
    const M = this.M, K = this.K, tk = this.tasks;
    this.robotFirst = new Int32Array(M + 1);
    for (let k = 0; k < K; k++) this.robotFirst[tk[9 * k + 4] + 1]++;
    for (let m = 0; m < M; m++) this.robotFirst[m + 1] += this.robotFirst[m];
    const fill = this.robotFirst.slice(0, M);
    this.byRobot = new Int32Array(K);
    // Tasks are numbered by assignment time, so each robot's list comes out in time order.
    for (let k = 0; k < K; k++) this.byRobot[fill[tk[9 * k + 4]]++] = k;
  }
  field(k, i) { return this.tasks[9 * k + i]; }
  // Bring positions, states and tasks to integer timestep t.
  seek(t) {
    const M = this.M;
    if (t === this.at) return;
    if (t > this.at && this.at >= 0 && t - this.at < KEY) {
      for (let s = this.at; s < t; s++) this.applyRow(s);
    } else {
      const k = Math.floor(t / KEY);
      this.pos.set(this.keys[k]);
      for (let s = k * KEY; s < t; s++) this.applyRow(s);
    }
    this.at = t;
    const tk = this.tasks;
    for (let m = 0; m < M; m++) {
      let st = IDLE, cur = -1;
      for (let j = this.robotFirst[m]; j < this.robotFirst[m + 1]; j++) {
        const k = this.byRobot[j];
        if (tk[9 * k + 6] > t) break;
        if (t < tk[9 * k + 8]) { cur = k; st = t < tk[9 * k + 7] ? TO_PICKUP : CARRYING; break; }
      }
      this.state[m] = st;
      this.task[m] = cur;
    }
  }
  applyRow(s) {
    const T = this.T, pos = this.pos, mv = this.moves;
    for (let m = 0; m < this.M; m++) {
      const c = mv[m * T + s];
      if (c) { pos[2 * m] += DX[c]; pos[2 * m + 1] += DY[c]; }
    }
  }
  // Robot m's cells from timestep a to b (inclusive), from the current position.
  path(m, a, b) {
    const out = [];
    let k = Math.floor(a / KEY), x = this.keys[k][2 * m], y = this.keys[k][2 * m + 1];
    for (let s = k * KEY; s < a; s++) { const c = this.moves[m * this.T + s]; x += DX[c]; y += DY[c]; }
    out.push(x, y);
    for (let s = a; s < Math.min(b, this.T); s++) {
      const c = this.moves[m * this.T + s]; x += DX[c]; y += DY[c]; out.push(x, y);
    }
    return out;
  }
  waits(m, a, b) {
    let n = 0;
    for (let s = a; s < Math.min(b, this.T); s++) if (this.moves[m * this.T + s] === 0) n++;
    return n;
  }
  moveAt(m, t) { return t < this.T ? this.moves[m * this.T + t] : 0; }
}

// ---------------------------------------------------------------------------- the view
const view = {
  episodes: [], panels: [], W: 0, H: 0, time: 0, playing: false, speed: 10,
  scale: 1, offX: 0, offY: 0, selected: -1, selectedPanel: 0, follow: false, heat: false,
  frames: 0, drawMs: 0, lastTick: 0, message: "",
};

function el(id) { return document.getElementById(id); }

function mapCanvas(cells) {
  const c = document.createElement("canvas");
  c.width = view.W; c.height = view.H;
  const ctx = c.getContext("2d"), img = ctx.createImageData(view.W, view.H);
  for (let i = 0; i < cells.length; i++) {
    const rgb = CELL_COLORS[cells[i]] || CELL_COLORS[0];
    img.data.set([rgb[0], rgb[1], rgb[2], 255], 4 * i);
  }
  ctx.putImageData(img, 0, 0);
  return c;
}

function makePanel(ep, index) {
  const div = document.createElement("div");
  div.className = "panel";
  const canvas = document.createElement("canvas");
  const label = document.createElement("div");
  label.className = "label";
  div.append(canvas, label);
  el("panels").append(div);
  const heat = document.createElement("canvas");
  heat.width = view.W; heat.height = view.H;
  const mini = document.createElement("canvas");
  mini.width = view.W; mini.height = view.H;
  mini.title = ep.name;
  el("heatmaps").append(mini);
  const panel = { ep, index, div, canvas, label, heat, mini, heatBin: -1, ctx: canvas.getContext("2d") };
  attachMouse(panel);
  return panel;
}

function fit() {
  const r = view.panels[0].canvas.getBoundingClientRect();
  view.scale = Math.max(0.05, Math.min(r.width / view.W, r.height / view.H));
  view.offX = (r.width - view.W * view.scale) / 2;
  view.offY = (r.height - view.H * view.scale) / 2;
  view.follow = false;
  el("follow").checked = false;
}

function resize() {
  const dpr = window.devicePixelRatio || 1;
  for (const p of view.panels) {
    const r = p.canvas.getBoundingClientRect();
    p.canvas.width = Math.max(1, Math.round(r.width * dpr));
    p.canvas.height = Math.max(1, Math.round(r.height * dpr));
  }
}

// The robot's drawn position at fractional time: its cell at t moved by frac of its move.
function drawnXY(ep, m, frac) {
  const c = ep.moveAt(m, ep.at);
  return [ep.pos[2 * m] + DX[c] * frac, ep.pos[2 * m + 1] + DY[c] * frac];
}

function updateHeat(panel, bin) {
  const ep = panel.ep, size = view.W * view.H, counts = ep.congestion.subarray(bin * size, (bin + 1) * size);
  for (const canvas of [panel.heat, panel.mini]) {
    const ctx = canvas.getContext("2d"), img = ctx.createImageData(view.W, view.H);
    const overlay = canvas === panel.heat;
    for (let i = 0; i < size; i++) {
      const v = Math.min(1, counts[i] / Math.max(1, ep.binSize * 0.5));
      const o = 4 * i;
      if (overlay) { img.data[o] = 220; img.data[o + 1] = 20; img.data[o + 2] = 20; img.data[o + 3] = v > 0 ? 40 + 200 * v : 0; }
      else {
        const base = CELL_COLORS[view.cells[i]] || CELL_COLORS[0];
        const shade = view.cells[i] === 1 ? base : base.map((b, j) => Math.round(b * (1 - v) + [220, 20, 20][j] * v));
        img.data[o] = shade[0]; img.data[o + 1] = shade[1]; img.data[o + 2] = shade[2]; img.data[o + 3] = 255;
      }
    }
    ctx.putImageData(img, 0, 0);
  }
}

function drawPanel(panel, frac) {
  const ep = panel.ep, ctx = panel.ctx, dpr = window.devicePixelRatio || 1;
  const s = view.scale;
  ctx.setTransform(1, 0, 0, 1, 0, 0);
  ctx.fillStyle = "#ffffff";
  ctx.fillRect(0, 0, panel.canvas.width, panel.canvas.height);
  ctx.setTransform(dpr * s, 0, 0, dpr * s, dpr * view.offX, dpr * view.offY);
  ctx.imageSmoothingEnabled = false;
  if (s < PIXEL_MODE) drawRobotPixels(panel, frac);
  else drawRobotRects(panel, frac);
  if (view.heat) ctx.drawImage(panel.heat, 0, 0);
  if (view.selected >= 0 && view.selected < ep.M) drawSelected(panel, frac);
  panel.label.textContent = `${ep.name}: ${ep.finishedBefore[ep.at + 1]} tasks delivered by t = ${ep.at}`;
}

// Zoomed out, a robot is a cell's pixel of one image the size of the grid, scaled up
// once: one blit instead of thousands of rectangles (software rasterizers choke on those).
function drawRobotPixels(panel, frac) {
  const ep = panel.ep, W = view.W, H = view.H;
  if (!panel.pixels) {
    panel.pixelCanvas = document.createElement("canvas");
    panel.pixelCanvas.width = W; panel.pixelCanvas.height = H;
    panel.image = panel.pixelCanvas.getContext("2d").createImageData(W, H);
    panel.pixels = new Uint32Array(panel.image.data.buffer);
  }
  const px = panel.pixels;
  px.set(view.mapPixels);
  for (let m = 0; m < ep.M; m++) {
    const [x, y] = drawnXY(ep, m, frac);
    const cx = Math.round(x), cy = Math.round(y);
    if (cx >= 0 && cx < W && cy >= 0 && cy < H) px[cy * W + cx] = STATE_PIXELS[ep.state[m]];
  }
  panel.pixelCanvas.getContext("2d").putImageData(panel.image, 0, 0);
  panel.ctx.drawImage(panel.pixelCanvas, 0, 0);
}

// Zoomed in: the map, then robots in view as rectangles that glide between cells, one
// path per state colour.
function drawRobotRects(panel, frac) {
  const ep = panel.ep, ctx = panel.ctx, s = view.scale, dpr = window.devicePixelRatio || 1;
  ctx.drawImage(view.map, 0, 0);
  const x0 = -view.offX / s - 1, y0 = -view.offY / s - 1;
  const x1 = x0 + panel.canvas.width / dpr / s + 2, y1 = y0 + panel.canvas.height / dpr / s + 2;
  drawQueued(panel, x0, y0, x1, y1);
  const pad = 0.12;
  for (let st = 0; st < 3; st++) {
    ctx.beginPath();
    for (let m = 0; m < ep.M; m++) {
      if (ep.state[m] !== st) continue;
      const [x, y] = drawnXY(ep, m, frac);
      if (x < x0 || x > x1 || y < y0 || y > y1) continue;
      ctx.rect(x + pad, y + pad, 1 - 2 * pad, 1 - 2 * pad);
    }
    ctx.fillStyle = STATE_COLORS[st];
    ctx.fill();
  }
}

// Tasks waiting in the queue at t (arrived, not yet assigned): hollow squares at their
// pickups. Tasks are sorted by assignment time, so the search starts past t's.
function drawQueued(panel, x0, y0, x1, y1) {
  const ep = panel.ep, tk = ep.tasks, t = ep.at;
  let lo = 0, hi = ep.K;
  while (lo < hi) { const mid = (lo + hi) >> 1; if (tk[9 * mid + 6] <= t) lo = mid + 1; else hi = mid; }
  const ctx = panel.ctx;
  ctx.beginPath();
  for (let k = lo; k < ep.K; k++) {
    if (tk[9 * k + 5] > t) continue;
    const x = tk[9 * k], y = tk[9 * k + 1];
    if (x < x0 || x > x1 || y < y0 || y > y1) continue;
    ctx.rect(x + 0.3, y + 0.3, 0.4, 0.4);
  }
  ctx.strokeStyle = QUEUED_COLOR;
  ctx.lineWidth = Math.max(0.08, 1 / view.scale);
  ctx.stroke();
}

function drawSelected(panel, frac) {
  const ep = panel.ep, ctx = panel.ctx, m = view.selected, s = view.scale;
  const lw = Math.max(0.12, 2 / s);
  const k = ep.task[m];
  if (k >= 0) {
    const a = ep.field(k, 6), b = ep.field(k, 8);
    const cells = ep.path(m, a, b);
    ctx.beginPath();
    for (let i = 0; i < cells.length; i += 2) ctx[i ? "lineTo" : "moveTo"](cells[i] + 0.5, cells[i + 1] + 0.5);
    ctx.strokeStyle = "rgba(20,20,20,0.7)";
    ctx.lineWidth = lw;
    ctx.stroke();
    const [ox, oy, dx, dy] = [ep.field(k, 0), ep.field(k, 1), ep.field(k, 2), ep.field(k, 3)];
    ctx.strokeStyle = STATE_COLORS[TO_PICKUP];
    ctx.lineWidth = 2 * lw;
    ctx.strokeRect(ox + 0.05, oy + 0.05, 0.9, 0.9);
    ctx.strokeStyle = STATE_COLORS[CARRYING];
    ctx.beginPath();
    ctx.moveTo(dx + 0.1, dy + 0.1); ctx.lineTo(dx + 0.9, dy + 0.9);
    ctx.moveTo(dx + 0.9, dy + 0.1); ctx.lineTo(dx + 0.1, dy + 0.9);
    ctx.stroke();
  }
  const [x, y] = drawnXY(ep, m, frac);
  ctx.beginPath();
  ctx.arc(x + 0.5, y + 0.5, Math.max(0.9, 6 / s), 0, 2 * Math.PI);
  ctx.strokeStyle = "#d0021b";
  ctx.lineWidth = 2 * lw;
  ctx.stroke();
}

// Tasks delivered per bin of timesteps, per episode: computed once.
function throughputSeries() {
  const T = view.T, bin = Math.max(1, Math.ceil((T + 1) / 150));
  const series = view.episodes.map((ep) => {
    const out = new Float64Array(Math.ceil((T + 1) / bin));
    for (let t = 0; t <= ep.T; t++) out[Math.floor(t / bin)] += ep.delivered[t];
    return out;
  });
  el("tp-bin").textContent = String(bin);
  return { bin, series, top: Math.max(1, ...series.map((s) => Math.max(...s))) };
}

function drawThroughput() {
  const c = el("throughput"), ctx = c.getContext("2d"), T = view.T;
  if (!view.throughput) view.throughput = throughputSeries();
  const { bin, series, top } = view.throughput;
  ctx.clearRect(0, 0, c.width, c.height);
  ctx.font = "10px sans-serif";
  const colors = ["#1f6fd1", "#d0021b"];
  series.forEach((s, i) => {
    ctx.beginPath();
    s.forEach((v, j) => ctx[j ? "lineTo" : "moveTo"]((j / s.length) * c.width, c.height - 12 - (v / top) * (c.height - 24)));
    ctx.strokeStyle = colors[i % 2];
    ctx.stroke();
    ctx.fillStyle = colors[i % 2];
    ctx.fillText(view.episodes[i].name, 4 + 110 * i, 10);
  });
  ctx.fillStyle = "#444";
  ctx.fillText(`max ${top} per ${bin}`, c.width - 80, 10);
  const x = (view.time / (T + 1)) * c.width;
  ctx.fillStyle = "rgba(0,0,0,0.6)";
  ctx.fillRect(x, 0, 1, c.height);
}

function showInfo() {
  const m = view.selected;
  if (m < 0) { el("info").textContent = view.message || "Click a robot, or find one by id."; return; }
  const lines = [`robot ${m}`];
  for (const ep of view.episodes) {
    const k = ep.task[m], t = ep.at;
    const [x, y] = [ep.pos[2 * m], ep.pos[2 * m + 1]];
    lines.push(`${ep.name}: (${x}, ${y}) ${STATE_NAMES[ep.state[m]]}`);
    if (k >= 0) {
      const f = (i) => ep.field(k, i);
      lines.push(`  task ${k}: (${f(0)}, ${f(1)}) -> (${f(2)}, ${f(3)})`);
      lines.push(`  arrived ${f(5)}, assigned ${f(6)}, pickup ${f(7)}, delivered ${f(8)}`);
      lines.push(`  waits in this task so far: ${ep.waits(m, f(6), Math.min(t, f(8)))}`);
    }
    let done = 0;
    for (let j = ep.robotFirst[m]; j < ep.robotFirst[m + 1]; j++) if (ep.field(ep.byRobot[j], 8) <= t) done++;
    lines.push(`  tasks delivered: ${done}, waits so far: ${ep.waits(m, 0, t)}`);
  }
  el("info").textContent = lines.join("\n");
}

// ----------------------------------------------------------------------------- control
function setTime(t) {
  const T = view.T;
  view.time = Math.max(0, Math.min(T, t));
  if (view.time >= T) view.playing = false;
}

function tick(now) {
  const dt = view.lastTick ? Math.min(0.25, (now - view.lastTick) / 1000) : 0;
  view.lastTick = now;
  if (view.playing) setTime(view.time + dt * view.speed);
  render();
  requestAnimationFrame(tick);
}

function render() {
  const start = performance.now();
  const t = Math.floor(view.time), frac = view.playing ? view.time - t : 0;
  for (const p of view.panels) p.ep.seek(Math.min(t, p.ep.T));
  for (const p of view.panels) {
    const bins = p.ep.congestion.length / (view.W * view.H);
    const bin = Math.min(Math.floor(t / p.ep.binSize), bins - 1);
    if (bin !== p.heatBin) { p.heatBin = bin; updateHeat(p, bin); }
  }
  const b = view.episodes[0].binSize, hb = view.panels[0].heatBin;
  el("heat-range").textContent = `${hb * b}-${(hb + 1) * b - 1}`;
  if (view.follow && view.selected >= 0) {
    const p = view.panels[0], [x, y] = drawnXY(p.ep, view.selected, frac), r = p.canvas.getBoundingClientRect();
    view.offX = r.width / 2 - (x + 0.5) * view.scale;
    view.offY = r.height / 2 - (y + 0.5) * view.scale;
  }
  for (const p of view.panels) drawPanel(p, frac);
  el("timeline").value = String(t);
  el("clock").textContent = `t = ${t} / ${view.T}` + (view.playing ? " (playing)" : "");
  el("play").textContent = view.playing ? "❚❚" : "▶";
  drawThroughput();
  if (view.frames % 10 === 0 || !view.playing) showInfo();
  view.frames++;
  view.drawMs += performance.now() - start;
}

function pick(panel, clientX, clientY) {
  const r = panel.canvas.getBoundingClientRect();
  const cx = (clientX - r.left - view.offX) / view.scale, cy = (clientY - r.top - view.offY) / view.scale;
  const ep = panel.ep, frac = view.playing ? view.time - Math.floor(view.time) : 0;
  let best = -1, bestD = 0.75 * 0.75;
  for (let m = 0; m < ep.M; m++) {
    const [x, y] = drawnXY(ep, m, frac);
    const d = (x + 0.5 - cx) ** 2 + (y + 0.5 - cy) ** 2;
    if (d < bestD) { bestD = d; best = m; }
  }
  select(best, panel.index);
}

function select(m, panelIndex) {
  view.selected = m;
  view.selectedPanel = panelIndex || 0;
  view.message = "";
  showInfo();
}

function attachMouse(panel) {
  let drag = null;
  panel.canvas.addEventListener("mousedown", (e) => { drag = { x: e.clientX, y: e.clientY, moved: false }; });
  window.addEventListener("mousemove", (e) => {
    if (!drag) return;
    const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
    if (drag.moved || Math.abs(dx) + Math.abs(dy) > 4) {
      drag.moved = true;
      view.offX += dx; view.offY += dy;
      drag.x = e.clientX; drag.y = e.clientY;
      view.follow = false; el("follow").checked = false;
    }
  });
  window.addEventListener("mouseup", (e) => {
    if (drag && !drag.moved && e.target === panel.canvas) pick(panel, e.clientX, e.clientY);
    drag = null;
  });
  panel.canvas.addEventListener("wheel", (e) => {
    e.preventDefault();
    const r = panel.canvas.getBoundingClientRect(), px = e.clientX - r.left, py = e.clientY - r.top;
    zoomAt(px, py, Math.exp(-e.deltaY * 0.0015));
  }, { passive: false });
}

function zoomAt(px, py, factor) {
  const s = Math.max(0.05, Math.min(80, view.scale * factor));
  view.offX = px - ((px - view.offX) * s) / view.scale;
  view.offY = py - ((py - view.offY) * s) / view.scale;
  view.scale = s;
}

// "12" or "r12": robot 12; "t34": the robot serving task 34, at the task's assignment.
function search(text) {
  const q = String(text).trim().toLowerCase().replace(/^(robot|task)\s*/, (w) => (w[0] === "t" ? "t" : "r"));
  const match = /^([rt]?)\s*(\d+)$/.exec(q);
  const ep = view.episodes[0];
  if (!match) { view.selected = -1; view.message = `not understood: "${text}" (try 12, r12 or t34)`; showInfo(); return false; }
  const id = Number(match[2]);
  if (match[1] === "t") {
    if (id >= ep.K) { view.selected = -1; view.message = `no task ${id} in ${ep.name} (tasks 0-${ep.K - 1})`; showInfo(); return false; }
    const a = ep.field(id, 6), b = ep.field(id, 8);
    if (view.time < a || view.time >= b) { view.playing = false; setTime(a); }
    select(ep.field(id, 4), 0);
  } else {
    if (id >= ep.M) { view.selected = -1; view.message = `no robot ${id} (robots 0-${ep.M - 1})`; showInfo(); return false; }
    select(id, 0);
  }
  view.follow = true;
  el("follow").checked = true;
  if (view.scale < 8) { const r = view.panels[0].canvas.getBoundingClientRect(); zoomAt(r.width / 2, r.height / 2, 8 / view.scale); }
  return true;
}

function legend() {
  const items = STATE_NAMES.map((n, i) => [n, STATE_COLORS[i]]);
  items.push(["queued task (zoomed in)", "#ffffff"], ["obstacle", "rgb(58,63,75)"], ["pickup station", "rgb(204,236,204)"], ["delivery station", "rgb(252,222,190)"], ["congestion", "rgb(220,20,20)"]);
  el("legend").innerHTML = items.map(([n, c]) => `<span class="item"><span class="swatch" style="background:${c}"></span>${n}</span>`).join("");
}

function controls() {
  el("play").onclick = () => { if (view.time >= view.T) setTime(0); view.playing = !view.playing; };
  el("back").onclick = () => { view.playing = false; setTime(Math.floor(view.time) - 1); };
  el("fwd").onclick = () => { view.playing = false; setTime(Math.floor(view.time) + 1); };
  el("speed").onchange = (e) => { view.speed = Number(e.target.value); };
  el("timeline").max = String(view.T);
  el("timeline").oninput = (e) => { view.playing = false; setTime(Number(e.target.value)); };
  el("go").onclick = () => search(el("search").value);
  el("search").onkeydown = (e) => { if (e.key === "Enter") search(el("search").value); e.stopPropagation(); };
  el("follow").onchange = (e) => { view.follow = e.target.checked; };
  el("heat").onchange = (e) => { view.heat = e.target.checked; };
  el("fit").onclick = fit;
  el("throughput").onclick = (e) => {
    const r = e.target.getBoundingClientRect();
    view.playing = false;
    setTime(Math.round(((e.clientX - r.left) / r.width) * view.T));
  };
  window.addEventListener("keydown", (e) => {
    if (e.key === " ") { e.preventDefault(); el("play").onclick(); }
    else if (e.key === "ArrowLeft") el("back").onclick();
    else if (e.key === "ArrowRight") el("fwd").onclick();
    else if (e.key === "+" || e.key === "=") zoomAt(200, 200, 1.25);
    else if (e.key === "-") zoomAt(200, 200, 0.8);
    else if (e.key === "f") { view.follow = !view.follow; el("follow").checked = view.follow; }
    else if (e.key === "Escape") select(-1, 0);
  });
  window.addEventListener("resize", resize);
}

async function main() {
  const data = JSON.parse(el("rtaw-data").textContent);
  view.W = data.width; view.H = data.height;
  el("title").textContent = data.title;
  view.cells = await decode(data.cells);
  view.map = mapCanvas(view.cells);
  view.mapPixels = new Uint32Array(view.map.getContext("2d").getImageData(0, 0, view.W, view.H).data.buffer);
  for (const meta of data.episodes) {
    const arrays = {};
    for (const key of ["start", "moves", "tasks", "congestion", "delivered"]) arrays[key] = await decode(meta[key]);
    view.episodes.push(new Episode(meta, arrays));
  }
  view.T = Math.max(...view.episodes.map((e) => e.T));
  view.panels = view.episodes.map(makePanel);
  legend();
  controls();
  resize();
  fit();
  el("loading").remove();
  view.ready = true;
  requestAnimationFrame(tick);
}

// For tests and benchmarks (and the curious, from the console).
window.rtawView = {
  get ready() { return Boolean(view.ready); },
  state: () => ({ time: view.time, t: Math.floor(view.time), playing: view.playing, speed: view.speed,
    selected: view.selected, follow: view.follow, scale: view.scale, offX: view.offX, offY: view.offY,
    steps: view.T, robots: view.episodes.map((e) => e.M), info: el("info").textContent }),
  stats: () => ({ frames: view.frames, drawMs: view.drawMs }),
  play: () => { view.playing = true; },
  pause: () => { view.playing = false; },
  seek: (t) => { view.playing = false; setTime(t); render(); },
  setSpeed: (v) => { view.speed = v; },
  setCamera: (scale, offX, offY) => { view.scale = scale; view.offX = offX; view.offY = offY; view.follow = false; render(); },
  search,
  cellToClient: (panel, x, y) => {
    const r = view.panels[panel].canvas.getBoundingClientRect();
    return [r.left + view.offX + (x + 0.5) * view.scale, r.top + view.offY + (y + 0.5) * view.scale];
  },
  cells: () => view.cells,
  colors: { states: STATE_COLORS, cells: CELL_COLORS },
};

main().catch((e) => { window.rtawErrors.push(String(e && e.stack || e)); el("loading").textContent = "error: " + e; });
