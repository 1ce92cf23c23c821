//! What every part of the `.k` writer shares: long-format cards and the file's numbering
//! of node sets and curves.

use crate::curve::Curve;
use std::fmt::Write;

/// Numbered node sets and curves of the file being written.
pub trait Numbering {
    /// The number of node set `name` (defined on first use).
    fn set(&mut self, name: &str, nodes: &[usize]) -> usize;
    /// The number of a curve (one per distinct curve).
    fn curve(&mut self, c: &Curve) -> usize;
}

/// A long-format card: every field 20 columns.
pub fn card(out: &mut String, fields: &[String]) {
    for f in fields {
        let _ = write!(out, "{f:>20}");
    }
    out.push('\n');
}

/// A real in at most a field's 20 columns: the shortest text that reads back as the same
/// f64 where it fits (so a model comes back bit for bit), else rounded to fit.
pub fn r(x: f64) -> String {
    let (plain, sci) = (format!("{x}"), format!("{x:e}"));
    let s = if plain.len() < sci.len() && plain.contains('.') {
        plain
    } else {
        sci
    };
    if s.len() <= 20 {
        return s;
    }
    (0..16)
        .rev()
        .map(|p| format!("{x:.p$e}"))
        .find(|s| s.len() <= 20)
        .unwrap_or(s)
}

#[cfg(test)]
mod tests {
    use super::r;

    #[test]
    fn reals_fit_and_read_back() {
        for x in [
            -2.0 / 3.0 * 100.0,
            1e-300 / 3.0,
            -1e300 / 7.0,
            0.1,
            0.0,
            -5e-324,
        ] {
            let s = r(x);
            assert!(s.len() <= 20, "{s}");
            let y: f64 = s.parse().unwrap();
            assert!((x - y).abs() <= 1e-13 * x.abs(), "{x} {s}");
        }
        assert_eq!(r(-200.0 / 3.0).parse::<f64>().unwrap(), -200.0 / 3.0);
        assert_eq!(r(-46.333333333333336), "-46.333333333333336");
    }
}
