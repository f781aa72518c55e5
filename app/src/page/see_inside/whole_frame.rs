//! Whole-frame matching: every match of the chosen strategy and threshold
//! between the two frames, judged correct or wrong by the ground-truth
//! epipolar geometry, drawn by the core (correct: solid, circled ends; wrong:
//! dashed, crossed ends) as flow on the current frame — each match a segment
//! from where its point was to where it is now — or side by side; a filter
//! shows all, the correct or the wrong ones. A click (or the arrow keys) picks
//! a match: its epipolar line in the current frame from the true poses, its
//! Sampson distance against the threshold, the query's two nearest distances
//! and why the strategy kept it. Below, the trade-off chart: precision against
//! number of matches as each strategy's threshold sweeps its range. The sweep
//! runs once per pair in a worker (the core's `matching::sweep`); thresholds
//! then cost a binary search.

use super::canvas2d::{context, put_rgba};
use crate::model::frame::Frame;
use crate::model::lab::Lab;
use crate::model::plot::marker_paint;
use crate::model::see_inside::tradeoff::{
    chart_points, chart_x, chart_xmax, chart_xy, chart_y, crossings_text, marker_points,
};
use crate::model::see_inside::whole_frame::{
    clip_line, counts_text, current, ends, filter_pairs, nearest_match, parse_px, pick_of, rule_text, step_pick,
    true_fundamental, verdict_text, Filter, Layout,
};
use crate::model::see_inside::Inside;
use crate::page::legend::{swatch, Legend, Sw};
use crate::protocol::inside::SweepData;
use crate::services::inside;
use crate::services::sources;
use leptos::prelude::*;
use nalgebra::Matrix3;
use siftlab_core::matching::explain;
use siftlab_core::matching::{DMatch, StrategyKind};
use siftlab_core::pyfmt::py_f32;
use siftlab_core::render::palette::{self, hex, CORRECT, EPIPOLAR, PICKED, UNJUDGED, WRONG};
use siftlab_core::render::{flow_frame, whole_frame};
use std::sync::Arc;

/// At most this many lines are drawn (the lowest keys first): dt near 500
/// has hundreds of thousands of candidates, which would paint the frames over.
const MAX_LINES: usize = 20_000;

/// The judged lines' legend: the core's styles, as the canvas draws them.
const LEGEND: &[Sw] = &[
    Sw { style: CORRECT, line: true, outline: true, label: " correct (solid, circled ends) " },
    Sw { style: WRONG, line: true, outline: true, label: " wrong (dashed, crossed ends) " },
    Sw { style: UNJUDGED, line: true, outline: true, label: " not judged (no poses) " },
    Sw { style: PICKED, line: true, outline: true, label: " the picked match " },
    Sw { style: EPIPOLAR, line: true, outline: false, label: " its epipolar line ·" },
];

/// A click picks a match within this many picture pixels.
const REACH: f64 = 12.0;

/// Markers along each curve of the trade-off chart.
const CURVE_MARKS: usize = 7;

#[derive(Clone)]
struct Swept(Arc<SweepData>, Frame, Frame);

impl PartialEq for Swept {
    fn eq(&self, o: &Self) -> bool {
        Arc::ptr_eq(&self.0, &o.0)
    }
}

/// The picture's size: the current frame (flow) or both side by side.
fn picture_size(s: &Swept, layout: Layout) -> (f64, f64) {
    let Swept(_, p, c) = s;
    match layout {
        Layout::Flow => (c.width as f64, c.height as f64),
        Layout::Side => ((p.width + c.width) as f64, p.height.max(c.height) as f64),
    }
}

fn draw(canvas: &web_sys::HtmlCanvasElement, s: &Swept, layout: Layout, pairs: &[[u32; 2]], ok: Option<&[bool]>) {
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
    let (pk, ck) = (&p.features.keypoints, &c.features.keypoints);
    let ok = ok.map(|o| &o[..n]);
    let img = match layout {
        Layout::Flow => flow_frame(&ci, pk, ck, &ms, ok),
        Layout::Side => whole_frame(&pi, pk, &ci, ck, &ms, ok),
    };
    let Ok(img) = img else { return };
    let rgba: Vec<u8> = img.pixels().flat_map(|px| [px[0], px[1], px[2], 255]).collect();
    if let Some(ctx) = context(canvas, img.width(), img.height()) {
        put_rgba(&ctx, &rgba, img.width(), img.height(), 0.0, 0.0);
    }
}

#[component]
pub fn WholeFrameView() -> impl IntoView {
    let lab = expect_context::<Lab>();
    let inside = expect_context::<Inside>();
    let swept = RwSignal::new(None::<Swept>);
    let status = RwSignal::new(String::new());
    let error = RwSignal::new(None::<String>);
    let canvas_ref = NodeRef::<leptos::html::Canvas>::new();
    let layout = RwSignal::new(Layout::Flow);
    let filter = RwSignal::new(Filter::All);
    // The picked match as (query, train): it stays picked while it is shown.
    let picked = RwSignal::new(None::<[u32; 2]>);
    // The true geometry of the pair, for the picked match's line and distance.
    let fmat = RwSignal::new(None::<Matrix3<f64>>);

    // Once per pair (and per epipolar threshold): the sweep in the worker.
    Effect::new(move |_| {
        let (Some(p), Some(c)) = (lab.prev.get(), lab.cur.get()) else { return };
        let px = match parse_px(&inside.px.get()) {
            Ok(px) => px,
            Err(e) => return error.set(Some(e)),
        };
        let (source, fid) = (lab.source.get_untracked(), lab.frame_id.get_untracked());
        let camera = lab.sequence.with_untracked(|s| s.camera);
        error.set(None);
        swept.set(None);
        fmat.set(None);
        status.set("reading the ground-truth poses".into());
        leptos::task::spawn_local(async move {
            let poses = match sources::pair_poses(&source, fid).await {
                Ok(x) => x,
                Err(e) => {
                    status.set(format!("{e}: counting without judging"));
                    None
                }
            };
            fmat.set(true_fundamental(poses.as_ref(), &camera));
            let t0 = crate::platform::now_ms();
            let poses = poses.map(Box::new);
            let (p2, c2) = (p.clone(), c.clone());
            let (prev, cur) = (p.features.clone(), c.features.clone());
            let sent = inside::sweep(
                prev,
                cur,
                poses,
                camera,
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
        Some(lab.strategy.get().and_then(|st| current(&s.0.sweep, &st).map(|(v, _)| v)))
    });
    // The matches shown: the strategy's at the threshold, through the filter.
    let shown = Memo::new(move |_| {
        let (s, st) = (swept.get()?, lab.strategy.get().ok()?);
        let (_, (pairs, ok)) = current(&s.0.sweep, &st).ok()?;
        Some(Arc::new(filter_pairs(pairs, ok, filter.get())))
    });
    Effect::new(move |_| {
        let (Some(s), Some(m)) = (swept.get(), shown.get()) else { return };
        let Some(canvas) = canvas_ref.get() else { return };
        draw(&canvas, &s, layout.get(), &m.0, m.1.as_deref());
    });

    let pick = Memo::new(move |_| {
        let (pk, m, s) = (picked.get()?, shown.get()?, swept.get()?);
        let Swept(_, p, c) = &s;
        pick_of(&m.0, pk, &p.features, &c.features, fmat.get().as_ref())
    });

    let pick_at = move |ev: web_sys::MouseEvent| {
        let (Some(s), Some(m), Some(canvas)) =
            (swept.get_untracked(), shown.get_untracked(), canvas_ref.get_untracked())
        else {
            return;
        };
        let rect = canvas.get_bounding_client_rect();
        if rect.width() <= 0.0 {
            return;
        }
        let scale = canvas.width() as f64 / rect.width();
        let p = ((ev.client_x() as f64 - rect.left()) * scale, (ev.client_y() as f64 - rect.top()) * scale);
        let Swept(_, pf, cf) = &s;
        let n = m.0.len().min(MAX_LINES);
        let i = nearest_match(
            &m.0[..n],
            &pf.features.keypoints,
            &cf.features.keypoints,
            layout.get_untracked(),
            pf.width as f64,
            p,
            REACH * scale.max(1.0),
        );
        picked.set(i.map(|i| m.0[i]));
    };
    let on_key = move |ev: web_sys::KeyboardEvent| {
        let delta = match ev.key().as_str() {
            "ArrowRight" | "ArrowDown" | "n" => 1,
            "ArrowLeft" | "ArrowUp" | "p" => -1,
            "Escape" => {
                picked.set(None);
                return;
            }
            _ => return,
        };
        let Some(m) = shown.get_untracked() else { return };
        ev.prevent_default();
        let now = pick.get_untracked().map(|p| p.index);
        picked.set(step_pick(now, delta, m.0.len().min(MAX_LINES)).map(|i| m.0[i]));
    };

    // Over the picture: the picked match and its epipolar line.
    let overlay = move || {
        let s = swept.get()?;
        let pk = pick.get()?;
        let lay = layout.get();
        let (w, h) = picture_size(&s, lay);
        let Swept(_, p, c) = &s;
        let (a, b) = (p.features.keypoints[pk.query as usize], c.features.keypoints[pk.train as usize]);
        let (pa, pb) = ends(lay, &a, &b, p.width as f64);
        let dx = if lay == Layout::Side { p.width as f64 } else { 0.0 };
        let line = pk.line.and_then(|l| clip_line(l, c.width as f64, c.height as f64)).map(|(u, v)| {
            view! {
                <line x1=u.0 + dx y1=u.1 x2=v.0 + dx y2=v.1 class="epipolar" stroke=hex(EPIPOLAR.color)
                    stroke-dasharray=EPIPOLAR.dasharray()/>
            }
        });
        let (fill, stroke, width) = marker_paint(&PICKED, true);
        Some(view! {
            <svg class="wf-overlay" viewBox=format!("0 0 {w} {h}") aria-hidden="true" focusable="false">
                {line}
                <line x1=pa.0 y1=pa.1 x2=pb.0 y2=pb.1 class="picked-halo"/>
                <line x1=pa.0 y1=pa.1 x2=pb.0 y2=pb.1 class="picked" stroke=hex(PICKED.color)/>
                <path d=PICKED.marker.svg_path(&[pb.0 as f32, pb.1 as f32], 7.0) fill=fill stroke=stroke stroke-width=width/>
            </svg>
        })
    };

    let details = move || {
        let pk = pick.get()?;
        let s = swept.get()?;
        let Swept(_, p, c) = &s;
        let (a, b) = (p.features.keypoints[pk.query as usize], c.features.keypoints[pk.train as usize]);
        let px = parse_px(&inside.px.get()).unwrap_or(2.0);
        let fid = lab.frame_id.get();
        let strategy = lab.strategy.get().ok()?;
        let ex = explain(&strategy, &p.features, &c.features, pk.query as usize).ok()?;
        let nearest = |i: usize| {
            ex.ranked.get(i).map(|m| format!("d{} = {} (keypoint {})", i + 1, py_f32(m.distance), m.train_idx))
        };
        let near = [nearest(0), nearest(1)].into_iter().flatten().collect::<Vec<_>>().join(", ");
        let verdict = verdict_text(pk.sampson, px);
        let q = pk.query as usize;
        Some(view! {
            <div
                class="wf-pick"
                data-testid="wf-pick"
                data-query=pk.query
                data-train=pk.train
                data-sampson=pk.sampson.map(|d| format!("{d:?}")).unwrap_or_default()
                data-distance=pk.distance.map(py_f32).unwrap_or_default()
                role="status"
            >
                <p>
                    <strong>{format!("match {} of {}: ", pk.index + 1, pk.of)}</strong>
                    {format!(
                        "keypoint {} at ({:.1}, {:.1}) in frame {} → keypoint {} at ({:.1}, {:.1}) in frame {}, distance {}",
                        pk.query, a.x, a.y, fid.saturating_sub(1), pk.train, b.x, b.y, fid,
                        pk.distance.map(py_f32).unwrap_or_else(|| "?".into())
                    )}
                </p>
                <p data-testid="wf-pick-verdict">{verdict}</p>
                <p>{format!("nearest descriptors of keypoint {}: {near}", pk.query)}</p>
                <p>{ex.rule()}</p>
                <p class="muted small">
                    "← → (or n, p) step through the matches shown · Esc clears · "
                    <button class="linkish" data-testid="wf-explain" on:click=move |_| lab.set_feature(q)>
                        {format!("explain feature {q} step by step")}
                    </button>
                </p>
            </div>
        })
    };

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
    let judged = move || swept.with(|s| s.as_ref().is_some_and(|s| s.0.judged));

    view! {
        <div class="whole-frame" data-testid="whole-frame">
            <p class="muted">{move || rule_text(parse_px(&inside.px.get()).unwrap_or(2.0))}</p>
            <div class="row wrap">
                <label>
                    "Correct within "
                    <input
                        class="px"
                        data-testid="epipolar-px"
                        prop:value=move || inside.px.get()
                        on:change=move |ev| inside.px.set(event_target_value(&ev))
                    />
                    " px"
                </label>
                <fieldset class="seg" data-testid="wf-layout">
                    <legend>"layout"</legend>
                    {[(Layout::Flow, "flow on the current frame"), (Layout::Side, "side by side")]
                        .map(|(l, label)| view! {
                            <label>
                                <input type="radio" name="wf-layout" value=l.name()
                                    data-testid=format!("wf-layout-{}", l.name())
                                    prop:checked=move || layout.get() == l
                                    on:change=move |_| layout.set(l)/>
                                {label}
                            </label>
                        })}
                </fieldset>
                <fieldset class="seg" data-testid="wf-filter" prop:disabled=move || !judged()>
                    <legend>"show"</legend>
                    {Filter::ALL.map(|f| view! {
                        <label>
                            <input type="radio" name="wf-filter" value=f.name()
                                data-testid=format!("wf-filter-{}", f.name())
                                prop:checked=move || filter.get() == f
                                on:change=move |_| filter.set(f)/>
                            {f.name()}
                        </label>
                    })}
                </fieldset>
                <span class="muted" data-testid="wf-status">{move || status.get()}</span>
            </div>
            {move || error.get().map(|e| view! { <p class="error" role="alert">{e}</p> })}
            {counts}
            <Legend swatches=LEGEND tail="the strategy and threshold are the ones chosen above" dark=true/>
            <div
                class="stage wf-stage"
                tabindex="0"
                role="group"
                aria-label="Whole-frame matches: click a match, or use the arrow keys, to pick one"
                data-testid="wf-stage"
                on:keydown=on_key
            >
                <canvas node_ref=canvas_ref data-testid="wf-canvas" on:click=pick_at></canvas>
                {overlay}
            </div>
            {details}
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
        let marker = lab.strategy.get().and_then(|st| current(sweep, &st)).ok().and_then(|(v, _)| {
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
