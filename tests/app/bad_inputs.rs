//! Bad JSON and FITS inputs in memory (what the browser app passes to the core): each error
//! names the file, says line and column once, and the size limits refuse a huge input before
//! it is parsed. Catalogue cases are in tests/files/catalog.rs, command-line ones in tests/cli.rs.

use wslap::app::{DataRole, Session};
use wslap::ModelFile;
use wslap::ReconstructConfig;
use wslap::{parse_arcs, ArcsError};
use wslap::{read_image, FitsError};
use wslap::{MAX_ARC_PIXELS, MAX_FITS_PIXELS};

fn config_err(text: &str) -> String {
    ReconstructConfig::from_json_str(text, "config.json")
        .expect_err("must be rejected")
        .to_string()
}

fn arcs_err(text: &str) -> String {
    parse_arcs(text, "arcs.json")
        .expect_err("must be rejected")
        .to_string()
}

/// The message names the place once: one "line" and one "column".
#[track_caller]
fn assert_place_once(message: &str) {
    assert_eq!(message.matches("line").count(), 1, "{message}");
    assert_eq!(message.matches("column").count(), 1, "{message}");
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn config_syntax_errors_say_the_place_once() {
    let err = config_err("{\n  \"grid\": {\"cells\": }\n}");
    assert_eq!(err, "config.json: line 2, column 21: expected value");
    let err = config_err("{\"solver\": {\"method\": \"newton\"}}");
    assert!(
        err.starts_with("config.json: line 1, column 30: 'method' must be one of exact, qadp, accelerated_gradient (got newton)"),
        "{err}"
    );
    let err = config_err("{\"solver\": {\"iterations\": 10, \"speed\": 2}}");
    assert!(
        err.starts_with("config.json: line 1, column 37: unknown field 'speed' (the fields here: "),
        "{err}"
    );
    assert_place_once(&err);
    // JSON has no NaN or infinity; a number beyond f64 is refused where it is written.
    let err = config_err("{\"products\": {\"z_source\": 1e999}}");
    assert_eq!(
        err,
        "config.json: line 1, column 31: a number too large for a computer (above 1.8e308)"
    );
    let err = config_err("");
    assert_eq!(
        err,
        "config.json: line 1, column 0: ends too early, where a value should be"
    );
}

/// A value of the wrong type in a settings file is refused in words a person reads, naming the
/// field and what was found: never serde's "invalid type: ..., expected usize" or "expected
/// struct GridConfig".
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn config_values_of_the_wrong_type_are_refused_in_words() {
    for (text, expected) in [
        (
            "{\"grid\": {\"cells\": 32.5}}",
            "config.json: line 1, column 23: 'cells' must be a whole number of 0 or more (got 32.5)",
        ),
        (
            "{\"grid\": {\"cells\": \"32\"}}",
            "config.json: line 1, column 23: 'cells' must be a whole number of 0 or more (got the \
             text \"32\")",
        ),
        (
            "{\"grid\": null}",
            "config.json: line 1, column 13: 'grid' must be an object in braces { } (got null)",
        ),
        (
            "{\"grid\": {\"center_arcsec\": [1]}}",
            "config.json: line 1, column 30: 'center_arcsec' must be a list of 2 numbers in \
             brackets [ ] (got 1 value)",
        ),
        (
            "{\"grid\": {\"cells\": 8}, \"grid\": {}}",
            "config.json: line 1, column 29: the field 'grid' is given twice",
        ),
        (
            "{\"grid\": {\"cells\": 8},}",
            "config.json: line 1, column 23: a comma before a closing bracket or brace (JSON \
             allows none there)",
        ),
        (
            "{} {}",
            "config.json: line 1, column 4: more text after the end of the JSON (a file holds \
             one value)",
        ),
        (
            "// settings\n{}",
            "config.json: line 1, column 1: expected value: JSON has no comments (// or /* */); \
             remove them",
        ),
    ] {
        let err = config_err(text);
        assert_eq!(err, expected, "{text}");
        for word in ["usize", "f64", "invalid type", "struct", "EOF", "trailing"] {
            assert!(!err.contains(word), "{err}");
        }
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn config_values_out_of_range_name_the_file_and_field() {
    let err = config_err("{\"products\": {\"z_source\": -1}}");
    assert_eq!(
        err,
        "config.json: products.z_source = -1 is not allowed (a source redshift must be in \
         (0, 20))"
    );
    // Every setting that sizes a run is bounded: the first value past each bound is refused,
    // naming the file, the field as written and the value.
    for (block, field, value, says) in [
        // Below 2^32, so that it is a usize in wasm32 too (the CLI's test gives 1e15).
        (
            "solver",
            "iterations",
            "4000000000",
            "= 4e9 is not allowed (at most 10^6",
        ),
        (
            "solver",
            "iterations",
            "1000001",
            "= 1000001 is not allowed (at most 10^6",
        ),
        (
            "solver",
            "report_every",
            "0",
            "= 0 is not allowed (must be 1 to 10^6)",
        ),
        (
            "solver",
            "report_every",
            "1000001",
            "= 1000001 is not allowed (must be 1 to 10^6)",
        ),
        (
            "solver",
            "start_c",
            "1001",
            "= 1001 is not allowed (the start C must be positive",
        ),
        (
            "solver",
            "start_cell_mass_msun",
            "1e19",
            "= 1e19 is not allowed (the start mass",
        ),
        (
            "products",
            "pixels",
            "8193",
            "= 8193 is not allowed (the map side must be 16 to 8192",
        ),
        (
            "products",
            "pixels",
            "15",
            "= 15 is not allowed (the map side must be 16 to 8192",
        ),
        (
            "products",
            "size_arcsec",
            "0",
            "= 0 is not allowed (the map width must be in (0",
        ),
        (
            "products",
            "z_source",
            "20",
            "= 20 is not allowed (a source redshift must be in",
        ),
        (
            "grid",
            "cells",
            "257",
            "= 257 is not allowed (must be in 1..=256)",
        ),
        (
            "grid",
            "refinements",
            "5",
            "= 5 is not allowed (must be in 0..=4)",
        ),
        (
            "objective",
            "folds",
            "21",
            "= 21 is not allowed (must be 2 to 20)",
        ),
        (
            "objective",
            "image_plane_iterations",
            "11",
            "= 11 is not allowed (must be 0 to 10)",
        ),
        (
            "constraints",
            "free_z_passes",
            "11",
            "= 11 is not allowed (must be 0 to 10)",
        ),
        (
            "constraints",
            "max_pixels_per_image",
            "1000001",
            "= 1000001 is not allowed (must be 1 to 10^6",
        ),
        (
            "system",
            "threads",
            "1025",
            "= 1025 is not allowed (must be 0 (all cores) to 1024)",
        ),
        (
            "system",
            "block_mbytes",
            "1e6",
            "= 1000000 is not allowed (must be in [0.001, 1e5] MB)",
        ),
    ] {
        let err = config_err(&format!("{{\"{block}\": {{\"{field}\": {value}}}}}"));
        let expected = format!("config.json: {block}.{field} {says}");
        assert!(err.starts_with(&expected), "{err}\nexpected: {expected}");
    }
    let err = config_err("{\"members\": {\"layers\": \"brightest:1001\"}}");
    assert!(
        err.contains("layers = \"brightest:1001\" is not one of none, single, bcg, brightest:N (N from 1 to 1000)"),
        "{err}"
    );
}

/// A setting that a run could not hold in memory is refused with the estimate when it is set,
/// before any data is loaded, and the settings stay as they were.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn app_settings_too_large_for_memory_are_refused_when_set() {
    let mut s = wslap::app::Session::new();
    s.set_field("reconstruct.grid.refine_fraction", serde_json::json!(1.0))
        .unwrap();
    // Four refinements of every cell: 32^2 * 4^4 = 262144 cells, a matrix of 550 GB.
    let err = s
        .set_field("reconstruct.grid.refinements", serde_json::json!(4))
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with(
            "reconstruct.grid.refinements: a run with these settings would need at least "
        ),
        "{err}"
    );
    assert!(
        err.contains("its linear system has 262144 unknowns (262144 cells after refinement), so a 262144 x 262144 matrix of 512 GiB"),
        "{err}"
    );
    assert!(
        err.ends_with("; lower grid.cells (or grid.refinements)"),
        "{err}"
    );
    assert_eq!(s.settings.reconstruct.grid.refinements, 0);
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn model_syntax_errors_say_the_place_once() {
    let text = "{\"z_lens\": 0.3,\n \"components\": [{\"type\": \"sis\", \"x\": 1e999, \"y\": 0, \
                \"sigma_v\": 200}]}";
    let err = ModelFile::from_json_str(text, "model.json")
        .unwrap_err()
        .to_string();
    assert_eq!(
        err,
        "model.json: line 2, column 42: a number too large for a computer (above 1.8e308)"
    );
    let err = ModelFile::from_json_str("{\"z_lens\": 0.3, \"components\": [", "model.json")
        .unwrap_err()
        .to_string();
    assert_place_once(&err);
    assert!(err.starts_with("model.json: line 1, column 31: "), "{err}");
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn arcs_errors_name_the_line_of_the_system() {
    let text = "{\"systems\": [\n  {\"id\": \"a\", \"z\": 2, \"pixels\": [[0, 1], [1, 1]]},\n  \
                {\"id\": \"b\", \"z\": 2, \"images\": [[[3, 4]], []]}\n]}";
    assert_eq!(
        arcs_err(text),
        "arcs.json: line 3: system b: no pixels in image 1 (from 0): every pixel list must \
         hold at least one pixel"
    );
    let text = "{\"systems\": [\n  {\"id\": \"a\", \"z\": 2, \"pixels\": []}]}";
    assert!(arcs_err(text).starts_with("arcs.json: line 2: system a: no pixels"));
    // A syntax error inside a system: its line and column in the file, said once.
    let text = "{\"systems\": [\n  {\"id\": \"a\", \"z\": 2, \"pixels\": [[0, 1]]},\n  \
                {\"id\": \"b\", \"z\": 2, \"pixels\": [[1e999, 0]]}]}";
    assert_eq!(
        arcs_err(text),
        "arcs.json: line 3, column 39: a number too large for a computer (above 1.8e308)"
    );
    let text = "{\"systems\": [\n  {\"id\": \"a\",\n   \"zz\": 2, \"pixels\": [[0, 1]]}]}";
    let err = arcs_err(text);
    assert!(
        err.starts_with("arcs.json: line 3, column 7: unknown field 'zz'"),
        "{err}"
    );
    assert_place_once(&err);
    // NaN, as Python's json.dump writes a missing value: named, with where it came from.
    let text = "{\"systems\": [\n  {\"id\": \"a\", \"z\": 2, \"pixels\": [[0, NaN]]}]}";
    let err = arcs_err(text);
    assert_eq!(
        err,
        "arcs.json: line 2, column 38: expected value: 'NaN' is not a number in JSON \
         (Python's json.dump writes NaN and Infinity for such values; leave them out)"
    );
    assert_place_once(&err);
    let text = "{\"systems\": [{\"id\": \"a\", \"z\": 1e30, \"pixels\": [[0, 1]]}]}";
    assert_eq!(
        arcs_err(text),
        "arcs.json: line 1: system a: z = 1000000000000000000000000000000 must be in (0, 20), \
         or 0/null when unknown"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn arcs_pixel_limit() {
    let pixels = vec!["[0,0]"; MAX_ARC_PIXELS / 2 + 1].join(",");
    let text = format!(
        "{{\"systems\": [{{\"id\": 1, \"pixels\": [{pixels}]}}, {{\"id\": 2, \"pixels\": \
         [{pixels}]}}]}}"
    );
    let err = parse_arcs(&text, "arcs.json").unwrap_err();
    assert!(matches!(err, ArcsError::TooLarge(_)), "{err}");
    assert_eq!(
        err.to_string(),
        format!(
            "arcs.json: {} pixels is more than the limit of {MAX_ARC_PIXELS} pixels for an \
             arcs file",
            2 * (MAX_ARC_PIXELS / 2 + 1)
        )
    );
}

#[cfg(not(target_arch = "wasm32"))]
#[test]
fn json_size_limit() {
    use wslap::MAX_JSON_BYTES;
    let text = " ".repeat(MAX_JSON_BYTES as usize + 1);
    let err = ModelFile::from_json_str(&text, "model.json")
        .unwrap_err()
        .to_string();
    assert_eq!(
        err,
        format!(
            "model.json: {} bytes is more than the limit of {MAX_JSON_BYTES} bytes for a model \
             file",
            MAX_JSON_BYTES + 1
        )
    );
    assert!(config_err(&text).contains("bytes for a settings file"));
}

/// One FITS header block of the given cards (80 characters each) and END.
fn fits_header(cards: &[&str]) -> Vec<u8> {
    let mut out: Vec<u8> = cards
        .iter()
        .chain(&["END"])
        .flat_map(|c| format!("{c:<80}").into_bytes())
        .collect();
    out.resize(out.len().div_ceil(2880) * 2880, b' ');
    out
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn fits_header_claiming_a_huge_image() {
    // The header alone (2880 bytes) claims 10^12 pixels: refused without reading or allocating.
    let bytes = fits_header(&[
        "SIMPLE  =                    T",
        "BITPIX  =                  -32",
        "NAXIS   =                    2",
        "NAXIS1  =              1000000",
        "NAXIS2  =              1000000",
    ]);
    let err = read_image(&bytes, "huge.fits").unwrap_err();
    assert!(matches!(err, FitsError::BadKeyword { .. }), "{err}");
    assert_eq!(
        err.to_string(),
        format!(
            "huge.fits: keyword NAXIS1 x NAXIS2 = 1000000 x 1000000: an image must have 1 to \
             {MAX_FITS_PIXELS} pixels (a 10000 x 10000 map); this header claims 1000000000000"
        )
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn fits_nan_and_infinite_pixels_are_refused_as_maps() {
    let mut bytes = fits_header(&[
        "SIMPLE  =                    T",
        "BITPIX  =                  -32",
        "NAXIS   =                    2",
        "NAXIS1  =                    2",
        "NAXIS2  =                    2",
        "CTYPE1  = 'RA---TAN'",
        "CTYPE2  = 'DEC--TAN'",
        "CRPIX1  =                  1.5",
        "CRPIX2  =                  1.5",
        "CRVAL1  =                 10.0",
        "CRVAL2  =                 20.0",
        "CDELT1  =             -0.00025",
        "CDELT2  =              0.00025",
    ]);
    for v in [1.0f32, f32::NAN, f32::INFINITY, 2.0] {
        bytes.extend_from_slice(&v.to_be_bytes());
    }
    bytes.resize(2 * 2880, 0);
    let image = read_image(&bytes, "nan.fits").unwrap();
    let err = image.to_map().unwrap_err().to_string();
    assert_eq!(
        err,
        "nan.fits: 2 pixels are NaN or infinite (first at column 1, row 0, from 0)"
    );
}

/// A setting of the wrong type is refused in words a person reads (the form shows it next to
/// the field), not serde's "invalid type: string, expected usize".
#[test]
fn settings_of_the_wrong_type_are_refused_in_words() {
    let mut s = Session::new();
    let err = |s: &mut Session, path: &str, v: serde_json::Value| {
        s.set_field(path, v).unwrap_err().to_string()
    };
    let mut all = Vec::new();
    let m = err(
        &mut s,
        "reconstruct.solver.iterations",
        serde_json::json!("many"),
    );
    assert!(m.ends_with("reconstruct.solver.iterations: must be a whole number of 0 or more (got the text \"many\")"), "{m}");
    all.push(m);
    let m = err(
        &mut s,
        "reconstruct.solver.iterations",
        serde_json::json!(-3),
    );
    assert!(
        m.ends_with("must be a whole number of 0 or more (got integer -3)"),
        "{m}"
    );
    all.push(m);
    let m = err(&mut s, "z_lens", serde_json::json!("0.3"));
    assert!(
        m.ends_with("z_lens: must be a number (got the text \"0.3\")"),
        "{m}"
    );
    all.push(m);
    let m = err(
        &mut s,
        "reconstruct.solver.method",
        serde_json::json!("newton"),
    );
    assert!(
        m.ends_with("must be one of exact, qadp, accelerated_gradient (got newton)"),
        "{m}"
    );
    all.push(m);
    for m in &all {
        for word in ["usize", "f64", "invalid type", "variant"] {
            assert!(!m.contains(word), "{m}");
        }
    }
}

/// JSON that is not a model object is refused as JSON, not read as a Lenstool `.par` that
/// lacks its blocks; a `.par` still reads as one.
#[test]
fn json_that_is_not_a_model_is_refused_as_json() {
    let mut s = Session::new();
    for (name, text) in [
        ("m.json", "[]"),
        ("m.txt", "[[[1]]]"),
        ("m.json", "\"model\""),
    ] {
        let err = s
            .load_text(DataRole::Model, name, text)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("must be an object in braces { }, not "),
            "{name}: {err}"
        );
        assert!(!err.contains("cosmologie"), "{err}");
    }
    let err = s
        .load_text(DataRole::Model, "m.par", "runmode\n\tend\n")
        .unwrap_err()
        .to_string();
    assert!(err.contains("cosmologie"), "{err}");
}

/// A catalogue whose lines end in a carriage return alone (classic Mac OS, some spreadsheet
/// exports) reads as the same rows as with line feeds, not as one long first line.
#[test]
fn carriage_return_line_ends_read_as_lines() {
    let images = include_str!("../data/weak_lensing/images.cat");
    assert!(images.lines().count() > 5 && !images.contains('\r'));
    let mut s = Session::new();
    let unix = s.load_text(DataRole::Images, "i.cat", images).unwrap();
    let mac = s
        .load_text(DataRole::Images, "i.cat", &images.replace('\n', "\r"))
        .unwrap();
    assert_eq!(mac.summary, unix.summary);
    assert_eq!(mac.warnings, unix.warnings);
    // A file edited on several systems: some lines end in CR LF, some in LF, some in CR.
    let mixed: String = images
        .lines()
        .enumerate()
        .map(|(k, line)| format!("{line}{}", ["\r\n", "\n", "\r"][k % 3]))
        .collect();
    let mixed = s.load_text(DataRole::Images, "i.cat", &mixed).unwrap();
    assert_eq!(mixed.summary, unix.summary);
    assert_eq!(mixed.warnings, unix.warnings);
}
