//! A figure's legend: each style's sample (dash and marker) and its label,
//! as the figures draw them (colour is never the only cue).

use leptos::prelude::*;
use siftlab_core::render::palette::{hex, Style};

/// One legend entry: the style, whether its sample is a line (else the
/// marker alone, stroked with the style's dash), whether the figure draws its
/// markers as outlines (over photographs) or filled (on white), and the label.
#[derive(Clone, Copy)]
pub struct Sw {
    pub style: Style,
    pub line: bool,
    pub outline: bool,
    pub label: &'static str,
}

/// A sample of a style as the figure draws it: its dash and its marker.
/// Hidden from screen readers: the label beside it says the same in words.
pub fn swatch(sw: Sw, dark: bool) -> impl IntoView {
    let st = sw.style;
    let (fill, stroke, width) = crate::model::plot::marker_paint(&st, sw.outline);
    let line = sw.line.then(|| {
        view! {
            <line x1="1" x2="31" y1="7" y2="7" stroke=hex(st.color) stroke-width="2" stroke-dasharray=st.dasharray()/>
        }
    });
    let marker_dash = if sw.line { None } else { st.dasharray() };
    view! {
        <svg class="sw-svg" class:dark=dark viewBox="0 0 32 14" width="32" height="14" aria-hidden="true" focusable="false">
            {line}
            <path d=st.marker.svg_path(&[16.0, 7.0], 4.5) fill=fill stroke=stroke stroke-width=width stroke-dasharray=marker_dash/>
        </svg>
    }
}

/// A figure's legend: each entry's sample (dash and marker) and label, then
/// a closing remark. `dark` puts the samples on the dark ground of the
/// photographs they are drawn over.
#[component]
pub fn Legend(swatches: &'static [Sw], tail: &'static str, #[prop(optional)] dark: bool) -> impl IntoView {
    let swatches =
        swatches.iter().map(|&sw| view! { <span class="sw-item">{swatch(sw, dark)}{sw.label}</span> }).collect_view();
    view! { <p class="muted legend">{swatches}" "{tail}</p> }
}
