//! The views and read-outs: what the kappa, source and data views draw (predicted and
//! observed images, arc pixels, the legend, the show toggles) and a clicked point's images.

use crate::fixtures::{count_near, forward_session, solved, teaching_session};
use glam::DVec2;
use serde_json::json;
use wslap::Control;
use wslap::TEACHING_MODEL_JSON;
use wslap::{app::examples::teaching_image_catalog, app::examples::TEACHING_SOURCES};
use wslap::{
    app::system_rgb, app::DataRole, app::RunKind, app::Session, app::ViewOptions,
    app::COUNTER_IMAGE_RGB, app::OBSERVED_RGB, app::PREDICTED_RGB, app::SHOWN_MIN_MAGNIFICATION,
};
use wslap::{LegendPlace, PIXEL_ALPHA};

/// The map draws the predicted images down to `|mu|` = [`SHOWN_MIN_MAGNIFICATION`]; the
/// demagnified central images below it stay in `sources.json`.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn the_map_leaves_out_the_demagnified_predicted_images() {
    // The paper's QADP on the source-plane chi^2 makes a cuspy centre with demagnified images
    // (the regularised default's smooth centre may have none).
    let mut s = teaching_session();
    for (path, value) in [
        ("reconstruct.solver.method", json!("qadp")),
        ("reconstruct.objective.regulariser", json!("none")),
        ("reconstruct.objective.strength", json!(0)),
        ("reconstruct.objective.image_plane_iterations", json!(0)),
    ] {
        s.set_field(path, value).unwrap();
    }
    s.run(RunKind::Reconstruct, &mut |_| Control::Continue)
        .unwrap();
    let r = s.result().unwrap();
    let all: Vec<_> = r
        .reconstruction()
        .iter()
        .flat_map(|rec| rec.sources.iter())
        .flat_map(|src| src.predicted.iter())
        .collect();
    let faint = all
        .iter()
        .filter(|p| p.magnification.abs() < SHOWN_MIN_MAGNIFICATION)
        .count();
    let shown = r.predicted();
    println!("{} predicted, {faint} fainter than the limit", all.len());
    assert!(faint > 0, "the teaching lens predicts no demagnified image");
    assert_eq!(shown.len(), all.len() - faint);
    for p in &shown {
        let image = all.iter().find(|a| a.position_arcsec == *p).unwrap();
        assert!(image.magnification.abs() >= SHOWN_MIN_MAGNIFICATION);
    }
    let sources: serde_json::Value = serde_json::from_str(&r.sources_json().unwrap()).unwrap();
    let listed: usize = sources
        .as_array()
        .unwrap()
        .iter()
        .map(|src| src["predicted"].as_array().unwrap().len())
        .sum();
    assert_eq!(listed, all.len());
}

/// Two systems of 3 x 3 arc pixels (0.5 arcsec) on the teaching model's map.
const TWO_ARCS_JSON: &str = r#"{"systems": [
  {"id": "a", "z": 2.0, "pixels": [[-10.5, 9.5], [-10, 9.5], [-9.5, 9.5], [-10.5, 10], [-10, 10],
     [-9.5, 10], [-10.5, 10.5], [-10, 10.5], [-9.5, 10.5]]},
  {"id": "b", "z": 2.0, "pixels": [[9.5, -10.5], [10, -10.5], [10.5, -10.5], [9.5, -10], [10, -10],
     [10.5, -10], [9.5, -9.5], [10, -9.5], [10.5, -9.5]]}
]}"#;

fn rgb(pm: &tiny_skia::Pixmap, (x, y): (f32, f32)) -> [u8; 3] {
    let p = pm.pixel(x as u32, y as u32).expect("inside the figure");
    [p.red(), p.green(), p.blue()]
}

/// Where a predicted image lands on an observed one (a good fit), the observed image's marker
/// (the data) is drawn on top: the centre of every observed marker has the observed colour.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn observed_images_are_drawn_over_the_predicted_ones() {
    let s = solved();
    let r = s.result().unwrap();
    let opts = ViewOptions {
        show_members: false,
        ..ViewOptions::default()
    };
    let frame = s.kappa_frame(&opts).unwrap();
    let map = tiny_skia::Pixmap::decode_png(&s.kappa_view(&opts).unwrap().png).unwrap();
    let predicted: Vec<_> = r
        .predicted()
        .iter()
        .map(|&p| frame.arcsec_to_screen(p))
        .collect();
    let mut covered = 0;
    for &o in &r.marks.observed {
        let at = frame.arcsec_to_screen(o);
        // A predicted cross within 2 screen pixels also covers this centre.
        if predicted
            .iter()
            .any(|p| (p.0 - at.0).hypot(p.1 - at.1) < 2.0)
        {
            covered += 1;
        }
        assert_eq!(rgb(&map, at), OBSERVED_RGB, "observed image at {o}");
    }
    assert_ne!(OBSERVED_RGB, PREDICTED_RGB);
    // The test means something only if some predicted images do land on observed ones.
    println!(
        "{covered} of {} observed images have a predicted image on them",
        r.marks.observed.len()
    );
    assert!(covered > 0);
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn arc_pixels_are_drawn_in_system_colours_and_the_legend_leaves_the_map_free() {
    /// Channel tolerance of the alpha blend (rounding of 8-bit colours).
    const BLEND_TOL: i32 = 3;
    let (mut s, _, _) = forward_session();
    s.load_text(DataRole::Arcs, "arcs.json", TWO_ARCS_JSON)
        .unwrap();
    s.run(RunKind::Forward, &mut |_| Control::Continue).unwrap();
    let r = s.result().unwrap();
    assert_eq!(r.marks.arcs.len(), 2);
    assert_eq!(r.marks.arc_pixel_mas, 500);
    let below = ViewOptions::default();
    let bare = ViewOptions {
        show_observed: false,
        ..below
    };
    let frame = s.kappa_frame(&below).unwrap();
    let decode = |o: &ViewOptions| tiny_skia::Pixmap::decode_png(&s.kappa_view(o).unwrap().png);
    let (with, without) = (decode(&below).unwrap(), decode(&bare).unwrap());
    assert_eq!((with.width(), with.height()), (frame.width, frame.height));
    for (k, centre) in [(0, DVec2::new(-10.0, 10.0)), (1, DVec2::new(10.0, -10.0))] {
        let at = frame.arcsec_to_screen(centre);
        let (fg, bg) = (system_rgb(k), rgb(&without, at));
        let got = rgb(&with, at);
        for c in 0..3 {
            let want = PIXEL_ALPHA * fg[c] as f32 + (1.0 - PIXEL_ALPHA) * bg[c] as f32;
            assert!(
                (got[c] as i32 - want.round() as i32).abs() <= BLEND_TOL,
                "system {k}: {got:?} is not {fg:?} at {PIXEL_ALPHA} over {bg:?}"
            );
        }
    }
    assert_ne!(system_rgb(0), system_rgb(1));
    // Legend under the map: the map is the same with or without it except for the arcs;
    // its text (dark pixels) lies below the x-axis title, and the figure is taller than
    // the one with the legend in the map's corner.
    let inside = ViewOptions {
        legend: LegendPlace::InsideTopRight,
        ..below
    };
    let corner = decode(&inside).unwrap();
    let (x0, y0) = (frame.map_left + frame.map_side * 0.75, frame.map_top + 4.0);
    let differs = |a: &tiny_skia::Pixmap, b: &tiny_skia::Pixmap| {
        (0..20).any(|k| {
            rgb(a, (x0 + 2.0 * k as f32, y0 + 6.0)) != rgb(b, (x0 + 2.0 * k as f32, y0 + 6.0))
        })
    };
    assert!(differs(&corner, &without), "the corner legend is not drawn");
    let bare_inside = decode(&ViewOptions {
        show_observed: false,
        ..inside
    })
    .unwrap();
    assert!(corner.height() < with.height());
    assert!(bare_inside.height() < without.height());
    assert!(!differs(&with, &without), "the legend covers the map");
    let legend_rows = (frame.map_top + frame.map_side + 40.0) as u32..with.height();
    let dark = legend_rows
        .flat_map(|y| (0..with.width()).map(move |x| (x, y)))
        .filter(|&(x, y)| rgb(&with, (x as f32, y as f32)).iter().all(|&c| c < 60))
        .count();
    assert!(
        dark > 50,
        "no legend text under the map ({dark} dark pixels)"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn the_data_view_follows_the_show_toggles() {
    let mut s = Session::new();
    s.load_text(DataRole::Arcs, "arcs.json", TWO_ARCS_JSON)
        .unwrap();
    s.load_text(
        DataRole::Members,
        "members.cat",
        "#REFERENCE 3 0 0\n1 0.0 0.0 1 1 0 17.0 1\n2 -8.0 -6.0 1 1 0 18.5 1\n",
    )
    .unwrap();
    let all = ViewOptions::default();
    let png = |o: &ViewOptions| s.data_view(o).unwrap().png;
    let no_members = ViewOptions {
        show_members: false,
        ..all
    };
    let no_images = ViewOptions {
        show_observed: false,
        ..all
    };
    let nothing = ViewOptions {
        show_members: false,
        show_observed: false,
        ..all
    };
    let views = [png(&all), png(&no_members), png(&no_images), png(&nothing)];
    for (i, a) in views.iter().enumerate() {
        for b in &views[i + 1..] {
            assert_ne!(a, b, "two settings of the toggles draw the same view");
        }
    }
    // Same figure size: toggling does not move the field.
    let size = |p: &[u8]| {
        let pm = tiny_skia::Pixmap::decode_png(p).unwrap();
        (pm.width(), pm.height())
    };
    assert_eq!(size(&views[0][..]).0, size(&views[3][..]).0);
}

/// A click on the map finds the source behind the point and all its images, on the result's
/// maps. On the forward maps of the teaching model at system 1's redshift, a click on image
/// 1.1 gives back system 1: its source (1.5, 1.0) and both catalogue images, which were found
/// on the exact lens (src/app/examples.rs), to a fraction of the 0.23-arcsec pixel. The view
/// with the pin draws the images as yellow squares.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_clicked_point_shows_the_images_of_its_source() {
    let cat = teaching_image_catalog().unwrap();
    let rows: Vec<(String, DVec2)> = cat
        .lines()
        .filter(|l| l.starts_with("1."))
        .map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            let xy = DVec2::new(f[1].parse().unwrap(), f[2].parse().unwrap());
            (f[0].to_string(), xy)
        })
        .collect();
    assert_eq!(rows.len(), 2);
    let mut s = Session::new();
    s.load_text(DataRole::Model, "model.json", TEACHING_MODEL_JSON)
        .unwrap();
    s.set_field("z_lens", json!(0.3)).unwrap();
    s.set_field("reconstruct.products.size_arcsec", json!(60.0))
        .unwrap();
    s.run(RunKind::Forward, &mut |_| Control::Continue).unwrap();
    s.set_z_source(TEACHING_SOURCES[0].1).unwrap();
    let c = s.counter_images(rows[0].1).unwrap();
    assert_eq!(c.z_source, 1.5);
    let [bx, by] = TEACHING_SOURCES[0].2;
    let beta = DVec2::from_array(c.beta_arcsec);
    assert!(beta.distance(DVec2::new(bx, by)) < 0.05, "{beta}");
    for (id, p) in &rows {
        let nearest = c
            .images
            .iter()
            .map(|i| i.position_arcsec.distance(*p))
            .fold(f64::INFINITY, f64::min);
        assert!(
            nearest < 0.05,
            "image {id}: {nearest} arcsec from the nearest"
        );
    }
    let bright = c.images.iter().filter(|i| i.magnification.abs() > 0.1);
    assert_eq!(bright.count(), 2, "{:?}", c.images);
    // As DS9 regions: the clicked point and the two images, yellow, where they are.
    let text = s.counter_image_regions(rows[0].1).unwrap();
    let regions = wslap::read_regions(&text, "counter-images.reg").unwrap();
    let r = s.result().unwrap();
    let geometry = r.products().maps.geometry();
    let centres: Vec<DVec2> = regions
        .iter()
        .map(|g| {
            assert_eq!(g.color.as_deref(), Some("yellow"));
            match g
                .to_frame_arcsec(r.products().reference, Some(&geometry))
                .unwrap()
            {
                wslap::Shape::Circle { center, .. } => center,
                other => panic!("{other:?}"),
            }
        })
        .collect();
    assert_eq!(regions[0].text.as_deref(), Some("clicked point"));
    assert_eq!(centres.len(), 3, "{text}");
    assert!(centres[0].distance(rows[0].1) < 1e-3);
    for (id, p) in &rows {
        let nearest = centres[1..]
            .iter()
            .map(|c| c.distance(*p))
            .fold(f64::INFINITY, f64::min);
        assert!(nearest < 0.05, "region of image {id}: {nearest} arcsec off");
    }
    // Off the maps: an error that says so.
    let err = s.counter_images(DVec2::new(100.0, 0.0)).unwrap_err();
    assert!(err.to_string().contains("not on the maps"), "{err}");
    // Drawn with the pin: yellow squares that are not there without it.
    let yellow = |pin: Option<[f64; 2]>| {
        let opts = ViewOptions {
            pin_arcsec: pin,
            ..ViewOptions::default()
        };
        let png = s.kappa_view(&opts).unwrap().png;
        count_near(
            &tiny_skia::Pixmap::decode_png(&png).unwrap(),
            COUNTER_IMAGE_RGB,
        )
    };
    let (with, without) = (yellow(Some(rows[0].1.to_array())), yellow(None));
    assert!(
        with > without + 20,
        "{with} yellow pixels with the pin, {without} without"
    );
    // And the source plane marks its source (a forward model has no other source marks).
    let yellow = |pin: Option<[f64; 2]>| {
        let opts = ViewOptions {
            pin_arcsec: pin,
            ..ViewOptions::default()
        };
        let png = s.source_view(&opts).unwrap().png;
        count_near(
            &tiny_skia::Pixmap::decode_png(&png).unwrap(),
            COUNTER_IMAGE_RGB,
        )
    };
    let (with, without) = (yellow(Some(rows[0].1.to_array())), yellow(None));
    assert!(
        with > without + 10,
        "source plane: {with} yellow pixels with the pin, {without} without"
    );
}

/// Figures for a slide or a paper: every view drawn at `figure_scale` 2 (3) is a PNG twice
/// (three times) as wide and high as at 1, up to the rounding of the parts to whole pixels;
/// a scale outside 0.25 to 4 is refused with its value.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn views_drawn_at_figure_scale_k_are_k_times_larger() {
    /// Pixels a scaled figure may differ from `k` times the size (parts rounded one by one).
    const ROUNDING_PX: i64 = 4;
    let s = solved();
    let size = |png: &[u8]| {
        let pm = tiny_skia::Pixmap::decode_png(png).expect("a PNG");
        (pm.width() as i64, pm.height() as i64)
    };
    let views = |opts: &ViewOptions| {
        [
            s.kappa_view(opts).unwrap(),
            s.source_view(opts).unwrap(),
            s.radial_view(opts).unwrap(),
            s.convergence_view(opts).unwrap(),
        ]
    };
    let one = views(&ViewOptions::default());
    for k in [2, 3] {
        let opts = ViewOptions {
            figure_scale: k as f32,
            ..ViewOptions::default()
        };
        for (a, b) in one.iter().zip(views(&opts)) {
            let ((w1, h1), (wk, hk)) = (size(&a.png), size(&b.png));
            assert!(
                (wk - k * w1).abs() <= ROUNDING_PX && (hk - k * h1).abs() <= ROUNDING_PX,
                "{} at {k}x: {wk} x {hk}, at 1x {w1} x {h1}",
                a.name
            );
        }
    }
    for bad in [0.0, 5.0, f32::NAN] {
        let opts = ViewOptions {
            figure_scale: bad,
            ..ViewOptions::default()
        };
        let err = s.radial_view(&opts).unwrap_err().to_string();
        assert!(err.contains("figure_scale"), "{err}");
        assert!(s.kappa_view(&opts).is_err());
    }
}

/// A typed position (RA/Dec in degrees or sexagesimal, or arcsec) reads out as a click there
/// would, with RA/Dec; the read-out and the image list agree on the magnification: at the
/// point itself, and at the image found there.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_typed_position_reads_out_as_a_click_would() {
    // The teaching catalogue's frame has a sky reference (RA 150, Dec 2.2).
    let s = solved();
    let opts = ViewOptions::default();
    // Image 1.1 of the teaching catalogue.
    let p = DVec2::new(8.0429, 8.6278);
    let reference = s.result().unwrap().products().reference.unwrap();
    let (ra, dec) = reference.offset_to_radec(p);
    // Sexagesimal RA to 0.01 s and Dec to 0.1 arcsec: within 0.15 arcsec.
    for text in [
        format!("{ra:.7} {dec:.7}"),
        wslap::sexagesimal_text(ra, dec),
        "8.0429 8.6278 arcsec".to_string(),
    ] {
        let t = s.locate(&text).unwrap();
        let d = t.position_arcsec.distance(p);
        assert!(d < 0.15, "{text}: {d} arcsec off");
    }
    let h = s.readout_at(&opts, p).unwrap();
    let [hra, hdec] = h.radec_deg.unwrap();
    assert!((hra - ra).abs() < 1e-9 && (hdec - dec).abs() < 1e-9);
    let sexagesimal = h.radec_sexagesimal.clone().unwrap();
    assert_eq!(sexagesimal, "09:59:59.46 +02:12:08.6");
    let c = s.counter_images(p).unwrap();
    assert_eq!(c.point_magnification, h.magnification);
    let k = c.point_image.expect("an image of the source at the point");
    let found = c.images[k];
    assert!(c.point_image_distance_arcsec.unwrap() < 0.05, "{c:?}");
    let at_found = s.readout_at(&opts, found.position_arcsec).unwrap();
    let tol = 1e-9 * found.magnification.abs().max(1.0);
    assert!(
        (at_found.magnification - found.magnification).abs() < tol,
        "read-out {} at the found image, list {}",
        at_found.magnification,
        found.magnification
    );
    assert_eq!(c.images_sexagesimal.len(), c.images.len());
    // Bad input says what it could not read; a point off the maps says so.
    let e = s.locate("xyz").unwrap_err().to_string();
    assert!(
        e.starts_with("could not read 'xyz' as a coordinate: "),
        "{e}"
    );
    let e = s.locate("100 0 arcsec").unwrap_err().to_string();
    assert!(e.contains("arcsec maps"), "{e}");
}
