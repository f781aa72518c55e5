//! Strategy, threshold (slider + box), feature id, keypoint toggle.

use crate::model::lab::{get_info_command, strategy_label, threshold_hint, Lab, Source, Which};
use crate::model::parse::parse_threshold;
use leptos::prelude::*;
use siftlab_core::matching::StrategyKind;

#[component]
pub fn Controls() -> impl IntoView {
    let lab = expect_context::<Lab>();
    let is_nndr = move || lab.algo.get() == StrategyKind::Nndr;
    let range_max = move || if is_nndr() { "1" } else { "500" };
    let range_step = move || if is_nndr() { "0.01" } else { "1" };
    let slider_value =
        move || parse_threshold(&lab.threshold()).ok().flatten().map(|t| t.to_string()).unwrap_or_else(|| "0".into());
    let count = move || lab.frame(Which::Prev).with(|f| f.as_ref().map(|f| f.features.keypoints.len()));
    let step_feature = move |delta: i64| {
        if let Some(f) = crate::model::plot::step_feature(lab.feature().unwrap_or(0), delta, count().unwrap_or(0)) {
            lab.set_feature(f);
        }
    };
    let link_copied = RwSignal::new(false);
    let copy_link = move |_| {
        if let Some(w) = web_sys::window() {
            if let Ok(href) = w.location().href() {
                let _ = w.navigator().clipboard().write_text(&href);
                link_copied.set(true);
            }
        }
    };
    Effect::new(move |_| {
        lab.analysis.track();
        link_copied.set(false);
    });
    view! {
        <section class="card controls" aria-label="Matching parameters">
            <h2>"2 · Strategy"</h2>
            <div class="control-row">
                <label class="ctl">
                    <span>"Strategy (-a)"</span>
                    <select
                        data-testid="algo"
                        prop:value=move || lab.algo.get().name()
                        on:change=move |ev| {
                            if let Some(k) = StrategyKind::parse(&event_target_value(&ev)) {
                                lab.algo.set(k);
                            }
                        }
                    >
                        {StrategyKind::ALL.map(|k| view! { <option value=k.name()>{strategy_label(k)}</option> })}
                    </select>
                </label>
                <label class="ctl">
                    <span>
                        "Threshold (-t) "
                        <span class="muted">
                            {move || threshold_hint(lab.algo.get())}
                        </span>
                    </span>
                    <div class="threshold">
                        <input
                            type="range"
                            min="0"
                            aria-label="threshold slider"
                            max=range_max
                            step=range_step
                            prop:value=slider_value
                            prop:disabled=move || lab.threshold().trim().is_empty() && lab.algo.get() == StrategyKind::Nn
                            on:input=move |ev| lab.set_threshold(event_target_value(&ev))
                        />
                        <input
                            type="text"
                            inputmode="decimal"
                            class="num"
                            data-testid="threshold"
                            placeholder="none"
                            prop:value=move || lab.threshold()
                            on:input=move |ev| lab.set_threshold(event_target_value(&ev))
                        />
                    </div>
                </label>
                <label class="ctl">
                    <span>
                        "Feature id "
                        <span class="muted">{move || count().map(|n| format!("0 … {}", n.saturating_sub(1))).unwrap_or_default()}</span>
                    </span>
                    <div class="feature">
                        <button aria-label="previous feature" on:click=move |_| step_feature(-1)>"‹"</button>
                        <input
                            type="number"
                            min="0"
                            class="num"
                            data-testid="feature"
                            max=move || count().map(|n| n.saturating_sub(1).to_string()).unwrap_or_default()
                            prop:value=move || lab.feature_text.get()
                            on:input=move |ev| lab.feature_text.set(event_target_value(&ev))
                        />
                        <button aria-label="next feature" on:click=move |_| step_feature(1)>"›"</button>
                    </div>
                </label>
                <label class="ctl check">
                    <input
                        type="checkbox"
                        data-testid="show-all"
                        prop:checked=move || lab.show_all.get()
                        on:change=move |ev| lab.show_all.set(event_target_checked(&ev))
                    />
                    " show all keypoints"
                </label>
            </div>
            <p class="cli muted">
                "Same as: "
                <code data-testid="cli-equivalent">
                    {move || {
                        let frame = match lab.source.get() {
                            Source::Files => "FRAME_ID".to_string(),
                            _ => lab.frame_id.get().to_string(),
                        };
                        let args =
                            get_info_command(lab.algo.get(), &lab.threshold(), &frame, &lab.feature_text.get());
                        format!("siftlab {args}")
                    }}
                </code>
                " · "
                <button class="link" on:click=copy_link title="the address bar always holds this view">
                    {move || if link_copied.get() { "link copied" } else { "copy a link to this view" }}
                </button>
            </p>
        </section>
    }
}
