//! The odometry figures: the core's top view and error plot
//! (`siftlab_core::render::plot`, what the CLI's `--plot` writes) shown as
//! SVG, with the frame under the pointer, and exported as PNG or SVG.

use crate::model::odometry::{error_hover_text, hover_text};
use leptos::prelude::*;
use siftlab_core::render::plot::axes::{Map, TopDown};
use siftlab_core::render::plot::figures::{error_figure, report_figure, run_errors, trajectory_figure, Run};
use siftlab_core::render::plot::{raster::rasterize, svg::to_svg};
use wasm_bindgen::JsCast;

type P3 = [f64; 3];
/// Width of the figures in scene pixels (CSS scales them to the page).
const W: u32 = 560;

/// Saves `bytes` as a file named `name` (a temporary link clicked once).
fn save(bytes: &[u8], name: &str) {
    let parts = js_sys::Array::new();
    parts.push(&js_sys::Uint8Array::from(bytes));
    let Ok(blob) = web_sys::Blob::new_with_u8_array_sequence(&parts) else { return };
    let Ok(url) = web_sys::Url::create_object_url_with_blob(&blob) else { return };
    if let Some(a) = document().create_element("a").ok().and_then(|e| e.dyn_into::<web_sys::HtmlElement>().ok()) {
        let _ = a.set_attribute("href", &url);
        let _ = a.set_attribute("download", name);
        a.click();
    }
    let _ = web_sys::Url::revoke_object_url(&url);
}

/// The pointer's position in scene pixels of the figure it is over.
fn scene_xy(ev: &web_sys::MouseEvent, w: u32, h: u32) -> Option<(f64, f64)> {
    let el: web_sys::Element = ev.current_target()?.dyn_into().ok()?;
    let r = el.get_bounding_client_rect();
    crate::model::plot::to_composite(
        ev.client_x() as f64 - r.left(),
        ev.client_y() as f64 - r.top(),
        r.width(),
        r.height(),
        w as usize,
        h as usize,
    )
}

/// Both figures for `truth` and `runs`; `name` is the exported files' stem.
#[component]
pub fn OdometryFigures(truth: Signal<Vec<P3>>, runs: Signal<Vec<Run>>, name: &'static str) -> impl IntoView {
    let top = Memo::new(move |_| {
        let (scene, td) = truth.with(|t| runs.with(|r| trajectory_figure(t, r, W, W)));
        (to_svg(&scene, Some(&format!("{name}-plot"))), scene.height, td)
    });
    let errors = Memo::new(move |_| {
        let e = truth.with(|t| runs.with(|r| run_errors(t, r)));
        let (scene, x, _): (_, Map, Map) = error_figure(&e, W, W * 3 / 8);
        let named: Vec<(String, Vec<f64>)> = e.into_iter().map(|(n, _, v)| (n, v)).collect();
        (to_svg(&scene, Some(&format!("{name}-error-plot"))), scene.height, x, named)
    });
    let hover = RwSignal::new(None::<String>);
    let on_top = move |ev: web_sys::MouseEvent| {
        let (_, h, td): (String, u32, TopDown) = top.get_untracked();
        let Some((px, py)) = scene_xy(&ev, W, h) else { return };
        let (x, z) = (td.x.value(px), td.z.value(py));
        let text = truth
            .with_untracked(|t| runs.with_untracked(|r| r.last().and_then(|run| hover_text(&run.positions, t, x, z))));
        hover.set(text);
    };
    let on_err = move |ev: web_sys::MouseEvent| {
        let (_, h, x, named) = errors.get_untracked();
        let Some((px, _)) = scene_xy(&ev, W, h) else { return };
        hover.set(error_hover_text(x.value(px), &named));
    };
    let export = move |svg: bool| {
        let scene = truth.with_untracked(|t| runs.with_untracked(|r| report_figure(t, r, 720)));
        if svg {
            save(to_svg(&scene, None).as_bytes(), &format!("{name}.svg"));
        } else if let Ok(png) = siftlab_core::render::encode_png(&rasterize(&scene)) {
            save(&png, &format!("{name}.png"));
        }
    };
    view! {
        <div class="vo-figures">
            <div class="vo-fig" on:mousemove=on_top on:mouseleave=move |_| hover.set(None) inner_html=move || top.with(|t| t.0.clone())></div>
            <div class="vo-fig" on:mousemove=on_err on:mouseleave=move |_| hover.set(None) inner_html=move || errors.with(|e| e.0.clone())></div>
            <p class="mono small vo-hover" data-testid=format!("{name}-hover")>{move || hover.get().unwrap_or_else(|| "point at a figure: frame, position, error".into())}</p>
            <p class="small">
                "Export (both figures): "
                <button data-testid=format!("{name}-png") on:click=move |_| export(false)>"PNG"</button>" "
                <button data-testid=format!("{name}-svg") on:click=move |_| export(true)>"SVG"</button>
            </p>
        </div>
    }
}
