// End-to-end tests of the siftlab app (tests/e2e/app/, one file per view; helpers in
// common.mjs), in the engine E2E_ENGINE names, against the native CLI.
// "Class results": a class's summary.json (from `siftlab mark --out`) picked in the view:
// the statuses, tasks and mistakes as summary.json has them, and a mistake's example link
// opens the explorer on that case (its tuple is `get_info`'s).
import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import {
  appSuite, shot, cliRet8, BASE, LANES, page, tid, idle, tuple, classSummary,
} from './common.mjs';

appSuite();

test('class results: a file that is not a summary says so; summary.json shown as the CLI wrote it; a mistake\'s link opens its case', async () => {
  const { summary, file } = classSummary();
  await page.goto(`${BASE}?lanes=${LANES}`);
  await idle();
  // Not a class summary: a message, nothing shown, the page usable.
  const bad = file.replace(/summary\.json$/, 'package.json');
  fs.writeFileSync(bad, '{"name": "not a summary"}');
  await page.setInputFiles(tid('class-file'), bad);
  await page.waitForSelector(tid('class-error'), { timeout: 30000 });
  assert.match(await page.textContent(tid('class-error')), /not a siftlab class summary/);
  assert.equal(await page.count(tid('class-summary')), 0);
  await page.setInputFiles(tid('class-file'), file);
  await page.waitForSelector(tid('class-summary'), { timeout: 30000 });
  assert.equal(await page.count(tid('class-error')), 0);
  const statuses = Object.fromEntries(await page.evalAll(tid('class-status'), (tr) => [tr.dataset.status, Number(tr.dataset.n)]));
  assert.deepEqual(statuses, summary.status);
  const tasks = await page.evalAll(tid('class-task'), (tr) => [tr.dataset.task, Number(tr.dataset.calls), Number(tr.dataset.correct)]);
  assert.deepEqual(tasks, summary.tasks.map((t) => [t.task, t.calls, t.correct]));
  const mistakes = await page.evalAll(tid('class-mistake'), (tr) => [tr.dataset.code, Number(tr.dataset.students), Number(tr.dataset.cases)]);
  assert.deepEqual(mistakes, summary.mistakes.map((m) => [m.code, m.students, m.cases]));
  assert.ok(mistakes.length >= 2, JSON.stringify(summary.mistakes));
  await page.elementScreenshot(tid('class'), shot('class-results.png'));
  // The first mistake's first example: the explorer on its pair, strategy, threshold and feature.
  const href = await page.getAttribute(`${tid('class-mistake')} ${tid('class-case-link')}`, 'href');
  assert.equal(href, summary.mistakes[0].examples[0].link);
  const q = new URLSearchParams(href);
  await page.goto(`${BASE}${href}&lanes=${LANES}`);
  await idle();
  assert.equal(await page.inputValue(tid('frame-id')), q.get('frame'));
  assert.equal(await page.inputValue(tid('feature')), q.get('feature'));
  const t = q.get('t');
  assert.equal(await tuple(), cliRet8(['-a', q.get('algo'), ...(t ? ['-t', t] : []), q.get('frame'), q.get('feature')]), href);
});
