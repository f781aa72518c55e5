//! The whole page: the explorer in the lab's order, and the link that
//! restores a view (the URL state read into the lab and written back).

use super::class_results::ClassResults;
use super::mark::MarkMyCode;
use super::matching::{Controls, Exercises, Explanation, FramesView, Loader, ResultPanel, SelfCheck, Status};
use super::odometry::OdometryView;
use super::see_inside::SeeInside;
use crate::model::lab::Source;
use crate::model::urlstate::UrlState;
use crate::model::views::Views;
use crate::services::loading;
use leptos::prelude::*;
use siftlab_core::matching::StrategyKind;

/// The whole explorer for a given state (tests mount this with their own `Views`).
#[component]
pub fn Explorer(views: Views) -> impl IntoView {
    views.provide();
    view! {
        <header class="top">
            <h1>"siftlab"<span class="sub">" — feature matching, step by step"</span></h1>
            <p class="tag">
                "The COMP24011 lab's "<code>"get_info"</code>" in your browser: OpenCV 4.8's SIFT (nfeatures=1500), "
                "brute-force L2 matching and the dt / nn / nndr strategies, computed here by siftlab's core. "
                "Nothing leaves this page."
            </p>
        </header>
        <main>
            <Loader/>
            <Status/>
            <Controls/>
            <FramesView/>
            <ResultPanel/>
            <div class="columns">
                <Explanation/>
                <div class="side">
                    <SelfCheck/>
                    <Exercises/>
                </div>
            </div>
            <SeeInside/>
            <OdometryView/>
            <MarkMyCode/>
            <ClassResults/>
        </main>
        <footer>
            <p>
                "siftlab reproduces the lab's reference (Python + OpenCV 4.8.0.76) bit for bit; "
                "the tuple above is what "<code>"siftlab get_info"</code>" prints on the same frames. "
                "Keyboard: Tab to the frames, ←/→ to step through features, PgUp/PgDn by 10."
            </p>
        </footer>
    }
}

fn current_query() -> String {
    web_sys::window().and_then(|w| w.location().search().ok()).unwrap_or_default()
}

/// The feature the demo opens on (KITTI 00, frames 0 → 1, nndr 0.8): the
/// largest keypoint near the middle of frame 0 whose nndr 0.8 match in frame 1
/// exists. It is 39.7 px across at (606.2, 116.5), at the far end of the street
/// where the road vanishes — near the focus of expansion, so it moves only 2 px:
/// `siftlab --opencv-lanes 8 -d www/demo/MyKITTI get_info -a nndr -t 0.8 1 1256`
/// prints `((606, 116), [(608, 116)], [42.10700607299805])` (the same at 16
/// lanes). So the first view shows a match with its circle, line and distance;
/// feature 0 (the strongest response) sits on the left edge and has no match
/// under nndr 0.8.
pub const DEMO_FEATURE: usize = 1256;

/// Applies a link's state to fresh `Views` and starts loading what it names.
pub fn apply_url(views: Views, st: &UrlState) {
    let Views { lab, exercises, mark, inside } = views;
    if let Some(a) = st.algo {
        lab.algo.set(a);
    }
    if let Some(t) = &st.t {
        lab.set_threshold(t.clone());
    } else if st.algo == Some(StrategyKind::Nn) {
        lab.set_threshold(String::new());
    }
    if let Some(f) = st.feature {
        lab.set_feature(f);
    } else if st.src.as_deref() != Some("folder") && st.frame.unwrap_or(1) == 1 {
        lab.set_feature(DEMO_FEATURE);
    }
    if let Some(l) = st.lanes.filter(|l| matches!(l, 8 | 16)) {
        lab.lanes.set(l as usize);
    }
    if let Some(v) = st.see.as_deref().and_then(crate::model::see_inside::InsideView::parse) {
        inside.view.set(Some(v));
    }
    if let Some(px) = &st.px {
        inside.px.set(px.clone());
    }
    inside.kp.set(st.kp);
    if let Some(seed) = st.mark {
        mark.seed.set(seed);
    }
    if let Some(n) = st.mn.filter(|&n| (1..=crate::model::mark::MAX_CASES).contains(&n)) {
        mark.n.set(n);
    }
    if let Some(seed) = st.ex {
        exercises.seed.set(Some(seed));
        exercises.q.set(st.q.unwrap_or(1).max(1));
    }
    match st.src.as_deref() {
        Some("folder") => {
            if let Some(f) = st.frame {
                lab.frame_id.set(f);
            }
            lab.load_error.set(Some(format!(
                "this link refers to frames of a MyKITTI folder (FRAME_ID {}): open the folder to continue",
                st.frame.unwrap_or(1)
            )));
        }
        _ => loading::load_demo(lab, st.frame),
    }
}

/// The URL for the current state (what "share this view" links to).
pub fn url_state(views: Views) -> UrlState {
    let Views { lab, exercises, mark, inside } = views;
    let source = lab.source.get();
    let linkable = !matches!(source, Source::Files);
    let algo = lab.algo.get();
    let t = lab.threshold();
    UrlState {
        src: source.url_name().map(str::to_string),
        frame: linkable.then(|| lab.frame_id.get()),
        feature: lab.feature(),
        t: if t.trim().is_empty() { None } else { Some(t.trim().to_string()) },
        algo: Some(algo),
        ex: exercises.seed.get(),
        q: exercises.seed.get().map(|_| exercises.q.get()),
        lanes: Some(lab.lanes.get() as u32).filter(|&l| l != 8),
        see: inside.view.get().map(|v| v.name().to_string()),
        px: Some(inside.px.get()).filter(|p| p.trim() != "2"),
        kp: inside.kp.get(),
        mark: Some(mark.seed.get()).filter(|&s| s != 0),
        mn: Some(mark.n.get()).filter(|&n| n != crate::model::mark::DEFAULT_CASES),
    }
}

/// The app as the page mounts it: state from the URL, the demo by default, and
/// the URL kept in step with every change (replaceState: no history spam).
#[component]
pub fn App() -> impl IntoView {
    let views = Views::with_lab(crate::model::lab::Lab::with_clock(crate::platform::now_ms));
    apply_url(views, &UrlState::from_query(&current_query()));
    Effect::new(move |_| {
        let q = url_state(views).to_query();
        if let Some(w) = web_sys::window() {
            let path = w.location().pathname().unwrap_or_default();
            if q != current_query() {
                if let Ok(h) = w.history() {
                    let _ = h.replace_state_with_url(&wasm_bindgen::JsValue::NULL, "", Some(&format!("{path}{q}")));
                }
            }
        }
    });
    view! { <Explorer views=views/> }
}
