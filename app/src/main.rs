//! The page: mounts the explorer on <body>.

fn main() {
    siftlab_app::install_panic_hook();
    leptos::mount::mount_to_body(siftlab_app::App);
}
