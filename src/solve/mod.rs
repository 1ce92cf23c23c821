//! Solvers: distributed linear algebra ([`linear`]), nonlinear solvers ([`nonlinear`])
//! load stepping ([`stepping`]) and time integration ([`time`]).

pub mod linear;
pub mod nonlinear;
pub mod stepping;
pub mod time;
