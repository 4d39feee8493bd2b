//! The map product set of [method §6] for one lens, as `wslap maps` writes it and the
//! app shows it: reference-normalised maps, magnification, critical curves and caustics at one
//! source redshift, the radial profile, and the files (FITS, DS9, PNG, JSON).
//!
//! [method §6]: crate::method#6-products

use glam::DVec2;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::cosmology::{CosmologyError, LensPlane};
use crate::curves::{critical_curves, critical_curves_about, CriticalCurves, LensRegion};
use crate::ds9::write_regions;
use crate::fits::{write_image, Card, FitsError, FitsWriteOptions};
use crate::map::{LensMaps, MapsError};
use crate::map::{Map, MapGeometry};
use crate::model::{ModelError, ModelFile};
use crate::profiles::MassComponent;
use crate::radial::{radial_profile, RadialBins, RadialError, RadialProfile};
use crate::render::{render_kappa_png, ColorScale, KappaPlotOptions, Overlay, RenderError};
use crate::sky::SkyReference;

/// Largest map side in pixels (a 8192^2 map of five float64 quantities is 2.7 GB).
pub const MAX_PIXELS: usize = 8192;

/// What went wrong while making the products.
#[derive(Debug, Error)]
pub enum ProductsError {
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error(transparent)]
    Cosmology(#[from] CosmologyError),
    #[error(transparent)]
    BadFieldValue(#[from] crate::error::BadFieldValue),
    #[error(transparent)]
    Maps(#[from] MapsError),
    #[error(transparent)]
    Fits(#[from] FitsError),
    #[error(transparent)]
    Radial(#[from] RadialError),
    #[error(transparent)]
    Render(#[from] RenderError),
}

/// Settings of one product run; every field has a documented default.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ProductOptions {
    /// Source redshift of the magnification map and the critical curves (default 2).
    pub z_source: f64,
    /// Width of the square map in arcsec, centred on (0, 0) (default 200).
    pub size_arcsec: f64,
    /// Pixels on a side (default 512).
    pub pixels: usize,
    /// Colour scale of the kappa figure (default log).
    pub scale: ColorScale,
    /// Maps only: no critical curves, caustics or Einstein radius (for runs whose maps only
    /// serve to find images, as the trials of an "auto" regulariser strength). Not a setting.
    #[serde(skip)]
    pub maps_only: bool,
}

impl Default for ProductOptions {
    fn default() -> Self {
        Self {
            z_source: 2.0,
            size_arcsec: 200.0,
            pixels: 512,
            scale: ColorScale::Log,
            maps_only: false,
        }
    }
}

impl ProductOptions {
    /// Checks the ranges: `size_arcsec` in (0, 36000], `pixels` in [16, MAX_PIXELS].
    pub fn validate(&self) -> Result<(), ProductsError> {
        if !(self.size_arcsec.is_finite() && self.size_arcsec > 0.0 && self.size_arcsec <= 36_000.0)
        {
            return Err(ProductsError::from(crate::error::BadFieldValue::new(
                "products.size",
                self.size_arcsec,
                "the map width in arcsec must be in (0, 36000]",
            )));
        }
        if !(16..=MAX_PIXELS).contains(&self.pixels) {
            return Err(ProductsError::from(crate::error::BadFieldValue::new(
                "products.pixels",
                self.pixels as f64,
                "the map side must be 16 to 8192 pixels",
            )));
        }
        if !self.z_source.is_finite() {
            return Err(ProductsError::from(crate::error::BadFieldValue::new(
                "products.z_source",
                self.z_source,
                "the source redshift must be a number",
            )));
        }
        Ok(())
    }
}

/// Wall-clock time of each stage in milliseconds.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Timings {
    pub maps_ms: f64,
    pub curves_ms: f64,
    pub profile_ms: f64,
}

/// Everything derived from one lens at one source redshift.
#[derive(Debug, Clone)]
pub struct Products {
    pub plane: LensPlane,
    pub reference: Option<SkyReference>,
    /// `f(z_s) = D_ls/D_s`.
    pub distance_ratio: f64,
    pub maps: LensMaps,
    pub magnification: Map,
    pub curves: CriticalCurves,
    /// Side in arcsec of the map on which `curves.einstein_radius_arcsec` was measured: the
    /// products' own map, or a wider one (see [`EINSTEIN_MAP_WIDENING`]) when the tangential
    /// curve leaves it. `None` when the curve left every map tried (the radius counts only the
    /// closed loops then, so it is too small).
    pub einstein_radius_map_arcsec: Option<f64>,
    pub profile: RadialProfile,
    pub timings: Timings,
}

/// A short account of the products (`summary.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    pub z_lens: f64,
    pub z_source: f64,
    pub distance_ratio: f64,
    pub d_l_mpc: f64,
    pub sigma_cr_ref_msun_per_arcsec2: f64,
    pub map_size_arcsec: f64,
    pub map_pixels: usize,
    pub einstein_radius_arcsec: f64,
    /// The main tangential curve's alone ([`CriticalCurves::main_curve_radius_arcsec`]),
    /// measured on the same map; 0 in files written before it was kept.
    #[serde(default)]
    pub einstein_radius_main_curve_arcsec: f64,
    /// See [`Products::einstein_radius_map_arcsec`]: `null` when the radius is a lower bound.
    #[serde(default)]
    pub einstein_radius_map_arcsec: Option<f64>,
    pub tangential_curves: usize,
    /// Share of the area inside the tangential curves (on this map) that the largest one
    /// holds: near 1 for one main curve with a few small ones beside it, small when the
    /// critical region is broken into islands (`null` without a tangential curve).
    #[serde(default)]
    pub tangential_main_area_share: Option<f64>,
    pub radial_curves: usize,
    pub kappa_max: f64,
    /// Projected mass inside 10, 20 and 50 arcsec of (0, 0), Msun (`null` where the circle
    /// leaves the map).
    pub mass_within_arcsec: Vec<(f64, Option<f64>)>,
    /// The sky position of the frame's origin (0, 0), about which `mass_within_arcsec` is
    /// measured: a catalogue's `#REFERENCE`, or for absolute RA/Dec without one the images'
    /// mean position (`null` for a frame without a sky position).
    #[serde(default)]
    pub frame_reference: Option<SkyReference>,
    pub timings_ms: Timings,
}

/// The largest of the areas enclosed by `curves` (a curve cut by the map border closed by its
/// chord) over their sum; `None` when they enclose nothing.
fn main_area_share(curves: &[crate::curves::Polyline]) -> Option<f64> {
    let areas: Vec<f64> = curves
        .iter()
        .map(|c| crate::curves::signed_area_arcsec2(c).abs())
        .collect();
    let total: f64 = areas.iter().sum();
    (total > 0.0).then(|| areas.iter().copied().fold(0.0, f64::max) / total)
}

/// When the tangential critical curve of a known lens leaves the products' map, its Einstein
/// radius is measured again on maps this many times wider (same centre), in turn, until one
/// holds the whole curve.
pub const EINSTEIN_MAP_WIDENING: [f64; 2] = [2.0, 4.0];

/// Pixels per side, at most, of those wider maps (they serve the Einstein radius only).
const EINSTEIN_MAP_MAX_PIXELS: usize = 256;

impl Summary {
    /// The Einstein radius for a reader, saying on which map it was measured when that is not
    /// the products' own, that it is a lower bound when the curve left every map, and the main
    /// curve's alone when the other loops (members', a neighbouring group's) add more than
    /// [`MAIN_CURVE_NOTE_SHARE`] to it.
    pub fn einstein_radius_text(&self) -> String {
        let text = self.einstein_radius_words();
        match self.main_curve_apart_arcsec() {
            Some(main) => format!("{text}; the main curve alone {main:.2} arcsec"),
            None => text,
        }
    }

    /// The main curve's Einstein radius (arcsec) when a reader should be given it beside the
    /// Einstein radius: it is more than [`MAIN_CURVE_NOTE_SHARE`] smaller; else `None`.
    pub fn main_curve_apart_arcsec(&self) -> Option<f64> {
        let (r, main) = (
            self.einstein_radius_arcsec,
            self.einstein_radius_main_curve_arcsec,
        );
        (main > 0.0 && main < (1.0 - MAIN_CURVE_NOTE_SHARE) * r).then_some(main)
    }

    fn einstein_radius_words(&self) -> String {
        let r = self.einstein_radius_arcsec;
        match self.einstein_radius_map_arcsec {
            // A map that holds every curve and none that encloses anything.
            Some(_) if r == 0.0 => {
                "none (no tangential critical curve at this source redshift)".into()
            }
            Some(side) if side > self.map_size_arcsec => format!(
                "{r:.2} arcsec (measured on a {side:.0} arcsec map: the tangential critical curve leaves the {:.0} arcsec map)",
                self.map_size_arcsec
            ),
            Some(_) => format!("{r:.2} arcsec"),
            None => format!(
                "at least {r:.2} arcsec (the tangential critical curve leaves the map: only its closed loops count)"
            ),
        }
    }
}

/// How much smaller than the Einstein radius the main curve's must be for the text to give it
/// too (the run's one-line summary, `einstein_radius_text` of the products' summary): 2%.
pub const MAIN_CURVE_NOTE_SHARE: f64 = 0.02;

/// Radii of the enclosed masses reported in the summary, arcsec.
const SUMMARY_RADII_ARCSEC: [f64; 3] = [10.0, 20.0, 50.0];

impl Products {
    /// Products of a parametric model file.
    pub fn from_model(model: &ModelFile, opts: &ProductOptions) -> Result<Self, ProductsError> {
        let plane = model.lens_plane()?;
        let lens = model.build_lens()?;
        Self::from_lens(&lens, plane, model.reference, opts)
    }

    /// Products of any lens (a parametric model, or a reconstruction) on the map of `opts`.
    pub fn from_lens(
        lens: &dyn MassComponent,
        plane: LensPlane,
        reference: Option<SkyReference>,
        opts: &ProductOptions,
    ) -> Result<Self, ProductsError> {
        opts.validate()?;
        let f = plane.distance_ratio(opts.z_source)?;
        let geometry = MapGeometry::centered(opts.size_arcsec, opts.pixels);
        let t = Clock::start();
        let maps = LensMaps::from_lens(lens, geometry);
        let maps_ms = t.ms();
        if opts.maps_only {
            return Self::finish_maps_only(maps, plane, reference, f, opts.z_source, maps_ms);
        }
        Self::finish(
            maps,
            plane,
            reference,
            f,
            opts.z_source,
            Some(lens),
            maps_ms,
        )
    }

    /// Products of lens maps already computed for `lens` (e.g. the simulation's truth maps),
    /// at `z_source`; the maps' geometry is the products'.
    pub fn from_lens_maps(
        maps: LensMaps,
        lens: &dyn MassComponent,
        plane: LensPlane,
        reference: Option<SkyReference>,
        z_source: f64,
    ) -> Result<Self, ProductsError> {
        let f = plane.distance_ratio(z_source)?;
        Self::finish(maps, plane, reference, f, z_source, Some(lens), 0.0)
    }

    /// Products of published deflection maps (HFF convention, `D_ls/D_s = 1`, arcsec).
    pub fn from_deflection(
        alpha_x: Map,
        alpha_y: Map,
        plane: LensPlane,
        reference: Option<SkyReference>,
        z_source: f64,
    ) -> Result<Self, ProductsError> {
        let f = plane.distance_ratio(z_source)?;
        let t = Clock::start();
        let maps = LensMaps::from_deflection(alpha_x, alpha_y)?;
        let maps_ms = t.ms();
        Self::finish(maps, plane, reference, f, z_source, None, maps_ms)
    }

    /// The products of `maps` without curves: an empty [`CriticalCurves`] (Einstein radius 0)
    /// and no profile bins beyond one.
    fn finish_maps_only(
        maps: LensMaps,
        plane: LensPlane,
        reference: Option<SkyReference>,
        f: f64,
        z_source: f64,
        maps_ms: f64,
    ) -> Result<Self, ProductsError> {
        let geometry = maps.geometry();
        let bins = RadialBins::Linear {
            r_min_arcsec: 0.0,
            r_max_arcsec: geometry.pixel_arcsec(),
            count: 1,
        };
        let profile = radial_profile(&maps.kappa, DVec2::ZERO, &bins, &plane)?;
        Ok(Self {
            plane,
            reference,
            distance_ratio: f,
            magnification: maps.magnification(f),
            curves: CriticalCurves {
                z_source,
                ..CriticalCurves::default()
            },
            einstein_radius_map_arcsec: None,
            profile,
            maps,
            timings: Timings {
                maps_ms,
                ..Timings::default()
            },
        })
    }

    fn finish(
        maps: LensMaps,
        plane: LensPlane,
        reference: Option<SkyReference>,
        f: f64,
        z_source: f64,
        lens: Option<&dyn MassComponent>,
        maps_ms: f64,
    ) -> Result<Self, ProductsError> {
        let t = Clock::start();
        let magnification = maps.magnification(f);
        let mut curves = critical_curves(&maps, f, z_source, lens);
        let einstein_radius_map_arcsec = match lens {
            Some(lens) if curves.tangential_leaves_map => {
                let (wide, map) = einstein_radius_on_wider_maps(lens, maps.geometry(), f, z_source);
                curves.einstein_radius_arcsec = wide.einstein_radius_arcsec;
                curves.main_curve_radius_arcsec = wide.main_curve_radius_arcsec;
                map
            }
            _ => own_map_side(&curves, maps.geometry()),
        };
        let curves_ms = t.ms();
        let t = Clock::start();
        let geometry = maps.geometry();
        let r_max = (0.5 * geometry.size_arcsec - geometry.center.length())
            .min(data_radius_arcsec(&maps.kappa, DVec2::ZERO));
        let bins = RadialBins::Linear {
            r_min_arcsec: 0.0,
            r_max_arcsec: r_max.max(geometry.pixel_arcsec()),
            count: (geometry.pixels / 4).clamp(4, 200),
        };
        let profile = radial_profile(&maps.kappa, DVec2::ZERO, &bins, &plane)?;
        let profile_ms = t.ms();
        Ok(Self {
            plane,
            reference,
            distance_ratio: f,
            maps,
            magnification,
            curves,
            einstein_radius_map_arcsec,
            profile,
            timings: Timings {
                maps_ms,
                curves_ms,
                profile_ms,
            },
        })
    }

    /// The summary written as `summary.json`.
    pub fn summary(&self) -> Summary {
        let g = self.maps.geometry();
        let profile_mass_at = |r: f64| -> Option<f64> {
            let edges = &self.profile.r_edges_arcsec;
            let k = edges.iter().position(|&e| e >= r)?;
            if k == 0 {
                return Some(0.0);
            }
            // Linear interpolation between the bracketing edges (r^2 would be exact for a sheet).
            let (r0, r1) = (edges[k - 1], edges[k]);
            let (m0, m1) = (
                self.profile.enclosed_mass_msun[k - 1],
                self.profile.enclosed_mass_msun[k],
            );
            Some(m0 + (m1 - m0) * (r * r - r0 * r0) / (r1 * r1 - r0 * r0))
        };
        Summary {
            z_lens: self.plane.z_lens,
            z_source: self.curves.z_source,
            distance_ratio: self.distance_ratio,
            d_l_mpc: self.plane.d_l_mpc,
            sigma_cr_ref_msun_per_arcsec2: self.plane.sigma_cr_ref_msun_per_arcsec2,
            map_size_arcsec: g.size_arcsec,
            map_pixels: g.pixels,
            einstein_radius_arcsec: self.curves.einstein_radius_arcsec,
            einstein_radius_main_curve_arcsec: self.curves.main_curve_radius_arcsec,
            einstein_radius_map_arcsec: self.einstein_radius_map_arcsec,
            tangential_curves: self.curves.tangential.len(),
            tangential_main_area_share: main_area_share(&self.curves.tangential),
            radial_curves: self.curves.radial.len(),
            kappa_max: self.maps.kappa.min_max().1,
            mass_within_arcsec: SUMMARY_RADII_ARCSEC
                .iter()
                .map(|&r| (r, profile_mass_at(r)))
                .collect(),
            frame_reference: self.reference,
            timings_ms: self.timings,
        }
    }

    /// The kappa figure (PNG) with the critical curves on top.
    pub fn kappa_png(&self, scale: ColorScale) -> Result<Vec<u8>, ProductsError> {
        let overlay = Overlay {
            lines: Vec::new(),
            curves: Some(&self.curves),
            points: Vec::new(),
            labels: Vec::new(),
        };
        // A map without mass (e.g. a solve stopped at its start) has no log scale: drawn linear.
        let massless = !self
            .maps
            .kappa
            .data
            .iter()
            .any(|v| v.is_finite() && *v > 0.0);
        let scale = match scale {
            ColorScale::Log if massless => ColorScale::Linear,
            other => other,
        };
        let opts = KappaPlotOptions {
            scale,
            title: Some(format!(
                "z_l = {}, critical curves at z_s = {}",
                self.plane.z_lens, self.curves.z_source
            )),
            ..KappaPlotOptions::default()
        };
        Ok(render_kappa_png(&self.maps.kappa, &overlay, &opts)?)
    }

    /// The HFF-style FITS maps: `(file name, bytes)` for kappa, gamma1, gamma2, the two
    /// deflections, the potential `psi` ([`crate::potential_map`]; all at `D_ls/D_s = 1`) and
    /// the magnification at `z_s` (header `ZSOURCE`).
    pub fn fits_files(&self) -> Result<Vec<(&'static str, Vec<u8>)>, ProductsError> {
        let z = self.curves.z_source;
        let base = |bunit: &str, what: &str| FitsWriteOptions {
            bunit: bunit.to_string(),
            comments: vec![
                format!("{what}, written by wslap {}", env!("CARGO_PKG_VERSION")),
                "Normalised to D_ls/D_s = 1 (HFF convention) unless stated.".to_string(),
            ],
            reference: self.reference,
            extra_cards: vec![Card::real("ZLENS", self.plane.z_lens, "lens redshift")],
        };
        let m = &self.maps;
        let mut magnif = base("", "Magnification");
        magnif
            .extra_cards
            .push(Card::real("ZSOURCE", z, "source redshift of this map"));
        Ok(vec![
            (
                "kappa.fits",
                write_image(&m.kappa, &base("", "Convergence"))?,
            ),
            (
                "gamma1.fits",
                write_image(&m.gamma1, &base("", "Shear component 1"))?,
            ),
            (
                "gamma2.fits",
                write_image(&m.gamma2, &base("", "Shear component 2"))?,
            ),
            (
                "x-arcsec-deflect.fits",
                write_image(
                    &m.alpha_x,
                    &base("arcsec", "Deflection along x (pixel axis 1)"),
                )?,
            ),
            (
                "y-arcsec-deflect.fits",
                write_image(
                    &m.alpha_y,
                    &base("arcsec", "Deflection along y (pixel axis 2)"),
                )?,
            ),
            ("magnif.fits", write_image(&self.magnification, &magnif)?),
            (
                "psi.fits",
                write_image(
                    &crate::potential::potential_map(m),
                    &base(
                        "arcsec2",
                        "Lensing potential, zero at the centre pixel (n/2, n/2)",
                    ),
                )?,
            ),
        ])
    }

    /// `critical-curves.json`: curves and caustics in arcsec.
    pub fn curves_json(&self) -> String {
        serde_json::to_string(&self.curves).expect("curves serialise")
    }

    /// `critical-curves.reg`: DS9 regions (fk5 when the sky reference is known).
    pub fn regions(&self) -> String {
        write_regions(&self.curves, self.reference, &self.maps.geometry())
    }
}

/// Wall-clock timer that also works in a browser worker (where `std::time::Instant` panics).
pub(crate) struct Clock(f64);

impl Clock {
    pub(crate) fn start() -> Self {
        Self(now_ms())
    }
    pub(crate) fn ms(&self) -> f64 {
        now_ms() - self.0
    }
}

#[cfg(not(target_arch = "wasm32"))]
fn now_ms() -> f64 {
    use std::time::{SystemTime, UNIX_EPOCH};
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_secs_f64() * 1e3)
        .unwrap_or(0.0)
}

#[cfg(target_arch = "wasm32")]
fn now_ms() -> f64 {
    js_sys::Date::now()
}

/// [`Products::einstein_radius_map_arcsec`] when the curves were traced on `geometry` alone:
/// its side, or `None` when the tangential curve leaves it.
pub(crate) fn own_map_side(curves: &CriticalCurves, geometry: MapGeometry) -> Option<f64> {
    (!curves.tangential_leaves_map).then_some(geometry.size_arcsec)
}

/// The Einstein radius of `lens` (and its main curve's, [`CriticalCurves`]) measured on the
/// maps of [`EINSTEIN_MAP_WIDENING`] around `geometry`, and the side of the first map that
/// holds the whole tangential curve (`None` when none does: the radius is then the widest
/// map's closed loops only). The lens is the one of `geometry` (within half its side of its
/// centre): what the wider maps add beyond is another structure's.
fn einstein_radius_on_wider_maps(
    lens: &dyn MassComponent,
    geometry: MapGeometry,
    f: f64,
    z_source: f64,
) -> (CriticalCurves, Option<f64>) {
    let mut last = CriticalCurves::default();
    for widen in EINSTEIN_MAP_WIDENING {
        let wide = MapGeometry {
            pixels: geometry.pixels.min(EINSTEIN_MAP_MAX_PIXELS),
            size_arcsec: geometry.size_arcsec * widen,
            center: geometry.center,
        };
        let maps = LensMaps::from_lens(lens, wide);
        let about = LensRegion {
            center: geometry.center,
            radius_arcsec: 0.5 * geometry.size_arcsec,
        };
        last = critical_curves_about(&maps, f, z_source, None, about);
        if !last.tangential_leaves_map {
            return (last, Some(wide.size_arcsec));
        }
    }
    (last, None)
}

/// The radius (arcsec) of the largest disc about `center` holding no pixel without data (NaN)
/// of `map`: the nearest point of the nearest such pixel; infinite when every pixel has data.
fn data_radius_arcsec(map: &Map, center: DVec2) -> f64 {
    let g = map.geometry;
    let half = 0.5 * g.pixel_arcsec();
    let n = g.pixels;
    (0..n * n)
        .filter(|&k| map.data[k].is_nan())
        .map(|k| {
            let d = g.pixel_center(k % n, k / n) - center;
            DVec2::new((d.x.abs() - half).max(0.0), (d.y.abs() - half).max(0.0)).length()
        })
        .fold(f64::INFINITY, f64::min)
}
