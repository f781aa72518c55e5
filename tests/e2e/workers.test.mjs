// Every worker count gives the CLI's numbers (Chromium, Playwright). The page sizes its SIFT
// pool from the machine (cores − 1, 2 to 8) unless the address says `workers=N`; the
// odometry and the comparison take each frame's SIFT from that pool, so this checks, for
// N = 1, 2, 3 and 8 on whatever machine runs it:
// - the odometry view's poses.txt (LK) equals `view_trajectory --save-poses`, byte for byte;
// - the comparison's four runs (LK, dt 200, nn, nndr 0.8) each equal the CLI's
//   `--save-poses` byte for byte, and its table the CLI's metrics;
// - the page says how many workers ran.
// E2E_WORKERS_FRAMES (default 30) sets the run length: frames 0 … N−1.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { serve, ROOT, launchChromium } from './harness.mjs';

const CLI = process.env.SIFTLAB_CLI || path.join(ROOT, 'target/release/siftlab');
const DEMO = path.join(ROOT, 'www/demo/MyKITTI');
const FRAMES = Number(process.env.E2E_WORKERS_FRAMES || 30);
const LAST = FRAMES - 1;
const RUNS = { LK: [], 'dt 200': ['-a', 'dt', '-t', '200'], nn: ['-a', 'nn'], 'nndr 0.8': ['-a', 'nndr', '-t', '0.8'] };
const tid = (id) => `[data-testid="${id}"]`;

let browser;
let server;
const cli = {};

before(async () => {
  server = await serve(path.join(ROOT, 'dist'), { hooks: false });
  browser = await launchChromium();
  // The CLI's poses and metrics for each tracker on the same frames.
  for (const [name, args] of Object.entries(RUNS)) {
    const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'siftlab-workers-'));
    const r = spawnSync(CLI, ['-d', DEMO, 'view_trajectory', ...args, String(LAST), '--save-poses', 'p.txt', '--metrics', 'm.json', '--output', '/dev/null'],
      { cwd: tmp, encoding: 'utf8' });
    assert.equal(r.status, 0, r.stderr);
    cli[name] = { poses: fs.readFileSync(path.join(tmp, 'p.txt'), 'utf8'), metrics: JSON.parse(fs.readFileSync(path.join(tmp, 'm.json'), 'utf8')) };
    fs.rmSync(tmp, { recursive: true });
  }
});
after(async () => {
  await browser?.close();
  await server?.close();
});

async function download(page, selector) {
  const [dl] = await Promise.all([page.waitForEvent('download'), page.click(selector)]);
  return fs.readFileSync(await dl.path(), 'utf8');
}

for (const n of [1, 2, 3, 8]) {
  test(`workers=${n}: odometry and comparison on frames 0-${LAST} equal the CLI`, async () => {
    const context = await browser.newContext({ viewport: { width: 1400, height: 900 }, acceptDownloads: true });
    const page = await context.newPage();
    const errors = [];
    page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
    page.on('pageerror', (e) => errors.push(String(e)));
    await page.goto(`${server.base}?workers=${n}`);
    await page.waitForSelector(tid('keypoint-count-cur'), { timeout: 300000 });
    await page.fill(tid('vo-frame-id'), String(LAST));
    await page.click(tid('vo-run'));
    await page.waitForSelector(tid('vo-ate'), { timeout: 900000 });
    assert.equal(await download(page, tid('vo-poses')), cli.LK.poses, 'LK poses');
    assert.match(await page.textContent(tid('vo-workers')), new RegExp(`^SIFT on ${n} worker${n === 1 ? '' : 's'}, each up to \\d+ MB`));

    await page.click(tid('vo-compare-run'));
    await page.waitForFunction((sel) => document.querySelector(sel)?.textContent === '4 runs done', tid('vo-compare-status'), { timeout: 1800000 });
    const rows = await page.$$eval(tid('vo-compare-row'), (trs) => trs.map((tr) => [...tr.children].map((td) => td.textContent)));
    assert.deepEqual(rows.map((r) => r[0]), Object.keys(RUNS));
    for (const [k, row] of rows.entries()) {
      const m = cli[row[0]].metrics;
      assert.deepEqual(row.slice(1, 5), [m.ate_rmse, m.ate_rmse_aligned, m.rpe_trans_rmse, m.rpe_rot_rmse_deg].map((v) => v.toFixed(4)), row[0]);
      const poses = await download(page, `${tid('vo-compare-row')}:nth-child(${k + 1}) ${tid('vo-compare-poses')}`);
      assert.equal(poses, cli[row[0]].poses, `${row[0]} poses`);
    }
    assert.deepEqual(errors, []);
    await context.close();
  });
}
