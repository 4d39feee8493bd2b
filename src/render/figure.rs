//! The convergence figure: layout, map, axes, colour bar, overlays and legend.

use glam::DVec2;
use tiny_skia::{Color, Pixmap, Rect, Transform};

use super::axes::nice_ticks;
use super::colormap::{color_limits, value_rgb};
use super::font::{draw_text, fit, minus_signs, text_width, Anchor};
use super::layout::{text_scale, Layout, MIN_TEXT_SCALE};
use super::overlay::{below_height, draw_legend, draw_overlay, legend_entries, Key};
use super::paint::{color, frame, paint};
use super::{check_map, KappaPlotOptions, Overlay, RenderError};
use super::{ColorScale, LegendPlace};
use crate::map::{Map, MapGeometry};

/// Where the map lies in a figure of [`render_kappa_png`] (screen pixels, origin top-left),
/// e.g. to turn a click on the PNG into arcsec.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FigureFrame {
    /// PNG size in pixels.
    pub width: u32,
    pub height: u32,
    /// Left and top edges of the map area and its side, in pixels.
    pub map_left: f32,
    pub map_top: f32,
    pub map_side: f32,
    pub geometry: MapGeometry,
}

impl FigureFrame {
    /// Screen position of `p` (arcsec): `x = left + (p.x - x_min) / size * side`,
    /// `y = top + (y_max - p.y) / size * side` (+y up on screen).
    pub fn arcsec_to_screen(&self, p: DVec2) -> (f32, f32) {
        let g = &self.geometry;
        let half = g.size_arcsec / 2.0;
        let u = (p.x - (g.center.x - half)) / g.size_arcsec;
        let v = ((g.center.y + half) - p.y) / g.size_arcsec;
        let side = self.map_side as f64;
        (
            self.map_left + (u * side) as f32,
            self.map_top + (v * side) as f32,
        )
    }

    /// Arcsec under the screen point `(x, y)`; the inverse of [`Self::arcsec_to_screen`].
    pub fn screen_to_arcsec(&self, x: f32, y: f32) -> DVec2 {
        let g = &self.geometry;
        let half = g.size_arcsec / 2.0;
        let u = (x - self.map_left) as f64 / self.map_side as f64;
        let v = (y - self.map_top) as f64 / self.map_side as f64;
        DVec2::new(
            g.center.x - half + u * g.size_arcsec,
            g.center.y + half - v * g.size_arcsec,
        )
    }
}

struct Plan {
    layout: Layout,
    legend: Vec<(String, Key)>,
    limits: (f64, f64),
    x_ticks: Vec<(f64, String)>,
    y_ticks: Vec<(f64, String)>,
    cb_ticks: Vec<(f64, String)>,
}

fn plan(kappa: &Map, overlay: &Overlay, opts: &KappaPlotOptions) -> Result<Plan, RenderError> {
    opts.validate()?;
    check_map(kappa)?;
    let limits = color_limits(kappa, opts.scale, opts.vmin, opts.vmax)?;
    let g = kappa.geometry;
    let half = g.size_arcsec / 2.0;
    let ticks = |lo: f64, hi: f64| -> Vec<(f64, String)> {
        let t = nice_ticks(lo, hi, 5).into_iter();
        t.map(|(v, l)| (v, minus_signs(&l))).collect()
    };
    let x_ticks = ticks(g.center.x - half, g.center.x + half);
    let y_ticks = ticks(g.center.y - half, g.center.y + half);
    let cb_ticks = ticks(limits.0, limits.1);
    let s = text_scale(opts.map_pixels_on_screen);
    let widest = |t: &[(f64, String)]| t.iter().map(|(_, l)| text_width(l, s)).fold(0.0, f32::max);
    let mut layout = Layout::new(
        opts.map_pixels_on_screen,
        opts.title.is_some(),
        widest(&y_ticks),
        widest(&cb_ticks),
    );
    let legend = legend_entries(overlay, opts.show_caustics);
    if opts.legend == LegendPlace::Below {
        add_legend_below(&mut layout, &legend);
    }
    Ok(Plan {
        layout,
        legend,
        limits,
        x_ticks,
        y_ticks,
        cb_ticks,
    })
}

/// Makes room for a legend of `entries` under the map.
fn add_legend_below(layout: &mut Layout, entries: &[(String, Key)]) {
    let h = below_height(layout, entries, layout.legend_avail());
    if h > 0.0 {
        layout.height = (layout.legend_top + h).ceil() as u32;
    }
}

/// The [`FigureFrame`] of the figure [`render_kappa_png`] draws for `kappa` and `opts` with
/// an overlay without legend entries. The map's place does not depend on the overlay; the
/// figure's height does when the legend goes below it (see [`kappa_figure_frame_for`]).
pub fn kappa_figure_frame(
    kappa: &Map,
    opts: &KappaPlotOptions,
) -> Result<FigureFrame, RenderError> {
    kappa_figure_frame_for(kappa, &Overlay::default(), opts)
}

/// The [`FigureFrame`] of the figure [`render_kappa_png`] draws for exactly these inputs.
pub fn kappa_figure_frame_for(
    kappa: &Map,
    overlay: &Overlay,
    opts: &KappaPlotOptions,
) -> Result<FigureFrame, RenderError> {
    let l = plan(kappa, overlay, opts)?.layout;
    Ok(FigureFrame {
        width: l.width,
        height: l.height,
        map_left: l.left,
        map_top: l.top,
        map_side: l.m,
        geometry: kappa.geometry,
    })
}

/// A PNG figure of `kappa` (options: [`super::KappaPlotOptions`]): colour-mapped map with +x right, +y up,
/// axes in arcsec, colour bar ("κ" or "log₁₀ κ"), critical curves, points, a legend
/// (in the map's corner or under it, [`KappaPlotOptions::legend`]) and an optional title. The map occupies `opts.map_pixels_on_screen` pixels a side; colour
/// limits as in [`super::color_limits`].
pub fn render_kappa_png(
    kappa: &Map,
    overlay: &Overlay,
    opts: &KappaPlotOptions,
) -> Result<Vec<u8>, RenderError> {
    let Plan {
        layout,
        legend,
        limits,
        x_ticks,
        y_ticks,
        cb_ticks,
    } = plan(kappa, overlay, opts)?;
    let g = kappa.geometry;
    let s = layout.s;
    let mut pm = Pixmap::new(layout.width, layout.height).ok_or_else(|| {
        RenderError::Png(format!(
            "cannot allocate {} x {}",
            layout.width, layout.height
        ))
    })?;
    pm.fill(Color::WHITE);
    draw_map(&mut pm, kappa, &layout, opts, limits);
    draw_axes(&mut pm, &layout, &g, &x_ticks, &y_ticks);
    draw_colorbar(&mut pm, &layout, opts, limits, &cb_ticks);
    draw_overlay(&mut pm, &layout, &g, overlay, opts.show_caustics);
    draw_legend(&mut pm, &layout, &legend, opts.legend);
    if let Some(title) = &opts.title {
        // Centred over the map, within the figure: a long title is drawn smaller, down to
        // the smallest text scale, and only then shortened.
        let centre = layout.left + layout.m / 2.0;
        let room = 2.0 * centre.min(layout.width as f32 - centre) - 8.0;
        let full = text_width(title, s);
        let ts = if full > room {
            (s * room / full).max(MIN_TEXT_SCALE)
        } else {
            s
        };
        let text = fit(title, room, ts);
        let at = (centre, layout.pad());
        draw_text(
            &mut pm,
            &text,
            at,
            ts,
            Color::BLACK,
            Anchor::TopCenter,
            true,
        );
    }
    pm.encode_png().map_err(|e| RenderError::Png(e.to_string()))
}

/// Each screen pixel takes the colour of the map pixel under its centre (nearest neighbour).
fn draw_map(pm: &mut Pixmap, kappa: &Map, l: &Layout, opts: &KappaPlotOptions, limits: (f64, f64)) {
    let n = kappa.geometry.pixels;
    let (m, width) = (l.m as usize, pm.width() as usize);
    let (x0, y0) = (l.left as usize, l.top as usize);
    let data = pm.data_mut();
    for b in 0..m {
        let j = n - 1 - ((b as f64 + 0.5) * n as f64 / m as f64) as usize;
        for a in 0..m {
            let i = ((a as f64 + 0.5) * n as f64 / m as f64) as usize;
            let [r, g, bl] = value_rgb(kappa.data[j * n + i], opts.scale, limits, opts.colormap);
            let k = ((y0 + b) * width + x0 + a) * 4;
            data[k..k + 4].copy_from_slice(&[r, g, bl, 255]);
        }
    }
}

/// A tick: a `len` long line `w` pixels wide from `(x, y)` along `(dx, dy)`.
fn tick(pm: &mut Pixmap, (x, y): (f32, f32), (dx, dy): (f32, f32), len: f32, w: f32) {
    let (x, y) = (x.round(), y.round());
    let rect = if dx != 0.0 {
        Rect::from_xywh(
            if dx > 0.0 { x } else { x - len },
            y - (w / 2.0).floor(),
            len,
            w,
        )
    } else {
        Rect::from_xywh(
            x - (w / 2.0).floor(),
            if dy > 0.0 { y } else { y - len },
            w,
            len,
        )
    };
    if let Some(r) = rect {
        pm.fill_rect(r, &paint(Color::BLACK, false), Transform::identity(), None);
    }
}

fn draw_axes(
    pm: &mut Pixmap,
    l: &Layout,
    g: &MapGeometry,
    xt: &[(f64, String)],
    yt: &[(f64, String)],
) {
    let (s, ch, tk, gap, lw) = (l.s, l.ch(), l.tick(), l.gap(), l.line());
    frame(pm, l.left, l.top, l.m, l.m, lw);
    let bottom = l.top + l.m;
    for (v, label) in xt {
        let (x, _) = l.screen(g, DVec2::new(*v, g.center.y));
        tick(pm, (x, bottom), (0.0, 1.0), tk, lw);
        draw_text(
            pm,
            label,
            (x, bottom + tk + gap),
            s,
            Color::BLACK,
            Anchor::TopCenter,
            true,
        );
    }
    for (v, label) in yt {
        let (_, y) = l.screen(g, DVec2::new(g.center.x, *v));
        tick(pm, (l.left, y), (-1.0, 0.0), tk, lw);
        draw_text(
            pm,
            label,
            (l.left - tk - gap, y),
            s,
            Color::BLACK,
            Anchor::MiddleRight,
            true,
        );
    }
    let x_title_y = bottom + tk + gap + ch + 3.0 * gap;
    draw_text(
        pm,
        "x [arcsec]",
        (l.left + l.m / 2.0, x_title_y),
        s,
        Color::BLACK,
        Anchor::TopCenter,
        true,
    );
    let pad = l.pad();
    draw_text(
        pm,
        "y [arcsec]",
        (pad, l.top + l.m / 2.0),
        s,
        Color::BLACK,
        Anchor::TopCenter,
        false,
    );
}

fn draw_colorbar(
    pm: &mut Pixmap,
    l: &Layout,
    opts: &KappaPlotOptions,
    limits: (f64, f64),
    ticks: &[(f64, String)],
) {
    let (s, tk, gap, lw) = (l.s, l.tick(), l.gap(), l.line());
    let rows = l.m as usize;
    for r in 0..rows {
        let t = 1.0 - (r as f64 + 0.5) / rows as f64;
        let c = color(opts.colormap.rgb(t), 1.0);
        if let Some(rect) = Rect::from_xywh(l.cb_x, l.top + r as f32, l.cb_w, 1.0) {
            pm.fill_rect(rect, &paint(c, false), Transform::identity(), None);
        }
    }
    frame(pm, l.cb_x, l.top, l.cb_w, l.m, lw);
    let right = l.cb_x + l.cb_w;
    let mut widest: f32 = 0.0;
    for (v, label) in ticks {
        let y = l.top + l.m - ((v - limits.0) / (limits.1 - limits.0)) as f32 * l.m;
        tick(pm, (right, y), (1.0, 0.0), tk, lw);
        draw_text(
            pm,
            label,
            (right + tk + gap, y),
            s,
            Color::BLACK,
            Anchor::MiddleLeft,
            true,
        );
        widest = widest.max(text_width(label, s));
    }
    let default = if opts.scale == ColorScale::Log {
        "log_{10} κ"
    } else {
        "κ"
    };
    let label = opts.colorbar_label.as_deref().unwrap_or(default);
    let x = right + tk + gap + widest + 2.0 * gap;
    draw_text(
        pm,
        label,
        (x, l.top + l.m / 2.0),
        s,
        Color::BLACK,
        Anchor::TopCenter,
        false,
    );
}
