//! The page: mounts the explorer on <body>.

fn main() {
    siftlab_app::install_panic_hook();
    // `?wasm=portable` keeps the workers on the SIMD128 build even where relaxed
    // SIMD is available (www/worker.js): to compare the two, or as a way out if
    // an engine's relaxed build misbehaves. Read once, before any worker starts.
    let query = web_sys::window().and_then(|w| w.location().search().ok()).unwrap_or_default();
    let params = web_sys::UrlSearchParams::new_with_str(&query).ok();
    if params.as_ref().and_then(|p| p.get("wasm")).as_deref() == Some("portable") {
        siftlab_app::services::sift_pool::set_worker_script("./worker.js?wasm=portable");
    }
    // `workers=N`: the number of SIFT workers, instead of the machine's cores − 1
    // (a teacher on a shared machine, or a test checking every count gives the same).
    if let Some(text) = params.as_ref().and_then(|p| p.get("workers")) {
        match siftlab_app::model::parse::parse_workers(&text) {
            Ok(n) => siftlab_app::services::sift_pool::set_workers(Some(n)),
            Err(e) => web_sys::console::warn_1(&format!("siftlab: {e}").into()),
        }
    }
    leptos::mount::mount_to_body(siftlab_app::App);
}
