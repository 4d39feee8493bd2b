//! FITS images in the HFF lens-model convention ([method §1] and [§7]), written by hand.
//!
//! Written files: one float32 (`BITPIX = -32`, big-endian) 2-D primary image in 2880-byte
//! blocks of 80-character cards, WCS `RA---TAN` / `DEC--TAN` in degrees,
//! `CDELT1 = -pixel/3600 < 0` (pixel `i` grows West), `CDELT2 = +pixel/3600`,
//! `CRPIX = n/2 + 0.5` (the map centre) and `CRVAL` the sky position of the map centre.
//! Two private cards keep the frame's origin so that a read gives back the same geometry:
//! `REFRA` / `REFDEC` (degrees), or `NOSKYREF = T` when the frame has no sky position (then
//! `CRVAL` is measured from RA = Dec = 0 and is only a placeholder).
//!
//! Read files: a 2-D image in the primary HDU, or in the first `IMAGE` extension when the
//! primary HDU is empty; `BITPIX` -32, -64, 16 or 32 with `BSCALE` / `BZERO` / `BLANK`.
//!
//! [method §1]: crate::method#1-frames-and-units
//! [§7]: crate::method#7-file-formats

use glam::DVec2;
use thiserror::Error;

use crate::map::{Map, MapGeometry};
use crate::sky::SkyReference;

mod card;
mod read;

pub use card::{Card, CardValue};
pub use read::read_image;

const BLOCK: usize = 2880;
/// Keywords the writer sets itself; extra cards may not use them.
const RESERVED: &[&str] = &[
    "SIMPLE", "BITPIX", "NAXIS", "NAXIS1", "NAXIS2", "EXTEND", "BUNIT", "WCSAXES", "CTYPE1",
    "CTYPE2", "CUNIT1", "CUNIT2", "CRPIX1", "CRPIX2", "CRVAL1", "CRVAL2", "CDELT1", "CDELT2",
    "RADESYS", "EQUINOX", "REFRA", "REFDEC", "NOSKYREF", "BSCALE", "BZERO", "BLANK", "END",
];

/// What went wrong reading or writing a FITS file; `file` is the name given by the caller.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum FitsError {
    #[error("{file}: empty file (0 bytes)")]
    Empty { file: String },
    #[error("{file}: not a FITS file: it must start with the card `SIMPLE = T`, but it starts with {found}")]
    NotFits { file: String, found: String },
    #[error("{file}: truncated: the {what} needs {needed} bytes but the file has {got}")]
    Truncated {
        file: String,
        what: String,
        needed: usize,
        got: usize,
    },
    #[error(transparent)]
    TooLarge(#[from] crate::limits::TooLarge),
    #[error("{file}: header has no END card")]
    NoEnd { file: String },
    #[error("{file}: missing keyword {keyword}")]
    MissingKeyword { file: String, keyword: String },
    #[error("{file}: keyword {keyword} = {value}: {reason}")]
    BadKeyword {
        file: String,
        keyword: String,
        value: String,
        reason: String,
    },
    #[error("{file}: unsupported BITPIX = {bitpix} (supported: -32, -64, 16, 32)")]
    UnsupportedBitpix { file: String, bitpix: i64 },
    #[error("{file}: the image is {shape} (NAXIS = {naxis}); a 2-D image is needed")]
    NotTwoDimensional {
        file: String,
        naxis: i64,
        shape: String,
    },
    #[error("{file}: the image is {width} x {height} pixels; lens-model maps must be square")]
    NotSquare {
        file: String,
        width: usize,
        height: usize,
    },
    #[error("{file}: {count} pixels are NaN or infinite (first at column {i}, row {j}, from 0)")]
    NonFinitePixels {
        file: String,
        count: usize,
        i: usize,
        j: usize,
    },
    #[error("{file}: no pixel has data (every pixel is NaN, blank or in a border of zeros)")]
    NoData { file: String },
    #[error("{file}: WCS: {reason}")]
    Wcs { file: String, reason: String },
    #[error("cannot write FITS card {keyword}: {reason}")]
    BadCard { keyword: String, reason: String },
    #[error("cannot write FITS: the map has {len} values for {pixels} x {pixels} pixels of {pixel_arcsec} arcsec")]
    BadMap {
        len: usize,
        pixels: usize,
        pixel_arcsec: f64,
    },
    #[error("cannot write FITS: pixel (column {i}, row {j}) = {value} is not a finite float32")]
    NonFiniteValue { i: usize, j: usize, value: f64 },
}

/// The pixels [`FitsImage::to_map_no_data`] found without data.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct NoDataPixels {
    /// NaN or `BLANK` pixels.
    pub blank: usize,
    /// Zeros in the borders of zeros.
    pub zero_border: usize,
}

impl NoDataPixels {
    /// Every pixel without data.
    pub fn total(&self) -> usize {
        self.blank + self.zero_border
    }
}

/// What goes in the header besides the image and its WCS.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FitsWriteOptions {
    /// Physical unit of the pixel values (`BUNIT`), e.g. `"arcsec"`; omitted when empty.
    pub bunit: String,
    /// Free text, written as `COMMENT` cards (wrapped at 72 characters).
    pub comments: Vec<String>,
    /// Sky position of the frame origin; `None` writes `NOSKYREF = T` and `CRVAL` from (0, 0).
    pub reference: Option<SkyReference>,
    /// More cards, e.g. `Card::real("ZSOURCE", 2.0, "source redshift")`.
    pub extra_cards: Vec<Card>,
}

/// A 2-D image read from a FITS file.
#[derive(Debug, Clone, PartialEq)]
pub struct FitsImage {
    /// The name used in error messages.
    pub source_name: String,
    /// `NAXIS1`: columns.
    pub width: usize,
    /// `NAXIS2`: rows.
    pub height: usize,
    /// Physical values (`BZERO + BSCALE * stored`) in FITS order, `data[j * width + i]`, row 0 at
    /// the bottom; undefined pixels (`BLANK`, NaN) are NaN.
    pub data: Vec<f64>,
    /// Every card of the image's header, in file order (without END).
    pub header: Vec<Card>,
}

/// Writes `map` as a float32 HFF-style FITS file (module docs; [method §7]). The map's
/// centre sits at `CRPIX = n/2 + 0.5`, `CRVAL = reference + centre offset` with the
/// tangent-plane relation of [method §1] ([`SkyReference::offset_to_radec`]). Pixels without
/// data (NaN) are written as NaN, the float images' undefined value; infinite ones are refused.
///
/// [method §7]: crate::method#7-file-formats
/// [method §1]: crate::method#1-frames-and-units
pub fn write_image(map: &Map, opts: &FitsWriteOptions) -> Result<Vec<u8>, FitsError> {
    let g = &map.geometry;
    let n = g.pixels;
    // The pixel in degrees (CDELT) must stay a normal number: a subnormal pixel in arcsec
    // would write CDELT = 0, a file that does not read.
    let pixel_ok = g.pixel_arcsec().is_finite()
        && (g.pixel_arcsec() / 3600.0).is_normal()
        && g.pixel_arcsec() > 0.0
        && g.center.is_finite();
    if n == 0 || map.data.len() != n * n || !pixel_ok {
        let (len, pixel_arcsec) = (map.data.len(), g.pixel_arcsec());
        return Err(FitsError::BadMap {
            len,
            pixels: n,
            pixel_arcsec,
        });
    }
    let pixel_deg = g.pixel_arcsec() / 3600.0;
    let origin = opts.reference.unwrap_or(SkyReference {
        ra_deg: 0.0,
        dec_deg: 0.0,
    });
    let (crval1, crval2) = origin.offset_to_radec(g.center);
    let crpix = n as f64 / 2.0 + 0.5;
    let mut cards = vec![
        Card::logical("SIMPLE", true, "conforms to FITS standard"),
        Card::integer("BITPIX", -32, "IEEE single precision floating point"),
        Card::integer("NAXIS", 2, ""),
        Card::integer("NAXIS1", n as i64, "columns, +x (West)"),
        Card::integer("NAXIS2", n as i64, "rows, +y (North)"),
        Card::logical("EXTEND", true, ""),
    ];
    if !opts.bunit.is_empty() {
        cards.push(Card::text("BUNIT", &opts.bunit, "unit of the pixel values"));
    }
    cards.extend([
        Card::integer("WCSAXES", 2, ""),
        Card::text("CTYPE1", "RA---TAN", "gnomonic projection"),
        Card::text("CTYPE2", "DEC--TAN", "gnomonic projection"),
        Card::text("CUNIT1", "deg", ""),
        Card::text("CUNIT2", "deg", ""),
        Card::real("CRPIX1", crpix, "map centre"),
        Card::real("CRPIX2", crpix, "map centre"),
        Card::real("CRVAL1", crval1, "[deg] RA of the map centre"),
        Card::real("CRVAL2", crval2, "[deg] Dec of the map centre"),
        Card::real("CDELT1", -pixel_deg, "[deg] pixel width, West to the right"),
        Card::real("CDELT2", pixel_deg, "[deg] pixel height"),
        Card::text("RADESYS", "ICRS", ""),
        Card::real("EQUINOX", 2000.0, ""),
    ]);
    match opts.reference {
        Some(r) => cards.extend([
            Card::real("REFRA", r.ra_deg, "[deg] RA of the arcsec frame origin"),
            Card::real("REFDEC", r.dec_deg, "[deg] Dec of the arcsec frame origin"),
        ]),
        None => cards.push(Card::logical(
            "NOSKYREF",
            true,
            "no sky position: CRVAL is a placeholder",
        )),
    }
    for card in &opts.extra_cards {
        if RESERVED.contains(&card.keyword.as_str()) {
            return Err(bad_card(
                &card.keyword,
                "the writer sets this keyword itself".into(),
            ));
        }
        cards.push(card.clone());
    }
    for text in &opts.comments {
        let chars: Vec<char> = text.chars().collect();
        cards.extend(
            chars
                .chunks(72)
                .map(|c| Card::comment(&c.iter().collect::<String>())),
        );
    }
    let mut out = Vec::with_capacity(BLOCK * (2 + (n * n * 4) / BLOCK));
    for card in &cards {
        out.extend_from_slice(
            card.format()
                .map_err(|r| bad_card(&card.keyword, r))?
                .as_bytes(),
        );
    }
    out.extend_from_slice(format!("{:<80}", "END").as_bytes());
    pad_to_block(&mut out, b' ');
    for (k, &v) in map.data.iter().enumerate() {
        let f = v as f32;
        // NaN is a float image's "no data" (FITS 4.0, 5.3); infinities are refused.
        if f.is_infinite() {
            return Err(FitsError::NonFiniteValue {
                i: k % n,
                j: k / n,
                value: v,
            });
        }
        out.extend_from_slice(&f.to_be_bytes());
    }
    pad_to_block(&mut out, 0);
    Ok(out)
}

fn bad_card(keyword: &str, reason: String) -> FitsError {
    FitsError::BadCard {
        keyword: keyword.into(),
        reason,
    }
}

fn pad_to_block(out: &mut Vec<u8>, fill: u8) {
    let rem = out.len() % BLOCK;
    if rem != 0 {
        out.resize(out.len() + BLOCK - rem, fill);
    }
}

impl FitsImage {
    /// The first card with this keyword.
    pub fn card(&self, keyword: &str) -> Option<&Card> {
        self.header.iter().find(|c| c.keyword == keyword)
    }

    /// Number of NaN or infinite pixels.
    pub fn non_finite_count(&self) -> usize {
        self.data.iter().filter(|v| !v.is_finite()).count()
    }

    /// The map geometry and sky reference from the WCS: pixel size from `CDELT1/2` (times a
    /// `PCi_j` matrix) or `CDi_j`, which must be square, unrotated, with `CDELT1 < 0` and
    /// `CDELT2 > 0`; the map centre offset from `CRVAL` is `pixel * (n/2 + 0.5 - CRPIX)`.
    /// The frame origin is `REFRA/REFDEC` if present, none if `NOSKYREF = T`, else `CRVAL`.
    pub fn geometry(&self) -> Result<(MapGeometry, Option<SkyReference>), FitsError> {
        if self.width != self.height {
            let (file, width, height) = (self.source_name.clone(), self.width, self.height);
            return Err(FitsError::NotSquare {
                file,
                width,
                height,
            });
        }
        for (key, want) in [("CTYPE1", "RA---TAN"), ("CTYPE2", "DEC--TAN")] {
            let got = self.text(key)?;
            if got.trim() != want {
                return Err(self.bad(
                    key,
                    &got,
                    &format!("only the {want} projection is supported"),
                ));
            }
        }
        for key in ["CUNIT1", "CUNIT2"] {
            if let Some(unit) = self.card(key).and_then(Card::as_str) {
                if !unit.trim().eq_ignore_ascii_case("deg") {
                    return Err(self.bad(key, unit, "WCS units must be deg"));
                }
            }
        }
        let [m11, m12, m21, m22] = self.linear_matrix()?;
        let scale = m11.abs().max(m22.abs());
        if m12.abs() > 1e-6 * scale || m21.abs() > 1e-6 * scale {
            return Err(self.wcs("the pixel axes are rotated on the sky (off-diagonal CD/PC terms); North must be up".into()));
        }
        if m11 >= 0.0 {
            return Err(self.wcs(format!("CDELT1 = {m11:e} deg is not negative: RA grows to the right (East right); the HFF frame needs CDELT1 < 0")));
        }
        if m22 <= 0.0 {
            return Err(self.wcs(format!(
                "CDELT2 = {m22:e} deg is not positive: North is down"
            )));
        }
        if (m11.abs() - m22).abs() > 1e-6 * m22 {
            return Err(self.wcs(format!(
                "pixels are not square: |CDELT1| = {:e}, CDELT2 = {m22:e} deg",
                m11.abs()
            )));
        }
        let pixel_arcsec = m22 * 3600.0;
        let centre_pix = self.width as f64 / 2.0 + 0.5;
        let shift = DVec2::new(
            centre_pix - self.real("CRPIX1")?,
            centre_pix - self.real("CRPIX2")?,
        ) * pixel_arcsec;
        let (crval1, crval2) = (self.real("CRVAL1")?, self.real("CRVAL2")?);
        let no_ref = matches!(
            self.card("NOSKYREF").and_then(|c| c.value.clone()),
            Some(CardValue::Logical(true))
        );
        let (origin, reference) = if no_ref {
            (
                SkyReference {
                    ra_deg: 0.0,
                    dec_deg: 0.0,
                },
                None,
            )
        } else if self.card("REFRA").is_some() {
            let r = self.sky("REFRA", "REFDEC")?;
            (r, Some(r))
        } else {
            let r = self.sky("CRVAL1", "CRVAL2")?;
            (r, Some(r))
        };
        let center = origin.to_offset_arcsec(crval1, crval2) + shift;
        let geometry = MapGeometry {
            pixels: self.width,
            size_arcsec: pixel_arcsec * self.width as f64,
            center,
        };
        Ok((geometry, reference))
    }

    /// The image as a [`Map`] on [`Self::geometry`]; every pixel must be finite.
    pub fn to_map(&self) -> Result<Map, FitsError> {
        let (geometry, _) = self.geometry()?;
        if let Some(k) = self.data.iter().position(|v| !v.is_finite()) {
            let (file, count) = (self.source_name.clone(), self.non_finite_count());
            return Err(FitsError::NonFinitePixels {
                file,
                count,
                i: k % self.width,
                j: k / self.width,
            });
        }
        Ok(Map {
            geometry,
            data: self.data.clone(),
        })
    }

    /// The image as a [`Map`] in which pixels without data are NaN, as published lens-model
    /// maps have them: NaN or `BLANK` pixels anywhere, and borders of exact zeros (each edge
    /// row or column, from the outside in, that holds only zeros and no-data pixels). Fails on
    /// infinite pixels and on an image with no data at all.
    pub fn to_map_no_data(&self) -> Result<(Map, NoDataPixels), FitsError> {
        let (geometry, _) = self.geometry()?;
        let (w, h) = (self.width, self.height);
        if let Some(k) = self.data.iter().position(|v| v.is_infinite()) {
            return Err(FitsError::NonFinitePixels {
                file: self.source_name.clone(),
                count: self.data.iter().filter(|v| v.is_infinite()).count(),
                i: k % w,
                j: k / w,
            });
        }
        let blank = self.data.iter().filter(|v| v.is_nan()).count();
        let mut data = self.data.clone();
        let empty = |v: f64| v == 0.0 || v.is_nan();
        // The data window [i0, i1) x [j0, j1): edges of zeros and NaN are peeled off.
        let (mut i0, mut i1, mut j0, mut j1) = (0, w, 0, h);
        loop {
            let row = |j: usize, d: &[f64]| (i0..i1).all(|i| empty(d[j * w + i]));
            let col = |i: usize, d: &[f64]| (j0..j1).all(|j| empty(d[j * w + i]));
            if i0 < i1 && j0 < j1 && row(j0, &data) {
                j0 += 1;
            } else if i0 < i1 && j0 < j1 && row(j1 - 1, &data) {
                j1 -= 1;
            } else if i0 < i1 && j0 < j1 && col(i0, &data) {
                i0 += 1;
            } else if i0 < i1 && j0 < j1 && col(i1 - 1, &data) {
                i1 -= 1;
            } else {
                break;
            }
        }
        let mut zero_border = 0;
        for j in 0..h {
            for i in 0..w {
                let v = &mut data[j * w + i];
                if !(i0..i1).contains(&i) || !(j0..j1).contains(&j) {
                    zero_border += usize::from(*v == 0.0);
                    *v = f64::NAN;
                }
            }
        }
        if data.iter().all(|v| v.is_nan()) {
            return Err(FitsError::NoData {
                file: self.source_name.clone(),
            });
        }
        let counts = NoDataPixels { blank, zero_border };
        Ok((Map { geometry, data }, counts))
    }

    /// The image as a [`Map`], NaN / infinite pixels replaced by `fill`; also returns how many
    /// were replaced.
    pub fn to_map_filled(&self, fill: f64) -> Result<(Map, usize), FitsError> {
        let (geometry, _) = self.geometry()?;
        let data = self
            .data
            .iter()
            .map(|&v| if v.is_finite() { v } else { fill })
            .collect();
        Ok((Map { geometry, data }, self.non_finite_count()))
    }

    /// `[m11, m12, m21, m22]` in deg/pixel from `CDi_j`, or `CDELTi * PCi_j`.
    fn linear_matrix(&self) -> Result<[f64; 4], FitsError> {
        let get = |k: &str, default: f64| self.card(k).and_then(Card::as_f64).unwrap_or(default);
        if self.card("CD1_1").is_some() || self.card("CD2_2").is_some() {
            return Ok([
                get("CD1_1", 0.0),
                get("CD1_2", 0.0),
                get("CD2_1", 0.0),
                get("CD2_2", 0.0),
            ]);
        }
        let (c1, c2) = (self.real("CDELT1")?, self.real("CDELT2")?);
        Ok([
            c1 * get("PC1_1", 1.0),
            c1 * get("PC1_2", 0.0),
            c2 * get("PC2_1", 0.0),
            c2 * get("PC2_2", 1.0),
        ])
    }

    fn real(&self, key: &str) -> Result<f64, FitsError> {
        let card = self.card(key).ok_or_else(|| self.missing(key))?;
        card.as_f64()
            .filter(|v| v.is_finite())
            .ok_or_else(|| self.bad(key, &CardValue::shown(card.value.as_ref()), "not a number"))
    }

    fn text(&self, key: &str) -> Result<String, FitsError> {
        let card = self.card(key).ok_or_else(|| self.missing(key))?;
        card.as_str()
            .map(str::to_string)
            .ok_or_else(|| self.bad(key, &CardValue::shown(card.value.as_ref()), "not a string"))
    }

    fn sky(&self, ra_key: &str, dec_key: &str) -> Result<SkyReference, FitsError> {
        let (ra, dec) = (self.real(ra_key)?, self.real(dec_key)?);
        SkyReference::new(ra, dec).ok_or_else(|| {
            self.bad(
                dec_key,
                &dec.to_string(),
                "not a usable sky position (|Dec| >= 90 or RA out of range)",
            )
        })
    }

    fn missing(&self, keyword: &str) -> FitsError {
        FitsError::MissingKeyword {
            file: self.source_name.clone(),
            keyword: keyword.into(),
        }
    }

    fn bad(&self, keyword: &str, value: &str, reason: &str) -> FitsError {
        let file = self.source_name.clone();
        FitsError::BadKeyword {
            file,
            keyword: keyword.into(),
            value: value.into(),
            reason: reason.into(),
        }
    }

    fn wcs(&self, reason: String) -> FitsError {
        FitsError::Wcs {
            file: self.source_name.clone(),
            reason,
        }
    }
}
