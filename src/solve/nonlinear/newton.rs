//! Full Newton with the assembled Jacobian, GMRES + block Jacobi inner solves.
//!
//! Convergence (both): ‖r_free‖ ≤ residual_rtol · f_ref and ‖Δu‖ ≤ increment_rtol · ‖u‖
//! for the last correction (a zero residual at the start of a step needs no correction).
//! Prescribed dofs: each linear solve imposes Δu_c = g − u_c exactly and moves the
//! coupling −K_fc (g − u_c) to the right-hand side, so a large prescribed increment is
//! linearised consistently instead of being forced into the first residual.

use super::{NonlinearProblem, SolveStats};
use crate::parallel::Comm;
use crate::solve::linear::gmres::{gmres, GmresOptions};
use crate::solve::linear::lagged::LaggedBlockJacobi;
use crate::solve::linear::matrix::DistMatrix;
use crate::solve::linear::{Identity, Preconditioner};
use crate::{ErrorKind, Result};
use std::time::Instant;

#[derive(Debug, Clone)]
pub struct NewtonOptions {
    pub max_iterations: usize,
    pub residual_rtol: f64,
    pub increment_rtol: f64,
    pub linear: GmresOptions,
    pub block_jacobi: bool,
    /// Newton iterations a block-Jacobi factorization is kept for before the next one
    /// (0 = refactor at every iteration; it is also kept across load steps).
    pub pc_lag: usize,
}

/// A step that makes the residual this many times larger than at the start has diverged.
const DIVERGENCE_FACTOR: f64 = 1e8;

/// Solve r(u) = 0 on the free dofs with u_c = g on `prescribed` (owned local dof, value).
/// `u` holds the start point and receives the solution; `r` the final residual.
/// Non-convergence is `Ok` with `converged = false`; only runtime failures are `Err`.
#[allow(clippy::too_many_arguments)]
pub fn newton(
    comm: &dyn Comm,
    problem: &mut dyn NonlinearProblem,
    u: &mut [f64],
    r: &mut [f64],
    prescribed: &[(usize, f64)],
    k: &mut DistMatrix,
    pc: &mut LaggedBlockJacobi,
    opts: &NewtonOptions,
) -> Result<SolveStats> {
    let n = u.len();
    let mut st = SolveStats::default();
    let mut is_c = vec![false; n];
    for &(d, _) in prescribed {
        is_c[d] = true;
    }
    let cdofs: Vec<usize> = prescribed.iter().map(|p| p.0).collect();
    let mut du = vec![0.0; n];
    let mut rhs = vec![0.0; n];
    let mut kd = vec![0.0; n];
    let mut last_du = f64::INFINITY;
    let mut first = f64::NAN;
    for it in 0..=opts.max_iterations {
        let t0 = Instant::now();
        let f_ref = match problem.residual(comm, u, r) {
            Ok(f) => f,
            Err(e) if e.kind == ErrorKind::Convergence => {
                st.reason = e.message;
                return Ok(st);
            }
            Err(e) => return Err(e),
        };
        st.seconds_assembly += t0.elapsed().as_secs_f64();
        st.residual_evaluations += 1;
        // Free residual and the gap to the prescribed values (one reduction for both).
        let mut sums = [0.0, 0.0, 0.0];
        for i in 0..n {
            if !is_c[i] {
                sums[0] += r[i] * r[i];
            }
            sums[2] += u[i] * u[i];
        }
        for &(d, g) in prescribed {
            sums[1] += (g - u[d]).powi(2);
        }
        comm.allreduce_sum(&mut sums);
        let (rn, gap, un) = (sums[0].sqrt(), sums[1].sqrt(), sums[2].sqrt());
        let rel = if f_ref > 0.0 { rn / f_ref } else { rn };
        st.residual_history.push(rel);
        // Divergence is judged against the first non-trivial scale of the step (a step
        // driven only by prescribed displacements starts from a zero residual).
        if first.is_nan() && rn.max(f_ref) > 0.0 {
            first = rn.max(f_ref);
        }
        let small_r = rn <= opts.residual_rtol * f_ref;
        let small_du = if it == 0 {
            true
        } else {
            last_du <= opts.increment_rtol * un
        };
        if small_r && small_du && gap == 0.0 {
            st.converged = true;
            return Ok(st);
        }
        if !rn.is_finite() {
            st.reason = "the residual is not finite".into();
            return Ok(st);
        }
        if it > 0 && !first.is_nan() && rn > DIVERGENCE_FACTOR * first {
            st.reason = format!("diverged: residual grew from {first:.3e} to {rn:.3e}");
            return Ok(st);
        }
        if it == opts.max_iterations {
            st.reason = format!(
                "no convergence in {} iterations (relative residual {rel:.3e})",
                opts.max_iterations
            );
            return Ok(st);
        }
        // Jacobian and the linear solve K Δu = −r with Δu_c = g − u_c.
        let t1 = Instant::now();
        match problem.jacobian(comm, u, k) {
            Ok(()) => {}
            Err(e) if e.kind == ErrorKind::Convergence => {
                st.reason = e.message;
                return Ok(st);
            }
            Err(e) => return Err(e),
        }
        du.iter_mut().for_each(|x| *x = 0.0);
        for &(d, g) in prescribed {
            du[d] = g - u[d];
        }
        if gap > 0.0 {
            k.spmv(comm, &du, &mut kd);
        } else {
            kd.iter_mut().for_each(|x| *x = 0.0);
        }
        for i in 0..n {
            rhs[i] = if is_c[i] { du[i] } else { -r[i] - kd[i] };
        }
        k.constrain(comm, &cdofs);
        st.seconds_assembly += t1.elapsed().as_secs_f64();
        let t2 = Instant::now();
        let x0 = du.clone();
        let mut gs;
        let mut fresh = false;
        loop {
            if opts.block_jacobi {
                match pc.update(comm, k) {
                    Ok(f) => {
                        fresh |= f;
                        st.factorizations += f as usize;
                    }
                    Err(e) => {
                        st.reason = e;
                        return Ok(st);
                    }
                }
            }
            let prec: &dyn Preconditioner = match (opts.block_jacobi, pc.get()) {
                (true, Some(p)) => p,
                _ => &Identity,
            };
            gs = gmres(comm, k, prec, &rhs, &mut du, &opts.linear)?;
            // A kept (lagged) factorization that no longer helps GMRES is refreshed once.
            if gs.converged || fresh || !opts.block_jacobi {
                break;
            }
            st.linear_iterations += gs.iterations;
            pc.invalidate();
            du.copy_from_slice(&x0);
        }
        st.seconds_linear += t2.elapsed().as_secs_f64();
        st.linear_iterations += gs.iterations;
        st.iterations += 1;
        if !gs.converged {
            st.reason = format!(
                "GMRES did not converge in {} iterations (relative residual {:.3e})",
                gs.iterations,
                gs.residual_norm / gs.rhs_norm.max(f64::MIN_POSITIVE)
            );
            return Ok(st);
        }
        for i in 0..n {
            u[i] += du[i];
        }
        last_du = comm.norm2(&du);
    }
    unreachable!("the loop returns at max_iterations")
}
