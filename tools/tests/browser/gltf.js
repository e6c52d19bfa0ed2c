// Loads glTF exports in Debian's Chromium headless with three.js' GLTFLoader (npm `three`,
// from target/npm) and renders each from its world's Viewpoint (the export's camera): once
// shaded (lights, materials, textures) and once as a silhouette (every surface white on
// black). Chromium is driven over the DevTools protocol on a pipe; the page and three.js are
// served by a small HTTP server here (ES modules do not load from file: URLs).
// Prints one JSON line: for each file, the loader's errors and the two PNGs written.
// Usage: NODE_PATH=target/npm/node_modules node gltf.js OUTDIR WIDTHxHEIGHT FILE.glb...
"use strict";
const { spawn } = require("child_process");
const fs = require("fs");
const http = require("http");
const os = require("os");
const path = require("path");

const [outDir, size, ...files] = process.argv.slice(2);
const [width, height] = size.split("x").map(Number);
// The package's folder, found along NODE_PATH as `require` would (its exports hide
// package.json).
const threeDir = (process.env.NODE_PATH || "").split(path.delimiter)
  .map((dir) => path.join(dir, "three")).find((dir) => fs.existsSync(path.join(dir, "build")));
if (!threeDir) throw new Error("three.js is not installed (npm install --prefix target/npm three)");

const page = `<!doctype html><html><body style="margin:0;background:#000">
<script type="importmap">{"imports": {"three": "/three/build/three.module.js",
  "three/addons/": "/three/examples/jsm/"}}</script>
<script type="module">
import * as THREE from "three";
import { GLTFLoader } from "three/addons/loaders/GLTFLoader.js";
window.renderGlb = async (url, width, height, silhouette) => {
  const errors = [];
  const gltf = await new Promise((resolve) => new GLTFLoader().load(url, resolve, undefined,
    (e) => { errors.push(String(e && e.message || e)); resolve(null); }));
  if (!gltf) return { errors };
  const scene = gltf.scene;
  const camera = gltf.cameras[0];
  if (!camera) return { errors: ["the export has no camera"] };
  camera.aspect = width / height;
  camera.updateProjectionMatrix();
  scene.updateMatrixWorld(true);
  if (silhouette) {
    const white = new THREE.MeshBasicMaterial({ color: 0xffffff, side: THREE.DoubleSide });
    scene.traverse((o) => { if (o.isMesh) o.material = white; if (o.isLight) o.visible = false;
      if (o.isLine || o.isPoints) o.visible = false; });
    scene.background = new THREE.Color(0x000000);
  } else {
    scene.add(new THREE.AmbientLight(0xffffff, 0.6));
    scene.background = new THREE.Color(0x202020);
  }
  const canvas = document.createElement("canvas");
  canvas.width = width; canvas.height = height;
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: false, preserveDrawingBuffer: true });
  renderer.setSize(width, height, false);
  renderer.render(scene, camera);
  const png = canvas.toDataURL("image/png");
  renderer.dispose();
  return { errors, png };
};
window.ready = true;
</script></body></html>`;

const server = http.createServer((request, response) => {
  const url = decodeURIComponent(request.url.split("?")[0]);
  let file = null;
  let type = "application/octet-stream";
  if (url === "/") {
    response.writeHead(200, { "content-type": "text/html" });
    response.end(page);
    return;
  } else if (url.startsWith("/three/")) {
    file = path.join(threeDir, path.normalize(url.slice("/three/".length)));
    if (file.endsWith(".js")) type = "text/javascript";
  } else if (url.startsWith("/glb/")) {
    file = files[Number(url.slice("/glb/".length))];
  }
  if (!file || !fs.existsSync(file)) {
    response.writeHead(404);
    response.end();
    return;
  }
  response.writeHead(200, { "content-type": type });
  fs.createReadStream(file).pipe(response);
});

const profile = fs.mkdtempSync(path.join(os.tmpdir(), "regatta-chromium-"));
let browser = null;
let browserLog = "";
let nextId = 1;
const pending = new Map();
let buffer = Buffer.alloc(0);

function send(method, params = {}, sessionId) {
  const id = nextId++;
  const message = { id, method, params };
  if (sessionId) message.sessionId = sessionId;
  browser.stdio[3].write(JSON.stringify(message) + "\0");
  return new Promise((resolve, reject) => pending.set(id, { resolve, reject }));
}

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

async function main() {
  await new Promise((resolve) => server.listen(0, "127.0.0.1", resolve));
  const origin = `http://127.0.0.1:${server.address().port}`;
  browser = spawn(process.env.CHROMIUM || "chromium", [
    "--headless", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
    "--disable-quic", "--no-first-run", "--disable-background-networking",
    "--disable-component-update", "--disable-sync", "--disable-dev-shm-usage",
    "--hide-scrollbars", "--remote-debugging-pipe", `--user-data-dir=${profile}`, "about:blank",
  ], { stdio: ["ignore", "ignore", "pipe", "pipe", "pipe"] });
  browser.stderr.on("data", (d) => { browserLog += d; });
  browser.stdio[4].on("data", (chunk) => {
    buffer = Buffer.concat([buffer, chunk]);
    let end;
    while ((end = buffer.indexOf(0)) >= 0) {
      const message = JSON.parse(buffer.subarray(0, end).toString());
      buffer = buffer.subarray(end + 1);
      const waiter = pending.get(message.id);
      if (waiter) {
        pending.delete(message.id);
        if (message.error) waiter.reject(new Error(JSON.stringify(message.error)));
        else waiter.resolve(message.result);
      }
    }
  });
  const { targetId } = await send("Target.createTarget", { url: "about:blank" });
  const { sessionId } = await send("Target.attachToTarget", { targetId, flatten: true });
  const tab = (method, params) => send(method, params, sessionId);
  const evaluate = async (expression) => {
    const r = await tab("Runtime.evaluate", { expression, awaitPromise: true, returnByValue: true });
    if (r.exceptionDetails) throw new Error(`${expression}: ${JSON.stringify(r.exceptionDetails)}`);
    return r.result.value;
  };
  await tab("Page.enable");
  await tab("Page.navigate", { url: `${origin}/` });
  const started = Date.now();
  while (!(await evaluate("window.ready === true").catch(() => false))) {
    if (Date.now() - started > 60000) throw new Error("the page did not load three.js");
    await sleep(50);
  }
  const results = [];
  for (let i = 0; i < files.length; i++) {
    const name = path.basename(files[i], ".glb");
    const result = { file: files[i], errors: [] };
    for (const silhouette of [false, true]) {
      const r = await evaluate(`renderGlb("/glb/${i}", ${width}, ${height}, ${silhouette})`);
      result.errors.push(...r.errors);
      if (r.png) {
        const out = path.join(outDir, `${name}-${silhouette ? "mask" : "shaded"}.png`);
        fs.writeFileSync(out, Buffer.from(r.png.split(",")[1], "base64"));
        result[silhouette ? "mask" : "shaded"] = out;
      }
    }
    results.push(result);
  }
  process.stdout.write(JSON.stringify({ results }) + "\n");
}

// The profile goes once the browser has exited (it writes there until then).
function finish(code) {
  server.close();
  if (!browser) process.exit(code);
  browser.on("exit", () => {
    try { fs.rmSync(profile, { recursive: true, force: true }); } catch (e) { /* left in tmp */ }
    process.exit(code);
  });
  browser.kill();
}

main().then(() => finish(0), (error) => {
  process.stderr.write(`${error.stack || error}\n--- chromium ---\n${browserLog.slice(-4000)}\n`);
  finish(1);
});
