//! Text of the figures: DejaVu Sans (cut to the characters figures use, `fonts/`) rasterised
//! with antialiasing by `ab_glyph` and blended into tiny-skia pixmaps.
//!
//! Sizes are given as a text scale `s`: the cap height is [`CAP`]` * s` pixels, so layouts
//! written in font units keep their proportions at any size. `_{...}` and `^{...}` in a text
//! set their contents as a subscript or superscript (`z_{s}`, `log_{10}`, `M_{⊙}`); other
//! characters are drawn as they are, unknown ones as the font's empty box.

use std::sync::OnceLock;

use ab_glyph::{point, Font, FontRef, GlyphId, PxScale, ScaleFont};
use tiny_skia::{Color, Pixmap};

/// Cap height in font units (one unit = `s` pixels at text scale `s`).
pub const CAP: f32 = 7.0;
/// About one digit's advance in font units (DejaVu Sans digits: 0.87 cap heights).
pub const ADVANCE: f32 = 6.0;
/// Size of sub- and superscripts relative to the text.
const SCRIPT_SIZE: f32 = 0.7;
/// How far a subscript's baseline drops, in cap heights of the text.
const SUB_DROP: f32 = 0.3;
/// How far a superscript's baseline rises, in cap heights of the text.
const SUP_RISE: f32 = 0.5;

/// The embedded font: DejaVu Sans 2.37, subset by `fonts/subset.sh` (licence beside it).
static FONT_BYTES: &[u8] = include_bytes!("fonts/DejaVuSans-figures.ttf");

struct Face {
    font: FontRef<'static>,
    /// Cap height ('H') over the font's `ascent - descent` (what [`PxScale`] measures).
    cap_per_height: f32,
}

fn face() -> &'static Face {
    static FACE: OnceLock<Face> = OnceLock::new();
    FACE.get_or_init(|| {
        // The bytes are compiled in and checked by the tests: parsing cannot fail at run time.
        let font = FontRef::try_from_slice(FONT_BYTES).expect("the embedded font parses");
        // ab_glyph's outline bounds keep the top of the glyph in `min.y` (font units, +y up).
        let cap = font
            .outline(font.glyph_id('H'))
            .map_or(0.7 * font.height_unscaled(), |o| {
                o.bounds.min.y.max(o.bounds.max.y)
            });
        Face {
            cap_per_height: cap / font.height_unscaled(),
            font,
        }
    })
}

/// Vertical place of a piece of text.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Level {
    Normal,
    Sub,
    Sup,
}

/// `text` cut into runs at `_{...}` and `^{...}` (an unclosed brace is plain text).
fn runs(text: &str) -> Vec<(Level, &str)> {
    let mut out = Vec::new();
    let mut rest = text;
    while !rest.is_empty() {
        let next = ["_{", "^{"]
            .iter()
            .filter_map(|m| rest.find(m).map(|k| (k, *m)))
            .filter(|&(k, _)| rest[k + 2..].contains('}'))
            .min_by_key(|&(k, _)| k);
        let Some((k, mark)) = next else {
            out.push((Level::Normal, rest));
            break;
        };
        if k > 0 {
            out.push((Level::Normal, &rest[..k]));
        }
        let inner = &rest[k + 2..];
        let end = inner.find('}').unwrap_or(inner.len());
        let level = if mark == "_{" { Level::Sub } else { Level::Sup };
        out.push((level, &inner[..end]));
        rest = &inner[(end + 1).min(inner.len())..];
    }
    out
}

/// One glyph placed on the text's line: its id, size, pen position from the start and
/// baseline offset (pixels, +y down).
struct Placed {
    id: GlyphId,
    scale: PxScale,
    x: f32,
    dy: f32,
}

/// The glyphs of `text` at scale `s` and the text's width (sum of advances and kerning).
fn layout(text: &str, s: f32) -> (Vec<Placed>, f32) {
    let f = face();
    let cap = CAP * s;
    let mut out = Vec::new();
    let mut x = 0.0;
    let mut prev: Option<(GlyphId, PxScale)> = None;
    for (level, part) in runs(text) {
        let (size, dy) = match level {
            Level::Normal => (cap, 0.0),
            Level::Sub => (SCRIPT_SIZE * cap, SUB_DROP * cap),
            Level::Sup => (SCRIPT_SIZE * cap, -SUP_RISE * cap),
        };
        let scale = PxScale::from(size / f.cap_per_height);
        let sf = f.font.as_scaled(scale);
        for c in part.chars() {
            let id = f.font.glyph_id(c);
            if let Some((p, ps)) = prev {
                if ps == scale {
                    x += sf.kern(p, id);
                }
            }
            out.push(Placed { id, scale, x, dy });
            x += sf.h_advance(id);
            prev = Some((id, scale));
        }
    }
    (out, x)
}

/// Width in pixels of `text` at text scale `s`.
pub fn text_width(text: &str, s: f32) -> f32 {
    layout(text, s).1
}

/// `text` shortened with "…" to at most `max_px` pixels wide at scale `s` (empty when not
/// even one character and the ellipsis fit).
pub(crate) fn fit(text: &str, max_px: f32, s: f32) -> String {
    if text_width(text, s) <= max_px {
        return text.to_string();
    }
    let mut out = String::new();
    for c in text.chars() {
        let next = format!("{out}{c}…");
        if text_width(&next, s) > max_px {
            break;
        }
        out.push(c);
    }
    if out.is_empty() {
        String::new()
    } else {
        out + "…"
    }
}

/// A number's label as figures print it: a leading or exponent hyphen becomes the minus
/// sign U+2212, as in typeset numbers ("-0.5" -> "−0.5", "1e-6" -> "1e−6").
pub(crate) fn minus_signs(label: &str) -> String {
    label.replace('-', "\u{2212}")
}

/// Where `(x, y)` sits on the text's box (cap height, no descenders).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Anchor {
    TopCenter,
    MiddleLeft,
    MiddleRight,
}

/// Coverage (0 to 1) of a text drawn left to right, `w` x `h` pixels, row-major.
struct Coverage {
    w: usize,
    h: usize,
    data: Vec<f32>,
}

/// Rasterises `text` with its first pen position at `(ox, baseline)` of a fresh coverage
/// buffer (fractional positions keep the glyphs' sub-pixel placement).
fn rasterise(placed: &[Placed], width: f32, s: f32, ox: f32) -> (Coverage, f32) {
    let f = face();
    let cap = CAP * s;
    // Room above the cap height (accents, superscripts) and below (descenders, subscripts).
    let (above, below) = ((0.9 * cap).ceil() + 1.0, (0.7 * cap).ceil() + 1.0);
    let baseline = cap + above;
    let (w, h) = (
        (ox + width + cap).ceil() as usize + 2,
        (baseline + below).ceil() as usize,
    );
    let mut cov = Coverage {
        w,
        h,
        data: vec![0.0; w * h],
    };
    for p in placed {
        let glyph =
            p.id.with_scale_and_position(p.scale, point(ox + p.x, baseline + p.dy));
        let Some(g) = f.font.outline_glyph(glyph) else {
            continue;
        };
        let b = g.px_bounds();
        g.draw(|gx, gy, c| {
            let (x, y) = (b.min.x as i64 + gx as i64, b.min.y as i64 + gy as i64);
            if (0..w as i64).contains(&x) && (0..h as i64).contains(&y) {
                let v = &mut cov.data[y as usize * w + x as usize];
                *v = (*v + c).min(1.0);
            }
        });
    }
    (cov, baseline)
}

/// Blends `color` into pixel `(x, y)` of `pm` with coverage `c` (source over, premultiplied).
fn blend(pm: &mut Pixmap, (x, y): (i64, i64), color: Color, c: f32) {
    let (w, h) = (pm.width() as i64, pm.height() as i64);
    if c <= 0.0 || !(0..w).contains(&x) || !(0..h).contains(&y) {
        return;
    }
    let a = color.alpha() * c;
    let k = (y * w + x) as usize * 4;
    let px = &mut pm.data_mut()[k..k + 4];
    let src = [color.red(), color.green(), color.blue(), 1.0];
    for (d, s) in px.iter_mut().zip(src) {
        let v = s * a * 255.0 + *d as f32 * (1.0 - a);
        *d = v.round().clamp(0.0, 255.0) as u8;
    }
}

/// Draws `text` with its `anchor` point at `(x, y)` pixels, text scale `s` (cap height
/// [`CAP`]` * s` pixels); `upright = false` rotates it by 90 degrees counter-clockwise
/// (reading bottom to top, for vertical axis titles).
pub fn draw_text(
    pm: &mut Pixmap,
    text: &str,
    (x, y): (f32, f32),
    s: f32,
    color: Color,
    anchor: Anchor,
    upright: bool,
) {
    let (placed, w) = layout(text, s);
    if placed.is_empty() {
        return;
    }
    let cap = CAP * s;
    // The anchor's offset from the text's start on its baseline, along and across the line.
    let (along, across) = match anchor {
        Anchor::TopCenter => (-w / 2.0, cap),
        Anchor::MiddleLeft => (0.0, cap / 2.0),
        Anchor::MiddleRight => (-w, cap / 2.0),
    };
    // Where the text's start on its baseline falls on the pixmap.
    let (sx, sy) = if upright {
        (x + along, y + across)
    } else {
        (x + across, y - along)
    };
    // The pen starts at the fractional part of its pixmap position along the line, so that
    // buffer pixels are pixmap pixels.
    let along_px = if upright { sx } else { -sy };
    let ox = along_px - along_px.floor() + 1.0;
    let (cov, baseline) = rasterise(&placed, w, s, ox);
    let across_px = if upright { sy } else { sx };
    let shift = across_px - baseline;
    // A fractional baseline is rounded: text reads better sitting on whole pixels.
    let (start, shift) = (along_px.floor() as i64 - 1, shift.round() as i64);
    for by in 0..cov.h {
        for bx in 0..cov.w {
            let c = cov.data[by * cov.w + bx];
            if c <= 0.0 {
                continue;
            }
            let (along_i, across_i) = (start + bx as i64, shift + by as i64);
            let at = if upright {
                (along_i, across_i)
            } else {
                // Along the line is up the pixmap: local pixel i covers rows -(i + 1) to -i.
                (across_i, -along_i - 1)
            };
            blend(pm, at, color, c);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markup_makes_scripts_and_leaves_the_rest() {
        assert_eq!(
            runs("z_{s} = 2"),
            [
                (Level::Normal, "z"),
                (Level::Sub, "s"),
                (Level::Normal, " = 2")
            ]
        );
        assert_eq!(
            runs("10^{14} M"),
            [
                (Level::Normal, "10"),
                (Level::Sup, "14"),
                (Level::Normal, " M")
            ]
        );
        assert_eq!(runs("model_v2.json"), [(Level::Normal, "model_v2.json")]);
        assert_eq!(runs("a_{b"), [(Level::Normal, "a_{b")]);
        assert_eq!(minus_signs("-0.5"), "\u{2212}0.5");
        assert_eq!(minus_signs("1e-6"), "1e\u{2212}6");
    }

    #[test]
    fn the_font_has_the_figures_characters() {
        let f = &face().font;
        for c in "κγθαβΣμΔ″′°±×−≤≥⊙☉·…éü₀₁ₛ⁰¹²ABCxyz0123456789[]()".chars()
        {
            assert_ne!(f.glyph_id(c), GlyphId(0), "{c} missing");
        }
        let cap = face().cap_per_height;
        assert!((0.55..0.7).contains(&cap), "{cap}");
    }

    #[test]
    fn width_scales_with_the_size_and_kerning_applies() {
        let (a, b) = (text_width("x [arcsec]", 1.0), text_width("x [arcsec]", 2.0));
        assert!((b - 2.0 * a).abs() < 1e-3, "{a} {b}");
        // "AV" is kerned tighter than "AA" is wide.
        assert!(text_width("AV", 2.0) < text_width("AA", 2.0));
        assert_eq!(
            fit("a long legend label", 30.0, 1.0).chars().last(),
            Some('…')
        );
        assert!(text_width(&fit("a long legend label", 30.0, 1.0), 1.0) <= 30.0);
    }
}
