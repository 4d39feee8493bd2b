//! The bodies of the fuzz targets, shared by `fuzz/fuzz_targets/*.rs` (cargo fuzz) and
//! `tests/fuzz_corpus.rs` (which replays the committed corpus and regressions under plain
//! `cargo test`). Each body takes the raw input, feeds it to one parser family the way a
//! user's file reaches it, and checks properties beyond "no panic": what parses writes back
//! and parses to the same values (where a writer exists or a faithful one is a few lines).
//! A property violation panics, as a crash would.
#![allow(dead_code)] // each fuzz binary uses one body

use std::fmt::Write as _;

use glam::DVec2;

use wslap::parse_par;
use wslap::MassComponent;
use wslap::ModelFile;
use wslap::ReconstructConfig;
use wslap::SkyReference;
use wslap::{arclet_ellipticity, parse_arclet_catalog};
use wslap::{arcs_from_regions, parse_arcs, ArcCatalog};
use wslap::{parse_image_catalog, parse_member_catalog, ImageCatalog, MemberCatalog};
use wslap::{read_image, write_image, FitsWriteOptions};
use wslap::{read_regions, Ds9Frame, Region, Shape};
use wslap::{Map, MapGeometry};

/// A target's body.
pub type Target = fn(&[u8]);

/// Every target by the name of its corpus directory (`fuzz/corpus/<name>/`).
pub const TARGETS: &[(&str, Target)] = &[
    ("image_catalog", image_catalog),
    ("member_catalog", member_catalog),
    ("arclet_catalog", arclet_catalog),
    ("arcs_json", arcs_json),
    ("ds9_regions", ds9_regions),
    ("lenstool_par", lenstool_par),
    ("fits_read", fits_read),
    ("fits_roundtrip", fits_roundtrip),
    ("model_json", model_json),
    ("settings_json", settings_json),
    ("project_json", project_json),
];

/// The input as text the way the app and the CLI get it (invalid UTF-8 is refused before any
/// parser sees it).
fn text(data: &[u8]) -> Option<&str> {
    std::str::from_utf8(data).ok()
}

/// Whether the catalogue's positions are arcsec offsets (`#REFERENCE 1` or `3` header): only
/// those round-trip exactly through a `#REFERENCE 3` file.
fn relative_header(text: &str) -> bool {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    for line in text.lines() {
        let t = line.trim();
        if !t.starts_with('#') {
            if t.is_empty() {
                continue;
            }
            return false;
        }
        let key = "#REFERENCE";
        if t.len() >= key.len()
            && t.is_char_boundary(key.len())
            && t[..key.len()].eq_ignore_ascii_case(key)
            && t[key.len()..]
                .chars()
                .next()
                .is_none_or(char::is_whitespace)
        {
            return matches!(t.split_whitespace().nth(1), Some("1" | "3"));
        }
    }
    false
}

fn reference_header(r: Option<SkyReference>) -> String {
    let r = r.expect("a parsed catalogue has a reference");
    format!("#REFERENCE 3 {:?} {:?}\n", r.ra_deg, r.dec_deg)
}

/// A Lenstool image catalogue of `c` (the project has no general catalogue writer; this is
/// the format's definition, numbers written exactly).
fn write_image_catalog(c: &ImageCatalog) -> String {
    let mut out = reference_header(c.reference);
    for s in &c.systems {
        for im in &s.images {
            let _ = writeln!(
                out,
                "{} {:?} {:?} {:?} {:?} {:?} {:?} {:?}",
                im.id,
                im.position.x,
                im.position.y,
                im.a_arcsec,
                im.b_arcsec,
                im.theta_deg,
                s.z.unwrap_or(0.0),
                im.mag
            );
        }
    }
    out
}

fn write_member_catalog(c: &MemberCatalog) -> String {
    let mut out = reference_header(c.reference);
    for m in &c.members {
        let _ = writeln!(
            out,
            "{} {:?} {:?} {:?} {:?} {:?} {:?} {:?}",
            m.id, m.position.x, m.position.y, m.a_arcsec, m.b_arcsec, m.theta_deg, m.mag, m.lum
        );
    }
    out
}

/// Same rows: everything but the line numbers; a system's z (a mean of its images') to a
/// few ulp.
fn same_images(a: &ImageCatalog, b: &ImageCatalog) -> bool {
    a.reference == b.reference
        && a.systems.len() == b.systems.len()
        && a.systems.iter().zip(&b.systems).all(|(s, t)| {
            let z_ok = match (s.z, t.z) {
                (None, None) => true,
                (Some(x), Some(y)) => (x - y).abs() <= 1e-14 * x.abs(),
                _ => false,
            };
            z_ok && s.id == t.id
                && s.images.len() == t.images.len()
                && s.images.iter().zip(&t.images).all(|(i, j)| {
                    i.id == j.id
                        && i.position == j.position
                        && i.a_arcsec == j.a_arcsec
                        && i.b_arcsec == j.b_arcsec
                        && i.theta_deg == j.theta_deg
                        && i.mag == j.mag
                })
        })
}

/// Lenstool image catalogue (`app` role "images", `wslap reconstruct --images`).
pub fn image_catalog(data: &[u8]) {
    let Some(text) = text(data) else { return };
    let Ok((cat, _)) = parse_image_catalog(text, "images.cat", None) else {
        return;
    };
    assert!(cat.image_count() > 0);
    let written = write_image_catalog(&cat);
    match parse_image_catalog(&written, "images.cat", None) {
        Ok((again, _)) => assert!(
            same_images(&cat, &again),
            "rows changed on a round trip:\n{cat:?}\n{again:?}\nwritten:\n{written}"
        ),
        // Absolute positions become offsets: the unit checks may then judge them otherwise.
        Err(e) => assert!(
            !relative_header(text),
            "a relative catalogue that parsed does not parse again: {e}\nwritten:\n{written}"
        ),
    }
}

/// Lenstool arclet catalogue (`wslap reconstruct --shear`, the app's "Arclets" file): what
/// parses is usable as weak-lensing rows (finite positions, `z > 0`, an ellipticity that is
/// the catalogue's `a`, `b`, `theta` and at most 1 in size), and the same rows parse again
/// from a catalogue written back in the header's frame.
pub fn arclet_catalog(data: &[u8]) {
    let Some(text) = text(data) else { return };
    let Ok((cat, _)) = parse_arclet_catalog(text, "arclets.cat", None) else {
        return;
    };
    assert!(!cat.arclets.is_empty());
    for a in &cat.arclets {
        assert!(a.position.is_finite(), "{a:?}");
        assert!(a.z > 0.0 && a.z.is_finite(), "{a:?}");
        assert!(
            a.ellipticity.is_finite() && a.ellipticity.length() <= 1.0 + 1e-12,
            "{a:?}"
        );
        assert_eq!(
            a.ellipticity,
            arclet_ellipticity(a.a_arcsec, a.b_arcsec, a.theta_deg),
            "{a:?}"
        );
    }
    if relative_header(text) {
        let mut written = String::new();
        if let Some(r) = cat.reference {
            let _ = writeln!(written, "#REFERENCE 3 {:?} {:?}", r.ra_deg, r.dec_deg);
        }
        for a in &cat.arclets {
            let _ = writeln!(
                written,
                "{} {:?} {:?} {:?} {:?} {:?} {:?}",
                a.id, a.position.x, a.position.y, a.a_arcsec, a.b_arcsec, a.theta_deg, a.z
            );
        }
        if let Ok((again, _)) = parse_arclet_catalog(&written, "arclets.cat", None) {
            let same = again.arclets.len() == cat.arclets.len()
                && again.arclets.iter().zip(&cat.arclets).all(|(p, q)| {
                    p.position == q.position && p.ellipticity == q.ellipticity && p.z == q.z
                });
            assert!(same, "rows changed on a round trip:\nwritten:\n{written}");
        }
    }
}

/// Lenstool member catalogue (potfile).
pub fn member_catalog(data: &[u8]) {
    let Some(text) = text(data) else { return };
    let Ok((cat, _)) = parse_member_catalog(text, "members.cat", None) else {
        return;
    };
    let written = write_member_catalog(&cat);
    match parse_member_catalog(&written, "members.cat", None) {
        Ok((again, _)) => {
            let same = cat.reference == again.reference
                && cat.members.len() == again.members.len()
                && cat.members.iter().zip(&again.members).all(|(m, n)| {
                    m.id == n.id
                        && m.position == n.position
                        && m.a_arcsec == n.a_arcsec
                        && m.b_arcsec == n.b_arcsec
                        && m.theta_deg == n.theta_deg
                        && m.mag == n.mag
                        && m.lum == n.lum
                });
            assert!(same, "rows changed on a round trip:\n{cat:?}\n{again:?}");
        }
        Err(e) => assert!(
            !relative_header(text),
            "a relative catalogue that parsed does not parse again: {e}\nwritten:\n{written}"
        ),
    }
}

fn write_arcs(c: &ArcCatalog) -> String {
    let systems: Vec<serde_json::Value> = c
        .systems
        .iter()
        .map(|s| {
            let images: Vec<Vec<[f64; 2]>> = s
                .images
                .iter()
                .map(|im| im.iter().map(|p| [p.x, p.y]).collect())
                .collect();
            serde_json::json!({"id": s.id, "z": s.z, "images": images})
        })
        .collect();
    serde_json::json!({ "systems": systems }).to_string()
}

/// Arc pixels, JSON (`app` role "arcs" when the text starts with `{`).
pub fn arcs_json(data: &[u8]) {
    let Some(text) = text(data) else { return };
    let Ok(arcs) = parse_arcs(text, "arcs.json") else {
        return;
    };
    let written = write_arcs(&arcs);
    let again = parse_arcs(&written, "arcs.json")
        .unwrap_or_else(|e| panic!("written arcs do not parse: {e}\n{written}"));
    let strip = |c: &ArcCatalog| {
        let mut c = c.clone();
        c.systems.iter_mut().for_each(|s| s.line = 0);
        c
    };
    assert_eq!(strip(&arcs), strip(&again), "arcs changed on a round trip");
}

/// DS9 region text of `regions`, numbers written exactly (only the text label is kept of
/// the properties).
fn write_regions(regions: &[Region]) -> String {
    let mut out = String::from("# Region file format: DS9 version 4.1\n");
    let mut frame = None;
    for r in regions {
        if frame != Some(r.frame) {
            out.push_str(match r.frame {
                Ds9Frame::Fk5 => "fk5\n",
                Ds9Frame::Image => "image\n",
            });
            frame = Some(r.frame);
        }
        let len = |v: f64| match r.frame {
            Ds9Frame::Fk5 => format!("{v:?}\""),
            Ds9Frame::Image => format!("{v:?}"),
        };
        let pts = |p: &[DVec2]| {
            p.iter()
                .map(|p| format!("{:?},{:?}", p.x, p.y))
                .collect::<Vec<_>>()
                .join(",")
        };
        let body = match &r.shape {
            Shape::Polygon(p) => format!("polygon({})", pts(p)),
            Shape::Polyline(p) => format!("segment({})", pts(p)),
            Shape::Point(p) => format!("point({})", pts(&[*p])),
            Shape::Circle { center, radius } => {
                format!("circle({},{})", pts(&[*center]), len(*radius))
            }
            Shape::Ellipse {
                center,
                radii,
                angle_deg,
            } => format!(
                "ellipse({},{},{},{angle_deg:?})",
                pts(&[*center]),
                len(radii.x),
                len(radii.y)
            ),
            Shape::Box {
                center,
                size,
                angle_deg,
            } => format!(
                "box({},{},{},{angle_deg:?})",
                pts(&[*center]),
                len(size.x),
                len(size.y)
            ),
        };
        let sign = if r.include { "" } else { "-" };
        // DS9 quotes a label with {}, "" or '': the first that does not close inside it.
        let label = match &r.text {
            Some(t) if !t.contains('}') => format!(" # text={{{t}}}"),
            Some(t) if !t.contains('"') => format!(" # text=\"{t}\""),
            Some(t) if !t.contains('\'') => format!(" # text='{t}'"),
            _ => String::new(),
        };
        let _ = writeln!(out, "{sign}{body}{label}");
    }
    out
}

/// DS9 regions: the parser, each region in arcsec, and the arcs the app and `wslap
/// reconstruct --arcs` make of a region file.
pub fn ds9_regions(data: &[u8]) {
    let Some(text) = text(data) else { return };
    if let Ok(regions) = read_regions(text, "arcs.reg") {
        let reference = SkyReference::new(197.87, -1.34);
        let geometry = MapGeometry::centered(100.0, 200);
        for r in &regions {
            let _ = r.to_frame_arcsec(reference, Some(&geometry));
        }
        let written = write_regions(&regions);
        let again = read_regions(&written, "arcs.reg")
            .unwrap_or_else(|e| panic!("written regions do not parse: {e}\n{written}"));
        assert_eq!(regions.len(), again.len(), "written:\n{written}");
        for (a, b) in regions.iter().zip(&again) {
            let writable = |t: &String| !(t.contains('}') && t.contains('"') && t.contains('\''));
            let text = a.text.as_ref().filter(|t| writable(t));
            assert_eq!(
                (a.frame, &a.shape, text, a.include),
                (b.frame, &b.shape, b.text.as_ref(), b.include),
                "a region changed on a round trip; written:\n{written}"
            );
        }
    }
    // A coarse lattice: the pixel limit (1e6) is what bounds the work, not the pitch.
    let _ = arcs_from_regions(text, "arcs.reg", None, 0.5, &|_| Some(2.0));
}

/// A member catalogue for the `potfile` blocks of a fuzzed `.par`.
const PAR_MEMBERS: &str = "#REFERENCE 3 197.87 -1.34\n\
    1 0.0 0.0 1.2 0.9 30 17.5 1.0\n\
    2 12.5 -8.0 0.6 0.4 -20 19.0 0.3\n\
    3 -20.0 15.0 0.4 0.4 0 20.5 0.1\n";

/// Points where a built lens is evaluated (the centre, near it, and out in the field).
const PROBES: [DVec2; 4] = [
    DVec2::new(0.0, 0.0),
    DVec2::new(0.37, -0.21),
    DVec2::new(25.0, 14.0),
    DVec2::new(-300.0, 410.0),
];

/// Lenstool `.par`: parsed, built with a member catalogue per potfile, evaluated.
pub fn lenstool_par(data: &[u8]) {
    let Some(text) = text(data) else { return };
    let Ok(par) = parse_par(text, "model.par") else {
        return;
    };
    if par.potfiles.len() > 8 {
        return;
    }
    let texts: Vec<(&str, &str)> = par
        .potfiles
        .iter()
        .map(|_| ("members.cat", PAR_MEMBERS))
        .collect();
    if let Ok((model, _)) = par.build_from_texts(&texts) {
        for p in PROBES {
            let _ = model.lens.deflection_hessian(p);
            let _ = model.lens.kappa(p);
        }
    }
}

/// FITS maps as the app and `wslap maps --deflection` read them.
pub fn fits_read(data: &[u8]) {
    let Ok(image) = read_image(data, "map.fits") else {
        return;
    };
    assert_eq!(image.data.len(), image.width * image.height);
    let _ = image.non_finite_count();
    if let Ok((map, _)) = image.to_map_filled(0.0) {
        let _ = map.sample(DVec2::new(1.5, -2.5));
    }
    let Ok(map) = image.to_map() else { return };
    let Ok((_, reference)) = image.geometry() else {
        return;
    };
    // A map that reads writes back (as float32) and reads again to the same values.
    let opts = FitsWriteOptions {
        reference,
        ..FitsWriteOptions::default()
    };
    if let Ok(bytes) = write_image(&map, &opts) {
        let again = read_image(&bytes, "again.fits").expect("a written map reads");
        for (a, b) in map.data.iter().zip(&again.data) {
            assert_eq!((*a as f32 as f64).to_bits(), b.to_bits());
        }
    }
}

/// Reads `N` bytes from the front of `data` (zeros when it runs out).
fn take<const N: usize>(data: &mut &[u8]) -> [u8; N] {
    let mut out = [0u8; N];
    let n = N.min(data.len());
    out[..n].copy_from_slice(&data[..n]);
    *data = &data[n..];
    out
}

/// The project's FITS writer on fuzzed sizes, geometry, sky reference and values: what it
/// writes reads back with bit-identical pixels and the same geometry.
pub fn fits_roundtrip(data: &[u8]) {
    let mut d = data;
    let [side, flags] = take::<2>(&mut d);
    let pixels = 1 + side as usize % 64;
    let pixel_arcsec = f64::from_le_bytes(take(&mut d));
    let center = DVec2::new(
        f64::from_le_bytes(take(&mut d)),
        f64::from_le_bytes(take(&mut d)),
    );
    let reference = if flags & 1 == 1 {
        SkyReference::new(
            f64::from_le_bytes(take(&mut d)),
            f64::from_le_bytes(take(&mut d)),
        )
    } else {
        None
    };
    let values: Vec<f64> = (0..pixels * pixels)
        .map(|_| f32::from_le_bytes(take(&mut d)) as f64)
        .collect();
    let map = Map {
        geometry: MapGeometry {
            pixels,
            size_arcsec: pixel_arcsec * pixels as f64,
            center,
        },
        data: values,
    };
    let opts = FitsWriteOptions {
        bunit: "arcsec".into(),
        comments: vec!["fuzzed map".into()],
        reference,
        extra_cards: Vec::new(),
    };
    // The writer may refuse a map (non-finite values, a pixel or centre it cannot write); what
    // it writes must read back.
    let Ok(bytes) = write_image(&map, &opts) else {
        return;
    };
    assert_eq!(bytes.len() % 2880, 0);
    let image = read_image(&bytes, "map.fits").expect("a written map reads");
    assert_eq!((image.width, image.height), (pixels, pixels));
    for (a, b) in map.data.iter().zip(&image.data) {
        assert_eq!(a.to_bits(), b.to_bits(), "a pixel changed");
    }
    let (g, r) = match image.geometry() {
        Ok(x) => x,
        Err(e) => panic!("a written map's WCS does not read: {e}\n{map:?}"),
    };
    assert_eq!(g.pixels, pixels);
    let rel = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs());
    assert!(
        rel(g.size_arcsec, map.geometry.size_arcsec),
        "{g:?} {:?}",
        map.geometry
    );
    match (r, reference) {
        (None, None) => {}
        (Some(a), Some(b)) => assert!(rel(a.ra_deg, b.ra_deg) && rel(a.dec_deg, b.dec_deg)),
        _ => panic!("the sky reference changed: {r:?} {reference:?}"),
    }
}

/// Model JSON (forward mode): parsed, written, parsed again to the same model, evaluated.
pub fn model_json(data: &[u8]) {
    let Some(text) = text(data) else { return };
    let Ok(model) = ModelFile::from_json_str(text, "model.json") else {
        return;
    };
    let written = model.to_json_string();
    let again = ModelFile::from_json_str(&written, "model.json")
        .unwrap_or_else(|e| panic!("a written model does not parse: {e}\n{written}"));
    assert_eq!(model, again);
    if model.components.len() <= 64 {
        if let Ok(lens) = model.build_lens() {
            for p in PROBES {
                let _ = lens.deflection_hessian(p);
            }
        }
    }
}

/// Reconstruction settings (`CONFIG.json`) and the app's settings (the same JSON inside the
/// app's).
pub fn settings_json(data: &[u8]) {
    let Some(text) = text(data) else { return };
    if let Ok(c) = ReconstructConfig::from_json_str(text, "config.json") {
        let written = serde_json::to_string(&c).expect("settings serialise");
        let again = ReconstructConfig::from_json_str(&written, "config.json")
            .unwrap_or_else(|e| panic!("written settings do not parse: {e}\n{written}"));
        assert_eq!(c, again);
    }
    if let Ok(s) = wslap::app::AppSettings::from_json_str(text, "settings.json") {
        let written = serde_json::to_string(&s).expect("settings serialise");
        let again = wslap::app::AppSettings::from_json_str(&written, "settings.json")
            .unwrap_or_else(|e| panic!("written settings do not parse: {e}\n{written}"));
        assert_eq!(s, again);
    }
}

/// Project files: the JSON round trip, and opening the project (every data file it holds
/// read by its parser; the stored result left out, since reopening it runs the solver).
pub fn project_json(data: &[u8]) {
    let Some(text) = text(data) else { return };
    let Ok(mut p) = serde_json::from_str::<wslap::app::Project>(text) else {
        return;
    };
    let written = serde_json::to_string(&p).expect("a project serialises");
    let again: wslap::app::Project = serde_json::from_str(&written)
        .unwrap_or_else(|e| panic!("a written project does not parse: {e}\n{written}"));
    assert_eq!(p, again);
    p.result = None;
    let without_result = serde_json::to_string(&p).expect("a project serialises");
    let mut session = wslap::app::Session::new();
    if session.open_project(&without_result, "fuzz.wslap").is_ok() {
        let reopened = session.project_json().expect("an opened project saves");
        let mut fresh = wslap::app::Session::new();
        fresh
            .open_project(&reopened, "again.wslap")
            .unwrap_or_else(|e| panic!("a saved project does not open: {e}"));
    }
}
