// Checks a W3C WebDriver session cannot make, in Chromium only, with Playwright (npm
// playwright-core driving Debian's Chromium over CDP). The full suite (app/*.test.mjs) runs
// in all three engines; what it cannot see there is seen here:
// - requests made by the page's Web Workers (Resource Timing and CSP events in the page
//   cover the page only): every request of page and workers stays on our origin;
// - the workers' own consoles (WebKitGTK's driver has no BiDi; the page's hooks see a
//   worker's uncaught errors only);
// - a real browser download of the app's <a download> links (the suite's hooks read the
//   bytes in the page instead).
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { serve, ROOT, launchChromium } from './harness.mjs';
import { classSummary } from './app/common.mjs';

let browser;
let server;

before(async () => {
  // Served as the real site is (no test hooks in index.html): the hooks are the suite's.
  server = await serve(path.join(ROOT, 'dist'), { hooks: false });
  browser = await launchChromium();
});
after(async () => {
  await browser?.close();
  await server?.close();
});

test('page and workers: every request on our origin, no console error, real downloads', async () => {
  const origin = new URL(server.base).origin;
  const context = await browser.newContext({ viewport: { width: 1400, height: 900 }, acceptDownloads: true });
  const offOrigin = [];
  const errors = [];
  context.on('request', (r) => {
    const u = r.url();
    if (!u.startsWith('data:') && !u.startsWith('blob:') && new URL(u).origin !== origin) offOrigin.push(u);
  });
  const page = await context.newPage();
  const onConsole = (m) => { if (m.type() === 'error') errors.push(m.text()); };
  page.on('console', onConsole);
  page.on('pageerror', (e) => errors.push(String(e)));
  let workers = 0;
  page.on('worker', (w) => { workers++; w.on('console', onConsole); });
  const tid = (id) => `[data-testid="${id}"]`;

  await page.goto(`${server.base}?src=demo&frame=120&algo=nndr&t=0.8&see=matches`);
  await page.waitForSelector(tid('wf-counts'), { timeout: 180000 });
  await page.waitForSelector(tid('busy'), { state: 'detached', timeout: 180000 });
  // A short odometry run: its detection helpers are workers too.
  await page.fill(tid('vo-frame-id'), '5');
  await page.click(tid('vo-run'));
  await page.waitForSelector(tid('vo-ate'), { timeout: 300000 });
  const [download] = await Promise.all([page.waitForEvent('download'), page.click(tid('vo-download'))]);
  assert.equal(download.suggestedFilename(), 'trajectory.png');
  const png = fs.readFileSync(await download.path());
  assert.equal(png.subarray(1, 4).toString('latin1'), 'PNG');
  await context.close();

  assert.ok(workers >= 2, `the page started ${workers} workers`);
  assert.deepEqual(offOrigin, [], 'requests left the origin');
  assert.deepEqual(errors, [], 'console errors in the page or its workers');
});

// What a student does before the data has arrived (issue 42), made deterministic by
// holding the demo's frame list and frame 1 back (Playwright's routing; the suite's
// engines cannot hold a request):
// - a FRAME_ID typed in the odometry before the frame list arrives stays;
// - "Check my answer" pressed while the frames are computed says so, then checks.
test('input before the data arrives: an early FRAME_ID stays, an early check waits', async () => {
  const context = await browser.newContext({ viewport: { width: 1400, height: 900 } });
  const tid = (id) => `[data-testid="${id}"]`;
  const held = async (glob) => {
    let release;
    const gate = new Promise((r) => { release = r; });
    await context.route(glob, async (route) => { await gate; await route.continue(); });
    return release;
  };
  const releaseIndex = await held('**/demo/index.txt');
  const releaseFrame = await held('**/gray/00/image_0/000001.png');
  const page = await context.newPage();
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  await page.goto(server.base);
  await page.waitForSelector(tid('vo-frame-id'));
  assert.match(await page.textContent(tid('vo-range')), /no frame 0/, 'the frame list arrived before the test typed');
  await page.fill(tid('vo-frame-id'), '40');
  releaseIndex();
  await page.waitForFunction((sel) => (document.querySelector(sel)?.textContent || '').includes('available: frames 0 to 150'),
    tid('vo-range'), { timeout: 60000 });
  assert.equal(await page.inputValue(tid('vo-frame-id')), '40', 'the typed FRAME_ID was overwritten by the default');
  assert.match(await page.textContent(tid('vo-range')), /^frames 0 to 40 \(41 frames\)/);
  // Frame 1 is still held: the answer waits for the result, then gets its verdict.
  await page.fill(tid('answer'), 'ret value: ((1, 2), [(3, 4)], [5.0])');
  await page.click(tid('check'));
  await page.waitForSelector(tid('check-pending'), { timeout: 5000 });
  assert.equal(await page.$(tid('check-result')), null, 'a verdict before the frames were computed');
  releaseFrame();
  await page.waitForSelector(tid('check-result'), { timeout: 180000 });
  assert.match(await page.textContent(tid('check-result')), /\S/);
  assert.equal(await page.$(tid('check-pending')), null, 'still pending after the verdict');
  await context.close();
  assert.deepEqual(errors, []);
});

test('summary.html from disk with the network off: renders the summary, no request, no console error', async () => {
  const { summary, html } = classSummary();
  const context = await browser.newContext({ viewport: { width: 1400, height: 900 }, offline: true });
  const requests = [];
  const errors = [];
  context.on('request', (r) => { if (!r.url().startsWith('file:')) requests.push(r.url()); });
  const page = await context.newPage();
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  page.on('pageerror', (e) => errors.push(String(e)));
  await page.goto(`file://${html}`);
  assert.equal(await page.locator('table.mistakes tbody tr').count(), summary.mistakes.length);
  const codes = await page.locator('table.mistakes tbody tr td:first-child code').allTextContents();
  assert.deepEqual(codes, summary.mistakes.map((m) => m.code));
  assert.equal(await page.locator('svg.hist').count(), 1 + summary.tasks.length);
  // The links point at the app with each case's own query.
  const hrefs = await page.locator('a.case').evaluateAll((as) => as.map((a) => a.getAttribute('data-q')));
  assert.ok(hrefs.length > 0 && hrefs.every((q) => q.startsWith('?src=demo&frame=')), JSON.stringify(hrefs));
  fs.mkdirSync(path.join(ROOT, 'tests/e2e/screenshots/chromium'), { recursive: true });
  for (const width of [1400, 390]) {
    await page.setViewportSize({ width, height: 900 });
    const over = await page.evaluate(() => document.documentElement.scrollWidth - document.documentElement.clientWidth);
    assert.ok(over <= 0, `summary.html at ${width} px scrolls sideways by ${over} px`);
    await page.screenshot({ path: path.join(ROOT, `tests/e2e/screenshots/chromium/summary-html-${width}.png`), fullPage: true });
  }
  assert.deepEqual(requests, []);
  assert.deepEqual(errors, []);
  await context.close();
});
