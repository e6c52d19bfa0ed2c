// Drives Debian's Chromium headless over the DevTools protocol (on a pipe: no WebSocket, no
// npm package) against a running `regatta view`: waits for frames of the running world,
// pauses it, takes a screenshot, steps the world, takes another, and prints as JSON where
// the page draws each robot (at the poses the run reports in /state.json) and each lamp.
// The Rust test reads the pixels. Usage: node view.js URL OUTDIR STEPS (URL with its ?token=)
"use strict";
const { spawn } = require("child_process");
const fs = require("fs");
const os = require("os");
const path = require("path");

const [url, outDir, stepsArg] = process.argv.slice(2);
const steps = Number(stepsArg || 60);
const profile = fs.mkdtempSync(path.join(os.tmpdir(), "regatta-chromium-"));
const browser = spawn(process.env.CHROMIUM || "chromium", [
  "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
  "--disable-background-networking", "--disable-component-update", "--disable-sync",
  "--disable-dev-shm-usage", "--hide-scrollbars", "--remote-debugging-pipe",
  `--user-data-dir=${profile}`, "about:blank",
], { stdio: ["ignore", "ignore", "pipe", "pipe", "pipe"] });
let browserLog = "";
browser.stderr.on("data", (d) => { browserLog += d; });

let nextId = 1;
const pending = new Map();
let buffer = Buffer.alloc(0);
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

function send(method, params = {}, sessionId) {
  const id = nextId++;
  const message = { id, method, params };
  if (sessionId) message.sessionId = sessionId;
  browser.stdio[3].write(JSON.stringify(message) + "\0");
  return new Promise((resolve, reject) => pending.set(id, { resolve, reject }));
}

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

async function main() {
  const { targetId } = await send("Target.createTarget", { url: "about:blank" });
  const { sessionId } = await send("Target.attachToTarget", { targetId, flatten: true });
  const page = (method, params) => send(method, params, sessionId);
  const evaluate = async (expression) => {
    const r = await page("Runtime.evaluate", { expression, awaitPromise: true, returnByValue: true });
    if (r.exceptionDetails) throw new Error(`${expression}: ${JSON.stringify(r.exceptionDetails)}`);
    return r.result.value;
  };
  const until = async (what, expression, seconds = 30) => {
    const started = Date.now();
    for (;;) {
      const value = await evaluate(expression).catch(() => null);
      if (value) return value;
      if (Date.now() - started > seconds * 1000) throw new Error(`timed out waiting for ${what}`);
      await sleep(50);
    }
  };
  await page("Emulation.setDeviceMetricsOverride", { width: 1200, height: 720, deviceScaleFactor: 1, mobile: false });
  await page("Page.enable");
  await page("Page.navigate", { url });
  // The world runs: wait for frames showing it past half a simulated second.
  await until("frames of the running world",
    "window.regatta && window.regatta.frames > 2 && regatta.hist.length > 0 && regatta.hist[regatta.cur].t > 20");
  // The page's own requests carry the URL's token; these carry it the page's way.
  const paused = await evaluate("fetch(regatta.api('control?cmd=pause'), {method: 'POST'}).then(r => r.status)");
  if (paused !== 200) throw new Error(`pause answered ${paused}`);
  const shots = [];
  for (const [index, advance] of [[1, 0], [2, steps]]) {
    const stepped = advance && await evaluate(`fetch(regatta.api('control?cmd=step&n=${advance}'), {method: 'POST'}).then(r => r.status)`);
    if (advance && stepped !== 200) throw new Error(`step answered ${stepped}`);
    const before = index === 1 ? null : shots[0].state.sample.steps;
    // The run's own report of where it stands, once it has stopped moving.
    const state = await until("the paused run", `fetch(regatta.api('state.json')).then(r => r.json()).then(s =>
      s.status.paused && s.sample && (${before === null} || s.sample.steps >= ${before} + ${advance}) ? s : null)`);
    await until("the page showing that step", `(() => { const s = regatta.hist[regatta.cur];
      return s && s.steps === ${state.sample.steps} && !regatta.dirty; })()`);
    const frames = await evaluate("regatta.frames");
    await until("one more frame", `(() => { regatta.dirty = true; return regatta.frames > ${frames}; })()`);
    const probes = await evaluate(`(() => {
      const s = ${JSON.stringify(state.sample)};
      const scene = regatta.scene;
      return {
        robots: scene.robots.map((r, i) => ({ name: r.name, colour: r.colour,
          at: regatta.project(s.robots[i][0], r.floorY + r.bodyHeight + 0.004, s.robots[i][1]) })),
        lamps: scene.buoys.map((b) => ({ name: b.name, colour: b.lamp, at: regatta.project(b.x, b.lampY, b.z) })),
      };
    })()`);
    const shot = await page("Page.captureScreenshot", { format: "png" });
    const file = path.join(outDir, `view-${index}.png`);
    fs.writeFileSync(file, Buffer.from(shot.data, "base64"));
    shots.push({ file, state, probes });
  }
  process.stdout.write(JSON.stringify({ shots }) + "\n");
}

// The profile goes once the browser has exited (it writes there until then).
function finish(code) {
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
