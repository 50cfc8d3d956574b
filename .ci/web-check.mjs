// The page (`./run web`) in a real browser: Debian's Chromium, headless, driven by
// puppeteer-core, the page served from localhost (WebGPU needs a secure context). Checks:
//   - it loads and draws with no console error and no uncaught exception;
//   - the canvas shows a forest: sky above (blue over red), ground below (not sky), trees
//     between (dark foliage), not a blank image;
//   - two screenshots a second apart differ (the trees sway);
//   - a storm moves the crowns more than a calm over the same simulated time;
//   - switching the geometry level of detail off changes the triangle count shown;
//   - a bad scene file opened in the page gives the command line's named error in the
//     panel, and the page goes on drawing;
//   - the tree picker and the 1 000-tree scene grow without error.
// Screenshots go to OUT (CI keeps them). Prints the backend, the time from navigation to the
// first frame and the frames per second. Exit 1 on any failure.
// Usage: node web-check.mjs SITE_DIR OUT_DIR  (CHROMIUM: the browser, default /usr/bin/chromium)
import { createServer } from "node:http";
import { mkdirSync, readFileSync, writeFileSync } from "node:fs";
import { extname, join, normalize } from "node:path";
import puppeteer from "puppeteer-core";

const [site, out] = process.argv.slice(2);
mkdirSync(out, { recursive: true });
const types = { ".html": "text/html", ".js": "text/javascript", ".css": "text/css", ".wasm": "application/wasm" };
const server = createServer((req, res) => {
  let path = normalize(decodeURIComponent(new URL(req.url, "http://x").pathname)).replace(/^(\.\.[/\\])+/, "");
  if (path.endsWith("/")) path += "index.html";
  try {
    const body = readFileSync(join(site, path));
    res.setHeader("content-type", types[extname(path)] ?? "application/octet-stream");
    res.end(body);
  } catch {
    res.statusCode = 404;
    res.end();
  }
});
await new Promise((r) => server.listen(0, "127.0.0.1", r));
const url = `http://localhost:${server.address().port}/`;

// SwiftShader's Vulkan device under WebGPU, composited through ANGLE on Vulkan: without a
// GPU, the flags under which Chromium both runs WebGPU and shows its canvas in screenshots.
// WebGL2 runs on ANGLE's SwiftShader GL instead.
const launch = (args) => puppeteer.launch({
  executablePath: process.env.CHROMIUM ?? "/usr/bin/chromium",
  headless: true,
  protocolTimeout: 600_000,
  args: ["--no-sandbox", "--enable-unsafe-swiftshader", ...args],
});
const WEBGPU = ["--enable-unsafe-webgpu", "--enable-features=Vulkan", "--use-vulkan=swiftshader", "--use-angle=vulkan", "--ignore-gpu-blocklist"];
const WEBGL2 = ["--use-angle=swiftshader"];
let browser = await launch(WEBGPU);
const failures = [];
const check = (ok, what) => {
  console.log(`${ok ? "ok  " : "FAIL"} ${what}`);
  if (!ok) failures.push(what);
};
const consoleErrors = [];
const [W, H] = [720, 540];
async function open(b) {
  const p = await b.newPage();
  await p.setViewport({ width: W, height: H });
  p.on("console", (m) => {
    if (m.type() === "error") consoleErrors.push(m.text());
  });
  p.on("pageerror", (e) => consoleErrors.push(`uncaught: ${e.message}`));
  return p;
}
let page = await open(browser);

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const state = () => page.evaluate(() => ({
  frames: window.sylva?.frames ?? 0,
  busy: window.sylva?.busy ?? true,
  app: !!window.sylva?.app,
  first: window.sylva?.firstFrameMs,
  start: window.sylva?.startMs,
  fps: window.sylva?.fps ?? 0,
  error: document.getElementById("error").hidden ? "" : document.getElementById("error").textContent,
  status: document.getElementById("status").textContent,
  triangles: document.getElementById("fig-triangles").textContent,
  trees: document.getElementById("fig-trees").textContent,
}));
// Wait until `n` more frames are drawn after any busy work (and at least `ms`).
async function frames(n, ms = 0, timeout = 240_000) {
  const t0 = Date.now();
  let s = await state();
  while (s.busy || !s.app) {
    if (Date.now() - t0 > timeout) throw new Error(`still busy after ${timeout} ms: ${JSON.stringify(s)}`);
    await sleep(200);
    s = await state();
  }
  const start = s.frames;
  while (s.frames < start + n || Date.now() - t0 < ms) {
    if (Date.now() - t0 > timeout) throw new Error(`no frames after ${timeout} ms: ${JSON.stringify(s)}`);
    await sleep(100);
    s = await state();
  }
  return s;
}

// The canvas right of the panel, as RGBA rows (decoded by the browser itself).
const PANEL = 270;
async function shot(name) {
  const png = await page.screenshot({ encoding: "base64" });
  writeFileSync(join(out, `${name}.png`), Buffer.from(png, "base64"));
  return page.evaluate(async (b64, x0) => {
    const img = new Image();
    img.src = `data:image/png;base64,${b64}`;
    await img.decode();
    const c = new OffscreenCanvas(img.width - x0, img.height);
    const g = c.getContext("2d");
    g.drawImage(img, -x0, 0);
    return { w: c.width, h: c.height, rgba: Array.from(g.getImageData(0, 0, c.width, c.height).data) };
  }, png, PANEL);
}
function band(img, y0, y1) {
  let [r, g, b, n] = [0, 0, 0, 0];
  for (let y = Math.floor(y0 * img.h); y < Math.floor(y1 * img.h); y++) {
    for (let x = 0; x < img.w; x++) {
      const i = 4 * (y * img.w + x);
      r += img.rgba[i];
      g += img.rgba[i + 1];
      b += img.rgba[i + 2];
      n++;
    }
  }
  return [r / n, g / n, b / n];
}
const lum = (p) => 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
function foliage(img, y0, y1) {
  // Dark, green-over-blue pixels: leaves in light and shade (sky is blue over green).
  let [k, n] = [0, 0];
  for (let y = Math.floor(y0 * img.h); y < Math.floor(y1 * img.h); y++) {
    for (let x = 0; x < img.w; x++) {
      const i = 4 * (y * img.w + x);
      const p = [img.rgba[i], img.rgba[i + 1], img.rgba[i + 2]];
      if (p[1] > p[2] && lum(p) < 110) k++;
      n++;
    }
  }
  return k / n;
}
function difference(a, b) {
  let [sum, changed] = [0, 0];
  for (let i = 0; i < a.rgba.length; i += 4) {
    const d = Math.abs(a.rgba[i] - b.rgba[i]) + Math.abs(a.rgba[i + 1] - b.rgba[i + 1]) + Math.abs(a.rgba[i + 2] - b.rgba[i + 2]);
    sum += d;
    if (d > 24) changed++;
  }
  const n = a.rgba.length / 4;
  return { mean: sum / (3 * n), changed: changed / n };
}
async function choose(id, value) {
  await page.select(`#${id}`, value);
  return frames(3);
}
// Motion over the same simulated time: the frames step at most 0.2 s each, so k frames at
// a few frames a second are 0.2 k s of simulation whatever the browser's speed.
async function motion(name) {
  await frames(2);
  const a = await shot(`${name}-a`);
  await frames(3);
  const b = await shot(`${name}-b`);
  return difference(a, b);
}

// The canvas shows a forest: not blank, sky above, ground below, foliage between.
async function looksLikeAForest(name) {
  const forest = await shot(name);
  const sky = band(forest, 0, 0.12);
  const ground = band(forest, 0.88, 1);
  const lumAll = band(forest, 0, 1);
  let spread = 0;
  for (let i = 0; i < forest.rgba.length; i += 4) {
    spread += (lum([forest.rgba[i], forest.rgba[i + 1], forest.rgba[i + 2]]) - lum(lumAll)) ** 2;
  }
  spread = Math.sqrt(spread / (forest.rgba.length / 4));
  const sx = (p) => p.map((v) => v.toFixed(0)).join(",");
  check(spread > 15, `the canvas is not blank (luminance spread ${spread.toFixed(1)} > 15)`);
  check(sky[2] > sky[0] + 20 && lum(sky) > lum(ground), `sky above: top band rgb ${sx(sky)} is blue over red, brighter than the ground`);
  check(ground[2] < ground[1] && ground[2] < sky[2] - 40, `ground below: bottom band rgb ${sx(ground)} is not sky`);
  const leaves = foliage(forest, 0.15, 0.75);
  check(leaves > 0.05, `trees between: ${(100 * leaves).toFixed(1)} % of the middle band is foliage (> 5 %)`);

  return forest;
}

try {
  const t0 = Date.now();
  await page.goto(url);
  let s = await frames(2, 0, 180_000);
  const backend = await page.$eval("#backend", (e) => e.textContent);
  console.log(`page at ${url}: ${backend}; first frame ${s.first?.toFixed(0)} ms after navigation, ${s.start?.toFixed(0)} ms of it starting the engine (${Date.now() - t0} ms to two frames here)`);
  check(!s.error, `the page starts without an error shown (${s.error})`);

  const forest = await looksLikeAForest("forest");

  s = await frames(2, 1000);
  const later = await shot("forest-1s-later");
  const moved = difference(forest, later);
  check(moved.changed > 0.002, `two screenshots 1 s apart differ: ${(100 * moved.changed).toFixed(2)} % of pixels changed, mean ${moved.mean.toFixed(2)}`);
  console.log(`scene small: ${s.fps.toFixed(2)} frames per second at ${W}×${H}, ${s.triangles} triangles`);

  await choose("wind", "calm");
  const calm = await motion("calm");
  await choose("wind", "storm");
  const storm = await motion("storm");
  check(storm.mean > 1.3 * calm.mean, `a storm moves the crowns more than a calm: mean change ${storm.mean.toFixed(2)} against ${calm.mean.toFixed(2)}`);
  await choose("wind", "strong");

  s = await frames(3, 700);
  const withLod = s.triangles;
  await page.click("#lod-geometry");
  s = await frames(3, 700);
  const fullDetail = s.triangles;
  check(withLod !== fullDetail, `the geometry LOD switch changes the triangles shown: ${withLod} with it, ${fullDetail} without`);
  await page.click("#lod-geometry");
  await frames(2);

  const badScene = join(out, "bad-scene.toml");
  writeFileSync(badScene, 'name = "bad"\ntrees = 0\nspecies = [{ name = "sugar_maple" }]\n');
  const input = await page.$("#open");
  await input.uploadFile(badScene);
  s = await frames(2, 500);
  check(s.error.includes("bad-scene.toml") && s.error.includes("trees"), `a bad scene file gives the named error in the panel: "${s.error}"`);
  check(s.frames > 0 && s.app, "the page goes on drawing after the bad file");
  await shot("bad-file");

  await page.select("#species", "douglas_fir");
  await page.click("#show-species");
  s = await frames(3, 500);
  check(!s.error && s.status.includes("douglas fir"), `the tree picker shows a Douglas fir close up ("${s.status}")`);
  await shot("douglas-fir");

  const tA = Date.now();
  s = await choose("scene", "A");
  check(!s.error && s.trees.endsWith("1,000"), `the 1 000-tree scene grows and draws: trees ${s.trees}, in ${((Date.now() - tA) / 1000).toFixed(1)} s`);
  s = await frames(2, 1000);
  await shot("scene-A");
  console.log(`scene A: ${s.fps.toFixed(2)} frames per second, ${s.triangles} triangles, trees drawn ${s.trees}`);

  await browser.close();
  browser = await launch(WEBGL2);
  page = await open(browser);
  await page.goto(`${url}?webgl2`);
  s = await frames(3, 0, 180_000);
  const gl = await page.$eval("#backend", (e) => e.textContent);
  check(gl.startsWith("WebGL2") && !s.error, `?webgl2 runs on WebGL2: ${gl}`);
  await looksLikeAForest("webgl2");
  s = await frames(2, 1000);
  console.log(`WebGL2, scene small, default levels: ${s.fps.toFixed(2)} frames per second, ${s.triangles} triangles`);

  check(consoleErrors.length === 0, `no console errors${consoleErrors.length ? `: ${consoleErrors.join(" | ")}` : ""}`);
} catch (e) {
  failures.push(String(e));
  console.log(`FAIL ${e}`);
  if (consoleErrors.length) console.log(`console errors: ${consoleErrors.join(" | ")}`);
} finally {
  await browser.close();
  server.close();
}
process.exit(failures.length ? 1 : 0);
