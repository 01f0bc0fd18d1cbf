// The report's player (report/springlab_report/kinds/motion.py): plays the
// frames embedded in the page, one panel per integrator, on one clock and
// one camera. Written for springlab; no library, no network.
//
// Each <figure class="player"> holds its data as JSON (frames as base64
// little-endian int16, frame x particle x xyz, each frame on its own grid
// q: position = lo + (value + 32767) step, -32768 for a non-finite one). While it plays it counts
// the frames it drew (data-frames-drawn) and, from the canvas pixels, the
// panels that show something (data-nonempty-panels of data-panels): what
// tests/report/check_report.py reads. `index.html#player-t=0.5` opens every
// player paused at t = 0.5 s (for screenshots). A player scrolled off screen
// pauses its clock after that first check.
(function () {
  if (window.springlabPlayer) return;
  window.springlabPlayer = true;

  function decode(b64, q, n) {
    var s = atob(b64), view = new DataView(new ArrayBuffer(s.length));
    for (var i = 0; i < s.length; i++) view.setUint8(i, s.charCodeAt(i));
    var out = new Float32Array(s.length / 2);
    for (var k = 0; k < out.length; k++) {
      var v = view.getInt16(2 * k, true), f = Math.floor(k / (3 * n)), a = k % 3;
      out[k] = v === -32768 ? NaN : q[6 * f + a] + (v + 32767) * q[6 * f + 3 + a];
    }
    return out;
  }

  // A fluid's speeds (data.fluid, panel.speed: base64 bytes, frame x fluid
  // particle, 0..255 of data.speed_max) and the colour of a level: blue
  // (slow) through green and yellow to red (fast).
  function bytes(b64) {
    var s = atob(b64), out = new Uint8Array(s.length);
    for (var i = 0; i < s.length; i++) out[i] = s.charCodeAt(i);
    return out;
  }
  function speedColour(level) {
    return 'hsl(' + Math.round(240 * (1 - level / 255)) + ',85%,45%)';
  }

  // Orthographic camera. A planar scene is seen face on (x right, the
  // gravity axis up); a 3-D one turned 30 degrees about the vertical and
  // looked at 20 degrees from above. With (a, b, c) the two horizontal axes
  // and the vertical, the screen axes are u = (cy, -sy, 0) and
  // v = (sy sp, cy sp, cp); the third value returned is the depth toward the
  // viewer along u x v = (-sy cp, -cy cp, sp) (larger: nearer).
  function camera(data) {
    var up = data.up, h = [0, 1, 2].filter(function (a) { return a !== up; });
    var yaw = data.planar ? 0 : 0.52, pitch = data.planar ? 0 : 0.35;
    var cy = Math.cos(yaw), sy = Math.sin(yaw), cp = Math.cos(pitch), sp = Math.sin(pitch);
    return function (x, y, z) {
      var p = [x, y, z], a = p[h[0]], b = p[h[1]], c = p[up];
      return [cy * a - sy * b, c * cp + (sy * a + cy * b) * sp, -sy * cp * a - cy * cp * b + sp * c];
    };
  }

  // The bodies' surface triangles (data.faces) as filled polygons, far ones
  // first (painter's order by mean depth), each shaded by how squarely it
  // faces the viewer (|n . view| of its projected area over its area) and
  // outlined in the panel's colour. A frame past the blow-up bound is only
  // outlined (its huge triangles would fill the panel).
  function drawFaces(g, faces, X, base, screen, project, colour, outline) {
    if (!faces || !faces.length) return;
    var list = [];
    faces.forEach(function (f) {
      var pts = [], depth = 0, ok = true, P = [];
      for (var m = 0; m < 3; m++) {
        var i = base + 3 * f[m], q = project(X[i], X[i + 1], X[i + 2]);
        if (!isFinite(q[0] + q[1] + q[2])) { ok = false; break; }
        pts.push(screen(X[i], X[i + 1], X[i + 2]));
        P.push([X[i], X[i + 1], X[i + 2]]);
        depth += q[2];
      }
      if (!ok) return;
      var e1 = [0, 1, 2].map(function (a) { return P[1][a] - P[0][a]; });
      var e2 = [0, 1, 2].map(function (a) { return P[2][a] - P[0][a]; });
      var n = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]];
      var area = Math.hypot(n[0], n[1], n[2]);
      var shown = Math.abs((pts[1][0] - pts[0][0]) * (pts[2][1] - pts[0][1]) -
                           (pts[1][1] - pts[0][1]) * (pts[2][0] - pts[0][0]));
      list.push({pts: pts, depth: depth, shade: area > 0 ? shown : 0, area: area});
    });
    var largest = list.reduce(function (m, f) { return Math.max(m, f.area > 0 ? f.shade / f.area : 0); }, 1e-30);
    list.sort(function (a, b) { return a.depth - b.depth; });
    g.lineWidth = 1; g.strokeStyle = colour;
    list.forEach(function (f) {
      var light = f.area > 0 ? f.shade / f.area / largest : 0;
      g.beginPath();
      g.moveTo(f.pts[0][0], f.pts[0][1]); g.lineTo(f.pts[1][0], f.pts[1][1]); g.lineTo(f.pts[2][0], f.pts[2][1]);
      g.closePath();
      var keep = g.globalAlpha;
      if (!outline) {
        g.fillStyle = '#fff'; g.fill();
        g.globalAlpha = keep * (0.25 + 0.5 * light); g.fillStyle = colour; g.fill();
        g.globalAlpha = keep;
      }
      g.stroke();
    });
  }

  // Unique edges of the cells (a spring, a triangle's sides, a tetrahedron's).
  function edges(cells, n) {
    var seen = {}, out = [];
    function add(i, j) {
      var k = i < j ? i * n + j : j * n + i;
      if (!seen[k]) { seen[k] = true; out.push(i, j); }
    }
    cells.forEach(function (c) {
      for (var a = 0; a < c.length; a++) {
        for (var b = a + 1; b < c.length; b++) {
          if (c.length === 3 || c.length === 4 || b === a + 1) add(c[a], c[b]);
        }
      }
    });
    return out;
  }

  function fmt(x) {
    if (x === null || x === undefined || !isFinite(x)) return '–';
    var a = Math.abs(x);
    return (a !== 0 && (a < 1e-3 || a >= 1e4)) ? x.toExponential(2) : x.toPrecision(3);
  }

  function setup(fig) {
    var data = JSON.parse(fig.querySelector('.player-data').textContent);
    var n = data.particles, project = camera(data), lines = edges(data.cells, n);
    var panels = data.panels.map(function (p, k) {
      var el = fig.querySelectorAll('.player-panel')[k];
      var good = p.energy.filter(function (e, f) { return e !== null && !p.past[f]; });
      var rel = function (e) { return p.Es ? (e - p.E0) / p.Es : 0; };
      var span = good.reduce(function (m, e) { return Math.max(m, Math.abs(rel(e))); }, 1e-3);
      return {p: p, x: decode(p.x, p.q, n), speed: p.speed ? bytes(p.speed) : null,
              view: el.querySelector('.player-view'),
              energy: el.querySelector('.player-energy'), value: el.querySelector('.player-value'),
              rel: rel, span: span};
    });
    // One scale for every panel: the box of every good frame, projected.
    var lo = data.bounds[0], hi = data.bounds[1], u0 = 1e300, u1 = -1e300, v0 = 1e300, v1 = -1e300;
    for (var c = 0; c < 8; c++) {
      var q = project(c & 1 ? hi[0] : lo[0], c & 2 ? hi[1] : lo[1], c & 4 ? hi[2] : lo[2]);
      u0 = Math.min(u0, q[0]); u1 = Math.max(u1, q[0]); v0 = Math.min(v0, q[1]); v1 = Math.max(v1, q[1]);
    }
    var W = panels[0].view.width, H = panels[0].view.height, margin = 14;
    var scale = Math.min((W - 2 * margin) / Math.max(u1 - u0, 1e-9), (H - 2 * margin) / Math.max(v1 - v0, 1e-9));
    var uc = (u0 + u1) / 2, vc = (v0 + v1) / 2;
    function screen(x, y, z) {
      var q = project(x, y, z);
      return [W / 2 + (q[0] - uc) * scale, H / 2 - (q[1] - vc) * scale];
    }
    var tEnd = data.t_end, T = 0, playing = true, drawn = 0, lastDrawn = -1, checked = false;
    var button = fig.querySelector('.player-play'), slider = fig.querySelector('.player-slider');
    var label = fig.querySelector('.player-time');

    // Each axis-aligned plane (the ground) as a grey rectangle over the
    // bounds, widened by a fifth on each side.
    function drawPlanes(g) {
      g.strokeStyle = '#999'; g.fillStyle = 'rgba(0,0,0,0.06)'; g.lineWidth = 1;
      (data.planes || []).forEach(function (pl) {
        var others = [0, 1, 2].filter(function (a) { return a !== pl.axis; });
        var a = others[0], b = others[1], corners = [[0, 0], [1, 0], [1, 1], [0, 1]];
        g.beginPath();
        corners.forEach(function (c, k) {
          var p3 = [0, 0, 0];
          p3[pl.axis] = pl.at;
          [a, b].forEach(function (ax, m) {
            var w = hi[ax] - lo[ax], pad = ax === 2 && data.planar ? 0 : 0.2 * w + 0.05;
            p3[ax] = c[m] ? hi[ax] + pad : lo[ax] - pad;
          });
          var q = screen(p3[0], p3[1], p3[2]);
          if (k === 0) g.moveTo(q[0], q[1]); else g.lineTo(q[0], q[1]);
        });
        g.closePath(); g.fill(); g.stroke();
      });
    }

    function frameAt(p, t) {
      var k = -1;
      for (var f = 0; f < p.t.length; f++) if (p.t[f] <= t + 1e-9) k = f;
      return Math.max(k, 0);
    }

    function drawPanel(s, t) {
      var p = s.p, g = s.view.getContext('2d'), k = frameAt(p, t);
      var ended = p.status !== 'completed' && t > p.t[p.t.length - 1] + 1e-9;
      g.clearRect(0, 0, W, H);
      drawPlanes(g);
      g.strokeStyle = p.colour; g.lineWidth = 1; g.globalAlpha = ended ? 0.35 : 1;
      var base = k * n * 3, X = s.x;
      g.beginPath();
      for (var e = 0; e < lines.length; e += 2) {
        var i = base + 3 * lines[e], j = base + 3 * lines[e + 1];
        var a = screen(X[i], X[i + 1], X[i + 2]), b = screen(X[j], X[j + 1], X[j + 2]);
        if (!isFinite(a[0] + a[1] + b[0] + b[1])) continue;
        g.moveTo(a[0], a[1]); g.lineTo(b[0], b[1]);
      }
      g.stroke();
      drawFaces(g, data.faces, X, base, screen, project, p.colour, p.past[k] === 1);
      if (s.speed && data.fluid) {
        var nf = data.fluid.length;
        data.fluid.forEach(function (i, j) {
          var q = screen(X[base + 3 * i], X[base + 3 * i + 1], X[base + 3 * i + 2]);
          if (!isFinite(q[0] + q[1])) return;
          g.fillStyle = speedColour(s.speed[k * nf + j]);
          g.fillRect(q[0] - 1.5, q[1] - 1.5, 3, 3);
        });
      }
      g.fillStyle = '#000';
      data.fixed.forEach(function (f) {
        var q = screen(X[base + 3 * f], X[base + 3 * f + 1], X[base + 3 * f + 2]);
        g.fillRect(q[0] - 2, q[1] - 2, 4, 4);
      });
      g.globalAlpha = 1;
      if (p.past[k] && !ended) {
        g.fillStyle = '#c00000'; g.font = '12px sans-serif';
        g.fillText('past the blow-up bound', 6, 16);
      }
      if (ended) {
        g.fillStyle = '#c00000'; g.font = 'bold 14px sans-serif';
        var what = p.status === 'diverged' ? 'diverged' : 'failed';
        g.fillText(what + ' at t = ' + fmt(p.stopped_at) + ' s', 6, 18);
        if (p.failure) {
          g.font = '11px sans-serif';
          var words = p.failure.split(' '), line = '', y = 36;
          words.forEach(function (w) {
            if (g.measureText(line + w).width > W - 12 && y < H - 8) { g.fillText(line, 6, y); line = ''; y += 13; }
            line += w + ' ';
          });
          if (y < H - 8) g.fillText(line, 6, y);
        }
      }
      // The energy change over time, and now.
      var ge = s.energy.getContext('2d'), EW = s.energy.width, EH = s.energy.height;
      ge.clearRect(0, 0, EW, EH);
      ge.strokeStyle = '#bbb'; ge.beginPath(); ge.moveTo(0, EH / 2); ge.lineTo(EW, EH / 2); ge.stroke();
      var ex = function (tt) { return 2 + (EW - 4) * tt / tEnd; };
      var ey = function (r) { return EH / 2 - (EH / 2 - 3) * Math.max(-1, Math.min(1, r / s.span)); };
      ge.strokeStyle = p.colour; ge.beginPath();
      var started = false;
      for (var f = 0; f < p.t.length; f++) {
        if (p.energy[f] === null) continue;
        var px = ex(p.t[f]), py = ey(s.rel(p.energy[f]));
        if (started) ge.lineTo(px, py); else ge.moveTo(px, py);
        started = true;
      }
      ge.stroke();
      var now = p.energy[k];
      if (now !== null) {
        ge.fillStyle = p.colour; ge.beginPath(); ge.arc(ex(p.t[k]), ey(s.rel(now)), 3, 0, 6.3); ge.fill();
      }
      ge.fillStyle = '#666'; ge.font = '10px sans-serif';
      ge.fillText('±' + fmt(s.span) + ' E_s', EW - 70, 10);
      s.value.textContent = now === null ? '' : '(E - E(0)) / E_s = ' + fmt(s.rel(now));
    }

    function draw() {
      panels.forEach(function (s) { drawPanel(s, T); });
      label.textContent = 't = ' + T.toFixed(2) + ' s';
      slider.value = String(Math.round(1000 * Math.min(T, tEnd) / tEnd));
      if (T !== lastDrawn) { drawn++; lastDrawn = T; fig.dataset.framesDrawn = String(drawn); }
      if (!checked && drawn >= 5) {
        checked = true;
        var nonempty = 0;
        panels.forEach(function (s) {
          var px = s.view.getContext('2d').getImageData(0, 0, W, H).data, any = false;
          for (var i = 3; i < px.length && !any; i += 4) any = px[i] > 0;
          if (any) nonempty++;
        });
        fig.dataset.panels = String(panels.length);
        fig.dataset.nonemptyPanels = String(nonempty);
      }
    }

    button.addEventListener('click', function () {
      playing = !playing;
      button.textContent = playing ? 'Pause' : 'Play';
    });
    slider.addEventListener('input', function () {
      playing = false; button.textContent = 'Play';
      T = tEnd * Number(slider.value) / 1000;
      draw();
    });
    var start = /player-t=([0-9.eE+-]+)/.exec(location.hash);
    if (start) { T = Math.min(tEnd, Number(start[1])); playing = false; button.textContent = 'Play'; }
    var step = 0.04;
    // Off screen, a player stops drawing once it has shown that it plays:
    // the page's players would otherwise keep a laptop's CPU busy, and a
    // headless screenshot with a time budget would never settle.
    var onScreen = true;
    if ('IntersectionObserver' in window) {
      new IntersectionObserver(function (seen) {
        onScreen = seen[seen.length - 1].isIntersecting;
      }).observe(fig);
    }
    setInterval(function () {
      if (!playing || (checked && !onScreen)) return;
      T += step;
      if (T > tEnd + 0.8) T = 0;
      draw();
    }, 40);
    draw();
    if (start) { checked = false; drawn = 5; draw(); }
  }

  window.addEventListener('load', function () {
    var figs = document.querySelectorAll('figure.player');
    for (var i = 0; i < figs.length; i++) setup(figs[i]);
  });
})();
