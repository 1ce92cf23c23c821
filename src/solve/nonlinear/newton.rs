//! Full Newton with the assembled (generalized) Jacobian at every iteration and GMRES +
//! block Jacobi inner solves (the factorization refreshed per iteration unless lagged).
//!
//! Convergence: residual, increment and energy tests together ([`super::common::Monitor`]);
//! a zero residual at the start of a step needs no correction.
//! Prescribed dofs hold their values before the first residual (the solver context's
//! predictor), so every correction has Δu_c = 0.

use super::common::Eval;
use super::context::{Next, NonlinearSolver, SolverContext};
use super::SolveStats;
use crate::linalg::gmres::GmresStats;
use crate::Result;
use std::path::PathBuf;
use std::time::Instant;

/// The run's first linear system was written ([`super::NonlinearOptions::export_system`]).
static EXPORTED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Newton's method: its work vectors.
pub struct Newton {
    du: Vec<f64>,
    rhs: Vec<f64>,
}

impl Newton {
    /// For `n` owned dofs.
    pub fn new(n: usize) -> Self {
        Self {
            du: vec![0.0; n],
            rhs: vec![0.0; n],
        }
    }
}

impl NonlinearSolver for Newton {
    fn iterate(&mut self, cx: &mut SolverContext, ev: &Eval) -> Result<Next> {
        // Jacobian and the linear solve K Δu = −r with Δu_c = 0.
        let t1 = Instant::now();
        if !cx.jacobian()? {
            return Ok(Next::Stop);
        }
        for i in 0..cx.n() {
            self.rhs[i] = if cx.cons.is_c[i] { 0.0 } else { -cx.r[i] };
        }
        self.du.iter_mut().for_each(|x| *x = 0.0);
        cx.constrain();
        cx.stats.seconds_assembly += t1.elapsed().as_secs_f64();
        let export = export_system(cx, &self.rhs)?;
        let solved = cx.linear_solve(&self.rhs, &mut self.du)?;
        if let (Some((dir, before)), Some(gs)) = (export, &solved) {
            export_solve(cx, &dir, &before, gs)?;
        }
        if solved.is_none() {
            return Ok(Next::Stop);
        }
        cx.stats.iterations += 1;
        Ok(cx.take_step(&self.du, ev)?.into())
    }
}

/// Write the run's first linear system if asked for ([`crate::linalg::export`]): the
/// folder and the statistics before its solve.
fn export_system(cx: &SolverContext, rhs: &[f64]) -> Result<Option<(PathBuf, SolveStats)>> {
    match &cx.opts.export_system {
        Some(dir) if !EXPORTED.swap(true, std::sync::atomic::Ordering::Relaxed) => {
            crate::linalg::export::write_petsc(cx.comm, dir, cx.k, rhs, cx.pc.points())?;
            Ok(Some((dir.clone(), cx.stats.clone())))
        }
        _ => Ok(None),
    }
}

/// The exported system's solve: this very solve's cost, for the peers that solve it.
fn export_solve(
    cx: &SolverContext,
    dir: &std::path::Path,
    before: &SolveStats,
    gs: &GmresStats,
) -> Result<()> {
    let setup = cx.stats.seconds_pc_setup - before.seconds_pc_setup;
    let total = cx.stats.seconds_linear - before.seconds_linear;
    let mut t = [setup, total];
    cx.comm.allreduce_max(&mut t);
    crate::linalg::export::write_alfe_solve(
        cx.comm,
        dir,
        cx.opts.preconditioner.name(),
        t[0],
        t[1] - t[0],
        gs.iterations,
        gs.residual_norm / gs.rhs_norm.max(f64::MIN_POSITIVE),
    )
}
