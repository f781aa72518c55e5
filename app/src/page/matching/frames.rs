//! The two frames side by side as `cv2.drawMatchesKnn` lays them out, with the
//! selected keypoint (scale and orientation), lines to its matches, and the
//! green `view_info` circles at the `matching_info` coordinates.

use crate::model::frame::Frame;
use crate::model::lab::{nearest_keypoint, Lab, Which};
use crate::model::plot::{key_step, keypoint_path, orientation, step_feature, to_composite};
use crate::page::legend::{Legend, Sw};
use leptos::prelude::*;
use siftlab_core::render::palette::{hex, Marker, Style, INFO, SELECTED, SERIES, SOLID};
use wasm_bindgen::{Clamped, JsCast};

/// The frames' legend: what each mark is, by its shape as much as its colour.
const LEGEND: &[Sw] = &[
    Sw {
        style: SELECTED,
        line: false,
        outline: true,
        label: " selected keypoint (circle = scale, line = orientation) ",
    },
    Sw {
        style: Style { color: SERIES[0], dash: SOLID, marker: Marker::None },
        line: true,
        outline: true,
        label: " lines to its matches (drawMatchesKnn) ",
    },
    Sw { style: INFO, line: false, outline: true, label: " matching_info points (view_info, dashed circles) ·" },
];

/// Where the frames sit in the composite: the previous frame at (0, 0), the
/// current one at (`dx`, `dy`); `w`×`h` in all.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Layout {
    pub dx: f64,
    pub dy: f64,
    pub w: usize,
    pub h: usize,
}

impl Layout {
    /// Side by side as `cv2.drawMatchesKnn` composes them, or stacked (twice the
    /// size on a laptop screen).
    pub fn new(prev: Option<&Frame>, cur: Option<&Frame>, stacked: bool) -> Layout {
        let (w1, h1) = prev.or(cur).map(|f| (f.width, f.height)).unwrap_or((1241, 376));
        let (w2, h2) = cur.map(|f| (f.width, f.height)).unwrap_or((w1, h1));
        if stacked {
            Layout { dx: 0.0, dy: h1 as f64, w: w1.max(w2), h: h1 + h2 }
        } else {
            Layout { dx: w1 as f64, dy: 0.0, w: w1 + w2, h: h1.max(h2) }
        }
    }

    /// Whether a composite point lies on the previous frame.
    pub fn on_prev(&self, x: f64, y: f64) -> bool {
        if self.dy > 0.0 {
            y < self.dy
        } else {
            x < self.dx
        }
    }
}

fn draw(canvas: &web_sys::HtmlCanvasElement, prev: Option<&Frame>, cur: Option<&Frame>, l: Layout) {
    let (w, h) = (l.w, l.h);
    canvas.set_width(w as u32);
    canvas.set_height(h as u32);
    let Some(ctx) =
        canvas.get_context("2d").ok().flatten().and_then(|c| c.dyn_into::<web_sys::CanvasRenderingContext2d>().ok())
    else {
        return;
    };
    ctx.set_fill_style_str("#1b1e24");
    ctx.fill_rect(0.0, 0.0, w as f64, h as f64);
    for (f, x0, y0) in [(prev, 0.0, 0.0), (cur, l.dx, l.dy)] {
        let Some(f) = f else { continue };
        let mut rgba = Vec::with_capacity(f.gray.len() * 4);
        for &g in &f.gray {
            rgba.extend_from_slice(&[g, g, g, 255]);
        }
        if let Ok(img) =
            web_sys::ImageData::new_with_u8_clamped_array_and_sh(Clamped(&rgba), f.width as u32, f.height as u32)
        {
            let _ = ctx.put_image_data(&img, x0, y0);
        }
    }
}

#[component]
pub fn FramesView() -> impl IntoView {
    let lab = expect_context::<Lab>();
    let canvas_ref = NodeRef::<leptos::html::Canvas>::new();
    let stacked = RwSignal::new(true);
    let dims = move || {
        let (p, c) = (lab.prev.get(), lab.cur.get());
        Layout::new(p.as_ref(), c.as_ref(), stacked.get())
    };
    Effect::new(move |_| {
        let (p, c) = (lab.prev.get(), lab.cur.get());
        let l = dims();
        if let Some(canvas) = canvas_ref.get() {
            draw(&canvas, p.as_ref(), c.as_ref(), l);
        }
    });
    let view_box = move || {
        let l = dims();
        format!("0 0 {} {}", l.w, l.h)
    };
    let kp_count = move |w: Which| lab.frame(w).with(|f| f.as_ref().map(|f| f.features.keypoints.len()).unwrap_or(0));
    let select_at = move |ev: web_sys::MouseEvent| {
        let Some(el) = ev.current_target().and_then(|t| t.dyn_into::<web_sys::Element>().ok()) else { return };
        let r = el.get_bounding_client_rect();
        let l = dims();
        let (cx, cy) = (ev.client_x() as f64 - r.left(), ev.client_y() as f64 - r.top());
        let Some((x, y)) = to_composite(cx, cy, r.width(), r.height(), l.w, l.h) else { return };
        if l.on_prev(x, y) {
            if let Some(i) =
                lab.prev.with_untracked(|p| p.as_ref().and_then(|p| nearest_keypoint(&p.features.keypoints, x, y)))
            {
                lab.set_feature(i);
            }
        }
    };
    let on_key = move |ev: web_sys::KeyboardEvent| {
        let (n, f) = (kp_count(Which::Prev), lab.feature().unwrap_or(0));
        let Some(next) = key_step(&ev.key(), f, n).and_then(|d| step_feature(f, d, n)) else { return };
        ev.prevent_default();
        lab.set_feature(next);
    };

    let all_keypoints = move || {
        if !lab.show_all.get() {
            return None;
        }
        let l = dims();
        let p =
            lab.prev.with(|p| p.as_ref().map(|p| keypoint_path(&p.features.keypoints, 0.0, 0.0))).unwrap_or_default();
        let c =
            lab.cur.with(|c| c.as_ref().map(|c| keypoint_path(&c.features.keypoints, l.dx, l.dy))).unwrap_or_default();
        Some(view! {
            <path d=p class="kp-all"/>
            <path d=c class="kp-all"/>
        })
    };

    let selection = move || {
        let a = lab.analysis.get()?.ok()?;
        let l = dims();
        let p = lab.prev.get()?;
        let c = lab.cur.get()?;
        let q = *p.features.keypoints.get(a.feature)?;
        let (r, (ox, oy)) = orientation(&q);
        let info = &a.explanation.info;
        let has_matches = !a.explanation.matches.is_empty();
        let lines = a
            .explanation
            .matches
            .iter()
            .enumerate()
            .filter_map(|(i, m)| {
                let k = c.features.keypoints.get(m.train_idx)?;
                let col = hex(SERIES[i % SERIES.len()]);
                Some(view! {
                    <line x1=q.x x2=k.x as f64 + l.dx y1=q.y y2=k.y as f64 + l.dy stroke=col.clone() class="match-line"/>
                    <circle cx=k.x as f64 + l.dx cy=k.y as f64 + l.dy r="4" stroke=col class="match-end"/>
                })
            })
            .collect_view();
        let circles = has_matches.then(|| {
            let pts = info
                .points
                .iter()
                .map(|&(x, y)| {
                    view! { <circle cx=x as f64 + l.dx cy=y as f64 + l.dy r="10" class="info-circle" stroke-dasharray=INFO.dasharray()/> }
                })
                .collect_view();
            view! {
                <circle cx=info.query.0 as f64 cy=info.query.1 as f64 r="10" class="info-circle" stroke-dasharray=INFO.dasharray()/>
                {pts}
            }
        });
        Some(view! {
            {lines}
            {circles}
            <circle cx=q.x cy=q.y r=r class="kp-sel"/>
            <line x1=q.x y1=q.y x2=ox y2=oy class="kp-sel-ori"/>
            <circle cx=q.x cy=q.y r="1.5" class="kp-sel-dot"/>
        })
    };

    view! {
        <section class="card frames" aria-label="Frames">
            <div class="frames-head">
                <h2>"3 · The two frames"</h2>
                <Legend swatches=LEGEND tail="click the previous frame to pick the nearest keypoint" dark=true/>
            </div>
            <div class="frames-labels muted">
                <span>
                    {move || if stacked.get() { "top — " } else { "left — " }}
                    {move || lab.prev.with(|p| p.as_ref().map(|p| format!("previous: {}", p.label)).unwrap_or_else(|| "previous frame".into()))}
                </span>
                <span>
                    {move || if stacked.get() { "bottom — " } else { "right — " }}
                    {move || lab.cur.with(|c| c.as_ref().map(|c| format!("current: {}", c.label)).unwrap_or_else(|| "current frame".into()))}
                </span>
                <label class="layout-toggle">
                    <input
                        type="checkbox"
                        data-testid="side-by-side"
                        prop:checked=move || !stacked.get()
                        on:change=move |ev| stacked.set(!event_target_checked(&ev))
                    />
                    " side by side (as drawMatchesKnn)"
                </label>
            </div>
            <div
                class="stage"
                tabindex="0"
                role="application"
                aria-label="Frames; left and right arrow keys change the selected feature"
                on:keydown=on_key
            >
                <canvas node_ref=canvas_ref data-testid="frames-canvas"></canvas>
                <svg
                    class="overlay"
                    data-testid="overlay"
                    viewBox=view_box
                    preserveAspectRatio="none"
                    on:click=select_at
                >
                    {all_keypoints}
                    {selection}
                </svg>
            </div>
        </section>
    }
}
