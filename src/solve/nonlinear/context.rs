//! The solver context (PETSc's SNES): one object holding what every nonlinear method
//! works with — the problem and its iterate, the constraints, the Jacobian's storage and
//! the preconditioner, the options, the convergence monitor and the counters with the
//! typed failure reason ([`SolveStats`]). The iteration loop, the convergence test, the
//! Jacobian assembly, the preconditioned linear solve and the line search are written
//! once here; a method ([`NonlinearSolver`]: Newton, BFGS, JFNK) provides only its step.

use super::auto::{distinct, incumbent_link, links, merge, AutoState, Switch};
use super::common::{Constraints, Eval, Monitor, Verdict};
use super::{
    Failure, LineSearch, NonlinearOptions, NonlinearProblem, Preconditioning, SolveStats,
    SolverKind,
};
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
    /// What `solver = "auto"` has learned (`auto.rs`).
    pub auto: AutoState,
}

impl<'o> Solver<'o> {
    pub fn new(opts: &'o NonlinearOptions, k: DistMatrix, pc: Preconditioning) -> Self {
        let auto = AutoState::default();
        Self { opts, k, pc, auto }
    }

    /// Solve one load step with the method of `opts.kind`: r(u) = 0 on the free dofs
    /// with u_c = g on `prescribed` (owned local dof, value). `u` holds the start point
    /// (`start` says whether it is a prediction) and receives the solution; `r` the final
    /// residual. Non-convergence is `Ok` with `converged = false`; only runtime failures
    /// are `Err`.
    pub fn solve(
        &mut self,
        comm: &dyn Comm,
        problem: &mut dyn NonlinearProblem,
        u: &mut [f64],
        r: &mut [f64],
        prescribed: &[(usize, f64)],
        start: Start,
    ) -> Result<SolveStats> {
        if self.opts.kind == SolverKind::Auto {
            return self.solve_auto(comm, problem, u, r, prescribed, start);
        }
        self.solve_with(self.opts.kind, comm, problem, u, r, prescribed, start)
    }

    /// `auto` (`auto.rs`): the chain of the method that has been cheapest, each link
    /// from the increment's start point, until one converges.
    fn solve_auto(
        &mut self,
        comm: &dyn Comm,
        problem: &mut dyn NonlinearProblem,
        u: &mut [f64],
        r: &mut [f64],
        prescribed: &[(usize, f64)],
        start: Start,
    ) -> Result<SolveStats> {
        let clock = Instant::now();
        let (first, incumbent) = (self.auto.choose(), self.auto.incumbent());
        let links = distinct(&links(first, incumbent), self.opts);
        let u0 = u.to_vec();
        let mut total = SolveStats::default();
        let mut i = 0;
        while let Some((link, opts)) = links.get(i) {
            if i > 0 {
                u.copy_from_slice(&u0);
                self.pc.invalidate();
            }
            let budget = self.auto.budget(first).filter(|_| i == 0);
            let st = self.solve_opts(opts, comm, problem, u, r, prescribed, start, budget)?;
            merge(&mut total, st);
            total.method = link.name();
            if total.converged {
                break;
            }
            // A probe over its budget goes on with the incumbent's chain at once. An
            // element that cannot be evaluated ends the chain: the step is too large for
            // the element's own solve (EAS, return mapping) wherever the global method
            // goes, and the step is cut as a named solver's would be (panel-dent: chains
            // of three links failing at elements cost a third of `auto`'s run).
            i = match total.failure {
                Some(Failure::ProbeBudget) => incumbent_link(&links, incumbent)
                    .filter(|&j| j > i)
                    .unwrap_or(i + 1),
                Some(Failure::Element) => links.len(),
                _ => i + 1,
            };
            if let Some((next, _)) = links.get(i) {
                total.switches.push(Switch {
                    from: link.name(),
                    to: next.name(),
                    reason: total.reason.clone(),
                    at: total.residual_history.len(),
                });
            }
        }
        let mut seconds = [clock.elapsed().as_secs_f64()];
        comm.allreduce_max(&mut seconds);
        let clean = total.converged && total.switches.is_empty();
        self.auto.record(first, seconds[0], clean);
        Ok(total)
    }

    /// [`Solver::solve`] with the method `kind` instead of the options' one.
    #[allow(clippy::too_many_arguments)]
    pub fn solve_with(
        &mut self,
        kind: super::SolverKind,
        comm: &dyn Comm,
        problem: &mut dyn NonlinearProblem,
        u: &mut [f64],
        r: &mut [f64],
        prescribed: &[(usize, f64)],
        start: Start,
    ) -> Result<SolveStats> {
        let opts = NonlinearOptions {
            kind,
            ..self.opts.clone()
        };
        self.solve_opts(&opts, comm, problem, u, r, prescribed, start, None)
    }

    /// One solve with the options `opts` (their method) on this solver's storage, given
    /// up after `budget` seconds if one is set.
    #[allow(clippy::too_many_arguments)]
    fn solve_opts(
        &mut self,
        opts: &NonlinearOptions,
        comm: &dyn Comm,
        problem: &mut dyn NonlinearProblem,
        u: &mut [f64],
        r: &mut [f64],
        prescribed: &[(usize, f64)],
        start: Start,
        budget: Option<f64>,
    ) -> Result<SolveStats> {
        let mut method = opts.kind.method(u.len(), opts);
        let mut cx = SolverContext::new(comm, self, opts, problem, u, r, prescribed);
        cx.budget = budget.map(|b| (Instant::now(), b));
        cx.run(method.as_mut(), start)?;
        let mut stats = cx.stats;
        stats.method = opts.kind.name();
        Ok(stats)
    }
}

/// Where a solve starts: how its prescribed values are brought in before the method's
/// first residual, so that its first linearization is at the new pose.
#[derive(Debug, Clone, Copy)]
pub enum Start<'b> {
    /// `u` is the converged state: the tangent predictor imposes the prescribed values.
    Tangent,
    /// `u` is a prediction (extrapolated, or the time integrator's) from the converged
    /// state `base`; how well it foresees the prescribed values decides ([`Prediction`]).
    Predicted(&'b [f64]),
}

/// How well a prediction foresees the prescribed values g of an increment from the
/// converged state u₀: by the miss ‖g − u_c‖ against the increment ‖g − u₀_c‖.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Prediction {
    /// Within [`EXACT_PREDICTION`] of the increment (a wall moving at constant speed): the
    /// prescribed values are set exactly and no solve is made.
    Exact,
    /// Within [`CLOSE_PREDICTION`] (a rotation changing pace): the tangent predictor
    /// imposes the rest from the predicted point.
    Close,
    /// Farther (the motion stopped or turned): the prediction is dropped and the tangent
    /// predictor starts from the converged state.
    Wrong,
}

/// A prediction this close to the prescribed values (relative to the increment) is
/// [`Prediction::Exact`].
pub const EXACT_PREDICTION: f64 = 1e-6;
/// A prediction this close is [`Prediction::Close`]; farther, [`Prediction::Wrong`].
pub const CLOSE_PREDICTION: f64 = 0.5;

impl Prediction {
    /// Classify the miss `gap` = ‖g − u_c‖ against the increment `inc` = ‖g − u₀_c‖
    /// (global norms, so every rank decides alike).
    pub fn of(gap: f64, inc: f64) -> Self {
        if gap <= EXACT_PREDICTION * inc {
            Prediction::Exact
        } else if gap <= CLOSE_PREDICTION * inc {
            Prediction::Close
        } else {
            Prediction::Wrong
        }
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
    /// The next correction is taken in full (the first after a snapped prediction).
    full_next: bool,
    /// The predictor's evaluation of the start point, if it made one.
    first: Option<Eval>,
    /// `auto`'s probe: its start and the seconds it may take.
    budget: Option<(Instant, f64)>,
}

impl<'a> SolverContext<'a> {
    /// A solve from `u` with u_c = g on `prescribed` (owned local dof, value), its
    /// residual written to `r`.
    pub fn new(
        comm: &'a dyn Comm,
        solver: &'a mut Solver<'_>,
        opts: &'a NonlinearOptions,
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
            opts,
            monitor: Monitor::default(),
            stats: SolveStats::default(),
            scale: 0.0,
            full_next: false,
            first: None,
            budget: None,
        }
    }

    /// Number of owned dofs.
    pub fn n(&self) -> usize {
        self.u.len()
    }

    /// Bring the prescribed values in from `start` (module doc of [`Start`]), then run
    /// `method` to convergence or failure. Non-convergence is `Ok` with `converged =
    /// false` in the statistics; only runtime failures are `Err`.
    pub fn run(&mut self, method: &mut dyn NonlinearSolver, start: Start) -> Result<()> {
        if !self.predict(start)? {
            return Ok(());
        }
        let out = self.iterate_with(method);
        method.finish(self);
        out
    }

    /// ‖g − u_c‖ and ‖g − base_c‖ over the prescribed dofs (one reduction).
    fn misses(&self, base: &[f64]) -> (f64, f64) {
        let mut s = [0.0, 0.0];
        for &(d, g) in self.cons.prescribed {
            s[0] += (g - self.u[d]).powi(2);
            s[1] += (g - base[d]).powi(2);
        }
        self.comm.allreduce_sum(&mut s);
        (s[0].sqrt(), s[1].sqrt())
    }

    /// Set the prescribed values before the method's first residual. A prediction that
    /// foresees them is snapped to them; otherwise the tangent predictor
    /// ([`SolverContext::tangent_predictor`]) imposes them from the predicted point
    /// (close) or from the converged state (wrong, or no prediction). `Ok(false)`: the
    /// predictor failed (reason set).
    fn predict(&mut self, start: Start) -> Result<bool> {
        let gap = match start {
            Start::Tangent => self.misses(self.u).0,
            Start::Predicted(base) => {
                let (gap, inc) = self.misses(base);
                match Prediction::of(gap, inc) {
                    Prediction::Exact => {
                        self.snap();
                        // Its first correction is the one the predictor would have made:
                        // taken in full, like the predictor's.
                        self.full_next = inc > 0.0;
                        0.0
                    }
                    Prediction::Close => gap,
                    Prediction::Wrong => {
                        self.u.copy_from_slice(base);
                        inc
                    }
                }
            }
        };
        if gap == 0.0 {
            return Ok(true);
        }
        self.tangent_predictor()
    }

    /// u_c = g exactly.
    fn snap(&mut self) {
        for &(d, g) in self.cons.prescribed {
            self.u[d] = g;
        }
    }

    /// The tangent predictor (Abaqus's and FEAP's first iteration of an increment with
    /// prescribed motion): K(u) Δu = −r(u) − K_fc Δg on the free dofs with Δu_c = Δg =
    /// g − u_c, then u_c = g exactly; the free part is halved while an element inverts.
    /// Counted as an iteration and in `predictor_solves`. `Ok(false)`: failed (reason
    /// set).
    fn tangent_predictor(&mut self) -> Result<bool> {
        let n = self.n();
        let Some(ev) = self.evaluate()? else {
            return Ok(false);
        };
        let t1 = Instant::now();
        if !self.jacobian()? {
            return Ok(false);
        }
        let (mut dg, mut kd) = (vec![0.0; n], vec![0.0; n]);
        self.coupling(&ev, &mut dg, &mut kd);
        let rhs: Vec<f64> = (0..n)
            .map(|i| {
                if self.cons.is_c[i] {
                    dg[i]
                } else {
                    -self.r[i] - kd[i]
                }
            })
            .collect();
        self.constrain();
        self.stats.seconds_assembly += t1.elapsed().as_secs_f64();
        let mut du = dg.clone();
        if self.linear_solve(&rhs, &mut du)?.is_none() {
            return Ok(false);
        }
        self.stats.iterations += 1;
        self.stats.predictor_solves += 1;
        let measured = Monitor::measure(self.comm, &du, self.r, &self.cons.is_c);
        let base = self.u.to_vec();
        let mut lambda = 1.0;
        loop {
            for i in 0..n {
                self.u[i] = base[i] + lambda * du[i];
            }
            self.snap();
            // A full predictor that inverts an element is shortened on the free dofs (at
            // most 5 halvings); the first residual of the method then tests the point.
            if lambda <= 0.05 {
                break;
            }
            if let Some(ev) = self.evaluate()? {
                self.first = Some(ev);
                break;
            }
            self.stats.failure = None;
            self.stats.reason.clear();
            lambda *= 0.5;
        }
        self.monitor.record(measured, lambda);
        Ok(true)
    }

    fn iterate_with(&mut self, method: &mut dyn NonlinearSolver) -> Result<()> {
        if !method.setup(self)? {
            return Ok(());
        }
        let first = match self.first.take() {
            Some(ev) => Some(ev),
            None => self.evaluate()?,
        };
        let Some(mut ev) = first else {
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
            if let Some(why) = self.over_budget() {
                self.stats.fail(Failure::ProbeBudget, why);
                return Ok(());
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

    /// Why a probe with a budget stops here: its slowest rank's time is past the
    /// budget (one reduction, so every rank stops alike).
    fn over_budget(&self) -> Option<String> {
        let (t0, budget) = self.budget?;
        let mut s = [t0.elapsed().as_secs_f64()];
        self.comm.allreduce_max(&mut s);
        (s[0] > budget).then(|| {
            format!(
                "probe over its budget: {:.3} s, {} times the cheapest method's average increment",
                s[0],
                super::auto::PROBE_BUDGET
            )
        })
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
            if k > 0 {
                self.stats.backtracks += 1;
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

    /// Take the correction `du` from `u` (residual `r`, evaluation `ev`) as the line
    /// search setting says ([`LineSearch`]; the first correction after a snapped
    /// prediction always in full), then record it in the monitor. On return `u` and `r` hold the new point; `Ok(None)`: it
    /// could not be evaluated (reason set).
    pub fn take_step(&mut self, du: &[f64], ev: &Eval) -> Result<Option<Eval>> {
        let measured = Monitor::measure(self.comm, du, self.r, &self.cons.is_c);
        let full = std::mem::take(&mut self.full_next);
        let (next, lambda) = if self.opts.line_search == LineSearch::On && !full {
            match self.line_search(du, ev.rn, 6)? {
                Some(x) => x,
                None => return Ok(None),
            }
        } else {
            let (next, lambda) = match self.full_step(du)? {
                Some(x) => x,
                None => return Ok(None),
            };
            let auto = self.opts.line_search == LineSearch::Auto && !full;
            if auto && next.rn > AUTO_GROWTH * ev.rn && lambda == 1.0 {
                match self.backtrack(du, ev, next)? {
                    Some(x) => x,
                    None => return Ok(None),
                }
            } else {
                (next, lambda)
            }
        };
        self.monitor.record(measured, lambda);
        Ok(Some(next))
    }

    /// The line search `auto` after a full step `full` that grew ‖r‖ past
    /// [`AUTO_GROWTH`]: Armijo halvings from ½ (at most 5), keeping the best point found
    /// (the full one included). `u`, `r` hold it on return.
    fn backtrack(&mut self, du: &[f64], ev: &Eval, full: Eval) -> Result<Option<(Eval, f64)>> {
        let base: Vec<f64> = (0..self.n()).map(|i| self.u[i] - du[i]).collect();
        let mut best = (full, 1.0, self.u.to_vec(), self.r.to_vec());
        let mut lambda = 0.5;
        for _ in 0..5 {
            for i in 0..self.n() {
                self.u[i] = base[i] + lambda * du[i];
            }
            self.stats.backtracks += 1;
            if let Some(e) = self.evaluate()? {
                if e.rn < best.0.rn {
                    best = (e, lambda, self.u.to_vec(), self.r.to_vec());
                }
                if e.rn <= (1.0 - 1e-4 * lambda) * ev.rn {
                    return Ok(Some((e, lambda)));
                }
            } else {
                self.stats.failure = None;
                self.stats.reason.clear();
            }
            lambda *= 0.5;
        }
        self.u.copy_from_slice(&best.2);
        self.r.copy_from_slice(&best.3);
        Ok(Some((best.0, best.1)))
    }

    /// The full step along `du` (prescribed dofs untouched: Δu_c = 0), halved while it
    /// cannot be evaluated (an inverted element). `Ok(None)`: it never could (reason set).
    fn full_step(&mut self, du: &[f64]) -> Result<Option<(Eval, f64)>> {
        let base = self.u.to_vec();
        let mut lambda = 1.0;
        loop {
            for (x, (b, d)) in self.u.iter_mut().zip(base.iter().zip(du)) {
                *x = b + lambda * d;
            }
            match self.evaluate()? {
                Some(e) => return Ok(Some((e, lambda))),
                // A full step that inverts an element (a nearly incompressible body
                // overshooting, a thin wall folding) is shortened, not fatal: halve it up
                // to 5 times.
                None if lambda > 0.05 => lambda *= 0.5,
                None => return Ok(None),
            }
        }
    }
}

/// The line search `auto` backtracks only after a full step that multiplied ‖r_free‖ by
/// more than this.
pub const AUTO_GROWTH: f64 = 1e3;

/// A linear solve that missed its tolerance but reached this relative residual is
/// still used as the Newton correction.
pub const ACCEPTABLE_LINEAR_RESIDUAL: f64 = 1e-6;

#[cfg(test)]
mod tests {
    use super::super::testing::{equilibrium, options, solve, Toy};
    use super::super::SolverKind;
    use super::*;

    const KINDS: [SolverKind; 3] = [SolverKind::Newton, SolverKind::Bfgs, SolverKind::Jfnk];

    fn close(a: &[f64; 3], b: &[f64; 3], tol: f64) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
    }

    /// From the converged state, the tangent predictor imposes u₀ = g with one solve
    /// linearized at the old pose; every later residual and Jacobian is at u₀ = g
    /// exactly, whatever the method.
    #[test]
    fn tangent_predictor_imposes_before_the_first_residual() {
        for kind in KINDS {
            let opts = options(kind);
            let mut toy = Toy::new(1.0, 3.0, 0.5);
            let mut u = [0.0; 3];
            let st = solve(&opts, &mut toy, &mut u, 2.0, Start::Tangent);
            assert!(st.converged, "{kind:?}: {}", st.reason);
            assert_eq!(st.predictor_solves, 1, "{kind:?}");
            assert_eq!(
                toy.jacobians[0][0], 0.0,
                "{kind:?}: the predictor at the old pose"
            );
            assert_eq!(toy.residuals[0][0], 0.0, "{kind:?}");
            assert!(
                toy.residuals[1..].iter().all(|p| p[0] == 2.0),
                "{kind:?}: {:?}",
                toy.residuals
            );
            assert!(toy.jacobians[1..].iter().all(|p| p[0] == 2.0), "{kind:?}");
            assert!(close(&u, &equilibrium(&toy, 2.0), 1e-8), "{kind:?}: {u:?}");
        }
    }

    /// A prediction that foresees the prescribed value is snapped to it: no predictor
    /// solve, and nothing is evaluated at another pose.
    #[test]
    fn exact_prediction_is_snapped_without_a_solve() {
        for kind in KINDS {
            let opts = options(kind);
            let mut toy = Toy::new(1.0, 3.0, 0.5);
            let base = [1.0, 1.3, 1.6];
            let mut u = [2.0 + 1e-9, 2.3, 2.6];
            let st = solve(&opts, &mut toy, &mut u, 2.0, Start::Predicted(&base));
            assert!(st.converged, "{kind:?}: {}", st.reason);
            assert_eq!(st.predictor_solves, 0, "{kind:?}");
            assert!(toy.residuals.iter().all(|p| p[0] == 2.0), "{kind:?}");
            assert!(toy.jacobians.iter().all(|p| p[0] == 2.0), "{kind:?}");
            assert!(close(&u, &equilibrium(&toy, 2.0), 1e-8), "{kind:?}");
        }
    }

    /// A close prediction is corrected by the tangent predictor from the predicted
    /// point; a wrong one (the motion turned) is dropped for the converged state.
    #[test]
    fn close_and_wrong_predictions() {
        let opts = options(SolverKind::Newton);
        let base = [1.0, 1.3, 1.6];
        let mut toy = Toy::new(1.0, 3.0, 0.5);
        let mut u = [1.8, 2.1, 2.4];
        let st = solve(&opts, &mut toy, &mut u, 2.0, Start::Predicted(&base));
        assert!(st.converged && st.predictor_solves == 1);
        assert_eq!(toy.jacobians[0], [1.8, 2.1, 2.4], "from the prediction");
        let mut toy = Toy::new(1.0, 3.0, 0.5);
        let mut u = [3.0, 3.3, 3.6];
        let st = solve(&opts, &mut toy, &mut u, 0.5, Start::Predicted(&base));
        assert!(st.converged && st.predictor_solves == 1);
        assert_eq!(toy.jacobians[0], base, "from the converged state");
        assert!(close(&u, &equilibrium(&toy, 0.5), 1e-8));
    }

    #[test]
    fn prediction_thresholds() {
        assert_eq!(Prediction::of(0.0, 0.0), Prediction::Exact);
        assert_eq!(Prediction::of(1e-7, 1.0), Prediction::Exact);
        assert_eq!(Prediction::of(1e-3, 1.0), Prediction::Close);
        assert_eq!(Prediction::of(0.5, 1.0), Prediction::Close);
        assert_eq!(Prediction::of(0.51, 1.0), Prediction::Wrong);
        assert_eq!(Prediction::of(1e-9, 0.0), Prediction::Wrong);
    }

    /// The line search `auto` keeps full steps unless one multiplies ‖r‖ by more than
    /// [`AUTO_GROWTH`]: a tangent 10⁻⁵ of the true one (steps 10⁵ too long) backtracks,
    /// and the point kept has a smaller residual than the full step's.
    #[test]
    fn auto_line_search_backtracks_only_on_growth() {
        let first_step = |ls: LineSearch, jscale: f64| {
            let mut opts = options(SolverKind::Newton);
            opts.line_search = ls;
            opts.max_iterations = 2;
            let mut toy = Toy::new(1.0, 0.0, 1.0);
            toy.jscale = jscale;
            let mut u = [0.0; 3];
            let st = solve(&opts, &mut toy, &mut u, 0.0, Start::Tangent);
            (st.residual_history[1], st.backtracks)
        };
        let (full, none) = first_step(LineSearch::Off, 1e-5);
        let (auto, backtracks) = first_step(LineSearch::Auto, 1e-5);
        assert_eq!(none, 0);
        assert!(full > AUTO_GROWTH, "{full}");
        assert!(backtracks >= 5, "{backtracks}");
        assert!(auto < full / 10.0, "{auto} against {full}");
        // With the true tangent the full step is kept.
        let (_, backtracks) = first_step(LineSearch::Auto, 1.0);
        assert_eq!(backtracks, 0);
    }
}
