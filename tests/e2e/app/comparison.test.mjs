// End-to-end tests of the siftlab app (tests/e2e/app/, one file per view; helpers in
// common.mjs), in the engine E2E_ENGINE names, against the native CLI.
// The odometry comparison view: LK, dt 200, nn and nndr 0.8 against the CLI's metrics.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import {
  appSuite, COMPARE_LAST, shot, metrics, LANES, BASE, page, tid, idle, cliTrajectory,
} from './common.mjs';

appSuite();

test(`comparison view: LK, dt 200, nn, nndr 0.8 on frames 0-${COMPARE_LAST}, metrics (KITTI included) equal the CLI's`, async () => {
  await page.goto(`${BASE}?lanes=${LANES}`);
  await idle();
  await page.fill(tid('vo-frame-id'), String(COMPARE_LAST));
  const t0 = Date.now();
  await page.click(tid('vo-compare-run'));
  await page.waitForFunction((sel) => document.querySelector(sel)?.textContent === '4 runs done', tid('vo-compare-status'), { timeout: 1800000, what: 'the four runs' });
  metrics.compareWallS = (Date.now() - t0) / 1000;
  const rows = await page.evalAll(tid('vo-compare-row'), (tr) => [...tr.children].map((td) => td.textContent));
  assert.deepEqual(rows.map((r) => r[0]), ['LK', 'dt 200', 'nn', 'nndr 0.8']);
  const args = { LK: [], 'dt 200': ['-a', 'dt', '-t', '200'], nn: ['-a', 'nn'], 'nndr 0.8': ['-a', 'nndr', '-t', '0.8'] };
  metrics.compareFps = {};
  // All four equal the CLI (on longer runs, dt 200 included: its frame-96 RANSAC sample is one
  // where the last bit of hypot picks the model; core/tests/essential_matrix.rs, §VO-8).
  for (const r of rows) {
    const m = cliTrajectory([...args[r[0]], String(COMPARE_LAST)]).metrics;
    assert.deepEqual(r.slice(1, 5), [m.ate_rmse.toFixed(4), m.ate_rmse_aligned.toFixed(4), m.rpe_trans_rmse.toFixed(4), m.rpe_rot_rmse_deg.toFixed(4)], r[0]);
    // KITTI's figures need 100 m of path (frames 0-150 hold 110 m); a shorter run has none: n/a.
    const kitti = m.kitti_segments > 0 ? [m.kitti_t_err_pct.toFixed(2), m.kitti_r_err_deg_per_100m.toFixed(3)] : ['n/a', 'n/a'];
    assert.deepEqual(r.slice(5, 7), kitti, `${r[0]}: KITTI on ${m.kitti_segments} segments`);
    metrics.compareFps[r[0]] = Number(r[7]);
  }
  const note = await page.textContent(tid('vo-compare-kitti'));
  const seg = cliTrajectory([String(COMPARE_LAST)]).stderr.split('\n').find((l) => l.startsWith('KITTI metric: '));
  assert.ok(note.startsWith(seg), `${note} / ${seg}`);
  metrics.compareKitti = seg;
  // Truth and four runs overlaid, with a legend naming them.
  const svg = await page.innerHTML(tid('vo-compare-plot'));
  for (const name of ['ground truth', 'LK', 'dt 200', 'nn', 'nndr 0.8']) assert.ok(svg.includes(`>${name}</text>`), name);
  assert.equal((svg.match(/<polyline/g) || []).length, 5);
  await page.elementScreenshot('.vo-compare', shot('vo-compare.png'));
});
