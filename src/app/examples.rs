//! The teaching example's data, made deterministically from [`TEACHING_MODEL_JSON`]: point
//! sources behind the model, their images found by solving the lens equation, written as a
//! Lenstool image catalogue (`www/examples/teaching/images.cat`, checked by a test).

use std::fmt::Write;

use glam::DVec2;

use crate::demo::TEACHING_MODEL_JSON;
use crate::image_search::{find_images, ImageSearch, SearchGrid};
use crate::map::MapGeometry;
use crate::model::ModelFile;

use super::AppError;

/// The sources of the teaching example: `(id, z_s, beta in arcsec)`.
pub const TEACHING_SOURCES: [(&str, f64, [f64; 2]); 4] = [
    ("1", 1.5, [1.5, 1.0]),
    ("2", 2.5, [-2.0, 2.5]),
    ("3", 3.0, [0.8, -1.8]),
    ("4", 2.0, [3.5, -0.5]),
];

/// Sky position of the teaching catalogue's frame origin (RA, Dec in degrees; made up).
pub const TEACHING_REFERENCE_DEG: (f64, f64) = (150.0, 2.2);
/// Semi-axes of every image ellipse in arcsec.
const IMAGE_SIZE_ARCSEC: f64 = 0.3;
/// The image search grid: 80 arcsec wide, 0.4 arcsec pixels.
const SEARCH_FIELD_ARCSEC: f64 = 80.0;
const SEARCH_PIXELS: usize = 200;

/// The Lenstool image catalogue of the teaching example (`#REFERENCE 3` header; rows
/// `id x y a b theta z mag` with x, y in arcsec), images in order of decreasing |mu|.
pub fn teaching_image_catalog() -> Result<String, AppError> {
    let model = ModelFile::from_json_str(TEACHING_MODEL_JSON, "teaching model")
        .map_err(|e| AppError::Run(e.to_string()))?;
    let plane = model
        .lens_plane()
        .map_err(|e| AppError::Run(e.to_string()))?;
    let lens = model
        .build_lens()
        .map_err(|e| AppError::Run(e.to_string()))?;
    let grid = SearchGrid::Lens(MapGeometry::centered(SEARCH_FIELD_ARCSEC, SEARCH_PIXELS));
    let (ra, dec) = TEACHING_REFERENCE_DEG;
    let mut out = format!(
        "#REFERENCE 3 {ra} {dec}\n# Teaching example: images of {} point sources behind the \
         model of src/demo.rs (TEACHING_MODEL_JSON), made by src/app/examples.rs\n",
        TEACHING_SOURCES.len()
    );
    for (id, z, [bx, by]) in TEACHING_SOURCES {
        let f = plane
            .distance_ratio(z)
            .map_err(|e| AppError::Run(e.to_string()))?;
        let images = find_images(&lens, grid, f, DVec2::new(bx, by), &ImageSearch::default())
            .map_err(|e| AppError::Run(format!("system {id}: {e}")))?;
        for (k, im) in images.iter().enumerate() {
            let p = im.position;
            let s = IMAGE_SIZE_ARCSEC;
            // Writing into a String cannot fail.
            let _ = writeln!(
                out,
                "{id}.{} {:.4} {:.4} {s} {s} 0.0 {z} 0.0",
                k + 1,
                p.x,
                p.y
            );
        }
    }
    Ok(out)
}
