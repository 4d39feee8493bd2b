//! The figures of `wslap paper` (PNG, tiny-skia), after the paper's figures 5 to 10: mass maps
//! with critical curves per case (the truth's dashed over them) next to the truth; radial profiles and their relative errors;
//! the soft (dark) component recovered vs true; grid mass, galaxy mass and C vs iteration; the
//! source-position error vs iteration; the deflection-error map.

use crate::map::Map;
use crate::render::{
    compose_png_grid, render_kappa_png, Axis, AxisScale, ColorScale, KappaPlotOptions, LinePlot,
    LineStyle, Marker, Overlay, OverlayLines, OverlayPoints, Reference, Series, PALETTE,
};

use super::metrics::quantile;
use super::{Case, PaperError, PaperRun};

/// One figure: its file name and PNG bytes.
#[derive(Debug, Clone)]
pub struct Figure {
    pub file_name: &'static str,
    pub png: Vec<u8>,
}

/// Side of each map panel on screen, pixels.
const MAP_PANEL_PX: u32 = 384;
/// Size of each line-plot panel, pixels.
const PLOT_W: u32 = 720;
const PLOT_H: u32 = 360;
/// Gap between composed panels, pixels.
const GAP_PX: u32 = 12;
/// Lowest kappa shown on the log maps (the outskirts of the field sit near 0.1).
const KAPPA_LOG_MIN: f64 = 0.05;
/// The truth's critical curves over each case's mass map: magenta, dashed (no other colour of
/// the figure is near it).
pub const TRUE_CURVE_RGB: [u8; 3] = [255, 0, 255];

fn fig_err(figure: &'static str) -> impl Fn(crate::render::RenderError) -> PaperError {
    move |e| PaperError::Figure {
        figure,
        message: e.to_string(),
    }
}

/// Every figure of a paper run (`convergence.png` only when the convergence study ran).
pub fn render_figures(run: &PaperRun) -> Result<Vec<Figure>, PaperError> {
    let mut figures = vec![
        Figure {
            file_name: "maps.png",
            png: mass_maps(run)?,
        },
        Figure {
            file_name: "profiles.png",
            png: profiles(run)?,
        },
        Figure {
            file_name: "soft-component.png",
            png: soft_component(run)?,
        },
        Figure {
            file_name: "deflection-error.png",
            png: deflection_error(run)?,
        },
    ];
    if run.config.convergence {
        figures.push(Figure {
            file_name: "convergence.png",
            png: convergence(run)?,
        });
    }
    Ok(figures)
}

/// Kappa (log) with the critical curves at z_s = 3, per case (with the truth's curves dashed)
/// and the truth, on one colour scale.
fn mass_maps(run: &PaperRun) -> Result<Vec<u8>, PaperError> {
    let vmax = run.truth.maps.kappa.min_max().1;
    let opts = |title: String| KappaPlotOptions {
        scale: ColorScale::Log,
        vmin: Some(KAPPA_LOG_MIN),
        vmax: Some(vmax),
        map_pixels_on_screen: MAP_PANEL_PX,
        title: Some(title),
        ..KappaPlotOptions::default()
    };
    // The truth's curves over each case, dashed, to compare in place.
    let true_curves = OverlayLines {
        label: "true curves".to_string(),
        color: TRUE_CURVE_RGB,
        dashed: true,
        lines: run
            .truth
            .curves
            .tangential
            .iter()
            .chain(&run.truth.curves.radial)
            .cloned()
            .collect(),
    };
    let mut pngs = Vec::new();
    for c in &run.cases {
        let overlay = Overlay {
            lines: vec![true_curves.clone()],
            curves: Some(&c.reconstruction.products.curves),
            points: Vec::new(),
            labels: Vec::new(),
        };
        pngs.push(
            render_kappa_png(
                &c.reconstruction.products.maps.kappa,
                &overlay,
                &opts(c.case.label().to_string()),
            )
            .map_err(fig_err("maps"))?,
        );
    }
    let overlay = Overlay {
        lines: Vec::new(),
        curves: Some(&run.truth.curves),
        points: vec![arc_points(run)],
        labels: Vec::new(),
    };
    pngs.push(
        render_kappa_png(
            &run.truth.maps.kappa,
            &overlay,
            &opts("truth (curves at z_s = 3)".to_string()),
        )
        .map_err(fig_err("maps"))?,
    );
    compose_png_grid(&pngs, 2, GAP_PX).map_err(fig_err("maps"))
}

/// One marker per observed image (the centroid of its arc pixels): thousands of pixel
/// markers would hide the map.
fn arc_points(run: &PaperRun) -> OverlayPoints {
    OverlayPoints {
        label: "images".to_string(),
        color: [255, 255, 255],
        positions_arcsec: run
            .simulation
            .arcs
            .systems
            .iter()
            .flat_map(|s| s.images.iter())
            .filter(|pixels| !pixels.is_empty())
            .map(|pixels| pixels.iter().copied().sum::<glam::DVec2>() / pixels.len() as f64)
            .collect(),
        marker: Marker::Plus,
    }
}

fn style(case: Case) -> (LineStyle, [u8; 3]) {
    match case {
        Case::NoGalaxies => (LineStyle::Solid, PALETTE[1]),
        Case::GalaxyModel => (LineStyle::Dotted, PALETTE[2]),
        Case::GalaxyTrue => (LineStyle::Dashed, PALETTE[3]),
    }
}

fn series(
    label: &str,
    xs: &[f64],
    ys: &[f64],
    style: LineStyle,
    color: [u8; 3],
    width: f32,
) -> Series {
    Series {
        label: label.to_string(),
        points: xs.iter().copied().zip(ys.iter().copied()).collect(),
        color,
        style,
        width,
        markers: false,
    }
}

fn axis(label: &str, scale: AxisScale) -> Axis {
    Axis {
        label: label.to_string(),
        scale,
        range: None,
    }
}

/// Radial kappa profiles and `(rec - true)/true` (the paper's figure 6).
fn profiles(run: &PaperRun) -> Result<Vec<u8>, PaperError> {
    let r = &run.truth_profile.r_arcsec;
    let mut top = vec![series(
        "truth",
        r,
        &run.truth_profile.kappa,
        LineStyle::Solid,
        [0, 0, 0],
        3.0,
    )];
    let mut bottom = Vec::new();
    for c in &run.cases {
        let (st, color) = style(c.case);
        top.push(series(c.case.label(), r, &c.profile.kappa, st, color, 2.0));
        bottom.push(series(
            c.case.label(),
            r,
            &c.report.profile_rel_error,
            st,
            color,
            2.0,
        ));
    }
    let top = LinePlot {
        title: "Radial profile (mean kappa in annuli, D_ls/D_s = 1)".to_string(),
        x: axis("r (arcsec)", AxisScale::Linear),
        y: axis("kappa", AxisScale::Log),
        series: top,
        references: vec![],
        width_px: PLOT_W,
        height_px: PLOT_H,
    };
    let bottom = LinePlot {
        title: "Relative error (reconstruction - truth) / truth".to_string(),
        x: axis("r (arcsec)", AxisScale::Linear),
        y: axis("relative error", AxisScale::Linear),
        series: bottom,
        references: vec![Reference {
            value: 0.0,
            label: "0".to_string(),
            color: [120, 120, 120],
        }],
        width_px: PLOT_W,
        height_px: PLOT_H,
    };
    let pngs = [
        top.render_png().map_err(fig_err("profiles"))?,
        bottom.render_png().map_err(fig_err("profiles"))?,
    ];
    compose_png_grid(&pngs, 1, GAP_PX).map_err(fig_err("profiles"))
}

/// Share of the true soft component's map pixels below the top of the colour scale: the halo's
/// cusp (kappa ~ 10 in a few central pixels) would otherwise take the whole scale and leave
/// the halo's shape and its dark clump in one dark colour.
const SOFT_SCALE_QUANTILE: f64 = 0.995;

/// The soft component: true smooth halo vs the grid cells of case (ii), same linear colour scale
/// (the paper's figure 7), topped at the [`SOFT_SCALE_QUANTILE`] of the truth's pixels.
fn soft_component(run: &PaperRun) -> Result<Vec<u8>, PaperError> {
    let lo = run.truth_soft_kappa.min_max().0;
    let mut sorted = run.truth_soft_kappa.data.clone();
    sorted.sort_by(f64::total_cmp);
    let hi = quantile(&sorted, SOFT_SCALE_QUANTILE);
    let opts = |title: &str| KappaPlotOptions {
        scale: ColorScale::Linear,
        vmin: Some(lo.max(0.0)),
        vmax: Some(hi),
        map_pixels_on_screen: MAP_PANEL_PX,
        title: Some(title.to_string()),
        colorbar_label: Some("kappa (soft, cusp saturated)".to_string()),
        ..KappaPlotOptions::default()
    };
    let empty = Overlay::default();
    let mut pngs =
        vec![
            render_kappa_png(&run.truth_soft_kappa, &empty, &opts("true soft component"))
                .map_err(fig_err("soft"))?,
        ];
    if let Some(c) = run.cases.iter().find(|c| c.case == Case::GalaxyModel) {
        pngs.push(
            render_kappa_png(&c.soft_kappa, &empty, &opts("grid cells, case (ii)"))
                .map_err(fig_err("soft"))?,
        );
    }
    compose_png_grid(&pngs, 2, GAP_PX).map_err(fig_err("soft"))
}

/// Grid mass, galaxy mass (C x the true galaxy mass) and C vs iteration, and the source-position
/// error vs iteration (the paper's figure 8).
fn convergence(run: &PaperRun) -> Result<Vec<u8>, PaperError> {
    let conv = &run.report.convergence;
    let it: Vec<f64> = conv.iterations.iter().map(|&i| i.max(1) as f64).collect();
    let m_gal = run.simulation.galaxy_mass_msun;
    let runs = [
        (
            "reasonable start",
            &conv.reasonable,
            LineStyle::Dotted,
            PALETTE[2],
        ),
        ("bad start", &conv.bad_start, LineStyle::Dashed, PALETTE[3]),
        (
            "no galaxies",
            &conv.no_galaxies,
            LineStyle::DashDot,
            PALETTE[1],
        ),
    ];
    let mut mass = Vec::new();
    let mut cs = Vec::new();
    let mut beta = Vec::new();
    for (label, s, st, color) in runs {
        mass.push(series(
            &format!("grid, {label}"),
            &it,
            &s.grid_mass_msun,
            st,
            color,
            2.0,
        ));
        if !s.c.is_empty() {
            let galaxies: Vec<f64> = s.c.iter().map(|c| c * m_gal).collect();
            mass.push(series(
                &format!("galaxies, {label}"),
                &it,
                &galaxies,
                st,
                PALETTE[5],
                1.5,
            ));
            cs.push(series(label, &it, &s.c, st, color, 2.0));
        }
        beta.push(series(label, &it, &s.beta_error, st, color, 2.0));
    }
    let plot = |title: &str, y: Axis, series: Vec<Series>, references: Vec<Reference>| LinePlot {
        title: title.to_string(),
        x: axis("QADP iteration", AxisScale::Log),
        y,
        series,
        references,
        width_px: PLOT_W,
        height_px: PLOT_H,
    };
    let pngs = [
        plot(
            "Mass of the grid and of the galaxies (C x true galaxy mass)",
            axis("mass (Msun)", AxisScale::Log),
            mass,
            vec![
                Reference {
                    value: run.simulation.soft_mass_msun,
                    label: "Soft mass (true)".to_string(),
                    color: [0, 0, 0],
                },
                Reference {
                    value: m_gal,
                    label: "Galaxies (true)".to_string(),
                    color: [110, 110, 110],
                },
            ],
        )
        .render_png()
        .map_err(fig_err("convergence"))?,
        plot(
            "Galaxy factor C (truth: 1)",
            axis("C", AxisScale::Linear),
            cs,
            vec![Reference {
                value: 1.0,
                label: "true C".to_string(),
                color: [0, 0, 0],
            }],
        )
        .render_png()
        .map_err(fig_err("convergence"))?,
        plot(
            "Source-position error (paper eq. 8)",
            axis("sum |beta_rec - beta_true|^2 (arcsec^2)", AxisScale::Log),
            beta,
            vec![],
        )
        .render_png()
        .map_err(fig_err("convergence"))?,
    ];
    compose_png_grid(&pngs, 1, GAP_PX).map_err(fig_err("convergence"))
}

/// `|alpha_true - alpha_rec|` at z_s = 3 for case (ii), with the arc pixels (the paper's
/// figure 10).
fn deflection_error(run: &PaperRun) -> Result<Vec<u8>, PaperError> {
    let Some(c) = run.cases.iter().find(|c| c.case == Case::GalaxyModel) else {
        return Err(PaperError::Figure {
            figure: "deflection-error",
            message: "case (ii) was not run".to_string(),
        });
    };
    let map: &Map = &c.deflection_error.map;
    let opts = KappaPlotOptions {
        scale: ColorScale::Linear,
        vmin: Some(0.0),
        vmax: Some((3.0 * c.deflection_error.p90_arcsec).max(1.0)),
        map_pixels_on_screen: 2 * MAP_PANEL_PX,
        title: Some(format!(
            "Deflection error, case (ii), z_s = 3: median {:.2}\", p90 {:.2}\" inside r < {:.0}\"",
            c.deflection_error.median_arcsec,
            c.deflection_error.p90_arcsec,
            run.region.radius_arcsec
        )),
        colorbar_label: Some("|alpha_true - alpha_rec| (arcsec)".to_string()),
        ..KappaPlotOptions::default()
    };
    let overlay = Overlay {
        lines: Vec::new(),
        curves: None,
        points: vec![arc_points(run)],
        labels: Vec::new(),
    };
    render_kappa_png(map, &overlay, &opts).map_err(fig_err("deflection-error"))
}
