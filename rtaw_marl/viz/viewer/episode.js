// rtaw-view's page, 1/4: the episodes' data (rtaw_marl.viz.episode_data). Positions (and
// headings, when robots turn) are rebuilt from move codes: a keyframe every KEY timesteps
// is computed on load, so any timestep is at most KEY - 1 moves per robot from one.
"use strict";
window.rtawErrors = [];
window.addEventListener("error", (e) => window.rtawErrors.push(String(e.message)));
window.addEventListener("unhandledrejection", (e) => window.rtawErrors.push(String(e.reason)));

const KEY = 64;
const DX = [0, 1, -1, 0, 0];
const DY = [0, 0, 0, 1, -1];
const IDLE = 0, TO_PICKUP = 1, CARRYING = 2;
// A task row: ox, oy, dx, dy, robot, arrival, assigned, pickup, delivered, stream id.
const TC = 10;
const TYPES = { uint8: Uint8Array, uint16: Uint16Array, uint32: Uint32Array, int32: Int32Array };

async function decode(a) {
  const text = atob(a.data);
  const bytes = new Uint8Array(text.length);
  for (let i = 0; i < text.length; i++) bytes[i] = text.charCodeAt(i);
  const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("deflate"));
  return new TYPES[a.dtype](await new Response(stream).arrayBuffer());
}

// One episode: positions (and headings) at any timestep, robot states, tasks by robot and
// by id. Moves come robot by robot: robot m's move from s to s + 1 is moves[m * T + s];
// turns likewise (0 none, 1 clockwise, 3 counter-clockwise), when robots turn.
class Episode {
  constructor(meta, arrays) {
    this.name = meta.name;
    this.summary = meta.summary;
    this.M = meta.robots;
    this.T = meta.steps;
    this.binSize = meta.bin_size;
    Object.assign(this, arrays);
    this.K = this.tasks.length / TC;
    this.buildKeyframes();
    if (this.turns) this.buildHeadingKeys();
    this.indexTasks();
    this.pos = new Int16Array(2 * this.M);
    this.head = this.turns ? new Uint8Array(this.M) : null;
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
  buildHeadingKeys() {
    const M = this.M, T = this.T, head = this.headings.slice();
    this.hkeys = [];
    for (let t = 0; t <= T; t++) {
      if (t % KEY === 0) this.hkeys.push(head.slice());
      if (t === T) break;
      for (let m = 0; m < M; m++) head[m] = (head[m] + this.turns[m * T + t]) & 3;
    }
  }
  indexTasks() {
    const M = this.M, K = this.K, tk = this.tasks;
    this.robotFirst = new Int32Array(M + 1);
    for (let k = 0; k < K; k++) this.robotFirst[tk[TC * k + 4] + 1]++;
    for (let m = 0; m < M; m++) this.robotFirst[m + 1] += this.robotFirst[m];
    const fill = this.robotFirst.slice(0, M);
    this.byRobot = new Int32Array(K);
    // Rows are in assignment order, so each robot's list comes out in time order.
    for (let k = 0; k < K; k++) this.byRobot[fill[tk[TC * k + 4]]++] = k;
    this.rowOfId = new Map();
    for (let k = 0; k < K; k++) this.rowOfId.set(tk[TC * k + 9], k);
  }
  field(k, i) { return this.tasks[TC * k + i]; }
  // The row of the task with stream id `id`, -1 if this episode never assigned it.
  row(id) { const k = this.rowOfId.get(id); return k === undefined ? -1 : k; }
  // Bring positions, states and tasks to integer timestep t.
  seek(t) {
    const M = this.M;
    if (t === this.at) return;
    if (t > this.at && this.at >= 0 && t - this.at < KEY) {
      for (let s = this.at; s < t; s++) this.applyRow(s);
    } else {
      const k = Math.floor(t / KEY);
      this.pos.set(this.keys[k]);
      if (this.head) this.head.set(this.hkeys[k]);
      for (let s = k * KEY; s < t; s++) this.applyRow(s);
    }
    this.at = t;
    const tk = this.tasks;
    for (let m = 0; m < M; m++) {
      let st = IDLE, cur = -1;
      for (let j = this.robotFirst[m]; j < this.robotFirst[m + 1]; j++) {
        const k = this.byRobot[j];
        if (tk[TC * k + 6] > t) break;
        if (t < tk[TC * k + 8]) { cur = k; st = t < tk[TC * k + 7] ? TO_PICKUP : CARRYING; break; }
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
    if (!this.head) return;
    const head = this.head, turns = this.turns;
    for (let m = 0; m < this.M; m++) head[m] = (head[m] + turns[m * T + s]) & 3;
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
  turnAt(m, t) { return t < this.T ? this.turns[m * this.T + t] : 0; }
}
