//! Reference lines with their labels, and where labels may go without hiding the data.

use tiny_skia::{PathBuilder, Pixmap, Transform};

use super::draw::{area_mask, fill, fit, screen_points, stroke};
use super::layout::Plan;
use super::scale::PlotFrame;
use super::{LineStyle, Reference, Series};
use crate::render::font::{draw_text, text_width, Anchor};
use crate::render::paint::{color, paint};

/// Spacing in pixels of the sample points along lines used to place labels and the legend.
pub(super) const SAMPLE_STEP_PX: f32 = 3.0;
/// Most samples taken along one segment.
const MAX_SAMPLES_PER_SEGMENT: usize = 1000;
/// Score of a label position overlapping another label (as many hidden line samples).
pub(super) const LABEL_OVERLAP_SCORE: usize = 10_000;

/// A screen rectangle `(x0, y0, x1, y1)` taken by a label.
pub(super) type Taken = (f32, f32, f32, f32);

/// Draws each reference inside the y range as a dashed line across the plot with its label
/// at one end or the middle, above or below the line, where it hides the fewest series `samples` and
/// overlaps no earlier label. Returns the rectangles the labels took.
pub(super) fn references(
    pm: &mut Pixmap,
    plan: &Plan,
    refs: &[Reference],
    samples: &[(f32, f32)],
) -> Vec<Taken> {
    let f = &plan.frame;
    let (s, ch, gap) = (plan.s, plan.ch(), plan.gap());
    let (right, bottom) = (f.left + f.plot_width, f.top + f.plot_height);
    let width = s.max(1.5);
    let mask = area_mask(pm, f);
    let mut taken: Vec<Taken> = Vec::new();
    for r in refs {
        let Some(y) = f.sy(r.value).map(|y| y as f32) else {
            continue;
        };
        if !(f.top..=bottom).contains(&y) {
            continue;
        }
        let mut pb = PathBuilder::new();
        pb.move_to(f.left, y);
        pb.line_to(right, y);
        if let Some(path) = pb.finish() {
            let c = paint(color(r.color, 1.0), true);
            let st = stroke(LineStyle::Dashed, width);
            pm.stroke_path(&path, &c, &st, Transform::identity(), mask.as_ref());
        }
        let text = fit(&r.label, f.plot_width - 2.0 * gap, s);
        if text.is_empty() {
            continue;
        }
        let (tw, off) = (text_width(&text, s), ch / 2.0 + width / 2.0 + gap);
        let centre = (f.left + (f.plot_width - tw) / 2.0).round();
        let spots = [
            (right - gap - tw, y - off),
            (right - gap - tw, y + off),
            (f.left + gap, y - off),
            (f.left + gap, y + off),
            (centre, y - off),
            (centre, y + off),
        ];
        let rect = |(x, cy): (f32, f32)| {
            (
                x - 2.0,
                cy - ch / 2.0 - 2.0,
                x + tw + 2.0,
                cy + ch / 2.0 + 2.0,
            )
        };
        // Fewest hidden line samples, no overlap with earlier labels, inside the area.
        let score = |p: (f32, f32)| {
            let b = rect(p);
            // Lines passing close to the text count as hiding it too.
            let near = (
                b.0 - gap - width,
                b.1 - width,
                b.2 + gap + width,
                b.3 + width,
            );
            let hidden = samples.iter().filter(|&&q| inside(q, &near)).count();
            let clash = taken.iter().filter(|t| overlaps(t, &b)).count();
            let out = usize::from(b.1 < f.top || b.3 > bottom);
            hidden + LABEL_OVERLAP_SCORE * (clash + 2 * out)
        };
        let spot = spots
            .iter()
            .map(|&p| (score(p), p))
            .min_by_key(|(sc, _)| *sc)
            .map_or(spots[0], |(_, p)| p);
        let b = rect(spot);
        fill(pm, b.0, b.1, b.2 - b.0, b.3 - b.1, [255, 255, 255], 0.8);
        draw_text(
            pm,
            &text,
            spot,
            s,
            color(r.color, 1.0),
            Anchor::MiddleLeft,
            true,
        );
        taken.push(b);
    }
    taken
}

/// Whether the point `p` lies in the rectangle `b`.
pub(super) fn inside(p: (f32, f32), b: &Taken) -> bool {
    p.0 >= b.0 && p.0 <= b.2 && p.1 >= b.1 && p.1 <= b.3
}

/// Points every [`SAMPLE_STEP_PX`] along the drawn series (and their data points) inside the
/// plot area: what labels and the legend should not hide.
pub(super) fn series_samples(f: &PlotFrame, series: &[Series]) -> Vec<(f32, f32)> {
    let mut out = Vec::new();
    let step = SAMPLE_STEP_PX as f64;
    for s in series {
        let pts = screen_points(f, s);
        for w in pts.windows(2) {
            let (Some(a), Some(b)) = (w[0], w[1]) else {
                continue;
            };
            let len = (b.0 - a.0).hypot(b.1 - a.1);
            let n = ((len / step).ceil() as usize).clamp(1, MAX_SAMPLES_PER_SEGMENT);
            for k in 0..=n {
                let t = k as f64 / n as f64;
                out.push((
                    (a.0 + t * (b.0 - a.0)) as f32,
                    (a.1 + t * (b.1 - a.1)) as f32,
                ));
            }
        }
        out.extend(pts.iter().flatten().map(|&(x, y)| (x as f32, y as f32)));
    }
    out.retain(|&(x, y)| f.contains(x, y));
    out
}

/// Whether two screen rectangles intersect.
pub(super) fn overlaps(a: &Taken, b: &Taken) -> bool {
    a.0 < b.2 && b.0 < a.2 && a.1 < b.3 && b.1 < a.3
}
