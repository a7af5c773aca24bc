// Where a lesson's page spends its main thread's time: opens a URL of the built site
// (web/dist) in headless Chromium, presses Space to run it, records a CPU profile over
// a few seconds (the DevTools protocol's sampling profiler) and prints the share of
// samples per function, the idle share first. The wasm keeps its function names, so
// Rust functions appear by path.
//
//   node web/tests/profile.mjs "lesson=kidnap&estimator=amcl,acmcl&particles=5000&init=tracking&seed=5" [seconds]
//
// Environment: SLAMLAB_CHROMIUM (default /usr/bin/chromium). Build the site first
// (web/build.sh). Not part of web/test.sh: a tool for looking, not a check.
import { chromium } from "playwright-core";
import { createServer } from "node:http";
import { readFile } from "node:fs/promises";
import path from "node:path";
import { fileURLToPath } from "node:url";

const dist = path.join(path.dirname(fileURLToPath(import.meta.url)), "..", "dist");
const query = process.argv[2] || "lesson=kidnap&particles=5000&init=tracking&seed=5";
const seconds = Number(process.argv[3] || 6);
const TYPES = { ".html": "text/html", ".js": "text/javascript", ".wasm": "application/wasm" };

const server = createServer(async (req, res) => {
  const file = path.join(dist, decodeURIComponent(new URL(req.url, "http://localhost").pathname));
  if (!file.startsWith(dist)) {
    res.writeHead(403).end();
    return;
  }
  try {
    const body = await readFile(file.endsWith(path.sep) ? path.join(file, "index.html") : file);
    res.writeHead(200, { "content-type": TYPES[path.extname(file)] || "application/octet-stream" }).end(body);
  } catch {
    res.writeHead(404).end();
  }
});
await new Promise((resolve) => server.listen(0, "127.0.0.1", resolve));
const browser = await chromium.launch({
  executablePath: process.env.SLAMLAB_CHROMIUM || "/usr/bin/chromium",
  headless: true,
  args: ["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader"],
});
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 800 } });
  await page.goto(`http://127.0.0.1:${server.address().port}/index.html?${query}`);
  await page.waitForFunction(() => document.getElementById("status")?.textContent === "running", null, {
    timeout: 60_000,
  });
  await page.waitForTimeout(2000);
  await page.mouse.click(640, 20); // keyboard focus, away from any map
  const cdp = await page.context().newCDPSession(page);
  await cdp.send("Profiler.enable");
  await cdp.send("Profiler.setSamplingInterval", { interval: 200 });
  await page.keyboard.press("Space");
  await cdp.send("Profiler.start");
  await page.waitForTimeout(seconds * 1000);
  const { profile } = await cdp.send("Profiler.stop");
  const nodes = new Map(profile.nodes.map((n) => [n.id, n]));
  const share = new Map();
  for (const id of profile.samples) {
    const frame = nodes.get(id).callFrame;
    const name = frame.functionName || `(${frame.url.split("/").pop() || "anonymous"})`;
    share.set(name, (share.get(name) || 0) + 1);
  }
  const total = profile.samples.length;
  console.log(`${query}: ${total} samples over ${seconds} s`);
  for (const [name, n] of [...share].sort((a, b) => b[1] - a[1]).slice(0, 30)) {
    console.log(`${((100 * n) / total).toFixed(1).padStart(5)} %  ${name.slice(0, 120)}`);
  }
} finally {
  await browser.close();
  server.close();
}
