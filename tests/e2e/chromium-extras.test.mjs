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
import { chromium } from 'playwright-core';
import { serve, ROOT } from './harness.mjs';

let browser;
let server;

before(async () => {
  // Served as the real site is (no test hooks in index.html): the hooks are the suite's.
  server = await serve(path.join(ROOT, 'dist'), { hooks: false });
  browser = await chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking', '--no-first-run',
      '--disable-component-update', '--disable-sync', '--disable-quic'],
  });
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
