//! DS9 regions: written files parse back (ours and the `regions` package), user files, errors.

use super::*;
use crate::common::assert_abs;
use wslap::{
    polyline_is_open, read_regions, write_marks, write_regions, Ds9Error, Ds9Frame, Mark, Shape,
};

fn vertices(shape: &Shape) -> &[DVec2] {
    match shape {
        Shape::Polygon(v) | Shape::Polyline(v) => v,
        other => panic!("expected a polygon or polyline, got {other:?}"),
    }
}

/// The marks of [`written_marks_parse_back_as_circles`]: an observed and a predicted image and
/// one with no position.
fn marks() -> Vec<Mark> {
    let mark = |x: f64, y: f64, label: &str, dashed: bool| Mark {
        position_arcsec: DVec2::new(x, y),
        label: label.to_string(),
        color: if dashed { "magenta" } else { "green" },
        tag: if dashed { "predicted" } else { "observed" },
        dashed,
    };
    vec![
        mark(3.25, -7.5, "1.1", false),
        mark(-12.0, 4.75, "1: predicted, mu=-2.3", true),
        mark(f64::NAN, 0.0, "lost", false),
    ]
}

/// Marked positions (the observed and predicted images of `images.reg`) come back as circles
/// of the given radius at the same places, with their labels, colours and dashes, in both
/// frames; a non-finite position is left out. The files are committed
/// (tests/data/files_ours_marks_*.reg) for the `regions` package's check below.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn written_marks_parse_back_as_circles() {
    let g = small_map().geometry;
    let marks = marks();
    for (reference, committed, file) in [
        (Some(sky()), OURS_MARKS_FK5_REG, "files_ours_marks_fk5.reg"),
        (None, OURS_MARKS_IMAGE_REG, "files_ours_marks_image.reg"),
    ] {
        let text = write_marks("line one\nline two", &marks, 0.5, reference, &g);
        maybe_make_ref(file, text.as_bytes());
        assert_eq!(text, committed, "{file} differs (MAKE_REF=1 regenerates)");
        assert!(text.starts_with("# Region file format: DS9 version 4.1\n# line one\n# line two\n"));
        let regions = read_regions(&text, file).unwrap();
        assert_eq!(regions.len(), 2, "{text}");
        for (region, m) in regions.iter().zip(&marks) {
            let frame = if reference.is_some() {
                Ds9Frame::Fk5
            } else {
                Ds9Frame::Image
            };
            assert_eq!(region.frame, frame);
            let Shape::Circle { center, radius } =
                region.to_frame_arcsec(reference, Some(&g)).unwrap()
            else {
                panic!("not a circle: {region:?}");
            };
            // 8 decimals in degrees (fk5) or 4 in pixels of 0.5 arcsec (image).
            assert!(
                (center - m.position_arcsec).length() < 1e-3,
                "{center} vs {}",
                m.position_arcsec
            );
            assert_abs("radius (arcsec)", radius, 0.5, 1e-4);
            assert_eq!(region.text.as_deref(), Some(m.label.as_str()));
            assert_eq!(region.color.as_deref(), Some(m.color));
        }
        let predicted = text.lines().find(|l| l.contains("predicted")).unwrap();
        assert!(
            predicted.contains("dash=1") && predicted.contains("tag={predicted}"),
            "{predicted}"
        );
        assert!(!text
            .lines()
            .find(|l| l.contains("{1.1}"))
            .unwrap()
            .contains("dash=1"));
    }
}

/// The `regions` package (tests/data/files_reference.py) reads the marks files as circles at
/// our positions, with our radii, colours, labels and dashes.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn regions_package_reads_our_marks_like_we_do() {
    let json = reference();
    let g = small_map().geometry;
    let marks = marks();
    for (name, reference) in [("marks_fk5", Some(sky())), ("marks_image", None)] {
        let theirs = json[name].as_array().unwrap();
        assert_eq!(theirs.len(), 2, "{name}: circles");
        for (t, m) in theirs.iter().zip(&marks) {
            let f = |k: &str| t[k].as_f64().unwrap();
            // Their centre in our frame: fk5 degrees, or 0-based pixels (DS9 files: 1-based).
            let (center, radius_arcsec) = match reference {
                Some(r) => (r.to_offset_arcsec(f("x"), f("y")), f("radius")),
                None => (
                    g.pixel_to_arcsec(f("x"), f("y")),
                    f("radius") * g.pixel_arcsec(),
                ),
            };
            let what = format!("{name} {}", m.label);
            assert!(
                (center - m.position_arcsec).length() < 1e-3,
                "{what}: {center}"
            );
            assert_abs(&format!("{what}: radius"), radius_arcsec, 0.5, 1e-4);
            assert_eq!(t["color"].as_str(), Some(m.color), "{what}");
            assert_eq!(t["text"].as_str(), Some(m.label.as_str()), "{what}");
            assert_eq!(t["dashed"].as_bool(), Some(m.dashed), "{what}");
        }
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn written_regions_are_committed_and_parse_back() {
    let (curves, g) = (small_curves(), small_map().geometry);
    let fk5 = write_regions(&curves, Some(sky()), &g);
    let image = write_regions(&curves, None, &g);
    maybe_make_ref("files_ours_fk5.reg", fk5.as_bytes());
    maybe_make_ref("files_ours_image.reg", image.as_bytes());
    assert_eq!(
        fk5, OURS_FK5_REG,
        "fk5 output differs from the committed file (MAKE_REF=1 regenerates)"
    );
    assert_eq!(
        image, OURS_IMAGE_REG,
        "image output differs from the committed file"
    );
    assert!(fk5.starts_with("# Region file format: DS9"));

    let all: Vec<&Vec<DVec2>> = curves
        .tangential
        .iter()
        .chain(&curves.radial)
        .chain(&curves.caustics.tangential)
        .chain(&curves.caustics.radial)
        .collect();
    for (text, frame) in [(&fk5, Ds9Frame::Fk5), (&image, Ds9Frame::Image)] {
        let regions = read_regions(text, "ours.reg").unwrap();
        assert_eq!(regions.len(), all.len());
        for (region, line) in regions.iter().zip(&all) {
            assert_eq!(region.frame, frame);
            let open = polyline_is_open(line, &g);
            assert_eq!(
                matches!(region.shape, Shape::Polyline(_)),
                open,
                "line {}",
                region.line
            );
            let back = region.to_frame_arcsec(Some(sky()), Some(&g)).unwrap();
            for (p, q) in vertices(&back).iter().zip(line.iter()) {
                // 8 decimals in degrees (fk5) or 4 in pixels of 0.5 arcsec (image).
                assert!(
                    (*p - *q).length() < 1e-3,
                    "vertex {p} vs {q} on line {}",
                    region.line
                );
            }
        }
        assert_eq!(regions[0].color.as_deref(), Some("red"));
        assert_eq!(regions[2].color.as_deref(), Some("cyan"));
        assert_eq!(
            regions[0].text.as_deref(),
            Some("tangential critical curve z=2")
        );
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn regions_package_reads_our_files_like_we_do() {
    let json = reference();
    let ours_fk5 = read_regions(OURS_FK5_REG, "fk5.reg").unwrap();
    let ours_img = read_regions(OURS_IMAGE_REG, "image.reg").unwrap();
    // `regions` skips DS9 `segment` (open curves): it only sees the polygons.
    let polygons = |r: &[wslap::Region]| -> Vec<Vec<DVec2>> {
        r.iter()
            .filter(|r| matches!(r.shape, Shape::Polygon(_)))
            .map(|r| vertices(&r.shape).to_vec())
            .collect()
    };
    for (name, ours, offset) in [
        ("regions_fk5", polygons(&ours_fk5), 0.0),
        ("regions_image", polygons(&ours_img), 1.0),
    ] {
        let theirs = json[name]["polygons"].as_array().unwrap();
        assert_eq!(theirs.len(), ours.len(), "{name}: number of polygons");
        for (k, (t, o)) in theirs.iter().zip(&ours).enumerate() {
            let t = t.as_array().unwrap();
            assert_eq!(t.len(), o.len(), "{name} polygon {k}: vertex count");
            for (tv, ov) in t.iter().zip(o) {
                // `regions` gives 0-based pixels for the image frame; DS9 files are 1-based.
                let (tx, ty) = (
                    tv[0].as_f64().unwrap() + offset,
                    tv[1].as_f64().unwrap() + offset,
                );
                assert_abs(&format!("{name} polygon {k} x"), ov.x, tx, REGION_ATOL_DEG);
                assert_abs(&format!("{name} polygon {k} y"), ov.y, ty, REGION_ATOL_DEG);
            }
        }
        assert_eq!(
            json[name]["colors"][0].as_str(),
            Some("red"),
            "{name}: first polygon colour"
        );
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn reads_a_hand_written_user_file() {
    let text = "# Region file format: DS9 version 4.1\n\
        global color=green width=1\n\
        fk5\n\
        circle(13:11:30.000,-01:20:33.00,1.5\") # color=red text={arc 1.1}\n\
        point(197.87d,-1.3425) # point=x\n\
        fk5;box(197.875,-1.3425,2\",1',30) ; polygon(197.875,-1.34,197.876,-1.34,197.876,-1.341)\n\
        -ellipse 197.875 -1.3425 0.001 0.0005 45\n\
        # text(197.875,-1.3425) text={ignored comment}\n\
        image\n\
        text 5 5 {a label}\n\
        circle point 8.5 8.5\n";
    let regions = read_regions(text, "user.reg").unwrap();
    assert_eq!(regions.len(), 6);
    match &regions[0].shape {
        Shape::Circle { center, radius } => {
            assert_abs(
                "circle RA",
                center.x,
                15.0 * (13.0 + 11.0 / 60.0 + 30.0 / 3600.0),
                1e-12,
            );
            assert_abs(
                "circle Dec",
                center.y,
                -(1.0 + 20.0 / 60.0 + 33.0 / 3600.0),
                1e-12,
            );
            assert_abs("radius arcsec", *radius, 1.5, 1e-12);
        }
        s => panic!("expected a circle, got {s:?}"),
    }
    assert_eq!(regions[0].text.as_deref(), Some("arc 1.1"));
    assert_eq!(regions[0].line, 4);
    assert!(
        matches!(regions[2].shape, Shape::Box { size, angle_deg, .. } if size == DVec2::new(2.0, 60.0) && angle_deg == 30.0)
    );
    assert!(matches!(regions[3].shape, Shape::Polygon(ref v) if v.len() == 3));
    assert!(!regions[4].include, "leading '-' excludes");
    assert!(
        matches!(regions[4].shape, Shape::Ellipse { radii, .. } if (radii - DVec2::new(3.6, 1.8)).length() < 1e-9)
    );
    assert_eq!(regions[5].frame, Ds9Frame::Image);
    // Pixel (8.5, 8.5) 1-based is the corner shared by the four central pixels of a 16-pixel map.
    let centre = regions[5]
        .to_frame_arcsec(None, Some(&small_map().geometry))
        .unwrap();
    assert_eq!(centre, Shape::Point(small_map().geometry.center));
    assert!(matches!(
        regions[1].to_frame_arcsec(None, None),
        Err(Ds9Error::NeedsReference { line: 5 })
    ));
    let p = regions[1].to_frame_arcsec(Some(sky()), None).unwrap();
    // 0.005 deg West of RA0 at Dec0 = -1.3425 deg: x = 18 cos(Dec0) arcsec.
    let x = 18.0 * 1.3425f64.to_radians().cos();
    assert!(
        matches!(p, Shape::Point(q) if (q - DVec2::new(x, 0.0)).length() < 1e-9),
        "{p:?}"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn bad_region_files_name_line_and_token() {
    let err = read_regions("fk5\ncircle(10,20,abc)\n", "bad.reg").unwrap_err();
    assert!(
        matches!(err, Ds9Error::Syntax { line: 2, ref token, .. } if token == "abc"),
        "{err}"
    );
    assert!(err.to_string().contains("bad.reg line 2"), "{err}");
    let err = read_regions("galactic\ncircle(10,20,1)\n", "bad.reg").unwrap_err();
    assert!(
        matches!(err, Ds9Error::UnsupportedFrame { line: 1, .. }),
        "{err}"
    );
    let err = read_regions("image\nannulus(10,20,1,2)\n", "bad.reg").unwrap_err();
    assert!(
        matches!(err, Ds9Error::UnsupportedShape { line: 2, ref shape, .. } if shape == "annulus"),
        "{err}"
    );
    let err = read_regions("image\npolygon(1,2,3,4,5)\n", "bad.reg").unwrap_err();
    assert!(matches!(err, Ds9Error::Syntax { line: 2, .. }), "{err}");
    let err = read_regions("fk5\npoint(10,95)\n", "bad.reg").unwrap_err();
    assert!(
        matches!(err, Ds9Error::Syntax { ref token, .. } if token == "95"),
        "{err}"
    );
    let err = read_regions("image\ncircle(1,2,3\"\n", "bad.reg").unwrap_err();
    assert!(matches!(err, Ds9Error::Syntax { line: 2, .. }), "{err}");
}
