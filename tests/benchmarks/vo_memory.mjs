// The odometry view's memory over a long run (issue 44), in Chromium with Playwright:
// opens the app on a long MyKITTI folder (tests/benchmarks/long_sequence.py: the demo's
// frames 0–150 there and back, N frames), runs view_trajectory N−1 (LK) and samples the
// resident memory (VmRSS, /proc/PID/status) of every Chromium process once a second. The
// page and its SIFT workers are one renderer process (workers are threads), found by
// `--type=renderer` in its command line. Reports the peak renderer RSS, the peak total of
// all Chromium processes, the RSS at every 10 % of the run (the frame count read from the
// page's progress, "frame n / N"), the renderer's growth per frame, the elapsed time and the
// ATE the page shows, which must equal the CLI's on the same frames (exit 1 if not).
//
//   node tests/benchmarks/vo_memory.mjs --frames 4541 --dist /tmp/dist-before44
//
// Options: --frames N (4541), --dist DIR (ROOT/dist, served by the e2e harness's server),
// --dir FOLDER (/tmp/siftlab-long-N, built by long_sequence.py when incomplete),
// --lanes 8|16 (OpenCV's SIMD width for page and CLI alike; default the host's, as the e2e
// suite), --workers K (the page's ?workers=, default the page's own choice), --ate X (the
// CLI's ATE when already known: skips the CLI run), --cli PATH, --samples FILE (every
// sample as JSON lines), --stop-fraction F (0.7: stop the run once the Chromium processes
// together hold more than F of the machine's RAM, and report the growth per frame so far).
// Output: a human summary on stderr, one JSON line on stdout.
// The module also exports the pieces tests/e2e/vo-memory.test.mjs uses.
import { spawnSync } from 'node:child_process';
import { createRequire } from 'node:module';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';
import { serve, launchChromium, descendants } from '../e2e/harness.mjs';

export const ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
const require = createRequire(path.join(ROOT, 'tests/e2e/package.json'));
const tid = (id) => `[data-testid="${id}"]`;
const MB = 1024 * 1024;
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));


/** OpenCV's SIMD width on this CPU, as the CLI picks it by default (tests/e2e/app/common.mjs). */
export function hostLanes() {
  if (process.arch !== 'x64') return 8;
  const flags = (fs.readFileSync('/proc/cpuinfo', 'utf8').match(/^flags\s*:(.*)$/m) || [, ''])[1].split(/\s+/);
  return ['avx512f', 'avx512cd', 'avx512bw', 'avx512dq', 'avx512vl'].every((f) => flags.includes(f)) ? 16 : 8;
}

export function memTotalBytes() {
  return Number(fs.readFileSync('/proc/meminfo', 'utf8').match(/^MemTotal:\s+(\d+) kB/m)[1]) * 1024;
}

/** Builds (or checks) the long folder with long_sequence.py; returns its path. */
export function longFolder(dir, frames) {
  const r = spawnSync('python3', [path.join(ROOT, 'tests/benchmarks/long_sequence.py'), dir, String(frames)], { encoding: 'utf8' });
  if (r.status !== 0) throw new Error(`long_sequence.py failed: ${r.stderr}`);
  return { dir, note: r.stdout.trim() };
}

/** The CLI's view_trajectory LAST (LK) on `dir`: its ATE as the app prints it, and its wall time. */
export function cliAte(cli, dir, last, lanes) {
  const t0 = Date.now();
  const r = spawnSync(cli, ['--opencv-lanes', String(lanes), '-d', dir, 'view_trajectory', String(last), '--output', '/dev/null'],
    { encoding: 'utf8', maxBuffer: 1 << 28 });
  const wall = (Date.now() - t0) / 1000;
  if (r.status !== 0) throw new Error(`${cli} view_trajectory ${last} failed: ${r.stderr.slice(-2000)}`);
  const m = (r.stdout + r.stderr).match(/trajectory error \(ATE RMSE, (\d+) frames\): ([\d.]+) m/);
  if (!m || Number(m[1]) !== last + 1) throw new Error(`no ATE for ${last + 1} frames in the CLI's output`);
  return { ate: m[2], wallS: wall };
}

/**
 * One reading of the Chromium processes under `rootPid` (this Node process by default:
 * Playwright starts the browser as its child, the zygote and every renderer below it):
 * their VmRSS, the renderers' apart.
 */
export function chromiumRss(rootPid = process.pid) {
  const out = { total: 0, renderers: [], processes: 0 };
  for (const pid of descendants(rootPid).keys()) {
    let cmd;
    let rss;
    try {
      // Chromium rewrites its children's command lines as one space-separated string.
      cmd = fs.readFileSync(`/proc/${pid}/cmdline`, 'utf8').replace(/\0/g, ' ');
      const m = fs.readFileSync(`/proc/${pid}/status`, 'utf8').match(/^VmRSS:\s+(\d+) kB/m);
      rss = m ? Number(m[1]) * 1024 : 0;   // a zombie has no VmRSS
    } catch {
      continue;
    }
    if (!/^\S*chrom/i.test(cmd)) continue;
    out.total += rss;
    out.processes++;
    if (/ --type=renderer( |$)/.test(cmd)) out.renderers.push({ pid, rss });
  }
  out.renderer = out.renderers.reduce((a, r) => Math.max(a, r.rss), 0);
  return out;
}

/** Least-squares slope of rss against frame over the samples (bytes per frame). */
export function slope(samples, key = 'renderer') {
  const n = samples.length;
  if (n < 2) return NaN;
  const mx = samples.reduce((a, s) => a + s.frame, 0) / n;
  const my = samples.reduce((a, s) => a + s[key], 0) / n;
  let sxy = 0;
  let sxx = 0;
  for (const s of samples) {
    sxy += (s.frame - mx) * (s[key] - my);
    sxx += (s.frame - mx) ** 2;
  }
  return sxx > 0 ? sxy / sxx : NaN;
}

const median = (xs) => {
  const s = [...xs].sort((a, b) => a - b);
  return s.length ? (s.length % 2 ? s[(s.length - 1) / 2] : (s[s.length / 2 - 1] + s[s.length / 2]) / 2) : NaN;
};

/**
 * The renderer's growth per frame between about frame `from` and the end of the run:
 * the median RSS (and frame) of the samples within `from` ± `window` frames, against that
 * of the last samples of the run (the last `tail` while it ran), divided by the frames
 * between. Medians, so one garbage collection does not make the figure.
 */
export function growth(samples, from, { window = 20, tail = 3 } = {}) {
  const running = samples.filter((s) => s.frame > 0);
  const a = running.filter((s) => Math.abs(s.frame - from) <= window);
  const b = running.slice(-tail);
  if (!a.length || b.length < 1) return null;
  const fa = median(a.map((s) => s.frame));
  const fb = median(b.map((s) => s.frame));
  const ra = median(a.map((s) => s.renderer));
  const rb = median(b.map((s) => s.renderer));
  return { fromFrame: fa, toFrame: fb, fromRss: ra, toRss: rb, bytesPerFrame: fb > fa ? (rb - ra) / (fb - fa) : NaN };
}

/**
 * How the floor of `samples` (their least value, `key`) moves from the frames just after
 * `from` (`from` … `from` + `span`) to the last `tail` samples, per frame. A leak raises
 * the floor; garbage a collection has not reached yet only adds spikes (V8 after `gc()`
 * still varies by several MB between samples), which a median of a few samples mistakes
 * for growth.
 */
export function floorGrowth(samples, from, { key = 'page', span = 60, tail = 6 } = {}) {
  const running = samples.filter((s) => s.frame > 0);
  const a = running.filter((s) => s.frame >= from && s.frame <= from + span);
  const b = running.slice(-tail);
  if (!a.length || b.length < tail) return null;
  const fa = median(a.map((s) => s.frame));
  const fb = median(b.map((s) => s.frame));
  const ra = Math.min(...a.map((s) => s[key]));
  const rb = Math.min(...b.map((s) => s[key]));
  return { fromFrame: fa, toFrame: fb, fromRss: ra, toRss: rb, bytesPerFrame: fb > fa ? (rb - ra) / (fb - fa) : NaN };
}

/**
 * On `page` (served at `base`): opens `dir` by the folder input, runs the odometry on frames
 * 0 … frames−1 (LK) and samples the RSS every `everyMs`. Resolves to the run's record.
 * `stopBytes`: stop (the page's Stop button) once the Chromium processes hold more.
 */
export async function runVo(page, { base, dir, frames, lanes, workers, gc = false, everyMs = 1000, stopBytes = Infinity, log = () => {}, timeoutMs = 6 * 3600e3 }) {
  const rec = { samples: [], outcome: null, pageAte: null, pageError: null, pageDone: null };
  let crashed = false;
  page.on('crash', () => { crashed = true; });
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  const q = new URLSearchParams();
  if (lanes) q.set('lanes', String(lanes));
  if (workers) q.set('workers', String(workers));
  await page.goto(`${base}?${q}`);
  await page.waitForSelector(tid('keypoint-count-cur'), { timeout: 300000 });
  await page.waitForSelector(tid('busy'), { state: 'detached', timeout: 300000 });
  const tLoad = Date.now();
  await page.setInputFiles(tid('folder'), dir);
  // The folder is open when the odometry offers its frames: "available: frames 0 to N−1".
  await page.waitForFunction(([sel, last]) => (document.querySelector(sel)?.textContent || '').includes(`available: frames 0 to ${last}`),
    [tid('vo-range'), frames - 1], { timeout: 600000 });
  await page.waitForSelector(tid('busy'), { state: 'detached', timeout: 600000 });
  rec.folderOpenS = (Date.now() - tLoad) / 1000;
  rec.idle = chromiumRss();
  log(`folder open in ${rec.folderOpenS.toFixed(1)} s; idle: renderer ${(rec.idle.renderer / MB).toFixed(0)} MB, total ${(rec.idle.total / MB).toFixed(0)} MB`);
  await page.fill(tid('vo-frame-id'), String(frames - 1));
  const t0 = Date.now();
  await page.click(tid('vo-run'));
  let nextPct = 10;
  rec.checkpoints = [];
  let stopped = false;
  for (;;) {
    await sleep(everyMs);
    const t = (Date.now() - t0) / 1000;
    // With --js-flags=--expose-gc (the CI test): the page's garbage collected before
    // each sample, so the figure is what the page holds, not how late V8 collects.
    if (gc && !crashed) await page.evaluate(() => window.gc?.()).catch(() => {});
    const mem = chromiumRss();
    let state = null;
    if (!crashed) {
      state = await Promise.race([
        page.evaluate((ids) => {
          const text = (id) => document.querySelector(`[data-testid="${id}"]`)?.textContent ?? null;
          // What the page itself holds: V8's heap (Chromium's performance.memory) and the
          // page's wasm memory (boot.js exposes its size), apart from the browser's caches.
          const own = (performance.memory?.usedJSHeapSize ?? 0) + (globalThis.siftlabWasmBytes?.() ?? 0);
          return { own, progress: text(ids[0]), ate: text(ids[1]), error: text(ids[2]), done: document.querySelector('.trajectory')?.textContent.match(/over \d+ frames · [\d.]+ s( \([\d.]+ frames\/s\))?/)?.[0] ?? null };
        }, ['vo-progress', 'vo-ate', 'vo-error']).catch(() => null),
        sleep(10000).then(() => null),
      ]);
    }
    const m = state?.progress?.match(/frame (\d+) \/ (\d+)/);
    const last = rec.samples.at(-1);
    const frame = m ? Number(m[1]) : (last?.frame ?? 0);
    const s = { t: Math.round(t * 10) / 10, frame, renderer: mem.renderer, total: mem.total, renderers: mem.renderers.length, page: state?.own ?? last?.page ?? 0 };
    rec.samples.push(s);
    while (frame >= (nextPct / 100) * frames && nextPct <= 100) {
      rec.checkpoints.push({ pct: nextPct, ...s });
      log(`${String(nextPct).padStart(3)} %  frame ${String(frame).padStart(5)}  ${t.toFixed(0).padStart(5)} s  renderer ${(mem.renderer / MB).toFixed(0).padStart(5)} MB  total ${(mem.total / MB).toFixed(0).padStart(5)} MB`);
      nextPct += 10;
    }
    if (crashed || (mem.renderers.length === 0 && rec.samples.length > 2)) {
      rec.outcome = 'renderer crashed';
      break;
    }
    if (state?.ate) {
      rec.outcome = 'done';
      rec.pageAte = state.ate.replace(/ m$/, '');
      rec.pageDone = state.done;
      break;
    }
    if (state?.error) {
      rec.outcome = 'error';
      rec.pageError = state.error;
      break;
    }
    if (mem.total > stopBytes && !stopped) {
      stopped = true;
      rec.outcome = `stopped: Chromium's RSS ${(mem.total / MB).toFixed(0)} MB passed ${(stopBytes / MB).toFixed(0)} MB`;
      log(rec.outcome);
      await page.getByRole('button', { name: 'Stop' }).click({ timeout: 10000 }).catch(() => {});
      break;
    }
    if (Date.now() - t0 > timeoutMs) {
      rec.outcome = 'timeout';
      break;
    }
  }
  rec.elapsedS = (Date.now() - t0) / 1000;
  rec.errors = errors;
  rec.peakRenderer = Math.max(...rec.samples.map((s) => s.renderer));
  rec.peakTotal = Math.max(...rec.samples.map((s) => s.total));
  rec.framesDone = rec.samples.at(-1)?.frame ?? 0;
  return rec;
}

function parseArgs(argv) {
  const a = { frames: 4541, dist: path.join(ROOT, 'dist'), lanes: hostLanes(), stopFraction: 0.7, cli: process.env.SIFTLAB_CLI || path.join(ROOT, 'target/release/siftlab') };
  for (let i = 0; i < argv.length; i++) {
    const k = argv[i];
    const v = () => argv[++i];
    if (k === '--frames') a.frames = Number(v());
    else if (k === '--dist') a.dist = path.resolve(v());
    else if (k === '--dir') a.dir = path.resolve(v());
    else if (k === '--lanes') a.lanes = Number(v());
    else if (k === '--workers') a.workers = Number(v());
    else if (k === '--ate') a.ate = v();
    else if (k === '--cli') a.cli = path.resolve(v());
    else if (k === '--samples') a.samples = path.resolve(v());
    else if (k === '--stop-fraction') a.stopFraction = Number(v());
    else if (k === '-h' || k === '--help') {
      console.log(fs.readFileSync(fileURLToPath(import.meta.url), 'utf8').split('\n').filter((l) => l.startsWith('//')).slice(0, 22).map((l) => l.slice(3)).join('\n'));
      process.exit(0);
    } else throw new Error(`unknown argument ${k}`);
  }
  if (!(a.frames >= 2)) throw new Error('--frames must be at least 2');
  a.dir ||= path.join(os.tmpdir(), `siftlab-long-${a.frames}`);
  return a;
}

async function main() {
  const a = parseArgs(process.argv.slice(2));
  const log = (s) => process.stderr.write(`[vo_memory] ${s}\n`);
  if (!fs.existsSync(path.join(a.dist, 'index.html'))) throw new Error(`${a.dist} has no index.html`);
  const folder = longFolder(a.dir, a.frames);
  log(folder.note);
  let cli = { ate: a.ate, wallS: null };
  if (cli.ate === undefined) {
    log(`CLI: ${a.cli} --opencv-lanes ${a.lanes} -d ${a.dir} view_trajectory ${a.frames - 1} …`);
    cli = cliAte(a.cli, a.dir, a.frames - 1, a.lanes);
    log(`CLI: ATE ${cli.ate} m in ${cli.wallS.toFixed(1)} s`);
  }
  const ram = memTotalBytes();
  const server = await serve(a.dist, { hooks: false });
  const browser = await launchChromium();
  let rec;
  try {
    const context = await browser.newContext({ viewport: { width: 1400, height: 900 } });
    const page = await context.newPage();
    rec = await runVo(page, { base: server.base, dir: a.dir, frames: a.frames, lanes: a.lanes, workers: a.workers, stopBytes: a.stopFraction * ram, log });
    rec.workersText = await page.textContent(tid('vo-workers'), { timeout: 2000 }).catch(() => null);
  } finally {
    await browser.close().catch(() => {});
    await server.close();
  }
  if (a.samples) fs.writeFileSync(a.samples, rec.samples.map((s) => JSON.stringify(s)).join('\n') + '\n');
  const from = Math.min(200, Math.floor(rec.framesDone / 3));
  const g = growth(rec.samples, from);
  const fit = slope(rec.samples.filter((s) => s.frame >= from));
  const mb = (x) => Math.round((x / MB) * 10) / 10;
  const out = {
    frames: a.frames, dist: a.dist, dir: a.dir, lanes: a.lanes, workers: a.workers ?? null, ram_mb: mb(ram), outcome: rec.outcome,
    frames_done: rec.framesDone, elapsed_s: Math.round(rec.elapsedS * 10) / 10, page_done: rec.pageDone, folder_open_s: rec.folderOpenS,
    idle_renderer_mb: mb(rec.idle.renderer), idle_total_mb: mb(rec.idle.total),
    peak_renderer_mb: mb(rec.peakRenderer), peak_total_mb: mb(rec.peakTotal),
    growth_kb_per_frame: g ? Math.round(g.bytesPerFrame / 1024 * 10) / 10 : null, growth_from_frame: g?.fromFrame ?? null, growth_to_frame: g?.toFrame ?? null,
    fit_kb_per_frame: Math.round(fit / 1024 * 10) / 10,
    checkpoints: rec.checkpoints.map((c) => ({ pct: c.pct, frame: c.frame, t_s: c.t, renderer_mb: mb(c.renderer), total_mb: mb(c.total) })),
    page_ate: rec.pageAte, cli_ate: cli.ate, cli_wall_s: cli.wallS === null ? null : Math.round(cli.wallS * 10) / 10,
    ate_equal: rec.pageAte !== null && rec.pageAte === cli.ate, page_error: rec.pageError, page_errors: rec.errors, workers_text: rec.workersText,
  };
  log(`${rec.outcome} after ${rec.elapsedS.toFixed(1)} s, ${rec.framesDone} / ${a.frames} frames${rec.pageDone ? ` (page: ${rec.pageDone})` : ''}`);
  log(`peak RSS: renderer ${mb(rec.peakRenderer)} MB, all Chromium processes ${mb(rec.peakTotal)} MB (RAM ${mb(ram)} MB); idle before the run ${mb(rec.idle.renderer)} / ${mb(rec.idle.total)} MB`);
  if (g) log(`renderer growth: ${(g.bytesPerFrame / 1024).toFixed(1)} KB/frame (frame ${g.fromFrame} → ${g.toFrame}: ${mb(g.fromRss)} → ${mb(g.toRss)} MB); least squares over frames ≥ ${from}: ${(fit / 1024).toFixed(1)} KB/frame`);
  log(`ATE: page ${rec.pageAte ?? '-'} m, CLI ${cli.ate} m${cli.wallS ? ` (CLI ${cli.wallS.toFixed(1)} s)` : ''}: ${out.ate_equal ? 'equal' : 'DIFFERENT'}`);
  if (rec.pageError) log(`page error: ${rec.pageError}`);
  console.log(JSON.stringify(out));
  process.exitCode = out.ate_equal ? 0 : 1;
}

if (process.argv[1] && import.meta.url === pathToFileURL(path.resolve(process.argv[1])).href) {
  main().catch((e) => {
    console.error(e);
    process.exit(2);
  });
}
