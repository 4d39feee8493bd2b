//! Line-plot views: the radial profile (kappa and enclosed mass against radius) and the QADP
//! convergence (objective, grid mass and `C` per layer against iteration).

use crate::render::{compose_grid, Axis, LinePlot, RenderError, Series, PALETTE};

use super::views::ViewPng;
use super::{AppError, Session};

/// One panel's size in pixels: 400 high gives the text two font units (readable at the
/// view's width); the panels are stacked in one column (they share the x axis in the
/// convergence view), so the image is as wide as one panel.
const PANEL_PX: (u32, u32) = (720, 400);
/// Gap between panels in pixels.
const GAP_PX: u32 = 8;

fn panel(title: &str, x: Axis, y: Axis, series: Vec<Series>) -> LinePlot {
    LinePlot {
        title: title.to_string(),
        x,
        y,
        series,
        width_px: PANEL_PX.0,
        height_px: PANEL_PX.1,
        ..LinePlot::default()
    }
}

fn compose(name: &str, plots: &[LinePlot]) -> Result<ViewPng, AppError> {
    let render = |e: RenderError| AppError::Run(format!("rendering {name}: {e}"));
    let panels = plots
        .iter()
        .map(|p| p.render_pixmap())
        .collect::<Result<Vec<_>, _>>()
        .map_err(render)?;
    let png = compose_grid(&panels, 1, GAP_PX)
        .map_err(render)?
        .encode_png()
        .map_err(|e| AppError::Run(format!("rendering {name}: {e}")))?;
    Ok(ViewPng {
        name: name.to_string(),
        png,
    })
}

impl Session {
    /// The radial profile about (0, 0): area-weighted mean kappa (`D_ls/D_s = 1`) per annulus and
    /// the projected mass inside each radius (Msun), both on log10 axes.
    pub fn radial_view(&self) -> Result<ViewPng, AppError> {
        let p = &self.result()?.products.profile;
        let kappa: Vec<(f64, f64)> = p
            .r_arcsec
            .iter()
            .copied()
            .zip(p.kappa.iter().copied())
            .collect();
        let mass: Vec<(f64, f64)> = p
            .r_edges_arcsec
            .iter()
            .copied()
            .zip(p.enclosed_mass_msun.iter().copied())
            .collect();
        compose(
            "radial-profile.png",
            &[
                panel(
                    "mean kappa in annuli",
                    Axis::linear("r [arcsec]"),
                    Axis::log("kappa"),
                    vec![Series::line("kappa", kappa, PALETTE[0])],
                ),
                panel(
                    "enclosed projected mass",
                    Axis::linear("r [arcsec]"),
                    Axis::log("M(<r) [Msun]"),
                    vec![Series::line("M(<r)", mass, PALETTE[1])],
                ),
            ],
        )
    }

    /// The QADP history: objective, grid mass (Msun) and `C` of every layer against iteration
    /// (iterations of refinement levels continue after the previous level's).
    pub fn convergence_view(&self) -> Result<ViewPng, AppError> {
        let r = self.result()?;
        let records = r
            .reconstruction
            .as_ref()
            .map(|x| x.convergence.as_slice())
            .unwrap_or(&[]);
        if records.is_empty() {
            return Err(AppError::Missing(
                "no convergence history (not a reconstruction)".into(),
            ));
        }
        let mut offset = 0.0;
        let mut last = (0usize, 0.0);
        let mut xs = Vec::with_capacity(records.len());
        for rec in records {
            if rec.level != last.0 {
                offset = last.1;
            }
            let x = offset + rec.iteration as f64;
            xs.push(x);
            last = (rec.level, x);
        }
        let series = |f: &dyn Fn(usize) -> f64| -> Vec<(f64, f64)> {
            (0..records.len()).map(|k| (xs[k], f(k))).collect()
        };
        let layers = records[0].c.len();
        let c_series: Vec<Series> = (0..layers)
            .map(|l| {
                let pts = series(&|k| records[k].c.get(l).copied().unwrap_or(f64::NAN));
                Series::line(format!("C{}", l + 1), pts, PALETTE[l % PALETTE.len()])
            })
            .collect();
        let mut plots = vec![
            panel(
                "objective",
                Axis::linear("iteration"),
                Axis::linear("objective"),
                vec![Series::line(
                    "",
                    series(&|k| records[k].objective),
                    PALETTE[0],
                )],
            ),
            panel(
                "grid mass",
                Axis::linear("iteration"),
                Axis::log("grid mass [Msun]"),
                vec![Series::line(
                    "",
                    series(&|k| records[k].grid_mass_msun),
                    PALETTE[1],
                )],
            ),
        ];
        if !c_series.is_empty() {
            plots.push(panel(
                "layer factors C",
                Axis::linear("iteration"),
                Axis::linear("C"),
                c_series,
            ));
        }
        compose("convergence.png", &plots)
    }
}
