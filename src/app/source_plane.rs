//! The source-plane view (caustics, each system's beta and its back-projected images over the
//! ray-shot total magnification) and the data view shown before anything is computed.

use glam::DVec2;

use crate::map::LensMaps;
use crate::map::{Map, MapGeometry};
use crate::render::OverlayPoints;
use crate::render::{render_kappa_png, ColorScale, Colormap, KappaPlotOptions, Marker, Overlay};
use crate::CriticalCurves;

use super::data::DataViews;
use super::views::{
    arc_overlays, ViewOptions, ViewPng, COUNTER_IMAGE_RGB, MEMBER_RGB, OBSERVED_RGB,
};
use super::{AppError, Session};

/// Source-plane pixels a side.
const SOURCE_PIXELS: usize = 96;
/// Rays per lens-plane pixel and axis (3 x 3 sub-pixels).
const SUBSAMPLE: usize = 3;
/// Smallest source-plane field (arcsec).
const MIN_SOURCE_FIELD_ARCSEC: f64 = 10.0;
/// Upper colour limit of the total magnification.
const MAX_SHOWN_MAGNIFICATION: f64 = 100.0;
/// Betas: yellow squares.
const BETA_RGB: [u8; 3] = [255, 235, 0];

/// A square field holding `points` with a 20 % margin, at least `min_arcsec` wide.
fn square_around(
    points: impl Iterator<Item = DVec2>,
    min_arcsec: f64,
    pixels: usize,
) -> MapGeometry {
    let (lo, hi) = points.filter(|p| p.is_finite()).fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(p), hi.max(p)),
    );
    if !(lo.is_finite() && hi.is_finite()) {
        return MapGeometry::centered(min_arcsec, pixels);
    }
    let size = ((hi - lo).max_element() * 1.2).max(min_arcsec);
    MapGeometry {
        pixels,
        size_arcsec: size,
        center: (lo + hi) / 2.0,
    }
}

/// Total magnification of a point source at each source pixel, by ray shooting: rays through
/// sub-pixels of the lens plane land at `beta = theta - f alpha(theta)`; the count per source
/// pixel times (lens sub-pixel area / source pixel area) estimates `sum_i |mu_i|`.
fn ray_shot(maps: &LensMaps, f: f64, region: MapGeometry) -> Map {
    let g = maps.geometry();
    let n = g.pixels;
    let h = g.pixel_arcsec() / SUBSAMPLE as f64;
    let mut counts = vec![0.0; region.pixels * region.pixels];
    let step = region.pixel_arcsec();
    let half = region.size_arcsec / 2.0;
    let origin = region.center - DVec2::splat(half);
    for j in 0..n * SUBSAMPLE {
        for i in 0..n * SUBSAMPLE {
            let theta = g.center - DVec2::splat(g.size_arcsec / 2.0)
                + DVec2::new(i as f64 + 0.5, j as f64 + 0.5) * h;
            let alpha = DVec2::new(maps.alpha_x.sample(theta), maps.alpha_y.sample(theta));
            let u = (theta - f * alpha - origin) / step;
            if u.x >= 0.0 && u.y >= 0.0 && u.x < region.pixels as f64 && u.y < region.pixels as f64
            {
                counts[u.y as usize * region.pixels + u.x as usize] += 1.0;
            }
        }
    }
    let ratio = h * h / (step * step);
    Map {
        geometry: region,
        data: counts.into_iter().map(|c| c * ratio).collect(),
    }
}

/// The caustics as "curves" so the figure draws them in the curve colours.
fn caustics_as_curves(c: &CriticalCurves) -> CriticalCurves {
    CriticalCurves {
        z_source: c.z_source,
        einstein_radius_arcsec: c.einstein_radius_arcsec,
        main_curve_radius_arcsec: c.main_curve_radius_arcsec,
        tangential_leaves_map: c.tangential_leaves_map,
        tangential: c.caustics.tangential.clone(),
        radial: c.caustics.radial.clone(),
        caustics: Default::default(),
    }
}

fn set(label: &str, color: [u8; 3], marker: Marker, p: Vec<DVec2>) -> OverlayPoints {
    OverlayPoints {
        label: label.to_string(),
        color,
        positions_arcsec: p,
        marker,
    }
}

impl Session {
    /// The source plane at the curves' redshift: tangential (red) and radial (cyan) caustics,
    /// each system's beta and its back-projected observed images, over the ray-shot total
    /// magnification (log10); with `opts.pin_arcsec`, the source of that point (a yellow
    /// circle).
    pub fn source_view(&self, opts: &ViewOptions) -> Result<ViewPng, AppError> {
        let r = self.result()?;
        let p = &r.products();
        let sources = r
            .reconstruction()
            .into_iter()
            .flat_map(|x| x.sources.iter());
        let betas: Vec<DVec2> = sources.clone().map(|s| s.beta_arcsec).collect();
        // With arcs, each system's images mapped back in its colour (as its arc pixels).
        let mut back: Vec<OverlayPoints> = Vec::new();
        for s in sources {
            let rgb = r.marks.system_rgb(&s.id).unwrap_or(OBSERVED_RGB);
            let label = if back.is_empty() {
                "images mapped back"
            } else {
                ""
            };
            let p = s.observed.iter().map(|i| i.beta_arcsec).collect();
            back.push(set(label, rgb, Marker::Plus, p));
        }
        // The source of the point clicked on the mass map (pin_arcsec), if it is on the maps.
        let pinned: Vec<DVec2> = opts
            .pin_arcsec
            .and_then(|[x, y]| self.source_behind(DVec2::new(x, y)).ok())
            .into_iter()
            .collect();
        let caustics = caustics_as_curves(&p.curves);
        let all = caustics.tangential.iter().chain(&caustics.radial).flatten();
        let region = square_around(
            all.copied()
                .chain(betas.iter().copied())
                .chain(pinned.iter().copied()),
            MIN_SOURCE_FIELD_ARCSEC,
            SOURCE_PIXELS,
        );
        let map = ray_shot(&p.maps, p.distance_ratio, region);
        let overlay = Overlay {
            lines: Vec::new(),
            curves: Some(&caustics),
            points: back
                .into_iter()
                .chain([set("beta", BETA_RGB, Marker::Square, betas)])
                .chain((!pinned.is_empty()).then(|| {
                    let label = "source of the clicked point";
                    set(label, COUNTER_IMAGE_RGB, Marker::Circle, pinned)
                }))
                .collect(),
            labels: Vec::new(),
        };
        let plot = KappaPlotOptions {
            scale: ColorScale::Log,
            vmin: Some(0.5),
            vmax: Some(MAX_SHOWN_MAGNIFICATION),
            colormap: Colormap::Magma,
            map_pixels_on_screen: opts.map_side_px()?,
            title: Some(format!(
                "source plane, caustics at z_{{s}} = {}",
                p.curves.z_source
            )),
            colorbar_label: Some("log_{10} total magnification".to_string()),
            show_caustics: false,
            legend: opts.legend,
        };
        let png = render_kappa_png(&map, &overlay, &plot)
            .map_err(|e| AppError::Run(format!("rendering: {e}")))?;
        Ok(ViewPng {
            name: "source-plane.png".to_string(),
            png,
        })
    }

    /// The loaded data before any result: images (or arc pixels) and members, as `opts`
    /// selects, on the field a reconstruction would use (1.3 x their extent, at least 60
    /// arcsec).
    pub fn data_view(&self, opts: &ViewOptions) -> Result<ViewPng, AppError> {
        let parsed = self.parsed()?;
        let observed = parsed.observed_arcsec();
        let marks = parsed.marks();
        if observed.is_empty() && marks.members.is_empty() {
            return Err(AppError::Missing("no catalogue is loaded".to_string()));
        }
        let g = square_around(observed.iter().copied(), 60.0, 64);
        let g = MapGeometry {
            size_arcsec: g.size_arcsec * 1.3 / 1.2,
            ..g
        };
        let map = Map {
            geometry: g,
            data: vec![0.0; g.pixels * g.pixels],
        };
        // The Show toggles as in the kappa view; the field stays that of all the data.
        let mut points = Vec::new();
        if opts.show_observed {
            points.extend(arc_overlays(&marks.arcs, marks.arc_pixel_mas));
        }
        if opts.show_members {
            points.push(set("members", MEMBER_RGB, Marker::Circle, marks.members));
        }
        if opts.show_observed {
            points.push(set(
                "observed images",
                OBSERVED_RGB,
                Marker::Plus,
                marks.observed,
            ));
        }
        let overlay = Overlay {
            lines: Vec::new(),
            curves: None,
            points,
            labels: Vec::new(),
        };
        let plot = KappaPlotOptions {
            vmin: Some(-1.0),
            vmax: Some(1.0),
            colormap: Colormap::Viridis,
            map_pixels_on_screen: opts.map_side_px()?,
            title: Some("the data (no mass map yet)".to_string()),
            colorbar_label: Some("(reconstruct to see kappa)".to_string()),
            legend: opts.legend,
            ..KappaPlotOptions::default()
        };
        let png = render_kappa_png(&map, &overlay, &plot)
            .map_err(|e| AppError::Run(format!("rendering: {e}")))?;
        Ok(ViewPng {
            name: "data.png".to_string(),
            png,
        })
    }
}
