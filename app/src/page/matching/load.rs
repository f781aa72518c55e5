//! Loading frames (demo, files, MyKITTI folder) and the progress / error strip.

use super::manual::ManualExamples;
use crate::model::frameset::describe_ids;
use crate::model::lab::{Lab, Source, Which};
use crate::page::file_input::{dropped_file, picked_files, take_picked_file};
use crate::platform::now_ms;
use crate::services::loading;
use crate::services::sources::frame_path;
use leptos::prelude::*;
use wasm_bindgen::JsCast;

/// One frame slot: a file picker that also accepts a dropped file.
#[component]
fn FrameSlot(which: Which, testid: &'static str) -> impl IntoView {
    let lab = expect_context::<Lab>();
    let over = RwSignal::new(false);
    let label = match which {
        Which::Prev => "Previous frame (FRAME_ID−1)",
        Which::Cur => "Current frame (FRAME_ID)",
    };
    let count_id = match which {
        Which::Prev => "keypoint-count-prev",
        Which::Cur => "keypoint-count-cur",
    };
    view! {
        <div
            class="slot"
            class:over=move || over.get()
            on:dragover=move |ev: web_sys::DragEvent| {
                ev.prevent_default();
                over.set(true);
            }
            on:dragleave=move |_| over.set(false)
            on:drop=move |ev: web_sys::DragEvent| {
                over.set(false);
                if let Some(f) = dropped_file(&ev) {
                    loading::load_file(lab, which, f);
                }
            }
        >
            <label class="slot-label">
                <span>{label}</span>
                <input
                    type="file"
                    accept="image/png,image/jpeg,.png,.jpg,.jpeg"
                    data-testid=testid
                    on:change=move |ev| {
                        if let Some(f) = take_picked_file(&ev) {
                            loading::load_file(lab, which, f);
                        }
                    }
                />
            </label>
            <p class="slot-info">
                {move || lab.frame(which).with(|f| match f {
                    Some(f) => view! {
                        <span class="fname">{f.label.clone()}</span>
                        <span class="muted">{format!(" · {}×{} · ", f.width, f.height)}</span>
                        <strong data-testid=count_id>{f.features.keypoints.len()}</strong>
                        <span class="muted">{format!(" keypoints · SIFT {:.0} ms · ", f.sift_ms)}</span>
                        // The build's multiply-add path: its first words shown, all of it on hover.
                        <span class="muted engine" title=f.engine.clone() data-testid=format!("{count_id}-engine")>
                            {f.engine.split(':').next().unwrap_or_default().to_string()}
                        </span>
                    }.into_any(),
                    None => view! {
                        <span class="muted">"no frame yet — pick or drop a PNG/JPEG"</span>
                    }.into_any(),
                })}
            </p>
        </div>
    }
}

#[component]
pub fn Loader() -> impl IntoView {
    let lab = expect_context::<Lab>();
    let frame_text = RwSignal::new(String::new());
    Effect::new(move |_| frame_text.set(lab.frame_id.get().to_string()));
    let folder_ref = NodeRef::<leptos::html::Input>::new();
    Effect::new(move |_| {
        // `webkitdirectory` has no leptos attribute helper; set it on the element.
        if let Some(el) = folder_ref.get() {
            let _ = el.set_attribute("webkitdirectory", "");
        }
    });
    let has_frames = move || !lab.source.with(|s| s.frames().is_empty());
    let go = move || match frame_text.get_untracked().trim().parse::<u32>() {
        Ok(f) => loading::load_pair(lab, f),
        Err(_) => lab
            .load_error
            .set(Some(format!("FRAME_ID {:?} is not a whole number ≥ 1", frame_text.get_untracked().trim()))),
    };
    view! {
        <section class="card loader" aria-label="Load frames">
            <h2>"1 · Frames"</h2>
            <div class="load-row">
                <button class="primary" data-testid="demo" on:click=move |_| loading::load_demo(lab, None)>
                    "Load the demo pair"
                </button>
                <label class="folder">
                    "Open a MyKITTI or KITTI folder… "
                    <input
                        type="file"
                        multiple=true
                        node_ref=folder_ref
                        data-testid="folder"
                        on:change=move |ev| {
                            let fid = frame_text.get_untracked().trim().parse().ok();
                            loading::open_folder(lab, picked_files(&ev), fid);
                        }
                    />
                </label>
                <Show when=has_frames>
                    <form
                        class="frame-id"
                        on:submit=move |ev| {
                            // Enter already fired `change` (which loads); nothing to send anywhere.
                            ev.prevent_default();
                        }
                    >
                        <label>
                            "FRAME_ID "
                            <input
                                type="number"
                                min="1"
                                data-testid="frame-id"
                                prop:value=move || frame_text.get()
                                on:change=move |ev| {
                                    frame_text.set(event_target_value(&ev));
                                    go();
                                }
                            />
                        </label>
                        <span class="muted">
                            {move || {
                                let f = lab.frame_id.get();
                                format!(
                                    "matches {} → {}",
                                    frame_path(f.saturating_sub(1)).rsplit('/').next().unwrap_or_default(),
                                    frame_path(f).rsplit('/').next().unwrap_or_default()
                                )
                            }}
                            {move || lab.source.with(|s| match s {
                                Source::Demo(ids) | Source::Folder(ids) => format!(" · frames {}", describe_ids(ids)),
                                Source::Files => String::new(),
                            })}
                        </span>
                    </form>
                </Show>
            </div>
            <SequenceChoice/>
            <div class="slots">
                <FrameSlot which=Which::Prev testid="frame-prev"/>
                <FrameSlot which=Which::Cur testid="frame-cur"/>
            </div>
            <ManualExamples/>
            <Show when=move || matches!(lab.source.get(), Source::Demo(_))>
                // KITTI's licence (CC BY-NC-SA 3.0) asks for the attribution wherever
                // the frames are shown; the README beside them has it in full.
                <p class="attribution" data-testid="attribution">
                    {move || lab.attribution.get()}
                    " "
                    <a href="demo/README.md" target="_blank" rel="noopener">"attribution and licence in full"</a>
                    " · "
                    <a href="https://creativecommons.org/licenses/by-nc-sa/3.0/" target="_blank" rel="noopener license">
                        "the licence's text"
                    </a>
                </p>
            </Show>
        </section>
    }
}

/// A picked folder's sequence choice (its KITTI sequences, in the lab's
/// layout or KITTI's), and the camera the odometry and the epipolar judge
/// use with where it comes from.
#[component]
fn SequenceChoice() -> impl IntoView {
    let lab = expect_context::<Lab>();
    let is_folder = move || matches!(lab.source.get(), Source::Folder(_));
    let shown = move || lab.sequence.with(|s| s.seq.clone());
    view! {
        <Show when=move || !matches!(lab.source.get(), Source::Files)>
            <p class="sequence muted">
                <Show when=is_folder>
                    <label>
                        "Sequence "
                        <select
                            data-testid="folder-sequence"
                            // The shown sequence, also after a choice that could not be opened.
                            prop:value=move || {
                                let shown = shown();
                                lab.folder_sequences
                                    .with(|v| v.iter().position(|(k, _)| *k == shown))
                                    .map_or(String::new(), |i| i.to_string())
                            }
                            on:change=move |ev| {
                                let i: usize = event_target_value(&ev).parse().unwrap_or(0);
                                if let Some((key, _)) = lab.folder_sequences.with_untracked(|v| v.get(i).cloned()) {
                                    let fid = Some(lab.frame_id.get_untracked());
                                    loading::use_sequence(lab, key, fid);
                                }
                            }
                        >
                            {move || {
                                lab.folder_sequences
                                    .get()
                                    .into_iter()
                                    .enumerate()
                                    .map(|(i, (key, label))| {
                                        let selected = key == shown();
                                        view! { <option value=i.to_string() selected=selected>{label}</option> }
                                    })
                                    .collect_view()
                            }}
                        </select>
                    </label>
                    " "
                </Show>
                <span data-testid="camera">{move || lab.sequence.with(|s| s.camera_line())}</span>
            </p>
            {move || {
                lab.sequence
                    .with(|s| s.warning())
                    .map(|w| view! { <p class="warning" data-testid="camera-warning" role="note">{w}</p> })
            }}
        </Show>
    }
}

/// Progress of running jobs (`busy` while any) and the inline error.
#[component]
pub fn Status() -> impl IntoView {
    let lab = expect_context::<Lab>();
    // Ticks every 100 ms while something runs, for the elapsed-time readout.
    let tick = RwSignal::new(0u32);
    Effect::new(move |prev: Option<Option<i32>>| {
        let busy = lab.busy();
        let window = web_sys::window();
        let handle = prev.flatten();
        match (busy, handle, window) {
            (true, None, Some(w)) => {
                let cb = wasm_bindgen::closure::Closure::<dyn FnMut()>::new(move || tick.update(|t| *t += 1));
                let h = w.set_interval_with_callback_and_timeout_and_arguments_0(cb.as_ref().unchecked_ref(), 100).ok();
                cb.forget();
                h
            }
            (false, Some(h), Some(w)) => {
                w.clear_interval_with_handle(h);
                None
            }
            (_, h, _) => h,
        }
    });
    let analysis_error = move || lab.analysis.with(|a| a.as_ref().and_then(|r| r.as_ref().err().cloned()));
    view! {
        <Show when=move || lab.busy()>
            <div class="busy" data-testid="busy" role="status" aria-live="polite">
                {move || {
                    tick.get();
                    let now = now_ms();
                    // Once one frame has been analysed, its SIFT time predicts the next
                    // (same size, same machine): show a filling bar instead of a sweep.
                    let expected = [Which::Prev, Which::Cur]
                        .iter()
                        .filter_map(|&w| lab.frame(w).with_untracked(|f| f.as_ref().map(|f| f.sift_ms)))
                        .fold(0.0f64, f64::max);
                    lab.jobs.get().into_iter().map(|j| {
                        let sifting = j.stage.starts_with("running SIFT");
                        let fraction = (sifting && expected > 0.0).then(|| ((now - j.started_ms) / expected).min(0.95));
                        view! {
                        <div class="job">
                            {match fraction {
                                Some(f) => view! {
                                    <div class="bar"><div class="bar-known" style:width=format!("{:.0}%", f * 100.0)></div></div>
                                }.into_any(),
                                None => view! { <div class="bar"><div class="bar-fill"></div></div> }.into_any(),
                            }}
                            <span class="job-what">{j.what}</span>
                            <span class="job-stage">{format!("{} · {:.1} s", j.stage, (now - j.started_ms) / 1000.0)}</span>
                        </div>
                    }}).collect_view()
                }}
            </div>
        </Show>
        <Show when=move || lab.load_error.with(|e| e.is_some()) || analysis_error().is_some()>
            <div class="error" data-testid="error" role="alert">
                {move || lab.load_error.get().map(|e| view! {
                    <p>
                        <strong>"Could not load: "</strong>{e}" "
                        <button class="link" on:click=move |_| lab.load_error.set(None)>"dismiss"</button>
                    </p>
                })}
                {move || analysis_error().map(|e| view! { <p><strong>"Cannot match: "</strong>{e}</p> })}
            </div>
        </Show>
    }
}
