// The lock-down of the "Mark my code" worker (mark-worker.js calls it once Pyodide, our
// Python files and the matcher's WebAssembly are loaded, before any student code runs).
// The student's Python must reach nothing of the app's origin: no storage (CacheStorage,
// IndexedDB, OPFS, storage buckets, the old FileSystem API), no request (the CSP already
// keeps them to this origin), no nested worker (a fresh global with all of that) and no
// channel to the origin's other pages. Deleting a name from `self` is not enough: Web IDL
// puts a global's operations and attributes on its prototypes (WorkerGlobalScope.prototype,
// WorkerNavigator.prototype...) in some engines, so each member is removed where it is
// really defined, the prototypes of the interfaces that hold storage are emptied (an
// instance captured before would be inert), `navigator` becomes a plain copy of what
// Pyodide reads, and the result is checked: a member still reachable stops the worker
// (the page reports that Python could not start) rather than run the student's code.

// Names removed from `self` and every prototype above it: values, getters and interface
// objects (constructors) alike.
const DENIED = [
  // requests and connections
  'fetch', 'XMLHttpRequest', 'XMLHttpRequestEventTarget', 'XMLHttpRequestUpload', 'WebSocket',
  'WebSocketStream', 'EventSource', 'WebTransport', 'RTCPeerConnection', 'RTCDataChannel',
  'importScripts',
  // other globals and the origin's other pages
  'Worker', 'SharedWorker', 'ServiceWorker', 'ServiceWorkerContainer', 'ServiceWorkerRegistration',
  'BroadcastChannel', 'LockManager', 'Lock',
  // storage of the origin
  'indexedDB', 'IDBFactory', 'IDBDatabase', 'IDBObjectStore', 'IDBTransaction', 'IDBRequest',
  'IDBOpenDBRequest', 'IDBIndex', 'IDBCursor', 'IDBCursorWithValue', 'IDBKeyRange',
  'IDBVersionChangeEvent', 'IDBRecord',
  'caches', 'CacheStorage', 'Cache',
  'StorageManager', 'StorageBucketManager', 'StorageBucket',
  'FileSystemHandle', 'FileSystemDirectoryHandle', 'FileSystemFileHandle',
  'FileSystemSyncAccessHandle', 'FileSystemWritableFileStream', 'FileSystemObserver',
  'webkitRequestFileSystem', 'webkitRequestFileSystemSync', 'webkitResolveLocalFileSystemURL',
  'webkitResolveLocalFileSystemSyncURL', 'requestFileSystem', 'requestFileSystemSync',
  'cookieStore', 'CookieStore',
  // the navigator (replaced below by a plain object) and its interface
  'navigator', 'WorkerNavigator',
];

// Interfaces whose prototypes are emptied (every member but `constructor`), so that an
// instance obtained before the lock-down (none is known) can do nothing.
const EMPTIED = [
  'IDBFactory', 'IDBDatabase', 'IDBObjectStore', 'IDBTransaction', 'CacheStorage', 'Cache',
  'StorageManager', 'StorageBucketManager', 'StorageBucket', 'FileSystemHandle',
  'FileSystemDirectoryHandle', 'FileSystemFileHandle', 'FileSystemSyncAccessHandle',
  'FileSystemWritableFileStream', 'WorkerNavigator', 'Worker', 'SharedWorker',
  'BroadcastChannel', 'XMLHttpRequest', 'WebSocket', 'EventSource', 'LockManager',
];

// What of the navigator stays (read by Pyodide and Emscripten): plain values.
const NAVIGATOR_KEPT = ['userAgent', 'language', 'languages', 'hardwareConcurrency', 'platform'];

function chain(obj) {
  const out = [];
  for (let o = obj; o !== null && o !== Object.prototype && o !== Function.prototype; o = Object.getPrototypeOf(o)) out.push(o);
  return out;
}

function strip(obj, name) {
  try { delete obj[name]; } catch (_) { /* checked below */ }
}

/** Locks the worker's global down; `py` is the Pyodide API. Throws when a member stays. */
export function lockDown(py) {
  // Python first: no module of it names JavaScript any more (`import js`, `pyodide_js`);
  // the harness keeps its one JsProxy, the matcher's function.
  for (const m of ['js', 'pyodide_js']) {
    try { py.unregisterJsModule(m); } catch (_) { /* not registered */ }
  }
  py.runPython(`
def _forget_js():
    import sys
    for name in ('js', 'pyodide_js'):
        gone = sys.modules.pop(name, None)
        if gone is None:
            continue
        for mod in list(sys.modules.values()):
            try:
                d = vars(mod)
            except TypeError:
                continue
            for k, v in list(d.items()):
                if v is gone:
                    del d[k]
_forget_js()
del _forget_js
`);

  const nav = self.navigator;
  const kept = {};
  for (const k of NAVIGATOR_KEPT) {
    const v = nav ? nav[k] : undefined;
    kept[k] = Array.isArray(v) ? Object.freeze([...v]) : v;
  }
  const navChain = nav ? chain(nav) : [];
  const interfaces = EMPTIED.map((n) => self[n]).filter((c) => typeof c === 'function' && c.prototype);
  for (const c of interfaces) {
    for (const k of Reflect.ownKeys(c.prototype)) if (k !== 'constructor') strip(c.prototype, k);
  }
  for (const o of navChain) for (const k of Reflect.ownKeys(o)) strip(o, k);
  for (const o of chain(self)) for (const name of DENIED) strip(o, name);
  Object.defineProperty(self, 'navigator', { value: Object.freeze(kept), enumerable: true });

  const left = DENIED.filter((n) => n !== 'navigator' && (n in self || chain(self).some((o) => Object.getOwnPropertyDescriptor(o, n))));
  for (const o of navChain) left.push(...Reflect.ownKeys(o).map((k) => `navigator.${String(k)}`));
  for (const k of ['storage', 'storageBuckets', 'locks', 'serviceWorker', 'sendBeacon']) {
    if (k in self.navigator) left.push(`navigator.${k}`);
  }
  if (left.length) throw new Error(`the worker could not remove ${left.join(', ')}`);
}
