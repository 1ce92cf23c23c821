//! Full Newton with the assembled (generalized) Jacobian at every iteration and GMRES +
//! block Jacobi inner solves (the factorization refreshed per iteration unless lagged).
//!
//! Convergence: residual, increment and energy tests together ([`super::common::Monitor`]);
//! a zero residual at the start of a step needs no correction.
//! Prescribed dofs: each linear solve imposes Δu_c = g − u_c exactly and moves the
//! coupling −K_fc (g − u_c) to the right-hand side, so a large prescribed increment is
//! linearised consistently instead of being forced into the first residual.

use super::common::{evaluate, precond_solve, take_step, Constraints, Monitor, Verdict};
use super::Preconditioning;
use super::{Failure, NonlinearOptions, NonlinearProblem, SolveStats};
use crate::linalg::matrix::DistMatrix;
use crate::parallel::Comm;
use crate::{ErrorKind, Result};
use std::time::Instant;

/// The run's first linear system was written ([`NonlinearOptions::export_system`]).
static EXPORTED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

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
    pc: &mut Preconditioning,
    opts: &NonlinearOptions,
) -> Result<SolveStats> {
    let n = u.len();
    let mut st = SolveStats::default();
    let cons = Constraints::new(n, prescribed);
    let mut du = vec![0.0; n];
    let mut rhs = vec![0.0; n];
    let mut kd = vec![0.0; n];
    let Some(mut ev) = evaluate(comm, problem, u, r, &cons, &mut st)? else {
        return Ok(st);
    };
    let scale = ev.rn.max(ev.f_ref);
    let mut monitor = Monitor::default();
    for it in 0.. {
        st.residual_history.push(ev.relative());
        match monitor.verdict(&ev, it, scale, opts) {
            Verdict::Converged => {
                st.converged = true;
                return Ok(st);
            }
            Verdict::Fail(kind, why) => {
                st.fail(kind, why);
                return Ok(st);
            }
            Verdict::Continue => {}
        }
        // Jacobian and the linear solve K Δu = −r with Δu_c = g − u_c.
        let t1 = Instant::now();
        match problem.jacobian(comm, u, k) {
            Ok(()) => {}
            Err(e) if e.kind == ErrorKind::Convergence => {
                st.fail(Failure::Element, e.message);
                return Ok(st);
            }
            Err(e) => return Err(e),
        }
        cons.gap_vector(u, &mut du);
        if ev.gap > 0.0 {
            k.spmv(comm, &du, &mut kd);
        } else {
            kd.iter_mut().for_each(|x| *x = 0.0);
        }
        for i in 0..n {
            rhs[i] = if cons.is_c[i] { du[i] } else { -r[i] - kd[i] };
        }
        k.constrain(comm, &cons.dofs);
        st.seconds_assembly += t1.elapsed().as_secs_f64();
        let export = match &opts.export_system {
            Some(dir) if !EXPORTED.swap(true, std::sync::atomic::Ordering::Relaxed) => {
                crate::linalg::export::write_petsc(comm, dir, k, &rhs, pc.points())?;
                Some((dir, st.clone()))
            }
            _ => None,
        };
        let kref: &DistMatrix = k;
        let mut op = kref;
        let solved = precond_solve(
            comm,
            &mut op,
            kref,
            pc,
            &rhs,
            &mut du,
            &opts.linear,
            &mut st,
        )?;
        if let (Some((dir, before)), Some(gs)) = (export, &solved) {
            // This very solve's cost, for the peers that solve the written system.
            let setup = st.seconds_pc_setup - before.seconds_pc_setup;
            let total = st.seconds_linear - before.seconds_linear;
            let mut t = [setup, total];
            comm.allreduce_max(&mut t);
            crate::linalg::export::write_alfe_solve(
                comm,
                dir,
                opts.preconditioner.name(),
                t[0],
                t[1] - t[0],
                gs.iterations,
                gs.residual_norm / gs.rhs_norm.max(f64::MIN_POSITIVE),
            )?;
        }
        if solved.is_none() {
            return Ok(st);
        }
        st.iterations += 1;
        match take_step(
            comm,
            problem,
            u,
            r,
            &du,
            &ev,
            &cons,
            opts.line_search,
            &mut monitor,
            &mut st,
        )? {
            Some(next) => ev = next,
            None => return Ok(st),
        }
    }
    unreachable!("the loop returns")
}
