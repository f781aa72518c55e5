// Loads the app's WebAssembly (built by www/build into pkg/); its start function mounts the page.
import init from './pkg/siftlab_app.js';

init().then((wasm) => {
  // The page's wasm memory in bytes, for the memory tests (tests/e2e/vo-memory.test.mjs).
  globalThis.siftlabWasmBytes = () => wasm.memory.buffer.byteLength;
}).catch((e) => {
  const p = document.createElement('p');
  p.className = 'fatal';
  p.textContent = 'siftlab could not start: ' + e + ' (this browser needs WebAssembly with SIMD, e.g. Chromium 91+, Firefox 89+, Safari 16.4+).';
  document.body.append(p);
  throw e;
});
