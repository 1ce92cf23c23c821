//! Solvers: distributed linear algebra ([`linear`]), nonlinear solvers ([`nonlinear`])
//! and load stepping ([`stepping`]).

pub mod linear;
pub mod nonlinear;
pub mod stepping;
