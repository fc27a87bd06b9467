"use strict";
// hcomc replay, the player: controls, keyboard and pointer, the vehicle and plan panels, the
// frame loop, and window.hcomcReplay, the API tests and scripts read the page through.

HC.SPEEDS = [0.1, 0.25, 0.5, 1, 2, 4, 8, 16];

HC.App = class {
  constructor(data) {
    this.runs = data.runs.map((d, k) => new HC.Run(d, k));
    this.tMin = Math.min(...this.runs.map((r) => r.t0));
    this.tMax = Math.max(...this.runs.map((r) => r.t1));
    this.t = this.tMin;
    this.playing = false; this.speedIndex = HC.SPEEDS.indexOf(1);
    this.selected = -1; this.hover = null; this.follow = false;
    this.cam = { cx: 0, cy: 0, scale: 4 };
    this.dirty = true; this.last = 0; this.frames = 0;
    const zone = this.runs[0].events.zone_vr;
    this.firstVR = zone.length ? zone[0] : -1;
    this.build(data.title);
    this.bind();
    this.resize();
    this.home();
    this.render();
    requestAnimationFrame((now) => this.tick(now));
  }

  el(id) { return document.getElementById(id); }

  build(title) {
    document.title = title;
    this.el("page-title").textContent = title;
    const holder = this.el("runs"), tables = this.el("plan-tables");
    this.scenes = []; this.liveBoxes = []; this.planRows = []; this.liveKeys = [];
    for (const run of this.runs) {
      const box = document.createElement("section"); box.className = "run";
      const head = document.createElement("div"); head.className = "run-head";
      const sw = document.createElement("span"); sw.className = "swatch";
      sw.style.background = HC.COLOURS.runs[run.index % HC.COLOURS.runs.length];
      const name = document.createElement("span"); name.className = "run-title"; name.textContent = run.title;
      const live = document.createElement("span"); live.className = "live-plan";
      head.append(sw, name, live);
      const canvas = document.createElement("canvas"); canvas.className = "scene";
      canvas.dataset.run = String(run.index);
      box.append(head, canvas); holder.append(box);
      this.scenes.push(new HC.Scene(canvas, run)); this.liveBoxes.push(live);
      tables.append(this.planTable(run));
    }
    this.timeline = new HC.Timeline(this.el("timeline"), this.runs);
    this.el("timeline").style.height = (22 + 18 * this.runs.length) + "px";
    this.overview = new HC.Overview(this.el("overview"), this.runs[0]);
    this.chart = new HC.Chart(this.el("chart"));
    const speed = this.el("speed");
    for (const s of HC.SPEEDS) speed.append(new Option(s + "×", String(s)));
    speed.value = "1";
  }

  planTable(run) {
    if (run.merges) return this.mergeTable(run);
    const wrap = document.createElement("div"), box = document.createElement("div");
    const name = document.createElement("h3");
    name.textContent = run.title + " — " + run.plans.length + " plan(s)";
    box.className = "plans";
    const table = document.createElement("table");
    const head = ["#", "t0 [s]", "VR", "VMC", "mode", "sequence", "Eq. 19", "decision [ms]",
      "merge x [m]", "VR change [s]", "horizon [s]", "live until [s]", "ended"];
    table.createTHead().insertRow().append(...head.map((h) => { const th = document.createElement("th"); th.textContent = h; return th; }));
    const body = table.createTBody(), rows = [];
    for (const p of run.plans) {
      const tr = body.insertRow();
      const cells = [p.index + 1, HC.fmt(p.t0, 2), p.group.VR, p.group.VMC, p.mode, p.sequence,
        p.eq19_branch || "–", HC.fmt(p.decision_ms, 1), HC.fmt(p.merge_x, 1), HC.fmt(p.vr_duration, 2),
        HC.fmt(p.horizon, 2), HC.fmt(p.end, 2), p.ended + (p.fallback ? " (fallback)" : "")];
      for (const c of cells) tr.insertCell().textContent = String(c);
      tr.title = p.reason || "";
      tr.addEventListener("click", () => { this.pause(); this.seek(p.t0); });
      rows.push(tr);
    }
    if (!run.plans.length) body.insertRow().insertCell().textContent = "no merge plans in this run";
    this.planRows.push(rows);
    box.append(table);
    wrap.append(name, box);
    return wrap;
  }

  // A corridor run's merge events (merges.csv): a click goes to the control-zone entry and
  // follows its ramp vehicle.
  mergeTable(run) {
    const wrap = document.createElement("div"), box = document.createElement("div");
    const name = document.createElement("h3"), merged = run.merges.filter((m) => m.merged).length;
    name.textContent = run.title + " — " + run.merges.length + " merge event(s), " + merged +
      " merged (the corridor engine does not record its plans)";
    box.className = "plans";
    const table = document.createElement("table");
    const head = ["VR", "ramp", "kind", "zone entry [s]", "VMC", "VMF", "VMR", "VNF", "VNR",
      "merged at [s]", "position [m]", "least TTC [s]", "max DRAC [m/s²]", "plans", "mode"];
    table.createTHead().insertRow().append(...head.map((h) => { const th = document.createElement("th"); th.textContent = h; return th; }));
    const body = table.createTBody(), key = (k) => (k >= 0 ? k : "–");
    for (const m of run.merges) {
      const tr = body.insertRow();
      const cells = [m.vr, m.ramp, m.cav ? "CAV" : "HDV", HC.fmt(m.zone_time, 2), key(m.vmc), key(m.vmf),
        key(m.vmr), key(m.vnf), key(m.vnr), m.merged ? HC.fmt(m.merge_time, 2) : "no",
        HC.fmt(m.merge_position, 1), HC.fmt(m.min_ttc, 2), HC.fmt(m.max_drac, 2), m.plans, m.final_mode || "–"];
      for (const c of cells) tr.insertCell().textContent = String(c);
      tr.title = "position: past the start of the acceleration lane; least TTC and max DRAC over the event's window";
      tr.addEventListener("click", () => { this.pause(); this.seek(m.zone_time); this.select(m.vr); this.setFollow(true); });
    }
    if (!run.merges.length) body.insertRow().insertCell().textContent = "no ramp vehicle reached its control zone";
    this.planRows.push([]);
    box.append(table);
    wrap.append(name, box);
    return wrap;
  }

  bind() {
    this.el("play").addEventListener("click", () => this.toggle());
    this.el("back").addEventListener("click", () => this.step(-1));
    this.el("fwd").addEventListener("click", () => this.step(1));
    this.el("speed").addEventListener("change", (e) => this.setSpeed(Number(e.target.value)));
    this.el("follow").addEventListener("change", (e) => { this.follow = e.target.checked; this.dirty = true; });
    this.el("home").addEventListener("click", () => this.home());
    this.el("whole").addEventListener("click", () => this.whole());
    this.el("help-button").addEventListener("click", () => this.toggleHelp());
    this.el("help").addEventListener("click", () => this.toggleHelp());
    window.addEventListener("resize", () => { this.resize(); this.dirty = true; });
    document.addEventListener("keydown", (e) => this.key(e));
    for (const scene of this.scenes) this.bindScene(scene);
    this.bindTimeline();
    const ov = this.el("overview");
    const jump = (e) => { this.unfollow(); this.cam.cx = this.overview.worldX(e.offsetX); this.dirty = true; };
    ov.addEventListener("mousedown", (e) => { jump(e); this.ovDrag = true; });
    ov.addEventListener("mousemove", (e) => { if (this.ovDrag) jump(e); });
    window.addEventListener("mouseup", () => { this.ovDrag = false; this.drag = null; this.scrub = false; });
  }

  bindScene(scene) {
    const c = scene.canvas;
    c.addEventListener("mousedown", (e) => { this.drag = { scene, x: e.offsetX, y: e.offsetY, moved: false }; });
    c.addEventListener("mousemove", (e) => {
      const d = this.drag;
      if (d && d.scene === scene && (d.moved || Math.abs(e.offsetX - d.x) + Math.abs(e.offsetY - d.y) > 3)) {
        if (!d.moved) { this.unfollow(); d.moved = true; }
        this.cam.cx -= (e.offsetX - d.x) / this.cam.scale; this.cam.cy += (e.offsetY - d.y) / this.cam.scale;
        d.x = e.offsetX; d.y = e.offsetY; this.dirty = true;
        return;
      }
      const id = scene.pick(e.offsetX, e.offsetY);
      this.setHover(id >= 0 ? { run: scene.run.index, id } : null);
    });
    c.addEventListener("mouseup", (e) => {
      if (this.drag && this.drag.scene === scene && !this.drag.moved) this.select(scene.pick(e.offsetX, e.offsetY));
      this.drag = null;
    });
    c.addEventListener("mouseleave", () => this.setHover(null));
    c.addEventListener("wheel", (e) => {
      e.preventDefault();
      const f = Math.pow(1.0015, -e.deltaY), scale = Math.min(80, Math.max(0.005, this.cam.scale * f));
      if (!this.follow) { const wx = scene.wx(e.offsetX); this.cam.cx = wx - (e.offsetX - scene.w / 2) / scale; }
      this.cam.scale = scale; this.dirty = true;
    }, { passive: false });
  }

  bindTimeline() {
    const c = this.el("timeline"), tip = this.el("tip");
    const at = (e) => {
      const marks = this.timeline.marksAt(e.offsetX, e.offsetY);
      this.seek(marks.length ? marks[0].t : this.timeline.time(e.offsetX));
    };
    c.addEventListener("mousedown", (e) => { this.pause(); this.scrub = true; at(e); });
    c.addEventListener("mousemove", (e) => {
      if (this.scrub) at(e);
      const marks = this.timeline.marksAt(e.offsetX, e.offsetY);
      tip.hidden = !marks.length;
      if (marks.length) {
        tip.textContent = marks.slice(0, 6).map((m) => m.t.toFixed(2) + " s · " + m.text).join("\n");
        tip.style.left = (e.pageX + 12) + "px"; tip.style.top = (e.pageY + 12) + "px";
      }
    });
    c.addEventListener("mouseleave", () => { tip.hidden = true; });
  }

  key(e) {
    if (e.target && (e.target.tagName === "INPUT" || e.target.tagName === "SELECT") && e.key !== " ") return;
    const k = e.key, big = e.shiftKey ? 10 : 1;
    const actions = {
      " ": () => this.toggle(), ArrowRight: () => this.step(big), ArrowLeft: () => this.step(-big),
      ".": () => this.step(1), ",": () => this.step(-1),
      "+": () => this.faster(1), "=": () => this.faster(1), "-": () => this.faster(-1), "_": () => this.faster(-1),
      Home: () => this.seek(this.tMin), End: () => this.seek(this.tMax),
      "]": () => this.jump(1), "[": () => this.jump(-1),
      f: () => this.setFollow(!this.follow), "0": () => this.home(), w: () => this.whole(),
      Escape: () => this.select(-1), "?": () => this.toggleHelp(), h: () => this.toggleHelp(),
    };
    if (actions[k]) { e.preventDefault(); actions[k](); }
  }

  // ---------------------------------------------------------------- time and view
  seek(t) { this.t = Math.min(this.tMax, Math.max(this.tMin, Number(t))); this.dirty = true; }
  toggle() { if (this.playing) this.pause(); else this.play(); }
  play() { if (this.t >= this.tMax) this.t = this.tMin; this.playing = true; this.el("play").textContent = "❚❚"; }
  pause() { this.playing = false; this.el("play").textContent = "▶"; this.dirty = true; }
  setSpeed(s) {
    let best = 0;
    HC.SPEEDS.forEach((v, k) => { if (Math.abs(v - s) < Math.abs(HC.SPEEDS[best] - s)) best = k; });
    this.speedIndex = best; this.el("speed").value = String(HC.SPEEDS[best]);
  }
  faster(d) { this.setSpeed(HC.SPEEDS[Math.min(HC.SPEEDS.length - 1, Math.max(0, this.speedIndex + d))]); }
  step(n) {
    this.pause();
    const run = this.runs[0];
    run.locate(this.t);
    const row = n < 0 && run.frac > 0 ? run.row + 1 + n : run.row + n;
    this.seek(run.t[Math.min(run.rows - 1, Math.max(0, row))]);
  }
  jump(dir) { const m = this.timeline.nextMark(this.t, dir); if (m) { this.pause(); this.seek(m.t); } }
  toggleHelp() { const h = this.el("help"); h.hidden = !h.hidden; }
  setFollow(on) { this.follow = on; this.el("follow").checked = on; this.dirty = true; }
  unfollow() { if (this.follow) { this.cam.cx = this.scenes[0].cx; this.setFollow(false); } }
  target() { return this.selected >= 0 ? this.selected : this.firstVR; }

  home() {
    const road = this.runs[0].road, s = this.scenes[0], b = road.bounds;
    this.cam.scale = Math.max(s.w / (road.focus[1] - road.focus[0]), 0.55 * s.h / (b[3] - b[2]));
    this.cam.cx = 0.5 * (road.focus[0] + road.focus[1]); this.cam.cy = 0.5 * (b[2] + b[3]);
    this.setFollow(this.target() >= 0);
  }

  whole() {
    const b = this.runs[0].road.bounds, s = this.scenes[0];
    this.setFollow(false);
    this.cam.scale = s.w / (b[1] - b[0]); this.cam.cx = 0.5 * (b[0] + b[1]); this.cam.cy = 0.5 * (b[2] + b[3]);
  }

  resize() {
    for (const s of this.scenes) s.resize();
    this.timeline.resize(); this.overview.resize(); this.chart.resize();
  }

  // --------------------------------------------------------------- vehicles and panels
  select(id) { this.selected = id; this.chart.set(this.runs, id); this.dirty = true; }
  setHover(h) {
    const same = (h === null && this.hover === null) || (h && this.hover && h.run === this.hover.run && h.id === this.hover.id);
    if (!same) { this.hover = h; this.dirty = true; }
  }

  panelText(run, id) {
    if (id < 0) return "hover over or click a vehicle";
    const r = this.runs[run], idx = r.cell(id);
    const head = "vehicle " + id + " · " + (HC.KIND_NAMES[r.kind[id]] || "?") + " · " + r.title;
    if (idx < 0) return head + "\nnot on the road at t = " + this.t.toFixed(2) + " s";
    const k = r.cmdOf[id], plan = r.rolePlan[id];
    const vr = r.roleVR[id], of = r.roleOf[id] > 0 && vr >= 0 ? " of VR " + vr : "";
    const name = HC.ROLE_NAMES[r.roleOf[id]];
    const role = r.roleOf[id] < 0 ? "–" : name === "STALLED" ?
      "STALLED (a broken-down car no controller plans for)" : name + of +
      (plan >= 0 ? " of plan " + (plan + 1) : " at VR's control-zone entry");
    return [head,
      "t " + this.t.toFixed(2) + " s · x " + r.x[idx].toFixed(2) + " m · lane " + r.lane[idx],
      "speed " + (r.v[idx] * r.vStep).toFixed(2) + " m/s · acceleration " + (r.a[idx] * r.aStep).toFixed(2) + " m/s²",
      "role " + role + " · commanded: " +
        (r.merges ? "not recorded" : k >= 0 ? "yes, " + r.commanded.what[k] : "no")].join("\n");
  }

  liveText(run) {
    const p = run.livePlan();
    if (!p) return run.plans.length ? "no live plan" : run.note;
    return "live plan " + (p.index + 1) + "/" + run.plans.length + " · t0 " + p.t0.toFixed(1) + " s · " +
      p.mode + " · VR " + (p.sequence === "ahead" ? "ahead of" : "behind") + " VMC · Eq. 19: " + (p.eq19_branch || "–") + " · " +
      HC.fmt(p.decision_ms, 1) + " ms" + (p.merge_x !== null ? " · merge at x = " + p.merge_x.toFixed(0) + " m" : "");
  }

  // ------------------------------------------------------------------------ frames
  tick(now) {
    if (this.playing) {
      this.t += Math.min(0.25, (now - this.last) / 1000) * HC.SPEEDS[this.speedIndex];
      if (this.t >= this.tMax) { this.t = this.tMax; this.pause(); }
      this.dirty = true;
    }
    this.last = now;
    if (this.dirty) this.render();
    requestAnimationFrame((n) => this.tick(n));
  }

  render() {
    this.dirty = false; this.frames++;
    for (const run of this.runs) run.frame(this.t);
    const target = this.target();
    for (const s of this.scenes) {
      s.scale = this.cam.scale; s.cy = this.cam.cy; s.cx = this.cam.cx;
      const c = this.follow ? s.run.drawnColumn(target) : -1;
      if (c >= 0) s.cx = s.run.dx[c];
      if (this.follow && s.run.index === 0) this.cam.cx = s.cx;
      s.draw(this);
    }
    this.overview.draw(this.scenes[0]);
    this.timeline.draw(this.t);
    this.chart.draw(this.t);
    this.text(this.el("clock"), "t = " + this.t.toFixed(2) + " s / " + this.tMax.toFixed(1) + " s");
    this.runs.forEach((run, k) => {
      this.text(this.liveBoxes[k], this.liveText(run));
      const p = run.livePlan(), rows = this.planRows[k];
      if (p && !rows[p.index].classList.contains("live")) {  // the live plan changed: show it
        const tr = rows[p.index], box = tr.closest(".plans");
        box.scrollTop = tr.offsetTop + tr.closest("table").offsetTop - box.clientHeight / 2;
      }
      const key = run.live.join(",");
      if (key !== this.liveKeys[k]) {
        rows.forEach((tr, j) => tr.classList.toggle("live", run.live.includes(j)));
        this.liveKeys[k] = key;
      }
    });
    const h = this.hover, all = this.runs.map((r) => this.panelText(r.index, this.selected));
    this.text(this.el("panel"), h ? this.panelText(h.run, h.id) : this.selected < 0 ? all[0] : all.join("\n\n"));
  }

  // Set an element's text only when it changed (a change costs the page a layout).
  text(el, value) { if (el.textContent !== value) el.textContent = value; }
};

HC.api = function (app) {
  const drawn = (id, r) => {
    const run = app.runs[r], c = run.drawnColumn(id);
    if (c < 0) return null;
    const s = app.scenes[r], x = run.dx[c], y = run.dy[c], h = run.dh[c], L = run.length[id], W = run.width[id];
    const cs = Math.cos(h), sn = Math.sin(h), hw = W / 2;
    const corners = [[x + hw * sn, y - hw * cs], [x - hw * sn, y + hw * cs],
      [x - L * cs - hw * sn, y - L * sn + hw * cs], [x - L * cs + hw * sn, y - L * sn - hw * cs]];
    const mx = x - 0.5 * L * cs, my = y - 0.5 * L * sn, px = s.sx(mx), py = s.sy(my);
    return { id, run: r, x, y, heading: h, length: L, width: W, corners,
      screen: { x: px, y: py }, onCanvas: px >= 0 && px < s.w && py >= 0 && py < s.h };
  };
  return {
    ready: true,
    seek(t) { app.seek(t); app.render(); return app.t; },
    time() { return app.t; },
    range() { return [app.tMin, app.tMax]; },
    play() { app.play(); }, pause() { app.pause(); app.render(); }, playing() { return app.playing; },
    setSpeed(s) { app.setSpeed(s); return HC.SPEEDS[app.speedIndex]; },
    speed() { return HC.SPEEDS[app.speedIndex]; },
    step(n) { app.step(n); app.render(); return app.t; },
    runs() { return app.runs.map((r) => r.title); },
    keyVehicle() { return app.firstVR; },
    vehicleAt(id, run = 0) { return drawn(id, run); },
    hover(id, run = 0) { app.setHover(id >= 0 ? { run, id } : null); app.render(); return app.el("panel").textContent; },
    select(id) { app.select(id); app.render(); },
    panelText() { return app.el("panel").textContent; },
    livePlan(run = 0) {
      const p = app.runs[run].livePlan();
      if (!p) return null;
      const { ghosts, merge_path, ...record } = p;
      return record;
    },
    liveText(run = 0) { return app.liveBoxes[run].textContent; },
    view() { return { cx: app.cam.cx, cy: app.cam.cy, scale: app.cam.scale, follow: app.follow }; },
    setView(v) {
      if ("follow" in v) app.setFollow(Boolean(v.follow));
      for (const k of ["cx", "cy", "scale"]) if (k in v) app.cam[k] = Number(v[k]);
      app.render(); return this.view();
    },
    home() { app.home(); app.render(); }, whole() { app.whole(); app.render(); },
    pixel(run, x, y) {
      const s = app.scenes[run];
      return Array.from(s.ctx.getImageData(Math.round(x * s.dpr), Math.round(y * s.dpr), 1, 1).data);
    },
    // Mean, 95th percentile and largest time [ms] to draw a frame, over `frames` frames of
    // playback at the current speed, each flushed to pixels before the next.
    benchmark(frames = 120) {
      const times = [];
      for (let k = 0; k < frames; k++) {
        app.seek(app.tMin + ((k / 60) * HC.SPEEDS[app.speedIndex]) % (app.tMax - app.tMin));
        const start = performance.now();
        app.render();
        for (const s of app.scenes) s.ctx.getImageData(0, 0, 1, 1);
        times.push(performance.now() - start);
      }
      times.sort((a, b) => a - b);
      return { frames, mean: times.reduce((a, b) => a + b, 0) / frames,
        p95: times[Math.floor(0.95 * (frames - 1))], max: times[frames - 1] };
    },
    frames() { return app.frames; },
  };
};

window.addEventListener("DOMContentLoaded", () => {
  const data = JSON.parse(document.getElementById("replay-data").textContent);
  const app = new HC.App(data);
  window.hcomcReplay = HC.api(app);
});
