// The time to the demo's first result (issue 44), in Chromium with Playwright: a cold
// load (a fresh browser, so no HTTP or compiled-wasm cache) of each build's dist/, from
// navigation to the moment the matching_info tuple of frames 0/1 is on screen (both
// frames' SIFT done in the workers, the page drawn). Builds alternate A B A B … so that
// the machine's noise falls on both alike; the medians and their ratio are reported.
//
//   node tests/benchmarks/first_result.mjs /tmp/dist-before44 dist [--runs 5]
//
// Also reports each build's page wasm, gzipped (what a first visit downloads).
import { createRequire } from 'node:module';
import fs from 'node:fs';
import path from 'node:path';
import zlib from 'node:zlib';
import { ROOT } from './vo_memory.mjs';
import { serve, launchChromium } from '../e2e/harness.mjs';

const require = createRequire(path.join(ROOT, 'tests/e2e/package.json'));
const { chromium } = require('playwright-core');

const args = process.argv.slice(2);
const runsAt = args.indexOf('--runs');
const runs = runsAt >= 0 ? Number(args.splice(runsAt, 2)[1]) : 5;
if (args.length !== 2) {
  console.error('usage: node tests/benchmarks/first_result.mjs DIST_A DIST_B [--runs N]');
  process.exit(2);
}
const dists = args.map((d) => path.resolve(d));
const median = (v) => [...v].sort((a, b) => a - b)[Math.floor(v.length / 2)];
const gz = (f) => zlib.gzipSync(fs.readFileSync(f), { level: 9 }).length;

async function once(base) {
  const browser = await launchChromium();
  try {
    const page = await browser.newPage({ viewport: { width: 1400, height: 900 } });
    const t0 = Date.now();
    await page.goto(base);
    await page.waitForFunction((sel) => /^\(\(\d+, \d+\), \[/.test(document.querySelector(sel)?.textContent.trim() || ''),
      '[data-testid="result-tuple"]', { timeout: 180000, polling: 20 });
    return Date.now() - t0;
  } finally {
    await browser.close();
  }
}

const servers = await Promise.all(dists.map((d) => serve(d, { hooks: false })));
const times = dists.map(() => []);
try {
  for (let r = 0; r < runs; r++) {
    for (let k = 0; k < dists.length; k++) {
      times[k].push(await once(servers[k].base));
      process.stderr.write(`[first_result] run ${r + 1}: ${dists[k]} ${times[k].at(-1)} ms\n`);
    }
  }
} finally {
  await Promise.all(servers.map((s) => s.close()));
}
const out = dists.map((d, k) => ({
  dist: d, page_wasm_gz: gz(path.join(d, 'pkg/siftlab_app_bg.wasm')), worker_wasm_gz: gz(path.join(d, 'pkg/siftlab_worker_bg.wasm')),
  first_result_ms: times[k], median_ms: median(times[k]),
}));
console.log(JSON.stringify({ runs, builds: out, ratio_b_over_a: Math.round((out[1].median_ms / out[0].median_ms) * 1000) / 1000 }));
