//! The odometry's own view: on the camera frame, what the loop did with it —
//! each tracked (or, for a matcher-driven run, matched) point's flow from the
//! previous frame, findEssentialMat's RANSAC inliers and outliers, the points
//! SIFT re-detected — with the frame's counts, and a chart of tracked points
//! and inliers per frame. While the run lasts it follows the newest frame; a
//! slider (or the arrow keys on it) steps through the frames run so far.

use crate::model::odometry::frame::{
    chart_top, chart_x, counts_text, flow_paths, png_size, redetections_text, series_points,
};
use crate::page::legend::{Legend, Sw};
use crate::platform::{blob_url, revoke};
use crate::protocol::odometry::StepCounts;
use leptos::prelude::*;
use siftlab_core::render::palette::{hex, Style, INLIER, OUTLIER, REDETECTED, SKY_BLUE, TRACKERS};
use siftlab_core::vo::StepDetail;
use std::sync::Arc;

/// One frame of the run as the view keeps it.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameStep {
    pub counts: StepCounts,
    pub detail: Option<Arc<StepDetail>>,
}

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
    /// The run's frames as PNG bytes, by frame index.
    frames: StoredValue<Vec<Vec<u8>>, LocalStorage>,
    /// One entry per frame done.
    steps: RwSignal<Vec<FrameStep>>,
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
    // The shown frame's image as an object URL (revoked when it changes).
    let url = RwSignal::new(None::<(usize, String)>);
    Effect::new(move |_| {
        let Some(i) = shown() else { return };
        if url.with_untracked(|u| u.as_ref().is_some_and(|(j, _)| *j == i)) {
            return;
        }
        let new = frames.with_value(|f| f.get(i).and_then(|b| blob_url(b)));
        if let Some((_, old)) = url.get_untracked() {
            revoke(Some(old));
        }
        url.set(new.map(|u| (i, u)));
    });
    on_cleanup(move || {
        if let Some((_, old)) = url.get_untracked() {
            revoke(Some(old));
        }
    });
    let size = move || {
        let i = shown()?;
        frames.with_value(|f| f.get(i).and_then(|b| png_size(b)))
    };

    let picture = move || {
        let i = shown()?;
        let (w, h) = size()?;
        let href = url.with(|u| u.as_ref().filter(|(j, _)| *j == i).map(|(_, u)| u.clone()))?;
        let step = steps.with(|s| s.get(i).cloned())?;
        let paths = step.detail.as_deref().map(flow_paths).unwrap_or_default();
        let dash = |s: &Style| s.dasharray().unwrap_or_default();
        Some(view! {
            <svg
                class="vo-flow"
                data-testid="vo-flow"
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
        })
    };

    let counts = move || {
        let i = shown()?;
        let step = steps.with(|s| s.get(i).cloned())?;
        let c = step.counts;
        let detected = step.detail.as_ref().map_or(0, |d| d.detected.len());
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
        let all: Vec<StepCounts> = steps.with(|s| s.iter().map(|f| f.counts).collect());
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
                        let n = shown().and_then(|i| steps.with(|s| s.get(i).and_then(|f| f.detail.as_ref().map(|d| d.detected.len())))).unwrap_or(0);
                        format!(" show the {n} points SIFT re-detected on this frame (the next frame tracks them)")
                    }}
                </label>
            </Show>
            <div class="vo-frame">{picture}</div>
            {chart}
        </div>
    }
}
