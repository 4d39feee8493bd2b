//! Reading a 2-D image HDU: header blocks up to END, then big-endian data (FITS 4.0, sec. 3-5).

use super::card::{Card, CardValue, CARD_LEN};
use super::{FitsError, FitsImage, BLOCK};

use crate::limits::{InputKind, TooLarge, MAX_FITS_PIXELS};

/// What a file that is not FITS starts with, in words: the kind of a well-known binary file
/// (a FITS map saved as PNG, a compressed FITS), its first text when that is printable, or
/// "binary data"; never its raw bytes.
fn what_it_starts_with(bytes: &[u8]) -> String {
    const KNOWN: [(&[u8], &str); 7] = [
        (b"\x89PNG", "a PNG image"),
        (b"\xff\xd8\xff", "a JPEG image"),
        (
            b"\x1f\x8b",
            "gzip-compressed data (decompress the .fits.gz first)",
        ),
        (b"BZh", "bzip2-compressed data (decompress it first)"),
        (b"PK\x03\x04", "a ZIP archive"),
        (b"%PDF", "a PDF document"),
        (b"\0asm", "a WebAssembly module"),
    ];
    if let Some((_, kind)) = KNOWN.iter().find(|(magic, _)| bytes.starts_with(magic)) {
        return kind.to_string();
    }
    let head = &bytes[..bytes.len().min(CARD_LEN)];
    match std::str::from_utf8(head) {
        Ok(text)
            if text
                .chars()
                .all(|c| !c.is_control() || c == '\n' || c == '\t') =>
        {
            let line = text.lines().next().unwrap_or("").trim();
            format!("the text `{}`", line.chars().take(40).collect::<String>())
        }
        _ => "binary data".to_string(),
    }
}

/// Reads the 2-D image of a FITS file: the primary HDU, or the first `IMAGE` extension when the
/// primary HDU has no data (`NAXIS = 0`). Values are `BZERO + BSCALE * stored`; integer pixels
/// equal to `BLANK` become NaN. `source_name` (e.g. the file name) is used in every error.
pub fn read_image(bytes: &[u8], source_name: &str) -> Result<FitsImage, FitsError> {
    let file = source_name.to_string();
    if bytes.is_empty() {
        return Err(FitsError::Empty { file });
    }
    TooLarge::check_bytes(&file, InputKind::Fits, bytes.len() as u64)?;
    let first = Card::parse(&bytes[..bytes.len().min(CARD_LEN)]);
    if first.keyword != "SIMPLE" || first.value != Some(CardValue::Logical(true)) {
        return Err(FitsError::NotFits {
            file,
            found: what_it_starts_with(bytes),
        });
    }
    let (header, data_start) = read_header(bytes, 0, &file)?;
    let hdu = Hdu {
        header,
        data_start,
        file: &file,
    };
    if hdu.int("NAXIS")? != 0 {
        return hdu.image(bytes);
    }
    let next = hdu.data_start + hdu.data_len()?;
    if next >= bytes.len() {
        return Err(FitsError::NotTwoDimensional {
            file,
            naxis: 0,
            shape: "empty".into(),
        });
    }
    let (header, data_start) = read_header(bytes, next, &file)?;
    let ext = Hdu {
        header,
        data_start,
        file: &file,
    };
    match ext.header.first() {
        Some(c) if c.keyword == "XTENSION" && c.as_str().map(str::trim) == Some("IMAGE") => {
            ext.image(bytes)
        }
        _ => Err(FitsError::NotTwoDimensional {
            file,
            naxis: 0,
            shape: "an empty primary HDU not followed by an IMAGE extension".into(),
        }),
    }
}

/// Cards from `start` up to END, and the offset of the block after the header.
fn read_header(bytes: &[u8], start: usize, file: &str) -> Result<(Vec<Card>, usize), FitsError> {
    let mut cards = Vec::new();
    let mut at = start;
    while at + CARD_LEN <= bytes.len() {
        let card = Card::parse(&bytes[at..at + CARD_LEN]);
        at += CARD_LEN;
        if card.keyword == "END" && card.value.is_none() {
            let end = start + (at - start).div_ceil(BLOCK) * BLOCK;
            return Ok((cards, end));
        }
        cards.push(card);
    }
    if bytes.len() - start < BLOCK {
        let file = file.to_string();
        return Err(FitsError::Truncated {
            file,
            what: "header".into(),
            needed: start + BLOCK,
            got: bytes.len(),
        });
    }
    Err(FitsError::NoEnd { file: file.into() })
}

struct Hdu<'a> {
    header: Vec<Card>,
    data_start: usize,
    file: &'a str,
}

impl Hdu<'_> {
    fn card(&self, key: &str) -> Option<&Card> {
        self.header.iter().find(|c| c.keyword == key)
    }

    fn int(&self, key: &str) -> Result<i64, FitsError> {
        match self.card(key).map(|c| &c.value) {
            Some(Some(CardValue::Integer(v))) => Ok(*v),
            Some(v) => Err(self.bad(key, CardValue::shown(v.as_ref()), "not an integer")),
            None => Err(FitsError::MissingKeyword {
                file: self.file.into(),
                keyword: key.into(),
            }),
        }
    }

    fn real_or(&self, key: &str, default: f64) -> Result<f64, FitsError> {
        match self.card(key) {
            None => Ok(default),
            Some(c) => c
                .as_f64()
                .filter(|v| v.is_finite())
                .ok_or_else(|| self.bad(key, CardValue::shown(c.value.as_ref()), "not a number")),
        }
    }

    fn bad(&self, key: &str, value: String, reason: &str) -> FitsError {
        FitsError::BadKeyword {
            file: self.file.into(),
            keyword: key.into(),
            value,
            reason: reason.into(),
        }
    }

    /// The `NAXISn` values.
    fn axes(&self) -> Result<Vec<usize>, FitsError> {
        let naxis = self.int("NAXIS")?;
        if !(0..=999).contains(&naxis) {
            return Err(self.bad("NAXIS", naxis.to_string(), "must be 0 to 999"));
        }
        (1..=naxis)
            .map(|k| {
                let key = format!("NAXIS{k}");
                let v = self.int(&key)?;
                usize::try_from(v)
                    .map_err(|_| self.bad(&key, v.to_string(), "negative axis length"))
            })
            .collect()
    }

    /// Bytes of data (without padding), checked against overflow.
    fn data_len(&self) -> Result<usize, FitsError> {
        let bitpix = self.int("BITPIX")?;
        if ![8, 16, 32, 64, -32, -64].contains(&bitpix) {
            return Err(self.bad("BITPIX", bitpix.to_string(), "not a FITS BITPIX value"));
        }
        let axes = self.axes()?;
        if axes.is_empty() {
            return Ok(0);
        }
        let pixels = axes.iter().try_fold(1usize, |acc, &n| acc.checked_mul(n));
        pixels
            .and_then(|p| p.checked_mul(bitpix.unsigned_abs() as usize / 8))
            .ok_or_else(|| self.bad("NAXIS", format!("{axes:?}"), "the data size overflows"))
    }

    fn image(self, bytes: &[u8]) -> Result<FitsImage, FitsError> {
        let file = self.file.to_string();
        let axes = self.axes()?;
        let bitpix = self.int("BITPIX")?;
        let extra_axes_are_one = axes.iter().skip(2).all(|&n| n == 1);
        if axes.len() < 2 || !extra_axes_are_one {
            let shape = axes
                .iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(" x ");
            return Err(FitsError::NotTwoDimensional {
                file,
                naxis: axes.len() as i64,
                shape,
            });
        }
        let (width, height) = (axes[0], axes[1]);
        if width == 0 || height == 0 || width.saturating_mul(height) > MAX_FITS_PIXELS {
            return Err(self.bad(
                "NAXIS1 x NAXIS2",
                format!("{width} x {height}"),
                &format!(
                    "an image must have 1 to {MAX_FITS_PIXELS} pixels (a 10000 x 10000 map); \
                     this header claims {}",
                    width as u128 * height as u128
                ),
            ));
        }
        let len = self.data_len()?;
        if ![16, 32, -32, -64].contains(&bitpix) {
            return Err(FitsError::UnsupportedBitpix { file, bitpix });
        }
        let needed = self.data_start.saturating_add(len);
        if needed > bytes.len() {
            let what = format!("{width} x {height} image (BITPIX = {bitpix})");
            return Err(FitsError::Truncated {
                file,
                what,
                needed,
                got: bytes.len(),
            });
        }
        let (bscale, bzero) = (self.real_or("BSCALE", 1.0)?, self.real_or("BZERO", 0.0)?);
        let blank = self.card("BLANK").and_then(Card::as_f64);
        let raw = &bytes[self.data_start..needed];
        // The identity scaling returns the stored value itself: `0.0 + 1.0 * -0.0` would be
        // +0.0, and a map must read back bit-identical to what was written.
        let identity = bscale == 1.0 && bzero == 0.0;
        let scale = |v: f64| if identity { v } else { bzero + bscale * v };
        let int = |v: i64| {
            if blank == Some(v as f64) {
                f64::NAN
            } else {
                scale(v as f64)
            }
        };
        let data: Vec<f64> = match bitpix {
            16 => raw
                .chunks_exact(2)
                .map(|c| int(i16::from_be_bytes([c[0], c[1]]) as i64))
                .collect(),
            32 => raw
                .chunks_exact(4)
                .map(|c| int(i32::from_be_bytes([c[0], c[1], c[2], c[3]]) as i64))
                .collect(),
            -32 => raw
                .chunks_exact(4)
                .map(|c| scale(f32::from_be_bytes([c[0], c[1], c[2], c[3]]) as f64))
                .collect(),
            _ => raw
                .chunks_exact(8)
                .map(|c| scale(f64::from_be_bytes(c.try_into().unwrap_or([0; 8]))))
                .collect(),
        };
        Ok(FitsImage {
            source_name: file,
            width,
            height,
            data,
            header: self.header,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fits::{write_image, FitsWriteOptions};
    use crate::map::{Map, MapGeometry};

    /// Found by fuzzing (fuzz/regressions/fits_roundtrip/): `BZERO + BSCALE * v` turned a
    /// written -0.0 into +0.0.
    #[test]
    fn written_pixels_read_back_bit_identical() {
        let values = [-0.0, 0.0, 1e-40, -3.5, f32::MAX as f64];
        let map = Map {
            geometry: MapGeometry::centered(1.0, 1),
            data: vec![values[0]],
        };
        for v in values {
            let map = Map {
                data: vec![v],
                ..map.clone()
            };
            let bytes = write_image(&map, &FitsWriteOptions::default()).unwrap();
            let read = read_image(&bytes, "map.fits").unwrap();
            assert_eq!(read.data[0].to_bits(), (v as f32 as f64).to_bits(), "{v}");
        }
    }
}
