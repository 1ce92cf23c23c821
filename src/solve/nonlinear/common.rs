//! What the nonlinear solvers share: the constraint algebra, the convergence test, the
//! preconditioned linear solve with a (lagged) block-Jacobi factorization, and the
//! backtracking line search on ‖r_free‖.

use super::{NonlinearOptions, NonlinearProblem, SolveStats};
use crate::parallel::Comm;
use crate::solve::linear::gmres::{gmres, GmresOptions, GmresStats};
use crate::solve::linear::lagged::LaggedBlockJacobi;
use crate::solve::linear::{Identity, LinearOperator, Preconditioner};
use crate::{ErrorKind, Result};
use std::time::Instant;

/// A step that makes the residual this many times larger than the step's force scale
/// has diverged.
pub const DIVERGENCE_FACTOR: f64 = 1e8;

/// The prescribed dofs of a step: owned local dof → target value.
pub struct Constraints<'a> {
    pub prescribed: &'a [(usize, f64)],
    pub is_c: Vec<bool>,
    pub dofs: Vec<usize>,
}

impl<'a> Constraints<'a> {
    pub fn new(n: usize, prescribed: &'a [(usize, f64)]) -> Self {
        let mut is_c = vec![false; n];
        for &(d, _) in prescribed {
            is_c[d] = true;
        }
        Self {
            prescribed,
            is_c,
            dofs: prescribed.iter().map(|p| p.0).collect(),
        }
    }
    /// g − u on the constrained dofs, zero elsewhere.
    pub fn gap_vector(&self, u: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|x| *x = 0.0);
        for &(d, g) in self.prescribed {
            out[d] = g - u[d];
        }
    }
    /// Zero the constrained entries (project onto the free dofs).
    pub fn zero_constrained(&self, v: &mut [f64]) {
        for &d in &self.dofs {
            v[d] = 0.0;
        }
    }
}

/// One residual evaluation with the norms every solver needs (one extra reduction).
#[derive(Debug, Clone, Copy)]
pub struct Eval {
    /// ‖r‖ over the free dofs.
    pub rn: f64,
    pub f_ref: f64,
    /// ‖g − u_c‖ over the constrained dofs.
    pub gap: f64,
    /// ‖u‖.
    pub un: f64,
}

impl Eval {
    pub fn relative(&self) -> f64 {
        if self.f_ref > 0.0 {
            self.rn / self.f_ref
        } else {
            self.rn
        }
    }
}

/// Evaluate r(u). `Ok(None)` means the residual could not be evaluated (an inverted
/// element): a failed iteration, with the reason left in `st.reason`.
pub fn evaluate(
    comm: &dyn Comm,
    problem: &mut dyn NonlinearProblem,
    u: &[f64],
    r: &mut [f64],
    cons: &Constraints,
    st: &mut SolveStats,
) -> Result<Option<Eval>> {
    let t0 = Instant::now();
    let f_ref = match problem.residual(comm, u, r) {
        Ok(f) => f,
        Err(e) if e.kind == ErrorKind::Convergence => {
            st.reason = e.message;
            st.seconds_assembly += t0.elapsed().as_secs_f64();
            return Ok(None);
        }
        Err(e) => return Err(e),
    };
    st.seconds_assembly += t0.elapsed().as_secs_f64();
    st.residual_evaluations += 1;
    let mut sums = [0.0, 0.0, 0.0];
    for i in 0..u.len() {
        if !cons.is_c[i] {
            sums[0] += r[i] * r[i];
        }
        sums[2] += u[i] * u[i];
    }
    for &(d, g) in cons.prescribed {
        sums[1] += (g - u[d]).powi(2);
    }
    comm.allreduce_sum(&mut sums);
    Ok(Some(Eval {
        rn: sums[0].sqrt(),
        f_ref,
        gap: sums[1].sqrt(),
        un: sums[2].sqrt(),
    }))
}

/// What to do after an evaluation.
pub enum Verdict {
    Converged,
    Continue,
    Fail(String),
}

/// The convergence test (module doc of `newton`): residual and last correction small,
/// prescribed values reached; divergence, non-finite values and the budget end it.
pub fn verdict(ev: &Eval, it: usize, last_du: f64, scale: f64, opts: &NonlinearOptions) -> Verdict {
    let small_r = ev.rn <= opts.residual_rtol * ev.f_ref;
    let small_du = it == 0 || last_du <= opts.increment_rtol * ev.un;
    if small_r && small_du && ev.gap == 0.0 {
        return Verdict::Converged;
    }
    if !ev.rn.is_finite() {
        return Verdict::Fail("the residual is not finite".into());
    }
    if it > 0 && scale > 0.0 && ev.rn > DIVERGENCE_FACTOR * scale {
        return Verdict::Fail(format!(
            "diverged: residual grew to {:.3e} (force scale {scale:.3e})",
            ev.rn
        ));
    }
    if it >= opts.max_iterations {
        return Verdict::Fail(format!(
            "no convergence in {} iterations (relative residual {:.3e})",
            opts.max_iterations,
            ev.relative()
        ));
    }
    Verdict::Continue
}

/// Solve `a x = b` by GMRES preconditioned with the (possibly kept) block-Jacobi
/// factorization in `pc` of the matrix `pc_of`; a kept factorization under which GMRES
/// fails is refreshed once. `x` holds the initial guess. `Ok(None)`: failed (reason set).
#[allow(clippy::too_many_arguments)]
pub fn precond_solve(
    comm: &dyn Comm,
    a: &mut dyn LinearOperator,
    pc_of: &crate::solve::linear::matrix::DistMatrix,
    pc: &mut LaggedBlockJacobi,
    b: &[f64],
    x: &mut [f64],
    lin: &GmresOptions,
    block_jacobi: bool,
    st: &mut SolveStats,
) -> Result<Option<GmresStats>> {
    let t = Instant::now();
    let x0 = x.to_vec();
    let mut fresh = false;
    let out = loop {
        if block_jacobi {
            match pc.update(comm, pc_of) {
                Ok(f) => {
                    fresh |= f;
                    st.factorizations += f as usize;
                }
                Err(e) => {
                    st.reason = e;
                    break None;
                }
            }
        }
        let prec: &dyn Preconditioner = match (block_jacobi, pc.get()) {
            (true, Some(p)) => p,
            _ => &Identity,
        };
        let gs = gmres(comm, a, prec, b, x, lin)?;
        st.linear_iterations += gs.iterations;
        if gs.converged {
            break Some(gs);
        }
        if fresh || !block_jacobi {
            st.reason = format!(
                "GMRES did not converge in {} iterations (relative residual {:.3e})",
                gs.iterations,
                gs.residual_norm / gs.rhs_norm.max(f64::MIN_POSITIVE)
            );
            break None;
        }
        pc.invalidate();
        x.copy_from_slice(&x0);
    };
    st.seconds_linear += t.elapsed().as_secs_f64();
    Ok(out)
}

/// Backtracking line search on ‖r_free‖ along `du` from `u` (whose residual norm is
/// `rn0`): step lengths 1, ½, ¼, ... until ‖r(u + λ du)‖ ≤ (1 − 10⁻⁴ λ) ‖r(u)‖ (Armijo,
/// Dennis & Schnabel §6.3), at most `max_halvings` times. On return `u` holds the
/// accepted point, `r` its residual, and the result its evaluation and λ; if no
/// length is accepted the smallest is taken (the convergence test then decides).
#[allow(clippy::too_many_arguments)]
pub fn line_search(
    comm: &dyn Comm,
    problem: &mut dyn NonlinearProblem,
    u: &mut [f64],
    r: &mut [f64],
    du: &[f64],
    rn0: f64,
    cons: &Constraints,
    max_halvings: usize,
    st: &mut SolveStats,
) -> Result<Option<(Eval, f64)>> {
    let base = u.to_vec();
    let mut lambda = 1.0;
    for k in 0..=max_halvings {
        for i in 0..u.len() {
            u[i] = base[i] + lambda * du[i];
        }
        let ev = evaluate(comm, problem, u, r, cons, st)?;
        if let Some(ev) = ev {
            if ev.rn <= (1.0 - 1e-4 * lambda) * rn0 || k == max_halvings {
                return Ok(Some((ev, lambda)));
            }
        } else if k == max_halvings {
            return Ok(None);
        }
        lambda *= 0.5;
    }
    unreachable!()
}
