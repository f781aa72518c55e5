// SIFT time per frame: the app's worker in headless Chromium vs the native CLI, interleaved in
// one run on the same frames (tests/fixtures/mykitti, frames 0-5), one frame at a time.
//   BASE_URL=http://127.0.0.1:8080/ node tests/e2e/bench.mjs     (dist/ served, CLI built)
import { execFileSync } from 'node:child_process';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';

const ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
const BASE = process.env.BASE_URL || 'http://127.0.0.1:8080/';
const CLI = path.join(ROOT, 'target/release/siftlab');
const frame = (i) => path.join(ROOT, 'tests/fixtures/mykitti/gray/00/image_0', String(i).padStart(6, '0') + '.png');
const median = (v) => [...v].sort((a, b) => a - b)[Math.floor(v.length / 2)];

const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking', '--no-first-run', '--disable-component-update', '--disable-sync'],
});
const page = await browser.newPage();
// src=folder: no demo autoload, so exactly one SIFT runs at a time.
await page.goto(`${BASE}?src=folder`);
const wasm = [];
const native = [];
const nativeOneThread = [];
for (let i = 0; i < 6; i++) {
  await page.setInputFiles('[data-testid="frame-prev"]', frame(i));
  await page.waitForFunction((n) => new RegExp(`${n}\\.png.*SIFT \\d+ ms`).test(document.querySelector('.slots').textContent),
    String(i).padStart(6, '0'), { timeout: 300000 });
  const text = await page.textContent('.slots');
  wasm.push(Number(text.match(/SIFT (\d+) ms/)[1]));
  const ms = (cmd, args) => Number(execFileSync(cmd, args, { encoding: 'utf8' }).match(/in ([\d.]+) ms/)[1]);
  native.push(ms(CLI, ['--opencv-lanes', '8', 'sift', frame(i)]));
  // One core, like the single worker (Rust's available_parallelism follows the affinity mask).
  nativeOneThread.push(ms('taskset', ['-c', '0', CLI, '--opencv-lanes', '8', 'sift', frame(i)]));
}
await browser.close();
const r = {
  chromiumWasmMs: wasm, nativeMs: native, nativeOneCoreMs: nativeOneThread,
  medianChromiumMs: median(wasm), medianNativeMs: median(native), medianNativeOneCoreMs: median(nativeOneThread),
  ratio: +(median(wasm) / median(native)).toFixed(2), ratioOneCore: +(median(wasm) / median(nativeOneThread)).toFixed(2),
};
console.log(JSON.stringify(r, null, 2));
