// regatta's viewer page: the arena in 3D on a 2-D canvas (triangles projected and painted
// far to near; no WebGL, so that it draws in any browser, headless ones without a GPU
// included), trails, the selected robot's retina, IR and wheels, the events, and the
// controls. Samples come from /events (Server-Sent Events); a replayed log sends them all
// at once and the timeline plays them here.
"use strict";

const $ = (id) => document.getElementById(id);
const PALETTE_IR = ["#e69f00", "#56b4e9", "#009e73", "#f0e442", "#0072b2", "#d55e00", "#cc79a7", "#999999"];
const MAX_HISTORY = 20000;

const view = {
  scene: null,
  hist: [],          // samples, oldest first
  events: [],
  status: {},
  cur: -1,           // the sample shown (the newest, live)
  robot: 0,
  frames: 0,         // frames drawn (tests wait for them)
  dirty: true,
  camera: { yaw: -0.6, pitch: 0.85, dist: 1, target: [0, 0, 0], fov: 0.9 },
  playing: false,    // replay: the timeline plays
  playFrom: null,
};
window.regatta = view;

// The run's token, from the page's own URL (regatta view prints it there): every request
// the page makes carries it, as the server refuses requests without it beyond the loopback.
const TOKEN = new URLSearchParams(location.search).get("token");
function api(path) {
  if (!TOKEN) return path;
  return `${path}${path.includes("?") ? "&" : "?"}token=${encodeURIComponent(TOKEN)}`;
}
view.api = api;

// ---------- geometry ----------

function sub(a, b) { return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]; }
function cross(a, b) { return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]; }
function dot(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
function norm(a) { const l = Math.hypot(a[0], a[1], a[2]) || 1; return [a[0] / l, a[1] / l, a[2] / l]; }

const LIGHT = norm([0.4, 1.0, 0.3]);

// A triangle's colour: diffuse lit by one light from above plus ambient, and a lamp's
// emissive colour where it is brighter (a glowing lamp shows its own colour).
function shade(soup, t, normal) {
  const lit = 0.35 + 0.65 * Math.abs(dot(normal, LIGHT));
  const c = [];
  for (let k = 0; k < 3; k++) {
    const d = soup.colours[3 * t + k] * lit;
    c.push(Math.min(255, Math.round(Math.max(d, soup.emissive[3 * t + k]))));
  }
  return `rgb(${c[0]},${c[1]},${c[2]})`;
}

function triangles(soup) {
  const out = [];
  const p = soup.positions;
  for (let t = 0; t * 9 < p.length; t++) {
    const a = [p[9 * t], p[9 * t + 1], p[9 * t + 2]];
    const b = [p[9 * t + 3], p[9 * t + 4], p[9 * t + 5]];
    const c = [p[9 * t + 6], p[9 * t + 7], p[9 * t + 8]];
    const n = norm(cross(sub(b, a), sub(c, a)));
    out.push({ v: [a, b, c], n, colour: shade(soup, t, n), t });
  }
  return out;
}

// The robot frame: +x forward, +y up; a heading h turns it counter-clockwise seen from above.
function place(robotSample, floorY, p) {
  const h = robotSample[2], c = Math.cos(h), s = Math.sin(h);
  return [c * p[0] + s * p[2] + robotSample[0], p[1] + floorY, -s * p[0] + c * p[2] + robotSample[1]];
}

// ---------- camera ----------

function eye() {
  const cam = view.camera;
  const cp = Math.cos(cam.pitch);
  return [cam.target[0] + cam.dist * cp * Math.sin(cam.yaw),
          cam.target[1] + cam.dist * Math.sin(cam.pitch),
          cam.target[2] + cam.dist * cp * Math.cos(cam.yaw)];
}

function basis() {
  const e = eye();
  const f = norm(sub(view.camera.target, e));
  let r = cross(f, [0, 1, 0]);
  if (Math.hypot(r[0], r[1], r[2]) < 1e-6) r = [1, 0, 0];
  r = norm(r);
  const u = cross(r, f);
  return { e, f, r, u };
}

let frameBasis = null;
let canvasSize = [1, 1];

// World point to canvas pixel [x, y, depth]; null behind the eye.
function project(p, b = frameBasis) {
  const d = sub(p, b.e);
  const z = dot(d, b.f);
  if (z < 1e-3) return null;
  const scale = canvasSize[1] / 2 / Math.tan(view.camera.fov / 2);
  return [canvasSize[0] / 2 + dot(d, b.r) / z * scale, canvasSize[1] / 2 - dot(d, b.u) / z * scale, z];
}

// For scripts and tests: where a world point is drawn, in page pixels.
view.project = (x, y, z) => {
  const canvas = $("arena");
  const q = project([x, y, z], basis());
  if (!q) return null;
  const box = canvas.getBoundingClientRect();
  return [box.left + q[0] * box.width / canvasSize[0], box.top + q[1] * box.height / canvasSize[1]];
};

function fitCamera(top) {
  const b = view.scene.bounds;
  const cam = view.camera;
  cam.target = [(b[0] + b[3]) / 2, b[1], (b[2] + b[5]) / 2];
  const span = Math.max(b[3] - b[0], b[5] - b[2], 0.2);
  cam.dist = span * (top ? 1.25 : 1.35);
  cam.pitch = top ? Math.PI / 2 - 1e-4 : 0.85;
  cam.yaw = top ? 0 : -0.6;
  view.dirty = true;
}

// ---------- drawing ----------

function resize(canvas) {
  const w = Math.max(1, canvas.clientWidth), h = Math.max(1, canvas.clientHeight);
  if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
  canvasSize = [w, h];
}

function drawArena() {
  const canvas = $("arena");
  resize(canvas);
  const g = canvas.getContext("2d");
  const sky = view.scene.sky;
  g.fillStyle = `rgb(${Math.round(sky[0] * 0.35)},${Math.round(sky[1] * 0.35)},${Math.round(sky[2] * 0.35)})`;
  g.fillRect(0, 0, canvas.width, canvas.height);
  frameBasis = basis();
  const sample = view.hist[view.cur];
  const faces = [];
  const add = (v, colour) => {
    const a = project(v[0]), b = project(v[1]), c = project(v[2]);
    if (!a || !b || !c) return;
    faces.push({ a, b, c, z: (a[2] + b[2] + c[2]) / 3, colour });
  };
  for (const t of view.fixed) add(t.v, t.colour);
  view.scene.robots.forEach((robot, i) => {
    const r = sample ? sample.robots[i] : null;
    if (!r) return;
    const h = r[2], c = Math.cos(h), s = Math.sin(h);
    for (const t of view.robotTris[i]) {
      const v = t.v.map((p) => place(r, robot.floorY, p));
      const n = [c * t.n[0] + s * t.n[2], t.n[1], -s * t.n[0] + c * t.n[2]];
      add(v, shade(robot.mesh, t.t, n));
    }
  });
  faces.sort((p, q) => q.z - p.z);
  g.lineWidth = 0.6;
  g.lineJoin = "round";
  for (const f of faces) {
    g.beginPath();
    g.moveTo(f.a[0], f.a[1]); g.lineTo(f.b[0], f.b[1]); g.lineTo(f.c[0], f.c[1]); g.closePath();
    g.fillStyle = f.colour; g.strokeStyle = f.colour;
    g.fill(); g.stroke();
  }
  drawTrails(g);
  drawMarkers(g, sample);
}

const rgb = (c, a = 1) => `rgba(${c[0]},${c[1]},${c[2]},${a})`;

function drawTrails(g) {
  const n = view.scene.robots.length;
  const span = Math.min(view.cur + 1, n > 20 ? 1000 : 8000);
  const from = view.cur + 1 - span;
  view.scene.robots.forEach((robot, i) => {
    g.beginPath();
    let started = false;
    for (let k = from; k <= view.cur; k++) {
      const r = view.hist[k].robots[i];
      const q = project([r[0], robot.floorY + 0.001, r[1]]);
      if (!q) { started = false; continue; }
      if (started) g.lineTo(q[0], q[1]); else g.moveTo(q[0], q[1]);
      started = true;
    }
    g.strokeStyle = rgb(robot.colour, 0.55);
    g.lineWidth = 2;
    g.stroke();
  });
}

// Each robot's heading: an arrow over its top in the robot's colour, drawn last.
function drawMarkers(g, sample) {
  if (!sample) return;
  view.scene.robots.forEach((robot, i) => {
    const r = sample.robots[i];
    if (!r) return;
    const y = robot.floorY + robot.bodyHeight + 0.004;
    const rad = robot.bodyRadius;
    const pts = [[1.3 * rad, 0], [-0.8 * rad, 0.75 * rad], [-0.45 * rad, 0], [-0.8 * rad, -0.75 * rad]]
      .map(([fx, fz]) => project(place(r, 0, [fx, y, fz])));
    if (pts.some((p) => !p)) return;
    g.beginPath();
    g.moveTo(pts[0][0], pts[0][1]);
    for (const p of pts.slice(1)) g.lineTo(p[0], p[1]);
    g.closePath();
    g.fillStyle = rgb(robot.colour);
    g.fill();
    g.strokeStyle = i === view.robot ? "#fff" : "#000";
    g.lineWidth = 1.5;
    g.stroke();
  });
}

function drawRetina() {
  const box = $("retinas");
  const robot = view.scene.robots[view.robot];
  const rows = [];
  for (let k = Math.max(0, view.cur - 199); k <= view.cur; k++) {
    const r = view.hist[k] && view.hist[k].robots[view.robot];
    if (r && r[7]) rows.push(r[7]);
  }
  if (!robot || !robot.retina || rows.length === 0) {
    if (box.dataset.kinds !== "") { box.textContent = robot && robot.retina ? "waiting for the retina" : "no retina"; box.dataset.kinds = ""; }
    return;
  }
  const kinds = Object.keys(rows[rows.length - 1]);
  if (box.dataset.kinds !== kinds.join()) {
    box.textContent = "";
    for (const kind of kinds) {
      const label = document.createElement("div");
      label.textContent = kind === "image" ? "normalised image" : `${kind} filter`;
      const c = document.createElement("canvas");
      c.width = 150; c.height = 100; c.dataset.kind = kind;
      c.style.height = "100px"; c.style.imageRendering = "pixelated";
      box.append(label, c);
    }
    box.dataset.kinds = kinds.join();
  }
  for (const c of box.querySelectorAll("canvas")) {
    const g = c.getContext("2d");
    const img = g.createImageData(150, 100);
    const shown = rows.slice(-100);
    const offset = 100 - shown.length;
    shown.forEach((row, y) => {
      const values = row[c.dataset.kind] || [];
      for (let x = 0; x < 150; x++) {
        const v = values[x] || 0;
        const o = 4 * ((y + offset) * 150 + x);
        if (c.dataset.kind === "image") {
          const w = Math.max(0, Math.min(255, v * 255));
          img.data[o] = img.data[o + 1] = img.data[o + 2] = w;
        } else {
          // Diverging: blue below zero, orange above.
          const a = Math.max(-1, Math.min(1, v));
          img.data[o] = a > 0 ? 40 + 215 * a : 40;
          img.data[o + 1] = 40 + 100 * Math.abs(a);
          img.data[o + 2] = a < 0 ? 40 - 215 * a : 40;
        }
        img.data[o + 3] = 255;
      }
    });
    g.putImageData(img, 0, 0);
  }
}

// The last WINDOW seconds of one robot's readings, newest at the right.
const WINDOW = 10;

function series(id, pick, count, fixedMax) {
  const c = $(id), g = c.getContext("2d");
  g.fillStyle = "#111"; g.fillRect(0, 0, c.width, c.height);
  const now = view.hist[view.cur] ? view.hist[view.cur].t : 0;
  let from = view.cur;
  while (from > 0 && view.hist[from - 1].t >= now - WINDOW) from--;
  const rows = view.hist.slice(from, view.cur + 1).filter((s) => s.robots[view.robot]);
  if (rows.length === 0) return;
  let lo = 0, hi = fixedMax || 1;
  if (!fixedMax) {
    for (const s of rows) for (let k = 0; k < count; k++) hi = Math.max(hi, Math.abs(pick(s.robots[view.robot], k)));
    lo = -hi;
  }
  const y = (v) => c.height - 2 - (v - lo) / (hi - lo) * (c.height - 4);
  g.strokeStyle = "#444"; g.beginPath(); g.moveTo(0, y(0)); g.lineTo(c.width, y(0)); g.stroke();
  for (let k = 0; k < count; k++) {
    g.beginPath();
    rows.forEach((s, i) => {
      const px = c.width * (1 - (now - s.t) / WINDOW);
      const py = y(pick(s.robots[view.robot], k));
      if (i) g.lineTo(px, py); else g.moveTo(px, py);
    });
    g.strokeStyle = count === 2 ? ["#56b4e9", "#e69f00"][k] : PALETTE_IR[k];
    g.lineWidth = 1.3;
    g.stroke();
  }
}

function drawStatus() {
  const s = view.status, sample = view.hist[view.cur];
  const t = sample ? sample.t.toFixed(2) : "–";
  let text = `t ${t} s`;
  if (sample) text += ` · step ${sample.steps}`;
  if (!s.replay) {
    text += ` · ${s.speed == null ? "as fast as possible" : s.speed + "× real time"}`;
    if (s.rate) text += ` · ${Math.round(s.rate)} steps/s`;
    if (s.finished) text += " · ended";
    else if (s.paused) text += " · paused";
  }
  $("status").textContent = text;
  $("note").textContent = s.note || "";
  $("play").textContent = (s.replay ? !view.playing : s.paused) ? "play" : "pause";
  // The selector follows the run's speed (another client, or --speed, may have set it).
  if (!s.replay && document.activeElement !== $("speed")) {
    const value = s.speed == null ? "fast" : String(s.speed);
    if (![...$("speed").options].some((o) => o.value === value)) {
      const o = document.createElement("option");
      o.value = value; o.textContent = `${value}×`;
      $("speed").append(o);
    }
    $("speed").value = value;
  }
  if (document.activeElement !== $("seed") && s.seed !== undefined) $("seed").placeholder = s.seed;
  if (s.replay) {
    $("scrub").max = String(Math.max(0, view.hist.length - 1));
    $("scrub").value = String(view.cur);
    $("rtime").textContent = `${t} s`;
  }
}

function drawEvents() {
  const box = $("events");
  const names = view.scene.robots.map((r) => r.name);
  const t = view.hist[view.cur] ? view.hist[view.cur].t : Infinity;
  const shown = view.events.filter((e) => e.t <= t + 1e-9).slice(-200).reverse();
  const key = shown.length + ":" + (shown[0] ? shown[0].t : "");
  if (box.dataset.key === key) return;
  box.dataset.key = key;
  box.textContent = "";
  for (const e of shown) {
    const line = document.createElement("div");
    const what = e.kind === "visit" ? `visits buoy ${e.buoy + 1}` : "touches something";
    line.textContent = `${e.t.toFixed(2).padStart(8)} s  ${names[e.robot] || e.robot} ${what}`;
    box.append(line);
  }
}

function frame(now) {
  if (view.playing && view.status.replay) advanceReplay(now);
  if (view.dirty && view.scene && view.cur >= 0) {
    view.dirty = false;
    drawArena();
    drawRetina();
    series("ir", (r, k) => r[6][k], 8, 1023);
    series("wheels", (r, k) => r[3 + k], 2, 0);
    drawEvents();
    drawStatus();
    view.frames++;
  }
  requestAnimationFrame(frame);
}

// ---------- data ----------

function connect() {
  if (view.source) view.source.close();
  const source = new EventSource(api(`events?robot=${view.robot}`));
  view.source = source;
  source.onmessage = (message) => {
    let data;
    try { data = JSON.parse(message.data); } catch (e) { return; }
    if (data.reset) { view.hist = []; view.events = []; }
    view.status = data.status;
    for (const s of data.samples) view.hist.push(s);
    if (view.hist.length > MAX_HISTORY && !data.status.replay) view.hist.splice(0, view.hist.length - MAX_HISTORY);
    for (const e of data.events) view.events.push(e);
    if (view.events.length > 5000) view.events.splice(0, view.events.length - 5000);
    if (data.status.replay) {
      $("timeline").style.display = "flex";
      if (view.cur < 0 || view.cur >= view.hist.length) view.cur = 0;
    } else {
      view.cur = view.hist.length - 1;
    }
    view.dirty = true;
    drawStatus();
  };
  source.onerror = () => { $("status").textContent = "disconnected; retrying…"; };
}

function control(query) {
  fetch(api(`control?${query}`), { method: "POST" }).catch(() => {});
}

function advanceReplay(now) {
  if (view.playFrom === null) view.playFrom = { wall: now, t: view.hist[view.cur].t };
  const speed = $("speed").value === "fast" ? 100 : Number($("speed").value);
  const target = view.playFrom.t + (now - view.playFrom.wall) / 1000 * speed;
  let k = view.cur;
  while (k + 1 < view.hist.length && view.hist[k + 1].t <= target) k++;
  if (k !== view.cur) { view.cur = k; view.dirty = true; }
  if (k + 1 >= view.hist.length) { view.playing = false; view.dirty = true; }
}

function controls() {
  $("play").onclick = () => {
    if (view.status.replay) {
      if (view.cur + 1 >= view.hist.length) view.cur = 0;
      view.playing = !view.playing; view.playFrom = null; view.dirty = true;
    } else control(view.status.paused ? "cmd=play" : "cmd=pause");
  };
  $("rplay").onclick = $("play").onclick;
  $("step").onclick = () => {
    if (view.status.replay) { view.playing = false; view.cur = Math.min(view.cur + 1, view.hist.length - 1); view.dirty = true; }
    else control("cmd=step&n=1");
  };
  $("speed").onchange = () => {
    view.playFrom = null;
    if (!view.status.replay) control(`cmd=speed&x=${$("speed").value}`);
  };
  $("reset").onclick = () => {
    if (view.status.replay) { view.cur = 0; view.playing = false; view.dirty = true; }
    else control(`cmd=reset&seed=${encodeURIComponent($("seed").value)}`);
  };
  $("top").onclick = () => fitCamera(view.camera.pitch < 1.5);
  $("robot").onchange = () => { view.robot = Number($("robot").value); connect(); view.dirty = true; };
  $("scrub").oninput = () => { view.playing = false; view.cur = Number($("scrub").value); view.dirty = true; };
  const canvas = $("arena");
  let drag = null;
  canvas.onpointerdown = (e) => { drag = [e.clientX, e.clientY]; canvas.setPointerCapture(e.pointerId); };
  canvas.onpointerup = () => { drag = null; };
  canvas.onpointermove = (e) => {
    if (!drag) return;
    view.camera.yaw -= (e.clientX - drag[0]) * 0.008;
    view.camera.pitch = Math.max(0.05, Math.min(Math.PI / 2 - 1e-4, view.camera.pitch + (e.clientY - drag[1]) * 0.008));
    drag = [e.clientX, e.clientY];
    view.dirty = true;
  };
  canvas.onwheel = (e) => { e.preventDefault(); view.camera.dist *= Math.exp(e.deltaY * 0.001); view.dirty = true; };
  window.onresize = () => { view.dirty = true; };
}

async function main() {
  const response = await fetch(api("scene.json"));
  view.scene = await response.json();
  view.fixed = triangles(view.scene.static);
  view.robotTris = view.scene.robots.map((r) => triangles(r.mesh));
  $("title").textContent = view.scene.title || "regatta";
  document.title = `regatta view · ${view.scene.title || "world"}`;
  view.scene.robots.forEach((r, i) => {
    const o = document.createElement("option");
    o.value = String(i); o.textContent = r.name;
    $("robot").append(o);
  });
  const params = new URLSearchParams(location.search);
  fitCamera(params.get("camera") === "top");
  controls();
  connect();
  requestAnimationFrame(frame);
}

main();
