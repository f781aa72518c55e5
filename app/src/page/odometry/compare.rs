//! The comparison: LK, dt 200, nn and nndr 0.8 run side by side on the same
//! frames (each frame's SIFT computed once for all four), their trajectories
//! overlaid and their metrics in a table.

use super::figures::OdometryFigures;
use crate::model::lab::Source;
use crate::model::odometry::{compare_runs, kitti_note_text, metric_cells, RunResult};
use crate::platform::{blob_url, revoke};
use crate::protocol::odometry::VoReply;
use crate::services::odometry;
use crate::services::sources;
use leptos::prelude::*;
use siftlab_core::render::plot::figures::run_style;
use siftlab_core::vo::TrajectoryMetrics;

type P3 = [f64; 3];

/// What the comparison shares between its runs.
#[derive(Clone, Copy)]
struct Ctx {
    results: RwSignal<Vec<RunResult>>,
    truth: RwSignal<Vec<P3>>,
    status: RwSignal<String>,
    running: RwSignal<bool>,
    error: RwSignal<Option<String>>,
    /// The run's frames (read as it goes), poses and camera.
    inputs: StoredValue<Option<sources::VoInputs>, LocalStorage>,
    /// Per run: its estimated poses (KITTI format) as a download, once done.
    poses_urls: RwSignal<Vec<Option<String>>>,
}

/// Starts the four runs of [`compare_runs`] side by side: one tracking
/// worker each, fed from one SIFT computation per frame (`vo_run`).
fn start(ctx: Ctx) {
    let runs = compare_runs();
    let n = runs.len();
    ctx.results.set(
        runs.iter().map(|&tracker| RunResult { tracker, positions: Vec::new(), metrics: None, ms: 0.0 }).collect(),
    );
    ctx.status.set(format!("running the {n} trackers side by side"));
    ctx.poses_urls.update(|u| {
        for url in u.drain(..) {
            revoke(url);
        }
        u.resize(n, None);
    });
    let Some(inputs) = ctx.inputs.get_value() else { return };
    let total = inputs.frames.frame_count();
    // Which trackers are over (done or failed): the last one ends the comparison.
    let over = std::rc::Rc::new(std::cell::RefCell::new(vec![false; n]));
    let on_event = move |k: usize, m: VoReply| {
        let ended = match m {
            VoReply::Step { position, truth, .. } => {
                ctx.results.update(|r| r[k].positions.push(position));
                if k == 0 {
                    if let Some(t) = truth {
                        ctx.truth.update(|v| v.push(t));
                    }
                }
                let least = ctx.results.with(|r| r.iter().map(|r| r.positions.len()).min().unwrap_or(0));
                ctx.status.set(format!("running the {n} trackers side by side · {least} of {total} frames"));
                false
            }
            VoReply::Metrics { metrics, .. } => {
                ctx.results.update(|r| r[k].metrics = Some(TrajectoryMetrics::from_array(&metrics)));
                false
            }
            VoReply::Done { ms, kitti, .. } => {
                ctx.results.update(|r| r[k].ms = ms);
                ctx.poses_urls.update(|u| {
                    if let Some(slot) = u.get_mut(k) {
                        *slot = blob_url(kitti.as_bytes());
                    }
                });
                true
            }
            VoReply::Replayed { .. } => false,
            VoReply::Failed { message, .. } => {
                let e = format!("{}: {message}", run_style(runs[k].strategy()).0);
                ctx.error.update(|old| *old = Some(old.take().map_or(e.clone(), |o| format!("{o}; {e}"))));
                true
            }
        };
        if ended {
            let all = {
                let mut over = over.borrow_mut();
                over[k] = true;
                over.iter().all(|&o| o)
            };
            if all {
                ctx.running.set(false);
                ctx.status.set(format!("{n} runs done"));
            }
        }
    };
    if let Err(e) = odometry::start(inputs, &runs, on_event) {
        ctx.error.set(Some(e));
        ctx.running.set(false);
    }
}

/// The comparison's button, figures and table, over `count()` frames from 0
/// (the odometry view's FRAME_ID + 1, or its error).
#[component]
pub fn OdometryCompare(source: Signal<Source>, count: Signal<Result<u32, String>>) -> impl IntoView {
    let ctx = Ctx {
        results: RwSignal::new(Vec::new()),
        truth: RwSignal::new(Vec::new()),
        status: RwSignal::new(String::new()),
        running: RwSignal::new(false),
        error: RwSignal::new(None),
        inputs: StoredValue::new_local(None),
        poses_urls: RwSignal::new(Vec::new()),
    };
    let run = move |_| {
        let n = match count.get_untracked() {
            Ok(n) => n,
            Err(e) => return ctx.error.set(Some(e)),
        };
        ctx.error.set(None);
        ctx.results.set(Vec::new());
        ctx.truth.set(Vec::new());
        ctx.running.set(true);
        let source = source.get_untracked();
        leptos::task::spawn_local(async move {
            match sources::vo_inputs(&source, n).await {
                Ok(inputs) => {
                    ctx.inputs.set_value(Some(inputs));
                    start(ctx);
                }
                Err(e) => {
                    ctx.error.set(Some(e));
                    ctx.running.set(false);
                }
            }
        });
    };
    let plot_runs = Signal::derive(move || ctx.results.with(|r| r.iter().map(RunResult::plot_run).collect::<Vec<_>>()));
    let rows = move || {
        ctx.results.with(|r| {
            r.iter()
                .enumerate()
                .filter_map(|(k, run)| run.metrics.map(|m| (k, metric_cells(&run.plot_run().name, &m, run.ms))))
                .map(|(k, cells)| {
                    let name = cells[0].clone();
                    let url = ctx.poses_urls.with(|u| u.get(k).cloned().flatten());
                    let file = format!("poses_{}.txt", name.replace(' ', "_"));
                    view! {
                        <tr data-testid="vo-compare-row" data-run=name.clone()>
                            {cells.into_iter().map(|c| view! { <td>{c}</td> }).collect_view()}
                            <td>{url.map(|u| view! {
                                <a href=u download=file.clone() data-testid="vo-compare-poses"
                                    aria-label=format!("{file}, the estimated poses of {name} in KITTI format")>{file.clone()}</a>
                            })}</td>
                        </tr>
                    }
                })
                .collect_view()
        })
    };
    view! {
        <div class="vo-compare">
            <h3>"Compare the trackers"</h3>
            <p class="muted">
                "The same loop four times on the same frames, side by side (each frame's SIFT is computed once and shared): the lab's Lucas–Kanade tracking, and SIFT matching of consecutive frames "
                "with dt 200, nn and nndr 0.8 (each query's nearest match feeds findEssentialMat). ATE: position error, raw and after the best rigid "
                "alignment; RPE: error of each frame-to-frame motion; KITTI: the benchmark's error per 100–800 m segment, from every 10th frame (n/a under 100 m of path); frames/s: each run's pace with all four running at once."
            </p>
            <button class="primary" data-testid="vo-compare-run" on:click=run prop:disabled=move || ctx.running.get()>
                "Run all four"
            </button>
            " "<span class="muted" data-testid="vo-compare-status">{move || ctx.status.get()}</span>
            {move || ctx.error.get().map(|e| view! { <p class="error" role="alert" data-testid="vo-compare-error">{e}</p> })}
            <Show when=move || !ctx.results.with(|r| r.is_empty())>
                <OdometryFigures truth=ctx.truth.into() runs=plot_runs name="vo-compare"/>
                // Eight columns are wider than a phone: the table scrolls in its own
                // region, which the keyboard can reach.
                <div class="table-scroll" tabindex="0" role="region" aria-label="Metrics of the four trackers">
                    <table class="vo-table" data-testid="vo-compare-table">
                        <thead><tr>
                            <th>"run"</th><th>"ATE (m)"</th><th>"ATE aligned (m)"</th><th>"RPE (m)"</th><th>"RPE (°)"</th>
                            <th>"KITTI t (%)"</th><th>"KITTI r (°/100 m)"</th><th>"frames/s"</th><th>"poses"</th>
                        </tr></thead>
                        <tbody>{rows}</tbody>
                    </table>
                </div>
                {move || {
                    let done = ctx.results.with(|r| r.iter().any(|r| r.metrics.is_some()));
                    let note = done
                        .then(|| ctx.inputs.with_value(|i| i.as_ref().and_then(|i| kitti_note_text(&i.poses, i.frames.frame_count()))))
                        .flatten()?;
                    Some(view! {
                        <p class="small" data-testid="vo-compare-kitti">
                            {note}
                            " — each segment is one stretch of true path scored as a whole, so with this few the KITTI figures are a rough guide; ATE and RPE use every frame."
                        </p>
                    })
                }}
            </Show>
        </div>
    }
}
