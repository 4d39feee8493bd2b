//! The playground's frame (src/playground), stage by stage, on one thread as in the browser's
//! worker (BENCHMARKS.md, "Playground frame times").
//!
//! ```text
//! cargo bench --bench playground_bench -- [PIXELS] [REPEATS]
//! ```
//! (defaults 512 5). Scene: the page's default scene (www/playground/scene.js). Prints the
//! median wall time of the whole frame (drawn again with nothing changed, and after the SIE
//! moved: a released lens drag, also for a heavier SIE whose curve leaves the view) and of its
//! stages.

use std::time::Instant;

use glam::DVec2;
use wslap::playground::{Playground, Scene, CURVE_PIXELS};
use wslap::{critical_curves, LensMaps, MapGeometry, MassComponent};

const SCENE: &str = r#"{"v": 1, "z_lens": 0.3, "fov": 40,
 "lenses": [{"type": "sie", "x": 0, "y": 0, "sigma_v": 850, "q": 0.75, "pa": 20},
            {"type": "member", "x": 7, "y": -5, "mag": 19},
            {"type": "shear", "gamma1": 0.03, "gamma2": 0.02}],
 "sources": [{"type": "sersic", "x": 1.2, "y": 0.8, "z": 2, "r_eff": 0.6, "n": 1, "q": 0.7, "pa": 30},
             {"type": "gaussian", "x": -1.5, "y": -1.0, "z": 1.2, "sigma": 0.35, "q": 1, "pa": 0},
             {"type": "point", "x": 0.6, "y": -0.4, "z": 3}]}"#;

/// Median wall time in ms of `repeats` runs of `f`.
fn median_ms(repeats: usize, mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..repeats.max(1))
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let pixels = args.first().copied().unwrap_or(512);
    let repeats = args.get(1).copied().unwrap_or(5);
    let pg = Playground::new(Scene::from_json_str(SCENE).expect("scene")).expect("playground");
    let lens = &pg.built().lens;
    let geometry = MapGeometry::centered(pg.scene().fov, pixels);
    wslap::with_thread_limit(1, || {
        let frame = median_ms(repeats, || {
            std::hint::black_box(pg.frame(pixels));
        });
        let maps = median_ms(repeats, || {
            std::hint::black_box(LensMaps::from_lens(lens, geometry));
        });
        let deflection = median_ms(repeats, || {
            let mut s = DVec2::ZERO;
            for j in 0..pixels {
                for i in 0..pixels {
                    s += lens.deflection(geometry.pixel_center(i, j));
                }
            }
            std::hint::black_box(s);
        });
        // A frame after the lens of `text` moved (a released drag): nothing of it is kept.
        let released = |text: &str| {
            let mut moving =
                Playground::new(Scene::from_json_str(text).expect("scene")).expect("playground");
            let mut step = 0;
            median_ms(repeats, || {
                step += 1;
                let moved = text.replace(
                    r#""sie", "x": 0,"#,
                    &format!(r#""sie", "x": {},"#, 0.1 * step as f64),
                );
                let scene = Scene::from_json_str(&moved).expect("moved scene");
                moving.set_scene(scene).expect("scene");
                std::hint::black_box(moving.frame(pixels));
            })
        };
        let lens_moved = released(SCENE);
        // The same with a heavier SIE whose tangential curve leaves the view: the caustics
        // are then traced again on a field twice as wide (src/playground/frame.rs).
        let heavy_moved = released(&SCENE.replace(
            r#""sigma_v": 850, "q": 0.75"#,
            r#""sigma_v": 1200, "q": 0.6"#,
        ));
        // The same without the point source: what its image search costs.
        let no_point = SCENE.replace(
            r#",
             {"type": "point", "x": 0.6, "y": -0.4, "z": 3}"#,
            "",
        );
        let pg_np = Playground::new(Scene::from_json_str(&no_point).expect("scene")).expect("pg");
        let without_point = median_ms(repeats, || {
            std::hint::black_box(pg_np.frame(pixels));
        });
        let curve_maps = median_ms(repeats, || {
            std::hint::black_box(LensMaps::from_lens(
                lens,
                MapGeometry::centered(pg.scene().fov, pixels.min(CURVE_PIXELS)),
            ));
        });
        let m = LensMaps::from_lens(lens, geometry);
        let curves = median_ms(repeats, || {
            for p in &pg.built().planes {
                std::hint::black_box(critical_curves(&m, p.f, p.z, Some(lens)));
            }
        });
        let f = pg.frame(pixels);
        let vertices: usize = f
            .curves
            .iter()
            .map(|c| {
                c.tangential
                    .iter()
                    .chain(&c.radial)
                    .map(Vec::len)
                    .sum::<usize>()
                    * 2
            })
            .sum();
        println!(
            "{pixels}^2: frame {frame:.1} ms (lens and sources kept; {without_point:.1} ms \
             without the point source's images), {lens_moved:.1} ms after the lens moved \
             ({heavy_moved:.1} ms with a tangential curve that leaves the view); maps with Hessian {maps:.1} ms ({curve_maps:.1} ms on the curve grid); \
             deflection only {deflection:.1} ms; curves of {} planes {curves:.1} ms \
             ({vertices} curve and caustic vertices)",
            pg.built().planes.len()
        );
    });
}
