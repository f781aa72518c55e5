// End-to-end test of "Mark my code"'s isolation (docs/marking.md, "In the browser"), in the
// engine E2E_ENGINE names, against the native CLI: hostile/browser_storage tries, from the
// student's Python, every route to the app's origin it can find (JavaScript through
// Pyodide's imports and the garbage collector, the members the worker removes reached on
// their prototypes, CacheStorage, IndexedDB, OPFS, an IDBFS mount, requests, nested
// workers) and is otherwise the good solution. Marked, it must get the CLI's table; then a
// fresh page load of the app's origin must find nothing written, and a listener on a free
// port no connection.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import crypto from 'node:crypto';
import fs from 'node:fs';
import net from 'node:net';
import os from 'node:os';
import path from 'node:path';
import { ROOT } from '../harness.mjs';
import { appSuite, ENGINE, CLI, DATASET, cliCached, metrics, LANES, BASE, page, tid, idle } from './common.mjs';

appSuite();

// One call per task: every route is tried at load and on each task's first call.
const MARK_N = Number(process.env.E2E_MARK_N || 1);
const FIXTURE = path.join(ROOT, 'tests/fixtures/mark/hostile/browser_storage/vision_tasks.py');

/** What the app's origin holds, read by a page of it. */
async function originStorage() {
  return page.evaluate(async () => {
    const out = {};
    try {
      out.caches = await caches.keys();
    } catch (e) {
      out.caches = `unavailable: ${e}`;
    }
    try {
      if (indexedDB.databases) {
        out.indexedDB = (await indexedDB.databases()).map((d) => d.name);
      } else {
        // No list in this engine: open the fixture's names; a new database has version 0.
        out.indexedDB = [];
        for (const name of ['siftlab-pwned', 'siftlab-pwned-nested']) {
          const existed = await new Promise((ok, fail) => {
            const r = indexedDB.open(name);
            let fresh = false;
            r.onupgradeneeded = (ev) => { fresh = ev.oldVersion === 0; };
            r.onsuccess = () => { r.result.close(); ok(!fresh); };
            r.onerror = () => fail(r.error);
          });
          if (existed) out.indexedDB.push(name);
          else indexedDB.deleteDatabase(name);
        }
      }
    } catch (e) {
      out.indexedDB = `unavailable: ${e}`;
    }
    try {
      const root = await navigator.storage.getDirectory();
      out.opfs = [];
      for await (const [name] of root.entries()) out.opfs.push(name);
    } catch (e) {
      out.opfs = `unavailable: ${e}`;
    }
    return out;
  });
}

function cliMarks(file) {
  // The file's bytes are the key (each suite marks its own copy of the same fixture).
  const args = ['--opencv-lanes', String(LANES), '-d', DATASET, 'mark', file, '-n', String(MARK_N), '--seed', '1', '--json'];
  const sha = crypto.createHash('sha256').update(fs.readFileSync(file)).digest('hex');
  const j = cliCached([...args, sha], () => JSON.parse(spawnSync(CLI, args, { cwd: ROOT, encoding: 'utf8', maxBuffer: 1 << 26 }).stdout));
  return {
    rows: j.tasks.map((t) => [t.task, t.marks.toFixed(2), String(t.correct), String(t.errors)]),
    total: j.total.toFixed(2),
    diagnoses: j.cases.filter((c) => c.status !== 'correct').map((c) => `${c.task}:${c.diagnosis}`),
  };
}

test('mark my code: a file trying every route to the origin writes nothing, reaches nothing, gets the CLI\'s table', async () => {
  let connections = 0;
  const server = net.createServer((s) => { connections += 1; s.destroy(); });
  await new Promise((ok, fail) => { server.once('error', fail); server.listen(0, '127.0.0.1', ok); });
  const port = server.address().port;
  const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'siftlab-isolation-'));
  try {
    // The fixture aims at this run's listener.
    const file = path.join(tmp, 'vision_tasks.py');
    const src = fs.readFileSync(FIXTURE, 'utf8');
    assert.match(src, /^PORT = 47012$/m);
    fs.writeFileSync(file, src.replace(/^PORT = 47012$/m, `PORT = ${port}`));

    await page.goto(`${BASE}?lanes=${LANES}&mark=1&mn=${MARK_N}`);
    await idle();
    const before = await originStorage();
    // The worker's messages the page ignores: the fixture's report of each route.
    await page.evaluate(() => {
      window.__probes = [];
      const Native = window.Worker;
      window.Worker = class extends Native {
        constructor(url, opts) {
          super(url, opts);
          this.addEventListener('message', (ev) => {
            if (ev.data && ev.data.type === 'isolationProbe') window.__probes.push(`${ev.data.route} => ${ev.data.outcome}`);
          });
        }
      };
    });
    await page.setInputFiles(tid('mark-file'), file);
    await page.waitForFunction((sel) => !document.querySelector(sel).disabled, tid('mark-run'), { timeout: 10000 }).catch(() => {});
    await page.click(tid('mark-run'));
    await page.waitForSelector(`${tid('mark-report')}, ${tid('mark-error')}`, { timeout: 900000 });
    if (await page.count(tid('mark-error'))) assert.fail(`the marking failed: ${await page.textContent(tid('mark-error'))}`);
    const rows = await page.evalAll(tid('mark-row'), (tr) => [tr.dataset.task, tr.dataset.marks, tr.dataset.correct, tr.dataset.errors]);
    const total = await page.getAttribute(tid('mark-total'), 'data-total');
    const diagnoses = await page.evalAll(tid('mark-failure'), (li) => `${li.dataset.task}:${li.dataset.diagnosis}`);
    // Writes the file started finish between its calls: give the last ones time.
    await new Promise((r) => setTimeout(r, 3000));
    const probes = await page.evaluate(() => window.__probes);
    metrics.isolationProbes = probes;

    // WebKit's SIMD128 Pyodide may time out an honest dt call (mark.test.mjs): only there is
    // dt left out of the comparison.
    const cli = cliMarks(file);
    const slowDt = ENGINE === 'webkit' && diagnoses.includes('dt:timeout');
    const keep = (list, key) => list.filter((x) => !(slowDt && key(x).startsWith('dt')));
    assert.deepEqual(keep(rows, (r) => r[0]), keep(cli.rows, (r) => r[0]));
    assert.deepEqual(keep(diagnoses, (d) => d), keep(cli.diagnoses, (d) => d));
    if (!slowDt) assert.equal(total, '20.00', 'its honest code earns 20');
    assert.equal(cli.total, '20.00', 'under CPython it is the good solution');
    metrics.isolationTotal = total;

    // A fresh load of the app's origin: what the file could have left there.
    await page.goto(BASE);
    const after = await originStorage();
    metrics.isolationStorage = { before, after };
    const empty = (v) => (Array.isArray(v) ? v.length === 0 : String(v).startsWith('unavailable'));
    assert.ok(empty(before.caches) && empty(before.indexedDB) && empty(before.opfs), `the origin held something before: ${JSON.stringify(before)}`);
    assert.deepEqual(after, before, `the file wrote to the origin's storage; routes: ${JSON.stringify(probes, null, 1)}`);
    const reached = probes.filter((p) => / => (reached|resolved|done)/.test(p) && !/^gc JsProxy/.test(p));
    assert.deepEqual(reached, [], 'routes the file reached');
  } finally {
    await new Promise((ok) => server.close(ok));
    fs.rmSync(tmp, { recursive: true, force: true });
  }
  metrics.isolationConnections = connections;
  assert.equal(connections, 0, 'a connection reached the listener');
});

// The second wall alone: were Python to find the worker's global again, what would it
// reach? A module worker of the page's (a blob:, as the marking worker) runs
// mark-lockdown.js with a stand-in Pyodide, and looks for each member as the fixture does:
// on `self`, then up its prototype chain (getters and values), and on the navigator's.
test('mark my code: the lock-down removes every member where it is defined', async () => {
  await page.goto(BASE);
  const got = await page.evaluate(async (lockdownUrl) => {
    const code = `
      import { lockDown } from ${JSON.stringify(lockdownUrl)};
      const NAMES = ['fetch', 'caches', 'indexedDB', 'importScripts', 'Worker', 'SharedWorker', 'XMLHttpRequest',
        'WebSocket', 'EventSource', 'BroadcastChannel', 'CacheStorage', 'IDBFactory', 'StorageManager',
        'FileSystemDirectoryHandle', 'webkitRequestFileSystem'];
      function find(obj, name) {
        for (let o = obj; o !== null; o = Object.getPrototypeOf(o)) {
          const d = Object.getOwnPropertyDescriptor(o, name);
          if (d) return (d.get ? d.get.call(obj) : Reflect.get(o, name, obj)) !== undefined ? 'reachable' : 'gone';
        }
        return 'gone';
      }
      function probe() {
        const out = {};
        for (const n of NAMES) out[n] = find(self, n);
        for (const n of ['storage', 'storageBuckets', 'locks', 'serviceWorker']) out['navigator.' + n] = find(self.navigator, n);
        out['StorageManager.prototype.getDirectory'] = typeof StorageManager === 'function' && StorageManager.prototype.getDirectory ? 'reachable' : 'gone';
        return out;
      }
      const before = probe();
      let failed = null;
      try { lockDown({ unregisterJsModule() {}, runPython() {} }); } catch (e) { failed = String(e); }
      postMessage({ before, after: probe(), failed, ua: navigator.userAgent.length > 0 });`;
    const url = URL.createObjectURL(new Blob([code], { type: 'text/javascript' }));
    const w = new Worker(url, { type: 'module' });
    return new Promise((ok, fail) => {
      w.onmessage = (ev) => { w.terminate(); ok(ev.data); };
      w.onerror = (ev) => fail(new Error(ev.message || 'the probe worker failed'));
    });
  }, new URL('mark-lockdown.js', BASE).href);
  metrics.lockdownProbe = got;
  assert.equal(got.failed, null);
  assert.ok(got.ua, 'navigator.userAgent kept');
  // What the engine has before the lock-down must be gone after it.
  assert.equal(got.before.fetch, 'reachable', JSON.stringify(got.before));
  assert.equal(got.before.indexedDB, 'reachable', JSON.stringify(got.before));
  const left = Object.entries(got.after).filter(([, v]) => v !== 'gone').map(([k]) => k);
  assert.deepEqual(left, [], JSON.stringify(got));
});
