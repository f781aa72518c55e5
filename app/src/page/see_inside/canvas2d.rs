//! Small canvas helpers shared by the "see inside" views.

use wasm_bindgen::{Clamped, JsCast};

/// The canvas's 2D context, sized `w`×`h`.
pub fn context(canvas: &web_sys::HtmlCanvasElement, w: u32, h: u32) -> Option<web_sys::CanvasRenderingContext2d> {
    canvas.set_width(w);
    canvas.set_height(h);
    canvas.get_context("2d").ok().flatten().and_then(|c| c.dyn_into::<web_sys::CanvasRenderingContext2d>().ok())
}

/// Puts RGBA pixels (`w`×`h`) at (x, y).
pub fn put_rgba(ctx: &web_sys::CanvasRenderingContext2d, rgba: &[u8], w: u32, h: u32, x: f64, y: f64) {
    if let Ok(img) = web_sys::ImageData::new_with_u8_clamped_array_and_sh(Clamped(rgba), w, h) {
        let _ = ctx.put_image_data(&img, x, y);
    }
}

/// Gray pixels as RGBA.
pub fn gray_rgba(gray: &[u8]) -> Vec<u8> {
    gray.iter().flat_map(|&g| [g, g, g, 255]).collect()
}
