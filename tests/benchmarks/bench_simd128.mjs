// SIFT per frame in the app's two worker builds, two builds of the site interleaved in one
// run (docs/performance.md, "The SIMD128 path"): for each demo frame 0-5, one SIFT in every
// page in turn, each page kept open (warm) and fed one frame at a time, as
// tests/benchmarks/bench.mjs does (each round on freshly loaded pages: a page keeps the SIFT of a
// frame it has seen). Medians per page, and the portable/relaxed ratio per site.
//   node tests/benchmarks/bench_simd128.mjs --a /tmp/dist-before --b dist [--engine chromium|webkit] [--rounds 1]
// Chromium (playwright-core) opens four pages: each site with the relaxed-SIMD worker and
// with `?wasm=portable`. WebKitGTK (WebDriver, under xvfb-run) has no relaxed SIMD, so two
// sessions, one per site. Prints JSON.
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { launchChromium } from '../e2e/harness.mjs';

const ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
const E2E = path.join(ROOT, 'tests/e2e');
const opt = (name, dflt) => { const i = process.argv.indexOf(name); return i > 0 ? process.argv[i + 1] : dflt; };
const sites = { a: path.resolve(opt('--a', 'dist')), b: path.resolve(opt('--b', 'dist')) };
const engine = opt('--engine', 'chromium');
const rounds = Number(opt('--rounds', '1'));
const frame = (i) => path.join(ROOT, 'www/demo/MyKITTI/gray/00/image_0', String(i).padStart(6, '0') + '.png');
const median = (v) => [...v].sort((x, y) => x - y)[Math.floor(v.length / 2)];
const { serve, launch } = await import(path.join(E2E, 'harness.mjs'));

const servers = {};
for (const [k, dir] of Object.entries(sites)) servers[k] = await serve(dir, { hooks: false });

// The page's slot line for frame i: "000000.png … SIFT N ms".
const done = (n) => new RegExp(`${n}\\.png.*SIFT \\d+ ms`).test(document.querySelector('.slots')?.textContent || '');
const siftMs = (text) => Number(text.match(/SIFT (\d+) ms/)[1]);

const pages = {};
const closers = [];
if (engine === 'chromium') {
  const { chromium } = await import(path.join(E2E, 'node_modules/playwright-core/index.mjs'));
  const browser = await launchChromium();
  closers.push(() => browser.close());
  for (const k of Object.keys(sites)) {
    for (const [build, q] of [['relaxed', ''], ['portable', '&wasm=portable']]) {
      const page = await browser.newPage();
      const url = `${servers[k].base}?src=folder${q}`;
      await page.goto(url);
      pages[`${k}-${build}`] = {
        reload: () => page.goto(url),
        sift: async (i) => {
          await page.setInputFiles('[data-testid="frame-prev"]', frame(i));
          await page.waitForFunction(done, String(i).padStart(6, '0'), { timeout: 300000 });
          return siftMs(await page.textContent('.slots'));
        },
      };
    }
  }
} else {
  for (const k of Object.keys(sites)) {
    const b = await launch(engine);
    closers.push(() => b.close());
    const page = await b.newPage();
    const url = `${servers[k].base}?src=folder`;
    await page.goto(url);
    pages[`${k}-simd128`] = {
      reload: () => page.goto(url),
      sift: async (i) => {
        await page.setInputFiles('[data-testid="frame-prev"]', frame(i));
        await page.waitForFunction(done, String(i).padStart(6, '0'), { timeout: 300000 });
        return siftMs(await page.textContent('.slots'));
      },
    };
  }
}

const ms = Object.fromEntries(Object.keys(pages).map((k) => [k, []]));
for (let r = 0; r < rounds; r++) {
  // A fresh page each round: the page keeps the SIFT of a frame it has seen.
  if (r > 0) for (const p of Object.values(pages)) await p.reload();
  for (let i = 0; i < 6; i++) {
    // Alternate which site goes first, so neither always runs right after the other.
    const order = Object.keys(pages);
    if ((i + r) % 2) order.reverse();
    for (const k of order) ms[k].push(await pages[k].sift(i));
  }
}
for (const c of closers) await c();
for (const s of Object.values(servers)) await s.close();

const med = Object.fromEntries(Object.entries(ms).map(([k, v]) => [k, median(v)]));
const out = { engine, sites, ms, median: med };
if (engine === 'chromium') {
  out.portableOverRelaxed = Object.fromEntries(Object.keys(sites).map((k) => [k, +(med[`${k}-portable`] / med[`${k}-relaxed`]).toFixed(2)]));
  // Per frame, the same ratio (both pages of a site ran that frame back to back).
  out.perFrameRatio = Object.fromEntries(Object.keys(sites).map((k) => [k, ms[`${k}-portable`].map((p, j) => +(p / ms[`${k}-relaxed`][j]).toFixed(2))]));
  out.portableBOverA = +(med['b-portable'] / med['a-portable']).toFixed(3);
  out.relaxedBOverA = +(med['b-relaxed'] / med['a-relaxed']).toFixed(3);
} else {
  out.bOverA = +(med['b-simd128'] / med['a-simd128']).toFixed(3);
}
console.log(JSON.stringify(out, null, 2));
