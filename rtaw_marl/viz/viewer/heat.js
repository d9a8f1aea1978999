// rtaw-view's page, 3/4: congestion (on the map, per cell or per block of cells, and the
// difference of two episodes), the congestion minimaps and the throughput chart.
// Blocks are aggregated once per change of time bin, block size or overlay, not per frame.
const HEAT_RGB = [220, 20, 20];
// The difference A - B: red where the first episode is more congested, blue the second.
const DIFF_RGB = [[220, 20, 20], [20, 90, 220]];
// A congestion block is at least this many screen pixels a side.
const BLOCK_PX = 3;
const MINI_WIDTH = 300;

// Cells a block side for `pixels` screen pixels a cell: 1 when a cell is big enough.
function blockSize(pixels) { return pixels >= BLOCK_PX ? 1 : Math.ceil(BLOCK_PX / pixels); }

function binOf(ep, t) {
  const bins = ep.congestion.length / (view.W * view.H);
  return Math.min(Math.floor(t / ep.binSize), bins - 1);
}

// Congestion of bin `bin` per block of k x k cells, 0..1: the most congested cell of the
// block, its waits over half the bin (saturating). [bw * bh] with bw = ceil(W / k).
function blockHeat(ep, bin, k) {
  const W = view.W, H = view.H, bw = Math.ceil(W / k), bh = Math.ceil(H / k);
  const counts = ep.congestion.subarray(bin * W * H, (bin + 1) * W * H);
  const out = new Float32Array(bw * bh), norm = 1 / Math.max(1, ep.binSize * 0.5);
  for (let y = 0; y < H; y++) {
    const row = ((y / k) | 0) * bw;
    for (let x = 0; x < W; x++) {
      const c = counts[y * W + x];
      if (c) { const b = row + ((x / k) | 0), v = Math.min(1, c * norm); if (v > out[b]) out[b] = v; }
    }
  }
  return { out, bw, bh, k };
}

// An image of `values` (-1..1 per block): alpha grows with |v|, colour by its sign.
function paint(canvas, { out, bw, bh }, colors) {
  canvas.width = bw; canvas.height = bh;
  const ctx = canvas.getContext("2d"), img = ctx.createImageData(bw, bh), d = img.data;
  for (let i = 0; i < out.length; i++) {
    const v = out[i];
    if (v === 0) continue;
    const rgb = colors[v > 0 ? 0 : 1], o = 4 * i;
    d[o] = rgb[0]; d[o + 1] = rgb[1]; d[o + 2] = rgb[2]; d[o + 3] = 40 + 200 * Math.abs(v);
  }
  ctx.putImageData(img, 0, 0);
}

// The overlay at the current bin and zoom: congestion, or the difference of the two
// episodes (the same on both panels), aggregated into blocks when cells are small.
function updateOverlay(panel) {
  const t = panel.ep.at, k = blockSize(view.scale), diff = view.overlay === "diff" && view.panels.length > 1;
  const bins = view.panels.map((p) => binOf(p.ep, Math.min(t, p.ep.T)));
  const key = `${view.overlay}:${k}:${diff ? bins.join(",") : bins[panel.index]}`;
  if (key === panel.heatKey) return;
  panel.heatKey = key;
  const mine = blockHeat(panel.ep, bins[panel.index], k);
  if (diff) {
    const [a, b] = view.panels.map((p, i) => (i === panel.index ? mine : blockHeat(p.ep, bins[i], k)));
    for (let i = 0; i < mine.out.length; i++) mine.out[i] = a.out[i] - b.out[i];
  }
  paint(panel.heat, mine, diff ? DIFF_RGB : [HEAT_RGB, HEAT_RGB]);
  panel.heatBlock = k;
}

function drawOverlay(panel) {
  updateOverlay(panel);
  const ctx = panel.ctx, k = panel.heatBlock;
  ctx.save();
  ctx.beginPath();
  ctx.rect(0, 0, view.W, view.H);
  ctx.clip();
  ctx.drawImage(panel.heat, 0, 0, panel.heat.width * k, panel.heat.height * k);
  ctx.restore();
}

// The minimap of a panel's congestion: blocks of >= BLOCK_PX pixels at MINI_WIDTH wide,
// over the map's colours (a block of obstacles only is an obstacle).
function updateMini(panel, bin) {
  if (bin === panel.miniBin) return;
  panel.miniBin = bin;
  const k = blockSize(MINI_WIDTH / view.W), heat = blockHeat(panel.ep, bin, k), { out, bw, bh } = heat;
  if (!view.blockFree || view.blockFree.k !== k) view.blockFree = blockFree(k, bw, bh);
  const c = panel.mini;
  c.width = bw; c.height = bh;
  const ctx = c.getContext("2d"), img = ctx.createImageData(bw, bh), d = img.data;
  for (let i = 0; i < out.length; i++) {
    const base = view.blockFree.free[i] ? CELL_COLORS[0] : CELL_COLORS[1], v = out[i], o = 4 * i;
    for (let j = 0; j < 3; j++) d[o + j] = Math.round(base[j] * (1 - v) + HEAT_RGB[j] * v);
    d[o + 3] = 255;
  }
  ctx.putImageData(img, 0, 0);
}

function blockFree(k, bw, bh) {
  const free = new Uint8Array(bw * bh);
  for (let y = 0; y < view.H; y++) {
    for (let x = 0; x < view.W; x++) if (view.cells[y * view.W + x] !== 1) free[((y / k) | 0) * bw + ((x / k) | 0)] = 1;
  }
  return { k, free };
}

// Tasks delivered per timestep, the mean over a window of `tpWindow` timesteps centred
// on each point, one point per pixel column of the chart: computed once per window.
function throughputSeries(width) {
  const T = view.T, w = view.tpWindow, half = w / 2;
  const series = view.episodes.map((ep) => {
    const out = new Float64Array(width), F = ep.finishedBefore;
    for (let x = 0; x < width; x++) {
      const t = (x / Math.max(1, width - 1)) * T;
      const lo = Math.max(0, Math.round(t - half)), hi = Math.min(ep.T + 1, Math.max(lo + 1, Math.round(t + half)));
      out[x] = lo < ep.T + 1 ? (F[hi] - F[lo]) / (hi - lo) : 0;
    }
    return out;
  });
  return { w, series, top: Math.max(1e-9, ...series.map((s) => Math.max(...s))) };
}

function drawThroughput() {
  const c = el("throughput"), ctx = c.getContext("2d"), T = view.T;
  if (!view.throughput || view.throughput.w !== view.tpWindow) view.throughput = throughputSeries(c.width);
  const { series, top } = view.throughput;
  ctx.clearRect(0, 0, c.width, c.height);
  ctx.font = "10px sans-serif";
  const colors = ["#1f6fd1", "#d0021b"];
  series.forEach((s, i) => {
    ctx.beginPath();
    s.forEach((v, j) => ctx[j ? "lineTo" : "moveTo"](j, c.height - 12 - (v / top) * (c.height - 24)));
    ctx.strokeStyle = colors[i % 2];
    ctx.stroke();
    ctx.fillStyle = colors[i % 2];
    ctx.fillText(view.episodes[i].name, 4 + 110 * i, 10);
  });
  ctx.fillStyle = "#444";
  const text = `max ${top.toFixed(top < 10 ? 2 : 1)}/timestep`;
  ctx.fillText(text, c.width - ctx.measureText(text).width - 4, 10);
  const x = (view.time / Math.max(1, T)) * (c.width - 1);
  ctx.fillStyle = "rgba(0,0,0,0.6)";
  ctx.fillRect(x, 0, 1, c.height);
}
