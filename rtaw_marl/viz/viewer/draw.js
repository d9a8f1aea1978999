// rtaw-view's page, 2/3: the view's state and the drawing (maps, robots, heat, charts).
const STATE_NAMES = ["idle", "to pickup", "carrying"];
const QUEUED_COLOR = "#5a5a5a";
const STATE_COLORS = ["#8c8c8c", "#1f6fd1", "#e8710a"];
const CELL_COLORS = [[242, 242, 242], [58, 63, 75], [204, 236, 204], [252, 222, 190]];
// Below this many pixels per cell, robots are drawn as pixels of a grid-sized image.
const PIXEL_MODE = 4;
const rgba32 = (hex) => { const v = parseInt(hex.slice(1), 16); return (0xff << 24 | (v & 0xff) << 16 | (v & 0xff00) | (v >> 16)) >>> 0; };
const STATE_PIXELS = Uint32Array.from(STATE_COLORS, rgba32);

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
