//! Drawing primitives shared by the convergence figure, its overlays and the line plots.

use tiny_skia::{Color, Paint, PathBuilder, Pixmap, Rect, Stroke, Transform};

/// `rgb` with opacity `alpha` (0 to 1).
pub(super) fn color([r, g, b]: [u8; 3], alpha: f32) -> Color {
    Color::from_rgba8(r, g, b, (alpha * 255.0).round() as u8)
}

/// A solid paint of `c`, anti-aliased or not.
pub(super) fn paint(c: Color, anti_alias: bool) -> Paint<'static> {
    let mut p = Paint::default();
    p.set_color(c);
    p.anti_alias = anti_alias;
    p
}

/// A black frame `line` pixels wide (whole pixels) just outside the `w` x `h` box at `(x, y)`.
pub(super) fn frame(pm: &mut Pixmap, x: f32, y: f32, w: f32, h: f32, line: f32) {
    let half = line / 2.0;
    if let Some(r) = Rect::from_xywh(x - half, y - half, w + line, h + line) {
        let stroke = Stroke {
            width: line,
            ..Stroke::default()
        };
        pm.stroke_path(
            &PathBuilder::from_rect(r),
            &paint(Color::BLACK, false),
            &stroke,
            Transform::identity(),
            None,
        );
    }
}
