// rtaw-view's page, 4/4: the clock, the controls, search, loading, the test API.
function setTime(t) {
  const T = view.T;
  view.time = Math.max(0, Math.min(T, t));
  if (view.time >= T) view.playing = false;
}

// The throughput chart's window: about a fiftieth of the episode, at least one timestep.
function defaultWindow(T) { return Math.max(1, Math.round(T / 50)); }

function setWindow(w) {
  view.tpWindow = Math.max(1, Math.min(Math.max(1, view.T), Math.round(Number(w)) || 1));
  el("tp-window").value = String(view.tpWindow);
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
  for (const p of view.panels) updateMini(p, binOf(p.ep, Math.min(t, p.ep.T)));
  const b = view.episodes[0].binSize, hb = view.panels[0].miniBin;
  el("heat-range").textContent = `${hb * b}-${(hb + 1) * b - 1}`;
  placeCameras(frac);
  for (const p of view.panels) drawPanel(p, frac);
  el("timeline").value = String(t);
  el("clock").textContent = `t = ${t} / ${view.T}` + (view.playing ? " (playing)" : "");
  el("play").textContent = view.playing ? "❚❚" : "▶";
  drawThroughput();
  if (view.frames % 10 === 0 || !view.playing) showInfo();
  view.frames++;
  view.drawMs += performance.now() - start;
}

// The shared camera, or, following, each panel centred on its selected robot (the
// shared camera then follows the first panel that has one).
function placeCameras(frac) {
  let lead = true;
  for (const p of view.panels) {
    p.offX = view.offX; p.offY = view.offY;
    if (!view.follow || p.sel < 0) continue;
    const [x, y] = drawnXY(p.ep, p.sel, frac), r = p.canvas.getBoundingClientRect();
    p.offX = r.width / 2 - (x + 0.5) * view.scale;
    p.offY = r.height / 2 - (y + 0.5) * view.scale;
    if (lead) { view.offX = p.offX; view.offY = p.offY; lead = false; }
  }
}

function pick(panel, clientX, clientY) {
  const r = panel.canvas.getBoundingClientRect();
  const cx = (clientX - r.left - panel.offX) / view.scale, cy = (clientY - r.top - panel.offY) / view.scale;
  const ep = panel.ep, frac = view.playing ? view.time - Math.floor(view.time) : 0;
  let best = -1, bestD = 0.75 * 0.75;
  for (let m = 0; m < ep.M; m++) {
    const [x, y] = drawnXY(ep, m, frac);
    const d = (x + 0.5 - cx) ** 2 + (y + 0.5 - cy) ** 2;
    if (d < bestD) { bestD = d; best = m; }
  }
  select(best);
}

// Robot m in every panel (the same robot of the same fleet), or none (-1).
function select(m) {
  for (const p of view.panels) p.sel = m;
  view.task = -1;
  view.message = "";
  showInfo();
}

function unfollow() { view.follow = false; view.atFit = false; el("follow").checked = false; }

function attachMouse(panel) {
  let drag = null;
  panel.canvas.addEventListener("mousedown", (e) => { drag = { x: e.clientX, y: e.clientY, moved: false }; });
  window.addEventListener("mousemove", (e) => {
    if (!drag) return;
    const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
    if (drag.moved || Math.abs(dx) + Math.abs(dy) > 4) {
      drag.moved = true;
      view.offX = panel.offX + dx; view.offY = panel.offY + dy;
      for (const p of view.panels) { p.offX = view.offX; p.offY = view.offY; }
      drag.x = e.clientX; drag.y = e.clientY;
      unfollow();
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
  view.atFit = false;
}

function refuse(message) { select(-1); view.message = message; showInfo(); return false; }

// "12" or "r12": robot 12; "t34": task 34 of the task stream (the same task in both
// episodes): in each panel the robot serving it, at its assignment in the first episode
// that has it if the clock is outside it there.
function search(text) {
  const q = String(text).trim().toLowerCase().replace(/^(robot|task)\s*/, (w) => (w[0] === "t" ? "t" : "r"));
  const match = /^([rt]?)\s*(\d+)$/.exec(q);
  if (!match) return refuse(`not understood: "${text}" (try 12, r12 or t34)`);
  const id = Number(match[2]), M = view.episodes[0].M;
  if (match[1] === "t") {
    const rows = view.panels.map((p) => p.ep.row(id)), first = rows.findIndex((k) => k >= 0);
    if (first < 0) return refuse(`no task ${id} was assigned in ${view.episodes.map((e) => e.name).join(" or ")}`);
    const ep = view.panels[first].ep, a = ep.field(rows[first], 6), b = ep.field(rows[first], 8);
    if (view.time < a || view.time >= b) { view.playing = false; setTime(a); }
    select(-1);
    view.panels.forEach((p, i) => { p.sel = rows[i] >= 0 ? p.ep.field(rows[i], 4) : -1; });
    view.task = id;
  } else {
    if (id >= M) return refuse(`no robot ${id} (robots 0-${M - 1})`);
    select(id);
  }
  view.follow = true;
  el("follow").checked = true;
  if (view.scale < 8) { const r = view.panels[0].canvas.getBoundingClientRect(); zoomAt(r.width / 2, r.height / 2, 8 / view.scale); }
  showInfo();
  return true;
}

function legend() {
  const items = STATE_NAMES.map((n, i) => [n, STATE_COLORS[i]]);
  items.push(["queued task (zoomed in)", "#ffffff"], ["obstacle", "rgb(58,63,75)"], ["pickup station", "rgb(204,236,204)"], ["delivery station", "rgb(252,222,190)"], ["congestion", "rgb(220,20,20)"]);
  if (view.episodes.length > 1) items.push([`A − B: more congested in ${view.episodes[1].name}`, "rgb(20,90,220)"]);
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
  el("follow").onchange = (e) => { view.follow = e.target.checked; view.atFit = false; };
  el("overlay").onchange = (e) => { view.overlay = e.target.value; };
  if (view.panels.length < 2) el("overlay").querySelector("option[value=diff]").remove();
  else el("overlay").querySelector("option[value=diff]").textContent = `${view.episodes[0].name} − ${view.episodes[1].name}`;
  el("tp-window").max = String(Math.max(1, view.T));
  el("tp-window").value = String(view.tpWindow);
  el("tp-window").onchange = (e) => { setWindow(Number(e.target.value)); };
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
    else if (e.key === "f") { view.follow = !view.follow; el("follow").checked = view.follow; view.atFit = false; }
    else if (e.key === "Escape") select(-1);
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
    for (const key of ["start", "moves", "tasks", "congestion", "delivered", "headings", "turns"]) {
      if (meta[key]) arrays[key] = await decode(meta[key]);
    }
    view.episodes.push(new Episode(meta, arrays));
  }
  view.T = Math.max(...view.episodes.map((e) => e.T));
  view.tpWindow = defaultWindow(view.T);
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
    selected: view.panels[0].sel, selectedRobots: view.panels.map((p) => p.sel), task: view.task,
    follow: view.follow, scale: view.scale, offX: view.offX, offY: view.offY, stacked: view.stacked,
    overlay: view.overlay, heatBlock: view.panels.map((p) => p.heatBlock || 1), tpWindow: view.tpWindow,
    steps: view.T, robots: view.episodes.map((e) => e.M), info: el("info").textContent }),
  setOverlay: (mode) => { view.overlay = mode; el("overlay").value = mode; render(); },
  setWindow: (w) => { setWindow(w); render(); },
  throughput: () => view.throughput.series.map((s) => Array.from(s)),
  fit: () => { fit(); render(); },
  stats: () => ({ frames: view.frames, drawMs: view.drawMs }),
  play: () => { view.playing = true; },
  pause: () => { view.playing = false; },
  seek: (t) => { view.playing = false; setTime(t); render(); },
  setSpeed: (v) => { view.speed = v; },
  setCamera: (scale, offX, offY) => {
    Object.assign(view, { scale, offX, offY });
    unfollow();
    render();
  },
  search: (text) => { const found = search(text); render(); return found; },
  cellToClient: (panel, x, y) => {
    const p = view.panels[panel], r = p.canvas.getBoundingClientRect();
    return [r.left + p.offX + (x + 0.5) * view.scale, r.top + p.offY + (y + 0.5) * view.scale];
  },
  cells: () => view.cells,
  colors: { states: STATE_COLORS, cells: CELL_COLORS },
};

main().catch((e) => { window.rtawErrors.push(String(e && e.stack || e)); el("loading").textContent = "error: " + e; });
