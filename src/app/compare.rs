//! "Compare with truth": a reconstruction's kappa next to the loaded model's (the true lens of
//! an example or of a playground scene) on one colour scale, and their difference on a
//! diverging one, with the data drawn over the difference: the mass is measured where the
//! images are and hardly anywhere else.

use crate::map::Map;
use crate::render::{
    compose_png_grid, render_kappa_png, ColorScale, Colormap, KappaPlotOptions, LegendPlace,
    Marker, Overlay, OverlayLines, LOG_RANGE,
};

use super::views::{arc_overlays, points, ViewOptions, ViewPng, OBSERVED_RGB};
use super::{AppError, Session};

/// Map side of each of the three panels on screen, pixels.
const PANEL_MAP_PX: u32 = 420;
/// Gap between the panels, pixels.
const PANEL_GAP_PX: u32 = 12;
/// The difference's colour limits are `+-` this quantile of `|difference|` (the cusp of a
/// singular truth would otherwise take the whole scale).
const DIFFERENCE_QUANTILE: f64 = 0.99;
/// Tangential critical curves of the true lens on its panel: the red of the reconstruction's.
const TRUTH_CURVE_RGB: [u8; 3] = [255, 40, 40];

fn render(e: impl std::fmt::Display) -> AppError {
    AppError::Run(format!("rendering the comparison: {e}"))
}

impl Session {
    /// Three panels: the reconstruction's kappa, the loaded model's (both log10, one colour
    /// scale, each with its critical curves at the result's source redshift) and
    /// reconstruction minus model (linear, diverging, symmetric limits), with the observed
    /// images and arc pixels over the difference. Both maps are on the model's grid over the
    /// reconstruction's map ([`Session::model_profile`] explains when a model is compared).
    /// Of the options' sizes only [`ViewOptions::figure_scale`] applies: the panels, the gaps
    /// and their text grow with it.
    pub fn compare_view(&self, opts: &ViewOptions) -> Result<ViewPng, AppError> {
        let scale = opts.checked_figure_scale()?;
        let scaled = |px: u32| (px as f32 * scale).round().max(1.0) as u32;
        let (panel_px, gap_px) = (scaled(PANEL_MAP_PX), scaled(PANEL_GAP_PX));
        let r = self.result()?;
        let Some((name, truth)) = self.model_kappa(r)? else {
            return Err(AppError::Missing(
                self.model_not_compared(r).unwrap_or_else(|| {
                    "load a model file (the true lens) and reconstruct to compare".to_string()
                }),
            ));
        };
        let ours_full = &r.products().maps.kappa;
        let ours = Map::from_fn(truth.geometry, |p| ours_full.sample(p));
        let diff = Map {
            geometry: truth.geometry,
            data: ours
                .data
                .iter()
                .zip(&truth.data)
                .map(|(a, b)| a - b)
                .collect(),
        };
        let vmax = ours.min_max().1.max(truth.min_max().1);
        let (vmin, vmax) = (vmax / LOG_RANGE * 10.0, vmax);
        let truth_label = if opts.model_is_truth {
            "the true lens".to_string()
        } else {
            name.clone()
        };
        let base = |title: String| KappaPlotOptions {
            scale: ColorScale::Log,
            vmin: Some(vmin),
            vmax: Some(vmax),
            map_pixels_on_screen: panel_px,
            title: Some(title),
            legend: LegendPlace::Below,
            ..KappaPlotOptions::default()
        };
        let z_s = r.products().curves.z_source;
        let ours_png = render_kappa_png(
            &ours,
            &Overlay {
                curves: Some(&r.products().curves),
                ..Overlay::default()
            },
            &base(format!("reconstruction (curves at z_s = {z_s})")),
        )
        .map_err(render)?;
        let mut truth_overlay = Overlay::default();
        if let Some(c) = self.model_curves(r)? {
            truth_overlay.lines.push(OverlayLines {
                label: "tangential critical curve".to_string(),
                color: TRUTH_CURVE_RGB,
                dashed: false,
                lines: c.tangential,
            });
        }
        let truth_png =
            render_kappa_png(&truth, &truth_overlay, &base(truth_label.clone())).map_err(render)?;
        let mut abs: Vec<f64> = diff.data.iter().map(|v| v.abs()).collect();
        abs.sort_by(f64::total_cmp);
        let k = ((abs.len() as f64 - 1.0) * DIFFERENCE_QUANTILE) as usize;
        let limit = abs.get(k).copied().filter(|v| *v > 0.0).unwrap_or(1.0);
        let mut diff_overlay = Overlay::default();
        diff_overlay
            .points
            .extend(arc_overlays(&r.marks.arcs, r.marks.arc_pixel_mas));
        diff_overlay.points.push(points(
            "observed images",
            OBSERVED_RGB,
            Marker::Plus,
            r.marks.observed.clone(),
        ));
        let diff_png = render_kappa_png(
            &diff,
            &diff_overlay,
            &KappaPlotOptions {
                scale: ColorScale::Linear,
                vmin: Some(-limit),
                vmax: Some(limit),
                colormap: Colormap::Diverging,
                map_pixels_on_screen: panel_px,
                title: Some(format!("reconstruction - {truth_label} (red: too much)")),
                colorbar_label: Some("kappa difference".to_string()),
                legend: LegendPlace::Below,
                ..KappaPlotOptions::default()
            },
        )
        .map_err(render)?;
        let png = compose_png_grid(&[ours_png, truth_png, diff_png], 3, gap_px).map_err(render)?;
        Ok(ViewPng {
            name: "compare-with-truth.png".to_string(),
            png,
        })
    }
}
