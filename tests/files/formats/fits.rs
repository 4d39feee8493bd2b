//! FITS: round trips, the committed file against astropy, astropy-written files, bad inputs.

use super::*;
use crate::common::assert_abs;
use wslap::{read_image, write_image, CardValue, FitsError};

/// Header cards of a FITS file up to and including END.
fn header_cards(bytes: &[u8]) -> Vec<String> {
    let mut cards = Vec::new();
    for chunk in bytes.chunks(80) {
        let card = String::from_utf8(chunk.to_vec()).expect("header is ASCII");
        let end = card.starts_with("END ");
        cards.push(card);
        if end {
            break;
        }
    }
    cards
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn fits_round_trip_keeps_data_geometry_reference_and_cards() {
    let map = small_map();
    for reference in [Some(sky()), None] {
        let opts = FitsWriteOptions {
            reference,
            ..small_fits_options()
        };
        let bytes = write_image(&map, &opts).unwrap();
        assert_eq!(
            bytes.len() % 2880,
            0,
            "file length {} is not a multiple of 2880",
            bytes.len()
        );
        let cards = header_cards(&bytes);
        assert!(cards.last().unwrap().starts_with("END "), "no END card");
        for c in &cards {
            assert_eq!(c.len(), 80, "card `{c}`");
            assert!(
                c.bytes().all(|b| (32..=126).contains(&b)),
                "non-printable byte in `{c}`"
            );
        }
        let img = read_image(&bytes, "round-trip.fits").unwrap();
        assert_eq!((img.width, img.height), (16, 16));
        for (k, (&a, &b)) in img.data.iter().zip(&map.data).enumerate() {
            assert_abs(&format!("pixel {k}"), a, b, F32_ATOL);
        }
        let (g, r) = img.geometry().unwrap();
        assert_eq!(g.pixels, map.geometry.pixels);
        assert_abs(
            "size_arcsec",
            g.size_arcsec,
            map.geometry.size_arcsec,
            1e-12,
        );
        assert_abs("center.x", g.center.x, map.geometry.center.x, 1e-9);
        assert_abs("center.y", g.center.y, map.geometry.center.y, 1e-9);
        assert_eq!(r, reference, "sky reference");
        assert_eq!(img.card("ZSOURCE").and_then(|c| c.as_f64()), Some(2.0));
        assert_eq!(
            img.card("MODEL").and_then(|c| c.as_str()),
            Some("test 'quoted'")
        );
        let map2 = img.to_map().unwrap();
        assert_eq!(map2.geometry.pixels, 16);
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn committed_fits_is_what_the_writer_produces() {
    let bytes = write_image(&small_map(), &small_fits_options()).unwrap();
    maybe_make_ref("files_ours.fits", &bytes);
    assert!(
        bytes == OURS_FITS,
        "writer output differs from tests/data/files_ours.fits (MAKE_REF=1 regenerates)"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn astropy_reads_our_fits_and_agrees_on_world_coordinates() {
    let json = reference();
    let ours = &json["ours"];
    assert_eq!(
        ours["verify_ok"],
        Value::Bool(true),
        "astropy verify: {}",
        ours["verify_messages"]
    );
    let img = read_image(OURS_FITS, "files_ours.fits").unwrap();
    for key in [
        "CRPIX1", "CRPIX2", "CRVAL1", "CRVAL2", "CDELT1", "CDELT2", "ZSOURCE",
    ] {
        let ours_v = img.card(key).and_then(|c| c.as_f64()).unwrap();
        assert_abs(key, ours_v, ours["header"][key].as_f64().unwrap(), 0.0);
    }
    for s in ours["samples"].as_array().unwrap() {
        let (i, j, v) = (
            s[0].as_u64().unwrap() as usize,
            s[1].as_u64().unwrap() as usize,
            s[2].as_f64().unwrap(),
        );
        assert_abs(
            &format!("astropy data[{j}, {i}]"),
            img.data[j * 16 + i],
            v,
            0.0,
        );
    }
    let (g, r) = img.geometry().unwrap();
    let r = r.unwrap();
    for w in ours["world"].as_array().unwrap() {
        let (i, j) = (
            w[0].as_u64().unwrap() as usize,
            w[1].as_u64().unwrap() as usize,
        );
        let (ra, dec) = r.offset_to_radec(g.pixel_center(i, j));
        assert_abs(
            &format!("RA of pixel ({i}, {j})"),
            ra,
            w[2].as_f64().unwrap(),
            WCS_ATOL_DEG,
        );
        assert_abs(
            &format!("Dec of pixel ({i}, {j})"),
            dec,
            w[3].as_f64().unwrap(),
            WCS_ATOL_DEG,
        );
    }
}

/// astropy returns BSCALE-scaled int16 data as float32: values up to ~32 carry ~2e-6 rounding.
const I16_SCALED_ATOL: f64 = 1e-5;

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn reads_astropy_float32_and_scaled_int16_files() {
    let json = reference();
    let f32_ref = &json["astropy_f32"];
    let img = read_image(ASTROPY_F32, "files_astropy_f32.fits").unwrap();
    assert_eq!((img.width, img.height), (16, 12));
    assert_eq!(
        img.card("BUNIT").and_then(|c| c.as_str()),
        f32_ref["bunit"].as_str()
    );
    for s in f32_ref["samples"].as_array().unwrap() {
        let (i, j, v) = (
            s[0].as_u64().unwrap() as usize,
            s[1].as_u64().unwrap() as usize,
            s[2].as_f64().unwrap(),
        );
        assert_abs(&format!("f32 data[{j}, {i}]"), img.data[j * 16 + i], v, 0.0);
    }
    let err = img.geometry().unwrap_err();
    assert!(
        matches!(
            err,
            FitsError::NotSquare {
                width: 16,
                height: 12,
                ..
            }
        ),
        "{err}"
    );

    let i16_ref = &json["astropy_i16"];
    let img = read_image(ASTROPY_I16, "files_astropy_i16.fits").unwrap();
    assert_eq!((img.width, img.height), (8, 8));
    for s in i16_ref["samples"].as_array().unwrap() {
        let (i, j) = (
            s[0].as_u64().unwrap() as usize,
            s[1].as_u64().unwrap() as usize,
        );
        let got = img.data[j * 8 + i];
        match s[2].as_f64() {
            Some(v) => assert_abs(&format!("i16 data[{j}, {i}]"), got, v, I16_SCALED_ATOL),
            None => assert!(
                got.is_nan(),
                "BLANK pixel ({i}, {j}) should be NaN, got {got}"
            ),
        }
    }
    assert_eq!(
        img.non_finite_count(),
        i16_ref["blank_count"].as_u64().unwrap() as usize
    );
    assert!(matches!(
        img.to_map(),
        Err(FitsError::NonFinitePixels { count: 1, .. })
    ));
    let (map, replaced) = img.to_map_filled(0.0).unwrap();
    assert_eq!(replaced, 1);
    assert!(map.data.iter().all(|v| v.is_finite()));
    // No REFRA/REFDEC: the frame origin is CRVAL, and CRPIX is off the map centre.
    let (g, r) = img.geometry().unwrap();
    let r = r.unwrap();
    assert_abs(
        "RA0 = CRVAL1",
        r.ra_deg,
        i16_ref["crval"][0].as_f64().unwrap(),
        0.0,
    );
    for w in i16_ref["world"].as_array().unwrap() {
        let (i, j) = (
            w[0].as_u64().unwrap() as usize,
            w[1].as_u64().unwrap() as usize,
        );
        let (ra, dec) = r.offset_to_radec(g.pixel_center(i, j));
        assert_abs(
            &format!("RA of i16 pixel ({i}, {j})"),
            ra,
            w[2].as_f64().unwrap(),
            WCS_ATOL_DEG,
        );
        assert_abs(
            &format!("Dec of i16 pixel ({i}, {j})"),
            dec,
            w[3].as_f64().unwrap(),
            WCS_ATOL_DEG,
        );
    }
}

/// A valid header with the given cards replaced or added, followed by `data_bytes` zeros.
fn handmade(cards: &[(&str, &str)], data_bytes: usize) -> Vec<u8> {
    let mut base = vec![
        ("SIMPLE", "T"),
        ("BITPIX", "-32"),
        ("NAXIS", "2"),
        ("NAXIS1", "4"),
        ("NAXIS2", "4"),
    ];
    for &(k, v) in cards {
        match base.iter_mut().find(|(bk, _)| *bk == k) {
            Some(slot) => slot.1 = v,
            None => base.push((k, v)),
        }
    }
    let mut out = Vec::new();
    for (k, v) in base {
        out.extend_from_slice(format!("{k:<8}= {v:>20}{:50}", "").as_bytes());
    }
    out.extend_from_slice(format!("{:<80}", "END").as_bytes());
    out.resize(2880, b' ');
    out.resize(2880 + data_bytes, 0);
    out
}

/// Whether an error is the expected kind.
type ErrorCheck = fn(&FitsError) -> bool;

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn bad_fits_inputs_each_give_their_own_error() {
    let name = "bad.fits";
    assert!(
        read_image(&handmade(&[], 2880), name).is_ok(),
        "the hand-made base file is valid"
    );
    let cases: Vec<(&str, Vec<u8>, ErrorCheck)> = vec![
        ("empty", vec![], |e| matches!(e, FitsError::Empty { .. })),
        (
            "garbage",
            b"\x89PNG\r\n\x1a\n not a fits file".to_vec(),
            |e| matches!(e, FitsError::NotFits { .. }),
        ),
        ("truncated data", handmade(&[], 40), |e| {
            matches!(e, FitsError::Truncated { .. })
        }),
        ("truncated header", handmade(&[], 0)[..300].to_vec(), |e| {
            matches!(e, FitsError::Truncated { .. })
        }),
        ("BITPIX 8", handmade(&[("BITPIX", "8")], 2880), |e| {
            matches!(e, FitsError::UnsupportedBitpix { bitpix: 8, .. })
        }),
        ("BITPIX 12", handmade(&[("BITPIX", "12")], 2880), |e| {
            matches!(e, FitsError::BadKeyword { .. })
        }),
        (
            "3-D cube",
            handmade(&[("NAXIS", "3"), ("NAXIS3", "2")], 2880),
            |e| matches!(e, FitsError::NotTwoDimensional { naxis: 3, .. }),
        ),
        (
            "NAXIS1 not an integer",
            handmade(&[("NAXIS1", "'x'")], 2880),
            |e| matches!(e, FitsError::BadKeyword { .. }),
        ),
    ];
    for (what, bytes, expected) in cases {
        let err = read_image(&bytes, name).unwrap_err();
        assert!(expected(&err), "{what}: unexpected error {err:?}");
        assert!(
            err.to_string().contains(name),
            "{what}: the message names the file: {err}"
        );
    }
    let mut no_end = handmade(&[], 0);
    no_end[5 * 80..5 * 80 + 3].copy_from_slice(b"XYZ");
    assert!(matches!(
        read_image(&no_end, name),
        Err(FitsError::NoEnd { .. })
    ));
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn wcs_problems_are_named() {
    let wcs = [
        ("CTYPE1", "'RA---TAN'"),
        ("CTYPE2", "'DEC--TAN'"),
        ("CRPIX1", "2.5"),
        ("CRPIX2", "2.5"),
        ("CRVAL1", "10.0"),
        ("CRVAL2", "20.0"),
        ("CDELT1", "-1.0E-4"),
        ("CDELT2", "1.0E-4"),
    ];
    let with = |changes: &[(&'static str, &'static str)]| {
        let mut cards = wcs.to_vec();
        cards.extend_from_slice(changes);
        read_image(&handmade(&cards, 2880), "wcs.fits")
            .unwrap()
            .geometry()
    };
    let (g, r) = with(&[]).unwrap();
    assert_abs("pixel", g.pixel_arcsec(), 0.36, 1e-12);
    assert_eq!(
        r,
        Some(SkyReference {
            ra_deg: 10.0,
            dec_deg: 20.0
        })
    );
    let err = with(&[("CDELT1", "1.0E-4")]).unwrap_err();
    assert!(err.to_string().contains("CDELT1 < 0"), "{err}");
    let err = with(&[("CDELT2", "2.0E-4")]).unwrap_err();
    assert!(err.to_string().contains("not square"), "{err}");
    let err = with(&[("PC1_2", "0.5")]).unwrap_err();
    assert!(err.to_string().contains("rotated"), "{err}");
    let err = with(&[("CTYPE1", "'RA---SIN'")]).unwrap_err();
    assert!(
        matches!(err, FitsError::BadKeyword { ref keyword, .. } if keyword == "CTYPE1"),
        "{err}"
    );
    let missing = read_image(&handmade(&wcs[..7], 2880), "wcs.fits")
        .unwrap()
        .geometry()
        .unwrap_err();
    assert!(
        matches!(missing, FitsError::MissingKeyword { ref keyword, .. } if keyword == "CDELT2"),
        "{missing}"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn writer_rejects_reserved_cards_and_non_finite_pixels() {
    let mut opts = small_fits_options();
    opts.extra_cards.push(Card::real("CDELT1", 1.0, ""));
    assert!(matches!(
        write_image(&small_map(), &opts),
        Err(FitsError::BadCard { .. })
    ));
    let short = Map {
        data: vec![0.0; 10],
        ..small_map()
    };
    let err = write_image(&short, &small_fits_options()).unwrap_err();
    assert!(
        matches!(
            err,
            FitsError::BadMap {
                len: 10,
                pixels: 16,
                ..
            }
        ),
        "{err}"
    );
    let mut map = small_map();
    map.data[17] = f64::INFINITY;
    let err = write_image(&map, &small_fits_options()).unwrap_err();
    assert!(
        matches!(err, FitsError::NonFiniteValue { i: 1, j: 1, .. }),
        "{err}"
    );
    // NaN is a pixel without data: written as NaN, read back as NaN.
    map.data[17] = f64::NAN;
    let bytes = write_image(&map, &small_fits_options()).unwrap();
    let back = read_image(&bytes, "nan.fits").unwrap();
    assert!(back.data[17].is_nan() && back.non_finite_count() == 1);
    let long = Card {
        keyword: "NOTE".into(),
        value: Some(CardValue::Text("x".repeat(80))),
        comment: String::new(),
    };
    let opts = FitsWriteOptions {
        extra_cards: vec![long],
        ..small_fits_options()
    };
    assert!(matches!(
        write_image(&small_map(), &opts),
        Err(FitsError::BadCard { .. })
    ));
}

/// A small deterministic generator (xorshift64) for the fuzz test.
fn xorshift(state: &mut u64) -> u64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    *state
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn garbage_and_mutated_files_never_panic() {
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut errors = 0;
    for round in 0..400 {
        let mut bytes = OURS_FITS.to_vec();
        match round % 4 {
            0 => bytes.truncate((xorshift(&mut state) % bytes.len() as u64) as usize),
            1 => {
                for _ in 0..8 {
                    let k = (xorshift(&mut state) % 2880) as usize;
                    bytes[k] = xorshift(&mut state) as u8;
                }
            }
            2 => {
                let k = (xorshift(&mut state) % 36) as usize * 80 + 10;
                let digits = format!("{:>20}", xorshift(&mut state) as i64);
                bytes[k..k + 20].copy_from_slice(digits.as_bytes());
            }
            _ => {
                bytes = (0..(xorshift(&mut state) % 6000))
                    .map(|_| xorshift(&mut state) as u8)
                    .collect()
            }
        }
        match read_image(&bytes, "fuzz.fits") {
            Ok(img) => {
                let _ = img.geometry();
                let _ = img.to_map();
            }
            Err(e) => {
                assert!(!e.to_string().is_empty());
                errors += 1;
            }
        }
    }
    assert!(
        errors > 100,
        "most damaged files are rejected ({errors} of 400)"
    );
}

/// A file that is not FITS is named by what it is, never by its raw bytes (a PNG saved as
/// `.fits` used to echo its binary header into the message).
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_file_that_is_not_fits_is_described_in_words() {
    let message = |bytes: &[u8]| read_image(bytes, "map.fits").unwrap_err().to_string();
    let png = message(b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR\0\0\x02\x88");
    assert!(png.ends_with("but it starts with a PNG image"), "{png}");
    let gz = message(b"\x1f\x8b\x08\x00\xff\x01");
    assert!(gz.contains("gzip-compressed data"), "{gz}");
    let text = message(b"# x y kappa\n1 2 3\n");
    assert!(
        text.ends_with("but it starts with the text `# x y kappa`"),
        "{text}"
    );
    let binary = message(&[0u8, 1, 2, 200, 201, 3, 7, 255, 254, 17]);
    assert!(
        binary.ends_with("but it starts with binary data"),
        "{binary}"
    );
    for m in [&png, &gz, &text, &binary] {
        assert!(m.starts_with("map.fits: not a FITS file"), "{m}");
        assert!(
            !m.chars().any(|c| c.is_control() || c == '\u{fffd}'),
            "{m:?}"
        );
    }
}
