//! Nonlinear solvers behind one seam. A [`NonlinearProblem`] gives residuals and
//! Jacobians on owned dofs; the solver owns the constraint algebra (prescribed dofs),
//! the linear solves and the convergence tests.

pub mod newton;

use crate::parallel::Comm;
use crate::solve::linear::matrix::DistMatrix;
use crate::Result;

pub trait NonlinearProblem {
    /// r(u) on owned dofs (rows of constrained dofs hold reactions) and the force
    /// scale f_ref that relative residual tolerances refer to.
    fn residual(&mut self, comm: &dyn Comm, u: &[f64], r: &mut [f64]) -> Result<f64>;
    /// The unconstrained Jacobian ∂r/∂u at u, assembled into `k` (pattern fixed).
    fn jacobian(&mut self, comm: &dyn Comm, u: &[f64], k: &mut DistMatrix) -> Result<()>;
}

/// Statistics of one nonlinear solve (one load step attempt).
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct SolveStats {
    pub converged: bool,
    /// Nonlinear iterations (linear solves).
    pub iterations: usize,
    pub linear_iterations: usize,
    pub residual_evaluations: usize,
    pub factorizations: usize,
    /// ‖r_free‖ / f_ref at every evaluation.
    pub residual_history: Vec<f64>,
    /// Why it stopped when it did not converge.
    pub reason: String,
    pub seconds_assembly: f64,
    pub seconds_linear: f64,
}
