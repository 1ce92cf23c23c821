//! Solvers that drive the model: nonlinear solvers ([`nonlinear`]), one step controller
//! ([`control`]) shared by load stepping ([`stepping`]) and time integration ([`time`]).
//! The distributed linear algebra they use is [`crate::linalg`].

pub mod analysis;
pub mod armijo;
pub mod control;
pub mod nonlinear;
pub mod record;
pub mod stepping;
pub mod time;

pub use analysis::{Analysis, AnalysisKind, MassKind, Predictor, Scheme, Stage};
