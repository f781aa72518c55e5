// Developer helper: open the app, wait for the demo, print console messages, save a screenshot.
//   node tests/e2e/shot.mjs http://127.0.0.1:8080/ out.png [width]
import { chromium } from 'playwright-core';

const [url = 'http://127.0.0.1:8080/', out = 'screenshots/shot.png', width = '1400'] = process.argv.slice(2);
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking', '--no-first-run',
         '--disable-component-update', '--disable-sync'],
});
const page = await browser.newPage({ viewport: { width: Number(width), height: 900 } });
page.on('console', (m) => console.log(`[console.${m.type()}] ${m.text()}`));
page.on('pageerror', (e) => console.log(`[pageerror] ${e}`));
const t0 = Date.now();
await page.goto(url);
await page.waitForSelector('[data-testid=keypoint-count-cur]', { timeout: 120000 });
await page.waitForSelector('[data-testid=busy]', { state: 'detached', timeout: 120000 });
console.log(`demo ready in ${Date.now() - t0} ms`);
console.log('tuple:', await page.textContent('[data-testid=result-tuple]'));
await page.screenshot({ path: out, fullPage: true });
await browser.close();
