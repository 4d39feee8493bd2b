//! Lenstool catalogues ([method §7]): the real AS1063 and MACS1931 inputs in
//! ../shared/data (native only), the formats' variants and frame changes, and one test per bad
//! input, each expecting its specific error text.
//!
//! [method §7]: wslap::method#7-file-formats

use crate::common;

use common::assert_abs;
use glam::DVec2;
use wslap::SkyReference;
use wslap::MAX_CATALOG_ROWS;
use wslap::{
    parse_image_catalog, parse_member_catalog, CatalogError, ImageCatalog, DEGREE_LOOKALIKE,
    FIELD_ERROR_DEG, Z_AGREEMENT_TOL,
};

/// Positions computed by the same formula in another order: rounding of `RA - RA0` (~1e-13 deg)
/// times 3600 arcsec/deg.
const POSITION_ATOL_ARCSEC: f64 = 1e-8;
/// Round trip through (RA, Dec) and back: double rounding of degrees near 342 (~6e-14 deg).
const ROUND_TRIP_ATOL_ARCSEC: f64 = 1e-9;

/// The AS1063 members' frame (`#REFERENCE 3 342.1832200 -44.5308890`).
const AS1063_RA0: f64 = 342.18322;
const AS1063_DEC0: f64 = -44.530889;

fn as1063_reference() -> SkyReference {
    SkyReference::new(AS1063_RA0, AS1063_DEC0).unwrap()
}

/// `x = -(RA - RA0) cos(Dec0) 3600`, `y = (Dec - Dec0) 3600` ([method §1]).
///
/// [method §1]: wslap::method#1-frames-and-units
fn lenstool_offset(ra: f64, dec: f64, ra0: f64, dec0: f64) -> DVec2 {
    DVec2::new(
        -(ra - ra0) * dec0.to_radians().cos() * 3600.0,
        (dec - dec0) * 3600.0,
    )
}

fn image_err(text: &str) -> String {
    let err = parse_image_catalog(text, "bad.cat", None).expect_err("must be rejected");
    err.to_string()
}

#[track_caller]
fn assert_contains(message: &str, parts: &[&str]) {
    for p in parts {
        assert!(message.contains(p), "'{p}' missing from: {message}");
    }
}

#[cfg(not(target_arch = "wasm32"))]
mod real_files {
    use super::*;

    fn read(rel: &str) -> String {
        let path = format!("{}/../shared/data/{rel}", env!("CARGO_MANIFEST_DIR"));
        std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
    }

    fn images(rel: &str, reference: Option<SkyReference>) -> ImageCatalog {
        let (cat, warnings) = parse_image_catalog(&read(rel), rel, reference).unwrap();
        assert!(
            warnings.is_empty(),
            "{rel}: unexpected warnings {warnings:?}"
        );
        cat
    }

    fn unknown_z_images(cat: &ImageCatalog) -> usize {
        cat.unknown_redshift_systems().map(|s| s.images.len()).sum()
    }

    #[test]
    fn as1063_gold_images() {
        let cat = images("AS1063/lenstool_cats/cats_gold_mul_gold.cat", None);
        assert_eq!(cat.image_count(), 50);
        assert_eq!(cat.systems.len(), 19);
        assert_eq!(cat.systems_with_redshift().count(), 19);
        assert_eq!(cat.unknown_redshift_systems().count(), 0);
        let s12 = cat.systems.iter().find(|s| s.id == "12").unwrap();
        assert_eq!((s12.images.len(), s12.z), (5, Some(6.107)));
        // Without a requested frame: the mean image position, so the mean offset is zero.
        let mean = cat.images().map(|im| im.position).sum::<DVec2>() / 50.0;
        assert!(mean.length() < POSITION_ATOL_ARCSEC, "mean offset {mean}");
        let (lo, hi) = cat.bounding_box_arcsec();
        assert!(
            lo.x < -30.0 && hi.x > 40.0 && lo.y < -35.0 && hi.y > 40.0,
            "{lo} {hi}"
        );
    }

    #[test]
    fn as1063_gold_images_in_members_frame() {
        let cat = images(
            "AS1063/lenstool_cats/cats_gold_mul_gold.cat",
            Some(as1063_reference()),
        );
        assert_eq!(cat.reference, Some(as1063_reference()));
        let im = &cat.systems[0].images[0];
        assert_eq!((im.id.as_str(), im.line), ("1.1", 1));
        let expected = lenstool_offset(342.1945, -44.526998, AS1063_RA0, AS1063_DEC0);
        assert_abs(
            "image 1.1 x",
            im.position.x,
            expected.x,
            POSITION_ATOL_ARCSEC,
        );
        assert_abs(
            "image 1.1 y",
            im.position.y,
            expected.y,
            POSITION_ATOL_ARCSEC,
        );
        assert_abs("image 1.1 x (approx.)", im.position.x, -28.948, 1e-3);
        assert_abs("image 1.1 y (approx.)", im.position.y, 14.0076, 1e-3);
    }

    #[test]
    fn as1063_silver_images_and_default_z() {
        let cat = images("AS1063/lenstool_cats/cats_silver_mul_silver.cat", None);
        assert_eq!((cat.image_count(), cat.systems.len()), (72, 27));
        let unknown: Vec<&str> = cat
            .unknown_redshift_systems()
            .map(|s| s.id.as_str())
            .collect();
        assert_eq!(unknown, ["3", "8", "9", "43", "141", "142", "143", "144"]);
        assert_eq!(unknown_z_images(&cat), 22);
        let filled = cat.clone().with_default_z(2.0).unwrap();
        assert_eq!(filled.unknown_redshift_systems().count(), 0);
        for (a, b) in cat.systems.iter().zip(&filled.systems) {
            assert_eq!(b.z, Some(a.z.unwrap_or(2.0)), "system {}", a.id);
        }
    }

    #[test]
    fn as1063_members() {
        let rel = "AS1063/lenstool_cats/cats_gold_ref_potential_w_clumpNE.cat";
        let (cat, warnings) = parse_member_catalog(&read(rel), rel, None).unwrap();
        assert!(warnings.is_empty(), "{warnings:?}");
        assert_eq!(cat.members.len(), 260);
        assert_eq!(cat.reference, Some(as1063_reference()));
        let m = &cat.members[0];
        assert_eq!((m.id.as_str(), m.line), ("13475", 2));
        assert_eq!(
            (m.position, m.mag, m.lum),
            (DVec2::new(79.7384, 33.1776), 18.3953, 0.0)
        );
        assert_eq!((m.a_arcsec, m.theta_deg), (1.23055596, 38.85));
        let mag_range = cat
            .members
            .iter()
            .fold((f64::MAX, f64::MIN), |(lo, hi), m| {
                (lo.min(m.mag), hi.max(m.mag))
            });
        assert_eq!(mag_range, (18.2961, 25.099));
    }

    /// A catalogue given as the other kind is refused, told by its 7th column: MACS1931's and
    /// AS1063's member catalogues as images (magnitudes where redshifts go), AS1063's images
    /// as members (redshifts where magnitudes go).
    #[test]
    fn a_catalogue_of_the_other_kind_is_named() {
        for (rel, first) in [
            (
                "MACS1931/lenstool_cats/m1931.cat",
                "16.8822 to 28.859 on 198 rows (line 3",
            ),
            (
                "AS1063/lenstool_cats/cats_gold_ref_potential_w_clumpNE.cat",
                "18.2961 to 25.099 on 260 rows (line 2",
            ),
        ] {
            let err = parse_image_catalog(&read(rel), rel, None).unwrap_err();
            assert_contains(
                &err.to_string(),
                &[
                    &format!("{rel}: column 7 (z) holds {first}"),
                    "which read as magnitudes, not source redshifts: this looks like a member \
                     catalogue (id x y a b theta mag lum), not an image catalogue",
                ],
            );
        }
        let rel = "AS1063/lenstool_cats/cats_gold_mul_gold.cat";
        let err = parse_member_catalog(&read(rel), rel, None).unwrap_err();
        assert_eq!(
            err.to_string(),
            format!(
                "{rel}: column 7 (mag) holds 0.7287 to 6.107 on 50 rows (line 1: 1.2279), which \
                 read as redshifts, not magnitudes: this looks like an image catalogue (id x y a \
                 b theta z mag), not a member catalogue"
            )
        );
    }

    #[test]
    fn macs1931_images() {
        let rel = "MACS1931/lenstool_cats/immul_ongoing.cat";
        let (cat, warnings) = parse_image_catalog(&read(rel), rel, None).unwrap();
        assert_eq!((cat.image_count(), cat.systems.len()), (28, 10));
        assert_eq!(unknown_z_images(&cat), 11);
        assert_eq!(cat.unknown_redshift_systems().count(), 4);
        // System 32: z = 1.1781 (line 9), 1.1783 (lines 13, 15): within the tolerance, averaged,
        // with one warning naming both lines.
        let s32 = cat.systems.iter().find(|s| s.id == "32").unwrap();
        assert_abs(
            "z of system 32",
            s32.z.unwrap(),
            (1.1781 + 2.0 * 1.1783) / 3.0,
            1e-12,
        );
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert_eq!(warnings[0].line, 9);
        assert_contains(
            &warnings[0].to_string(),
            &[rel, "system '32'", "line 13", "1.1783"],
        );
        // The mean as a person writes it (was "1.1782333333333332").
        assert!(
            warnings[0]
                .to_string()
                .ends_with("using their mean z = 1.178233"),
            "{}",
            warnings[0]
        );
        let ids: Vec<&str> = cat.systems.iter().map(|s| s.id.as_str()).collect();
        assert_eq!(
            ids,
            ["1", "954", "32", "23", "26", "27", "2", "4", "6", "5"]
        );
    }

    #[test]
    fn macs1931_members_and_images_share_a_frame() {
        let rel = "MACS1931/lenstool_cats/m1931.cat";
        let (members, warnings) = parse_member_catalog(&read(rel), rel, None).unwrap();
        assert!(warnings.is_empty(), "{warnings:?}");
        assert_eq!(members.members.len(), 198);
        assert_eq!(members.reference, SkyReference::new(292.95682, -26.575718));
        // The 8th column of this file holds redshifts, kept as written.
        assert!(members.members.iter().all(|m| (0.2..0.5).contains(&m.lum)));
        let rel = "MACS1931/lenstool_cats/immul_ongoing.cat";
        let (cat, _) = parse_image_catalog(&read(rel), rel, members.reference).unwrap();
        let (lo, hi) = members.bounding_box_arcsec();
        for im in cat.images() {
            let p = im.position;
            assert!(
                p.cmpge(lo).all() && p.cmple(hi).all(),
                "image {} at {p}",
                im.id
            );
        }
        // Five rows are commented out, its BCG (line 10) among them: kept aside, never
        // fitted, for the run to name.
        let lines: Vec<usize> = members.commented.iter().map(|m| m.line).collect();
        assert_eq!(lines, [10, 19, 20, 22, 30]);
        let bcg = &members.commented[0];
        assert_eq!((bcg.id.as_str(), bcg.line, bcg.mag), ("1009.0", 10, 17.325));
        assert_eq!(bcg.position, DVec2::ZERO);
        let im = &cat.systems[0].images[0];
        let expected = lenstool_offset(292.96063, -26.569172, 292.95682, -26.575718);
        assert!(
            (im.position - expected).length() < POSITION_ATOL_ARCSEC,
            "{}",
            im.position
        );
    }
}

// ---------------------------------------------------------------- formats and frames

const MEMBERS_REL: &str = "#REFERENCE 3 342.18322 -44.530889\n\
    1 79.7384 33.1776 1.2 1.1 38.85 18.39 0.0\n\
    2 -59.1622 67.7765 1.1 0.9 -29.98 18.46 0.0\n\
    3 -300.5 -250.25 0.5 0.4 10.0 22.1 0.0\n";

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn relative_catalogue_reprojects_and_back() {
    let other = SkyReference::new(342.21, -44.49).unwrap();
    let (native, _) = parse_member_catalog(MEMBERS_REL, "m.cat", None).unwrap();
    let (moved, _) = parse_member_catalog(MEMBERS_REL, "m.cat", Some(other)).unwrap();
    assert_eq!(moved.reference, Some(other));
    // The moved positions are the same sky positions.
    let m = &moved.members[0];
    let (ra, dec) = as1063_reference().offset_to_radec(native.members[0].position);
    let expected = lenstool_offset(ra, dec, other.ra_deg, other.dec_deg);
    assert!(
        (m.position - expected).length() < POSITION_ATOL_ARCSEC,
        "{}",
        m.position
    );
    assert!((m.position - native.members[0].position).length() > 100.0);
    let back = moved.reframed(as1063_reference()).unwrap();
    for (a, b) in back.members.iter().zip(&native.members) {
        assert!(
            (a.position - b.position).length() < ROUND_TRIP_ATOL_ARCSEC,
            "member {}: {} vs {}",
            a.id,
            a.position,
            b.position
        );
    }
}

/// A `.par`'s potfile without a `#REFERENCE` header, in arcsec relative to the `.par`'s
/// reference (A1835's published model of Richard et al. writes `199 -70.4727720 -22.8484800
/// ...`), reads as Lenstool reads it: in that frame, with one warning naming the first row that
/// cannot be degrees. The same text as a member catalogue of its own stays refused, and a
/// headerless catalogue in degrees reads as degrees either way.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_par_s_headerless_potfile_in_arcsec_reads_in_the_par_s_frame() {
    let r = as1063_reference();
    let text = "1 12.5 30.0 0.5 0.4 10.0 19.0 1.0\n2 -70.47 -22.85 0.6 0.4 -63.1 20.0 1.0\n";
    let (cat, warnings) = wslap::parse_potfile_catalog(text, "pot.cat", Some(r)).unwrap();
    assert_eq!(cat.reference, Some(r));
    let got: Vec<DVec2> = cat.members.iter().map(|m| m.position).collect();
    assert_eq!(got, [DVec2::new(12.5, 30.0), DVec2::new(-70.47, -22.85)]);
    let [w] = &warnings[..] else {
        panic!("{warnings:?}")
    };
    assert_eq!(w.line, 2);
    assert_contains(
        &w.message,
        &[
            "no #REFERENCE header",
            "-70.47 -22.85",
            "relative to the .par's reference",
        ],
    );
    let refused = parse_member_catalog(text, "pot.cat", Some(r)).unwrap_err();
    assert_contains(&refused.to_string(), &["line 2", "not a right ascension"]);
    // Without a reference to read them against, refused as before.
    let e = wslap::parse_potfile_catalog(text, "pot.cat", None).unwrap_err();
    assert_contains(&e.to_string(), &["line 2", "not a right ascension"]);
    // In degrees: both read the same, without a warning.
    let deg = "1 342.18 -44.53 0.5 0.4 10.0 19.0 1.0\n2 342.19 -44.52 0.5 0.4 10.0 19.5 1.0\n";
    let (a, wa) = wslap::parse_potfile_catalog(deg, "deg.cat", Some(r)).unwrap();
    let (b, wb) = parse_member_catalog(deg, "deg.cat", Some(r)).unwrap();
    assert!(wa.is_empty() && wb.is_empty(), "{wa:?} {wb:?}");
    assert_eq!(a.members, b.members);
    // A header is obeyed whatever the values.
    let headed = format!("#REFERENCE 0\n{text}");
    let e = wslap::parse_potfile_catalog(&headed, "pot.cat", Some(r)).unwrap_err();
    assert_contains(&e.to_string(), &["line 3", "not a right ascension"]);
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn commented_rows_are_kept_aside_in_the_frame() {
    // A header, prose, a short row, a row without a magnitude and one with a bad axis are
    // comments; the two full rows are kept, in the requested frame like the members.
    let text = "#REFERENCE 3 342.18322 -44.530889\n\
        #(string name) X Y A B THETA MAG LUM\n\
        # the BCG is potential O3 of the .par\n\
        #bcg 0.5 -1.0 2.0 1.5 -35.0 17.04 0.0\n\
        ## 7 1.0 2.0 0.3 0.2 10.0 19.5\n\
        #8 1.0 2.0 0.3 0.2 10.0\n\
        #9 1.0 2.0 0.3 0.2 10.0 nan 0\n\
        #10 1.0 2.0 -0.3 0.2 10.0 20.0 0\n\
        1 79.7384 33.1776 1.2 1.1 38.85 18.39 0.0\n";
    let (native, warnings) = parse_member_catalog(text, "m.cat", None).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(native.members.len(), 1);
    let ids: Vec<(&str, usize)> = native
        .commented
        .iter()
        .map(|m| (m.id.as_str(), m.line))
        .collect();
    assert_eq!(ids, [("bcg", 4), ("7", 5)]);
    assert_eq!(native.commented[0].position, DVec2::new(0.5, -1.0));
    assert_eq!(native.commented[1].mag, 19.5);
    let other = SkyReference::new(342.21, -44.49).unwrap();
    let (moved, _) = parse_member_catalog(text, "m.cat", Some(other)).unwrap();
    let (ra, dec) = as1063_reference().offset_to_radec(DVec2::new(0.5, -1.0));
    let expected = lenstool_offset(ra, dec, other.ra_deg, other.dec_deg);
    let p = moved.commented[0].position;
    assert!((p - expected).length() < POSITION_ATOL_ARCSEC, "{p}");
    let back = moved.reframed(as1063_reference()).unwrap();
    let p = back.commented[0].position;
    assert!(
        (p - DVec2::new(0.5, -1.0)).length() < ROUND_TRIP_ATOL_ARCSEC,
        "{p}"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn whitespace_comments_and_ids_as_people_write_them() {
    let text = "\u{feff}# gold list\r\n\
        \t4.2\t342.1945   -44.526998\t0.1 0.1 0.0 1.5 24.0   \r\n\
        \r\n\
        \x20  #4.9 342.19 -44.52 0.1 0.1 0 1.5 0  (commented out)\r\n\
        4.1 342.1959 -44.528965 0.1 0.1 0.0 1.5\r\n\
        14c.1 342.18645 -44.521197 0.2 0.1 30 0 0\r\n\
        14c.2 342.1927 -44.531135 0.2 0.1 30 0 0 99 extra\r\n";
    let (cat, warnings) = parse_image_catalog(text, "w.cat", None).unwrap();
    let ids: Vec<(&str, usize)> = cat
        .systems
        .iter()
        .map(|s| (s.id.as_str(), s.images.len()))
        .collect();
    assert_eq!(ids, [("4", 2), ("14c", 2)]);
    assert_eq!((cat.systems[0].z, cat.systems[1].z), (Some(1.5), None));
    let first = &cat.systems[0].images[0];
    assert_eq!((first.id.as_str(), first.line, first.mag), ("4.2", 2, 24.0));
    assert_eq!(cat.systems[0].images[1].mag, 0.0, "missing mag is 0");
    assert_eq!(cat.systems[1].images[0].theta_deg, 30.0);
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert_eq!(
        warnings[0].to_string(),
        "w.cat: line 7: 1 row(s) have more than 8 columns; the extra columns are ignored"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn single_images_and_partly_unknown_redshifts_warn() {
    let text = "1.1 10 20 0.1 0.1 0 0 0\n\
                1.2 10.001 20 0.1 0.1 0 2.5 0\n\
                7.1 10.002 20 0.1 0.1 0 3.0 0\n";
    let (cat, warnings) = parse_image_catalog(text, "w.cat", None).unwrap();
    assert_eq!(
        cat.systems[0].z,
        Some(2.5),
        "unknown z = 0 does not contradict 2.5"
    );
    let messages: Vec<String> = warnings.iter().map(ToString::to_string).collect();
    assert_eq!(messages.len(), 2, "{messages:?}");
    assert_contains(
        &messages[0],
        &["w.cat: line 1:", "system '1'", "line 2 gives z = 2.5"],
    );
    assert_contains(
        &messages[1],
        &["w.cat: line 3:", "system '7' has a single image ('7.1')"],
    );
}

/// A row written twice (SDSS J1004+4112 and A1703 converted from Grale's files: two systems
/// with an image at the very same place) is named, in two systems or in one; images 0.1"
/// apart are not.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn an_image_written_twice_is_named() {
    let text = "#REFERENCE 3 150.0 2.2\n\
                5.1 10.0 20.0 0.1 0.1 0 2.0 0\n\
                5.2 -12.0 -3.0 0.1 0.1 0 2.0 0\n\
                6.1 10.01 20.0 0.1 0.1 0 2.0 0\n\
                6.2 -8.0 5.0 0.1 0.1 0 2.0 0\n\
                6.3 -8.0 5.1 0.1 0.1 0 2.0 0\n\
                6.4 -8.02 5.1 0.1 0.1 0 2.0 0\n";
    let (_, warnings) = parse_image_catalog(text, "w.cat", None).unwrap();
    let messages: Vec<String> = warnings.iter().map(ToString::to_string).collect();
    assert_eq!(
        messages,
        [
            "w.cat: line 4: image '6.1' lies where image '5.1' (line 2) does, in systems 5 \
             and 6: an image has one source, so the map is asked for two at one place; delete \
             one row if it is the same image",
            "w.cat: line 7: image '6.4' lies where image '6.3' (line 6) does, in system 6: it \
             is counted twice; delete one row if it is the same image",
        ]
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn reference_modes_0_1_3_agree() {
    let (ra, dec) = as1063_reference().offset_to_radec(DVec2::new(-28.5, 14.25));
    let abs0 = format!("#REFERENCE 0 342.18322 -44.530889\n1.1 {ra:.12} {dec:.12} 0 0 0 2 0\n");
    let rel1 = "#REFERENCE 1 22:48:43.9728 -44:31:51.2004\n1.1 -28.5 14.25 0 0 0 2 0\n";
    let rel3 = "#REFERENCE 3 342.18322 -44.530889\n1.1 -28.5 14.25 0 0 0 2 0\n";
    for text in [abs0.as_str(), rel1, rel3] {
        let (cat, _) = parse_image_catalog(text, "r.cat", None).unwrap();
        let r = cat.reference.unwrap();
        assert_abs("ra0", r.ra_deg, AS1063_RA0, 1e-10);
        assert_abs("dec0", r.dec_deg, AS1063_DEC0, 1e-10);
        let p = cat.systems[0].images[0].position;
        assert!(
            (p - DVec2::new(-28.5, 14.25)).length() < 1e-6,
            "{text}: {p}"
        );
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn members_without_lum_and_absolute_members() {
    let text = "a 342.19 -44.52 0.5 0.4 10 19.5\nb 342.17 -44.54 0.5 0.4 10 20.5 1e11\n";
    let (cat, warnings) = parse_member_catalog(text, "m.cat", Some(as1063_reference())).unwrap();
    assert!(warnings.is_empty());
    assert_eq!((cat.members[0].lum, cat.members[1].lum), (0.0, 1e11));
    let expected = lenstool_offset(342.17, -44.54, AS1063_RA0, AS1063_DEC0);
    assert!((cat.members[1].position - expected).length() < POSITION_ATOL_ARCSEC);
    let (lo, hi) = cat.bounding_box_arcsec();
    assert!(lo.x < hi.x && lo.y < hi.y);
}

/// A member row written twice (as in MACS J1149's published member catalogues, four rows
/// each) is two galaxies, as Lenstool reads it, and the warning says the mass is doubled; a
/// reused id on another galaxy keeps the plain warning.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_repeated_member_row_is_fitted_twice_and_said_so() {
    let text = "#REFERENCE 3 10 20\n\
                95 -6.77 -100.72 0.7 0.4 7.9 22.97 0.01\n\
                95 -6.77 -100.72 0.7 0.4 7.9 22.97 0.01\n\
                7 1 2 0.5 0.4 0 20\n\
                7 3 4 0.5 0.4 0 21\n";
    let (cat, warnings) = parse_member_catalog(text, "m.cat", None).unwrap();
    assert_eq!(cat.members.len(), 4, "every row is a galaxy");
    let texts: Vec<String> = warnings.iter().map(ToString::to_string).collect();
    assert_eq!(
        texts,
        [
            "m.cat: line 3: member '95' repeats line 2 exactly: both rows are fitted (as \
             Lenstool reads them), which doubles that galaxy's mass; delete one if that is not \
             meant",
            "m.cat: line 5: member id '7' is already used on line 4: both rows are used (ids only \
             name rows in messages)",
        ]
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn image_catalog_helpers() {
    let text = "#REFERENCE 3 10 20\n\
                1.1 -3 4 0 0 0 1.5\n1.2 5 -6 0 0 0 1.5\n2.1 1 1 0 0 0 0\n2.2 0 9 0 0 0 0\n";
    let (cat, _) = parse_image_catalog(text, "h.cat", None).unwrap();
    assert_eq!(cat.image_count(), 4);
    assert_eq!(
        cat.bounding_box_arcsec(),
        (DVec2::new(-3.0, -6.0), DVec2::new(5.0, 9.0))
    );
    assert_eq!(
        cat.systems_with_redshift()
            .map(|s| &s.id)
            .collect::<Vec<_>>(),
        ["1"]
    );
    assert_eq!(
        cat.unknown_redshift_systems()
            .map(|s| &s.id)
            .collect::<Vec<_>>(),
        ["2"]
    );
    let filled = cat.clone().with_default_z(3.0).unwrap();
    assert_eq!(
        (filled.systems[0].z, filled.systems[1].z),
        (Some(1.5), Some(3.0))
    );
    let err = cat.with_default_z(f64::NAN).unwrap_err().to_string();
    assert_eq!(
        err,
        "h.cat: default source redshift NaN must be finite and > 0"
    );
    let empty = ImageCatalog {
        source_name: "e".into(),
        reference: None,
        systems: vec![],
    };
    assert_eq!(empty.bounding_box_arcsec(), (DVec2::ZERO, DVec2::ZERO));
    assert!(matches!(
        empty.reframed(as1063_reference()),
        Err(CatalogError::NoReference { .. })
    ));
}

// ---------------------------------------------------------------- bad inputs

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn missing_columns() {
    let err = image_err("1.1 342.1 -44.5 0.1 0.1 0 1.2\n1.2 342.2 -44.5 0.1 0.1\n");
    assert_eq!(
        err,
        "bad.cat: line 2: '1.2 342.2 -44.5 0.1 0.1': 5 column(s) found, at least 7 needed \
         (id x y a b theta z [mag])"
    );
    // A Lenstool .par given as a catalogue is named as one, with where it goes instead.
    let err = image_err("# made by Lenstool\nrunmode\n\treference 3 292.95 -26.57\n");
    assert_eq!(
        err,
        "bad.cat: line 2: 'runmode': 1 column(s) found, at least 7 needed \
         (id x y a b theta z [mag]); this is a Lenstool parameter file (.par), not a \
         catalogue: load it as the model file in the app, or give it with --par"
    );
    // A long row is quoted shortened.
    let long = format!("1.1 {}\n", "x".repeat(80));
    let err = image_err(&long);
    assert!(
        err.starts_with(&format!(
            "bad.cat: line 1: '1.1 {}...': 2 column(s)",
            "x".repeat(56)
        )),
        "{err}"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn nan_value() {
    let err = image_err("# list\n1.1 342.1 -44.5 0.1 0.1 NaN 1.2 0\n");
    assert_eq!(
        err,
        "bad.cat: line 2, column 6 (theta): 'NaN' is not a finite number"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn non_numeric_value() {
    let err = image_err("1.1 342.1 -44.5 0.1 0.1 0 1.2 0\n\n1.2 342.2 -44.5 0.1 0.1 0 abc 0\n");
    assert_eq!(err, "bad.cat: line 3, column 7 (z): 'abc' is not a number");
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn duplicate_image_ids() {
    let err = image_err(
        "1.1 342.1 -44.5 0 0 0 1.2 0\n1.2 342.2 -44.5 0 0 0 1.2 0\n1.1 342.3 -44.5 0 0 0 1.2 0\n",
    );
    assert_eq!(
        err,
        "bad.cat: line 3: image id '1.1' is already used on line 1"
    );
}

/// Ids are grouped as Lenstool groups them (its manual's example: `C1a`, `C1b`, `C1c` are one
/// source), by all but their last character; the rows here are of the form public catalogues
/// use (`1A 1B`, `A3a A3b`, `1a 1b`), mixed with dotted ids. Knots of one galaxy written
/// `2.1a 2.1b 2.2a 2.2b` (Bergamini et al. 2022's MACS J0416 catalogue) are two sources, as
/// Lenstool fits them (its `chires.dat` lists families `12.6`, `12.5`, ... for `12.6c`,
/// `12.5c`); `system.number` ids keep their system past a tenth image (`6.10`). A file of
/// them says once how it was read; a one-character id names no system.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn ids_are_grouped_as_lenstool_groups_them() {
    let text = "5.1 342.1 -44.5 0 0 0 1.5 0\n\
                1A 342.101 -44.5 0 0 0 1.2 0\n\
                1B 342.102 -44.5 0 0 0 1.2 0\n\
                A3a 342.103 -44.5 0 0 0 0 0\n\
                5.2 342.104 -44.5 0 0 0 1.5 0\n\
                A3b 342.105 -44.5 0 0 0 0 0\n\
                A3c 342.106 -44.5 0 0 0 0 0\n\
                2a 342.107 -44.5 0 0 0 3.1 0\n\
                2b 342.108 -44.5 0 0 0 3.1 0\n";
    let (cat, warnings) = parse_image_catalog(text, "w.cat", None).unwrap();
    let systems: Vec<(&str, Vec<&str>, Option<f64>)> = cat
        .systems
        .iter()
        .map(|s| {
            let ids = s.images.iter().map(|im| im.id.as_str()).collect();
            (s.id.as_str(), ids, s.z)
        })
        .collect();
    assert_eq!(
        systems,
        [
            ("5", vec!["5.1", "5.2"], Some(1.5)),
            ("1", vec!["1A", "1B"], Some(1.2)),
            ("A3", vec!["A3a", "A3b", "A3c"], None),
            ("2", vec!["2a", "2b"], Some(3.1)),
        ]
    );
    let messages: Vec<String> = warnings.iter().map(ToString::to_string).collect();
    assert_eq!(
        messages,
        [
            "w.cat: line 2: image ids not of the form system.number are grouped as Lenstool \
             groups them, by all but their last character: '1A' is an image of system 1"
        ]
    );
    // Two knots of one galaxy, three images each, and a system with ten images.
    let mut knots = String::new();
    for (k, id) in ["2.1a", "2.1b", "2.1c", "2.2a", "2.2b", "2.2c"]
        .iter()
        .enumerate()
    {
        knots += &format!("{id} 64.04{k} -24.06 0.37 0.37 90 6.145 25\n");
    }
    for k in 1..=10 {
        let ra = 64.05 + 0.001 * k as f64;
        knots += &format!("6.{k} {ra} -24.07 0.37 0.37 90 1.5 25\n");
    }
    let (cat, warnings) = parse_image_catalog(&knots, "knots.cat", None).unwrap();
    let systems: Vec<(&str, usize)> = cat
        .systems
        .iter()
        .map(|s| (s.id.as_str(), s.images.len()))
        .collect();
    assert_eq!(systems, [("2.1", 3), ("2.2", 3), ("6", 10)]);
    let messages: Vec<String> = warnings.iter().map(ToString::to_string).collect();
    assert_eq!(
        messages,
        [
            "knots.cat: line 1: image ids not of the form system.number are grouped as Lenstool \
             groups them, by all but their last character: '2.1a' is an image of system 2.1"
        ]
    );
    // Two knots blended in one image (Bergamini et al.'s 14.1c and 14.2c): said as such.
    let blended = "14.1a 64.041 -24.06 0.37 0.37 90 1.6 25\n\
                   14.1c 64.042 -24.06 0.37 0.37 90 1.6 25\n\
                   14.2a 64.043 -24.06 0.37 0.37 90 1.6 25\n\
                   14.2c 64.042 -24.06 0.37 0.37 90 1.6 25\n";
    let (_, warnings) = parse_image_catalog(blended, "b.cat", None).unwrap();
    let messages: Vec<String> = warnings.iter().map(ToString::to_string).collect();
    assert_eq!(
        messages[1],
        "b.cat: line 4: image '14.2c' lies where image '14.1c' (line 2) does, as knots 14.1 and \
         14.2 of one galaxy blended in one image: it is fitted as an image of each, as Lenstool \
         fits it"
    );
    assert_eq!(wslap::system_of_image("14c.1"), Some("14c"));
    assert_eq!(wslap::system_of_image("1.a"), Some("1"));
    assert_eq!(wslap::system_of_image("1."), None);
    let err = image_err("1.1 342.1 -44.5 0 0 0 1.2 0\n7 342.2 -44.5 0 0 0 1.2 0\n");
    assert_eq!(
        err,
        "bad.cat: line 2, column 1 (id): '7' is not an image id: name an image by its system \
         and then the image, as '4.2' or '4b'"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn inconsistent_redshift_in_a_system() {
    let err = image_err(
        "5.1 342.1 -44.5 0 0 0 1.39 0\n6.1 342.2 -44.5 0 0 0 2 0\n5.2 342.3 -44.5 0 0 0 1.42 0\n",
    );
    assert_eq!(
        err,
        format!(
            "bad.cat: system '5': line 1 gives z = 1.39 but line 3 gives z = 1.42; images of \
             one source must agree within {Z_AGREEMENT_TOL} (1 + z)"
        )
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn empty_file() {
    assert_eq!(
        image_err(""),
        "bad.cat: no catalogue rows in 0 line(s) (only blank lines and # comments)"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn only_comments() {
    let err = parse_member_catalog(
        "#REFERENCE 3 10 20\n# id x y\n\n  #1 0 0 1 1 0 20 0\n",
        "m.cat",
        None,
    )
    .unwrap_err();
    assert_eq!(
        err,
        CatalogError::Empty {
            source_name: "m.cat".into(),
            lines: 4
        }
    );
    assert_eq!(
        err.to_string(),
        "m.cat: no catalogue rows in 4 line(s) (only blank lines and # comments)"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn unsupported_reference_mode() {
    let err = image_err("# pixels\n#REFERENCE 2 2048 2048\n1.1 100 200 0 0 0 1.2 0\n");
    assert_contains(
        &err,
        &[
            "bad.cat: line 2: unsupported REFERENCE mode 2:",
            "pixels",
            "#REFERENCE 3 ra0 dec0",
        ],
    );
    let err = image_err("#REFERENCE 7 10 20\n1.1 100 200 0 0 0 1.2 0\n");
    assert_contains(&err, &["bad.cat: line 1: unsupported REFERENCE mode 7"]);
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn negative_semi_axis() {
    let err = image_err("1.1 342.1 -44.5 -0.1 0.1 0 1.2 0\n");
    assert_eq!(
        err,
        "bad.cat: line 1, column 4 (a): '-0.1' is negative: ellipse semi-axes must be >= 0 arcsec"
    );
    let err = parse_member_catalog("#REFERENCE 3 10 20\nm1 1 2 0.5 -1 0 20\n", "m.cat", None)
        .unwrap_err()
        .to_string();
    assert_contains(&err, &["m.cat: line 2, column 5 (b): '-1' is negative"]);
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn negative_redshift() {
    let err = image_err("1.1 342.1 -44.5 0 0 0 -1.2 0\n");
    assert_contains(
        &err,
        &[
            "bad.cat: line 1, column 7 (z): '-1.2' is negative",
            "exactly 0",
        ],
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn relative_positions_without_header() {
    // An arcsec catalogue that lost its '#REFERENCE 3' line reads as degrees: RA -28.9 fails.
    let err = image_err("1.1 -28.9 14.0 0 0 0 1.2 0\n");
    assert_contains(
        &err,
        &[
            "bad.cat: line 1, column 2 (ra): '-28.9'",
            "#REFERENCE 3 ra0 dec0",
        ],
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn misplaced_or_malformed_reference() {
    let err = image_err("1.1 342.1 -44.5 0 0 0 1.2 0\n#REFERENCE 3 342 -44\n");
    assert_contains(
        &err,
        &[
            "bad.cat: line 2: bad header",
            "before the first row (line 1)",
        ],
    );
    let err = image_err("#REFERENCE 3 342\n1.1 1 2 0 0 0 1.2 0\n");
    assert_contains(
        &err,
        &[
            "bad.cat: line 1: bad header '#REFERENCE 3 342'",
            "needs ra0 and dec0",
        ],
    );
    let err = image_err("#REFERENCE 3 342 -95\n1.1 1 2 0 0 0 1.2 0\n");
    assert_contains(&err, &["bad.cat: line 1: bad header", "|Dec| < 90"]);
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn unusable_requested_reference() {
    let bad = SkyReference {
        ra_deg: f64::NAN,
        dec_deg: 0.0,
    };
    let err = parse_member_catalog(MEMBERS_REL, "m.cat", Some(bad)).unwrap_err();
    assert!(
        matches!(err, CatalogError::InvalidReference { .. }),
        "{err}"
    );
    assert_contains(&err.to_string(), &["m.cat: requested sky reference"]);
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn infinite_and_overflowing_values() {
    let err = image_err("1.1 342.1 -44.5 0.1 0.1 0 1.2 0\n1.2 342.1 -44.5 inf 0.1 0 1.2 0\n");
    assert_eq!(
        err,
        "bad.cat: line 2, column 4 (a): 'inf' is not a finite number"
    );
    let err = image_err("1.1 342.1 -44.5 0.1 0.1 0 1e999 0\n");
    assert_eq!(
        err,
        "bad.cat: line 1, column 7 (z): '1e999' is out of range (it overflows a 64-bit float)"
    );
    let err = parse_member_catalog("m1 342.1 -44.5 0.1 0.1 0 -Infinity\n", "m.cat", None)
        .unwrap_err()
        .to_string();
    assert_eq!(
        err,
        "m.cat: line 1, column 7 (mag): '-Infinity' is not a finite number"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn degrees_under_a_relative_header() {
    // Absolute degrees with '#REFERENCE 3 ra0 dec0': every row is within DEGREE_LOOKALIKE of
    // (ra0, dec0), which as arcsec offsets would put all images inside one arcsec.
    let text = "#REFERENCE 3 342.18322 -44.530889\n\
                1.1 342.1901 -44.5201 0.1 0.1 0 1.2 0\n\
                1.2 342.1702 -44.5402 0.1 0.1 0 1.2 0\n";
    let err = image_err(text);
    assert_contains(
        &err,
        &[
            "bad.cat: line 2, column 2 (x): '342.1901' (with y '-44.5201')",
            "looks like a position in degrees",
            &format!("every row is within {DEGREE_LOOKALIKE}"),
            "'#REFERENCE 0'",
        ],
    );
    // One row only: possible (an image at that very offset), so a warning.
    let one = "#REFERENCE 3 342.18322 -44.530889\n1.1 342.19 -44.52 0.1 0.1 0 1.2 0\n";
    let (_, warnings) = parse_image_catalog(one, "one.cat", None).unwrap();
    assert_eq!(warnings.len(), 2, "{warnings:?}"); // and the single-image system
    assert_contains(
        &warnings[0].to_string(),
        &["one.cat: line 2: column 2 (x): '342.19'", "the only row is"],
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn arcsec_offsets_read_as_degrees() {
    // An arcsec catalogue without its header whose values are all valid degrees: the rows
    // spread over tens of degrees, not one lensing field.
    let text = "1.1 12.5 30.2 0.1 0.1 0 1.2 0\n1.2 40.1 -20.3 0.1 0.1 0 1.2 0\n\
                1.3 25.0 5.0 0.1 0.1 0 1.2 0\n";
    let err = image_err(text);
    assert_contains(
        &err,
        &[
            "bad.cat: line 2, column 2 (ra): '40.1' (with dec '-20.3') is ",
            "deg from the mean position",
            "'#REFERENCE 3 ra0 dec0'",
        ],
    );
    // A member about 2 deg from the others: unusual but possible, so a warning.
    let members = "a 342.19 -44.52 0.5 0.4 10 19.5\nb 342.17 -44.54 0.5 0.4 10 20.5\n\
                   c 346.0 -44.53 0.5 0.4 10 20.5\n";
    let (_, warnings) = parse_member_catalog(members, "m.cat", None).unwrap();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert_contains(
        &warnings[0].to_string(),
        &["m.cat: line 3: column 2 (ra): '346.0'", "deg from the mean"],
    );
    // Relative offsets of more than FIELD_ERROR_DEG (here 10 deg in arcsec): an error.
    let far = format!(
        "#REFERENCE 3 10 20\n1.1 1.5 2.5 0 0 0 1.2 0\n1.2 {} 0 0 0 0 1.2 0\n",
        FIELD_ERROR_DEG * 2.0 * 3600.0
    );
    assert_contains(
        &image_err(&far),
        &["bad.cat: line 3, column 2 (x): '36000'", "are arcsec"],
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn too_many_rows() {
    // The row count is checked as the rows are split, before any field is read.
    let text = "x\n".repeat(MAX_CATALOG_ROWS + 1);
    let err = parse_member_catalog(&text, "big.cat", None).unwrap_err();
    assert!(matches!(err, CatalogError::TooLarge(_)), "{err}");
    assert_eq!(
        err.to_string(),
        format!(
            "big.cat: {} rows is more than the limit of {MAX_CATALOG_ROWS} rows for a catalogue",
            MAX_CATALOG_ROWS + 1
        )
    );
}

#[cfg(not(target_arch = "wasm32"))]
#[test]
fn too_many_bytes() {
    // Refused on its length alone (a text of blanks would otherwise read as "empty").
    use wslap::MAX_CATALOG_BYTES;
    let text = " ".repeat(MAX_CATALOG_BYTES as usize + 1);
    let err = image_err(&text);
    assert_eq!(
        err,
        format!(
            "bad.cat: {} bytes is more than the limit of {MAX_CATALOG_BYTES} bytes for a \
             catalogue",
            MAX_CATALOG_BYTES + 1
        )
    );
}

/// Absurd offsets are refused with numbers a person can read (`2.778e304 deg`, not 300 digits
/// or `inf`).
#[test]
fn absurd_offsets_are_said_in_readable_numbers() {
    for (y, shown) in [
        ("1e308", "2.777777777777778e304 deg"),
        ("-1e308", "-2.777777777777778e304"),
    ] {
        let text = format!("#REFERENCE 3 342.18 -44.53\n1.1 0 {y} 0.1 0.1 0 2 25\n");
        let e = image_err(&text);
        assert!(e.contains(shown) && e.contains("outside (-90, 90)"), "{e}");
    }
    let e = image_err("#REFERENCE 3 342.18 -44.53\n1.1 1e308 0 0.1 0.1 0 2 25\n");
    assert!(e.contains("is 2.778e304 deg from"), "{e}");
    assert!(!e.contains("inf"), "{e}");
}

/// The kind check needs three values in column 7 and leaves the ones it cannot judge alone:
/// two members with magnitudes read as images are not refused by it; absolute (negative)
/// magnitudes and a 99 that means none are read as members; one image at z = 13 among
/// ordinary redshifts is an image catalogue.
#[test]
fn the_kind_check_leaves_what_it_cannot_judge() {
    let two = "#REFERENCE 3 150.1 2.2\n1 0 0 1 1 0 18.5\n2 5 5 1 1 0 19.5\n";
    assert!(!image_err(two).contains("column 7"), "{}", image_err(two));
    let absolute = "#REFERENCE 3 150.1 2.2\n1 0 0 1 1 0 -22.1\n2 5 5 1 1 0 -20.3\n3 9 1 1 1 0 -19.0\n4 2 8 1 1 0 99\n";
    let (members, _) = parse_member_catalog(absolute, "abs.cat", None).unwrap();
    assert_eq!(members.members.len(), 3);
    let high = "#REFERENCE 3 150.1 2.2\n1.1 0 0 1 1 0 13.0\n1.2 5 5 1 1 0 13.0\n2.1 9 1 1 1 0 2.1\n2.2 2 8 1 1 0 2.1\n\
                3.1 -9 1 1 1 0 1.2\n3.2 -2 -8 1 1 0 1.2\n";
    let (images, _) = parse_image_catalog(high, "high.cat", None).unwrap();
    assert_eq!(images.systems.len(), 3);
}
