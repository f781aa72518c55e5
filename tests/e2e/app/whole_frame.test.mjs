// End-to-end tests of the siftlab app (tests/e2e/app/, one file per view; helpers in
// common.mjs), in the engine E2E_ENGINE names, against the native CLI.
// The whole-frame flow view on 119→120: a picked match, its epipolar line and Sampson distance.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { ROOT } from '../harness.mjs';
import {
  appSuite, CLI, DATASET, shot, metrics, LANES, cliSift, BASE, page, tid, idle,
} from './common.mjs';

appSuite();

test('whole-frame flow on 119→120: a picked match shows its epipolar line and the CLI\'s Sampson distance', async () => {
  const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'siftlab-pick-'));
  const cliMatchAll = (algo, t) => JSON.parse(execFileSync(CLI,
    ['--opencv-lanes', String(LANES), '-d', path.join(ROOT, DATASET), 'match_all', '-a', algo, '-t', t, '--json', '120'],
    { cwd: tmp, encoding: 'utf8', stdio: ['ignore', 'pipe', 'pipe'], maxBuffer: 1 << 26 }));
  await page.goto(`${BASE}?lanes=${LANES}&src=demo&frame=120&algo=nndr&t=0.8&see=matches`);
  await idle();
  const want = cliMatchAll('nndr', '0.8');
  await page.waitForSelector(`${tid('wf-counts')}[data-matches="${want.matches}"]`, { timeout: 180000 });
  assert.equal(want.records.length, want.matches);
  assert.ok(await page.evaluate((sel) => document.querySelector(sel).checked, tid('wf-layout-flow')), 'flow is the default layout');
  const canvas = await page.evaluate((sel) => { const c = document.querySelector(sel); return [c.width, c.height]; }, tid('wf-canvas'));
  assert.deepEqual(canvas, [1241, 376], 'flow: the current frame only');
  await page.elementScreenshot('.whole-frame', shot('flow-nndr-0.8.png'));
  const byPair = new Map(want.records.map((r) => [`${r.query}/${r.train}`, r]));
  const pickedIs = async () => {
    const d = await page.evaluate((sel) => ({ ...document.querySelector(sel).dataset }), tid('wf-pick'));
    const r = byPair.get(`${d.query}/${d.train}`);
    assert.ok(r, `the picked ${d.query} → ${d.train} is one of the CLI's matches`);
    // Same f64 on both sides: the core's Sampson distance, natively and in wasm.
    assert.equal(Number(d.sampson), r.sampson, `Sampson of ${d.query} → ${d.train}`);
    assert.equal(d.distance, String(r.distance));
    assert.match(await page.textContent(tid('wf-pick-verdict')), new RegExp(`: ${r.correct ? 'correct' : 'wrong'}$`));
    assert.equal(await page.count('svg.wf-overlay line.epipolar'), 1, 'the epipolar line is drawn');
    return r;
  };
  // Keys step through the matches shown.
  await page.focus(tid('wf-stage'));
  await page.keyboard('ArrowRight');
  await page.waitForSelector(tid('wf-pick'), { timeout: 10000 });
  const first = await pickedIs();
  await page.keyboard('ArrowRight');
  await page.waitForFunction(([sel, q, t]) => { const d = document.querySelector(sel)?.dataset; return d && `${d.query}/${d.train}` !== `${q}/${t}`; },
    [tid('wf-pick'), first.query, first.train], { timeout: 10000 });
  await pickedIs();
  // The filter: only the wrong ones; a click on one's current end picks it.
  await page.click(tid('wf-filter-wrong'));
  const wrong = want.records.filter((r) => r.correct === false);
  assert.ok(wrong.length > 0);
  const target = wrong[0];
  const kp = cliSift(120).keypoints[target.train];
  const box = await page.boundingBox(tid('wf-canvas'));
  await page.mouseClick(box.x + kp.x * box.width / 1241, box.y + kp.y * box.height / 376);
  await page.waitForFunction(([sel, q, t]) => { const d = document.querySelector(sel)?.dataset; return d && d.query === String(q) && d.train === String(t); },
    [tid('wf-pick'), target.query, target.train], { timeout: 10000, what: `the wrong match ${target.query} → ${target.train}` });
  const r = await pickedIs();
  assert.equal(r.correct, false);
  metrics.pickedWrong = await page.textContent(tid('wf-pick'));
  await page.elementScreenshot('.whole-frame', shot('flow-nndr-0.8-picked-wrong.png'));
  // dt 300 on the same pair: all matches under 300, far more of them wrong.
  await page.click(tid('wf-filter-all'));
  await page.selectOption(tid('algo'), 'dt');
  await page.fill(tid('threshold'), '300');
  const dt = cliMatchAll('dt', '300');
  await page.waitForSelector(`${tid('wf-counts')}[data-matches="${dt.matches}"]`, { timeout: 180000 });
  assert.equal(await page.getAttribute(tid('wf-counts'), 'data-correct'), String(dt.correct));
  await page.elementScreenshot('.whole-frame', shot('flow-dt-300.png'));
  // The side-by-side layout stays available.
  await page.click(tid('wf-layout-side'));
  await page.waitForFunction((sel) => document.querySelector(sel)?.width === 2482, tid('wf-canvas'), { timeout: 10000 });
  fs.rmSync(tmp, { recursive: true });
});
