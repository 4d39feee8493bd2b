//! `wslap lookup`: kappa, shear and magnification of a lens's maps at given sky positions, with
//! the ensemble's magnification interval where there is one.

use std::path::{Path, PathBuf};

use clap::Args;
use glam::DVec2;
use serde::Serialize;
use wslap::{
    magnification_at_point, parse_sky_angle, InputKind, LensMaps, Map, TooLarge, MAX_CATALOG_ROWS,
};

use super::images::read_maps_dir;
use super::input::read_text;
use super::maps::read_map;

/// Kappa, shear and magnification at sky positions, as JSON.
///
/// Reads a folder of HFF-style maps (a `wslap reconstruct` or `wslap maps` output, or a
/// published model): the deflection pair x/y-arcsec-deflect.fits (kappa.fits, gamma1.fits and
/// gamma2.fits too when present, more accurate than the deflections' derivatives) and, when
/// present, the ensemble's magnif-p16.fits and magnif-p84.fits of `--ensemble` (at their
/// ZSOURCE). Prints per position: kappa and |gamma| at the source redshift, the magnification
/// there and its 16th - 84th percentile interval over the ensemble.
#[derive(Debug, Args)]
#[command(group(clap::ArgGroup::new("where").required(true).args(["at", "at_arcsec", "positions"])))]
pub struct LookupArgs {
    /// The folder of maps.
    #[arg(long, value_name = "DIR")]
    maps: PathBuf,
    /// A sky position: RA and Dec in degrees or sexagesimal (22:48:44.0 -44:31:51).
    #[arg(long, num_args = 2, value_names = ["RA", "DEC"], allow_negative_numbers = true)]
    at: Option<Vec<String>>,
    /// A position in arcsec in the maps' frame (+x West, +y North).
    #[arg(long, num_args = 2, value_names = ["X", "Y"], allow_negative_numbers = true)]
    at_arcsec: Option<Vec<f64>>,
    /// A text file of positions, one per line: `[id] RA DEC` (degrees or sexagesimal); `#`
    /// starts a comment.
    #[arg(long, value_name = "FILE")]
    positions: Option<PathBuf>,
    /// Source redshift.
    #[arg(long, allow_negative_numbers = true)]
    z_source: f64,
    /// Lens redshift (default: the maps' ZLENS card).
    #[arg(long, allow_negative_numbers = true)]
    z_lens: Option<f64>,
}

#[derive(Debug, Serialize)]
struct LookupReport {
    z_lens: f64,
    z_source: f64,
    distance_ratio: f64,
    /// Where the interval comes from, or why there is none.
    interval: String,
    positions: Vec<PositionOut>,
}

#[derive(Debug, Serialize)]
struct PositionOut {
    #[serde(skip_serializing_if = "Option::is_none")]
    id: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    radec_deg: Option<(f64, f64)>,
    position_arcsec: DVec2,
    /// `false` outside the maps or where they have no data: the values below are then absent.
    has_data: bool,
    /// Convergence and shear at the source redshift (`f kappa`, `f |gamma|`).
    #[serde(skip_serializing_if = "Option::is_none")]
    kappa: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    gamma: Option<f64>,
    /// Signed magnification at the source redshift.
    #[serde(skip_serializing_if = "Option::is_none")]
    magnification: Option<f64>,
    /// 16th and 84th percentiles of the magnification over the ensemble.
    #[serde(skip_serializing_if = "Option::is_none")]
    magnification_interval: Option<[f64; 2]>,
}

/// One position asked for.
struct Position {
    id: Option<String>,
    radec: Option<(f64, f64)>,
    arcsec: Option<DVec2>,
}

pub fn run(args: &LookupArgs) -> Result<(), String> {
    let (mut maps, plane, reference) = read_maps_dir(&args.maps, args.z_lens)?;
    use_kappa_and_shear(&args.maps, &mut maps)?;
    let f = plane
        .distance_ratio(args.z_source)
        .map_err(|e| e.to_string())?;
    let (interval, bands) = ensemble_bands(&args.maps, args.z_source, &maps)?;
    let positions = positions(args)?;
    let mut out = Vec::new();
    for p in positions {
        let theta = match (p.arcsec, p.radec) {
            (Some(x), _) => x,
            (None, Some((ra, dec))) => reference
                .ok_or_else(|| {
                    format!(
                        "{}: the maps have no sky reference (WCS), so RA/Dec cannot be placed; \
                         give --at-arcsec X Y",
                        args.maps.display()
                    )
                })?
                .to_offset_arcsec(ra, dec),
            (None, None) => unreachable!("every position has one"),
        };
        let g = maps.geometry();
        let inside = (theta - g.center).abs().max_element() <= 0.5 * g.size_arcsec;
        let sample = |m: &Map| Some(m.sample(theta)).filter(|v| inside && v.is_finite());
        let fields = (|| {
            Some((
                sample(&maps.kappa)?,
                sample(&maps.gamma1)?,
                sample(&maps.gamma2)?,
            ))
        })();
        let (kappa, gamma, mu) = match fields {
            Some((k, g1, g2)) => (
                Some(f * k),
                Some(f * g1.hypot(g2)),
                Some(magnification_at_point(f, k, g1, g2)),
            ),
            None => (None, None, None),
        };
        let magnification_interval = bands.as_ref().and_then(|(lo, hi)| {
            let (a, b) = (sample(lo)?, sample(hi)?);
            Some([a.min(b), a.max(b)])
        });
        out.push(PositionOut {
            id: p.id,
            radec_deg: p
                .radec
                .or_else(|| reference.map(|r| r.offset_to_radec(theta))),
            position_arcsec: theta,
            has_data: fields.is_some(),
            kappa,
            gamma,
            magnification: mu,
            magnification_interval,
        });
    }
    let report = LookupReport {
        z_lens: plane.z_lens,
        z_source: args.z_source,
        distance_ratio: f,
        interval,
        positions: out,
    };
    println!(
        "{}",
        serde_json::to_string_pretty(&report).expect("the report serialises")
    );
    Ok(())
}

/// Replaces the deflections' finite-difference kappa and shear by the folder's kappa.fits,
/// gamma1.fits and gamma2.fits when all three are there with the same pixels.
fn use_kappa_and_shear(dir: &Path, maps: &mut LensMaps) -> Result<(), String> {
    let paths = ["kappa.fits", "gamma1.fits", "gamma2.fits"].map(|n| dir.join(n));
    if !paths.iter().all(|p| p.exists()) {
        return Ok(());
    }
    let (k, g1, g2) = (
        read_map(&paths[0])?.0,
        read_map(&paths[1])?.0,
        read_map(&paths[2])?.0,
    );
    let g = maps.geometry();
    if [&k, &g1, &g2].iter().all(|m| m.geometry == g) {
        (maps.kappa, maps.gamma1, maps.gamma2) = (k, g1, g2);
    }
    Ok(())
}

/// The ensemble's magnification percentiles (16th, 84th) of `dir` when they exist for
/// `z_source`, with a sentence saying where the interval comes from or why there is none.
#[allow(clippy::type_complexity)] // the pair of maps, or none
fn ensemble_bands(
    dir: &Path,
    z_source: f64,
    maps: &LensMaps,
) -> Result<(String, Option<(Map, Map)>), String> {
    let (lo, hi) = (dir.join("magnif-p16.fits"), dir.join("magnif-p84.fits"));
    if !(lo.exists() && hi.exists()) {
        return Ok((
            "none: the folder has no magnif-p16.fits and magnif-p84.fits (run wslap \
             reconstruct --ensemble N)"
                .to_string(),
            None,
        ));
    }
    let z_of = |path: &Path| -> Result<Option<f64>, String> {
        let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let image =
            wslap::read_image(&bytes, &path.display().to_string()).map_err(|e| e.to_string())?;
        Ok(image.card("ZSOURCE").and_then(|c| c.as_f64()))
    };
    let z = z_of(&lo)?;
    if z.is_none_or(|z| (z - z_source).abs() > 1e-6) {
        return Ok((
            format!(
                "none at z_s = {z_source}: the ensemble's magnification maps are for z_s = {} \
                 (ask for that redshift, or run the ensemble at this one)",
                z.map_or("an unstated redshift".to_string(), |z| z.to_string())
            ),
            None,
        ));
    }
    let (a, b) = (read_map(&lo)?.0, read_map(&hi)?.0);
    if a.geometry != maps.geometry() || b.geometry != maps.geometry() {
        return Err(format!(
            "{}: its pixels differ from the deflection maps' of the same folder",
            lo.display()
        ));
    }
    Ok((
        "16th - 84th percentile of the ensemble's magnification maps (magnif-p16.fits, \
         magnif-p84.fits)"
            .to_string(),
        Some((a, b)),
    ))
}

fn positions(args: &LookupArgs) -> Result<Vec<Position>, String> {
    if let Some(radec) = &args.at {
        let ra = parse_sky_angle(&radec[0], true).map_err(|e| format!("--at: {e}"))?;
        let dec = parse_sky_angle(&radec[1], false).map_err(|e| format!("--at: {e}"))?;
        return Ok(vec![Position {
            id: None,
            radec: Some((ra, dec)),
            arcsec: None,
        }]);
    }
    if let Some(xy) = &args.at_arcsec {
        let p = DVec2::new(xy[0], xy[1]);
        if !p.is_finite() {
            return Err(format!(
                "--at-arcsec: ({}, {}) is not a position",
                xy[0], xy[1]
            ));
        }
        return Ok(vec![Position {
            id: None,
            radec: None,
            arcsec: Some(p),
        }]);
    }
    let path = args.positions.as_deref().expect("clap requires a position");
    let text = read_text(path, InputKind::Catalog)?;
    let name = path.display().to_string();
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let words: Vec<&str> = line.split_whitespace().collect();
        let (id, ra, dec) = match words[..] {
            [ra, dec] => (None, ra, dec),
            [id, ra, dec] => (Some(id.to_string()), ra, dec),
            _ => {
                return Err(format!(
                    "{}: line {}: expected `[id] RA DEC`, found {} words",
                    path.display(),
                    n + 1,
                    words.len()
                ))
            }
        };
        let at = |e: String| format!("{}: line {}: {e}", path.display(), n + 1);
        // Each position's answer is kept until all are written: as many as a catalogue's rows.
        let count = out.len() as u64 + 1;
        TooLarge::check(
            &name,
            "positions",
            count,
            MAX_CATALOG_ROWS as u64,
            "a look-up",
        )
        .map_err(|e| e.to_string())?;
        out.push(Position {
            id,
            radec: Some((
                parse_sky_angle(ra, true).map_err(at)?,
                parse_sky_angle(dec, false).map_err(at)?,
            )),
            arcsec: None,
        });
    }
    if out.is_empty() {
        return Err(format!("{}: no positions in the file", path.display()));
    }
    Ok(out)
}
