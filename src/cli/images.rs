//! `wslap images`: every image of a point source, with magnification, parity and time delay:
//! the look-up made when a supernova or a candidate arc appears behind a lens.

use std::path::{Path, PathBuf};

use clap::Args;
use glam::DVec2;
use serde::Serialize;
use wslap::{
    arrival_time_days, find_images, parse_sky_angle, potential_at, potential_difference,
    potential_map, Cosmology, ImageKind, ImageSearch, InputKind, InterpolatedLens, LensMaps,
    LensPlane, MapGeometry, MassComponent, ModelFile, ParOptions, Parity, SearchGrid, SkyReference,
};

use super::input::read_text;
use super::maps::{load_lenstool, read_map};

/// The images of a point source behind a lens, as JSON.
///
/// Prints every image of the source: position (arcsec, and RA/Dec when the lens has a sky
/// reference), signed magnification, parity, kind (minimum, saddle, maximum of the arrival
/// time) and the delay in days after the first image to arrive, images in order of arrival.
#[derive(Debug, Args)]
#[command(group(clap::ArgGroup::new("lens").required(true).args(["model", "lenstool", "maps"])))]
#[command(group(clap::ArgGroup::new("where").required(true).args(["source", "source_radec"])))]
pub struct ImagesArgs {
    /// Model file (JSON) of a parametric lens.
    #[arg(long, value_name = "MODEL.json")]
    model: Option<PathBuf>,
    /// A Lenstool parametric model (.par, with its potfile members as `wslap maps` reads them).
    #[arg(long, value_name = "MODEL.par")]
    lenstool: Option<PathBuf>,
    /// Member catalogue of the --lenstool model's potfile blocks (repeat the option).
    #[arg(long, value_name = "MEMBERS.cat", requires = "lenstool")]
    potfile: Vec<PathBuf>,
    /// Evaluate a --lenstool model with potentials at other redshifts in the single-plane
    /// approximation (as `wslap maps --single-plane`).
    #[arg(long, requires = "lenstool")]
    single_plane: bool,
    /// A folder of HFF-style maps: x-arcsec-deflect.fits and y-arcsec-deflect.fits
    /// (D_ls/D_s = 1), e.g. a `wslap reconstruct` or `wslap maps` output, or a published model.
    #[arg(long, value_name = "DIR")]
    maps: Option<PathBuf>,
    /// Lens redshift for --maps (default: the ZLENS card of the deflection maps).
    #[arg(long, allow_negative_numbers = true)]
    z_lens: Option<f64>,
    /// Source position in arcsec in the lens's frame (+x West, +y North).
    #[arg(long, num_args = 2, value_names = ["X", "Y"], allow_negative_numbers = true)]
    source: Option<Vec<f64>>,
    /// Source position on the sky: RA and Dec in degrees or sexagesimal (22:48:44.0 -44:31:51).
    #[arg(long, num_args = 2, value_names = ["RA", "DEC"], allow_negative_numbers = true)]
    source_radec: Option<Vec<String>>,
    /// Source redshift.
    #[arg(long, allow_negative_numbers = true)]
    z_source: f64,
    /// Width in arcsec of the square searched for images, centred on (0, 0) (model files and
    /// Lenstool models; --maps searches the maps' own field).
    #[arg(long, allow_negative_numbers = true, default_value_t = 200.0)]
    size: f64,
}

/// What `wslap images` prints.
#[derive(Debug, Serialize)]
struct ImagesReport {
    z_lens: f64,
    z_source: f64,
    /// `D_ls / D_s`.
    distance_ratio: f64,
    source_arcsec: DVec2,
    #[serde(skip_serializing_if = "Option::is_none")]
    source_radec_deg: Option<(f64, f64)>,
    /// How the images were found and how far they are good.
    method: String,
    images: Vec<ImageOut>,
}

#[derive(Debug, Serialize)]
struct ImageOut {
    position_arcsec: DVec2,
    #[serde(skip_serializing_if = "Option::is_none")]
    radec_deg: Option<(f64, f64)>,
    magnification: f64,
    /// "+" or "-": the sign of the magnification.
    parity: &'static str,
    /// "minimum", "saddle" or "maximum" of the arrival time.
    kind: &'static str,
    /// Days after the first image to arrive (0 for it).
    delay_days: f64,
}

/// `psi(b) - psi(a)` (arcsec^2, `D_ls/D_s = 1`); `None` off the maps.
type PotentialDifference<'a> = Box<dyn Fn(DVec2, DVec2) -> Option<f64> + 'a>;

/// Where the lens comes from: an analytic lens, or maps.
enum Source {
    Lens {
        lens: Box<dyn MassComponent>,
        plane: LensPlane,
        reference: Option<SkyReference>,
    },
    Maps {
        maps: Box<LensMaps>,
        plane: LensPlane,
        reference: Option<SkyReference>,
    },
}

pub fn run(args: &ImagesArgs) -> Result<(), String> {
    let source = load(args)?;
    let (plane, reference) = match &source {
        Source::Lens {
            plane, reference, ..
        }
        | Source::Maps {
            plane, reference, ..
        } => (*plane, *reference),
    };
    let beta = match (&args.source, &args.source_radec) {
        (Some(xy), _) => DVec2::new(xy[0], xy[1]),
        (None, Some(radec)) => {
            let reference = reference.ok_or(
                "--source-radec needs a lens with a sky reference (the model file's \
                 `reference`, the .par's `reference`, or the maps' WCS); give --source X Y",
            )?;
            let ra =
                parse_sky_angle(&radec[0], true).map_err(|e| format!("--source-radec: {e}"))?;
            let dec =
                parse_sky_angle(&radec[1], false).map_err(|e| format!("--source-radec: {e}"))?;
            reference.to_offset_arcsec(ra, dec)
        }
        (None, None) => unreachable!("clap requires one of them"),
    };
    if !beta.is_finite() {
        return Err(format!(
            "--source: ({}, {}) is not a position",
            beta.x, beta.y
        ));
    }
    let f = plane
        .distance_ratio(args.z_source)
        .map_err(|e| e.to_string())?;
    let search = ImageSearch::default();
    let (found, method, psi): (Vec<_>, String, PotentialDifference) = match &source {
        Source::Lens { lens, .. } => {
            if !(args.size.is_finite() && (1.0..=3600.0).contains(&args.size)) {
                return Err(format!("--size {} must be in [1, 3600] arcsec", args.size));
            }
            // Half-arcsec pixels or finer, as the image finder's grid.
            let pixels = ((2.0 * args.size) as usize).clamp(64, 1024);
            let grid = SearchGrid::Lens(MapGeometry::centered(args.size, pixels));
            let found =
                find_images(lens.as_ref(), grid, f, beta, &search).map_err(|e| e.to_string())?;
            let method = format!(
                "lens equation solved on the model itself over {} arcsec ({} x {} \
                     seed grid), Newton-refined to 1e-11 arcsec in the source plane; potential \
                     differences integrated along straight segments",
                args.size, pixels, pixels
            );
            let psi = move |a: DVec2, b: DVec2| Some(potential_difference(lens.as_ref(), a, b));
            (found, method, Box::new(psi))
        }
        Source::Maps { maps, .. } => {
            // Interpolated maps are good to a fraction of a pixel: Newton stops at 1e-3 arcsec.
            let on_maps = ImageSearch {
                tolerance_arcsec: 1e-3,
                ..search
            };
            let found = find_images(
                &InterpolatedLens(maps),
                SearchGrid::Maps(maps),
                f,
                beta,
                &on_maps,
            )
            .map_err(|e| e.to_string())?;
            let g = maps.geometry();
            let method = format!(
                "lens equation solved on the deflection maps ({} x {} pixels of {:.3} \
                     arcsec, interpolated) to 1e-3 arcsec; potential from the maps integrated",
                g.pixels,
                g.pixels,
                g.pixel_arcsec()
            );
            let map = potential_map(maps);
            let psi = move |a: DVec2, b: DVec2| {
                Some(potential_at(&map, maps, b)? - potential_at(&map, maps, a)?)
            };
            (found, method, Box::new(psi))
        }
    };
    if found.is_empty() {
        return Err(format!(
            "no image of a source at ({:.3}, {:.3}) arcsec was found in the searched field",
            beta.x, beta.y
        ));
    }
    let origin = found[0].position;
    let mut images: Vec<(f64, ImageOut)> = Vec::new();
    for i in &found {
        let dpsi = psi(origin, i.position).ok_or_else(|| {
            format!(
                "the image at ({:.2}, {:.2}) arcsec lies outside the maps",
                i.position.x, i.position.y
            )
        })?;
        let t = arrival_time_days(&plane, args.z_source, i.position, beta, dpsi)
            .map_err(|e| e.to_string())?;
        images.push((
            t,
            ImageOut {
                position_arcsec: i.position,
                radec_deg: reference.map(|r| r.offset_to_radec(i.position)),
                magnification: i.magnification,
                parity: match i.parity {
                    Parity::Positive => "+",
                    Parity::Negative => "-",
                },
                kind: match i.kind {
                    ImageKind::Minimum => "minimum",
                    ImageKind::Saddle => "saddle",
                    ImageKind::Maximum => "maximum",
                },
                delay_days: 0.0,
            },
        ));
    }
    images.sort_by(|a, b| a.0.total_cmp(&b.0));
    let first = images[0].0;
    let report = ImagesReport {
        z_lens: plane.z_lens,
        z_source: args.z_source,
        distance_ratio: f,
        source_arcsec: beta,
        source_radec_deg: reference.map(|r| r.offset_to_radec(beta)),
        method,
        images: images
            .into_iter()
            .map(|(t, mut i)| {
                i.delay_days = t - first;
                i
            })
            .collect(),
    };
    println!(
        "{}",
        serde_json::to_string_pretty(&report).expect("the report serialises")
    );
    Ok(())
}

fn load(args: &ImagesArgs) -> Result<Source, String> {
    if let Some(path) = &args.model {
        let text = read_text(path, InputKind::Model)?;
        let model = ModelFile::from_json_str(&text, &path.display().to_string())
            .map_err(|e| e.to_string())?;
        return Ok(Source::Lens {
            lens: Box::new(model.build_lens().map_err(|e| e.to_string())?),
            plane: model.lens_plane().map_err(|e| e.to_string())?,
            reference: model.reference,
        });
    }
    if let Some(path) = &args.lenstool {
        let options = ParOptions {
            single_plane: args.single_plane,
        };
        let model = load_lenstool(path, &args.potfile, &options)?;
        return Ok(Source::Lens {
            lens: Box::new(model.lens),
            plane: model.plane,
            reference: model.reference,
        });
    }
    let dir = args.maps.as_deref().expect("clap requires a lens");
    maps_source(dir, args.z_lens)
}

/// The deflection maps of `dir` as a lens: see [`read_maps_dir`].
fn maps_source(dir: &Path, z_lens: Option<f64>) -> Result<Source, String> {
    let (maps, plane, reference) = read_maps_dir(dir, z_lens)?;
    Ok(Source::Maps {
        maps: Box::new(maps),
        plane,
        reference,
    })
}

/// The HFF-style maps of `dir` (`x-arcsec-deflect.fits`, `y-arcsec-deflect.fits`, both at
/// `D_ls/D_s = 1`), their sky reference and the lens plane at `z_lens`, else at the maps'
/// `ZLENS` card, in the default cosmology.
pub(super) fn read_maps_dir(
    dir: &Path,
    z_lens: Option<f64>,
) -> Result<(LensMaps, LensPlane, Option<SkyReference>), String> {
    let x = dir.join("x-arcsec-deflect.fits");
    let y = dir.join("y-arcsec-deflect.fits");
    let (ax, reference, card_z) = read_map(&x)?;
    let (ay, _, _) = read_map(&y)?;
    let given = z_lens.is_some();
    let z_lens = match z_lens {
        Some(z) => z,
        None => card_z?.ok_or_else(|| {
            format!(
                "{}: no ZLENS card says the lens redshift; give --z-lens",
                x.display()
            )
        })?,
    };
    let plane = LensPlane::new(Cosmology::default(), z_lens).map_err(|e| match given {
        true => e.to_string(),
        false => format!("{}: its ZLENS card: {e}", x.display()),
    })?;
    let maps = LensMaps::from_deflection(ax, ay).map_err(|e| e.to_string())?;
    Ok((maps, plane, reference))
}
