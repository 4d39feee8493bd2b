//! Line plots and multi-panel figures: pixels land where `PlotFrame` says, styles, log axes,
//! references, legend, composition and bad input.

use crate::common;
#[cfg(not(target_arch = "wasm32"))]
mod examples;

use tiny_skia::Pixmap;
use wslap::{
    compose_grid, compose_png_grid, Axis, AxisScale, LinePlot, LineStyle, Reference, RenderError,
    Series, PALETTE,
};

const RED: [u8; 3] = [220, 20, 20];
const BLUE: [u8; 3] = [20, 20, 220];
/// Rows a 2-pixel anti-aliased line may touch away from its predicted centre.
const LINE_HALF_SPREAD_PX: f32 = 2.0;
/// Screen-position agreement of the log-axis mapping (pixels).
const MAP_TOL_PX: f64 = 1e-3;
/// Agreement of a marker's pixel centroid with the predicted screen position (pixels).
const MARKER_TOL_PX: f64 = 1.0;

fn rgb(pm: &Pixmap, x: u32, y: u32) -> [u8; 3] {
    let p = pm.pixel(x, y).expect("pixel inside the image").demultiply();
    [p.red(), p.green(), p.blue()]
}

fn is_red(c: [u8; 3]) -> bool {
    c[0] > 150 && c[1] < 120 && c[2] < 120
}

fn is_blue(c: [u8; 3]) -> bool {
    c[2] > 150 && c[0] < 120 && c[1] < 120
}

fn flat_plot(style: LineStyle, label: &str, points: Vec<(f64, f64)>) -> LinePlot {
    LinePlot {
        title: "flat".into(),
        x: Axis {
            range: Some((0.0, 10.0)),
            ..Axis::linear("x")
        },
        y: Axis {
            range: Some((0.0, 2.0)),
            ..Axis::linear("y")
        },
        series: vec![Series {
            style,
            ..Series::line(label, points, RED)
        }],
        references: vec![],
        width_px: 400,
        height_px: 300,
    }
}

/// Columns of the plot area that have a pixel matching `pred` within `spread` rows of `y`.
fn hit_columns(
    pm: &Pixmap,
    plot: &LinePlot,
    y: f32,
    spread: f32,
    pred: fn([u8; 3]) -> bool,
) -> Vec<bool> {
    let f = plot.frame().unwrap();
    let (x0, x1) = (f.left as u32, (f.left + f.plot_width) as u32);
    let (y0, y1) = ((y - spread).floor() as u32, (y + spread).ceil() as u32);
    (x0..x1)
        .map(|x| (y0..=y1).any(|yy| pred(rgb(pm, x, yy))))
        .collect()
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn horizontal_series_lands_on_the_predicted_row() {
    let plot = flat_plot(LineStyle::Solid, "", vec![(0.0, 1.0), (10.0, 1.0)]);
    let f = plot.frame().unwrap();
    let (_, y) = f.data_to_screen(5.0, 1.0).unwrap();
    common::assert_abs(
        "y = 1 at mid-height",
        y as f64,
        (f.top + f.plot_height / 2.0) as f64,
        1e-3,
    );
    let pm = plot.render_pixmap().unwrap();
    assert_eq!((pm.width(), pm.height()), (400, 300));
    let mut on_row = 0;
    for py in 0..pm.height() {
        for px in 0..pm.width() {
            if is_red(rgb(&pm, px, py)) {
                assert!(
                    (py as f32 + 0.5 - y).abs() <= LINE_HALF_SPREAD_PX,
                    "red at ({px}, {py}), line at y = {y}"
                );
                on_row += 1;
            }
        }
    }
    let hits = hit_columns(&pm, &plot, y, LINE_HALF_SPREAD_PX, is_red);
    assert!(hits.iter().all(|&h| h), "solid line has a hole");
    assert!(on_row as f32 >= f.plot_width, "{on_row} red pixels");
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn dashed_and_dotted_lines_have_gaps() {
    for style in [LineStyle::Dashed, LineStyle::Dotted, LineStyle::DashDot] {
        let plot = flat_plot(style, "", vec![(0.0, 1.0), (10.0, 1.0)]);
        let (_, y) = plot.frame().unwrap().data_to_screen(5.0, 1.0).unwrap();
        let hits = hit_columns(
            &plot.render_pixmap().unwrap(),
            &plot,
            y,
            LINE_HALF_SPREAD_PX,
            is_red,
        );
        let filled = hits.iter().filter(|&&h| h).count() as f64 / hits.len() as f64;
        let gaps = hits.windows(2).filter(|w| w[0] && !w[1]).count();
        assert!(
            (0.2..0.85).contains(&filled),
            "{style:?}: {filled} of the columns drawn"
        );
        assert!(gaps >= 10, "{style:?}: {gaps} gaps");
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn nan_and_infinite_points_break_the_line() {
    let pts = vec![
        (0.0, 1.0),
        (4.0, 1.0),
        (f64::NAN, 1.0),
        (6.0, f64::INFINITY),
        (6.0, 1.0),
        (10.0, 1.0),
    ];
    let plot = flat_plot(LineStyle::Solid, "", pts);
    let f = plot.frame().unwrap();
    let pm = plot.render_pixmap().unwrap();
    let (_, y) = f.data_to_screen(0.0, 1.0).unwrap();
    let hits = hit_columns(&pm, &plot, y, LINE_HALF_SPREAD_PX, is_red);
    let col = |x: f64| (f.data_to_screen(x, 1.0).unwrap().0 - f.left) as usize;
    assert!(
        hits[col(2.0)] && hits[col(8.0)],
        "line missing where it should be"
    );
    assert!(
        !hits[col(4.5)..col(5.5)].iter().any(|&h| h),
        "line drawn across the NaN"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn log_axis_spaces_decades_evenly() {
    let nan = (f64::NAN, f64::NAN);
    let pts = vec![
        (10.0, 1.0),
        nan,
        (100.0, 1.0),
        nan,
        (1000.0, 1.0),
        nan,
        (-5.0, 1.0),
    ];
    let mut plot = flat_plot(LineStyle::Solid, "", pts);
    plot.x = Axis {
        range: Some((1.0, 1e4)),
        ..Axis::log("iteration")
    };
    plot.series[0].markers = true;
    let f = plot.frame().unwrap();
    assert_eq!((f.x_scale, f.y_scale), (AxisScale::Log, AxisScale::Linear));
    let x = |v: f64| f.data_to_screen(v, 1.0).unwrap().0 as f64;
    common::assert_abs(
        "x(1000) - x(10) = 2 (x(100) - x(10))",
        x(1000.0) - x(10.0),
        2.0 * (x(100.0) - x(10.0)),
        MAP_TOL_PX,
    );
    common::assert_abs("x(1) at the left edge", x(1.0), f.left as f64, MAP_TOL_PX);
    assert!(f.data_to_screen(-5.0, 1.0).is_none() && f.data_to_screen(0.0, 1.0).is_none());
    let (back, _) = f.screen_to_data(x(300.0) as f32, 10.0);
    common::assert_rel("screen_to_data inverts", back, 300.0, 1e-5);
    // Markers only (every segment touches a NaN): three red blobs centred on the predictions.
    let pm = plot.render_pixmap().unwrap();
    let y = f.data_to_screen(10.0, 1.0).unwrap().1;
    let hits = hit_columns(&pm, &plot, y, 0.5, is_red);
    let mut blobs: Vec<(usize, usize)> = Vec::new();
    for (k, &h) in hits.iter().enumerate() {
        match blobs.last_mut() {
            Some(b) if h && b.1 + 1 == k => b.1 = k,
            _ if h => blobs.push((k, k)),
            _ => {}
        }
    }
    assert_eq!(blobs.len(), 3, "blobs {blobs:?}");
    for ((a, b), v) in blobs.iter().zip([10.0, 100.0, 1000.0]) {
        let centre = f.left as f64 + (a + b + 1) as f64 / 2.0;
        common::assert_abs("marker centre", centre, x(v), MARKER_TOL_PX);
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn reference_line_sits_at_its_value() {
    let mut plot = flat_plot(LineStyle::Solid, "", vec![]);
    plot.references.push(Reference {
        value: 1.5,
        label: "true".into(),
        color: BLUE,
    });
    let f = plot.frame().unwrap();
    let (_, y) = f.data_to_screen(0.0, 1.5).unwrap();
    common::assert_abs(
        "y = 1.5 at a quarter height",
        y as f64,
        (f.top + f.plot_height / 4.0) as f64,
        1e-3,
    );
    let pm = plot.render_pixmap().unwrap();
    let near = hit_columns(&pm, &plot, y, LINE_HALF_SPREAD_PX, is_blue);
    let filled = near.iter().filter(|&&h| h).count() as f64 / near.len() as f64;
    assert!(filled > 0.4, "reference covers {filled} of the width");
    // Away from the line only its label may be blue: nothing below y + 12 pixels.
    let far = hit_columns(&pm, &plot, y + 40.0, 20.0, is_blue);
    assert!(
        !far.iter().any(|&h| h),
        "blue pixels far from the reference"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn legend_box_holds_text() {
    let pts = vec![(0.0, 0.2), (10.0, 0.2)];
    let with = flat_plot(LineStyle::Dashed, "model kappa", pts.clone())
        .render_pixmap()
        .unwrap();
    let without = flat_plot(LineStyle::Dashed, "", pts)
        .render_pixmap()
        .unwrap();
    let f = flat_plot(LineStyle::Solid, "", vec![]).frame().unwrap();
    let (mut changed, mut dark, mut red) = (0, 0, 0);
    for y in 0..with.height() {
        for x in 0..with.width() {
            let (a, b) = (rgb(&with, x, y), rgb(&without, x, y));
            if a != b {
                assert!(
                    f.contains(x as f32, y as f32),
                    "legend outside the plot area at ({x}, {y})"
                );
                // The data sit low, so the legend goes to the top half.
                assert!(
                    (y as f32) < f.top + f.plot_height / 2.0,
                    "legend over the data at ({x}, {y})"
                );
                changed += 1;
                dark += usize::from(a.iter().all(|&c| c < 60));
                red += usize::from(is_red(a));
            }
        }
    }
    assert!(
        changed > 200 && dark > 30 && red > 10,
        "changed {changed}, dark {dark}, red {red}"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn empty_and_wild_inputs_render_without_panic() {
    let empty = LinePlot::default();
    assert_eq!(empty.render_pixmap().unwrap().width(), 800);
    let log_empty = LinePlot {
        x: Axis::log("iteration"),
        y: Axis::log("objective"),
        series: vec![Series::line("nothing yet", vec![], PALETTE[0])],
        ..LinePlot::default()
    };
    assert!(log_empty.render_png().unwrap().starts_with(b"\x89PNG"));
    let wild = vec![
        (f64::NAN, f64::NAN),
        (1e300, -1e300),
        (-1e-300, 1e-300),
        (f64::INFINITY, 0.0),
        (0.5, 3.0),
    ];
    let mut plot = flat_plot(LineStyle::DashDot, "wild", wild.clone());
    plot.series[0].markers = true;
    plot.render_png().unwrap();
    plot.x.range = None;
    plot.y.range = None;
    // Auto ranges over -1e300 .. 3 are fine; over -1.7e308 .. 1.7e308 the span overflows.
    plot.render_png().unwrap();
    plot.series[0]
        .points
        .extend([(1.0, 1.7e308), (2.0, -1.7e308)]);
    assert!(matches!(
        plot.render_png(),
        Err(RenderError::BadOption {
            name: "y.range",
            ..
        })
    ));
    plot.series[0].points = vec![(3.0, 7.0), (3.0, 7.0)];
    let f = plot.frame().unwrap();
    assert!(f.x_range.0 < 3.0 && f.x_range.1 > 3.0 && f.y_range.0 < 7.0 && f.y_range.1 > 7.0);
    plot.render_png().unwrap();
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn bad_plots_are_errors() {
    let ok = flat_plot(LineStyle::Solid, "a", vec![(1.0, 1.0)]);
    let bad_name = |p: &LinePlot| match p.render_png() {
        Err(RenderError::BadOption { name, .. }) => name,
        other => panic!("expected BadOption, got {other:?}"),
    };
    for (w, h) in [(0, 300), (400, 0), (100_000, 300), (400, 1 << 20)] {
        let p = LinePlot {
            width_px: w,
            height_px: h,
            ..ok.clone()
        };
        assert!(matches!(bad_name(&p), "width_px" | "height_px"));
    }
    let mut p = ok.clone();
    p.x.range = Some((2.0, 2.0));
    assert_eq!(bad_name(&p), "x.range");
    p.x.range = Some((0.0, f64::NAN));
    assert_eq!(bad_name(&p), "x.range");
    let mut p = ok.clone();
    p.y = Axis {
        range: Some((0.0, 10.0)),
        ..Axis::log("y")
    };
    assert_eq!(bad_name(&p), "y.range");
    let mut p = ok.clone();
    p.x = Axis::log("x");
    p.series[0].points = vec![(-1.0, 1.0), (0.0, 2.0)];
    assert_eq!(bad_name(&p), "x.range");
    let mut p = ok.clone();
    p.series[0].width = f32::NAN;
    assert_eq!(bad_name(&p), "series.width");
    assert!(p.frame().is_err());
}

fn solid(w: u32, h: u32, c: [u8; 3]) -> Pixmap {
    let mut p = Pixmap::new(w, h).unwrap();
    p.fill(tiny_skia::Color::from_rgba8(c[0], c[1], c[2], 255));
    p
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn compose_grid_places_panels_at_their_offsets() {
    let colors = [RED, BLUE, [20, 160, 20]];
    let panels: Vec<Pixmap> = colors.iter().map(|&c| solid(100, 80, c)).collect();
    let out = compose_grid(&panels, 2, 10).unwrap();
    assert_eq!((out.width(), out.height()), (100 + 10 + 100, 80 + 10 + 80));
    for (k, &c) in colors.iter().enumerate() {
        let (x0, y0) = ((k % 2) as u32 * 110, (k / 2) as u32 * 90);
        for (dx, dy) in [(0, 0), (99, 0), (0, 79), (99, 79), (50, 40)] {
            assert_eq!(rgb(&out, x0 + dx, y0 + dy), c, "panel {k} at +({dx}, {dy})");
        }
    }
    for (x, y) in [(105, 40), (50, 85), (160, 130), (209, 169)] {
        assert_eq!(
            rgb(&out, x, y),
            [255, 255, 255],
            "gap or empty cell at ({x}, {y})"
        );
    }
    let pngs: Vec<Vec<u8>> = panels.iter().map(|p| p.encode_png().unwrap()).collect();
    let decoded = Pixmap::decode_png(&compose_png_grid(&pngs, 2, 10).unwrap()).unwrap();
    assert_eq!(decoded.data(), out.data());
    let one_row = compose_grid(&panels, 5, 0).unwrap();
    assert_eq!((one_row.width(), one_row.height()), (300, 80));
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn bad_compositions_are_errors() {
    let p = vec![solid(10, 10, RED)];
    assert!(matches!(
        compose_grid(&[], 2, 0),
        Err(RenderError::BadOption { name: "panels", .. })
    ));
    assert!(matches!(
        compose_grid(&p, 0, 0),
        Err(RenderError::BadOption {
            name: "columns",
            ..
        })
    ));
    assert!(compose_grid(&p, 1, 0).is_ok());
    let many = vec![solid(10, 10, RED); 3];
    assert!(compose_grid(&many, 3, u32::MAX).is_err());
    let layout = wslap::grid_offsets(&[(4096, 4096); 4], 2, 0);
    assert!(layout.is_err(), "8192 x 8192 exceeds the pixel budget");
    let layout = wslap::grid_offsets(&[(4096, 4096); 2], 2, 0).unwrap();
    assert_eq!((layout.width, layout.height), (8192, 4096));
    assert!(
        matches!(compose_png_grid(&[b"not a png".to_vec()], 1, 0), Err(RenderError::Png(m)) if m.contains("panel 0"))
    );
}

/// A value drawn from a mix of ordinary, extreme and non-finite numbers.
fn wild_value(rng: &mut common::rng::Rng) -> f64 {
    let pool = [
        0.0,
        -0.0,
        1.0,
        -1.0,
        1e-300,
        -1e300,
        1e300,
        f64::MAX,
        f64::MIN_POSITIVE,
    ];
    match rng.next_u64() % 8 {
        0 => pool[(rng.next_u64() % pool.len() as u64) as usize],
        1 => [f64::NAN, f64::INFINITY, f64::NEG_INFINITY][(rng.next_u64() % 3) as usize],
        2 => 10f64.powf(40.0 * rng.normal()),
        _ => rng.normal() * 10.0,
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn random_inputs_never_panic() {
    let mut rng = common::rng::Rng(0x5eed_1234);
    let (mut drawn, mut refused) = (0, 0);
    for _ in 0..80 {
        let scale = |r: &mut common::rng::Rng| {
            if r.next_u64() % 2 == 0 {
                AxisScale::Log
            } else {
                AxisScale::Linear
            }
        };
        let axis = |r: &mut common::rng::Rng| Axis {
            label: "axis [unit]".into(),
            scale: scale(r),
            range: (r.next_u64() % 3 == 0).then(|| {
                let (a, b) = (wild_value(r), wild_value(r));
                // Mostly ordered, to get past the range check to the drawing.
                if r.next_u64() % 4 == 0 || b < a {
                    (b, a)
                } else {
                    (a, b)
                }
            }),
        };
        let (x, y) = (axis(&mut rng), axis(&mut rng));
        let series = (0..rng.next_u64() % 4)
            .map(|k| {
                let n = rng.next_u64() % 30;
                let pts = (0..n).map(|_| (wild_value(&mut rng), wild_value(&mut rng)));
                Series {
                    markers: k % 2 == 0,
                    ..Series::line(format!("s{k}"), pts.collect(), PALETTE[k as usize])
                }
            })
            .collect();
        let references = vec![Reference {
            value: wild_value(&mut rng),
            label: "ref".into(),
            color: PALETTE[6],
        }];
        let plot = LinePlot {
            title: "random".into(),
            x,
            y,
            series,
            references,
            width_px: 64 + (rng.next_u64() % 400) as u32,
            height_px: 64 + (rng.next_u64() % 300) as u32,
        };
        match (plot.render_pixmap(), plot.frame()) {
            (Ok(pm), Ok(f)) => {
                assert_eq!((pm.width(), pm.height()), (f.width, f.height));
                drawn += 1;
            }
            (Err(a), Err(b)) => {
                assert_eq!(a, b);
                refused += 1;
            }
            (a, b) => panic!("render and frame disagree: {:?} vs {b:?}", a.map(|_| ())),
        }
    }
    assert!(
        drawn > 10 && refused > 5,
        "drawn {drawn}, refused {refused}"
    );
}
