"use strict";
// hcomc replay, core: the runs' data as typed arrays and their state at a time t.
// Every frame reads typed arrays and writes preallocated ones (no per-vehicle objects).

const HC = {};

HC.TYPES = { f4: Float32Array, f8: Float64Array, i2: Int16Array, i1: Int8Array, i4: Int32Array };

// A base64 typed array of the page's data (see hcomc.viz.replay.pack).
HC.decode = function (enc) {
  const s = atob(enc.b64);
  const n = s.length;
  const bytes = new Uint8Array(n);
  for (let i = 0; i < n; i++) bytes[i] = s.charCodeAt(i);
  return new HC.TYPES[enc.dtype](bytes.buffer);
};

HC.Run = class {
  constructor(d, index) {
    const A = d.arrays;
    this.index = index;
    this.title = d.title;
    this.seed = d.seed;
    this.rows = d.rows;
    this.cols = d.columns;
    this.n = d.vehicles;
    this.road = d.road;
    this.plans = d.plans;
    this.roles = d.roles;
    this.commanded = d.commanded;
    this.events = d.events;
    this.merges = d.merges || null;  // a corridor run's merge events (its table)
    this.note = d.note || "";
    // a corridor run has no lateral motion: a lane change is a jump, never interpolated
    this.jumps = Boolean(d.lane_jumps);
    this.t = HC.decode(A.t);
    this.x = HC.decode(A.x);
    this.lane = HC.decode(A.lane);
    this.y = HC.decode(A.y); this.yStep = A.y.step;
    this.h = HC.decode(A.heading); this.hStep = A.heading.step;
    this.v = HC.decode(A.v); this.vStep = A.v.step;
    this.a = HC.decode(A.a); this.aStep = A.a.step;
    // where a vehicle is drawn minus its x (a corridor's sloping ramp roads), or none
    this.shift = A.dx ? HC.decode(A.dx) : null; this.shiftStep = A.dx ? A.dx.step : 0;
    this.kind = HC.decode(A.kind);
    this.length = HC.decode(A.length);
    this.width = HC.decode(A.width);
    this.column = HC.decode(A.column);
    this.first = HC.decode(A.first);
    this.last = HC.decode(A.last);
    // which vehicle each (row, column) cell holds
    this.owner = new Int32Array(this.rows * this.cols).fill(-1);
    for (let i = 0; i < this.n; i++) {
      const c = this.column[i];
      if (c < 0) continue;
      for (let r = this.first[i]; r <= this.last[i]; r++) this.owner[r * this.cols + c] = i;
    }
    this.t0 = this.t[0];
    this.t1 = this.t[this.rows - 1];
    // the frame: row, fraction to the next row, and each column's drawn vehicle
    this.row = 0;
    this.frac = 0;
    this.inside = false;
    this.did = new Int32Array(this.cols).fill(-1);
    this.dx = new Float64Array(this.cols);
    this.dy = new Float64Array(this.cols);
    this.dh = new Float64Array(this.cols);
    this.roleOf = new Int8Array(this.n).fill(-1);
    this.rolePlan = new Int32Array(this.n).fill(-1);  // the plan the role is from, -1: key group
    this.roleVR = new Int32Array(this.n).fill(-1);  // whose key vehicle (where roles name it)
    this.cmdOf = new Int32Array(this.n).fill(-1);
    this.live = [];  // indices of the plans live at the frame's time
  }

  // Row k with t[k] <= t < t[k + 1] and the fraction of the way to row k + 1.
  locate(t) {
    const T = this.t;
    this.inside = t >= this.t0 - 1e-9 && t <= this.t1 + 1e-9;
    if (t <= this.t0) { this.row = 0; this.frac = 0; return; }
    if (t >= this.t1) { this.row = this.rows - 1; this.frac = 0; return; }
    let lo = 0, hi = this.rows - 1;
    while (hi - lo > 1) {
      const mid = (lo + hi) >> 1;
      if (T[mid] <= t) lo = mid; else hi = mid;
    }
    this.row = lo;
    const f = (t - T[lo]) / (T[lo + 1] - T[lo]);
    this.frac = f < 1e-9 ? 0 : f;
  }

  // Where the cell at idx is drawn along x: its x, shifted where the road slopes.
  drawnX(idx) { return this.shift ? this.x[idx] + this.shift[idx] * this.shiftStep : this.x[idx]; }

  // Positions of every vehicle at time t (interpolated between rows, but not across a lane
  // change of a run whose lane changes are jumps), roles, commands, plans.
  frame(t) {
    this.locate(t);
    const C = this.cols, base = this.row * C, next = base + C;
    const f = this.frac, interp = f > 0 && this.row + 1 < this.rows;
    for (let c = 0; c < C; c++) {
      const i = this.inside ? this.owner[base + c] : -1;
      const x0 = i >= 0 ? this.x[base + c] : NaN;
      if (i < 0 || x0 !== x0) { this.did[c] = -1; continue; }
      let x = this.drawnX(base + c), y = this.y[base + c] * this.yStep, h = this.h[base + c] * this.hStep;
      if (interp && this.owner[next + c] === i && this.x[next + c] === this.x[next + c]) {
        x += f * (this.drawnX(next + c) - x);
        if (!this.jumps || this.lane[next + c] === this.lane[base + c]) {
          y += f * (this.y[next + c] * this.yStep - y);
          h += f * (this.h[next + c] * this.hStep - h);
        }
      }
      this.did[c] = i; this.dx[c] = x; this.dy[c] = y; this.dh[c] = h;
    }
    this.stamp(t);
  }

  // Roles, commanded vehicles and live plans at time t.
  stamp(t) {
    const R = this.roles, K = this.commanded;
    this.roleOf.fill(-1);
    this.cmdOf.fill(-1);
    for (let k = 0; k < R.vehicle.length; k++) {
      if (R.t0[k] <= t && (t < R.t1[k] || R.t1[k] >= this.t1)) {
        this.roleOf[R.vehicle[k]] = R.role[k];
        this.rolePlan[R.vehicle[k]] = R.plan[k];
        this.roleVR[R.vehicle[k]] = R.vr ? R.vr[k] : -1;
      }
    }
    for (let k = 0; k < K.vehicle.length; k++) {
      if (K.t0[k] <= t && t < K.t1[k]) this.cmdOf[K.vehicle[k]] = k;
    }
    this.live.length = 0;
    for (let k = 0; k < this.plans.length; k++) if (HC.isLive(this.plans[k], t)) this.live.push(k);
  }

  // The column cell of vehicle i at the frame's row, or -1 when it is not on the road.
  cell(i) {
    if (!this.inside || i < 0 || i >= this.n || this.column[i] < 0) return -1;
    if (this.row < this.first[i] || this.row > this.last[i]) return -1;
    const idx = this.row * this.cols + this.column[i];
    return this.x[idx] === this.x[idx] ? idx : -1;
  }

  // The column vehicle i is drawn in, or -1.
  drawnColumn(i) {
    if (i < 0 || i >= this.n || this.column[i] < 0) return -1;
    const c = this.column[i];
    return this.did[c] === i ? c : -1;
  }

  // The plan live at the frame's time that was made last, or null.
  livePlan() {
    let best = null;
    for (const k of this.live) if (!best || this.plans[k].t0 >= best.t0) best = this.plans[k];
    return best;
  }

  // Speed and acceleration of vehicle i over the rows it is on the road.
  series(i) {
    if (i < 0 || i >= this.n || this.column[i] < 0) return null;
    const r0 = this.first[i], r1 = this.last[i], c = this.column[i], m = r1 - r0 + 1;
    const t = new Float64Array(m), v = new Float32Array(m), a = new Float32Array(m);
    for (let r = r0; r <= r1; r++) {
      const idx = r * this.cols + c;
      t[r - r0] = this.t[r];
      const on = this.x[idx] === this.x[idx];
      v[r - r0] = on ? this.v[idx] * this.vStep : NaN;
      a[r - r0] = on ? this.a[idx] * this.aStep : NaN;
    }
    return { t, v, a };
  }
};

// A plan is live from its decision until it is replaced, its merge completes or its VR
// leaves the road (the end of the run included).
HC.isLive = function (p, t) {
  return p.start <= t && (t < p.end || (p.ended === "end of run" && t <= p.end));
};

HC.ROLE_NAMES = ["VR", "VMC", "VMF", "VMR", "VNF", "VNR", "STALLED"];
HC.KIND_NAMES = ["HDV", "CAV"];
HC.COLOURS = {
  kind: ["#d95f02", "#1b9e77"], ghost: "#7570b3", verge: "#eef3e8", asphalt: "#d9d9d9",
  ramp: "#cfcfcf", zone: "rgba(255, 224, 102, 0.42)", marking: "#ffffff", select: "#1f5fd6",
  runs: ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#8c564b", "#e377c2"],
};
HC.EVENT_COLOURS = {
  LANE_CHANGE_START: "#6b6b6b", LANE_CHANGE_END: "#a8a8a8", MERGE: "#1b9e77",
  COLLISION: "#e00000", RAMP_WAIT: "#e6820e", PLAN: "#7570b3", FALLBACK: "#c51b8a",
  ZONE: "#c9a800", PLAN_LOST: "#9e9ac8", V2X_SILENT: "#bcbddc", SHIELD: "#08519c",
  FAULT: "#a50f15",
};

HC.fmt = function (value, digits) {
  return value === null || value === undefined || value !== value ? "–" : value.toFixed(digits);
};
