// One harness for the three engines a student's browser runs on: Chromium (Debian's
// chromium + chromedriver), Firefox ESR (geckodriver) and WebKitGTK, Safari's engine
// (WebKitWebDriver + MiniBrowser under an X display). Each is driven over the W3C
// WebDriver protocol by selenium-webdriver; the page object (harness/page.mjs) offers the few
// Playwright-like calls the suite uses, implemented the same way in every engine.
//
// The harness serves dist/ itself (same MIME types and no-cache as www/serve.py) so that
// it can put tests/e2e/hooks.js first in index.html: WebDriver classic has no console or
// download events, so the page records them (see hooks.js). It also serves local test
// folders under /__e2e/fs/ so that a folder can be handed to the page in engines whose
// driver cannot upload a directory (WebKitWebDriver sends a directory as an empty file).
//
// The parts live in harness/: base.mjs (ROOT, sleep), serve.mjs (the server),
// browsers.mjs (the engines' launchers and CHROMIUM_ARGS) and page.mjs (the page
// object); this file re-exports them and registers a test file's hooks.
import assert from 'node:assert/strict';
import { before, after, beforeEach, afterEach } from 'node:test';
import path from 'node:path';
import { ROOT } from './harness/base.mjs';
import { launch } from './harness/browsers.mjs';
import { serve } from './harness/serve.mjs';

export { ROOT, sleep, descendants, descendantsCpuSeconds } from './harness/base.mjs';
export { CHROMIUM_ARGS, ENGINES, launch, launchChromium } from './harness/browsers.mjs';
export { serve } from './harness/serve.mjs';

/**
 * Registers a test file's hooks: dist/ served and one `engine` session for the file
 * (`onStart({ base, browser })`), a fresh 1400×900 page for each case (`onPage(page)`; with
 * `onePage`, the file's first case's page for every case, left as the last case left it),
 * and after each case the checks every case shares: no resource fetched off our origin,
 * no error recorded by the page or its workers. `onEnd` runs once, after the last case.
 */
export function suite(engine, { onStart = () => {}, onPage, onEnd = () => {}, onePage = false }) {
  let server;
  let browser;
  let page;
  before(async () => {
    server = await serve(path.join(ROOT, 'dist'));
    browser = await launch(engine);
    await onStart({ base: server.base, browser });
  });
  after(async () => {
    await browser?.close();
    await server?.close();
    await onEnd();
  });
  beforeEach(async () => {
    if (!(onePage && page)) page = await browser.newPage({ width: 1400, height: 900 });
    onPage(page);
  });
  afterEach(async () => {
    assert.deepEqual(await page.offOrigin(), [], 'requests left the origin');
    assert.deepEqual(await page.flushErrors(), [], 'console errors');
  });
}
