//! The error every settings check shares: a field whose value is outside what a run can use;
//! and the small helpers that write messages for people.

use std::borrow::Cow;

use thiserror::Error;

/// A setting or option outside the range a run can use: the field as a settings file names it
/// (its block first, e.g. `grid.cells`, `products.pixels`, `cosmology.omega_m`), the value
/// given, and the reason, which states the range.
#[derive(Debug, Error, Clone, PartialEq)]
#[error("{field} = {} is not allowed ({reason})", number(*.value))]
pub struct BadFieldValue {
    pub field: String,
    pub value: f64,
    pub reason: Cow<'static, str>,
}

impl BadFieldValue {
    /// `reason` states the range (a fixed text, or one made with the values it depends on).
    pub fn new(field: impl Into<String>, value: f64, reason: impl Into<Cow<'static, str>>) -> Self {
        Self {
            field: field.into(),
            value,
            reason: reason.into(),
        }
    }
}

/// The reason of a value outside `[lo, hi]` (`(lo, hi]` when `lo_open`), as a person reads
/// it: "must be between 0 and 2", "must be above 0 and at most 1e4".
pub fn range_reason(lo: f64, hi: f64, lo_open: bool) -> String {
    match lo_open {
        true => format!("must be above {} and at most {}", number(lo), number(hi)),
        false => format!("must be between {} and {}", number(lo), number(hi)),
    }
}

/// `value` as a person would write it in a settings file: whole numbers up to 10^7 in full,
/// larger and smaller magnitudes in exponent form (`1e15`, not `1000000000000000`).
pub(crate) fn number(value: f64) -> String {
    let magnitude = value.abs();
    if magnitude != 0.0 && magnitude.is_finite() && !(1e-4..1e7).contains(&magnitude) {
        format!("{value:e}")
    } else {
        value.to_string()
    }
}

/// `items` joined as English lists them: "a", "a and b", "a, b and c".
pub(crate) fn and_list(items: impl Iterator<Item = String>) -> String {
    let items: Vec<String> = items.collect();
    match items.split_last() {
        None => String::new(),
        Some((last, [])) => last.clone(),
        Some((last, rest)) => format!("{} and {last}", rest.join(", ")),
    }
}

/// Line numbers as a note lists them: "12, 15, 40"; past [`LISTED_LINES`] the first of
/// them and how many more, up to which line ("108, 122, ... 234 and 131 more, up to line
/// 2078"): a `best.par` lists hundreds of galaxies.
pub(crate) fn line_list(lines: impl Iterator<Item = usize>) -> String {
    let lines: Vec<usize> = lines.collect();
    let shown = |l: &[usize]| {
        l.iter()
            .map(|l| l.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    };
    match &lines[..] {
        few if few.len() <= LISTED_LINES => shown(few),
        [first @ .., last] => format!(
            "{} and {} more, up to line {last}",
            shown(&first[..LISTED_LINES]),
            lines.len() - LISTED_LINES
        ),
        [] => unreachable!("an empty list has fewer lines than LISTED_LINES"),
    }
}

/// Most line numbers a note lists one by one ([`line_list`]).
const LISTED_LINES: usize = 10;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_are_stated() {
        assert_eq!(range_reason(0.0, 2.0, false), "must be between 0 and 2");
        assert_eq!(
            range_reason(0.0, 1e4, true),
            "must be above 0 and at most 10000"
        );
        assert_eq!(
            range_reason(1e-9, 1e13, true),
            "must be above 1e-9 and at most 1e13"
        );
    }

    #[test]
    fn values_are_written_as_in_a_settings_file() {
        let e = |v: f64| BadFieldValue::new("solver.iterations", v, "at most 10^6").to_string();
        assert_eq!(
            e(1e15),
            "solver.iterations = 1e15 is not allowed (at most 10^6)"
        );
        assert_eq!(
            e(8000.0),
            "solver.iterations = 8000 is not allowed (at most 10^6)"
        );
        assert_eq!(
            e(0.25),
            "solver.iterations = 0.25 is not allowed (at most 10^6)"
        );
        assert_eq!(
            e(-2.5e-9),
            "solver.iterations = -2.5e-9 is not allowed (at most 10^6)"
        );
        assert_eq!(
            e(f64::NAN),
            "solver.iterations = NaN is not allowed (at most 10^6)"
        );
        assert_eq!(
            e(0.0),
            "solver.iterations = 0 is not allowed (at most 10^6)"
        );
    }

    #[test]
    fn a_long_list_of_lines_is_cut_after_ten() {
        assert_eq!(line_list([12, 15, 40].into_iter()), "12, 15, 40");
        assert_eq!(
            line_list((1..=10).map(|k| 20 * k)),
            "20, 40, 60, 80, 100, 120, 140, 160, 180, 200"
        );
        assert_eq!(
            line_list((1..=267).map(|k| 20 * k + 105)),
            "125, 145, 165, 185, 205, 225, 245, 265, 285, 305 and 257 more, up to line 5445"
        );
    }
}
