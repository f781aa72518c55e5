// The odometry's speed in Chromium against the worker count, and the comparison view's wall
// time against an older build, in one run (Playwright; the builds alternate round by round):
//   node tests/benchmarks/bench_workers.mjs [--before DIST] [--rounds R] [--frames F]
// - the odometry view (LK) on frames 0 … F−1 with workers=1, 2 and 3: frames/s from the
//   page's own "over N frames · S s"; and with the default workers, in both builds;
// - the comparison view ("Run all four") on the same frames with the default workers: wall
//   time from the click to "4 runs done", this build (dist/) and, with --before, an older
//   build's dist/ served beside it.
// Prints JSON. Defaults: 1 round, 100 frames (the demo's 0-99).
import path from 'node:path';
import { serve, ROOT, launchChromium } from '../e2e/harness.mjs';

const opt = (name, d) => { const i = process.argv.indexOf(name); return i > 0 ? process.argv[i + 1] : d; };
const rounds = Number(opt('--rounds', 1));
const frames = Number(opt('--frames', 100));
const before = opt('--before');
const tid = (id) => `[data-testid="${id}"]`;
const median = (v) => [...v].sort((a, b) => a - b)[Math.floor(v.length / 2)];

const servers = { after: await serve(path.join(ROOT, 'dist'), { hooks: false }) };
if (before) servers.before = await serve(path.resolve(before), { hooks: false });
const browser = await launchChromium();

async function open(base, query = '') {
  const page = await browser.newPage({ viewport: { width: 1400, height: 900 } });
  await page.goto(`${base}${query}`);
  await page.waitForSelector(tid('keypoint-count-cur'), { timeout: 300000 });
  await page.waitForSelector(tid('busy'), { state: 'detached', timeout: 300000 });
  await page.fill(tid('vo-frame-id'), String(frames - 1));
  return page;
}

const fps = { 1: [], 2: [], 3: [] };
const compare = Object.fromEntries(Object.keys(servers).map((k) => [k, []]));
const odometry = Object.fromEntries(Object.keys(servers).map((k) => [k, []]));
let workersText;
// The odometry view's LK run: frames/s from its own "over N frames · S s".
async function odometryFps(base, query) {
  const page = await open(base, query);
  await page.click(tid('vo-run'));
  await page.waitForSelector(tid('vo-ate'), { timeout: 1800000 });
  const m = (await page.textContent('.trajectory')).match(/over (\d+) frames · ([\d.]+) s/);
  if (await page.$(tid('vo-workers'))) workersText = await page.textContent(tid('vo-workers'));
  await page.close();
  return +(Number(m[1]) / Number(m[2])).toFixed(2);
}
for (let r = 0; r < rounds; r++) {
  for (const n of Object.keys(fps)) fps[n].push(await odometryFps(servers.after.base, `?workers=${n}`));
  for (const [name, server] of Object.entries(servers)) odometry[name].push(await odometryFps(server.base, ''));
  for (const [name, server] of Object.entries(servers)) {
    const page = await open(server.base);
    const t0 = Date.now();
    await page.click(tid('vo-compare-run'));
    await page.waitForFunction((sel) => document.querySelector(sel)?.textContent === '4 runs done', tid('vo-compare-status'), { timeout: 3600000 });
    compare[name].push((Date.now() - t0) / 1000);
    await page.close();
  }
}
await browser.close();
for (const s of Object.values(servers)) await s.close();
const out = {
  frames,
  rounds,
  cores: (await import('node:os')).cpus().length,
  odometryFramesPerS: fps,
  odometryDefaultFramesPerS: odometry,
  workersText,
  compareWallS: compare,
  medianCompareWallS: Object.fromEntries(Object.entries(compare).map(([k, v]) => [k, median(v)])),
};
if (before) out.compareRatio = +(median(compare.after) / median(compare.before)).toFixed(3);
console.log(JSON.stringify(out, null, 2));
