//! Multi-panel figures: images laid out row by row on a grid over a white background.

use tiny_skia::{Color, Pixmap, PixmapPaint, Transform};

use super::RenderError;

/// Largest side in pixels of a composed figure.
pub const MAX_COMPOSED_SIDE_PX: u32 = 8192;
/// Most pixels in a composed figure (128 MB of RGBA).
pub const MAX_COMPOSED_PIXELS: u64 = 8192 * 4096;

fn bad(name: &'static str, value: String, reason: &'static str) -> RenderError {
    RenderError::BadOption {
        name,
        value,
        reason,
    }
}

/// Sum of `sizes` plus `gap_px` between neighbours, if it stays within
/// [`MAX_COMPOSED_SIDE_PX`].
fn total(sizes: &[u32], gap_px: u32) -> Option<u32> {
    let gaps = (sizes.len().saturating_sub(1) as u64) * gap_px as u64;
    let sum = sizes.iter().map(|&v| v as u64).sum::<u64>() + gaps;
    u32::try_from(sum)
        .ok()
        .filter(|&v| v <= MAX_COMPOSED_SIDE_PX)
}

/// Where [`compose_grid`] puts each panel, and the size of the figure, in pixels.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GridLayout {
    /// Top-left corner `(x, y)` of each panel.
    pub offsets: Vec<(u32, u32)>,
    pub width: u32,
    pub height: u32,
}

/// The [`GridLayout`] of panels of `sizes` `(width, height)`: panel `k` sits in row
/// `k / columns`, column `k % columns`, at the top-left of its cell; a column is as wide as its
/// widest panel, a row as tall as its tallest, with `gap_px` between cells (none around the
/// edge). `columns` above the panel count is reduced to it.
pub fn grid_offsets(
    sizes: &[(u32, u32)],
    columns: usize,
    gap_px: u32,
) -> Result<GridLayout, RenderError> {
    if sizes.is_empty() {
        return Err(bad("panels", "0".into(), "need at least one panel"));
    }
    if columns == 0 {
        return Err(bad("columns", "0".into(), "must be at least 1"));
    }
    let cols = columns.min(sizes.len());
    let rows = sizes.len().div_ceil(cols);
    let mut col_w = vec![0u32; cols];
    let mut row_h = vec![0u32; rows];
    for (k, &(w, h)) in sizes.iter().enumerate() {
        col_w[k % cols] = col_w[k % cols].max(w);
        row_h[k / cols] = row_h[k / cols].max(h);
    }
    let too_big = || {
        let value = format!("{} panels, {cols} columns, gap {gap_px}", sizes.len());
        let reason = "the figure would exceed 8192 pixels a side or 8192 x 4096 pixels";
        bad("compose_grid", value, reason)
    };
    let width = total(&col_w, gap_px).ok_or_else(too_big)?;
    let height = total(&row_h, gap_px).ok_or_else(too_big)?;
    if width as u64 * height as u64 > MAX_COMPOSED_PIXELS {
        return Err(too_big());
    }
    let start = |sizes: &[u32], i: usize| sizes[..i].iter().map(|&v| v + gap_px).sum::<u32>();
    let offsets = (0..sizes.len())
        .map(|k| (start(&col_w, k % cols), start(&row_h, k / cols)))
        .collect();
    Ok(GridLayout {
        offsets,
        width,
        height,
    })
}

/// One image of `panels` laid out on a grid of `columns` columns with `gap_px` pixels
/// between them, over white (see [`grid_offsets`]; translucent panel pixels blend onto white).
pub fn compose_grid(panels: &[Pixmap], columns: usize, gap_px: u32) -> Result<Pixmap, RenderError> {
    let sizes: Vec<(u32, u32)> = panels.iter().map(|p| (p.width(), p.height())).collect();
    let GridLayout {
        offsets,
        width: w,
        height: h,
    } = grid_offsets(&sizes, columns, gap_px)?;
    let mut out =
        Pixmap::new(w, h).ok_or_else(|| RenderError::Png(format!("cannot allocate {w} x {h}")))?;
    out.fill(Color::WHITE);
    for (p, &(x, y)) in panels.iter().zip(&offsets) {
        // Offsets are at most MAX_COMPOSED_SIDE_PX, so they fit in i32.
        out.draw_pixmap(
            x as i32,
            y as i32,
            p.as_ref(),
            &PixmapPaint::default(),
            Transform::identity(),
            None,
        );
    }
    Ok(out)
}

/// [`compose_grid`] of PNG images, encoded as PNG.
pub fn compose_png_grid(
    pngs: &[Vec<u8>],
    columns: usize,
    gap_px: u32,
) -> Result<Vec<u8>, RenderError> {
    let panels = pngs
        .iter()
        .enumerate()
        .map(|(k, bytes)| {
            Pixmap::decode_png(bytes).map_err(|e| RenderError::Png(format!("panel {k}: {e}")))
        })
        .collect::<Result<Vec<_>, _>>()?;
    compose_grid(&panels, columns, gap_px)?
        .encode_png()
        .map_err(|e| RenderError::Png(e.to_string()))
}
