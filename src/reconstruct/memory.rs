//! The memory a reconstruction needs at its peak, estimated from its sizes before any work, so
//! that a run the machine (or a browser tab) cannot hold is refused at once with the estimate
//! instead of failing when an allocation does, which in WebAssembly ends the whole core.
//!
//! What a run allocates (`n` unknowns: the cells of its largest grid level, one per member
//! layer and two per system; `c` cells; `P` map pixels per side), phase by phase:
//!
//! - building the linear system: the normal matrix `A` (`8 n^2` bytes), the regulariser's
//!   cell matrix (`8 c^2`, while it is added to `A`), a block of rows of `Gamma` (at most
//!   `system.block_mbytes`) with its packed copy, and the layers' deflections at the pixels
//!   (an image-plane update frees the previous system's `A` before it builds the next);
//! - solving: `A` and the solver's own matrix: the exact solver's Cholesky factor of the free
//!   unknowns (up to `8 n^2`), QADP's single-precision upper triangle (`2 n^2`, up to twice that
//!   while it grows); the accelerated gradient works on `A` itself;
//! - the products: `A` (the result keeps its system) and six maps of `8 P^2` (kappa, the two
//!   shears and deflections, the magnification) with the FFT convolution's five complex
//!   buffers of up to 2048^2 points each.
//!
//! Natively the peak is the largest phase's; in WebAssembly, whose memory never shrinks and
//! whose allocator cannot reuse a hole for a larger block, the phases' large blocks add up
//! ([`Heap`]). Measured against peak resident memory and the wasm memory's size in
//! BENCHMARKS.md ("Memory of a run").

use std::fmt;

use thiserror::Error;

use super::{ReconstructConfig, SolverMethod};
use crate::inversion::{LayerSplit, Regulariser};

/// Most memory a run may need in a browser tab: 2.5 GiB of WebAssembly's 4 GiB address space,
/// leaving room for the data, the last result (kept while the next run is made) and the
/// allocator's slack. A single allocation above 2 GiB cannot be made there at all.
pub const WASM_MEMORY_LIMIT_BYTES: u64 = 5 << 29;

/// Memory a run may use when the machine's cannot be read (not Linux): 64 GiB.
pub const FALLBACK_MEMORY_LIMIT_BYTES: u64 = 64 << 30;

/// Bytes held by the program, the data and the constraints' small tables, whatever the sizes.
const BASE_BYTES: u64 = 64 << 20;
/// Largest FFT side of the maps' convolution (`cells_fft`'s `MAX_FFT_SIDE` rounded up to a
/// smooth size).
const MAX_FFT_SIDE: u64 = 2048;
/// Rows of `Gamma` packed at once by the normal equations (`gram`'s `KC`).
const PACKED_ROWS: u64 = 256;

/// The most memory a run may use here and what that is, for messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MemoryLimit {
    pub bytes: u64,
    /// E.g. "a browser tab can use", "this machine has".
    pub what: &'static str,
}

impl MemoryLimit {
    /// On wasm32, [`WASM_MEMORY_LIMIT_BYTES`]; natively the machine's memory (`MemTotal` of
    /// `/proc/meminfo`), else [`FALLBACK_MEMORY_LIMIT_BYTES`].
    pub fn here() -> Self {
        if cfg!(target_arch = "wasm32") {
            return Self {
                bytes: WASM_MEMORY_LIMIT_BYTES,
                what: "a browser tab can give a run",
            };
        }
        match machine_memory_bytes() {
            Some(bytes) => Self {
                bytes,
                what: "this machine has",
            },
            None => Self {
                bytes: FALLBACK_MEMORY_LIMIT_BYTES,
                what: "a run may use",
            },
        }
    }
}

/// `MemTotal` of `/proc/meminfo` in bytes (Linux).
fn machine_memory_bytes() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// How the memory a run frees is given again.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Heap {
    /// Natively a freed block returns to the system or is reused: the peak is the largest
    /// phase's.
    Native,
    /// WebAssembly's linear memory never shrinks, and its allocator cannot put a larger block
    /// into the hole a smaller one left (the regulariser's cell matrix, then the exact
    /// solver's slightly larger factor): the large blocks of the phases add up.
    Wasm,
}

impl Heap {
    /// The heap of this build.
    pub fn here() -> Self {
        match cfg!(target_arch = "wasm32") {
            true => Self::Wasm,
            false => Self::Native,
        }
    }
}

/// The sizes a run's memory depends on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RunSize {
    /// Grid cells per side (`grid.cells`).
    pub cells_per_side: usize,
    /// Cells of the largest grid level (after `grid.refinements`).
    pub cells: usize,
    /// Member layers (unknowns `C`).
    pub layers: usize,
    /// Fitted systems (two unknowns `beta` each).
    pub systems: usize,
    /// Constraint pixels (two rows of `Gamma` each).
    pub pixels: usize,
    /// Map side in pixels.
    pub map_pixels: usize,
    /// Runs made side by side (an "auto" strength's candidates on several cores).
    pub side_by_side: usize,
}

impl RunSize {
    /// The sizes of a run of `config` on `pixels` constraint pixels of `systems` systems with
    /// `layers` member layers. Each refinement splits `ceil(refine_fraction * cells)` cells in
    /// four, as [`crate::inversion::CellGrid::refine`] does.
    pub fn of(config: &ReconstructConfig, pixels: usize, systems: usize, layers: usize) -> Self {
        let side = config.grid.cells;
        let mut cells = side.saturating_mul(side);
        for _ in 0..config.grid.refinements {
            let split = (config.grid.refine_fraction * cells as f64).ceil() as usize;
            cells = cells.saturating_add(split.min(cells).saturating_mul(3));
        }
        Self {
            cells_per_side: side,
            cells,
            layers,
            systems,
            pixels,
            map_pixels: config.products.pixels,
            side_by_side: 1,
        }
    }

    /// The least a run of `config` can need, before any data is known: the grid and the maps
    /// alone (no pixel, system or layer).
    pub fn of_settings(config: &ReconstructConfig) -> Self {
        Self::of(config, 0, 0, 0)
    }

    /// The maps alone (a forward model): no linear system.
    pub fn maps(map_pixels: usize) -> Self {
        Self {
            cells_per_side: 0,
            cells: 0,
            layers: 0,
            systems: 0,
            pixels: 0,
            map_pixels,
            side_by_side: 1,
        }
    }

    /// Unknowns of the linear system at its largest level.
    pub fn unknowns(&self) -> usize {
        self.cells
            .saturating_add(self.layers)
            .saturating_add(self.systems.saturating_mul(2))
    }

    /// The estimate for `config`'s solver, regulariser, image-plane updates and row blocks
    /// on this build's heap ([`Heap::here`]).
    pub fn memory(&self, config: &ReconstructConfig) -> MemoryEstimate {
        self.memory_on(config, Heap::here())
    }

    /// The estimate on `heap`.
    pub fn memory_on(&self, config: &ReconstructConfig, heap: Heap) -> MemoryEstimate {
        let n = self.unknowns() as u64;
        let square = |k: u64| k.saturating_mul(k).saturating_mul(8);
        let matrix = square(n);
        let penalty = match regularised(config) {
            true => square(self.cells as u64),
            false => 0,
        };
        let row_bytes = n.saturating_mul(16);
        let block = ((config.system.block_mbytes * 1e6) as u64)
            .min(row_bytes.saturating_mul(self.pixels as u64))
            .max(row_bytes);
        let threads = crate::threads::count(config.system.threads, self.pixels, 1) as u64;
        let rows = block + PACKED_ROWS * row_bytes / 2 * (1 + threads);
        let deflections = 16 * (self.layers as u64).saturating_mul(self.pixels as u64);
        let build = matrix + penalty + rows + deflections;
        let solver = match config.solver.method {
            SolverMethod::Exact => matrix,
            SolverMethod::Qadp => matrix / 2,
            SolverMethod::AcceleratedGradient => 0,
        };
        let solve = matrix + solver;
        // The member layers' independence (up to INDEPENDENCE_MAX_UNKNOWNS unknowns): a copy of
        // `A` without the regulariser, the cell matrix, and a Cholesky factor.
        let independence = match n as usize <= crate::solver::INDEPENDENCE_MAX_UNKNOWNS {
            true => 3 * matrix + penalty,
            false => 0,
        };
        let p = self.map_pixels as u64;
        let maps = 6 * square(p);
        let fft_side = (p + self.cells_per_side as u64).min(MAX_FFT_SIDE);
        let fft = 5 * 16 * fft_side * fft_side;
        let products = matrix + maps + fft;
        let one_run = match heap {
            Heap::Native => build.max(solve).max(independence).max(products),
            // The independence's copy of `A` may not fit the factor's hole; its cell matrix
            // and factor fit those of the build and the solver (the same sizes or smaller).
            Heap::Wasm => {
                let copy = match independence {
                    0 => 0,
                    _ => matrix,
                };
                build + solver + copy + maps + fft
            }
        };
        MemoryEstimate {
            bytes: BASE_BYTES + one_run.saturating_mul(self.side_by_side.max(1) as u64),
            size: *self,
            matrix_bytes: matrix,
            maps_bytes: maps + fft,
        }
    }
}

/// Whether `config` adds a regulariser's cell matrix to `A` (a fixed strength above 0, or
/// "auto" with any regulariser but none).
fn regularised(config: &ReconstructConfig) -> bool {
    let o = &config.objective;
    match o.strength.value() {
        Some(s) => s > 0.0 && o.regulariser != Regulariser::None,
        None => o.auto_regularisers.iter().any(|&r| r != Regulariser::None),
    }
}

/// The most member layers `split` can make of `members` members (`None`: no catalogue).
pub fn layer_count(split: LayerSplit, members: Option<usize>) -> usize {
    let Some(members) = members.filter(|&m| m > 0) else {
        return 0;
    };
    match split {
        LayerSplit::None => 0,
        LayerSplit::Single => 1,
        LayerSplit::Bcg => members.min(2),
        LayerSplit::Brightest(k) => k.min(members) + usize::from(members > k),
    }
}

/// The estimated peak memory of a run and what dominates it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MemoryEstimate {
    /// Bytes at the peak.
    pub bytes: u64,
    pub size: RunSize,
    /// The normal matrix `A`.
    pub matrix_bytes: u64,
    /// The maps and the FFT buffers.
    pub maps_bytes: u64,
}

impl MemoryEstimate {
    /// `Err` when the estimate is above `limit`.
    pub fn check(&self, limit: MemoryLimit) -> Result<(), TooMuchMemory> {
        if self.bytes <= limit.bytes {
            return Ok(());
        }
        Err(TooMuchMemory {
            estimate: *self,
            limit,
        })
    }
}

/// A run whose estimated memory is above what it may use here.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub struct TooMuchMemory {
    pub estimate: MemoryEstimate,
    pub limit: MemoryLimit,
}

impl fmt::Display for TooMuchMemory {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let e = &self.estimate;
        let s = &e.size;
        let n = s.unknowns();
        // Without data (a setting being changed), the estimate is the least a run needs.
        let (run, about) = match s.pixels {
            0 => ("a run with these settings", "at least"),
            _ => ("this run", "about"),
        };
        write!(
            f,
            "{run} would need {about} {} of memory, more than the {} {}: ",
            Bytes(e.bytes),
            Bytes(self.limit.bytes),
            self.limit.what,
        )?;
        if n > 0 {
            let refined = match s.cells != s.cells_per_side * s.cells_per_side {
                true => " after refinement",
                false => "",
            };
            write!(
                f,
                "its linear system has {n} unknowns ({} cells{refined}), so a {n} x {n} matrix \
                 of {}, and ",
                s.cells,
                Bytes(e.matrix_bytes),
            )?;
        }
        write!(
            f,
            "its maps of {p} x {p} pixels take {}",
            Bytes(e.maps_bytes),
            p = s.map_pixels,
        )?;
        if s.side_by_side > 1 {
            write!(f, ", for each of {} runs side by side", s.side_by_side)?;
        }
        // The advice lowers what takes the most: the maps, else the largest share of the
        // unknowns (cells, two per system for its source position, one per member layer).
        let (systems, layers) = (s.systems.saturating_mul(2), s.layers);
        if e.maps_bytes > e.matrix_bytes {
            write!(f, "; lower products.pixels")
        } else if s.cells >= systems.max(layers) {
            write!(f, "; lower grid.cells (or grid.refinements)")
        } else if systems >= layers {
            write!(
                f,
                "; fit fewer systems: {} systems are {systems} of the unknowns (hold some out, \
                 or split the catalogue)",
                s.systems
            )
        } else {
            write!(
                f,
                "; use fewer member layers (members.layers): {layers} layers are {layers} of \
                 the unknowns"
            )
        }
    }
}

/// A byte count for people: `512 MiB`, `4.2 GiB`, `1.9 TiB`.
#[derive(Debug, Clone, Copy)]
pub struct Bytes(pub u64);

impl fmt::Display for Bytes {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let b = self.0 as f64;
        let units = [("TiB", 40), ("GiB", 30), ("MiB", 20), ("KiB", 10)];
        for (unit, shift) in units {
            let size = (1u64 << shift) as f64;
            if b >= size {
                let v = b / size;
                return match v < 10.0 {
                    true => write!(f, "{v:.1} {unit}"),
                    false => write!(f, "{v:.0} {unit}"),
                };
            }
        }
        write!(f, "{} bytes", self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_are_written_for_people() {
        assert_eq!(Bytes(512).to_string(), "512 bytes");
        assert_eq!(Bytes(3 << 19).to_string(), "1.5 MiB");
        assert_eq!(Bytes(512 << 20).to_string(), "512 MiB");
        assert_eq!(Bytes(WASM_MEMORY_LIMIT_BYTES).to_string(), "2.5 GiB");
        assert_eq!(Bytes(34 << 40).to_string(), "34 TiB");
    }

    /// Refinement splits a quarter of the cells in four per pass, rounded up, as
    /// `CellGrid::refine` does.
    #[test]
    fn refinement_grows_the_cells_as_the_grid_does() {
        let mut config = ReconstructConfig::default();
        config.grid.cells = 10;
        assert_eq!(RunSize::of_settings(&config).cells, 100);
        config.grid.refinements = 2;
        // 100 + 3 * 25 = 175, then 175 + 3 * ceil(43.75) = 307.
        assert_eq!(RunSize::of_settings(&config).cells, 307);
        let size = RunSize::of(&config, 1000, 4, 2);
        assert_eq!(size.unknowns(), 307 + 2 + 8);
    }

    #[test]
    fn layers_follow_the_split() {
        assert_eq!(layer_count(LayerSplit::Single, None), 0);
        assert_eq!(layer_count(LayerSplit::Single, Some(0)), 0);
        assert_eq!(layer_count(LayerSplit::None, Some(40)), 0);
        assert_eq!(layer_count(LayerSplit::Single, Some(40)), 1);
        assert_eq!(layer_count(LayerSplit::Bcg, Some(40)), 2);
        assert_eq!(layer_count(LayerSplit::Brightest(3), Some(40)), 4);
        assert_eq!(layer_count(LayerSplit::Brightest(50), Some(40)), 40);
    }

    /// The default run (32 x 32 cells, 256-pixel maps) fits a browser tab many times over; the
    /// cells-128 run of the app does not (its 16384 x 16384 matrix alone is 2 GiB, an
    /// allocation WebAssembly cannot make), nor do 8192-pixel maps.
    #[test]
    fn the_browser_limit_refuses_what_it_cannot_hold() {
        let tab = MemoryLimit {
            bytes: WASM_MEMORY_LIMIT_BYTES,
            what: "a browser tab can give a run",
        };
        let mut config = ReconstructConfig::default();
        config.products.pixels = 256;
        let fits = RunSize::of(&config, 3000, 7, 1).memory_on(&config, Heap::Wasm);
        assert!(fits.bytes < 256 << 20, "{}", Bytes(fits.bytes));
        assert!(fits.check(tab).is_ok());
        config.grid.cells = 128;
        let e = RunSize::of_settings(&config).memory_on(&config, Heap::Wasm);
        assert!(e.matrix_bytes >= 2 << 30);
        // Natively the cell matrix's and the factor's memory is given back in turn.
        let native = RunSize::of_settings(&config).memory_on(&config, Heap::Native);
        assert_eq!(Bytes(native.bytes).to_string(), "4.1 GiB");
        let message = e.check(tab).unwrap_err().to_string();
        assert!(
            message.starts_with(
                "a run with these settings would need at least 6.1 GiB of memory, more than \
                 the 2.5 GiB a browser tab can give a run: its linear system has 16384 \
                 unknowns (16384 cells), so a 16384 x 16384 matrix of 2.0 GiB"
            ),
            "{message}"
        );
        assert!(message.ends_with("; lower grid.cells (or grid.refinements)"));
        config.grid.cells = 32;
        config.products.pixels = 8192;
        let message = RunSize::of_settings(&config)
            .memory_on(&config, Heap::Wasm)
            .check(tab)
            .unwrap_err()
            .to_string();
        assert!(message.ends_with("; lower products.pixels"), "{message}");
        let message = RunSize::maps(8192)
            .memory_on(&config, Heap::Wasm)
            .check(tab)
            .unwrap_err()
            .to_string();
        assert!(
            message.starts_with(
                "a run with these settings would need at least 3.4 GiB of memory, more than \
                 the 2.5 GiB a browser tab can give a run: its maps of 8192 x 8192 pixels take"
            ),
            "{message}"
        );
        // Where the systems' source positions are most of the unknowns, fewer cells would
        // not help: the advice says so.
        config.grid.cells = 16;
        let message = RunSize::of(&config, 40_000, 20_000, 1)
            .memory_on(&config, Heap::Wasm)
            .check(tab)
            .unwrap_err()
            .to_string();
        assert!(
            message.ends_with(
                "; fit fewer systems: 20000 systems are 40000 of the unknowns (hold some out, \
                 or split the catalogue)"
            ),
            "{message}"
        );
        // With data, the estimate is the run's own.
        config.products.pixels = 256;
        config.grid.cells = 128;
        let message = RunSize::of(&config, 3000, 7, 1)
            .memory_on(&config, Heap::Wasm)
            .check(tab)
            .unwrap_err()
            .to_string();
        assert!(
            message.starts_with("this run would need about 6.2 GiB of memory"),
            "{message}"
        );
    }
}
