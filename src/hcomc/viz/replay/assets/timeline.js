"use strict";
// hcomc replay, time: the timeline (scrubbing, a track of events and plans per run) and the
// selected vehicle's speed and acceleration chart.

HC.niceStep = function (span, target) {
  const raw = span / Math.max(1, target), p = Math.pow(10, Math.floor(Math.log10(raw)));
  for (const m of [1, 2, 5, 10]) if (m * p >= raw) return m * p;
  return 10 * p;
};

// An offscreen copy of what does not change from frame to frame, redrawn by `paint(ctx)`
// when `key` changes (size, selection); each frame then starts from a copy of it.
HC.background = function (owner, key, paint) {
  if (owner.bgKey !== key) {
    const c = owner.bg || document.createElement("canvas");
    c.width = owner.canvas.width; c.height = owner.canvas.height;
    const ctx = c.getContext("2d");
    ctx.setTransform(owner.dpr, 0, 0, owner.dpr, 0, 0);
    paint(ctx);
    owner.bg = c; owner.bgKey = key;
  }
  owner.ctx.setTransform(1, 0, 0, 1, 0, 0);
  owner.ctx.drawImage(owner.bg, 0, 0);
  owner.ctx.setTransform(owner.dpr, 0, 0, owner.dpr, 0, 0);
};

HC.Timeline = class {
  constructor(canvas, runs) {
    this.canvas = canvas; this.ctx = canvas.getContext("2d"); this.runs = runs;
    this.w = 1; this.h = 1; this.dpr = 1;
    this.tMin = Math.min(...runs.map((r) => r.t0));
    this.tMax = Math.max(...runs.map((r) => r.t1));
    this.marks = [];  // {t, run, colour, text}, sorted by t
    for (const run of runs) this.collect(run);
    this.marks.sort((a, b) => a.t - b.t);
  }

  collect(run) {
    const E = run.events, names = E.names;
    for (let k = 0; k < E.t.length; k++) {
      const name = names[E.kind[k]] || "EVENT " + E.kind[k];
      let text = name + " · vehicle " + E.vehicle[k];
      if (name === "COLLISION" && E.other[k] >= 0) text += " and " + E.other[k];
      if (name === "PLAN") {
        const p = run.plans.find((q) => Math.abs(q.t0 - E.t[k]) < 1e-6 && q.group.VR === E.vehicle[k]);
        if (p) text = "PLAN " + (p.index + 1) + " · VR " + p.group.VR + " · " + p.mode + " · " + p.sequence;
      }
      if (name === "SHIELD") {
        const action = ["brakes", "holds the lane change of", "releases from its plan"][E.value[k]];
        text = "SHIELD " + action + " vehicle " + E.vehicle[k] + " · unsafe to " + E.other[k];
      }
      if (name === "FAULT") text = "FAULT " + E.value[k] + " begins · vehicle " + E.vehicle[k];
      if (name === "PLAN_LOST") text = "PLAN LOST on the V2X channel · VR " + E.vehicle[k];
      if (name === "V2X_SILENT") {
        text = "V2X SILENT · nothing new of vehicle " + E.vehicle[k] + " for " + E.value[k].toFixed(1) + " s";
      }
      if (E.text && E.text[k]) text = E.text[k];  // a corridor run's own wording
      this.marks.push({ t: E.t[k], run: run.index, colour: HC.EVENT_COLOURS[name] || "#333", text });
    }
    for (let k = 0; k < E.zone_t.length; k++) {
      const text = E.zone_text ? E.zone_text[k] : "CONTROL ZONE ENTRY · VR " + E.zone_vr[k];
      this.marks.push({ t: E.zone_t[k], run: run.index, colour: HC.EVENT_COLOURS.ZONE, text });
    }
  }

  resize() { HC.Scene.prototype.resize.call(this); }
  tx(t) { return 8 + (t - this.tMin) / Math.max(1e-9, this.tMax - this.tMin) * (this.w - 16); }
  time(px) {
    const t = this.tMin + (px - 8) / Math.max(1, this.w - 16) * (this.tMax - this.tMin);
    return Math.min(this.tMax, Math.max(this.tMin, t));
  }
  trackTop(r) { return 18 + r * 18; }

  draw(t) {
    HC.background(this, this.w + "x" + this.h + "x" + this.dpr, (ctx) => this.paint(ctx));
    this.ctx.fillStyle = "#d62728"; this.ctx.fillRect(this.tx(t) - 1, 0, 2, this.h);
  }

  paint(ctx) {
    ctx.fillStyle = "#fbfbfc"; ctx.fillRect(0, 0, this.w, this.h);
    ctx.fillStyle = "#555"; ctx.strokeStyle = "#bbb"; ctx.lineWidth = 1;
    ctx.font = "10px system-ui, sans-serif"; ctx.textAlign = "center";
    const step = HC.niceStep(this.tMax - this.tMin, this.w / 70);
    for (let s = Math.ceil(this.tMin / step) * step; s <= this.tMax + 1e-9; s += step) {
      const px = this.tx(s);
      ctx.beginPath(); ctx.moveTo(px, 11); ctx.lineTo(px, this.h); ctx.stroke();
      ctx.fillText(s.toFixed(step < 1 ? 1 : 0) + " s", px, 9);
    }
    for (const run of this.runs) {
      const top = this.trackTop(run.index);
      ctx.fillStyle = "rgba(0,0,0,0.035)"; ctx.fillRect(0, top, this.w, 16);
      ctx.fillStyle = "rgba(117, 112, 179, 0.2)";
      for (const p of run.plans) ctx.fillRect(this.tx(p.start), top + 3, Math.max(1, this.tx(p.end) - this.tx(p.start)), 10);
      ctx.fillStyle = HC.COLOURS.runs[run.index % HC.COLOURS.runs.length];
      ctx.fillRect(0, top, 4, 16);
      ctx.fillStyle = "rgba(60,60,60,0.55)"; ctx.textAlign = "left"; ctx.font = "10px system-ui, sans-serif";
      ctx.fillText(run.title, 8, top + 12);
    }
    for (const m of this.marks) {
      const top = this.trackTop(m.run), px = this.tx(m.t);
      ctx.fillStyle = m.colour;
      ctx.fillRect(px - 1, top + 1, 2, 14);
    }
  }

  // The marks within a few pixels of canvas point (px, py), nearest first.
  marksAt(px, py) {
    const r = Math.floor((py - 18) / 18);
    if (r < 0 || r >= this.runs.length) return [];
    return this.marks.filter((m) => m.run === r && Math.abs(this.tx(m.t) - px) <= 4)
      .sort((a, b) => Math.abs(this.tx(a.t) - px) - Math.abs(this.tx(b.t) - px));
  }

  // The first mark after t (dir > 0) or the last before it (dir < 0), or null.
  nextMark(t, dir) {
    if (dir > 0) return this.marks.find((m) => m.t > t + 1e-6) || null;
    for (let k = this.marks.length - 1; k >= 0; k--) if (this.marks[k].t < t - 1e-6) return this.marks[k];
    return null;
  }
};

// Speed (top) and acceleration (bottom) of one vehicle in every run, with the time cursor.
HC.Chart = class {
  constructor(canvas) {
    this.canvas = canvas; this.ctx = canvas.getContext("2d");
    this.w = 1; this.h = 1; this.dpr = 1; this.id = -1; this.series = [];
  }

  resize() { HC.Scene.prototype.resize.call(this); }

  set(runs, id) {
    if (id === this.id) return;
    this.id = id;
    this.range = { t0: 0, t1: 1 };
    this.series = id < 0 ? [] : runs.map((r) => r.series(id));
    let t0 = Infinity, t1 = -Infinity, v1 = 1, a0 = -1, a1 = 1;
    for (const s of this.series) {
      if (!s) continue;
      t0 = Math.min(t0, s.t[0]); t1 = Math.max(t1, s.t[s.t.length - 1]);
      for (let k = 0; k < s.v.length; k++) {
        if (s.v[k] === s.v[k]) v1 = Math.max(v1, s.v[k]);
        if (s.a[k] === s.a[k]) { a0 = Math.min(a0, s.a[k]); a1 = Math.max(a1, s.a[k]); }
      }
    }
    this.range = { t0, t1: Math.max(t1, t0 + 1), v1: Math.ceil(v1 / 5) * 5, a0: Math.floor(a0), a1: Math.ceil(a1) };
  }

  x(t) { const R = this.range; return 34 + (t - R.t0) / (R.t1 - R.t0) * (this.w - 40); }

  draw(t) {
    HC.background(this, [this.w, this.h, this.dpr, this.id].join("x"), (ctx) => this.paint(ctx));
    const R = this.range;
    if (this.id >= 0 && t >= R.t0 && t <= R.t1) {
      this.ctx.fillStyle = "#d62728"; this.ctx.fillRect(this.x(t) - 0.5, 0, 1, this.h);
    }
  }

  paint(ctx) {
    const w = this.w, h = this.h;
    ctx.fillStyle = "#fff"; ctx.fillRect(0, 0, w, h);
    ctx.font = "10px system-ui, sans-serif"; ctx.fillStyle = "#666"; ctx.textAlign = "left";
    if (!this.series.some((s) => s)) { ctx.fillText("click a vehicle to chart its speed and acceleration", 8, 16); return; }
    const R = this.range, half = (h - 16) / 2, left = 34, right = w - 6;
    const X = (tt) => this.x(tt);
    const panels = [["v [m/s]", "v", 0, R.v1, 4], ["a [m/s²]", "a", R.a0, R.a1, half + 12]];
    for (const [label, key, lo, hi, top] of panels) {
      const Y = (val) => top + (1 - (val - lo) / Math.max(1e-9, hi - lo)) * (half - 4);
      ctx.strokeStyle = "#ddd"; ctx.lineWidth = 1; ctx.strokeRect(left, top, right - left, half - 4);
      ctx.fillStyle = "#666"; ctx.textAlign = "right";
      ctx.fillText(String(hi), left - 3, top + 8); ctx.fillText(String(lo), left - 3, top + half - 4);
      ctx.textAlign = "left"; ctx.fillText(label, left + 4, top + 10);
      if (lo < 0 && hi > 0) { ctx.beginPath(); ctx.moveTo(left, Y(0)); ctx.lineTo(right, Y(0)); ctx.stroke(); }
      this.series.forEach((s, r) => {
        if (!s) return;
        ctx.strokeStyle = HC.COLOURS.runs[r % HC.COLOURS.runs.length]; ctx.lineWidth = 1.3;
        ctx.beginPath();
        let pen = false;
        for (let k = 0; k < s.t.length; k++) {
          const val = s[key][k];
          if (val !== val) { pen = false; continue; }
          if (pen) ctx.lineTo(X(s.t[k]), Y(val)); else ctx.moveTo(X(s.t[k]), Y(val));
          pen = true;
        }
        ctx.stroke();
      });
    }
  }
};
