//! DS9 region files as arcs: shapes to lattice pixels, labels to systems and redshifts, the
//! frame from the regions, and errors by line.

use crate::common::assert_rel;
use glam::DVec2;
use wslap::SkyReference;

/// RA, Dec (degrees, 9 decimals: 4 microarcsec) of the offset `p` (arcsec) from `sky`.
fn fk5(sky: SkyReference, p: DVec2) -> String {
    let (ra, dec) = sky.offset_to_radec(p);
    format!("{ra:.9},{dec:.9}")
}

/// DS9 regions as arcs: each shape gives the lattice points inside it (as many as its area
/// holds), labels group images into systems, an excluded region cuts pixels out, and a point is
/// one pixel at its position.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn region_files_become_arc_pixels() {
    let sky = SkyReference::new(150.0, 2.2).unwrap();
    let at = |x: f64, y: f64| fk5(sky, DVec2::new(x, y));
    let text = format!(
        "# Region file format: DS9 version 4.1\n\
         global color=green\n\
         fk5\n\
         circle({c},1.5\") # text={{1.1 z=2.5}}\n\
         ellipse({e},2\",0.5\",30) # text={{1.2}}\n\
         polygon({p0},{p1},{p2}) # text={{2.1 z=1.8}}\n\
         box({b},3\",1\",0) # text={{2.2}} color=red\n\
         box({b2},3\",1\",0) # text={{2.2}}\n\
         point({pt}) # point=x text={{2.3}}\n\
         -circle({c},0.5\")\n",
        c = at(10.0, 5.0),
        e = at(-8.0, 3.0),
        // Off the lattice: a triangle with edges along lattice lines holds their points too.
        p0 = at(0.033, -9.967),
        p1 = at(4.033, -9.967),
        p2 = at(0.033, -6.967),
        b = at(-5.0, -5.0),
        b2 = at(-4.0, -5.0),
        pt = at(7.3, -2.1),
    );
    let pixel = 0.1;
    let r = wslap::arcs_from_regions(&text, "arcs.reg", Some(sky), pixel, &|_| None).unwrap();
    assert!(!r.reference_from_regions);
    let a = &r.arcs;
    assert_eq!(a.systems.len(), 2);
    let (s1, s2) = (&a.systems[0], &a.systems[1]);
    assert_eq!((s1.id.as_str(), s1.z), ("1", Some(2.5)));
    assert_eq!((s2.id.as_str(), s2.z), ("2", Some(1.8)));
    assert_eq!((s1.images.len(), s2.images.len()), (2, 3));
    assert_eq!(s1.image_ids, ["1.1", "1.2"]);
    assert_eq!(s2.image_ids, ["2.1", "2.2", "2.3"]);
    let area = |n: usize| n as f64 * pixel * pixel;
    let pi = std::f64::consts::PI;
    // The circle (r = 1.5) less the excluded one (r = 0.5) about the same centre.
    let ring = &s1.images[0];
    assert_rel(
        "ring area",
        area(ring.len()),
        pi * (1.5f64.powi(2) - 0.25),
        0.03,
    );
    for p in ring {
        let d = p.distance(DVec2::new(10.0, 5.0));
        assert!(
            (0.5 - 1e-6..=1.5 + 1e-6).contains(&d),
            "ring pixel at {d} arcsec"
        );
    }
    assert_rel(
        "ellipse area",
        area(s1.images[1].len()),
        pi * 2.0 * 0.5,
        0.05,
    );
    assert_rel(
        "triangle area",
        area(s2.images[0].len()),
        0.5 * 4.0 * 3.0,
        0.05,
    );
    // Two 3 x 1 boxes 1 arcsec apart: their union is 4 x 1, each pixel once.
    assert_rel("union of the boxes", area(s2.images[1].len()), 4.0, 0.05);
    assert_eq!(s2.images[2].len(), 1);
    assert!(
        s2.images[2][0].distance(DVec2::new(7.3, -2.1)) < 1e-5,
        "{:?}",
        s2.images[2]
    );
    // Lattice points lie on multiples of the pixel.
    for p in &s1.images[1] {
        let off = (*p / pixel - (*p / pixel).round()).abs();
        assert!(off.max_element() < 1e-9, "{p}");
    }

    // Without a reference the frame is the regions' mean position.
    let r2 = wslap::arcs_from_regions(&text, "arcs.reg", None, pixel, &|_| None).unwrap();
    assert!(r2.reference_from_regions);
    let shift = sky.to_offset_arcsec(r2.reference.ra_deg, r2.reference.dec_deg);
    let centres = [
        (10.0, 5.0),
        (-8.0, 3.0),
        (4.0 / 3.0 + 0.033, -9.0 + 0.033),
        (-5.0, -5.0),
        (-4.0, -5.0),
        (7.3, -2.1),
    ];
    let mean = centres
        .iter()
        .map(|&(x, y)| DVec2::new(x, y))
        .sum::<DVec2>()
        / 6.0;
    assert!(
        shift.distance(mean) < 1e-3,
        "frame origin {shift} vs mean {mean}"
    );
    // A polygon across RA = 0 is averaged there, not at RA 180.
    let across = "fk5\npolygon(359.999,0,0.001,0,0.001,0.001,359.999,0.001) # text={1.1 z=2}\n";
    let r3 = wslap::arcs_from_regions(across, "a.reg", None, pixel, &|_| None).unwrap();
    let (ra, dec) = (r3.reference.ra_deg, r3.reference.dec_deg);
    assert!(
        ra.min(360.0 - ra) < 1e-9 && (dec - 0.0005).abs() < 1e-9,
        "{ra}, {dec}"
    );
}

/// Redshifts: labels of one system must agree, and a system without one takes the lookup's.
/// Bad region files name their line.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn region_files_report_their_errors_by_line() {
    let sky = SkyReference::new(150.0, 2.2).unwrap();
    let c = |x: f64| fk5(sky, DVec2::new(x, 0.0));
    let read = |body: &str| {
        wslap::arcs_from_regions(&format!("fk5\n{body}"), "arcs.reg", Some(sky), 0.2, &|id| {
            (id == "7").then_some(3.3)
        })
    };
    let ok = read(&format!(
        "circle({},1\") # text={{7.1}}\ncircle({},1\") # text={{7.2}}\ncircle({},1\") # text={{8.1}}",
        c(0.0),
        c(10.0),
        c(20.0)
    ))
    .unwrap();
    assert_eq!(ok.arcs.systems[0].z, Some(3.3));
    assert_eq!(ok.arcs.systems[1].z, None);
    // Labels whose z agree within the tolerance: the system's z is their mean, as in a
    // Lenstool catalogue.
    let mean = read(&format!(
        "circle({},1\") # text={{1.1 z=2.000}}\ncircle({},1\") # text={{1.2 z=2.002}}",
        c(0.0),
        c(10.0)
    ))
    .unwrap();
    assert!((mean.arcs.systems[0].z.unwrap() - 2.001).abs() < 1e-12);

    let message = |body: String| read(&body).unwrap_err().to_string();
    let cases = [
        (
            format!(
                "circle({},1\") # text={{1.1 z=2}}\ncircle({},1\") # text={{1.2 z=2.5}}",
                c(0.0),
                c(5.0)
            ),
            "arcs.reg: line 3: image 1.2: z = 2.5, but line 2 gives system 1 z = 2",
        ),
        (
            // Each agrees with the first (tolerance 1e-3 (1 + z) = 0.003), but the last two
            // are 0.004 apart: one source cannot have both.
            format!(
                "circle({},1\") # text={{1.1 z=2.000}}\ncircle({},1\") # text={{1.2 z=2.002}}\n\
                 circle({},1\") # text={{1.3 z=1.998}}",
                c(0.0),
                c(5.0),
                c(10.0)
            ),
            "line 4: image 1.3: z = 1.998, but line 3 gives system 1 z = 2.002",
        ),
        (
            format!("circle({},1\")", c(0.0)),
            "line 2: a region without a label",
        ),
        (
            format!("circle({},1\") # text={{A}}", c(0.0)),
            "'A' is not an image id",
        ),
        (
            format!("circle({},1\") # text={{1.1 zz=2}}", c(0.0)),
            "'zz=2' is not z=VALUE",
        ),
        (
            format!("circle({},1\") # text={{1.1 z=25}}", c(0.0)),
            "z = 25 must be in (0, 20)",
        ),
        (
            format!("segment({},{}) # text={{1.1}}", c(0.0), c(1.0)),
            "line 2: an open line has no inside",
        ),
        (
            "image\ncircle(10,10,3) # text={1.1}".to_string(),
            "line 3: is in image pixels",
        ),
        (
            format!(
                "circle({},1\") # text={{1.1}}\n-circle({},2\")",
                c(0.0),
                c(0.0)
            ),
            "line 2: image 1.1: an excluded region covers all of its pixels",
        ),
        (
            format!("-circle({},1\")", c(0.0)),
            "arcs.reg: holds no region",
        ),
        (
            format!("circle({},2d) # text={{1.1}}", c(0.0)),
            "line 2: the regions up to here hold up to",
        ),
        (
            format!("circle({},1\" # text={{1.1}}", c(0.0)),
            "arcs.reg line 2",
        ),
    ];
    for (body, want) in cases {
        let got = message(body.clone());
        assert!(got.contains(want), "{body}\n  gave: {got}\n  want: {want}");
    }
}
