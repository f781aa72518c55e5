//! "Class results": a class's summary.json (or its output folder) dropped
//! or picked, shown as `siftlab mark --out`'s summary.html shows it: the
//! students per status, the marks' histogram, each task's share of calls
//! correct, the mistakes ranked with their examples and the cases most
//! students failed; each example and case links to the explorer on it (a
//! new tab: the class stays here). Model logic: `model::class_results`.

use crate::model::class_results::{app_link, counts, list, read_summary, text, MAX_BYTES};
use crate::page::file_input::{dropped_file, picked_files};
use crate::services::sources::{read_file, relative_path};
use leptos::prelude::*;
use siftlab_core::render::palette::{hex, BLUE, REST};
use siftlab_mark::Json;

/// A bar chart of `counts` (Okabe–Ito blue, scaled to its box).
fn bars(counts: Vec<i64>, labels: Vec<String>, title: String, testid: &'static str) -> impl IntoView {
    let n = counts.len().max(1) as f64;
    let (w, h) = (36.0 * n + 40.0, 170.0);
    let max = counts.iter().copied().max().unwrap_or(0).max(1) as f64;
    let bw = (w - 40.0) / n;
    let bars = counts
        .into_iter()
        .zip(labels)
        .enumerate()
        .map(|(i, (c, l))| {
            let bh = (h - 50.0) * c as f64 / max;
            let x = 34.0 + i as f64 * bw;
            let cx = x + (bw - 4.0) / 2.0;
            view! {
                <rect x=x y=h - 30.0 - bh width=bw - 4.0 height=bh fill=hex(BLUE)><title>{format!("{l}: {c}")}</title></rect>
                {(c > 0).then(|| view! { <text x=cx y=h - 34.0 - bh text-anchor="middle" class="n">{c}</text> })}
                <text x=cx y=h - 16.0 text-anchor="middle" class="l">{l}</text>
            }
        })
        .collect_view();
    let label = title.clone();
    view! {
        <svg viewBox=format!("0 0 {w} {h}") class="class-hist" role="img" aria-label=label data-testid=testid>
            <title>{title}</title>
            <line x1="30" y1=h - 30.0 x2=w - 6.0 y2=h - 30.0 stroke=hex(REST)/>
            {bars}
        </svg>
    }
}

/// A case's text, linked to the explorer when the summary gives a link.
fn case_link(link: Option<&Json>, words: String) -> AnyView {
    match app_link(link) {
        Some(q) => {
            view! { <a href=q target="_blank" rel="noopener" data-testid="class-case-link">{words}</a> }.into_any()
        }
        None => view! { <span>{words}</span> }.into_any(),
    }
}

fn summary_view(s: Json) -> impl IntoView {
    let g = |k: &str| s.get(k);
    let facts = format!(
        "{} students · seed {} · {} calls per task · siftlab {}",
        text(g("students")),
        text(g("seed")),
        text(g("n")),
        text(g("siftlab"))
    );
    let status = g("status");
    let statuses = [
        ("ok", "marked"),
        ("zero", "scored 0 without a call"),
        ("refused", "refused"),
        ("failed", "could not be marked"),
    ]
    .into_iter()
    .map(|(k, w)| {
        let n = text(status.and_then(|x| x.get(k)));
        let shown = n.clone();
        view! { <tr data-testid="class-status" data-status=k data-n=n><td>{w}</td><td>{shown}</td></tr> }
    })
    .collect_view();
    let totals = g("totals");
    let total_line = format!(
        "{} marked · mean {} · median {}",
        text(totals.and_then(|t| t.get("marked"))),
        text(totals.and_then(|t| t.get("mean"))),
        text(totals.and_then(|t| t.get("median")))
    );
    let labels: Vec<String> = (0..20).map(|i| if i == 19 { "19–20".into() } else { i.to_string() }).collect();
    let hist = bars(
        counts(totals.and_then(|t| t.get("histogram"))),
        labels,
        "students per mark out of 20 (bins of 1)".into(),
        "class-totals",
    );
    let tasks = list(g("tasks"))
        .iter()
        .map(|t| {
            let share = t.get("share_correct").and_then(Json::as_f64).unwrap_or(0.0);
            view! {
                <tr data-testid="class-task" data-task=text(t.get("task")) data-calls=text(t.get("calls")) data-correct=text(t.get("correct"))>
                    <td><code>{text(t.get("task"))}</code></td>
                    <td>{format!("{:.1} % ({} of {})", share * 100.0, text(t.get("correct")), text(t.get("calls")))}</td>
                    <td>{text(t.get("mean_marks"))}</td>
                </tr>
            }
        })
        .collect_view();
    let mistakes = list(g("mistakes"))
        .iter()
        .map(|m| {
            let examples = list(m.get("examples"))
                .iter()
                .map(|e| {
                    let who = text(e.get("student"));
                    let case = text(e.get("case"));
                    view! { <li>{who}": "{case_link(e.get("link"), case)}</li> }
                })
                .collect_view();
            let tasks = list(m.get("tasks")).iter().map(|t| text(Some(t))).collect::<Vec<_>>().join(", ");
            view! {
                <tr data-testid="class-mistake" data-code=text(m.get("code")) data-students=text(m.get("students")) data-cases=text(m.get("cases"))>
                    <td><code>{text(m.get("code"))}</code>" ("{tasks}")"<br/>{text(m.get("explanation"))}</td>
                    <td>{text(m.get("students"))}</td>
                    <td>{text(m.get("cases"))}</td>
                    <td><ul>{examples}</ul></td>
                </tr>
            }
        })
        .collect_view();
    let hardest = list(g("hardest_cases"))
        .iter()
        .map(|c| {
            view! {
                <tr data-testid="class-hard">
                    <td>{case_link(c.get("link"), text(c.get("case")))}</td>
                    <td>{format!("{} of {}", text(c.get("failed")), text(c.get("of")))}</td>
                </tr>
            }
        })
        .collect_view();
    view! {
        <div data-testid="class-summary">
            <p class="muted" data-testid="class-facts">{facts}</p>
            <h3>"Students"</h3>
            <table class="class-table"><thead><tr><th scope="col">"status"</th><th scope="col">"students"</th></tr></thead><tbody>{statuses}</tbody></table>
            <h3>"Marks out of 20"</h3>
            <p>{total_line}</p>
            {hist}
            <h3>"Tasks"</h3>
            <table class="class-table"><thead><tr><th scope="col">"task"</th><th scope="col">"calls correct"</th><th scope="col">"mean mark / 5"</th></tr></thead><tbody>{tasks}</tbody></table>
            <h3>"Mistakes, most students first"</h3>
            <div class="class-scroll" tabindex="0" role="region" aria-label="the mistakes, most students first">
                <table class="class-table"><thead><tr><th scope="col">"mistake"</th><th scope="col">"students"</th><th scope="col">"cases"</th><th scope="col">"examples (open in the explorer)"</th></tr></thead><tbody>{mistakes}</tbody></table>
            </div>
            <h3>"Cases most students failed"</h3>
            <table class="class-table"><thead><tr><th scope="col">"case"</th><th scope="col">"failed"</th></tr></thead><tbody>{hardest}</tbody></table>
        </div>
    }
}

#[component]
pub fn ClassResults() -> impl IntoView {
    let summary = RwSignal::new(None::<Json>);
    let error = RwSignal::new(None::<String>);
    let take = move |file: web_sys::File| {
        leptos::task::spawn_local(async move {
            if file.size() > MAX_BYTES as f64 {
                error.set(Some(format!("{}: more than a class summary's {MAX_BYTES} bytes", file.name())));
                return;
            }
            match read_file(&file).await.and_then(|b| read_summary(&b)) {
                Ok(s) => {
                    summary.set(Some(s));
                    error.set(None);
                }
                Err(e) => error.set(Some(format!("{}: {e}", file.name()))),
            }
        });
    };
    // A folder picked: its summary.json at the top (DIR/summary.json).
    let pick = move |ev: web_sys::Event| {
        let mut all = picked_files(&ev);
        // "summary.json" alone, or "DIR/summary.json" of a picked folder.
        let top = |f: &web_sys::File| relative_path(f).split('/').count() <= 2;
        match all.iter().position(|f| f.name() == "summary.json" && top(f)) {
            Some(i) => take(all.swap_remove(i)),
            None if all.len() == 1 => take(all.swap_remove(0)),
            None if all.is_empty() => {}
            None => error.set(Some(
                "no summary.json at the top of that folder: pick the folder `siftlab mark --out DIR` wrote".into(),
            )),
        }
    };
    let on_drop = move |ev: web_sys::DragEvent| {
        if let Some(f) = dropped_file(&ev) {
            take(f);
        }
    };
    view! {
        <section class="card class-view" aria-label="Class results" data-testid="class">
            <h2>"Class results"</h2>
            <p class="muted">
                "For the lecturer: the summary of a class marked with "<code>"siftlab mark SUBMISSIONS --out DIR"</code>
                " (its "<code>"DIR/summary.json"</code>"): how the marks are spread, which mistakes were common and in how many "
                "students, and the cases most students failed, each linked to the explorer on it. It is read here; nothing leaves this page."
            </p>
            <div class="row wrap dropzone" on:dragover=move |ev: web_sys::DragEvent| ev.prevent_default() on:drop=on_drop>
                <label class="ctl">
                    <span>"summary.json"</span>
                    <input type="file" accept=".json,application/json" data-testid="class-file" on:change=pick/>
                </label>
                <label class="ctl">
                    <span>"or the class's folder"</span>
                    <input type="file" prop:webkitdirectory=true data-testid="class-folder" on:change=pick/>
                </label>
            </div>
            {move || error.get().map(|e| view! { <p class="error" role="alert" data-testid="class-error">{e}</p> })}
            {move || summary.get().map(summary_view)}
        </section>
    }
}
