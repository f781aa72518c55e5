// Developer helper: open the app, wait for the demo, print console messages, save a screenshot.
//   node tests/benchmarks/shot.mjs http://127.0.0.1:8080/ out.png [width]
import { launchChromium } from '../e2e/harness.mjs';

const [url = 'http://127.0.0.1:8080/', out = 'shot.png', width = '1400'] = process.argv.slice(2);
const browser = await launchChromium();
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
