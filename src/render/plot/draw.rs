//! Drawing the parts of a line plot: grid, ticks and labels, series, reference lines, frame
//! and title (reference lines are in `annotate.rs`, the legend in `legend.rs`).

use tiny_skia::{
    Color, FillRule, LineCap, LineJoin, Mask, Path, PathBuilder, Pixmap, Rect, Stroke, StrokeDash,
    Transform,
};

use super::layout::Plan;
use super::scale::PlotFrame;
use super::{LinePlot, LineStyle, Series};
pub(super) use crate::render::font::fit;
use crate::render::font::{draw_text, text_width, Anchor};
use crate::render::paint::{color, frame, paint};

/// Light grey of the grid lines at the major ticks.
const GRID_RGB: [u8; 3] = [225, 225, 225];
/// How far outside the plot area (pixels) lines are cut before the mask clips them exactly.
const CLIP_SLACK_PX: f64 = 64.0;

pub(super) fn fill(pm: &mut Pixmap, x: f32, y: f32, w: f32, h: f32, rgb: [u8; 3], alpha: f32) {
    if let Some(r) = Rect::from_xywh(x, y, w, h) {
        pm.fill_rect(
            r,
            &paint(color(rgb, alpha), false),
            Transform::identity(),
            None,
        );
    }
}

/// The stroke of a `style` line `width` pixels wide; dash lengths scale with the width.
pub(super) fn stroke(style: LineStyle, width: f32) -> Stroke {
    let u = width.max(1.0);
    let dash = match style {
        LineStyle::Solid => None,
        LineStyle::Dashed => StrokeDash::new(vec![6.0 * u, 4.0 * u], 0.0),
        LineStyle::Dotted => StrokeDash::new(vec![u, 2.0 * u], 0.0),
        LineStyle::DashDot => StrokeDash::new(vec![6.0 * u, 3.0 * u, u, 3.0 * u], 0.0),
    };
    Stroke {
        width,
        line_cap: LineCap::Butt,
        line_join: LineJoin::Round,
        dash,
        ..Stroke::default()
    }
}

/// Grid lines at the major ticks, tick marks (minor ones half as long), tick labels and the
/// axis titles.
pub(super) fn grid_and_axes(pm: &mut Pixmap, plan: &Plan, plot: &LinePlot) {
    let f = &plan.frame;
    let (s, ch, desc, gap, pad, tk) = (
        plan.s,
        plan.ch(),
        plan.desc(),
        plan.gap(),
        plan.pad(),
        plan.tick(),
    );
    let tw = plan.line();
    let (right, bottom) = (f.left + f.plot_width, f.top + f.plot_height);
    let black = [0, 0, 0];
    for (v, label) in &plan.x_ticks.major {
        let Some(x) = f.sx(*v).map(|x| (x as f32).floor().clamp(f.left, right)) else {
            continue;
        };
        fill(pm, x, f.top, plan.line(), f.plot_height, GRID_RGB, 1.0);
        fill(pm, x - (tw / 2.0).floor(), bottom, tw, tk, black, 1.0);
        let half = text_width(label, s) / 2.0;
        let cx = x.clamp(pad + half, f.width as f32 - pad - half);
        let at = (cx, bottom + tk + gap);
        draw_text(pm, label, at, s, Color::BLACK, Anchor::TopCenter, true);
    }
    for v in &plan.x_ticks.minor {
        if let Some(x) = f.sx(*v).map(|x| (x as f32).floor().clamp(f.left, right)) {
            fill(pm, x - (tw / 2.0).floor(), bottom, tw, tk / 2.0, black, 1.0);
        }
    }
    for (v, label) in &plan.y_ticks.major {
        let Some(y) = f.sy(*v).map(|y| (y as f32).floor().clamp(f.top, bottom)) else {
            continue;
        };
        fill(pm, f.left, y, f.plot_width, plan.line(), GRID_RGB, 1.0);
        fill(pm, f.left - tk, y - (tw / 2.0).floor(), tk, tw, black, 1.0);
        let at = (f.left - tk - gap, y);
        draw_text(pm, label, at, s, Color::BLACK, Anchor::MiddleRight, true);
    }
    for v in &plan.y_ticks.minor {
        if let Some(y) = f.sy(*v).map(|y| (y as f32).floor().clamp(f.top, bottom)) {
            fill(
                pm,
                f.left - tk / 2.0,
                y - (tw / 2.0).floor(),
                tk / 2.0,
                tw,
                black,
                1.0,
            );
        }
    }
    if !plot.x.label.is_empty() {
        let text = fit(&plot.x.label, f.width as f32 - 2.0 * pad, s);
        let y = bottom + tk + gap + ch + desc + 2.0 * gap;
        let half = text_width(&text, s) / 2.0;
        let cx = (f.left + f.plot_width / 2.0).clamp(pad + half, f.width as f32 - pad - half);
        draw_text(pm, &text, (cx, y), s, Color::BLACK, Anchor::TopCenter, true);
    }
    if !plot.y.label.is_empty() {
        let text = fit(&plot.y.label, f.height as f32 - 2.0 * pad, s);
        let half = text_width(&text, s) / 2.0;
        let cy = (f.top + f.plot_height / 2.0).clamp(pad + half, f.height as f32 - pad - half);
        draw_text(
            pm,
            &text,
            (pad, cy),
            s,
            Color::BLACK,
            Anchor::TopCenter,
            false,
        );
    }
}

/// A mask of the plot area, so that nothing drawn through it leaves the area.
pub(super) fn area_mask(pm: &Pixmap, f: &PlotFrame) -> Option<Mask> {
    let mut mask = Mask::new(pm.width(), pm.height())?;
    let r = Rect::from_xywh(f.left, f.top, f.plot_width, f.plot_height)?;
    mask.fill_path(
        &PathBuilder::from_rect(r),
        FillRule::Winding,
        false,
        Transform::identity(),
    );
    Some(mask)
}

/// Cuts the segment `a`-`b` to the rectangle `(x0, y0, x1, y1)` (Liang–Barsky).
fn clip_segment(
    a: (f64, f64),
    b: (f64, f64),
    (x0, y0, x1, y1): (f64, f64, f64, f64),
) -> Option<((f64, f64), (f64, f64))> {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-dx, a.0 - x0),
        (dx, x1 - a.0),
        (-dy, a.1 - y0),
        (dy, y1 - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    if t0 > t1 {
        return None;
    }
    let at = |t: f64| (a.0 + t * dx, a.1 + t * dy);
    Some((
        if t0 > 0.0 { at(t0) } else { a },
        if t1 < 1.0 { at(t1) } else { b },
    ))
}

/// Screen positions of a series' points, None where a point is not drawable.
pub(super) fn screen_points(f: &PlotFrame, s: &Series) -> Vec<Option<(f64, f64)>> {
    s.points
        .iter()
        .map(|&(x, y)| Some((f.sx(x)?, f.sy(y)?)))
        .collect()
}

/// The polyline through the drawable points, broken at undrawable ones, cut to the plot area
/// plus [`CLIP_SLACK_PX`] (so that far-away points give sane coordinates).
fn series_path(f: &PlotFrame, pts: &[Option<(f64, f64)>]) -> Option<Path> {
    let slack = CLIP_SLACK_PX;
    let (l, t) = (f.left as f64, f.top as f64);
    let rect = (
        l - slack,
        t - slack,
        l + f.plot_width as f64 + slack,
        t + f.plot_height as f64 + slack,
    );
    let mut pb = PathBuilder::new();
    let mut pen: Option<(f64, f64)> = None;
    for w in pts.windows(2) {
        let (Some(a), Some(b)) = (w[0], w[1]) else {
            pen = None;
            continue;
        };
        if let Some((c, d)) = clip_segment(a, b, rect) {
            if pen != Some(c) {
                pb.move_to(c.0 as f32, c.1 as f32);
            }
            pb.line_to(d.0 as f32, d.1 as f32);
            pen = Some(d);
        } else {
            pen = None;
        }
    }
    pb.finish()
}

/// Radius in pixels of a series' point markers.
pub(super) fn marker_radius(width: f32) -> f32 {
    (1.5 * width).max(2.5)
}

/// Draws every series, clipped to the plot area.
pub(super) fn all_series(pm: &mut Pixmap, f: &PlotFrame, series: &[Series]) {
    let mask = area_mask(pm, f);
    for s in series {
        let pts = screen_points(f, s);
        let c = paint(color(s.color, 1.0), true);
        if let Some(path) = series_path(f, &pts) {
            let st = stroke(s.style, s.width);
            pm.stroke_path(&path, &c, &st, Transform::identity(), mask.as_ref());
        }
        if s.markers {
            let r = marker_radius(s.width);
            let mut pb = PathBuilder::new();
            for &(x, y) in pts.iter().flatten() {
                if f.contains(x as f32, y as f32) {
                    pb.push_circle(x as f32, y as f32, r);
                }
            }
            if let Some(path) = pb.finish() {
                let id = Transform::identity();
                pm.fill_path(&path, &c, FillRule::Winding, id, mask.as_ref());
            }
        }
    }
}

/// The frame around the plot area and the title above it.
pub(super) fn frame_and_title(pm: &mut Pixmap, plan: &Plan, plot: &LinePlot) {
    let f = &plan.frame;
    frame(pm, f.left, f.top, f.plot_width, f.plot_height, plan.line());
    if plot.title.is_empty() {
        return;
    }
    let (s, pad) = (plan.s, plan.pad());
    let text = fit(&plot.title, f.width as f32 - 2.0 * pad, s);
    let half = text_width(&text, s) / 2.0;
    let cx = (f.left + f.plot_width / 2.0).clamp(pad + half, f.width as f32 - pad - half);
    draw_text(
        pm,
        &text,
        (cx, pad),
        s,
        Color::BLACK,
        Anchor::TopCenter,
        true,
    );
}
