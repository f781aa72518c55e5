//! A SIFT descriptor drawn as OpenCV lays it out, with its 128 numbers: one
//! widget for the explorer's explanation and SIFT's anatomy.

use crate::model::plot::{descriptor_cells, descriptor_rows};
use leptos::prelude::*;

/// A SIFT descriptor as OpenCV lays it out: 4×4 spatial cells (row-major,
/// rows = y), each an 8-bin orientation histogram; index `(row*4 + col)*8 + bin`.
/// Each bin is drawn as a ray at bin·45° (counter-clockwise, in the keypoint's
/// rotated frame), its length proportional to the value.
#[component]
pub fn DescriptorGrid(
    desc: [u8; 128],
    #[prop(into)] title: String,
    #[prop(optional)] testid: &'static str,
) -> impl IntoView {
    const CELL: f64 = 44.0;
    let cells = descriptor_cells(&desc, CELL)
        .into_iter()
        .enumerate()
        .map(|(c, cell)| {
            let (cx, cy) = (cell.x0 + CELL / 2.0, cell.y0 + CELL / 2.0);
            let (row, col) = (cell.row, cell.col);
            let rays = cell
                .rays
                .iter()
                .enumerate()
                .map(|(b, &(x2, y2))| {
                    view! {
                        <line x1=cx y1=cy x2=x2 y2=y2 class="ray">
                            <title>{format!("cell ({row}, {col}), bin {b} ({}°): {}", b * 45, desc[c * 8 + b])}</title>
                        </line>
                    }
                })
                .collect_view();
            view! {
                <rect x=cell.x0 y=cell.y0 width=CELL height=CELL class="cell" fill-opacity=cell.shade/>
                {rays}
            }
        })
        .collect_view();
    let rows = descriptor_rows(&desc);
    let nums_label = format!("{title}: the 128 numbers");
    view! {
        <figure class="descriptor" data-testid=testid>
            <svg viewBox=format!("0 0 {} {}", CELL * 4.0, CELL * 4.0) class="desc-svg" role="img" aria-label=title.clone()>
                {cells}
            </svg>
            <figcaption>{title}</figcaption>
            <details>
                <summary>"the 128 numbers"</summary>
                <pre class="desc-nums" tabindex="0" role="region" aria-label=nums_label>{rows}</pre>
            </details>
        </figure>
    }
}
