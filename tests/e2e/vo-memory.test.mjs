// The odometry's memory does not grow with the run's length (issue 44), Chromium only
// (Playwright; the RSS read from /proc). A 600-frame MyKITTI folder (the demo's frames
// 0–150 there and back, tests/benchmarks/long_sequence.py, hard links in a temp dir) is
// opened by the folder input and run with view_trajectory 599 (LK) while the renderer's
// resident memory (the page and its SIFT workers, which are threads of it) is sampled once
// a second (tests/benchmarks/vo_memory.mjs). Asserts:
// - the page's ATE equals the CLI's view_trajectory 599 on the same folder;
// - what the page holds (its JS heap, collected before each sample, and its wasm memory)
//   grows by less than 20 KB a frame from frame 200 (half a shorter run: the page's
//   caches fill over the first ~150 frames) to the end: its floor, the least sample in
//   each place (tests/benchmarks/vo_memory.mjs, floorGrowth), since the JS heap still
//   varies by several MB after a collection: the run keeps a few hundred bytes of results a frame,
//   not each frame's file and points (~0.5 MB a frame before issue 44's fix);
// - the renderer's peak RSS (the page, its workers and the browser's own bounded caches of
//   decoded frames, which fill over the first few hundred frames) stays below 1.5 GB.
// DIST (default ROOT/dist) names the build; E2E_MEMORY_FRAMES (600) the run's length.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { serve, ROOT, launchChromium } from './harness.mjs';
import { cliAte, floorGrowth, growth, hostLanes, longFolder, runVo, slope } from '../benchmarks/vo_memory.mjs';

const DIST = path.resolve(process.env.DIST || path.join(ROOT, 'dist'));
const CLI = process.env.SIFTLAB_CLI || path.join(ROOT, 'target/release/siftlab');
const FRAMES = Number(process.env.E2E_MEMORY_FRAMES || 600);
const FROM = Math.min(200, Math.floor(FRAMES / 2));
const BOUND_KB = 20;
const LANES = hostLanes();
const MB = 1024 * 1024;

let browser;
let server;
let tmp;

before(async () => {
  assert.ok(fs.existsSync(CLI), `${CLI} missing: cargo build --release --bin siftlab`);
  tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'siftlab-vo-memory-'));
  server = await serve(DIST, { hooks: false });
  browser = await launchChromium(['--js-flags=--expose-gc', '--enable-precise-memory-info']);
});
after(async () => {
  await browser?.close();
  await server?.close();
  if (tmp) fs.rmSync(tmp, { recursive: true, force: true });
});

test(`odometry over ${FRAMES} frames: the CLI's ATE, the page's memory growth below ${BOUND_KB} KB/frame, renderer below 1.5 GB`, async () => {
  const { dir } = longFolder(path.join(tmp, 'MyKITTI'), FRAMES);
  const cli = cliAte(CLI, dir, FRAMES - 1, LANES);
  const context = await browser.newContext({ viewport: { width: 1400, height: 900 } });
  const page = await context.newPage();
  const rec = await runVo(page, { base: server.base, dir, frames: FRAMES, lanes: LANES, gc: true, log: (s) => console.log(`# ${s}`) });
  await context.close();
  const g = growth(rec.samples, FROM);
  const own = floorGrowth(rec.samples, FROM);
  const fit = slope(rec.samples.filter((s) => s.frame >= FROM));
  const figures = {
    dist: DIST, frames: FRAMES, outcome: rec.outcome, elapsed_s: Math.round(rec.elapsedS * 10) / 10, page_done: rec.pageDone,
    idle_renderer_mb: Math.round(rec.idle.renderer / MB), peak_renderer_mb: Math.round(rec.peakRenderer / MB), peak_total_mb: Math.round(rec.peakTotal / MB),
    growth_kb_per_frame: g && Math.round(g.bytesPerFrame / 1024 * 10) / 10, growth_frames: g && [g.fromFrame, g.toFrame],
    growth_rss_mb: g && [Math.round(g.fromRss / MB), Math.round(g.toRss / MB)], fit_kb_per_frame: Math.round(fit / 1024 * 10) / 10,
    page_own_kb_per_frame: own && Math.round(own.bytesPerFrame / 1024 * 10) / 10, page_own_mb: own && [Math.round(own.fromRss / MB), Math.round(own.toRss / MB)],
    page_ate: rec.pageAte, cli_ate: cli.ate, cli_wall_s: Math.round(cli.wallS * 10) / 10,
  };
  console.log(`# vo-memory: ${JSON.stringify(figures)}`);
  assert.equal(rec.outcome, 'done', `the run ended with ${rec.outcome}${rec.pageError ? `: ${rec.pageError}` : ''}`);
  assert.deepEqual(rec.errors, [], 'errors thrown in the page');
  assert.equal(rec.pageAte, cli.ate, 'the page\'s ATE differs from the CLI\'s');
  assert.ok(own && own.toFrame - own.fromFrame >= FRAMES / 4, `too few samples to measure the growth: ${JSON.stringify(own)}`);
  // What the page holds (its JS heap after a collection, and its wasm memory) grows by
  // the results only: a few hundred bytes a frame, far below the bound.
  assert.ok(own.bytesPerFrame < BOUND_KB * 1024,
    `the page's own memory grew ${(own.bytesPerFrame / 1024).toFixed(1)} KB/frame between frames ${own.fromFrame} and ${own.toFrame} `
    + `(${(own.fromRss / MB).toFixed(1)} → ${(own.toRss / MB).toFixed(1)} MB), bound ${BOUND_KB} KB/frame`);
  // The renderer as a whole (with the browser's bounded caches of decoded frames, which
  // fill over the first few hundred frames: 4541 frames peak at 0.85 GB): below 1.5 GB.
  assert.ok(rec.peakRenderer < 1.5 * 1024 * MB, `the renderer peaked at ${(rec.peakRenderer / MB).toFixed(0)} MB`);
});
