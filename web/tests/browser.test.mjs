// Browser tests for the SLAM Lab web build (web/dist/), in headless Chromium.
//
// Run with web/test.sh (it builds web/dist first if needed). What it does:
//   - serves web/dist on a free 127.0.0.1 port (a small static server in this file);
//   - opens index.html?lesson=landmark-slam&seed=7, waits for #status "running", and looks
//     at screenshots to check that the canvas is really drawn (not blank);
//   - clicks the canvas and presses Space (run) and the stepping keys, and checks that the
//     simulation advances (slamlab_test_state()) and the picture changes;
//   - opens the embed URL, a malformed URL and the lecture page with its three iframes
//     (and its homework figure: an assignment link graded in the page);
//   - opens the "Many runs" window from the URL and checks its averages against native ones;
//   - fails on any console error, uncaught exception, failed request or Rust panic.
// Screenshots, metrics.json (time to first frame, wasm size) and result.json go to
// web/test-output/. The last line is "N passed, M failed"; the exit code is 1 on failure.
//
// Environment: SLAMLAB_CHROMIUM (default /usr/bin/chromium).

import { createServer } from "node:http";
import { readFile, mkdir, writeFile, stat } from "node:fs/promises";
import { gzipSync, inflateRawSync } from "node:zlib";
import path from "node:path";
import { fileURLToPath } from "node:url";
import { chromium } from "playwright-core";
import { decodePng, imageStats, changedShare } from "./png.mjs";
import { photoPair } from "./photos.mjs";
import { HERO, LESSON_SHOTS, pictureSize, takePictures } from "./screenshots.mjs";

const webDir = path.resolve(path.dirname(fileURLToPath(import.meta.url)), "..");
const distDir = path.join(webDir, "dist");
// The external data sets beside the repository (README: ../shared/data); checks that
// need them skip with a message when they are absent.
// SLAMLAB_SHARED_DATA names them elsewhere (a worktree away from the repository).
const sharedDataDir = path.resolve(process.env.SLAMLAB_SHARED_DATA || path.join(webDir, "..", "..", "shared", "data"));
// Small test files kept in the repository (a ROS 2 bag written by rosbags).
const repoDataDir = path.resolve(webDir, "..", "crates", "slamlab-sim", "tests", "data");
const outDir = path.join(webDir, "test-output");
const chromiumPath = process.env.SLAMLAB_CHROMIUM || "/usr/bin/chromium";

const LESSON = "lesson=landmark-slam&seed=7";
const VIEWPORT = { width: 1280, height: 800 };
const START_TIMEOUT_MS = 90_000; // loading and compiling ~10 MB of wasm on a slow CI machine
const RUN_WAIT_MS = 2_000; // how long the simulation runs after Space
const LOAD_RUN_MS = 6_000; // how long the 50-landmark run is timed
// A drawn canvas has text, lines and shapes: many colours, and a visible share of pixels
// that differ from the background. A blank or cleared canvas has one colour.
const MIN_DISTINCT_COLOURS = 16;
const MIN_NON_BACKGROUND_SHARE = 0.001;
// After two seconds of running, at least this share of the pixels must have changed.
const MIN_CHANGED_SHARE = 0.0005;
// Harmless messages from wgpu/egui in a GPU-less headless browser (they are warnings; the
// list is here in case a future version logs them as errors).
const ALLOWED_CONSOLE = [/No available adapters/, /Software rasterizer detected/];

const CHROMIUM_ARGS = [
  "--no-sandbox", // CI and containers run as root
  "--no-first-run",
  "--disable-background-networking",
  "--disable-component-update",
  "--disable-sync",
  "--disable-quic",
  "--use-angle=swiftshader", // WebGL2 on the CPU (SwiftShader): no GPU needed
  "--enable-unsafe-swiftshader",
];

// ---------------------------------------------------------------------------------------
// A static file server for web/dist on 127.0.0.1 and a free port.

const MIME = {
  ".html": "text/html; charset=utf-8",
  ".js": "text/javascript; charset=utf-8",
  ".mjs": "text/javascript; charset=utf-8",
  ".wasm": "application/wasm", // needed by WebAssembly.instantiateStreaming
  ".json": "application/json",
  ".css": "text/css",
  ".png": "image/png",
  ".svg": "image/svg+xml",
};

function startServer(root) {
  const server = createServer(async (req, res) => {
    try {
      const url = new URL(req.url, "http://localhost");
      // /shared-data/ serves ../shared/data (the Intel log), as an instructor would host
      // a log beside the site; everything else comes from web/dist.
      // /repo-data/ serves the repository's small test files the same way.
      const shared = url.pathname.startsWith("/shared-data/");
      const repo = url.pathname.startsWith("/repo-data/");
      const base = shared ? sharedDataDir : repo ? repoDataDir : root;
      const rel = shared
        ? url.pathname.slice("/shared-data".length)
        : repo
          ? url.pathname.slice("/repo-data".length)
          : url.pathname;
      let file = path.normalize(path.join(base, decodeURIComponent(rel)));
      if (!file.startsWith(base)) throw new Error("outside the root");
      if ((await stat(file)).isDirectory()) file = path.join(file, "index.html");
      const body = await readFile(file);
      res.writeHead(200, {
        "Content-Type": MIME[path.extname(file)] ?? "application/octet-stream",
        "Cache-Control": "no-cache",
      });
      res.end(body);
    } catch {
      res.writeHead(404, { "Content-Type": "text/plain" });
      res.end("not found");
    }
  });
  return new Promise((resolve, reject) => {
    server.once("error", reject);
    server.listen(0, "127.0.0.1", () => resolve(server));
  });
}

// ---------------------------------------------------------------------------------------
// Checks: each is one line of output and one entry in result.json.

const results = [];
// SLAMLAB_ONLY=text runs only the checks whose name contains the text (while working
// on one; web/test.sh and CI run them all).
const ONLY = process.env.SLAMLAB_ONLY || "";
async function check(name, body) {
  if (ONLY && !name.includes(ONLY)) return true;
  const started = Date.now();
  try {
    const details = await body();
    results.push({ name, ok: true, details: details ?? null, ms: Date.now() - started });
    console.log(`ok     ${name}${details ? `: ${details}` : ""}`);
    return true;
  } catch (err) {
    results.push({ name, ok: false, error: String(err?.stack ?? err), ms: Date.now() - started });
    console.log(`FAILED ${name}: ${err?.message ?? err}`);
    return false;
  }
}

function assert(condition, message) {
  if (!condition) throw new Error(message);
}

/** The names of a WebAssembly module's custom sections (id 0), in order. */
function customSectionNames(bytes) {
  const names = [];
  let at = 8; // magic and version
  const leb = () => {
    let value = 0;
    let shift = 0;
    for (;;) {
      const byte = bytes[at++];
      value += (byte & 0x7f) * 2 ** shift;
      shift += 7;
      if (byte < 0x80 || at >= bytes.length) return value;
    }
  };
  while (at < bytes.length) {
    const id = bytes[at++];
    const size = leb();
    const end = at + size;
    if (id === 0) {
      const length = leb();
      names.push(bytes.subarray(at, at + length).toString("utf8"));
    }
    at = end;
  }
  return names;
}

const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

// ---------------------------------------------------------------------------------------
// Pages.

/** Every page's console, uncaught errors and failed requests. */
const pageLogs = [];

/** Opens `url` in a fresh browser context (no shared cache or local storage). */
async function openPage(browser, baseUrl, relativeUrl, label, viewport = VIEWPORT) {
  const context = await browser.newContext({ viewport, deviceScaleFactor: 1 });
  const page = await context.newPage();
  const log = { label, url: relativeUrl, console: [], problems: [] };
  pageLogs.push(log);
  page.on("console", (msg) => {
    const text = msg.text();
    log.console.push(`[${msg.type()}] ${text}`);
    if (msg.type() === "error" && !ALLOWED_CONSOLE.some((re) => re.test(text))) {
      log.problems.push(`console.error: ${text}`);
    }
  });
  page.on("pageerror", (err) => log.problems.push(`uncaught exception: ${err.message}`));
  page.on("requestfailed", (req) => log.problems.push(`request failed: ${req.url()} (${req.failure()?.errorText})`));
  page.on("response", (res) => {
    if (res.status() >= 400) log.problems.push(`HTTP ${res.status()} for ${res.url()}`);
  });
  // In every frame: note when #status changes state (performance.now(): ms since navigation start).
  await page.addInitScript(() => {
    window.__slamlabStatusTimes = {};
    document.addEventListener("DOMContentLoaded", () => {
      const status = document.getElementById("status");
      if (!status) return;
      const note = () => {
        const state = status.dataset.state;
        if (!(state in window.__slamlabStatusTimes)) window.__slamlabStatusTimes[state] = performance.now();
      };
      note();
      new MutationObserver(note).observe(status, { attributes: true, childList: true, characterData: true, subtree: true });
    });
  });
  await page.goto(new URL(relativeUrl, baseUrl).href, { waitUntil: "load" });
  return { context, page, log };
}

/** Waits until the app in `frame` has left "loading"; throws unless #status says "running". */
async function waitRunning(frame) {
  await frame.waitForFunction(
    () => ["running", "error", "panicked"].includes(document.getElementById("status")?.dataset.state),
    null,
    { timeout: START_TIMEOUT_MS, polling: 50 },
  );
  const { text, times } = await frame.evaluate(() => ({
    text: document.getElementById("status").textContent.trim(),
    times: window.__slamlabStatusTimes,
  }));
  assert(text === "running", `#status is "${text}", not "running"`);
  return times.running;
}

/** The app's own summary (SlamLabApp::test_state_json) through the wasm export. */
async function testState(frame) {
  const json = await frame.evaluate(() => window.slamlab.slamlab_test_state());
  const state = JSON.parse(json);
  assert(!("error" in state), `slamlab_test_state() says ${json}`);
  return state;
}

/** Drops files on the app's canvas as a drag from the desktop would, all in one drop.
 * Each file is `{ name, type }` (the MIME type, text/plain when none is given) and one of
 * `text` (a string), `bytes` (an array of bytes), `b64` (bytes in base64, compact for
 * photos), `url` (fetched by the page from this server, e.g. `shared-data/...`) or `zeros`
 * (that many zero bytes, made in the page so that a huge file never crosses over). */
async function dropFiles(frame, files) {
  await frame.evaluate(async (list) => {
    const dt = new DataTransfer();
    for (const f of list) {
      let body = f.text;
      if (f.bytes !== undefined) body = new Uint8Array(f.bytes);
      if (f.b64 !== undefined) body = Uint8Array.from(atob(f.b64), (c) => c.charCodeAt(0));
      if (f.url !== undefined) body = new Uint8Array(await (await fetch(f.url)).arrayBuffer());
      if (f.zeros !== undefined) body = new Uint8Array(f.zeros);
      dt.items.add(new File([body], f.name, { type: f.type || "text/plain" }));
    }
    const canvas = document.getElementById("the_canvas_id");
    for (const type of ["dragenter", "dragover", "drop"]) {
      canvas.dispatchEvent(new DragEvent(type, { dataTransfer: dt, bubbles: true, cancelable: true }));
    }
  }, files);
}

/** Drops files fetched by the page from this server: each `[url, name]`. */
async function dropFetched(frame, files) {
  await dropFiles(frame, files.map(([url, name]) => ({ url, name })));
}

/** The files of a zip as the app's exports write it: its local file headers
 * (PK\x03\x04), each deflated (method 8) or stored (0), by name. */
function unzip(bytes) {
  const files = {};
  let at = 0;
  while (at + 30 <= bytes.length && bytes.readUInt32LE(at) === 0x04034b50) {
    const method = bytes.readUInt16LE(at + 8);
    const size = bytes.readUInt32LE(at + 18);
    const nameLength = bytes.readUInt16LE(at + 26);
    const extra = bytes.readUInt16LE(at + 28);
    const name = bytes.subarray(at + 30, at + 30 + nameLength).toString("utf8");
    const start = at + 30 + nameLength + extra;
    const data = bytes.subarray(start, start + size);
    files[name] = method === 8 ? inflateRawSync(data) : Buffer.from(data);
    at = start + size;
  }
  return files;
}

/** Polls the app's state until `done(state)` holds; throws after `timeoutMs`. */
async function waitState(frame, done, what, timeoutMs = 15_000) {
  const deadline = Date.now() + timeoutMs;
  let state = await testState(frame);
  while (!done(state)) {
    if (Date.now() > deadline) throw new Error(`timed out after ${timeoutMs} ms waiting for ${what}; state ${JSON.stringify(state)}`);
    await sleep(50);
    state = await testState(frame);
  }
  return state;
}

/** The lesson state (JSON) after `steps` ticks of `query` run without drawing in the page's wasm. */
async function runHeadless(page, query, steps) {
  return JSON.parse(await page.evaluate(([q, n]) => window.slamlab.slamlab_test_headless(q, n), [query, steps]));
}

/**
 * Replays a recorded log in the page's wasm without drawing: `query`'s lesson reads the file
 * at `url` (same host) under `name` for at most `steps` steps. Returns the lesson state
 * (JSON) and the seconds the replay took in the page (the download not counted).
 */
async function replayLog(page, query, url, name, steps) {
  const took = await page.evaluate(async ([q, u, file, n]) => {
    const bytes = new Uint8Array(await (await fetch(u)).arrayBuffer());
    const started = performance.now();
    const state = window.slamlab.slamlab_test_headless_log(q, file, bytes, n);
    return { state, ms: performance.now() - started };
  }, [query, url, name, steps]);
  return { headless: JSON.parse(took.state), seconds: took.ms / 1000 };
}

/** As replayLog, for a data set of several files `names` in the folder `dir` (same host). */
async function replayFiles(page, query, dir, names, steps) {
  const took = await page.evaluate(async ([q, d, list, n]) => {
    const parts = [];
    for (const name of list) parts.push(new Uint8Array(await (await fetch(`${d}/${name}`)).arrayBuffer()));
    const bytes = new Uint8Array(parts.reduce((total, b) => total + b.length, 0));
    let at = 0;
    for (const b of parts) {
      bytes.set(b, at);
      at += b.length;
    }
    const lengths = new Uint32Array(parts.map((b) => b.length));
    const started = performance.now();
    const state = window.slamlab.slamlab_test_headless_files(q, list.join("\n"), bytes, lengths, n);
    return { state, ms: performance.now() - started };
  }, [query, dir, names, steps]);
  return { headless: JSON.parse(took.state), seconds: took.ms / 1000 };
}

/** Throws if the app has panicked (the export, or the visible banner). */
async function assertNoPanic(frame) {
  const p = await frame.evaluate(() => ({
    panicked: window.slamlab.slamlab_panicked(),
    message: window.slamlab.slamlab_panic_message() ?? null,
    banner: !document.getElementById("panic").hidden,
    bannerText: document.getElementById("panic").textContent,
  }));
  assert(!p.panicked && !p.banner, `the app panicked: ${p.message ?? p.bannerText}`);
}

async function screenshot(target, name) {
  const buffer = await target.screenshot({ path: path.join(outDir, name) });
  return decodePng(buffer);
}

function describe(stats) {
  return `${stats.distinctColours} colours, ${(100 * stats.nonDominantShare).toFixed(2)} % non-background`;
}

function assertNotBlank(stats, what) {
  assert(
    stats.distinctColours >= MIN_DISTINCT_COLOURS && stats.nonDominantShare >= MIN_NON_BACKGROUND_SHARE,
    `${what} looks blank: ${describe(stats)} (background ${stats.dominantColour})`,
  );
}

/** Screenshots until the canvas shows something; returns the image and when it was seen. */
async function waitNotBlank(page, name) {
  const deadline = Date.now() + 30_000;
  for (;;) {
    const image = await screenshot(page, name);
    const seenAt = await page.evaluate(() => performance.now());
    const stats = imageStats(image);
    const blank = stats.distinctColours < MIN_DISTINCT_COLOURS || stats.nonDominantShare < MIN_NON_BACKGROUND_SHARE;
    if (!blank || Date.now() > deadline) return { image, stats, seenAt };
    await sleep(100);
  }
}

/**
 * What every check of one page does around its own steps: opens `relativeUrl` in a fresh
 * context (openPage), runs `body({ context, page, log })`, then throws if the app panicked
 * or the page logged a problem (console error, uncaught exception, failed request), and
 * closes the context whatever happened. Returns what `body` returns (the check's note).
 */
async function withPage(browser, baseUrl, relativeUrl, label, body, viewport = VIEWPORT) {
  const opened = await openPage(browser, baseUrl, relativeUrl, label, viewport);
  try {
    const note = await body(opened);
    await assertNoPanic(opened.page);
    assert(opened.log.problems.length === 0, opened.log.problems.join("; "));
    return note;
  } finally {
    await opened.context.close();
  }
}

/** Opens a URL and checks that the app starts, draws and does not panic. */
async function checkStartsAndDraws(browser, baseUrl, relativeUrl, label, shotName) {
  return withPage(browser, baseUrl, relativeUrl, label, async ({ page }) => {
    await waitRunning(page);
    const { stats } = await waitNotBlank(page, shotName);
    assertNotBlank(stats, shotName);
    await testState(page);
    await sleep(500); // a few more frames: a panic in the first frames would show up now
    return `${describe(stats)}; state ${JSON.stringify(await testState(page))}`;
  });
}

// ---------------------------------------------------------------------------------------

async function main() {
  await mkdir(outDir, { recursive: true });
  const wasmPath = path.join(distDir, "pkg", "slamlab_app_bg.wasm");
  const wasm = await readFile(wasmPath).catch(() => null);
  if (!wasm) {
    console.log(`web/dist is missing or incomplete (${wasmPath}): run web/build.sh first`);
    console.log("0 passed, 1 failed");
    process.exit(1);
  }
  const metrics = { wasm_bytes: wasm.length, wasm_gzip_bytes: gzipSync(wasm, { level: 9 }).length };

  // --- The download's budget once binaryen's wasm-opt has shrunk it (web/build.sh's
  // default; a SLAMLAB_WASM_OPT=0 build keeps its function names, the "name" section, and
  // is not held to it): at most 6.9 MB and 2.85 MB gzipped. The targets (6 MB, 2 MB
  // gzipped) are not met since ROS 2 bags, zip archives and the real landmark data sets
  // came in (6,400,679 bytes, 2,624,595 gzipped on 2026-11-28), and homework in the page
  // (the assignments' inputs and graders: 6,675,148 bytes, 2,739,113 gzipped (Node, level 9) with the
  // pose-graph, grid-mapping and icp assignments; 6,810,899 and 2,800,868 with the fusion
  // assignment, the map and graph drop-in and Victoria Park's reference map); the bound
  // keeps the download from growing unnoticed. docs/web-build.md says what the bytes are.
  await check("the wasm download is at most 6.9 MB (2.85 MB gzipped)", async () => {
    const sizes = `${metrics.wasm_bytes} bytes, ${metrics.wasm_gzip_bytes} gzip -9`;
    if (customSectionNames(wasm).includes("name")) return `${sizes}; not checked: built without wasm-opt`;
    assert(metrics.wasm_bytes <= 6_900_000, `${sizes}: over the 6,900,000-byte budget`);
    assert(metrics.wasm_gzip_bytes <= 2_850_000, `${sizes}: over the 2,850,000-byte gzip budget`);
    return sizes;
  });

  const server = await startServer(distDir);
  const baseUrl = `http://127.0.0.1:${server.address().port}/`;
  console.log(`serving ${distDir} at ${baseUrl}`);
  const browser = await chromium.launch({ executablePath: chromiumPath, headless: true, args: CHROMIUM_ARGS });
  console.log(`browser: Chromium ${browser.version()}`);

  try {
    // --- The main page: start, first frame, run, step.
    const main = await openPage(browser, baseUrl, `index.html?${LESSON}`, "main");
    const { page } = main;
    let before = null;

    const started = await check(`index.html?${LESSON} starts (#status "running")`, async () => {
      metrics.status_running_ms = Math.round(await waitRunning(page));
      return `after ${metrics.status_running_ms} ms`;
    });

    if (started) {
      await check("the canvas is drawn (not blank)", async () => {
        const { image, stats, seenAt } = await waitNotBlank(page, "main-1-start.png");
        assertNotBlank(stats, "main-1-start.png");
        before = image;
        metrics.ttff_ms = Math.round(seenAt);
        metrics.start_screenshot = stats;
        return `${describe(stats)}; first drawn frame seen after ${metrics.ttff_ms} ms`;
      });

      await check("Space runs the simulation and the view changes", async () => {
        await page.mouse.click(VIEWPORT.width / 2, VIEWPORT.height / 2); // gives the canvas keyboard focus
        await sleep(300);
        const clicked = await screenshot(page, "main-2-clicked.png");
        const s0 = await testState(page);
        await page.keyboard.press("Space");
        const startedAt = Date.now();
        if ("tick" in s0) await waitState(page, (s) => s.tick > s0.tick, "the first tick after Space");
        await sleep(Math.max(0, RUN_WAIT_MS - (Date.now() - startedAt)));
        const s1 = await testState(page);
        const after = await screenshot(page, "main-3-running.png");
        const seconds = (Date.now() - startedAt) / 1000;
        const changed = changedShare(clicked, after);
        metrics.run_changed_share = Number(changed.toFixed(4));
        metrics.run_frames_per_second = Number(((s1.frames - s0.frames) / seconds).toFixed(1));
        if ("tick" in s1) metrics.run_ticks_per_second = Number(((s1.tick - s0.tick) / seconds).toFixed(1));
        const summary =
          `state ${JSON.stringify(s0)} -> ${JSON.stringify(s1)}; ${(100 * changed).toFixed(2)} % of pixels changed; ` +
          `${metrics.run_frames_per_second} frames/s while running`;
        if ("tick" in s1) {
          assert(s1.tick > s0.tick, `tick did not increase: ${summary}`);
          if ("running" in s1) assert(s1.running === true, `"running" is not true after Space: ${summary}`);
          assert(changed >= MIN_CHANGED_SHARE, `the view did not change while running: ${summary}`);
        } else {
          // The placeholder app has no simulation yet: check that it keeps drawing frames.
          assert(s1.frames > s0.frames, `no new frames: ${summary}`);
          return `${summary} (no "tick" in the state yet: checked frames only)`;
        }
        return summary;
      });

      await check("Space pauses, 'n' steps one tick, '.' steps a phase, 'r' resets", async () => {
        // The app handles a key in its next frame, and frames are slow in a software
        // renderer on a busy CI machine: wait for each key's effect instead of sleeping.
        const history = [];
        const note = (s) => (history.push(s), s);
        const explain = () => history.map((s) => JSON.stringify(s)).join(" -> ");
        const hasTick = "tick" in (await testState(page));
        const pressAndWait = async (key, done, what) => {
          const before = note(await testState(page));
          await page.keyboard.press(key);
          return note(await waitState(page, (s) => (hasTick ? done(s, before) : s.frames > before.frames), what));
        };

        const paused = await pressAndWait(
          "Space",
          (s) => ("running" in s ? s.running === false : true),
          "pause after Space",
        );
        await sleep(1000);
        const stillPaused = note(await testState(page));
        const stepped = await pressAndWait("n", (s, b) => s.tick !== b.tick, "a tick after 'n'");
        await sleep(300); // a second step would show up now
        const steppedSettled = note(await testState(page));
        const phased = await pressAndWait(".", (s, b) => s.tick !== b.tick || s.phase !== b.phase, "a phase after '.'");
        await screenshot(page, "main-4-stepped.png");
        const reset = await pressAndWait("r", (s, b) => s.tick < b.tick, "a reset after 'r'");
        await screenshot(page, "main-5-reset.png");
        if (hasTick) {
          if ("running" in paused) assert(paused.running === false, `"running" is not false after the second Space: ${explain()}`);
          assert(stillPaused.tick === paused.tick, `tick advanced while paused: ${explain()}`);
          assert(stepped.tick === paused.tick + 1 && steppedSettled.tick === stepped.tick, `'n' did not step exactly one tick: ${explain()}`);
          assert(phased.tick >= stepped.tick, `'.' went back in time: ${explain()}`);
          assert(reset.tick < phased.tick, `'r' did not reset the tick count: ${explain()}`);
        }
        await assertNoPanic(page);
        return explain();
      });

      await check("no panic on the main page", async () => {
        await assertNoPanic(page);
      });
    }
    await main.context.close();

    // --- Other ways in.
    await check(`embed mode: index.html?${LESSON}&embed=1 runs and draws`, () =>
      checkStartsAndDraws(browser, baseUrl, `index.html?${LESSON}&embed=1`, "embed", "embed.png"),
    );
    await check("a malformed URL (?lesson=nope&seed=abc) still runs and draws", () =>
      checkStartsAndDraws(browser, baseUrl, "index.html?lesson=nope&seed=abc", "malformed", "malformed-url.png"),
    );

    // --- The lecture page with two embedded apps.
    await check("lecture.html: the three embedded apps run and draw", async () => {
      const { context, page: lecture, log } = await openPage(browser, baseUrl, "lecture.html", "lecture");
      try {
        const iframes = lecture.locator("iframe.slamlab");
        const count = await iframes.count();
        assert(count === 3, `expected 3 iframes, found ${count}`);
        const notes = [];
        for (let i = 0; i < count; i++) {
          // The page loads its figures lazily: bring each into view, as a reader would.
          await iframes.nth(i).scrollIntoViewIfNeeded();
          const frame = await (await iframes.nth(i).elementHandle()).contentFrame();
          await waitRunning(frame);
          let stats = null;
          const deadline = Date.now() + 30_000;
          do {
            stats = imageStats(await screenshot(iframes.nth(i), `lecture-iframe-${i + 1}.png`));
            if (stats.distinctColours >= MIN_DISTINCT_COLOURS && stats.nonDominantShare >= MIN_NON_BACKGROUND_SHARE) break;
            await sleep(100);
          } while (Date.now() < deadline);
          assertNotBlank(stats, `iframe ${i + 1}`);
          await assertNoPanic(frame);
          // The iframe's query string reaches the app.
          const params = new URL(frame.url()).searchParams;
          const state = await testState(frame);
          if ("seed" in state) assert(String(state.seed) === params.get("seed"), `iframe ${i + 1}: seed ${state.seed}, URL says ${params.get("seed")}`);
          if ("embed" in state) assert(state.embed === true, `iframe ${i + 1} is not in embed mode: ${JSON.stringify(state)}`);
          if ("filters" in state && params.has("estimator")) {
            assert(state.filters.join(",") === params.get("estimator"), `iframe ${i + 1}: filters ${state.filters}, URL says ${params.get("estimator")}`);
          }
          if (params.has("many-runs")) {
            const runs = Number(params.get("many-runs"));
            const done = await waitState(frame, (st) => st.many_runs && st.many_runs.done === runs, `${runs} runs in iframe ${i + 1}`, 120_000);
            await screenshot(iframes.nth(i), `lecture-iframe-${i + 1}.png`);
            notes.push(`iframe ${i + 1}: ${runs} runs, average NEES ${JSON.stringify(done.many_runs.nees)}`);
          }
          notes.push(`iframe ${i + 1} (${frame.url().split("?")[1]}): ${describe(stats)}`);
        }
        await lecture.screenshot({ path: path.join(outDir, "lecture.png"), fullPage: true });
        assert(log.problems.length === 0, log.problems.join("; "));
        return notes.join("; ");
      } finally {
        await context.close();
      }
    });

    // Opens `url`, presses Space, runs LOAD_RUN_MS and records the frame timing under
    // metrics.`${key}_*`; `filters` is the estimators the lesson must show, as
    // `filtersOf` writes the state's filters; the click that gives the page keyboard
    // focus lands at `focusAt`.
    const timedRun = (
      url,
      key,
      filters,
      { filtersOf = (fs) => fs.join(","), focusAt = [VIEWPORT.width / 2, VIEWPORT.height / 2] } = {},
    ) => async () => {
      return withPage(browser, baseUrl, url, key, async ({ page: p }) => {
        await waitRunning(p);
        const { stats } = await waitNotBlank(p, `${key}-1-start.png`);
        assertNotBlank(stats, `${key}-1-start.png`);
        await p.mouse.click(...focusAt);
        const s0 = await testState(p);
        await p.keyboard.press("Space");
        await waitState(p, (s) => s.tick > s0.tick, "the first tick after Space", 60_000);
        const startedAt = Date.now();
        await sleep(LOAD_RUN_MS);
        const s1 = await testState(p);
        const seconds = (Date.now() - startedAt) / 1000;
        await screenshot(p, `${key}-2-running.png`);
        const t = s1.frame_timing;
        assert(t && t.frames > 0 && Number.isFinite(t.cpu_ms_median), `no frame timing: ${JSON.stringify(s1)}`);
        assert(filtersOf(s1.filters) === filters, `filters ${JSON.stringify(s1.filters)}`);
        assert(s1.tick > s0.tick, "the simulation did not advance");
        metrics[`${key}_frame_cpu_ms_median`] = t.cpu_ms_median;
        metrics[`${key}_frame_cpu_ms_p95`] = t.cpu_ms_p95;
        metrics[`${key}_sim_ms_median`] = t.sim_ms_median;
        metrics[`${key}_sim_ms_p95`] = t.sim_ms_p95;
        metrics[`${key}_frames_per_second`] = Number((1000 / t.interval_ms_median).toFixed(1));
        metrics[`${key}_ticks_per_second`] = Number(((s1.tick - s0.tick) / seconds).toFixed(1));
        return (
          `tick ${s0.tick} -> ${s1.tick} in ${seconds.toFixed(1)} s; frame CPU median ${t.cpu_ms_median.toFixed(2)} ms ` +
          `(p95 ${t.cpu_ms_p95?.toFixed(2)}), simulation ${t.sim_ms_median.toFixed(2)} ms, ` +
          `${metrics[`${key}_frames_per_second`]} frames/s`
        );
      });
    };

    // --- The heaviest landmark setting: 50 landmarks, EKF and UKF side by
    // side. Its frame timing (the app's CPU time per frame, the simulation's share, the
    // frame rate) is recorded in metrics.json, never asserted: wall-clock numbers
    // belong in docs/results.md, not in a pass/fail test.
    await check(
      "50 landmarks with EKF and UKF: runs, draws and reports its frame timing",
      timedRun("index.html?lesson=landmark-slam&seed=1&landmarks=50&estimator=ekf,ukf", "lm50", "ekf,ukf"),
    );

    // --- FastSLAM 2.0 with 100 particles beside EKF and UKF on 50 landmarks (the
    // setting where FastSLAM must stay interactive): recorded the same way.
    await check(
      "FastSLAM 2.0 (100 particles) beside EKF and UKF: runs and reports its frame timing",
      timedRun(
        "index.html?lesson=landmark-slam&seed=1&landmarks=50&estimator=ekf,ukf,fastslam2&particles=100",
        "fastslam100",
        "ekf,ukf,fastslam2",
      ),
    );

    // --- "Many runs" opened by the URL: 20 runs of one lap each, EKF and FEJ-EKF, in
    // the browser's wasm. The averages must be the native ones to the last bit (same seed):
    //   slamlab experiment consistency --preset lesson --estimator ekf,fej-ekf --seed 7 --trials 20 --json
    await check("many-runs=20 averages the NEES over 20 runs, with the native numbers", async () => {
      const url = "index.html?lesson=landmark-slam&seed=7&estimator=ekf,fej-ekf&many-runs=20";
      const NATIVE = { ekf: 3.9292620356909818, "fej-ekf": 3.278394232063156 };
      return withPage(browser, baseUrl, url, "many runs", async ({ page: p }) => {
        await waitRunning(p);
        const startedAt = Date.now();
        const s = await waitState(p, (st) => st.many_runs && st.many_runs.done === 20 && !st.many_runs.running, "20 runs", 120_000);
        metrics.many_runs_20_laps_ms = Date.now() - startedAt;
        await sleep(300);
        const { stats } = await waitNotBlank(p, "many-runs.png");
        assertNotBlank(stats, "many-runs.png");
        const notes = [];
        for (const [name, native] of Object.entries(NATIVE)) {
          const got = s.many_runs.nees[name];
          const diff = Math.abs(got - native) / native;
          // One implementation of sin, exp, ln and the Gaussian draws: the same bits.
          assert(got === native, `${name}: average NEES ${got} in the browser, ${native} natively`);
          notes.push(`${name} ${got} (relative difference ${diff.toExponential(1)})`);
        }
        assert(s.tick === 0, `the run on the map moved: tick ${s.tick}`);
        return `${notes.join(", ")}; done after ${metrics.many_runs_20_laps_ms} ms`;
      });
    });

    // --- Landmark SLAM on real data: MRCLAM Dataset 6 (the UTIAS zip as distributed,
    // 5 MB) opened by `data=` from the same host, robot 1 with EKF-SLAM. The page runs it
    // live against Vicon; the page's wasm then replays 6,000 steps of the same bytes
    // without drawing, and its error against Vicon must be the native run's to the bit
    // (crates/slamlab-app/tests/lessons/landmark_data_ui.rs pins the same number).
    await check("landmark SLAM opens MRCLAM by data= and its error against Vicon is the native one", async () => {
      const rel = "landmarks/mrclam/MRCLAM_Dataset6.zip";
      const file = path.join(sharedDataDir, rel);
      const found = await stat(file).then(() => true, () => false);
      if (!found) return `skipped: ${file} is absent (the shared data sets are not beside the repository; SLAMLAB_SHARED_DATA names them)`;
      const NATIVE_RMSE_6000 = 0.11077003955614562;
      const url = `index.html?lesson=landmark-slam&estimator=ekf&data=shared-data/${rel}`;
      return withPage(browser, baseUrl, url, "landmark-mrclam", async ({ page: p }) => {
        await waitRunning(p);
        const s0 = await waitState(p, (st) => st.data && st.data.name === "MRCLAM_Dataset6, robot 1", "MRCLAM loaded by data=", 60_000);
        assert(s0.data.kind === "UTIAS MRCLAM" && s0.data.mode === "slam" && s0.data.steps === 62955, `opened ${JSON.stringify(s0.data)}`);
        assert(JSON.stringify(s0.filters) === JSON.stringify(["ekf"]), `filters ${JSON.stringify(s0.filters)}`);
        // Live: Space plays the recorded robot; the error against Vicon fills in.
        await p.mouse.click(VIEWPORT.width / 2, VIEWPORT.height / 2);
        await p.keyboard.press("Space");
        const live = await waitState(p, (st) => st.data.played >= 300 && st.position_error.ekf.samples > 0, "300 steps played live", 60_000);
        const liveRmse = live.position_error.ekf.rmse;
        assert(Number.isFinite(liveRmse) && liveRmse < 1, `live EKF RMSE against Vicon ${liveRmse} m after ${live.data.played} steps`);
        await p.keyboard.press("Space");
        // Headless in this page's wasm: 6,000 steps of the same bytes.
        const { headless } = await replayLog(p, "lesson=landmark-slam&estimator=ekf", `shared-data/${rel}`, "MRCLAM_Dataset6.zip", 6000);
        const rmse = headless.position_error?.ekf?.rmse;
        assert(headless.data?.played === 6000, `the headless replay played ${headless.data?.played} steps: ${JSON.stringify(headless).slice(0, 300)}`);
        assert(rmse === NATIVE_RMSE_6000, `EKF RMSE against Vicon after 6000 steps: ${rmse} m in the browser, ${NATIVE_RMSE_6000} m natively`);
        return `live: ${live.data.played} steps, EKF RMSE ${liveRmse.toFixed(3)} m over ${live.position_error.ekf.samples} Vicon samples; headless 6000 steps: ${rmse} m, bit-identical to native`;
      });
    });

    // --- Landmark SLAM on the Freiburg course's files (world.dat and sensor_data.dat,
    // dropped together on the page as a student would): the page opens them and plays
    // them; the page's wasm then replays all 331 steps without drawing, and EKF-SLAM's
    // final pose and nine landmarks must be the native run's to the bit
    // (crates/slamlab-app/tests/lessons/landmark_data_ui.rs pins the same literals).
    await check("landmark SLAM replays the Freiburg files to the native bits", async () => {
      const dir = path.join(sharedDataDir, "landmarks/freiburg");
      const names = ["world.dat", "sensor_data.dat"];
      const found = await Promise.all(names.map((n) => stat(path.join(dir, n)).then(() => true, () => false)));
      if (found.includes(false)) return `skipped: ${dir}/{world,sensor_data}.dat are absent (the shared data sets are not beside the repository; SLAMLAB_SHARED_DATA names them)`;
      const NATIVE_POSE = [5.157982773800305, 4.841744721973463, 1.5354577017929945];
      const NATIVE_LANDMARKS = [
        [1, 1.960805942593951, 0.9585871281360637],
        [2, 0.046256843531036027, 4.0004427708171555],
        [8, 5.018295033038587, 2.8848847836228595],
        [7, 5.085780314984741, 4.89648360518319],
        [3, 2.1632290788768174, 6.946397425475357],
        [9, 5.1776412299858725, 8.896267504909765],
        [6, 9.17332474863098, 7.748333547697875],
        [5, 10.104516500632393, 4.741022022157567],
        [4, 9.006923754450272, 1.7611825006196329],
      ];
      return withPage(browser, baseUrl, "index.html?lesson=landmark-slam&estimator=ekf", "landmark-freiburg", async ({ page: p }) => {
        await waitRunning(p);
        // Dropped on the canvas (the path of a drag from the desktop).
        await dropFetched(p, names.map((n) => [`shared-data/landmarks/freiburg/${n}`, n]));
        const s0 = await waitState(p, (st) => st.data && st.data.kind === "Freiburg Robot Mapping course", "the Freiburg files opened by a drop", 30_000);
        assert(s0.data.steps === 331 && s0.data.truth_known === false, `opened ${JSON.stringify(s0.data)}`);
        await p.mouse.click(VIEWPORT.width / 2, VIEWPORT.height / 2);
        await p.keyboard.press("Space");
        const live = await waitState(p, (st) => st.data.played >= 120, "120 Freiburg steps played live", 60_000);
        await p.keyboard.press("Space");
        await sleep(300);
        const { stats } = await waitNotBlank(p, "landmark-freiburg.png");
        assertNotBlank(stats, "landmark-freiburg.png");
        // Headless in this page's wasm: the same two files to their end.
        const { headless } = await replayFiles(p, "lesson=landmark-slam&estimator=ekf", "shared-data/landmarks/freiburg", names, 100000);
        assert(headless.data?.played === 331 && headless.data?.finished === true, `the headless replay: ${JSON.stringify(headless).slice(0, 300)}`);
        const ekf = headless.estimates?.ekf;
        assert(ekf && ekf.pose.every((v, i) => v === NATIVE_POSE[i]), `final pose ${JSON.stringify(ekf?.pose)} in the browser, ${JSON.stringify(NATIVE_POSE)} natively`);
        assert(
          ekf.landmarks.length === 9 && ekf.landmarks.every((l, i) => l.every((v, j) => v === NATIVE_LANDMARKS[i][j])),
          `final landmarks ${JSON.stringify(ekf.landmarks)} in the browser, ${JSON.stringify(NATIVE_LANDMARKS)} natively`,
        );
        return `live: ${live.data.played} steps played; headless 331 steps: pose (${ekf.pose.map((v) => v.toFixed(3)).join(", ")}) and 9 landmarks bit-identical to native`;
      });
    });

    // --- Victoria Park to the end of its data with EKF-SLAM in this page's wasm (the
    // three files dropped together, then replayed headless and timed): the issue asks
    // for the speed the docs state (docs/real-landmark-data.md records the measured
    // seconds and real-time factor). Minutes on a loaded machine, so it runs only when
    // SLAMLAB_LONG=1.
    await check("landmark SLAM plays Victoria Park to its end with EKF-SLAM (SLAMLAB_LONG=1)", async () => {
      if (process.env.SLAMLAB_LONG !== "1") return "skipped: set SLAMLAB_LONG=1 to run it (minutes)";
      const dir = path.join(sharedDataDir, "landmarks/victoria_park");
      const names = ["inputs.dat", "measurements.dat", "gps.dat"];
      const found = await Promise.all(names.map((n) => stat(path.join(dir, n)).then(() => true, () => false)));
      if (found.includes(false)) return `skipped: ${dir}/{inputs,measurements,gps}.dat are absent (the shared data sets are not beside the repository)`;
      return withPage(browser, baseUrl, "index.html?lesson=landmark-slam&estimator=ekf", "landmark-victoria-park", async ({ page: p }) => {
        await waitRunning(p);
        await dropFetched(p, names.map((n) => [`shared-data/landmarks/victoria_park/${n}`, n]));
        const s0 = await waitState(p, (st) => st.data && st.data.kind === "Victoria Park", "Victoria Park opened by a drop", 60_000);
        await p.mouse.click(VIEWPORT.width / 2, VIEWPORT.height / 2);
        await p.keyboard.press("Space");
        await waitState(p, (st) => st.data.played >= 1500, "1500 Victoria Park steps played live", 120_000);
        await p.keyboard.press("Space");
        await sleep(300);
        const { stats } = await waitNotBlank(p, "landmark-victoria-park.png");
        assertNotBlank(stats, "landmark-victoria-park.png");
        const { headless, seconds } = await replayFiles(p, "lesson=landmark-slam&estimator=ekf", "shared-data/landmarks/victoria_park", names, 200000);
        const dataSeconds = headless.time;
        const factor = dataSeconds / seconds;
        const landmarks = headless.estimates?.ekf?.landmarks?.length;
        metrics.victoria_park_ekf_s = Number(seconds.toFixed(1));
        metrics.victoria_park_ekf_real_time_factor = Number(factor.toFixed(2));
        metrics.victoria_park_ekf_counts = { steps: headless.data?.played, data_seconds: dataSeconds, landmarks, gps_rmse_m: headless.data?.gps?.rmse ?? null };
        assert(headless.data?.finished === true && headless.data.played === s0.data.steps, `the headless replay stopped at ${headless.data?.played} of ${s0.data.steps} steps: ${JSON.stringify(headless).slice(0, 300)}`);
        return `${headless.data.played} steps (${dataSeconds.toFixed(0)} s of data) in ${seconds.toFixed(1)} s = ${factor.toFixed(2)}x real time; ${landmarks} landmarks at the end`;
      });
    });

    // --- Monte Carlo localization by URL: the lesson runs on the maze, and a seeded
    // global localization run in this page's wasm converges with exactly the native bits
    // (crates/slamlab-app/tests/lessons/kidnap_ui.rs pins the same numbers).
    await check("lesson=kidnap runs on the maze and converges with the native numbers", async () => {
      const url = "index.html?lesson=kidnap&map=maze&seed=3&particles=1000";
      return withPage(browser, baseUrl, url, "kidnap", async ({ page: p }) => {
        await waitRunning(p);
        const s0 = await waitState(p, (st) => st.lesson === "kidnap" && st.frames > 2, "the kidnap lesson");
        assert(s0.map === "maze" && s0.seed === 3, `opened ${JSON.stringify(s0)}`);
        assert(s0.filters.length === 1 && s0.filters[0].particles === 1000, `filters ${JSON.stringify(s0.filters)}`);
        await p.mouse.click(VIEWPORT.width / 2, VIEWPORT.height / 2); // gives the canvas keyboard focus
        await p.keyboard.press("Space");
        const s1 = await waitState(p, (st) => st.tick >= 20, "20 ticks running", 60_000);
        await sleep(300);
        const { stats } = await waitNotBlank(p, "kidnap-running.png");
        assertNotBlank(stats, "kidnap-running.png");
        const headless = await runHeadless(p, "lesson=kidnap&map=maze&seed=3&particles=1000", 300);
        const f = headless.filters[0];
        assert(f.position_error < 0.5, `the estimate did not converge: ${JSON.stringify(f)}`);
        const NATIVE = [3.6749150412703995, 3.2807691616908534, 1.0349869652703703];
        assert(
          f.estimate.every((v, i) => v === NATIVE[i]),
          `estimate ${JSON.stringify(f.estimate)} in the browser, ${JSON.stringify(NATIVE)} natively`,
        );
        return `ran to tick ${s1.tick}; headless 300 ticks: error ${f.position_error.toFixed(3)} m, estimate bit-identical to native`;
      });
    });

    // --- The kidnapped robot by URL: AMCL and ACMCL track, the robot is kidnapped at
    // tick 30 (kidnap-at=30), and each filter's status says it is lost, then recovering
    // or recovered.
    await check("a kidnap by URL: the status goes from tracking to lost or recovering", async () => {
      const url = "index.html?lesson=kidnap&estimator=amcl,acmcl&init=tracking&particles=500&kidnap-at=30&seed=4";
      return withPage(browser, baseUrl, url, "kidnap status", async ({ page: p }) => {
        await waitRunning(p);
        await waitState(p, (st) => st.lesson === "kidnap" && st.frames > 2, "the kidnap lesson");
        await p.mouse.click(VIEWPORT.width / 2, VIEWPORT.height / 2);
        await p.keyboard.press("Space");
        const before = await waitState(p, (st) => st.tick >= 25, "25 ticks", 90_000);
        const tracking = before.filters.map((f) => f.status);
        assert(tracking.every((s) => s.startsWith("tracking")), `before the kidnap: ${JSON.stringify(tracking)}`);
        const after = await waitState(p, (st) => st.kidnap_tick === 30 && st.tick >= 34, "the kidnap", 90_000);
        const statuses = after.filters.map((f) => f.status);
        assert(statuses.every((s) => /^(lost|recover)/.test(s)), `after the kidnap: ${JSON.stringify(statuses)}`);
        await sleep(300);
        const { stats } = await waitNotBlank(p, "kidnap-status.png");
        assertNotBlank(stats, "kidnap-status.png");
        return `before: ${tracking.join(" | ")}; after: ${statuses.join(" | ")}`;
      });
    });

    // --- map= names a ROS map hosted beside the site (web/build.sh copies the built-in
    // maps to dist/maps/): the lesson fetches the YAML and its image and runs on it; a
    // location that does not exist leaves the maze and a note.
    await check("map=maps/office.yaml loads a hosted ROS map; a missing one keeps the maze", async () => {
      const url = "index.html?lesson=kidnap&map=maps/office.yaml&particles=300&seed=2";
      return withPage(browser, baseUrl, url, "hosted map", async ({ page: p }) => {
        await waitRunning(p);
        const s1 = await waitState(p, (st) => st.lesson === "kidnap" && st.map === "office.yaml", "the hosted office map", 60_000);
        const { stats } = await waitNotBlank(p, "kidnap-hosted-map.png");
        assertNotBlank(stats, "kidnap-hosted-map.png");
        const missing = await openPage(browser, baseUrl, "index.html?lesson=kidnap&map=maps/nowhere.yaml", "missing hosted map");
        try {
          await waitRunning(missing.page);
          await sleep(1500);
          const s2 = await testState(missing.page);
          assert(s2.map === "maze", `a missing map replaced the maze: ${JSON.stringify(s2)}`);
          await assertNoPanic(missing.page);
          // The failed request is the point of this check, not a problem.
          missing.log.problems = missing.log.problems.filter((q) => !/nowhere\.yaml|404/.test(q));
        } finally {
          await missing.context.close();
        }
        return `map ${s1.map} loaded by URL; maps/nowhere.yaml left the maze`;
      });
    });

    // --- The Monte Carlo lesson at 5,000 particles, one filter (MCL) and two side by side
    // (AMCL and ACMCL): the lesson runs, draws, and reports its frame timing (recorded in
    // metrics.json, not asserted: docs/results.md has the numbers with the machine and date).
    for (const [key, estimator, what] of [
      ["mcl5000", "mcl", "MCL with 5,000 particles"],
      ["mcl2x5000", "amcl,acmcl", "AMCL and ACMCL with 5,000 particles each"],
    ]) {
      await check(
        `${what}: runs and reports its frame timing`,
        timedRun(
          `index.html?lesson=kidnap&estimator=${estimator}&particles=5000&init=tracking&seed=5`,
          key,
          estimator.split(",").map((name) => `${name}:5000`).join(","),
          {
            filtersOf: (fs) => fs.map((f) => `${f.name}:${f.particles}`).join(","),
            focusAt: [VIEWPORT.width / 2, 20], // away from the map (a click there may kidnap)
          },
        ),
      );
    }

    // --- The resampling lab by URL: a press of the Resample button (the "." shortcut)
    // resamples with every method, and five seeded presses in this page's wasm give
    // exactly the native copies (crates/slamlab-app/tests/lessons/resampling_ui.rs pins them).
    // --- Mapping with a lidar: the simulated robot explores the maze and scan-to-map
    // matching builds the map; its agreement with the true map rises as scans come in.
    await check("lesson=mapping builds the maze map and its agreement with the truth rises", async () => {
      const url = "index.html?lesson=mapping&map=maze&seed=3&steps=300";
      return withPage(browser, baseUrl, url, "mapping", async ({ page: p }) => {
        await waitRunning(p);
        const s0 = await waitState(p, (st) => st.lesson === "mapping" && st.frames > 2, "the mapping lesson");
        assert(s0.total_scans === 300 && s0.poses === "scan-to-map" && s0.scans === 0, `opened ${JSON.stringify(s0)}`);
        await p.mouse.click(VIEWPORT.width / 2, VIEWPORT.height / 2); // gives the canvas keyboard focus
        await p.keyboard.press("Space");
        const s1 = await waitState(p, (st) => st.scans >= 150, "150 scans mapped", 120_000);
        // Measured natively: 0.852 after 150 scans (true poses 0.923, raw odometry 0.775).
        assert(s1.map_agreement > 0.82, `map agreement ${s1.map_agreement} after ${s1.scans} scans`);
        assert(s1.trajectory_rmse < 0.5, `trajectory RMSE ${s1.trajectory_rmse} m`);
        await sleep(300);
        const { stats } = await waitNotBlank(p, "mapping.png");
        assertNotBlank(stats, "mapping.png");
        // Scan-to-map in wasm without drawing: the office, 600 scans of 360 beams (60 s of
        // data), timed for the real-time factor (reported, not asserted), and the pose it
        // ends at against the native run (crates/slamlab-app/tests/lessons/mapping_ui.rs).
        const started = Date.now();
        const headless = await runHeadless(p, "lesson=mapping&map=office&steps=600&seed=1", 600);
        const seconds = (Date.now() - started) / 1000;
        const NATIVE = [19.29859043482542, 47.94699415441172, -1.546091238599251];
        const apart = Math.hypot(headless.pose[0] - NATIVE[0], headless.pose[1] - NATIVE[1]);
        assert(headless.scans === 600 && apart < 0.05, `ended at ${JSON.stringify(headless.pose)}, natively ${JSON.stringify(NATIVE)}`);
        const same = headless.pose.every((v, i) => v === NATIVE[i]);
        metrics.mapping_office_600_scans_s = Number(seconds.toFixed(2));
        metrics.mapping_real_time_factor = Number((60 / seconds).toFixed(1));
        return `${s1.scans} scans: map agreement ${s1.map_agreement.toFixed(3)}, trajectory RMSE ${s1.trajectory_rmse.toFixed(3)} m, ${s1.known_cells} known cells; office headless: 600 scans (60 s of data, simulation included) in ${seconds.toFixed(1)} s = ${(60 / seconds).toFixed(1)}x real time, pose ${same ? "bit-identical to native" : `${(apart * 1000).toFixed(2)} mm from native`}`;
      });
    });

    // --- A real laser log in the browser: the Intel Research Lab log (13,631 scans, about
    // 45 minutes of data) opened by `log=` from the same host, then mapped whole with
    // scan-to-map poses in this page's wasm without drawing, timed for the real-time
    // factor (the issue asks at least 20x in Chromium; natively it is about 250x, see
    // docs/mapping.md). The end pose must be the native run's, bit for bit
    // (crates/slamlab-app/tests/lessons/mapping_ui.rs pins it).
    await check("the Intel log opens by log= and maps whole at 20x real time or faster", async () => {
      const rel = "laser/intel.clf.bz2";
      const file = path.join(sharedDataDir, rel);
      const found = await stat(file).then(() => true, () => false);
      if (!found) return `skipped: ${file} is absent (the shared data sets are not beside the repository)`;
      const url = `index.html?lesson=mapping&log=shared-data/${rel}`;
      return withPage(browser, baseUrl, url, "mapping-intel", async ({ page: p }) => {
        await waitRunning(p);
        const s0 = await waitState(p, (st) => st.lesson === "mapping" && st.total_scans === 13631, "the Intel log loaded by log=", 120_000);
        assert(s0.poses === "scan-to-map" && s0.log === "intel.clf.bz2", `opened ${JSON.stringify({ poses: s0.poses, log: s0.log, note: s0.note })}`);
        const { headless, seconds } = await replayLog(p, "lesson=mapping", `shared-data/${rel}`, "intel.clf.bz2", 13631);
        const factor = headless.input_seconds / seconds;
        const NATIVE = [-2.751285284132404, 1.482646573714355, -0.043476162369528115];
        const same = headless.pose.every((v, i) => v === NATIVE[i]);
        metrics.mapping_intel_log_s = Number(seconds.toFixed(2));
        metrics.mapping_intel_real_time_factor = Number(factor.toFixed(1));
        assert(headless.scans === 13631, `mapped ${headless.scans} scans: ${headless.note}`);
        assert(same, `ended at ${JSON.stringify(headless.pose)}, natively ${JSON.stringify(NATIVE)}`);
        assert(factor >= 20, `${headless.input_seconds.toFixed(0)} s of data in ${seconds.toFixed(1)} s = ${factor.toFixed(1)}x real time`);
        return `${headless.scans} scans (${headless.input_seconds.toFixed(0)} s of data, decompression and parsing included) in ${seconds.toFixed(1)} s = ${factor.toFixed(1)}x real time, end pose bit-identical to native`;
      });
    });

    // --- A ROS 2 bag (MCAP with zstd chunks, written by PyPI's rosbags from the Intel
    // log's first 300 scans: crates/slamlab-sim/tests/data/ros2_bags) opened by `log=`
    // with `scan-topic=`, then mapped by the lesson as it runs and by the page's wasm
    // without drawing: the end pose must be the native run's to the bit
    // (mapping_ui::a_rosbags_bag_mapped_through_the_lesson_ends_at_the_pose_the_browser_must_match).
    await check("a ROS 2 bag opens by log= and maps, ending on the native pose", async () => {
      const rel = "ros2_bags/rosbags-intel-300-scans.mcap";
      const url = `index.html?lesson=mapping&log=repo-data/${rel}&scan-topic=/scan&odom-topic=/odom`;
      return withPage(browser, baseUrl, url, "mapping-ros2-bag", async ({ page: p }) => {
        await waitRunning(p);
        const s0 = await waitState(p, (st) => st.lesson === "mapping" && st.total_scans === 300, "the bag loaded by log=", 60_000);
        assert(s0.log === "rosbags-intel-300-scans.mcap", `opened ${JSON.stringify({ log: s0.log, note: s0.note })}`);
        assert(JSON.stringify(s0.topics) === JSON.stringify(["/scan", "/odom"]), `topics ${JSON.stringify(s0.topics)}`);
        assert(/^Loaded rosbags-intel-300-scans\.mcap \(ROS 2 bag, MCAP with zstd chunks\): 300 scans/.test(s0.note), `note ${s0.note}`);
        // Run the lesson itself for a while and look at it.
        await p.mouse.click(VIEWPORT.width / 2, VIEWPORT.height / 2); // gives the canvas keyboard focus
        await p.keyboard.press("Space");
        const s1 = await waitState(p, (st) => st.scans >= 40, "40 scans mapped from the bag", 60_000);
        const image = await screenshot(p, "mapping-ros2-bag.png");
        const stats = imageStats(image);
        assert(stats.distinctColours > 50, `the page looks blank: ${describe(stats)}`);
        const { headless } = await replayLog(p, "lesson=mapping", `repo-data/${rel}`, "rosbags-intel-300-scans.mcap", 300);
        const NATIVE = [2.1332476175095056, 0.02236945271272885, -0.11727858044618644];
        const same = headless.pose.every((v, i) => v === NATIVE[i]);
        assert(headless.scans === 300, `mapped ${headless.scans} scans: ${headless.note}`);
        assert(same, `ended at ${JSON.stringify(headless.pose)}, natively ${JSON.stringify(NATIVE)}`);
        return `300 scans from /scan with /odom; ${s1.scans} mapped live; the whole bag in wasm ends bit-identical to native`;
      });
    });

    // --- The localization lesson replays a bag by log= in its map. The rosbags bag holds
    // the Intel log's first scans: a real robot without truth, recorded in a building that
    // is not the maze, so the check is of the route, not of the localization (natively,
    // kidnap_ui and replay_tests pin a simulated bag's numbers).
    await check("the localization lesson replays a ROS 2 bag by log= and says it has no truth", async () => {
      const rel = "ros2_bags/rosbags-intel-300-scans.mcap";
      const url = `index.html?lesson=kidnap&particles=500&log=repo-data/${rel}&scan-topic=/scan`;
      const notes = [];
      for (const viewport of [VIEWPORT, { width: 800, height: 500 }]) {
        const size = `${viewport.width}x${viewport.height}`;
        await withPage(browser, baseUrl, url, `kidnap-ros2-bag-${size}`, async ({ page: p }) => {
          await waitRunning(p);
          const s0 = await waitState(p, (st) => st.lesson === "kidnap" && st.log === "rosbags-intel-300-scans.mcap", "the bag loaded by log=", 60_000);
          assert(JSON.stringify(s0.topics) === JSON.stringify(["/scan", "/odom"]), `topics ${JSON.stringify(s0.topics)}`);
          assert(/^Loaded rosbags-intel-300-scans\.mcap .*no ground truth; localizing in maze$/.test(s0.note), `note ${s0.note}`);
          // The middle of the map gives the canvas keyboard focus (at 800 x 500 the
          // window's middle is the map's toolbar).
          const [left, top, width, height] = s0.map_rect ?? [0, 0, viewport.width, viewport.height];
          await p.mouse.click(left + width / 2, top + height / 2);
          await p.keyboard.press("Space");
          const s1 = await waitState(p, (st) => st.log_progress && st.log_progress[0] >= 40, "40 scans replayed", 60_000);
          assert(s1.truth === null, `truth ${JSON.stringify(s1.truth)}`);
          assert(s1.filters.every((f) => f.position_error === null && /^no truth in this log/.test(f.status)), `filters ${JSON.stringify(s1.filters)}`);
          const image = await screenshot(p, `kidnap-ros2-bag-${size}.png`);
          const stats = imageStats(image);
          assert(stats.distinctColours > 50, `the page looks blank: ${describe(stats)}`);
          notes.push(`${size}: ${s1.log_progress[0]} of ${s1.log_progress[1]} scans replayed, "${s1.filters[0].status}"`);
        }, viewport);
      }
      return notes.join("; ");
    });

    // --- The Intel log through the Cartographer lesson, loop closures and all, in this
    // page's wasm: the issue asks for faster than real time in Chromium. It takes many
    // minutes, so it runs only when SLAMLAB_LONG=1 (docs/cartographer.md records the
    // measured factor); natively `slamlab run cartographer --log` gives the same counts.
    await check("the Intel log maps through the Cartographer lesson faster than real time (SLAMLAB_LONG=1)", async () => {
      if (process.env.SLAMLAB_LONG !== "1") return "skipped: set SLAMLAB_LONG=1 to run it (many minutes)";
      const rel = "laser/intel.clf.bz2";
      const file = path.join(sharedDataDir, rel);
      const found = await stat(file).then(() => true, () => false);
      if (!found) return `skipped: ${file} is absent (the shared data sets are not beside the repository)`;
      return withPage(browser, baseUrl, "index.html?lesson=cartographer&steps=10", "cartographer-intel", async ({ page: p }) => {
        await waitRunning(p);
        const { headless, seconds } = await replayLog(p, "lesson=cartographer", `shared-data/${rel}`, "intel.clf.bz2", 13631);
        const factor = headless.input_seconds / seconds;
        metrics.cartographer_intel_log_s = Number(seconds.toFixed(1));
        metrics.cartographer_intel_real_time_factor = Number(factor.toFixed(2));
        metrics.cartographer_intel_counts = { nodes: headless.nodes, submaps: headless.submaps, loop_closures: headless.loop_closures, searches: headless.bbs?.searches };
        assert(headless.scans === 13631, `mapped ${headless.scans} scans: ${JSON.stringify(headless).slice(0, 300)}`);
        assert(factor > 1, `${headless.input_seconds.toFixed(0)} s of data in ${seconds.toFixed(1)} s = ${factor.toFixed(2)}x real time`);
        return `${headless.scans} scans (${headless.input_seconds.toFixed(0)} s of data) in ${seconds.toFixed(1)} s = ${factor.toFixed(2)}x real time; ${headless.nodes} nodes, ${headless.submaps} submaps, ${headless.loop_closures} loop closures, ${headless.bbs?.searches} searches`;
      });
    });

    // --- The same log on screen: `log=` with `run=1&speed=max` plays it through the
    // lesson as a student sees it, each frame simulating through the time the last one
    // left idle (up to 250 ms) and then drawing the submaps, constraints and plots. Timed
    // from the log's loading to
    // the last scan (the issue asks at most 90 s, still drawing); opt-in as above.
    await check("the Intel log plays through the Cartographer lesson on screen at speed=max (SLAMLAB_LONG=1)", async () => {
      if (process.env.SLAMLAB_LONG !== "1") return "skipped: set SLAMLAB_LONG=1 to run it (minutes)";
      const rel = "laser/intel.clf.bz2";
      const file = path.join(sharedDataDir, rel);
      const found = await stat(file).then(() => true, () => false);
      if (!found) return `skipped: ${file} is absent (the shared data sets are not beside the repository)`;
      const url = `index.html?lesson=cartographer&log=shared-data/${rel}&run=1&speed=max`;
      return withPage(browser, baseUrl, url, "cartographer-intel-on-screen", async ({ page: p }) => {
        await waitRunning(p);
        const s0 = await waitState(p, (st) => st.lesson === "cartographer" && st.total_scans === 13631, "the Intel log loaded by log=", 120_000);
        const started = Date.now();
        let state = s0;
        let halfway = null;
        const deadline = started + 20 * 60_000;
        // Polled once a second: the state's JSON is built on the page's one thread.
        while (state.scans < 13631) {
          assert(Date.now() < deadline, `still at scan ${state.scans} after 20 minutes`);
          await sleep(1000);
          state = await testState(p);
          if (!halfway && state.scans >= 6800) {
            halfway = await screenshot(p, "cartographer-intel-on-screen-half.png");
          }
        }
        const seconds = (Date.now() - started) / 1000;
        const factor = state.input_seconds / seconds;
        const frames = state.frames - s0.frames;
        metrics.cartographer_intel_on_screen_s = Number(seconds.toFixed(1));
        metrics.cartographer_intel_on_screen_real_time_factor = Number(factor.toFixed(1));
        metrics.cartographer_intel_on_screen_frames = frames;
        const image = await screenshot(p, "cartographer-intel-on-screen.png");
        assertNotBlank(imageStats(image), "cartographer-intel-on-screen.png");
        assert(state.nodes === 6837 && state.loop_closures === 2832, `counts ${JSON.stringify({ nodes: state.nodes, loop_closures: state.loop_closures })}, natively 6837 nodes and 2832 loop closures`);
        assert(factor > 1, `${state.input_seconds.toFixed(0)} s of data in ${seconds.toFixed(1)} s on screen = ${factor.toFixed(2)}x real time`);
        return `${state.scans} scans (${state.input_seconds.toFixed(0)} s of data) on screen in ${seconds.toFixed(1)} s = ${factor.toFixed(1)}x real time, ${frames} frames drawn (${(frames / seconds).toFixed(1)}/s); ${state.nodes} nodes, ${state.loop_closures} loop closures`;
      });
    });

    // --- Grid FastSLAM in the mapping lesson. A short seeded run in this page's wasm
    // ends with the heaviest particle exactly where the native run puts it
    // (crates/slamlab-app/tests/lessons/mapping_ui.rs pins it); then 30 particles with
    // the improved proposal run live on the office and the frame timing is recorded
    // (metrics.json: grid_fastslam_*; reported, not asserted). Frames that only draw
    // and skip scans are timed apart from update frames (each runs one or more
    // particles' scan matches, or the weights, resampling and map updates), and the
    // lesson's own median time per update scan is recorded beside them.
    await check("lesson=mapping with grid FastSLAM: native bits, and 30 particles running live", async () => {
      const url = "index.html?lesson=mapping&map=office&seed=1&steps=3000&poses=grid-fastslam&particles=30";
      return withPage(browser, baseUrl, url, "grid-fastslam", async ({ page: p }) => {
        await waitRunning(p);
        const headless = await runHeadless(p, "lesson=mapping&map=maze&steps=300&seed=2&poses=grid-fastslam&particles=10", 300);
        const NATIVE = [2.2339493485723514, 5.709111183307648, 3.0152847451913276];
        const best = headless.grid_fastslam?.best;
        assert(
          Array.isArray(best) && best.every((v, i) => v === NATIVE[i]),
          `heaviest particle at ${JSON.stringify(best)} in the browser, ${JSON.stringify(NATIVE)} natively`,
        );
        const s0 = await waitState(p, (st) => st.lesson === "mapping" && st.frames > 2, "the mapping lesson");
        assert(s0.poses === "grid-fastslam", `opened ${JSON.stringify(s0)}`);
        await p.mouse.click(VIEWPORT.width / 2, VIEWPORT.height / 2);
        await p.keyboard.press("Space");
        const s1 = await waitState(p, (st) => st.grid_fastslam && st.grid_fastslam.updates >= 4, "four filter updates", 120_000);
        await sleep(LOAD_RUN_MS);
        const s2 = await testState(p);
        const { stats } = await waitNotBlank(p, "grid-fastslam.png");
        assertNotBlank(stats, "grid-fastslam.png");
        const t = s2.frame_timing;
        const g = s2.grid_fastslam;
        assert(t && t.frames > 0 && Number.isFinite(t.cpu_ms_median), `no frame timing: ${JSON.stringify(s2)}`);
        assert(g.particles === 30 && g.updates > s1.grid_fastslam.updates - 1, `particles ${JSON.stringify(g)}`);
        metrics.grid_fastslam_frame_cpu_ms_median = t.cpu_ms_median;
        metrics.grid_fastslam_frame_cpu_ms_p95 = t.cpu_ms_p95;
        metrics.grid_fastslam_frame_cpu_ms_median_outside_updates = t.cpu_ms_median_outside_updates;
        metrics.grid_fastslam_frame_cpu_ms_median_update_frames = t.cpu_ms_median_update_frames;
        metrics.grid_fastslam_update_frames = t.update_frames;
        metrics.grid_fastslam_frames = t.frames;
        metrics.grid_fastslam_update_ms_median = g.update_ms_median;
        metrics.grid_fastslam_update_scans = g.update_scans_timed;
        metrics.grid_fastslam_scans = s2.scans;
        return (
          `heaviest particle bit-identical to native; 30 particles: ${s2.scans} scans, ${g.updates} updates, ` +
          `${g.resamplings} resamplings; frame CPU median ${t.cpu_ms_median_outside_updates?.toFixed(2)} ms outside updates ` +
          `(${t.frames - t.update_frames} frames), ${t.cpu_ms_median_update_frames?.toFixed(2)} ms in update frames (${t.update_frames}); ` +
          `an update scan takes ${g.update_ms_median?.toFixed(1)} ms (median of ${g.update_scans_timed})`
        );
      });
    });

    // --- The filters lesson: the polar banana with 100,000 samples. Drag the prior's
    // mean with the mouse: every move recomputes the samples, the EKF, the UKF and the
    // particles and redraws the density image. The frame CPU median while dragging is
    // recorded in metrics.json (filters_drag_*), not asserted: the issue asks for under
    // 16 ms, and docs/results.md states what was measured where. A seeded headless run in
    // wasm gives the native table (crates/slamlab-app/tests/lessons/filters_ui.rs pins it).
    // --- Submaps, loop closure and the kidnapped robot: the thesis's case, a kidnap
    // before scan 152 of a run with none before, on the maze with seed 3 (the robot
    // carried to a place on its path so far, `kidnap-place=mapped`). Running live, the
    // detector fires at scan 152 and the second trajectory's map merges into the first
    // at scan 154 (crates/slamlab-app/tests/lessons/cartographer_ui.rs pins the same
    // scans natively); a headless run in this page's wasm to scan 200 gives the native
    // counts exactly (`slamlab run cartographer --map maze --steps 200 --kidnap-at 152
    // --seed 3 --json`): branch and bound's candidate count moves with any bit of any
    // pose.
    await check("lesson=cartographer detects the kidnap at 152 and merges the maps", async () => {
      const url = "index.html?lesson=cartographer&map=maze&kidnap-at=152&seed=3";
      return withPage(browser, baseUrl, url, "cartographer", async ({ page: p }) => {
        await waitRunning(p);
        const s0 = await waitState(p, (st) => st.lesson === "cartographer" && st.frames > 2, "the cartographer lesson");
        assert(s0.total_scans === 600 && s0.kidnap_at === 152 && s0.scans === 0, `opened ${JSON.stringify(s0)}`);
        await p.mouse.click(VIEWPORT.width / 2, VIEWPORT.height / 2); // gives the canvas keyboard focus
        await p.keyboard.press("Space");
        const s1 = await waitState(p, (st) => st.recovered_at !== null, "the maps merged", 240_000);
        assert(JSON.stringify(s1.detections) === "[152]", `detections ${JSON.stringify(s1.detections)}`);
        assert(s1.kidnap_detected_at === 152 && s1.recovered_at === 154, `detected ${s1.kidnap_detected_at}, merged ${s1.recovered_at}`);
        assert(s1.trajectories === 2, `${s1.trajectories} trajectories`);
        await sleep(300);
        const { stats } = await waitNotBlank(p, "cartographer.png");
        assertNotBlank(stats, "cartographer.png");
        const started = Date.now();
        const headless = await runHeadless(p, "lesson=cartographer&map=maze&kidnap-at=152&seed=3", 200);
        const seconds = (Date.now() - started) / 1000;
        const NATIVE = { submaps: 7, nodes: 163, loop_closures: 15, optimizations: 6, searches: 34, nodes_evaluated: 153183, exhaustive_candidates: 43636618 };
        const got = {
          submaps: headless.submaps,
          nodes: headless.nodes,
          loop_closures: headless.loop_closures,
          optimizations: headless.optimizations,
          searches: headless.bbs.searches,
          nodes_evaluated: headless.bbs.nodes_evaluated,
          exhaustive_candidates: headless.bbs.exhaustive_candidates,
        };
        assert(JSON.stringify(got) === JSON.stringify(NATIVE), `headless ${JSON.stringify(got)}, natively ${JSON.stringify(NATIVE)}`);
        assert(headless.scans === 200 && headless.recovered_at === 154 && JSON.stringify(headless.detections) === "[152]", `headless ${JSON.stringify(headless)}`);
        metrics.cartographer_maze_200_scans_s = Number(seconds.toFixed(2));
        metrics.cartographer_scan_ms_median = s1.scan_ms_median;
        metrics.cartographer_scan_ms_max = s1.scan_ms_max;
        return `detected at ${s1.kidnap_detected_at}, merged at ${s1.recovered_at} (${s1.submaps} submaps, ${s1.loop_closures} loop closures); scan median ${s1.scan_ms_median?.toFixed(1)} ms, max ${s1.scan_ms_max?.toFixed(1)} ms; headless 200 scans in ${seconds.toFixed(1)} s, counts identical to native`;
      });
    });

    await check("lesson=filters drags the prior over 100,000 samples and matches native", async () => {
      const url = "index.html?lesson=filters&function=polar&seed=1";
      return withPage(browser, baseUrl, url, "filters", async ({ page: p }) => {
        await waitRunning(p);
        const s0 = await waitState(p, (st) => st.lesson === "filters" && st.frames > 2 && st.handles_px, "the filters lesson");
        assert(s0.samples === 100000 && s0.results.length === 3 && s0.note === null, `opened ${JSON.stringify(s0)}`);
        const [mean, handle] = s0.handles_px;
        const scale = handle[0] - mean[0]; // the first handle is one range deviation (0.1 m) to the right
        assert(scale > 1, `handles ${JSON.stringify(s0.handles_px)}`);
        await p.mouse.move(mean[0], mean[1]);
        await p.mouse.down();
        const MOVES = 150;
        const startedAt = Date.now();
        for (let k = 1; k <= MOVES; k++) {
          // Back and forth along the range axis, at most half a deviation from the start.
          const dx = 0.5 * scale * Math.sin((2 * Math.PI * k) / 50);
          await p.mouse.move(mean[0] + dx, mean[1] + 0.2 * dx);
        }
        await p.mouse.move(mean[0] + 0.5 * scale, mean[1]);
        await sleep(300);
        const during = await testState(p);
        await p.mouse.up();
        const seconds = (Date.now() - startedAt) / 1000;
        const s1 = await waitState(p, (st) => st.frames > during.frames, "a frame after the release");
        assert(s1.note === null, `a note after the drag: ${s1.note}`);
        const moved = s1.prior.mean[0] - s0.prior.mean[0];
        assert(Math.abs(moved - 0.05) < 0.01, `the mean moved ${moved} m, not 0.05 m: ${JSON.stringify(s1.prior)}`);
        assert(s1.results.every((r) => Number.isFinite(r.mean_error) && Number.isFinite(r.covariance_error)), JSON.stringify(s1.results));
        await screenshot(p, "filters-dragged.png");
        const t = during.frame_timing;
        assert(t && t.frames > 0 && Number.isFinite(t.cpu_ms_median), `no frame timing: ${JSON.stringify(during)}`);
        metrics.filters_drag_frame_cpu_ms_median = t.cpu_ms_median;
        metrics.filters_drag_frame_cpu_ms_p95 = t.cpu_ms_p95;
        metrics.filters_drag_frames_per_second = Number((1000 / t.interval_ms_median).toFixed(1));
        // Frames whose prior did not move run no computation, so the median mixes both
        // kinds: the frames drawn and the computations run say how many of each.
        metrics.filters_drag_frames = during.frames - s0.frames;
        metrics.filters_drag_computations = during.computations - s0.computations;
        metrics.filters_drag_last_compute_ms = Number(during.compute_ms.toFixed(2));
        const headless = await runHeadless(p, "lesson=filters&samples=20000&seed=1", 0);
        const table = headless.results.map((r) => `${r.method}=${r.mean_error}`);
        const NATIVE = ["ekf=0.12957845707913004", "ukf=0.001541246456905519", "particles=0.021033324669198564"];
        assert(JSON.stringify(table) === JSON.stringify(NATIVE), `${table} in the browser, ${NATIVE} natively`);
        return (
          `${MOVES} moves in ${seconds.toFixed(1)} s; frame CPU median ${t.cpu_ms_median.toFixed(2)} ms ` +
          `(p95 ${t.cpu_ms_p95?.toFixed(2)}), ` +
          `${metrics.filters_drag_frames_per_second} frames/s, ${metrics.filters_drag_frames} frames and ` +
          `${metrics.filters_drag_computations} computations (the last ${metrics.filters_drag_last_compute_ms} ms); ` +
          `headless ${table.join(" ")}`
        );
      });
    });

    await check("lesson=resampling resamples and gives the native copies", async () => {
      const url = "index.html?lesson=resampling&weights=5,1,1,3&seed=3";
      return withPage(browser, baseUrl, url, "resampling", async ({ page: p }) => {
        await waitRunning(p);
        const s0 = await waitState(p, (st) => st.lesson === "resampling" && st.frames > 2, "the resampling lab");
        assert(s0.particles === 4 && s0.resamplings === 0, `opened ${JSON.stringify(s0)}`);
        await p.mouse.click(VIEWPORT.width / 2, VIEWPORT.height / 2); // gives the canvas keyboard focus
        await p.keyboard.press("Period");
        const s1 = await waitState(p, (st) => st.resamplings === 1, "one press");
        assert(
          s1.methods.every((m) => m.last_copies.reduce((a, b) => a + b, 0) === 4),
          `each method draws M = 4: ${JSON.stringify(s1.methods)}`,
        );
        await sleep(300);
        const { stats } = await waitNotBlank(p, "resampling.png");
        assertNotBlank(stats, "resampling.png");
        const headless = await runHeadless(p, "lesson=resampling&weights=5,1,1,3&seed=3", 5);
        const copies = headless.methods.map((m) => `${m.name}=${JSON.stringify(m.last_copies)}`);
        const NATIVE = ["multinomial=[3,0,1,0]", "low-variance=[2,1,0,1]", "stratified=[2,0,1,1]", "residual=[2,1,0,1]"];
        assert(JSON.stringify(copies) === JSON.stringify(NATIVE), `copies ${copies} in the browser, ${NATIVE} natively`);
        return `one press by key; headless 5 presses: ${copies.join(" ")}`;
      });
    });

    // --- The visual-odometry lesson by URL: Space runs RANSAC one sample per tick until
    // its adaptive bound stops it; the frame CPU time while it runs is recorded in
    // metrics.json (visual_odometry_*; the issue asks for under 16 ms), and a seeded
    // headless run in wasm gives the native counts (crates/slamlab-app/tests/lessons/
    // visual_odometry_ui.rs pins them).
    await check("lesson=visual-odometry runs RANSAC to its bound and matches native", async () => {
      const url = "index.html?lesson=visual-odometry&seed=3";
      return withPage(browser, baseUrl, url, "visual-odometry", async ({ page: p }) => {
        await waitRunning(p);
        const s0 = await waitState(p, (st) => st.lesson === "visual-odometry" && st.frames > 2, "the visual-odometry lesson");
        assert(s0.seed === 3 && s0.iteration === 0 && s0.matches > 100 && s0.vo_steps === 39, `opened ${JSON.stringify(s0)}`);
        await p.mouse.click(VIEWPORT.width / 2, VIEWPORT.height / 2); // gives the canvas keyboard focus
        await p.keyboard.press("Space");
        const s1 = await waitState(p, (st) => st.done && st.estimate, "RANSAC at its bound", 60_000);
        assert(s1.iteration === s1.bound, `stopped at ${s1.iteration} of ${s1.bound}`);
        const e = s1.estimate;
        assert(e.motion === "general" && e.in_front[e.chosen] === Math.max(...e.in_front), `estimate ${JSON.stringify(e)}`);
        await sleep(300);
        const { stats } = await waitNotBlank(p, "visual-odometry.png");
        assertNotBlank(stats, "visual-odometry.png");
        const t = s1.frame_timing;
        assert(t && t.frames > 0 && Number.isFinite(t.cpu_ms_median), `no frame timing: ${JSON.stringify(s1)}`);
        metrics.visual_odometry_frame_cpu_ms_median = t.cpu_ms_median;
        metrics.visual_odometry_frame_cpu_ms_p95 = t.cpu_ms_p95;
        metrics.visual_odometry_frames_per_second = Number((1000 / t.interval_ms_median).toFixed(1));
        const headless = await runHeadless(p, "lesson=visual-odometry&seed=3", 10);
        const got = `best_inliers=${headless.best_inliers} bound=${headless.bound} rmse=${headless.trajectory_rmse.visual_odometry}`;
        const NATIVE = "best_inliers=491 bound=35 rmse=0.741133627603435";
        assert(got === NATIVE, `${got} in the browser, ${NATIVE} natively`);
        return (
          `${s1.iteration} samples to the bound, ${e.inliers} inliers, candidate ${e.chosen} chosen (${e.in_front}); ` +
          `frame CPU median ${t.cpu_ms_median.toFixed(2)} ms (p95 ${t.cpu_ms_p95?.toFixed(2)}); headless ${got}`
        );
      });
    });

    // --- The visual-odometry lesson with early-rejection=sprt from the URL: the share link
    // keeps it, stepping shows hypotheses rejected after a few matches, and a seeded
    // headless run in wasm gives the native counts (visual_odometry_ui.rs pins them).
    await check("lesson=visual-odometry&early-rejection=sprt: steps show early rejections and match native", async () => {
      const url = "index.html?lesson=visual-odometry&seed=3&early-rejection=sprt";
      return withPage(browser, baseUrl, url, "visual-odometry sprt", async ({ page: p }) => {
        await waitRunning(p);
        const s0 = await waitState(p, (st) => st.lesson === "visual-odometry" && st.frames > 2, "the visual-odometry lesson");
        assert(s0.early_rejection === "sprt" && s0.iteration === 0, `opened ${JSON.stringify(s0)}`);
        await p.mouse.click(VIEWPORT.width / 2, VIEWPORT.height / 2); // keyboard focus
        let rejected = [];
        for (let i = 1; i <= 6; i++) {
          await p.keyboard.press(".");
          const s = await waitState(p, (st) => st.iteration === i, `sample ${i}`);
          rejected = rejected.concat((s.last_sample_checks || []).filter((c) => c.rejected));
        }
        // Before the first accepted hypothesis the test is weak (ε = 0.1, δ = 0.05): the
        // first rejections take up to about a hundred matches; then a dozen or so.
        const checked = rejected.map((c) => c.evaluated).sort((a, b) => a - b);
        const median = checked[Math.floor(checked.length / 2)];
        assert(rejected.length > 0 && median < 30 && checked[checked.length - 1] < s0.matches / 2, `rejections ${JSON.stringify(rejected)}`);
        await sleep(300);
        const { stats } = await waitNotBlank(p, "visual-odometry-sprt.png");
        assertNotBlank(stats, "visual-odometry-sprt.png");
        const headless = await runHeadless(p, "lesson=visual-odometry&seed=3&early-rejection=sprt", 10);
        const got = `best_inliers=${headless.best_inliers} bound=${headless.bound} rmse=${headless.trajectory_rmse.visual_odometry}`;
        const NATIVE = "best_inliers=467 bound=46 rmse=0.7308602394501984";
        assert(got === NATIVE, `${got} in the browser, ${NATIVE} natively`);
        return `${rejected.length} hypotheses rejected early in 6 samples, after ${rejected.map((c) => c.evaluated).join(", ")} matches; headless ${got}`;
      });
    });

    // --- The visual-odometry lesson with two photos dropped on the page (the same path as
    // a drag from the desktop: DataTransfer files on the canvas): FAST corners, BRIEF,
    // Hamming matching and five-point RANSAC in wasm; the matches and the estimate appear,
    // at 1280 x 800, at 800 x 500 and embedded at 900 x 600 in web/lecture.html. Then a file
    // that is not an image and the same photo twice: a message, the pair kept, no panic.
    {
      const pair = photoPair();
      const asFile = (name, bytes, type) => ({ name, type, b64: Buffer.from(bytes).toString("base64") });
      const photoFiles = [asFile("left.png", pair.left, "image/png"), asFile("right.png", pair.right, "image/png")];
      const checkPhotos = (photos, where) => {
        assert(photos.showing === true && photos.left === "left.png" && photos.right === "right.png", `${where}: ${JSON.stringify(photos)}`);
        assert(photos.matches >= 150 && photos.inliers >= 0.8 * photos.matches, `${where}: matches ${JSON.stringify(photos)}`);
        assert(Math.abs(photos.rotation_deg - pair.rotationDeg) < 0.3, `${where}: rotation ${photos.rotation_deg} deg, truth ${pair.rotationDeg.toFixed(3)}`);
      };
      await check("lesson=visual-odometry: two dropped photos are matched and RANSAC's estimate appears", async () => {
        const notes = [];
        for (const viewport of [VIEWPORT, { width: 800, height: 500 }]) {
          const context = await browser.newContext({ viewport, deviceScaleFactor: 1 });
          const p = await context.newPage();
          const log = { label: `visual-odometry photos ${viewport.width}x${viewport.height}`, url: "", console: [], problems: [] };
          pageLogs.push(log);
          p.on("pageerror", (err) => log.problems.push(`uncaught exception: ${err.message}`));
          try {
            await p.goto(new URL("index.html?lesson=visual-odometry&seed=3", baseUrl).href, { waitUntil: "load" });
            await p.waitForFunction(() => document.getElementById("status")?.dataset.state === "running", null, { timeout: START_TIMEOUT_MS });
            await waitState(p, (st) => st.lesson === "visual-odometry" && st.frames > 2, "the visual-odometry lesson");
            await dropFiles(p, photoFiles);
            const s = await waitState(p, (st) => st.photos && st.photos.inliers > 0, "the photos' estimate", 60_000);
            checkPhotos(s.photos, `${viewport.width} x ${viewport.height}`);
            await sleep(300);
            const name = `visual-odometry-photos-${viewport.width}x${viewport.height}.png`;
            const { stats } = await waitNotBlank(p, name);
            assertNotBlank(stats, name);
            notes.push(
              `${viewport.width} x ${viewport.height}: ${s.photos.matches} matches, ${s.photos.inliers} inliers, ` +
                `rotation ${s.photos.rotation_deg.toFixed(3)} deg (truth ${pair.rotationDeg.toFixed(3)})`,
            );
            if (viewport === VIEWPORT) {
              // Not an image: a message, the pair kept (a .txt would be a student's relative pose,
              // read as an estimate; a document is refused by the photos).
              await dropFiles(p, [{ name: "notes.md", type: "text/markdown", b64: Buffer.from("not a photo").toString("base64") }]);
              const bad = await waitState(p, (st) => st.photos && st.photos.message, "a message for notes.md");
              assert(/notes\.md is not an image/.test(bad.photos.message), `message ${bad.photos.message}`);
              checkPhotos(bad.photos, "after notes.md");
              // The same photo twice: a pure rotation, no translation.
              await dropFiles(p, [asFile("left.png", pair.left, "image/png"), asFile("left-again.png", pair.left, "image/png")]);
              const same = await waitState(p, (st) => st.photos && st.photos.right === "left-again.png" && st.photos.inliers > 0, "the same photo twice");
              assert(same.photos.rotation_deg < 0.01, `the same photo twice: ${JSON.stringify(same.photos)}`);
              if ("motion" in same.photos) assert(same.photos.motion === "pure-rotation", `the same photo twice: ${JSON.stringify(same.photos)}`);
              await sleep(300);
              await screenshot(p, "visual-odometry-photos-identical.png");
              notes.push(`notes.md refused; the same photo twice: rotation ${same.photos.rotation_deg.toFixed(4)} deg, ${same.photos.motion ?? "?"}`);
            }
            await assertNoPanic(p);
            assert(log.problems.length === 0, log.problems.join("; "));
          } finally {
            await context.close();
          }
        }
        // Embedded in the lecture page at 900 x 600, as a lecturer would add it.
        const { context, page: lecture, log } = await openPage(browser, baseUrl, "lecture.html", "lecture (visual odometry)");
        try {
          await lecture.evaluate(() => {
            const iframe = document.createElement("iframe");
            iframe.className = "slamlab-vo";
            iframe.width = "900";
            iframe.height = "600";
            iframe.style.border = "0";
            iframe.src = "index.html?lesson=visual-odometry&seed=3&embed=1";
            document.body.prepend(iframe);
          });
          const element = lecture.locator("iframe.slamlab-vo");
          const frame = await (await element.elementHandle()).contentFrame();
          await waitRunning(frame);
          await waitState(frame, (st) => st.lesson === "visual-odometry" && st.frames > 2, "the embedded lesson");
          await dropFiles(frame, photoFiles);
          const s = await waitState(frame, (st) => st.photos && st.photos.inliers > 0, "the photos' estimate (embedded)", 60_000);
          checkPhotos(s.photos, "embedded 900 x 600");
          await sleep(300);
          const stats = imageStats(await screenshot(element, "visual-odometry-photos-lecture-900x600.png"));
          assertNotBlank(stats, "the embedded lesson with photos");
          await assertNoPanic(frame);
          assert(log.problems.length === 0, log.problems.join("; "));
          notes.push(`embedded 900 x 600 in lecture.html: ${s.photos.inliers} inliers`);
        } finally {
          await context.close();
        }
        return notes.join("; ");
      });
    }

    // --- The teaching shell: every lesson keeps its map at small and large
    // windows; an embedded figure lets the lecture page scroll until it is clicked; a
    // figure opened with tick= shows the run mid-lap with its plots drawn.
    {
      // The map (the central panel) must get at least this share of the window.
      const SHELL_SIZES = [
        // 360 x 480: a phone in landscape; the plots are a drawer, closed at first.
        { width: 360, height: 480, minShare: 0.55, narrow: true },
        { width: 800, height: 500, minShare: 0.45, narrow: true },
        { width: 1280, height: 800, minShare: 0.3, narrow: false },
      ];
      // Pixels within `tol` of `rgb` in rows y0..y1 of a decoded PNG.
      const countColour = (image, rgb, tol, y0 = 0, y1 = image.height) => {
        let n = 0;
        for (let y = Math.max(0, Math.floor(y0)); y < Math.min(image.height, Math.ceil(y1)); y++) {
          for (let x = 0; x < image.width; x++) {
            const o = (y * image.width + x) * image.channels;
            if (Math.abs(image.data[o] - rgb[0]) <= tol && Math.abs(image.data[o + 1] - rgb[1]) <= tol && Math.abs(image.data[o + 2] - rgb[2]) <= tol) n++;
          }
        }
        return n;
      };
      const openSized = async (relativeUrl, viewport, label) => {
        const context = await browser.newContext({ viewport, deviceScaleFactor: 1 });
        const page = await context.newPage();
        const log = { label, url: relativeUrl, console: [], problems: [] };
        pageLogs.push(log);
        page.on("console", (msg) => {
          log.console.push(`[${msg.type()}] ${msg.text()}`);
          if (msg.type() === "error" && !ALLOWED_CONSOLE.some((re) => re.test(msg.text()))) log.problems.push(`console.error: ${msg.text()}`);
        });
        page.on("pageerror", (err) => log.problems.push(`uncaught exception: ${err.message}`));
        // waitRunning() reads when #status changed (as openPage records it).
        await page.addInitScript(() => {
          window.__slamlabStatusTimes = {};
          document.addEventListener("DOMContentLoaded", () => {
            const status = document.getElementById("status");
            const note = () => {
              if (!(status.dataset.state in window.__slamlabStatusTimes)) window.__slamlabStatusTimes[status.dataset.state] = performance.now();
            };
            note();
            new MutationObserver(note).observe(status, { attributes: true, childList: true, characterData: true, subtree: true });
          });
        });
        await page.goto(new URL(relativeUrl, baseUrl).href, { waitUntil: "load" });
        return { context, page, log };
      };
      const LAYOUT_QUERIES = {
        "landmark-slam": "lesson=landmark-slam&seed=7",
        kidnap: "lesson=kidnap&seed=7",
        "pose-graph": "lesson=pose-graph&seed=7",
        resampling: "lesson=resampling&seed=7",
        fusion: "lesson=fusion&seed=7",
        "visual-odometry": "lesson=visual-odometry&seed=7",
        "mapping-grid-fastslam": "lesson=mapping&seed=7&steps=300&poses=grid-fastslam&tick=120",
      };
      for (const [lesson, query] of Object.entries(LAYOUT_QUERIES)) {
        for (const size of SHELL_SIZES) {
          const name = `layout-${lesson}-${size.width}x${size.height}`;
          await check(`${lesson} at ${size.width} x ${size.height}: the map keeps ≥ ${(100 * size.minShare).toFixed(0)} % of the window`, async () => {
            const { context, page, log } = await openSized(`index.html?${query}`, { width: size.width, height: size.height }, name);
            try {
              await waitRunning(page);
              const state = await waitState(page, (s) => s.frames >= 1 && Array.isArray(s.map_rect), "the map's rectangle");
              const { stats } = await waitNotBlank(page, `${name}.png`);
              assertNotBlank(stats, name);
              const [x, y, w, h] = state.map_rect;
              const share = (w * h) / (size.width * size.height);
              assert(state.narrow === size.narrow, `narrow is ${state.narrow}`);
              assert(share >= size.minShare, `the map is ${w.toFixed(0)} x ${h.toFixed(0)} px at (${x.toFixed(0)}, ${y.toFixed(0)}): ${(100 * share).toFixed(1)} % of the window`);
              assert(x >= 0 && x + w <= size.width + 0.5 && y + h <= size.height + 0.5, `the map is cut off: ${state.map_rect}`);
              if (size.narrow) assert(!state.panels.parameters && !state.panels.explanation, `drawers open: ${JSON.stringify(state.panels)}`);
              await assertNoPanic(page);
              assert(log.problems.length === 0, log.problems.join("; "));
              return `map ${w.toFixed(0)} x ${h.toFixed(0)} px = ${(100 * share).toFixed(1)} %; ${describe(stats)}`;
            } finally {
              await context.close();
            }
          });
        }
      }

      await check("lecture.html: the wheel scrolls the page over a figure until it is clicked; figure 1 opens at tick= with its plots", async () => {
        const { context, page: lecture, log } = await openPage(browser, baseUrl, "lecture.html", "lecture (wheel)");
        try {
          const figure = lecture.locator("iframe.slamlab").first();
          await figure.scrollIntoViewIfNeeded();
          const frame = await (await figure.elementHandle()).contentFrame();
          await waitRunning(frame);
          const wanted = Number(new URL(frame.url()).searchParams.get("tick"));
          assert(wanted > 0, `figure 1 has no tick= (${frame.url()})`);
          const first = await waitState(frame, (s) => s.frames >= 1 && Array.isArray(s.map_rect), "figure 1's first frames");
          assert(first.tick === wanted && !first.running, `figure 1 opened at tick ${first.tick} (running ${first.running}), the URL says ${wanted}`);
          // The plots below the map are drawn: EKF blue (#0072B2) in the plots' rows.
          await sleep(300);
          const image = await screenshot(figure, "lecture-figure1-tick.png");
          const [, mapTop, , mapHeight] = first.map_rect;
          const plotBlue = countColour(image, [0x00, 0x72, 0xb2], 40, mapTop + mapHeight, image.height);
          const mapBlue = countColour(image, [0x00, 0x72, 0xb2], 40, mapTop, mapTop + mapHeight);
          assert(plotBlue > 100, `only ${plotBlue} EKF-blue pixels in the plots (map ${mapBlue})`);
          assert(mapBlue > 100, `only ${mapBlue} EKF-blue pixels in the map`);

          // Put the figure in the middle of the window, the pointer over its map, and wheel.
          await lecture.evaluate(() => {
            const f = document.querySelector("iframe.slamlab");
            window.scrollTo(0, f.getBoundingClientRect().top + window.scrollY - 150);
          });
          await sleep(200);
          const box = await figure.boundingBox();
          await lecture.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
          const before = await lecture.evaluate(() => window.scrollY);
          let hint = null;
          for (let i = 0; i < 4; i++) {
            await lecture.mouse.wheel(0, 120);
            await sleep(80);
            // The hint shows while the wheel passes the figure by (the first turn).
            if (i === 0) hint = await frame.evaluate(() => document.getElementById("wheel_hint").dataset.shown);
          }
          await sleep(400);
          const after = await lecture.evaluate(() => window.scrollY);
          const wheel = await frame.evaluate(() => window.slamlabWheel);
          await lecture.screenshot({ path: path.join(outDir, "lecture-wheel-scrolled.png") });
          assert(after - before >= 300, `the page scrolled ${after - before} px over the figure (wheel state ${JSON.stringify(wheel)})`);
          assert(wheel.embedded && !wheel.active && wheel.passed >= 1, `the figure's wheel state ${JSON.stringify(wheel)}`);
          assert(hint === "1", `the hint is not shown (${hint})`);

          // After a click into the figure the wheel is the figure's: the page stays put.
          const box2 = await figure.boundingBox();
          const visibleTop = Math.max(box2.y, 0);
          const inside = { x: box2.x + box2.width / 2, y: (visibleTop + Math.min(box2.y + box2.height, VIEWPORT.height)) / 2 };
          await lecture.mouse.click(inside.x, inside.y);
          await sleep(200);
          const held = await lecture.evaluate(() => window.scrollY);
          for (let i = 0; i < 3; i++) {
            await lecture.mouse.wheel(0, 120);
            await sleep(80);
          }
          await sleep(300);
          const still = await lecture.evaluate(() => window.scrollY);
          const active = await frame.evaluate(() => window.slamlabWheel.active);
          assert(active, "the click did not activate the figure");
          assert(Math.abs(still - held) < 5, `the page scrolled ${still - held} px over an active figure`);
          await assertNoPanic(frame);
          assert(log.problems.length === 0, log.problems.join("; "));
          return `opened at tick ${first.tick}; EKF-blue pixels: map ${mapBlue}, plots ${plotBlue}; page scrolled ${after - before} px over the passive figure, ${still - held} px over the clicked one`;
        } finally {
          await context.close();
        }
      });
    }

    // --- A panic must be visible: the red banner, #status "panicked", and the app stops.
    await check("a panic shows the red #panic banner and stops the app", async () => {
      const { context, page: p, log } = await openPage(browser, baseUrl, `index.html?${LESSON}`, "panic (deliberate)");
      try {
        await waitRunning(p);
        const message = "deliberate panic from the browser test";
        const thrown = await p.evaluate((m) => {
          try {
            window.slamlab.slamlab_debug_panic(m);
            return null;
          } catch (err) {
            return String(err); // a Rust panic aborts: JS sees a RuntimeError ("unreachable")
          }
        }, message);
        await sleep(300);
        await p.screenshot({ path: path.join(outDir, "panic-banner.png") });
        const seen = await p.evaluate(() => ({
          banner: !document.getElementById("panic").hidden,
          bannerText: document.getElementById("panic").textContent,
          status: document.getElementById("status").textContent.trim(),
          panicked: window.slamlab.slamlab_panicked(),
          message: window.slamlab.slamlab_panic_message() ?? null,
          state: window.slamlab.slamlab_test_state(),
        }));
        assert(thrown !== null, "slamlab_debug_panic returned normally");
        assert(seen.banner && seen.bannerText.includes(message), `no visible banner with the message: ${JSON.stringify(seen)}`);
        assert(seen.status === "panicked", `#status is "${seen.status}", not "panicked"`);
        assert(seen.panicked && seen.message?.includes(message), `slamlab_panicked()/slamlab_panic_message(): ${JSON.stringify(seen)}`);
        assert(JSON.parse(seen.state).error === "panicked", `slamlab_test_state() after the panic: ${seen.state}`);
        const logged = log.console.some((line) => line.startsWith("[error]") && line.includes(message));
        assert(logged, "the panic was not logged with console.error");
        log.problems = log.problems.filter((problem) => !problem.includes(message) && !/unreachable/i.test(problem));
        return `banner shown, #status "${seen.status}", JS saw ${thrown}`;
      } finally {
        await context.close();
      }
    });

    // --- Sensor fusion by URL: the lesson runs, and a seeded 40 s drive fused headless in
    // this page's wasm gives each mode's RMSE with exactly the native bits
    // (crates/slamlab-app/tests/lessons/fusion_ui.rs pins the same numbers).
    await check("lesson=fusion runs and its RMSE table has the native numbers", async () => {
      const query = "lesson=fusion&seed=3&duration=40";
      return withPage(browser, baseUrl, `index.html?${query}`, "fusion", async ({ page: p }) => {
        await waitRunning(p);
        const s0 = await waitState(p, (st) => st.lesson === "fusion" && st.frames > 2, "the fusion lesson");
        assert(s0.seed === 3 && s0.runs.length === 2, `opened ${JSON.stringify(s0)}`);
        assert(s0.runs[0].mode === "differential" && s0.runs[1].mode === "relative", `modes ${JSON.stringify(s0.runs)}`);
        await p.mouse.click(VIEWPORT.width / 2, VIEWPORT.height / 2); // gives the canvas keyboard focus
        await p.keyboard.press("Space");
        const s1 = await waitState(p, (st) => st.time >= 5, "5 s of the drive running", 60_000);
        assert(/ at \d+\.\d\d s/.test(s1.phase), `the step label names no reading: "${s1.phase}"`);
        await sleep(300);
        const { stats } = await waitNotBlank(p, "fusion-running.png");
        assertNotBlank(stats, "fusion-running.png");
        const headless = JSON.parse(await p.evaluate((q) => window.slamlab.slamlab_test_headless(q, 41), query));
        assert(headless.finished, `the headless drive did not finish: ${JSON.stringify(headless)}`);
        const NATIVE = [
          [0.018338686029263813, 0.009054579079795273, 0.02768865985373698],
          [0.07364447075865203, 0.05369803159610187, 0.04716598788885103],
        ];
        headless.runs.forEach((run, k) => {
          assert(
            run.rmse.every((v, i) => v === NATIVE[k][i]),
            `${run.mode}: RMSE ${JSON.stringify(run.rmse)} in the browser, ${JSON.stringify(NATIVE[k])} natively`,
          );
        });
        const text = headless.runs.map((r) => `${r.mode} x ${r.rmse[0].toFixed(4)} m`).join(", ");
        return `ran to ${s1.time.toFixed(2)} s ("${s1.phase}"); headless 40 s: ${text}, bit-identical to native`;
      });
    });

    // --- lesson=pose-graph: one solver iteration lowers the cost; then M3500 (from
    // ../shared/data/posegraphs when present) is dropped on the canvas as a file and
    // optimized to convergence in the page, frame by frame; its time is reported.
    await check("lesson=pose-graph: one iteration lowers the cost; M3500 dropped on the page optimizes", async () => {
      const url = "index.html?lesson=pose-graph&example=manhattan&seed=1";
      return withPage(browser, baseUrl, url, "pose-graph", async ({ page: p }) => {
        await waitRunning(p);
        const s0 = await waitState(p, (st) => st.lesson === "pose-graph" && st.frames > 2, "the pose-graph lesson");
        assert(s0.source === "manhattan" && s0.iterations === 0, `opened ${JSON.stringify(s0)}`);
        await p.mouse.click(VIEWPORT.width / 2, VIEWPORT.height / 2); // keyboard focus
        await p.keyboard.press(".");
        const s1 = await waitState(p, (st) => st.iterations === 1, "one GN iteration");
        assert(s1.cost < s0.cost, `the cost did not fall: ${s0.cost} -> ${s1.cost}`);
        await sleep(300);
        const { stats } = await waitNotBlank(p, "pose-graph-step.png");
        assertNotBlank(stats, "pose-graph-step.png");
        const file = path.join(sharedDataDir, "posegraphs", "M3500.g2o");
        let m3500 = `M3500 not measured: ${file} is absent (SLAMLAB_SHARED_DATA names the shared data sets)`;
        let text = null;
        try {
          text = await readFile(file, "utf8");
        } catch {
          console.log(`  (skipping the M3500 timing: ${file} is absent)`);
        }
        if (text !== null) {
          await dropFiles(p, [{ name: "M3500.g2o", text }]);
          const done = await waitState(
            p,
            (st) => st.source === "M3500.g2o" && !st.optimizing && st.optimize !== null,
            "M3500 optimized",
            60_000,
          );
          assert(done.vertices === 3500 && done.converged, `M3500: ${JSON.stringify(done)}`);
          assert(done.cost < 1e-3 * done.initial_cost, `M3500 cost ${done.initial_cost} -> ${done.cost}`);
          m3500 =
            `M3500 (${done.vertices} vertices, ${done.edges} edges) ${done.solver}: ${done.optimize.iterations} iterations, ` +
            `cost ${done.initial_cost.toExponential(4)} -> ${done.cost.toExponential(4)} in ${done.optimize.wall_ms.toFixed(0)} ms ` +
            `(${done.optimize.compute_ms.toFixed(0)} ms in the solver)`;
          metrics.pose_graph_m3500_wall_ms = done.optimize.wall_ms;
          metrics.pose_graph_m3500_solver_ms = done.optimize.compute_ms;
          await sleep(300);
          await screenshot(p, "pose-graph-m3500.png");
        }
        return `cost ${s0.cost.toExponential(4)} -> ${s1.cost.toExponential(4)} after one iteration; ${m3500}`;
      });
    });

    // --- Exports (File menu; started here through the test hook, as the menu does):
    // every plot's data as CSV, the scenario as JSON, the map as PNG, each a real
    // download. The JSON, dropped on a page of another lesson, reopens the same setup.
    await check("exports: plot CSV, scenario JSON and map PNG download, and the JSON reopens the setup", async () => {
      const url = "index.html?lesson=landmark-slam&seed=7&estimator=ekf,ukf&tick=30";
      return withPage(browser, baseUrl, url, "exports", async ({ page: p }) => {
        await waitRunning(p);
        const s0 = await waitState(p, (st) => st.frames >= 2 && Array.isArray(st.map_rect), "the first frames");
        const download = async (kind) => {
          // A click on the map first: Chromium allows a page's second download only
          // after a user gesture, as the student's click on the File menu is.
          await p.mouse.click(s0.map_rect[0] + s0.map_rect[2] / 2, s0.map_rect[1] + s0.map_rect[3] / 2);
          const [file, asked] = await Promise.all([
            p.waitForEvent("download", { timeout: 20_000 }).catch(async (err) => {
              const st = await testState(p);
              throw new Error(`${kind}: no download; the app says ${JSON.stringify(st.export_status)} (${err.message.split("\n")[0]})`);
            }),
            p.evaluate((k) => window.slamlab.slamlab_test_export(k), kind),
          ]);
          assert(asked, `${kind}: the export hook refused`);
          const where = await file.path();
          return { name: file.suggestedFilename(), bytes: await readFile(where) };
        };
        const csv = await download("plots-csv");
        const rows = csv.bytes.toString("utf8").trim().split("\n");
        assert(rows[0] === "plot,x_axis,y_axis,series,x,y", `CSV header: ${rows[0]}`);
        assert(rows.length > 100, `only ${rows.length} CSV rows`);
        assert(rows.some((r) => r.startsWith("Robot pose NEES (3 dof),time (s),NEES,UKF NEES,")), "no UKF NEES rows");
        assert(csv.name === "slamlab-landmark-slam-t30-plots.csv", `CSV name ${csv.name}`);
        const json = await download("scenario-json");
        const scenario = JSON.parse(json.bytes.toString("utf8"));
        assert(scenario.format === "slamlab-scenario" && scenario.lesson === "landmark-slam", json.bytes.toString());
        // (EKF and UKF are the lesson's default estimators, so the link leaves them out.)
        assert(scenario.params.seed === "7" && scenario.view.tick === "30", json.bytes.toString());
        const png = await download("map-png");
        const image = decodePng(png.bytes);
        const [, , mw, mh] = s0.map_rect;
        assert(Math.abs(image.width - mw) <= 2 && Math.abs(image.height - mh) <= 2, `PNG ${image.width} x ${image.height}, map ${mw} x ${mh}`);
        assertNotBlank(imageStats(image), "the exported map");
        await writeFile(path.join(outDir, "export-map.png"), png.bytes);

        // The JSON dropped on the fusion lesson's page opens the landmark lesson at tick 30.
        const { context: c2, page: other, log: log2 } = await openPage(browser, baseUrl, "index.html?lesson=fusion", "exports (reopen)");
        try {
          await waitRunning(other);
          await waitState(other, (st) => st.lesson === "fusion" && st.frames >= 2, "the fusion lesson");
          await dropFiles(other, [{ name: "scenario.json", type: "application/json", text: json.bytes.toString("utf8") }]);
          const reopened = await waitState(other, (st) => st.lesson === "landmark-slam", "the dropped scenario", 20_000);
          assert(reopened.tick === 30 && reopened.seed === 7 && reopened.filters.join(",") === "ekf,ukf", JSON.stringify(reopened));
          assert(reopened.notices === 0, `notices after the drop: ${reopened.notices}`);
          await assertNoPanic(other);
          assert(log2.problems.length === 0, log2.problems.join("; "));
        } finally {
          await c2.close();
        }
        return `CSV ${rows.length - 1} rows, JSON ${json.bytes.length} bytes, map PNG ${image.width} x ${image.height}; the JSON dropped on another lesson reopened tick 30`;
      });
    });

    // --- A student's estimate: File > Export trajectories downloads a zip of TUM and CSV
    // files; the EKF's TUM file, dropped back on the page under another name, becomes one
    // more estimator, scored in wasm exactly as the lesson scores its own EKF; it is drawn
    // on the map, at 1280 x 800 and at 800 x 500.
    await check("estimates: the exported EKF dropped back as a student's estimate scores as the lesson's own", async () => {
      const results = [];
      for (const [w, h] of [[1280, 800], [800, 500]]) {
        const url = "index.html?lesson=landmark-slam&seed=7&estimator=ekf,ukf&tick=60";
        await withPage(browser, baseUrl, url, `estimates ${w}x${h}`, async ({ page: p }) => {
          await waitRunning(p);
          const s0 = await waitState(p, (st) => st.frames >= 2 && Array.isArray(st.map_rect), "the first frames");
          await p.mouse.click(s0.map_rect[0] + s0.map_rect[2] / 2, s0.map_rect[1] + s0.map_rect[3] / 2);
          const [file, asked] = await Promise.all([
            p.waitForEvent("download", { timeout: 20_000 }),
            p.evaluate(() => window.slamlab.slamlab_test_export("trajectories-zip")),
          ]);
          assert(asked, "the export hook refused");
          assert(file.suggestedFilename() === "slamlab-landmark-slam-t60-trajectories.zip", file.suggestedFilename());
          const files = unzip(await readFile(await file.path()));
          const folder = "slamlab-landmark-slam-t60-trajectories/";
          for (const name of ["truth.tum", "ekf.tum", "ekf.csv", "ukf.tum", "dead-reckoning.tum", "ekf-landmarks.csv", "README.txt"]) {
            assert(files[folder + name], `${name} missing from the zip: ${Object.keys(files).join(", ")}`);
          }
          const ekf = files[folder + "ekf.tum"].toString("utf8");
          assert(ekf.trim().split("\n").length === 62, `ekf.tum has ${ekf.trim().split("\n").length} lines`);
          await dropFiles(p, [{ name: "mine.tum", text: ekf }]);
          const st = await waitState(p, (s) => Array.isArray(s.estimates) && s.estimates.some((e) => e.name === "mine.tum" && e.ate_rmse !== null), "the dropped estimate's score", 20_000);
          const mine = st.estimates.find((e) => e.name === "mine.tum");
          const own = st.estimates.find((e) => e.name === "ekf");
          assert(mine.pairs === 61 && own.pairs === 61, `pairs ${mine.pairs} and ${own.pairs}`);
          assert(Math.abs(mine.ate_rmse - own.ate_rmse) <= 1e-9 * Math.max(1, own.ate_rmse), `ATE ${mine.ate_rmse} against the lesson's ${own.ate_rmse}`);
          assert(mine.ate_rmse > 0.01 && mine.ate_rmse < 2, `ATE ${mine.ate_rmse}`);
          assert(st.notices === 0, `notices after the drop: ${st.notices}`);
          const shot = await screenshot(p, `estimates-${w}x${h}.png`);
          assertNotBlank(imageStats(shot), `the page with an estimate at ${w}x${h}`);
          results.push(`${w}x${h}: ATE ${mine.ate_rmse.toFixed(4)} m (the lesson's EKF ${own.ate_rmse.toFixed(4)} m)`);
        }, { width: w, height: h });
      }
      return results.join("; ");
    });

    // --- A student's map and a student's optimized graph dropped on their lessons
    // (issue 40): the mapping lesson's own map (its ROS map as Export map writes it) and
    // the pose-graph lesson's own optimized graph (g2o), taken from the page
    // (slamlab_test_own_files) and dropped back, score as the lesson's own: the same map
    // agreement and coverage to the bit, a cost ratio of 1 to 1e-9. Then a 65 MiB file
    // made in the page, dropped on the lesson: refused from its size before eframe reads
    // it, a notice names it and its size, the lesson keeps running, and the estimate
    // dropped before stays. Screenshots at 800 x 500 and 1280 x 800.
    await check("estimates: a dropped map and optimized graph score as the lesson's own; a 65 MiB drop is refused unread", async () => {
      const drop = (p, files) => dropFiles(p, files.map((f) => ({ name: f.name, type: "application/octet-stream", bytes: f.bytes })));
      const results = [];
      for (const [w, h] of [[800, 500], [1280, 800]]) {
        // The mapping lesson: 120 scans of the maze with scan-to-map matching.
        {
          const url = "index.html?lesson=mapping&map=maze&seed=3&steps=200&poses=scan-to-map&tick=120";
          await withPage(browser, baseUrl, url, `map estimate ${w}x${h}`, async ({ page: p }) => {
            await waitRunning(p);
            await waitState(p, (st) => st.frames >= 2 && st.tick >= 120, "120 scans");
            const files = JSON.parse(await p.evaluate(() => window.slamlab.slamlab_test_own_files()));
            assert(files.map((f) => f.name).join(",") === "slamlab-map.yaml,slamlab-map.pgm", JSON.stringify(files.map((f) => f.name)));
            await drop(p, files);
            const st = await waitState(p, (s) => Array.isArray(s.estimates) && s.estimates.some((e) => e.name === "slamlab-map.yaml" && e.map_agreement !== null), "the dropped map's score", 20_000);
            const mine = st.estimates.find((e) => e.name === "slamlab-map.yaml");
            const own = st.estimates.find((e) => e.name === "scan-to-map (map)");
            assert(own && mine.map_agreement === own.map_agreement && mine.map_coverage === own.map_coverage,
              `agreement ${mine.map_agreement} / ${own && own.map_agreement}, coverage ${mine.map_coverage} / ${own && own.map_coverage}`);
            assert(mine.map_agreement > 0.8 && mine.map_agreement < 0.9, `agreement ${mine.map_agreement}`);
            await screenshot(p, `map-estimate-${w}x${h}.png`);
            // A 65 MiB file made in the page: refused before it is read.
            const before = st.notices;
            await dropFiles(p, [{ name: "big.tum", zeros: 65 * 1024 * 1024 }]);
            const refused = await waitState(p, (s) => s.notices > before, "the refusal's notice", 20_000);
            assert(refused.notice_list.some((n) => n.startsWith("big.tum has 68157440 bytes, more than the 67108864 bytes SLAM Lab reads")), JSON.stringify(refused.notice_list));
            assert(refused.estimates.some((e) => e.name === "slamlab-map.yaml"), "the map dropped before stays");
            const t0 = refused.tick;
            await p.keyboard.press("Space");
            await waitState(p, (s) => s.tick > t0, "the lesson running on after the refusal", 20_000);
            await screenshot(p, `big-drop-refused-${w}x${h}.png`);
            results.push(`${w}x${h}: map agreement ${mine.map_agreement.toFixed(4)} (the lesson's ${own.map_agreement.toFixed(4)}), coverage ${mine.map_coverage.toFixed(4)}`);
          }, { width: w, height: h });
        }
        // The pose-graph lesson: the thesis example optimized to convergence.
        {
          const url = "index.html?lesson=pose-graph&example=thesis&solver=gn&seed=1";
          await withPage(browser, baseUrl, url, `graph solution ${w}x${h}`, async ({ page: p }) => {
            await waitRunning(p);
            const s0 = await waitState(p, (st) => st.frames >= 2 && Array.isArray(st.map_rect), "the first frames");
            await p.mouse.click(s0.map_rect[0] + s0.map_rect[2] / 2, s0.map_rect[1] + s0.map_rect[3] / 2);
            await p.keyboard.press("Space");
            await waitState(p, (st) => st.converged === true, "the lesson's graph converged", 30_000);
            const files = JSON.parse(await p.evaluate(() => window.slamlab.slamlab_test_own_files()));
            assert(files.length === 1 && files[0].name === "optimized.g2o", JSON.stringify(files.map((f) => f.name)));
            await drop(p, files);
            const st = await waitState(p, (s) => Array.isArray(s.solutions) && s.solutions.length === 1 && s.solutions[0].cost_ratio !== null, "the solution's score", 20_000);
            const ratio = st.solutions[0].cost_ratio;
            assert(Math.abs(ratio - 1) <= 1e-9, `cost ratio ${ratio}`);
            assert(st.solutions[0].ate === st.rmse, `RMSE ${st.solutions[0].ate} against the lesson's ${st.rmse}`);
            await screenshot(p, `graph-solution-${w}x${h}.png`);
            results.push(`${w}x${h}: cost ratio ${ratio}`);
          }, { width: w, height: h });
        }
      }
      return results.join("; ");
    });

    // --- Homework by link (web/lecture.html's fourth figure): the page asks for the
    // student's id; with it (student=), the landmark lesson runs the student's variant to its
    // last step; the lesson's EKF and dead reckoning, exported and dropped back on the figure,
    // are graded in wasm (EKF 100 of 100 and pass, dead reckoning 0 and fail, its ATE beside
    // the reference EKF's to the bit); the report names the file's SHA-256; the Assignment
    // panel beside the map at 1280 x 800 and 800 x 500.
    await check("assignment: a homework link grades a dropped estimate in the page", async () => {
      const { createHash } = await import("node:crypto");
      const notes = [];
      const { context, page: lecture, log } = await openPage(browser, baseUrl, "lecture.html", "lecture (homework)");
      let estimates;
      try {
        const element = lecture.locator("iframe.slamlab-homework");
        assert(await element.count() === 1, "lecture.html has no homework figure");
        await element.scrollIntoViewIfNeeded();
        let frame = await (await element.elementHandle()).contentFrame();
        await waitRunning(frame);
        const asks = await waitState(frame, (st) => st.assignment && st.frames >= 2, "the assignment");
        assert(asks.assignment.stage === "needs-student" && asks.assignment.id === "ekf-slam", JSON.stringify(asks.assignment));
        // Alice's link: first her variant's length, then the lesson at its last step.
        const open = async (query) => {
          await element.evaluate((el, src) => { el.src = src; }, `index.html?${query}`);
          frame = await (await element.elementHandle()).contentFrame();
          await frame.waitForURL((u) => u.href.endsWith(query), { waitUntil: "load", timeout: 30_000 });
          await waitRunning(frame);
          return waitState(frame, (st) => st.assignment && st.assignment.stage === "ready" && st.frames >= 2, "Alice's variant", 60_000);
        };
        const base = "assignment=ekf-slam&student=alice%40example.edu&estimator=ekf&embed=1&panels=plots";
        const first = await open(base);
        const steps = first.assignment.steps;
        assert(steps >= 1000 && steps <= 1200 && first.seed === first.assignment.seed, JSON.stringify(first.assignment));
        const atEnd = await open(`${base}&tick=${steps}`);
        assert(atEnd.tick === steps && atEnd.notices === 0, `tick ${atEnd.tick} of ${steps}, ${atEnd.notices} notices`);
        const [zip, asked] = await Promise.all([
          lecture.waitForEvent("download", { timeout: 30_000 }),
          frame.evaluate(() => window.slamlab.slamlab_test_export("trajectories-zip")),
        ]);
        assert(asked, "the export hook refused");
        const files = unzip(await readFile(await zip.path()));
        const folder = zip.suggestedFilename().replace(/\.zip$/, "/");
        estimates = { ekf: files[folder + "ekf.tum"].toString("utf8"), dr: files[folder + "dead-reckoning.tum"].toString("utf8") };
        assert(estimates.ekf.trim().split("\n").length === steps + 2, `ekf.tum has ${estimates.ekf.trim().split("\n").length} lines`);
        await dropFiles(frame, [{ name: "estimate.tum", text: estimates.ekf }]);
        await waitState(frame, (st) => st.assignment.graded.length === 1, "the first grade", 60_000);
        await dropFiles(frame, [{ name: "dead-reckoning.tum", text: estimates.dr }]);
        const st = await waitState(frame, (s) => s.assignment.graded.length === 2, "the second grade", 60_000);
        const [ekf, dr] = st.assignment.graded;
        assert(ekf.file === "estimate.tum" && ekf.score === 100 && ekf.max_score === 100 && ekf.pass === true, JSON.stringify(ekf));
        assert(dr.score === 0 && dr.pass === false, JSON.stringify(dr));
        const ate = ekf.criteria[0];
        const reference = ate.references.find((r) => r.name === "ekf").value;
        assert(ate.metric === "ate_rmse" && Math.abs(ate.value - reference) <= 1e-12, `the lesson's EKF ${ate.value} m, the reference EKF ${reference} m`);
        assert(dr.criteria[0].value > 0.5, `dead reckoning's ATE ${dr.criteria[0].value} m`);
        assert(ekf.sha256 === createHash("sha256").update(estimates.ekf).digest("hex"), "the SHA-256 of estimate.tum");
        // The report of the grade shown (the latest): the dead reckoning's.
        const [report, reportAsked] = await Promise.all([
          lecture.waitForEvent("download", { timeout: 20_000 }),
          frame.evaluate(() => window.slamlab.slamlab_test_export("grade-json")),
        ]);
        assert(reportAsked, "the grade-json hook refused");
        const json = JSON.parse((await readFile(await report.path())).toString("utf8"));
        assert(json.assignment === "ekf-slam" && json.student === "alice@example.edu" && json.variant === st.assignment.variant && json.seed === st.assignment.seed, JSON.stringify(json).slice(0, 300));
        assert(json.estimate_sha256 === createHash("sha256").update(estimates.dr).digest("hex") && json.score === 0 && json.max_score === 100 && json.pass === false, JSON.stringify(json).slice(0, 300));
        assert(report.suggestedFilename() === `slamlab-ekf-slam-${st.assignment.variant}-grade.json`, report.suggestedFilename());
        await screenshot(element, "assignment-lecture.png");
        await assertNoPanic(frame);
        assert(log.problems.length === 0, log.problems.join("; "));
        notes.push(`variant ${st.assignment.variant}, ${steps} steps: the lesson's EKF ${ekf.score}/100 (ATE ${ate.value.toFixed(4)} m), dead reckoning ${dr.score}/100 (ATE ${dr.criteria[0].value.toFixed(3)} m)`);
      } finally {
        await context.close();
      }
      // The full page at 1280 x 800 and 800 x 500: the panel beside the map, the grade in it.
      for (const [w, h] of [[1280, 800], [800, 500]]) {
        const url = "index.html?assignment=ekf-slam&student=alice%40example.edu&tick=300";
        await withPage(browser, baseUrl, url, `assignment ${w}x${h}`, async ({ page: p }) => {
          await waitRunning(p);
          const s0 = await waitState(p, (st) => st.frames >= 2 && Array.isArray(st.map_rect) && st.assignment && st.assignment.stage === "ready", "the assignment", 60_000);
          await dropFiles(p, [{ name: "dead-reckoning.tum", text: estimates.dr }]);
          const st = await waitState(p, (s) => s.assignment.graded.length === 1, "the grade", 60_000);
          const [mx, , mw, mh] = st.map_rect;
          assert(mx + mw <= w * 0.7 && mw >= w * 0.35 && mh >= h * 0.3, `the map ${JSON.stringify(st.map_rect)} in ${w} x ${h}`);
          assert(st.assignment.graded[0].pass === false && s0.notices === 0, JSON.stringify(st.assignment.graded[0]).slice(0, 200));
          assertNotBlank(imageStats(await screenshot(p, `assignment-${w}x${h}.png`)), `the assignment at ${w}x${h}`);
          notes.push(`${w}x${h}: map ${mw} x ${mh}`);
        }, { width: w, height: h });
      }
      return notes.join("; ");
    });

    // --- A two-view assignment's link shows the variant's two views
    // (crates/slamlab-app/src/visual_odometry/scene.rs): Alice's 215 matches, the very
    // numbers `slamlab export-inputs two-view --student alice@example.edu` writes (its first
    // line pinned, as the native UI test pins it), the reference RANSAC's inliers, the wrong
    // matches hidden until a pose is graded; the starter's naive pose dropped is graded (fail)
    // and drawn in the top view where the naive reference is. Full page at 1280 x 800 and
    // 800 x 500, and in lecture.html's homework figure.
    await check("assignment: a two-view link shows the variant's two views", async () => {
      const ALICE_FIRST_MATCH = [71.88514417534088, 248.99848867567, 145.40899940678563, 266.8309973367838];
      const naive = "1 0 0\n0 1 0\n0 0 1\n0 0 -1\n";
      const query = "assignment=two-view&student=alice%40example.edu";
      const checkScene = (st) => {
        const tv = st.two_view;
        assert(tv && tv.showing === true, `no two-view scene: ${JSON.stringify(st.two_view)}`);
        assert(st.lesson === "visual-odometry" && tv.seed === st.assignment.seed, `seed ${tv.seed}, variant ${st.assignment.seed}`);
        assert(tv.matches === 215 && tv.matches === st.assignment.steps && tv.pixels.length === 215, `${tv.matches} matches, ${st.assignment.steps} steps`);
        assert(JSON.stringify(tv.pixels[0]) === JSON.stringify(ALICE_FIRST_MATCH), `first match ${JSON.stringify(tv.pixels[0])}`);
        assert(tv.inliers === 148 && tv.wrong === 62, `${tv.inliers} inliers, ${tv.wrong} wrong`);
        assert(tv.top_view[0].name === "true b", JSON.stringify(tv.top_view[0]));
        return tv;
      };
      const notes = [];
      for (const [w, h] of [[1280, 800], [800, 500]]) {
        await withPage(browser, baseUrl, `index.html?${query}`, `two-view ${w}x${h}`, async ({ page: p }) => {
          await waitRunning(p);
          const s0 = await waitState(p, (st) => st.frames >= 2 && st.assignment && st.assignment.stage === "ready" && st.two_view, "the two views", 60_000);
          const tv0 = checkScene(s0);
          assert(tv0.wrong_shown === false && s0.notices === 0, `wrong shown ${tv0.wrong_shown}, ${s0.notices} notices`);
          assertNotBlank(imageStats(await screenshot(p, `assignment-two-view-${w}x${h}.png`)), `the two views at ${w}x${h}`);
          await dropFetched(p, [[`data:text/plain,${encodeURIComponent(naive)}`, "pose.txt"]]);
          const st = await waitState(p, (s) => s.assignment.graded.length === 1 && s.two_view.top_view.length === 5, "the grade", 60_000);
          const tv = checkScene(st);
          const mine = tv.top_view.find((b) => b.name === "b by pose.txt");
          const ref = tv.top_view.find((b) => b.name === "b by naive");
          assert(mine && ref && mine.pose.every((v, k) => v === ref.pose[k]), `pose.txt at ${JSON.stringify(mine)}, the naive reference at ${JSON.stringify(ref)}`);
          assert(st.assignment.graded[0].pass === false && tv.wrong_shown === true, JSON.stringify(st.assignment.graded[0]).slice(0, 200));
          assertNotBlank(imageStats(await screenshot(p, `assignment-two-view-graded-${w}x${h}.png`)), `the graded two views at ${w}x${h}`);
          notes.push(`${w}x${h}: ${tv.inliers} inliers of ${tv.matches}`);
        }, { width: w, height: h });
      }
      const { context, page: lecture, log } = await openPage(browser, baseUrl, "lecture.html", "lecture (two-view homework)");
      try {
        const element = lecture.locator("iframe.slamlab-homework");
        await element.scrollIntoViewIfNeeded();
        // The lazy figure starts loading its own homework once scrolled to: let it
        // run before pointing it elsewhere, or its download is aborted (a failed
        // request, which fails the page).
        await waitRunning(await (await element.elementHandle()).contentFrame());
        await element.evaluate((el, src) => { el.src = src; }, `index.html?${query}&embed=1`);
        const frame = await (await element.elementHandle()).contentFrame();
        await frame.waitForURL((u) => u.href.endsWith("embed=1"), { waitUntil: "load", timeout: 30_000 });
        await waitRunning(frame);
        const st = await waitState(frame, (s) => s.frames >= 2 && s.assignment && s.assignment.stage === "ready" && s.two_view, "the two views in the lecture", 60_000);
        checkScene(st);
        await sleep(300);
        assertNotBlank(imageStats(await screenshot(element, "assignment-two-view-lecture.png")), "the two views in lecture.html");
        await assertNoPanic(frame);
        assert(log.problems.length === 0, log.problems.join("; "));
      } finally {
        await context.close();
      }
      return notes.join("; ");
    });

    // --- The pictures of the README and the lesson documents (web/tests/screenshots.mjs,
    // which scripts/screenshots.sh runs for every picture): one lesson's in every run, so
    // that the script cannot stop working unnoticed. SLAMLAB_SCREENSHOTS=DIR makes them all
    // into DIR.
    const picturesCheck = "screenshots: a lesson's pictures for the README and its document are drawn";
    await check(picturesCheck, async () => {
      // The script selects this check by name (SLAMLAB_ONLY): a rename must not leave it
      // running no check at all.
      const script = await readFile(path.join(webDir, "..", "scripts", "screenshots.sh"), "utf8");
      const only = script.match(/SLAMLAB_ONLY="([^"]+)"/)?.[1];
      assert(only && picturesCheck.includes(only) && script.includes("SLAMLAB_SCREENSHOTS="), `scripts/screenshots.sh does not select this check (SLAMLAB_ONLY="${only}")`);
      const into = process.env.SLAMLAB_SCREENSHOTS;
      const shots = into ? [HERO, ...LESSON_SHOTS] : LESSON_SHOTS.filter((shot) => shot.id === "landmark-slam");
      const dir = into ? path.resolve(into) : outDir;
      await mkdir(dir, { recursive: true });
      const notes = [];
      for (const shot of shots) {
        await withPage(browser, baseUrl, `index.html?${shot.query}`, shot.name, async ({ page }) => {
          await waitRunning(page);
          const { pictures } = await takePictures(page, shot);
          for (const [size, bytes] of Object.entries(pictures)) {
            const file = size === "small" ? `${shot.name}-small.png` : `${shot.name}.png`;
            const { width, height } = pictureSize(shot, size);
            const image = decodePng(bytes);
            assert(image.width === width && image.height === height, `${file} is ${image.width} x ${image.height}, not ${width} x ${height}`);
            assertNotBlank(imageStats(image), file);
            const budget = size === "small" ? 60_000 : 300_000;
            assert(bytes.length <= budget, `${file} has ${bytes.length} bytes, more than ${budget}`);
            await writeFile(path.join(dir, file), bytes);
            notes.push(`${file} ${image.width} x ${image.height}, ${bytes.length} bytes`);
          }
        }, shot.viewport);
      }
      return `${notes.join("; ")} in ${dir}`;
    });

    await check("no console errors, uncaught exceptions or failed requests", async () => {
      const problems = pageLogs.flatMap((log) => log.problems.map((p) => `${log.label}: ${p}`));
      assert(problems.length === 0, problems.join("\n"));
    });
  } finally {
    await browser.close();
    server.close();
  }

  await writeFile(path.join(outDir, "metrics.json"), `${JSON.stringify(metrics, null, 2)}\n`);
  await writeFile(path.join(outDir, "result.json"), `${JSON.stringify({ results, metrics, pages: pageLogs }, null, 2)}\n`);
  console.log(
    `metrics: time to "running" ${metrics.status_running_ms ?? "?"} ms, to first drawn frame ${metrics.ttff_ms ?? "?"} ms; ` +
      `wasm ${metrics.wasm_bytes} bytes (${metrics.wasm_gzip_bytes} gzip -9); ` +
      `50 landmarks, EKF+UKF: frame CPU median ${metrics.lm50_frame_cpu_ms_median ?? "?"} ms, ` +
      `simulation ${metrics.lm50_sim_ms_median ?? "?"} ms, ${metrics.lm50_frames_per_second ?? "?"} frames/s`,
  );
  console.log(`screenshots, metrics.json and result.json: ${outDir}`);
  const failed = results.filter((r) => !r.ok).length;
  console.log(`${results.length - failed} passed, ${failed} failed`);
  process.exit(failed === 0 ? 0 : 1);
}

// A hung browser must not hang CI. SLAMLAB_LONG=1 adds the Cartographer lesson's whole
// Intel log (a quarter of an hour or more), so it allows 90 minutes.
const DEADLINE_MINUTES = process.env.SLAMLAB_LONG === "1" ? 90 : 10;
setTimeout(() => {
  console.log(`the browser tests did not finish within ${DEADLINE_MINUTES} minutes`);
  console.log(`${results.filter((r) => r.ok).length} passed, ${results.filter((r) => !r.ok).length + 1} failed`);
  process.exit(1);
}, DEADLINE_MINUTES * 60_000).unref();

main().catch((err) => {
  console.log(`the browser tests crashed: ${err?.stack ?? err}`);
  const failed = results.filter((r) => !r.ok).length + 1;
  console.log(`${results.length + 1 - failed} passed, ${failed} failed`);
  process.exit(1);
});
