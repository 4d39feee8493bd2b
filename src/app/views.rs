//! The app's views, rendered with tiny-skia: the kappa map with curves and points, the source
//! plane, the radial profile and the convergence plot; and the hover read-out of the kappa map.

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::render::{
    kappa_figure_frame_for, render_kappa_png, ColorScale, FigureFrame, KappaPlotOptions,
    LegendPlace, Marker, Overlay, OverlayLabel, OverlayLines, OverlayPoints,
};

use super::data::{ArcPixels, DataMarks};
use super::{AppError, Session, SessionResult, SHOWN_MIN_MAGNIFICATION};
use crate::coordinates::{parse_position, sexagesimal_text, TypedPosition};
use crate::ds9::{write_marks, Mark};
use crate::image_search::magnification_at;
use crate::products::Products;
use crate::reconstruct::{
    images_on_maps, source_on_maps, ArrivalTimes, InterpolatedLens, PredictedImage,
    IMAGE_REGION_RADIUS_ARCSEC,
};

/// The images of a clicked point's source: yellow squares.
pub const COUNTER_IMAGE_RGB: [u8; 3] = [255, 235, 0];

/// Observed images: magenta plus signs.
pub const OBSERVED_RGB: [u8; 3] = [255, 60, 255];
/// Predicted images: orange crosses.
pub const PREDICTED_RGB: [u8; 3] = [255, 170, 0];
/// Member galaxies: white circles.
pub const MEMBER_RGB: [u8; 3] = [255, 255, 255];
/// The verdict's worst systems: a thick ring at the worst image and the system's id.
pub const WORST_RGB: [u8; 3] = [255, 90, 0];
/// The loaded model file's critical curves over a reconstruction: white, dashed.
pub const MODEL_CURVE_RGB: [u8; 3] = [255, 255, 255];
/// One colour per multiple-image system (arc pixels, their images mapped back, the systems
/// table), used in turn; none is the red or cyan of the curves, the white of the members or
/// the orange of the predicted images.
pub const SYSTEM_RGB: [[u8; 3]; 10] = [
    [255, 60, 255],
    [120, 255, 90],
    [255, 220, 110],
    [150, 120, 255],
    [255, 120, 150],
    [90, 255, 210],
    [120, 170, 255],
    [230, 255, 60],
    [255, 150, 230],
    [200, 150, 90],
];
/// Legend text of the arc pixels (one set per system, only the first is labelled).
const ARC_LABEL: &str = "arc pixels (colour: system)";

/// The colour of the `k`-th system (in the order of the data file).
pub fn system_rgb(k: usize) -> [u8; 3] {
    SYSTEM_RGB[k % SYSTEM_RGB.len()]
}

/// The arc pixels of every system as filled squares of side `side_mas`, in the system colours.
pub(super) fn arc_overlays(arcs: &[ArcPixels], side_mas: u32) -> Vec<OverlayPoints> {
    let marker = Marker::Pixel { side_mas };
    let sets = arcs.iter().enumerate().map(|(k, a)| {
        let label = if k == 0 { ARC_LABEL } else { "" };
        points(label, system_rgb(k), marker, a.pixels_arcsec.clone())
    });
    sets.collect()
}

/// How legends name the loaded model file: "the true lens" when it is one, its file name
/// otherwise, after `prefix` ("critical curves of", ...).
fn model_label(opts: &ViewOptions, file_name: &str, prefix: &str) -> String {
    if opts.model_is_truth {
        format!("{prefix} the true lens")
    } else {
        format!("{prefix} {file_name}")
    }
}

/// What to draw.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ViewOptions {
    /// Colour scale of the kappa map (default log).
    pub scale: ColorScale,
    pub show_members: bool,
    pub show_observed: bool,
    pub show_predicted: bool,
    /// After a reconstruction, the loaded model file's critical curves (white, dashed).
    pub show_model_curves: bool,
    /// The loaded model file is the true lens (the built-in examples' models): legends call
    /// it "the true lens" instead of by its file name.
    pub model_is_truth: bool,
    /// Map side on screen in pixels (default 512).
    pub map_pixels_on_screen: u32,
    /// Every figure drawn this many times larger, text and lines included (default 1; 0.25
    /// to 4, e.g. 2 or 3 for a slide or a paper): the map side becomes
    /// `map_pixels_on_screen * figure_scale`, the line plots' panels grow alike.
    pub figure_scale: f32,
    /// Where the figures' legends go (default: under the map, so no data are hidden).
    pub legend: LegendPlace,
    /// A point of the map (arcsec): the images of the source behind it are drawn
    /// ([`Session::counter_images`]).
    pub pin_arcsec: Option<[f64; 2]>,
    /// After a reconstruction, the kept iterate (index into
    /// [`crate::Reconstruction::iterates`]) whose kappa map, curves and predicted images the
    /// mass map and its read-out show instead of the solution's (default none: the solution).
    /// The pin's images are not drawn then.
    pub iterate: Option<usize>,
}

impl Default for ViewOptions {
    fn default() -> Self {
        Self {
            scale: ColorScale::Log,
            show_members: true,
            show_observed: true,
            show_predicted: true,
            show_model_curves: true,
            model_is_truth: false,
            map_pixels_on_screen: 512,
            figure_scale: 1.0,
            legend: LegendPlace::Below,
            pin_arcsec: None,
            iterate: None,
        }
    }
}

/// Smallest and largest [`ViewOptions::figure_scale`].
pub const FIGURE_SCALE_RANGE: (f32, f32) = (0.25, 4.0);

impl ViewOptions {
    /// [`Self::figure_scale`], checked to lie in [`FIGURE_SCALE_RANGE`].
    pub fn checked_figure_scale(&self) -> Result<f32, AppError> {
        let k = self.figure_scale;
        let (lo, hi) = FIGURE_SCALE_RANGE;
        if !(lo..=hi).contains(&k) {
            return Err(AppError::Setting(format!(
                "figure_scale = {k}: must be {lo} to {hi}"
            )));
        }
        Ok(k)
    }

    /// The map side of the figures in pixels: `map_pixels_on_screen * figure_scale`.
    pub fn map_side_px(&self) -> Result<u32, AppError> {
        let k = self.checked_figure_scale()?;
        Ok((self.map_pixels_on_screen as f32 * k).round() as u32)
    }
}

/// One rendered view.
#[derive(Debug, Clone, PartialEq)]
pub struct ViewPng {
    /// File name for downloads, e.g. `kappa.png`.
    pub name: String,
    pub png: Vec<u8>,
}

/// What is under the cursor on the kappa map (or at a typed position).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HoverReadout {
    /// The point in the arcsec frame (offsets from the sky reference when there is one).
    pub x_arcsec: f64,
    pub y_arcsec: f64,
    /// RA and Dec of the point (degrees) when the data have a sky reference.
    pub radec_deg: Option<[f64; 2]>,
    /// The same as `22:48:43.97 -44:31:51.2` ([`crate::sexagesimal_text`]).
    pub radec_sexagesimal: Option<String>,
    /// `kappa` at `D_ls/D_s = 1` (bilinear).
    pub kappa: f64,
    /// Magnification at the point at the curves' source redshift: `1 / det A` of the
    /// interpolated kappa and shear, as the images of [`Session::counter_images`] have it, so
    /// the two agree at one point.
    pub magnification: f64,
    pub z_source: f64,
    /// The maps have no data there (pixels without data in published deflection maps):
    /// `kappa` and `magnification` are NaN.
    pub no_data: bool,
    /// The result's ensemble there (not for an earlier iterate), if it has one.
    pub ensemble: Option<super::EnsembleReadout>,
}

/// The source behind a point of the map and all its images, at the curves' source redshift.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CounterImages {
    /// The point (arcsec).
    pub x_arcsec: f64,
    pub y_arcsec: f64,
    pub z_source: f64,
    /// Its source position `theta - f alpha(theta)` (arcsec).
    pub beta_arcsec: [f64; 2],
    /// Every image of that source (the point itself among them), with its signed
    /// magnification and its delay in days after the first to arrive, brightest first.
    pub images: Vec<PredictedImage>,
    /// The magnification at the point itself (as [`HoverReadout::magnification`]).
    pub point_magnification: f64,
    /// The image found at the point (index into `images`): the nearest one, when it lies
    /// within [`POINT_IMAGE_ARCSEC`] or a map pixel of the point. Its magnification is that of
    /// the found position, which differs from `point_magnification` by the step between them:
    /// near a critical curve even a small step changes it a lot.
    pub point_image: Option<usize>,
    /// Its distance from the point (arcsec).
    pub point_image_distance_arcsec: Option<f64>,
    /// RA and Dec of each image as `22:48:43.97 -44:31:51.2` (empty without a sky reference).
    pub images_sexagesimal: Vec<String>,
}

/// An image found within this distance of a clicked point (arcsec), or within a map pixel, is
/// the point's own image.
pub const POINT_IMAGE_ARCSEC: f64 = 0.2;

pub(super) fn points(label: &str, rgb: [u8; 3], marker: Marker, p: Vec<DVec2>) -> OverlayPoints {
    OverlayPoints {
        label: label.to_string(),
        color: rgb,
        positions_arcsec: p,
        marker,
    }
}

fn render(e: impl std::fmt::Display) -> AppError {
    AppError::Run(format!("rendering: {e}"))
}

/// What the mass map shows: the result's products and predicted images, or those of a kept
/// iterate ([`ViewOptions::iterate`]).
struct Shown<'a> {
    products: &'a Products,
    predicted: Vec<DVec2>,
    /// The iterate's iteration count and the run's.
    iteration: Option<(usize, usize)>,
}

impl Session {
    /// Runs `f` on what the mass map drawn with `opts` shows.
    fn with_shown<T>(
        &self,
        opts: &ViewOptions,
        f: impl FnOnce(&SessionResult, Shown<'_>) -> Result<T, AppError>,
    ) -> Result<T, AppError> {
        let r = self.result()?;
        let Some(index) = opts.iterate else {
            let shown = Shown {
                products: r.products(),
                predicted: r.predicted(),
                iteration: None,
            };
            return f(r, shown);
        };
        let total = r.reconstruction().map_or(0, |x| x.iterations);
        let kept = r.reconstruction().map_or(0, |x| x.iterates.len());
        if kept > 0 && index == kept - 1 {
            // The last iterate is the result: its own maps.
            let shown = Shown {
                products: r.products(),
                predicted: r.predicted(),
                iteration: Some((total, total)),
            };
            return f(r, shown);
        }
        let m = r.at_iterate(index)?;
        let shown = Shown {
            products: &m.products,
            predicted: m.predicted.clone(),
            iteration: Some((m.iteration, total)),
        };
        f(r, shown)
    }

    fn kappa_options(
        &self,
        opts: &ViewOptions,
        shown: &Shown,
    ) -> Result<KappaPlotOptions, AppError> {
        let at = shown
            .iteration
            .map_or(String::new(), |(k, n)| format!(", iteration {k} of {n}"));
        Ok(KappaPlotOptions {
            scale: opts.scale,
            map_pixels_on_screen: opts.map_side_px()?,
            title: Some(format!(
                "κ (z_{{l}} = {}), critical curves at z_{{s}} = {}{at}",
                shown.products.plane.z_lens, shown.products.curves.z_source
            )),
            legend: opts.legend,
            ..KappaPlotOptions::default()
        })
    }

    /// What the kappa view draws over the map: the curves, the loaded model's curves, the arc
    /// pixels (one colour per system), members, catalogue images and predicted images, as
    /// `opts` selects.
    fn kappa_overlay<'a>(
        &'a self,
        r: &'a SessionResult,
        opts: &ViewOptions,
        shown: &'a Shown,
    ) -> Result<Overlay<'a>, AppError> {
        let mut overlay = Overlay {
            lines: Vec::new(),
            curves: Some(&shown.products.curves),
            points: Vec::new(),
            labels: Vec::new(),
        };
        if opts.show_model_curves {
            if let Some(m) = self.model_curves(r)? {
                overlay.lines.push(OverlayLines {
                    label: model_label(opts, &m.name, "critical curves of"),
                    color: MODEL_CURVE_RGB,
                    dashed: true,
                    lines: m.tangential.into_iter().chain(m.radial).collect(),
                });
            }
        }
        if opts.show_observed {
            overlay
                .points
                .extend(arc_overlays(&r.marks.arcs, r.marks.arc_pixel_mas));
        }
        if opts.show_members {
            let m = r.marks.members.clone();
            overlay
                .points
                .push(points("members", MEMBER_RGB, Marker::Circle, m));
        }
        // Predicted before observed: markers are drawn in this order, and the observed images
        // (the data) stay visible where a predicted image lands on them.
        if opts.show_predicted {
            let p = shown.predicted.clone();
            let label = format!("predicted, |μ| >= {SHOWN_MIN_MAGNIFICATION}");
            overlay
                .points
                .push(points(&label, PREDICTED_RGB, Marker::Cross, p));
        }
        if opts.show_observed {
            let o = r.marks.observed.clone();
            overlay
                .points
                .push(points("observed", OBSERVED_RGB, Marker::Plus, o));
            // The verdict's worst systems, of the result (not of an iterate).
            if let Some(rec) = r.reconstruction().filter(|_| shown.iteration.is_none()) {
                let worst = rec.verdict().worst;
                let at: Vec<DVec2> = worst.iter().map(|w| w.position_arcsec).collect();
                let label = "worst systems (see the verdict)";
                overlay
                    .points
                    .push(points(label, WORST_RGB, Marker::Ring, at));
                overlay
                    .labels
                    .extend(worst.into_iter().map(|w| OverlayLabel {
                        text: w.id,
                        position_arcsec: w.position_arcsec,
                        color: WORST_RGB,
                    }));
            }
        }
        // A pin off these maps (left from another result) draws nothing; the app's list of
        // the images says why.
        let pin = opts.pin_arcsec.filter(|_| shown.iteration.is_none());
        if let Some(Ok(c)) = pin.map(|[x, y]| self.counter_images(DVec2::new(x, y))) {
            let label = format!(
                "images of the clicked point's source (z_s = {})",
                c.z_source
            );
            // As the predicted images: the faint central ones are listed, not drawn.
            let shown = c.images.iter().filter(|i| i.is_shown());
            let p = shown.map(|i| i.position_arcsec).collect();
            overlay
                .points
                .push(points(&label, COUNTER_IMAGE_RGB, Marker::Square, p));
        }
        Ok(overlay)
    }

    /// The kappa map (lin/log) with colour bar, arcsec axes, tangential (red) and radial (cyan)
    /// critical curves, arc pixels, members, observed and predicted images; the legend where
    /// `opts.legend` puts it.
    pub fn kappa_view(&self, opts: &ViewOptions) -> Result<ViewPng, AppError> {
        let png = self.with_shown(opts, |r, shown| {
            let overlay = self.kappa_overlay(r, opts, &shown)?;
            let options = self.kappa_options(opts, &shown)?;
            render_kappa_png(&shown.products.maps.kappa, &overlay, &options).map_err(render)
        })?;
        Ok(ViewPng {
            name: "kappa.png".to_string(),
            png,
        })
    }

    /// Where the map lies in the kappa view drawn with `opts` (PNG pixels).
    pub fn kappa_frame(&self, opts: &ViewOptions) -> Result<FigureFrame, AppError> {
        self.with_shown(opts, |r, shown| {
            let overlay = self.kappa_overlay(r, opts, &shown)?;
            let options = self.kappa_options(opts, &shown)?;
            kappa_figure_frame_for(&shown.products.maps.kappa, &overlay, &options).map_err(render)
        })
    }

    /// The point of the kappa view drawn with `opts` under `(px, py)` (PNG pixels, origin
    /// top-left), in arcsec; `None` outside the map.
    pub fn kappa_point(
        &self,
        opts: &ViewOptions,
        px: f32,
        py: f32,
    ) -> Result<Option<DVec2>, AppError> {
        let frame = self.kappa_frame(opts)?;
        let inside = |v: f32, lo: f32| v >= lo && v <= lo + frame.map_side;
        let on_map = inside(px, frame.map_left) && inside(py, frame.map_top);
        Ok(on_map.then(|| frame.screen_to_arcsec(px, py)))
    }

    /// The source behind the point `p` (arcsec) of the result's maps at the curves' source
    /// redshift, and every image of it: the lens equation solved forward on the maps, as for
    /// the predicted images of a reconstruction. Any result will do (a reconstruction, a
    /// forward model, deflection maps): where else a candidate arc should appear.
    pub fn counter_images(&self, p: DVec2) -> Result<CounterImages, AppError> {
        let products = &self.result()?.products();
        let f = products.distance_ratio;
        let beta = self.source_behind(p)?;
        let mut images =
            images_on_maps(&products.maps, f, beta).map_err(|e| AppError::Run(e.to_string()))?;
        images.sort_by(|a, b| b.magnification.abs().total_cmp(&a.magnification.abs()));
        ArrivalTimes::new(products).set_delays(products.curves.z_source, beta, &mut images);
        let pixel = products.maps.geometry().pixel_arcsec();
        let nearest = images
            .iter()
            .enumerate()
            .map(|(k, i)| (k, i.position_arcsec.distance(p)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .filter(|(_, d)| *d <= POINT_IMAGE_ARCSEC.max(pixel));
        let sky = |q: DVec2| {
            products.reference.map(|r| {
                let (ra, dec) = r.offset_to_radec(q);
                sexagesimal_text(ra, dec)
            })
        };
        Ok(CounterImages {
            x_arcsec: p.x,
            y_arcsec: p.y,
            z_source: products.curves.z_source,
            beta_arcsec: beta.to_array(),
            point_magnification: magnification_on(products, p),
            point_image: nearest.map(|(k, _)| k),
            point_image_distance_arcsec: nearest.map(|(_, d)| d),
            images_sexagesimal: images
                .iter()
                .filter_map(|i| sky(i.position_arcsec))
                .collect(),
            images,
        })
    }

    /// The source position (arcsec) behind the point `p` of the result's maps at the curves'
    /// source redshift; an error when `p` is not on the maps or the maps have no data there.
    pub(super) fn source_behind(&self, p: DVec2) -> Result<DVec2, AppError> {
        let products = &self.result()?.products();
        let g = products.maps.geometry();
        let on_maps = (p - g.center).abs().max_element() <= 0.5 * g.size_arcsec;
        if !(p.is_finite() && on_maps) {
            return Err(AppError::Setting(format!(
                "({:.2}, {:.2}) arcsec is not on the maps",
                p.x, p.y
            )));
        }
        let beta = source_on_maps(&products.maps, products.distance_ratio, p);
        if beta.is_nan() {
            return Err(AppError::Missing(format!(
                "({:.2}, {:.2}) arcsec: the deflection maps have no data there",
                p.x, p.y
            )));
        }
        Ok(beta)
    }

    /// [`Session::counter_images`] of `p` as a DS9 region file to lay over the cluster image:
    /// the clicked point (yellow) and every image of its source with `|mu| >=`
    /// [`SHOWN_MIN_MAGNIFICATION`] (yellow, dashed, labelled with the signed magnification);
    /// fk5 with the result's sky reference, else pixels of its maps.
    pub fn counter_image_regions(&self, p: DVec2) -> Result<String, AppError> {
        let c = self.counter_images(p)?;
        let products = &self.result()?.products();
        let clicked = Mark {
            position_arcsec: p,
            label: "clicked point".to_string(),
            color: "yellow",
            tag: "clicked",
            dashed: false,
        };
        let images = c.images.iter().filter(|i| i.is_shown()).map(|i| Mark {
            position_arcsec: i.position_arcsec,
            label: format!("image, mu={:.2}", i.magnification),
            color: "yellow",
            tag: "image",
            dashed: true,
        });
        let marks: Vec<Mark> = std::iter::once(clicked).chain(images).collect();
        let comment = format!(
            "WSLAP+: the images (dashed) of the source behind the clicked point at z_s = {},\n\
             source at beta = ({:.3}, {:.3}) arcsec; mu: signed magnification (|mu| >= {})",
            c.z_source, c.beta_arcsec[0], c.beta_arcsec[1], SHOWN_MIN_MAGNIFICATION
        );
        Ok(write_marks(
            &comment,
            &marks,
            IMAGE_REGION_RADIUS_ARCSEC,
            products.reference,
            &products.maps.geometry(),
        ))
    }

    /// x, y (arcsec), kappa and magnification under the point `(px, py)` of the kappa view
    /// drawn with `opts` (PNG pixels, origin top-left); `None` outside the map.
    pub fn hover(
        &self,
        opts: &ViewOptions,
        px: f32,
        py: f32,
    ) -> Result<Option<HoverReadout>, AppError> {
        let Some(p) = self.kappa_point(opts, px, py)? else {
            return Ok(None);
        };
        self.readout_at(opts, p).map(Some)
    }

    /// x, y (arcsec), RA/Dec, kappa and magnification at the point `p` (arcsec) of the maps
    /// the kappa view drawn with `opts` shows (a typed position's read-out).
    pub fn readout_at(&self, opts: &ViewOptions, p: DVec2) -> Result<HoverReadout, AppError> {
        self.with_shown(opts, |_, shown| {
            let products = shown.products;
            let kappa = products.maps.kappa.sample(p);
            let magnification = magnification_on(products, p);
            let radec = products.reference.map(|r| r.offset_to_radec(p));
            Ok(HoverReadout {
                x_arcsec: p.x,
                y_arcsec: p.y,
                radec_deg: radec.map(|(ra, dec)| [ra, dec]),
                radec_sexagesimal: radec.map(|(ra, dec)| sexagesimal_text(ra, dec)),
                kappa,
                magnification,
                z_source: products.curves.z_source,
                no_data: kappa.is_nan() || magnification.is_nan(),
                ensemble: match shown.iteration {
                    Some((k, n)) if k < n => None,
                    _ => self.ensemble_at(p),
                },
            })
        })
    }

    /// A typed or pasted position ([`crate::parse_position`]) on the result's maps, with the
    /// result's sky reference; an error (saying what could not be read, or that the point is
    /// off the maps) otherwise.
    pub fn locate(&self, text: &str) -> Result<TypedPosition, AppError> {
        let products = self.result()?.products();
        let typed = parse_position(text, products.reference)
            .map_err(|e| AppError::Setting(e.to_string()))?;
        let g = products.maps.geometry();
        let p = typed.position_arcsec;
        if (p - g.center).abs().max_element() > 0.5 * g.size_arcsec {
            return Err(AppError::Setting(format!(
                "'{}' ({}) is at ({:.1}, {:.1}) arcsec from the reference, off the {:.0} arcsec maps",
                text.trim(),
                typed.form.words(),
                p.x,
                p.y,
                g.size_arcsec
            )));
        }
        Ok(typed)
    }
}

/// The magnification at `p` on `products`' maps at their source redshift: `1 / det A` of the
/// interpolated kappa and shear, as the image search computes it at the images it finds.
fn magnification_on(products: &Products, p: DVec2) -> f64 {
    let maps = &products.maps;
    magnification_at(&InterpolatedLens(maps), products.distance_ratio, p)
}

impl DataMarks {
    /// The colour of system `id`'s arc pixels (`None` when it has none: catalogue systems).
    pub fn system_rgb(&self, id: &str) -> Option<[u8; 3]> {
        let k = self.arcs.iter().position(|a| a.id == id)?;
        Some(system_rgb(k))
    }
}
