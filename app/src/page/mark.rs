//! "Mark my code": the student's own `vision_tasks.py` (picked, dropped or
//! pasted) run in the browser under Pyodide with siftlab's `cv2`, marked as
//! the lab's automarker marks it: the 20-mark table, and each failed case with
//! its arguments, the expected and the returned value and a diagnosis.

use crate::model::lab::Lab;
use crate::model::mark::MAX_CASES;
use crate::page::file_input::{dropped_file, take_picked_file};
use crate::services::mark::{run, Timing};
use crate::services::sources::read_file;
use leptos::prelude::*;
use siftlab_mark::{Marks, Status};

#[derive(Clone, Debug, PartialEq)]
struct Outcome {
    marks: Marks,
    timing: Timing,
    ms: f64,
}

#[component]
fn Report(o: Outcome) -> impl IntoView {
    let m = &o.marks;
    let rows = m
        .tasks
        .iter()
        .map(|t| {
            // The slowest call against the 10 s limit: how close a correct but slow
            // solution comes to losing its marks.
            let slowest =
                m.results.iter().filter(|r| r.case.task() == t.task).map(|r| r.seconds).fold(0.0f64, f64::max);
            view! {
                <tr data-testid="mark-row" data-task=t.task.name() data-marks=format!("{:.2}", t.marks)
                    data-correct=t.correct data-errors=t.errors data-calls=t.calls data-slowest=format!("{slowest:.3}")>
                    <td><code>{t.task.name()}</code></td>
                    <td>{t.calls}</td>
                    <td>{t.correct}</td>
                    <td>{t.errors}</td>
                    <td>{format!("{:.2} / 5", t.marks)}</td>
                    <td>{format!("{slowest:.1} s")}</td>
                </tr>
            }
        })
        .collect_view();
    let rejection = m.rejection.as_ref().map(|r| {
        view! { <p class="error" role="alert" data-testid="mark-rejected" data-code=r.code()>{r.to_string()}</p> }
    });
    let failures = m
        .results
        .iter()
        .filter(|r| r.status != Status::Correct)
        .map(|r| {
            let why = r.diagnosis.as_ref().map(|d| d.describe()).unwrap_or_default();
            let code = r.diagnosis.as_ref().map(|d| d.code()).unwrap_or_default();
            // The explorer on this case's pair, strategy, threshold and feature, in a
            // new tab: the mark stays where it is.
            let link = siftlab_mark::result_link(r);
            view! {
                <li data-testid="mark-failure" data-task=r.case.task().name() data-diagnosis=code data-status=r.status.name()>
                    <p><code>{r.case.call_text()}</code>" — "<strong>{r.status.name()}</strong></p>
                    <p class="small">"expected: "<code class="wrap">{r.expected.clone()}</code></p>
                    <p class="small">"returned: "<code class="wrap">{r.returned.clone()}</code></p>
                    <p class="small diag">{why}</p>
                    <p class="small"><a href=link target="_blank" rel="noopener" data-testid="see-case">
                        "see this case"</a>" in the explorer (frames, matches, the feature)"</p>
                </li>
            }
        })
        .collect_view();
    let full = m.full();
    // How this browser's speed scaled the limits (the lab's are CPU time on
    // the lab's machine; here only wall time exists).
    let first = o.timing.speeds.first().copied().unwrap_or(1.0);
    let slowest = o.timing.speeds.iter().copied().fold(first, f64::max);
    // Every start's speed, in order, for the e2e suite's check of which try ran too slow.
    let speeds = o.timing.speeds.iter().map(|s| format!("{s:.3}")).collect::<Vec<_>>().join(",");
    let speed_text = if o.timing.speeds.is_empty() {
        String::new()
    } else {
        let again = if slowest > first { format!(" (up to {slowest:.2}× at a restart)") } else { String::new() };
        format!(
            " · this browser ran the reference at {first:.2}× the reference time{again}; limits scaled to {:.1} s",
            o.timing.call_limit_s
        )
    };
    let too_slow =
        m.results.iter().filter(|r| r.diagnosis.as_ref().is_some_and(|d| d.code() == "too_slow_here")).count();
    let too_slow = (too_slow > 0).then(|| {
        view! {
            <p class="error" role="alert" data-testid="mark-too-slow" data-count=too_slow>
                {format!(
                    "{too_slow} call(s) too slow to tell here: this machine is too slow (or too busy) for its time to \
                     say whether the lab's 10 s limit would be kept; they count as time-outs in this total. Mark the \
                     file with `siftlab mark` on a computer for its real mark."
                )}
            </p>
        }
    });
    view! {
        <div class="mark-report" data-testid="mark-report">
            {rejection}
            <p class=if full { "verdict ok" } else { "verdict bad" }>
                <strong data-testid="mark-total" data-total=format!("{:.2}", m.total)>{format!("{:.2} / 20", m.total)}</strong>
                {if full { " — full marks: every call returned the lab's value" } else { "" }}
            </p>
            <div class="table-scroll" tabindex="0" role="region" aria-label="Marks per task">
                <table class="mark-table" data-testid="mark-table">
                    <thead><tr><th>"task"</th><th>"calls"</th><th>"correct"</th><th>"errors"</th><th>"marks"</th><th>"slowest call"</th></tr></thead>
                    <tbody>{rows}</tbody>
                </table>
            </div>
            {too_slow}
            <p class="muted small" data-testid="mark-timing" data-speed=format!("{first:.3}")
                data-slowest-speed=format!("{slowest:.3}")
                data-speeds=speeds
                data-restored=o.timing.restored
                data-shared=o.timing.shared
                data-call-limit=format!("{:.3}", o.timing.call_limit_s)>
                {format!(
                    "seed {}, {} calls per task · marked in {:.1} s (SIFT {:.1} s, Python's start {:.1} s, the calls {:.1} s){speed_text}",
                    m.seed, m.cases_per_task, o.ms / 1000.0, o.timing.sift_ms / 1000.0, o.timing.start_ms / 1000.0,
                    o.timing.calls_ms / 1000.0
                )}
            </p>
            <ol class="mark-failures">{failures}</ol>
        </div>
    }
}

#[component]
pub fn MarkMyCode() -> impl IntoView {
    let lab = expect_context::<Lab>();
    let state = expect_context::<crate::model::mark::MarkState>();
    let source = RwSignal::new(String::new());
    let name = RwSignal::new(String::new());
    let running = RwSignal::new(false);
    let status = RwSignal::new(String::new());
    let error = RwSignal::new(None::<String>);
    let outcome = RwSignal::new(None::<Outcome>);
    // The bytes exactly as picked or dropped (the ASCII check sees them all);
    // typing or pasting replaces them by the box's text.
    let bytes = StoredValue::new(None::<Vec<u8>>);
    // Whether those bytes are a picked file (an empty one is marked too: the
    // lab gives it 0, and says why).
    let picked = RwSignal::new(false);

    let take_file = move |file: web_sys::File| {
        leptos::task::spawn_local(async move {
            match read_file(&file).await {
                Ok(b) => {
                    name.set(file.name());
                    source.set(String::from_utf8_lossy(&b).into_owned());
                    bytes.set_value(Some(b));
                    picked.set(true);
                    error.set(None);
                }
                Err(e) => error.set(Some(format!("{}: {e}", file.name()))),
            }
        });
    };
    let on_pick = move |ev: web_sys::Event| {
        if let Some(f) = take_picked_file(&ev) {
            take_file(f);
        }
    };
    let on_drop = move |ev: web_sys::DragEvent| {
        if let Some(f) = dropped_file(&ev) {
            take_file(f);
        }
    };
    let mark = move |_| {
        let b = bytes.get_value().unwrap_or_else(|| source.get_untracked().into_bytes());
        let (seed, n) = (state.seed.get_untracked(), state.n.get_untracked() as usize);
        let src = lab.source.get_untracked();
        running.set(true);
        error.set(None);
        outcome.set(None);
        leptos::task::spawn_local(async move {
            let t0 = crate::platform::now_ms();
            match run(b, seed, n, src, move |s| status.set(s)).await {
                Ok((marks, timing)) => {
                    outcome.set(Some(Outcome { marks, timing, ms: crate::platform::now_ms() - t0 }));
                    status.set(String::new());
                }
                Err(e) => error.set(Some(e)),
            }
            running.set(false);
        });
    };

    view! {
        <section class="card mark-view" aria-label="Mark my code" data-testid="mark">
            <h2>"Mark my code"</h2>
            <p class="muted" data-testid="mark-intro">
                "Your "<code>"vision_tasks.py"</code>" runs here, in Python compiled to WebAssembly (Pyodide), with siftlab's "
                <code>"cv2"</code>" (SIFT and "<code>"BFMatcher().knnMatch"</code>" exactly as OpenCV 4.8) and the lab's "
                <code>"vision_tasks_base"</code>", and is marked as the lab's automarker marks it: each function on random "
                "valid calls (frame pairs of the loaded frames), 10 s a call (scaled to this machine's speed), 0.5 marks per task for no runtime error plus 4.5 × the "
                "share of exactly right values, 20 in all. Nothing leaves this page: your code runs under the page's security "
                "policy, which lets it reach no other site."
            </p>
            <div class="row wrap">
                <label class="ctl">
                    <span>"your file"</span>
                    <input type="file" accept=".py,text/x-python,text/plain" data-testid="mark-file" on:change=on_pick/>
                </label>
                <label class="ctl">
                    <span>"calls per task"</span>
                    <input type="number" min="1" max=MAX_CASES class="num" data-testid="mark-n"
                        prop:value=move || state.n.get().to_string()
                        on:change=move |ev| {
                            if let Ok(n) = event_target_value(&ev).trim().parse::<u32>() {
                                state.n.set(n.clamp(1, MAX_CASES));
                            }
                        }/>
                </label>
                <label class="ctl">
                    <span>"seed (in the link)"</span>
                    <input class="num" data-testid="mark-seed"
                        prop:value=move || state.seed.get().to_string()
                        on:change=move |ev| {
                            if let Ok(s) = event_target_value(&ev).trim().parse::<u64>() {
                                state.seed.set(s);
                            }
                        }/>
                </label>
                <button class="primary" data-testid="mark-run" on:click=mark
                    prop:disabled=move || running.get() || (source.with(String::is_empty) && !picked.get())>
                    "Mark my code"
                </button>
            </div>
            <div class="dropzone" on:dragover=move |ev: web_sys::DragEvent| ev.prevent_default() on:drop=on_drop>
                <textarea
                    rows="8"
                    class="code"
                    data-testid="mark-source"
                    aria-label="vision_tasks.py: drop the file here or paste its text"
                    placeholder="drop vision_tasks.py here, pick it above, or paste its text"
                    prop:value=move || source.get()
                    on:input=move |ev| {
                        source.set(event_target_value(&ev));
                        bytes.set_value(None);
                        picked.set(false);
                        name.set(String::new());
                    }
                ></textarea>
            </div>
            <p class="muted small">{move || (!name.get().is_empty()).then(|| format!("{} · {} bytes", name.get(), source.with(String::len)))}</p>
            <p class="muted" data-testid="mark-status" role="status">{move || status.get()}</p>
            {move || error.get().map(|e| view! { <p class="error" role="alert" data-testid="mark-error">{e}</p> })}
            {move || outcome.get().map(|o| view! { <Report o=o/> })}
        </section>
    }
}
