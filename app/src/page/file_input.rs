//! Reading what a user gives a file input or drops on a zone, for every
//! feature that takes files (frames, a student's file, a class summary).

use leptos::prelude::*;

/// The first file a drop carries; the browser's own handling (opening the
/// file in the tab, which would lose the page's state) is stopped.
pub fn dropped_file(ev: &web_sys::DragEvent) -> Option<web_sys::File> {
    ev.prevent_default();
    ev.data_transfer().and_then(|d| d.files()).and_then(|l| l.get(0))
}

/// Every file an `<input type="file">` holds after its `change` event.
pub fn picked_files(ev: &web_sys::Event) -> Vec<web_sys::File> {
    let input: web_sys::HtmlInputElement = event_target(ev);
    input.files().map(|l| (0..l.length()).filter_map(|i| l.get(i)).collect()).unwrap_or_default()
}

/// The first file an `<input type="file">` holds; the input is emptied so
/// that picking the same file again fires `change` again.
pub fn take_picked_file(ev: &web_sys::Event) -> Option<web_sys::File> {
    let input: web_sys::HtmlInputElement = event_target(ev);
    let file = input.files().and_then(|l| l.get(0));
    input.set_value("");
    file
}
