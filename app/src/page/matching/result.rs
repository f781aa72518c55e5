//! The `ret value:` line exactly as the CLI prints it, and the table of matches.

use super::manual::ManualComparison;
use crate::model::lab::{Lab, Which};
use leptos::prelude::*;
use siftlab_core::pyfmt::py_float;
use siftlab_core::render;
use siftlab_core::GrayImage;
use wasm_bindgen::JsCast;

/// The lab's two pictures of the current result, drawn by the core's renderer
/// exactly as `siftlab view_feature` / `view_info` write them.
#[derive(Clone, Copy, PartialEq)]
enum Picture {
    /// `opencv_visual.png`: drawMatchesKnn of the feature.
    Feature,
    /// `custom_visual.png`: that image above the frames with the green circles.
    Info,
}

fn render_png(lab: Lab, which: Picture) -> Result<Vec<u8>, String> {
    let a = lab.analysis.get_untracked().ok_or("load the frames first")??;
    let p = lab.frame(Which::Prev).get_untracked().ok_or("load the frames first")?;
    let c = lab.frame(Which::Cur).get_untracked().ok_or("load the frames first")?;
    let e = |e: siftlab_core::Error| e.to_string();
    let pi = GrayImage::new(p.width, p.height, p.gray.clone()).map_err(e)?;
    let ci = GrayImage::new(c.width, c.height, c.gray.clone()).map_err(e)?;
    let (pk, ck, m) = (&p.features.keypoints, &c.features.keypoints, &a.explanation.matches);
    let img = match which {
        Picture::Feature => render::view_feature(&pi, pk, &ci, ck, m).map_err(e)?,
        Picture::Info => render::view_info(&pi, pk, &ci, ck, m, &a.explanation.info).map_err(e)?,
    };
    render::encode_png(&img).map_err(e)
}

/// Offers `bytes` as a file download (a temporary blob URL on a hidden link).
fn download(bytes: &[u8], name: &str) -> Result<(), String> {
    let parts = js_sys::Array::new();
    parts.push(&js_sys::Uint8Array::from(bytes));
    let blob = web_sys::Blob::new_with_u8_array_sequence(&parts).map_err(|e| format!("{e:?}"))?;
    let url = web_sys::Url::create_object_url_with_blob(&blob).map_err(|e| format!("{e:?}"))?;
    let doc = web_sys::window().and_then(|w| w.document()).ok_or("no document")?;
    let a: web_sys::HtmlElement = doc.create_element("a").map_err(|e| format!("{e:?}"))?.unchecked_into();
    let _ = a.set_attribute("href", &url);
    let _ = a.set_attribute("download", name);
    a.click();
    // The download has its own reference; the URL can go once the click is handled.
    let cb = wasm_bindgen::closure::Closure::once_into_js(move || {
        let _ = web_sys::Url::revoke_object_url(&url);
    });
    if let Some(w) = web_sys::window() {
        let _ = w.set_timeout_with_callback_and_timeout_and_arguments_0(cb.unchecked_ref(), 10_000);
    }
    Ok(())
}

/// Matches listed in full up to this many (dt with a large threshold can match
/// most of the frame).
const TABLE_ROWS: usize = 200;

#[component]
pub fn ResultPanel() -> impl IntoView {
    let lab = expect_context::<Lab>();
    let copied = RwSignal::new(false);
    let tuple = move || lab.analysis.with(|a| a.as_ref().and_then(|r| r.as_ref().ok()).map(|a| a.tuple.clone()));
    Effect::new(move |_| {
        lab.analysis.track();
        copied.set(false);
    });
    let copy = move |_| {
        if let (Some(t), Some(w)) = (tuple(), web_sys::window()) {
            let _ = w.navigator().clipboard().write_text(&t);
            copied.set(true);
        }
    };
    let export_error = RwSignal::new(None::<String>);
    let export = move |which: Picture| {
        let name = match which {
            Picture::Feature => "opencv_visual.png",
            Picture::Info => "custom_visual.png",
        };
        export_error.set(render_png(lab, which).and_then(|png| download(&png, name)).err());
    };
    let table = move || {
        let a = lab.analysis.get()?.ok()?;
        let cur = lab.frame(Which::Cur).get()?;
        let m = &a.explanation.matches;
        let info = &a.explanation.info;
        let rows = m
            .iter()
            .take(TABLE_ROWS)
            .enumerate()
            .map(|(i, d)| {
                let k = cur.features.keypoints.get(d.train_idx).copied();
                let (ix, iy) = info.points.get(i).copied().unwrap_or((0, 0));
                view! {
                    <tr>
                        <td class="r">{i}</td>
                        <td class="r">{d.train_idx}</td>
                        <td class="r mono">{k.map(|k| format!("({}, {})", py_float(k.x as f64), py_float(k.y as f64))).unwrap_or_default()}</td>
                        <td class="r mono">{format!("({ix}, {iy})")}</td>
                        <td class="r mono">{py_float(d.distance as f64)}</td>
                    </tr>
                }
            })
            .collect_view();
        let more = (m.len() > TABLE_ROWS)
            .then(|| view! { <p class="muted">{format!("… and {} more matches", m.len() - TABLE_ROWS)}</p> });
        Some(view! {
            <p class="muted">
                {format!(
                    "{} match{} · ret count: {} · computed in {:.1} ms",
                    m.len(),
                    if m.len() == 1 { "" } else { "es" },
                    m.len(),
                    a.ms
                )}
            </p>
            {(!m.is_empty()).then(|| view! {
                // Wider than a phone: it scrolls in its own region, which the keyboard can reach.
                <div class="table-wrap" tabindex="0" role="region" aria-label="Matches of the selected feature">
                    <table class="matches" data-testid="match-table">
                        <thead>
                            <tr>
                                <th>"#"</th><th>"train id"</th><th>"keypoint pt (float)"</th>
                                <th>"int(pt)"</th><th>"distance"</th>
                            </tr>
                        </thead>
                        <tbody>{rows}</tbody>
                    </table>
                </div>
            })}
            {more}
        })
    };
    view! {
        <section class="card result" aria-label="Result">
            <h2>"4 · Result"</h2>
            <p class="muted">"What the lab's "<code>"get_info"</code>" prints as "<code>"ret value:"</code></p>
            <div class="tuple-row">
                <code class="tuple" data-testid="result-tuple" tabindex="0" role="region" aria-label="ret value">{move || tuple().unwrap_or_default()}</code>
                <button
                    class="copy"
                    on:click=copy
                    prop:disabled=move || tuple().is_none()
                    aria-label="copy the ret value"
                >
                    {move || if copied.get() { "copied" } else { "copy" }}
                </button>
            </div>
            <ManualComparison/>
            <p class="exports">
                "Save the lab's pictures: "
                <button on:click=move |_| export(Picture::Feature) prop:disabled=move || tuple().is_none() data-testid="export-feature">
                    "view_feature (opencv_visual.png)"
                </button>
                " "
                <button on:click=move |_| export(Picture::Info) prop:disabled=move || tuple().is_none() data-testid="export-info">
                    "view_info (custom_visual.png)"
                </button>
            </p>
            {move || export_error.get().map(|e| view! { <p class="error-inline">{e}</p> })}
            {table}
        </section>
    }
}
