//! Distributed sparse linear algebra: block-sparse matrix, GMRES, block Jacobi and
//! restricted additive Schwarz preconditioners.
//!
//! Vectors are distributed by their owned parts (the scalar slice of the rank's
//! contiguous range). The seams are [`LinearOperator`] (an assembled matrix, or a
//! matrix-free Jacobian product that evaluates a residual and may fail) and
//! [`Preconditioner`] (block Jacobi is local; restricted additive Schwarz does one halo
//! exchange per application).

pub mod asm;
pub mod block_jacobi;
pub mod gmres;
pub mod lagged;
pub mod matrix;
pub mod ordering;

pub use asm::RestrictedSchwarz;
pub use block_jacobi::{BlockJacobi, Factorization, FillOrdering, LocalBlockPattern, LocalFactor};
pub use gmres::{gmres, GmresOptions, GmresStats};
pub use lagged::LaggedPreconditioner;

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

/// z = M⁻¹ r on owned parts.
///
/// Collective: every rank applies its preconditioner together (an implementation may
/// communicate, e.g. [`RestrictedSchwarz`] gathers r on its overlap).
pub trait Preconditioner {
    fn apply(&self, comm: &dyn Comm, r: &[f64], z: &mut [f64]);
}

/// Which preconditioner the Krylov solves use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PcKind {
    /// None: z = r.
    None,
    /// Block Jacobi ([`BlockJacobi`]): each rank's diagonal block factored exactly.
    #[default]
    BlockJacobi,
    /// Restricted additive Schwarz with one layer of overlap ([`RestrictedSchwarz`]).
    Asm,
}

/// No preconditioning: z = r.
#[derive(Debug, Default, Clone, Copy)]
pub struct Identity;

impl Preconditioner for Identity {
    fn apply(&self, _comm: &dyn Comm, r: &[f64], z: &mut [f64]) {
        z.copy_from_slice(r);
    }
}
