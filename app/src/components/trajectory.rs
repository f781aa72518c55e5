//! The lab's `view_trajectory FRAME_ID`: monocular visual odometry over frames
//! 0 … FRAME_ID (FRAME_ID + 1 frames, as the lab counts) of the demo or a
//! MyKITTI folder, computed by the core in workers, drawn as it grows (truth
//! green, estimate red, as in the lab's window), with the trajectory error and
//! the lab's window as a PNG to download.

use crate::client;
use crate::frameset::{run_from_zero, vo_frame_count, vo_range_label};
use crate::loading;
use crate::msg::FromWorker;
use crate::plot::{fit_xz, percent, polyline_xz, vo_done_text, vo_progress_text};
use crate::state::Lab;
use leptos::prelude::*;
use siftlab_core::render::coordinates_text;

type P3 = [f64; 3];
/// One plotted step: frame, estimate, ground truth.
type Step = (u32, P3, Option<P3>);

fn blob_url(bytes: &[u8]) -> Option<String> {
    let parts = js_sys::Array::new();
    parts.push(&js_sys::Uint8Array::from(bytes));
    let blob = web_sys::Blob::new_with_u8_array_sequence(&parts).ok()?;
    web_sys::Url::create_object_url_with_blob(&blob).ok()
}

fn revoke(url: Option<String>) {
    if let Some(u) = url {
        let _ = web_sys::Url::revoke_object_url(&u);
    }
}

#[derive(Clone, Debug, PartialEq)]
struct Done {
    ate: f64,
    png_url: Option<String>,
    ms: f64,
}

#[component]
pub fn TrajectoryView() -> impl IntoView {
    let lab = expect_context::<Lab>();
    // The lab's FRAME_ID: the last frame of the run.
    let frame_text = RwSignal::new(String::new());
    let steps = RwSignal::new(Vec::<Step>::new());
    let total = RwSignal::new(0u32);
    let running = RwSignal::new(false);
    let error = RwSignal::new(None::<String>);
    let done = RwSignal::new(None::<Done>);
    let frame_url = RwSignal::new(None::<String>);
    let frames = StoredValue::new_local(Vec::<Vec<u8>>::new());
    // When the workers got the frames: the live rate counts from there.
    let started_ms = StoredValue::new(0.0f64);
    // Frames 0, 1, 2, … with no gap: the demo's 119, 120, 149, 150 are not part of it.
    let available = move || lab.source.with(|s| run_from_zero(s.frames()));
    Effect::new(move |_| frame_text.set(available().saturating_sub(1).to_string()));

    let run = move |_| {
        let n = match vo_frame_count(&frame_text.get_untracked(), available()) {
            Ok(n) => n,
            Err(e) => {
                error.set(Some(e));
                return;
            }
        };
        error.set(None);
        if let Some(d) = done.get_untracked() {
            revoke(d.png_url);
        }
        done.set(None);
        steps.set(vec![]);
        total.set(n);
        running.set(true);
        let source = lab.source.get_untracked();
        leptos::task::spawn_local(async move {
            let (fr, poses) = match loading::vo_inputs(&source, n).await {
                Ok(x) => x,
                Err(e) => {
                    error.set(Some(e));
                    running.set(false);
                    return;
                }
            };
            frames.set_value(fr.clone());
            started_ms.set_value(crate::worker::now_ms());
            let started = client::run_vo(fr, poses, move |m| match m {
                FromWorker::VoStep { frame, position, truth, .. } => {
                    steps.update(|s| s.push((frame, position, truth)));
                    let url = frames.with_value(|f| f.get(frame as usize).and_then(|b| blob_url(b)));
                    revoke(frame_url.get_untracked());
                    frame_url.set(url);
                }
                FromWorker::VoDone { ate, png, ms, .. } => {
                    done.set(Some(Done { ate, png_url: blob_url(&png), ms }));
                    running.set(false);
                }
                FromWorker::Failed { message, .. } => {
                    error.set(Some(message));
                    running.set(false);
                }
                _ => {}
            });
            if let Err(e) = started {
                error.set(Some(e));
                running.set(false);
            }
        });
    };
    let stop = move |_| {
        client::stop_vo();
        running.set(false);
    };

    let plot = move || {
        let s = steps.get();
        if s.is_empty() {
            return None;
        }
        // The lab's window: x to the right, z (forward) downwards; fit all points.
        let (vx, vz, vs) = fit_xz(s.iter().flat_map(|(_, e, t)| std::iter::once(*e).chain(*t)));
        let est = polyline_xz(s.iter().map(|(_, e, _)| *e));
        let gt = polyline_xz(s.iter().filter_map(|(_, _, t)| *t));
        let last = s.last().map(|(_, e, _)| *e).unwrap_or([0.0; 3]);
        let r = vs / 120.0;
        Some(view! {
            <svg class="traj-svg" viewBox=format!("{vx} {vz} {vs} {vs}") data-testid="vo-plot" role="img" aria-label="trajectory: truth green, estimate red">
                <polyline points=gt class="traj-gt" stroke-width=r * 0.8/>
                <polyline points=est class="traj-est" stroke-width=r * 0.8/>
                <circle cx=last[0] cy=last[2] r=r * 1.6 class="traj-now"/>
            </svg>
            <p class="muted small">"x → right, z (forward) ↓ as in the lab's window; dot: the camera now"</p>
            <p class="mono small" data-testid="vo-coordinates">{coordinates_text(&last)}</p>
        })
    };

    view! {
        <section class="card trajectory" aria-label="Visual odometry">
            <h2>"8 · Visual odometry (the lab's view_trajectory)"</h2>
            <p class="muted">
                "The lab's monocular VO, "<code>"view_trajectory FRAME_ID"</code>", on frames 0 … FRAME_ID: SIFT keypoints of the first frame, Lucas–Kanade tracking, "
                "essential matrix (5-point RANSAC), recoverPose, scale from the ground-truth poses. "
                <span class="legend-gt">"green: ground truth"</span>", "<span class="legend-est">"red: estimate"</span>"."
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
                        on:input=move |ev| frame_text.set(event_target_value(&ev))/>
                </label>
                <button class="primary" data-testid="vo-run" on:click=run prop:disabled=move || running.get() || available() < 2>
                    "Run the odometry"
                </button>
                <Show when=move || running.get()>
                    <button on:click=stop>"Stop"</button>
                </Show>
            </div>
            {move || error.get().map(|e| view! { <p class="error" data-testid="vo-error" role="alert">{e}</p> })}
            <Show when=move || running.get() || !steps.with(|s| s.is_empty())>
                <div class="vo-progress" data-testid="vo-progress">
                    <div class="pbar"><div class="pbar-fill" style:width=move || percent(steps.with(|s| s.len()), total.get())></div></div>
                    <span class="muted">{move || {
                        // The rate so far, updated with each step while the run lasts
                        // (then the run's own figure, with the error, replaces it).
                        let elapsed = crate::worker::now_ms() - started_ms.get_value();
                        vo_progress_text(steps.with(|s| s.len()), total.get(), running.get(), elapsed)
                    }}</span>
                </div>
                <div class="vo-views">
                    <div class="vo-plot">{plot}</div>
                    <div class="vo-frame">
                        {move || frame_url.get().map(|u| view! { <img src=u alt="the current camera frame" class="vo-img"/> })}
                    </div>
                </div>
            </Show>
            {move || done.get().map(|d| view! {
                <p>
                    "Trajectory error (RMSE, no alignment, GT scale): "
                    <strong data-testid="vo-ate">{format!("{:.4} m", d.ate)}</strong>
                    {vo_done_text(steps.with(|s| s.len()), d.ms)}
                    {d.png_url.map(|u| view! { " · " <a href=u download="trajectory.png" data-testid="vo-download">"download trajectory.png"</a> })}
                </p>
            })}
        </section>
    }
}
