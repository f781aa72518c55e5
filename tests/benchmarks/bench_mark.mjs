// "Mark my code" in Chromium: the time to mark the correct solution, this build (dist/)
// against an older build's dist/, alternating round by round (Playwright):
//   node tests/benchmarks/bench_mark.mjs --before OLD_DIST [--rounds 3] [--n 25] [--seed 0]
// Wall time from the click on "Mark" to the report (SIFT of the frames, Python's start and
// every call). Both must give 20.00. Prints one line per run and JSON with the medians.
import path from 'node:path';
import { serve, ROOT, launchChromium } from '../e2e/harness.mjs';

const opt = (name, d) => { const i = process.argv.indexOf(name); return i > 0 ? process.argv[i + 1] : d; };
const rounds = Number(opt('--rounds', 3));
const n = Number(opt('--n', 25));
const seed = Number(opt('--seed', 0));
const before = opt('--before');
if (!before) throw new Error('--before OLD_DIST is needed');
const tid = (id) => `[data-testid="${id}"]`;
const median = (v) => [...v].sort((a, b) => a - b)[Math.floor(v.length / 2)];
const servers = {
  before: await serve(path.resolve(before), { hooks: false }),
  after: await serve(path.join(ROOT, 'dist'), { hooks: false }),
};
const browser = await launchChromium();
const file = path.join(ROOT, 'tests/fixtures/mark/good/vision_tasks.py');
const times = { before: [], after: [] };
for (let r = 0; r < rounds; r++) {
  const order = r % 2 ? ['after', 'before'] : ['before', 'after'];
  for (const name of order) {
    const page = await browser.newPage({ viewport: { width: 1400, height: 900 } });
    await page.goto(`${servers[name].base}?lanes=8&mark=${seed}&mn=${n}`);
    await page.waitForSelector(tid('keypoint-count-cur'), { timeout: 300000 });
    await page.setInputFiles(tid('mark-file'), file);
    await page.waitForFunction((sel) => !document.querySelector(sel).disabled, tid('mark-run'), { timeout: 30000 });
    const t0 = Date.now();
    await page.click(tid('mark-run'));
    await page.waitForSelector(`${tid('mark-report')}, ${tid('mark-error')}`, { timeout: 1800000 });
    const s = (Date.now() - t0) / 1000;
    const total = await page.getAttribute(tid('mark-total'), 'data-total');
    console.log(`round ${r + 1} ${name.padEnd(6)} ${s.toFixed(1)} s total ${total}`);
    if (total !== '20.00') throw new Error(`${name}: ${total}`);
    times[name].push(s);
    await page.close();
  }
}
const b = median(times.before);
const a = median(times.after);
console.log(JSON.stringify({ rounds, n, before: times.before, after: times.after, medianBefore: b, medianAfter: a,
  ratio: +(a / b).toFixed(3) }));
await browser.close();
for (const s of Object.values(servers)) s.close?.();
process.exit(0);
