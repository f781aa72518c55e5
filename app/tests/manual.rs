//! The lab manual's seven `get_info` examples through the app's own path, in
//! headless Chromium: the real KITTI frames 119/120 and 149/150 (bundled in
//! `www/demo/MyKITTI`) decoded and analysed by the worker's handler at the
//! app's default width (8 lanes), turned into frames as the page does, and
//! matched by the page's model: siftlab's `ret value` must be the manual's
//! printed value, character for character. Then the explorer, mounted on those
//! frames, must show that value beside siftlab's with ✓ for every example a
//! click puts on screen.
#![cfg(target_arch = "wasm32")]

use leptos::prelude::*;
use siftlab_app::model::frame::{Frame, FrameData};
use siftlab_app::model::lab::{analyse, Lab, Source};
use siftlab_app::model::parse::parse_strategy;
use siftlab_app::model::views::Views;
use siftlab_app::page::{current_example, Explorer};
use siftlab_app::protocol::sift::{SiftReply, SiftRequest};
use siftlab_app::services::sources::frame_path;
use siftlab_core::manual::EXAMPLES;
use std::collections::BTreeMap;
use std::sync::Arc;
use wasm_bindgen::JsCast;
use wasm_bindgen_test::*;

wasm_bindgen_test_configure!(run_in_browser);

fn png(id: u32) -> &'static [u8] {
    match id {
        100 => include_bytes!("../../www/demo/MyKITTI/gray/00/image_0/000100.png"),
        101 => include_bytes!("../../www/demo/MyKITTI/gray/00/image_0/000101.png"),
        119 => include_bytes!("../../www/demo/MyKITTI/gray/00/image_0/000119.png"),
        120 => include_bytes!("../../www/demo/MyKITTI/gray/00/image_0/000120.png"),
        149 => include_bytes!("../../www/demo/MyKITTI/gray/00/image_0/000149.png"),
        150 => include_bytes!("../../www/demo/MyKITTI/gray/00/image_0/000150.png"),
        _ => panic!("frame {id} is not an example frame"),
    }
}

/// SIFT in the worker's handler, as the page's worker runs it; the result as the
/// page keeps it (labelled with the frame's path, as a demo frame is).
fn sift(id: u32) -> Frame {
    let bytes = png(id).to_vec();
    let got = std::cell::RefCell::new(Vec::new());
    siftlab_app::worker::sift::handle(SiftRequest::Sift { id, bytes: bytes.clone(), lanes: 8 }, &|m| {
        got.borrow_mut().push(m)
    });
    // Through the postMessage encoding too, as the page receives it.
    let last = got.into_inner().pop().unwrap().to_js();
    let SiftReply::Done { result, .. } = SiftReply::from_js(&last).unwrap() else { panic!("frame {id}: no result") };
    Arc::new(FrameData::from_result(frame_path(id), result, Arc::new(bytes), 8))
}

fn frames() -> BTreeMap<u32, Frame> {
    siftlab_core::manual::frames().into_iter().map(|id| (id as u32, sift(id as u32))).collect()
}

#[wasm_bindgen_test]
async fn the_manual_examples_through_the_app() {
    let frames = frames();
    // The model: every example's tuple is the manual's.
    for ex in &EXAMPLES {
        let f = ex.frame as u32;
        let t = siftlab_app::model::lab_manual::example_threshold_box(ex);
        let kind = siftlab_app::model::lab_manual::example_kind(ex).unwrap();
        let a = analyse(&frames[&(f - 1)], &frames[&f], parse_strategy(kind, &t).unwrap(), &ex.feature.to_string())
            .unwrap();
        assert_eq!(a.tuple, ex.siftlab_value(), "{}", ex.command());
        if let Some(d) = ex.differs {
            let a = analyse(&frames[&(f - 1)], &frames[&f], parse_strategy(kind, &t).unwrap(), &d.feature.to_string())
                .unwrap();
            assert_eq!(a.tuple, ex.expected, "{}", ex.command_for(d.feature));
        }
    }

    // The page: a click on each example shows the manual's value, siftlab's and ✓.
    // The source is the demo with both pairs; the test puts each pair on screen
    // itself (there is no server for demo/ here), as the demo loader would.
    let lab = Lab::new();
    lab.source.set(Source::Demo((0..=150).collect()));
    let show = |f: u32| {
        lab.prev.set(Some(frames[&(f - 1)].clone()));
        lab.cur.set(Some(frames[&f].clone()));
        lab.frame_id.set(f);
    };
    let div: web_sys::HtmlElement =
        web_sys::window().unwrap().document().unwrap().create_element("div").unwrap().unchecked_into();
    web_sys::window().unwrap().document().unwrap().body().unwrap().append_child(&div).unwrap();
    leptos::mount::mount_to(div.clone(), move || view! { <Explorer views=Views::with_lab(lab)/> }).forget();
    let text = |id: &str| {
        div.query_selector(&format!("[data-testid={id}]"))
            .unwrap()
            .map(|e| e.text_content().unwrap_or_default())
            .unwrap_or_default()
    };
    for (i, ex) in EXAMPLES.iter().enumerate() {
        show(ex.frame as u32);
        let button: web_sys::HtmlElement =
            div.query_selector(&format!("[data-testid=manual-example-{i}]")).unwrap().unwrap().unchecked_into();
        assert!(button.text_content().unwrap().contains(&ex.command()), "{}", ex.command());
        button.click();
        leptos::task::tick().await;
        assert_eq!(current_example(lab), Some(i));
        assert_eq!(lab.load_error.get_untracked(), None, "the pair on screen is the example's: nothing to fetch");
        assert_eq!(text("result-tuple"), ex.siftlab_value(), "{}", ex.command());
        assert_eq!(text("manual-expected"), ex.expected);
        assert_eq!(text("manual-got"), ex.siftlab_value());
        let mark = if ex.differs.is_some() { '≠' } else { '✓' };
        assert!(text("manual-mark").starts_with(mark), "{}: {}", ex.command(), text("manual-mark"));
        assert!(button.class_list().contains("active"));
        if let Some(d) = ex.differs {
            // One click shows the manual's tuple at OpenCV 4.8.0.76's index, still the example.
            let other: web_sys::HtmlElement =
                div.query_selector("[data-testid=manual-other-feature]").unwrap().unwrap().unchecked_into();
            assert!(other.text_content().unwrap().contains(&format!("show feature {}", d.feature)));
            other.click();
            leptos::task::tick().await;
            assert_eq!(current_example(lab), Some(i));
            assert_eq!(text("result-tuple"), ex.expected);
            assert_eq!(text("manual-got"), ex.expected);
            assert!(text("manual-mark").starts_with('✓'), "{}", text("manual-mark"));
        }
    }

    // The mark is a comparison: Task 3's nndr 0.97 example on frames 149/150
    // (labelled 119/120 here) gives another value, marked ✗.
    let wrong = |id: u32| Arc::new(FrameData { label: frame_path(id - 30), ..(*frames[&id]).clone() });
    lab.prev.set(Some(wrong(149)));
    lab.cur.set(Some(wrong(150)));
    lab.set_threshold("0.97".into());
    leptos::task::tick().await;
    assert_eq!(current_example(lab), Some(6));
    assert_ne!(text("manual-got"), EXAMPLES[6].expected);
    assert!(text("manual-mark").starts_with('✗'), "{}", text("manual-mark"));
    // Another setting: no longer an example, no comparison.
    lab.set_feature(46);
    leptos::task::tick().await;
    assert_eq!(current_example(lab), None);
    assert!(div.query_selector("[data-testid=manual-compare]").unwrap().is_none());
}
