// End-to-end tests of the siftlab app (tests/e2e/app/, one file per view; helpers in
// common.mjs), in the engine E2E_ENGINE names, against the native CLI.
// Check my answer and the seeded exercises.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { sleep } from '../harness.mjs';
import {
  appSuite, shot, LANES, cliRet, BASE, page, tid, idle,
} from './common.mjs';

appSuite();

test('check my answer and a seeded exercise', async () => {
  // Checked the moment the result appears, not once the page is idle: the verdict
  // stays while the page finishes loading (it answers the same question).
  await page.goto(`${BASE}?lanes=${LANES}&algo=nn&feature=77`);
  const right = cliRet(['-a', 'nn', '1', '77']);
  await page.waitForFunction((sel) => (document.querySelector(sel)?.textContent || '').startsWith('(('), tid('result-tuple'), { timeout: 180000 });
  await page.fill(tid('answer'), `ret value: ${right}`);
  await page.click(tid('check'));
  assert.match(await page.textContent(tid('check-result')), /Correct/);
  await idle();
  await sleep(1000);
  assert.match(await page.textContent(tid('check-result')), /Correct/, 'the verdict was cleared by a recomputation');
  // Float query coordinates (no int()): the diagnosis names it.
  const wrong = right.replace(/^\(\((\d+), (\d+)\)/, (m, x, y) => `((${x}.5, ${y}.25)`);
  assert.notEqual(wrong, right);
  await page.fill(tid('answer'), wrong);
  await page.click(tid('check'));
  assert.match(await page.textContent(tid('check-result')), /int\(\)/);
  await page.screenshot(shot('selfcheck.png'), { fullPage: true });
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
  const link = await page.url();
  assert.match(link, /ex=\d+&q=1/);
  await page.screenshot(shot('exercise.png'), { fullPage: true });
  // The same link gives the same question.
  await page.goto(link);
  await page.waitForFunction((sel) => /get_info -a \S+ .*\d+ \d+\?/.test(document.querySelector(sel)?.textContent || ''), tid('question'), { timeout: 180000 });
  assert.equal(await page.textContent(tid('question')), q);
});
