//! Size limits on inputs, line ends, and where a JSON error is.
//!
//! Every limit is far above any real use (the largest real catalogues are a few thousand rows,
//! HFF maps 4096 x 4096 pixels, the paper's arcs about 10^4 pixels) and well below what would
//! exhaust memory, so that a wrong or corrupt file (a 2 GB log given as a catalogue, a FITS
//! header claiming 10^6 x 10^6 pixels) is refused at once with a message naming the file, its
//! size and the limit, before it is read into memory. The command line checks a file's size
//! before reading it; the parsers, which also take texts from the browser app, check again.

use thiserror::Error;

/// Largest catalogue (Lenstool images or members) in bytes: 64 MiB, about 10^6 rows.
pub const MAX_CATALOG_BYTES: u64 = 64 << 20;
/// Most data rows in one catalogue.
pub const MAX_CATALOG_ROWS: usize = 1_000_000;
/// Largest JSON file of settings or of a parametric model in bytes: 16 MiB (a model of 10^5
/// components is about 10 MiB).
pub const MAX_JSON_BYTES: u64 = 16 << 20;
/// Largest arcs JSON file in bytes: 128 MiB (10^6 pixels written with full precision).
pub const MAX_ARCS_BYTES: u64 = 128 << 20;
/// Most arc pixels in one arcs file, all systems together: each is two rows of the linear
/// system, so 10^6 of them are already far beyond what the solver can use.
pub const MAX_ARC_PIXELS: usize = 1_000_000;
/// Most pixels in one FITS image: 10^8 (a 10000 x 10000 map).
pub const MAX_FITS_PIXELS: usize = 100_000_000;
/// Largest FITS file in bytes: 1 GiB (10^8 double-precision pixels and their headers).
pub const MAX_FITS_BYTES: u64 = 1 << 30;

/// `text` with its line ends as every parser reads them: a carriage return alone (classic
/// Mac OS, some spreadsheet exports, or a few lines of a file edited on several systems)
/// becomes a line feed, so the file is read line by line and not with lines run together.
/// Windows' CR LF, which the parsers take as it is, stays; text without a lone carriage
/// return comes back unchanged.
pub fn with_line_feeds(text: &str) -> std::borrow::Cow<'_, str> {
    let bytes = text.as_bytes();
    let lone_cr = |k: usize| bytes[k] == b'\r' && bytes.get(k + 1) != Some(&b'\n');
    if !(0..bytes.len()).any(lone_cr) {
        return std::borrow::Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len());
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        if c == '\r' && chars.peek() != Some(&'\n') {
            out.push('\n');
        } else {
            out.push(c);
        }
    }
    std::borrow::Cow::Owned(out)
}

/// The kinds of input file, each with its size limit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InputKind {
    /// A Lenstool image or member catalogue.
    Catalog,
    /// Settings (`CONFIG.json`).
    Config,
    /// A parametric model file.
    Model,
    /// Arc pixels (JSON).
    Arcs,
    /// A FITS image.
    Fits,
}

impl InputKind {
    /// Largest accepted file in bytes.
    pub fn max_bytes(self) -> u64 {
        match self {
            Self::Catalog => MAX_CATALOG_BYTES,
            Self::Config | Self::Model => MAX_JSON_BYTES,
            Self::Arcs => MAX_ARCS_BYTES,
            Self::Fits => MAX_FITS_BYTES,
        }
    }

    /// What the file is, for messages.
    pub fn name(self) -> &'static str {
        match self {
            Self::Catalog => "a catalogue",
            Self::Config => "a settings file",
            Self::Model => "a model file",
            Self::Arcs => "an arcs file",
            Self::Fits => "a FITS file",
        }
    }
}

/// An input over one of the limits of this module.
#[derive(Debug, Error, Clone, PartialEq)]
#[error("{source_name}: {count} {unit} is more than the limit of {limit} {unit} for {what}")]
pub struct TooLarge {
    /// File name, as given by the caller.
    pub source_name: String,
    /// What was counted: `"bytes"`, `"rows"`, `"pixels"`.
    pub unit: &'static str,
    pub count: u64,
    pub limit: u64,
    /// What the limit is for, e.g. `"a catalogue"`.
    pub what: &'static str,
}

impl TooLarge {
    /// `Err` when `count > limit`.
    pub fn check(
        source_name: &str,
        unit: &'static str,
        count: u64,
        limit: u64,
        what: &'static str,
    ) -> Result<(), Self> {
        if count <= limit {
            return Ok(());
        }
        Err(Self {
            source_name: source_name.to_string(),
            unit,
            count,
            limit,
            what,
        })
    }

    /// `Err` when a file or text of `bytes` bytes is over the limit of `kind`.
    pub fn check_bytes(source_name: &str, kind: InputKind, bytes: u64) -> Result<(), Self> {
        Self::check(source_name, "bytes", bytes, kind.max_bytes(), kind.name())
    }
}

/// Line, column and reason of a `serde_json` error in `text` (the text it parsed), the reason
/// without the `" at line L column C"` that its `Display` appends (so that a message says them
/// once), and with a hint when the value there is `NaN` or `Infinity`, which JSON does not have
/// but Python's `json.dump` writes. Line and column are 1-based; both are 0 when serde_json
/// does not know them.
pub fn json_error_parts(text: &str, e: &serde_json::Error) -> (usize, usize, String) {
    let (line, column) = (e.line(), e.column());
    let full = e.to_string();
    let suffix = format!(" at line {line} column {column}");
    let mut reason = json_words(full.strip_suffix(&suffix).unwrap_or(&full));
    if reason.starts_with("must be ") {
        if let Some(key) = key_before(text, line, column) {
            reason = format!("'{key}' {reason}");
        }
    }
    if reason == "expected value" && comment_at(text, line, column) {
        reason.push_str(": JSON has no comments (// or /* */); remove them");
    }
    if let Some(word) = non_json_number(text, line, column) {
        reason.push_str(&format!(
            ": '{word}' is not a number in JSON (Python's json.dump writes NaN and Infinity \
             for such values; leave them out)"
        ));
    }
    (line, column, reason)
}

/// A `serde_json` error's reason (without its place) in words for a person: "invalid type:
/// string \"abc\", expected usize" becomes "must be a whole number of 0 or more (got the text
/// \"abc\")", "EOF while parsing a list" "ends too early, inside a list", and so on; a
/// reason it does not know is returned as it is.
pub fn json_words(reason: &str) -> String {
    let kind = |expected: &str| match expected {
        "usize" | "u64" | "u32" | "u16" | "u8" => "a whole number of 0 or more".to_string(),
        "i64" | "i32" => "a whole number".to_string(),
        "f64" | "f32" => "a number".to_string(),
        "a boolean" => "true or false".to_string(),
        "a string" => "text in quotes".to_string(),
        "a sequence" => "a list in brackets [ ]".to_string(),
        "a map" => "an object in braces { }".to_string(),
        other if other.starts_with("struct ") || other.starts_with("a map") => {
            "an object in braces { }".to_string()
        }
        other if other.starts_with("a sequence of ") => format!(
            "a list of {} in brackets [ ]",
            other
                .trim_start_matches("a sequence of ")
                .replace(" f64 values", " numbers")
                .replace('`', "")
        ),
        other => other.replace('`', ""),
    };
    let got = |found: &str| match found {
        "map" => "an object".to_string(),
        "sequence" => "a list".to_string(),
        "unit value" => "null".to_string(),
        other => other
            .replacen("string ", "the text ", 1)
            .replace('`', "")
            .replacen("floating point ", "", 1),
    };
    if let Some(rest) = reason
        .strip_prefix("invalid type: ")
        .or_else(|| reason.strip_prefix("invalid value: "))
    {
        if let Some((found, expected)) = rest.split_once(", expected ") {
            return format!("must be {} (got {})", kind(expected), got(found));
        }
    }
    if let Some(rest) = reason.strip_prefix("invalid length ") {
        if let Some((found, expected)) = rest.split_once(", expected ") {
            if expected.starts_with("struct ") {
                return "must be an object in braces { } (got a list)".to_string();
            }
            let values = if found == "1" { "value" } else { "values" };
            return format!("must be {} (got {found} {values})", kind(expected));
        }
    }
    if let Some(rest) = reason.strip_prefix("duplicate field ") {
        return format!("the field '{}' is given twice", rest.trim_matches('`'));
    }
    if let Some(rest) = reason.strip_prefix("unknown field ") {
        if let Some((found, expected)) = rest.split_once(", expected ") {
            let known = expected.trim_start_matches("one of ").replace('`', "");
            return format!(
                "unknown field '{}' (the fields here: {known})",
                found.trim_matches('`')
            );
        }
        if let Some((found, _)) = rest.split_once(", there are no fields") {
            return format!(
                "unknown field '{}' (nothing is expected here)",
                found.trim_matches('`')
            );
        }
    }
    if let Some(rest) = reason.strip_prefix("missing field ") {
        return format!("the field '{}' is missing", rest.trim_matches('`'));
    }
    if let Some(rest) = reason.strip_prefix("unknown variant ") {
        if let Some((found, expected)) = rest.split_once(", expected ") {
            let options = expected.trim_start_matches("one of ").replace('`', "");
            return format!("must be one of {options} (got {})", found.replace('`', ""));
        }
    }
    if let Some(what) = reason.strip_prefix("EOF while parsing ") {
        let inside = match what {
            "a value" => "where a value should be".to_string(),
            "a list" => "inside a list [ ] that is not closed".to_string(),
            "an object" => "inside an object { } that is not closed".to_string(),
            "a string" => "inside text in quotes that is not closed".to_string(),
            other => format!("inside {other}"),
        };
        return format!("ends too early, {inside}");
    }
    match reason {
        "trailing comma" => {
            "a comma before a closing bracket or brace (JSON allows none there)".to_string()
        }
        "trailing characters" => {
            "more text after the end of the JSON (a file holds one value)".to_string()
        }
        "key must be a string" => "a name in an object must be in double quotes".to_string(),
        "recursion limit exceeded" => {
            "nested too deeply (more than 128 levels of [ ] and { })".to_string()
        }
        "number out of range" => "a number too large for a computer (above 1.8e308)".to_string(),
        "control character (\\u0000-\\u001F) found while parsing a string" => {
            "a control character (a tab, line break or NUL byte) inside text in quotes; JSON \
             needs it written as an escape"
                .to_string()
        }
        other => other.to_string(),
    }
}

/// Whether a `//` or `/*` comment starts at (or just before) 1-based `line` and `column`.
fn comment_at(text: &str, line: usize, column: usize) -> bool {
    let Some(row) = line.checked_sub(1).and_then(|l| text.lines().nth(l)) else {
        return false;
    };
    let mut at = column.saturating_sub(1).min(row.len());
    while !row.is_char_boundary(at) {
        at -= 1;
    }
    let from = row[..at].char_indices().next_back().map_or(0, |(i, _)| i);
    row.get(from..).is_some_and(|rest| {
        rest.trim_start().starts_with("//") || rest.trim_start().starts_with("/*")
    })
}

/// The name of the JSON key whose value ends at 1-based `line` and `column` of `text` (the
/// last `"name":` before it), for a message about that value.
fn key_before(text: &str, line: usize, column: usize) -> Option<&str> {
    let start: usize = text
        .split_inclusive('\n')
        .take(line.checked_sub(1)?)
        .map(str::len)
        .sum();
    let mut end = (start + column).min(text.len());
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    let before = &text[..end];
    let colon = before.rfind(':')?;
    let name_end = before[..colon].trim_end();
    let name = name_end.strip_suffix('"')?;
    let open = name.rfind('"')?;
    let key = &name[open + 1..];
    (!key.is_empty() && key.len() <= 64 && !key.contains(['{', '}', '[', ']', ','])).then_some(key)
}

/// The word at 1-based `line` and `column` of `text` (serde_json stops on it or just after
/// its first letters) when it is a NaN or an infinity.
fn non_json_number(text: &str, line: usize, column: usize) -> Option<&str> {
    let row = text.lines().nth(line.checked_sub(1)?)?;
    let at = column.checked_sub(1)?.min(row.len());
    // serde_json counts columns in bytes; never cut a character whatever it counts.
    if !row.is_char_boundary(at) {
        return None;
    }
    let part = |c: char| c.is_ascii_alphanumeric() || matches!(c, '-' | '+' | '.');
    let start = row[..at]
        .char_indices()
        .rev()
        .take_while(|&(_, c)| part(c))
        .last()
        .map_or(at, |(i, _)| i);
    let end = row[start..]
        .find(|c: char| !part(c))
        .map_or(row.len(), |k| start + k);
    let word = &row[start..end];
    let bare = word.trim_start_matches(['-', '+']).to_ascii_lowercase();
    matches!(bare.as_str(), "nan" | "inf" | "infinity").then_some(word)
}

/// Line, column and reason (as [`json_error_parts`]) when `text` is JSON whose first value is
/// not an object: a file of settings or a model must be `{ ... }`, and serde would read a
/// list as the object's fields in order and blame its first field.
pub fn not_an_object(text: &str) -> Option<(usize, usize, String)> {
    let trimmed = text.trim_start();
    let first = trimmed.chars().next()?;
    if first == '{' {
        return None;
    }
    let before = &text[..text.len() - trimmed.len()];
    let line = 1 + before.matches('\n').count();
    let column = 1 + before.rsplit('\n').next().map_or(0, |l| l.len());
    let what = match first {
        '[' => "a list [ ]".to_string(),
        '"' => "text in quotes".to_string(),
        c if c == '-' || c.is_ascii_digit() => "a number".to_string(),
        _ => return None, // not JSON at all: serde says where
    };
    Some((
        line,
        column,
        format!("the file must be an object in braces {{ }}, not {what}"),
    ))
}

/// [`not_an_object`] as `"line L, column C: reason"`, as [`json_error_message`] says a place.
pub fn not_an_object_message(text: &str) -> Option<String> {
    not_an_object(text).map(placed)
}

/// `"line L, column C: reason"` for a `serde_json` error in `text` (only the reason when
/// serde_json does not know the place); see [`json_error_parts`].
pub fn json_error_message(text: &str, e: &serde_json::Error) -> String {
    placed(json_error_parts(text, e))
}

/// `"line L, column C: reason"`, only the reason at line 0 (a place not known).
fn placed((line, column, reason): (usize, usize, String)) -> String {
    match line {
        0 => reason,
        _ => format!("line {line}, column {column}: {reason}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lone carriage returns become line feeds wherever they are; CR LF and LF stay, and
    /// text without a lone CR is not copied.
    #[test]
    fn lone_carriage_returns_become_line_feeds() {
        use std::borrow::Cow;
        for text in ["a\nb\n", "a\r\nb\r\n", "", "no line end", "a\r\n"] {
            assert!(
                matches!(with_line_feeds(text), Cow::Borrowed(t) if t == text),
                "{text:?}"
            );
        }
        for (text, read) in [
            ("a\rb\r", "a\nb\n"),
            ("a\r\nb\rc\nd\r", "a\r\nb\nc\nd\n"),
            ("\r\r\n\r", "\n\r\n\n"),
            ("é\rü", "é\nü"),
        ] {
            assert_eq!(with_line_feeds(text), read, "{text:?}");
        }
    }

    #[test]
    fn json_place_is_said_once() {
        let text = "{\n  \"a\": }";
        let e = serde_json::from_str::<serde_json::Value>(text).unwrap_err();
        let m = json_error_message(text, &e);
        assert_eq!(m, "line 2, column 8: expected value");
        assert_eq!(m.matches("line").count(), 1);
    }

    /// NaN and infinities, as Python writes them (and as people type them), are named; other
    /// words are not.
    #[test]
    fn nan_and_infinity_are_named() {
        for (text, word) in [
            ("[1, NaN]", "NaN"),
            ("[1, -Infinity]", "-Infinity"),
            ("[1, Infinity]", "Infinity"),
            ("[1,\n  nan]", "nan"),
            ("{\"a\": -inf}", "-inf"),
            ("{\"μ\": [1, NaN]}", "NaN"),
        ] {
            let e = serde_json::from_str::<serde_json::Value>(text).unwrap_err();
            let m = json_error_message(text, &e);
            assert!(
                m.contains(&format!("'{word}' is not a number in JSON")),
                "{text}: {m}"
            );
        }
        for text in ["[1, none]", "[1, 2", "[1, x]", "[\"μμμ\", x]", "[\"μ\"x]"] {
            let e = serde_json::from_str::<serde_json::Value>(text).unwrap_err();
            assert!(
                !json_error_message(text, &e).contains("not a number"),
                "{text}"
            );
        }
    }

    /// The key before a place is found in any text at any place without cutting a character.
    #[test]
    fn the_key_of_a_value_is_found_anywhere() {
        let text = "{\"μμ\": {\"cells\": 1.5},\n \"b\": [1, \"x\"]}";
        assert_eq!(key_before(text, 1, 19), Some("cells"));
        assert_eq!(key_before(text, 2, 13), Some("b"));
        for line in 0..4 {
            for column in 0..40 {
                let _ = key_before(text, line, column);
                let _ = comment_at(text, line, column);
            }
        }
        assert_eq!(key_before("[1, 2]", 1, 3), None);
    }

    /// serde's words become a person's; what it does not know passes unchanged.
    #[test]
    fn serde_words_become_a_persons() {
        for (serde, person) in [
            (
                "invalid type: floating point `2.5`, expected usize",
                "must be a whole number of 0 or more (got 2.5)",
            ),
            (
                "invalid type: map, expected a sequence",
                "must be a list in brackets [ ] (got an object)",
            ),
            (
                "invalid type: sequence, expected struct ModelFile",
                "must be an object in braces { } (got a list)",
            ),
            ("missing field `type`", "the field 'type' is missing"),
            (
                "EOF while parsing a list",
                "ends too early, inside a list [ ] that is not closed",
            ),
            ("something new", "something new"),
        ] {
            assert_eq!(json_words(serde), person);
        }
    }

    #[test]
    fn limits_are_checked() {
        assert!(TooLarge::check_bytes("a.cat", InputKind::Catalog, MAX_CATALOG_BYTES).is_ok());
        let e =
            TooLarge::check_bytes("a.cat", InputKind::Catalog, MAX_CATALOG_BYTES + 1).unwrap_err();
        assert_eq!(
            e.to_string(),
            "a.cat: 67108865 bytes is more than the limit of 67108864 bytes for a catalogue"
        );
    }
}
