//! The page: mounts the explorer on <body>.

fn main() {
    siftlab_app::install_panic_hook();
    // `?wasm=portable` keeps the workers on the SIMD128 build even where relaxed
    // SIMD is available (www/worker.js): to compare the two, or as a way out if
    // an engine's relaxed build misbehaves. Read once, before any worker starts.
    let query = web_sys::window().and_then(|w| w.location().search().ok()).unwrap_or_default();
    if query.trim_start_matches('?').split('&').any(|p| p == "wasm=portable") {
        siftlab_app::client::set_worker_script("./worker.js?wasm=portable");
    }
    leptos::mount::mount_to_body(siftlab_app::App);
}
