//! The lab manual's eight `get_info` examples one click away, and — whenever
//! the view is one of them, by a click, a link or typed settings — the
//! manual's printed value beside siftlab's, with a mark. The introduction's
//! example is the one whose printed tuple OpenCV 4.8.0.76 gives at another
//! feature index: the comparison says why and offers that feature.

use crate::model::frameset::has_pair;
use crate::model::lab::{Lab, Source, Which};
use crate::model::lab_manual::{example_for, example_kind, example_threshold_box, verdict};
use crate::model::parse::parse_feature;
use crate::services::loading;
use crate::services::sources::frame_path;
use leptos::prelude::*;
use siftlab_core::manual::EXAMPLES;

/// The example the view currently is (frames from the demo or a MyKITTI
/// folder: two loose files have no FRAME_ID to compare).
pub fn current_example(lab: Lab) -> Option<usize> {
    if matches!(lab.source.get(), Source::Files) {
        return None;
    }
    example_for(lab.frame_id.get(), lab.algo.get(), &lab.threshold(), &lab.feature_text.get())
}

/// Puts example `i` in the explorer: its strategy, threshold and feature, and
/// its pair (frames F−1, F) from the current source if it has them, else from
/// the demo, which bundles every example's frames.
pub fn apply_example(lab: Lab, i: usize) {
    let ex = &EXAMPLES[i];
    if let Some(k) = example_kind(ex) {
        lab.algo.set(k);
    }
    // After the strategy: the threshold box is per strategy.
    lab.set_threshold(example_threshold_box(ex));
    lab.set_feature(ex.feature);
    let f = ex.frame as u32;
    if lab.source.with_untracked(|s| has_pair(s.frames(), f)) {
        loading::load_pair(lab, f);
    } else {
        loading::load_demo(lab, Some(f));
    }
}

/// Whether the frames on screen are the pair of `frame_id` (and not the
/// previous pair while the new one loads).
fn pair_shown(lab: Lab, frame_id: u32) -> bool {
    let is = |w: Which, id: u32| lab.frame(w).with(|f| f.as_ref().is_some_and(|f| f.label == frame_path(id)));
    frame_id >= 1 && is(Which::Prev, frame_id - 1) && is(Which::Cur, frame_id)
}

/// The list of examples (in the Frames card): task and command, one button each.
#[component]
pub fn ManualExamples() -> impl IntoView {
    let lab = expect_context::<Lab>();
    let items = EXAMPLES
        .iter()
        .enumerate()
        .map(|(i, ex)| {
            view! {
                <li>
                    <button
                        class="manual-ex"
                        class:active=move || current_example(lab) == Some(i)
                        data-testid=format!("manual-example-{i}")
                        title=format!("load frames {} and {} with these settings", ex.frame - 1, ex.frame)
                        on:click=move |_| apply_example(lab, i)
                    >
                        <span class="task">{ex.task}</span>
                        <code>{ex.command()}</code>
                        {ex.differs.map(|d| view! { <span class="differs">{format!(" · printed tuple differs: feature {} here", d.feature)}</span> })}
                    </button>
                </li>
            }
        })
        .collect_view();
    view! {
        <div class="manual" role="group" aria-label="Lab manual examples">
            <h3>
                "Lab manual examples "
                <span class="muted small">
                    "— the manual's eight "<code>"get_info"</code>" examples on the bundled KITTI frames; "
                    "a click loads the pair and the settings"
                </span>
            </h3>
            <ul class="manual-list">{items}</ul>
        </div>
    }
}

/// The manual's value and siftlab's, one above the other, with ✓ or ✗.
#[component]
pub fn ManualComparison() -> impl IntoView {
    let lab = expect_context::<Lab>();
    move || {
        let ex = EXAMPLES[current_example(lab)?];
        let feature = parse_feature(&lab.feature_text.get()).ok()?;
        let loading = format!("… loading frames {} and {}", ex.frame - 1, ex.frame);
        // Only the example's own pair counts: not the previous pair while it loads.
        let got: Result<String, String> = if pair_shown(lab, ex.frame as u32) {
            lab.analysis.with(|a| match a {
                Some(Ok(a)) => Ok(a.tuple.clone()),
                Some(Err(e)) => Err(format!("no value: {e}")),
                None => Err(loading),
            })
        } else {
            Err(loading)
        };
        let mark = got.as_deref().ok().map(|g| {
            let (ok, text) = verdict(&ex, feature, g);
            view! { <p class=if ok { "mark ok" } else { "mark bad" } data-testid="manual-mark">{text}</p> }
        });
        // The one example whose tuple sits at another index here: a click on
        // either index shows the other.
        let other = ex.differs.map(|d| {
            let (to, label) = if feature == d.feature {
                (ex.feature, format!("back to feature {} (the manual's index)", ex.feature))
            } else {
                (d.feature, format!("show feature {} (the manual's tuple)", d.feature))
            };
            view! {
                <button class="secondary" data-testid="manual-other-feature" on:click=move |_| lab.set_feature(to)>
                    {label}
                </button>
            }
        });
        Some(view! {
            <div class="manual-compare" data-testid="manual-compare">
                <p class="muted">
                    "The lab manual's "{ex.task}" example "<code>{ex.command()}</code>
                    {(feature != ex.feature).then(|| view! { ", here at "<code>{ex.command_for(feature)}</code> })}":"
                </p>
                <dl>
                    <dt>"manual"</dt>
                    <dd><code data-testid="manual-expected">{ex.expected}</code></dd>
                    <dt>"siftlab"</dt>
                    <dd>
                        <code data-testid="manual-got">
                            {got.unwrap_or_else(|e| e)}
                        </code>
                    </dd>
                </dl>
                {mark}
                {other}
            </div>
        })
    }
}
