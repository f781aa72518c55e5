//! The comparison: LK, dt 200, nn and nndr 0.8 run one after the other on
//! the same frames, their trajectories overlaid and their metrics in a table.

use super::vo_plot::VoFigures;
use crate::client;
use crate::loading;
use crate::msg::FromWorker;
use crate::state::Source;
use crate::vo_view::{compare_runs, metric_cells, RunResult};
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
    frames: StoredValue<Vec<Vec<u8>>, LocalStorage>,
    poses: StoredValue<String>,
}

/// Starts run `k` of [`compare_runs`]; its `VoDone` starts run k + 1.
fn start(ctx: Ctx, k: usize) {
    let runs = compare_runs();
    let Some(strategy) = runs.get(k).copied() else {
        ctx.running.set(false);
        ctx.status.set(format!("{} runs done", runs.len()));
        return;
    };
    let label = run_style(strategy.as_ref()).0;
    ctx.status.set(format!("running {label} ({} of {})", k + 1, runs.len()));
    ctx.results.update(|r| r.push(RunResult { strategy, positions: Vec::new(), metrics: None, ms: 0.0 }));
    let frames = ctx.frames.get_value();
    let poses = ctx.poses.get_value();
    let on_event = move |m: FromWorker| match m {
        FromWorker::VoStep { frame, position, truth, .. } => {
            ctx.results.update(|r| {
                if let Some(last) = r.last_mut() {
                    last.positions.push(position);
                }
            });
            if k == 0 {
                if let Some(t) = truth {
                    ctx.truth.update(|v| v.push(t));
                }
            }
            ctx.status.set(format!("running {label} ({} of 4) · frame {}", k + 1, frame + 1));
        }
        FromWorker::VoMetrics { metrics, .. } => ctx.results.update(|r| {
            if let Some(last) = r.last_mut() {
                last.metrics = Some(TrajectoryMetrics::from_array(&metrics));
            }
        }),
        FromWorker::VoDone { ms, .. } => {
            ctx.results.update(|r| {
                if let Some(last) = r.last_mut() {
                    last.ms = ms;
                }
            });
            // The next run replaces this one's workers: start it after this
            // message's handler has returned.
            leptos::task::spawn_local(async move { start(ctx, k + 1) });
        }
        FromWorker::Failed { message, .. } => {
            ctx.error.set(Some(format!("{label}: {message}")));
            ctx.running.set(false);
        }
        _ => {}
    };
    let started = match strategy {
        None => client::run_vo(frames, poses, on_event),
        Some(s) => client::run_vo_matched(frames, poses, s, on_event),
    };
    if let Err(e) = started {
        ctx.error.set(Some(e));
        ctx.running.set(false);
    }
}

/// The comparison's button, figures and table, over `count()` frames from 0
/// (the odometry view's FRAME_ID + 1, or its error).
#[component]
pub fn VoCompare(source: Signal<Source>, count: Signal<Result<u32, String>>) -> impl IntoView {
    let ctx = Ctx {
        results: RwSignal::new(Vec::new()),
        truth: RwSignal::new(Vec::new()),
        status: RwSignal::new(String::new()),
        running: RwSignal::new(false),
        error: RwSignal::new(None),
        frames: StoredValue::new_local(Vec::new()),
        poses: StoredValue::new(String::new()),
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
            match loading::vo_inputs(&source, n).await {
                Ok((frames, poses)) => {
                    ctx.frames.set_value(frames);
                    ctx.poses.set_value(poses);
                    start(ctx, 0);
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
                .filter_map(|run| run.metrics.map(|m| metric_cells(&run.plot_run().name, &m, run.ms)))
                .map(|cells| {
                    let name = cells[0].clone();
                    view! { <tr data-testid="vo-compare-row" data-run=name>{cells.into_iter().map(|c| view! { <td>{c}</td> }).collect_view()}</tr> }
                })
                .collect_view()
        })
    };
    view! {
        <div class="vo-compare">
            <h3>"Compare the trackers"</h3>
            <p class="muted">
                "The same loop four times on the same frames: the lab's Lucas–Kanade tracking, and SIFT matching of consecutive frames "
                "with dt 200, nn and nndr 0.8 (each query's nearest match feeds findEssentialMat). ATE: position error, raw and after the best rigid "
                "alignment; RPE: error of each frame-to-frame motion; KITTI: the benchmark's error per 100–800 m segment (n/a under 100 m of path)."
            </p>
            <button class="primary" data-testid="vo-compare-run" on:click=run prop:disabled=move || ctx.running.get()>
                "Run all four"
            </button>
            " "<span class="muted" data-testid="vo-compare-status">{move || ctx.status.get()}</span>
            {move || ctx.error.get().map(|e| view! { <p class="error" role="alert" data-testid="vo-compare-error">{e}</p> })}
            <Show when=move || !ctx.results.with(|r| r.is_empty())>
                <VoFigures truth=ctx.truth.into() runs=plot_runs name="vo-compare"/>
                // Eight columns are wider than a phone: the table scrolls in its own
                // region, which the keyboard can reach.
                <div class="table-scroll" tabindex="0" role="region" aria-label="Metrics of the four trackers">
                    <table class="vo-table" data-testid="vo-compare-table">
                        <thead><tr>
                            <th>"run"</th><th>"ATE (m)"</th><th>"ATE aligned (m)"</th><th>"RPE (m)"</th><th>"RPE (°)"</th>
                            <th>"KITTI t (%)"</th><th>"KITTI r (°/100 m)"</th><th>"frames/s"</th>
                        </tr></thead>
                        <tbody>{rows}</tbody>
                    </table>
                </div>
            </Show>
        </div>
    }
}
