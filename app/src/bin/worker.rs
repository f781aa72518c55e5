//! The SIFT web worker (loaded by `worker.js` as a module worker).

fn main() {
    siftlab_app::worker::start();
}
