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
//! * Forcing terms: Eisenstat–Walker choice 2 (η = 0.9 (‖r_k‖/‖r_{k−1}‖)², with their
//!   safeguard, capped at 0.9), never tighter than needed to meet the residual tolerance.
//! * Globalisation: optional backtracking (Armijo) line search on ‖r_free‖ (`[solver]
//!   line_search`; off by default, see the deck).
//! * Prescribed dofs as in Newton: Δu_c = g − u_c exactly; the coupling K_fc (g − u_c) on
//!   the right-hand side is itself one finite-difference product.

use super::common::{evaluate, take_step, Constraints, Eval, Monitor, Verdict};
use super::Preconditioning;
use super::{Failure, FdRule, NonlinearOptions, NonlinearProblem, SolveStats};
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
/// Forcing term of an iteration that imposes a prescribed increment.
const ETA_IMPOSE: f64 = 1e-4;
/// GMRES iterations under the lagged preconditioner beyond which it is refreshed at the
/// next iterate: it struggles there, and its finite-difference products then cost more
/// than a refactorization (on rubber-indent one assembly and factorization costs about
/// 14 residual evaluations). jfnk (iterations, GMRES iterations, wall, side by side):
/// rubber-indent, 30 → 288 / 7036 / 79 s, 15 → 297 / 4077 / 51 s, 8 → 325 / 4980;
/// cook-membrane 30 → 86 iterations / 77 s, 15 → 73 / 45 s; cylinder-press
/// never 128 / 4661 / 10.2 s, 60 → 119 / 2694 / 6.2 s, 30 → 123 / 1754 / 4.8 s,
/// 15 → 156 / 1395 / 4.2 s with a retry (`scripts/solver-table`, issue 11).
const REFRESH_AFTER_GMRES: usize = 15;

/// The finite-difference Jacobian of `problem` at `u` (whose residual is `r0`), acting
/// on the free dofs; constrained rows are the identity.
pub struct FdJacobian<'a> {
    pub problem: &'a mut dyn NonlinearProblem,
    pub u: &'a [f64],
    pub r0: &'a [f64],
    pub is_c: &'a [bool],
    pub rule: FdRule,
    pub delta: f64,
    pub h: f64,
    /// ‖u‖ (for Walker–Pernice).
    pub u_norm: f64,
    pub products: usize,
    pub seconds: f64,
    w: Vec<f64>,
    r1: Vec<f64>,
}

impl<'a> FdJacobian<'a> {
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        problem: &'a mut dyn NonlinearProblem,
        u: &'a [f64],
        r0: &'a [f64],
        is_c: &'a [bool],
        rule: FdRule,
        delta: f64,
        h: f64,
        u_norm: f64,
    ) -> Self {
        let n = u.len();
        Self {
            problem,
            u,
            r0,
            is_c,
            rule,
            delta,
            h,
            u_norm,
            products: 0,
            seconds: 0.0,
            w: vec![0.0; n],
            r1: vec![0.0; n],
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
#[allow(clippy::too_many_arguments)]
fn refresh_preconditioner(
    comm: &dyn Comm,
    problem: &mut dyn NonlinearProblem,
    u: &[f64],
    k: &mut DistMatrix,
    pc: &mut Preconditioning,
    cons: &Constraints,
    st: &mut SolveStats,
) -> Result<bool> {
    let t = Instant::now();
    match problem.jacobian(comm, u, k) {
        Ok(()) => {}
        Err(e) if e.kind == ErrorKind::Convergence => {
            st.fail(Failure::Element, e.message);
            return Ok(false);
        }
        Err(e) => return Err(e),
    }
    k.constrain(comm, &cons.dofs);
    st.seconds_assembly += t.elapsed().as_secs_f64();
    let t = Instant::now();
    pc.invalidate();
    let s0 = pc.seconds_setup;
    let res = pc.update(comm, k);
    st.seconds_pc_setup += pc.seconds_setup - s0;
    st.coarse = pc.coarse.or(st.coarse);
    let ok = match res {
        Ok(f) => {
            st.factorizations += f as usize;
            true
        }
        Err(e) => {
            st.fail(Failure::LinearSolver, e);
            false
        }
    };
    st.seconds_linear += t.elapsed().as_secs_f64();
    Ok(ok)
}

/// Solve one load step by JFNK; same contract as [`super::newton::newton`].
#[allow(clippy::too_many_arguments)]
pub fn jfnk(
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
    let factored = pc.is_factored();
    if factored && !refresh_preconditioner(comm, problem, u, k, pc, &cons, &mut st)? {
        return Ok(st);
    }
    let mut du = vec![0.0; n];
    let mut gapv = vec![0.0; n];
    let Some(mut ev) = evaluate(comm, problem, u, r, &cons, &mut st)? else {
        return Ok(st);
    };
    let scale = ev.rn.max(ev.f_ref);
    let mut monitor = Monitor::default();
    let (eta_max, gamma, alpha) = (ETA_MAX, 0.9, 2.0);
    let mut eta = ETA_0;
    let mut prev_rn = f64::NAN;
    // The preconditioning stiffness was (re)assembled at the current iterate.
    let mut fresh_here = factored;
    // GMRES struggled under the lagged preconditioner.
    let mut refresh_next = false;
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
        if refresh_next {
            // Refresh it here, and take this direction on the Jacobian just assembled,
            // as at the start of the step.
            if !refresh_preconditioner(comm, problem, u, k, pc, &cons, &mut st)? {
                return Ok(st);
            }
            fresh_here = true;
        }
        // Eisenstat–Walker choice 2 with safeguard (Eisenstat & Walker 1996, §2).
        if it > 0 && prev_rn > 0.0 && ev.gap == 0.0 {
            let mut e = gamma * (ev.rn / prev_rn).powf(alpha);
            let guard = gamma * eta.powf(alpha);
            if guard > 0.1 {
                e = e.max(guard);
            }
            eta = e.min(eta_max);
        }
        // No need to solve much below what the residual tolerance asks for.
        let target = 0.5 * opts.residual_rtol * ev.f_ref / ev.rn.max(f64::MIN_POSITIVE);
        let mut eta_k = eta.max(target).min(eta_max).max(opts.linear.rtol);
        if ev.gap > 0.0 {
            // The iteration that imposes a prescribed increment carries the whole motion
            // of the step: solve it nearly exactly (a loose solve inverts elements).
            eta_k = ETA_IMPOSE.max(opts.linear.rtol);
        }
        prev_rn = ev.rn;
        cons.gap_vector(u, &mut gapv);
        // The first iteration starts where the preconditioning stiffness was just
        // assembled: it is the exact Jacobian there, so it is the operator too. That
        // also keeps the Krylov operator linear at a converged plastic state, where a
        // finite-difference product loads or unloads depending on the direction.
        let assembled = fresh_here;
        let Some(gmres_its) = direction(
            comm, problem, u, r, &cons, &gapv, &ev, eta_k, &mut du, k, pc, opts, assembled, &mut st,
        )?
        else {
            return Ok(st);
        };
        fresh_here = false;
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
        refresh_next = factored && !assembled && gmres_its > REFRESH_AFTER_GMRES;
    }
    unreachable!("the loop returns")
}

/// One JFNK linear solve J Δu = −r_f − J_fc (g − u_c), Δu_c = g − u_c (the coupling is
/// itself one finite-difference product), by GMRES to the forcing term `eta` with the
/// lagged preconditioner, refreshed once at the current point if GMRES fails under it.
/// With `assembled`, GMRES works on `k` itself (the Jacobian just assembled at `u` for
/// the preconditioner) instead of finite-difference products.
/// `Ok(Some(its))`: GMRES converged in `its` iterations (its last attempt);
/// `Ok(None)`: the iteration failed (reason in `st`).
#[allow(clippy::too_many_arguments)]
fn direction(
    comm: &dyn Comm,
    problem: &mut dyn NonlinearProblem,
    u: &[f64],
    r: &[f64],
    cons: &Constraints,
    gapv: &[f64],
    ev: &Eval,
    eta: f64,
    du: &mut [f64],
    k: &mut DistMatrix,
    pc: &mut Preconditioning,
    opts: &NonlinearOptions,
    assembled: bool,
    st: &mut SolveStats,
) -> Result<Option<usize>> {
    let n = u.len();
    let t = Instant::now();
    let outside = st.seconds_linear + st.seconds_assembly;
    let mut op = FdJacobian::new(
        problem,
        u,
        r,
        &cons.is_c,
        opts.fd_rule,
        opts.fd_delta,
        opts.char_length,
        ev.un,
    );
    let res = (|| -> Result<Option<usize>> {
        let mut coupling = vec![0.0; n];
        if ev.gap > 0.0 {
            coupling_product(comm, &mut op, gapv, &mut coupling)?;
        }
        let rhs: Vec<f64> = (0..n)
            .map(|i| {
                if cons.is_c[i] {
                    gapv[i]
                } else {
                    -r[i] - coupling[i]
                }
            })
            .collect();
        let lin = GmresOptions {
            rtol: eta,
            ..opts.linear
        };
        // A kept factorization gets one refresh; a fresh one (the assembled operator's)
        // none.
        let attempts = if assembled { 1 } else { 2 };
        for attempt in 0..attempts {
            du.copy_from_slice(gapv);
            let prec = pc.get();
            let gs = if assembled {
                let mut kop: &DistMatrix = k;
                gmres(comm, &mut kop, prec, &rhs, du, &lin)?
            } else {
                gmres(comm, &mut op, prec, &rhs, du, &lin)?
            };
            st.linear_iterations += gs.iterations;
            if gs.converged {
                return Ok(Some(gs.iterations));
            }
            if attempt == 0 && pc.is_factored() && !assembled {
                // GMRES stalled under the lagged factorization: refresh it at this point.
                if !refresh_preconditioner(comm, op.problem, u, k, pc, cons, st)? {
                    return Ok(None);
                }
                continue;
            }
            st.fail(
                Failure::LinearSolver,
                format!(
                    "GMRES did not converge in {} iterations (relative residual {:.3e}, forcing term {eta:.1e})",
                    gs.iterations,
                    gs.residual_norm / gs.rhs_norm.max(f64::MIN_POSITIVE)
                ),
            );
        }
        Ok(None)
    })();
    // Time in GMRES and FD products; a refresh booked its own assembly and factorization.
    let refresh = st.seconds_linear + st.seconds_assembly - outside;
    st.seconds_linear += (t.elapsed().as_secs_f64() - refresh).max(0.0);
    st.fd_products += op.products;
    st.residual_evaluations += op.products;
    match res {
        Err(e) if e.kind == ErrorKind::Convergence => {
            st.fail(
                Failure::Element,
                format!("a finite-difference product failed: {}", e.message),
            );
            Ok(None)
        }
        other => other,
    }
}

/// J_fc (g − u_c): the Jacobian's response on the free rows to the prescribed increment.
fn coupling_product(
    comm: &dyn Comm,
    op: &mut FdJacobian,
    gap: &[f64],
    out: &mut [f64],
) -> Result<()> {
    // The operator zeroes constrained inputs, so perturb along the gap directly.
    let gn = comm.norm2(gap);
    let eps = op.epsilon(gn);
    let w: Vec<f64> = op.u.iter().zip(gap).map(|(u, g)| u + eps * g).collect();
    let mut r1 = vec![0.0; gap.len()];
    op.problem.residual_frozen(comm, &w, &mut r1)?;
    op.products += 1;
    for i in 0..gap.len() {
        out[i] = if op.is_c[i] {
            0.0
        } else {
            (r1[i] - op.r0[i]) / eps
        };
    }
    Ok(())
}
