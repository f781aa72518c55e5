// The SIFT web worker: a module worker whose WebAssembly start function installs the
// message handler and then posts {type: "ready"} (the page queues requests until then).
//
// www/build makes two builds of it. pkg/siftlab_worker needs WebAssembly SIMD128 (every
// browser siftlab targets). pkg/siftlab_worker_relaxed adds relaxed SIMD, so that SIFT's
// Gaussian blur, most of its time, runs on the engine's fused multiply-add (the operation
// OpenCV performs) instead of emulating it exactly: about 3x faster SIFT, same results.
// That build checks at start that the engine's relaxed_madd really is fused, and emulates
// otherwise. A module using relaxed SIMD does not compile where the engine lacks it
// (Safari), so this 37-byte module using f32x4.relaxed_madd is validated first.
// `worker.js?wasm=portable` (the page's `?wasm=portable`) forces the SIMD128 build.
const RELAXED_MADD = new Uint8Array([
  0x00, 0x61, 0x73, 0x6d, 0x01, 0x00, 0x00, 0x00, // \0asm, version 1
  0x01, 0x08, 0x01, 0x60, 0x03, 0x7b, 0x7b, 0x7b, 0x01, 0x7b, // type: (v128 v128 v128) -> v128
  0x03, 0x02, 0x01, 0x00, // one function of that type
  0x0a, 0x0d, 0x01, 0x0b, 0x00, 0x20, 0x00, 0x20, 0x01, 0x20, 0x02, // local.get 0, 1, 2
  0xfd, 0x85, 0x02, 0x0b, // f32x4.relaxed_madd, end
]);

const portable = new URL(self.location.href).searchParams.get('wasm') === 'portable';
const relaxed = !portable && WebAssembly.validate(RELAXED_MADD);

const start = (build) => import(`./pkg/${build}.js`).then((m) => m.default());
(relaxed
  // A relaxed build that cannot start (a partial deployment, an engine that validates
  // relaxed SIMD but fails to compile it) leaves the SIMD128 one to try.
  ? start('siftlab_worker_relaxed').catch((e) => {
    console.warn('siftlab: the relaxed-SIMD worker did not start, using the SIMD128 one:', e);
    return start('siftlab_worker');
  })
  : start('siftlab_worker'))
  .catch((e) => {
    // Surface start-up failures as a worker `error` event on the page side.
    setTimeout(() => { throw e; });
  });
