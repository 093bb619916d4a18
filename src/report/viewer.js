// drape's interactive 3D view of a report: the tool and its plies drawn on a 2D canvas by a
// small depth-buffered rasteriser (orthographic projection, each face lit by a light that moves
// with the viewer). Drag to rotate, shift-drag or right-drag to pan, wheel to zoom, point at a cell to
// read its values. Written for drape; it reads only the JSON embedded in the same page.
(function () {
  "use strict";
  const data = JSON.parse(document.getElementById("drape-data").textContent);
  const canvas = document.getElementById("drape-view");
  const ctx = canvas.getContext("2d");
  const tip = document.getElementById("drape-tip");
  const colourBy = document.getElementById("drape-colour");
  const scaleBar = document.getElementById("drape-scale");

  // All vertices in one array (tool first), every face as a run of vertex indices.
  const xyz = [];
  const faces = []; // {v: [..], ply: -1 for the tool, cell: k}
  function addMesh(v, polys, size, ply) {
    const base = xyz.length / 3;
    for (const x of v) xyz.push(x);
    for (let k = 0; k < polys.length / size; k++) {
      const idx = [];
      for (let m = 0; m < size; m++) idx.push(base + polys[k * size + m]);
      faces.push({ v: idx, ply: ply, cell: k });
    }
  }
  if (data.tool) addMesh(data.tool.v, data.tool.t, 3, -1);
  data.plies.forEach((p, n) => addMesh(p.v, p.q, 4, n));
  const visible = data.plies.map(() => true);
  let showTool = true;

  // Centre and size of everything.
  const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  for (let k = 0; k < xyz.length; k += 3) {
    for (let a = 0; a < 3; a++) {
      lo[a] = Math.min(lo[a], xyz[k + a]);
      hi[a] = Math.max(hi[a], xyz[k + a]);
    }
  }
  const centre = [0, 1, 2].map((a) => 0.5 * (lo[a] + hi[a]));
  const size = Math.max(1e-9, Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]));
  const start = { yaw: -Math.PI / 4, pitch: Math.atan(1 / Math.SQRT2), zoom: 1, pan: [0, 0] };
  let view = Object.assign({}, start, { pan: [0, 0] });

  function frame() {
    const cy = Math.cos(view.yaw), sy = Math.sin(view.yaw);
    const cp = Math.cos(view.pitch), sp = Math.sin(view.pitch);
    const toward = [cp * cy, cp * sy, sp];
    const right = [-sy, cy, 0];
    const up = [
      toward[1] * right[2] - toward[2] * right[1],
      toward[2] * right[0] - toward[0] * right[2],
      toward[0] * right[1] - toward[1] * right[0],
    ];
    return { toward, right, up };
  }

  // Colour maps: the report's shear map (stops from the page's data) and a blue-green-yellow
  // sequential map for thickness and Vf.
  const SEQUENTIAL = [[0, [68, 1, 84]], [0.25, [59, 82, 139]], [0.5, [33, 145, 140]], [0.75, [94, 201, 98]], [1, [253, 231, 37]]];
  function ramp(stops, t) {
    t = Math.min(stops[stops.length - 1][0], Math.max(stops[0][0], t));
    for (let k = 1; k < stops.length; k++) {
      if (t <= stops[k][0]) {
        const [a, ca] = stops[k - 1], [b, cb] = stops[k];
        const s = (t - a) / (b - a || 1);
        return ca.map((c, m) => c + s * (cb[m] - c));
      }
    }
    return stops[stops.length - 1][1];
  }
  const quantities = {
    shear: { label: "shear angle (°)", lo: -data.shearLimit, hi: data.shearLimit, stops: data.shearStops, signed: true },
    thickness: { label: "thickness (mm)", key: "t", stops: SEQUENTIAL },
    vf: { label: "fibre volume fraction (%)", key: "vf", stops: SEQUENTIAL },
  };
  for (const q of [quantities.thickness, quantities.vf]) {
    q.lo = Infinity;
    q.hi = -Infinity;
    for (const p of data.plies) {
      for (const x of p[q.key] || []) {
        q.lo = Math.min(q.lo, x);
        q.hi = Math.max(q.hi, x);
      }
    }
    if (!(q.hi >= q.lo)) q.missing = true;
    else if (q.hi - q.lo < 1e-9) { q.lo -= 0.5; q.hi += 0.5; }
  }
  function cellColour(f) {
    const p = data.plies[f.ply];
    const q = quantities[colourBy.value];
    const values = q.key ? p[q.key] : p.shear;
    if (!values) return [200, 200, 200];
    const v = values[f.cell];
    const t = q.signed ? v / (q.hi || 1) : (v - q.lo) / (q.hi - q.lo);
    return ramp(q.stops, q.signed ? t : t * (q.stops[q.stops.length - 1][0] - q.stops[0][0]) + q.stops[0][0]);
  }

  // The last frame: which face covers each pixel (-1: none), for pointing at cells.
  let owner = new Int32Array(0);

  // Fill triangle (screen x, y, depth) with colour c into the frame buffers, nearer wins.
  function fill(P, c, id, rgba, depth, w, h) {
    const area = (P[1][0] - P[0][0]) * (P[2][1] - P[0][1]) - (P[2][0] - P[0][0]) * (P[1][1] - P[0][1]);
    if (!(Math.abs(area) > 1e-12)) return;
    const x0 = Math.max(0, Math.floor(Math.min(P[0][0], P[1][0], P[2][0])));
    const x1 = Math.min(w, Math.ceil(Math.max(P[0][0], P[1][0], P[2][0])));
    const y0 = Math.max(0, Math.floor(Math.min(P[0][1], P[1][1], P[2][1])));
    const y1 = Math.min(h, Math.ceil(Math.max(P[0][1], P[1][1], P[2][1])));
    for (let y = y0; y < y1; y++) {
      const py = y + 0.5;
      for (let x = x0; x < x1; x++) {
        const px = x + 0.5;
        const w1 = ((px - P[0][0]) * (P[2][1] - P[0][1]) - (P[2][0] - P[0][0]) * (py - P[0][1])) / area;
        const w2 = ((P[1][0] - P[0][0]) * (py - P[0][1]) - (px - P[0][0]) * (P[1][1] - P[0][1])) / area;
        const w0 = 1 - w1 - w2;
        if (w0 < 0 || w1 < 0 || w2 < 0) continue;
        const z = w0 * P[0][2] + w1 * P[1][2] + w2 * P[2][2];
        const k = y * w + x;
        if (z <= depth[k]) continue;
        depth[k] = z;
        owner[k] = id;
        rgba[4 * k] = c[0];
        rgba[4 * k + 1] = c[1];
        rgba[4 * k + 2] = c[2];
      }
    }
  }

  function render() {
    const w = canvas.width, h = canvas.height;
    const { toward, right, up } = frame();
    const scale = 1.1 * Math.min(w, h) / size * view.zoom;
    const n = xyz.length / 3;
    const sx = new Float64Array(n), sy = new Float64Array(n), sz = new Float64Array(n);
    for (let k = 0; k < n; k++) {
      const d = [xyz[3 * k] - centre[0], xyz[3 * k + 1] - centre[1], xyz[3 * k + 2] - centre[2]];
      sx[k] = w / 2 + view.pan[0] + scale * (d[0] * right[0] + d[1] * right[1] + d[2] * right[2]);
      sy[k] = h / 2 + view.pan[1] - scale * (d[0] * up[0] + d[1] * up[1] + d[2] * up[2]);
      sz[k] = d[0] * toward[0] + d[1] * toward[1] + d[2] * toward[2];
    }
    const light = [0, 1, 2].map((a) => -0.4 * right[a] + 0.6 * up[a] + 0.7 * toward[a]);
    const ll = Math.hypot(light[0], light[1], light[2]);
    const image = ctx.createImageData(w, h);
    const rgba = image.data;
    rgba.fill(255);
    const depth = new Float64Array(w * h).fill(-Infinity);
    owner = new Int32Array(w * h).fill(-1);
    let count = 0;
    faces.forEach((f, id) => {
      if (f.ply < 0 ? !showTool : !visible[f.ply]) return;
      const [a, b, c] = f.v;
      const e1 = [0, 1, 2].map((m) => xyz[3 * b + m] - xyz[3 * a + m]);
      const e2 = [0, 1, 2].map((m) => xyz[3 * c + m] - xyz[3 * a + m]);
      const nrm = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]];
      const nl = Math.hypot(nrm[0], nrm[1], nrm[2]) || 1;
      const facing = (nrm[0] * toward[0] + nrm[1] * toward[1] + nrm[2] * toward[2]) / nl;
      // A ply is seen from its outer side only (its cells are wound outwards); the tool from both.
      if (f.ply >= 0 && facing < 0) return;
      // Plies lie on the tool: lifted towards the viewer a little, each ply over the last.
      const lift = f.ply >= 0 ? 0.002 * size * (1 + f.ply) : 0;
      const lit = 0.35 + 0.65 * Math.abs((nrm[0] * light[0] + nrm[1] * light[1] + nrm[2] * light[2]) / (nl * ll));
      const base = f.ply < 0 ? [150, 154, 160] : cellColour(f);
      const col = base.map((x) => Math.max(0, Math.min(255, Math.round(x * lit))));
      const P = f.v.map((v) => [sx[v], sy[v], sz[v] + lift]);
      fill([P[0], P[1], P[2]], col, id, rgba, depth, w, h);
      if (P.length === 4) fill([P[0], P[2], P[3]], col, id, rgba, depth, w, h);
      count++;
    });
    ctx.putImageData(image, 0, 0);
    drawScale();
    api.faces = count;
  }

  function drawScale() {
    const q = quantities[colourBy.value];
    const s = scaleBar.getContext("2d");
    s.clearRect(0, 0, scaleBar.width, scaleBar.height);
    s.fillStyle = "#222";
    s.font = "12px sans-serif";
    if (q.missing) {
      s.fillText(q.label + ": not known for these plies (no thickness or Vf recorded)", 4, 14);
      return;
    }
    const x0 = 4, x1 = scaleBar.width - 4;
    for (let x = x0; x < x1; x++) {
      const t = (x - x0) / (x1 - x0);
      const first = q.stops[0][0], last = q.stops[q.stops.length - 1][0];
      const c = ramp(q.stops, first + t * (last - first)).map(Math.round);
      s.fillStyle = "rgb(" + c.join(",") + ")";
      s.fillRect(x, 2, 1, 14);
    }
    s.fillStyle = "#222";
    const digits = Math.abs(q.hi - q.lo) < 1 ? 3 : 1;
    s.fillText(q.lo.toFixed(digits), x0, 30);
    const hiText = q.hi.toFixed(digits);
    s.fillText(hiText, x1 - s.measureText(hiText).width, 30);
    const mid = q.label;
    s.fillText(mid, (x0 + x1 - s.measureText(mid).width) / 2, 30);
  }

  // What is at canvas pixel (x, y): the nearest face drawn there, in words.
  function pick(x, y) {
    x = Math.floor(x);
    y = Math.floor(y);
    if (x < 0 || y < 0 || x >= canvas.width || y >= canvas.height) return null;
    const id = owner[y * canvas.width + x];
    if (id >= 0) {
      const f = faces[id];
      if (f.ply < 0) return "tool";
      const p = data.plies[f.ply];
      const parts = ["ply " + p.name, "cell (" + p.ij[2 * f.cell] + ", " + p.ij[2 * f.cell + 1] + ")",
        "shear " + p.shear[f.cell].toFixed(1) + "°"];
      if (p.t) parts.push("thickness " + p.t[f.cell].toFixed(3) + " mm");
      if (p.vf) parts.push("Vf " + p.vf[f.cell].toFixed(1) + "%");
      return parts.join(" · ");
    }
    return null;
  }

  const api = { faces: 0, pick, render, plies: data.plies.length };
  window.drapeViewer = api;

  // Controls.
  const list = document.getElementById("drape-plies");
  data.plies.forEach((p, n) => {
    const label = document.createElement("label");
    const box = document.createElement("input");
    box.type = "checkbox";
    box.checked = true;
    box.addEventListener("change", () => { visible[n] = box.checked; render(); });
    label.appendChild(box);
    label.appendChild(document.createTextNode(" " + p.name + " "));
    list.appendChild(label);
  });
  const toolBox = document.getElementById("drape-tool");
  if (!data.tool) toolBox.disabled = true;
  toolBox.addEventListener("change", () => { showTool = toolBox.checked; render(); });
  colourBy.addEventListener("change", render);
  document.getElementById("drape-reset").addEventListener("click", () => {
    view = Object.assign({}, start, { pan: [0, 0] });
    render();
  });

  let drag = null;
  canvas.addEventListener("contextmenu", (e) => e.preventDefault());
  canvas.addEventListener("mousedown", (e) => {
    drag = { x: e.clientX, y: e.clientY, pan: e.shiftKey || e.button !== 0 };
  });
  window.addEventListener("mouseup", () => { drag = null; });
  canvas.addEventListener("mousemove", (e) => {
    const r = canvas.getBoundingClientRect();
    const x = (e.clientX - r.left) * canvas.width / r.width, y = (e.clientY - r.top) * canvas.height / r.height;
    if (drag) {
      const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
      drag.x = e.clientX;
      drag.y = e.clientY;
      if (drag.pan) {
        view.pan[0] += dx;
        view.pan[1] += dy;
      } else {
        view.yaw -= dx * 0.01;
        view.pitch = Math.max(-Math.PI / 2 + 0.01, Math.min(Math.PI / 2 - 0.01, view.pitch + dy * 0.01));
      }
      render();
      return;
    }
    const what = pick(x, y);
    tip.textContent = what || "Point at a cell to read its values.";
  });
  canvas.addEventListener("wheel", (e) => {
    e.preventDefault();
    view.zoom *= Math.exp(-e.deltaY * 0.001);
    render();
  }, { passive: false });

  render();
})();
