//! "See inside": two views that open up what `get_info` takes for granted,
//! SIFT's anatomy of a frame and the whole-frame matching of the pair.
//! Closed until asked for (they run a worker), and linkable (`see=`).

mod anatomy;
mod canvas2d;
mod whole_frame;

use crate::model::see_inside::InsideView;
use anatomy::AnatomyView;
use leptos::prelude::*;
use whole_frame::WholeFrameView;

#[component]
pub fn SeeInside() -> impl IntoView {
    let view_sig = expect_context::<crate::model::see_inside::Inside>().view;
    let tab = move |v: InsideView, label: &'static str| {
        view! {
            <button
                class="tab"
                data-testid=format!("see-{}", v.name())
                class:sel=move || view_sig.get() == Some(v)
                aria-pressed=move || (view_sig.get() == Some(v)).to_string()
                on:click=move |_| view_sig.update(|s| *s = if *s == Some(v) { None } else { Some(v) })
            >
                {label}
            </button>
        }
    };
    view! {
        <section class="card see-inside" aria-label="See inside">
            <h2>"See inside"</h2>
            <div class="tabs">
                {tab(InsideView::Anatomy, "SIFT's anatomy")}
                {tab(InsideView::Matches, "Whole-frame matching")}
            </div>
            {move || match view_sig.get() {
                Some(InsideView::Anatomy) => view! { <AnatomyView/> }.into_any(),
                Some(InsideView::Matches) => view! { <WholeFrameView/> }.into_any(),
                None => ().into_any(),
            }}
        </section>
    }
}
