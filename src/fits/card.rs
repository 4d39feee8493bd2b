//! FITS header cards: 80 ASCII characters, `KEYWORD = value / comment` (FITS 4.0, section 4).

/// The value of a header card.
#[derive(Debug, Clone, PartialEq)]
pub enum CardValue {
    Logical(bool),
    Integer(i64),
    Real(f64),
    Text(String),
    /// A value this reader does not interpret (complex numbers, malformed text), kept verbatim.
    Unparsed(String),
}

impl CardValue {
    /// The value as a FITS header writes it (`T`, `42`, `0.5`, `'TEXT'`), for messages;
    /// "no value" for a card without one.
    pub fn shown(value: Option<&CardValue>) -> String {
        match value {
            None => "no value".to_string(),
            Some(CardValue::Logical(b)) => if *b { "T" } else { "F" }.to_string(),
            Some(CardValue::Integer(v)) => v.to_string(),
            Some(CardValue::Real(v)) => v.to_string(),
            Some(CardValue::Text(t)) => format!("'{t}'"),
            Some(CardValue::Unparsed(t)) => t.clone(),
        }
    }
}

/// One header card. Commentary cards (`COMMENT`, `HISTORY`, blank keyword) have no value and
/// keep their text in `comment`.
#[derive(Debug, Clone, PartialEq)]
pub struct Card {
    pub keyword: String,
    pub value: Option<CardValue>,
    pub comment: String,
}

/// Bytes in one card.
pub const CARD_LEN: usize = 80;

impl Card {
    fn new(keyword: &str, value: CardValue, comment: &str) -> Self {
        Self {
            keyword: keyword.to_ascii_uppercase(),
            value: Some(value),
            comment: comment.into(),
        }
    }
    /// A string-valued card, e.g. `BUNIT = 'arcsec'`.
    pub fn text(keyword: &str, value: &str, comment: &str) -> Self {
        Self::new(keyword, CardValue::Text(value.into()), comment)
    }
    /// A real-valued card, e.g. `ZSOURCE = 2.0`.
    pub fn real(keyword: &str, value: f64, comment: &str) -> Self {
        Self::new(keyword, CardValue::Real(value), comment)
    }
    /// An integer-valued card.
    pub fn integer(keyword: &str, value: i64, comment: &str) -> Self {
        Self::new(keyword, CardValue::Integer(value), comment)
    }
    /// A logical card (`T` / `F`).
    pub fn logical(keyword: &str, value: bool, comment: &str) -> Self {
        Self::new(keyword, CardValue::Logical(value), comment)
    }
    /// A `COMMENT` card; text beyond 72 characters is wrapped by the writer.
    pub fn comment(text: &str) -> Self {
        Self {
            keyword: "COMMENT".into(),
            value: None,
            comment: text.into(),
        }
    }

    /// The value as a real number (integers convert).
    pub fn as_f64(&self) -> Option<f64> {
        match self.value {
            Some(CardValue::Real(v)) => Some(v),
            Some(CardValue::Integer(v)) => Some(v as f64),
            _ => None,
        }
    }

    /// The value as text (string cards only).
    pub fn as_str(&self) -> Option<&str> {
        match &self.value {
            Some(CardValue::Text(s)) => Some(s),
            _ => None,
        }
    }

    /// Formats the card as exactly 80 ASCII characters; the comment is cut to fit. Errors name
    /// what cannot be written (bad keyword, non-ASCII text, non-finite number, too long).
    pub fn format(&self) -> Result<String, String> {
        let kw = &self.keyword;
        let kw_ok = kw.len() <= 8
            && kw
                .bytes()
                .all(|b| b.is_ascii_uppercase() || b.is_ascii_digit() || b == b'_' || b == b'-');
        if !kw_ok {
            return Err("a keyword is 1 to 8 characters of A-Z, 0-9, '_', '-'".into());
        }
        if !self.comment.bytes().all(|b| (32..=126).contains(&b)) {
            return Err("the comment has characters outside printable ASCII".into());
        }
        let mut out = format!("{kw:<8}");
        let Some(value) = &self.value else {
            if self.comment.len() > 72 {
                return Err("commentary text is longer than 72 characters".into());
            }
            out.push_str(&self.comment);
            return Ok(format!("{out:<80}"));
        };
        if kw.is_empty() {
            return Err("a valued card needs a keyword".into());
        }
        out.push_str("= ");
        out.push_str(&format_value(value)?);
        if out.len() > CARD_LEN {
            return Err(format!(
                "the value needs {} characters, more than a card holds",
                out.len()
            ));
        }
        if !self.comment.is_empty() && out.len() + 3 < CARD_LEN {
            out.push_str(" / ");
            let room = CARD_LEN - out.len();
            out.push_str(&self.comment[..self.comment.len().min(room)]);
        }
        Ok(format!("{out:<80}"))
    }

    /// Parses one 80-byte card; never fails (unreadable values become [`CardValue::Unparsed`]).
    pub fn parse(raw: &[u8]) -> Card {
        let text: String = raw
            .iter()
            .map(|&b| {
                if (32..=126).contains(&b) {
                    b as char
                } else {
                    '?'
                }
            })
            .collect();
        let keyword = text.get(..8).unwrap_or(&text).trim().to_string();
        let is_commentary = matches!(keyword.as_str(), "" | "COMMENT" | "HISTORY");
        if is_commentary || text.get(8..10) != Some("= ") {
            let rest = text.get(8..).unwrap_or("").trim_end().to_string();
            return Card {
                keyword,
                value: None,
                comment: rest,
            };
        }
        let (value, comment) = parse_value(&text[10..]);
        Card {
            keyword,
            value,
            comment,
        }
    }
}

fn format_value(value: &CardValue) -> Result<String, String> {
    Ok(match value {
        CardValue::Logical(b) => format!("{:>20}", if *b { "T" } else { "F" }),
        CardValue::Integer(i) => format!("{i:>20}"),
        CardValue::Real(v) => format!("{:>20}", format_real(*v)?),
        CardValue::Text(s) | CardValue::Unparsed(s) => {
            if !s.bytes().all(|b| (32..=126).contains(&b)) {
                return Err("the string has characters outside printable ASCII".into());
            }
            let escaped = s.replace('\'', "''");
            format!("'{escaped:<8}'")
        }
    })
}

/// Shortest round-trip decimal with a decimal point and an upper-case exponent (`-2.5E-05`).
fn format_real(v: f64) -> Result<String, String> {
    if !v.is_finite() {
        return Err(format!("the value {v} is not a finite number"));
    }
    let s = format!("{v:?}").to_ascii_uppercase();
    let (mantissa, exponent) = match s.split_once('E') {
        Some((m, e)) => (m.to_string(), format!("E{e}")),
        None => (s.clone(), String::new()),
    };
    let mantissa = if mantissa.contains('.') {
        mantissa
    } else {
        format!("{mantissa}.0")
    };
    Ok(format!("{mantissa}{exponent}"))
}

/// Splits the value field (columns 11-80) into a value and a comment.
fn parse_value(field: &str) -> (Option<CardValue>, String) {
    let trimmed = field.trim_start();
    if let Some(body) = trimmed.strip_prefix('\'') {
        let mut s = String::new();
        let mut chars = body.char_indices().peekable();
        while let Some((k, c)) = chars.next() {
            if c != '\'' {
                s.push(c);
            } else if chars.peek().map(|&(_, c2)| c2) == Some('\'') {
                s.push('\'');
                chars.next();
            } else {
                let rest = &body[k + 1..];
                let comment = rest.split_once('/').map_or("", |(_, c)| c.trim());
                return (Some(CardValue::Text(s.trim_end().into())), comment.into());
            }
        }
        return (
            Some(CardValue::Unparsed(trimmed.trim_end().into())),
            String::new(),
        );
    }
    let (token, comment) = match trimmed.split_once('/') {
        Some((v, c)) => (v.trim(), c.trim().to_string()),
        None => (trimmed.trim(), String::new()),
    };
    let value = match token {
        "" => None,
        "T" => Some(CardValue::Logical(true)),
        "F" => Some(CardValue::Logical(false)),
        _ => Some(parse_number(token)),
    };
    (value, comment)
}

fn parse_number(token: &str) -> CardValue {
    if let Ok(i) = token.parse::<i64>() {
        return CardValue::Integer(i);
    }
    match token.replace(['D', 'd'], "E").parse::<f64>() {
        Ok(v) if v.is_finite() => CardValue::Real(v),
        _ => CardValue::Unparsed(token.into()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A card's value is shown as a header writes it, never as a Rust debug dump.
    #[test]
    fn values_are_shown_as_written() {
        assert_eq!(
            CardValue::shown(Some(&CardValue::Text("NAN".into()))),
            "'NAN'"
        );
        assert_eq!(CardValue::shown(Some(&CardValue::Logical(true))), "T");
        assert_eq!(CardValue::shown(Some(&CardValue::Real(0.5))), "0.5");
        assert_eq!(CardValue::shown(None), "no value");
    }

    #[test]
    fn cards_round_trip() {
        for card in [
            Card::real("CDELT1", -2.777777777777778e-5, "deg"),
            Card::integer("NAXIS1", 512, ""),
            Card::logical("SIMPLE", true, "conforms"),
            Card::text("BUNIT", "it's", "quote inside"),
            Card::comment("free text"),
        ] {
            let s = card.format().unwrap();
            assert_eq!(s.len(), 80, "{s}");
            assert_eq!(Card::parse(s.as_bytes()), card, "{s}");
        }
    }

    #[test]
    fn reals_have_a_point_and_parse_d_exponents() {
        assert_eq!(format_real(1e-5).unwrap(), "1.0E-5");
        assert_eq!(format_real(2.0).unwrap(), "2.0");
        let c = Card::parse(format!("{:<80}", "CRVAL1  =   1.5D2 / x").as_bytes());
        assert_eq!(c.as_f64(), Some(150.0));
        assert!(Card::real("X", f64::NAN, "").format().is_err());
        assert!(
            Card::text("lower", "a", "").format().is_ok(),
            "keywords are upper-cased"
        );
        assert!(Card::text("TOOLONGKEY", "a", "").format().is_err());
    }
}
