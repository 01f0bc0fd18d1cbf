// springlab's lab page (docs/browser-lab.md): panels running one built-in
// scene under different integrators, in step, drawn on 2-D canvases:
// springs and element edges as lines, rigid bodies as shaded surfaces,
// fluids as dots coloured by speed, contact planes as a floor. The
// physics is the C++ core compiled to WebAssembly (web/lab_api.cc); this
// file only draws, reads the controls and decides how many steps each frame
// takes. Its API, window.springlab, is what the tests drive.
"use strict";

(function () {
  const DT_MIN = 1e-5, DT_MAX = 1e-1;    // the dt slider's ends [s]
  const STEP_BUDGET_MS = 10;             // of a 16.7 ms frame, for stepping all panels
                                         // (drawing two cloth 32 panels takes ~4 ms more)
  const PLOT_SAMPLES = 600;              // energy samples kept per panel
  const VIEW_W = 440, VIEW_H = 360, PLOT_H = 90;
  const COLORS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd"];
  // Where a scene chosen from the menu starts (the rest keep the current
  // dt and methods): the box scenes at a frame step under implicit Euler,
  // whose contacts between bodies hold there (docs/physics.md "Contact
  // between bodies"), beside BDF2.
  const SCENE_STARTS = {
    "box-pile": { dt: 1 / 60, integrators: ["implicit-euler", "bdf2"] },
    "box-tower": { dt: 1 / 60, integrators: ["implicit-euler", "bdf2"] },
    "box-drop": { dt: 1 / 60, integrators: ["implicit-euler", "symplectic-euler"] },
  };

  let M = null;           // the WebAssembly module
  let catalog = null;     // lab_list(): methods and scenes of this build
  const lab = {
    scene: "cloth", params: { n: 16 },
    integrators: ["symplectic-euler", "implicit-euler"],
    dt: 0.0005, substeps: 0, iterations: 0,
    paused: false, panels: [],
    view: null,           // projection shared by the panels
    drag: null,           // {particle, depth}
    speedMax: 0,          // the fluid colours' scale: the fastest particle seen [m/s]
  };
  // Per half second: frames, steps taken and wanted, time in steps and in
  // drawing (where a frame's time goes), simulated and real time.
  const stats = { frames: 0, steps: 0, wanted: 0, stepMs: 0, drawMs: 0, realS: 0, simS: 0,
                  fps: 0, stepsPerFrame: 0, wantedPerFrame: 0, msPerStep: 0, stepMsPerFrame: 0,
                  drawMsPerFrame: 0, speed: 1, slowed: false, framesTotal: 0 };
  let owed = 0;           // simulated time the frames still owe [s]
  let msPerStep = null;   // measured cost of one step of every panel [ms]

  const $ = (id) => document.getElementById(id);
  const call = (name, text) => JSON.parse(M.ccall(name, "string", ["string"], [text]));
  const panelState = (id) => JSON.parse(M.ccall("lab_panel_state", "string", ["number"], [id]));

  // ------------------------------------------------------------ panels
  function panelRequest(integrator, wMax) {
    const r = { scene: lab.scene, params: lab.params, integrator: integrator };
    if (wMax !== undefined) r.w_max = wMax;  // the scene's, computed by the first panel
    if (lab.substeps > 0) r.substeps = lab.substeps;
    if (lab.iterations > 0) r.iterations = lab.iterations;
    return r;
  }

  // The largest stable dt of a method on this scene: its w h limit on the
  // undamped oscillator over the scene's highest frequency w_max (both from
  // the core: IntegratorInfo::stability_limit, max_angular_frequency).
  function dtLimit(info) {
    const m = info.integrator;
    if (m.unconditionally_stable) return Infinity;
    if (m.stability_limit === null || !(info.w_max > 0)) return NaN;
    return m.stability_limit / info.w_max;
  }

  function makePanels() {
    for (const p of lab.panels) if (p.id) M.ccall("lab_panel_delete", null, ["number"], [p.id]);
    lab.panels = [];
    const box = $("panels");
    box.innerHTML = "";
    $("error").textContent = "";
    lab.integrators.forEach((name, i) => {
      const p = { index: i, name: name, energies: [], mark: "" };
      const div = document.createElement("div");
      div.className = "panel";
      const head = document.createElement("div");
      head.className = "panel-head";
      const sel = document.createElement("select");
      for (const m of catalog.integrators) sel.add(new Option(m.name, m.name, false, m.name === name));
      sel.onchange = () => { lab.integrators[i] = sel.value; makePanels(); };
      const swatch = document.createElement("span");
      swatch.textContent = "\u25A0";
      swatch.style.color = COLORS[i % COLORS.length];
      const mark = document.createElement("span");
      mark.className = "diverged-mark";
      head.append(swatch, sel, mark);
      const view = document.createElement("canvas");
      view.className = "view"; view.width = VIEW_W; view.height = VIEW_H;
      const plot = document.createElement("canvas");
      plot.width = VIEW_W; plot.height = PLOT_H;
      const status = document.createElement("div");
      status.className = "status";
      div.append(head, view, plot, status);
      box.append(div);
      Object.assign(p, { div, view, plot, status, markEl: mark, select: sel });
      const known = lab.panels.find((q) => q.info);
      const info = call("lab_panel_new", JSON.stringify(panelRequest(name, known && known.info.w_max)));
      if (info.error) {
        p.error = info.error;
        status.innerHTML = '<span class="error"></span>';
        status.firstChild.textContent = name + ": " + info.error + remedyText(info.remedy);
      } else {
        p.id = info.id;
        p.info = info;
        p.limit = dtLimit(info);
        p.state = panelState(p.id);
        p.e0 = p.state.total;
        attachMouse(p);
      }
      lab.panels.push(p);
    });
    const first = lab.panels.find((p) => p.info);
    lab.view = first ? makeView(first) : null;
    owed = 0; msPerStep = null; lab.speedMax = 0;
    drawLimits();
    drawAll();
  }

  // Steps every live panel n steps of dt (the panels stay in step: a
  // diverged one stops, the others go on).
  function stepAll(n) {
    for (const p of lab.panels) {
      if (!p.id || p.state.status !== "completed") continue;
      M.ccall("lab_panel_step", "number", ["number", "number", "number"], [p.id, n, lab.dt]);
      p.state = panelState(p.id);
      p.energies.push([p.state.t, p.state.total]);
      if (p.energies.length > PLOT_SAMPLES) p.energies.shift();
      if (p.state.diverged_at !== null) {
        p.mark = (p.state.status === "failed" ? "failed" : "diverged") +
                 " at t = " + Number(p.state.diverged_at.toPrecision(6)) + " s";
      }
    }
  }

  // ------------------------------------------------------------ drawing
  // A fixed view: rotated (yaw, pitch) for 3-D scenes, scaled to fit the
  // first panel's initial state (and the contact planes' points) with room
  // below for what falls freely (gravity, no plane, no fluid in its box).
  function makeView(p) {
    const pos = positions(p), n = p.info.points;
    const three = p.info.dimension === 3;
    const yaw = three ? -0.5 : 0, pitch = three ? 0.35 : 0;
    const cy = Math.cos(yaw), sy = Math.sin(yaw), cp = Math.cos(pitch), sp = Math.sin(pitch);
    // World -> view: turn about y by yaw, then about x by pitch.
    const R = [[cy, 0, sy], [-sp * sy, cp, sp * cy], [-cp * sy, -sp, cp * cy]];
    const lo = [Infinity, Infinity], hi = [-Infinity, -Infinity];
    const fit = (v) => {
      for (let a = 0; a < 2; ++a) { lo[a] = Math.min(lo[a], v[a]); hi[a] = Math.max(hi[a], v[a]); }
    };
    for (let i = 0; i < n; ++i) fit(rotate(R, pos, i));
    for (const plane of p.info.planes) fit(rotate(R, plane.point, 0));
    const size = Math.max(hi[0] - lo[0], hi[1] - lo[1], 1e-3);
    const falls = p.info.gravity.some((g) => g !== 0) && p.info.planes.length === 0 &&
                  p.info.fluid.particles.length === 0;
    // A fluid stays in its box (walls included in the fit): fill the view.
    const scale = p.info.fluid.particles.length > 0
        ? Math.min(VIEW_W / (hi[0] - lo[0]), VIEW_H / (hi[1] - lo[1])) / 1.1
        : Math.min(VIEW_W, VIEW_H) / ((falls ? 2.2 : 1.3) * size);
    const cx = (lo[0] + hi[0]) / 2, cyv = (lo[1] + hi[1]) / 2 - (falls ? 0.45 * size : 0);
    return { R, scale, cx, cy: cyv, size };
  }
  function rotate(R, pos, i) {
    const x = pos[3 * i], y = pos[3 * i + 1], z = pos[3 * i + 2];
    return [R[0][0] * x + R[0][1] * y + R[0][2] * z,
            R[1][0] * x + R[1][1] * y + R[1][2] * z,
            R[2][0] * x + R[2][1] * y + R[2][2] * z];
  }
  function toScreen(v) {
    const w = lab.view;
    return [VIEW_W / 2 + (v[0] - w.cx) * w.scale, VIEW_H / 2 - (v[1] - w.cy) * w.scale];
  }
  // Screen point at view depth `depth` -> world point (R is orthonormal).
  function fromScreen(sx, sy, depth) {
    const w = lab.view, R = w.R;
    const v = [(sx - VIEW_W / 2) / w.scale + w.cx, -(sy - VIEW_H / 2) / w.scale + w.cy, depth];
    return [0, 1, 2].map((c) => R[0][c] * v[0] + R[1][c] * v[1] + R[2][c] * v[2]);
  }
  // The panel's points (particles, then the bodies' surface vertices) and
  // their speeds: views of the module's memory, valid until the next step.
  function positions(p) {
    const at = M.ccall("lab_panel_positions", "number", ["number"], [p.id]);
    return new Float64Array(M.HEAPF64.buffer, at, 3 * p.info.points);
  }
  function speeds(p) {
    const at = M.ccall("lab_panel_speeds", "number", ["number"], [p.id]);
    return new Float64Array(M.HEAPF64.buffer, at, p.info.points);
  }

  // A contact plane: a square of side 1.2 x the view's size about its
  // point, spanned by two unit tangents t1, t2 (n x t1); in a planar scene
  // the square is seen edge on, a line.
  function drawPlane(g, plane) {
    const n = plane.normal, c = plane.point, h = 0.6 * lab.view.size;
    const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                             a[0] * b[1] - a[1] * b[0]];
    const unit = (a) => { const l = Math.hypot(...a); return a.map((x) => x / l); };
    const t1 = unit(cross(n, Math.abs(n[2]) < 0.9 ? [0, 0, 1] : [1, 0, 0])), t2 = cross(n, t1);
    const corner = (a, b) => toScreen(rotate(lab.view.R,
        [0, 1, 2].map((k) => c[k] + h * (a * t1[k] + b * t2[k])), 0));
    const q = [corner(-1, -1), corner(1, -1), corner(1, 1), corner(-1, 1)];
    g.beginPath(); g.moveTo(q[0][0], q[0][1]);
    for (let k = 1; k < 4; ++k) g.lineTo(q[k][0], q[k][1]);
    g.closePath();
    g.fillStyle = "#e8e4dc"; g.fill();
    g.strokeStyle = "#a89f91"; g.lineWidth = 1.5; g.stroke();
  }

  // The bodies' surface triangles, far ones first (painter's order by mean
  // view depth), each shaded by how squarely it faces the viewer
  // (|n . view| / |n|, n its normal) and outlined in the panel's colour.
  function drawFaces(g, p, pos, sx, sy, color) {
    const f = p.info.faces;
    if (f.length === 0) return;
    const R = lab.view.R, list = [];
    for (let k = 0; k < f.length; k += 3) {
      const v = [f[k], f[k + 1], f[k + 2]].map((i) => rotate(R, pos, i));
      const e1 = [0, 1, 2].map((a) => v[1][a] - v[0][a]);
      const e2 = [0, 1, 2].map((a) => v[2][a] - v[0][a]);
      const nx = e1[1] * e2[2] - e1[2] * e2[1], ny = e1[2] * e2[0] - e1[0] * e2[2];
      const nz = e1[0] * e2[1] - e1[1] * e2[0], area = Math.hypot(nx, ny, nz);
      list.push({ k, depth: v[0][2] + v[1][2] + v[2][2],
                  light: area > 0 ? Math.abs(nz) / area : 0 });
    }
    list.sort((a, b) => a.depth - b.depth);
    g.lineWidth = 1; g.strokeStyle = color;
    for (const face of list) {
      const a = f[face.k], b = f[face.k + 1], c = f[face.k + 2];
      g.beginPath();
      g.moveTo(sx[a], sy[a]); g.lineTo(sx[b], sy[b]); g.lineTo(sx[c], sy[c]);
      g.closePath();
      g.globalAlpha = 1; g.fillStyle = "#fff"; g.fill();
      g.globalAlpha = 0.25 + 0.5 * face.light; g.fillStyle = color; g.fill();
      g.globalAlpha = 1; g.stroke();
    }
  }

  // Blue (at rest) through green and yellow to red (the fastest seen), in
  // SPEED_LEVELS steps: one path per colour.
  const SPEED_LEVELS = 24;
  const speedColor = (level) =>
      "hsl(" + Math.round(240 * (1 - level / (SPEED_LEVELS - 1))) + ",85%,45%)";

  // Screen coordinates of every point into p.sx, p.sy (kept per panel: a
  // frame allocates nothing per point).
  function project(p, pos) {
    const N = p.info.points, w = lab.view, R = w.R;
    if (!p.sx || p.sx.length !== N) { p.sx = new Float64Array(N); p.sy = new Float64Array(N); }
    const sx = p.sx, sy = p.sy, cx = VIEW_W / 2, cy = VIEW_H / 2;
    for (let i = 0; i < N; ++i) {
      const x = pos[3 * i], y = pos[3 * i + 1], z = pos[3 * i + 2];
      sx[i] = cx + (R[0][0] * x + R[0][1] * y + R[0][2] * z - w.cx) * w.scale;
      sy[i] = cy - (R[1][0] * x + R[1][1] * y + R[1][2] * z - w.cy) * w.scale;
    }
  }

  // A panel is drawn again only when what it shows changed: its state (a
  // step), the mouse's spring, the shared speed scale (paused: nothing).
  function drawPanel(p) {
    const key = [p.state ? p.state.steps : -1, p.state ? p.state.status : "", !!lab.view,
                 lab.drag ? lab.drag.screen.join() : "", lab.speedMax].join("|");
    if (p.drawn === key) return;
    p.drawn = key;
    const g = p.view.getContext("2d");
    g.clearRect(0, 0, VIEW_W, VIEW_H);
    if (!p.id || !lab.view) return;
    const pos = positions(p), n = p.info.particles;
    project(p, pos);
    const sx = p.sx, sy = p.sy;
    const color = COLORS[p.index % COLORS.length];
    for (const plane of p.info.planes) drawPlane(g, plane);
    if (!p.edgeList) p.edgeList = Int32Array.from(p.info.edges.flat());
    const e = p.edgeList;
    g.strokeStyle = color; g.globalAlpha = 0.55; g.lineWidth = 1;
    g.beginPath();
    for (let k = 0; k < e.length; k += 2) {
      g.moveTo(sx[e[k]], sy[e[k]]); g.lineTo(sx[e[k + 1]], sy[e[k + 1]]);
    }
    g.stroke();
    g.globalAlpha = 1;
    drawFaces(g, p, pos, sx, sy, color);
    const fluid = p.info.fluid.particles;
    if (fluid.length > 0) {
      // Dots of the particle spacing's size, coloured by speed on one scale
      // for all panels (the fastest particle any panel has had).
      const v = speeds(p);
      for (const i of fluid) lab.speedMax = Math.max(lab.speedMax, v[i]);
      if (!(lab.speedMax > 0)) lab.speedMax = 1e-9;
      const r = Math.max(1.5, 0.5 * p.info.fluid.spacing * lab.view.scale);
      const paths = Array.from({ length: SPEED_LEVELS }, () => new Path2D());
      for (const i of fluid) {
        const level = Math.round((SPEED_LEVELS - 1) * Math.min(1, v[i] / lab.speedMax));
        paths[level].moveTo(sx[i] + r, sy[i]);
        paths[level].arc(sx[i], sy[i], r, 0, 2 * Math.PI);
      }
      paths.forEach((path, level) => { g.fillStyle = speedColor(level); g.fill(path); });
    } else if (n > 0 && (p.info.edges.length === 0 || n <= 64)) {
      g.fillStyle = color;
      for (let i = 0; i < n; ++i) g.fillRect(sx[i] - 2, sy[i] - 2, 4, 4);
    }
    // Fixed particles: black squares, or small grey ones when many (walls).
    const many = p.info.fixed.length > 64, w = many ? 2 : 6;
    g.fillStyle = many ? "#888" : "#000";
    g.beginPath();
    for (const f of p.info.fixed) g.rect(sx[f] - w / 2, sy[f] - w / 2, w, w);
    g.fill();
    if (lab.drag) {
      const i = lab.drag.particle, c = lab.drag.screen;
      g.strokeStyle = "#e67e22"; g.lineWidth = 2;
      g.beginPath(); g.moveTo(sx[i], sy[i]); g.lineTo(c[0], c[1]); g.stroke();
    }
    if (p.state.status !== "completed") {
      g.fillStyle = "rgba(192,57,43,0.12)"; g.fillRect(0, 0, VIEW_W, VIEW_H);
    }
    if (p.markEl.textContent !== p.mark) p.markEl.textContent = p.mark;
    const s = p.state, lim = p.limit;
    // A limit of 0 (w h <= 0) is already in the stability text, which the
    // core writes from the same stability_limit: "no stable step without damping".
    const limit = lim === Infinity ? "; no step limit" :
                  Number.isNaN(lim) ? "; step limit: not one number" :
                  lim === 0 ? "" : "; dt limit " + lim.toPrecision(3) + " s";
    p.status.textContent = "t = " + s.t.toFixed(4) + " s   E = " + fmt(s.total) + " J   " +
        "(E0 " + fmt(p.e0) + ")\n" + p.info.integrator.stability_text + limit +
        (fluid.length > 0 ?
         "\ncolour: speed, blue 0 to red " + lab.speedMax.toPrecision(3) + " m/s" : "") +
        (s.failure ? "\n" + s.failure : "");
    drawPlot(p);
  }
  const fmt = (x) => (x === null ? "inf" : Math.abs(x) >= 1e4 || (Math.abs(x) < 1e-3 && x !== 0) ?
                      x.toExponential(3) : x.toFixed(4));

  // Total energy against t, the scale fitted to what is shown.
  function drawPlot(p) {
    const g = p.plot.getContext("2d");
    g.clearRect(0, 0, VIEW_W, PLOT_H);
    g.fillStyle = "#f4f4f4"; g.fillRect(0, 0, VIEW_W, PLOT_H);
    g.fillStyle = "#555"; g.font = "11px sans-serif";
    g.fillText("total energy [J]", 4, 11);
    const e = p.energies.filter((q) => q[1] !== null && Number.isFinite(q[1]));
    if (e.length < 2) return;
    let lo = Math.min(p.e0, ...e.map((q) => q[1])), hi = Math.max(p.e0, ...e.map((q) => q[1]));
    if (hi - lo < 1e-12) { hi += 0.5; lo -= 0.5; }
    const t0 = e[0][0], t1 = e[e.length - 1][0] || t0 + 1;
    const X = (t) => 4 + (VIEW_W - 8) * (t - t0) / Math.max(t1 - t0, 1e-12);
    const Y = (v) => PLOT_H - 4 - (PLOT_H - 18) * (v - lo) / (hi - lo);
    g.strokeStyle = "#aaa"; g.setLineDash([3, 3]);
    g.beginPath(); g.moveTo(4, Y(p.e0)); g.lineTo(VIEW_W - 4, Y(p.e0)); g.stroke();
    g.setLineDash([]);
    g.strokeStyle = COLORS[p.index % COLORS.length]; g.lineWidth = 1.5;
    g.beginPath();
    e.forEach((q, i) => (i ? g.lineTo(X(q[0]), Y(q[1])) : g.moveTo(X(q[0]), Y(q[1]))));
    g.stroke();
    g.fillStyle = "#555";
    g.fillText(fmt(hi), VIEW_W - 70, 11); g.fillText(fmt(lo), VIEW_W - 70, PLOT_H - 2);
  }

  function drawAll() { for (const p of lab.panels) drawPanel(p); }

  // ------------------------------------------------------------ the frame loop
  // Real time: each frame owes the simulated time that passed; it takes the
  // steps that fit in STEP_BUDGET_MS (measured cost per step), and when
  // that is fewer than owed, drops the rest and says so (slow motion).
  let last = null;
  function frame(now) {
    requestAnimationFrame(frame);
    const elapsed = last === null ? 0 : Math.min((now - last) / 1000, 0.1);
    last = now;
    if (!lab.paused && lab.panels.some((p) => p.id && p.state.status === "completed")) {
      owed += elapsed;
      const wanted = Math.floor(owed / lab.dt + 1e-9);
      const fit = msPerStep === null ? 1 : Math.max(1, Math.floor(STEP_BUDGET_MS / msPerStep));
      const n = Math.min(wanted, fit);
      owed = wanted > n ? 0 : owed - n * lab.dt;
      if (n > 0) {
        const t0 = performance.now();
        stepAll(n);
        const ms = performance.now() - t0;
        msPerStep = msPerStep === null ? ms / n : 0.8 * msPerStep + 0.2 * (ms / n);
        stats.stepMs += ms;
      }
      stats.steps += n; stats.wanted += wanted; stats.simS += n * lab.dt;
    }
    stats.frames += 1; stats.framesTotal += 1; stats.realS += elapsed;
    if (stats.realS >= 0.5) {
      stats.fps = stats.frames / stats.realS;
      stats.stepsPerFrame = stats.steps / stats.frames;
      stats.wantedPerFrame = stats.wanted / stats.frames;
      stats.msPerStep = stats.steps ? stats.stepMs / stats.steps : 0;
      stats.stepMsPerFrame = stats.stepMs / stats.frames;
      stats.drawMsPerFrame = stats.drawMs / stats.frames;
      stats.speed = stats.simS / stats.realS;
      stats.slowed = stats.steps < stats.wanted;
      showSpeed();
      Object.assign(stats, { frames: 0, steps: 0, wanted: 0, stepMs: 0, drawMs: 0,
                             realS: 0, simS: 0 });
    }
    const t0 = performance.now();
    drawAll();
    stats.drawMs += performance.now() - t0;
  }

  function showSpeed() {
    const el = $("speed");
    if (lab.paused) { el.textContent = "paused"; el.className = "speed"; return; }
    const per = stats.stepsPerFrame.toFixed(1) + " steps/frame, " + stats.fps.toFixed(0) + " frames/s";
    if (stats.slowed) {
      el.textContent = "slow motion: " + (100 * stats.speed).toFixed(0) + "% of real time (" + per +
                       " of " + stats.wantedPerFrame.toFixed(1) + " wanted)";
      el.className = "speed slow";
    } else {
      el.textContent = "real time (" + per + ")";
      el.className = "speed";
    }
  }

  // ------------------------------------------------------------ controls
  const sliderToDt = (s) => DT_MIN * Math.pow(DT_MAX / DT_MIN, s / 1000);
  const dtToSlider = (dt) => 1000 * Math.log(dt / DT_MIN) / Math.log(DT_MAX / DT_MIN);

  function setDt(dt) {
    if (!(dt > 0) || !Number.isFinite(dt)) return;
    lab.dt = dt;
    $("dt").value = dt.toPrecision(4);
    $("dt-slider").value = Math.round(dtToSlider(dt));
    owed = 0; msPerStep = null;
  }

  // Each panel's dt limit marked on the slider, in its colour.
  function drawLimits() {
    const box = $("dt-box");
    for (const el of [...box.querySelectorAll(".limit-mark, .limit-label")]) el.remove();
    const lines = [];
    for (const p of lab.panels) {
      if (!p.info) continue;
      const color = COLORS[p.index % COLORS.length], lim = p.limit;
      if (Number.isFinite(lim) && lim > 0) {
        const x = Math.max(0, Math.min(1, dtToSlider(lim) / 1000)) * box.clientWidth;
        const mark = document.createElement("div");
        mark.className = "limit-mark"; mark.style.left = x + "px"; mark.style.background = color;
        const label = document.createElement("div");
        label.className = "limit-label"; label.style.left = x + "px"; label.style.color = color;
        label.textContent = p.name;
        box.append(mark, label);
      }
      lines.push(p.name + ": " + (lim === Infinity ? "stable at every dt" :
                 Number.isNaN(lim) ? "no single limit" :
                 lim === 0 ? "unstable at every dt without damping" :
                 "dt <= " + lim.toPrecision(4) + " s (w h <= " +
                 p.info.integrator.stability_limit.toPrecision(4) + ", w_max = " +
                 p.info.w_max.toPrecision(5) + " rad/s)"));
    }
    $("dt-limits").textContent = "theoretical limits (undamped, linearized at the start): " +
                                 lines.join(";  ");
  }

  // A refusal's remedy (the scene setting that makes the pairing work), told
  // as the command line tells it, where this scene has that parameter.
  function remedyText(remedy) {
    const scene = catalog.scenes.find((s) => s.name === lab.scene);
    if (!remedy || !scene || !scene.parameters.some((q) => q.name === remedy.field)) return "";
    return " (for this scene: " + remedy.field + " = " + remedy.value +
           (remedy.meaning ? " (" + remedy.meaning + ")" : "") + ")";
  }

  function showSceneParams() {
    const scene = catalog.scenes.find((s) => s.name === lab.scene);
    const box = $("scene-params");
    box.innerHTML = "";
    $("scene-description").textContent = scene.description;
    for (const par of scene.parameters) {
      const label = document.createElement("label");
      label.title = par.meaning;
      const input = document.createElement("input");
      input.type = "number"; input.step = "any"; input.dataset.param = par.name;
      input.value = par.name in lab.params ? lab.params[par.name] : par.default;
      label.append(par.name + " ", input);
      box.append(label);
    }
  }
  function readSceneParams() {
    const scene = catalog.scenes.find((s) => s.name === lab.scene);
    const params = {};
    for (const input of $("scene-params").querySelectorAll("input")) {
      const par = scene.parameters.find((q) => q.name === input.dataset.param);
      if (Number(input.value) !== par.default) params[par.name] = input.value;
    }
    return params;
  }

  function attachMouse(p) {
    const pick = (ev) => {
      const r = p.view.getBoundingClientRect();
      return [ev.clientX - r.left, ev.clientY - r.top];
    };
    p.view.onmousedown = (ev) => {
      const [sx, sy] = pick(ev), pos = positions(p);
      const fixed = new Set(p.info.fixed);
      let best = -1, bestD = 400;  // within 20 px
      for (let i = 0; i < p.info.particles; ++i) {
        if (fixed.has(i)) continue;
        const q = toScreen(rotate(lab.view.R, pos, i));
        const d = (q[0] - sx) ** 2 + (q[1] - sy) ** 2;
        if (d < bestD) { bestD = d; best = i; }
      }
      if (best < 0) return;
      lab.drag = { particle: best, depth: rotate(lab.view.R, pos, best)[2], screen: [sx, sy] };
      moveCursor(sx, sy);
    };
    p.view.onmousemove = (ev) => { if (lab.drag) moveCursor(...pick(ev)); };
  }
  // Every panel's particle pulled toward the same point: the same input.
  function moveCursor(sx, sy) {
    lab.drag.screen = [sx, sy];
    const c = fromScreen(sx, sy, lab.drag.depth);
    for (const p of lab.panels) {
      if (p.id) M.ccall("lab_panel_grab", "number", ["number", "number", "number", "number", "number"],
                        [p.id, lab.drag.particle, c[0], c[1], c[2]]);
    }
  }
  function release() {
    if (!lab.drag) return;
    lab.drag = null;
    for (const p of lab.panels) if (p.id) M.ccall("lab_panel_release", null, ["number"], [p.id]);
  }

  function setPaused(paused) {
    lab.paused = paused;
    $("pause").textContent = paused ? "play" : "pause";
    showSpeed();
  }

  function wireControls() {
    const sceneSel = $("scene");
    for (const s of catalog.scenes) sceneSel.add(new Option(s.name, s.name, false, s.name === lab.scene));
    sceneSel.onchange = () => {
      lab.scene = sceneSel.value;
      lab.params = {};
      const start = SCENE_STARTS[lab.scene];
      if (start) {
        lab.integrators = start.integrators.slice();
        $("panel-count").value = String(lab.integrators.length);
        setDt(start.dt);
      }
      showSceneParams();
      makePanels();
    };
    showSceneParams();
    $("apply").onclick = () => { lab.params = readSceneParams(); makePanels(); };
    $("dt-slider").oninput = (ev) => setDt(sliderToDt(Number(ev.target.value)));
    $("dt").onchange = (ev) => setDt(Number(ev.target.value));
    $("substeps").onchange = (ev) => { lab.substeps = Math.max(0, Math.round(ev.target.value)); makePanels(); };
    $("iterations").onchange = (ev) => { lab.iterations = Math.max(0, Math.round(ev.target.value)); makePanels(); };
    $("pause").onclick = () => setPaused(!lab.paused);
    $("step").onclick = () => { setPaused(true); stepAll(1); drawAll(); };
    $("reset").onclick = () => makePanels();
    $("panel-count").onchange = (ev) => {
      const n = Number(ev.target.value);
      const more = ["xpbd", "projective-dynamics", "vbd", "rk4", "verlet"];
      while (lab.integrators.length < n) lab.integrators.push(more[lab.integrators.length % more.length]);
      lab.integrators.length = n;
      makePanels();
    };
    window.addEventListener("mouseup", release);
    setDt(lab.dt);
  }

  function showMethods() {
    const rows = catalog.integrators.map((m) =>
      "<tr><td>" + m.name + "</td><td>order " + m.order + "</td><td>" +
      (m.implicit ? "implicit" : "explicit") + "</td><td>" + escapeHtml(m.stability_text) + "</td></tr>");
    $("methods-list").innerHTML = "<p>" + catalog.integrators.length + " methods (" +
        (catalog.build.sundials ? "with" : "without") + " SUNDIALS's adaptive methods; sparse " +
        "Cholesky: " + escapeHtml(catalog.build.positive_definite_solver) + ")</p><table>" +
        rows.join("") + "</table>";
    $("build-line").textContent = "This build: " + catalog.integrators.length + " methods, " +
                                  catalog.scenes.length + " scenes (see list below).";
  }
  const escapeHtml = (s) => s.replace(/[&<>]/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;" })[c]);

  // ------------------------------------------------------------ the API
  function panelStates() {
    return lab.panels.map((p) => ({
      integrator: p.name, error: p.error || null,
      t: p.state ? p.state.t : null, steps: p.state ? p.state.steps : null,
      status: p.state ? p.state.status : null,
      diverged_at: p.state ? p.state.diverged_at : null,
      failure: p.state ? p.state.failure : null,
      mark: p.markEl.textContent, total: p.state ? p.state.total : null,
      w_max: p.info ? p.info.w_max : null, dt_limit: p.info ? p.limit : null,
    }));
  }

  const api = {
    list: () => catalog,
    // One run, as `springlab run SCENE -p ... --integrator I --dt DT --t-end T`:
    // {scene, params, integrator, dt, t_end | steps, substeps, iterations}.
    run: (request) => call("lab_run", JSON.stringify(request)),
    setScene: (name, params) => {
      lab.scene = name; lab.params = Object.assign({}, params || {});
      $("scene").value = name; showSceneParams(); makePanels();
    },
    setIntegrators: (names) => {
      lab.integrators = names.slice();
      $("panel-count").value = String(Math.min(4, Math.max(2, names.length)));
      makePanels();
    },
    setIntegrator: (i, name) => { lab.integrators[i] = name; makePanels(); },
    setDt: (dt) => setDt(dt),
    setOptions: (o) => {
      if ("substeps" in o) $("substeps").value = lab.substeps = o.substeps;
      if ("iterations" in o) $("iterations").value = lab.iterations = o.iterations;
      makePanels();
    },
    pause: () => setPaused(true),
    play: () => setPaused(false),
    step: (n) => { stepAll(n || 1); drawAll(); return panelStates(); },
    reset: () => makePanels(),
    state: () => panelStates(),
    stats: () => Object.assign({}, stats),
    // Pull scene particle i of every panel toward world point c (null: let go).
    drag: (i, c) => {
      if (i === null) { release(); return; }
      for (const p of lab.panels) {
        if (p.id) M.ccall("lab_panel_grab", "number", ["number", "number", "number", "number", "number"],
                          [p.id, i, c[0], c[1], c[2]]);
      }
    },
  };

  window.springlab = Object.assign({ ready: null }, api);
  window.springlab.ready = createSpringlab().then((module) => {
    M = module;
    catalog = call("lab_list", "");
    showMethods();
    wireControls();
    makePanels();
    requestAnimationFrame(frame);
    document.body.dataset.labReady = "1";
    return true;
  }).catch((e) => {
    $("error").textContent = "the WebAssembly module failed to start: " + e;
    throw e;
  });
})();
