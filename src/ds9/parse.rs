//! Parser for DS9 region files: `polygon`, `point`, `circle`, `ellipse`, `box`, `line`,
//! `segment` in `fk5` / `icrs` / `j2000` (degrees or sexagesimal) or `image` / `physical`
//! frames. `text` regions, `global` lines and `#` comments are skipped. Before any frame line
//! DS9 assumes `physical`, taken here as image pixels.

use glam::DVec2;

use super::{Ds9Error, Ds9Frame, Region, Shape};

/// Parses DS9 region text; `source_name` (e.g. the file name) is used in errors, which name the
/// line and the offending token. Positions and lengths are as documented on [`Ds9Frame`].
pub fn read_regions(text: &str, source_name: &str) -> Result<Vec<Region>, Ds9Error> {
    let mut frame = Ds9Frame::Image;
    let mut regions = Vec::new();
    for (k, raw) in text.lines().enumerate() {
        let ctx = Ctx {
            file: source_name,
            line: k + 1,
        };
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let (body, props) = split_outside_braces(line, '#');
        let statements: Vec<&str> = split_all_outside_braces(body, ';');
        let last = statements.len().saturating_sub(1);
        for (s, statement) in statements.iter().enumerate() {
            let statement = statement.trim();
            if statement.is_empty() {
                continue;
            }
            let word = leading_word(statement).to_ascii_lowercase();
            if word == "global" {
                continue;
            }
            if let Some(f) = frame_of(&word, &ctx)? {
                frame = f;
                continue;
            }
            let props = if s == last { props.unwrap_or("") } else { "" };
            if let Some(region) = parse_shape(statement, props, frame, &ctx)? {
                regions.push(region);
            }
        }
    }
    Ok(regions)
}

struct Ctx<'a> {
    file: &'a str,
    line: usize,
}

impl Ctx<'_> {
    fn syntax(&self, token: &str, reason: &str) -> Ds9Error {
        Ds9Error::Syntax {
            file: self.file.into(),
            line: self.line,
            token: token.into(),
            reason: reason.into(),
        }
    }
}

fn leading_word(s: &str) -> &str {
    let s = s.trim_start_matches(['+', '-']);
    let end = s
        .find(|c: char| !c.is_ascii_alphanumeric())
        .unwrap_or(s.len());
    &s[..end]
}

/// `Some(frame)` for a coordinate-system statement, an error for unsupported systems.
fn frame_of(word: &str, ctx: &Ctx) -> Result<Option<Ds9Frame>, Ds9Error> {
    match word {
        "fk5" | "icrs" | "j2000" => Ok(Some(Ds9Frame::Fk5)),
        "image" | "physical" => Ok(Some(Ds9Frame::Image)),
        "fk4" | "b1950" | "galactic" | "ecliptic" | "linear" | "amplifier" | "detector"
        | "tile" => Err(Ds9Error::UnsupportedFrame {
            file: ctx.file.into(),
            line: ctx.line,
            frame: word.into(),
        }),
        w if w.starts_with("wcs") => Err(Ds9Error::UnsupportedFrame {
            file: ctx.file.into(),
            line: ctx.line,
            frame: word.into(),
        }),
        _ => Ok(None),
    }
}

/// Splits at the first `sep` outside `{}` (quotes are not special: `"` and `'` are also the
/// arcsec and arcmin units of lengths).
fn split_outside_braces(s: &str, sep: char) -> (&str, Option<&str>) {
    let mut depth = 0i32;
    for (k, c) in s.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            c if c == sep && depth <= 0 => return (&s[..k], Some(&s[k + 1..])),
            _ => {}
        }
    }
    (s, None)
}

fn split_all_outside_braces(mut s: &str, sep: char) -> Vec<&str> {
    let mut parts = Vec::new();
    loop {
        let (head, tail) = split_outside_braces(s, sep);
        parts.push(head);
        match tail {
            Some(t) => s = t,
            None => return parts,
        }
    }
}

/// The value of `key={...}`, `key="..."`, `key='...'` or `key=word` in a property list.
/// The list is read pair by pair, so a key written inside another property's value
/// (`text={tag=1} tag={x}`) is not taken for the property itself.
fn property<'a>(props: &'a str, key: &str) -> Option<&'a str> {
    let mut rest = props.trim_start();
    while !rest.is_empty() {
        let name_end = rest.find(['=', ' ', '\t']).unwrap_or(rest.len());
        let name = &rest[..name_end];
        let after = rest[name_end..].trim_start();
        let Some(v) = after.strip_prefix('=') else {
            // A word without a value (`source`, `background`): skip it. `name` is not
            // empty here (a list starting with `=` has a value), so this moves on.
            rest = after;
            continue;
        };
        let v = v.trim_start();
        // `None`: an unclosed brace or quote, or no value at all.
        let parsed = match v.chars().next() {
            Some(open @ ('{' | '"' | '\'')) => {
                let close = if open == '{' { '}' } else { open };
                v[1..].find(close).map(|e| (&v[1..1 + e], &v[2 + e..]))
            }
            _ => {
                let e = v.find([' ', '\t']).unwrap_or(v.len());
                (e > 0).then(|| (&v[..e], &v[e..]))
            }
        };
        let (value, tail) = parsed?;
        if name == key {
            return Some(value);
        }
        rest = tail.trim_start();
    }
    None
}

fn parse_shape(
    statement: &str,
    props: &str,
    frame: Ds9Frame,
    ctx: &Ctx,
) -> Result<Option<Region>, Ds9Error> {
    let include = !statement.starts_with('-');
    let s = statement.trim_start_matches(['+', '-']).trim_start();
    let name = leading_word(s).to_ascii_lowercase();
    let mut rest = s[name.len()..].trim();
    let mut shape_name = name.as_str();
    // Legacy point syntax: `circle point x y`.
    if leading_word(rest).eq_ignore_ascii_case("point") {
        shape_name = "point";
        rest = rest[5..].trim();
    }
    if shape_name == "text" {
        return Ok(None);
    }
    let args_text = match rest.strip_prefix('(') {
        Some(r) => r
            .split_once(')')
            .map(|(a, _)| a)
            .ok_or_else(|| ctx.syntax(statement, "missing `)`"))?,
        None => rest,
    };
    let args: Vec<&str> = args_text
        .split([',', ' ', '\t'])
        .filter(|t| !t.is_empty())
        .collect();
    let coords = Coords { frame, ctx };
    let shape = match shape_name {
        "polygon" | "segment" | "line" => {
            if args.len() < 4 || args.len() % 2 != 0 {
                return Err(ctx.syntax(
                    args_text,
                    "needs an even number of coordinates, at least 2 points",
                ));
            }
            let pts = args
                .chunks(2)
                .map(|c| coords.point(c[0], c[1]))
                .collect::<Result<Vec<_>, _>>()?;
            if shape_name == "polygon" {
                if pts.len() < 3 {
                    return Err(ctx.syntax(args_text, "a polygon needs at least 3 points"));
                }
                Shape::Polygon(pts)
            } else {
                Shape::Polyline(pts)
            }
        }
        "point" => {
            coords.count(&args, 2, args_text)?;
            Shape::Point(coords.point(args[0], args[1])?)
        }
        "circle" => {
            coords.count(&args, 3, args_text)?;
            Shape::Circle {
                center: coords.point(args[0], args[1])?,
                radius: coords.length(args[2])?,
            }
        }
        "ellipse" | "box" => {
            if args.len() != 4 && args.len() != 5 {
                return Err(ctx.syntax(args_text, "needs x, y, two sizes and an optional angle"));
            }
            let center = coords.point(args[0], args[1])?;
            let size = DVec2::new(coords.length(args[2])?, coords.length(args[3])?);
            let angle_deg = args.get(4).map_or(Ok(0.0), |a| number(a, ctx))?;
            if shape_name == "box" {
                Shape::Box {
                    center,
                    size,
                    angle_deg,
                }
            } else {
                Shape::Ellipse {
                    center,
                    radii: size,
                    angle_deg,
                }
            }
        }
        _ => {
            // A row that starts with a number is a catalogue's (`1.1 342.18 -44.53 ...`).
            let hint = match name.parse::<f64>() {
                Ok(_) => {
                    "; this line reads as a Lenstool catalogue row (id x y a b theta z): give \
                     the catalogue with --images (in the app, as the image catalogue)"
                }
                Err(_) => "",
            };
            let e = Ds9Error::UnsupportedShape {
                file: ctx.file.into(),
                line: ctx.line,
                shape: name.clone(),
                hint,
            };
            return Err(e);
        }
    };
    let text = property(props, "text").map(str::to_string);
    let color = property(props, "color").map(str::to_string);
    Ok(Some(Region {
        frame,
        shape,
        text,
        color,
        include,
        line: ctx.line,
    }))
}

fn number(token: &str, ctx: &Ctx) -> Result<f64, Ds9Error> {
    token
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| ctx.syntax(token, "not a number"))
}

struct Coords<'a> {
    frame: Ds9Frame,
    ctx: &'a Ctx<'a>,
}

impl Coords<'_> {
    fn count(&self, args: &[&str], n: usize, text: &str) -> Result<(), Ds9Error> {
        if args.len() == n {
            return Ok(());
        }
        Err(self
            .ctx
            .syntax(text, &format!("expected {n} values, found {}", args.len())))
    }

    /// (RA, Dec) in degrees for fk5, 1-based pixels for image.
    fn point(&self, a: &str, b: &str) -> Result<DVec2, Ds9Error> {
        match self.frame {
            Ds9Frame::Image => Ok(DVec2::new(number(a, self.ctx)?, number(b, self.ctx)?)),
            Ds9Frame::Fk5 => {
                let ra = sky_angle_deg(a, true)
                    .ok_or_else(|| self.ctx.syntax(a, "not a right ascension"))?;
                let dec = sky_angle_deg(b, false)
                    .ok_or_else(|| self.ctx.syntax(b, "not a declination"))?;
                if !(-90.0..=90.0).contains(&dec) {
                    return Err(self.ctx.syntax(b, "declination outside [-90, 90] degrees"));
                }
                Ok(DVec2::new(ra.rem_euclid(360.0), dec))
            }
        }
    }

    /// Arcsec for fk5 (bare numbers are degrees), pixels for image.
    fn length(&self, token: &str) -> Result<f64, Ds9Error> {
        let (num, unit) = match token.char_indices().last() {
            Some((k, c)) if c.is_ascii_alphabetic() || c == '"' || c == '\'' => {
                (&token[..k], Some(c))
            }
            _ => (token, None),
        };
        let v = number(num, self.ctx).map_err(|_| self.ctx.syntax(token, "not a length"))?;
        let factor = match (self.frame, unit) {
            (Ds9Frame::Fk5, None | Some('d')) => 3600.0,
            (Ds9Frame::Fk5, Some('\'')) => 60.0,
            (Ds9Frame::Fk5, Some('"')) => 1.0,
            (Ds9Frame::Fk5, Some('r')) => 180.0 / std::f64::consts::PI * 3600.0,
            (Ds9Frame::Image, None | Some('i' | 'p')) => 1.0,
            _ => {
                return Err(self
                    .ctx
                    .syntax(token, "length unit not usable in this coordinate system"))
            }
        };
        if v < 0.0 {
            return Err(self.ctx.syntax(token, "negative length"));
        }
        Ok(v * factor)
    }
}

/// Degrees from `12.5`, `12.5d`, `12:30:00` / `12h30m00s` (hours when `is_ra`) or
/// `-00:30:00` / `-0d30m00s` (degrees).
fn sky_angle_deg(token: &str, is_ra: bool) -> Option<f64> {
    let t = token.trim();
    let negative = t.starts_with('-');
    let parts: Vec<&str>;
    let hours = if t.contains(':') {
        parts = t.split(':').collect();
        is_ra
    } else if t.contains('h') || (t.contains('d') && t.contains(['m', 's'])) {
        parts = t
            .split(['h', 'd', 'm', 's'])
            .filter(|p| !p.is_empty())
            .collect();
        t.contains('h')
    } else {
        let v: f64 = t.strip_suffix('d').unwrap_or(t).parse().ok()?;
        return v.is_finite().then_some(v);
    };
    if parts.is_empty() || parts.len() > 3 {
        return None;
    }
    let mut total = 0.0;
    for (k, p) in parts.iter().enumerate() {
        let v: f64 = p.trim_start_matches(['+', '-']).parse().ok()?;
        if !v.is_finite() || (k > 0 && !(0.0..60.0).contains(&v)) {
            return None;
        }
        total += v / 60f64.powi(k as i32);
    }
    let total = if negative { -total } else { total };
    Some(if hours { total * 15.0 } else { total })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sexagesimal_angles() {
        assert_eq!(sky_angle_deg("12:30:00", true), Some(187.5));
        assert_eq!(sky_angle_deg("-00:30:00", false), Some(-0.5));
        assert_eq!(sky_angle_deg("12h30m00s", true), Some(187.5));
        assert_eq!(sky_angle_deg("-0d30m00s", false), Some(-0.5));
        assert_eq!(sky_angle_deg("197.87d", true), Some(197.87));
        assert_eq!(sky_angle_deg("1:70:00", false), None);
    }

    #[test]
    fn properties_in_braces_and_quotes() {
        let p = " color=red text={a # b} tag={x}";
        assert_eq!(property(p, "text"), Some("a # b"));
        assert_eq!(property(p, "color"), Some("red"));
        assert_eq!(property(p, "width"), None);
        // A key inside another property's value is not the property.
        let p = "text={tag=1 color=blue} tag={x} color=red";
        assert_eq!(property(p, "tag"), Some("x"));
        assert_eq!(property(p, "color"), Some("red"));
        assert_eq!(property(p, "text"), Some("tag=1 color=blue"));
        assert_eq!(
            property("text='z = 2' color = green", "color"),
            Some("green")
        );
        assert_eq!(
            property("text='z = 2' color = green", "text"),
            Some("z = 2")
        );
        // Unclosed values and a bare key give nothing; an empty value is empty.
        assert_eq!(property("text={open", "text"), None);
        assert_eq!(property("text=", "text"), None);
        assert_eq!(property("text={}", "text"), Some(""));
        assert_eq!(property("source background", "source"), None);
        assert_eq!(property("colour=red", "color"), None);
    }
}
