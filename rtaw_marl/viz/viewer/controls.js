// rtaw-view's page, 3/3: the clock, the controls, search, loading, the test API.
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
  el("summary").textContent = view.episodes
    .map((e) => `${e.name}: ` + Object.entries(e.summary).map(([k, v]) => `${k} ${v}`).join(", "))
    .join("\n");
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
  setCamera: (scale, offX, offY) => {
    Object.assign(view, { scale, offX, offY, follow: false });
    el("follow").checked = false;
    render();
  },
  search,
  cellToClient: (panel, x, y) => {
    const r = view.panels[panel].canvas.getBoundingClientRect();
    return [r.left + view.offX + (x + 0.5) * view.scale, r.top + view.offY + (y + 0.5) * view.scale];
  },
  cells: () => view.cells,
  colors: { states: STATE_COLORS, cells: CELL_COLORS },
};

main().catch((e) => { window.rtawErrors.push(String(e && e.stack || e)); el("loading").textContent = "error: " + e; });
