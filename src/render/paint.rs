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

/// A one-pixel black frame around the `w` x `h` box at `(x, y)`.
pub(super) fn frame(pm: &mut Pixmap, x: f32, y: f32, w: f32, h: f32) {
    if let Some(r) = Rect::from_xywh(x - 0.5, y - 0.5, w + 1.0, h + 1.0) {
        let stroke = Stroke {
            width: 1.0,
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
