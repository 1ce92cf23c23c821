//! Why a constitutive model could not be evaluated at one point: a typed reason whose
//! `Display` is the message the user sees (after the element and point that
//! the element kernels add).

use std::fmt;

/// Why a material could not be evaluated (e.g. an inverted point, J ≤ 0). `model` is the
/// model's name as the messages print it ("J2", "Mooney-Rivlin", "neo-Hookean").
#[derive(Debug, Clone, PartialEq)]
pub enum MaterialError {
    /// det F ≤ 0 (or NaN): `"{model}: det F = {det:.3e} ≤ 0 (inverted)"`.
    Inverted { model: &'static str, det: f64 },
    /// A non-finite input or result: `"{model}: non-finite {what}"` (what: "deformation
    /// gradient", "history", "stress", "stress or tangent").
    NonFinite {
        model: &'static str,
        what: &'static str,
    },
    /// F could not be inverted: `"{model}: singular F"`.
    SingularF { model: &'static str },
    /// The history slices are shorter than the model needs.
    HistoryLength {
        model: &'static str,
        needs: usize,
        old: usize,
        new: usize,
    },
    /// The trial elastic left Cauchy–Green tensor has a non-positive eigenvalue.
    NonPositiveStretch {
        model: &'static str,
        eigenvalues: [f64; 3],
    },
    /// The plastic return mapping did not converge (trial Mises stress, committed
    /// equivalent plastic strain).
    ReturnMapping {
        model: &'static str,
        q_trial: f64,
        plastic_strain: f64,
    },
}

impl fmt::Display for MaterialError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MaterialError::Inverted { model, det } => {
                write!(f, "{model}: det F = {det:.3e} ≤ 0 (inverted)")
            }
            MaterialError::NonFinite { model, what } => write!(f, "{model}: non-finite {what}"),
            MaterialError::SingularF { model } => write!(f, "{model}: singular F"),
            MaterialError::HistoryLength {
                model,
                needs,
                old,
                new,
            } => write!(f, "{model}: history needs {needs} values, got {old} / {new}"),
            MaterialError::NonPositiveStretch { model, eigenvalues } => write!(
                f,
                "{model}: trial elastic b has non-positive eigenvalues {:?}",
                &eigenvalues[..]
            ),
            MaterialError::ReturnMapping {
                model,
                q_trial,
                plastic_strain,
            } => write!(
                f,
                "{model}: return mapping did not converge (q_tr = {q_trial:.6e}, ε̄p = {plastic_strain:.6e})"
            ),
        }
    }
}

impl std::error::Error for MaterialError {}
