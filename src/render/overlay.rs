//! Curves, point markers, constraint pixels and the legend (over the map or under it).

use glam::DVec2;
use tiny_skia::{
    Color, FillRule, LineCap, LineJoin, Mask, Path, PathBuilder, Pixmap, Rect, Stroke, StrokeDash,
    Transform,
};

use super::font::{draw_text, text_width, Anchor};
use super::layout::Layout;
use super::paint::{color, frame, paint};
use super::{LegendPlace, Marker, Overlay, OverlayLabel, MIN_PIXEL_SIDE_PX, PIXEL_ALPHA};
use crate::ds9::polyline_is_open;
use crate::map::MapGeometry;

/// Tangential critical curves.
pub const TANGENTIAL_RGB: [u8; 3] = [230, 30, 30];
/// Radial critical curves.
pub const RADIAL_RGB: [u8; 3] = [0, 215, 255];
/// Caustics (dashed).
pub const CAUSTIC_RGB: [u8; 3] = [255, 255, 255];

/// What the legend shows for one entry.
pub(super) enum Key {
    Line { rgb: [u8; 3], dashed: bool },
    Point { rgb: [u8; 3], marker: Marker },
}

fn polyline_path(l: &Layout, g: &MapGeometry, line: &[DVec2]) -> Option<Path> {
    let mut pb = PathBuilder::new();
    for (k, &p) in line.iter().enumerate() {
        let (x, y) = l.screen(g, p);
        if k == 0 {
            pb.move_to(x, y);
        } else {
            pb.line_to(x, y);
        }
    }
    if line.len() >= 3 && !polyline_is_open(line, g) {
        pb.close();
    }
    pb.finish()
}

/// Strokes `path` in `rgb` over a darker, wider halo so it reads on any colour.
fn halo_stroke(
    pm: &mut Pixmap,
    path: &Path,
    rgb: [u8; 3],
    width: f32,
    dashed: bool,
    mask: Option<&Mask>,
) {
    let mut stroke = Stroke {
        // A third of the line's width on either side.
        width: width * 5.0 / 3.0,
        line_cap: LineCap::Round,
        line_join: LineJoin::Round,
        ..Stroke::default()
    };
    if dashed {
        stroke.dash = StrokeDash::new(vec![4.0 * width, 3.0 * width], 0.0);
    }
    pm.stroke_path(
        path,
        &paint(Color::from_rgba8(0, 0, 0, 140), true),
        &stroke,
        Transform::identity(),
        mask,
    );
    stroke.width = width;
    pm.stroke_path(
        path,
        &paint(color(rgb, 1.0), true),
        &stroke,
        Transform::identity(),
        mask,
    );
}

fn marker_path(marker: Marker, (x, y): (f32, f32), r: f32) -> Option<Path> {
    let mut pb = PathBuilder::new();
    match marker {
        Marker::Circle => pb.push_circle(x, y, r),
        Marker::Square => pb.push_rect(Rect::from_xywh(x - r, y - r, 2.0 * r, 2.0 * r)?),
        Marker::Ring => pb.push_circle(x, y, 3.0 * r),
        Marker::Pixel { .. } => return None,
        Marker::Cross | Marker::Plus => {
            let (a, b) = if marker == Marker::Cross {
                (r, r)
            } else {
                (r, 0.0)
            };
            pb.move_to(x - a, y - b);
            pb.line_to(x + a, y + b);
            pb.move_to(x - b, y + a);
            pb.line_to(x + b, y - a);
        }
    }
    pb.finish()
}

/// Screen side of a [`Marker::Pixel`] of `side_mas` milliarcsec on a map of geometry `g`.
fn pixel_side_px(l: &Layout, g: &MapGeometry, side_mas: u32) -> f32 {
    let px_per_arcsec = l.m as f64 / g.size_arcsec;
    ((side_mas as f64 / 1000.0 * px_per_arcsec) as f32).max(MIN_PIXEL_SIDE_PX)
}

/// Fills one square per position as a single path, so overlaps are not darkened twice.
fn fill_pixels(
    pm: &mut Pixmap,
    centres: impl Iterator<Item = (f32, f32)>,
    side: f32,
    rgb: [u8; 3],
    mask: Option<&Mask>,
) {
    let mut pb = PathBuilder::new();
    for (x, y) in centres {
        if let Some(r) = Rect::from_xywh(x - side / 2.0, y - side / 2.0, side, side) {
            pb.push_rect(r);
        }
    }
    if let Some(path) = pb.finish() {
        let p = paint(color(rgb, PIXEL_ALPHA), false);
        pm.fill_path(&path, &p, FillRule::Winding, Transform::identity(), mask);
    }
}

/// The legend entries of `overlay`: the curves that have lines, then every labelled,
/// non-empty point set.
pub(super) fn legend_entries(overlay: &Overlay, show_caustics: bool) -> Vec<(String, Key)> {
    let mut legend: Vec<(String, Key)> = Vec::new();
    if let Some(c) = overlay.curves {
        let drawn = |lines: &Vec<Vec<DVec2>>| lines.iter().any(|v| v.len() >= 2);
        let mut sets = vec![
            ("tangential", drawn(&c.tangential), TANGENTIAL_RGB, false),
            ("radial", drawn(&c.radial), RADIAL_RGB, false),
        ];
        if show_caustics {
            let any = drawn(&c.caustics.tangential) || drawn(&c.caustics.radial);
            sets.push(("caustics", any, CAUSTIC_RGB, true));
        }
        for (label, drawn, rgb, dashed) in sets {
            if drawn {
                legend.push((label.to_string(), Key::Line { rgb, dashed }));
            }
        }
    }
    for set in &overlay.lines {
        if !set.label.is_empty() && set.lines.iter().any(|v| v.len() >= 2) {
            let (rgb, dashed) = (set.color, set.dashed);
            legend.push((set.label.clone(), Key::Line { rgb, dashed }));
        }
    }
    for set in &overlay.points {
        if !set.positions_arcsec.is_empty() && !set.label.is_empty() {
            let (rgb, marker) = (set.color, set.marker);
            legend.push((set.label.clone(), Key::Point { rgb, marker }));
        }
    }
    legend
}

/// Draws pixel sets, curves, other lines and point markers, clipped to the map.
pub(super) fn draw_overlay(
    pm: &mut Pixmap,
    l: &Layout,
    g: &MapGeometry,
    overlay: &Overlay,
    show_caustics: bool,
) {
    let mut mask = Mask::new(pm.width(), pm.height());
    if let (Some(m), Some(r)) = (mask.as_mut(), Rect::from_xywh(l.left, l.top, l.m, l.m)) {
        m.fill_path(
            &PathBuilder::from_rect(r),
            FillRule::Winding,
            false,
            Transform::identity(),
        );
    }
    let mask = mask.as_ref();
    // Pixels first: the curves and markers stay readable on top of them.
    for set in &overlay.points {
        if let Marker::Pixel { side_mas } = set.marker {
            let side = pixel_side_px(l, g, side_mas);
            let centres = set.positions_arcsec.iter().map(|&p| l.screen(g, p));
            fill_pixels(pm, centres, side, set.color, mask);
        }
    }
    let width = line_width(l);
    if let Some(c) = overlay.curves {
        let mut sets = vec![
            (&c.tangential, TANGENTIAL_RGB, false),
            (&c.radial, RADIAL_RGB, false),
        ];
        if show_caustics {
            sets.push((&c.caustics.tangential, CAUSTIC_RGB, true));
            sets.push((&c.caustics.radial, CAUSTIC_RGB, true));
        }
        for (lines, rgb, dashed) in sets {
            for path in lines
                .iter()
                .filter(|v| v.len() >= 2)
                .filter_map(|v| polyline_path(l, g, v))
            {
                halo_stroke(pm, &path, rgb, width, dashed, mask);
            }
        }
    }
    for set in &overlay.lines {
        for path in set
            .lines
            .iter()
            .filter(|v| v.len() >= 2)
            .filter_map(|v| polyline_path(l, g, v))
        {
            halo_stroke(pm, &path, set.color, width, set.dashed, mask);
        }
    }
    for set in &overlay.points {
        if matches!(set.marker, Marker::Pixel { .. }) {
            continue;
        }
        let (r, w) = marker_size(set.marker, l);
        for &p in &set.positions_arcsec {
            if let Some(path) = marker_path(set.marker, l.screen(g, p), r) {
                halo_stroke(pm, &path, set.color, w, false, mask);
            }
        }
    }
    let mut placed = Vec::new();
    for label in &overlay.labels {
        draw_map_label(pm, l, g, label, &mut placed);
    }
}

/// A label's box on screen: `[left, top, right, bottom]` in pixels.
type LabelBox = [f32; 4];

/// Draws `label` beside its position, one ring radius away, where it overlaps no label in
/// `placed` ([`place_label`]), and adds its box there. Nothing when the position is off the
/// map.
fn draw_map_label(
    pm: &mut Pixmap,
    l: &Layout,
    g: &MapGeometry,
    label: &OverlayLabel,
    placed: &mut Vec<LabelBox>,
) {
    let (x, y) = l.screen(g, label.position_arcsec);
    let inside = |v: f32, lo: f32| v >= lo && v <= lo + l.m;
    if !(inside(x, l.left) && inside(y, l.top)) {
        return;
    }
    let s = l.s;
    let gap = 3.0 * marker_radius(l) + 2.0 * s;
    let size = (
        text_width(&label.text, s),
        1.6 * crate::render::font::CAP * s,
    );
    let (at, left_side, taken) = place_label((x, y), gap, size, (l.left, l.left + l.m), placed);
    placed.push(taken);
    let anchor = if left_side {
        Anchor::MiddleRight
    } else {
        Anchor::MiddleLeft
    };
    // A dark halo: the text drawn offset in eight directions, then in its colour on top.
    let halo = Color::from_rgba8(0, 0, 0, 200);
    for (dx, dy) in [
        (-1.0, -1.0),
        (0.0, -1.0),
        (1.0, -1.0),
        (-1.0, 0.0),
        (1.0, 0.0),
        (-1.0, 1.0),
        (0.0, 1.0),
        (1.0, 1.0),
    ] {
        let p = (at.0 + dx * s, at.1 + dy * s);
        draw_text(pm, &label.text, p, s, halo, anchor, true);
    }
    draw_text(
        pm,
        &label.text,
        at,
        s,
        color(label.color, 1.0),
        anchor,
        true,
    );
}

/// Where a label of `(width, height)` goes beside the point `(x, y)`, `gap` away, with the
/// map's columns `map = (left, right)`: right of the point, left of it, then a line above or
/// below on either side, the first that stays on the map and overlaps no box of `placed`
/// (else the first that stays on the map). Returns the text's anchor point, whether it is
/// left of the point (anchored on its right end), and its box.
fn place_label(
    (x, y): (f32, f32),
    gap: f32,
    (w, h): (f32, f32),
    map: (f32, f32),
    placed: &[LabelBox],
) -> ((f32, f32), bool, LabelBox) {
    let mut options = Vec::new();
    for dy in [0.0, -h, h] {
        options.push(((x + gap, y + dy), false, x + gap));
        options.push(((x - gap, y + dy), true, x - gap - w));
    }
    let on_map = |left: f32| left >= map.0 && left + w <= map.1;
    let boxed = |at: (f32, f32), left: f32| [left, at.1 - h / 2.0, left + w, at.1 + h / 2.0];
    let overlaps = |b: &LabelBox| {
        placed
            .iter()
            .any(|p| b[0] < p[2] && p[0] < b[2] && b[1] < p[3] && p[1] < b[3])
    };
    let &(at, left_side, left) = options
        .iter()
        .find(|&&(at, _, left)| on_map(left) && !overlaps(&boxed(at, left)))
        .or_else(|| options.iter().find(|o| on_map(o.2)))
        .unwrap_or(&options[0]);
    (at, left_side, boxed(at, left))
}

/// Width of the curves and marker strokes (3 pixels on a 512-pixel map).
fn line_width(l: &Layout) -> f32 {
    1.5 * l.s
}

/// Radius of the point markers (7 pixels on a 512-pixel map).
fn marker_radius(l: &Layout) -> f32 {
    3.5 * l.s
}

/// Radius and line width of a point marker (curves are drawn `line_width` wide). The model's
/// predicted images (crosses) and the member galaxies (circles) can number in the hundreds:
/// they are drawn small and thin so that the map stays readable under them; the data (plus
/// signs) and a clicked point's images (squares) keep the full size.
fn marker_size(marker: Marker, l: &Layout) -> (f32, f32) {
    let (r, w) = (marker_radius(l), line_width(l));
    match marker {
        Marker::Cross => (0.65 * r, 0.6 * w),
        Marker::Circle => (0.7 * r, 0.6 * w),
        Marker::Ring => (r, 1.3 * w),
        _ => (r, w),
    }
}

/// Sizes of the legend parts: (padding, sample width, row height) in pixels.
fn legend_metrics(l: &Layout) -> (f32, f32, f32) {
    let s = l.s;
    (4.0 * s, 14.0 * s, l.ch() + 4.0 * s)
}

/// Left offsets and rows of the entries laid out in rows no wider than `avail` pixels (the
/// legend under the map): `(x offset from the first column, row index)` per entry.
pub(super) fn below_flow(l: &Layout, entries: &[(String, Key)], avail: f32) -> Vec<(f32, usize)> {
    let (_, sample, _) = legend_metrics(l);
    let (gap, spacing) = (l.gap() + 2.0 * l.s, 4.0 * l.gap());
    let mut out = Vec::with_capacity(entries.len());
    let (mut x, mut row) = (0.0, 0);
    for (label, _) in entries {
        let w = sample + gap + text_width(label, l.s);
        if x > 0.0 && x + w > avail {
            x = 0.0;
            row += 1;
        }
        out.push((x, row));
        x += w + spacing;
    }
    out
}

/// Height in pixels of the legend under the map (0 without entries).
pub(super) fn below_height(l: &Layout, entries: &[(String, Key)], avail: f32) -> f32 {
    let rows = below_flow(l, entries, avail)
        .last()
        .map_or(0, |&(_, r)| r + 1);
    let (pad, _, row) = legend_metrics(l);
    if rows == 0 {
        0.0
    } else {
        rows as f32 * row + pad
    }
}

/// Draws one legend row's sample (line, marker or pixel swatch) centred at height `cy`.
fn draw_sample(pm: &mut Pixmap, l: &Layout, key: &Key, x: f32, cy: f32, sample: f32) {
    let sf = l.s;
    let width = line_width(l);
    let (rgb, dashed) = match key {
        Key::Line { rgb, dashed } => (*rgb, *dashed),
        Key::Point { rgb, .. } => (*rgb, false),
    };
    let path = match key {
        Key::Line { .. } => {
            let mut pb = PathBuilder::new();
            pb.move_to(x, cy);
            pb.line_to(x + sample, cy);
            pb.finish()
        }
        Key::Point {
            marker: Marker::Pixel { .. },
            ..
        } => {
            let side = 7.0 * sf;
            let centre = [(x + sample / 2.0, cy)].into_iter();
            fill_pixels(pm, centre, side, rgb, None);
            None
        }
        // A ring's sample is a circle of the row's height, not a ring of its size on the map.
        Key::Point {
            marker: Marker::Ring,
            ..
        } => marker_path(
            Marker::Circle,
            (x + sample / 2.0, cy),
            1.2 * marker_radius(l),
        ),
        Key::Point { marker, .. } => marker_path(*marker, (x + sample / 2.0, cy), marker_radius(l)),
    };
    if let Some(p) = path {
        halo_stroke(pm, &p, rgb, width, dashed, None);
    }
}

/// Draws the legend: a box in the map's top-right corner, or rows under the x-axis title
/// starting at `l.legend_top` (see [`below_flow`]).
pub(super) fn draw_legend(
    pm: &mut Pixmap,
    l: &Layout,
    entries: &[(String, Key)],
    place: LegendPlace,
) {
    if entries.is_empty() {
        return;
    }
    let (s, ch) = (l.s, l.ch());
    let sf = s;
    let (pad, sample, row) = legend_metrics(l);
    let gap = l.gap() + 2.0 * sf;
    let text = |pm: &mut Pixmap, label: &str, at: (f32, f32)| {
        draw_text(pm, label, at, s, Color::BLACK, Anchor::MiddleLeft, true);
    };
    if place == LegendPlace::Below {
        let x0 = l.left;
        for ((label, key), (dx, r)) in entries.iter().zip(below_flow(l, entries, l.legend_avail()))
        {
            let (x, cy) = (x0 + dx, l.legend_top + row * r as f32 + ch / 2.0);
            draw_sample(pm, l, key, x, cy, sample);
            text(pm, label, (x + sample + gap, cy));
        }
        return;
    }
    let label_w = entries
        .iter()
        .map(|(t, _)| text_width(t, s))
        .fold(0.0, f32::max);
    let (w, h) = (
        pad + sample + gap + label_w + pad,
        2.0 * pad + row * entries.len() as f32 - 4.0 * sf,
    );
    let (x, y) = (
        (l.left + l.m - w - 4.0 * sf).round(),
        (l.top + 4.0 * sf).round(),
    );
    if let Some(r) = Rect::from_xywh(x, y, w, h) {
        pm.fill_rect(
            r,
            &paint(Color::from_rgba8(255, 255, 255, 215), false),
            Transform::identity(),
            None,
        );
        frame(pm, x, y, w, h, l.line());
    }
    for (k, (label, key)) in entries.iter().enumerate() {
        let cy = y + pad + row * k as f32 + ch / 2.0;
        draw_sample(pm, l, key, x + pad, cy, sample);
        text(pm, label, (x + pad + sample + gap, cy));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Labels of nearby points do not overlap: the second goes left, the third a line up; on
    /// their own they sit right of their point, or left of it at the map's right edge.
    #[test]
    fn labels_of_nearby_points_stand_apart() {
        let (gap, size, map) = (10.0, (30.0, 12.0), (0.0, 500.0));
        let mut placed = Vec::new();
        let mut sides = Vec::new();
        for p in [(200.0, 200.0), (203.0, 201.0), (198.0, 199.0)] {
            let (at, left, b) = place_label(p, gap, size, map, &placed);
            assert!(
                placed.iter().all(|q: &LabelBox| b[2] <= q[0]
                    || q[2] <= b[0]
                    || b[3] <= q[1]
                    || q[3] <= b[1]),
                "{b:?} overlaps {placed:?}"
            );
            placed.push(b);
            sides.push((left, at.1 - p.1));
        }
        assert_eq!(sides, [(false, 0.0), (true, 0.0), (false, -12.0)]);
        let alone = |p| place_label(p, gap, size, map, &[]);
        assert_eq!(alone((100.0, 50.0)).0, (110.0, 50.0));
        assert!(!alone((100.0, 50.0)).1);
        assert_eq!(alone((480.0, 50.0)).0, (470.0, 50.0));
        assert!(alone((480.0, 50.0)).1);
    }
}
