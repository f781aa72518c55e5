//! The step-by-step explanation (1)–(5) and the sorted-distance chart. Every number shown comes from the core's
//! `Explanation`; the only arithmetic here is for drawing.

use crate::model::lab::{Analysis, Lab, Which};
use crate::model::plot::{bar_y, chart_ymax, curve_points, curve_y, threshold_line};
use crate::page::descriptor::DescriptorGrid;
use crate::services::loading;
use leptos::prelude::*;
use siftlab_core::matching::py_int;
use siftlab_core::matching::Verdict;
use siftlab_core::pyfmt::{py_f32, py_float};
use siftlab_core::sift::SiftParams;
use std::collections::HashSet;

/// The distances from the query to every descriptor of the current frame,
/// nearest first; bars of the matches the core kept are highlighted and the
/// threshold the rule compares against is drawn.
#[component]
pub fn DistanceChart(analysis: Analysis) -> impl IntoView {
    const W: f64 = 560.0;
    const H: f64 = 190.0;
    const SHOWN: usize = 40;
    let e = &analysis.explanation;
    let ranked = &e.ranked;
    if ranked.is_empty() {
        return view! { <p class="muted">"The current frame has no descriptors."</p> }.into_any();
    }
    let kept: HashSet<usize> = e.matches.iter().map(|m| m.train_idx).collect();
    let shown = ranked.len().min(SHOWN);
    // What the rule compares d against, as a distance.
    let (line, line_label) = threshold_line(&e.verdict);
    let ymax = chart_ymax(ranked[shown - 1].distance as f64, line);
    let bw = W / shown as f64;
    let y = move |d: f64| bar_y(d, ymax, H);
    let bars = ranked[..shown]
        .iter()
        .enumerate()
        .map(|(i, m)| {
            let d = m.distance as f64;
            let class = if kept.contains(&m.train_idx) { "dbar kept" } else { "dbar" };
            view! {
                <rect x=i as f64 * bw + 1.0 y=y(d) width=(bw - 2.0).max(1.0) height=H - y(d) class=class>
                    <title>{format!("rank {i}: train id {}, distance {}", m.train_idx, py_f32(m.distance))}</title>
                </rect>
            }
        })
        .collect_view();
    let threshold = line.filter(|&l| l <= ymax).map(|l| {
        view! {
            <line x1="0" x2=W y1=y(l) y2=y(l) class="thr"/>
            <text x=W - 4.0 y=y(l) - 4.0 class="thr-label" text-anchor="end">{line_label.clone()}</text>
        }
    });
    let above = line.filter(|&l| l > ymax).map(|l| {
        view! { <text x=W - 4.0 y="12" class="thr-label" text-anchor="end">{format!("{line_label} (above this scale: {})", py_float(l))}</text> }
    });
    // The whole sorted curve, small.
    let n = ranked.len();
    let dmax = ranked[n - 1].distance.max(1.0) as f64;
    let distances: Vec<f32> = ranked.iter().map(|m| m.distance).collect();
    let pts = curve_points(&distances, W);
    let full_thr = line.filter(|&l| l <= dmax).map(|l| {
        let yy = curve_y(l, dmax);
        view! { <line x1="0" x2=W y1=yy y2=yy class="thr"/> }
    });
    view! {
        <figure class="chart" data-testid="distance-chart">
            <svg viewBox=format!("0 -2 {W} {}", H + 4.0) class="chart-svg" role="img" aria-label="sorted distances">
                <line x1="0" x2=W y1=H y2=H class="axis"/>
                {bars}
                {threshold}
                {above}
            </svg>
            <figcaption>
                {format!(
                    "The {shown} nearest of {n} distances (rank 0 = d1, the nearest), y from 0 to {:.0}; dark bars: kept by the strategy, light: not kept.",
                    ymax
                )}
            </figcaption>
            <svg viewBox=format!("0 0 {W} 52") class="chart-mini" role="img" aria-label="all sorted distances">
                <polyline points=pts class="curve"/>
                {full_thr}
            </svg>
            <figcaption>{format!("All {n} distances, sorted: from {} to {}.", py_f32(ranked[0].distance), py_f32(ranked[n - 1].distance))}</figcaption>
        </figure>
    }
    .into_any()
}

fn rule_text(a: &Analysis) -> AnyView {
    let e = &a.explanation;
    let body = match &e.verdict {
        Verdict::Dt { t, passed } => view! {
            <p>"dt keeps " <em>"every"</em> " descriptor of the current frame with " <code>"d < t"</code>
               " (strictly less), nearest first — the lab asks knnMatch for all " {e.ranked.len()} " neighbours, not 100."</p>
            <p class="formula">{format!("d < {}  →  {passed} of {} pass", py_float(*t), e.ranked.len())}</p>
        }
        .into_any(),
        Verdict::Nn { t, d1, kept } => view! {
            <p>"nn keeps only the nearest descriptor (d1)"
               {if t.is_some() { ", and only if d1 < t." } else { "; with no threshold it always keeps it." }}</p>
            <p class="formula">{match t {
                Some(t) => format!("d1 = {} < {} ?  {}", py_f32(*d1), py_float(*t), if *kept { "yes → 1 match" } else { "no → no match" }),
                None => format!("d1 = {}  →  1 match", py_f32(*d1)),
            }}</p>
        }
        .into_any(),
        Verdict::Nndr { t, d1, d2, ratio, kept } => view! {
            <p>"nndr (Lowe's ratio test) takes the two nearest, d1 ≤ d2, and keeps the nearest only if "
               <code>"d1 < t · d2"</code>" — i.e. d1/d2 < t: the best match must be clearly better than the second best."</p>
            <p class="formula">{format!(
                "d1 = {}, d2 = {}, d1/d2 = {:.4};  {} < {} × {} = {} ?  {}",
                py_f32(*d1), py_f32(*d2), ratio, py_f32(*d1), py_float(*t), py_f32(*d2),
                py_float(*t * *d2 as f64), if *kept { "yes → 1 match" } else { "no → no match" }
            )}</p>
        }
        .into_any(),
    };
    view! {
        {body}
        <p class="muted" data-testid="rule">{e.rule()}</p>
    }
    .into_any()
}

fn info_text(
    a: &Analysis,
    prev_kps: &[siftlab_core::sift::KeyPoint],
    cur_kps: &[siftlab_core::sift::KeyPoint],
) -> AnyView {
    let e = &a.explanation;
    if e.matches.is_empty() {
        return view! {
            <p>"No match survived, so " <code>"matching_info"</code> " returns its empty value "
               <code>"((0, 0), [], [])"</code> " — not the query's coordinates."</p>
        }
        .into_any();
    }
    let q = prev_kps.get(e.matches[0].query_idx).copied().unwrap_or(e.query);
    let items = e
        .matches
        .iter()
        .take(5)
        .map(|m| {
            let k = cur_kps.get(m.train_idx).copied();
            view! {
                <li>{k.map(|k| format!(
                    "train {}: ({}, {}) → ({}, {}), distance {}",
                    m.train_idx, py_f32(k.x), py_f32(k.y), py_int(k.x), py_int(k.y), py_f32(m.distance)
                )).unwrap_or_default()}</li>
            }
        })
        .collect_view();
    let more =
        (e.matches.len() > 5).then(|| view! { <li class="muted">{format!("… {} more", e.matches.len() - 5)}</li> });
    view! {
        <p>"The query point is the previous-frame keypoint of the first match, truncated with "
           <code>"int()"</code>" (toward zero, not rounded): "
           <code>{format!("({}, {}) → ({}, {})", py_f32(q.x), py_f32(q.y), py_int(q.x), py_int(q.y))}</code></p>
        <p>"Each match contributes its current-frame point, truncated the same way, and its distance as a Python float (the float32 value, printed in full):"</p>
        <ul class="mono small">{items}{more}</ul>
        <p>"Together: " <code class="tuple-small">{a.tuple.clone()}</code></p>
    }
    .into_any()
}

#[component]
pub fn Explanation() -> impl IntoView {
    let lab = expect_context::<Lab>();
    let params = SiftParams::default();
    let counts = move || {
        let n = |w: Which| lab.frame(w).with(|f| f.as_ref().map(|f| (f.features.keypoints.len(), f.sift_ms)));
        (n(Which::Prev), n(Which::Cur))
    };
    let step1 = move || {
        let (p, c) = counts();
        let fmt = |x: Option<(usize, f64)>| {
            x.map(|(n, ms)| format!("{n} keypoints ({ms:.0} ms)")).unwrap_or_else(|| "not loaded".into())
        };
        view! {
            <p>
                "Previous frame: " <strong>{fmt(p)}</strong> " · current frame: " <strong>{fmt(c)}</strong>
            </p>
            <p class="muted">{format!(
                "cv2.SIFT_create(nfeatures={}) — {} layers per octave, contrastThreshold {}, edgeThreshold {}, sigma {}; the base image is doubled, so octave −1 exists. At most nfeatures keypoints are kept (the strongest responses).",
                params.nfeatures, params.n_octave_layers, py_float(params.contrast_threshold), py_float(params.edge_threshold), py_float(params.sigma)
            )}</p>
        }
    };
    let step2 = move || {
        let a = lab.analysis.get()?.ok()?;
        let prev = lab.prev.get()?;
        let cur = lab.cur.get()?;
        let q = a.explanation.query;
        let desc = *prev.features.descriptors.get(a.feature)?;
        let nearest = a
            .explanation
            .ranked
            .first()
            .and_then(|m| cur.features.descriptors.get(m.train_idx).map(|d| (m.train_idx, *d)));
        Some(view! {
            <p>
                {format!("Feature {} of the previous frame: pt = ({}, {}) → int ({}, {}); size {}, angle {}°, response {}, octave {} (layer {}).",
                    a.feature, py_f32(q.x), py_f32(q.y), py_int(q.x), py_int(q.y), py_f32(q.size), py_f32(q.angle), py_f32(q.response),
                    q.octave_index(), q.layer())}
            </p>
            <p class="muted">"Its descriptor: 16 cells (a 4×4 grid around the keypoint, rotated to its orientation), each an 8-bin histogram of gradient directions — 128 numbers."</p>
            <div class="desc-pair">
                <DescriptorGrid desc=desc title=format!("query: feature {}", a.feature) testid="descriptor"/>
                {nearest.map(|(i, d)| view! { <DescriptorGrid desc=d title=format!("nearest in the current frame: train {i}")/> })}
            </div>
        })
    };
    let step3 = move || {
        let a = lab.analysis.get()?.ok()?;
        let n = a.explanation.ranked.len();
        Some(view! {
            <p>{format!("BFMatcher (L2) measures the Euclidean distance between the 128 numbers of the query and each of the {n} descriptors of the current frame (knnMatch order: ascending, ties by lower train id).")}</p>
            <DistanceChart analysis=a.clone()/>
        })
    };
    let step4 = move || {
        let a = lab.analysis.get()?.ok()?;
        Some(rule_text(&a))
    };
    let step5 = move || {
        let a = lab.analysis.get()?.ok()?;
        let p = lab.prev.get()?;
        let c = lab.cur.get()?;
        Some(info_text(&a, &p.features.keypoints, &c.features.keypoints))
    };
    let strategy_name = move || {
        lab.analysis.with(|a| a.as_ref().and_then(|r| r.as_ref().ok()).map_or("the strategy", |a| a.strategy.name()))
    };
    view! {
        <section class="card explain" aria-label="Step by step" data-testid="explanation">
            <h2>"5 · Step by step"</h2>
            <ol class="steps">
                <li>
                    <h3>"SIFT finds keypoints in each frame"</h3>
                    {step1}
                    <label class="lanes">
                        "OpenCV build reproduced: "
                        <select
                            data-testid="lanes"
                            prop:value=move || lab.lanes.get().to_string()
                            on:change=move |ev| {
                                if let Ok(l) = event_target_value(&ev).parse::<usize>() {
                                    lab.lanes.set(l);
                                    loading::reanalyse(lab);
                                }
                            }
                        >
                            <option value="8">"AVX2 CPU (most laptops)"</option>
                            <option value="16">"AVX-512 CPU"</option>
                        </select>
                        <span class="muted">" — OpenCV's SIMD width changes angles and descriptors by a few ulps, rarely a distance."</span>
                    </label>
                </li>
                <li><h3>"The query keypoint and its descriptor"</h3>{step2}</li>
                <li><h3>"Distances to every descriptor of the current frame"</h3>{step3}</li>
                <li><h3>{move || format!("The rule of {}", strategy_name())}</h3>{step4}</li>
                <li><h3>"matching_info turns the matches into the tuple"</h3>{step5}</li>
            </ol>
        </section>
    }
}
