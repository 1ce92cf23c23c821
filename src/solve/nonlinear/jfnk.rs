//! Jacobian-free Newton–Krylov (Knoll & Keyes 2004; the paper's §2.2): Newton's method
//! whose linear systems are solved by GMRES with matrix-free products
//! J v ≈ (r(u + ε v) − r(u)) / ε, so no matrix is assembled inside the Newton loop.
//!
//! * ε (see [`FdRule`]): by default δ·h/‖v‖ with h the mean element length and
//!   δ = 1e-4, i.e. the perturbation moves the nodes by 10⁻⁴ of an element whatever the
//!   scale of v; Walker–Pernice's √((1 + ‖u‖) ε_mach)/‖v‖ on request.
//! * Preconditioner: block Jacobi (or ASM) of the stiffness assembled and factored once at the
//!   start of the step (lagged); reassembled and refactored at the next iterate when GMRES
//!   struggles under it (more than [`REFRESH_AFTER_GMRES`] iterations), at once when it fails.
//! * When GMRES fails on the products, the direction is solved on the stiffness just
//!   assembled at the iterate (a Newton direction; `jfnk_assembled_directions` in
//!   `summary.json`). Near a converged iterate of b-pillar after the hinge snaps (67 mm),
//!   products at δ = 10⁻⁴ differed from K v by 79 % (10⁻⁵: 3 %, 10⁻⁶: 0.3 %: truncation,
//!   not a kink: the branches are frozen), GMRES stopped after 3–7 iterations with the
//!   true residual of its answer at 0.3–1.1 ‖b‖, and the step was cut: JFNK crawled at
//!   10⁻⁶ s and stopped at 67.3 mm. With the assembled direction it finishes (85 steps,
//!   8 retries from 67.2 mm).
//! * Forcing terms: Eisenstat–Walker choice 2 (η = 0.9 (‖r_k‖/‖r_{k−1}‖)², with their
//!   safeguard, capped at 0.9), never tighter than needed to meet the residual tolerance.
//! * Globalisation: optional backtracking (Armijo) line search on ‖r_free‖ (`[solver]
//!   line_search`; off by default, see the deck).
//! * Prescribed dofs hold their values before the first residual (the solver context's
//!   predictor): every direction has Δu_c = 0.
//! * Contact branches (active, stick, slip) and the return map's (elastic, plastic) are
//!   frozen per Newton iteration in the products (`NonlinearProblem::residual_frozen`),
//!   so J v is linear in v: the generalized Jacobian's product, not a difference across
//!   a kink. b-pillar from 55 to 64 mm (restart): GMRES per Newton iteration 5.75 →
//!   4.91 with the J2 freeze, and GMRES no longer ends above its right-hand side at
//!   64.3 mm, where JFNK failed without it.
//! * A refresh when the nonlinear contraction is poor (‖r_{k+1}‖ > 0.5 ‖r_k‖) was tried:
//!   cantilever 66 → 56 iterations, but sphere-roll on 2 ranks then stopped at t = 1.405
//!   (also at 0.9); without it, it finishes. Only GMRES's count refreshes.

use super::common::Eval;
use super::context::{Next, NonlinearSolver, SolverContext};
use super::{Failure, FdRule, NonlinearOptions, NonlinearProblem};
use crate::linalg::gmres::{gmres, GmresOptions};
use crate::linalg::matrix::DistMatrix;
use crate::linalg::LinearOperator;
use crate::parallel::Comm;
use crate::{ErrorKind, Result};
use std::time::Instant;

/// Forcing term of the first iteration without a prescribed increment.
const ETA_0: f64 = 1e-2;
/// Cap of the Eisenstat–Walker forcing terms: looser solves cost more Newton iterations
/// than the Krylov iterations they save on these problems.
const ETA_MAX: f64 = 0.1;
/// GMRES iterations under the lagged preconditioner beyond which it is refreshed at the
/// next iterate: it struggles there, and its finite-difference products then cost more
/// than a refactorization (on rubber-indent one assembly and factorization costs about
/// 14 residual evaluations). jfnk (iterations, GMRES iterations, wall, side by side):
/// rubber-indent, 30 → 288 / 7036 / 79 s, 15 → 297 / 4077 / 51 s, 8 → 325 / 4980;
/// cook-membrane 30 → 86 iterations / 77 s, 15 → 73 / 45 s; cylinder-press
/// never 128 / 4661 / 10.2 s, 60 → 119 / 2694 / 6.2 s, 30 → 123 / 1754 / 4.8 s,
/// 15 → 156 / 1395 / 4.2 s with a retry (`scripts/solver-table`, issue 11).
const REFRESH_AFTER_GMRES: usize = 15;

/// How the finite-difference step ε of a product is chosen ([`FdRule`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FdStep {
    pub rule: FdRule,
    /// Relative perturbation δ ([`FdRule::Element`]).
    pub delta: f64,
    /// A characteristic element length h ([`FdRule::Element`]).
    pub h: f64,
    /// ‖u‖ ([`FdRule::WalkerPernice`]).
    pub u_norm: f64,
}

impl Default for FdStep {
    /// The deck's defaults: δ = 10⁻⁴ of a unit element.
    fn default() -> Self {
        Self {
            rule: FdRule::Element,
            delta: 1e-4,
            h: 1.0,
            u_norm: 0.0,
        }
    }
}

impl FdStep {
    /// The step of a solve's options at a point of norm `u_norm`.
    pub fn of(opts: &NonlinearOptions, u_norm: f64) -> Self {
        Self {
            rule: opts.fd_rule,
            delta: opts.fd_delta,
            h: opts.char_length,
            u_norm,
        }
    }

    /// The step ε for a direction of norm `vn`.
    pub fn epsilon(&self, vn: f64) -> f64 {
        match self.rule {
            FdRule::Element => self.delta * self.h / vn,
            FdRule::WalkerPernice => ((1.0 + self.u_norm) * f64::EPSILON).sqrt() / vn,
        }
    }
}

/// The finite-difference Jacobian of `problem` at `u` (whose residual is `r0`), acting
/// on the free dofs; constrained rows are the identity.
pub struct FdJacobian<'a> {
    pub problem: &'a mut dyn NonlinearProblem,
    pub u: &'a [f64],
    pub r0: &'a [f64],
    pub is_c: &'a [bool],
    pub step: FdStep,
    pub products: usize,
    pub seconds: f64,
    w: Vec<f64>,
    r1: Vec<f64>,
}

impl<'a> FdJacobian<'a> {
    pub fn new(
        problem: &'a mut dyn NonlinearProblem,
        u: &'a [f64],
        r0: &'a [f64],
        is_c: &'a [bool],
        step: FdStep,
    ) -> Self {
        let n = u.len();
        Self {
            problem,
            u,
            r0,
            is_c,
            step,
            products: 0,
            seconds: 0.0,
            w: vec![0.0; n],
            r1: vec![0.0; n],
        }
    }

    /// The step ε for a direction of norm `vn`.
    pub fn epsilon(&self, vn: f64) -> f64 {
        self.step.epsilon(vn)
    }
}

impl LinearOperator for FdJacobian<'_> {
    fn apply(&mut self, comm: &dyn Comm, x: &[f64], y: &mut [f64]) -> Result<()> {
        let t = Instant::now();
        for ((w, &xi), &c) in self.w.iter_mut().zip(x).zip(self.is_c) {
            *w = if c { 0.0 } else { xi };
        }
        let vn = comm.norm2(&self.w);
        if vn == 0.0 {
            for i in 0..x.len() {
                y[i] = if self.is_c[i] { x[i] } else { 0.0 };
            }
            return Ok(());
        }
        let eps = self.epsilon(vn);
        for i in 0..x.len() {
            self.w[i] = self.u[i] + eps * self.w[i];
        }
        self.problem.residual_frozen(comm, &self.w, &mut self.r1)?;
        self.products += 1;
        for i in 0..x.len() {
            y[i] = if self.is_c[i] {
                x[i]
            } else {
                (self.r1[i] - self.r0[i]) / eps
            };
        }
        self.seconds += t.elapsed().as_secs_f64();
        Ok(())
    }
}

/// Assemble and factor the preconditioning stiffness at `u` (collective).
/// `Ok(false)`: failed (reason set).
fn refresh_preconditioner(cx: &mut SolverContext) -> Result<bool> {
    let t = Instant::now();
    if !cx.jacobian()? {
        return Ok(false);
    }
    cx.constrain();
    cx.stats.seconds_assembly += t.elapsed().as_secs_f64();
    Ok(cx.refactor())
}

/// JFNK (module doc): the forcing-term and preconditioner-refresh state of one solve.
pub struct Jfnk {
    du: Vec<f64>,
    /// The preconditioner is a factored one (set up on an assembled stiffness).
    factored: bool,
    eta: f64,
    prev_rn: f64,
    /// The preconditioning stiffness was (re)assembled at the current iterate.
    fresh_here: bool,
    /// GMRES struggled under the lagged preconditioner.
    refresh_next: bool,
}

impl Jfnk {
    /// For `n` owned dofs.
    pub fn new(n: usize) -> Self {
        Self {
            du: vec![0.0; n],
            factored: false,
            eta: ETA_0,
            prev_rn: f64::NAN,
            fresh_here: false,
            refresh_next: false,
        }
    }

    /// The forcing term of this iteration: Eisenstat–Walker choice 2 with safeguard
    /// (Eisenstat & Walker 1996, §2), never much below what the residual tolerance asks
    /// for.
    fn forcing_term(&mut self, ev: &Eval, it: usize, opts: &NonlinearOptions) -> f64 {
        let (eta_max, gamma, alpha) = (ETA_MAX, 0.9, 2.0);
        if it > 0 && self.prev_rn > 0.0 {
            let mut e = gamma * (ev.rn / self.prev_rn).powf(alpha);
            let guard = gamma * self.eta.powf(alpha);
            if guard > 0.1 {
                e = e.max(guard);
            }
            self.eta = e.min(eta_max);
        }
        // No need to solve much below what the residual tolerance asks for.
        let target = 0.5 * opts.residual_rtol * ev.f_ref / ev.rn.max(f64::MIN_POSITIVE);
        let eta_k = self.eta.max(target).min(eta_max).max(opts.linear.rtol);
        self.prev_rn = ev.rn;
        eta_k
    }

    /// One JFNK linear solve J Δu = −r_f, Δu_c = 0, by GMRES to the forcing term `eta` with
    /// the lagged preconditioner, refreshed once at the current point if GMRES fails
    /// under it. With `assembled`, GMRES works on `k` itself (the Jacobian just
    /// assembled at `u` for the preconditioner) instead of finite-difference products.
    /// `Ok(Some(its))`: GMRES converged in `its` iterations (its last attempt);
    /// `Ok(None)`: the iteration failed (reason set).
    fn direction(
        &mut self,
        cx: &mut SolverContext,
        ev: &Eval,
        eta: f64,
        assembled: bool,
    ) -> Result<Option<usize>> {
        let t = Instant::now();
        let outside = cx.stats.seconds_linear + cx.stats.seconds_assembly;
        let mut products = 0;
        let res = self.krylov(cx, ev, eta, assembled, &mut products);
        // Time in GMRES and FD products; a refresh booked its own assembly and
        // factorization.
        let refresh = cx.stats.seconds_linear + cx.stats.seconds_assembly - outside;
        cx.stats.seconds_linear += (t.elapsed().as_secs_f64() - refresh).max(0.0);
        cx.stats.fd_products += products;
        cx.stats.residual_evaluations += products;
        match res {
            Err(e) if e.kind == ErrorKind::Convergence => {
                cx.stats.fail(
                    Failure::Element,
                    format!("a finite-difference product failed: {}", e.message),
                );
                Ok(None)
            }
            other => other,
        }
    }

    /// The right-hand side and the GMRES attempts of [`Jfnk::direction`]; the
    /// finite-difference products made are added to `products` (errors included).
    fn krylov(
        &mut self,
        cx: &mut SolverContext,
        ev: &Eval,
        eta: f64,
        assembled: bool,
        products: &mut usize,
    ) -> Result<Option<usize>> {
        let n = cx.n();
        let step = FdStep::of(cx.opts, ev.un);
        let rhs: Vec<f64> = (0..n)
            .map(|i| if cx.cons.is_c[i] { 0.0 } else { -cx.r[i] })
            .collect();
        let lin = GmresOptions {
            rtol: eta,
            ..cx.opts.linear
        };
        // A kept factorization gets one refresh; a fresh one (the assembled operator's)
        // none.
        let attempts = if assembled { 1 } else { 2 };
        let mut on_k = assembled;
        for attempt in 0..attempts {
            self.du.iter_mut().for_each(|x| *x = 0.0);
            let prec = cx.pc.get();
            let gs = if on_k {
                let mut kop: &DistMatrix = cx.k;
                gmres(cx.comm, &mut kop, prec, &rhs, &mut self.du, &lin)?
            } else {
                let mut op = FdJacobian::new(cx.problem, cx.u, cx.r, &cx.cons.is_c, step);
                let res = gmres(cx.comm, &mut op, prec, &rhs, &mut self.du, &lin);
                *products += op.products;
                res?
            };
            cx.stats.linear_iterations += gs.iterations;
            if gs.converged {
                return Ok(Some(gs.iterations));
            }
            if attempt == 0 && cx.pc.is_factored() && !assembled {
                // GMRES stalled under the lagged factorization, or on products that
                // are not linear enough at this scale: refresh the stiffness here and
                // solve on it, a Newton direction.
                if !refresh_preconditioner(cx)? {
                    return Ok(None);
                }
                cx.stats.assembled_directions += 1;
                on_k = true;
                continue;
            }
            cx.stats.fail(
                Failure::LinearSolver,
                format!(
                    "GMRES did not converge in {} iterations (relative residual {:.3e}, forcing term {eta:.1e})",
                    gs.iterations,
                    gs.residual_norm / gs.rhs_norm.max(f64::MIN_POSITIVE)
                ),
            );
        }
        Ok(None)
    }
}

impl NonlinearSolver for Jfnk {
    /// The preconditioning stiffness assembled and factored at the start point, unless
    /// the tangent predictor has just factored one (at the converged state, one
    /// increment back): that one is kept, lagged, and the first direction is already
    /// matrix-free.
    fn setup(&mut self, cx: &mut SolverContext) -> Result<bool> {
        self.factored = cx.pc.is_factored();
        if cx.stats.predictor_solves > 0 {
            return Ok(true);
        }
        self.fresh_here = self.factored;
        Ok(!self.factored || refresh_preconditioner(cx)?)
    }

    fn iterate(&mut self, cx: &mut SolverContext, ev: &Eval) -> Result<Next> {
        if self.refresh_next {
            // Refresh it here, and take this direction on the Jacobian just assembled,
            // as at the start of the step.
            if !refresh_preconditioner(cx)? {
                return Ok(Next::Stop);
            }
            self.fresh_here = true;
        }
        let eta_k = self.forcing_term(ev, cx.stats.iterations, cx.opts);
        // The first iteration starts where the preconditioning stiffness was just
        // assembled: it is the exact Jacobian there, so it is the operator too. That
        // also keeps the Krylov operator linear at a converged plastic state, where a
        // finite-difference product loads or unloads depending on the direction.
        let assembled = self.fresh_here;
        let Some(gmres_its) = self.direction(cx, ev, eta_k, assembled)? else {
            return Ok(Next::Stop);
        };
        self.fresh_here = false;
        cx.stats.iterations += 1;
        let Some(next) = cx.take_step(&self.du, ev)? else {
            return Ok(Next::Stop);
        };
        self.refresh_next = self.factored && !assembled && gmres_its > REFRESH_AFTER_GMRES;
        Ok(Next::Moved(next))
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::{equilibrium, options, solver, Toy};
    use super::super::{NonlinearProblem, SolverKind, Start};
    use crate::linalg::matrix::DistMatrix;
    use crate::parallel::Comm;
    use crate::parallel::SerialComm;
    use crate::Result;

    /// The toy chain whose perturbed residuals carry a kink at the iterate, c·|w − u|
    /// (what an inner solve's stopping test or a slip direction does to a difference
    /// on a small scale): its products are not linear in the direction.
    struct Kinked {
        toy: Toy,
        at: [f64; 3],
        c: f64,
    }

    impl NonlinearProblem for Kinked {
        fn residual(&mut self, comm: &dyn Comm, u: &[f64], r: &mut [f64]) -> Result<f64> {
            self.at = [u[0], u[1], u[2]];
            self.toy.residual(comm, u, r)
        }
        fn residual_frozen(&mut self, comm: &dyn Comm, u: &[f64], r: &mut [f64]) -> Result<f64> {
            let f = self.toy.residual(comm, u, r)?;
            r[1] += self.c * (u[1] - self.at[1]).abs();
            r[2] -= 0.5 * self.c * (u[2] - self.at[2]).abs();
            Ok(f)
        }
        fn jacobian(&mut self, comm: &dyn Comm, u: &[f64], k: &mut DistMatrix) -> Result<()> {
            self.toy.jacobian(comm, u, k)
        }
    }

    fn solve_kinked(kind: SolverKind, c: f64) -> (super::super::SolveStats, [f64; 3]) {
        let opts = options(kind);
        let mut p = Kinked {
            toy: Toy::new(0.05, 4.0, 3.0),
            at: [0.0; 3],
            c,
        };
        let (mut u, mut r) = ([0.0; 3], [0.0; 3]);
        let st = solver(&opts)
            .solve(
                &SerialComm,
                &mut p,
                &mut u,
                &mut r,
                &[(0, 0.0)],
                Start::Tangent,
            )
            .unwrap();
        (st, u)
    }

    /// Products that are not linear in the direction (a kink 10× the springs'
    /// stiffness) make GMRES's Arnoldi estimate meet the forcing term while the true
    /// residual of its answer does not. The stiffness refreshed at that iterate then gives
    /// the direction, a Newton step: the solve converges as Newton's does. With linear
    /// products (no kink) no direction is taken on the assembled Jacobian.
    #[test]
    fn gmres_failing_on_products_takes_the_assembled_direction() {
        let exact = equilibrium(&Toy::new(0.05, 4.0, 3.0), 0.0);
        let (newton, _) = solve_kinked(SolverKind::Newton, 10.0);
        let (smooth, u) = solve_kinked(SolverKind::Jfnk, 0.0);
        assert!(smooth.converged && smooth.assembled_directions == 0);
        assert!(u.iter().zip(&exact).all(|(a, b)| (a - b).abs() < 1e-8));
        let (kinked, u) = solve_kinked(SolverKind::Jfnk, 10.0);
        assert!(kinked.converged, "{}", kinked.reason);
        assert!(kinked.assembled_directions >= 1, "{kinked:?}");
        assert!(kinked.iterations <= newton.iterations + 1, "{kinked:?}");
        assert!(
            u.iter().zip(&exact).all(|(a, b)| (a - b).abs() < 1e-8),
            "{u:?}"
        );
    }
}
