//! The kappa figure: golden PNGs, orientation, colour bar, curves, errors.

use super::*;
use tiny_skia::Pixmap;
use wslap::{
    kappa_figure_frame, render_colormap_rgba, render_kappa_png, value_rgb, ColorScale, Colormap,
    KappaPlotOptions, Marker, Overlay, OverlayPoints, RenderError,
};

/// 32 x 32 pixels over 40 arcsec: a cored elliptical halo at the origin plus a clump in the
/// North-West quadrant at (+10, +12) arcsec (+x West is to the right, +y North up).
fn figure_map() -> Map {
    Map::from_fn(MapGeometry::centered(40.0, 32), |p| {
        let halo = 1.2 / (1.0 + (p.x * p.x / 1.3 + p.y * p.y * 1.3) / 9.0).sqrt();
        let clump = 0.8 * (-(p - DVec2::new(10.0, 12.0)).length_squared() / 8.0).exp();
        halo + clump
    })
}

/// Tangential circle of 12 arcsec and radial circle of 3 arcsec about the origin, caustics.
fn figure_curves() -> CriticalCurves {
    CriticalCurves {
        z_source: 3.0,
        einstein_radius_arcsec: 12.0,
        main_curve_radius_arcsec: 12.0,
        tangential_leaves_map: false,
        tangential: vec![circle(DVec2::ZERO, 12.0, 90)],
        radial: vec![circle(DVec2::ZERO, 3.0, 40)],
        caustics: Caustics {
            tangential: vec![circle(DVec2::new(0.5, 0.0), 2.0, 40)],
            radial: vec![circle(DVec2::ZERO, 6.0, 60)],
        },
    }
}

fn figure_points() -> Vec<OverlayPoints> {
    vec![OverlayPoints {
        label: "images".into(),
        color: [255, 255, 255],
        positions_arcsec: vec![
            DVec2::new(-12.0, 1.0),
            DVec2::new(11.5, -3.0),
            DVec2::new(2.0, 12.2),
        ],
        marker: Marker::Circle,
    }]
}

fn decode(png: &[u8]) -> Pixmap {
    Pixmap::decode_png(png).expect("a PNG")
}

fn rgb_at(pm: &Pixmap, x: f32, y: f32) -> [u8; 3] {
    let p = pm.pixel(x as u32, y as u32).expect("inside the figure");
    [p.red(), p.green(), p.blue()]
}

/// Index of the colour-map entry equal to `rgb`, if any.
fn cmap_index(cmap: Colormap, rgb: [u8; 3]) -> Option<usize> {
    cmap.table().iter().position(|e| *e == rgb)
}

/// Compares with a golden PNG (per-channel tolerance, a few outliers allowed).
fn assert_golden(name: &str, png: &[u8], golden: &[u8]) {
    maybe_make_ref(&format!("golden/{name}"), png);
    let (a, b) = (decode(png), decode(golden));
    assert_eq!(
        (a.width(), a.height()),
        (b.width(), b.height()),
        "{name}: size (MAKE_REF=1 regenerates)"
    );
    let outliers = a
        .data()
        .chunks(4)
        .zip(b.data().chunks(4))
        .filter(|(p, q)| {
            p.iter()
                .zip(q.iter())
                .any(|(x, y)| x.abs_diff(*y) > GOLDEN_CHANNEL_TOL)
        })
        .count();
    let allowed = (GOLDEN_OUTLIER_FRACTION * (a.width() * a.height()) as f64) as usize;
    assert!(
        outliers <= allowed,
        "{name}: {outliers} pixels differ by more than {GOLDEN_CHANNEL_TOL} (allowed {allowed})"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn golden_figures() {
    let (map, curves) = (figure_map(), figure_curves());
    let overlay = Overlay {
        lines: Vec::new(),
        curves: Some(&curves),
        points: figure_points(),
        labels: Vec::new(),
    };
    let opts = KappaPlotOptions {
        map_pixels_on_screen: 256,
        ..KappaPlotOptions::default()
    };
    assert_golden(
        "kappa_linear.png",
        &render_kappa_png(&map, &overlay, &opts).unwrap(),
        GOLDEN_LINEAR,
    );
    let overlay = Overlay {
        lines: Vec::new(),
        curves: Some(&curves),
        points: vec![],
        labels: Vec::new(),
    };
    let opts = KappaPlotOptions {
        scale: ColorScale::Log,
        colormap: Colormap::Magma,
        show_caustics: true,
        map_pixels_on_screen: 256,
        title: Some("Test lens z_s = 3".into()),
        ..KappaPlotOptions::default()
    };
    assert_golden(
        "kappa_log_magma.png",
        &render_kappa_png(&map, &overlay, &opts).unwrap(),
        GOLDEN_LOG,
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn figure_has_north_up_west_right_a_monotonic_colour_bar_and_the_curves() {
    let (map, curves) = (figure_map(), figure_curves());
    let overlay = Overlay {
        lines: Vec::new(),
        curves: Some(&curves),
        points: vec![],
        labels: Vec::new(),
    };
    let opts = KappaPlotOptions::default();
    let png = render_kappa_png(&map, &overlay, &opts).unwrap();
    let pm = decode(&png);
    let frame = kappa_figure_frame(&map, &opts).unwrap();
    assert_eq!((pm.width(), pm.height()), (frame.width, frame.height));
    let back = frame.screen_to_arcsec(
        frame.arcsec_to_screen(DVec2::new(7.0, -3.0)).0,
        frame.arcsec_to_screen(DVec2::new(7.0, -3.0)).1,
    );
    assert!((back - DVec2::new(7.0, -3.0)).length() < 1e-4, "{back}");

    // Orientation: the clump at (+10, +12) is upper right and brighter than its mirror images.
    let level = |p: DVec2| {
        let (x, y) = frame.arcsec_to_screen(p);
        cmap_index(Colormap::Viridis, rgb_at(&pm, x, y)).expect("a map pixel")
    };
    let clump = level(DVec2::new(10.0, 12.0));
    for mirror in [
        DVec2::new(-10.0, 12.0),
        DVec2::new(10.0, -12.0),
        DVec2::new(-10.0, -12.0),
    ] {
        assert!(
            clump > level(mirror) + 40,
            "clump level {clump} vs {} at {mirror}",
            level(mirror)
        );
    }

    // The colour bar: right of the map, a column of colour-map entries decreasing downwards.
    let y_mid = frame.map_top + frame.map_side / 2.0;
    let x_bar = ((frame.map_left + frame.map_side) as u32 + 2..frame.width)
        .find(|&x| {
            (0..6).all(|d| {
                cmap_index(Colormap::Viridis, rgb_at(&pm, (x + d) as f32, y_mid)).is_some()
            })
        })
        .expect("a colour bar right of the map");
    let column: Vec<usize> = (frame.map_top as u32 + 1
        ..(frame.map_top + frame.map_side) as u32 - 1)
        .map(|y| {
            cmap_index(Colormap::Viridis, rgb_at(&pm, x_bar as f32 + 3.0, y as f32))
                .expect("colour bar pixel")
        })
        .collect();
    assert!(
        column.windows(2).all(|w| w[0] >= w[1]),
        "colour bar not monotonic"
    );
    assert!(
        column[0] >= 250 && *column.last().unwrap() <= 5,
        "colour bar spans {}..{}",
        column[0],
        column.last().unwrap()
    );

    // Curves: red on the 12-arcsec circle, cyan on the 3-arcsec one, neither at the centre.
    let near = |p: DVec2, pred: &dyn Fn([u8; 3]) -> bool| {
        let (x, y) = frame.arcsec_to_screen(p);
        (-2..=2).any(|dy| (-2..=2).any(|dx| pred(rgb_at(&pm, x + dx as f32, y + dy as f32))))
    };
    let red = |c: [u8; 3]| c[0] > 180 && c[1] < 90 && c[2] < 90;
    let cyan = |c: [u8; 3]| c[0] < 80 && c[1] > 170 && c[2] > 200;
    for angle in [0.0f64, 1.0, 2.5, 4.0] {
        assert!(
            near(12.0 * DVec2::new(angle.cos(), angle.sin()), &red),
            "no red at angle {angle}"
        );
    }
    assert!(
        near(DVec2::new(0.0, 3.0), &cyan),
        "no cyan on the radial curve"
    );
    assert!(
        !near(DVec2::new(7.0, 0.0), &red) && !near(DVec2::new(7.0, 0.0), &cyan),
        "stray curve pixels"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn raw_rgba_has_north_in_the_first_row() {
    let map = figure_map();
    let n = map.geometry.pixels;
    let rgba = render_colormap_rgba(&map, ColorScale::Log, None, None, Colormap::Magma).unwrap();
    assert_eq!(rgba.len(), n * n * 4);
    let limits = wslap::color_limits(&map, ColorScale::Log, None, None).unwrap();
    for (i, j) in [(0, n - 1), (n - 1, n - 1), (5, 0), (20, 27)] {
        let row = n - 1 - j;
        let k = (row * n + i) * 4;
        let want = value_rgb(map.at(i, j), ColorScale::Log, limits, Colormap::Magma);
        assert_eq!(&rgba[k..k + 3], &want, "pixel ({i}, {j}) is in row {row}");
        assert_eq!(rgba[k + 3], 255);
    }
    // log10 limits: max of the map and max / 1e3 at most below it.
    assert!((limits.1 - map.min_max().1.log10()).abs() < 1e-12);
    assert!(limits.1 - limits.0 <= 3.0 + 1e-12);
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn render_errors() {
    let map = figure_map();
    let none = Overlay::default();
    let bad_size = KappaPlotOptions {
        map_pixels_on_screen: 10,
        ..KappaPlotOptions::default()
    };
    let err = render_kappa_png(&map, &none, &bad_size).unwrap_err();
    assert!(
        matches!(
            err,
            RenderError::BadOption {
                name: "map_pixels_on_screen",
                ..
            }
        ),
        "{err}"
    );
    let swapped = KappaPlotOptions {
        vmin: Some(2.0),
        vmax: Some(1.0),
        ..KappaPlotOptions::default()
    };
    assert!(matches!(
        render_kappa_png(&map, &none, &swapped),
        Err(RenderError::BadOption { name: "vmin", .. })
    ));
    let negative = Map {
        data: vec![-1.0; 32 * 32],
        ..map.clone()
    };
    let log = KappaPlotOptions {
        scale: ColorScale::Log,
        ..KappaPlotOptions::default()
    };
    assert_eq!(
        render_kappa_png(&negative, &none, &log),
        Err(RenderError::NoPositiveValues)
    );
    let short = Map {
        data: vec![1.0; 10],
        ..map.clone()
    };
    assert!(matches!(
        render_kappa_png(&short, &none, &log),
        Err(RenderError::BadMap {
            len: 10,
            pixels: 32
        })
    ));
    // A constant map still renders (limits widened).
    let flat = Map {
        data: vec![0.5; 32 * 32],
        ..map
    };
    assert!(render_kappa_png(&flat, &none, &KappaPlotOptions::default()).is_ok());
}

/// Writes a 512-pixel sample figure to $WSLAP_SAMPLE_FIGURE (for looking at it).
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn sample_figure() {
    let (map, curves) = (figure_map(), figure_curves());
    let overlay = Overlay {
        lines: Vec::new(),
        curves: Some(&curves),
        points: figure_points(),
        labels: Vec::new(),
    };
    let opts = KappaPlotOptions {
        scale: ColorScale::Log,
        title: Some("Sample lens, z_s = 3.0".into()),
        show_caustics: true,
        ..Default::default()
    };
    let png = render_kappa_png(&map, &overlay, &opts).unwrap();
    assert_eq!(
        decode(&png).width(),
        kappa_figure_frame(&map, &opts).unwrap().width
    );
    if let Ok(path) = std::env::var("WSLAP_SAMPLE_FIGURE") {
        std::fs::write(&path, &png).unwrap_or_else(|e| panic!("writing {path}: {e}"));
    }
}

/// A title wider than the figure is drawn smaller (then shortened) so that it stays inside it:
/// its dark pixels lie above the map and clear of the figure's left and right edges.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_long_title_stays_inside_the_figure() {
    let map = figure_map();
    let title = "Deflection error, case (ii), z_s = 3: median 3.34\", p90 7.25\" inside r < 71\"";
    let opts = KappaPlotOptions {
        map_pixels_on_screen: 256,
        title: Some(title.into()),
        ..KappaPlotOptions::default()
    };
    let frame = kappa_figure_frame(&map, &opts).unwrap();
    let pm = decode(&render_kappa_png(&map, &Overlay::default(), &opts).unwrap());
    let dark = |x: u32, y: u32| rgb_at(&pm, x as f32, y as f32).iter().all(|&c| c < 80);
    let band = 0..frame.map_top as u32 - 2;
    let columns: Vec<u32> = (0..pm.width())
        .filter(|&x| band.clone().any(|y| dark(x, y)))
        .collect();
    assert!(
        columns.len() > 100,
        "title not drawn ({} dark columns)",
        columns.len()
    );
    let (first, last) = (columns[0], *columns.last().unwrap());
    assert!(
        first >= 2 && last < pm.width() - 2,
        "title spans columns {first}..={last} of {}",
        pm.width()
    );
}

/// The title's ink above the map: `(height of its bounding box in pixels, how many distinct
/// grey levels it has)`.
fn title_ink(map_px: u32) -> (u32, usize) {
    let opts = KappaPlotOptions {
        map_pixels_on_screen: map_px,
        title: Some("Hg".into()),
        ..KappaPlotOptions::default()
    };
    let map = figure_map();
    let pm = decode(&render_kappa_png(&map, &Overlay::default(), &opts).unwrap());
    // Above the map, between its sides (the top tick labels stick out beside it).
    let f = kappa_figure_frame(&map, &opts).unwrap();
    let (top, left, right) = (f.map_top - 2.0, f.map_left, f.map_left + f.map_side);
    let mut rows = Vec::new();
    let mut greys = std::collections::BTreeSet::new();
    for y in 0..top as u32 {
        for x in left as u32..right as u32 {
            let p = pm.pixel(x, y).unwrap();
            if p.red() < 250 {
                rows.push(y);
                greys.insert(p.red());
            }
        }
    }
    let (lo, hi) = (rows.iter().min().unwrap(), rows.iter().max().unwrap());
    (hi - lo + 1, greys.len())
}

/// Text is drawn from an outline font with antialiasing (many grey levels at the glyphs'
/// edges, where the old bitmap font had black only) and its size follows the figure's: the
/// title "Hg" (cap height and descender) of a figure twice as large is twice as tall.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn text_is_antialiased_and_scales_with_the_figure() {
    /// Pixels of difference allowed from rounding the baseline and the glyph edges.
    const EDGE_PX: i64 = 2;
    let (h1, greys) = title_ink(512);
    assert!(greys > 20, "{greys} grey levels in the title");
    // "Hg" at scale 2: cap height 14 pixels plus the descender of g.
    assert!((16..=22).contains(&h1), "title ink {h1} pixels high");
    let (h2, _) = title_ink(1024);
    assert!(
        (h2 as i64 - 2 * h1 as i64).abs() <= EDGE_PX,
        "title {h1} pixels high at 512, {h2} at 1024"
    );
    let (h_min, _) = title_ink(64);
    assert!(
        h_min >= 8,
        "the smallest figure's title is {h_min} pixels high"
    );
}
