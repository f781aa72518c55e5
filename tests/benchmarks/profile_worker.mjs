// Chromium's CPU profile of the app's SIFT workers (docs/performance.md, "The SIMD128 path"):
// loads the page on the demo pair (its workers detect frames 0 and 1), samples every worker
// from its first instruction (CDP auto-attach, paused at start) until the page is idle, and
// prints each function's self time, summed over the workers, heaviest first.
//   node tests/benchmarks/profile_worker.mjs BASE_URL [--portable] [--top 25]
// (dist/ built with SIFTLAB_WASM_NAMES=1 www/build, or functions show as wasm-function[N];
// served at BASE_URL, e.g. python3 -m http.server -d dist 8080). Raw CDP over the
// DevTools WebSocket: Playwright cannot send commands to a worker's flattened session.
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { CHROMIUM_ARGS } from '../e2e/harness.mjs';

const ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
const { default: WebSocket } = await import(path.join(ROOT, 'tests/e2e/node_modules/ws/index.js'));
const base = process.argv[2] || 'http://127.0.0.1:8080/';
const portable = process.argv.includes('--portable');
const topArg = process.argv.indexOf('--top');
const top = topArg > 0 ? Number(process.argv[topArg + 1]) : 25;

const profileDir = fs.mkdtempSync(path.join(os.tmpdir(), 'siftlab-profile-'));
const port = 9300 + Math.floor(Math.random() * 500);
const chrome = spawn(process.env.CHROMIUM || '/usr/bin/chromium', [
  ...CHROMIUM_ARGS, `--remote-debugging-port=${port}`, `--user-data-dir=${profileDir}`, 'about:blank',
], { stdio: 'ignore' });
let version;
for (let i = 0; !version; i++) {
  try {
    version = await (await fetch(`http://127.0.0.1:${port}/json/version`)).json();
  } catch {
    if (i > 100) throw new Error('chromium did not start');
    await new Promise((r) => setTimeout(r, 100));
  }
}
const ws = new WebSocket(version.webSocketDebuggerUrl, { perMessageDeflate: false });
await new Promise((r) => ws.once('open', r));
let nextId = 1;
const pending = new Map();
const handlers = [];
ws.on('message', (data) => {
  const m = JSON.parse(data);
  if (m.id && pending.has(m.id)) {
    const { resolve, reject } = pending.get(m.id);
    pending.delete(m.id);
    if (m.error) reject(new Error(JSON.stringify(m.error)));
    else resolve(m.result);
  } else if (m.method) {
    for (const h of handlers) h(m);
  }
});
const send = (method, params = {}, sessionId) => new Promise((resolve, reject) => {
  const id = nextId++;
  pending.set(id, { resolve, reject });
  ws.send(JSON.stringify({ id, method, params, ...(sessionId ? { sessionId } : {}) }));
});

const workers = [];
handlers.push(async (m) => {
  if (m.method !== 'Target.attachedToTarget') return;
  const { sessionId, targetInfo } = m.params;
  if (targetInfo.type === 'worker') {
    workers.push(sessionId);
    await send('Profiler.enable', {}, sessionId);
    await send('Profiler.setSamplingInterval', { interval: 200 }, sessionId);
    await send('Profiler.start', {}, sessionId);
  }
  await send('Runtime.runIfWaitingForDebugger', {}, sessionId);
});

const { targetId } = await send('Target.createTarget', { url: 'about:blank' });
const { sessionId: page } = await send('Target.attachToTarget', { targetId, flatten: true });
await send('Target.setAutoAttach', { autoAttach: true, waitForDebuggerOnStart: true, flatten: true }, page);
await send('Runtime.enable', {}, page);
await send('Page.enable', {}, page);
await send('Page.navigate', { url: `${base}?lanes=8${portable ? '&wasm=portable' : ''}` }, page);
const evaluate = async (expr) => (await send('Runtime.evaluate', { expression: expr, returnByValue: true }, page)).result.value;
// Idle: both frames' keypoint counts shown and no busy indicator.
for (let i = 0; ; i++) {
  const idle = await evaluate(`!!document.querySelector('[data-testid="keypoint-count-cur"]') && !document.querySelector('[data-testid="busy"]')`).catch(() => false);
  if (idle) break;
  if (i > 3000) throw new Error('the page did not finish');
  await new Promise((r) => setTimeout(r, 100));
}
const slots = await evaluate(`[...document.querySelectorAll('.slot-info')].map((e) => e.textContent.match(/SIFT \\d+ ms/)?.[0]).join(', ')`);
const self = new Map();
let total = 0;
for (const w of workers) {
  const { profile } = await send('Profiler.stop', {}, w);
  const byId = new Map(profile.nodes.map((n) => [n.id, n]));
  const dt = profile.timeDeltas;
  profile.samples.forEach((id, i) => {
    const n = byId.get(id);
    const name = n.callFrame.functionName || `(${n.callFrame.url.split('/').pop() || 'anonymous'})`;
    const ms = (dt[i + 1] ?? 0) / 1000;
    self.set(name, (self.get(name) || 0) + ms);
    total += ms;
  });
}
ws.close();
chrome.kill();
const rows = [...self].filter(([n]) => n !== '(idle)' && n !== '(program)').sort((a, b) => b[1] - a[1]);
const busy = rows.reduce((s, [, ms]) => s + ms, 0);
console.log(`${portable ? 'SIMD128' : 'relaxed-SIMD'} worker(s): ${workers.length}; page: ${slots}; sampled ${total.toFixed(0)} ms, busy ${busy.toFixed(0)} ms`);
for (const [name, ms] of rows.slice(0, top)) console.log(`${ms.toFixed(1).padStart(8)} ms ${(100 * ms / busy).toFixed(1).padStart(5)} %  ${name}`);
