//! The page: mounts the explorer on <body>.

fn main() {
    siftlab_app::install_panic_hook();
    // `?wasm=portable` keeps the workers on the SIMD128 build even where relaxed
    // SIMD is available (www/worker.js): to compare the two, or as a way out if
    // an engine's relaxed build misbehaves. Read once, before any worker starts.
    let query = web_sys::window().and_then(|w| w.location().search().ok()).unwrap_or_default();
    let params = web_sys::UrlSearchParams::new_with_str(&query).ok();
    if params.and_then(|p| p.get("wasm")).as_deref() == Some("portable") {
        siftlab_app::client::set_worker_script("./worker.js?wasm=portable");
    }
    leptos::mount::mount_to_body(siftlab_app::App);
}
