//! Whole-frame matching: every match of the chosen strategy and threshold
//! between the two frames, drawn over them by the core (correct: solid,
//! circled ends; wrong: dashed, crossed ends) by the ground-truth epipolar
//! geometry, with counts and precision;
//! and the trade-off chart: precision against number of matches as each
//! strategy's threshold sweeps its range. The sweep runs once per pair in a
//! worker (the core's `matching::sweep`); thresholds then cost a binary search.

use super::canvas2d::{context, put_rgba};
use super::legend::{swatch, Legend, Sw};
use crate::model::frame::Frame;
use crate::model::lab::Lab;
use crate::model::plot::marker_paint;
use crate::model::see_inside::{
    chart_points, chart_x, chart_xmax, chart_xy, chart_y, counts_text, crossings_text, current, marker_points,
    parse_px, rule_text,
};
use crate::protocol::inside::SweepData;
use crate::services::inside;
use crate::services::loading;
use leptos::prelude::*;
use siftlab_core::matching::DMatch;
use siftlab_core::matching::StrategyKind;
use siftlab_core::render::palette::{self, hex, CORRECT, UNJUDGED, WRONG};
use siftlab_core::render::whole_frame;
use std::sync::Arc;

/// At most this many lines are drawn (the lowest keys first): dt near 500
/// has hundreds of thousands of candidates, which would paint the frames over.
const MAX_LINES: usize = 20_000;

/// The judged lines' legend: the core's styles, as the canvas draws them.
const LEGEND: &[Sw] = &[
    Sw { style: CORRECT, line: true, outline: true, label: " correct (solid, circled ends) " },
    Sw { style: WRONG, line: true, outline: true, label: " wrong (dashed, crossed ends) " },
    Sw { style: UNJUDGED, line: true, outline: true, label: " not judged (no poses) ·" },
];

/// Markers along each curve of the trade-off chart.
const CURVE_MARKS: usize = 7;

#[derive(Clone)]
struct Swept(Arc<SweepData>, Frame, Frame);

impl PartialEq for Swept {
    fn eq(&self, o: &Self) -> bool {
        Arc::ptr_eq(&self.0, &o.0)
    }
}

fn draw(canvas: &web_sys::HtmlCanvasElement, s: &Swept, pairs: &[[u32; 2]], ok: Option<&[bool]>) {
    let Swept(_, p, c) = s;
    let (Ok(pi), Ok(ci)) = (
        siftlab_core::GrayImage::new(p.width, p.height, p.gray.clone()),
        siftlab_core::GrayImage::new(c.width, c.height, c.gray.clone()),
    ) else {
        return;
    };
    let n = pairs.len().min(MAX_LINES);
    let ms: Vec<DMatch> = pairs[..n]
        .iter()
        .map(|&[q, t]| DMatch { query_idx: q as usize, train_idx: t as usize, distance: 0.0 })
        .collect();
    let Ok(img) = whole_frame(&pi, &p.features.keypoints, &ci, &c.features.keypoints, &ms, ok.map(|o| &o[..n])) else {
        return;
    };
    let rgba: Vec<u8> = img.pixels().flat_map(|px| [px[0], px[1], px[2], 255]).collect();
    if let Some(ctx) = context(canvas, img.width(), img.height()) {
        put_rgba(&ctx, &rgba, img.width(), img.height(), 0.0, 0.0);
    }
}

#[component]
pub fn WholeFrameView() -> impl IntoView {
    let lab = expect_context::<Lab>();
    let swept = RwSignal::new(None::<Swept>);
    let status = RwSignal::new(String::new());
    let error = RwSignal::new(None::<String>);
    let canvas_ref = NodeRef::<leptos::html::Canvas>::new();

    // Once per pair (and per epipolar threshold): the sweep in the worker.
    Effect::new(move |_| {
        let (Some(p), Some(c)) = (lab.prev.get(), lab.cur.get()) else { return };
        let px = match parse_px(&lab.inside.px.get()) {
            Ok(px) => px,
            Err(e) => return error.set(Some(e)),
        };
        let (source, fid) = (lab.source.get_untracked(), lab.frame_id.get_untracked());
        error.set(None);
        swept.set(None);
        status.set("reading the ground-truth poses".into());
        leptos::task::spawn_local(async move {
            let poses = match loading::pair_poses(&source, fid).await {
                Ok(x) => x,
                Err(e) => {
                    status.set(format!("{e}: counting without judging"));
                    None
                }
            };
            let t0 = crate::platform::now_ms();
            let poses = poses.map(Box::new);
            let (p2, c2) = (p.clone(), c.clone());
            let (prev, cur) = (p.features.clone(), c.features.clone());
            let sent = inside::sweep(
                prev,
                cur,
                poses,
                px,
                move |stage| status.set(stage),
                move |r| match r {
                    Ok(data) => {
                        status.set(format!(
                            "sweep in {:.0} ms in the worker ({:.0} ms with the transfer)",
                            data.ms,
                            crate::platform::now_ms() - t0
                        ));
                        swept.set(Some(Swept(Arc::new(*data), p2.clone(), c2.clone())));
                    }
                    Err(message) => error.set(Some(message)),
                },
            );
            if let Err(e) = sent {
                error.set(Some(e));
            }
        });
    });

    let selection = Memo::new(move |_| {
        let s = swept.get()?;
        let (kind, t) = (lab.algo.get(), lab.threshold());
        Some(current(&s.0.sweep, kind, &t).map(|(v, _)| v))
    });
    Effect::new(move |_| {
        let Some(s) = swept.get() else { return };
        let (kind, t) = (lab.algo.get(), lab.threshold());
        let Some(canvas) = canvas_ref.get() else { return };
        if let Ok((_, (pairs, ok))) = current(&s.0.sweep, kind, &t) {
            draw(&canvas, &s, pairs, ok);
        }
    });

    let counts = move || {
        let r = selection.get()?;
        Some(match r {
            Ok(v) => {
                let truncated = (v.matches > MAX_LINES).then(|| format!(" (the {MAX_LINES} closest drawn)"));
                view! {
                    <p
                        class="wf-counts"
                        data-testid="wf-counts"
                        data-matches=v.matches
                        data-correct=v.correct.map(|c| c.to_string()).unwrap_or_default()
                    >
                        <strong>{format!("{} {}: ", lab.algo.get().name(), lab.threshold())}</strong>
                        {counts_text(&v)}
                        {truncated}
                    </p>
                }
                .into_any()
            }
            Err(e) => view! { <p class="error" role="alert">{e}</p> }.into_any(),
        })
    };

    view! {
        <div class="whole-frame" data-testid="whole-frame">
            <p class="muted">{move || rule_text(parse_px(&lab.inside.px.get()).unwrap_or(2.0))}</p>
            <div class="row">
                <label>
                    "Correct within "
                    <input
                        class="px"
                        data-testid="epipolar-px"
                        prop:value=move || lab.inside.px.get()
                        on:change=move |ev| lab.inside.px.set(event_target_value(&ev))
                    />
                    " px"
                </label>
                <span class="muted" data-testid="wf-status">{move || status.get()}</span>
            </div>
            {move || error.get().map(|e| view! { <p class="error" role="alert">{e}</p> })}
            {counts}
            <Legend swatches=LEGEND tail="the strategy and threshold are the ones chosen above" dark=true/>
            <div class="stage"><canvas node_ref=canvas_ref data-testid="wf-canvas"></canvas></div>
            <TradeoffChart swept=swept/>
        </div>
    }
}

#[component]
fn TradeoffChart(swept: RwSignal<Option<Swept>>) -> impl IntoView {
    let lab = expect_context::<Lab>();
    let (w, h) = (600.0, 260.0);
    move || {
        let s = swept.get()?;
        if !s.0.judged {
            return Some(view! { <p class="muted">"The trade-off chart needs ground-truth poses."</p> }.into_any());
        }
        let sweep = &s.0.sweep;
        let xmax = chart_xmax(sweep);
        // Each strategy in its palette style (the odometry's tracker of the
        // same name wears the same), with markers along the curve.
        let curves = StrategyKind::ALL
            .iter()
            .enumerate()
            .map(|(i, &k)| {
                let st = palette::strategy(k);
                let xy = chart_xy(sweep.curve(k), xmax, w, h);
                let (fill, stroke, width) = marker_paint(&st, false);
                view! {
                    <polyline
                        points=chart_points(sweep.curve(k), xmax, w, h)
                        class=format!("tcurve curve-{}", k.name())
                        stroke=hex(st.color)
                        stroke-dasharray=st.dasharray()
                    />
                    <path d=st.marker.svg_path(&marker_points(&xy, CURVE_MARKS, i), 4.5) fill=fill stroke=stroke stroke-width=width/>
                }
            })
            .collect_view();
        let marker = current(sweep, lab.algo.get(), &lab.threshold()).ok().and_then(|(v, _)| {
            let p = v.precision()?;
            Some(view! { <circle cx=chart_x(v.matches, xmax, w) cy=chart_y(p, h) r="6" class="chart-now"/> })
        });
        let ticks = [1usize, 10, 100, 1000, 10_000, 100_000, 1_000_000]
            .into_iter()
            .filter(|&t| t <= xmax)
            .map(|t| {
                let x = chart_x(t, xmax, w);
                view! { <line x1=x x2=x y1=h y2=h + 5.0 class="tick"/><text x=x y=h + 18.0 class="tick-label">{t}</text> }
            })
            .collect_view();
        let legend = StrategyKind::ALL
            .iter()
            .map(|&k| {
                let (lo, hi) = siftlab_core::matching::sweep::range(k);
                let sw = Sw { style: palette::strategy(k), line: true, outline: false, label: "" };
                view! { <span class="sw-item">{swatch(sw, false)}{format!(" {} ({lo}–{hi}) ", k.name())}</span> }
            })
            .collect_view();
        let crossings = crossings_text(sweep);
        let crossings = if crossings.is_empty() { "the curves do not cross".to_string() } else { crossings.join("; ") };
        Some(
            view! {
                <div class="tradeoff" data-testid="tradeoff">
                    <h3>"Precision against number of matches"</h3>
                    <svg viewBox=format!("-40 -10 {} {}", w + 60.0, h + 40.0) class="chart">
                        <rect x=0 y=0 width=w height=h class="chart-bg"/>
                        <line x1=0 x2=w y1=chart_y(0.5, h) y2=chart_y(0.5, h) class="grid"/>
                        <text x=-4 y=8 class="ylabel">"1.0"</text>
                        <text x=-4 y=chart_y(0.5, h) + 4.0 class="ylabel">"0.5"</text>
                        <text x=-4 y=h class="ylabel">"0"</text>
                        {ticks}
                        {curves}
                        {marker}
                    </svg>
                    <p class="muted">
                        {legend}" · matches on a log scale · ● the current setting · crossings: "
                        <span data-testid="crossings">{crossings}</span>
                    </p>
                </div>
            }
            .into_any(),
        )
    }
}
