//! Distributed sparse linear algebra: block-sparse matrix, GMRES, block Jacobi.
//!
//! Vectors are distributed by their owned parts (the scalar slice of the rank's
//! contiguous range). The seams are [`LinearOperator`] (an assembled matrix, or a
//! matrix-free Jacobian product that evaluates a residual and may fail) and
//! [`Preconditioner`] (local: block Jacobi needs no communication).

pub mod block_jacobi;
pub mod gmres;
pub mod lagged;
pub mod matrix;
pub mod ordering;

pub use block_jacobi::{BlockJacobi, Factorization, FillOrdering};
pub use gmres::{gmres, GmresOptions, GmresStats};

pub use matrix::DistMatrix;

use crate::parallel::Comm;

/// y = A x for distributed vectors given by their owned parts.
///
/// Collective. An implementation that can fail (e.g. a matrix-free product whose
/// residual evaluation meets an inverted element) must agree on failure across ranks
/// (e.g. with [`Comm::all_ok`]) so that every rank returns `Err` together.
pub trait LinearOperator {
    fn apply(&mut self, comm: &dyn Comm, x: &[f64], y: &mut [f64]) -> crate::Result<()>;
}

impl LinearOperator for DistMatrix {
    fn apply(&mut self, comm: &dyn Comm, x: &[f64], y: &mut [f64]) -> crate::Result<()> {
        self.spmv(comm, x, y);
        Ok(())
    }
}

impl LinearOperator for &DistMatrix {
    fn apply(&mut self, comm: &dyn Comm, x: &[f64], y: &mut [f64]) -> crate::Result<()> {
        self.spmv(comm, x, y);
        Ok(())
    }
}

/// z = M⁻¹ r on owned parts; local (no communication).
pub trait Preconditioner {
    fn apply(&self, r: &[f64], z: &mut [f64]);
}

/// No preconditioning: z = r.
#[derive(Debug, Default, Clone, Copy)]
pub struct Identity;

impl Preconditioner for Identity {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        z.copy_from_slice(r);
    }
}
