//! NumPy `.npy` files (format version 1.0, little-endian float64, C order) and the export of
//! a linear system for inspection in Python (`--export-system DIR`).
//!
//! A version 1.0 file is the magic `\x93NUMPY`, the bytes `1, 0`, the header length as a
//! little-endian u16, then an ASCII Python dict
//! `{'descr': '<f8', 'fortran_order': False, 'shape': (r, c), }` padded with spaces and ended
//! by `\n` so that the data start at a multiple of 64 bytes, then the values.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use serde::Serialize;
use thiserror::Error;

use super::system::{ColumnInfo, LinearSystem, RowBlock, SystemError};

/// Data alignment of the header (numpy writes 64; the format requires a multiple of 16).
const HEADER_ALIGN: usize = 64;

/// Writing an export failed.
#[derive(Debug, Error)]
pub enum NpyError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {values} values do not fill shape {shape:?}")]
    Shape {
        path: PathBuf,
        shape: Vec<usize>,
        values: usize,
    },
    #[error(transparent)]
    System(#[from] SystemError),
    #[error("{path}: {source}")]
    Json {
        path: PathBuf,
        #[source]
        source: serde_json::Error,
    },
}

/// The full header (magic to the final `\n`) of a version 1.0 `<f8` C-order array of `shape`.
pub fn npy_header(shape: &[usize]) -> Vec<u8> {
    let dims = match shape {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    let mut dict = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': {dims}, }}");
    // magic (6) + version (2) + length (2) + dict + '\n' must be a multiple of HEADER_ALIGN.
    let unpadded = 10 + dict.len() + 1;
    let padded = unpadded.div_ceil(HEADER_ALIGN) * HEADER_ALIGN;
    dict.push_str(&" ".repeat(padded - unpadded));
    dict.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(dict.len() as u16).to_le_bytes());
    out.extend_from_slice(dict.as_bytes());
    out
}

/// Writes `values` (little-endian f64) to `w`.
pub fn write_f64s<W: Write>(w: &mut W, values: &[f64]) -> std::io::Result<()> {
    for v in values {
        w.write_all(&v.to_le_bytes())?;
    }
    Ok(())
}

/// A whole array to `path`: `values` in C order filling `shape`.
pub fn write_npy(path: &Path, shape: &[usize], values: &[f64]) -> Result<(), NpyError> {
    let expected: usize = shape.iter().product();
    if expected != values.len() {
        return Err(NpyError::Shape {
            path: path.to_path_buf(),
            shape: shape.to_vec(),
            values: values.len(),
        });
    }
    let io = |source| NpyError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut w = BufWriter::new(File::create(path).map_err(io)?);
    w.write_all(&npy_header(shape)).map_err(io)?;
    write_f64s(&mut w, values).map_err(io)?;
    w.flush().map_err(io)
}

/// Per-system facts in `columns.json`.
#[derive(Serialize)]
struct SystemJson<'a> {
    id: &'a str,
    z: f64,
    z_assumed: bool,
    distance_ratio: f64,
    n_images: usize,
    n_pixels: usize,
}

/// The layout written to `columns.json`.
#[derive(Serialize)]
struct ColumnsJson<'a> {
    n_rows: usize,
    n_columns: usize,
    rows: &'static str,
    theta_shift_arcsec: f64,
    mass_unit_msun: f64,
    d_l_mpc: f64,
    systems: Vec<SystemJson<'a>>,
    columns: &'a [ColumnInfo],
}

/// Writes `gamma.npy` (`n_rows x n_columns`), `theta.npy` and `weights.npy` (`n_rows`) and
/// `columns.json` (column kinds, cell centres and widths, layer names, system ids and
/// redshifts, frame shift and mass unit) into `dir` (created if missing). `gamma.npy` is
/// written block by block, so memory stays that of one block.
pub fn export_system(system: &LinearSystem, dir: &Path) -> Result<(), NpyError> {
    let io_at = |path: &Path| {
        let path = path.to_path_buf();
        move |source| NpyError::Io {
            path: path.clone(),
            source,
        }
    };
    std::fs::create_dir_all(dir).map_err(io_at(dir))?;
    let gamma_path = dir.join("gamma.npy");
    let io = io_at(&gamma_path);
    let mut w = BufWriter::new(File::create(&gamma_path).map_err(&io)?);
    w.write_all(&npy_header(&[system.n_rows, system.n_columns()]))
        .map_err(&io)?;
    let (mut theta, mut weights) = (Vec::new(), Vec::new());
    let mut block = RowBlock::default();
    let n_pix = system.constraints.pixels.len();
    let mut start = 0;
    while start < n_pix {
        let end = (start + system.pixels_per_block()).min(n_pix);
        system.rows(start..end, &mut block)?;
        write_f64s(&mut w, &block.gamma).map_err(&io)?;
        theta.extend_from_slice(&block.theta);
        weights.extend_from_slice(&block.weights);
        start = end;
    }
    let n_gal = system.shear.len();
    let mut start = 0;
    while start < n_gal {
        let end = (start + system.pixels_per_block()).min(n_gal);
        system.shear_rows(start..end, &mut block)?;
        write_f64s(&mut w, &block.gamma).map_err(&io)?;
        theta.extend_from_slice(&block.theta);
        weights.extend_from_slice(&block.weights);
        start = end;
    }
    let prior = system.prior_rows();
    write_f64s(&mut w, &prior.gamma).map_err(&io)?;
    theta.extend_from_slice(&prior.theta);
    weights.extend_from_slice(&prior.weights);
    w.flush().map_err(&io)?;
    write_npy(&dir.join("theta.npy"), &[system.n_rows], &theta)?;
    write_npy(&dir.join("weights.npy"), &[system.n_rows], &weights)?;
    let layout = ColumnsJson {
        n_rows: system.n_rows,
        n_columns: system.n_columns(),
        rows: "row 2i is theta_x + shift of pixel i, row 2i+1 theta_y + shift; \
               weights in 1/arcsec^2; then rows 2g and 2g+1 of weak-lensing galaxy g \
               (gamma_i = e_i (1 - kappa_0), weight 1/(sigma_e (1 - kappa_0))^2); \
               then one row C_l = 1 (weight 1/sigma^2) per layer with \
               a prior on its factor",
        theta_shift_arcsec: system.theta_shift_arcsec,
        mass_unit_msun: system.mass_unit_msun,
        d_l_mpc: system.d_l_mpc,
        systems: system
            .constraints
            .systems
            .iter()
            .zip(&system.distance_ratios)
            .map(|(s, &f)| SystemJson {
                id: &s.id,
                z: s.z,
                z_assumed: s.z_assumed,
                distance_ratio: f,
                n_images: s.images.len(),
                n_pixels: s.n_pixels,
            })
            .collect(),
        columns: &system.columns,
    };
    let json_path = dir.join("columns.json");
    let text = serde_json::to_string_pretty(&layout).map_err(|source| NpyError::Json {
        path: json_path.clone(),
        source,
    })?;
    std::fs::write(&json_path, text).map_err(io_at(&json_path))
}
