/* fabkiri deployment viewer: vanilla JS, no network. Reads the JSON in #fabkiri-viewer-data (written by
   fabkiri/render/viewer.py) and draws it into #fabkiri-viewer. Tiles are <polygon data-tile="i"> whose
   points are the current frame's corners in mm (y up, flipped by the group's transform). */
(function () {
  "use strict";
  var root = document.getElementById("fabkiri-viewer");
  var src = document.getElementById("fabkiri-viewer-data");
  if (!root || !src) return;
  var D = JSON.parse(src.textContent);
  var NS = "http://www.w3.org/2000/svg";
  var F = D.t.length, T = D.corners[0].length;
  var ZERO_ENERGY = 1e-12; // as fabkiri's deploy: below this the energy is rounding noise
  var S = { f: D.marks.deployed, colour: D.path === "rigid" ? "rotation" : "energy", view: "flat",
            playing: false, timer: null, yaw: 0.6, pitch: -1.1, overlay: true };

  function el(tag, attrs, parent, ns) {
    var e = ns ? document.createElementNS(NS, tag) : document.createElement(tag);
    for (var k in attrs) e.setAttribute(k, attrs[k]);
    if (parent) parent.appendChild(e);
    return e;
  }
  function fmt(v, d) { return v === null || v === undefined ? "n/a" : Number(v).toPrecision(d || 3); }

  /* ---- styles, controls ---- */
  el("style", {}, root).textContent =
    ".fkv-bar{display:flex;flex-wrap:wrap;gap:10px;align-items:center;margin:4px 0 8px;font-size:14px}" +
    ".fkv-bar input[type=range]{flex:1 1 320px}.fkv-bar button{min-width:72px;font-size:14px;padding:3px 10px}" +
    ".fkv-stage{position:relative;border:1px solid #dde;border-radius:6px;background:#fbfcfd;overflow:auto}" +
    ".fkv-stage svg.fkv-main{display:block;width:100%;height:min(68vh,680px)}" +
    ".fkv-tip{position:absolute;pointer-events:none;background:#24313fee;color:#fff;font-size:12px;" +
    "padding:4px 8px;border-radius:4px;white-space:pre;display:none;z-index:2}" +
    ".fkv-legend{display:flex;align-items:center;gap:8px;font-size:13px;margin-top:6px;flex-wrap:wrap}" +
    ".fkv-grad{width:260px;height:12px;border:1px solid #889;border-radius:2px}" +
    ".fkv-state{font-weight:600;min-width:13em}.fkv-note{font-size:12px;color:#556;margin:4px 0}" +
    "polygon.fkv-tile:hover{stroke:#000;stroke-width:2.5px}" +
    ".fkv-main polygon,.fkv-main line,.fkv-main circle{vector-effect:non-scaling-stroke}";
  var bar = el("div", { "class": "fkv-bar" }, root);
  var play = el("button", { id: "fkv-play", type: "button" }, bar);
  play.textContent = "Play";
  var slider = el("input", { id: "fkv-t", type: "range", min: "0", max: "1", step: "0.001",
                             value: String(D.t[S.f]), "aria-label": "deployment parameter t" }, bar);
  var stateLabel = el("span", { id: "fkv-state", "class": "fkv-state" }, bar);
  var colourSel = el("select", { id: "fkv-colour", "aria-label": "tile colour" }, bar);
  [["energy", "colour: spring energy"], ["rotation", "colour: turn angle"]].forEach(function (o) {
    el("option", { value: o[0] }, colourSel).textContent = o[1];
  });
  colourSel.value = S.colour;
  var viewSel = el("select", { id: "fkv-view", "aria-label": "view" }, bar);
  var views = [["flat", "view: flat sheet"]];
  if (D.tube) views.push(["3d", "view: tube in 3D (drag to turn)"]);
  views.push(["sheet", D.sheets.length ? "view: cut sheets at true scale" : "view: closed state 1 at true scale"]);
  views.forEach(function (o) { el("option", { value: o[0] }, viewSel).textContent = o[1]; });
  var ovLabel = el("label", {}, bar);
  var ovBox = el("input", { id: "fkv-overlay", type: "checkbox", checked: "" }, ovLabel);
  var hiLabel = el("label", {}, bar);
  var hiBox = el("input", { id: "fkv-show-hinges", type: "checkbox", checked: "" }, hiLabel);
  hiLabel.appendChild(document.createTextNode(" hinges"));
  ovLabel.appendChild(document.createTextNode(" target + worst fit"));
  if (!D.overlay) ovLabel.style.display = "none";

  var stage = el("div", { "class": "fkv-stage" }, root);
  var svg = el("svg", { "class": "fkv-main", xmlns: NS, preserveAspectRatio: "xMidYMid meet" }, stage, true);
  var flip = el("g", { transform: "scale(1,-1)" }, svg, true);
  var gTiles = el("g", { id: "fkv-tiles" }, flip, true);
  var gHinges = el("g", { id: "fkv-hinges" }, flip, true);
  var gOver = el("g", { id: "fkv-overlay-g", "pointer-events": "none" }, flip, true);
  var g3d = el("g", { id: "fkv-3d" }, svg, true);
  var tip = el("div", { id: "fkv-tip", "class": "fkv-tip" }, stage);
  var legend = el("div", { id: "fkv-legend", "class": "fkv-legend" }, root);
  var note = el("p", { id: "fkv-note", "class": "fkv-note" }, root);

  /* ---- extents: one view box for every frame, so sizes compare across the path ---- */
  function bbox(points, box) {
    for (var i = 0; i < points.length; i++) {
      var p = points[i];
      if (p[0] < box[0]) box[0] = p[0]; if (p[1] < box[1]) box[1] = p[1];
      if (p[0] > box[2]) box[2] = p[0]; if (p[1] > box[3]) box[3] = p[1];
    }
    return box;
  }
  var box = [Infinity, Infinity, -Infinity, -Infinity];
  for (var f = 0; f < F; f++) for (var i = 0; i < T; i++) bbox(D.corners[f][i], box);
  if (D.overlay) bbox(D.overlay.outline, box);
  var pad = 0.03 * Math.max(box[2] - box[0], box[3] - box[1]);
  var flatBox = [box[0] - pad, -box[3] - pad, box[2] - box[0] + 2 * pad, box[3] - box[1] + 2 * pad];
  var unit = Math.max(flatBox[2], flatBox[3]) / 700; // about one screen pixel in mm at full width

  /* ---- colours ---- */
  var VIRIDIS = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];
  var COOLWARM = [[59, 76, 192], [221, 221, 221], [180, 4, 38]];
  function ramp(stops, x) {
    x = Math.min(1, Math.max(0, x)) * (stops.length - 1);
    var k = Math.min(stops.length - 2, Math.floor(x)), u = x - k, a = stops[k], b = stops[k + 1];
    return "rgb(" + [0, 1, 2].map(function (j) { return Math.round(a[j] + u * (b[j] - a[j])); }).join(",") + ")";
  }
  function gradient(stops) {
    return "linear-gradient(to right," + stops.map(function (s, k) {
      return ramp(stops, k / (stops.length - 1));
    }).join(",") + ")";
  }
  var eMax = 0, rMax = 1e-9;
  for (f = 0; f < F; f++) for (i = 0; i < T; i++) {
    eMax = Math.max(eMax, D.tileEnergy[f][i]); rMax = Math.max(rMax, Math.abs(D.rotation[f][i]));
  }
  var eLo = Math.max(eMax * 1e-6, ZERO_ENERGY);
  function colourOf(f, i) {
    if (S.colour === "rotation") return ramp(COOLWARM, 0.5 + 0.5 * D.rotation[f][i] / rMax);
    if (eMax <= ZERO_ENERGY) return "#c8ced6";
    var e = Math.max(D.tileEnergy[f][i], eLo);
    return ramp(VIRIDIS, Math.log(e / eLo) / Math.log(eMax / eLo));
  }
  function drawLegend() {
    legend.innerHTML = "";
    var deg = 180 / Math.PI;
    if (S.colour === "energy" && eMax <= ZERO_ENERGY) {
      el("span", {}, legend).textContent = "spring energy: below " + ZERO_ENERGY +
        " in every tile along the whole path (max " + fmt(eMax, 2) + "): the tiles move without straining, one colour";
      return;
    }
    var stops = S.colour === "energy" ? VIRIDIS : COOLWARM;
    var lo = S.colour === "energy" ? fmt(eLo, 2) : "−" + fmt(rMax * deg, 3) + "°";
    var hi = S.colour === "energy" ? fmt(eMax, 2) : "+" + fmt(rMax * deg, 3) + "°";
    el("span", {}, legend).textContent = S.colour === "energy"
      ? "tile spring energy (log scale)" : "tile turn angle from closed state 1 (common rotation removed)";
    el("span", {}, legend).textContent = lo;
    el("span", { "class": "fkv-grad", style: "background:" + gradient(stops) }, legend);
    el("span", {}, legend).textContent = hi;
  }

  /* ---- flat tiles ---- */
  var polys = [];
  for (i = 0; i < T; i++) {
    var pg = el("polygon", { "class": "fkv-tile", "data-tile": String(i), stroke: "#34495e",
                              "stroke-width": "0.7", "stroke-linejoin": "round" }, gTiles, true);
    polys.push(pg);
  }
  function pts(c) {
    return c.map(function (p) { return p[0].toFixed(4) + "," + p[1].toFixed(4); }).join(" ");
  }
  function drawOverlay() {
    gOver.innerHTML = "";
    var deployed = S.f === D.marks.deployed;
    if (!D.overlay || !S.overlay || !deployed || S.view !== "flat") return;
    var o = D.overlay;
    el("polygon", { id: "fkv-target", points: pts(o.outline), fill: "none", stroke: "#1f77b4",
                    "stroke-width": "2.2" }, gOver, true);
    if (o.worst) {
      if (o.nearest) el("line", { x1: o.worst[0], y1: o.worst[1], x2: o.nearest[0], y2: o.nearest[1],
                                  stroke: "#d62728", "stroke-width": "3" }, gOver, true);
      el("circle", { id: "fkv-worst", cx: o.worst[0], cy: o.worst[1], r: String(unit * 10), fill: "none",
                     stroke: "#d62728", "stroke-width": "2.5" }, gOver, true);
    }
  }
  /* hinges: a dot at each hinge corner (of its first tile), hover for its number and piece */
  var dots = D.hinges.map(function (h, k) {
    return el("circle", { "class": "fkv-hinge", "data-hinge": String(k), r: String(D.tileSize * 0.07),
                          fill: "#24313f", "fill-opacity": "0.55" }, gHinges, true);
  });
  function drawFlat() {
    var c = D.corners[S.f];
    for (var i = 0; i < T; i++) {
      polys[i].setAttribute("points", pts(c[i]));
      polys[i].setAttribute("fill", colourOf(S.f, i));
    }
    D.hinges.forEach(function (h, k) {
      var p = c[h[0]][h[2]];
      dots[k].setAttribute("cx", p[0].toFixed(4));
      dots[k].setAttribute("cy", p[1].toFixed(4));
    });
  }

  /* ---- tube in 3D: orthographic, painter's order, drag to turn ---- */
  var polys3d = [];
  var r3d = 1;
  if (D.tube) {
    D.tube.tiles.forEach(function (tile) {
      polys3d.push(el("polygon", { "class": "fkv-tile", "data-tile3d": String(tile), stroke: "#34495e",
                                   "stroke-linejoin": "round" }, g3d, true));
    });
    for (f = 0; f < F; f++) {
      var m = centroid3(D.tube.corners[f]);
      D.tube.corners[f].forEach(function (q) { q.forEach(function (p) {
        r3d = Math.max(r3d, Math.hypot(p[0] - m[0], p[1] - m[1], p[2] - m[2]));
      }); });
    }
  }
  function centroid3(tiles) {
    var s = [0, 0, 0], n = 0;
    tiles.forEach(function (q) { q.forEach(function (p) { s[0] += p[0]; s[1] += p[1]; s[2] += p[2]; n++; }); });
    return [s[0] / n, s[1] / n, s[2] / n];
  }
  function draw3d() {
    var tiles = D.tube.corners[S.f], m = centroid3(tiles);
    var cy = Math.cos(S.yaw), sy = Math.sin(S.yaw), cp = Math.cos(S.pitch), sp = Math.sin(S.pitch);
    var order = tiles.map(function (q, k) {
      var proj = q.map(function (p) {
        var x = p[0] - m[0], y = p[1] - m[1], z = p[2] - m[2];
        var x1 = cy * x - sy * y, y1 = sy * x + cy * y;      // turn about the tube's axis
        return [x1, cp * y1 - sp * z, sp * y1 + cp * z];       // then tip it towards the viewer
      });
      var depth = proj.reduce(function (a, p) { return a + p[2]; }, 0) / proj.length;
      return { k: k, proj: proj, depth: depth };
    }).sort(function (a, b) { return a.depth - b.depth; });
    order.forEach(function (o) {
      var p = o.proj, area = 0;
      for (var j = 0; j < p.length; j++) {
        var a = p[j], b = p[(j + 1) % p.length];
        area += a[0] * b[1] - b[0] * a[1];
      }
      var pg = polys3d[o.k];
      pg.setAttribute("points", p.map(function (q) { return q[0].toFixed(3) + "," + (-q[1]).toFixed(3); }).join(" "));
      pg.setAttribute("fill", colourOf(S.f, D.tube.tiles[o.k]));
      pg.setAttribute("fill-opacity", area < 0 ? "0.55" : "1");
      pg.setAttribute("stroke-width", "0.7");
      g3d.appendChild(pg); // re-appended far to near
    });
  }
  var drag = null;
  svg.addEventListener("pointerdown", function (ev) {
    if (S.view !== "3d") return;
    drag = [ev.clientX, ev.clientY, S.yaw, S.pitch];
    svg.setPointerCapture(ev.pointerId);
  });
  svg.addEventListener("pointermove", function (ev) {
    if (!drag) return;
    S.yaw = drag[2] + (ev.clientX - drag[0]) * 0.01;
    S.pitch = Math.max(-Math.PI, Math.min(0, drag[3] + (ev.clientY - drag[1]) * 0.01));
    draw3d();
  });
  svg.addEventListener("pointerup", function () { drag = null; });

  /* ---- closed state 1 at true scale: 1 mm of the sheet is 1 CSS mm ---- */
  var sheetSvg = null;
  function buildSheet() {
    if (D.sheets.length) return buildCutSheets();
    var c = D.corners[0], b = [Infinity, Infinity, -Infinity, -Infinity];
    c.forEach(function (q) { bbox(q, b); });
    var w = b[2] - b[0], h = b[3] - b[1], m = 0.06 * Math.max(w, h) + 6;
    var barLen = [1, 2, 5, 10, 20, 50, 100, 200, 500].filter(function (v) { return v <= 0.4 * w; }).pop() || 1;
    sheetSvg = el("svg", { id: "fkv-sheet", xmlns: NS, width: (w + 2 * m) + "mm", height: (h + 2 * m + 8) + "mm",
                           viewBox: [b[0] - m, -b[3] - m, w + 2 * m, h + 2 * m + 8].join(" ") }, stage, true);
    var g = el("g", { transform: "scale(1,-1)" }, sheetSvg, true);
    c.forEach(function (q, k) {
      el("polygon", { "data-sheet-tile": String(k), points: pts(q), fill: "#dfe6ee", stroke: "#b3261e",
                      "stroke-width": "0.1" }, g, true);
    });
    var y = b[3] + m * 0.5 + 4;
    el("line", { x1: b[0], y1: y, x2: b[0] + barLen, y2: y, stroke: "#000", "stroke-width": "0.6" }, sheetSvg, true);
    var tx = el("text", { x: b[0] + barLen + 1.5, y: y + 1.2, "font-size": "3.5" }, sheetSvg, true);
    tx.textContent = barLen + " mm";
    sheetSvg.style.display = "none";
  }
  function buildCutSheets() {
    sheetSvg = el("div", { id: "fkv-sheet" }, stage);
    D.sheets.forEach(function (sh) {
      var fig = el("figure", { style: "margin:8px" }, sheetSvg);
      el("img", { src: sh.uri, alt: sh.name, "data-sheet": sh.name,
                  style: "width:" + sh.width_mm + "mm;height:" + sh.height_mm + "mm;max-width:none;background:#fff" }, fig);
      var bar = el("svg", { xmlns: NS, width: "125mm", height: "8mm", viewBox: "0 0 125 8" }, fig, true);
      el("line", { x1: 0, y1: 3, x2: 100, y2: 3, stroke: "#000", "stroke-width": "0.6" }, bar, true);
      el("text", { x: 101, y: 4.2, "font-size": "3.5" }, bar, true).textContent = "100 mm";
      el("figcaption", {}, fig).textContent = sh.name + ": " + sh.width_mm + " x " + sh.height_mm +
        " mm, as cut (kerf, hinge marks, labels)";
    });
    sheetSvg.style.display = "none";
  }
  buildSheet();

  /* ---- hover: tile number, assembly pieces, fabrication figures ---- */
  function tileText(i) {
    var t = D.tiles[i] || {}, lines = ["tile " + i];
    lines.push("thinnest width " + fmt(t.width_mm, 3) + " mm");
    if (t.pieces) lines.push("assembly piece" + (t.pieces.length > 1 ? "s " : " ") + t.pieces.join(", "));
    lines.push("spring energy " + fmt(D.tileEnergy[S.f][i], 2));
    lines.push("turn " + fmt(D.rotation[S.f][i] * 180 / Math.PI, 3) + "°");
    return lines.join("\n");
  }
  function hingeText(k) {
    var h = D.hinges[k], p = D.hingePieces[String(k)];
    return "hinge " + k + "\njoins tiles " + h[0] + " and " + h[1] +
      (p ? "\nassembly piece" + (p.length > 1 ? "s " : " ") + p.join(", ") : "");
  }
  function hover(ev) {
    var t = ev.target, a = t.getAttribute && (t.getAttribute("data-tile") || t.getAttribute("data-tile3d") ||
                                                t.getAttribute("data-sheet-tile"));
    var hinge = t.getAttribute && t.getAttribute("data-hinge");
    if ((a === null || a === undefined) && hinge === null) { tip.style.display = "none"; return; }
    var r = stage.getBoundingClientRect();
    tip.textContent = hinge !== null ? hingeText(Number(hinge)) : tileText(Number(a));
    tip.style.left = (ev.clientX - r.left + stage.scrollLeft + 14) + "px";
    tip.style.top = (ev.clientY - r.top + stage.scrollTop + 14) + "px";
    tip.style.display = "block";
  }
  stage.addEventListener("mouseover", hover);
  stage.addEventListener("mousemove", hover);
  stage.addEventListener("mouseleave", function () { tip.style.display = "none"; });

  /* ---- the frame ---- */
  function markName(f) {
    for (var k in D.marks) if (D.marks[k] === f) return k;
    return f < D.marks.deployed ? "closed state 1 → deployed" : "deployed → closed state 2";
  }
  function draw() {
    var flat = S.view === "flat";
    svg.style.display = S.view === "sheet" ? "none" : "block";
    sheetSvg.style.display = S.view === "sheet" ? "block" : "none";
    flip.style.display = flat ? "" : "none";
    g3d.style.display = S.view === "3d" ? "" : "none";
    if (flat) { svg.setAttribute("viewBox", flatBox.join(" ")); drawFlat(); }
    if (S.view === "3d") { svg.setAttribute("viewBox", [-r3d, -r3d, 2 * r3d, 2 * r3d].join(" ")); draw3d(); }
    drawOverlay();
    stateLabel.textContent = "t = " + D.t[S.f].toFixed(3) + " · " + markName(S.f);
    root.setAttribute("data-frame", String(S.f));
    root.setAttribute("data-t", String(D.t[S.f]));
    root.setAttribute("data-view", S.view);
    root.setAttribute("data-colour", S.colour);
    note.textContent = (S.view === "sheet"
      ? (D.sheets.length ? "the cut sheets as written (SVG: kerf-offset cuts, hinge marks, labels; lines " +
          "drawn 1 px wide)" : "closed state 1 (the state the sheet is cut in), tiles as placed, without kerf " +
          "or hinge features (pass a cut folder for the sheets as cut)") +
        " at true scale: 1 mm is 1 mm on a screen at its nominal 96 px per inch. "
      : "frame " + S.f + " of " + (F - 1) + " of the " + D.path + " path" +
        (D.driver ? " (driver " + D.driver + ")" : "") + ", E = " + fmt(D.energy[S.f], 3) +
        "; the slider snaps to the computed frames. ") +
      (D.overlay && S.view === "flat" ? "Target " + D.overlay.name + " and the worst fit (Hausdorff " +
        fmt(D.overlay.hausdorff_mm, 3) + " mm) are drawn on the deployed state (t = 0.5). " : "") +
      (D.problems.length ? "Path problems: " + D.problems.join("; ") : "");
  }
  function setFrame(f) {
    S.f = Math.max(0, Math.min(F - 1, f | 0));
    if (!S.playing || document.activeElement !== slider) slider.value = String(D.t[S.f]);
    draw();
  }
  function setT(t) {
    var best = 0;
    for (var k = 1; k < F; k++) if (Math.abs(D.t[k] - t) < Math.abs(D.t[best] - t)) best = k;
    setFrame(best);
  }
  slider.addEventListener("input", function () { setT(Number(slider.value)); });
  slider.addEventListener("keydown", function (ev) { // arrows step one computed frame, not 0.001 in t
    var d = { ArrowRight: 1, ArrowUp: 1, ArrowLeft: -1, ArrowDown: -1 }[ev.key];
    if (d) { ev.preventDefault(); setFrame(S.f + d); }
  });
  colourSel.addEventListener("change", function () { S.colour = colourSel.value; drawLegend(); draw(); });
  viewSel.addEventListener("change", function () { S.view = viewSel.value; draw(); });
  ovBox.addEventListener("change", function () { S.overlay = ovBox.checked; draw(); });
  hiBox.addEventListener("change", function () { gHinges.style.display = hiBox.checked ? "" : "none"; });
  function setPlaying(on) {
    S.playing = on;
    play.textContent = on ? "Pause" : "Play";
    if (S.timer) { clearInterval(S.timer); S.timer = null; }
    if (on) S.timer = setInterval(function () { setFrame(S.f >= F - 1 ? 0 : S.f + 1); }, 70);
  }
  play.addEventListener("click", function () { setPlaying(!S.playing); });

  window.fabkiriViewer = {
    data: D,
    setT: setT,
    setFrame: setFrame,
    frame: function () { return S.f; },
    t: function () { return D.t[S.f]; },
    play: setPlaying,
    /* the drawn flat tiles, read back from the DOM: [tile][corner][x, y] in mm */
    positions: function () {
      return polys.map(function (p) {
        return p.getAttribute("points").split(" ").map(function (s) { return s.split(",").map(Number); });
      });
    }
  };
  drawLegend();
  draw();
})();
