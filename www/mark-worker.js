// The "Mark my code" worker: the student's vision_tasks.py runs here, in Pyodide (CPython
// compiled to WebAssembly, served from our origin: dist/pyodide/), with our `cv2` and
// `vision_tasks_base` (dist/py/). Its BFMatcher().knnMatch is answered by siftlab's own
// matcher (the worker's WebAssembly build, mark_host_knn), never computed in Python.
//
// The page sends {id, op, line}: one request of docs/marking.md's protocol; the worker
// answers {type: "markReply", id, line}. A call that runs too long is stopped by the page,
// which terminates this worker and starts another (Python cannot be interrupted from
// outside without cross-origin isolation).
//
// The page starts this module from a `blob:` URL (`import "<this URL>"`), so the worker runs
// under the page's Content-Security-Policy (connect-src 'self', no 'unsafe-eval'): whatever
// JavaScript the student's Python reaches, it cannot fetch from another origin or evaluate
// code. Relative URLs here resolve against import.meta.url, this file's real address.
import { loadPyodide } from './pyodide/pyodide.mjs';
import { lockDown } from './mark-lockdown.js';

const FILES = ['cv2.py', 'vision_tasks_base.py', 'siftlab_harness.py'];

async function start() {
  const t0 = performance.now();
  // The SIMD128 build: it runs in every engine, and k-NN needs no relaxed SIMD. Its start
  // function leaves this worker alone (the worker is named "siftlab-mark").
  const wasm = await import('./pkg/siftlab_worker.js');
  await wasm.default();
  const py = await loadPyodide({
    indexURL: new URL('./pyodide/', import.meta.url).href,
    // The student's prints are captured by the harness; anything else is a log line.
    stdout: (s) => console.log('[python]', s),
    stderr: (s) => console.warn('[python]', s),
  });
  for (const f of FILES) {
    const r = await fetch(new URL(`./py/${f}`, import.meta.url));
    if (!r.ok) throw new Error(`py/${f}: HTTP ${r.status}`);
    py.FS.writeFile(f, await r.text());
  }
  py.runPython("import sys\nif '.' not in sys.path: sys.path.insert(0, '.')");
  const harness = py.pyimport('siftlab_harness');
  harness.host_knn = (line) => wasm.mark_host_knn(line);
  // Python starts only now; what it must not reach goes first (mark-lockdown.js): the
  // network, this origin's storage, nested workers, and JavaScript from Python's imports.
  lockDown(py);
  return { wasm, harness, ms: performance.now() - t0 };
}

const ready = start();
ready.then(
  ({ ms }) => postMessage({ type: 'markReady', ms }),
  (e) => postMessage({ type: 'markFailed', message: `Python could not start: ${e && e.message ? e.message : e}` }),
);

onmessage = async (ev) => {
  const { id, op, line } = ev.data;
  let reply;
  try {
    const { wasm, harness } = await ready;
    // A pair's features are kept on both sides: Python's copy for the student's code,
    // the matcher's for knnMatch requests that name them ("K/1", "K/2").
    if (op === 'pair') wasm.mark_host_pair(ev.data);
    reply = harness.handle(line);
  } catch (e) {
    reply = JSON.stringify({ error: `the marking worker failed: ${e && e.message ? e.message : e}`, kind: 'host' });
  }
  postMessage({ type: 'markReply', id, line: reply });
};
