//! Self-check ("Check my answer") and seeded exercises with a score.

use crate::model::exercise::{question, Question};
use crate::model::lab::Lab;
use crate::model::parse::parse_strategy;
use crate::model::selfcheck::{diagnose, Diagnosis};
use crate::services::loading;
use leptos::prelude::*;
use siftlab_core::matching::{explain, mistaken_answers, Strategy};

#[component]
fn DiagnosisView(d: Diagnosis) -> impl IntoView {
    let fields = d
        .fields
        .iter()
        .map(|f| {
            view! {
                <li class=if f.ok { "ok" } else { "bad" }>
                    <span class="mark">{if f.ok { "✓" } else { "✗" }}</span>
                    <strong>{f.field}</strong>": "{f.note.clone()}
                </li>
            }
        })
        .collect_view();
    let likely = (!d.likely.is_empty()).then(|| {
        let items = d.likely.iter().map(|l| view! { <li>{l.clone()}</li> }).collect_view();
        view! {
            <p class="likely-title">"Likely mistake:"</p>
            <ul class="likely">{items}</ul>
        }
    });
    view! {
        <div class="diagnosis" data-testid="check-result">
            <p class=if d.correct { "verdict ok" } else { "verdict bad" }>
                {if d.correct { "Correct — this is exactly what the lab prints." } else { "Not the lab's answer." }}
            </p>
            <ul class="fields">{fields}</ul>
            {likely}
        </div>
    }
}

/// The box a student pastes a `ret value` into.
#[component]
fn AnswerBox(
    answer: RwSignal<String>,
    rows: &'static str,
    testid: &'static str,
    label: &'static str,
    #[prop(optional)] placeholder: Option<&'static str>,
) -> impl IntoView {
    view! {
        <textarea
            rows=rows
            data-testid=testid
            aria-label=label
            placeholder=placeholder
            prop:value=move || answer.get()
            on:input=move |ev| answer.set(event_target_value(&ev))
        ></textarea>
    }
}

/// The last check's outcome: the diagnosis, or why there is none.
#[component]
fn Outcome(#[prop(into)] result: Signal<Option<Result<Diagnosis, String>>>) -> impl IntoView {
    move || {
        result.get().map(|r| match r {
            Ok(d) => view! { <DiagnosisView d=d/> }.into_any(),
            Err(e) => view! { <p class="error-inline">{e}</p> }.into_any(),
        })
    }
}

/// Diagnoses an answer for the given settings on the loaded frames.
fn grade(lab: Lab, s: &Strategy, feature: usize, answer: &str) -> Result<Diagnosis, String> {
    let prev = lab.prev.get_untracked().ok_or("load the frames first")?;
    let cur = lab.cur.get_untracked().ok_or("load the frames first")?;
    let e = explain(s, &prev.features, &cur.features, feature).map_err(|e| e.to_string())?;
    let mistakes = mistaken_answers(s, &prev.features, &cur.features, feature).map_err(|e| e.to_string())?;
    Ok(diagnose(answer, &e.info, &mistakes, Some((e.query.x, e.query.y))))
}

/// What a `get_info` answer is checked against.
type Asked = (siftlab_core::matching::Strategy, usize, String);

fn asked(a: &crate::model::lab::Analysis) -> Asked {
    (a.strategy, a.feature, a.tuple.clone())
}

#[component]
pub fn SelfCheck() -> impl IntoView {
    let lab = expect_context::<Lab>();
    let answer = RwSignal::new(String::new());
    // The verdict and the question it answers: the strategy, the feature and
    // the expected tuple (which the frames decide). It is shown only while
    // that is still the question, so a new setting or new frames hide it, and
    // an analysis recomputed with the same inputs (the demo's first frames
    // arriving, a worker finishing late) leaves it in place.
    let checked = RwSignal::new(None::<(Option<Asked>, Result<Diagnosis, String>)>);
    let asked_now = move || lab.analysis.with(|a| a.as_ref().and_then(|a| a.as_ref().ok()).map(asked));
    let result =
        Signal::derive(move || checked.with(|c| c.as_ref().filter(|(q, _)| *q == asked_now()).map(|(_, r)| r.clone())));
    // Pressed while frames are still computed: the answer waits for them and
    // is checked as soon as they are in, instead of being judged against the
    // old pair (or dropped when the new one arrives).
    let pending = RwSignal::new(false);
    let check = move || {
        if lab.busy() {
            checked.set(None);
            pending.set(true);
            return;
        }
        let r = match lab.analysis.get_untracked() {
            Some(Ok(a)) => grade(lab, &a.strategy, a.feature, &answer.get_untracked()),
            Some(Err(e)) => Err(e),
            None => Err("load the two frames first".into()),
        };
        checked.set(Some((asked_now(), r)));
    };
    Effect::new(move |_| {
        if pending.get() && !lab.busy() && lab.analysis.with(Option::is_some) {
            pending.set(false);
            untrack(check);
        }
    });
    view! {
        <section class="card selfcheck" aria-label="Check my answer">
            <h2>"6 · Check my answer"</h2>
            <p class="muted">
                "Run your own "<code>"get_info"</code>" with the settings above and paste what it printed after "
                <code>"ret value:"</code>"."
            </p>
            <form on:submit=move |ev| {
                ev.prevent_default();
                check();
            }>
                <AnswerBox
                    answer=answer
                    rows="3"
                    testid="answer"
                    label="your ret value"
                    placeholder="((523, 181), [(517, 183)], [61.400001525878906])"
                />
                <button type="submit" class="primary" data-testid="check">"Check my answer"</button>
            </form>
            <Show when=move || pending.get()>
                <p class="muted" data-testid="check-pending" role="status">
                    "The frames are still being computed: your answer will be checked as soon as they are ready."
                </p>
            </Show>
            <Outcome result=result/>
        </section>
    }
}

#[component]
pub fn Exercises() -> impl IntoView {
    let lab = expect_context::<Lab>();
    let ex = expect_context::<crate::model::exercise::ExerciseState>();
    let answer = RwSignal::new(String::new());
    let result = RwSignal::new(None::<Result<Diagnosis, String>>);
    // First submission per question counts: (question, correct).
    let marks = RwSignal::new(Vec::<(u32, bool)>::new());
    let current = move || -> Option<Question> {
        let seed = ex.seed.get()?;
        lab.source.with(|s| question(seed, ex.q.get(), s.frames()))
    };
    // Bring the question's frames in when the question changes.
    Effect::new(move |_| {
        if let Some(q) = current() {
            if lab.frame_id.get_untracked() != q.frame_id || lab.prev.get_untracked().is_none() {
                loading::load_pair(lab, q.frame_id);
            }
        }
    });
    let ready = move || {
        current().is_some_and(|q| lab.frame_id.get() == q.frame_id && lab.prev.with(|p| p.is_some()) && !lab.busy())
    };
    let count = move || lab.prev.with(|p| p.as_ref().map(|p| p.features.keypoints.len()).unwrap_or(0));
    let start = move |_| {
        let seed = (js_sys::Math::random() * 1e9) as u64 + 1;
        ex.seed.set(Some(seed));
        ex.q.set(1);
        marks.set(vec![]);
        result.set(None);
        answer.set(String::new());
    };
    let next = move |_| {
        ex.q.update(|q| *q += 1);
        result.set(None);
        answer.set(String::new());
    };
    let submit = move || {
        let Some(q) = current() else { return };
        let r = parse_strategy(q.algo, &q.threshold)
            .and_then(|s| grade(lab, &s, q.feature(count()), &answer.get_untracked()));
        if let Ok(d) = &r {
            let qn = ex.q.get_untracked();
            marks.update(|m| {
                if !m.iter().any(|(n, _)| *n == qn) {
                    m.push((qn, d.correct));
                }
            });
        }
        result.set(Some(r));
    };
    let score = move || {
        marks.with(|m| {
            let ok = m.iter().filter(|(_, c)| *c).count();
            format!("Score: {ok} / {}", m.len())
        })
    };
    view! {
        <section class="card exercises" aria-label="Exercises">
            <h2>"7 · Exercises"</h2>
            {move || match ex.seed.get() {
                None => view! {
                    <p class="muted">"Random automarker-style questions on the loaded frames. The link in the address bar replays the same questions."</p>
                    <button class="primary" data-testid="exercise-start" on:click=start>"Start exercises"</button>
                }.into_any(),
                Some(seed) => view! {
                    <p class="muted">
                        {move || format!("Exercise {seed} · question {} · ", ex.q.get())}
                        <strong data-testid="score">{score}</strong>
                        " · "<button class="link" on:click=start>"new exercise"</button>
                    </p>
                    {move || match current() {
                        None => view! { <p class="error-inline">"Exercises need the demo or a MyKITTI folder (frame ids)."</p> }.into_any(),
                        Some(q) => view! {
                            <p class="question" data-testid="question">
                                "What does your code print as "<code>"ret value:"</code>" for "
                                <code>{move || if ready() { q.command(count()) } else { format!("get_info -a {} … (loading frames {})", q.algo.name(), q.frame_id) }}</code>"?"
                            </p>
                            <form on:submit=move |ev| {
                                ev.prevent_default();
                                submit();
                            }>
                                <AnswerBox answer=answer rows="2" testid="exercise-answer" label="your answer"/>
                                <div class="row">
                                    <button type="submit" class="primary" prop:disabled=move || !ready()>"Submit"</button>
                                    <button type="button" on:click=next data-testid="exercise-next">"Next question"</button>
                                </div>
                            </form>
                        }.into_any(),
                    }}
                    <Outcome result=result/>
                }.into_any(),
            }}
        </section>
    }
}
