//! Why an element kernel could not be evaluated: a typed reason with the point where it
//! happened. Its `Display` is the message the user sees after `element <id>: `, which
//! the model adds when it turns the error into a solver failure
//! (`solve::nonlinear::Failure::Element`) or an input error (`scene/`).

use crate::material::MaterialError;
use std::fmt;

/// Where in an element something happened.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum At {
    /// Integration point g of the element's rule.
    Gauss(usize),
    /// The element centre (the one point of a reduced element, EAS's J₀).
    Centre,
    /// Node (corner) c of the element.
    Corner(usize),
    /// The centroid (a tet4's one point, in the reference check).
    Centroid,
}

impl fmt::Display for At {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            At::Gauss(g) => write!(f, "Gauss point {g}"),
            At::Centre => f.write_str("the element centre"),
            At::Corner(c) => write!(f, "corner {c}"),
            At::Centroid => f.write_str("its centroid"),
        }
    }
}

/// Why an element could not be evaluated (inverted element, material failure, a
/// formulation's own failure), or why its reference shape is refused.
#[derive(Debug, Clone, PartialEq)]
pub enum ElementError {
    /// det F ≤ 0 (or NaN) at a point of the current configuration.
    Inverted { at: At, det: f64 },
    /// det J₀ ≤ 0 (or NaN) at a point of the reference configuration.
    ReferenceInverted { at: At, det: f64 },
    /// The material model failed at a point.
    Material { at: At, error: MaterialError },
    /// The hybrid element's material has no volumetric part U(J) (`material`: its debug
    /// form).
    NoVolumetricSplit { material: String },
    /// The reduced element's hourglass mode is degenerate (γ·h tiny).
    DegenerateHourglass { mode: usize, gamma_h: f64 },
    /// EAS: the enhanced-strain block K_αα is singular.
    SingularEnhanced,
    /// EAS: the local iteration on the enhanced parameters did not converge.
    EnhancedNotConverged { iterations: usize, residual: f64 },
    /// Reference check ([`super::measure::check_reference`]): det J ≤ 0 at a point or
    /// corner (`kind`: the element kind's name).
    InvertedShape {
        kind: &'static str,
        at: At,
        det: f64,
    },
    /// Reference check: det J tiny for the element's size (a flat element).
    DegenerateShape {
        kind: &'static str,
        at: At,
        det: f64,
        size: f64,
    },
}

impl fmt::Display for ElementError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ElementError::Inverted { at, det } => {
                write!(f, "det F = {det:.3e} ≤ 0 at {at} (element inverted)")
            }
            ElementError::ReferenceInverted { at, det } => {
                write!(f, "reference det J = {det:.3e} ≤ 0 at {at}")
            }
            ElementError::Material { at, error } => write!(f, "material at {at}: {error}"),
            ElementError::NoVolumetricSplit { material } => write!(
                f,
                "the hybrid element needs a material with a volumetric part U(J) ({material} has none)"
            ),
            ElementError::DegenerateHourglass { mode, gamma_h } => write!(
                f,
                "hourglass mode {mode} is degenerate (γ·h = {gamma_h:.3e})"
            ),
            ElementError::SingularEnhanced => {
                f.write_str("the enhanced-strain block K_αα is singular")
            }
            ElementError::EnhancedNotConverged {
                iterations,
                residual,
            } => write!(
                f,
                "the enhanced strains did not converge in {iterations} local iterations (|R_α| = {residual:.3e})"
            ),
            ElementError::InvertedShape { kind, at, det } => {
                write!(f, "inverted {kind}: det J = {det:.3e} ≤ 0 at {at}")
            }
            ElementError::DegenerateShape {
                kind,
                at,
                det,
                size,
            } => write!(
                f,
                "degenerate {kind}: det J = {det:.3e} at {at} is tiny for its size {size:.3e}"
            ),
        }
    }
}

impl std::error::Error for ElementError {}

/// A material failure at a point, as an element error.
pub(super) fn material_at(at: At) -> impl Fn(MaterialError) -> ElementError {
    move |error| ElementError::Material { at, error }
}
