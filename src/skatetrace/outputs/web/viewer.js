/* skatetrace viewer: plays a traced figure back from the JSON embedded in this page.
   Plain JavaScript and SVG; loads nothing. */
(function () {
  "use strict";

  var NS = "http://www.w3.org/2000/svg";
  var D = JSON.parse(document.getElementById("skatetrace-data").textContent);
  var S = D.series;

  function column(values) {
    var out = new Float64Array(values.length);
    for (var i = 0; i < values.length; i++) out[i] = values[i] === null ? NaN : values[i];
    return out;
  }

  // ---- the time series ---------------------------------------------------------------------
  var T = column(S.t), X = column(S.x), Y = column(S.y), TH = column(S.theta);
  var A = column(S.a), B = column(S.b), V = column(S.speed);
  var KS = column(S.ke_skate), KM = column(S.ke_mass);
  var N = T.length;
  var SEC = new Int32Array(N);
  (D.section_runs || []).forEach(function (run, j, runs) {
    var end = j + 1 < runs.length ? runs[j + 1][0] : N;
    for (var r = run[0]; r < end; r++) SEC[r] = run[1];
  });
  var KT = new Float64Array(N), MX = new Float64Array(N), MY = new Float64Array(N), JUMPS = new Int32Array(N);
  for (var k = 0; k < N; k++) {
    KT[k] = KS[k] + KM[k];
    var ck = Math.cos(TH[k]), sk = Math.sin(TH[k]);
    MX[k] = X[k] + A[k] * ck - B[k] * sk;
    MY[k] = Y[k] + A[k] * sk + B[k] * ck;
    if (k) JUMPS[k] = JUMPS[k - 1] + (T[k] <= T[k - 1] ? 1 : 0);  // a repeated time: a jump
  }
  var T0 = T[0], T1 = T[N - 1], DUR = Math.max(T1 - T0, 0);
  var U = D.units || {};
  var TUNIT = U.time ? " " + U.time : "";
  var DECIMALS = DUR >= 10 ? 2 : 3;

  // ---- helpers -----------------------------------------------------------------------------
  function el(name, attrs, parent) {
    var e = document.createElementNS(NS, name);
    if (attrs) for (var key in attrs) if (Object.prototype.hasOwnProperty.call(attrs, key)) e.setAttribute(key, attrs[key]);
    if (parent) parent.appendChild(e);
    return e;
  }
  function r2(v) { return Math.round(v * 100) / 100; }
  function clamp(v, lo, hi) { return v < lo ? lo : (v > hi ? hi : v); }
  function fmt(v, digits) {
    if (!isFinite(v)) return "–";
    var m = Math.abs(v);
    if (m !== 0 && (m >= 1e7 || m < 1e-3)) return v.toExponential(digits - 1);
    if (m >= Math.pow(10, digits)) return v.toFixed(0);
    return v.toPrecision(digits).replace(/(\.\d*?)0+$/, "$1").replace(/\.$/, "");
  }
  /** Largest row i with T[i] <= t (0 if t is before the start). */
  function rowAt(t) {
    var lo = 0, hi = N - 1;
    if (t >= T[hi]) return hi;
    if (!(t >= T[0])) return 0;
    while (hi - lo > 1) {
      var mid = (lo + hi) >> 1;
      if (T[mid] <= t) lo = mid; else hi = mid;
    }
    return lo;
  }
  /** Linear interpolation of column C at row i, fraction f of the step to row i + 1. */
  function at(C, i, f) { return f > 0 ? C[i] + f * (C[i + 1] - C[i]) : C[i]; }
  function locate(t) {
    var i = rowAt(t), f = 0;
    if (i < N - 1 && T[i + 1] > T[i]) f = clamp((t - T[i]) / (T[i + 1] - T[i]), 0, 1);
    return { i: i, f: f };
  }
  function niceStep(span, count) {
    var raw = span / Math.max(count, 1);
    var p = Math.pow(10, Math.floor(Math.log10(raw)));
    var m = raw / p;
    return (m < 1.5 ? 1 : m < 3.5 ? 2 : m < 7.5 ? 5 : 10) * p;
  }
  function stepTicks(lo, hi, step) {
    var out = [];
    if (!(hi > lo) || !(step > 0)) return [lo];
    for (var v = Math.ceil(lo / step - 1e-9) * step; v <= hi + step * 1e-9; v += step) out.push(Math.abs(v) < step * 1e-9 ? 0 : v);
    return out;
  }
  function tickLabel(v, step) {
    var d = Math.max(0, -Math.floor(Math.log10(step) + 1e-9));
    return d > 6 ? v.toExponential(1) : v.toFixed(d);
  }

  // ---- stage -------------------------------------------------------------------------------
  // Built for one view (the bounds it fits); rebuilt when the view changes.
  var stage = document.getElementById("stage");
  var W = 640, H = 640, SCALE = 1, OX = 0, OY = 0, BX0 = 0, BY0 = 0;
  function px(x) { return OX + (x - BX0) * SCALE; }
  function py(y) { return H - OY - (y - BY0) * SCALE; }
  var SX = new Float64Array(N), SY = new Float64Array(N);
  var C1X = new Float64Array(N), C1Y = new Float64Array(N), C2X = new Float64Array(N), C2Y = new Float64Array(N);
  var CURVED = new Uint8Array(N), CUM = new Float64Array(N);
  var pieces = [], restEls = [], trail, rod, skate, mass, clock, clockSub;

  /** Point at parameter u of the step from row q - 1 to row q, in screen units. */
  function bez(q, u, out) {
    var v = 1 - u;
    if (!CURVED[q]) { out[0] = v * SX[q - 1] + u * SX[q]; out[1] = v * SY[q - 1] + u * SY[q]; return out; }
    var b0 = v * v * v, b1 = 3 * v * v * u, b2 = 3 * v * u * u, b3 = u * u * u;
    out[0] = b0 * SX[q - 1] + b1 * C1X[q] + b2 * C2X[q] + b3 * SX[q];
    out[1] = b0 * SY[q - 1] + b1 * C1Y[q] + b2 * C2Y[q] + b3 * SY[q];
    return out;
  }
  var P = [0, 0];
  function stepLength(q) {
    var len = 0, lx = SX[q - 1], ly = SY[q - 1], n = CURVED[q] ? 12 : 1;
    for (var m = 1; m <= n; m++) {
      bez(q, m / n, P);
      len += Math.sqrt((P[0] - lx) * (P[0] - lx) + (P[1] - ly) * (P[1] - ly));
      lx = P[0]; ly = P[1];
    }
    return len;
  }

  /** Height of the stage and the scale (pixels per unit) that fit ``bounds``. */
  function fit(bounds) {
    var bw = Math.max(bounds[1] - bounds[0], 1e-12), bh = Math.max(bounds[3] - bounds[2], 1e-12), pad = 18;
    var h = Math.round(W * clamp(bh / bw, 0.5, 1.0));
    return { h: h, scale: Math.min((W - 2 * pad) / bw, (h - 2 * pad) / bh), bw: bw, bh: bh };
  }

  function buildStage(bounds) {
    while (stage.firstChild) stage.removeChild(stage.firstChild);
    var bx0 = bounds[0], by0 = bounds[2], ft = fit(bounds), bw = ft.bw, bh = ft.bh;
    H = ft.h;
    SCALE = ft.scale;
    OX = (W - bw * SCALE) / 2; OY = (H - bh * SCALE) / 2; BX0 = bx0; BY0 = by0;
    stage.setAttribute("viewBox", "0 0 " + W + " " + H);
    stage.setAttribute("width", W);
    stage.setAttribute("height", H);

    // grid in the figure's units over the whole stage, and a scale bar
    var step = niceStep(Math.max(W, H) / SCALE, 12);
    var grid = el("g", { id: "grid" }, stage);
    stepTicks(BX0 - OX / SCALE, BX0 + (W - OX) / SCALE, step).forEach(function (gx) {
      el("line", { "class": "grid-line", x1: r2(px(gx)), x2: r2(px(gx)), y1: 0, y2: H }, grid);
    });
    stepTicks(BY0 - OY / SCALE, BY0 + (H - OY) / SCALE, step).forEach(function (gy) {
      el("line", { "class": "grid-line", y1: r2(py(gy)), y2: r2(py(gy)), x1: 0, x2: W }, grid);
    });
    var barLen = niceStep(W * 0.16 / SCALE, 1), barPx = barLen * SCALE, bxr = W - 14;
    var scaleG = el("g", { id: "scale" }, stage);
    el("line", { "class": "scale-bar", x1: r2(bxr - barPx), x2: bxr, y1: H - 14, y2: H - 14 }, scaleG);
    el("line", { "class": "scale-bar", x1: r2(bxr - barPx), x2: r2(bxr - barPx), y1: H - 18, y2: H - 10 }, scaleG);
    el("line", { "class": "scale-bar", x1: bxr, x2: bxr, y1: H - 18, y2: H - 10 }, scaleG);
    el("text", { "class": "scale-text", x: r2(bxr - barPx / 2), y: H - 21, "text-anchor": "middle" }, scaleG)
      .textContent = fmt(barLen, 3) + (U.length ? " " + U.length : " unit" + (barLen === 1 ? "" : "s"));

    // target figure
    var fig = el("g", { id: "figure" }, stage);
    D.figure.forEach(function (poly) {
      var pts = [];
      for (var j = 0; j < poly[0].length; j++) {
        if (poly[0][j] === null || poly[1][j] === null) continue;
        pts.push(r2(px(poly[0][j])) + "," + r2(py(poly[1][j])));
      }
      el("polyline", { "class": "target", points: pts.join(" ") }, fig);
    });

    // the mass's trail goes under the blade's trace: where the mass sits on the blade they overlap
    trail = el("path", { id: "trail", "class": "trail", d: "" }, stage);

    // Blade trace: one path per stretch without a jump of the contact point (a jump from one
    // curve of the figure to the next), each revealed up to the current arc length with a dash
    // (dash patterns restart at every subpath, so a stretch must be a path of its own). Between
    // two rows the blade moves along its heading (forwards or backwards), so each step is a cubic
    // Bezier curve that leaves and arrives along the heading: smooth even where rows are sparse.
    var traceG = el("g", { id: "trace", "class": "trace" }, stage), cur = null;
    pieces = [];
    for (var q = 0; q < N; q++) {
      SX[q] = px(X[q]); SY[q] = py(Y[q]); CURVED[q] = 0;
      if (!isFinite(SX[q]) || !isFinite(SY[q])) { cur = null; continue; }
      if (cur !== null) {
        var cx = SX[q] - SX[q - 1], cy = SY[q] - SY[q - 1], chord = Math.sqrt(cx * cx + cy * cy);
        if (chord > 0.5 && T[q] <= T[q - 1]) cur = null;  // a jump in position: start afresh
        else if (chord > 1e-6 && isFinite(TH[q - 1]) && isFinite(TH[q])) {
          var h0x = Math.cos(TH[q - 1]), h0y = -Math.sin(TH[q - 1]), h1x = Math.cos(TH[q]), h1y = -Math.sin(TH[q]);
          var d0 = (cx * h0x + cy * h0y) / chord, d1 = (cx * h1x + cy * h1y) / chord;
          if (Math.abs(d0) > 0.65 && Math.abs(d1) > 0.65) {  // headings within ~50 degrees of the chord
            var k0 = (d0 > 0 ? 1 : -1) * chord / 3, k1 = (d1 > 0 ? 1 : -1) * chord / 3;
            C1X[q] = SX[q - 1] + k0 * h0x; C1Y[q] = SY[q - 1] + k0 * h0y;
            C2X[q] = SX[q] - k1 * h1x; C2Y[q] = SY[q] - k1 * h1y;
            CURVED[q] = 1;
          }
        }
      }
      if (cur === null) {
        cur = { first: q, last: q, d: ["M" + r2(SX[q]) + " " + r2(SY[q])] };
        pieces.push(cur);
        CUM[q] = 0;
        continue;
      }
      CUM[q] = CUM[cur.last] + stepLength(q);
      cur.d.push(CURVED[q] ? "C" + r2(C1X[q]) + " " + r2(C1Y[q]) + " " + r2(C2X[q]) + " " + r2(C2Y[q]) + " " + r2(SX[q]) + " " + r2(SY[q])
        : "L" + r2(SX[q]) + " " + r2(SY[q]));
      cur.last = q;
    }
    pieces.forEach(function (pc) {
      pc.len = Math.max(CUM[pc.last], 1e-9);
      pc.el = el("path", { d: pc.d.join(""), pathLength: r2(pc.len), "stroke-dasharray": "0 " + r2(pc.len + 1) }, traceG);
      pc.state = null;
      pc.d = null;
    });

    // rests (cusps)
    var restG = el("g", { id: "rests" }, stage);
    restEls = [];
    for (var ri = 0; ri < D.rests.t.length; ri++) {
      if (D.rests.x[ri] === null || D.rests.y[ri] === null) continue;
      var rc = el("circle", { "class": "rest", cx: r2(px(D.rests.x[ri])), cy: r2(py(D.rests.y[ri])), r: 4.2,
        "data-t": D.rests.t[ri] }, restG);
      el("title", null, rc).textContent = "rest at t = " + fmt(D.rests.t[ri], 5) + TUNIT;
      restEls.push({ el: rc, t: D.rests.t[ri], on: false });
    }

    // the rod from the contact point to the mass, the skate (toe mark in front), the mass
    rod = el("line", { id: "rod", "class": "rod" }, stage);
    var blade = clamp(0.085 * Math.max(bw, bh) * SCALE, 30, 70);
    skate = el("g", { id: "skate" }, stage);
    el("line", { "class": "blade", x1: r2(-blade / 2), y1: 0, x2: r2(blade / 2), y2: 0 }, skate);
    el("path", { "class": "toe", d: "M" + r2(blade / 2 + 9) + " 0L" + r2(blade / 2 - 1) + " -5.5L" + r2(blade / 2 - 1) + " 5.5Z" }, skate);
    el("circle", { "class": "contact", cx: 0, cy: 0, r: 3.2 }, skate);
    // the planner's reach: the mass stays inside this circle around the contact point
    var REACH = D.summary && typeof D.summary.reach === "number" ? D.summary.reach : null;
    if (REACH !== null) el("circle", { id: "reach", "class": "reach", cx: 0, cy: 0, r: r2(REACH * SCALE) }, skate);
    mass = el("circle", { id: "mass", r: 7 }, stage);

    // clock
    var clockG = el("g", { id: "clock" }, stage);
    el("rect", { "class": "clock-bg", x: 8, y: 8, width: 178, height: 44, rx: 6 }, clockG);
    clock = el("text", { "class": "clock", x: 18, y: 28 }, clockG);
    clockSub = el("text", { "class": "clock-sub", x: 18, y: 44 }, clockG);
  }

  function drawTrace(i, f) {
    pieces.forEach(function (pc) {
      var state;
      if (i >= pc.last) state = "all";
      else if (i < pc.first) state = "none";
      else state = f > 0 ? CUM[i] + f * (CUM[i + 1] - CUM[i]) : CUM[i];
      if (state === pc.state) return;
      pc.state = state;
      if (state === "all") pc.el.setAttribute("stroke-dasharray", "none");
      else if (state === "none") pc.el.setAttribute("stroke-dasharray", "0 " + r2(pc.len + 1));
      else pc.el.setAttribute("stroke-dasharray", r2(state) + " " + r2(pc.len + 1));
    });
  }

  // ---- plots -------------------------------------------------------------------------------
  var PW = 480, PH = 158, ML = 50, MR = 12, MT = 24, MB = 22;
  var plots = [];
  function makePlot(id, title, lines) {
    var svg = document.getElementById(id);
    svg.setAttribute("viewBox", "0 0 " + PW + " " + PH);
    var lo = Infinity, hi = -Infinity;
    lines.forEach(function (ln) {
      for (var j = 0; j < N; j++) {
        var v = ln.values[j];
        if (isFinite(v)) { if (v < lo) lo = v; if (v > hi) hi = v; }
      }
    });
    if (!isFinite(lo)) { lo = 0; hi = 1; }
    if (hi - lo < 1e-12 * Math.max(1, Math.abs(hi))) { lo -= 0.5; hi += 0.5; }
    var padv = 0.06 * (hi - lo);
    lo -= padv; hi += padv;
    var x0 = ML, x1 = PW - MR, y0 = MT, y1 = PH - MB;
    function tx(t) { return x0 + (DUR > 0 ? (t - T0) / DUR : 0) * (x1 - x0); }
    function vy(v) { return y1 - (v - lo) / (hi - lo) * (y1 - y0); }
    el("rect", { "class": "plot-bg", x: x0, y: y0, width: x1 - x0, height: y1 - y0 }, svg);
    var ystep = niceStep(hi - lo, 4);
    stepTicks(lo, hi, ystep).forEach(function (v) {
      el("line", { "class": "plot-grid", x1: x0, x2: x1, y1: r2(vy(v)), y2: r2(vy(v)) }, svg);
      el("text", { "class": "plot-tick", x: x0 - 5, y: r2(vy(v) + 3.5), "text-anchor": "end" }, svg).textContent = tickLabel(v, ystep);
    });
    if (lo < 0 && hi > 0) el("line", { "class": "plot-zero", x1: x0, x2: x1, y1: r2(vy(0)), y2: r2(vy(0)) }, svg);
    var tstep = niceStep(DUR || 1, 6);
    stepTicks(T0, T1, tstep).forEach(function (t) {
      if (tx(t) > x1 - 34) return;  // room for the axis label
      el("text", { "class": "plot-tick", x: r2(tx(t)), y: PH - 7, "text-anchor": "middle" }, svg).textContent = tickLabel(t, tstep);
    });
    el("text", { "class": "plot-tick", x: x1, y: PH - 7, "text-anchor": "end" }, svg).textContent = "t" + (U.time ? " [" + U.time + "]" : "");
    D.rests.t.forEach(function (rt) {
      if (rt !== null) el("line", { "class": "plot-rest", x1: r2(tx(rt)), x2: r2(tx(rt)), y1: y0, y2: y1 }, svg);
    });
    el("text", { "class": "plot-title", x: 4, y: 15 }, svg).textContent = title;
    // legend: one right-aligned text, a coloured span per line, with its value at the cursor
    var legend = el("text", { "class": "plot-legend", x: x1, y: 15, "text-anchor": "end" }, svg);
    var spans = lines.map(function (ln, j) {
      var span = el("tspan", { fill: ln.color }, legend);
      if (j) span.setAttribute("dx", 12);
      return span;
    });
    lines.forEach(function (ln) {
      var pts = [];
      for (var j = 0; j < N; j++) if (isFinite(ln.values[j])) pts.push(r2(tx(T[j])) + "," + r2(vy(ln.values[j])));
      el("polyline", { "class": "plot-line", points: pts.join(" "), stroke: ln.color }, svg);
    });
    var cursor = el("line", { "class": "plot-cursor", x1: x0, x2: x0, y1: y0, y2: y1 }, svg);
    var dots = lines.map(function (ln) { return el("circle", { "class": "plot-dot", r: 3.5, fill: ln.color }, svg); });
    function seekFrom(evt) {
      var m = svg.getScreenCTM();
      if (!m) return;
      var p = svg.createSVGPoint();
      p.x = evt.clientX; p.y = evt.clientY;
      var loc = p.matrixTransform(m.inverse());
      seek(T0 + clamp((loc.x - x0) / (x1 - x0), 0, 1) * DUR);
    }
    svg.addEventListener("pointerdown", function (evt) {
      if (svg.setPointerCapture && evt.pointerId !== undefined) {
        try { svg.setPointerCapture(evt.pointerId); } catch (e) { /* synthetic events have no capture */ }
      }
      seekFrom(evt);
    });
    svg.addEventListener("pointermove", function (evt) { if (evt.buttons & 1) seekFrom(evt); });
    plots.push({
      update: function (loc, t) {
        var cx = r2(tx(t));
        cursor.setAttribute("x1", cx);
        cursor.setAttribute("x2", cx);
        lines.forEach(function (ln, j) {
          var v = at(ln.values, loc.i, loc.f);
          spans[j].textContent = ln.name + " " + fmt(v, 4);
          dots[j].setAttribute("cx", cx);
          dots[j].setAttribute("cy", isFinite(v) ? r2(vy(v)) : -10);
        });
      }
    });
  }
  var eu = U.energy ? " [" + U.energy + "]" : "", lu = U.length ? " [" + U.length + "]" : "";
  var su = U.speed ? " [" + U.speed + "]" : "";
  makePlot("plot-ab", "mass in the body frame" + lu, [
    { name: "a (along blade)", values: A, color: "#1b6ec2" },
    { name: "b (across)", values: B, color: "#d6336c" }]);
  makePlot("plot-speed", "speed along the blade ξ₂" + su, [{ name: "ξ₂", values: V, color: "#12a06b" }]);
  makePlot("plot-energy", "kinetic energy" + eu, [
    { name: "skate", values: KS, color: "#1b6ec2" },
    { name: "mass", values: KM, color: "#ef7d18" },
    { name: "total", values: KT, color: "#1d2430" }]);

  // ---- controls ----------------------------------------------------------------------------
  var playBtn = document.getElementById("play");
  var speedSel = document.getElementById("speed");
  var viewSel = document.getElementById("view");
  var slider = document.getElementById("slider");
  var timeEl = document.getElementById("time");
  document.getElementById("time-total").textContent = " / " + DUR.toFixed(DECIMALS) + TUNIT;
  slider.min = String(T0);
  slider.max = String(T1);
  slider.value = String(T0);
  (D.speeds || [1]).forEach(function (f) {
    var o = document.createElement("option");
    o.value = String(f);
    o.textContent = f + "×";
    if (f === D.default_speed) o.selected = true;
    speedSel.appendChild(o);
  });
  var VIEWS = D.views || { all: D.bounds };
  // Where the mass strays far from the blade, fit the figure and let the mass leave the view.
  var defaultView = VIEWS.figure && fit(VIEWS.figure).scale > 2 * fit(VIEWS.all).scale ? "figure" : "all";
  [["figure", "figure"], ["all", "figure and mass"]].forEach(function (v) {
    if (!VIEWS[v[0]]) return;
    var o = document.createElement("option");
    o.value = v[0];
    o.textContent = v[1];
    if (v[0] === defaultView) o.selected = true;
    viewSel.appendChild(o);
  });
  document.getElementById("samples-note").textContent =
    D.samples + " of " + D.rows + " time steps · " + D.sections + " section" + (D.sections === 1 ? "" : "s") +
    " · " + (D.unit === "m" ? "SI units" : "model units");

  var current = T0, playing = false, factor = Number(speedSel.value) || 1, lastStamp = null, rafId = null;

  function render() {
    var loc = locate(current), i = loc.i, f = loc.f;
    var a = at(A, i, f), b = at(B, i, f);
    var th = TH[i];
    if (f > 0) {
      var dth = TH[i + 1] - TH[i];
      dth -= 2 * Math.PI * Math.round(dth / (2 * Math.PI));
      th += f * dth;
    }
    var c = Math.cos(th), s = Math.sin(th);
    var spos = f > 0 ? bez(i + 1, f, [0, 0]) : [SX[i], SY[i]];
    var sx = r2(spos[0]), sy = r2(spos[1]), deg = r2(-th * 180 / Math.PI);
    skate.setAttribute("transform", "translate(" + sx + " " + sy + ") rotate(" + deg + ")");
    skate.setAttribute("data-x", sx);
    skate.setAttribute("data-y", sy);
    skate.setAttribute("data-heading", r2(th));
    // the mass, from the skate's drawn position and the body-frame offset (a, b)
    var mxs = r2(spos[0] + SCALE * (a * c - b * s)), mys = r2(spos[1] - SCALE * (a * s + b * c));
    mass.setAttribute("cx", mxs);
    mass.setAttribute("cy", mys);
    rod.setAttribute("x1", sx); rod.setAttribute("y1", sy);
    rod.setAttribute("x2", mxs); rod.setAttribute("y2", mys);
    drawTrace(i, f);
    // the mass's trail over the last 3 % of the figure's time, broken at jumps
    var j0 = rowAt(current - Math.max(DUR * 0.03, 1e-9)), stride = Math.max(1, Math.floor((i - j0) / 150)), parts = [];
    var prev = -1;
    for (var j = j0; j <= i; j = (j < i && j + stride > i) ? i : j + stride) {
      if (!isFinite(MX[j]) || !isFinite(MY[j])) { prev = -1; continue; }
      parts.push((prev < 0 || JUMPS[j] !== JUMPS[prev] ? "M" : "L") + r2(px(MX[j])) + " " + r2(py(MY[j])));
      prev = j;
      if (j === i) break;
    }
    if (parts.length && f > 0 && isFinite(mxs) && isFinite(mys)) parts.push("L" + mxs + " " + mys);
    trail.setAttribute("d", parts.join(""));
    restEls.forEach(function (r) {
      var on = r.t <= current + 1e-12;
      if (on !== r.on) { r.on = on; r.el.setAttribute("class", on ? "rest passed" : "rest"); }
    });
    var txt = current.toFixed(DECIMALS);
    timeEl.textContent = txt;
    clock.textContent = "t = " + txt + TUNIT;
    clockSub.textContent = "section " + (SEC[i] + 1) + " of " + D.sections + (Math.abs(at(V, i, f)) < 1e-9 ? " · at rest" : "");
    if (document.activeElement !== slider || playing) slider.value = String(current);
    plots.forEach(function (p) { p.update(loc, current); });
  }

  function setPlaying(on) {
    playing = on;
    playBtn.setAttribute("data-state", on ? "playing" : "paused");
    playBtn.setAttribute("aria-label", on ? "pause" : "play");
    playBtn.textContent = on ? "❚❚ Pause" : "▶ Play";
    lastStamp = null;
    if (on && rafId === null) rafId = window.requestAnimationFrame(tick);
  }
  function tick(stamp) {
    rafId = null;
    if (!playing) return;
    if (lastStamp !== null) current += Math.min(stamp - lastStamp, 250) / 1000 * factor;
    lastStamp = stamp;
    if (current >= T1) { current = T1; setPlaying(false); }
    render();
    if (playing) rafId = window.requestAnimationFrame(tick);
  }
  function play() {
    if (current >= T1) current = T0;
    setPlaying(true);
  }
  function pause() { setPlaying(false); render(); }
  function seek(t) {
    t = Number(t);
    if (!isFinite(t)) return;
    current = clamp(t, T0, T1);
    lastStamp = null;
    render();
  }
  function setView(name) {
    buildStage(VIEWS[name] || D.bounds);
    stage.setAttribute("data-view", VIEWS[name] ? name : "all");
    render();
  }

  playBtn.addEventListener("click", function () { if (playing) pause(); else play(); });
  speedSel.addEventListener("change", function () { factor = Number(speedSel.value) || 1; lastStamp = null; });
  viewSel.addEventListener("change", function () { setView(viewSel.value); });
  slider.addEventListener("input", function () { seek(slider.value); });
  slider.addEventListener("change", function () { seek(slider.value); });
  document.addEventListener("keydown", function (evt) {
    var tag = evt.target && evt.target.tagName;
    if (tag === "INPUT" || tag === "SELECT" || tag === "BUTTON" || evt.ctrlKey || evt.metaKey || evt.altKey) return;
    if (evt.key === " ") { evt.preventDefault(); if (playing) pause(); else play(); }
    else if (evt.key === "ArrowRight") { evt.preventDefault(); seek(current + DUR / 100); }
    else if (evt.key === "ArrowLeft") { evt.preventDefault(); seek(current - DUR / 100); }
    else if (evt.key === "Home") { evt.preventDefault(); seek(T0); }
    else if (evt.key === "End") { evt.preventDefault(); seek(T1); }
  });

  window.skatetrace = Object.freeze({
    time: function () { return current; },
    seek: function (t) { seek(t); return current; },
    playing: function () { return playing; },
    play: function () { play(); },
    pause: function () { pause(); },
    duration: function () { return DUR; },
    screen: function (x, y) { return [px(x), py(y)]; },
    view: function (name) { if (name !== undefined) { viewSel.value = name; setView(name); } return stage.getAttribute("data-view"); },
    data: D
  });
  setView(viewSel.value || "all");
})();
