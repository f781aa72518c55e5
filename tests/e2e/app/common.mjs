// Shared by the app's end-to-end files (tests/e2e/app/*.test.mjs): the engine and its
// inputs, the native CLI as the reference, the page under test and the helpers every view's
// file uses. Each file calls appSuite() once: node --test runs each file in its own process,
// so each opens its own browser and server (tests/e2e/harness.mjs), and every case ends by
// checking that all requests stayed on our origin (CSP violations are recorded as errors
// too) and that nothing was logged as an error by the page or thrown by its workers.
import assert from 'node:assert/strict';
import { execFileSync, spawnSync } from 'node:child_process';
import crypto from 'node:crypto';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { suite, ROOT } from '../harness.mjs';

export const ENGINE = process.env.E2E_ENGINE || 'chromium';
// The odometry cases' FRAME_ID: the whole demo in Chromium (0–150, the manual's
// view_trajectory 150, through the first turn); the slower engines get short inputs, the
// same cases: 29 (thirty frames) in Firefox, 9 (ten) in WebKit (~2 s a frame, no relaxed
// SIMD). What an engine can change is each frame's numbers (its wasm, its SIMD); the turn
// and the drift over a long run are the core's, the same code in every engine.
export const VO_LAST = Number(process.env.E2E_VO_FRAME_ID || ({ webkit: 9, firefox: 29 }[ENGINE] ?? 150));
// The frame whose counts and picture the odometry case checks: in the turn (frame 110)
// when the run reaches it.
export const VO_SHOWN = Math.min(110, VO_LAST);
// The comparison view's FRAME_ID: four runs at once, so at most 29 in every engine. What it
// adds to the single runs above is that the four trackers run side by side and their rows,
// note and plot are the CLI's; each row's figures are the core's metrics, which the LK
// case checks on 0-150 (KITTI included) in Chromium, and its KITTI cells' text is
// `metric_cells`'s (unit-tested with and without KITTI figures). The frame-96 dt 200 RANSAC
// sample is core/tests/essential_matrix.rs's, in Chromium too.
export const COMPARE_LAST = Number(process.env.E2E_COMPARE_FRAME_ID || Math.min(VO_LAST, 29));
// Whether the engine validates relaxed SIMD (measured: Chromium 156 and Firefox 153 do,
// WebKitGTK 2.50 does not), i.e. which worker build www/worker.js must pick.
export const RELAXED = { chromium: true, firefox: true, webkit: false }[ENGINE];
// tests/e2e/run.sh passes the CLI it built (CARGO_TARGET_DIR honoured).
export const CLI = process.env.SIFTLAB_CLI || path.join(ROOT, 'target/release/siftlab');
export const DATASET = 'www/demo/MyKITTI';
export const FRAME = (id) => path.join(ROOT, DATASET, 'gray/00/image_0', String(id).padStart(6, '0') + '.png');
// Screenshots and measured figures: tests/e2e/screenshots/<engine>/ (gitignored).
export const SHOTS = path.join(path.dirname(fileURLToPath(import.meta.url)), '..', 'screenshots', ENGINE);
fs.mkdirSync(SHOTS, { recursive: true });
export const shot = (name) => path.join(SHOTS, name);
export const metrics = { engine: ENGINE };

// OpenCV dispatches SIFT to AVX-512 kernels (16 lanes) when the CPU has F/CD/BW/DQ/VL, else
// AVX2 (8); the CLI reproduces the host's build by default, so the app is told the same.
function hostLanes() {
  if (process.arch !== 'x64') return 8;
  const flags = (fs.readFileSync('/proc/cpuinfo', 'utf8').match(/^flags\s*:(.*)$/m) || [, ''])[1].split(/\s+/);
  return ['avx512f', 'avx512cd', 'avx512bw', 'avx512dq', 'avx512vl'].every((f) => flags.includes(f)) ? 16 : 8;
}
export const LANES = hostLanes();

export function cli(args) {
  return execFileSync(CLI, ['-d', DATASET, ...args], { cwd: ROOT, encoding: 'utf8', stdio: ['ignore', 'pipe', 'pipe'] });
}
export function cliRet(args) {
  const out = cli(['get_info', ...args]);
  const line = out.split('\n').find((l) => l.startsWith('ret value: '));
  assert.ok(line, out);
  return line.slice('ret value: '.length);
}
// The app's default width (8 lanes, AVX2), whatever the host: what the lab manual's
// examples and a plain link are computed with.
export function cliRet8(args) {
  const out = execFileSync(CLI, ['--opencv-lanes', '8', '-d', DATASET, 'get_info', ...args], { cwd: ROOT, encoding: 'utf8', stdio: ['ignore', 'pipe', 'pipe'] });
  return out.split('\n').find((l) => l.startsWith('ret value: ')).slice('ret value: '.length);
}
const siftCache = new Map();
export function cliSift(id, lanes = LANES) {
  const key = `${id}/${lanes}`;
  if (!siftCache.has(key)) {
    const json = execFileSync(CLI, ['--opencv-lanes', String(lanes), 'sift', FRAME(id), '--json'], { cwd: ROOT, encoding: 'utf8', maxBuffer: 1 << 28 });
    siftCache.set(key, JSON.parse(json));
  }
  return siftCache.get(key);
}


export let BASE;
export let page;

// metrics.json gathers the figures of every file of one engine's run: each file adds its
// own (tests/e2e/run.sh removes the engine's file before the first).
function saveMetrics() {
  const file = path.join(SHOTS, 'metrics.json');
  let old = {};
  try { old = JSON.parse(fs.readFileSync(file, 'utf8')); } catch { /* first file of the run */ }
  if (old.engine !== ENGINE) old = {};
  fs.writeFileSync(file, JSON.stringify({ ...old, ...metrics }, null, 2));
}

/** The browser, the server of dist/ and a fresh page per case, for one file's cases. */
export function appSuite({ onePage = false } = {}) {
  suite(ENGINE, {
    onePage,
    onStart: ({ base, browser }) => {
      assert.ok(fs.existsSync(CLI), `${CLI} missing: cargo build --release --bin siftlab`);
      BASE = base;
      metrics.browserVersion = browser.version;
    },
    onPage: (p) => { page = p; },
    onEnd: saveMetrics,
  });
}

export const tid = (id) => `[data-testid="${id}"]`;
export async function idle(p = page) {
  await p.waitForSelector(tid('keypoint-count-cur'), { timeout: 180000 });
  await p.waitForSelector(tid('busy'), { state: 'detached', timeout: 180000 });
}
export async function settings(algo, t, feature, p = page) {
  await p.selectOption(tid('algo'), algo);
  await p.fill(tid('threshold'), t);
  await p.fill(tid('feature'), String(feature));
}
export async function tuple(p = page) {
  return (await p.textContent(tid('result-tuple'))).trim();
}
/** Waits until the tuple on screen is `want` (the update is synchronous, the paint not). */
export async function tupleIs(want, what) {
  await page.waitForFunction(([sel, w]) => document.querySelector(sel)?.textContent.trim() === w, [tid('result-tuple'), want], { timeout: 5000 })
    .catch(() => {});
  assert.equal(await tuple(), want, what);
}
export const ENGINE_LABEL = RELAXED ? 'relaxed SIMD' : 'SIMD128';

function crc32(buf) {
  let c = ~0;
  for (const b of buf) {
    c ^= b;
    for (let k = 0; k < 8; k++) c = (c >>> 1) ^ (0xedb88320 & -(c & 1));
  }
  return ~c >>> 0;
}
function chunk(type, data) {
  const t = Buffer.from(type);
  const len = Buffer.alloc(4); len.writeUInt32BE(data.length);
  const crc = Buffer.alloc(4); crc.writeUInt32BE(crc32(Buffer.concat([t, data])));
  return Buffer.concat([len, t, data, crc]);
}
// A tiny file that declares a w×h 8-bit gray PNG (its pixel data is an empty zlib stream).
export function pngDeclaring(w, h) {
  const ihdr = Buffer.alloc(13);
  ihdr.writeUInt32BE(w, 0); ihdr.writeUInt32BE(h, 4); ihdr[8] = 8; ihdr[9] = 0;
  return Buffer.concat([Buffer.from([137, 80, 78, 71, 13, 10, 26, 10]), chunk('IHDR', ihdr),
    chunk('IDAT', Buffer.from([0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01])), chunk('IEND', Buffer.alloc(0))]);
}

// The CLI's answers within one run of tests/e2e/run.sh, shared by its suites (E2E_CLI_CACHE
// names a folder of that run, deleted with it): the three engines mark the same files on the
// same seed and the comparison asks the same runs, and the CLI's output depends only on its
// arguments and inputs. Without the folder, every call runs the CLI.
export function cliCached(key, compute) {
  const dir = process.env.E2E_CLI_CACHE;
  if (!dir) return compute();
  const file = path.join(dir, crypto.createHash('sha256').update(JSON.stringify([CLI, key])).digest('hex') + '.json');
  const read = () => {
    try {
      return { value: JSON.parse(fs.readFileSync(file, 'utf8')) };
    } catch {
      return null;
    }
  };
  let got = read();
  if (got) return got.value;
  // The first suite to ask computes it; one asking meanwhile waits for that answer
  // instead of running the same CLI beside it (up to 10 min, then computes its own).
  let mine = false;
  try {
    fs.closeSync(fs.openSync(`${file}.lock`, 'wx'));
    mine = true;
  } catch {
    // While the other's lock stands and no answer is there (a failed compute drops its lock).
    const pause = new Int32Array(new SharedArrayBuffer(4));
    for (let i = 0; i < 6000 && !(got = read()) && fs.existsSync(`${file}.lock`); i++) Atomics.wait(pause, 0, 0, 100);
    if (got || (got = read())) return got.value;
  }
  try {
    const value = compute();
    const tmp = `${file}.${process.pid}.tmp`;
    fs.writeFileSync(tmp, JSON.stringify(value));
    fs.renameSync(tmp, file);
    return value;
  } finally {
    if (mine) fs.rmSync(`${file}.lock`, { force: true });
  }
}

// The CLI's view_trajectory with `args` in a scratch folder: its files and stderr.
export function cliTrajectory(args) {
  const out = cliCached(['view_trajectory', DATASET, ...args], () => {
    const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'siftlab-vo24-'));
    const vo = spawnSync(CLI, ['-d', path.join(ROOT, DATASET), 'view_trajectory', ...args, '--metrics', 'm.json', '--plot', 'plot.svg'], { cwd: tmp, encoding: 'utf8' });
    assert.equal(vo.status, 0, vo.stderr);
    const r = { stderr: vo.stderr, metrics: JSON.parse(fs.readFileSync(path.join(tmp, 'm.json'), 'utf8')), svg: fs.readFileSync(path.join(tmp, 'plot.svg')).toString('base64') };
    fs.rmSync(tmp, { recursive: true });
    return r;
  });
  return { ...out, svg: Buffer.from(out.svg, 'base64') };
}

// A small class marked by the CLI (`siftlab mark DIR --out OUT`, n = 2, seed 1: the good
// file, two with a common mistake that these cases show, one that does not compile): its summary as JSON, and
// files holding summary.json and summary.html (for the "Class results" view and the page).
export function classSummary() {
  const fixtures = path.join(ROOT, 'tests/fixtures/mark');
  const files = ['good', 'inverted', 'round', 'syntax'];
  const summary = cliCached(['class-summary', files, 2, 1], () => {
    const work = fs.mkdtempSync(path.join(os.tmpdir(), 'siftlab-e2e-class-'));
    for (const f of files) {
      fs.mkdirSync(path.join(work, 'class', f), { recursive: true });
      fs.copyFileSync(path.join(fixtures, f, 'vision_tasks.py'), path.join(work, 'class', f, 'vision_tasks.py'));
    }
    const r = spawnSync(CLI, ['--opencv-lanes', String(LANES), '-d', DATASET, 'mark', path.join(work, 'class'),
      '--out', path.join(work, 'out'), '-n', '2', '--seed', '1', '--jobs', '2'], { cwd: ROOT, encoding: 'utf8' });
    if (!fs.existsSync(path.join(work, 'out', 'summary.json'))) throw new Error(`no summary.json: ${r.stderr}`);
    const s = JSON.parse(fs.readFileSync(path.join(work, 'out', 'summary.json'), 'utf8'));
    const html = fs.readFileSync(path.join(work, 'out', 'summary.html'), 'utf8');
    fs.rmSync(work, { recursive: true, force: true });
    return { s, html };
  });
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'siftlab-e2e-summary-'));
  const file = path.join(dir, 'summary.json');
  fs.writeFileSync(file, JSON.stringify(summary.s));
  fs.writeFileSync(path.join(dir, 'summary.html'), summary.html);
  return { summary: summary.s, file, html: path.join(dir, 'summary.html') };
}
