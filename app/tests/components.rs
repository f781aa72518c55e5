//! Component tests in headless Chromium (wasm-bindgen-test): the explorer
//! mounted on OpenCV's own SIFT output for the bundled KITTI frames
//! (`tests/fixtures/golden-avx2/ipp/*.sift`, OpenCV 8 lanes wide as the app
//! runs by default) must show exactly what OpenCV's lab code printed for the
//! same settings (`tests/fixtures/golden-avx2/get_info.jsonl`), and the
//! controls, click-to-select, keyboard, errors, URL state, self-check and the
//! odometry's frame control must behave. SIFT itself is not run here (the
//! core's wasm tests check it against the same goldens; `manual.rs` runs it for
//! the lab manual's examples); the e2e test runs the real worker.
#![cfg(target_arch = "wasm32")]

use leptos::prelude::*;
use siftlab_app::model::frame::FrameData;
use siftlab_app::model::lab::{analyse, nearest_keypoint, Lab, Source};
use siftlab_app::model::urlstate::UrlState;
use siftlab_app::model::views::Views;
use siftlab_app::page::{apply_url, url_state, Explorer, DEMO_FEATURE};
use siftlab_app::protocol::odometry::{StepCounts, Tracker, VoReply, VoRequest};
use siftlab_app::protocol::sift::{SiftReply, SiftRequest, SiftResult};
use siftlab_app::protocol::{is_ready, ready_js, Request};
use siftlab_core::matching::{Strategy, StrategyKind};
use siftlab_core::sift::{Features, KeyPoint};
use siftlab_core::vo::{Camera, StepDetail};
use std::sync::Arc;
use wasm_bindgen::JsCast;
use wasm_bindgen_test::*;

wasm_bindgen_test_configure!(run_in_browser);

/// The frames the goldens cover: 0–5 and the lab manual's pairs.
fn golden_bytes(id: usize) -> &'static [u8] {
    match id {
        0 => include_bytes!("../../tests/fixtures/golden-avx2/ipp/000000.sift"),
        1 => include_bytes!("../../tests/fixtures/golden-avx2/ipp/000001.sift"),
        2 => include_bytes!("../../tests/fixtures/golden-avx2/ipp/000002.sift"),
        3 => include_bytes!("../../tests/fixtures/golden-avx2/ipp/000003.sift"),
        4 => include_bytes!("../../tests/fixtures/golden-avx2/ipp/000004.sift"),
        5 => include_bytes!("../../tests/fixtures/golden-avx2/ipp/000005.sift"),
        119 => include_bytes!("../../tests/fixtures/golden-avx2/ipp/000119.sift"),
        120 => include_bytes!("../../tests/fixtures/golden-avx2/ipp/000120.sift"),
        149 => include_bytes!("../../tests/fixtures/golden-avx2/ipp/000149.sift"),
        150 => include_bytes!("../../tests/fixtures/golden-avx2/ipp/000150.sift"),
        _ => panic!("no golden for frame {id}"),
    }
}
const GET_INFO: &str = include_str!("../../tests/fixtures/golden-avx2/get_info.jsonl");

/// The frame ids of the bundled demo (`www/demo/MyKITTI`).
fn demo_ids() -> Vec<u32> {
    (0..=150).collect()
}

/// Reads a `SIFTGLD1` file (format in tests/fixtures/README.md).
fn golden(i: usize) -> (usize, usize, Features) {
    let b = golden_bytes(i);
    assert_eq!(&b[..8], b"SIFTGLD1");
    let u = |o: usize| u32::from_le_bytes(b[o..o + 4].try_into().unwrap());
    let (w, h, n) = (u(8) as usize, u(12) as usize, u(16) as usize);
    let f = |o: usize| f32::from_le_bytes(b[o..o + 4].try_into().unwrap());
    let mut keypoints = Vec::with_capacity(n);
    for k in 0..n {
        let o = 20 + 24 * k;
        keypoints.push(KeyPoint {
            x: f(o),
            y: f(o + 4),
            size: f(o + 8),
            angle: f(o + 12),
            response: f(o + 16),
            octave: i32::from_le_bytes(b[o + 20..o + 24].try_into().unwrap()),
        });
    }
    let d0 = 20 + 24 * n;
    let descriptors = (0..n).map(|k| b[d0 + 128 * k..d0 + 128 * (k + 1)].try_into().unwrap()).collect();
    (w, h, Features { keypoints, descriptors })
}

fn frame(i: usize) -> Arc<FrameData> {
    let (w, h, features) = golden(i);
    Arc::new(FrameData {
        label: format!("gray/00/image_0/{i:06}.png"),
        sift: SiftResult {
            width: w,
            height: h,
            // The frame view only needs some pixels; a gradient is enough here.
            gray: (0..w * h).map(|p| (p % 251) as u8).collect(),
            features,
            decode_ms: 0.0,
            sift_ms: 0.0,
            engine: String::new(),
            memory: 0,
        },
        bytes: Arc::new(Vec::new()),
        lanes: 8,
    })
}

/// One `get_info` golden: (FRAME_ID, feature, algo, threshold text, ret value).
struct Draw {
    frame: usize,
    feature: usize,
    algo: String,
    threshold: String,
    ret: String,
}

fn field<'a>(line: &'a str, key: &str) -> &'a str {
    let start = line.find(&format!("\"{key}\": ")).unwrap() + key.len() + 4;
    let rest = &line[start..];
    let end = rest.find([',', '}']).unwrap();
    rest[..end].trim().trim_matches('"')
}

fn draws() -> Vec<Draw> {
    GET_INFO
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let ret_start = l.find("ret value: ").unwrap() + "ret value: ".len();
            let ret_len = l[ret_start..].find("\\n").unwrap();
            let t = field(l, "threshold");
            Draw {
                frame: field(l, "dataset_frame").parse().unwrap(),
                feature: field(l, "feature").parse().unwrap(),
                algo: field(l, "algo").to_string(),
                // The lab's argparse reads -t as a float; the golden stores its repr.
                threshold: if t == "null" { String::new() } else { t.to_string() },
                ret: l[ret_start..ret_start + ret_len].to_string(),
            }
        })
        .collect()
}

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

fn loaded_lab(cur: usize) -> Lab {
    let lab = Lab::new();
    lab.prev.set(Some(frame(cur - 1)));
    lab.cur.set(Some(frame(cur)));
    lab.source.set(Source::Demo(demo_ids()));
    lab.frame_id.set(cur as u32);
    lab
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

#[wasm_bindgen_test]
fn worker_messages_round_trip_bit_for_bit() {
    let (w, h, features) = golden(2);
    let result = SiftResult {
        width: w,
        height: h,
        gray: vec![7; w * h],
        features,
        decode_ms: 1.5,
        sift_ms: 250.0,
        engine: "SIMD128: exact multiply-add emulation".into(),
        memory: 96 << 20,
    };
    let m = SiftReply::Done { id: 3, result };
    assert_eq!(SiftReply::from_js(&m.to_js()).unwrap(), m);
    for s in [
        SiftRequest::Sift { id: 4, bytes: vec![1, 2, 3], lanes: 16 },
        SiftRequest::Features { id: 5, bytes: vec![1, 2, 3], lanes: 8 },
    ] {
        assert_eq!(Request::from_js(&s.to_js()).unwrap(), Request::Sift(s));
    }
    let (_, _, features) = golden(3);
    let s = VoRequest::Features { id: 1, frame: 3, features };
    assert_eq!(Request::from_js(&s.to_js()).unwrap(), Request::Odometry(s));
    assert!(is_ready(&ready_js()));
    assert!(Request::from_js(&ready_js()).unwrap_err().contains("unknown message type"));
    for m in [SiftReply::Progress { id: 1, stage: "x".into() }, SiftReply::Failed { id: 2, message: "m".into() }] {
        assert_eq!(SiftReply::from_js(&m.to_js()).unwrap(), m);
    }
    assert!(SiftReply::from_js(&wasm_bindgen::JsValue::from_str("junk")).is_err());
}

#[wasm_bindgen_test]
fn odometry_messages_round_trip_and_bad_poses_are_named() {
    // Sequence 03's camera travels with the run.
    let camera = Camera { fx: 721.5377, fy: 721.5377, cx: 609.5593, cy: 172.854 };
    let v = VoRequest::Start { id: 5, total: 2, poses: "1 0 0 0 0 1 0 0 0 0 1 0".into(), camera, tracker: Tracker::Lk };
    assert_eq!(Request::from_js(&v.to_js()).unwrap(), Request::Odometry(v.clone()));
    // Each strategy travels typed, an absent threshold as null.
    for s in [Strategy::Nndr(0.8), Strategy::Nn(None), Strategy::Nn(Some(250.0)), Strategy::Dt(200.0)] {
        let m = VoRequest::Start { id: 5, total: 2, poses: "p".into(), camera, tracker: Tracker::Matched(s) };
        assert_eq!(Request::from_js(&m.to_js()).unwrap(), Request::Odometry(m));
    }
    // A tracker that is not one (an nndr without its ratio) is refused by name.
    let m = VoRequest::Start { id: 5, total: 2, poses: "p".into(), camera, tracker: Tracker::Lk }.to_js();
    js_sys::Reflect::set(&m, &"tracker".into(), &"nndr".into()).unwrap();
    assert_eq!(Request::from_js(&m).unwrap_err(), "voStart: tracker \"nndr\" with threshold None is not a tracker");
    // A camera that cannot be one is refused when the message is read.
    let js = v.to_js();
    let bad = js_sys::Float64Array::from([0.0, 721.5377, 609.5593, 172.854].as_slice());
    js_sys::Reflect::set(&js, &"camera".into(), &bad).unwrap();
    let e = Request::from_js(&js).unwrap_err();
    assert!(e.starts_with("message field camera: invalid camera intrinsics fx=0"), "{e}");
    for m in [
        VoReply::Step {
            id: 5,
            frame: 2,
            total: 6,
            position: [0.5, -0.25, 1.75],
            truth: Some([0.0, 0.0, 2.0]),
            counts: StepCounts {
                points_in: 1500,
                tracked: 2,
                essential_inliers: 1,
                pose_inliers: 1,
                redetected: true,
                points_out: 1499,
            },
            detail: Some(Box::new(StepDetail {
                prev: vec![[1.5, 2.25], [3.0, 4.0]],
                cur: vec![[1.0, 2.0], [3.5, 4.5]],
                essential_mask: vec![true, false],
                pose_mask: vec![true, false],
                detected: vec![[7.0, 8.0]],
            })),
        },
        VoReply::Step {
            id: 5,
            frame: 0,
            total: 6,
            position: [0.0; 3],
            truth: None,
            counts: StepCounts::default(),
            detail: None,
        },
        VoReply::Done { id: 5, ate: 0.2815, png: vec![137, 80, 78, 71], ms: 1234.5, kitti: "1 0 0 0\n".into() },
        VoReply::Metrics { id: 5, metrics: [100.0, 1.1, 0.14, 0.13, 0.12, f64::NAN, f64::NAN] },
    ] {
        let back = VoReply::from_js(&m.to_js()).unwrap();
        if let (VoReply::Metrics { metrics: a, .. }, VoReply::Metrics { metrics: b, .. }) = (&back, &m) {
            // NaN (no KITTI segment) is not equal to itself: compare the bits.
            assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits));
            continue;
        }
        assert_eq!(VoReply::from_js(&m.to_js()).unwrap(), m);
    }
    let run = |frames: Vec<Vec<u8>>, poses: &str| one_worker_odometry(1, frames, poses);
    // Malformed poses and too few poses fail before any SIFT runs, with the file named.
    let got = run(vec![vec![0; 4]; 2], "1 0 0 0\n");
    let [VoReply::Failed { message, .. }] = got.as_slice() else { panic!("{got:?}") };
    assert!(message.starts_with("the poses file line 1"), "{message}");
    let got = run(vec![vec![0; 4]; 3], "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1 1\n");
    let [VoReply::Failed { message, .. }] = got.as_slice() else { panic!("{got:?}") };
    assert!(message.contains("2 poses but 3 frames"), "{message}");
    // A frame that is not an image: named by its index.
    let got = run(vec![b"nope".to_vec(); 2], "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1 1\n");
    let [VoReply::Failed { message, .. }] = got.as_slice() else { panic!("{got:?}") };
    assert!(message.starts_with("frame 0: not an image"), "{message}");
}

/// The lab's odometry loop in one worker: `VoStart`, then every frame with no
/// keypoints given (the worker detects where the loop re-detects), until the
/// first failure.
fn one_worker_odometry(id: u32, frames: Vec<Vec<u8>>, poses: &str) -> Vec<VoReply> {
    let got = std::cell::RefCell::new(Vec::new());
    let post = |m: VoReply| got.borrow_mut().push(m);
    let failed = |got: &std::cell::RefCell<Vec<VoReply>>| matches!(got.borrow().last(), Some(VoReply::Failed { .. }));
    let total = frames.len() as u32;
    siftlab_app::worker::odometry::handle(
        VoRequest::Start { id, total, poses: poses.into(), camera: Camera::default(), tracker: Tracker::Lk },
        &post,
    );
    for (i, bytes) in frames.into_iter().enumerate() {
        if failed(&got) {
            break;
        }
        siftlab_app::worker::odometry::handle(VoRequest::Frame { id, frame: i as u32, bytes, points: None }, &post);
    }
    got.into_inner()
}

/// The app's odometry as `run_vo` drives it (a tracking worker fed one frame at a
/// time with keypoints detected ahead by helper workers) gives exactly what the
/// one-worker loop gives: every step's positions and counts, the trajectory error
/// and the PNG. Both are run here through the worker's message handler, on four of
/// the bundled KITTI frames; the e2e test compares the page with the CLI.
#[wasm_bindgen_test]
fn streamed_odometry_equals_the_one_worker_loop() {
    let frames: Vec<Vec<u8>> = (0..4)
        .map(|i| match i {
            0 => include_bytes!("../../www/demo/MyKITTI/gray/00/image_0/000000.png").to_vec(),
            1 => include_bytes!("../../www/demo/MyKITTI/gray/00/image_0/000001.png").to_vec(),
            2 => include_bytes!("../../www/demo/MyKITTI/gray/00/image_0/000002.png").to_vec(),
            _ => include_bytes!("../../www/demo/MyKITTI/gray/00/image_0/000003.png").to_vec(),
        })
        .collect();
    let poses = include_str!("../../www/demo/MyKITTI/poses/00.txt");
    let handle = |m: VoRequest| {
        let got = std::cell::RefCell::new(Vec::new());
        siftlab_app::worker::odometry::handle(m, &|m| got.borrow_mut().push(m));
        got.into_inner()
    };
    let handle_sift = |m: SiftRequest| {
        let got = std::cell::RefCell::new(Vec::new());
        siftlab_app::worker::sift::handle(m, &|m| got.borrow_mut().push(m));
        got.into_inner()
    };
    let without_time = |m: VoReply| match m {
        VoReply::Done { id, ate, png, kitti, .. } => VoReply::Done { id, ate, png, ms: 0.0, kitti },
        // The KITTI figures are NaN (4 frames: no 100 m segment), and NaN != NaN.
        VoReply::Metrics { id, metrics } => {
            VoReply::Metrics { id, metrics: metrics.map(|v| if v.is_nan() { -1.0 } else { v }) }
        }
        m => m,
    };
    let one_worker: Vec<VoReply> =
        one_worker_odometry(7, frames.clone(), poses).into_iter().map(without_time).collect();
    assert_eq!(one_worker.len(), 6, "{one_worker:?}");
    assert!(matches!(one_worker[4], VoReply::Metrics { metrics, .. } if metrics[0] == 4.0));
    assert!(matches!(one_worker[5], VoReply::Done { .. }));

    assert!(handle(VoRequest::Start {
        id: 7,
        total: 4,
        poses: poses.into(),
        camera: Camera::default(),
        tracker: Tracker::Lk
    })
    .is_empty());
    // Each frame's SIFT as the page's SIFT workers compute it (no gray image),
    // through the postMessage encoding.
    let features: Vec<Features> = frames
        .iter()
        .enumerate()
        .map(|(i, bytes)| {
            let msg = SiftRequest::Features { id: i as u32, bytes: bytes.clone(), lanes: 8 };
            assert_eq!(Request::from_js(&msg.to_js()).unwrap(), Request::Sift(msg.clone()));
            let got = handle_sift(msg);
            let Some(SiftReply::Done { result, .. }) = got.last() else { panic!("{got:?}") };
            assert!(result.gray.is_empty() && result.width == 1241, "{}x{}", result.width, result.height);
            assert!(result.memory > 0);
            let back = SiftReply::from_js(&got.last().unwrap().to_js()).unwrap();
            assert_eq!(&back, got.last().unwrap());
            assert!(
                result.features.keypoints.len() >= 1400,
                "frame {i}: {} keypoints",
                result.features.keypoints.len()
            );
            result.features.clone()
        })
        .collect();
    let mut streamed = Vec::new();
    for (i, bytes) in frames.iter().enumerate() {
        // As `vo_run` sends them: the keypoint positions, except on frame 1.
        let points = (i != 1).then(|| features[i].keypoints.iter().map(|k| [k.x, k.y]).collect::<Vec<_>>());
        let msg = VoRequest::Frame { id: 7, frame: i as u32, bytes: bytes.clone(), points };
        assert_eq!(Request::from_js(&msg.to_js()).unwrap(), Request::Odometry(msg.clone()));
        streamed.extend(handle(msg).into_iter().map(without_time));
    }
    assert_eq!(streamed, one_worker);
    // Each frame's points recomputed from the last frame the loop detected on
    // (what the page asks when an old frame of a long run is shown) are the
    // run's, through the message encoding both ways.
    let steps: Vec<(StepCounts, Option<Box<StepDetail>>)> = streamed
        .iter()
        .filter_map(|m| match m {
            VoReply::Step { counts, detail, .. } => Some((*counts, detail.clone())),
            _ => None,
        })
        .collect();
    assert_eq!(steps.len(), 4);
    let points = |f: &Features| f.keypoints.iter().map(|k| [k.x, k.y]).collect::<Vec<_>>();
    for i in 0..4 {
        let from = (0..i).rev().find(|&j| j == 0 || steps[j].0.redetected).unwrap_or(0);
        let msg = VoRequest::Replay {
            token: 40 + i as u32,
            from: from as u32,
            frame: i as u32,
            frames: frames[from..=i].to_vec(),
            refs: points(&features[from]),
            detected: (i > from && steps[i].0.redetected).then(|| points(&features[i])),
            features: Vec::new(),
        };
        assert_eq!(Request::from_js(&msg.to_js()).unwrap(), Request::Odometry(msg.clone()));
        let got = handle(msg);
        let [reply] = got.as_slice() else { panic!("{got:?}") };
        assert_eq!(VoReply::from_js(&reply.to_js()).unwrap(), *reply);
        let VoReply::Replayed { token, frame, detail: Ok(detail) } = reply else { panic!("{reply:?}") };
        assert_eq!((*token, *frame), (40 + i as u32, i as u32));
        assert!(detail.is_some(), "frame {i}");
        assert_eq!(detail, &steps[i].1, "frame {i} replayed from {from}");
    }
    // A frame the run has not reached is refused with the reason.
    let got = handle(VoRequest::Replay {
        token: 50,
        from: 0,
        frame: 9,
        frames: Vec::new(),
        refs: Vec::new(),
        detected: None,
        features: Vec::new(),
    });
    let [VoReply::Replayed { detail: Err(e), .. }] = got.as_slice() else { panic!("{got:?}") };
    assert!(e.contains("frame 9 is not among the run's frames"), "{e}");

    // A frame out of turn ends the run with a message, and later frames are refused.
    assert!(handle(VoRequest::Start {
        id: 8,
        total: 4,
        poses: poses.into(),
        camera: Camera::default(),
        tracker: Tracker::Lk
    })
    .is_empty());
    let got = handle(VoRequest::Frame { id: 8, frame: 2, bytes: frames[2].clone(), points: None });
    let [VoReply::Failed { message, .. }] = got.as_slice() else { panic!("{got:?}") };
    assert!(message.contains("out of order"), "{message}");
    let got = handle(VoRequest::Frame { id: 8, frame: 0, bytes: frames[0].clone(), points: None });
    let [VoReply::Failed { message, .. }] = got.as_slice() else { panic!("{got:?}") };
    assert!(message.contains("no odometry run"), "{message}");
    // An LK run refuses features without the image.
    assert!(handle(VoRequest::Start {
        id: 9,
        total: 4,
        poses: poses.into(),
        camera: Camera::default(),
        tracker: Tracker::Lk
    })
    .is_empty());
    let got = handle(VoRequest::Features { id: 9, frame: 0, features: features[0].clone() });
    let [VoReply::Failed { message, .. }] = got.as_slice() else { panic!("{got:?}") };
    assert!(message.contains("needs the image"), "{message}");

    // A matcher-driven run fed the shared features (`VoFeatures`) gives what
    // the same run computing SIFT itself from the images gives.
    let start = |id| VoRequest::Start {
        id,
        total: 4,
        poses: poses.into(),
        camera: Camera::default(),
        tracker: Tracker::Matched(Strategy::Nndr(0.8)),
    };
    let mut own = Vec::new();
    assert!(handle(start(10)).is_empty());
    for (i, bytes) in frames.iter().enumerate() {
        own.extend(
            handle(VoRequest::Frame { id: 10, frame: i as u32, bytes: bytes.clone(), points: None })
                .into_iter()
                .map(without_time),
        );
    }
    let mut shared = Vec::new();
    assert!(handle(start(10)).is_empty());
    for (i, f) in features.into_iter().enumerate() {
        shared
            .extend(handle(VoRequest::Features { id: 10, frame: i as u32, features: f }).into_iter().map(without_time));
    }
    assert_eq!(own.len(), 6, "{own:?}");
    assert_eq!(shared, own);
    // A SIFT worker given a broken frame says why.
    let got = handle_sift(SiftRequest::Features { id: 3, bytes: b"nope".to_vec(), lanes: 8 });
    let Some(SiftReply::Failed { message, .. }) = got.last() else { panic!("{got:?}") };
    assert!(message.starts_with("not an image"), "{message}");
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
