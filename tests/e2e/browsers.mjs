// The README's "Browsers" table, measured in one run on this machine: for each engine
// (Chromium, Firefox ESR, WebKitGTK), its version, the SIFT worker build www/worker.js
// chose, SIFT ms per frame on the demo pair (frames 0 and 1, as the page's worker timed
// them; median of `--rounds` page loads) and the odometry view's frames/s on frames 0-99
// (LK, the lab's loop), checked against the CLI's trajectory error.
//   tests/e2e/browsers.sh [--rounds 3] [--vo-frame-id 99] [--engines "chromium firefox webkit"]
// (browsers.sh builds what is missing and starts WebKit under xvfb-run; run from there.)
import { spawnSync } from 'node:child_process';
import path from 'node:path';
import { launch, serve, ROOT } from './harness.mjs';

const opt = (name, dflt) => { const i = process.argv.indexOf(name); return i > 0 ? process.argv[i + 1] : dflt; };
const rounds = Number(opt('--rounds', '3'));
const voLast = Number(opt('--vo-frame-id', '99'));
const engines = opt('--engines', 'chromium firefox webkit').split(/\s+/).filter(Boolean);
const CLI = process.env.SIFTLAB_CLI || path.join(ROOT, 'target/release/siftlab');
const DEMO = path.join(ROOT, 'www/demo/MyKITTI');
const median = (v) => [...v].sort((a, b) => a - b)[Math.floor(v.length / 2)];
const tid = (id) => `[data-testid="${id}"]`;

const server = await serve(path.join(ROOT, 'dist'), { hooks: true });
const cliRun = spawnSync(CLI, ['-d', DEMO, 'view_trajectory', String(voLast), '--output', '/dev/null'], { encoding: 'utf8' });
const cliAte = `${(cliRun.stdout + cliRun.stderr).match(/trajectory error \(ATE RMSE, \d+ frames\): ([\d.]+) m/)[1]} m`;
const rows = [];
for (const engine of engines) {
  const b = await launch(engine);
  const sift = [];
  let build;
  for (let r = 0; r < rounds; r++) {
    const page = await b.newPage();
    await page.goto(`${server.base}?lanes=8`);
    await page.waitForSelector(tid('keypoint-count-cur'), { timeout: 300000 });
    await page.waitForSelector(tid('busy'), { state: 'detached', timeout: 300000 });
    const infos = await page.evalAll('.slot-info', (e) => e.textContent);
    sift.push(...infos.map((s) => Number(s.match(/SIFT (\d+) ms/)[1])));
    build = (await page.textContent(tid('keypoint-count-cur-engine'))).trim();
  }
  const page = await b.newPage();
  await page.goto(`${server.base}?lanes=8`);
  await page.waitForSelector(tid('keypoint-count-cur'), { timeout: 300000 });
  await page.waitForSelector(tid('busy'), { state: 'detached', timeout: 300000 });
  await page.fill(tid('vo-frame-id'), String(voLast));
  await page.click(tid('vo-run'));
  await page.waitForSelector(tid('vo-ate'), { timeout: 3600000 });
  const m = (await page.textContent('.trajectory')).match(/over (\d+) frames · ([\d.]+) s/);
  const ate = (await page.textContent(tid('vo-ate'))).trim();
  if (ate !== cliAte) throw new Error(`${engine}: trajectory error ${ate}, the CLI's ${cliAte}`);
  rows.push({ engine, version: b.version, build, siftMs: median(sift), siftAll: sift, voFps: +(Number(m[1]) / Number(m[2])).toFixed(2), ate });
  await b.close();
}
await server.close();

const names = { chromium: 'Chromium', firefox: 'Firefox ESR', webkit: 'WebKitGTK (Safari\'s engine)' };
console.log(`| Engine | Worker build | SIFT ms/frame (demo pair, median) | Odometry frames/s (0–${voLast}) |`);
console.log('|---|---|---:|---:|');
for (const r of rows) console.log(`| ${names[r.engine]} ${r.version} | ${r.build} | ${r.siftMs} | ${r.voFps} |`);
console.error(JSON.stringify({ cliAte, rows }, null, 2));
