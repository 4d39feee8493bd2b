//! Example figures written to the temp dir (`wslap_plot_examples/`) to be looked at by eye:
//! a convergence plot with a log x axis and two reference lines, a two-panel profile figure,
//! a small log-log plot and a large one with big numbers.

use tiny_skia::Pixmap;
use wslap::{compose_png_grid, Axis, LinePlot, LineStyle, Reference, Series, PALETTE};

/// Convergence- and profile-style examples written to the temp dir for a look by eye.
#[test]
fn example_figures_are_written() {
    let iters: Vec<f64> = (1..=2000).map(f64::from).collect();
    let mass: Vec<(f64, f64)> = iters
        .iter()
        .map(|&i| (i, 1.6 - 0.6 * (-i / 150.0).exp()))
        .collect();
    let c: Vec<(f64, f64)> = iters
        .iter()
        .map(|&i| (i, 0.9 + 0.25 * (-i / 400.0).exp()))
        .collect();
    let conv = LinePlot {
        title: "Grid mass and C vs iteration".into(),
        x: Axis::log("iteration"),
        y: Axis::linear("value [1e14 Msun] / C"),
        series: vec![
            Series::line("grid mass", mass, PALETTE[0]),
            Series {
                style: LineStyle::DashDot,
                ..Series::line("C (member scaling)", c, PALETTE[1])
            },
        ],
        references: vec![
            Reference {
                value: 1.6,
                label: "true grid mass".into(),
                color: PALETTE[0],
            },
            Reference {
                value: 0.9,
                label: "true C".into(),
                color: PALETTE[1],
            },
        ],
        width_px: 800,
        height_px: 500,
    };
    let r: Vec<f64> = (1..=60).map(|k| k as f64 * 0.5).collect();
    let truth: Vec<(f64, f64)> = r.iter().map(|&r| (r, 2.0 / (1.0 + r / 4.0))).collect();
    let model: Vec<(f64, f64)> = r
        .iter()
        .map(|&r| (r, 2.0 / (1.0 + r / 4.2) * (1.0 + 0.03 * (r / 3.0).sin())))
        .collect();
    let rel: Vec<(f64, f64)> = truth
        .iter()
        .zip(&model)
        .map(|(t, m)| (t.0, (m.1 - t.1) / t.1))
        .collect();
    let profile = LinePlot {
        title: "Radial convergence profile".into(),
        x: Axis::log("r [arcsec]"),
        y: Axis::log("kappa(r)"),
        series: vec![
            Series::line("truth", truth, PALETTE[6]),
            Series {
                style: LineStyle::Dashed,
                markers: true,
                ..Series::line("WSLAP+", model, PALETTE[1])
            },
        ],
        references: vec![Reference {
            value: 1.0,
            label: "kappa = 1".into(),
            color: PALETTE[2],
        }],
        width_px: 520,
        height_px: 400,
    };
    let errors = LinePlot {
        title: "Relative error".into(),
        x: Axis::log("r [arcsec]"),
        y: Axis::linear("(model - truth) / truth"),
        series: vec![Series {
            style: LineStyle::Dotted,
            ..Series::line("WSLAP+", rel, PALETTE[1])
        }],
        references: vec![Reference {
            value: 0.0,
            label: "".into(),
            color: PALETTE[6],
        }],
        width_px: 520,
        height_px: 400,
    };
    let beta: Vec<(f64, f64)> = iters
        .iter()
        .map(|&i| (i, 0.3 * (-i / 120.0).exp() + 2e-6))
        .collect();
    let small = LinePlot {
        title: "beta error".into(),
        x: Axis::log("iteration"),
        y: Axis::log("|beta - beta_true| [arcsec]"),
        series: vec![Series {
            markers: false,
            ..Series::line("rms", beta, PALETTE[2])
        }],
        width_px: 360,
        height_px: 260,
        ..LinePlot::default()
    };
    let masses: Vec<(f64, f64)> = (0..50)
        .map(|k| (k as f64 * 4.0, 1.2e14 + 3e12 * (k as f64 / 5.0).sin()))
        .collect();
    let big = LinePlot {
        title: "Enclosed mass".into(),
        x: Axis::linear("r [kpc]"),
        y: Axis::linear("M(<r) [Msun]"),
        series: vec![Series {
            markers: true,
            ..Series::line("M", masses, PALETTE[4])
        }],
        references: vec![Reference {
            value: 1.21e14,
            label: "true".into(),
            color: PALETTE[6],
        }],
        width_px: 1600,
        height_px: 1000,
    };
    let dir = std::env::temp_dir().join("wslap_plot_examples");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("small.png"), small.render_png().unwrap()).unwrap();
    std::fs::write(dir.join("big.png"), big.render_png().unwrap()).unwrap();
    let conv_png = conv.render_png().unwrap();
    let panels = vec![profile.render_png().unwrap(), errors.render_png().unwrap()];
    let both = compose_png_grid(&panels, 2, 12).unwrap();
    for (name, bytes) in [
        ("convergence.png", &conv_png),
        ("profile_panels.png", &both),
    ] {
        std::fs::write(dir.join(name), bytes).unwrap();
        let back = Pixmap::decode_png(&std::fs::read(dir.join(name)).unwrap()).unwrap();
        assert!(back.width() >= 520, "{name}");
    }
    assert_eq!(Pixmap::decode_png(&both).unwrap().width(), 520 * 2 + 12);
}
