//! The explorer mounted on OpenCV's own keypoints: every golden draw's tuple,
//! counts, errors, click-to-select and keys, the self-check, URL state, the demo
//! feature and the odometry's frame control.

use crate::fixtures::{draws, frame, golden, loaded_lab};
use leptos::prelude::*;
use siftlab_app::model::lab::{analyse, nearest_keypoint, Lab};
use siftlab_app::model::urlstate::UrlState;
use siftlab_app::model::views::Views;
use siftlab_app::page::{apply_url, url_state, Explorer, DEMO_FEATURE};
use siftlab_app::protocol::sift::{SiftReply, SiftRequest};
use siftlab_core::matching::{Strategy, StrategyKind};
use wasm_bindgen::JsCast;
use wasm_bindgen_test::*;

fn document() -> web_sys::Document {
    web_sys::window().unwrap().document().unwrap()
}

/// Mounts the explorer on a fresh container and returns its state.
fn mount(lab: Lab) -> web_sys::HtmlElement {
    let div: web_sys::HtmlElement = document().create_element("div").unwrap().unchecked_into();
    document().body().unwrap().append_child(&div).unwrap();
    let handle = leptos::mount::mount_to(div.clone(), move || view! { <Explorer views=Views::with_lab(lab)/> });
    handle.forget();
    div
}

fn q(root: &web_sys::HtmlElement, testid: &str) -> Option<web_sys::HtmlElement> {
    root.query_selector(&format!("[data-testid={testid}]")).unwrap().map(|e| e.unchecked_into())
}

fn text(root: &web_sys::HtmlElement, testid: &str) -> String {
    q(root, testid).map(|e| e.text_content().unwrap_or_default()).unwrap_or_default()
}

fn set_value(root: &web_sys::HtmlElement, testid: &str, value: &str, event: &str) {
    let el = q(root, testid).unwrap_or_else(|| panic!("no element {testid}"));
    if let Some(i) = el.dyn_ref::<web_sys::HtmlInputElement>() {
        i.set_value(value);
    } else if let Some(s) = el.dyn_ref::<web_sys::HtmlSelectElement>() {
        s.set_value(value);
    } else if let Some(t) = el.dyn_ref::<web_sys::HtmlTextAreaElement>() {
        t.set_value(value);
    }
    el.dispatch_event(
        &web_sys::Event::new_with_event_init_dict(event, &{
            let i = web_sys::EventInit::new();
            i.set_bubbles(true);
            i
        })
        .unwrap(),
    )
    .unwrap();
}

#[wasm_bindgen_test]
async fn tuples_equal_opencv_lab_output_for_every_golden_draw() {
    let all = draws();
    assert!(all.len() >= 400, "{} draws", all.len());
    let lab = loaded_lab(1);
    let root = mount(lab);
    let mut checked = 0;
    let mut wrong = Vec::new();
    for cur in [1, 2, 3, 4, 5, 120, 150] {
        lab.prev.set(Some(frame(cur - 1)));
        lab.cur.set(Some(frame(cur)));
        for d in all.iter().filter(|d| d.frame == cur) {
            set_value(&root, "algo", &d.algo, "change");
            leptos::task::tick().await;
            set_value(&root, "threshold", &d.threshold, "input");
            set_value(&root, "feature", &d.feature.to_string(), "input");
            leptos::task::tick().await;
            let got = text(&root, "result-tuple");
            if got != d.ret {
                wrong.push(format!(
                    "get_info -a {} -t {:?} {cur} {}:\n  app:    {got}\n  OpenCV: {}",
                    d.algo, d.threshold, d.feature, d.ret
                ));
            }
            checked += 1;
        }
    }
    assert_eq!(checked, all.len());
    assert!(
        wrong.is_empty(),
        "{} of {checked} draws differ; first: {}",
        wrong.len(),
        wrong.iter().take(2).cloned().collect::<Vec<_>>().join("\n")
    );
}

#[wasm_bindgen_test]
async fn shows_counts_explanation_and_error_for_bad_settings() {
    let lab = loaded_lab(1);
    let root = mount(lab);
    leptos::task::tick().await;
    assert_eq!(text(&root, "keypoint-count-prev"), golden(0).2.keypoints.len().to_string());
    assert_eq!(text(&root, "keypoint-count-cur"), golden(1).2.keypoints.len().to_string());
    assert!(q(&root, "busy").is_none());
    // The step-by-step view: descriptor grid with 16 cells and 128 rays, the chart, the rule.
    let desc = q(&root, "descriptor").unwrap();
    assert_eq!(desc.query_selector_all("rect.cell").unwrap().length(), 16);
    assert_eq!(desc.query_selector_all("line.ray").unwrap().length(), 128);
    assert!(q(&root, "distance-chart").is_some());
    assert!(text(&root, "rule").starts_with("nndr keeps the nearest if d1 < t·d2"), "{}", text(&root, "rule"));
    // nndr with t > 1: the core's validation message, inline; no tuple.
    set_value(&root, "threshold", "1.5", "input");
    leptos::task::tick().await;
    assert!(text(&root, "error").contains("outside [0, 1]"), "{}", text(&root, "error"));
    assert_eq!(text(&root, "result-tuple"), "");
    // Feature beyond the count: the core's message.
    set_value(&root, "threshold", "0.8", "input");
    set_value(&root, "feature", "99999", "input");
    leptos::task::tick().await;
    assert!(text(&root, "error").contains("99999"), "{}", text(&root, "error"));
    set_value(&root, "feature", "3", "input");
    leptos::task::tick().await;
    assert!(q(&root, "error").is_none());
    assert!(!text(&root, "result-tuple").is_empty());
}

#[wasm_bindgen_test]
async fn a_load_error_is_inline_and_keeps_the_loaded_frames() {
    // What the worker answers for a non-image (the core's decoder message)...
    let got = std::cell::RefCell::new(Vec::new());
    siftlab_app::worker::sift::handle(
        SiftRequest::Sift { id: 9, bytes: b"GIF89a not really".to_vec(), lanes: 8 },
        &|m| got.borrow_mut().push(m),
    );
    let got = got.into_inner();
    let SiftReply::Failed { id: 9, message } = got.last().unwrap().clone() else { panic!("{got:?}") };
    assert!(message.contains("not an image") || message.contains("unsupported"), "{message}");
    // ...is shown inline while the previous result stays on screen.
    let lab = loaded_lab(1);
    let root = mount(lab);
    leptos::task::tick().await;
    let before = text(&root, "result-tuple");
    assert!(!before.is_empty());
    lab.load_error.set(Some(format!("current frame (notes.txt): {message}")));
    leptos::task::tick().await;
    assert!(text(&root, "error").contains(&message));
    assert_eq!(text(&root, "result-tuple"), before);
    assert_eq!(text(&root, "keypoint-count-cur"), golden(1).2.keypoints.len().to_string());
}

#[wasm_bindgen_test]
async fn click_selects_the_nearest_keypoint_and_arrows_step() {
    let lab = loaded_lab(1);
    let root = mount(lab);
    leptos::task::tick().await;
    let overlay = q(&root, "overlay").unwrap();
    let r = overlay.get_bounding_client_rect();
    assert!(r.width() > 0.0);
    let prev = golden(0).2;
    let (w, h) = (1241.0, 376.0 * 2.0); // stacked layout by default
    for target in [17usize, 400, 1203] {
        let k = prev.keypoints[target];
        let cx = r.left() + k.x as f64 * r.width() / w;
        let cy = r.top() + k.y as f64 * r.height() / h;
        let init = web_sys::MouseEventInit::new();
        init.set_client_x(cx.round() as i32);
        init.set_client_y(cy.round() as i32);
        init.set_bubbles(true);
        overlay.dispatch_event(&web_sys::MouseEvent::new_with_mouse_event_init_dict("click", &init).unwrap()).unwrap();
        leptos::task::tick().await;
        // The click lands on a whole CSS pixel: the expected pick is the
        // nearest keypoint to that pixel's image position.
        let (ix, iy) = ((cx.round() - r.left()) * w / r.width(), (cy.round() - r.top()) * h / r.height());
        let want = nearest_keypoint(&prev.keypoints, ix, iy).unwrap();
        let got: usize = lab.feature_text.get_untracked().parse().unwrap();
        assert_eq!(got, want);
        let kg = prev.keypoints[got];
        assert!(((kg.x as f64 - k.x as f64).powi(2) + (kg.y as f64 - k.y as f64).powi(2)).sqrt() < 3.0 * w / r.width());
    }
    // Keyboard: arrows, End, Home on the focused frames.
    let stage: web_sys::HtmlElement = root.query_selector(".stage").unwrap().unwrap().unchecked_into();
    stage.focus().unwrap();
    lab.set_feature(10);
    for (key, want) in
        [("ArrowRight", 11), ("ArrowLeft", 10), ("PageDown", 20), ("End", prev.keypoints.len() - 1), ("Home", 0)]
    {
        let init = web_sys::KeyboardEventInit::new();
        init.set_key(key);
        init.set_bubbles(true);
        stage
            .dispatch_event(&web_sys::KeyboardEvent::new_with_keyboard_event_init_dict("keydown", &init).unwrap())
            .unwrap();
        leptos::task::tick().await;
        assert_eq!(lab.feature_text.get_untracked(), want.to_string(), "{key}");
    }
}

#[wasm_bindgen_test]
async fn self_check_grades_the_golden_answer_and_names_a_mistake() {
    let d = draws().into_iter().find(|d| d.frame == 1 && d.algo == "nndr" && d.ret != "((0, 0), [], [])").unwrap();
    let lab = loaded_lab(1);
    let root = mount(lab);
    set_value(&root, "algo", "nndr", "change");
    leptos::task::tick().await;
    set_value(&root, "threshold", &d.threshold, "input");
    set_value(&root, "feature", &d.feature.to_string(), "input");
    leptos::task::tick().await;
    set_value(&root, "answer", &format!("ret value: {}", d.ret), "input");
    q(&root, "check").unwrap().click();
    leptos::task::tick().await;
    assert!(text(&root, "check-result").contains("Correct"), "{}", text(&root, "check-result"));
    // Float coordinates instead of int(): named.
    let p = golden(0).2.keypoints[d.feature];
    let wrong = d.ret.replacen(&format!("(({}, {})", p.x.trunc(), p.y.trunc()), &format!("(({}, {})", p.x, p.y), 1);
    assert_ne!(wrong, d.ret);
    set_value(&root, "answer", &wrong, "input");
    q(&root, "check").unwrap().click();
    leptos::task::tick().await;
    let r = text(&root, "check-result");
    assert!(r.contains("Not the lab's answer") && r.contains("int()"), "{r}");
}

/// The query strings themselves, encoded and decoded by the browser's URLSearchParams.
#[wasm_bindgen_test]
fn url_queries_round_trip_and_broken_links_open() {
    let q = "?src=demo&frame=1&feature=7&algo=nndr&t=0.8&ex=42&q=3&lanes=16";
    let st = UrlState::from_query(q);
    assert_eq!(st.to_query(), q);
    assert_eq!(st.to_pairs().len(), 8, "{st:?}");
    assert_eq!((st.algo, st.t.as_deref(), st.lanes), (Some(StrategyKind::Nndr), Some("0.8"), Some(16)));
    assert_eq!(UrlState::from_query(&q[1..]), st, "the leading ? is optional");
    let st = UrlState::from_query("?feature=abc&algo=dt&t=1%2E5&junk&frame=-3");
    assert_eq!(st.feature, None);
    assert_eq!(st.frame, None);
    assert_eq!(st.algo, Some(StrategyKind::Dt));
    assert_eq!(st.t.as_deref(), Some("1.5"));
    assert_eq!(UrlState::from_query(""), UrlState::default());
    assert_eq!(UrlState::default().to_query(), "");
    // Text the user typed survives the trip.
    let typed = UrlState { t: Some(" 1e2 & =?%".into()), ..UrlState::default() };
    assert_eq!(UrlState::from_query(&typed.to_query()), typed);
}

#[wasm_bindgen_test]
async fn url_state_round_trips_through_a_fresh_lab() {
    let lab = loaded_lab(3);
    lab.algo.set(StrategyKind::Dt);
    lab.set_threshold("212.5".into());
    lab.set_feature(42);
    lab.lanes.set(16);
    let st = url_state(Views::with_lab(lab));
    assert_eq!(st.to_query(), "?src=demo&frame=3&feature=42&algo=dt&t=212.5&lanes=16");
    let fresh = Lab::new();
    // A folder link cannot reopen the folder: it says so, and keeps the settings.
    let mut folder = UrlState::from_query(&st.to_query());
    folder.src = Some("folder".into());
    apply_url(Views::with_lab(fresh), &folder);
    assert_eq!(fresh.algo.get_untracked(), StrategyKind::Dt);
    assert_eq!(fresh.threshold(), "212.5");
    assert_eq!(fresh.feature(), Some(42));
    assert_eq!(fresh.lanes.get_untracked(), 16);
    assert_eq!(fresh.frame_id.get_untracked(), 3);
    assert!(fresh.load_error.get_untracked().unwrap().contains("open the folder"));
}

/// The demo opens on `DEMO_FEATURE` under nndr 0.8: on OpenCV's own keypoints of
/// frames 0 and 1 it is a large keypoint near the middle of frame 0, and it has a
/// match (so the first view shows a circle, a line and a distance).
#[wasm_bindgen_test]
fn the_demo_feature_is_large_central_and_matched() {
    let (w, h, kps) = golden(0);
    let k = kps.keypoints[DEMO_FEATURE];
    assert!(k.size > 30.0, "size {}", k.size);
    assert!((k.x as f64 - w as f64 / 2.0).abs() < w as f64 / 10.0, "x {}", k.x);
    assert!((k.y as f64 - h as f64 / 2.0).abs() < h as f64 / 4.0, "y {}", k.y);
    let a = analyse(&frame(0), &frame(1), Strategy::Nndr(0.8), &DEMO_FEATURE.to_string()).unwrap();
    assert_eq!(a.explanation.matches.len(), 1, "{}", a.tuple);
    // What OpenCV's lab code prints for it (the golden draw of the same settings, if drawn).
    if let Some(d) = draws()
        .into_iter()
        .find(|d| d.frame == 1 && d.feature == DEMO_FEATURE && d.algo == "nndr" && d.threshold == "0.8")
    {
        assert_eq!(a.tuple, d.ret);
    }
    // A link without a feature opens on it; one with a feature keeps its own.
    let lab = Lab::new();
    apply_url(Views::with_lab(lab), &UrlState::from_query("?src=folder"));
    assert_eq!(lab.feature(), Some(0));
    let lab = Lab::new();
    apply_url(Views::with_lab(lab), &UrlState::from_query("?src=demo&feature=7"));
    assert_eq!(lab.feature(), Some(7));
    let lab = Lab::new();
    apply_url(Views::with_lab(lab), &UrlState::from_query(""));
    assert_eq!(lab.feature(), Some(DEMO_FEATURE));
}

/// The odometry's control counts as the lab's `view_trajectory FRAME_ID`: the
/// demo offers frames 0 … 150 and starts on the manual's `view_trajectory 150`,
/// and a FRAME_ID past the run is refused with the reason, before any frame is read.
#[wasm_bindgen_test]
async fn the_odometry_control_counts_frames_as_the_lab() {
    let lab = loaded_lab(1);
    let root = mount(lab);
    leptos::task::tick().await;
    let input: web_sys::HtmlInputElement = q(&root, "vo-frame-id").unwrap().unchecked_into();
    assert_eq!(input.value(), "150");
    assert_eq!(text(&root, "vo-range"), "frames 0 to 150 (151 frames) · available: frames 0 to 150");
    set_value(&root, "vo-frame-id", "4", "input");
    leptos::task::tick().await;
    assert!(text(&root, "vo-range").starts_with("frames 0 to 4 (5 frames)"), "{}", text(&root, "vo-range"));
    set_value(&root, "vo-frame-id", "151", "input");
    q(&root, "vo-run").unwrap().click();
    leptos::task::tick().await;
    assert_eq!(
        text(&root, "vo-error"),
        "FRAME_ID 151 needs frames 0 to 151 (152 frames), but the frames in a row from 0 are frames 0 to 150 (151 frames)"
    );
}
