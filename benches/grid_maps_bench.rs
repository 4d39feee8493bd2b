//! Product maps of a reconstructed grid mass: the direct per-pixel sum against the FFT
//! convolution (src/inversion/grid_fft.rs), BENCHMARKS.md.
//!
//! ```text
//! cargo bench --bench grid_maps_bench -- [PIXELS] [REPEATS]
//! ```
//! (defaults 512 3). Cases: 32x32 and 64x64 regular grids of random cell masses (fixed seed)
//! on a map of the reconstruction's product geometry (side = grid width, centred on the origin,
//! the grid centred elsewhere). Prints the best wall time of each path and the largest
//! difference between them relative to each field's largest value.

use std::time::Instant;

use glam::DVec2;
use wslap::LensMaps;
use wslap::MapGeometry;
use wslap::{CellGrid, GridMass};

// Shared with the tests; this bench uses `uniform` only.
#[allow(dead_code)]
#[path = "../tests/common/rng.rs"]
mod rng;
use rng::Rng;

/// Best wall time in seconds of `repeats` runs of `f`, and its last result.
fn best_of<T>(repeats: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..repeats.max(1) {
        let t = Instant::now();
        out = Some(f());
        best = best.min(t.elapsed().as_secs_f64());
    }
    (best, out.expect("at least one run"))
}

/// Largest `|a - b| / max|b|` over the five fields.
fn max_rel_difference(a: &LensMaps, b: &LensMaps) -> f64 {
    let pairs = [
        (&a.kappa, &b.kappa),
        (&a.gamma1, &b.gamma1),
        (&a.gamma2, &b.gamma2),
        (&a.alpha_x, &b.alpha_x),
        (&a.alpha_y, &b.alpha_y),
    ];
    pairs
        .iter()
        .map(|(x, y)| {
            let scale = y.data.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            let diff = x
                .data
                .iter()
                .zip(&y.data)
                .fold(0.0_f64, |m, (p, q)| m.max((p - q).abs()));
            diff / scale
        })
        .fold(0.0, f64::max)
}

fn main() {
    // `cargo bench` adds `--bench` to the arguments: skip flags.
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .map(|a| a.parse().expect("arguments are PIXELS REPEATS"))
        .collect();
    let pixels = args.first().copied().unwrap_or(512);
    let repeats = args.get(1).copied().unwrap_or(3);
    let threads = std::thread::available_parallelism().map_or(1, |t| t.get());
    println!("map {pixels}^2 pixels, best of {repeats}, {threads} threads");
    println!("cells    direct_s  fft_s     speed-up  max_rel_diff");
    for n in [32, 64] {
        let grid = CellGrid::regular(DVec2::new(3.71, -2.13), 120.0, n, 0.75).expect("grid");
        let mut rng = Rng(1);
        let b2: Vec<f64> = (0..grid.len()).map(|_| 0.5 + rng.uniform()).collect();
        let mass = GridMass::new(&grid, b2).expect("grid mass");
        let geometry = MapGeometry::centered(grid.width_arcsec, pixels);
        let plan = mass.map_plan(&geometry);
        let (t_fft, fast) = best_of(repeats, || LensMaps::from_lens(&mass, geometry));
        let (t_direct, direct) =
            best_of(repeats, || LensMaps::from_lens_pixelwise(&mass, geometry));
        println!(
            "{n}x{n}    {t_direct:<9.3} {t_fft:<9.4} {:<9.0} {:.1e}   ({} cells by FFT)",
            t_direct / t_fft,
            max_rel_difference(&fast, &direct),
            plan.fft_cells
        );
    }
}
