//! Line-plot views: the radial profile (kappa and enclosed mass against radius) and the QADP
//! convergence (objective, grid mass and `C` per layer against iteration).

use std::cell::RefCell;
use std::hash::{DefaultHasher, Hash, Hasher};

use glam::DVec2;

use crate::cosmology::LensPlane;
use crate::curves::{critical_curves, Polyline};
use crate::map::LensMaps;
use crate::map::MapGeometry;
use crate::radial::{radial_profile, RadialBins, RadialProfile};
use crate::render::{
    compose_grid, Axis, LinePlot, LineStyle, Reference, RenderError, Series, PALETTE,
};

use super::data::ModelLens;
use super::run::{RunKind, SessionResult};
use super::views::{ViewOptions, ViewPng};
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

/// The panels `plots` stacked, each drawn [`ViewOptions::figure_scale`] times larger.
fn compose(name: &str, plots: &[LinePlot], opts: &ViewOptions) -> Result<ViewPng, AppError> {
    let k = opts.checked_figure_scale()?;
    let render = |e: RenderError| AppError::Run(format!("rendering {name}: {e}"));
    let panels = plots
        .iter()
        .map(|p| p.scaled(k).render_pixmap())
        .collect::<Result<Vec<_>, _>>()
        .map_err(render)?;
    let gap = (GAP_PX as f32 * k).round() as u32;
    let png = compose_grid(&panels, 1, gap)
        .map_err(render)?
        .encode_png()
        .map_err(|e| AppError::Run(format!("rendering {name}: {e}")))?;
    Ok(ViewPng {
        name: name.to_string(),
        png,
    })
}

/// Pixels per side, at most, of the model's maps behind its profile and critical curves. The
/// profile view's bins are two product pixels wide, so at 256 product pixels a 128-pixel map
/// has one pixel per bin; against a 512-pixel map of the built-in example's true lens its
/// profile differs by at most 1.2% in kappa and 0.8% in enclosed mass (a line width on the
/// plot), for a quarter of the cost of 256 pixels.
const MODEL_MAPS_MAX_PIXELS: usize = 128;

/// A model file's name and its profile.
pub type NamedProfile = (String, RadialProfile);

/// A model file's critical curves, in a reconstruction's frame.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelCurves {
    /// The model file's name.
    pub name: String,
    pub tangential: Vec<Polyline>,
    pub radial: Vec<Polyline>,
}

/// The loaded model file's maps over a reconstruction's map.
#[derive(Debug)]
pub(crate) struct ModelMaps {
    name: String,
    maps: LensMaps,
    /// The reconstruction's origin in the model's frame (the maps are centred on the
    /// reconstruction's map centre, in the model's frame).
    origin: DVec2,
    /// The model's own lens plane (its `z_lens` may differ a little from the
    /// reconstruction's: see [`MODEL_PLANE_TOLERANCE`]).
    plane: LensPlane,
    /// The model's critical curves at the last distance ratio asked for, in the
    /// reconstruction's frame.
    curves: RefCell<Option<(f64, ModelCurves)>>,
}

/// The last model maps computed, keyed by a hash of the model file's name and text and of the
/// maps' geometry, so that switching views, hovering, redrawing and the next reconstruction of
/// the same field do not compute them again (a model of many halos takes a noticeable part of a
/// second).
#[derive(Debug, Default)]
pub(crate) struct ModelCache {
    maps: RefCell<Option<(u64, ModelMaps)>>,
    /// How many times maps were computed.
    computed: std::cell::Cell<usize>,
}

/// Points `(x, y)` of a plotted line.
pub type Points = Vec<(f64, f64)>;

/// The profile's `(r, kappa)` and `(r, M(<r))` points.
fn profile_points(p: &RadialProfile) -> (Points, Points) {
    let kappa = p.r_arcsec.iter().copied().zip(p.kappa.iter().copied());
    let mass = p.r_edges_arcsec.iter().copied();
    let mass = mass.zip(p.enclosed_mass_msun.iter().copied());
    (kappa.collect(), mass.collect())
}

/// `(r, ours / theirs - 1)` of a reconstruction's profile against a model's in the same bins:
/// the mean kappa per annulus and the mass inside each radius. Radii where the model has no
/// positive value are left out.
pub fn profile_relative_differences(
    ours: &RadialProfile,
    model: &RadialProfile,
) -> (Points, Points) {
    let rel = |r: &[f64], a: &[f64], b: &[f64]| -> Points {
        r.iter()
            .zip(a.iter().zip(b))
            .filter(|(_, (_, &b))| b > 0.0)
            .map(|(&r, (&a, &b))| (r, a / b - 1.0))
            .collect()
    };
    (
        rel(&ours.r_arcsec, &ours.kappa, &model.kappa),
        rel(
            &ours.r_edges_arcsec,
            &ours.enclosed_mass_msun,
            &model.enclosed_mass_msun,
        ),
    )
}

impl Session {
    /// The radial profile about (0, 0): area-weighted mean kappa (`D_ls/D_s = 1`) per annulus and
    /// the projected mass inside each radius (Msun), both on log10 axes. Over a reconstruction,
    /// the loaded model file's profile in the same bins, dashed (see [`Self::model_profile`]),
    /// and a third panel with their relative differences
    /// ([`profile_relative_differences`]). Of `opts` only [`ViewOptions::figure_scale`] applies.
    pub fn radial_view(&self, opts: &ViewOptions) -> Result<ViewPng, AppError> {
        let result = self.result()?;
        let (kappa, mass) = profile_points(&result.products().profile);
        let (mut kappa_series, mut mass_series) = match result.kind {
            RunKind::Reconstruct => (
                vec![Series::line("reconstruction", kappa, PALETTE[0])],
                vec![Series::line("reconstruction", mass, PALETTE[0])],
            ),
            _ => (
                vec![Series::line("kappa", kappa, PALETTE[0])],
                vec![Series::line("M(<r)", mass, PALETTE[1])],
            ),
        };
        let mut difference = None;
        if let Some((name, model)) = self.model_profile(result)? {
            let (kappa, mass) = profile_points(&model);
            let dashed = |points| Series {
                style: LineStyle::Dashed,
                ..Series::line(model_name(opts, &name), points, PALETTE[1])
            };
            kappa_series.push(dashed(kappa));
            mass_series.push(dashed(mass));
            // How far the reconstruction is from the model, radius by radius: the paper's
            // profile error.
            let (kappa, mass) = profile_relative_differences(&result.products().profile, &model);
            let mut plot = panel(
                &format!("reconstruction / {} - 1", model_name(opts, &name)),
                Axis::linear("r [arcsec]"),
                Axis::linear("relative difference"),
                vec![
                    Series::line("mean kappa in annuli", kappa, PALETTE[0]),
                    Series::line("M(<r)", mass, PALETTE[2]),
                ],
            );
            plot.references.push(Reference {
                value: 0.0,
                label: "equal".to_string(),
                color: [110, 110, 110],
            });
            difference = Some(plot);
        }
        let mut plots = vec![
            panel(
                "mean kappa in annuli",
                Axis::linear("r [arcsec]"),
                Axis::log("kappa"),
                kappa_series,
            ),
            panel(
                "enclosed projected mass",
                Axis::linear("r [arcsec]"),
                Axis::log("M(<r) [Msun]"),
                mass_series,
            ),
        ];
        plots.extend(difference);
        compose("radial-profile.png", &plots, opts)
    }

    /// The radial profile of the loaded model file (the true lens of the built-in examples) in
    /// the bins of a reconstruction's profile, about the same sky position, with the file's
    /// name; `None` for other results, without a model file, or when the model's lens plane
    /// is not the reconstruction's (another cosmology, or a `z_lens` farther than
    /// [`MODEL_PLANE_TOLERANCE`]): its kappa and masses would not compare. Its masses are
    /// those of its own plane. When both frames have a sky reference the model's map is centred on the
    /// reconstruction's origin (the small rotation between the two tangent planes is ignored).
    /// The model's map has at most `MODEL_MAPS_MAX_PIXELS` per side.
    pub fn model_profile(&self, result: &SessionResult) -> Result<Option<NamedProfile>, AppError> {
        self.with_model_maps(result, |m| {
            let bins = RadialBins::Edges(result.products().profile.r_edges_arcsec.clone());
            // Masses on the model's own plane: the same whatever small z_lens difference.
            let profile = radial_profile(&m.maps.kappa, m.origin, &bins, &m.plane)
                .map_err(|e| AppError::Run(format!("{}: {e}", m.name)))?;
            Ok((m.name.clone(), profile))
        })
    }

    /// The loaded model file's tangential and radial critical curves at the result's source
    /// redshift, in the reconstruction's frame, with the file's name; `None` as for
    /// [`Self::model_profile`]. Traced on the model's maps (at most `MODEL_MAPS_MAX_PIXELS`
    /// per side), once per source redshift.
    pub fn model_curves(&self, result: &SessionResult) -> Result<Option<ModelCurves>, AppError> {
        self.with_model_maps(result, |m| {
            // The model's own D_ls / D_s at the result's source redshift.
            let z_s = result.products().curves.z_source;
            let f = m
                .plane
                .distance_ratio(z_s)
                .unwrap_or(result.products().distance_ratio);
            let mut cached = m.curves.borrow_mut();
            if !matches!(&*cached, Some((g, _)) if *g == f) {
                let curves = critical_curves(&m.maps, f, z_s, None);
                let shift = |lines: Vec<Polyline>| -> Vec<Polyline> {
                    let moved = lines
                        .into_iter()
                        .map(|l| l.into_iter().map(|p| p - m.origin).collect());
                    moved.collect()
                };
                let curves = ModelCurves {
                    name: m.name.clone(),
                    tangential: shift(curves.tangential),
                    radial: shift(curves.radial),
                };
                *cached = Some((f, curves));
            }
            Ok(cached.as_ref().expect("just computed").1.clone())
        })
    }

    /// The loaded model file's kappa (`D_ls/D_s = 1`) over a reconstruction's map, in the
    /// reconstruction's frame, with the file's name; `None` as for [`Self::model_profile`].
    /// At most `MODEL_MAPS_MAX_PIXELS` per side (the cached maps).
    pub(crate) fn model_kappa(
        &self,
        result: &SessionResult,
    ) -> Result<Option<(String, crate::map::Map)>, AppError> {
        self.with_model_maps(result, |m| {
            let mut kappa = m.maps.kappa.clone();
            kappa.geometry.center -= m.origin;
            Ok((m.name.clone(), kappa))
        })
    }

    /// Why the loaded model file is not compared with `result` (a reconstruction): it cannot be
    /// built (a Lenstool model without its member catalogue) or its lens plane is not the
    /// reconstruction's; `None` when it is compared, or when there is nothing to compare.
    pub fn model_not_compared(&self, result: &SessionResult) -> Option<String> {
        self.model_comparison(result)?.err()
    }

    /// What the caption says of the loaded model file over `result` (a reconstruction): why it
    /// is not compared ([`Self::model_not_compared`]), or, when it is compared although its
    /// `z_lens` differs a little from the reconstruction's, that it is compared at its own.
    pub fn model_note(&self, result: &SessionResult) -> Option<String> {
        let theirs = match self.model_comparison(result)? {
            Err(why) => return Some(why),
            Ok(plane) => plane,
        };
        let (name, ours) = (&self.data.model.as_ref()?.name, result.products().plane);
        (theirs.z_lens != ours.z_lens).then(|| {
            format!(
                "{name} is compared at its own z_lens = {} (the reconstruction's is {}: their \
                 distances to the lens differ by {:.1}%)",
                theirs.z_lens,
                ours.z_lens,
                100.0 * plane_mismatch(&theirs, &ours)
            )
        })
    }

    /// Whether the loaded model file is compared with `result`: its lens plane when it is, why
    /// not (with the file's name) when it is not; `None` when there is nothing to compare (not
    /// a reconstruction, or no model file).
    fn model_comparison(&self, result: &SessionResult) -> Option<Result<LensPlane, String>> {
        let (RunKind::Reconstruct, Some(file)) = (result.kind, &self.data.model) else {
            return None;
        };
        let why = match self.data.model_lens(&self.settings.par_options()) {
            Err(e) => e.to_string(),
            Ok(None) => return None,
            Ok(Some(model)) => match model_frame(result, &model) {
                Ok(_) => return Some(Ok(model.plane)),
                Err(why) => why,
            },
        };
        Some(Err(format!("{} is not compared: {why}", file.name)))
    }

    /// Before a reconstruction: when images or arcs and a model file are loaded and the
    /// model's `z_lens` is farther from the settings' than [`MODEL_PLANE_TOLERANCE`] allows
    /// (a reconstruction would not be compared with it), a sentence that says so and what to
    /// set; else `None`.
    pub fn model_z_lens_note(&self) -> Option<String> {
        let d = &self.data;
        if d.images.is_none() && d.arcs.is_none() {
            return None;
        }
        let name = &d.model.as_ref()?.name;
        let z = d.model_z_lens(&self.settings.par_options())?;
        let ours = self.settings.lens_plane().ok()?;
        let theirs = LensPlane::new(ours.cosmology, z).ok()?;
        (plane_mismatch(&theirs, &ours) > MODEL_PLANE_TOLERANCE).then(|| {
            format!(
                "{name} is at z_lens = {z} and the settings at {}: set z_lens to {z} if the \
                 images are of its cluster (else the model is not compared)",
                ours.z_lens
            )
        })
    }

    /// How many times this session computed the loaded model's maps (they are kept for the next
    /// result over the same field: a second reconstruction does not compute them again).
    pub fn model_maps_computed(&self) -> usize {
        self.model_maps.computed.get()
    }

    /// Calls `f` with the loaded model's maps over `result` (computed on first use, then
    /// cached); `None` when there are none to compare (see [`Self::model_profile`]).
    fn with_model_maps<T>(
        &self,
        result: &SessionResult,
        f: impl FnOnce(&ModelMaps) -> Result<T, AppError>,
    ) -> Result<Option<T>, AppError> {
        let (RunKind::Reconstruct, Some(file)) = (result.kind, &self.data.model) else {
            return Ok(None);
        };
        // A model that cannot be built (a Lenstool model without its member catalogue) is not
        // drawn; forward mode says why.
        let Ok(Some(model)) = self.data.model_lens(&self.settings.par_options()) else {
            return Ok(None);
        };
        let Ok((origin, geometry)) = model_frame(result, &model) else {
            return Ok(None);
        };
        let mut hasher = DefaultHasher::new();
        (&file.name, &file.text, geometry.pixels).hash(&mut hasher);
        // A Lenstool model's members come from the member catalogue.
        self.data
            .members
            .as_ref()
            .map(|m| &m.text)
            .hash(&mut hasher);
        for v in [geometry.center.x, geometry.center.y, geometry.size_arcsec] {
            v.to_bits().hash(&mut hasher);
        }
        let key = hasher.finish();
        let fresh = matches!(&*self.model_maps.maps.borrow(), Some((k, _)) if *k == key);
        if !fresh {
            let maps = ModelMaps {
                name: file.name.clone(),
                maps: LensMaps::from_lens(&model.lens, geometry),
                origin,
                plane: model.plane,
                curves: RefCell::new(None),
            };
            *self.model_maps.maps.borrow_mut() = Some((key, maps));
            self.model_maps
                .computed
                .set(self.model_maps.computed.get() + 1);
        }
        let cache = self.model_maps.maps.borrow();
        let (_, maps) = cache.as_ref().expect("just filled");
        f(maps).map(Some)
    }

    /// The QADP history: objective, grid mass (Msun) and `C` of every layer against iteration
    /// (iterations of refinement levels continue after the previous level's). Of `opts` only
    /// [`ViewOptions::figure_scale`] applies.
    pub fn convergence_view(&self, opts: &ViewOptions) -> Result<ViewPng, AppError> {
        let r = self.result()?;
        let records = r
            .reconstruction()
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
        let levels: Vec<usize> = records.iter().map(|r| r.level).collect();
        let objectives: Vec<f64> = records.iter().map(|r| r.objective).collect();
        let decrease = objective_decrease(&xs, &levels, &objectives);
        let objective_panel = if decrease.iter().any(|&(_, d)| d > 0.0) {
            panel(
                "objective decrease per iteration",
                Axis::linear("iteration"),
                Axis::log("decrease per iteration"),
                vec![Series::line("", decrease, PALETTE[0])],
            )
        } else {
            panel(
                "objective",
                Axis::linear("iteration"),
                Axis::linear("objective"),
                vec![Series::line("", series(&|k| objectives[k]), PALETTE[0])],
            )
        };
        let mut plots = vec![
            objective_panel,
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
        compose("convergence.png", &plots, opts)
    }
}

/// How fast the objective still falls: between consecutive reports of one refinement level
/// (a new level is a new problem), the decrease divided by the iterations between them, at the
/// later report's iteration `x`. On a log axis this shows the slow late progress that a linear
/// axis of the objective flattens into a line; a rise (or a change within the rounding of the
/// single-precision sums) is not positive and not drawn.
fn objective_decrease(x: &[f64], levels: &[usize], objectives: &[f64]) -> Vec<(f64, f64)> {
    (1..objectives.len())
        .filter(|&k| levels[k] == levels[k - 1] && x[k] > x[k - 1])
        .map(|k| {
            (
                x[k],
                (objectives[k - 1] - objectives[k]) / (x[k] - x[k - 1]),
            )
        })
        .collect()
}

/// How far apart two lens planes' distances `D_l` are (relative). A model's kappa
/// (`D_ls/D_s = 1`) is relative to `c^2 / (4 pi G D_l)` of its own plane, and its arcsec to its
/// own `D_l`: compared on another plane it is off by about this much.
fn plane_mismatch(a: &LensPlane, b: &LensPlane) -> f64 {
    (a.d_l_mpc / b.d_l_mpc - 1.0).abs()
}

/// The largest relative difference of `D_l` at which a loaded model is compared with a reconstruction
/// (1%): a published model's `z_lens` written to fewer or more digits (AS1063: 0.3475 for 0.348,
/// 0.1% apart; MACS1931: 0.35 for 0.352, 0.4%) is compared, with a note; another cluster's is
/// not.
pub const MODEL_PLANE_TOLERANCE: f64 = 0.01;

/// The reconstruction's origin in the model's frame and the geometry of the model's maps over
/// the reconstruction's map (see [`Session::model_profile`]); when the model's lens plane is
/// not close enough to the reconstruction's (its kappa would not compare), why, in words.
fn model_frame(result: &SessionResult, model: &ModelLens) -> Result<(DVec2, MapGeometry), String> {
    let (theirs, ours) = (model.plane, result.products().plane);
    if plane_mismatch(&theirs, &ours) > MODEL_PLANE_TOLERANCE {
        return Err(format!(
            "its z_lens = {} is not the reconstruction's {} (set z_lens to compare)",
            theirs.z_lens, ours.z_lens
        ));
    }
    if theirs.cosmology != ours.cosmology {
        return Err("its cosmology is not the reconstruction's".to_string());
    }
    let origin = match (result.products().reference, model.reference) {
        (Some(ours), Some(theirs)) => theirs.to_offset_arcsec(ours.ra_deg, ours.dec_deg),
        _ => DVec2::ZERO,
    };
    let g = result.products().maps.geometry();
    let geometry = MapGeometry {
        center: origin + g.center,
        pixels: g.pixels.min(MODEL_MAPS_MAX_PIXELS),
        ..g
    };
    Ok((origin, geometry))
}

/// The loaded model in the radial profile's legends: "true lens" or "loaded model (file)".
fn model_name(opts: &ViewOptions, file_name: &str) -> String {
    if opts.model_is_truth {
        "true lens".to_string()
    } else {
        format!("loaded model ({file_name})")
    }
}

#[cfg(test)]
mod tests {
    use super::objective_decrease;

    #[test]
    fn the_objective_is_drawn_as_its_decrease_per_iteration_within_a_level() {
        let x = [0.0, 100.0, 200.0, 250.0, 350.0];
        let levels = [0, 0, 0, 0, 1];
        let objectives = [-1.0, -3.0, -3.5, -3.25, -9.0];
        // 100 -> 200: 0.5 over 100 iterations; 200 -> 250 rises (negative, not drawn on a log
        // axis); 250 -> 350 changes level and is left out.
        assert_eq!(
            objective_decrease(&x, &levels, &objectives),
            vec![(100.0, 0.02), (200.0, 0.005), (250.0, -0.005)]
        );
        assert!(objective_decrease(&[0.0], &[0], &[1.0]).is_empty());
    }
}
