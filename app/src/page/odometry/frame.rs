//! The odometry's own view: on the camera frame, what the loop did with it —
//! each tracked (or, for a matcher-driven run, matched) point's flow from the
//! previous frame, findEssentialMat's RANSAC inliers and outliers, the points
//! SIFT re-detected — with the frame's counts, and a chart of tracked points
//! and inliers per frame. While the run lasts it follows the newest frame; a
//! slider (or the arrow keys on it) steps through the frames run so far. Only
//! the newest frame's points are kept (a long run would hold ~46 KB a frame):
//! an older frame's are recomputed by its tracker's worker when it is shown.

use crate::model::odometry::frame::{
    chart_top, chart_x, counts_text, flow_paths, redetections_text, replay_from, series_points,
};
use crate::page::legend::{Legend, Sw};
use crate::platform::revoke;
use crate::protocol::odometry::StepCounts;
use crate::services::odometry;
use crate::services::sources::FrameSource;
use leptos::prelude::*;
use siftlab_core::render::palette::{hex, Style, INLIER, OUTLIER, REDETECTED, SKY_BLUE, TRACKERS};
use siftlab_core::vo::StepDetail;
use std::sync::Arc;

/// A frame's points: the frame, and its detail (`None` where the run
/// recorded none: fewer than 5 matches, or frame 0 of a matched run).
pub type FrameDetail = (usize, Option<Arc<StepDetail>>);

const LEGEND: &[Sw] = &[
    Sw { style: INLIER, line: true, outline: true, label: " RANSAC inlier (solid, circled end) " },
    Sw { style: OUTLIER, line: true, outline: true, label: " outlier (dashed, crossed end) " },
    Sw { style: REDETECTED, line: false, outline: true, label: " re-detected point (on demand) ·" },
];

/// A chart series: its name, its style and the count it plots.
type Series = (&'static str, Style, fn(&StepCounts) -> u32);

/// The chart's three series: tracked points, RANSAC inliers, recoverPose's count.
const SERIES: [Series; 3] = [
    ("tracked / matched", TRACKERS[1], |c| c.tracked),
    ("RANSAC inliers", Style { color: SKY_BLUE, ..INLIER }, |c| c.essential_inliers),
    ("recoverPose", TRACKERS[2], |c| c.pose_inliers),
];

#[component]
pub fn OdometryFrameView(
    /// Where the run's frames are read (for the picture).
    source: StoredValue<Option<FrameSource>, LocalStorage>,
    /// Frame 0's size: the picture's.
    size: RwSignal<Option<(u32, u32)>>,
    /// One entry per frame done.
    steps: RwSignal<Vec<StepCounts>>,
    /// The newest frame's points.
    newest: RwSignal<Option<FrameDetail>>,
    /// The run's generation ([`odometry::start`]), for replays.
    generation: StoredValue<u32>,
    /// Whether the run tracks with Lucas–Kanade (else a strategy's matches).
    lk: Signal<bool>,
) -> impl IntoView {
    // None: follow the newest frame.
    let picked = RwSignal::new(None::<usize>);
    // The re-detected points cover the frame (the loop re-detects on almost
    // every frame): shown on demand.
    let show_detected = RwSignal::new(false);
    let count = move || steps.with(|s| s.len());
    let shown = move || {
        let n = count();
        (n > 0).then(|| picked.get().map_or(n - 1, |p| p.min(n - 1)))
    };
    // The shown frame's image: the demo's file, or an object URL of the
    // folder's file (revoked when it changes).
    let url = RwSignal::new(None::<(usize, String, bool)>);
    Effect::new(move |_| {
        let Some(i) = shown() else { return };
        if url.with_untracked(|u| u.as_ref().is_some_and(|(j, _, _)| *j == i)) {
            return;
        }
        let new = source.with_value(|s| s.as_ref().and_then(|s| s.url(i)));
        if let Some((_, old, true)) = url.get_untracked() {
            revoke(Some(old));
        }
        url.set(new.map(|(u, revocable)| (i, u, revocable)));
    });
    on_cleanup(move || {
        if let Some((_, old, true)) = url.get_untracked() {
            revoke(Some(old));
        }
    });

    // An older frame's points, recomputed on demand: one replay at a time;
    // when it ends, the frame shown then is asked for if it differs.
    let replayed = RwSignal::new(None::<(usize, Result<Option<Arc<StepDetail>>, String>)>);
    let asking = StoredValue::new(None::<usize>);
    Effect::new(move |_| {
        let Some(i) = shown() else { return };
        let newest_frame = newest.with(|n| n.as_ref().map(|(f, _)| *f));
        if newest_frame == Some(i) || replayed.with(|r| r.as_ref().is_some_and(|(f, _)| *f == i)) {
            return;
        }
        if asking.get_value().is_some() {
            return;
        }
        let (from, redetected) = steps.with_untracked(|s| (replay_from(s, i, lk.get_untracked()), s[i].redetected));
        asking.set_value(Some(i));
        odometry::replay(generation.get_value(), 0, i, from, redetected, move |r| {
            asking.set_value(None);
            replayed.set(Some((i, r.map(|d| d.map(Arc::from)))));
        });
    });
    // The shown frame's points, when known: Ok(None) for a frame without any.
    let detail = move || -> Option<Result<Option<Arc<StepDetail>>, String>> {
        let i = shown()?;
        if let Some(d) = newest.with(|n| n.as_ref().filter(|(f, _)| *f == i).map(|(_, d)| d.clone())) {
            return Some(Ok(d));
        }
        replayed.with(|r| r.as_ref().filter(|(f, _)| *f == i).map(|(_, d)| d.clone()))
    };

    let picture = move || {
        let i = shown()?;
        let (w, h) = size.get()?;
        let href = url.with(|u| u.as_ref().filter(|(j, _, _)| *j == i).map(|(_, u, _)| u.clone()))?;
        let known = detail();
        let paths = known.clone().and_then(Result::ok).flatten().as_deref().map(flow_paths).unwrap_or_default();
        let dash = |s: &Style| s.dasharray().unwrap_or_default();
        Some(view! {
            <svg
                class="vo-flow"
                data-testid="vo-flow"
                data-detail-frame=known.as_ref().map(|_| i.to_string())
                viewBox=format!("0 0 {w} {h}")
                role="img"
                aria-label=format!("frame {i} with the points the odometry used")
            >
                <image href=href x="0" y="0" width=w height=h/>
                <path d=paths.inlier_lines class="flow-line" stroke=hex(INLIER.color)/>
                <path d=paths.inlier_ends class="flow-end" stroke=hex(INLIER.color)/>
                <path d=paths.outlier_lines class="flow-line" stroke=hex(OUTLIER.color) stroke-dasharray=dash(&OUTLIER)/>
                <path d=paths.outlier_ends class="flow-end" stroke=hex(OUTLIER.color)/>
                {show_detected.get().then(|| view! { <path d=paths.detected.clone() class="flow-end" stroke=hex(REDETECTED.color)/> })}
            </svg>
            {match known {
                None => Some(view! {
                    <p class="muted small" data-testid="vo-replay-pending">
                        {format!("recomputing the points of frame {i} (a long run keeps only the newest frame's)…")}
                    </p>
                }.into_any()),
                Some(Err(e)) => Some(view! { <p class="error small" data-testid="vo-replay-error">{e}</p> }.into_any()),
                Some(Ok(_)) => None,
            }}
        })
    };

    let counts = move || {
        let i = shown()?;
        let c = steps.with(|s| s.get(i).copied())?;
        let detected = if c.redetected { c.points_out as usize } else { 0 };
        Some(view! {
            <p
                class="small"
                data-testid="vo-step-counts"
                data-frame=i
                data-tracked=c.tracked
                data-inliers=c.essential_inliers
                data-pose-inliers=c.pose_inliers
                data-redetected=c.redetected.to_string()
            >
                {counts_text(i as u32, &c, lk.get(), detected)}
            </p>
        })
    };

    let chart = move || {
        let all: Vec<StepCounts> = steps.get();
        if all.len() < 2 {
            return None;
        }
        let (w, h) = (600.0, 120.0);
        let top = chart_top(&all.iter().map(|c| c.points_in.max(c.tracked)).collect::<Vec<_>>());
        let lines = SERIES
            .iter()
            .map(|(_, st, f)| {
                let v: Vec<u32> = all.iter().map(f).collect();
                view! {
                    <polyline
                        points=series_points(&v, all.len(), top, w, h)
                        class="series"
                        stroke=hex(st.color)
                        stroke-dasharray=st.dasharray()
                    />
                }
            })
            .collect_view();
        let cursor = shown().map(|i| {
            let x = chart_x(i, all.len(), w);
            view! { <line x1=x x2=x y1=0 y2=h class="cursor"/> }
        });
        let redetections = lk.get().then(|| format!("· {} ", redetections_text(&all)));
        let keys = SERIES
            .iter()
            .map(|(name, st, _)| {
                let sw = Sw { style: *st, line: true, outline: false, label: "" };
                view! { <span class="sw-item">{crate::page::legend::swatch(sw, false)}{format!(" {name} ")}</span> }
            })
            .collect_view();
        Some(view! {
            <figure class="vo-chart" data-testid="vo-chart">
                <svg viewBox=format!("-44 -8 {} {}", w + 52.0, h + 30.0) class="chart" role="img"
                    aria-label="points tracked and inliers per frame">
                    <rect x=0 y=0 width=w height=h class="chart-bg"/>
                    <text x=-4 y=8 class="ylabel">{top}</text>
                    <text x=-4 y=h class="ylabel">"0"</text>
                    <text x=0 y=h + 20.0 class="tick-label start">"frame 0"</text>
                    <text x=w y=h + 20.0 class="tick-label end">{format!("frame {}", all.len() - 1)}</text>
                    {lines}
                    {cursor}
                </svg>
                <figcaption class="muted small">
                    {keys}{redetections}"· the vertical line: the frame shown"
                </figcaption>
            </figure>
        })
    };

    let on_input = move |ev| {
        let v: usize = event_target_value(&ev).parse().unwrap_or(0);
        let last = count().saturating_sub(1);
        // Back at the newest frame: follow the run again.
        picked.set(if v >= last { None } else { Some(v) });
    };

    view! {
        <div class="vo-own" data-testid="vo-own">
            <h3>"What the loop did with the frame"</h3>
            <div class="row">
                <label class="ctl grow">
                    <span>
                        "frame shown "
                        <span class="muted small">{move || if picked.get().is_none() { "(following the run)" } else { "" }}</span>
                    </span>
                    <input
                        type="range"
                        min="0"
                        data-testid="vo-frame-slider"
                        prop:max=move || count().saturating_sub(1)
                        prop:value=move || shown().unwrap_or(0)
                        on:input=on_input
                    />
                </label>
            </div>
            {counts}
            <Legend swatches=LEGEND tail="segments run from where a point was in the previous frame to where it is now" dark=true/>
            <Show when=move || lk.get()>
                <label class="small">
                    <input type="checkbox" data-testid="vo-show-detected"
                        prop:checked=move || show_detected.get()
                        on:change=move |ev| show_detected.set(event_target_checked(&ev))/>
                    {move || {
                        let n = shown().and_then(|i| steps.with(|s| s.get(i).map(|c| if c.redetected { c.points_out } else { 0 }))).unwrap_or(0);
                        format!(" show the {n} points SIFT re-detected on this frame (the next frame tracks them)")
                    }}
                </label>
            </Show>
            <div class="vo-frame">{picture}</div>
            {chart}
        </div>
    }
}
