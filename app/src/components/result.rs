//! The `ret value:` line exactly as the CLI prints it, and the table of matches.

use crate::state::{Lab, Which};
use leptos::prelude::*;
use siftlab_core::pyfmt::py_float;

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
        let more = (m.len() > TABLE_ROWS).then(|| view! { <p class="muted">{format!("… and {} more matches", m.len() - TABLE_ROWS)}</p> });
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
                <div class="table-wrap">
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
                <code class="tuple" data-testid="result-tuple">{move || tuple().unwrap_or_default()}</code>
                <button
                    class="copy"
                    on:click=copy
                    prop:disabled=move || tuple().is_none()
                    aria-label="copy the ret value"
                >
                    {move || if copied.get() { "copied" } else { "copy" }}
                </button>
            </div>
            {table}
        </section>
    }
}
