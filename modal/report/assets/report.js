// The report's own drawing code: zoomable line and scatter plots on canvas, and a 3D view of the
// mode shapes on the test geometry (orthographic, rotate by dragging, zoom with the wheel).
// It reads the JSON in #report-data and loads nothing from anywhere else.
(function () {
  "use strict";
  var data = JSON.parse(document.getElementById("report-data").textContent);
  var COLORS = ["#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#17becf"];
  var STAB_STYLE = [["#aaaaaa", 1.5], ["#ff7f0e", 2], ["#9467bd", 2.5], ["#1f77b4", 2.5], ["#2ca02c", 3]];
  var state = { ready: false, frames: 0, mode: 0, result: 0, playing: true, errors: [] };
  window.modalReport = state;

  function fmt(v) {
    var a = Math.abs(v);
    if (a !== 0 && (a >= 1e5 || a < 1e-3)) return v.toExponential(0).replace("e+", "e");
    return String(+v.toPrecision(4));
  }
  function linTicks(lo, hi, n) {
    var step = Math.pow(10, Math.floor(Math.log10((hi - lo) / n)));
    var err = (hi - lo) / n / step;
    step *= err >= 5 ? 5 : err >= 2 ? 2 : 1;
    var out = [];
    for (var t = Math.ceil(lo / step) * step; t <= hi + step * 1e-9; t += step) out.push(Math.abs(t) < step * 1e-9 ? 0 : t);
    return out;
  }
  function logTicks(lo, hi) {
    var out = [], a = Math.floor(Math.log10(lo)), b = Math.ceil(Math.log10(hi));
    var every = Math.max(1, Math.ceil((b - a) / 8));
    for (var e = a; e <= b; e += every) { var v = Math.pow(10, e); if (v >= lo && v <= hi) out.push(v); }
    if (out.length < 2) return linTicks(lo, hi, 4).filter(function (v) { return v > 0; });
    return out;
  }
  function setupCanvas(canvas, height) {
    var ratio = window.devicePixelRatio || 1;
    var parent = canvas.parentElement, style = window.getComputedStyle(parent);
    var width = (parent.clientWidth - parseFloat(style.paddingLeft) - parseFloat(style.paddingRight)) || 800;
    canvas.style.width = width + "px";
    canvas.style.height = height + "px";
    canvas.width = Math.round(width * ratio);
    canvas.height = Math.round(height * ratio);
    var ctx = canvas.getContext("2d");
    ctx.setTransform(ratio, 0, 0, ratio, 0, 0);
    return { ctx: ctx, w: width, h: height };
  }

  // a canvas is drawn at its container's width: draw again when that changes (a scroll bar appearing included)
  function redrawOnResize(element, draw) {
    if (!window.ResizeObserver) return;
    var width = element.clientWidth;
    new ResizeObserver(function () {
      if (element.clientWidth !== width) { width = element.clientWidth; draw(); }
    }).observe(element);
  }

  // ---------------------------------------------------------------- 2D plots
  function Plot(canvas, opts) {
    this.canvas = canvas; this.opts = opts; this.series = []; this.marks = []; this.xr = null; this.full = null;
    this.linked = [this];
    var self = this, start = null;
    canvas.addEventListener("mousedown", function (e) { start = e.offsetX; });
    canvas.addEventListener("mousemove", function (e) {
      if (start === null) return;
      self.draw();
      var ctx = self.ctx; ctx.fillStyle = "rgba(31,119,180,0.15)";
      ctx.fillRect(Math.min(start, e.offsetX), self.box.t, Math.abs(e.offsetX - start), self.box.h);
    });
    canvas.addEventListener("mouseup", function (e) {
      if (start === null) return;
      var a = self.toX(Math.min(start, e.offsetX)), b = self.toX(Math.max(start, e.offsetX));
      var wide = Math.abs(e.offsetX - start) > 3;
      start = null;
      if (wide) self.linked.forEach(function (p) { p.xr = [a, b]; p.draw(); });
      else self.draw();
    });
    canvas.addEventListener("mouseleave", function () { if (start !== null) { start = null; self.draw(); } });
    canvas.addEventListener("dblclick", function () { self.linked.forEach(function (p) { p.xr = null; p.draw(); }); });
    redrawOnResize(canvas.parentElement, function () { self.draw(); });
  }
  Plot.prototype.set = function (series, marks) {
    this.series = series; this.marks = marks || [];
    var lo = Infinity, hi = -Infinity;
    series.forEach(function (s) { s.x.forEach(function (v) { if (v !== null) { lo = Math.min(lo, v); hi = Math.max(hi, v); } }); });
    this.full = lo < hi ? [lo, hi] : [lo - 1, hi + 1];
    this.draw();
  };
  Plot.prototype.toX = function (px) { var r = this.xr || this.full; return r[0] + (px - this.box.l) / this.box.w * (r[1] - r[0]); };
  Plot.prototype.fromX = function (x) { var r = this.xr || this.full; return this.box.l + (x - r[0]) / (r[1] - r[0]) * this.box.w; };
  Plot.prototype.yRange = function (axis, log) {
    var r = this.xr || this.full, lo = Infinity, hi = -Infinity;
    this.series.forEach(function (s) {
      if ((s.axis || "y") !== axis) return;
      for (var i = 0; i < s.x.length; i++) {
        var x = s.x[i], y = s.y[i];
        if (y === null || x < r[0] || x > r[1] || (log && !(y > 0))) continue;
        lo = Math.min(lo, y); hi = Math.max(hi, y);
      }
    });
    if (!(lo <= hi)) return log ? [1e-3, 1] : [0, 1];
    if (this.opts[axis + "fixed"]) return this.opts[axis + "fixed"];
    if (log) { if (hi / lo < 10) { lo /= 3; hi *= 3; } return [lo / 1.5, hi * 1.5]; }
    var pad = (hi - lo) * 0.05 || 1; return [lo - pad, hi + pad];
  };
  Plot.prototype.draw = function () {
    var o = this.opts, g = setupCanvas(this.canvas, o.height || 240), ctx = g.ctx;
    this.ctx = ctx;
    var right = o.y2label ? 62 : 14;
    var box = this.box = { l: 66, t: 10, w: g.w - 66 - right, h: (o.height || 240) - 10 - 40 };
    ctx.fillStyle = "#fff"; ctx.fillRect(0, 0, g.w, g.h);
    if (!this.full) return;
    var xr = this.xr || this.full, self = this;
    var yr = this.yRange("y", o.ylog), y2r = o.y2label ? this.yRange("y2", o.y2log) : null;
    function my(v, range, log) {
      var a = log ? Math.log10(range[0]) : range[0], b = log ? Math.log10(range[1]) : range[1];
      var t = ((log ? Math.log10(v) : v) - a) / (b - a);
      return box.t + box.h * (1 - t);
    }
    ctx.font = "11px sans-serif"; ctx.strokeStyle = "#e5e5e5"; ctx.fillStyle = "#333"; ctx.lineWidth = 1;
    ctx.textAlign = "center";
    linTicks(xr[0], xr[1], Math.max(3, Math.floor(box.w / 90))).forEach(function (t) {
      var x = self.fromX(t); ctx.beginPath(); ctx.moveTo(x, box.t); ctx.lineTo(x, box.t + box.h); ctx.stroke();
      ctx.fillText(fmt(t), x, box.t + box.h + 14);
    });
    ctx.fillText(o.xlabel || "", box.l + box.w / 2, box.t + box.h + 30);
    ctx.textAlign = "right";
    (o.ylog ? logTicks(yr[0], yr[1]) : linTicks(yr[0], yr[1], 4)).forEach(function (t) {
      var y = my(t, yr, o.ylog); ctx.beginPath(); ctx.moveTo(box.l, y); ctx.lineTo(box.l + box.w, y); ctx.stroke();
      ctx.fillText(fmt(t), box.l - 4, y + 4);
    });
    if (y2r) {
      ctx.textAlign = "left";
      (o.y2log ? logTicks(y2r[0], y2r[1]) : linTicks(y2r[0], y2r[1], 4)).forEach(function (t) {
        ctx.fillText(fmt(t), box.l + box.w + 4, my(t, y2r, o.y2log) + 4);
      });
    }
    ctx.save(); ctx.translate(12, box.t + box.h / 2); ctx.rotate(-Math.PI / 2); ctx.textAlign = "center";
    ctx.fillText(o.ylabel || "", 0, 0); ctx.restore();
    if (y2r) { ctx.save(); ctx.translate(g.w - 8, box.t + box.h / 2); ctx.rotate(Math.PI / 2); ctx.textAlign = "center";
      ctx.fillText(o.y2label, 0, 0); ctx.restore(); }
    ctx.save(); ctx.beginPath(); ctx.rect(box.l, box.t, box.w, box.h); ctx.clip();
    this.marks.forEach(function (m) {
      var x = self.fromX(m.x); ctx.strokeStyle = m.color; ctx.globalAlpha = 0.5; ctx.beginPath();
      ctx.moveTo(x, box.t); ctx.lineTo(x, box.t + box.h); ctx.stroke(); ctx.globalAlpha = 1;
    });
    this.series.forEach(function (s) {
      var range = (s.axis || "y") === "y" ? yr : y2r, log = (s.axis || "y") === "y" ? o.ylog : o.y2log;
      ctx.strokeStyle = ctx.fillStyle = s.color; ctx.lineWidth = s.width || 1.2;
      if (s.mode === "dots") {
        var r = s.size || 1.5;
        for (var i = 0; i < s.x.length; i++) {
          if (s.y[i] === null || (log && !(s.y[i] > 0))) continue;
          if (s.colors) ctx.fillStyle = s.colors[i];
          ctx.fillRect(self.fromX(s.x[i]) - r, my(s.y[i], range, log) - r, 2 * r, 2 * r);
        }
        return;
      }
      ctx.beginPath(); var pen = false;
      for (var j = 0; j < s.x.length; j++) {
        var y = s.y[j];
        if (y === null || (log && !(y > 0))) { pen = false; continue; }
        var px = self.fromX(s.x[j]), py = my(y, range, log);
        if (pen) ctx.lineTo(px, py); else ctx.moveTo(px, py);
        pen = true;
      }
      ctx.stroke();
    });
    ctx.restore();
    ctx.strokeStyle = "#888"; ctx.strokeRect(box.l, box.t, box.w, box.h);
    var lx = box.l + 8, ly = box.t + 14;
    ctx.textAlign = "left";
    this.series.forEach(function (s) {
      if (!s.label) return;
      ctx.fillStyle = s.color; ctx.fillRect(lx, ly - 7, 12, 3); ctx.fillStyle = "#333";
      ctx.fillText(s.label, lx + 16, ly - 2); lx += ctx.measureText(s.label).width + 32;
    });
  };

  // ---------------------------------------------------------------- FRF section
  function setupFRF() {
    var frf = data.frf; if (!frf) return;
    var select = document.getElementById("frf-channel");
    frf.entries.forEach(function (e, i) { var o = document.createElement("option"); o.value = i; o.textContent = e.label; select.appendChild(o); });
    var unit = frf.units;
    var mag = new Plot(document.getElementById("frf-mag"), { ylog: true, ylabel: "|H| [" + unit + "]", xlabel: "frequency [Hz]", height: 260 });
    var phase = new Plot(document.getElementById("frf-phase"), { ylabel: "phase [deg]", xlabel: "frequency [Hz]", height: 180, yfixed: [-180, 180] });
    var cohCanvas = document.getElementById("frf-coherence");
    var coh = cohCanvas ? new Plot(cohCanvas, { ylabel: "coherence", xlabel: "frequency [Hz]", height: 150, yfixed: [0, 1.05] }) : null;
    var linked = [mag, phase].concat(coh ? [coh] : []);
    linked.forEach(function (p) { p.linked = linked; });
    var marks = [];
    frf.modes.forEach(function (m, k) { m.f.forEach(function (f) { marks.push({ x: f, color: COLORS[k % COLORS.length] }); }); });
    function show(i) {
      var e = frf.entries[i], sm = [{ x: e.x, y: e.mag, color: "#1f77b4", mode: "dots", label: "measured" }], sp = [];
      if (e.phase) sp.push({ x: e.x, y: e.phase, color: "#1f77b4", mode: "dots", label: "measured" });
      e.models.forEach(function (m, k) {
        sm.push({ x: e.x, y: m.mag, color: COLORS[k % COLORS.length], label: m.method + " model" });
        if (m.phase) sp.push({ x: e.x, y: m.phase, color: COLORS[k % COLORS.length], label: m.method + " model" });
      });
      mag.set(sm, marks);
      phase.set(sp.length ? sp : [{ x: e.x, y: e.x.map(function () { return null; }), color: "#fff" }], marks);
      if (coh && e.coherence) coh.set([{ x: e.x, y: e.coherence, color: "#444", label: "coherence" }], marks);
      document.getElementById("frf-phase-note").hidden = !!e.phase;
    }
    select.addEventListener("change", function () { show(+select.value); });
    show(frf.entries.length > 1 && frf.entries[0].phase === null ? 1 : 0);
    select.value = frf.entries.length > 1 && frf.entries[0].phase === null ? "1" : "0";
  }

  // ---------------------------------------------------------------- stabilisation
  function setupStabilisation() {
    (data.stabilisation || []).forEach(function (d, k) {
      var canvas = document.getElementById("stab-" + k);
      var plot = new Plot(canvas, { ylabel: "model order", xlabel: "frequency [Hz]", height: 320,
        y2label: d.rms ? "RMS |H| [" + d.rms.units + "]" : null, y2log: true });
      var series = [];
      d.classes.forEach(function (name, c) {
        var xs = [], ys = [];
        for (var i = 0; i < d.f.length; i++) if (d.cls[i] === c) { xs.push(d.f[i]); ys.push(d.order[i]); }
        series.push({ x: xs, y: ys, mode: "dots", size: STAB_STYLE[c][1], color: STAB_STYLE[c][0], label: name });
      });
      if (d.rms) series.push({ x: d.rms.x, y: d.rms.y, axis: "y2", color: "#222", width: 1, label: "RMS |H|" });
      plot.set(series, d.modes.map(function (f, i) { return { x: f, color: d.flagged[i] ? "#d62728" : "#2ca02c" }; }));
    });
  }

  // ---------------------------------------------------------------- mode shapes (3D)
  function ShapeView() {
    this.canvas = document.getElementById("shape-canvas");
    this.argand = document.getElementById("shape-argand");
    this.yaw = -0.6; this.pitch = 0.5; this.zoom = 1; this.phase = 0; this.last = null;
    var self = this, drag = null;
    this.canvas.addEventListener("mousedown", function (e) { drag = [e.clientX, e.clientY]; });
    window.addEventListener("mouseup", function () { drag = null; });
    window.addEventListener("mousemove", function (e) {
      if (!drag) return;
      self.yaw += (e.clientX - drag[0]) * 0.01;
      self.pitch = Math.max(-1.5, Math.min(1.5, self.pitch + (e.clientY - drag[1]) * 0.01));
      drag = [e.clientX, e.clientY]; self.draw();
    });
    this.canvas.addEventListener("wheel", function (e) {
      e.preventDefault(); self.zoom *= e.deltaY < 0 ? 1.1 : 1 / 1.1; self.draw();
    }, { passive: false });
  }
  ShapeView.prototype.use = function (r, m) {
    var s = data.shapes[r]; this.s = s; this.mode = s.modes[m];
    state.result = r; state.mode = m;
    this.phase = 0;  // a mode shown anew starts at its largest deflection (the shape's real part)
    var n = s.nodes.length / 3, lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    for (var i = 0; i < n; i++) for (var a = 0; a < 3; a++) { lo[a] = Math.min(lo[a], s.nodes[3 * i + a]); hi[a] = Math.max(hi[a], s.nodes[3 * i + a]); }
    this.centre = [0, 1, 2].map(function (a) { return (lo[a] + hi[a]) / 2; });
    this.extent = Math.max(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) || 1;
    // complex node displacements: entries on one node add up along their directions
    var re = new Float64Array(3 * n), im = new Float64Array(3 * n), mode = this.mode, peak = 0;
    s.entry_node.forEach(function (node, j) {
      for (var a = 0; a < 3; a++) {
        re[3 * node + a] += (mode.re[j] || 0) * s.entry_dir[3 * j + a];
        im[3 * node + a] += (mode.im[j] || 0) * s.entry_dir[3 * j + a];
      }
    });
    for (i = 0; i < n; i++) {
      var mag = 0;
      for (a = 0; a < 3; a++) mag += re[3 * i + a] * re[3 * i + a] + im[3 * i + a] * im[3 * i + a];
      peak = Math.max(peak, Math.sqrt(mag));
    }
    this.re = re; this.im = im; this.peak = peak || 1;
    document.getElementById("shape-info").textContent = mode.f.toPrecision(5) + " Hz, damping " +
      (100 * mode.zeta).toPrecision(3) + " %, MPC " + mode.mpc.toFixed(3) + ", MPD " + mode.mpd.toFixed(1) + "°" +
      (mode.flags.length ? ", flags: " + mode.flags.join(", ") : "");
    this.draw(); this.drawArgand();
  };
  ShapeView.prototype.project = function (p) {
    var x = p[0] - this.centre[0], y = p[1] - this.centre[1], z = p[2] - this.centre[2];
    var cy = Math.cos(this.yaw), sy = Math.sin(this.yaw), cp = Math.cos(this.pitch), sp = Math.sin(this.pitch);
    var x1 = cy * x - sy * y, y1 = sy * x + cy * y;   // about z
    var depth = cp * y1 - sp * z, up = sp * y1 + cp * z;  // about the screen's horizontal
    return [this.cx + this.scale * x1, this.cy - this.scale * up, depth];
  };
  ShapeView.prototype.draw = function () {
    if (!this.s) return;
    var g = setupCanvas(this.canvas, 420), ctx = g.ctx, s = this.s, n = s.nodes.length / 3;
    ctx.fillStyle = "#fff"; ctx.fillRect(0, 0, g.w, g.h);
    this.cx = g.w / 2; this.cy = g.h / 2; this.scale = 0.62 * Math.min(g.w, g.h) / this.extent * this.zoom;
    var amp = +document.getElementById("shape-amplitude").value / 100 * this.extent / this.peak;
    var c = Math.cos(this.phase), sn = Math.sin(this.phase), base = [], moved = [];
    for (var i = 0; i < n; i++) {
      var p = [s.nodes[3 * i], s.nodes[3 * i + 1], s.nodes[3 * i + 2]], q = [];
      for (var a = 0; a < 3; a++) q.push(p[a] + amp * (this.re[3 * i + a] * c - this.im[3 * i + a] * sn));
      base.push(this.project(p)); moved.push(this.project(q));
    }
    function strokeLines(pts, color, width) {
      ctx.strokeStyle = color; ctx.lineWidth = width; ctx.beginPath();
      for (var k = 0; k < s.lines.length; k += 2) {
        var a = pts[s.lines[k]], b = pts[s.lines[k + 1]]; ctx.moveTo(a[0], a[1]); ctx.lineTo(b[0], b[1]);
      }
      ctx.stroke();
    }
    strokeLines(base, "#c8c8c8", 1);
    strokeLines(moved, "#1f77b4", 2);
    ctx.fillStyle = "#1f77b4";
    var r = n > 300 ? 1.5 : 3;
    moved.forEach(function (q) { ctx.fillRect(q[0] - r, q[1] - r, 2 * r, 2 * r); });
    // axis triad
    var self = this, o = [44, g.h - 44];
    [["x", [1, 0, 0], "#d62728"], ["y", [0, 1, 0], "#2ca02c"], ["z", [0, 0, 1], "#1f77b4"]].forEach(function (ax) {
      var saved = [self.cx, self.cy, self.scale, self.centre];
      self.cx = o[0]; self.cy = o[1]; self.scale = 26; self.centre = [0, 0, 0];
      var e = self.project(ax[1]);
      self.cx = saved[0]; self.cy = saved[1]; self.scale = saved[2]; self.centre = saved[3];
      ctx.strokeStyle = ax[2]; ctx.lineWidth = 2; ctx.beginPath(); ctx.moveTo(o[0], o[1]); ctx.lineTo(e[0], e[1]); ctx.stroke();
      ctx.fillStyle = ax[2]; ctx.font = "11px sans-serif"; ctx.fillText(ax[0], e[0] + 2, e[1] - 2);
    });
  };
  ShapeView.prototype.drawArgand = function () {
    var g = setupCanvas(this.argand, 240), ctx = g.ctx, m = this.mode;
    var size = Math.min(g.w, g.h), cx = g.w / 2, cy = g.h / 2, rad = size * 0.42;
    ctx.fillStyle = "#fff"; ctx.fillRect(0, 0, g.w, g.h);
    ctx.strokeStyle = "#ddd"; ctx.beginPath(); ctx.arc(cx, cy, rad, 0, 2 * Math.PI);
    ctx.moveTo(cx - rad, cy); ctx.lineTo(cx + rad, cy); ctx.moveTo(cx, cy - rad); ctx.lineTo(cx, cy + rad); ctx.stroke();
    ctx.strokeStyle = ctx.fillStyle = "#1f77b4";
    for (var j = 0; j < m.re.length; j++) {
      var x = cx + rad * (m.re[j] || 0), y = cy - rad * (m.im[j] || 0);
      ctx.beginPath(); ctx.moveTo(cx, cy); ctx.lineTo(x, y); ctx.stroke(); ctx.fillRect(x - 2, y - 2, 4, 4);
    }
    ctx.fillStyle = "#333"; ctx.font = "11px sans-serif"; ctx.fillText("Re", cx + rad - 14, cy - 4); ctx.fillText("Im", cx + 4, cy - rad + 10);
  };

  function setupShapes() {
    if (!data.shapes || !data.shapes.length) return;
    var view = new ShapeView(), resultSel = document.getElementById("shape-result"), modeSel = document.getElementById("shape-mode");
    var play = document.getElementById("shape-play");
    data.shapes.forEach(function (s, i) { var o = document.createElement("option"); o.value = i; o.textContent = s.method; resultSel.appendChild(o); });
    function fillModes() {
      modeSel.innerHTML = "";
      data.shapes[+resultSel.value].modes.forEach(function (m, i) {
        var o = document.createElement("option"); o.value = i; o.textContent = "mode " + (i + 1) + ": " + m.f.toPrecision(5) + " Hz";
        modeSel.appendChild(o);
      });
    }
    fillModes();
    resultSel.addEventListener("change", function () { fillModes(); view.use(+resultSel.value, 0); });
    modeSel.addEventListener("change", function () { view.use(+resultSel.value, +modeSel.value); });
    document.getElementById("shape-amplitude").addEventListener("input", function () { view.draw(); });
    play.addEventListener("click", function () { state.playing = !state.playing; play.textContent = state.playing ? "pause" : "play"; });
    view.use(0, 0);
    function tick(t) {
      if (state.playing) {
        if (view.last !== null) view.phase = (view.phase + (t - view.last) / 1500 * 2 * Math.PI) % (2 * Math.PI);
        view.draw(); state.frames += 1;
      }
      view.last = t; state.phase = view.phase;
      window.requestAnimationFrame(tick);
    }
    window.requestAnimationFrame(tick);
    redrawOnResize(view.canvas.parentElement, function () { view.draw(); });
    redrawOnResize(view.argand.parentElement, function () { view.drawArgand(); });
  }

  [setupFRF, setupStabilisation, setupShapes].forEach(function (f) {
    try { f(); } catch (err) { state.errors.push(String(err)); throw err; }
  });
  state.ready = true;
  document.body.setAttribute("data-ready", "1");
})();
