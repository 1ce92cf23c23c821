//! The solver context (PETSc's SNES): one object holding what every nonlinear method
//! works with — the problem and its iterate, the constraints, the Jacobian's storage and
//! the preconditioner, the options, the convergence monitor and the counters with the
//! typed failure reason ([`SolveStats`]). The iteration loop, the convergence test, the
//! Jacobian assembly, the preconditioned linear solve and the line search are written
//! once here; a method ([`NonlinearSolver`]: Newton, BFGS, JFNK) provides only its step.

use super::common::{Constraints, Eval, Monitor, Verdict};
use super::{Failure, NonlinearOptions, NonlinearProblem, Preconditioning, SolveStats};
use crate::linalg::gmres::{gmres, GmresStats};
use crate::linalg::matrix::DistMatrix;
use crate::parallel::Comm;
use crate::{ErrorKind, Result};
use std::time::Instant;

/// What persists across the solves of a run (PETSc's SNES between two `SNESSolve`s):
/// the options, the Jacobian's storage (pattern fixed) and the preconditioner, whose
/// factorization may be kept from one step to the next (its lag).
pub struct Solver<'o> {
    pub opts: &'o NonlinearOptions,
    pub k: DistMatrix,
    pub pc: Preconditioning,
}

impl<'o> Solver<'o> {
    pub fn new(opts: &'o NonlinearOptions, k: DistMatrix, pc: Preconditioning) -> Self {
        Self { opts, k, pc }
    }

    /// Solve one load step with the method of `opts.kind`: r(u) = 0 on the free dofs
    /// with u_c = g on `prescribed` (owned local dof, value). `u` holds the start point
    /// and receives the solution; `r` the final residual. Non-convergence is `Ok` with
    /// `converged = false`; only runtime failures are `Err`.
    pub fn solve(
        &mut self,
        comm: &dyn Comm,
        problem: &mut dyn NonlinearProblem,
        u: &mut [f64],
        r: &mut [f64],
        prescribed: &[(usize, f64)],
    ) -> Result<SolveStats> {
        let mut method = self.opts.kind.method(u.len(), self.opts);
        let mut cx = SolverContext::new(comm, self, problem, u, r, prescribed);
        cx.run(method.as_mut())?;
        Ok(cx.stats)
    }
}

/// What a method's iteration leads to.
pub enum Next {
    /// A new accepted point (`u`, `r` hold it): its evaluation.
    Moved(Eval),
    /// The iteration was discarded (`u`, `r` back at the last point): test it again.
    Again,
    /// The iteration failed; the reason is in the statistics.
    Stop,
}

impl From<Option<Eval>> for Next {
    fn from(e: Option<Eval>) -> Self {
        e.map_or(Next::Stop, Next::Moved)
    }
}

/// One nonlinear method over the shared [`SolverContext`] (PETSc's SNES ops table).
pub trait NonlinearSolver {
    /// Before the first residual evaluation. `Ok(false)`: failed (reason set).
    fn setup(&mut self, _cx: &mut SolverContext) -> Result<bool> {
        Ok(true)
    }
    /// One iteration from the current point, whose evaluation is `ev` (not converged).
    fn iterate(&mut self, cx: &mut SolverContext, ev: &Eval) -> Result<Next>;
    /// After the solve, whatever its outcome (errors included).
    fn finish(&mut self, _cx: &mut SolverContext) {}
}

/// One nonlinear solve (one load step attempt): r(u) = 0 on the free dofs with u_c = g
/// on the prescribed ones.
pub struct SolverContext<'a> {
    pub comm: &'a dyn Comm,
    pub problem: &'a mut dyn NonlinearProblem,
    /// The iterate: the start point on entry, the solution on return.
    pub u: &'a mut [f64],
    /// The residual at `u`.
    pub r: &'a mut [f64],
    pub cons: Constraints<'a>,
    /// The Jacobian's storage.
    pub k: &'a mut DistMatrix,
    pub pc: &'a mut Preconditioning,
    pub opts: &'a NonlinearOptions,
    pub monitor: Monitor,
    pub stats: SolveStats,
    /// The force scale of the divergence test: max(‖r‖, f_ref) at the start point.
    scale: f64,
}

impl<'a> SolverContext<'a> {
    /// A solve from `u` with u_c = g on `prescribed` (owned local dof, value), its
    /// residual written to `r`.
    pub fn new(
        comm: &'a dyn Comm,
        solver: &'a mut Solver<'_>,
        problem: &'a mut dyn NonlinearProblem,
        u: &'a mut [f64],
        r: &'a mut [f64],
        prescribed: &'a [(usize, f64)],
    ) -> Self {
        let cons = Constraints::new(u.len(), prescribed);
        Self {
            comm,
            problem,
            u,
            r,
            cons,
            k: &mut solver.k,
            pc: &mut solver.pc,
            opts: solver.opts,
            monitor: Monitor::default(),
            stats: SolveStats::default(),
            scale: 0.0,
        }
    }

    /// Number of owned dofs.
    pub fn n(&self) -> usize {
        self.u.len()
    }

    /// Run `method` to convergence or failure. Non-convergence is `Ok` with
    /// `converged = false` in the statistics; only runtime failures are `Err`.
    pub fn run(&mut self, method: &mut dyn NonlinearSolver) -> Result<()> {
        let out = self.iterate_with(method);
        method.finish(self);
        out
    }

    fn iterate_with(&mut self, method: &mut dyn NonlinearSolver) -> Result<()> {
        if !method.setup(self)? {
            return Ok(());
        }
        let Some(mut ev) = self.evaluate()? else {
            return Ok(());
        };
        self.scale = ev.rn.max(ev.f_ref);
        self.stats.residual_history.push(ev.relative());
        loop {
            let it = self.stats.iterations;
            match self.monitor.verdict(&ev, it, self.scale, self.opts) {
                Verdict::Converged => {
                    self.stats.converged = true;
                    return Ok(());
                }
                Verdict::Fail(kind, why) => {
                    self.stats.fail(kind, why);
                    return Ok(());
                }
                Verdict::Continue => {}
            }
            match method.iterate(self, &ev)? {
                Next::Moved(next) => {
                    ev = next;
                    self.stats.residual_history.push(ev.relative());
                }
                Next::Again => {}
                Next::Stop => return Ok(()),
            }
        }
    }

    /// Evaluate r(u). `Ok(None)` means the residual could not be evaluated (an inverted
    /// element): a failed iteration, with the reason left in the statistics.
    pub fn evaluate(&mut self) -> Result<Option<Eval>> {
        let (u, r, st) = (&*self.u, &mut *self.r, &mut self.stats);
        let t0 = Instant::now();
        let f_ref = match self.problem.residual(self.comm, u, r) {
            Ok(f) => f,
            Err(e) if e.kind == ErrorKind::Convergence => {
                st.fail(Failure::Element, e.message);
                st.seconds_assembly += t0.elapsed().as_secs_f64();
                return Ok(None);
            }
            Err(e) => return Err(e),
        };
        st.seconds_assembly += t0.elapsed().as_secs_f64();
        st.residual_evaluations += 1;
        let mut sums = [0.0, 0.0, 0.0];
        for i in 0..u.len() {
            if !self.cons.is_c[i] {
                sums[0] += r[i] * r[i];
            }
            sums[2] += u[i] * u[i];
        }
        for &(d, g) in self.cons.prescribed {
            sums[1] += (g - u[d]).powi(2);
        }
        self.comm.allreduce_sum(&mut sums);
        Ok(Some(Eval {
            rn: sums[0].sqrt(),
            f_ref,
            gap: sums[1].sqrt(),
            un: sums[2].sqrt(),
        }))
    }

    /// Assemble the unconstrained Jacobian at `u` into `k`. `Ok(false)`: an element
    /// could not be evaluated (reason set).
    pub fn jacobian(&mut self) -> Result<bool> {
        match self.problem.jacobian(self.comm, self.u, self.k) {
            Ok(()) => Ok(true),
            Err(e) if e.kind == ErrorKind::Convergence => {
                self.stats.fail(Failure::Element, e.message);
                Ok(false)
            }
            Err(e) => Err(e),
        }
    }

    /// With the Jacobian assembled and not yet constrained: `gap` = g − u_c (zero on the
    /// free dofs) and `kd` = K (g − u_c), the coupling of a pending prescribed increment
    /// (zero without one: `ev.gap == 0`).
    pub fn coupling(&mut self, ev: &Eval, gap: &mut [f64], kd: &mut [f64]) {
        self.cons.gap_vector(self.u, gap);
        if ev.gap > 0.0 {
            self.k.spmv(self.comm, gap, kd);
        } else {
            kd.iter_mut().for_each(|x| *x = 0.0);
        }
    }

    /// Impose the constraints on the Jacobian (identity rows and columns).
    pub fn constrain(&mut self) {
        self.k.constrain(self.comm, &self.cons.dofs);
    }

    /// Set the preconditioner up on `k` as its lag says. `Some(factored)`, or `None`:
    /// failed (reason set).
    fn update_preconditioner(&mut self) -> Option<bool> {
        let s0 = self.pc.seconds_setup;
        let res = self.pc.update(self.comm, self.k);
        self.stats.seconds_pc_setup += self.pc.seconds_setup - s0;
        self.stats.coarse = self.pc.coarse.or(self.stats.coarse);
        match res {
            Ok(f) => {
                self.stats.factorizations += f as usize;
                Some(f)
            }
            Err(e) => {
                self.stats.fail(Failure::LinearSolver, e);
                None
            }
        }
    }

    /// Set the preconditioner up afresh on the constrained `k` (timed as linear-solve
    /// time). `false`: failed (reason set).
    pub fn refactor(&mut self) -> bool {
        let t = Instant::now();
        self.pc.invalidate();
        let ok = self.update_preconditioner().is_some();
        self.stats.seconds_linear += t.elapsed().as_secs_f64();
        ok
    }

    /// Solve `k x = b` by GMRES preconditioned by `pc` set up on `k` (or kept from an
    /// earlier one, as its policy says); a kept factorization under which GMRES fails is
    /// refreshed once. `x` holds the initial guess. `Ok(None)`: failed (reason set).
    pub fn linear_solve(&mut self, b: &[f64], x: &mut [f64]) -> Result<Option<GmresStats>> {
        let t = Instant::now();
        let x0 = x.to_vec();
        let factored = self.pc.is_factored();
        let mut fresh = false;
        let out = loop {
            if factored {
                match self.update_preconditioner() {
                    Some(f) => fresh |= f,
                    None => break None,
                }
            }
            let mut op: &DistMatrix = self.k;
            let gs = gmres(self.comm, &mut op, self.pc.get(), b, x, &self.opts.linear)?;
            self.stats.linear_iterations += gs.iterations;
            if gs.converged {
                break Some(gs);
            }
            // Inexact Newton (Eisenstat–Walker) only needs ‖r_lin‖ ≤ η ‖b‖ with η < 1: a
            // solve that stalls at the attainable accuracy of an ill-conditioned system
            // (nearly incompressible: K/μ ~ 1e4) is still an excellent correction.
            if gs.residual_norm <= ACCEPTABLE_LINEAR_RESIDUAL * gs.rhs_norm {
                break Some(gs);
            }
            if fresh || !factored {
                self.stats.fail(
                    Failure::LinearSolver,
                    format!(
                        "GMRES did not converge in {} iterations (relative residual {:.3e})",
                        gs.iterations,
                        gs.residual_norm / gs.rhs_norm.max(f64::MIN_POSITIVE)
                    ),
                );
                break None;
            }
            self.pc.invalidate();
            x.copy_from_slice(&x0);
        };
        self.stats.seconds_linear += t.elapsed().as_secs_f64();
        Ok(out)
    }

    /// Backtracking line search on ‖r_free‖ along `du` from `u` (whose residual norm is
    /// `rn0`): step lengths 1, ½, ¼, ... until ‖r(u + λ du)‖ ≤ (1 − 10⁻⁴ λ) ‖r(u)‖
    /// (Armijo, Dennis & Schnabel §6.3), at most `max_halvings` times. On return `u`
    /// holds the accepted point, `r` its residual, and the result its evaluation and λ;
    /// if no length is accepted the smallest is taken (the convergence test decides).
    pub fn line_search(
        &mut self,
        du: &[f64],
        rn0: f64,
        max_halvings: usize,
    ) -> Result<Option<(Eval, f64)>> {
        let base = self.u.to_vec();
        let mut lambda = 1.0;
        for k in 0..=max_halvings {
            for i in 0..self.u.len() {
                self.u[i] = base[i] + lambda * du[i];
            }
            let ev = self.evaluate()?;
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

    /// Take the correction `du` from `u` (residual `r`, evaluation `ev`): the
    /// backtracking line search if asked for, else the full step, halved while it cannot
    /// be evaluated (an inverted element; prescribed values always land in full), then
    /// record it in the monitor. On return `u` and `r` hold the new point; `Ok(None)`: it
    /// could not be evaluated (reason set).
    pub fn take_step(&mut self, du: &[f64], ev: &Eval) -> Result<Option<Eval>> {
        let measured = Monitor::measure(self.comm, du, self.r, &self.cons.is_c);
        let (next, lambda) = if self.opts.line_search && ev.gap == 0.0 {
            match self.line_search(du, ev.rn, 6)? {
                Some(x) => x,
                None => return Ok(None),
            }
        } else {
            let base = self.u.to_vec();
            let mut lambda = 1.0;
            loop {
                // On the iteration that imposes a prescribed increment (a moving wall's
                // reference point, a displacement boundary condition) the prescribed
                // values land in full; only the free unknowns' part is shortened.
                for (i, ((x, b), d)) in self.u.iter_mut().zip(&base).zip(du).enumerate() {
                    let s = if ev.gap > 0.0 && self.cons.is_c[i] {
                        1.0
                    } else {
                        lambda
                    };
                    *x = b + s * d;
                }
                match self.evaluate()? {
                    Some(e) => break (e, lambda),
                    // A full step that inverts an element (a nearly incompressible body
                    // overshooting, a thin wall folding) is shortened, not fatal: halve
                    // it up to 5 times.
                    None if lambda > 0.05 => lambda *= 0.5,
                    None => return Ok(None),
                }
            }
        };
        self.monitor.record(measured, lambda);
        Ok(Some(next))
    }
}

/// A linear solve that missed its tolerance but reached this relative residual is
/// still used as the Newton correction.
pub const ACCEPTABLE_LINEAR_RESIDUAL: f64 = 1e-6;
