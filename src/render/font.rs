//! A small built-in bitmap font: 5 x 9 cells (cap height 7, two descender rows), each lit cell
//! drawn as a `scale` x `scale` square, so text stays crisp and rendering deterministic.

use tiny_skia::{Color, Paint, Pixmap, Rect, Transform};

/// Cap height in font units (one unit = `scale` pixels).
pub const CAP: u32 = 7;
/// Horizontal advance per character in font units (5 wide plus 1 of spacing).
pub const ADVANCE: u32 = 6;

/// Glyph rows, top to bottom, `#` lit; missing rows are blank.
const GLYPHS: &[(char, &str)] = &[
    (' ', ""),
    ('0', ".###. #...# #..## #.#.# ##..# #...# .###."),
    ('1', "..#.. .##.. ..#.. ..#.. ..#.. ..#.. .###."),
    ('2', ".###. #...# ....# ...#. ..#.. .#... #####"),
    ('3', ".###. #...# ....# ..##. ....# #...# .###."),
    ('4', "...#. ..##. .#.#. #..#. ##### ...#. ...#."),
    ('5', "##### #.... ####. ....# ....# #...# .###."),
    ('6', "..##. .#... #.... ####. #...# #...# .###."),
    ('7', "##### ....# ...#. ..#.. .#... .#... .#..."),
    ('8', ".###. #...# #...# .###. #...# #...# .###."),
    ('9', ".###. #...# #...# .#### ....# ...#. .##.."),
    ('A', ".###. #...# #...# ##### #...# #...# #...#"),
    ('B', "####. #...# #...# ####. #...# #...# ####."),
    ('C', ".###. #...# #.... #.... #.... #...# .###."),
    ('D', "####. #...# #...# #...# #...# #...# ####."),
    ('E', "##### #.... #.... ####. #.... #.... #####"),
    ('F', "##### #.... #.... ####. #.... #.... #...."),
    ('G', ".###. #...# #.... #.### #...# #...# .####"),
    ('H', "#...# #...# #...# ##### #...# #...# #...#"),
    ('I', ".###. ..#.. ..#.. ..#.. ..#.. ..#.. .###."),
    ('J', "..### ...#. ...#. ...#. ...#. #..#. .##.."),
    ('K', "#...# #..#. #.#.. ##... #.#.. #..#. #...#"),
    ('L', "#.... #.... #.... #.... #.... #.... #####"),
    ('M', "#...# ##.## #.#.# #.#.# #...# #...# #...#"),
    ('N', "#...# #...# ##..# #.#.# #..## #...# #...#"),
    ('O', ".###. #...# #...# #...# #...# #...# .###."),
    ('P', "####. #...# #...# ####. #.... #.... #...."),
    ('Q', ".###. #...# #...# #...# #.#.# #..#. .##.#"),
    ('R', "####. #...# #...# ####. #.#.. #..#. #...#"),
    ('S', ".#### #.... #.... .###. ....# ....# ####."),
    ('T', "##### ..#.. ..#.. ..#.. ..#.. ..#.. ..#.."),
    ('U', "#...# #...# #...# #...# #...# #...# .###."),
    ('V', "#...# #...# #...# #...# #...# .#.#. ..#.."),
    ('W', "#...# #...# #...# #.#.# #.#.# #.#.# .#.#."),
    ('X', "#...# #...# .#.#. ..#.. .#.#. #...# #...#"),
    ('Y', "#...# #...# .#.#. ..#.. ..#.. ..#.. ..#.."),
    ('Z', "##### ....# ...#. ..#.. .#... #.... #####"),
    ('a', "..... ..... .###. ....# .#### #...# .####"),
    ('b', "#.... #.... ####. #...# #...# #...# ####."),
    ('c', "..... ..... .###. #.... #.... #...# .###."),
    ('d', "....# ....# .#### #...# #...# #...# .####"),
    ('e', "..... ..... .###. #...# ##### #.... .###."),
    ('f', "..##. .#..# .#... ###.. .#... .#... .#..."),
    ('g', "..... ..... .#### #...# #...# #...# .#### ....# .###."),
    ('h', "#.... #.... #.##. ##..# #...# #...# #...#"),
    ('i', "..#.. ..... .##.. ..#.. ..#.. ..#.. .###."),
    ('j', "...#. ..... ..##. ...#. ...#. ...#. ...#. #..#. .##.."),
    ('k', "#.... #.... #..#. #.#.. ##... #.#.. #..#."),
    ('l', ".##.. ..#.. ..#.. ..#.. ..#.. ..#.. .###."),
    ('m', "..... ..... ##.#. #.#.# #.#.# #.#.# #.#.#"),
    ('n', "..... ..... #.##. ##..# #...# #...# #...#"),
    ('o', "..... ..... .###. #...# #...# #...# .###."),
    ('p', "..... ..... ####. #...# #...# #...# ####. #.... #...."),
    ('q', "..... ..... .#### #...# #...# #...# .#### ....# ....#"),
    ('r', "..... ..... #.##. ##..# #.... #.... #...."),
    ('s', "..... ..... .#### #.... .###. ....# ####."),
    ('t', ".#... .#... ###.. .#... .#... .#..# ..##."),
    ('u', "..... ..... #...# #...# #...# #..## .##.#"),
    ('v', "..... ..... #...# #...# #...# .#.#. ..#.."),
    ('w', "..... ..... #...# #...# #.#.# #.#.# .#.#."),
    ('x', "..... ..... #...# .#.#. ..#.. .#.#. #...#"),
    ('y', "..... ..... #...# #...# #...# #...# .#### ....# .###."),
    ('z', "..... ..... ##### ...#. ..#.. .#... #####"),
    ('κ', "..... ..... #..#. #.#.. ##... #.#.. #..#."),
    ('μ', "..... ..... #...# #...# #...# ##..# #.##. #.... #...."),
    ('.', "..... ..... ..... ..... ..... .##.. .##.."),
    (',', "..... ..... ..... ..... ..... .##.. .##.. ..#.. .#..."),
    ('-', "..... ..... ..... .###. ..... ..... ....."),
    ('+', "..... ..#.. ..#.. ##### ..#.. ..#.. ....."),
    ('"', ".#.#. .#.#. .#.#."),
    ('\'', "..#.. ..#.. ..#.."),
    (':', "..... .##.. .##.. ..... .##.. .##.. ....."),
    (';', "..... .##.. .##.. ..... .##.. .##.. ..#.. .#..."),
    ('/', "....# ....# ...#. ..#.. .#... #.... #...."),
    ('=', "..... ..... ##### ..... ##### ..... ....."),
    ('(', "...#. ..#.. .#... .#... .#... ..#.. ...#."),
    (')', ".#... ..#.. ...#. ...#. ...#. ..#.. .#..."),
    ('[', ".###. .#... .#... .#... .#... .#... .###."),
    (']', ".###. ...#. ...#. ...#. ...#. ...#. .###."),
    ('_', "..... ..... ..... ..... ..... ..... #####"),
    ('%', "##... ##..# ...#. ..#.. .#... #..## ...##"),
    ('<', "...#. ..#.. .#... #.... .#... ..#.. ...#."),
    ('>', ".#... ..#.. ...#. ....# ...#. ..#.. .#..."),
    ('^', "..#.. .#.#. #...#"),
    ('*', "..... ..#.. #.#.# .###. #.#.# ..#.. ....."),
    ('!', "..#.. ..#.. ..#.. ..#.. ..#.. ..... ..#.."),
    ('|', "..#.. ..#.. ..#.. ..#.. ..#.. ..#.. ..#.."),
    ('?', ".###. #...# ....# ...#. ..#.. ..... ..#.."),
];

/// `text` shortened with "..." to at most `max_px` pixels wide at scale `s` (empty when not
/// even one character and the dots fit).
pub(crate) fn fit(text: &str, max_px: f32, s: u32) -> String {
    if text_width(text, s) <= max_px {
        return text.to_string();
    }
    let mut out: String = String::new();
    for c in text.chars() {
        let next = format!("{out}{c}...");
        if text_width(&next, s) > max_px {
            break;
        }
        out.push(c);
    }
    if out.is_empty() {
        String::new()
    } else {
        out + "..."
    }
}

/// Rows of the glyph for `c`; unknown characters are drawn as `?`.
fn glyph(c: char) -> &'static str {
    GLYPHS
        .iter()
        .find(|(g, _)| *g == c)
        .or_else(|| GLYPHS.iter().find(|(g, _)| *g == '?'))
        .map_or("", |(_, rows)| rows)
}

/// Width in pixels of `text` at `scale` (no trailing spacing).
pub fn text_width(text: &str, scale: u32) -> f32 {
    let n = text.chars().count() as u32;
    (n * ADVANCE).saturating_sub(1) as f32 * scale as f32
}

/// Where `(x, y)` sits on the text's box (cap height, no descenders).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Anchor {
    TopCenter,
    MiddleLeft,
    MiddleRight,
}

/// Draws `text` with its `anchor` point at `(x, y)` pixels; `upright = false` rotates it by
/// 90 degrees counter-clockwise (reading bottom to top, for vertical axis titles).
pub fn draw_text(
    pixmap: &mut Pixmap,
    text: &str,
    (x, y): (f32, f32),
    scale: u32,
    color: Color,
    anchor: Anchor,
    upright: bool,
) {
    let s = scale as f32;
    let (w, h) = (text_width(text, scale), CAP as f32 * s);
    let (dx, dy) = match anchor {
        Anchor::TopCenter => (-w / 2.0, 0.0),
        Anchor::MiddleLeft => (0.0, -h / 2.0),
        Anchor::MiddleRight => (-w, -h / 2.0),
    };
    let (dx, dy) = (dx.round(), dy.round());
    let (x, y) = (x.round(), y.round());
    let transform = if upright {
        Transform::from_translate(x, y)
    } else {
        Transform::from_row(0.0, -1.0, 1.0, 0.0, x, y)
    };
    let mut paint = Paint::default();
    paint.set_color(color);
    paint.anti_alias = false;
    for (k, c) in text.chars().enumerate() {
        let left = dx + (k as u32 * ADVANCE) as f32 * s;
        for (row, bits) in glyph(c).split(' ').enumerate() {
            let top = dy + row as f32 * s;
            // Runs of lit cells become one rectangle.
            let mut col = 0;
            let bytes = bits.as_bytes();
            while col < bytes.len() {
                if bytes[col] != b'#' {
                    col += 1;
                    continue;
                }
                let start = col;
                while col < bytes.len() && bytes[col] == b'#' {
                    col += 1;
                }
                let run = (col - start) as f32 * s;
                if let Some(r) = Rect::from_xywh(left + start as f32 * s, top, run, s) {
                    pixmap.fill_rect(r, &paint, transform, None);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glyphs_are_well_formed() {
        for (c, rows) in GLYPHS {
            let rows: Vec<&str> = if rows.is_empty() {
                vec![]
            } else {
                rows.split(' ').collect()
            };
            assert!(rows.len() <= 9, "{c}: {} rows", rows.len());
            for r in rows {
                assert!(
                    r.len() == 5 && r.bytes().all(|b| b == b'#' || b == b'.'),
                    "{c}: {r}"
                );
            }
        }
        assert_eq!(glyph('€'), glyph('?'));
    }
}
