// The app's speed in headless Chromium, both worker builds, against the native CLI, interleaved
// in one run on the same frames (the bundled KITTI frames www/demo/MyKITTI, frames 0-5):
// - SIFT (detect+compute) per frame, one frame at a time: the relaxed-SIMD worker (the default
//   where relaxed SIMD validates), the SIMD128 worker (`?wasm=portable`), the CLI on all cores
//   and on one core;
// - the odometry view on the demo frames (0-99), each build in turn, `--vo-rounds` times.
//   BASE_URL=http://127.0.0.1:8080/ node tests/benchmarks/bench.mjs [--vo-rounds 2] [--vo-dataset DIR --vo-frames N]
// (dist/ served, CLI built). --vo-dataset runs the odometry on a MyKITTI folder instead of
// the demo; --vo-frames N runs N frames (frames 0 … N−1: the page's FRAME_ID is N−1, as
// view_trajectory counts); the trajectory error is checked against the CLI's
// view_trajectory on the same frames.
import { execFileSync, spawnSync } from 'node:child_process';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { launchChromium } from '../e2e/harness.mjs';

const ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
const BASE = process.env.BASE_URL || 'http://127.0.0.1:8080/';
// tests/e2e/run.sh passes the CLI it built (CARGO_TARGET_DIR honoured).
const CLI = process.env.SIFTLAB_CLI || path.join(ROOT, 'target/release/siftlab');
const DEMO = path.join(ROOT, 'www/demo/MyKITTI');
const frame = (i) => path.join(DEMO, 'gray/00/image_0', String(i).padStart(6, '0') + '.png');
const median = (v) => [...v].sort((a, b) => a - b)[Math.floor(v.length / 2)];
const arg = process.argv.indexOf('--vo-rounds');
const voRounds = arg > 0 ? Number(process.argv[arg + 1]) : 2;
const opt = (name) => { const i = process.argv.indexOf(name); return i > 0 ? process.argv[i + 1] : undefined; };
const voDataset = opt('--vo-dataset') && path.resolve(opt('--vo-dataset'));
const voFrames = opt('--vo-frames');

const browser = await launchChromium();
const builds = { relaxed: '', portable: '&wasm=portable' };
// src=folder: no demo autoload, so exactly one SIFT runs at a time.
const pages = {};
for (const [name, q] of Object.entries(builds)) {
  pages[name] = await browser.newPage();
  await pages[name].goto(`${BASE}?src=folder${q}`);
}
const sift = { relaxed: [], portable: [] };
const native = [];
const nativeOneThread = [];
for (let i = 0; i < 6; i++) {
  for (const [name, page] of Object.entries(pages)) {
    await page.setInputFiles('[data-testid="frame-prev"]', frame(i));
    await page.waitForFunction((n) => new RegExp(`${n}\\.png.*SIFT \\d+ ms`).test(document.querySelector('.slots').textContent),
      String(i).padStart(6, '0'), { timeout: 300000 });
    sift[name].push(Number((await page.textContent('.slots')).match(/SIFT (\d+) ms/)[1]));
  }
  const ms = (cmd, args) => Number(execFileSync(cmd, args, { encoding: 'utf8' }).match(/in ([\d.]+) ms/)[1]);
  native.push(ms(CLI, ['--opencv-lanes', '8', 'sift', frame(i)]));
  // One core, like the single worker (Rust's available_parallelism follows the affinity mask).
  nativeOneThread.push(ms('taskset', ['-c', '0', CLI, '--opencv-lanes', '8', 'sift', frame(i)]));
}
for (const page of Object.values(pages)) await page.close();

// The odometry view on the demo frames: its own "over N frames · S s" figure.
const vo = { relaxed: [], portable: [] };
for (let r = 0; r < voRounds; r++) {
  for (const [name, q] of Object.entries(builds)) {
    const page = await browser.newPage();
    await page.goto(`${BASE}?${q.slice(1)}`);
    await page.waitForSelector('[data-testid="keypoint-count-cur"]', { timeout: 300000 });
    await page.waitForSelector('[data-testid="busy"]', { state: 'detached', timeout: 300000 });
    if (voDataset) {
      await page.setInputFiles('[data-testid="folder"]', voDataset);
      await page.waitForSelector('[data-testid="busy"]', { state: 'detached', timeout: 300000 });
    }
    if (voFrames) await page.fill('[data-testid="vo-frame-id"]', String(Number(voFrames) - 1));
    await page.click('[data-testid="vo-run"]');
    await page.waitForSelector('[data-testid="vo-ate"]', { timeout: 1800000 });
    const m = (await page.textContent('.trajectory')).match(/over (\d+) frames · ([\d.]+) s/);
    vo[name].push({ frames: Number(m[1]), s: Number(m[2]), ate: (await page.textContent('[data-testid="vo-ate"]')).trim() });
    await page.close();
  }
}
await browser.close();
// The CLI on the same frames (view_trajectory FRAME_ID runs frames 0 … FRAME_ID): the
// page's trajectory error must be the same text.
const frames = vo.relaxed[0]?.frames;
const cliRun = spawnSync(CLI, ['-d', voDataset || DEMO, 'view_trajectory', String(frames - 1), '--output', '/dev/null'], { encoding: 'utf8' });
const cliOut = cliRun.stdout + cliRun.stderr; // the error is reported with the progress, on stderr
const cliAte = `${cliOut.match(/trajectory error \(ATE RMSE, \d+ frames\): ([\d.]+) m/)[1]} m`;
const r = {
  chromiumSiftMs: sift, nativeMs: native, nativeOneCoreMs: nativeOneThread,
  median: { relaxed: median(sift.relaxed), portable: median(sift.portable), native: median(native), nativeOneCore: median(nativeOneThread) },
  relaxedSpeedup: +(median(sift.portable) / median(sift.relaxed)).toFixed(2),
  relaxedVsNativeOneCore: +(median(sift.relaxed) / median(nativeOneThread)).toFixed(2),
  vo,
  cliAte,
  ateEqual: Object.values(vo).every((runs) => runs.every((x) => x.ate === cliAte)),
  voFramesPerS: Object.fromEntries(Object.entries(vo).map(([k, v]) => [k, v.map((x) => +(x.frames / x.s).toFixed(2))])),
};
console.log(JSON.stringify(r, null, 2));
