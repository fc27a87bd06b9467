"use strict";
// hcomc replay, drawing: the road to scale, vehicles by kind and heading, the key roles,
// the live plans' virtual vehicles (ghosts) and predicted paths, and the road overview.

// An area whose ends are shifted laterally (dy0 upstream, dy1 downstream: a ramp road
// sloping away from the mainline), filled through the canvas mapping X, Y.
HC.fillArea = function (ctx, a, X, Y) {
  ctx.beginPath();
  ctx.moveTo(X(a.x0), Y(a.y0 + a.dy0)); ctx.lineTo(X(a.x1), Y(a.y0 + a.dy1));
  ctx.lineTo(X(a.x1), Y(a.y1 + a.dy1)); ctx.lineTo(X(a.x0), Y(a.y1 + a.dy0));
  ctx.closePath(); ctx.fill();
};

// One run's canvas. World (x, y) [m] maps to the canvas with one scale for both axes.
HC.Scene = class {
  constructor(canvas, run) {
    this.canvas = canvas;
    this.ctx = canvas.getContext("2d");
    this.run = run;
    this.w = 1; this.h = 1; this.dpr = 1;
    this.cx = 0; this.cy = 0; this.scale = 4;
  }

  resize() {
    const dpr = window.devicePixelRatio || 1, box = this.canvas.getBoundingClientRect();
    const w = Math.max(1, Math.round(box.width)), h = Math.max(1, Math.round(box.height));
    if (w !== this.w || h !== this.h || dpr !== this.dpr) {
      this.w = w; this.h = h; this.dpr = dpr;
      this.canvas.width = Math.round(w * dpr);
      this.canvas.height = Math.round(h * dpr);
    }
  }

  sx(x) { return (x - this.cx) * this.scale + this.w / 2; }
  sy(y) { return this.h / 2 - (y - this.cy) * this.scale; }
  wx(px) { return (px - this.w / 2) / this.scale + this.cx; }
  wy(py) { return this.cy - (py - this.h / 2) / this.scale; }

  draw(ui) {
    const ctx = this.ctx, run = this.run;
    ctx.setTransform(this.dpr, 0, 0, this.dpr, 0, 0);
    ctx.fillStyle = HC.COLOURS.verge;
    ctx.fillRect(0, 0, this.w, this.h);
    this.drawRoad();
    if (!run.inside) {
      ctx.fillStyle = "#555"; ctx.font = "13px system-ui, sans-serif"; ctx.textAlign = "center";
      ctx.fillText("no data at this time", this.w / 2, 18);
      return;
    }
    this.drawPaths(ui.t);
    this.drawVehicles(ui);
    this.drawGhosts();
    this.drawLabels(ui);
  }

  drawRoad() {
    const ctx = this.ctx, s = this.scale, road = this.run.road;
    const left = this.wx(-10), right = this.wx(this.w + 10);
    for (const a of road.areas) {
      const x0 = Math.max(a.x0, left), x1 = Math.min(a.x1, right);
      if (x1 <= x0) continue;
      ctx.fillStyle = HC.COLOURS[a.surface];
      if (a.dy0 || a.dy1) HC.fillArea(ctx, a, (x) => this.sx(x), (y) => this.sy(y));
      else ctx.fillRect(this.sx(x0), this.sy(a.y1), (x1 - x0) * s, (a.y1 - a.y0) * s);
    }
    ctx.strokeStyle = HC.COLOURS.marking;
    for (const m of road.markings) {
      const vertical = m.x0 === m.x1;
      let x0 = Math.max(m.x0, left), x1 = Math.min(m.x1, right);
      if (!vertical && x1 <= x0) continue;
      if (vertical) { x0 = m.x0; x1 = m.x1; if (x0 < left || x0 > right) continue; }
      const dashed = m.stroke === "dashed" && 3 * s >= 2;
      if (dashed) x0 = Math.max(m.x0, Math.floor(x0 / 9) * 9);  // dashes fixed to the road
      // the ends' y where the line is cut to the view (a line may slope: a ramp road)
      const slope = vertical ? 0 : (m.y1 - m.y0) / (m.x1 - m.x0);
      const y0 = vertical ? m.y0 : m.y0 + (x0 - m.x0) * slope;
      const y1 = vertical ? m.y1 : m.y0 + (x1 - m.x0) * slope;
      ctx.lineWidth = m.stroke === "barrier" ? Math.max(1.5, 0.3 * s) : Math.max(1, 0.15 * s);
      ctx.setLineDash(dashed ? [3 * s, 6 * s] : []);
      ctx.beginPath();
      ctx.moveTo(this.sx(x0), this.sy(y0));
      ctx.lineTo(this.sx(x1), this.sy(y1));
      ctx.stroke();
    }
    ctx.setLineDash([]);
    if (s < 0.5) return;  // zoomed out too far for the labels to fit
    ctx.fillStyle = "#5a5a5a"; ctx.font = "11px system-ui, sans-serif"; ctx.textAlign = "center";
    for (const lb of road.labels) {
      const px = this.sx(lb.x);
      if (px > -80 && px < this.w + 80) ctx.fillText(lb.text, px, this.sy(lb.y) + 4);
    }
  }

  // The outline of a vehicle (front-bumper reference point, Section II-C) as a sub-path.
  rectPath(x, y, h, L, W) {
    const ctx = this.ctx, s = this.scale;
    if (L * s < 2.5) {  // too small to show its shape: a dot
      ctx.rect(this.sx(x) - 1.5, this.sy(y) - 1, 3, 2);
      return;
    }
    const c = Math.cos(h), n = Math.sin(h), hw = W / 2;
    ctx.moveTo(this.sx(x + hw * n), this.sy(y - hw * c));
    ctx.lineTo(this.sx(x - hw * n), this.sy(y + hw * c));
    ctx.lineTo(this.sx(x - L * c - hw * n), this.sy(y - L * n + hw * c));
    ctx.lineTo(this.sx(x - L * c + hw * n), this.sy(y - L * n - hw * c));
    ctx.closePath();
  }

  visible(x, L) { return x >= this.wx(-20) && x - L <= this.wx(this.w + 20); }

  drawVehicles(ui) {
    const ctx = this.ctx, run = this.run, C = run.cols, big = 5 * this.scale >= 8;
    for (let kind = 0; kind < 2; kind++) {
      ctx.beginPath();
      for (let c = 0; c < C; c++) {
        const i = run.did[c];
        if (i < 0 || run.kind[i] !== kind || !this.visible(run.dx[c], run.length[i])) continue;
        this.rectPath(run.dx[c], run.dy[c], run.dh[c], run.length[i], run.width[i]);
      }
      ctx.fillStyle = HC.COLOURS.kind[kind];
      ctx.fill();
      if (big) { ctx.lineWidth = 0.7; ctx.strokeStyle = "rgba(0,0,0,0.5)"; ctx.stroke(); }
    }
    const hovered = ui.hover && ui.hover.run === run.index ? ui.hover.id : -1;
    for (let c = 0; c < C; c++) {
      const i = run.did[c];
      if (i < 0 || (run.roleOf[i] < 0 && i !== ui.selected && i !== hovered)) continue;
      ctx.beginPath();
      this.rectPath(run.dx[c], run.dy[c], run.dh[c], run.length[i], run.width[i]);
      ctx.lineWidth = i === ui.selected ? 3 : i === hovered ? 2 : 1.4;
      ctx.strokeStyle = i === ui.selected ? HC.COLOURS.select : "#111";
      ctx.stroke();
    }
  }

  // Where a live plan's ghost is at the frame's time: its x, or NaN outside its rows.
  ghostX(g) {
    const run = this.run, j = run.row - g.row;
    if (j < 0 || j >= g.x.length) return NaN;
    const x = g.x[j];
    return run.frac > 0 && j + 1 < g.x.length ? x + run.frac * (g.x[j + 1] - x) : x;
  }

  drawGhosts() {
    const ctx = this.ctx, run = this.run, road = run.road;
    ctx.setLineDash([4, 3]);
    for (const k of run.live) {
      for (const g of run.plans[k].ghosts) {
        const x = this.ghostX(g), L = g.length || road.vehicle_length;
        if (x !== x || !this.visible(x, L)) continue;
        ctx.beginPath();
        this.rectPath(x, g.y, 0, L, g.width || road.vehicle_width);
        ctx.fillStyle = "rgba(117, 112, 179, 0.22)"; ctx.fill();
        ctx.strokeStyle = HC.COLOURS.ghost; ctx.lineWidth = 1.5; ctx.stroke();
        this.tag(g.label, x - L / 2, g.y + (g.width || road.vehicle_width) / 2, null, HC.COLOURS.ghost);
      }
    }
    ctx.setLineDash([]);
  }

  // The live plans' predicted paths: each virtual vehicle's position every second of its
  // horizon along its lane, and VR's planned merge (to the merge position, then Eq. 4-6).
  drawPaths(t) {
    const ctx = this.ctx, run = this.run, lanes = run.road.lanes;
    ctx.strokeStyle = HC.COLOURS.ghost;
    for (const k of run.live) {
      const p = run.plans[k];
      for (const g of p.ghosts) {
        if (!g.ticks.length) continue;
        ctx.globalAlpha = 0.55; ctx.lineWidth = 1;
        ctx.beginPath();
        ctx.moveTo(this.sx(g.ticks[0]), this.sy(g.y));
        ctx.lineTo(this.sx(g.ticks[g.ticks.length - 1]), this.sy(g.y));
        ctx.stroke();
        const half = 0.3 * run.road.vehicle_width * this.scale + 2;
        for (let j = 0; j < g.ticks.length; j++) {
          ctx.globalAlpha = p.t0 + j >= t ? 0.9 : 0.3;
          ctx.beginPath();
          ctx.moveTo(this.sx(g.ticks[j]), this.sy(g.y) - half);
          ctx.lineTo(this.sx(g.ticks[j]), this.sy(g.y) + half);
          ctx.stroke();
        }
      }
      ctx.globalAlpha = 1;
      const path = p.merge_path;
      if (!path.length) continue;
      ctx.lineWidth = 2; ctx.setLineDash([6, 4]);
      ctx.beginPath();
      const c = run.drawnColumn(p.group.VR), ramp = lanes["0"];
      if (c >= 0 && run.dx[c] < path[0][0] && Math.abs(run.dy[c] - ramp) < 0.5) {
        ctx.moveTo(this.sx(run.dx[c]), this.sy(ramp));
        ctx.lineTo(this.sx(path[0][0]), this.sy(path[0][1]));
      } else {
        ctx.moveTo(this.sx(path[0][0]), this.sy(path[0][1]));
      }
      for (let j = 1; j < path.length; j++) ctx.lineTo(this.sx(path[j][0]), this.sy(path[j][1]));
      ctx.stroke();
      ctx.setLineDash([]);
      const mx = this.sx(path[0][0]), my = this.sy(path[0][1]);
      ctx.fillStyle = HC.COLOURS.ghost;
      ctx.beginPath(); ctx.moveTo(mx, my - 3); ctx.lineTo(mx - 5, my - 11); ctx.lineTo(mx + 5, my - 11);
      ctx.closePath(); ctx.fill();
    }
  }

  // A small label at world (x, y) [m], drawn above that point.
  tag(text, x, y, background, colour) {
    const ctx = this.ctx, px = this.sx(x), py = this.sy(y) - 4;
    ctx.font = "bold 11px system-ui, sans-serif"; ctx.textAlign = "center";
    if (background) {
      const w = ctx.measureText(text).width + 6;
      ctx.fillStyle = background;
      ctx.fillRect(px - w / 2, py - 12, w, 14);
    }
    ctx.fillStyle = colour;
    ctx.fillText(text, px, py - 1);
  }

  drawLabels(ui) {
    const run = this.run, C = run.cols;
    for (let c = 0; c < C; c++) {
      const i = run.did[c];
      if (i < 0 || (run.roleOf[i] < 0 && i !== ui.selected)) continue;
      const L = run.length[i];
      if (!this.visible(run.dx[c], L)) continue;
      const role = run.roleOf[i] >= 0 ? HC.ROLE_NAMES[run.roleOf[i]] : "#" + i;
      const commanded = run.cmdOf[i] >= 0;
      this.tag(role, run.dx[c] - L / 2, run.dy[c] + run.width[i] / 2,
        commanded ? HC.COLOURS.ghost : "rgba(255,255,255,0.85)", commanded ? "#fff" : "#111");
    }
  }

  // The vehicle drawn under the canvas point (px, py), or -1 (a few pixels of slack).
  pick(px, py) {
    const run = this.run, wx = this.wx(px), wy = this.wy(py), slack = 4 / this.scale;
    let best = -1;
    for (let c = 0; c < run.cols; c++) {
      const i = run.did[c];
      if (i < 0) continue;
      const h = run.dh[c], ex = wx - run.dx[c], ey = wy - run.dy[c];
      const u = ex * Math.cos(h) + ey * Math.sin(h), v = -ex * Math.sin(h) + ey * Math.cos(h);
      if (u <= slack && u >= -run.length[i] - slack && Math.abs(v) <= run.width[i] / 2 + slack) best = i;
    }
    return best;
  }
};

// The whole road of the first run, laterally stretched, with every vehicle as a dot and the
// part the scenes show; clicking or dragging moves the view there.
HC.Overview = class {
  constructor(canvas, run) {
    this.canvas = canvas; this.ctx = canvas.getContext("2d"); this.run = run;
    this.w = 1; this.h = 1; this.dpr = 1;
  }

  resize() { HC.Scene.prototype.resize.call(this); }

  ox(x) { const b = this.run.road.bounds; return 4 + (x - b[0]) / (b[1] - b[0]) * (this.w - 8); }
  oy(y) { const b = this.run.road.bounds; return this.h - 2 - (y - b[2]) / (b[3] - b[2]) * (this.h - 4); }
  worldX(px) { const b = this.run.road.bounds; return b[0] + (px - 4) / (this.w - 8) * (b[1] - b[0]); }

  draw(scene) {
    const ctx = this.ctx, run = this.run;
    ctx.setTransform(this.dpr, 0, 0, this.dpr, 0, 0);
    ctx.fillStyle = HC.COLOURS.verge; ctx.fillRect(0, 0, this.w, this.h);
    for (const a of run.road.areas) {
      ctx.fillStyle = HC.COLOURS[a.surface];
      if (a.dy0 || a.dy1) HC.fillArea(ctx, a, (x) => this.ox(x), (y) => this.oy(y));
      else ctx.fillRect(this.ox(a.x0), this.oy(a.y1), this.ox(a.x1) - this.ox(a.x0), this.oy(a.y0) - this.oy(a.y1));
    }
    for (let kind = 0; kind < 2; kind++) {
      ctx.beginPath();
      for (let c = 0; c < run.cols; c++) {
        const i = run.did[c];
        if (i >= 0 && run.kind[i] === kind) ctx.rect(this.ox(run.dx[c]) - 1, this.oy(run.dy[c]) - 1, 2, 2);
      }
      ctx.fillStyle = HC.COLOURS.kind[kind]; ctx.fill();
    }
    const x0 = this.ox(scene.wx(0)), x1 = this.ox(scene.wx(scene.w));
    ctx.strokeStyle = HC.COLOURS.select; ctx.lineWidth = 1.5;
    ctx.strokeRect(x0, 1, Math.max(2, x1 - x0), this.h - 2);
  }
};
