//! SIFT's anatomy of a loaded frame: the keypoint funnel with the points of
//! each stage drawn over the frame, the scale space (Gaussian and DoG levels
//! per octave, click to enlarge, value under the cursor), and for the
//! selected keypoint its place in the pyramid, its orientation histogram and
//! its descriptor. Computed in a worker by the core's own pipeline.

use super::canvas2d::{context, gray_rgba, put_rgba};
use crate::model::frame::Frame;
use crate::model::lab::{nearest_keypoint, Lab, Which};
use crate::model::plot::marker_paint;
use crate::model::see_inside::anatomy::{hist_bars, keypoint_place, level_rgba, level_value};
use crate::model::see_inside::Inside;
use crate::page::descriptor::DescriptorGrid;
use crate::page::legend::{swatch, Sw};
use crate::protocol::inside::{AnatomyData, LevelThumb};
use crate::services::inside;
use leptos::prelude::*;
use siftlab_core::render::palette::{Style, DROPS, STAGE_POINTS};
use std::sync::Arc;
use wasm_bindgen::JsCast;

/// What the funnel's stages are called on the page.
fn stage_label(name: &str) -> &'static str {
    match name {
        "extrema" => "scan extrema (26 neighbours, above the pre-threshold)",
        "refined" => "refined (sub-pixel, contrast and edge tests)",
        "oriented" => "oriented (one keypoint per histogram peak ≥ 80 %)",
        "deduplicated" => "duplicates removed",
        _ => "kept: the best 1500 by response",
    }
}

fn drop_label(name: &str) -> &'static str {
    match name {
        "no_convergence" => "no convergence in 5 steps",
        "left_border" => "left the image border or the layers",
        "low_contrast" => "low contrast",
        _ => "edge-like",
    }
}

/// Points over the frame: outlines of the style's marker, one path per set.
fn points_path(xy: &[f32], st: Style) -> impl IntoView {
    let (fill, stroke, width) = marker_paint(&st, true);
    view! { <path d=st.marker.svg_path(xy, 2.5) fill=fill stroke=stroke stroke-width=width class="anat-pts"/> }
}

/// A funnel entry's sample: the marker its points wear over the frame.
fn marker_sample(st: Style) -> impl IntoView {
    swatch(Sw { style: st, line: false, outline: true, label: "" }, true)
}

#[derive(Clone)]
struct Shown(Arc<AnatomyData>, Frame);

impl PartialEq for Shown {
    fn eq(&self, o: &Self) -> bool {
        Arc::ptr_eq(&self.0, &o.0)
    }
}

#[component]
pub fn AnatomyView() -> impl IntoView {
    let lab = expect_context::<Lab>();
    let inside = expect_context::<Inside>();
    let which = RwSignal::new(Which::Prev);
    let data = RwSignal::new(None::<Shown>);
    let status = RwSignal::new(String::new());
    let error = RwSignal::new(None::<String>);
    let stage = RwSignal::new(4usize);
    let enlarged = RwSignal::new(None::<usize>);
    let hover = RwSignal::new(String::new());
    let canvas_ref = NodeRef::<leptos::html::Canvas>::new();

    // Runs when the view opens and whenever the chosen frame changes.
    Effect::new(move |_| {
        let Some(frame) = lab.frame(which.get()).get() else { return };
        data.set(None);
        error.set(None);
        status.set("starting the anatomy worker".into());
        let t0 = crate::platform::now_ms();
        let f2 = frame.clone();
        let bytes = frame.bytes.as_ref().clone();
        let sent = inside::anatomy(
            bytes,
            frame.lanes as u32,
            move |stage| status.set(stage),
            move |r| match r {
                Ok(d) => {
                    status.set(format!(
                    "anatomy in {:.0} ms in the worker (plain SIFT of this frame: {:.0} ms; {:.0} ms with the transfer)",
                    d.ms,
                    f2.sift_ms,
                    crate::platform::now_ms() - t0
                ));
                    data.set(Some(Shown(Arc::new(*d), f2.clone())));
                }
                Err(message) => error.set(Some(message)),
            },
        );
        if let Err(e) = sent {
            error.set(Some(e));
        }
    });

    Effect::new(move |_| {
        let Some(Shown(_, f)) = data.get() else { return };
        if let Some(canvas) = canvas_ref.get() {
            if let Some(ctx) = context(&canvas, f.width as u32, f.height as u32) {
                put_rgba(&ctx, &gray_rgba(&f.gray), f.width as u32, f.height as u32, 0.0, 0.0);
            }
        }
    });

    let funnel = move || {
        let Shown(d, _) = data.get()?;
        let items = d
            .stages
            .iter()
            .enumerate()
            .map(|(i, (name, count))| {
                let drops = (name == "refined").then(|| {
                    d.drops
                        .iter()
                        .enumerate()
                        .map(|(j, (n, c))| {
                            view! {
                                <li data-drop=n.clone() data-count=*c>
                                    {marker_sample(DROPS[j % 4])}
                                    {format!(" − {c} {}", drop_label(n))}
                                </li>
                            }
                        })
                        .collect_view()
                });
                let cut = (name == "kept").then(|| d.cutoff.map(|c| format!(" (response ≥ {c})"))).flatten();
                view! {
                    <li data-stage=name.clone() data-count=*count class:sel=move || stage.get() == i>
                        <button on:click=move |_| stage.set(i)>
                            <strong>{count.to_string()}</strong>" "{stage_label(name)}{cut}
                        </button>
                        <ul class="drops">{drops}</ul>
                    </li>
                }
            })
            .collect_view();
        Some(view! {
            <p class="muted">{format!("{} octaves × {} Gaussian levels", d.octaves, d.levels_per_octave)}</p>
            <ol class="funnel" data-testid="funnel">{items}</ol>
        })
    };

    let overlay = move || {
        let Shown(d, f) = data.get()?;
        let i = stage.get();
        let pts = d.points.get(i)?;
        let dropped = (i == 1).then(|| {
            (0..4)
                .map(|r| {
                    let xy: Vec<f32> = d
                        .rejected
                        .chunks_exact(2)
                        .zip(&d.rejected_why)
                        .filter(|(_, &w)| w as usize == r)
                        .flat_map(|(p, _)| [p[0], p[1]])
                        .collect();
                    points_path(&xy, DROPS[r])
                })
                .collect_view()
        });
        let sel = inside.kp.get().and_then(|k| f.features.keypoints.get(k).copied()).map(|k| {
            view! { <circle cx=k.x cy=k.y r=(k.size / 2.0).max(3.0) class="kp-sel"/> }
        });
        Some(view! {
            {dropped}
            {points_path(pts, STAGE_POINTS)}
            {sel}
        })
    };
    let view_box = move || data.with(|d| d.as_ref().map(|Shown(_, f)| format!("0 0 {} {}", f.width, f.height)));
    let select_at = move |ev: web_sys::MouseEvent| {
        let Some(Shown(_, f)) = data.get_untracked() else { return };
        let Some(el) = ev.current_target().and_then(|t| t.dyn_into::<web_sys::Element>().ok()) else { return };
        let r = el.get_bounding_client_rect();
        let x = (ev.client_x() as f64 - r.left()) / r.width() * f.width as f64;
        let y = (ev.client_y() as f64 - r.top()) / r.height() * f.height as f64;
        inside.kp.set(nearest_keypoint(&f.features.keypoints, x, y));
    };

    view! {
        <div class="anatomy" data-testid="anatomy">
            <div class="row">
                <label>
                    "Frame: "
                    <select
                        data-testid="anatomy-frame"
                        on:change=move |ev| which.set(if event_target_value(&ev) == "cur" { Which::Cur } else { Which::Prev })
                    >
                        <option value="prev">"previous (the query frame)"</option>
                        <option value="cur">"current"</option>
                    </select>
                </label>
                <span class="muted" data-testid="anatomy-status">{move || status.get()}</span>
            </div>
            {move || error.get().map(|e| view! { <p class="error" role="alert">{e}</p> })}
            {funnel}
            <p class="muted legend">
                "Click a stage to draw its points ("{marker_sample(STAGE_POINTS)}"); at “refined” the dropped candidates "
                "are drawn too, one marker per reason as in the list. Click the frame to pick a kept keypoint."
            </p>
            <div class="stage">
                <canvas node_ref=canvas_ref data-testid="anatomy-canvas"></canvas>
                <svg class="overlay" viewBox=view_box preserveAspectRatio="none" on:click=select_at>
                    {overlay}
                </svg>
            </div>
            <KeypointDetail data=data/>
            <h3>"Scale space"</h3>
            <p class="muted">
                "Per octave: the Gaussian levels (blurred ever more), then their differences (DoG: grey = 0, "
                "light = positive, dark = negative). Click a level to enlarge it; hover for the value. "
                <span data-testid="level-value">{move || hover.get()}</span>
            </p>
            <Pyramid data=data enlarged=enlarged hover=hover/>
        </div>
    }
}

#[component]
fn Pyramid(data: RwSignal<Option<Shown>>, enlarged: RwSignal<Option<usize>>, hover: RwSignal<String>) -> impl IntoView {
    move || {
        let Shown(d, _) = data.get()?;
        let rows = (0..d.octaves)
            .flat_map(|o| [(o, false), (o, true)])
            .map(|(o, dog)| {
                let cells = d
                    .levels
                    .iter()
                    .enumerate()
                    .filter(|(_, l)| l.octave == o && l.dog == dog)
                    .map(|(i, l)| view! { <Level level=l.clone() index=i enlarged=enlarged hover=hover/> })
                    .collect_view();
                let label = format!("octave {} {}", o as i32 - 1, if dog { "DoG" } else { "Gaussian" });
                view! { <div class="octave"><span class="muted">{label}</span>{cells}</div> }
            })
            .collect_view();
        Some(view! { <div class="pyramid" data-testid="pyramid">{rows}</div> })
    }
}

#[component]
fn Level(level: LevelThumb, index: usize, enlarged: RwSignal<Option<usize>>, hover: RwSignal<String>) -> impl IntoView {
    let canvas_ref = NodeRef::<leptos::html::Canvas>::new();
    let l = level.clone();
    Effect::new(move |_| {
        if let Some(canvas) = canvas_ref.get() {
            if let Some(ctx) = context(&canvas, l.width, l.height) {
                put_rgba(&ctx, &level_rgba(&l), l.width, l.height, 0.0, 0.0);
            }
        }
    });
    let name = format!("{} {}", if level.dog { "DoG" } else { "Gaussian" }, level.index);
    let title = name.clone();
    let on_move = move |ev: web_sys::MouseEvent| {
        let Some(el) = ev.current_target().and_then(|t| t.dyn_into::<web_sys::Element>().ok()) else { return };
        let r = el.get_bounding_client_rect();
        let (fx, fy) = ((ev.client_x() as f64 - r.left()) / r.width(), (ev.client_y() as f64 - r.top()) / r.height());
        if let Some((c, row, v)) = level_value(&level, fx, fy) {
            hover.set(format!("{name}, octave pixel ({c}, {row}): {v}"));
        }
    };
    view! {
        <canvas
            node_ref=canvas_ref
            class="level"
            class:big=move || enlarged.get() == Some(index)
            title=title
            on:click=move |_| enlarged.update(|e| *e = if *e == Some(index) { None } else { Some(index) })
            on:mousemove=on_move
        ></canvas>
    }
}

#[component]
fn KeypointDetail(data: RwSignal<Option<Shown>>) -> impl IntoView {
    let inside = expect_context::<Inside>();
    move || {
        let Shown(d, f) = data.get()?;
        let i = inside.kp.get()?;
        let k = *f.features.keypoints.get(i)?;
        let bins = d.hist.get(i * 72..i * 72 + 72)?;
        let (raw, smooth) = bins.split_at(36);
        let thr = *d.hist_thr.get(i)?;
        let first: usize = d.peak_counts[..i].iter().map(|&c| c as usize).sum();
        let n = d.peak_counts[i] as usize;
        let peaks: Vec<(f32, f32)> =
            d.peaks.get(2 * first..2 * (first + n))?.chunks_exact(2).map(|p| (p[0], p[1])).collect();
        let (w, h) = (360.0, 120.0);
        let ymax = raw.iter().chain(smooth).fold(0f32, |m, &v| m.max(v)) as f64;
        let bars = hist_bars(raw, w, h, ymax)
            .into_iter()
            .map(|(x, y, bw, bh)| view! { <rect x=x y=y width=bw - 1.0 height=bh class="hist-raw"/> })
            .collect_view();
        let line: String = hist_bars(smooth, w, h, ymax)
            .iter()
            .map(|(x, y, bw, _)| format!("{:.1},{:.1}", x + bw / 2.0, y))
            .collect::<Vec<_>>()
            .join(" ");
        let thr_y = h - (thr as f64 / ymax).clamp(0.0, 1.0) * h;
        let marks = peaks
            .iter()
            .map(|&(bin, _)| {
                let x = (bin as f64 + 0.5) * w / 36.0;
                view! { <line x1=x x2=x y1=0 y2=h class="hist-peak"/> }
            })
            .collect_view();
        let angles = peaks.iter().map(|(_, a)| format!("{a:.2}°")).collect::<Vec<_>>().join(", ");
        let desc = *f.features.descriptors.get(i)?;
        Some(view! {
            <div class="kp-detail" data-testid="anatomy-keypoint">
                <h3>{format!("Keypoint {i}")}</h3>
                <p>{keypoint_place(&k)}</p>
                <svg viewBox=format!("0 0 {w} {h}") class="hist" data-testid="orientation-hist">
                    {bars}
                    <polyline points=line class="hist-smooth"/>
                    <line x1=0 x2=w y1=thr_y y2=thr_y class="hist-thr"/>
                    {marks}
                </svg>
                <p class="muted">
                    "Bars: the 36-bin gradient histogram (10° each); line: smoothed [1 4 6 4 1]/16; dashed: 80 % of "
                    "the highest bin. Peaks taken (angles of the keypoints made here): "{angles}
                    {format!(" — this keypoint's angle: {:.2}°", k.angle)}
                </p>
                <DescriptorGrid desc=desc title=format!("Descriptor of keypoint {i}")/>
            </div>
        })
    }
}
