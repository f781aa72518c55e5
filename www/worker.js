// The SIFT web worker: a module worker whose WebAssembly start function installs the
// message handler and then posts {type: "ready"} (the page queues requests until then).
import init from './pkg/siftlab_worker.js';

init().catch((e) => {
  // Surface start-up failures as a worker `error` event on the page side.
  setTimeout(() => { throw e; });
});
