// End-to-end tests of the siftlab app in real headless Chromium (Debian's), driven by
// playwright-core, against the static site in dist/ served on localhost (tests/e2e/run.sh
// starts the server and passes BASE_URL). The reference is the native CLI
// (target/release/siftlab) on the same frames.
import { test, before, after, beforeEach, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync, spawnSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';

const HERE = path.dirname(fileURLToPath(import.meta.url));
const ROOT = path.resolve(HERE, '../..');
const BASE = process.env.BASE_URL || 'http://127.0.0.1:8080/';
const ORIGIN = new URL(BASE).origin;
// tests/e2e/run.sh passes the CLI it built (CARGO_TARGET_DIR honoured).
const CLI = process.env.SIFTLAB_CLI || path.join(ROOT, 'target/release/siftlab');
const DATASET = 'www/demo/MyKITTI';
const FRAME = (id) => path.join(ROOT, DATASET, 'gray/00/image_0', String(id).padStart(6, '0') + '.png');
const SHOTS = path.join(HERE, 'screenshots');
fs.mkdirSync(SHOTS, { recursive: true });
const metrics = {};

// OpenCV dispatches SIFT to AVX-512 kernels (16 lanes) when the CPU has F/CD/BW/DQ/VL, else
// AVX2 (8); the CLI reproduces the host's build by default, so the app is told the same.
function hostLanes() {
  if (process.arch !== 'x64') return 8;
  const flags = (fs.readFileSync('/proc/cpuinfo', 'utf8').match(/^flags\s*:(.*)$/m) || [, ''])[1].split(/\s+/);
  return ['avx512f', 'avx512cd', 'avx512bw', 'avx512dq', 'avx512vl'].every((f) => flags.includes(f)) ? 16 : 8;
}
const LANES = hostLanes();

function cli(args) {
  return execFileSync(CLI, ['-d', DATASET, ...args], { cwd: ROOT, encoding: 'utf8', stdio: ['ignore', 'pipe', 'pipe'] });
}
function cliRet(args) {
  const out = cli(['get_info', ...args]);
  const line = out.split('\n').find((l) => l.startsWith('ret value: '));
  assert.ok(line, out);
  return line.slice('ret value: '.length);
}
const siftCache = new Map();
function cliSift(id, lanes = LANES) {
  const key = `${id}/${lanes}`;
  if (!siftCache.has(key)) {
    const json = execFileSync(CLI, ['--opencv-lanes', String(lanes), 'sift', FRAME(id), '--json'], { cwd: ROOT, encoding: 'utf8', maxBuffer: 1 << 28 });
    siftCache.set(key, JSON.parse(json));
  }
  return siftCache.get(key);
}

let browser;
let context;
let page;
let consoleErrors;
let offOrigin;

before(async () => {
  assert.ok(fs.existsSync(CLI), `${CLI} missing: cargo build --release --bin siftlab`);
  browser = await chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking', '--no-first-run',
           '--disable-component-update', '--disable-sync', '--disable-quic'],
  });
});
after(async () => {
  await browser?.close();
  fs.writeFileSync(path.join(SHOTS, 'metrics.json'), JSON.stringify(metrics, null, 2));
});

beforeEach(async () => {
  context = await browser.newContext({ viewport: { width: 1400, height: 900 } });
  consoleErrors = [];
  offOrigin = [];
  // Every request the page or its workers make must stay on our origin.
  context.on('request', (r) => {
    const u = r.url();
    if (!u.startsWith('data:') && !u.startsWith('blob:') && new URL(u).origin !== ORIGIN) offOrigin.push(u);
  });
  page = await context.newPage();
  const onConsole = (m) => { if (m.type() === 'error') consoleErrors.push(m.text()); };
  page.on('console', onConsole);
  page.on('pageerror', (e) => consoleErrors.push(String(e)));
  page.on('worker', (w) => { try { w.on('console', onConsole); } catch { /* older playwright */ } });
});
afterEach(async () => {
  await context?.close();
  assert.deepEqual(offOrigin, [], 'requests left the origin');
  assert.deepEqual(consoleErrors, [], 'console errors');
});

const tid = (id) => `[data-testid="${id}"]`;
async function idle(p = page) {
  await p.waitForSelector(tid('keypoint-count-cur'), { timeout: 180000 });
  await p.waitForSelector(tid('busy'), { state: 'detached', timeout: 180000 });
}
async function settings(algo, t, feature, p = page) {
  await p.selectOption(tid('algo'), algo);
  await p.fill(tid('threshold'), t);
  await p.fill(tid('feature'), String(feature));
}
async function tuple(p = page) {
  return (await p.textContent(tid('result-tuple'))).trim();
}

test('demo: counts and nndr 0.8 tuples equal the native CLI; URL restores the view', async () => {
  const t0 = Date.now();
  await page.goto(`${BASE}?lanes=${LANES}`);
  await page.click(tid('demo'));
  await idle();
  metrics.demoReadyMs = Date.now() - t0;
  // The opening view shows a match: the demo's own feature under nndr 0.8.
  const opening = await page.inputValue(tid('feature'));
  assert.equal(opening, '1256');
  assert.equal(await tuple(), cliRet(['-a', 'nndr', '-t', '0.8', '1', opening]));
  assert.notEqual(await tuple(), '((0, 0), [], [])');
  const sift = [0, 1].map((id) => cliSift(id));
  assert.equal(await page.textContent(tid('keypoint-count-prev')), String(sift[0].keypoints.length));
  assert.equal(await page.textContent(tid('keypoint-count-cur')), String(sift[1].keypoints.length));
  // SIFT time per frame as the page measured it in its worker.
  const infos = await page.$$eval('.slot-info', (els) => els.map((e) => e.textContent));
  metrics.chromiumSiftMs = infos.map((s) => Number((s.match(/SIFT (\d+) ms/) || [])[1]));
  // Chromium has relaxed SIMD, so worker.js loaded the relaxed build, and its
  // relaxed_madd is fused: SIFT ran on the engine's FMA (the counts above and the
  // tuples below are that build's).
  for (const which of ['prev', 'cur']) {
    assert.equal((await page.textContent(tid(`keypoint-count-${which}-engine`))).trim(), 'relaxed SIMD');
  }
  metrics.nativeSift = [0, 1].map((id) => execFileSync(CLI, ['sift', FRAME(id)], { cwd: ROOT, encoding: 'utf8' }).trim());
  const n = sift[0].keypoints.length;
  let nonEmpty = 0;
  for (const f of [0, 7, 42, 123, 500, 777, 1024, n - 1]) {
    await settings('nndr', '0.8', f);
    const want = cliRet(['-a', 'nndr', '-t', '0.8', '1', String(f)]);
    await page.waitForFunction(([sel, w]) => document.querySelector(sel)?.textContent.trim() === w, [tid('result-tuple'), want], { timeout: 5000 })
      .catch(() => {});
    assert.equal(await tuple(), want, `feature ${f}`);
    // The core's time for the update, as the page shows it ("computed in X ms").
    const ms = Number(((await page.textContent('.result')).match(/computed in ([\d.]+) ms/) || [])[1]);
    metrics.analysisMsMax = Math.max(metrics.analysisMsMax || 0, ms);
    assert.ok(ms < 50, `update took ${ms} ms`);
    if (want !== '((0, 0), [], [])') nonEmpty++;
  }
  assert.ok(nonEmpty >= 2, 'some features should match under nndr 0.8');
  // dt and nn too, on one feature.
  await settings('dt', '250', 42);
  assert.equal(await tuple(), cliRet(['-a', 'dt', '-t', '250', '1', '42']));
  await settings('nn', '', 42);
  assert.equal(await tuple(), cliRet(['-a', 'nn', '1', '42']));
  await settings('nndr', '0.8', 123);
  await page.screenshot({ path: path.join(SHOTS, 'demo-nndr.png'), fullPage: true });
  // The URL carries the view; a fresh page opens on it.
  const url = page.url();
  assert.match(url, /algo=nndr/);
  assert.match(url, /t=0\.8/);
  assert.match(url, /feature=123/);
  const p2 = await context.newPage();
  p2.on('console', (m) => { if (m.type() === 'error') consoleErrors.push(m.text()); });
  await p2.goto(url);
  await idle(p2);
  assert.equal(await tuple(p2), cliRet(['-a', 'nndr', '-t', '0.8', '1', '123']));
  await p2.close();
});

test('?wasm=portable: the SIMD128 worker build gives the same keypoints and tuples', async () => {
  const t0 = Date.now();
  await page.goto(`${BASE}?lanes=${LANES}&wasm=portable`);
  await idle();
  metrics.demoReadyMsPortable = Date.now() - t0;
  const infos = await page.$$eval('.slot-info', (els) => els.map((e) => e.textContent));
  metrics.chromiumSiftMsPortable = infos.map((s) => Number((s.match(/SIFT (\d+) ms/) || [])[1]));
  for (const [i, which] of ['prev', 'cur'].entries()) {
    assert.equal((await page.textContent(tid(`keypoint-count-${which}-engine`))).trim(), 'SIMD128');
    assert.equal(await page.textContent(tid(`keypoint-count-${which}`)), String(cliSift(i).keypoints.length));
  }
  for (const f of [7, 123, 1024]) {
    await settings('nndr', '0.8', f);
    assert.equal(await tuple(), cliRet(['-a', 'nndr', '-t', '0.8', '1', String(f)]), `feature ${f}`);
  }
});

test('default view (AVX2 build) equals the CLI with --opencv-lanes 8', async () => {
  await page.goto(BASE);
  await idle();
  for (const f of [7, 500]) {
    await settings('nndr', '0.8', f);
    const want = execFileSync(CLI, ['--opencv-lanes', '8', '-d', DATASET, 'get_info', '-a', 'nndr', '-t', '0.8', '1', String(f)], { cwd: ROOT, encoding: 'utf8' })
      .split('\n').find((l) => l.startsWith('ret value: ')).slice(11);
    assert.equal(await tuple(), want);
  }
});

// The app's default width (8 lanes, AVX2), whatever the host: what the lab manual's
// examples and a plain link are computed with.
function cliRet8(args) {
  const out = execFileSync(CLI, ['--opencv-lanes', '8', '-d', DATASET, 'get_info', ...args], { cwd: ROOT, encoding: 'utf8', stdio: ['ignore', 'pipe', 'pipe'] });
  return out.split('\n').find((l) => l.startsWith('ret value: ')).slice('ret value: '.length);
}

test('the page opens on real KITTI frames 0/1, fetching only those two frames, with the attribution', async () => {
  const fetched = [];
  page.on('request', (r) => { if (/\/demo\//.test(r.url())) fetched.push(new URL(r.url()).pathname); });
  await page.goto(BASE);
  await idle();
  assert.match(await page.textContent('.slots'), /000000\.png[\s\S]*000001\.png/);
  const sift = [0, 1].map((id) => cliSift(id, 8));
  assert.equal(await page.textContent(tid('keypoint-count-prev')), String(sift[0].keypoints.length));
  assert.equal(await page.inputValue(tid('feature')), '1256');
  assert.equal(await tuple(), cliRet8(['-a', 'nndr', '-t', '0.8', '1', '1256']));
  assert.notEqual(await tuple(), '((0, 0), [], [])');
  // Frames load lazily: of the 104 bundled frames, the page fetched the pair it shows.
  const frames = fetched.filter((u) => u.endsWith('.png')).sort();
  assert.deepEqual(frames, ['/demo/gray/00/image_0/000000.png', '/demo/gray/00/image_0/000001.png']);
  assert.ok(fetched.includes('/demo/index.txt'));
  // KITTI's attribution and licence beside the demo, and the README with them in full.
  const attribution = await page.textContent(tid('attribution'));
  assert.match(attribution, /KITTI odometry sequence 00/);
  assert.match(attribution, /Geiger, P\. Lenz, R\. Urtasun/);
  assert.match(attribution, /CC BY-NC-SA 3\.0/);
  const readme = await page.evaluate(async () => (await fetch('demo/README.md')).text());
  assert.match(readme, /Creative Commons Attribution-NonCommercial-ShareAlike 3\.0/);
  assert.equal(await page.evaluate(async () => (await fetch('demo/poses/00.txt')).text()),
    fs.readFileSync(path.join(ROOT, DATASET, 'poses/00.txt'), 'utf8'));
  await page.screenshot({ path: path.join(SHOTS, 'opening.png'), fullPage: true });
});

test('lab manual examples: each click shows the manual value beside siftlab\'s, equal (✓)', async () => {
  await page.goto(BASE);
  await idle();
  const buttons = await page.$$('[data-testid^="manual-example-"]');
  assert.equal(buttons.length, 7);
  for (let i = 0; i < 7; i++) {
    const label = await page.textContent(tid(`manual-example-${i}`));
    const m = label.match(/get_info -a (\S+)(?: -t (\S+))? (\d+) (\d+)/);
    assert.ok(m, label);
    const [, algo, t, frame, feature] = m;
    await page.click(tid(`manual-example-${i}`));
    // The example's own pair on screen, and its comparison filled in.
    await page.waitForFunction(([cmd]) => {
      const c = document.querySelector('[data-testid="manual-compare"]');
      return c && c.textContent.includes(cmd) && document.querySelector('[data-testid="manual-mark"]');
    }, [m[0]], { timeout: 180000 });
    await idle();
    const want = cliRet8(['-a', algo, ...(t ? ['-t', t] : []), frame, feature]);
    assert.equal(await page.inputValue(tid('feature')), feature);
    assert.equal(await page.inputValue(tid('threshold')), t || '');
    assert.equal(await page.inputValue(tid('frame-id')), frame);
    assert.equal(await tuple(), want, m[0]);
    assert.equal((await page.textContent(tid('manual-got'))).trim(), want);
    assert.equal((await page.textContent(tid('manual-expected'))).trim(), want, `the manual's value for ${m[0]}`);
    assert.match(await page.textContent(tid('manual-mark')), /^✓/);
    assert.match(await page.getAttribute(tid(`manual-example-${i}`), 'class'), /active/);
    if (i === 1) await page.screenshot({ path: path.join(SHOTS, 'manual-example.png'), fullPage: true });
  }
});

test('a link to the manual\'s Task 1 tuple opens on it, with the comparison', async () => {
  await page.goto(`${BASE}?src=demo&frame=150&feature=209&algo=dt&t=300`);
  await idle();
  assert.match(await page.textContent('.slots'), /000149\.png[\s\S]*000150\.png/);
  const want = cliRet8(['-a', 'dt', '-t', '300', '150', '209']);
  assert.equal(await tuple(), want);
  assert.equal((await page.textContent(tid('manual-expected'))).trim(), want);
  assert.match(await page.textContent(tid('manual-mark')), /^✓/);
  assert.match(await page.textContent(tid('manual-compare')), /Task 1 \(dt\)/);
  assert.match(page.url(), /\?src=demo&frame=150&feature=209&algo=dt&t=300$/);
});

test('a link to frames the demo lacks says which, and the app stays usable', async () => {
  await page.goto(`${BASE}?src=demo&frame=130&feature=5`);
  await page.waitForSelector(tid('error'));
  assert.match(await page.textContent(tid('error')),
    /FRAME_ID 130 needs frames 129 and 130: frames 129 and 130 are not in the demo, which has frames 0–99, 119, 120, 149, 150/);
  // Nothing else is shown under the link's settings, and the link stays as it was.
  assert.equal(await page.$(tid('keypoint-count-cur')), null);
  assert.equal(await page.inputValue(tid('frame-id')), '130');
  assert.match(page.url(), /frame=130/);
  await page.screenshot({ path: path.join(SHOTS, 'missing-frame.png') });
  // One of the two missing.
  await page.goto(`${BASE}?src=demo&frame=119`);
  await page.waitForSelector(tid('error'));
  assert.match(await page.textContent(tid('error')), /FRAME_ID 119 needs frames 118 and 119: frame 118 is not in the demo, which has frames 0–99, 119, 120, 149, 150/);
  // Usable: a FRAME_ID the demo has loads, and the message goes.
  await page.fill(tid('frame-id'), '120');
  await page.press(tid('frame-id'), 'Enter');
  await idle();
  assert.equal(await page.$(tid('error')), null);
  assert.equal(await tuple(), cliRet8(['-a', 'nndr', '-t', '0.8', '120', await page.inputValue(tid('feature'))]));
});

test('click-to-select picks the keypoint under the cursor', async () => {
  await page.goto(`${BASE}?lanes=${LANES}`);
  await idle();
  const kps = cliSift(0).keypoints;
  await page.locator(tid('overlay')).scrollIntoViewIfNeeded();
  const box = await page.locator(tid('overlay')).boundingBox();
  const [W, H] = [1241, 376 * 2]; // stacked: previous on top, current below
  assert.ok(box.y >= 0 && box.y + (376 * box.height) / H <= 900, `previous frame on screen: ${JSON.stringify(box)}`);
  for (const i of [3, 250, 999, kps.length - 1]) {
    const k = kps[i];
    const x = box.x + (k.x * box.width) / W;
    const y = box.y + (k.y * box.height) / H;
    await page.mouse.click(x, y);
    const got = Number(await page.inputValue(tid('feature')));
    // What is under the cursor: the keypoint nearest to the clicked point (the first on ties).
    const ix = ((x - box.x) * W) / box.width;
    const iy = ((y - box.y) * H) / box.height;
    let best = 0;
    let bd = Infinity;
    kps.forEach((q, j) => { const d = (q.x - ix) ** 2 + (q.y - iy) ** 2; if (d < bd) { bd = d; best = j; } });
    assert.equal(got, best, `clicked keypoint ${i}`);
    assert.ok(Math.hypot(kps[got].x - k.x, kps[got].y - k.y) < 1e-3 || bd < 1, `picked ${got} for ${i}`);
  }
  // Keyboard: focus the frames and step with the arrows.
  await page.focus('.stage');
  const f0 = Number(await page.inputValue(tid('feature')));
  await page.keyboard.press('ArrowLeft');
  assert.equal(Number(await page.inputValue(tid('feature'))), f0 - 1);
  await page.keyboard.press('Home');
  assert.equal(await page.inputValue(tid('feature')), '0');
  await page.check(tid('show-all'));
  await page.mouse.click(box.x + (kps[250].x * box.width) / W, box.y + (kps[250].y * box.height) / H);
  await page.screenshot({ path: path.join(SHOTS, 'click-select.png') });
});

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
function pngDeclaring(w, h) {
  const ihdr = Buffer.alloc(13);
  ihdr.writeUInt32BE(w, 0); ihdr.writeUInt32BE(h, 4); ihdr[8] = 8; ihdr[9] = 0;
  return Buffer.concat([Buffer.from([137, 80, 78, 71, 13, 10, 26, 10]), chunk('IHDR', ihdr),
    chunk('IDAT', Buffer.from([0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01])), chunk('IEND', Buffer.alloc(0))]);
}

test('bad files and folders show an inline error and keep what was loaded', async () => {
  await page.goto(`${BASE}?lanes=${LANES}&algo=nndr&t=0.8&feature=42`);
  await idle();
  const before = await tuple();
  const countCur = await page.textContent(tid('keypoint-count-cur'));
  const cases = [
    [{ name: 'notes.txt', mimeType: 'text/plain', buffer: Buffer.from('hello, not an image') }, /not an image/],
    [{ name: 'truncated.png', mimeType: 'image/png', buffer: fs.readFileSync(FRAME(2)).subarray(0, 20000) }, /corrupt or truncated/],
    [{ name: 'huge.png', mimeType: 'image/png', buffer: pngDeclaring(5000, 4000) }, /20000000 pixels, above the limit of 16000000/],
  ];
  for (const [file, message] of cases) {
    await page.setInputFiles(tid('frame-cur'), file);
    await page.waitForSelector(tid('error'));
    await idle();
    assert.match(await page.textContent(tid('error')), message);
    assert.equal(await tuple(), before, 'the previous result stays');
    assert.equal(await page.textContent(tid('keypoint-count-cur')), countCur);
  }
  await page.screenshot({ path: path.join(SHOTS, 'error.png') });
  // A folder without the MyKITTI layout.
  const junk = fs.mkdtempSync(path.join(os.tmpdir(), 'siftlab-e2e-'));
  fs.writeFileSync(path.join(junk, 'readme.txt'), 'not a dataset');
  await page.setInputFiles(tid('folder'), junk);
  await page.waitForFunction((sel) => /MyKITTI layout/.test(document.querySelector(sel)?.textContent || ''), tid('error'));
  assert.equal(await tuple(), before);
  // The real layout works, and a missing frame is named.
  await page.setInputFiles(tid('folder'), path.join(ROOT, DATASET));
  await page.waitForSelector(tid('error'), { state: 'detached' });
  await idle();
  assert.equal(await tuple(), cliRet(['-a', 'nndr', '-t', '0.8', '1', '42']));
  await page.fill(tid('frame-id'), '130');
  await page.press(tid('frame-id'), 'Enter');
  await page.waitForFunction((sel) => (document.querySelector(sel)?.textContent || '').includes(
    'FRAME_ID 130 needs frames 129 and 130: frames 129 and 130 are not in the folder, which has frames 0–99, 119, 120, 149, 150'), tid('error'));
  await page.fill(tid('frame-id'), '3');
  await page.press(tid('frame-id'), 'Enter');
  await page.waitForFunction(() => /000003\.png/.test(document.querySelector('.slots')?.textContent || ''));
  await idle();
  assert.equal(await tuple(), cliRet(['-a', 'nndr', '-t', '0.8', '3', '42']));
  assert.equal(await page.$(tid('error')), null, 'a pair that is there settles the message');
  // And a good file after the bad ones: the app still works.
  await page.setInputFiles(tid('frame-cur'), FRAME(5));
  await page.waitForFunction((sel) => /000005\.png/.test(document.querySelector(sel)?.textContent || ''), '.slots');
  await idle();
  assert.equal(await page.textContent(tid('keypoint-count-cur')), String(cliSift(5).keypoints.length));
  assert.ok((await tuple()).startsWith('(('));
  fs.rmSync(junk, { recursive: true });
});

test('check my answer and a seeded exercise', async () => {
  await page.goto(`${BASE}?lanes=${LANES}&algo=nn&feature=77`);
  await idle();
  const right = cliRet(['-a', 'nn', '1', '77']);
  await page.fill(tid('answer'), `ret value: ${right}`);
  await page.click(tid('check'));
  assert.match(await page.textContent(tid('check-result')), /Correct/);
  // Float query coordinates (no int()): the diagnosis names it.
  const wrong = right.replace(/^\(\((\d+), (\d+)\)/, (m, x, y) => `((${x}.5, ${y}.25)`);
  assert.notEqual(wrong, right);
  await page.fill(tid('answer'), wrong);
  await page.click(tid('check'));
  assert.match(await page.textContent(tid('check-result')), /int\(\)/);
  await page.screenshot({ path: path.join(SHOTS, 'selfcheck.png'), fullPage: true });
  // Exercises: start, answer with the CLI's output, score.
  await page.click(tid('exercise-start'));
  await page.waitForFunction((sel) => /get_info -a \S+ .*\d+ \d+\?/.test(document.querySelector(sel)?.textContent || ''), tid('question'), { timeout: 180000 });
  const q = await page.textContent(tid('question'));
  const m = q.match(/get_info -a (\S+)(?: -t (\S+))? (\d+) (\d+)/);
  assert.ok(m, q);
  const args = ['-a', m[1], ...(m[2] ? ['-t', m[2]] : []), m[3], m[4]];
  await page.fill(tid('exercise-answer'), cliRet(args));
  await page.click('.exercises button[type=submit]');
  assert.match(await page.textContent('.exercises ' + tid('check-result')), /Correct/);
  assert.equal(await page.textContent(tid('score')), 'Score: 1 / 1');
  const link = page.url();
  assert.match(link, /ex=\d+&q=1/);
  await page.screenshot({ path: path.join(SHOTS, 'exercise.png'), fullPage: true });
  // The same link gives the same question.
  const p2 = await context.newPage();
  await p2.goto(link);
  await p2.waitForFunction((sel) => /get_info -a \S+ .*\d+ \d+\?/.test(document.querySelector(sel)?.textContent || ''), tid('question'), { timeout: 180000 });
  assert.equal(await p2.textContent(tid('question')), q);
  await p2.close();
});

test('narrow screen layout', async () => {
  await page.setViewportSize({ width: 760, height: 1000 });
  await page.goto(`${BASE}?lanes=${LANES}&feature=300`);
  await idle();
  await page.screenshot({ path: path.join(SHOTS, 'narrow.png'), fullPage: true });
});

test('visual odometry on the bundled frames 0 to 99 equals the CLI view_trajectory 99', async () => {
  await page.goto(`${BASE}?lanes=${LANES}`);
  await idle();
  // The lab's count: view_trajectory FRAME_ID runs frames 0 … FRAME_ID; the demo's
  // contiguous run from 0 is 0–99 (its 119, 120, 149, 150 are not part of it).
  const ids = fs.readdirSync(path.join(ROOT, DATASET, 'gray/00/image_0')).filter((f) => /^\d{6}\.png$/.test(f)).map((f) => Number(f.slice(0, 6)));
  let last = 0;
  while (ids.includes(last + 1)) last++;
  assert.equal(last, 99);
  assert.equal(await page.inputValue(tid('vo-frame-id')), String(last));
  assert.equal(await page.textContent(tid('vo-range')), `frames 0 to ${last} (${last + 1} frames) · available: frames 0 to ${last}`);
  await page.click(tid('vo-run'));
  await page.waitForSelector(tid('vo-ate'), { timeout: 600000 });
  const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'siftlab-vo-'));
  // The CLI reports the trajectory error with its progress (stdout or stderr: read both).
  const vo = spawnSync(CLI, ['-d', path.join(ROOT, DATASET), 'view_trajectory', String(last)], { cwd: tmp, encoding: 'utf8' });
  assert.equal(vo.status, 0, vo.stderr);
  const ate = (vo.stdout + vo.stderr).match(/trajectory error \(ATE RMSE, (\d+) frames\): ([\d.]+) m/);
  assert.equal(ate[1], String(last + 1));
  assert.equal(await page.textContent(tid('vo-ate')), `${ate[2]} m`);
  assert.match(await page.textContent(tid('vo-progress')), new RegExp(`frame ${last + 1} / ${last + 1}`));
  metrics.voChromium = (await page.textContent('.trajectory')).match(/over \d+ frames · [\d.]+ s( \([\d.]+ frames\/s\))?/)?.[0];
  // The lab's window as a PNG: the same bytes the CLI writes.
  const [download] = await Promise.all([page.waitForEvent('download'), page.click(tid('vo-download'))]);
  const png = fs.readFileSync(await download.path());
  assert.ok(png.equals(fs.readFileSync(path.join(tmp, 'trajectory.png'))), 'trajectory.png differs from the CLI');
  await page.locator('.trajectory').screenshot({ path: path.join(SHOTS, 'trajectory.png') });
  fs.rmSync(tmp, { recursive: true });
  // Past the run: refused with the reason, nothing read.
  await page.fill(tid('vo-frame-id'), '120');
  await page.click(tid('vo-run'));
  assert.match(await page.textContent(tid('vo-error')), /FRAME_ID 120 needs frames 0 to 120 \(121 frames\), but the frames in a row from 0 are frames 0 to 99/);
  // A broken frame 3 in a MyKITTI folder: the detection helpers leave it to the
  // tracker, which fails on it in frame order, after the steps before it, with
  // the one-worker loop's message.
  const broken = fs.mkdtempSync(path.join(os.tmpdir(), 'siftlab-vo-broken-'));
  fs.mkdirSync(path.join(broken, 'gray/00/image_0'), { recursive: true });
  fs.cpSync(path.join(ROOT, DATASET, 'poses'), path.join(broken, 'poses'), { recursive: true });
  for (let i = 0; i <= 5; i++) fs.copyFileSync(FRAME(i), path.join(broken, 'gray/00/image_0', path.basename(FRAME(i))));
  fs.writeFileSync(path.join(broken, 'gray/00/image_0/000003.png'), fs.readFileSync(FRAME(3)).subarray(0, 20000));
  await page.setInputFiles(tid('folder'), broken);
  await idle();
  assert.equal(await page.inputValue(tid('vo-frame-id')), '5');
  await page.fill(tid('vo-frame-id'), '4');
  await page.click(tid('vo-run'));
  await page.waitForSelector(tid('vo-error'), { timeout: 300000 });
  assert.match(await page.textContent(tid('vo-error')), /^frame 3: .*(corrupt|truncated)/);
  assert.match(await page.textContent(tid('vo-progress')), /frame 3 \/ 5/);
  fs.rmSync(broken, { recursive: true });
});

test('view_feature and view_info exports equal the CLI PNGs byte for byte', async () => {
  await page.goto(`${BASE}?lanes=${LANES}&algo=dt&t=280&feature=42`);
  await idle();
  const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'siftlab-png-'));
  for (const [cmd, id, file] of [['view_feature', 'export-feature', 'opencv_visual.png'], ['view_info', 'export-info', 'custom_visual.png']]) {
    execFileSync(CLI, ['-d', path.join(ROOT, DATASET), cmd, '-a', 'dt', '-t', '280', '1', '42'], { cwd: tmp, encoding: 'utf8' });
    const [download] = await Promise.all([page.waitForEvent('download'), page.click(tid(id))]);
    assert.equal(download.suggestedFilename(), file);
    const png = fs.readFileSync(await download.path());
    assert.ok(png.equals(fs.readFileSync(path.join(tmp, file))), `${file} differs from the CLI's`);
    fs.copyFileSync(await download.path(), path.join(SHOTS, `export-${file}`));
  }
  fs.rmSync(tmp, { recursive: true });
});

// The CLI's view_trajectory with `args` in a scratch folder: its files and stderr.
function cliTrajectory(args) {
  const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'siftlab-vo24-'));
  const vo = spawnSync(CLI, ['-d', path.join(ROOT, DATASET), 'view_trajectory', ...args, '--metrics', 'm.json', '--plot', 'plot.svg'], { cwd: tmp, encoding: 'utf8' });
  assert.equal(vo.status, 0, vo.stderr);
  const out = { stderr: vo.stderr, metrics: JSON.parse(fs.readFileSync(path.join(tmp, 'm.json'), 'utf8')), svg: fs.readFileSync(path.join(tmp, 'plot.svg')) };
  fs.rmSync(tmp, { recursive: true });
  return out;
}

test('odometry with the student\'s matcher (nndr 0.8, frames 0-99) equals the CLI: metrics, plot SVG', async () => {
  await page.goto(`${BASE}?lanes=${LANES}`);
  await idle();
  await page.selectOption(tid('vo-tracker'), 'nndr');
  assert.equal(await page.inputValue(tid('vo-threshold')), '0.8');
  await page.click(tid('vo-run'));
  await page.waitForSelector(tid('vo-metrics'), { timeout: 600000 });
  const ref = cliTrajectory(['-a', 'nndr', '-t', '0.8', '99']);
  // stderr: "nndr 0.8 (100 frames): ATE … · KITTI …", the page shows the same summary.
  const line = ref.stderr.split('\n').find((l) => l.startsWith('nndr 0.8 (100 frames): '));
  assert.equal(await page.textContent(tid('vo-metrics')), line.slice('nndr 0.8 (100 frames): '.length));
  assert.equal(await page.textContent(tid('vo-ate')), `${ref.metrics.ate_rmse.toFixed(4)} m`);
  metrics.voMatchedChromium = (await page.textContent('.trajectory')).match(/over \d+ frames · [\d.]+ s( \([\d.]+ frames\/s\))?/)?.[0];
  // The figures are the core's: the exported SVG is the CLI's --plot, byte for byte
  // (so every position agrees to the plot's 0.01 px).
  const [download] = await Promise.all([page.waitForEvent('download'), page.click(tid('vo-svg'))]);
  assert.equal(download.suggestedFilename(), 'vo.svg');
  fs.copyFileSync(await download.path(), path.join(SHOTS, 'vo-export.svg'));
  assert.ok(fs.readFileSync(await download.path()).equals(ref.svg), 'the app\'s SVG differs from the CLI\'s --plot');
  const [pngDownload] = await Promise.all([page.waitForEvent('download'), page.click(tid('vo-png'))]);
  const png = fs.readFileSync(await pngDownload.path());
  assert.deepEqual([...png.subarray(1, 4)].map((c) => String.fromCharCode(c)).join(''), 'PNG');
  fs.copyFileSync(await pngDownload.path(), path.join(SHOTS, 'vo-export.png'));
  // Hover over the top view names a frame, its position and error.
  const box = await page.locator(`${tid('vo-plot')}`).boundingBox();
  await page.mouse.move(box.x + box.width / 2, box.y + box.height * 0.3);
  assert.match(await page.textContent(tid('vo-hover')), /^frame \d+ · x=-?[\d.]+ y=-?[\d.]+ z=-?[\d.]+ m · error [\d.]+ m$/);
  await page.locator('.trajectory .vo-views').screenshot({ path: path.join(SHOTS, 'vo-matched.png') });
});

test('comparison view: LK, dt 200, nn, nndr 0.8 on frames 0-99, metrics equal the CLI\'s', async () => {
  await page.goto(`${BASE}?lanes=${LANES}`);
  await idle();
  await page.click(tid('vo-compare-run'));
  await page.waitForFunction((sel) => document.querySelector(sel)?.textContent === '4 runs done', tid('vo-compare-status'), { timeout: 900000 });
  const rows = await page.$$eval(tid('vo-compare-row'), (trs) => trs.map((tr) => [...tr.children].map((td) => td.textContent)));
  assert.deepEqual(rows.map((r) => r[0]), ['LK', 'dt 200', 'nn', 'nndr 0.8']);
  const args = { LK: [], 'dt 200': ['-a', 'dt', '-t', '200'], nn: ['-a', 'nn'], 'nndr 0.8': ['-a', 'nndr', '-t', '0.8'] };
  metrics.compareChromiumFps = {};
  // All four equal the CLI, dt 200 included: its frame-96 RANSAC sample is one where the
  // last bit of hypot picks the model, and the core computes hypot itself so that the
  // browser's and the CLI's agree (core/tests/essential_matrix.rs, docs/fidelity.md §VO-8).
  for (const r of rows) {
    const m = cliTrajectory([...args[r[0]], '99']).metrics;
    assert.deepEqual(r.slice(1, 7), [m.ate_rmse.toFixed(4), m.ate_rmse_aligned.toFixed(4), m.rpe_trans_rmse.toFixed(4), m.rpe_rot_rmse_deg.toFixed(4), 'n/a', 'n/a'], r[0]);
    metrics.compareChromiumFps[r[0]] = Number(r[7]);
  }
  // Truth and four runs overlaid, with a legend naming them.
  const svg = await page.locator(tid('vo-compare-plot')).innerHTML();
  for (const name of ['ground truth', 'LK', 'dt 200', 'nn', 'nndr 0.8']) assert.ok(svg.includes(`>${name}</text>`), name);
  assert.equal((svg.match(/<polyline/g) || []).length, 5);
  await page.locator('.vo-compare').screenshot({ path: path.join(SHOTS, 'vo-compare.png') });
});

test('see inside: whole-frame counts and SIFT anatomy equal the CLI (match_all, anatomy)', async () => {
  const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'siftlab-match-all-'));
  const cliMatchAll = (algo, t) => JSON.parse(execFileSync(CLI,
    ['--opencv-lanes', String(LANES), '-d', path.join(ROOT, DATASET), 'match_all', '-a', algo, ...(t ? ['-t', t] : []), '--json', '120'],
    { cwd: tmp, encoding: 'utf8', stdio: ['ignore', 'pipe', 'pipe'] }));
  await page.goto(`${BASE}?lanes=${LANES}&src=demo&frame=120&algo=nndr&t=0.8&see=matches`);
  await idle();
  metrics.wholeFrame = {};
  for (const [algo, t] of [['nndr', '0.8'], ['dt', '250'], ['nn', '']]) {
    if (algo !== 'nndr') {
      await page.selectOption(tid('algo'), algo);
      await page.fill(tid('threshold'), t);
    }
    const want = cliMatchAll(algo, t);
    const sel = `${tid('wf-counts')}[data-matches="${want.matches}"]`;
    await page.waitForSelector(sel, { timeout: 180000 });
    assert.equal(await page.getAttribute(tid('wf-counts'), 'data-correct'), String(want.correct), `${algo} ${t}`);
    assert.match(await page.textContent(tid('wf-counts')), new RegExp(`precision ${want.precision.toFixed(4)}`));
    metrics.wholeFrame[`${algo} ${t || 'none'}`] = want;
    if (algo === 'nndr') {
      metrics.sweepStatus = (await page.textContent(tid('wf-status'))).trim();
      await page.locator('.see-inside').screenshot({ path: path.join(SHOTS, 'whole-frame.png') });
    }
  }
  metrics.crossings120 = (await page.textContent(tid('crossings'))).trim();
  // The view is in the link: see=matches and the current setting.
  assert.match(page.url(), /see=matches/);

  // The anatomy of the previous frame of the demo's first pair, against `siftlab anatomy`.
  await page.goto(`${BASE}?lanes=${LANES}&src=demo&frame=1&see=anatomy&kp=0`);
  await idle();
  const want = JSON.parse(execFileSync(CLI, ['--opencv-lanes', String(LANES), 'anatomy', FRAME(0), '--json'], { cwd: ROOT, encoding: 'utf8' }));
  await page.waitForSelector(`${tid('funnel')} li[data-stage="kept"]`, { timeout: 180000 });
  for (const s of want.stages) {
    assert.equal(await page.getAttribute(`${tid('funnel')} li[data-stage="${s.stage}"]`, 'data-count'), String(s.count), s.stage);
  }
  for (const [reason, n] of Object.entries(want.stages[1].dropped)) {
    assert.equal(await page.getAttribute(`${tid('funnel')} li[data-drop="${reason}"]`, 'data-count'), String(n), reason);
  }
  assert.equal(await page.locator(`${tid('pyramid')} canvas.level`).count(), want.octaves * 11);
  await page.waitForSelector(tid('orientation-hist'));
  metrics.anatomyStatus = (await page.textContent(tid('anatomy-status'))).trim();
  await page.locator('.see-inside').screenshot({ path: path.join(SHOTS, 'anatomy.png') });
  fs.rmSync(tmp, { recursive: true });
});
