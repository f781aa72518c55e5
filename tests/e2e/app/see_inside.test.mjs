// End-to-end tests of the siftlab app (tests/e2e/app/, one file per view; helpers in
// common.mjs), in the engine E2E_ENGINE names, against the native CLI.
// See inside: the whole-frame counts (match_all) and the SIFT anatomy against the CLI.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { ROOT } from '../harness.mjs';
import {
  appSuite, CLI, DATASET, FRAME, shot, metrics, LANES, BASE, page, tid, idle,
} from './common.mjs';

appSuite();

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
    metrics.wholeFrame[`${algo} ${t || 'none'}`] = { matches: want.matches, correct: want.correct, precision: want.precision };
    if (algo === 'nndr') {
      metrics.sweepStatus = (await page.textContent(tid('wf-status'))).trim();
      await page.elementScreenshot('.see-inside', shot('whole-frame.png'));
    }
  }
  metrics.crossings120 = (await page.textContent(tid('crossings'))).trim();
  // The view is in the link: see=matches and the current setting.
  assert.match(await page.url(), /see=matches/);

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
  assert.equal(await page.count(`${tid('pyramid')} canvas.level`), want.octaves * 11);
  await page.waitForSelector(tid('orientation-hist'), { timeout: 180000 });
  metrics.anatomyStatus = (await page.textContent(tid('anatomy-status'))).trim();
  await page.elementScreenshot('.see-inside', shot('anatomy.png'));
  fs.rmSync(tmp, { recursive: true });
});
