// End-to-end tests of the siftlab app (tests/e2e/app/, one file per view; helpers in
// common.mjs), in the engine E2E_ENGINE names, against the native CLI.
// The get_info view on the demo pair: counts and tuples equal the native CLI in both worker
// builds and the AVX2 default, the URL restores the view, click-to-select and the arrows,
// and the view_feature / view_info PNG exports.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { ROOT } from '../harness.mjs';
import {
  appSuite, CLI, DATASET, shot, metrics, LANES, cliRet, cliRet8, cliSift, BASE, page, tid, idle, settings, tuple, tupleIs, ENGINE_LABEL,
} from './common.mjs';

appSuite();

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
  const infos = await page.evalAll('.slot-info', (e) => e.textContent);
  metrics.siftMs = infos.map((s) => Number((s.match(/SIFT (\d+) ms/) || [])[1]));
  // worker.js picks the relaxed build where the engine validates relaxed SIMD, else SIMD128.
  for (const which of ['prev', 'cur']) {
    assert.equal((await page.textContent(tid(`keypoint-count-${which}-engine`))).trim(), ENGINE_LABEL);
  }
  const n = sift[0].keypoints.length;
  let nonEmpty = 0;
  const updateMs = [];
  for (const f of [0, 7, 42, 123, 500, 777, 1024, n - 1]) {
    await settings('nndr', '0.8', f);
    const want = cliRet(['-a', 'nndr', '-t', '0.8', '1', String(f)]);
    await tupleIs(want, `feature ${f}`);
    // The core's time for the update, as the page shows it ("computed in X ms").
    const ms = Number(((await page.textContent('.result')).match(/computed in ([\d.]+) ms/) || [])[1]);
    metrics.analysisMsMax = Math.max(metrics.analysisMsMax || 0, ms);
    updateMs.push(ms);
    if (want !== '((0, 0), [], [])') nonEmpty++;
  }
  // Interactive: the median update under 50 ms. The median, not each one: a wall-clock time
  // that another program on the machine preempted says nothing about the page.
  updateMs.sort((a, b) => a - b);
  const median = updateMs[Math.floor(updateMs.length / 2)];
  assert.ok(median < 50, `updates took ${updateMs.join(', ')} ms (median ${median})`);
  assert.ok(nonEmpty >= 2, 'some features should match under nndr 0.8');
  // dt and nn too, on one feature.
  await settings('dt', '250', 42);
  await tupleIs(cliRet(['-a', 'dt', '-t', '250', '1', '42']));
  await settings('nn', '', 42);
  await tupleIs(cliRet(['-a', 'nn', '1', '42']));
  await settings('nndr', '0.8', 123);
  await page.screenshot(shot('demo-nndr.png'), { fullPage: true });
  // The URL carries the view; a fresh page opens on it.
  const url = await page.url();
  assert.match(url, /algo=nndr/);
  assert.match(url, /t=0\.8/);
  assert.match(url, /feature=123/);
  await page.goto(url);
  await idle();
  assert.equal(await tuple(), cliRet(['-a', 'nndr', '-t', '0.8', '1', '123']));
});

test('?wasm=portable: the SIMD128 worker build gives the same keypoints and tuples', async () => {
  const t0 = Date.now();
  await page.goto(`${BASE}?lanes=${LANES}&wasm=portable`);
  await idle();
  metrics.demoReadyMsPortable = Date.now() - t0;
  const infos = await page.evalAll('.slot-info', (e) => e.textContent);
  metrics.siftMsPortable = infos.map((s) => Number((s.match(/SIFT (\d+) ms/) || [])[1]));
  for (const [i, which] of ['prev', 'cur'].entries()) {
    assert.equal((await page.textContent(tid(`keypoint-count-${which}-engine`))).trim(), 'SIMD128');
    assert.equal(await page.textContent(tid(`keypoint-count-${which}`)), String(cliSift(i).keypoints.length));
  }
  for (const f of [7, 123, 1024]) {
    await settings('nndr', '0.8', f);
    await tupleIs(cliRet(['-a', 'nndr', '-t', '0.8', '1', String(f)]), `feature ${f}`);
  }
});

test('default view (AVX2 build) equals the CLI with --opencv-lanes 8', async () => {
  await page.goto(BASE);
  await idle();
  for (const f of [7, 500]) {
    await settings('nndr', '0.8', f);
    await tupleIs(cliRet8(['-a', 'nndr', '-t', '0.8', '1', String(f)]), `feature ${f}`);
  }
});

test('click-to-select picks the keypoint under the cursor; arrows step', async () => {
  await page.goto(`${BASE}?lanes=${LANES}`);
  await idle();
  const kps = cliSift(0).keypoints;
  const box = await page.boundingBox(tid('overlay'));
  const [W, H] = [1241, 376 * 2]; // stacked: previous on top, current below
  assert.ok(box.y >= 0 && box.y + (376 * box.height) / H <= 900, `previous frame on screen: ${JSON.stringify(box)}`);
  for (const i of [3, 250, 999, kps.length - 1]) {
    const k = kps[i];
    // WebDriver pointers move in whole CSS pixels: click the pixel that holds the keypoint.
    const x = Math.round(box.x + (k.x * box.width) / W);
    const y = Math.round(box.y + (k.y * box.height) / H);
    await page.mouseClick(x, y);
    const got = Number(await page.inputValue(tid('feature')));
    // What is under the cursor: the keypoint nearest to the clicked point (the first on ties).
    const ix = ((x - box.x) * W) / box.width;
    const iy = ((y - box.y) * H) / box.height;
    let best = 0;
    let bd = Infinity;
    kps.forEach((q, j) => { const d = (q.x - ix) ** 2 + (q.y - iy) ** 2; if (d < bd) { bd = d; best = j; } });
    assert.equal(got, best, `clicked keypoint ${i}`);
  }
  // Keyboard: focus the frames and step with the arrows.
  await page.focus('.stage');
  const f0 = Number(await page.inputValue(tid('feature')));
  await page.keyboard('ArrowLeft');
  assert.equal(Number(await page.inputValue(tid('feature'))), f0 - 1);
  await page.keyboard('Home');
  assert.equal(await page.inputValue(tid('feature')), '0');
  await page.check(tid('show-all'));
  await page.screenshot(shot('click-select.png'));
});

test('view_feature and view_info exports equal the CLI PNGs byte for byte', async () => {
  await page.goto(`${BASE}?lanes=${LANES}&algo=dt&t=280&feature=42`);
  await idle();
  const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'siftlab-png-'));
  for (const [cmd, id, file] of [['view_feature', 'export-feature', 'opencv_visual.png'], ['view_info', 'export-info', 'custom_visual.png']]) {
    execFileSync(CLI, ['-d', path.join(ROOT, DATASET), cmd, '-a', 'dt', '-t', '280', '1', '42'], { cwd: tmp, encoding: 'utf8' });
    const got = await page.download(() => page.click(tid(id)));
    assert.equal(got.name, file);
    assert.ok(got.bytes.equals(fs.readFileSync(path.join(tmp, file))), `${file} differs from the CLI's`);
    fs.writeFileSync(shot(`export-${file}`), got.bytes);
  }
  fs.rmSync(tmp, { recursive: true });
});
