// The "Mark my code" worker: the student's vision_tasks.py runs here, in Pyodide (CPython
// compiled to WebAssembly, served from our origin: dist/pyodide/), with our `cv2` and
// `vision_tasks_base` (dist/py/). Its BFMatcher().knnMatch is answered by siftlab's own
// matcher (the worker's WebAssembly build, mark_host_knn), never computed in Python.
//
// The page first sends {op: "start", snapshot, warm, module}: the memory snapshot of a Python
// that has just started (below), the reference time that start measured and Pyodide's
// compiled WebAssembly, or none; the worker answers {type: "markReady"} once Python is up.
// Then the page sends {id, op, line}: one request of docs/marking.md's protocol; the worker
// answers {type: "markReply", id, line}. A call that runs too long is stopped by the page,
// which terminates this worker and starts another (Python cannot be interrupted from
// outside without cross-origin isolation). The page also sends the request's limit: past it
// the worker interrupts its own Python too, since JavaScriptCore keeps a terminated worker's
// WebAssembly running (an endless loop would hold a core until the page closes).
//
// The page starts this module from a `blob:` URL (`import "<this URL>"`), so the worker runs
// under the page's Content-Security-Policy (connect-src 'self', no 'unsafe-eval'): whatever
// JavaScript the student's Python reaches, it cannot fetch from another origin or evaluate
// code. Relative URLs here resolve against import.meta.url, this file's real address.
import { loadPyodide } from './pyodide/pyodide.mjs';
import { lockDown } from './mark-lockdown.js';

// Every file of core/mark/py/ (siftlab_mark::HARNESS_FILES; its test checks this list): the
// harness imports its parts and cv2's from the folder it is in.
const FILES = [
  'cv2.py', '_siftlab_cv2_base.py', '_siftlab_cv2_types.py', '_siftlab_cv2_descriptors.py',
  'vision_tasks_base.py', 'siftlab_harness.py', '_siftlab_harness_run.py',
  '_siftlab_harness_values.py', '_siftlab_harness_imports.py',
];

// The reference workload (docs/marking.md, "Mark my code"): what an honest call spends its
// time on in Pyodide, building DMatch objects from the matcher's answer the way cv2's
// knnMatch does and reading their distances the way a dt does (150,000 of them, 1/15 of the
// slowest honest dt call), with the harness's own DMatch class. Timed here, before the
// student's file is loaded, so that the page scales its wall-clock limits by how fast this
// machine, this engine and its current load run it.
const REFERENCE = `
def _siftlab_reference():
    import sys
    from itertools import repeat
    _Match = sys.modules['siftlab_harness'].cv2._Match
    kk, nq = 150, 1000
    tl = list(range(kk)) * nq
    dl = [i * 0.37 for i in range(kk)] * nq
    rows = tuple([tuple(map(_Match, repeat(q, kk), tl[q * kk:(q + 1) * kk], repeat(0, kk),
                            dl[q * kk:(q + 1) * kk])) for q in range(nq)])
    return sum(len([m for m in row if m.distance < 30.0]) for row in rows)
`;

// The median of three timed runs after untimed ones (the engine's first tiers are not what
// an honest call, which comes after the file's load, runs in), in ms. A Python started afresh
// has run CPython's start-up, so one untimed run suffices. One started from a snapshot (below)
// has run none of it: measured in WebKit, its first runs took 2-9x a warmed run and came down
// to it over 5-12 runs (Chromium and Firefox were at speed from the second run either way).
// So it runs untimed until a run is within 25 % of `warm`, the time the page's fresh start
// measured, or for at most 12 runs and 4 s: a machine that got busier since measures slower.
function timeReference(py, warm) {
  py.runPython(REFERENCE);
  const run = py.globals.get('_siftlab_reference');
  try {
    const t0 = performance.now();
    for (let i = 0; i < 12; i += 1) {
      const t = performance.now();
      run();
      const took = performance.now() - t;
      if (!(warm > 0) || took <= 1.25 * warm || performance.now() - t0 > 4000) break;
    }
    const ms = [];
    for (let i = 0; i < 3; i += 1) {
      const t = performance.now();
      run();
      ms.push(performance.now() - t);
    }
    return ms.sort((a, b) => a - b)[1];
  } finally {
    run.destroy();
    py.runPython('del _siftlab_reference\nimport gc\ngc.collect()');
  }
}

// The worker's own stop. Pyodide reads element 0 of its "interrupt buffer" every 50 of
// CPython's eval-breaker checks (loop back-edges, calls) and raises the signal it finds there
// (2: SIGINT, KeyboardInterrupt); it needs no SharedArrayBuffer when the reader is the worker
// itself. Here the read is a getter on the worker's own clock: 0 until the request's deadline,
// then 2 at every read (a student's `except BaseException` cannot make it stop asking).
// The deadline runs from this worker's receipt of the request, so it never comes before the
// page's, which runs from the sending. A call stopped this way gets no reply: the page's own
// time-out decides (a reply after the limit counts as a time-out anyway:
// core::mark::Session::outcome), so the verdict is the page's whichever clock fires first.
// The page terminates a worker at the limit; this ends what an engine leaves running, at once
// (a loop left for a grace slowed the next start's speed measurement 2.2x in WebKit).
let deadline = Infinity;
let overran = false;
const STOP = {
  get 0() {
    if (performance.now() <= deadline) return 0;
    overran = true;
    return 2;
  },
  set 0(_) { /* Pyodide clears the slot after each read: the getter decides alone */ },
};

// Python from a memory snapshot: Pyodide can save the heap of a Python that has just
// started and start another from it without running CPython's start-up again (measured on
// one machine: WebKit 6.6 s -> 0.8 s, Chromium and Firefox 2.5 s -> 0.3-0.5 s). The page's
// first worker starts Python afresh and snapshots it at once, before our files, the lock-down
// or any student code exist in it, and hands the bytes to the page; the page gives them to
// the workers it starts after (a restart after a time-out, the next file marked). Pyodide
// checks the snapshot's build; one it refuses, a fresh start replaces.
async function python(snapshot, module) {
  const indexURL = new URL('./pyodide/', import.meta.url).href;
  // The student's prints are captured by the harness; anything else is a log line.
  const io = { stdout: (s) => console.log('[python]', s), stderr: (s) => console.warn('[python]', s) };
  if (snapshot) {
    try {
      const { value: py, compiled } = await withCompiled(module, () => loadPyodide({ indexURL, ...io, _loadSnapshot: snapshot }));
      return { py, from: 'snapshot', compiled };
    } catch (e) {
      console.warn('[mark] the Python snapshot did not load, starting afresh:', String(e && e.message ? e.message : e));
    }
  }
  const { value: py, compiled } = await withCompiled(module, () => loadPyodide({ indexURL, ...io, _makeSnapshot: true }));
  return { py, from: 'fresh', made: py.makeMemorySnapshot(), compiled };
}

// Pyodide's compiled WebAssembly, shared: each worker would compile its 9.6 MB again, and an
// engine that compiles in tiers (JavaScriptCore, measured in WebKit: ~6 CPU-s a start, its
// restored Pythons 2-9x slow for their first runs) runs a new compile's slow tiers first. A
// WebAssembly.Module posted to another worker shares its code, optimised tiers included. The
// first worker hands its module to the page with the snapshot; each later one instantiates it
// instead of compiling. Pyodide compiles with instantiateStreaming, which is routed here
// while `load` runs (before our files or any student code exist in this worker), then put back.
async function withCompiled(module, load) {
  const streaming = WebAssembly.instantiateStreaming;
  let compiled = null;
  WebAssembly.instantiateStreaming = async (source, imports) => {
    if (module instanceof WebAssembly.Module) {
      try {
        const instance = await WebAssembly.instantiate(module, imports);
        // The response is not read: the compiled module stands for it.
        Promise.resolve(source).then((r) => r.body && r.body.cancel()).catch(() => {});
        compiled = module;
        return { instance, module };
      } catch (e) {
        console.warn('[mark] the shared Pyodide module did not instantiate, compiling:', String(e && e.message ? e.message : e));
      }
    }
    const made = await streaming.call(WebAssembly, source, imports);
    compiled = made.module;
    return made;
  };
  try {
    return { value: await load(), compiled };
  } finally {
    WebAssembly.instantiateStreaming = streaming;
  }
}

async function start(snapshot, warm, module) {
  const t0 = performance.now();
  // The SIMD128 build: it runs in every engine, and k-NN needs no relaxed SIMD. Its start
  // function leaves this worker alone (the worker is named "siftlab-mark").
  const wasm = await import('./pkg/siftlab_worker.js');
  await wasm.default();
  const { py, from, made, compiled } = await python(snapshot, module);
  // Before the reference workload: what it times includes the reads (one per 50 checks).
  py.setInterruptBuffer(STOP);
  for (const f of FILES) {
    const r = await fetch(new URL(`./py/${f}`, import.meta.url));
    if (!r.ok) throw new Error(`py/${f}: HTTP ${r.status}`);
    py.FS.writeFile(f, await r.text());
  }
  py.runPython("import sys\nif '.' not in sys.path: sys.path.insert(0, '.')");
  const harness = py.pyimport('siftlab_harness');
  // A fresh start: one untimed run (`warm` 0 stops after it).
  const reference = timeReference(py, from === 'snapshot' ? warm : 0);
  harness.host_knn = (line) => wasm.mark_host_knn(line);
  // Python starts only now; what it must not reach goes first (mark-lockdown.js): the
  // network, this origin's storage, nested workers, and JavaScript from Python's imports.
  lockDown(py);
  return { wasm, harness, ms: performance.now() - t0, reference, from, made, compiled, shared: compiled !== null && compiled === module };
}

// Started by the page's first message, which carries the snapshot (or none).
let ready = null;

onmessage = async (ev) => {
  const { id, op, line, limit } = ev.data;
  if (op === 'start') {
    if (ready) return;
    ready = start(ev.data.snapshot, Number(ev.data.warm) || 0, ev.data.module);
    ready.then(
      // The snapshot and the compiled module go to the page before the student's file is
      // sent to this worker (a module is shared, not copied).
      ({ ms, reference, from, made, compiled, shared }) => postMessage(
        {
          type: 'markReady', ms, reference, from, snapshot: made, module: made ? compiled : undefined,
          compiled: shared ? 'shared' : 'compiled',
        }, made ? [made.buffer] : []),
      (e) => postMessage({ type: 'markFailed', message: `Python could not start: ${e && e.message ? e.message : e}` }),
    );
    return;
  }
  if (overran) return; // stopped past a deadline: the page has ended this worker
  let reply;
  try {
    if (!ready) throw new Error('a request came before the start');
    const { wasm, harness } = await ready;
    // A pair's features are kept on both sides: Python's copy for the student's code,
    // the matcher's for knnMatch requests that name them ("K/1", "K/2").
    if (op === 'pair') wasm.mark_host_pair(ev.data);
    deadline = Number.isFinite(limit) && limit > 0 ? performance.now() + limit : Infinity;
    try {
      reply = harness.handle(line);
    } finally {
      deadline = Infinity;
    }
    if (overran) return;
  } catch (e) {
    if (overran) return;
    // The harness catches whatever the student's code raises, so a throw here means Python
    // itself ended: os._exit() makes Pyodide throw "Program terminated with exit(N)" and
    // refuse every later call. That is the native marker's crash (the process ended), told
    // at once rather than at the call's time limit.
    postMessage({ type: 'markCrashed', id, message: String(e && e.message ? e.message : e) });
    return;
  }
  postMessage({ type: 'markReply', id, line: reply });
};
