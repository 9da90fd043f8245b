#!/usr/bin/env node
// Drives the live viewer page in headless Chromium (Debian's /usr/bin/chromium,
// through playwright-core) for tests/viewer_browser.rs, which does the checking.
//
// Protocol: one JSON request per line on stdin, one JSON answer per line on stdout
// (`{"ok":true,…}` or `{"ok":false,"error":"…"}`); anything else goes to stderr.
//
//   {"cmd":"open","url":"http://127.0.0.1:8080/","page":"a"}   opens a page (a name of your choosing)
//   {"cmd":"wait","page":"a","until":"snapshots","min":5,"timeout_ms":20000}
//                                                               waits for viewerStats[until] >= min
//                                                               (without min: until it is set;
//                                                               "scene.posesSeq": a nested value)
//   {"cmd":"stats","page":"a"}                                  window.viewerStats, #view's rect (CSS px), the page's text
//   {"cmd":"screenshot","page":"a","path":"/tmp/x.png"}        a PNG of the viewport; answers #view's rect
//   {"cmd":"drag","page":"a","from":[x,y],"to":[x,y],"steps":30,"ms":1500,"hold_ms":500}
//                                                               a mouse drag in CSS px of the viewport
//   {"cmd":"stroke","page":"a","points":[[x,y],…],"ms":1500,"hold_ms":300,"shift":false}
//                                                               a mouse stroke through the points (CSS px; one
//                                                               point: a click), Shift held if asked
//   {"cmd":"fill","page":"a","selector":"#edit-from","value":"2.5"}
//   {"cmd":"click","page":"a","selector":"#btn-pause"}
//   {"cmd":"fps","page":"a","seconds":5}                        viewerStats.fps sampled once a second
//   {"cmd":"probe","page":"a","points":[[x,y],…]}              right after the page draws a frame: the
//                                                               canvas's RGB at each world point (m), at
//                                                               each moving thing's pose and at each
//                                                               agent, with the poses and subgroups drawn
//   {"cmd":"close"}
//
// Standalone: `node drive.js --shot URL OUT.png [seconds]` saves a screenshot after
// `seconds` (default 3) of drawing (how docs/viewer.png is made); `node drive.js
// --fps URL [seconds]` prints the page's frame rate over `seconds` (default 5).

"use strict";
const readline = require("readline");
const { chromium } = require("playwright-core");

const CHROMIUM = process.env.CHROMIUM || "/usr/bin/chromium";
const ARGS = [
  "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
  "--disable-background-networking", "--disable-component-update", "--disable-sync",
];
const VIEWPORT = { width: 1280, height: 720 };

let browser = null;
const pages = new Map();

async function launch() {
  if (!browser) {
    // playwright-core gives the browser an empty, temporary --user-data-dir.
    browser = await chromium.launch({ executablePath: CHROMIUM, headless: true, args: ARGS });
  }
  return browser;
}

function pageOf(req) {
  const p = pages.get(req.page || "a");
  if (!p) throw new Error(`no page ${JSON.stringify(req.page || "a")}: open it first`);
  return p;
}

async function viewRect(page) {
  return page.evaluate(() => {
    const r = document.getElementById("view").getBoundingClientRect();
    return { x: r.left, y: r.top, width: r.width, height: r.height, dpr: window.devicePixelRatio };
  });
}

async function run(req) {
  switch (req.cmd) {
    case "open": {
      const b = await launch();
      const context = await b.newContext({ viewport: VIEWPORT, deviceScaleFactor: 1 });
      const page = await context.newPage();
      page.on("console", (m) => console.error(`[${req.page || "a"} console] ${m.text()}`));
      page.on("pageerror", (e) => console.error(`[${req.page || "a"} error] ${e.message}`));
      await page.goto(req.url, { waitUntil: "load", timeout: 20000 });
      pages.set(req.page || "a", page);
      return {};
    }
    case "wait": {
      const page = pageOf(req);
      const key = req.until || "snapshots";
      // With `min`, until the value is at least that; without, until it is set.
      // A dotted key ("scene.posesSeq") reads a nested value.
      await page.waitForFunction(([k, min]) => {
        const v = k.split(".").reduce((o, part) => (o == null ? o : o[part]), window.viewerStats);
        return min === null ? Boolean(v) : v >= min;
      },
        [key, req.min ?? null], { timeout: req.timeout_ms ?? 20000, polling: 100 });
      return { stats: await page.evaluate(() => window.viewerStats) };
    }
    case "stats": {
      const page = pageOf(req);
      return {
        stats: await page.evaluate(() => window.viewerStats),
        view: await viewRect(page),
        text: await page.evaluate(() => document.body.innerText),
      };
    }
    case "screenshot": {
      const page = pageOf(req);
      await page.screenshot({ path: req.path, type: "png" });
      return { view: await viewRect(page), stats: await page.evaluate(() => window.viewerStats) };
    }
    case "drag": {
      const page = pageOf(req);
      const steps = req.steps ?? 30, ms = req.ms ?? 1500;
      const [x0, y0] = req.from, [x1, y1] = req.to;
      await page.mouse.move(x0, y0);
      await page.mouse.down();
      await page.waitForTimeout(req.hold_ms ?? 300);
      for (let i = 1; i <= steps; i++) {
        const f = i / steps;
        await page.mouse.move(x0 + (x1 - x0) * f, y0 + (y1 - y0) * f);
        await page.waitForTimeout(ms / steps);
      }
      await page.waitForTimeout(req.hold_ms ?? 300);
      await page.mouse.up();
      return {};
    }
    case "stroke": {
      const page = pageOf(req);
      const pts = req.points || [];
      if (pts.length === 0) throw new Error("a stroke needs points");
      if (req.shift) await page.keyboard.down("Shift");
      await page.mouse.move(pts[0][0], pts[0][1]);
      await page.mouse.down();
      const step = pts.length > 1 ? (req.ms ?? 1500) / (pts.length - 1) : 0;
      if (pts.length > 1) await page.waitForTimeout(req.hold_ms ?? 300);
      for (const [x, y] of pts.slice(1)) {
        await page.mouse.move(x, y);
        await page.waitForTimeout(step);
      }
      if (pts.length > 1) await page.waitForTimeout(req.hold_ms ?? 300);
      await page.mouse.up();
      if (req.shift) await page.keyboard.up("Shift");
      return {};
    }
    case "fill": {
      await pageOf(req).fill(req.selector, String(req.value), { timeout: 5000 });
      return {};
    }
    case "click": {
      await pageOf(req).click(req.selector, { timeout: 5000 });
      return {};
    }
    case "fps": {
      const page = pageOf(req);
      const samples = [];
      const f0 = await page.evaluate(() => window.viewerStats.framesDrawn);
      const t0 = Date.now();
      for (let i = 0; i < (req.seconds ?? 5); i++) {
        await page.waitForTimeout(1000);
        samples.push(await page.evaluate(() => window.viewerStats.fps));
      }
      const f1 = await page.evaluate(() => window.viewerStats.framesDrawn);
      return {
        samples,
        mean_fps: ((f1 - f0) * 1000) / (Date.now() - t0),
        stats: await page.evaluate(() => window.viewerStats),
      };
    }
    case "probe": {
      // In the animation frame's callbacks the page's own `frame` (registered at
      // the end of the frame before) runs first, so what is read here is what it
      // has just drawn, before any message can change its state.
      return pageOf(req).evaluate((points) => new Promise((resolve) => {
        requestAnimationFrame(() => {
          /* global view, world, ctx, positions, scenePoses, agentSubgroups */
          const at = (x, y) => {
            const X = Math.round(((x - world.minX) * view.scale + view.ox) * view.dpr);
            const Y = Math.round(((y - world.minY) * view.scale + view.oy) * view.dpr);
            return Array.from(ctx.getImageData(X, Y, 1, 1).data.slice(0, 3));
          };
          const poses = scenePoses ? scenePoses.poses : [];
          const agents = [];
          for (let i = 0; positions && i < positions.length >> 1; i++) {
            agents.push({ x: positions[2 * i], y: positions[2 * i + 1], rgb: at(positions[2 * i], positions[2 * i + 1]) });
          }
          resolve({
            stats: window.viewerStats,
            points: points.map(([x, y]) => at(x, y)),
            poses_t_s: scenePoses ? scenePoses.t_s : null,
            poses,
            moving: poses.map(([x, y]) => at(x, y)),
            agents,
            subgroups: agentSubgroups,
          });
        });
      }), req.points || []);
    }
    case "close": {
      if (browser) await browser.close();
      browser = null;
      return { exit: true };
    }
    default:
      throw new Error(`unknown cmd ${JSON.stringify(req.cmd)}`);
  }
}

async function serve() {
  const rl = readline.createInterface({ input: process.stdin });
  for await (const line of rl) {
    if (!line.trim()) continue;
    let answer;
    try {
      answer = Object.assign({ ok: true }, await run(JSON.parse(line)));
    } catch (e) {
      answer = { ok: false, error: String(e && e.message ? e.message : e) };
    }
    process.stdout.write(JSON.stringify(answer) + "\n");
    if (answer.exit) process.exit(0);
  }
  if (browser) await browser.close();
}

async function shot(url, out, seconds) {
  await run({ cmd: "open", url });
  await run({ cmd: "wait", until: "snapshots", min: 1 });
  await new Promise((r) => setTimeout(r, seconds * 1000));
  const s = await run({ cmd: "screenshot", path: out });
  console.error(`drive: ${out}: ${JSON.stringify(s.stats)}`);
  await run({ cmd: "close" });
}

async function fps(url, seconds) {
  await run({ cmd: "open", url });
  await run({ cmd: "wait", until: "agentsDrawn", min: 1 });
  const m = await run({ cmd: "fps", seconds });
  console.log(JSON.stringify(m));
  await run({ cmd: "close" });
}

if (process.argv[2] === "--fps") {
  fps(process.argv[3], Number(process.argv[4] || 5)).catch((e) => {
    console.error(`drive: ${e.message}`);
    process.exit(1);
  });
} else if (process.argv[2] === "--shot") {
  shot(process.argv[3], process.argv[4], Number(process.argv[5] || 3)).catch((e) => {
    console.error(`drive: ${e.message}`);
    process.exit(1);
  });
} else {
  serve();
}
