//! The checks every section builder shares: errors that name the deck field, names
//! defined once, positive numbers, unit directions. One place, so every deck error
//! reads the same (`field.path: what was expected, what was given`).

use crate::{Error, Result};
use std::collections::{BTreeMap, BTreeSet};

/// The most steps a deck may ask for at its nominal step (10 million: weeks of solving,
/// and the step list alone would take gigabytes beyond it).
pub(crate) const MAX_STEPS: f64 = 1e7;

/// An input error at deck field `field` (a path such as `walls[0].motion.x`).
pub(crate) fn err(field: impl std::fmt::Display, msg: impl std::fmt::Display) -> Error {
    Error::input(format!("{field}: {msg}"))
}

/// Every name of a list non-empty and used once (errors name `<what>[i].name`).
pub(crate) fn unique_names<'a>(what: &str, names: impl Iterator<Item = &'a str>) -> Result<()> {
    let mut seen = BTreeSet::new();
    for (i, n) in names.enumerate() {
        if n.trim().is_empty() {
            return Err(err(
                format!("{what}[{i}].name"),
                "expected a non-empty name",
            ));
        }
        if !seen.insert(n) {
            return Err(err(
                format!("{what}[{i}].name"),
                format!("`{n}` is defined twice"),
            ));
        }
    }
    Ok(())
}

/// The names a lookup could have used, for an error message.
pub(crate) fn known(names: &BTreeMap<String, impl Sized>) -> String {
    if names.is_empty() {
        "none defined".into()
    } else {
        format!(
            "defined: {}",
            names
                .keys()
                .map(|k| k.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        )
    }
}

/// `v`, which must be given, positive and finite (the `what` of a shape, a material).
pub(crate) fn positive(field: String, v: Option<f64>, what: &str) -> Result<f64> {
    match v {
        Some(x) if x > 0.0 && x.is_finite() => Ok(x),
        Some(x) => Err(err(field, format!("expected a positive {what}, got {x}"))),
        None => Err(err(field, format!("missing (the {what} of this shape)"))),
    }
}

/// `a` scaled to unit length; a zero or non-finite direction is an error at `field`.
pub(crate) fn unit(field: String, a: [f64; 3]) -> Result<[f64; 3]> {
    let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    if !(n > 0.0 && n.is_finite()) {
        return Err(err(
            field,
            format!("expected a non-zero direction, got {a:?}"),
        ));
    }
    Ok([a[0] / n, a[1] / n, a[2] / n])
}
