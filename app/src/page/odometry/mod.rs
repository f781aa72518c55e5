//! The lab's `view_trajectory FRAME_ID`: monocular visual odometry over frames
//! 0 … FRAME_ID (FRAME_ID + 1 frames, as the lab counts) of the demo or a
//! MyKITTI folder, computed by the core in workers, drawn as it grows (truth
//! solid, estimate dashed, in the palette's colours), with the trajectory error and
//! the lab's window as a PNG to download. A menu swaps LK for the student's
//! matcher (`vo::matched`); the metrics and the core's figures follow each run,
//! [`OdometryFrameView`] shows what the loop did with each frame, and [`OdometryCompare`]
//! runs all four trackers side by side.

mod compare;
mod figures;
mod frame;

use crate::model::frameset::{run_from_zero, vo_frame_count, vo_range_label};
use crate::model::lab::Lab;
use crate::model::odometry::{
    default_threshold, tracker_from, tracker_kind, tracker_label, tracker_value, RunResult, Tracker, TRACKERS,
};
use crate::model::plot::{percent, vo_done_text, vo_progress_text};
use crate::platform::{blob_url, revoke};
use crate::protocol::odometry::{StepCounts, VoReply};
use crate::services::odometry;
use crate::services::sift_pool;
use crate::services::sources;
use compare::OdometryCompare;
use figures::OdometryFigures;
use frame::{FrameDetail, OdometryFrameView};
use leptos::prelude::*;
use siftlab_core::render::coordinates_text;
use siftlab_core::vo::TrajectoryMetrics;

type P3 = [f64; 3];

/// The lab manual's odometry example: `view_trajectory 150`.
const MANUAL_FRAME_ID: u32 = 150;
/// One plotted step: frame, estimate, ground truth.
type Step = (u32, P3, Option<P3>);

#[derive(Clone, Debug, PartialEq)]
struct Done {
    ate: f64,
    png_url: Option<String>,
    /// The estimated poses in KITTI's format (the CLI's `--save-poses`).
    poses_url: Option<String>,
    ms: f64,
}

/// How the run was computed: SIFT workers and their memory.
fn workers_text() -> String {
    let n = sift_pool::worker_count();
    let peak = sift_pool::worker_memory_peak();
    let mem = if peak > 0 { format!(", each up to {} MB of wasm memory", peak >> 20) } else { String::new() };
    format!(
        "SIFT on {n} worker{}{mem}, each frame once for every tracker (add ?workers=N to the address to change the count)",
        if n == 1 { "" } else { "s" }
    )
}

#[component]
pub fn OdometryView() -> impl IntoView {
    let lab = expect_context::<Lab>();
    // The lab's FRAME_ID: the last frame of the run.
    let frame_text = RwSignal::new(String::new());
    let steps = RwSignal::new(Vec::<Step>::new());
    let total = RwSignal::new(0u32);
    let running = RwSignal::new(false);
    let error = RwSignal::new(None::<String>);
    let done = RwSignal::new(None::<Done>);
    // Per frame its counts (a few bytes), and the newest frame's points.
    let frame_steps = RwSignal::new(Vec::<StepCounts>::new());
    let newest = RwSignal::new(None::<FrameDetail>);
    // The tracker menu (`None`: the lab's LK) and the strategy's threshold,
    // parsed into a tracker once per change; the run keeps the one it ran.
    let tracker = RwSignal::new(None::<siftlab_core::matching::StrategyKind>);
    let threshold = RwSignal::new(String::new());
    let chosen = Memo::new(move |_| tracker_from(tracker.get(), &threshold.get()));
    let tracker_run = RwSignal::new(Tracker::Lk);
    let metrics = RwSignal::new(None::<TrajectoryMetrics>);
    // Where the run reads its frames, frame 0's size, and the run's generation.
    let frames = StoredValue::new_local(None::<sources::FrameSource>);
    let frame_size = RwSignal::new(None::<(u32, u32)>);
    let generation = StoredValue::new(0u32);
    // The run's ground-truth poses (the poses file's text), for the KITTI note.
    let poses_text = StoredValue::new(String::new());
    // When the workers got the frames: the live rate counts from there.
    let started_ms = StoredValue::new(0.0f64);
    // Frames 0, 1, 2, … with no gap: the demo's 119, 120, 149, 150 are not part of it.
    let available = move || lab.source.with(|s| run_from_zero(s.frames()));
    // Each source's last frame by default; but a FRAME_ID typed before the
    // first source's frame list arrived (the demo's index) is the student's
    // and stays.
    let typed_early = StoredValue::new(false);
    Effect::new(move |_| {
        let n = available();
        if typed_early.get_value() {
            typed_early.set_value(n == 0);
            return;
        }
        frame_text.set(n.saturating_sub(1).to_string());
    });

    let run = move |_: ()| {
        let n = match vo_frame_count(&frame_text.get_untracked(), available()) {
            Ok(n) => n,
            Err(e) => {
                error.set(Some(e));
                return;
            }
        };
        let chosen = match chosen.get_untracked() {
            Ok(t) => t,
            Err(e) => {
                error.set(Some(e));
                return;
            }
        };
        tracker_run.set(chosen);
        metrics.set(None);
        error.set(None);
        if let Some(d) = done.get_untracked() {
            revoke(d.png_url);
            revoke(d.poses_url);
        }
        done.set(None);
        steps.set(vec![]);
        frame_steps.set(vec![]);
        newest.set(None);
        total.set(n);
        running.set(true);
        let source = lab.source.get_untracked();
        leptos::task::spawn_local(async move {
            let inputs = match sources::vo_inputs(&source, n).await {
                Ok(x) => x,
                Err(e) => {
                    error.set(Some(e));
                    running.set(false);
                    return;
                }
            };
            frames.set_value(Some(inputs.frames.clone()));
            frame_size.set(inputs.size);
            poses_text.set_value(inputs.poses.clone());
            started_ms.set_value(crate::platform::now_ms());
            let on_event = move |m| match m {
                VoReply::Step { frame, position, truth, counts, detail, .. } => {
                    steps.update(|s| s.push((frame, position, truth)));
                    frame_steps.update(|s| s.push(counts));
                    newest.set(Some((frame as usize, detail.map(std::sync::Arc::from))));
                }
                VoReply::Metrics { metrics: m, .. } => metrics.set(Some(TrajectoryMetrics::from_array(&m))),
                VoReply::Done { ate, png, ms, kitti, .. } => {
                    done.set(Some(Done { ate, png_url: blob_url(&png), poses_url: blob_url(kitti.as_bytes()), ms }));
                    running.set(false);
                }
                VoReply::Failed { message, .. } => {
                    error.set(Some(message));
                    running.set(false);
                }
                VoReply::Replayed { .. } => {}
            };
            match odometry::start(inputs, &[chosen], move |_, m| on_event(m)) {
                Ok(g) => generation.set_value(g),
                Err(e) => {
                    error.set(Some(e));
                    running.set(false);
                }
            }
        });
    };
    let stop = move |_| {
        odometry::stop();
        running.set(false);
    };

    let truth = Signal::derive(move || steps.with(|s| s.iter().filter_map(|(_, _, t)| *t).collect::<Vec<_>>()));
    let runs = Signal::derive(move || {
        let positions = steps.with(|s| s.iter().map(|(_, e, _)| *e).collect());
        vec![RunResult { tracker: tracker_run.get(), positions, metrics: None, ms: 0.0 }.plot_run()]
    });
    let last = move || steps.with(|s| s.last().map(|(_, e, _)| *e).unwrap_or([0.0; 3]));
    let count = Signal::derive(move || vo_frame_count(&frame_text.get(), available()));
    let source = Signal::derive(move || lab.source.get());

    view! {
        <section class="card trajectory" aria-label="Visual odometry">
            <h2>"8 · Visual odometry (the lab's view_trajectory)"</h2>
            <p class="muted">
                "The lab's monocular VO, "<code>"view_trajectory FRAME_ID"</code>", on frames 0 … FRAME_ID: SIFT keypoints of the first frame, Lucas–Kanade tracking, "
                "essential matrix (5-point RANSAC), recoverPose, scale from the ground-truth poses. "
                "In the figures the ground truth is a black solid line, the estimate a dashed line with markers in "
                "the tracker's colour (the legend names each)."
            </p>
            <div class="control-row">
                <label class="ctl">
                    <span>
                        "FRAME_ID (the last frame) "
                        <span class="muted" data-testid="vo-range">
                            {move || frame_text.with(|t| vo_range_label(t, available()))}
                        </span>
                    </span>
                    <input type="number" min="1" class="num" data-testid="vo-frame-id"
                        prop:value=move || frame_text.get()
                        on:input=move |ev| {
                            if available() == 0 {
                                typed_early.set_value(true);
                            }
                            frame_text.set(event_target_value(&ev));
                        }/>
                </label>
                <label class="ctl">
                    <span>"tracker"</span>
                    <select data-testid="vo-tracker" on:change=move |ev| {
                        let k = tracker_kind(&event_target_value(&ev));
                        threshold.set(k.map(default_threshold).unwrap_or_default());
                        tracker.set(k);
                    }>
                        {TRACKERS.map(|k| view! {
                            <option value=tracker_value(k) selected=move || tracker.get() == k>{tracker_label(k)}</option>
                        })}
                    </select>
                </label>
                <Show when=move || tracker.get().is_some()>
                    <label class="ctl">
                        <span>"threshold"</span>
                        <input class="num" data-testid="vo-threshold" prop:value=move || threshold.get()
                            on:input=move |ev| threshold.set(event_target_value(&ev))/>
                    </label>
                </Show>
                <button class="primary" data-testid="vo-run" on:click=move |_| run(()) prop:disabled=move || running.get() || available() < 2>
                    "Run the odometry"
                </button>
                <Show when=move || running.get()>
                    <button on:click=stop>"Stop"</button>
                </Show>
            </div>
            <p class="small">
                <button
                    class="manual-ex"
                    data-testid="vo-manual-150"
                    title="FRAME_ID 150 with the lab's Lucas–Kanade tracker, as the manual's first odometry example"
                    prop:disabled=move || running.get() || available() < MANUAL_FRAME_ID + 1
                    on:click=move |_| {
                        frame_text.set(MANUAL_FRAME_ID.to_string());
                        tracker.set(None);
                        run(());
                    }
                >
                    <span class="task">"Lab manual example"</span>
                    <code>"view_trajectory 150"</code>
                </button>
                <span class="muted">" — frames 0 … 150, through the first right turn (frames ~100–125)"</span>
            </p>
            {move || error.get().map(|e| view! { <p class="error" data-testid="vo-error" role="alert">{e}</p> })}
            <Show when=move || running.get() || !steps.with(|s| s.is_empty())>
                <div class="vo-progress" data-testid="vo-progress">
                    <div class="pbar"><div class="pbar-fill" style:width=move || percent(steps.with(|s| s.len()), total.get())></div></div>
                    <span class="muted">{move || {
                        // The rate so far, updated with each step while the run lasts
                        // (then the run's own figure, with the error, replaces it).
                        let elapsed = crate::platform::now_ms() - started_ms.get_value();
                        vo_progress_text(steps.with(|s| s.len()), total.get(), running.get(), elapsed)
                    }}</span>
                </div>
                <div class="vo-views">
                    <div class="vo-plot">
                        <OdometryFigures truth=truth runs=runs name="vo"/>
                        <p class="mono small" data-testid="vo-coordinates">{move || coordinates_text(&last())}</p>
                    </div>
                    <OdometryFrameView source=frames size=frame_size steps=frame_steps newest=newest generation=generation lk=Signal::derive(move || tracker_run.get() == Tracker::Lk)/>
                </div>
            </Show>
            {move || done.get().map(|d| view! {
                <p>
                    "Trajectory error (RMSE, no alignment, GT scale): "
                    <strong data-testid="vo-ate">{format!("{:.4} m", d.ate)}</strong>
                    {vo_done_text(steps.with(|s| s.len()), d.ms)}
                    {d.png_url.map(|u| view! { " · " <a href=u download="trajectory.png" data-testid="vo-download">"download trajectory.png"</a> })}
                    {d.poses_url.map(|u| view! { " · " <a href=u download="poses.txt" data-testid="vo-poses"
                        title="the estimated poses, 12 numbers a line (KITTI's format, as view_trajectory --save-poses writes them)">"poses.txt"</a> })}
                </p>
                <p class="muted small" data-testid="vo-workers">{workers_text()}</p>
            })}
            {move || metrics.get().map(|m| {
                let n = steps.with(|s| s.len());
                let note = poses_text.with_value(|p| crate::model::odometry::kitti_note_text(p, n));
                view! {
                    <p class="small" data-testid="vo-metrics">{m.summary()}</p>
                    {note.map(|t| view! { <p class="small muted" data-testid="vo-kitti">{t}</p> })}
                }
            })}
            <OdometryCompare source=source count=count/>
        </section>
    }
}
