// path_explorer.js -- the one script of the book, inlined by docs/weave.lua
// into chapter 09's page beside its data: a click on the picture draws the
// path of the nearest pixel that build/data/ch09_paths.json explains (from
// the program's --explain), one SVG line per segment of the JSON: the eye
// ray (seen end on, a ring at the pixel), each bounce, each light sample's
// shadow ray (blue if it reached the light, red if blocked), a ray that left
// the scene (grey, dashed), and where the path ended (a cross: the roulette
// ended it; a square: it left the scene). The SVG's data-segments says how
// many lines it drew, which make test-docs compares with the JSON.
(function () {
  "use strict";
  var root = document.getElementById("path-explorer");
  var data = JSON.parse(document.getElementById("path-explorer-data").textContent);
  var img = root.querySelector("img");
  var svg = root.querySelector("svg");
  var note = root.querySelector(".path-explorer-note");
  var NS = "http://www.w3.org/2000/svg";
  svg.setAttribute("viewBox", "0 0 " + data.width + " " + data.height);
  var colours = { camera: "#ffffff", bounce: "#ffd23f", shadow: "#4cc9f0", blocked: "#f72585", escape: "#bbbbbb" };

  function add(name, attributes) {
    var e = document.createElementNS(NS, name);
    for (var k in attributes) e.setAttribute(k, attributes[k]);
    svg.appendChild(e);
    return e;
  }

  function draw(path) {
    while (svg.firstChild) svg.removeChild(svg.firstChild);
    var n = 0;
    path.segments.forEach(function (s) {
      var line = add("line", { x1: s.from[0], y1: s.from[1], x2: s.to[0], y2: s.to[1], "class": "seg seg-" + s.kind,
                               stroke: colours[s.kind] || "#ffffff", "stroke-width": 2,
                               "stroke-dasharray": s.kind === "escape" ? "6 4" : "none" });
      line.appendChild(document.createElementNS(NS, "title")).textContent = s.kind;
      if (s.kind === "camera") add("circle", { cx: s.to[0], cy: s.to[1], r: 6, fill: "none", stroke: colours.camera, "stroke-width": 2 });
      n++;
    });
    path.lights.forEach(function (p) { add("circle", { cx: p[0], cy: p[1], r: 4, fill: "none", stroke: colours.blocked, "stroke-width": 1.5 }); });
    if (path.end) {
      var x = path.end.at[0], y = path.end.at[1];
      if (path.end.why === "escape") add("rect", { x: x - 5, y: y - 5, width: 10, height: 10, fill: "none", stroke: colours.escape, "stroke-width": 2 });
      else {
        add("line", { x1: x - 7, y1: y - 7, x2: x + 7, y2: y + 7, stroke: "#ff5500", "stroke-width": 3 });
        add("line", { x1: x - 7, y1: y + 7, x2: x + 7, y2: y - 7, stroke: "#ff5500", "stroke-width": 3 });
      }
    }
    svg.setAttribute("data-segments", String(n));
    svg.setAttribute("data-pixel", path.pixel[0] + "," + path.pixel[1]);
    var bounces = path.segments.filter(function (s) { return s.kind === "bounce"; }).length;
    note.textContent = "Pixel (" + path.pixel[0] + ", " + path.pixel[1] + "): " + n + " segments, " + bounces +
      " bounces; " + (path.end ? ({ roulette: "the roulette ended it", escape: "it left the scene",
      "max depth": "the depth limit ended it", "no effect": "nothing reflects there" })[path.end.why] : "") +
      ". Command: " + data.command.replace("X,Y", path.pixel[0] + "," + path.pixel[1]);
  }

  root.querySelector(".path-explorer-stage").addEventListener("click", function (event) {
    var r = img.getBoundingClientRect();
    var x = (event.clientX - r.left) / r.width * data.width, y = (event.clientY - r.top) / r.height * data.height;
    var best = null, best_d = Infinity;
    data.paths.forEach(function (p) {
      var d = (p.pixel[0] + 0.5 - x) * (p.pixel[0] + 0.5 - x) + (p.pixel[1] + 0.5 - y) * (p.pixel[1] + 0.5 - y);
      if (d < best_d) { best_d = d; best = p; }
    });
    if (best) draw(best);
  });
})();
