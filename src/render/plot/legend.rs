//! The legend box: one row per labelled series (line sample in its style and colour, then the
//! label), at the corner or side of the plot area where it hides the fewest drawn points.

use tiny_skia::{Color, FillRule, PathBuilder, Pixmap, Rect, Transform};

use super::annotate::{inside, overlaps, Taken, LABEL_OVERLAP_SCORE, SAMPLE_STEP_PX};
use super::draw::{fit, marker_radius, stroke};
use super::layout::Plan;
use super::scale::PlotFrame;
use super::{Reference, Series};
use crate::render::font::{draw_text, text_width, Anchor};
use crate::render::paint::{color, frame, paint};

/// Points along the reference lines inside the plot area, every `SAMPLE_STEP_PX`.
fn reference_samples(f: &PlotFrame, refs: &[Reference]) -> Vec<(f32, f32)> {
    let mut out = Vec::new();
    for r in refs {
        if let Some(y) = f.sy(r.value) {
            let n = (f.plot_width / SAMPLE_STEP_PX) as usize;
            out.extend((0..=n).map(|k| (f.left + k as f32 * SAMPLE_STEP_PX, y as f32)));
        }
    }
    out.retain(|&(x, y)| f.contains(x, y));
    out
}

/// Draws the legend of the labelled series (none if no series has a label).
pub(super) fn draw(
    pm: &mut Pixmap,
    plan: &Plan,
    series: &[Series],
    refs: &[Reference],
    series_samples: &[(f32, f32)],
    taken: &[Taken],
) {
    let entries: Vec<&Series> = series.iter().filter(|s| !s.label.is_empty()).collect();
    if entries.is_empty() {
        return;
    }
    let f = &plan.frame;
    let (s, ch, desc) = (plan.s, plan.ch(), plan.desc());
    let sf = s;
    let (pad, sample, gap, row, inset) = (
        4.5 * sf,
        20.0 * sf,
        4.0 * sf,
        ch + desc + 2.0 * sf,
        5.0 * sf,
    );
    let max_label = f.plot_width - 2.0 * inset - 2.0 * pad - sample - gap;
    let labels: Vec<String> = entries
        .iter()
        .map(|e| fit(&e.label, max_label, s))
        .collect();
    let label_w = labels.iter().map(|t| text_width(t, s)).fold(0.0, f32::max);
    let (w, h) = (
        (2.0 * pad + sample + gap + label_w).round(),
        (2.0 * pad + row * entries.len() as f32 - row + ch).round(),
    );
    let (x_l, x_r) = (
        (f.left + inset).round(),
        (f.left + f.plot_width - inset - w).round(),
    );
    let (y_t, y_b) = (
        (f.top + inset).round(),
        (f.top + f.plot_height - inset - h).round(),
    );
    let (x_c, y_m) = (((x_l + x_r) / 2.0).round(), ((y_t + y_b) / 2.0).round());
    // Preferred first on equal scores: corners, then the middles of the sides, then centre.
    let spots = [
        (x_r, y_t),
        (x_l, y_t),
        (x_l, y_b),
        (x_r, y_b),
        (x_r, y_m),
        (x_l, y_m),
        (x_c, y_b),
        (x_c, y_t),
        (x_c, y_m),
    ];
    let ref_samples = reference_samples(f, refs);
    let score = |&(x, y): &(f32, f32)| {
        let b = (x, y, x + w, y + h);
        let hidden = series_samples
            .iter()
            .chain(&ref_samples)
            .filter(|&&p| inside(p, &b))
            .count();
        hidden + LABEL_OVERLAP_SCORE * taken.iter().filter(|t| overlaps(t, &b)).count()
    };
    let (x, y) = spots
        .iter()
        .map(|c| (score(c), *c))
        .min_by_key(|(sc, _)| *sc)
        .map_or(spots[0], |(_, c)| c);
    if let Some(r) = Rect::from_xywh(x, y, w, h) {
        let p = paint(Color::from_rgba8(255, 255, 255, 235), false);
        pm.fill_rect(r, &p, Transform::identity(), None);
        frame(pm, x, y, w, h, plan.line());
    }
    for (k, (e, label)) in entries.iter().zip(&labels).enumerate() {
        let cy = y + pad + row * k as f32 + ch / 2.0;
        let c = paint(color(e.color, 1.0), true);
        let mut pb = PathBuilder::new();
        pb.move_to(x + pad, cy);
        pb.line_to(x + pad + sample, cy);
        if let Some(path) = pb.finish() {
            let st = stroke(e.style, e.width.min(ch));
            pm.stroke_path(&path, &c, &st, Transform::identity(), None);
        }
        if e.markers {
            let r = marker_radius(e.width).min(ch / 2.0);
            let mut pb = PathBuilder::new();
            pb.push_circle(x + pad + sample / 2.0, cy, r);
            if let Some(path) = pb.finish() {
                pm.fill_path(&path, &c, FillRule::Winding, Transform::identity(), None);
            }
        }
        let at = (x + pad + sample + gap, cy);
        draw_text(pm, label, at, s, Color::BLACK, Anchor::MiddleLeft, true);
    }
}
