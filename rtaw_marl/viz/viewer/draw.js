// rtaw-view's page, 2/4: the view's state, the panels' layout and the drawing of maps
// and robots (the congestion and the charts are in heat.js).
const STATE_NAMES = ["idle", "to pickup", "carrying"];
const QUEUED_COLOR = "#5a5a5a";
const HEADING_COLOR = "rgba(255,255,255,0.9)";
const STATE_COLORS = ["#8c8c8c", "#1f6fd1", "#e8710a"];
const CELL_COLORS = [[242, 242, 242], [58, 63, 75], [204, 236, 204], [252, 222, 190]];
// Below this many pixels per cell, robots are drawn as pixels of a grid-sized image.
const PIXEL_MODE = 4;
const rgba32 = (hex) => { const v = parseInt(hex.slice(1), 16); return (0xff << 24 | (v & 0xff) << 16 | (v & 0xff00) | (v >> 16)) >>> 0; };
const STATE_PIXELS = Uint32Array.from(STATE_COLORS, rgba32);

// One camera (scale, offX, offY) for all panels; following, each panel centres its own
// selected robot (a task found by id has a different robot in each episode).
const view = {
  episodes: [], panels: [], W: 0, H: 0, time: 0, playing: false, speed: 10,
  scale: 1, offX: 0, offY: 0, task: -1, follow: false, overlay: "none", atFit: true,
  stacked: false, frames: 0, drawMs: 0, lastTick: 0, message: "",
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
  const mini = document.createElement("canvas");
  mini.title = ep.name;
  el("heatmaps").append(mini);
  const panel = { ep, index, div, canvas, label, mini, sel: -1, offX: 0, offY: 0, heatKey: "", miniBin: -1,
    heat: document.createElement("canvas"), ctx: canvas.getContext("2d") };
  attachMouse(panel);
  return panel;
}

// Panels side by side or stacked, whichever gives the map the larger cells.
function layoutPanels() {
  const box = el("panels"), n = view.panels.length;
  box.classList.remove("stacked");
  const r = box.getBoundingClientRect();
  const side = Math.min(r.width / n / view.W, r.height / view.H);
  const stack = Math.min(r.width / view.W, r.height / n / view.H);
  view.stacked = n > 1 && stack > side;
  box.classList.toggle("stacked", view.stacked);
}

function fit() {
  const r = view.panels[0].canvas.getBoundingClientRect();
  view.scale = Math.max(0.05, Math.min(r.width / view.W, r.height / view.H));
  view.offX = (r.width - view.W * view.scale) / 2;
  view.offY = (r.height - view.H * view.scale) / 2;
  view.follow = false;
  view.atFit = true;
  el("follow").checked = false;
}

function resize() {
  layoutPanels();
  const dpr = window.devicePixelRatio || 1;
  for (const p of view.panels) {
    const r = p.canvas.getBoundingClientRect();
    p.canvas.width = Math.max(1, Math.round(r.width * dpr));
    p.canvas.height = Math.max(1, Math.round(r.height * dpr));
  }
  if (view.atFit) fit();
}

// The robot's drawn position at fractional time: its cell at t moved by frac of its move.
function drawnXY(ep, m, frac) {
  const c = ep.moveAt(m, ep.at);
  return [ep.pos[2 * m] + DX[c] * frac, ep.pos[2 * m + 1] + DY[c] * frac];
}

function drawPanel(panel, frac) {
  const ep = panel.ep, ctx = panel.ctx, dpr = window.devicePixelRatio || 1;
  const s = view.scale;
  ctx.setTransform(1, 0, 0, 1, 0, 0);
  ctx.fillStyle = "#ffffff";
  ctx.fillRect(0, 0, panel.canvas.width, panel.canvas.height);
  ctx.setTransform(dpr * s, 0, 0, dpr * s, dpr * panel.offX, dpr * panel.offY);
  ctx.imageSmoothingEnabled = false;
  if (s < PIXEL_MODE) drawRobotPixels(panel, frac);
  else drawRobotRects(panel, frac);
  if (view.overlay !== "none") drawOverlay(panel);
  if (panel.sel >= 0 && panel.sel < ep.M) drawSelected(panel, frac);
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

// The cells in view: [x0, y0, x1, y1], a cell of margin.
function inView(panel) {
  const s = view.scale, dpr = window.devicePixelRatio || 1;
  const x0 = -panel.offX / s - 1, y0 = -panel.offY / s - 1;
  return [x0, y0, x0 + panel.canvas.width / dpr / s + 2, y0 + panel.canvas.height / dpr / s + 2];
}

// Zoomed in: the map, then robots in view as rectangles that glide between cells, one
// path per state colour, and their headings when they turn. Robots in view are found
// once per frame (their index and drawn cell), then drawn from that list.
function drawRobotRects(panel, frac) {
  const ep = panel.ep, ctx = panel.ctx;
  ctx.drawImage(view.map, 0, 0);
  const [x0, y0, x1, y1] = inView(panel);
  drawQueued(panel, x0, y0, x1, y1);
  if (!panel.vis) { panel.vis = new Int32Array(ep.M); panel.vxy = new Float32Array(2 * ep.M); }
  const vis = panel.vis, vxy = panel.vxy;
  let n = 0;
  for (let m = 0; m < ep.M; m++) {
    const [x, y] = drawnXY(ep, m, frac);
    if (x < x0 || x > x1 || y < y0 || y > y1) continue;
    vis[n] = m; vxy[2 * n] = x; vxy[2 * n + 1] = y; n++;
  }
  const pad = 0.12;
  for (let st = 0; st < 3; st++) {
    ctx.beginPath();
    for (let i = 0; i < n; i++) if (ep.state[vis[i]] === st) ctx.rect(vxy[2 * i] + pad, vxy[2 * i + 1] + pad, 1 - 2 * pad, 1 - 2 * pad);
    ctx.fillStyle = STATE_COLORS[st];
    ctx.fill();
  }
  if (ep.head) drawHeadings(panel, frac, n);
}

// A robot's heading (0 east, 1 south, 2 west, 3 north): a light bar on the side of its
// square it faces, where a forward move takes it; a turning robot faces its new way
// from half the timestep. Bars are rectangles: one fast path, as the robots' squares.
const TICK_X = [0.6, 0.3, 0.2, 0.3], TICK_Y = [0.3, 0.6, 0.3, 0.2], TICK_W = [0.2, 0.4, 0.2, 0.4], TICK_H = [0.4, 0.2, 0.4, 0.2];
function drawHeadings(panel, frac, n) {
  const ep = panel.ep, ctx = panel.ctx, vis = panel.vis, vxy = panel.vxy, half = frac >= 0.5;
  ctx.beginPath();
  for (let i = 0; i < n; i++) {
    const m = vis[i], h = half ? (ep.head[m] + ep.turnAt(m, ep.at)) & 3 : ep.head[m];
    ctx.rect(vxy[2 * i] + TICK_X[h], vxy[2 * i + 1] + TICK_Y[h], TICK_W[h], TICK_H[h]);
  }
  ctx.fillStyle = HEADING_COLOR;
  ctx.fill();
}

// Tasks waiting in the queue at t (arrived, not yet assigned): hollow squares at their
// pickups. Tasks are sorted by assignment time, so the search starts past t's.
function drawQueued(panel, x0, y0, x1, y1) {
  const ep = panel.ep, tk = ep.tasks, t = ep.at;
  let lo = 0, hi = ep.K;
  while (lo < hi) { const mid = (lo + hi) >> 1; if (tk[TC * mid + 6] <= t) lo = mid + 1; else hi = mid; }
  const ctx = panel.ctx;
  ctx.beginPath();
  for (let k = lo; k < ep.K; k++) {
    if (tk[TC * k + 5] > t) continue;
    const x = tk[TC * k], y = tk[TC * k + 1];
    if (x < x0 || x > x1 || y < y0 || y > y1) continue;
    ctx.rect(x + 0.3, y + 0.3, 0.4, 0.4);
  }
  ctx.strokeStyle = QUEUED_COLOR;
  ctx.lineWidth = Math.max(0.08, 1 / view.scale);
  ctx.stroke();
}

// The task shown with a selected robot: the task found by id, else the robot's own.
function shownTask(panel) {
  return view.task >= 0 ? panel.ep.row(view.task) : panel.ep.task[panel.sel];
}

function drawSelected(panel, frac) {
  const ep = panel.ep, ctx = panel.ctx, m = panel.sel, s = view.scale;
  const lw = Math.max(0.12, 2 / s);
  const k = shownTask(panel);
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

function taskLines(ep, k, m, t) {
  const f = (i) => ep.field(k, i);
  const lines = [`  task ${f(9)}: (${f(0)}, ${f(1)}) -> (${f(2)}, ${f(3)})` + (f(4) === m ? "" : ` (robot ${f(4)})`)];
  lines.push(`  arrived ${f(5)}, assigned ${f(6)}, pickup ${f(7)}, delivered ${f(8)}`);
  if (f(4) === m && t >= f(6)) lines.push(`  waits in this task so far: ${ep.waits(m, f(6), Math.min(t, f(8)))}`);
  return lines;
}

function showInfo() {
  if (view.panels.every((p) => p.sel < 0)) { el("info").textContent = view.message || "Click a robot, or find one by id."; return; }
  const lines = view.task >= 0 ? [`task ${view.task}`] : [`robot ${view.panels[0].sel}`];
  for (const p of view.panels) {
    const ep = p.ep, m = p.sel, t = ep.at;
    if (m < 0) { lines.push(`${ep.name}: task ${view.task} not assigned in this episode`); continue; }
    lines.push(`${ep.name}: robot ${m} (${ep.pos[2 * m]}, ${ep.pos[2 * m + 1]}) ${STATE_NAMES[ep.state[m]]}`);
    const k = shownTask(p);
    if (k >= 0) lines.push(...taskLines(ep, k, m, t));
    let done = 0;
    for (let j = ep.robotFirst[m]; j < ep.robotFirst[m + 1]; j++) if (ep.field(ep.byRobot[j], 8) <= t) done++;
    lines.push(`  tasks delivered: ${done}, waits so far: ${ep.waits(m, 0, t)}`);
  }
  el("info").textContent = lines.join("\n");
}
