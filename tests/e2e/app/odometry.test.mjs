// End-to-end tests of the siftlab app (tests/e2e/app/, one file per view; helpers in
// common.mjs), in the engine E2E_ENGINE names, against the native CLI.
// The odometry view: the bundled frames against view_trajectory (poses, PNG, --trace
// counts), a KITTI-layout folder with its sequences and cameras, and the odometry driven by
// the student's matcher (metrics, plot SVG).
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync, spawnSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { ROOT } from '../harness.mjs';
import {
  appSuite, ENGINE, VO_LAST, VO_SHOWN, CLI, DATASET, FRAME, shot, metrics, LANES, BASE, page, tid, idle, tuple, pngDeclaring, cliTrajectory,
} from './common.mjs';

appSuite();

test(`visual odometry on the bundled frames 0 to ${VO_LAST} equals the CLI view_trajectory ${VO_LAST}`, async () => {
  await page.goto(`${BASE}?lanes=${LANES}`);
  await idle();
  // The lab's count: view_trajectory FRAME_ID runs frames 0 … FRAME_ID; the demo is
  // frames 0–150, and the view starts on the manual's view_trajectory 150.
  const ids = fs.readdirSync(path.join(ROOT, DATASET, 'gray/00/image_0')).filter((f) => /^\d{6}\.png$/.test(f)).map((f) => Number(f.slice(0, 6)));
  let last = 0;
  while (ids.includes(last + 1)) last++;
  assert.equal(last, 150);
  assert.equal(await page.inputValue(tid('vo-frame-id')), String(last));
  if (VO_LAST === 150) {
    await page.click(tid('vo-manual-150'));
  } else {
    await page.fill(tid('vo-frame-id'), String(VO_LAST));
    await page.waitForFunction(([sel, w]) => document.querySelector(sel)?.textContent === w,
      [tid('vo-range'), `frames 0 to ${VO_LAST} (${VO_LAST + 1} frames) · available: frames 0 to ${last}`]);
    await page.click(tid('vo-run'));
  }
  await page.waitForSelector(tid('vo-ate'), { timeout: 900000 });
  const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'siftlab-vo-'));
  // The CLI reports the trajectory error with its progress (stdout or stderr: read both).
  const vo = spawnSync(CLI, ['--opencv-lanes', String(LANES), '-d', path.join(ROOT, DATASET), 'view_trajectory', String(VO_LAST),
    '--save-poses', 'poses.txt', '--trace', 'trace.jsonl'], { cwd: tmp, encoding: 'utf8' });
  assert.equal(vo.status, 0, vo.stderr);
  const ate = (vo.stdout + vo.stderr).match(/trajectory error \(ATE RMSE, (\d+) frames\): ([\d.]+) m/);
  assert.equal(ate[1], String(VO_LAST + 1));
  assert.equal(await page.textContent(tid('vo-ate')), `${ate[2]} m`);
  // The run's metrics and KITTI's (two 100 m segments on 0-150): the CLI's summary lines.
  await page.waitForSelector(tid('vo-metrics'), { timeout: 60000 });
  const said = (vo.stdout + vo.stderr).split('\n');
  const head = `LK (${VO_LAST + 1} frames): `;
  assert.equal(await page.textContent(tid('vo-metrics')), said.find((l) => l.startsWith(head)).slice(head.length));
  assert.equal(await page.textContent(tid('vo-kitti')), said.find((l) => l.startsWith('KITTI metric: ')));
  assert.match(await page.textContent(tid('vo-progress')), new RegExp(`frame ${VO_LAST + 1} / ${VO_LAST + 1}`));
  metrics.vo = (await page.textContent('.trajectory')).match(/over \d+ frames · [\d.]+ s( \([\d.]+ frames\/s\))?/)?.[0];
  // The poses, byte for byte the CLI's --save-poses.
  const poses = await page.download(() => page.click(tid('vo-poses')));
  assert.ok(poses.bytes.equals(fs.readFileSync(path.join(tmp, 'poses.txt'))), 'poses.txt differs from the CLI');
  // The lab's window as a PNG: the same bytes the CLI writes.
  const png = await page.download(() => page.click(tid('vo-download')));
  assert.equal(png.name, 'trajectory.png');
  assert.ok(png.bytes.equals(fs.readFileSync(path.join(tmp, 'trajectory.png'))), 'trajectory.png differs from the CLI');
  await page.elementScreenshot('.trajectory', shot('trajectory.png'));
  // The odometry's own view: the frame in the turn, its counts equal to the CLI's trace.
  const trace = fs.readFileSync(path.join(tmp, 'trace.jsonl'), 'utf8').trim().split('\n').map((l) => JSON.parse(l));
  assert.equal(trace.length, VO_LAST + 1);
  // Only the newest frame's points are kept: an older frame's are recomputed by
  // the tracker's worker (from the last frame the loop detected on) when shown.
  metrics.voReplayMs = [];
  const show = async (f) => {
    const t0 = Date.now();
    await page.fill(tid('vo-frame-slider'), String(f));
    await page.waitForSelector(`${tid('vo-step-counts')}[data-frame="${f}"]`, { timeout: 10000 });
    await page.waitForSelector(`${tid('vo-flow')}[data-detail-frame="${f}"]`, { timeout: 30000 });
    return Date.now() - t0;
  };
  for (const f of [VO_SHOWN, VO_LAST, 1]) {
    let ms = await show(f);
    if (f !== VO_LAST) {
      // Issue 44: an old frame is shown within a second in Chromium. A wall-clock time can
      // be another program's: over the second, it is measured twice more (via the newest
      // frame, which is kept) and the fastest counts.
      for (let again = 0; again < 2 && ENGINE === 'chromium' && ms > 1000; again++) {
        await show(VO_LAST);
        ms = Math.min(ms, await show(f));
      }
      metrics.voReplayMs.push(ms);
      if (ENGINE === 'chromium') assert.ok(ms <= 1000, `frame ${f}: its points took ${ms} ms to recompute`);
    }
    assert.equal(await page.evaluate((sel) => document.querySelector(sel)?.textContent ?? null, tid('vo-replay-error')), null,
      `frame ${f}: the replay failed`);
    const got = await page.evaluate((sel) => ({ ...document.querySelector(sel).dataset }), tid('vo-step-counts'));
    const t = trace[f];
    assert.deepEqual([got.tracked, got.inliers, got.poseInliers, got.redetected].map(String),
      [t.tracked, t.essential_inliers, t.pose_inliers, t.redetected].map(String), `frame ${f}`);
    // One segment per tracked point: inliers and outliers together.
    const segs = await page.evaluate((sel) => [...document.querySelectorAll(`${sel} path.flow-line`)]
      .map((p) => (p.getAttribute('d').match(/M/g) || []).length), tid('vo-flow'));
    assert.deepEqual(segs, [t.essential_inliers, t.tracked - t.essential_inliers], `frame ${f}: inlier / outlier segments`);
    if (f === VO_SHOWN) await page.elementScreenshot(tid('vo-own'), shot(`vo-frame-${f}.png`));
  }
  metrics.voFrame = await page.textContent(tid('vo-step-counts'));
  fs.rmSync(tmp, { recursive: true });
  // Past the run: refused with the reason, nothing read.
  await page.fill(tid('vo-frame-id'), '151');
  await page.click(tid('vo-run'));
  assert.match(await page.textContent(tid('vo-error')), /FRAME_ID 151 needs frames 0 to 151 \(152 frames\), but the frames in a row from 0 are frames 0 to 150/);
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

// The bundled frames 0..n as KITTI-layout sequence `seq` under `root` (sequences/SEQ/image_0),
// with `calib` as its calib.txt and the bundled poses as poses/SEQ.txt when `poses`.
function kittiSequence(root, seq, n, { calib, poses = true }) {
  const dir = path.join(root, 'sequences', seq, 'image_0');
  fs.mkdirSync(dir, { recursive: true });
  for (let i = 0; i <= n; i++) fs.copyFileSync(FRAME(i), path.join(dir, path.basename(FRAME(i))));
  if (calib !== undefined) fs.writeFileSync(path.join(root, 'sequences', seq, 'calib.txt'), calib);
  if (poses) {
    fs.mkdirSync(path.join(root, 'poses'), { recursive: true });
    fs.copyFileSync(path.join(ROOT, DATASET, 'poses/00.txt'), path.join(root, 'poses', `${seq}.txt`));
  }
}

// Sequences short enough for every engine: the odometry runs frames 0–VO_SEQ.
const VO_SEQ = Math.min(VO_LAST, 20);

test(`a KITTI-layout folder: sequence choice, its camera from calib.txt, odometry 0-${VO_SEQ} equal to the CLI's -s 03`, async () => {
  const calib03 = fs.readFileSync(path.join(ROOT, 'tests/fixtures/vo_kitti03/calib.txt'), 'utf8');
  const root = fs.mkdtempSync(path.join(os.tmpdir(), 'siftlab-kitti-'));
  const ds = path.join(root, 'dataset');
  kittiSequence(ds, '03', VO_SEQ, { calib: calib03 });
  kittiSequence(ds, '04', 2, {});                                   // no calib.txt
  kittiSequence(ds, '05', 3, { calib: calib03 });                   // frame 2 of another size
  fs.writeFileSync(path.join(ds, 'sequences/05/image_0/000002.png'), pngDeclaring(1226, 370));
  kittiSequence(ds, '06', 3, { calib: calib03, poses: false });     // no ground truth
  kittiSequence(ds, '07', 1, { calib: 'P0: 7.215377e+02 0 6.095593e+02\n' });  // a short P0 line
  await page.goto(`${BASE}?lanes=${LANES}&algo=nndr&t=0.8&feature=42`);
  await idle();
  assert.match(await page.textContent(tid('camera')), /^Sequence 00 \(the lab's MyKITTI layout\) · camera fx = fy = 718\.856, cx = 607\.1928, cy = 185\.2157 the lab's/);
  // Sequence 08 in the lab's layout, without calib.txt: the lab's 00 camera, with a warning.
  fs.mkdirSync(path.join(ds, 'gray/08/image_0'), { recursive: true });
  for (let i = 0; i <= 1; i++) fs.copyFileSync(FRAME(i), path.join(ds, 'gray/08/image_0', path.basename(FRAME(i))));
  await page.setInputFiles(tid('folder'), ds);
  // No sequence 00 here: the folder opens on its first, the lab layout's 08.
  await page.waitForFunction((sel) => /^Sequence 08 /.test(document.querySelector(sel)?.textContent || ''), tid('camera'), { timeout: 60000 });
  assert.match(await page.textContent(tid('camera-warning')), /^warning: gray\/08\/image_0 has no calib\.txt, so sequence 08's odometry uses the lab's sequence-00 camera \(fx = fy = 718\.856/);
  await idle();
  await page.elementScreenshot('.loader', shot('lab-sequence-08.png'));
  await page.selectOption(tid('folder-sequence'), '1');
  await page.waitForFunction((sel) => /from sequences\/03\/calib\.txt/.test(document.querySelector(sel)?.textContent || ''), tid('camera'), { timeout: 60000 });
  assert.ok(await page.evaluate((sel) => document.querySelector(sel) === null, tid('camera-warning')), 'no warning with a calib.txt');
  assert.equal(await page.textContent(tid('camera')), "Sequence 03 (KITTI's odometry layout) · camera fx = fy = 721.5377, cx = 609.5593, cy = 172.854 from sequences/03/calib.txt");
  await idle();
  const cliK = (args, cwd = ROOT) => execFileSync(CLI, ['--opencv-lanes', String(LANES), '-d', ds, ...args], { cwd, encoding: 'utf8', stdio: ['ignore', 'pipe', 'pipe'] });
  const ret = cliK(['-s', '03', 'get_info', '-a', 'nndr', '-t', '0.8', '1', '42']).split('\n').find((l) => l.startsWith('ret value: ')).slice(11);
  assert.equal(await tuple(), ret);
  assert.match(await page.textContent('.slots'), /sequences\/03\/image_0\/000001\.png/);
  const options = await page.evalAll(`${tid('folder-sequence')} option`, (o) => o.textContent);
  assert.deepEqual(options, ['08 · gray/ · 2 frames · no poses', `03 · sequences/ · ${VO_SEQ + 1} frames · poses · calib.txt`, '04 · sequences/ · 3 frames · poses',
    '05 · sequences/ · 4 frames · poses · calib.txt', '06 · sequences/ · 4 frames · no poses · calib.txt',
    '07 · sequences/ · 2 frames · poses · calib.txt']);
  // 04 has no calib.txt: refused with the reason, 03 stays shown and chosen.
  await page.selectOption(tid('folder-sequence'), '2');
  await page.waitForFunction((sel) => /has no sequences\/04\/calib\.txt/.test(document.querySelector(sel)?.textContent || ''), tid('error'));
  assert.match(await page.textContent(tid('camera')), /^Sequence 03 /);
  assert.equal(await page.inputValue(tid('folder-sequence')), '1');
  assert.equal(await tuple(), ret);
  await page.click(`${tid('error')} button.link`);
  await page.selectOption(tid('folder-sequence'), '5');
  await page.waitForFunction((sel) => /sequences\/07\/calib\.txt line 1: P0 has 3 numbers, not 12/.test(document.querySelector(sel)?.textContent || ''), tid('error'));
  assert.equal(await page.inputValue(tid('folder-sequence')), '1');
  // The odometry on 03 with its camera: the CLI's poses and window, byte for byte.
  await page.fill(tid('vo-frame-id'), String(VO_SEQ));
  await page.click(tid('vo-run'));
  await page.waitForSelector(tid('vo-ate'), { timeout: 900000 });
  const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'siftlab-vo03-'));
  const out = spawnSync(CLI, ['--opencv-lanes', String(LANES), '-d', ds, '-s', '03', 'view_trajectory', String(VO_SEQ), '--save-poses', 'poses.txt'], { cwd: tmp, encoding: 'utf8' });
  assert.equal(out.status, 0, out.stderr);
  assert.doesNotMatch(out.stderr, /camera: /, 'the camera comes from calib.txt');
  const poses = await page.download(() => page.click(tid('vo-poses')));
  assert.ok(poses.bytes.equals(fs.readFileSync(path.join(tmp, 'poses.txt'))), 'poses.txt differs from the CLI -s 03');
  const png = await page.download(() => page.click(tid('vo-download')));
  assert.ok(png.bytes.equals(fs.readFileSync(path.join(tmp, 'trajectory.png'))), 'trajectory.png differs from the CLI -s 03');
  // ... and not the 00 camera's run on the same frames.
  const lab = spawnSync(CLI, ['--opencv-lanes', String(LANES), '-d', path.join(ROOT, DATASET), 'view_trajectory', String(VO_SEQ), '--save-poses', 'lab.txt'], { cwd: tmp, encoding: 'utf8' });
  assert.equal(lab.status, 0, lab.stderr);
  assert.ok(!poses.bytes.equals(fs.readFileSync(path.join(tmp, 'lab.txt'))), 'the camera changes the odometry');
  await page.elementScreenshot('.loader', shot('kitti-sequence.png'));
  // 05: frames of two sizes; 06: no poses. Each says why; the page stays usable.
  await page.selectOption(tid('folder-sequence'), '3');
  await page.waitForFunction((sel) => /^Sequence 05 /.test(document.querySelector(sel)?.textContent || ''), tid('camera'));
  await idle();
  await page.fill(tid('vo-frame-id'), '3');
  await page.click(tid('vo-run'));
  await page.waitForSelector(tid('vo-error'), { timeout: 60000 });
  assert.match(await page.textContent(tid('vo-error')), /frame 2 \(sequences\/05\/image_0\/000002\.png\) is 1226x370 but frame 0 is 1241x376: every frame of a sequence must have the same size/);
  await page.selectOption(tid('folder-sequence'), '4');
  await page.waitForFunction((sel) => /^Sequence 06 .*no ground-truth poses$/.test(document.querySelector(sel)?.textContent || ''), tid('camera'));
  await idle();
  await page.fill(tid('vo-frame-id'), '3');
  await page.click(tid('vo-run'));
  await page.waitForFunction((sel) => /the folder has no poses\/06\.txt/.test(document.querySelector(sel)?.textContent || ''), tid('vo-error'), { timeout: 60000 });
  await page.selectOption(tid('folder-sequence'), '1');
  await page.waitForFunction((sel) => /^Sequence 03 /.test(document.querySelector(sel)?.textContent || ''), tid('camera'));
  await idle();
  assert.equal(await tuple(), ret);
  fs.rmSync(tmp, { recursive: true });
  fs.rmSync(root, { recursive: true });
});

// The matcher-driven run on frames 0-29 at most: what it adds to the LK run above (which
// checks the metrics and KITTI's on 0-150) is the student's matcher as the tracker, its
// summary, the SVG plot and its hover; the figures are the core's, as the LK run's.
const MATCHED_LAST = Math.min(VO_LAST, 29);
test(`odometry with the student's matcher (nndr 0.8, frames 0-${MATCHED_LAST}) equals the CLI: metrics, plot SVG`, async () => {
  await page.goto(`${BASE}?lanes=${LANES}`);
  await idle();
  await page.selectOption(tid('vo-tracker'), 'nndr');
  assert.equal(await page.inputValue(tid('vo-threshold')), '0.8');
  await page.fill(tid('vo-frame-id'), String(MATCHED_LAST));
  await page.click(tid('vo-run'));
  await page.waitForSelector(tid('vo-metrics'), { timeout: 900000 });
  const ref = cliTrajectory(['-a', 'nndr', '-t', '0.8', String(MATCHED_LAST)]);
  // stderr: "nndr 0.8 (N frames): ATE … · KITTI …", the page shows the same summary.
  const head = `nndr 0.8 (${MATCHED_LAST + 1} frames): `;
  const line = ref.stderr.split('\n').find((l) => l.startsWith(head));
  assert.equal(await page.textContent(tid('vo-metrics')), line.slice(head.length));
  assert.equal(await page.textContent(tid('vo-ate')), `${ref.metrics.ate_rmse.toFixed(4)} m`);
  assert.equal(await page.textContent(tid('vo-kitti')), ref.stderr.split('\n').find((l) => l.startsWith('KITTI metric: ')));
  metrics.voMatched = (await page.textContent('.trajectory')).match(/over \d+ frames · [\d.]+ s( \([\d.]+ frames\/s\))?/)?.[0];
  // The figures are the core's: the exported SVG is the CLI's --plot, byte for byte
  // (so every position agrees to the plot's 0.01 px).
  const svg = await page.download(() => page.click(tid('vo-svg')));
  assert.equal(svg.name, 'vo.svg');
  fs.writeFileSync(shot('vo-export.svg'), svg.bytes);
  assert.ok(svg.bytes.equals(ref.svg), 'the app\'s SVG differs from the CLI\'s --plot');
  const png = await page.download(() => page.click(tid('vo-png')));
  assert.equal(png.bytes.subarray(1, 4).toString('latin1'), 'PNG');
  fs.writeFileSync(shot('vo-export.png'), png.bytes);
  // Hover over the top view names a frame, its position and error.
  const box = await page.boundingBox(tid('vo-plot'));
  await page.mouseMove(box.x + box.width / 2, box.y + box.height * 0.3);
  await page.waitForFunction((sel) => /^frame \d+ · /.test(document.querySelector(sel)?.textContent || ''), tid('vo-hover'));
  assert.match(await page.textContent(tid('vo-hover')), /^frame \d+ · x=-?[\d.]+ y=-?[\d.]+ z=-?[\d.]+ m · error [\d.]+ m$/);
  await page.elementScreenshot('.trajectory .vo-views', shot('vo-matched.png'));
});
