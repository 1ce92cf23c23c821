//! Solvers: distributed linear algebra ([`linear`]) and, on top, nonlinear solvers and
//! load stepping.

pub mod linear;
