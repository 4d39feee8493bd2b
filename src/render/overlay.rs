//! Curves, point markers and the legend drawn over the map.

use glam::DVec2;
use tiny_skia::{
    Color, FillRule, LineCap, LineJoin, Mask, Path, PathBuilder, Pixmap, Rect, Stroke, StrokeDash,
    Transform,
};

use super::figure::{color, frame, paint, Layout};
use super::font::{draw_text, text_width, Anchor};
use super::{Marker, Overlay};
use crate::ds9::polyline_is_open;
use crate::grid::MapGeometry;

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
        width: width + 2.0,
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

/// Draws curves and points clipped to the map; returns the legend entries.
pub(super) fn draw_overlay(
    pm: &mut Pixmap,
    l: &Layout,
    g: &MapGeometry,
    overlay: &Overlay,
    show_caustics: bool,
) -> Vec<(String, Key)> {
    let mut legend = Vec::new();
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
    let width = 1.25 * l.s as f32 + 0.5;
    if let Some(c) = overlay.curves {
        let mut sets = vec![
            ("tangential", &c.tangential, TANGENTIAL_RGB, false),
            ("radial", &c.radial, RADIAL_RGB, false),
        ];
        if show_caustics {
            sets.push(("caustics", &c.caustics.tangential, CAUSTIC_RGB, true));
            sets.push(("caustics", &c.caustics.radial, CAUSTIC_RGB, true));
        }
        for (label, lines, rgb, dashed) in sets {
            let mut drawn = false;
            for path in lines
                .iter()
                .filter(|v| v.len() >= 2)
                .filter_map(|v| polyline_path(l, g, v))
            {
                halo_stroke(pm, &path, rgb, width, dashed, mask);
                drawn = true;
            }
            if drawn && !legend.iter().any(|(name, _)| name == label) {
                legend.push((label.to_string(), Key::Line { rgb, dashed }));
            }
        }
    }
    let r = 3.0 * l.s as f32 + 1.0;
    for set in &overlay.points {
        for &p in &set.positions_arcsec {
            if let Some(path) = marker_path(set.marker, l.screen(g, p), r) {
                halo_stroke(pm, &path, set.color, width, false, mask);
            }
        }
        if !set.positions_arcsec.is_empty() {
            legend.push((
                set.label.clone(),
                Key::Point {
                    rgb: set.color,
                    marker: set.marker,
                },
            ));
        }
    }
    legend
}

/// A box in the top-right corner of the map with one row per entry.
pub(super) fn draw_legend(pm: &mut Pixmap, l: &Layout, entries: &[(String, Key)]) {
    if entries.is_empty() {
        return;
    }
    let (s, ch, gap) = (l.s, l.ch(), l.gap());
    let sf = s as f32;
    let (pad, sample, row) = (3.0 * sf + 2.0, 14.0 * sf, ch + 4.0 * sf);
    let label_w = entries
        .iter()
        .map(|(t, _)| text_width(t, s))
        .fold(0.0, f32::max);
    let gap = gap + 2.0 * sf;
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
        frame(pm, x, y, w, h);
    }
    let width = 1.25 * sf + 0.5;
    for (k, (label, key)) in entries.iter().enumerate() {
        let cy = y + pad + row * k as f32 + ch / 2.0;
        let path = match key {
            Key::Line { .. } => {
                let mut pb = PathBuilder::new();
                pb.move_to(x + pad, cy);
                pb.line_to(x + pad + sample, cy);
                pb.finish()
            }
            Key::Point { marker, .. } => {
                marker_path(*marker, (x + pad + sample / 2.0, cy), 3.0 * sf + 1.0)
            }
        };
        let (rgb, dashed) = match key {
            Key::Line { rgb, dashed } => (*rgb, *dashed),
            Key::Point { rgb, .. } => (*rgb, false),
        };
        if let Some(p) = path {
            halo_stroke(pm, &p, rgb, width, dashed, None);
        }
        draw_text(
            pm,
            label,
            (x + pad + sample + gap, cy),
            s,
            Color::BLACK,
            Anchor::MiddleLeft,
            true,
        );
    }
}
