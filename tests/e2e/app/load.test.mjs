// End-to-end tests of the siftlab app (tests/e2e/app/, one file per view; helpers in
// common.mjs), in the engine E2E_ENGINE names, against the native CLI.
// Loading frames: the opening KITTI pair fetched lazily with its attribution, bad files and
// folders refused inline, two frames by picker and by drag and drop, the narrow layout.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { ROOT } from '../harness.mjs';
import {
  appSuite, DATASET, FRAME, shot, LANES, cliRet, cliRet8, cliSift, BASE, page, tid, idle, settings, tuple, tupleIs, pngDeclaring,
} from './common.mjs';

appSuite();

test('the page opens on real KITTI frames 0/1, fetching only those two frames, with the attribution', async () => {
  await page.goto(BASE);
  await idle();
  assert.match(await page.textContent('.slots'), /000000\.png[\s\S]*000001\.png/);
  const sift = [0, 1].map((id) => cliSift(id, 8));
  assert.equal(await page.textContent(tid('keypoint-count-prev')), String(sift[0].keypoints.length));
  assert.equal(await page.inputValue(tid('feature')), '1256');
  assert.equal(await tuple(), cliRet8(['-a', 'nndr', '-t', '0.8', '1', '1256']));
  assert.notEqual(await tuple(), '((0, 0), [], [])');
  // Frames load lazily: of the bundled frames, the page fetched the pair it shows (the
  // page's and its workers' requests: the workers receive bytes, they fetch nothing).
  const fetched = await page.evaluate(() => performance.getEntriesByType('resource').map((e) => new URL(e.name).pathname).filter((p) => p.startsWith('/demo/')));
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
  await page.screenshot(shot('opening.png'), { fullPage: true });
});

test('bad files and folders show an inline error and keep what was loaded', async () => {
  await page.goto(`${BASE}?lanes=${LANES}&algo=nndr&t=0.8&feature=42`);
  await idle();
  const before = await tuple();
  const countCur = await page.textContent(tid('keypoint-count-cur'));
  const cases = [
    [{ name: 'notes.txt', buffer: Buffer.from('hello, not an image') }, /not an image/],
    [{ name: 'truncated.png', buffer: fs.readFileSync(FRAME(2)).subarray(0, 20000) }, /corrupt or truncated/],
    [{ name: 'huge.png', buffer: pngDeclaring(5000, 4000) }, /20000000 pixels, above the limit of 16000000/],
  ];
  for (const [file, message] of cases) {
    await page.setInputFiles(tid('frame-cur'), file);
    await page.waitForSelector(tid('error'));
    await idle();
    assert.match(await page.textContent(tid('error')), message);
    assert.equal(await tuple(), before, 'the previous result stays');
    assert.equal(await page.textContent(tid('keypoint-count-cur')), countCur);
    await page.click(`${tid('error')} button.link`);
    await page.waitForSelector(tid('error'), { state: 'detached' });
  }
  await page.screenshot(shot('error.png'));
  // A folder without the MyKITTI layout.
  const junk = fs.mkdtempSync(path.join(os.tmpdir(), 'siftlab-e2e-'));
  fs.writeFileSync(path.join(junk, 'readme.txt'), 'not a dataset');
  await page.setInputFiles(tid('folder'), junk);
  await page.waitForFunction((sel) => /MyKITTI layout/.test(document.querySelector(sel)?.textContent || ''), tid('error'));
  assert.equal(await tuple(), before);
  // The real layout works, and a missing frame is named.
  await page.setInputFiles(tid('folder'), path.join(ROOT, DATASET));
  await page.waitForSelector(tid('error'), { state: 'detached', timeout: 60000 });
  await idle();
  assert.equal(await tuple(), cliRet(['-a', 'nndr', '-t', '0.8', '1', '42']));
  await page.fill(tid('frame-id'), '160');
  await page.press(tid('frame-id'), 'Enter');
  await page.waitForFunction((sel) => (document.querySelector(sel)?.textContent || '').includes(
    'FRAME_ID 160 needs frames 159 and 160: frames 159 and 160 are not in the folder, which has frames 0–150'), tid('error'));
  await page.fill(tid('frame-id'), '3');
  await page.press(tid('frame-id'), 'Enter');
  await page.waitForFunction(() => /000003\.png/.test(document.querySelector('.slots')?.textContent || ''), undefined, { timeout: 180000 });
  await idle();
  assert.equal(await tuple(), cliRet(['-a', 'nndr', '-t', '0.8', '3', '42']));
  assert.equal(await page.has(tid('error')), false, 'a pair that is there settles the message');
  // And a good file after the bad ones: the app still works.
  await page.setInputFiles(tid('frame-cur'), FRAME(5));
  await page.waitForFunction((sel) => /000005\.png/.test(document.querySelector(sel)?.textContent || ''), '.slots', { timeout: 180000 });
  await idle();
  assert.equal(await page.textContent(tid('keypoint-count-cur')), String(cliSift(5).keypoints.length));
  assert.ok((await tuple()).startsWith('(('));
  fs.rmSync(junk, { recursive: true });
});

test('two frames by picker and by drag and drop equal the CLI on that pair', async () => {
  await page.goto(`${BASE}?lanes=${LANES}&algo=nndr&t=0.8&feature=42`);
  await idle();
  await page.setInputFiles(tid('frame-prev'), FRAME(7));
  await page.waitForFunction(() => /000007\.png/.test(document.querySelector('.slots')?.textContent || ''), undefined, { timeout: 180000 });
  // The current frame dropped onto its slot, as a file dragged from the desktop.
  await page.dropFile('.slot:nth-child(2)', FRAME(8));
  await page.waitForFunction(() => /000008\.png/.test(document.querySelector('.slots')?.textContent || ''), undefined, { timeout: 180000 });
  await idle();
  assert.equal(await page.textContent(tid('keypoint-count-prev')), String(cliSift(7).keypoints.length));
  assert.equal(await page.textContent(tid('keypoint-count-cur')), String(cliSift(8).keypoints.length));
  await settings('nndr', '0.8', 42);
  await tupleIs(cliRet(['-a', 'nndr', '-t', '0.8', '8', '42']));
});

test('narrow screen layout', async () => {
  await page.setViewportSize({ width: 760, height: 1000 });
  await page.goto(`${BASE}?lanes=${LANES}&feature=300`);
  await idle();
  await page.screenshot(shot('narrow.png'), { fullPage: true });
});
