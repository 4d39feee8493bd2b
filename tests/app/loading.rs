//! Loading files without losing data, and settings: the teaching example's catalogue, a bad
//! file or a bad setting refused with the old one kept, DS9 regions loaded as arcs.

use crate::fixtures::teaching_session;
use serde_json::json;
use wslap::Control;
use wslap::{app::examples::teaching_image_catalog, app::examples::TEACHING_SOURCES};
use wslap::{app::DataRole, app::RunKind, app::Session};

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn teaching_catalogue_has_multiple_images_of_every_source() {
    let cat = teaching_image_catalog().unwrap();
    for (id, _, _) in TEACHING_SOURCES {
        let n = cat
            .lines()
            .filter(|l| l.starts_with(&format!("{id}.")))
            .count();
        assert!(n >= 2, "system {id} has {n} images:\n{cat}");
    }
}

#[cfg(not(target_arch = "wasm32"))]
#[test]
fn committed_teaching_catalogue_is_up_to_date() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("www/examples/teaching/images.cat");
    let fresh = teaching_image_catalog().unwrap();
    if std::env::var_os("WSLAP_REGENERATE").is_some() {
        std::fs::write(&path, &fresh).unwrap();
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert_eq!(
        committed,
        fresh,
        "run with WSLAP_REGENERATE=1 to rewrite {}",
        path.display()
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_bad_file_names_its_line_and_keeps_what_was_loaded() {
    let mut s = teaching_session();
    let before = s.data.images.clone();
    let err = s
        .load_text(
            DataRole::Images,
            "bad.cat",
            "1.1 1.0 2.0 0.1 0.1 0 1.5\n1.2 x 2.0 0.1 0.1 0 1.5\n",
        )
        .unwrap_err()
        .to_string();
    assert!(err.contains("bad.cat") && err.contains("line 2"), "{err}");
    assert_eq!(s.data.images, before);
    let err = s
        .load_text(DataRole::Arcs, "arcs.json", "{\n  \"systems\": [\n   oops")
        .unwrap_err();
    assert!(err.to_string().contains("line 3"), "{err}");
    assert!(s.data.arcs.is_none());
    // A member catalogue bad in itself has no code: only one a .par would read has.
    let err = s
        .load_text(DataRole::Members, "gal.cat", "1 x 2.0 0.1 0.1 0 19.5\n")
        .unwrap_err();
    assert_eq!(err.code(), None, "{err}");
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_bad_setting_is_refused_and_the_old_value_kept() {
    let mut s = Session::new();
    let err = s
        .set_field("reconstruct.grid.cells", json!(0))
        .unwrap_err()
        .to_string();
    assert!(err.contains("cells"), "{err}");
    assert_eq!(s.settings.reconstruct.grid.cells, 32);
    assert!(s.set_field("z_lens", json!(-1.0)).is_err());
    assert!(s.set_field("no.such.field", json!(1)).is_err());
    assert!(s
        .set_field("reconstruct.constraints.mode", json!("sideways"))
        .is_err());
    s.set_field("reconstruct.constraints.mode", json!("point"))
        .unwrap();
    s.set_field("reconstruct.grid.width_arcsec", json!(80.0))
        .unwrap();
    s.set_field("reconstruct.grid.width_arcsec", json!(null))
        .unwrap();
    assert_eq!(s.settings.reconstruct.grid.width_arcsec, None);
    let err = s
        .set_field("reconstruct.members.c_prior_sigma", json!(-0.1))
        .unwrap_err()
        .to_string();
    assert!(err.contains("c_prior_sigma"), "{err}");
    assert_eq!(s.settings.reconstruct.members.c_prior_sigma, None);
    s.set_field("reconstruct.members.c_prior_sigma", json!(0.1))
        .unwrap();
    assert_eq!(s.settings.reconstruct.members.c_prior_sigma, Some(0.1));
    // The curves' source behind the lens, whichever of the two redshifts is changed.
    let z_lens = s.settings.z_lens;
    let err = s
        .set_field("reconstruct.products.z_source", json!(z_lens))
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with("reconstruct.products.z_source: the curves' z_s = ")
            && err.contains("is not behind the lens"),
        "{err}"
    );
    let z_s = s.settings.reconstruct.products.z_source;
    assert!(z_s > z_lens);
    let err = s.set_field("z_lens", json!(z_s + 0.5)).unwrap_err();
    assert!(
        err.to_string().starts_with("z_lens: the curves' z_s"),
        "{err}"
    );
    assert_eq!(s.settings.z_lens, z_lens);
    assert_eq!(s.settings.reconstruct.products.z_source, z_s);
    // So must the redshift given to images with z = 0, and it keeps the lens where it is.
    let err = s
        .set_field("reconstruct.constraints.default_z", json!(z_lens))
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with(
            "reconstruct.constraints.default_z: the redshift for images with z = 0: z_s = "
        ) && err.contains("is not behind the lens"),
        "{err}"
    );
    assert_eq!(s.settings.reconstruct.constraints.default_z, None);
    s.set_field("reconstruct.constraints.default_z", json!(1.0))
        .unwrap();
    assert_eq!(s.settings.reconstruct.constraints.default_z, Some(1.0));
    assert!(z_s > 1.5);
    let err = s.set_field("z_lens", json!(1.5)).unwrap_err().to_string();
    assert!(err.contains("images with z = 0"), "{err}");
    assert_eq!(s.settings.z_lens, z_lens);
    s.set_field("reconstruct.constraints.default_z", json!(null))
        .unwrap();
    assert_eq!(
        s.settings.reconstruct.products.pixels,
        wslap::app::APP_MAP_PIXELS
    );
}

/// The teaching images drawn as DS9 circles (fk5) without redshifts in their labels, loaded as
/// arcs next to the image catalogue: the systems take the catalogue's redshifts, and the
/// reconstruction uses the regions' pixels (mode "arcs").
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn ds9_regions_load_as_arcs_with_the_catalogue_redshifts() {
    let mut s = teaching_session();
    let cat = teaching_image_catalog().unwrap();
    let (catalog, _) = wslap::parse_image_catalog(&cat, "images.cat", None).unwrap();
    let sky = catalog.reference.unwrap();
    let mut reg = String::from("# Region file format: DS9 version 4.1\nfk5\n");
    for im in catalog.images() {
        let (ra, dec) = sky.offset_to_radec(im.position);
        reg += &format!("circle({ra:.8},{dec:.8},0.4\") # text={{{}}}\n", im.id);
    }
    let report = s.load_text(DataRole::Arcs, "arcs.reg", &reg).unwrap();
    assert!(
        report.summary.starts_with("4 systems, ") && report.summary.contains("DS9 regions"),
        "{}",
        report.summary
    );
    s.set_field("reconstruct.constraints.mode", json!("arcs"))
        .unwrap();
    // A bad region file is refused with its line, and the good one stays.
    let bad = s
        .load_text(
            DataRole::Arcs,
            "bad.reg",
            "fk5\ncircle(150,2.2,1\") # text={1}\n",
        )
        .unwrap_err()
        .to_string();
    assert!(bad.contains("bad.reg: line 2: label '1'"), "{bad}");
    assert_eq!(s.data.arcs.as_ref().unwrap().name, "arcs.reg");
    s.run(RunKind::Reconstruct, &mut |_| Control::Continue)
        .unwrap();
    let r = s.result().unwrap();
    let rec = r.reconstruction().unwrap();
    let pixels = rec.config.constraints.pixel_arcsec;
    assert_eq!(rec.config.constraints.mode, wslap::ConstraintMode::Arcs);
    assert_eq!(rec.sources.len(), TEACHING_SOURCES.len());
    for (src, system) in rec.sources.iter().zip(&catalog.systems) {
        assert_eq!(src.z, system.z.unwrap(), "system {}", src.id);
    }
    // Arc pixels (about 12 per circle), drawn in the data's marks, in the catalogue's frame.
    let arcs = &r.marks.arcs;
    assert_eq!(arcs.len(), 4);
    for (a, system) in arcs.iter().zip(&catalog.systems) {
        for p in &a.pixels_arcsec {
            let nearest = system
                .images
                .iter()
                .map(|im| im.position.distance(*p))
                .fold(f64::INFINITY, f64::min);
            assert!(
                nearest <= 0.4 + 1e-6,
                "pixel {p} of {} is {nearest} arcsec off",
                a.id
            );
        }
        assert!(
            a.pixels_arcsec.len() >= 8 * system.images.len(),
            "{} pixels",
            a.pixels_arcsec.len()
        );
    }
    assert_eq!(r.marks.arc_pixel_mas, (pixels * 1000.0).round() as u32);
}

/// The constraint pixel samples loaded DS9 region arcs: a finer one gives more pixels (the
/// reloaded report says how many), and one that would exceed the arcs' pixel limit is refused,
/// keeping the old value.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn the_constraint_pixel_resamples_region_arcs() {
    let mut s = Session::new();
    let reg = "fk5\ncircle(150,2.2,20\") # text={1.1 z=2}\ncircle(150.01,2.2,20\") # text={1.2}\n";
    let count = |r: &wslap::app::LoadReport| -> usize {
        r.summary
            .split(", ")
            .nth(1)
            .unwrap()
            .split(' ')
            .next()
            .unwrap()
            .parse()
            .unwrap()
    };
    let at_02 = count(&s.load_text(DataRole::Arcs, "arcs.reg", reg).unwrap());
    s.set_field("reconstruct.constraints.pixel_arcsec", json!(0.1))
        .unwrap();
    let at_01 = count(&s.reload(DataRole::Arcs).unwrap().unwrap());
    // Twice the resolution, four times the pixels (2 x pi 20^2 / 0.01 = 251327).
    assert!(
        (at_01 as f64 / at_02 as f64 - 4.0).abs() < 0.01,
        "{at_02} -> {at_01}"
    );
    let err = s
        .set_field("reconstruct.constraints.pixel_arcsec", json!(0.02))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains(
            "reconstruct.constraints.pixel_arcsec: arcs.reg: line 2: the regions up to here hold"
        ),
        "{err}"
    );
    assert_eq!(s.settings.reconstruct.constraints.pixel_arcsec, 0.1);
    assert!(s.reload(DataRole::Members).unwrap().is_none());
    // Without a catalogue the frame is the regions' mean position, and the run says so.
    let parsed = s.parsed().unwrap();
    let r = parsed.reference().unwrap();
    assert!(
        (r.ra_deg - 150.005).abs() < 1e-9 && (r.dec_deg - 2.2).abs() < 1e-9,
        "{r:?}"
    );
    assert!(
        parsed
            .warnings
            .iter()
            .any(|w| w.contains("arcs.reg: no catalogue gives a frame")),
        "{:?}",
        parsed.warnings
    );
}

/// Real catalogues (`../shared/data`): those of one cluster, and the a1689-sim example's files,
/// say nothing about the sky; AS1063's images with MACS1931's members are named as apart, with
/// the files and positions, in the warning of the loaded files and of the run's data.
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn files_of_two_clusters_are_named_and_of_one_cluster_are_not() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let read = |path: &str| std::fs::read_to_string(root.join(path)).unwrap();
    let load = |files: &[(DataRole, &str)]| {
        let mut s = Session::new();
        for (role, path) in files {
            let name = path.rsplit('/').next().unwrap();
            s.load_text(*role, name, &read(path)).unwrap();
        }
        s
    };
    let as1063 = "../shared/data/AS1063/lenstool_cats/";
    let macs1931 = "../shared/data/MACS1931/lenstool_cats/";
    let gold = format!("{as1063}cats_gold_mul_gold.cat");
    for files in [
        vec![
            (DataRole::Images, gold.as_str()),
            (
                DataRole::Members,
                &format!("{as1063}cats_gold_ref_potential_w_clumpNE.cat"),
            ),
            (DataRole::Model, &format!("{as1063}cats_gold_bestopt.par")),
        ],
        vec![
            (DataRole::Images, &format!("{macs1931}immul_ongoing.cat")),
            (DataRole::Members, &format!("{macs1931}m1931.cat")),
        ],
        vec![
            (DataRole::Arcs, "www/examples/a1689-sim/arcs.json"),
            (DataRole::Members, "www/examples/a1689-sim/members.cat"),
            (DataRole::Model, "www/examples/a1689-sim/model.json"),
        ],
    ] {
        let s = load(&files);
        assert!(
            s.sky_warnings().is_empty(),
            "{files:?}: {:?}",
            s.sky_warnings()
        );
    }
    let s = load(&[
        (DataRole::Images, gold.as_str()),
        (DataRole::Members, &format!("{macs1931}m1931.cat")),
    ]);
    let w = s.sky_warnings();
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].starts_with("m1931.cat (RA 292.9")
            && w[0].contains("and cats_gold_mul_gold.cat (RA 342.1")
            && w[0].contains("degrees apart on the sky: they do not cover the same field"),
        "{}",
        w[0]
    );
    assert!(s.parsed().unwrap().warnings.contains(&w[0]));

    // HFF-style deflection maps of one field (a forward run of the a1689-sim model, whose
    // `reference` is at RA 197.87, Dec -1.34) under the catalogue of another.
    let mut f = load(&[(DataRole::Model, "www/examples/a1689-sim/model.json")]);
    f.set_field("reconstruct.products.pixels", json!(64))
        .unwrap();
    f.run(RunKind::Forward, &mut |_| Control::Continue).unwrap();
    let fits = f.result().unwrap().products().fits_files().unwrap();
    let x = &fits
        .iter()
        .find(|(n, _)| *n == "x-arcsec-deflect.fits")
        .unwrap()
        .1;
    let mut s = load(&[(DataRole::Images, gold.as_str())]);
    s.load_fits(0, "a1689_x.fits", x).unwrap();
    let w = s.sky_warnings();
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].starts_with("a1689_x.fits (RA 197.8"), "{}", w[0]);
    // The same maps over the model of their own field say nothing.
    f.load_fits(0, "a1689_x.fits", x).unwrap();
    assert!(f.sky_warnings().is_empty(), "{:?}", f.sky_warnings());
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_commented_member_row_is_fitted_on_request_and_nothing_else_is() {
    let text = "#REFERENCE 3 342.18322 -44.530889\n\
        #(string name) X Y A B THETA MAG LUM\n\
        1 79.7 33.2 1.2 1.1 38.85 18.39 0.0\n\
        #1009 0.0 0.0 2.0 1.1 58.8 17.3 0.35\n\
        ##7 1.0 2.0 0.3 0.2 10.0 19.5\n";
    let mut s = Session::new();
    s.load_text(DataRole::Members, "m.cat", text).unwrap();
    // Refused, the catalogue untouched: a row, the header, the frame, no line.
    for (line, says) in [
        (3, "m.cat: line 3 is not a commented-out row"),
        (
            2,
            "m.cat: line 2 does not read as a member without its '#': #(string name)",
        ),
        (
            1,
            "m.cat: line 1 does not read as a member without its '#': #REFERENCE",
        ),
        (9, "m.cat: line 9 is not a commented-out row"),
        (0, "m.cat: line 0 is not a commented-out row"),
    ] {
        let err = s.uncomment_members(&[line]).unwrap_err().to_string();
        assert!(err.starts_with(says), "{err}");
        assert_eq!(s.data.members.as_ref().unwrap().text, text);
        // With a good line first, nothing is uncommented either.
        let err = s.uncomment_members(&[4, line]).unwrap_err().to_string();
        assert!(err.starts_with(says), "{err}");
        assert_eq!(s.data.members.as_ref().unwrap().text, text);
    }
    assert!(s.uncomment_members(&[]).is_err());
    assert_eq!(s.data.members.as_ref().unwrap().text, text);
    let report = s.uncomment_members(&[4]).unwrap();
    assert_eq!(report.summary, "2 members (line 4 uncommented)");
    let kept = &s.data.members.as_ref().unwrap().text;
    assert_eq!(
        kept.lines().nth(3),
        Some("1009 0.0 0.0 2.0 1.1 58.8 17.3 0.35")
    );
    assert_eq!(kept.lines().count(), text.lines().count());
    let parsed = s.parsed().unwrap();
    let members = parsed.members.unwrap();
    assert_eq!(members.members[1].id, "1009");
    assert!(members.commented.iter().all(|m| m.id != "1009"));
    // Once uncommented it is no longer commented out.
    assert!(s.uncomment_members(&[4]).is_err());
    // A doubly commented row loses both '#', as the reader strips both.
    let report = s.uncomment_members(&[5]).unwrap();
    assert_eq!(report.summary, "3 members (line 5 uncommented)");
    let kept = &s.data.members.as_ref().unwrap().text;
    assert_eq!(kept.lines().nth(4), Some("7 1.0 2.0 0.3 0.2 10.0 19.5"));
    // Two rows at once (the BCGs of a cluster with two cores).
    let mut both = Session::new();
    both.load_text(DataRole::Members, "m.cat", text).unwrap();
    let report = both.uncomment_members(&[4, 5]).unwrap();
    assert_eq!(report.summary, "3 members (lines 4 and 5 uncommented)");
    assert_eq!(&both.data.members.as_ref().unwrap().text, kept);
    let mut empty = Session::new();
    let err = empty.uncomment_members(&[4]).unwrap_err().to_string();
    assert!(err.contains("load a member catalogue first"), "{err}");
}

/// A file of the published AS1063 models (`../shared/data`, read in place).
#[cfg(not(target_arch = "wasm32"))]
fn read_as1063(name: &str) -> String {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/data/AS1063/lenstool_cats");
    std::fs::read_to_string(dir.join(name)).unwrap()
}

/// A Lenstool `.par` loaded as the model: the galaxies it models on its own are offered, and
/// fitted as members once `members_from_model` is on (the published AS1063 files).
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn the_bcg_of_a_loaded_par_is_offered_then_fitted_as_a_member() {
    let mut s = Session::new();
    s.load_text(
        DataRole::Images,
        "gold.cat",
        &read_as1063("cats_gold_mul_gold.cat"),
    )
    .unwrap();
    s.load_text(
        DataRole::Members,
        "members.cat",
        &read_as1063("cats_gold_ref_potential_w_clumpNE.cat"),
    )
    .unwrap();
    // Before a .par is loaded there is nothing to offer, and the members are the catalogue's.
    assert!(s.model_galaxies().is_empty());
    let n = s.parsed().unwrap().members.unwrap().members.len();
    s.load_text(
        DataRole::Model,
        "best.par",
        &read_as1063("cats_gold_bestopt.par"),
    )
    .unwrap();
    let offered: Vec<(String, usize, f64)> = s
        .model_galaxies()
        .into_iter()
        .map(|g| (g.member.id, g.member.line, g.member.mag))
        .collect();
    assert_eq!(offered, [("O3".to_string(), 55, 17.037)]);
    assert!(!s.model_galaxies()[0].mag_from_mass);
    assert_eq!(s.parsed().unwrap().members.unwrap().members.len(), n);
    s.set_field("members_from_model", json!(true)).unwrap();
    let parsed = s.parsed().unwrap();
    let members = parsed.members.unwrap().members;
    assert_eq!((members.len(), members[n].id.as_str()), (n + 1, "O3"));
    assert!(
        parsed
            .warnings
            .iter()
            .any(|w| w.starts_with("best.par: line 55: galaxy O3 at (")
                && w.ends_with(" fitted as a member")),
        "{:?}",
        parsed.warnings
    );
    // Fitted, it is no longer offered.
    assert!(s.model_galaxies().is_empty());
}

/// A starting `.par` whose BCG has no `mag` (MACS1931's `potentiel 3`): without a member
/// catalogue its offer is the member of the magnitude its mass stands for, said to be so; with
/// the catalogue that comments its row out, that row is its BCG and nothing is offered.
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn a_galaxy_without_a_magnitude_is_offered_as_its_mass_or_its_row() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/data/MACS1931/lenstool_cats");
    let read = |name: &str| std::fs::read_to_string(dir.join(name)).unwrap();
    let mut s = Session::new();
    s.load_text(DataRole::Images, "m1931.cat", &read("immul_ongoing.cat"))
        .unwrap();
    s.load_text(DataRole::Model, "m1931.par", &read("m1931.par"))
        .unwrap();
    let offered = s.model_galaxies();
    let [bcg] = &offered[..] else {
        panic!("{offered:?}")
    };
    assert_eq!((bcg.member.id.as_str(), bcg.member.line), ("3", 66));
    assert!(bcg.mag_from_mass);
    s.load_text(DataRole::Members, "m1931.cat", &read("m1931.cat"))
        .unwrap();
    // The catalogue comments its row out (`#1009.0 ... 17.325`, line 10): that row is fitted
    // as the BCG already (members.fit_commented_bcg), so the .par's galaxy is a member.
    assert!(s.model_galaxies().is_empty());
    let parsed = s.parsed().unwrap();
    let members = parsed.members.unwrap();
    let bcg = members.members.iter().find(|m| m.id == "1009.0").unwrap();
    assert_eq!((bcg.line, bcg.mag), (10, 17.325));
}

/// The redshift priors of a loaded `.par` (AS1063 silver's starting model: uniform ranges for
/// the eight systems its catalogue gives no redshift) are taken with its galaxies once
/// `members_from_model` is on, and reach the run's settings; off, the catalogue alone counts.
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn the_redshift_priors_of_a_loaded_par_are_taken_with_its_galaxies() {
    let mut s = Session::new();
    s.load_text(
        DataRole::Images,
        "silver.cat",
        &read_as1063("cats_silver_mul_silver.cat"),
    )
    .unwrap();
    s.load_text(
        DataRole::Model,
        "start.par",
        &read_as1063("cats_silver_SMACS2248_HFF_NE.par"),
    )
    .unwrap();
    assert!(s.parsed().unwrap().z_priors.is_empty());
    s.set_field("members_from_model", json!(true)).unwrap();
    let parsed = s.parsed().unwrap();
    let priors: Vec<(&str, wslap::RedshiftPrior)> = parsed
        .z_priors
        .iter()
        .map(|(id, p)| (id.as_str(), *p))
        .collect();
    let range = |lo, hi| wslap::RedshiftPrior::Range([lo, hi]);
    assert_eq!(
        priors,
        [
            ("141", range(2.4, 4.0)),
            ("142", range(2.4, 4.0)),
            ("143", range(2.4, 4.0)),
            ("144", range(2.4, 4.0)),
            ("3", range(1.5, 2.7)),
            ("43", range(1.4, 1.8)),
            ("8", range(2.4, 3.2)),
            ("9", range(2.4, 3.2)),
        ]
    );
    assert!(
        parsed.warnings.iter().any(|w| w
            == "start.par: line 10: system 43's redshift is estimated under the model's prior, \
                uniform 1.4 - 1.8"),
        "{:?}",
        parsed.warnings
    );
}

/// A published `best.par` that lists every potfile member again (SMACS J0723, Mahler et al.
/// 2023, tests/data/lenstool/smacs0723): the verdict's offer is the one galaxy it would add,
/// its BCG (no `mag`; the row the member catalogue comments out), not the 141 members.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_best_par_offers_its_bcg_and_not_the_members_it_lists_again() {
    let mut s = Session::new();
    for (role, name, text) in [
        (
            DataRole::Images,
            "arcs.dat",
            include_str!("../data/lenstool/smacs0723/arcs.dat"),
        ),
        (
            DataRole::Members,
            "galcat.cat",
            include_str!("../data/lenstool/smacs0723/galcat.cat"),
        ),
        (
            DataRole::Model,
            "best.par",
            include_str!("../data/lenstool/smacs0723/best.par"),
        ),
    ] {
        s.load_text(role, name, text).unwrap();
    }
    let offered: Vec<(String, usize, f64)> = s
        .model_galaxies()
        .into_iter()
        .map(|g| (g.member.id, g.member.line, g.member.mag))
        .collect();
    assert_eq!(offered, [("4".to_string(), 5, 18.8654)]);
    let n = s.parsed().unwrap().members.unwrap().members.len();
    s.set_field("members_from_model", json!(true)).unwrap();
    let members = s.parsed().unwrap().members.unwrap().members;
    assert_eq!(members.len(), n + 1);
    assert_eq!((members[n].id.as_str(), members[n].line), ("4", 5));
    assert!(s.model_galaxies().is_empty());
}
