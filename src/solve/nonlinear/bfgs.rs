//! BFGS as the classic implicit codes run it (LS-DYNA, Abaqus, ADINA): a quasi-Newton
//! iteration on a stiffness that is reformed only now and then, improved between
//! reforms by rank-two BFGS updates built from the residual changes (Matthies & Strang
//! 1979, "The solution of nonlinear finite element equations", IJNME 14, 1613–1626).
//!
//! * **Reform**: assemble the Jacobian K₀ at the current point, constrain it and
//!   factor its block-Jacobi preconditioner once; K₀⁻¹ v is then a GMRES solve with K₀
//!   to the tight linear tolerance, preconditioned by that factorization (one GMRES
//!   iteration on one rank, where block Jacobi is an exact factorization). The
//!   factorization is kept until the next reform whatever `pc.lag` says.
//! * **First iteration** of a step: exactly Newton's (module doc of `newton`): the
//!   prescribed increment Δu_c = g − u_c is imposed with the coupling −K_fc (g − u_c) on
//!   the right-hand side, and that iteration takes the full step. Afterwards u_c = g
//!   holds exactly and every vector lives on the free dofs (constrained entries zero).
//! * **Search direction** d = −H r with H the BFGS inverse built from H₀ = K₀⁻¹ and
//!   the pairs (s, y), s = u_{k+1} − u_k, y = r_{k+1} − r_k, kept since the last reform:
//!   the two-loop recursion (Nocedal & Wright, *Numerical Optimization*, Alg. 7.4),
//!   algebraically the Matthies–Strang product form. A pair is skipped unless
//!   sᵀy > ε ‖s‖ ‖y‖ (curvature condition, ε = 10⁻⁸), which keeps H positive definite.
//!   Every dot product is an MPI reduction, so the recursion is run on the Gram matrix
//!   S_ij = s_iᵀ y_j (kept incrementally): besides the GMRES solve an iteration makes
//!   two batched reductions, one when the new pair is taken (its Gram row and column,
//!   ‖s‖, ‖y‖, and s_iᵀ r for the first loop) and one for y_iᵀ H₀ q (second loop) that
//!   also gives the slope dᵀ r for the line search; each line-search trial adds the
//!   residual evaluation's reduction and one for its slope.
//! * **Line search**: always (whatever `opts.line_search` says), except on the first
//!   iteration that imposes a prescribed increment. A length is accepted when ‖r_free‖
//!   decreases sufficiently (Armijo, the test of `common::line_search`) or when the
//!   energy slope along d has dropped, |dᵀ r(u + λ d)| ≤ ½ |dᵀ r(u)| (Matthies & Strang's
//!   line search, also that of ADINA and LS-DYNA); overshoot is corrected by regula
//!   falsi on the slope. The energy test matters: on the cantilever the Newton step
//!   itself raises ‖r‖ at the start of every step, and the pure Armijo search on ‖r‖
//!   (`common::line_search`) then creeps on with λ = 1/64 and does not converge.
//! * **Reform policy**: reassemble K at the current u, refactor and clear the pairs
//!   (i) after `opts.bfgs_reform` search directions since the last reform (0 counts as
//!   1: a reform every iteration, i.e. Newton with a line search), and (ii) when the line
//!   search accepts no length (or cannot evaluate the residual) along a quasi-Newton
//!   direction, or that direction is not a descent direction (dᵀ r ≥ 0): the iteration
//!   is then discarded (u back to the last accepted point) and a fresh Newton direction
//!   is taken from there. Along a direction computed
//!   with a fresh K and no pairs (Newton's) that no length satisfies, the full step is
//!   taken, as Newton without a line search does.
//!
//! Convergence, failure reasons and statistics are those of the other solvers
//! (`common::evaluate`, `common::Monitor`); `iterations` counts search directions.

use super::common::{evaluate, precond_solve, Constraints, Eval, Monitor, Verdict};
use super::Preconditioning;
use super::{Failure, NonlinearOptions, NonlinearProblem, SolveStats};
use crate::linalg::matrix::DistMatrix;
use crate::parallel::Comm;
use crate::{ErrorKind, Result};
use std::time::Instant;

/// A pair (s, y) is kept only if sᵀy > CURVATURE_EPS · ‖s‖ ‖y‖.
pub const CURVATURE_EPS: f64 = 1e-8;

/// Trial lengths after the first in the line search.
const MAX_TRIALS: usize = 6;

/// Energy tolerance of the line search: |dᵀ r(u + λ d)| ≤ STOL |dᵀ r(u)|
/// (Matthies & Strang recommend 0.5).
pub const STOL: f64 = 0.5;

/// The stored BFGS pairs with their Gram matrix `sy[i][j] = s_iᵀ y_j` and ρ_i = 1/s_iᵀy_i.
#[derive(Default)]
pub struct Pairs {
    s: Vec<Vec<f64>>,
    y: Vec<Vec<f64>>,
    rho: Vec<f64>,
    sy: Vec<Vec<f64>>,
}

impl Pairs {
    pub fn len(&self) -> usize {
        self.s.len()
    }
    pub fn is_empty(&self) -> bool {
        self.s.is_empty()
    }
    pub fn clear(&mut self) {
        self.s.clear();
        self.y.clear();
        self.rho.clear();
        self.sy.clear();
    }

    /// Collective (one reduction). Offer the pair (s, y) and compute, for the next
    /// direction from the residual `r` (free dofs), `a_i = s_iᵀ r` over the pairs kept
    /// afterwards. Returns ‖s‖, whether the pair was kept, and `a`.
    pub fn offer(
        &mut self,
        comm: &dyn Comm,
        s: Vec<f64>,
        y: Vec<f64>,
        r: &[f64],
    ) -> (f64, bool, Vec<f64>) {
        let m = self.len();
        // [sᵀy, sᵀs, yᵀy, s_jᵀy (m), sᵀy_j (m), s_jᵀr (m), sᵀr]
        let mut v = vec![0.0; 3 + 3 * m + 1];
        for i in 0..s.len() {
            v[0] += s[i] * y[i];
            v[1] += s[i] * s[i];
            v[2] += y[i] * y[i];
            v[3 + 3 * m] += s[i] * r[i];
        }
        for j in 0..m {
            v[3 + j] = dot(&self.s[j], &y);
            v[3 + m + j] = dot(&s, &self.y[j]);
            v[3 + 2 * m + j] = dot(&self.s[j], r);
        }
        comm.allreduce_sum(&mut v);
        let (sty, sn, yn) = (v[0], v[1].sqrt(), v[2].sqrt());
        let mut a = v[3 + 2 * m..3 + 3 * m].to_vec();
        let keep = sty > CURVATURE_EPS * sn * yn && sty.is_finite();
        if keep {
            for j in 0..m {
                self.sy[j].push(v[3 + j]);
            }
            let mut row = v[3 + m..3 + 2 * m].to_vec();
            row.push(sty);
            self.sy.push(row);
            self.s.push(s);
            self.y.push(y);
            self.rho.push(1.0 / sty);
            a.push(v[3 + 3 * m]);
        }
        (sn, keep, a)
    }

    /// First loop of the two-loop recursion from `a_i = s_iᵀ r` (local): the α_i and
    /// q = r − Σ α_i y_i written into `q`.
    pub fn first_loop(&self, a: &[f64], r: &[f64], q: &mut [f64]) -> Vec<f64> {
        let m = self.len();
        assert_eq!(a.len(), m);
        let mut alpha = vec![0.0; m];
        for i in (0..m).rev() {
            // s_iᵀ q_i with q_i = r − Σ_{j>i} α_j y_j
            let mut t = a[i];
            for (j, &aj) in alpha.iter().enumerate().skip(i + 1) {
                t -= aj * self.sy[i][j];
            }
            alpha[i] = self.rho[i] * t;
        }
        q.copy_from_slice(r);
        for (al, y) in alpha.iter().zip(&self.y) {
            for (qi, yi) in q.iter_mut().zip(y) {
                *qi -= al * yi;
            }
        }
        alpha
    }

    /// Collective (one reduction). Second loop: `z` holds z₀ = H₀ q on entry and H r on
    /// return; `a_i = s_iᵀ r` as for the first loop. Returns rᵀ H r.
    pub fn second_loop(
        &self,
        comm: &dyn Comm,
        alpha: &[f64],
        a: &[f64],
        r: &[f64],
        z: &mut [f64],
    ) -> f64 {
        let m = self.len();
        // [y_iᵀ z₀ (m), rᵀ z₀]
        let mut b: Vec<f64> = self.y.iter().map(|y| dot(y, z)).collect();
        b.push(dot(r, z));
        comm.allreduce_sum(&mut b);
        let mut c = vec![0.0; m];
        for i in 0..m {
            // y_iᵀ z_i with z_i = z₀ + Σ_{j<i} c_j s_j
            let t = b[i] + (0..i).map(|j| c[j] * self.sy[j][i]).sum::<f64>();
            c[i] = alpha[i] - self.rho[i] * t;
        }
        for (cj, s) in c.iter().zip(&self.s) {
            for (zi, si) in z.iter_mut().zip(s) {
                *zi += cj * si;
            }
        }
        b[m] + c.iter().zip(a).map(|(c, a)| c * a).sum::<f64>()
    }
}

/// The line search along a descent direction `d` (d_c = 0) from `u` with residual
/// evaluation `ev0` and slope g0 = dᵀ r(u) < 0: trial lengths from λ = 1, accepted when
/// ‖r_free‖ decreases sufficiently (Armijo, as `common::line_search`) or when the
/// energy slope G(λ) = dᵀ r(u + λ d) satisfies |G(λ)| ≤ STOL |g0| (Matthies & Strang
/// 1979). A positive slope (overshoot past the minimum of the energy along d) gives the
/// next λ by regula falsi on G; a negative one means that the energy still decreases
/// past λ, which is accepted; an element that cannot be evaluated halves λ. On an
/// accepted return (`true`) `u`, `r` hold that point; otherwise (`false`, the last
/// evaluated trial, or `Ok(None)`: none could be evaluated) they hold no useful point.
#[allow(clippy::too_many_arguments)]
fn search(
    comm: &dyn Comm,
    problem: &mut dyn NonlinearProblem,
    u: &mut [f64],
    r: &mut [f64],
    d: &[f64],
    ev0: &Eval,
    g0: f64,
    cons: &Constraints,
    st: &mut SolveStats,
) -> Result<Option<(Eval, f64, bool)>> {
    let base = u.to_vec();
    let (lo, glo) = (0.0, g0);
    let mut lambda = 1.0;
    let mut last = None;
    for trial in 0..=MAX_TRIALS {
        for i in 0..u.len() {
            u[i] = base[i] + lambda * d[i];
        }
        let Some(ev) = evaluate(comm, problem, u, r, cons, st)? else {
            lambda = lo + 0.5 * (lambda - lo);
            continue;
        };
        let g = comm.dot(d, r);
        let armijo = ev.rn <= (1.0 - 1e-4 * lambda) * ev0.rn;
        if armijo || g.abs() <= STOL * g0.abs() || g < 0.0 {
            return Ok(Some((ev, lambda, ev.rn.is_finite())));
        }
        last = Some((ev, lambda, false));
        if trial == MAX_TRIALS || !g.is_finite() {
            break;
        }
        // G(λ) > 0: regula falsi on G between 0 (G = g0 < 0) and λ, kept inside.
        let w = lambda - lo;
        let next = lo - glo * w / (g - glo);
        lambda = next.clamp(lo + 0.1 * w, lambda - 0.1 * w);
    }
    Ok(last)
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Solve r(u) = 0 on the free dofs with u_c = g on `prescribed` (owned local dof, value)
/// by BFGS (module doc). `u` holds the start point and receives the solution; `r` the
/// final residual. Non-convergence is `Ok` with `converged = false`; only runtime
/// failures are `Err`.
#[allow(clippy::too_many_arguments)]
pub fn bfgs(
    comm: &dyn Comm,
    problem: &mut dyn NonlinearProblem,
    u: &mut [f64],
    r: &mut [f64],
    prescribed: &[(usize, f64)],
    k: &mut DistMatrix,
    pc: &mut Preconditioning,
    opts: &NonlinearOptions,
) -> Result<SolveStats> {
    // The factorization lives from one reform to the next: no refactor on the lag count.
    let lag = pc.lag;
    pc.lag = usize::MAX;
    let out = run(comm, problem, u, r, prescribed, k, pc, opts);
    pc.lag = lag;
    pc.invalidate();
    out
}

/// Reassemble K at `u`, compute the prescribed-increment coupling K (g − u_c) into `kd`
/// when there is a gap, constrain and factor. `Ok(false)`: failed (reason set).
#[allow(clippy::too_many_arguments)]
fn reform(
    comm: &dyn Comm,
    problem: &mut dyn NonlinearProblem,
    u: &[f64],
    ev: &Eval,
    cons: &Constraints,
    k: &mut DistMatrix,
    pc: &mut Preconditioning,
    gap: &mut [f64],
    kd: &mut [f64],
    st: &mut SolveStats,
) -> Result<bool> {
    let t1 = Instant::now();
    match problem.jacobian(comm, u, k) {
        Ok(()) => {}
        Err(e) if e.kind == ErrorKind::Convergence => {
            st.fail(Failure::Element, e.message);
            st.seconds_assembly += t1.elapsed().as_secs_f64();
            return Ok(false);
        }
        Err(e) => return Err(e),
    }
    cons.gap_vector(u, gap);
    if ev.gap > 0.0 {
        k.spmv(comm, gap, kd);
    } else {
        kd.iter_mut().for_each(|x| *x = 0.0);
    }
    k.constrain(comm, &cons.dofs);
    st.seconds_assembly += t1.elapsed().as_secs_f64();
    if pc.is_factored() {
        let t2 = Instant::now();
        pc.invalidate();
        let s0 = pc.seconds_setup;
        let res = pc.update(comm, k);
        st.seconds_pc_setup += pc.seconds_setup - s0;
        st.coarse = pc.coarse.or(st.coarse);
        st.seconds_linear += t2.elapsed().as_secs_f64();
        match res {
            Ok(f) => st.factorizations += f as usize,
            Err(e) => {
                st.fail(Failure::LinearSolver, e);
                return Ok(false);
            }
        }
    }
    Ok(true)
}

#[allow(clippy::too_many_arguments)]
fn run(
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
    let reform_every = opts.bfgs_reform.max(1);
    let mut gap = vec![0.0; n];
    let mut kd = vec![0.0; n];
    let mut rhs = vec![0.0; n];
    let mut d = vec![0.0; n];
    let mut pairs = Pairs::default();
    // s_iᵀ r at the current point for the stored pairs (first loop).
    let mut a: Vec<f64> = Vec::new();
    let Some(mut ev) = evaluate(comm, problem, u, r, &cons, &mut st)? else {
        return Ok(st);
    };
    let scale = ev.rn.max(ev.f_ref);
    // r on the free dofs at the current accepted point.
    let mut rf = r.to_vec();
    cons.zero_constrained(&mut rf);
    let mut monitor = Monitor::default();
    // K not yet assembled for this step.
    let mut need_reform = true;
    // Directions computed since the last reform.
    let mut since_reform = 0usize;
    // K was assembled at the current point and there are no pairs: d is Newton's.
    let mut k_at_current = false;
    st.residual_history.push(ev.relative());
    loop {
        match monitor.verdict(&ev, st.iterations, scale, opts) {
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
        if need_reform || since_reform >= reform_every || (ev.gap > 0.0 && !k_at_current) {
            if !reform(
                comm, problem, u, &ev, &cons, k, pc, &mut gap, &mut kd, &mut st,
            )? {
                return Ok(st);
            }
            pairs.clear();
            a.clear();
            need_reform = false;
            since_reform = 0;
            k_at_current = true;
        }
        let kref: &DistMatrix = k;
        let mut op = kref;

        if ev.gap > 0.0 {
            // Newton's first iteration: K₀ Δu = −r − K_fc (g − u_c), Δu_c = g − u_c,
            // full step (the coupling `kd` was computed by the reform at this point).
            for i in 0..n {
                rhs[i] = if cons.is_c[i] { gap[i] } else { -r[i] - kd[i] };
            }
            d.copy_from_slice(&gap);
            if precond_solve(comm, &mut op, kref, pc, &rhs, &mut d, &opts.linear, &mut st)?
                .is_none()
            {
                return Ok(st);
            }
            st.iterations += 1;
            since_reform += 1;
            for i in 0..n {
                u[i] += d[i];
            }
            for &(dof, g) in prescribed {
                u[dof] = g;
            }
            ev = match evaluate(comm, problem, u, r, &cons, &mut st)? {
                Some(e) => e,
                None => return Ok(st),
            };
            st.residual_history.push(ev.relative());
            monitor.record(Monitor::measure(comm, &d, &rf, &cons.is_c), 1.0);
            rf.copy_from_slice(r);
            cons.zero_constrained(&mut rf);
            k_at_current = false;
            continue;
        }

        // d = −H r_f by the two-loop recursion with H₀ = K₀⁻¹.
        let alpha = pairs.first_loop(&a, &rf, &mut rhs);
        d.iter_mut().for_each(|x| *x = 0.0);
        if precond_solve(comm, &mut op, kref, pc, &rhs, &mut d, &opts.linear, &mut st)?.is_none() {
            return Ok(st);
        }
        cons.zero_constrained(&mut d);
        // H r and g0 = dᵀ r (d = −H r), the second loop's reduction carrying both.
        let g0 = -pairs.second_loop(comm, &alpha, &a, &rf, &mut d);
        d.iter_mut().for_each(|x| *x = -*x);
        st.iterations += 1;
        since_reform += 1;

        // Line search along d; a failure along a quasi-Newton direction reforms.
        let u_base = u.to_vec();
        let r_base = r.to_vec();
        let ls = if g0 < 0.0 {
            search(comm, problem, u, r, &d, &ev, g0, &cons, &mut st)?
        } else {
            // Not a descent direction: H (or K₀) is not positive definite here.
            None
        };
        let accepted = match ls {
            Some((e, lambda, true)) => Some((e, lambda)),
            _ if k_at_current => {
                // Newton's direction with no acceptable length: the full step, as
                // Newton takes it.
                for i in 0..n {
                    u[i] = u_base[i] + d[i];
                }
                match evaluate(comm, problem, u, r, &cons, &mut st)? {
                    Some(e) => Some((e, 1.0)),
                    None => return Ok(st),
                }
            }
            _ => None,
        };
        let Some((e, lambda)) = accepted else {
            u.copy_from_slice(&u_base);
            r.copy_from_slice(&r_base);
            need_reform = true;
            continue;
        };
        ev = e;
        st.residual_history.push(ev.relative());
        let s: Vec<f64> = d.iter().map(|x| lambda * x).collect();
        let mut y = r.to_vec();
        cons.zero_constrained(&mut y);
        for i in 0..n {
            std::mem::swap(&mut rf[i], &mut y[i]);
            y[i] = rf[i] - y[i];
        }
        // The pair, ‖s‖ and the first loop's s_iᵀ r in one reduction.
        let (sn, _, a_new) = pairs.offer(comm, s, y, &rf);
        a = a_new;
        // ‖s‖ = λ‖d‖ and the energy λ|dᵀr| of the correction taken.
        monitor.record((sn / lambda, g0.abs()), lambda);
        k_at_current = false;
    }
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)]
mod tests {
    use super::*;
    use crate::parallel::SerialComm;

    /// Dense Cholesky-free solve of a small SPD system by Gaussian elimination.
    fn solve_dense(a: &[Vec<f64>], b: &[f64]) -> Vec<f64> {
        let n = b.len();
        let mut m: Vec<Vec<f64>> = a.to_vec();
        let mut x = b.to_vec();
        for c in 0..n {
            for rr in c + 1..n {
                let f = m[rr][c] / m[c][c];
                for cc in c..n {
                    m[rr][cc] -= f * m[c][cc];
                }
                x[rr] -= f * x[c];
            }
        }
        for c in (0..n).rev() {
            let mut t = x[c];
            for cc in c + 1..n {
                t -= m[c][cc] * x[cc];
            }
            x[c] = t / m[c][c];
        }
        x
    }

    /// The batched two-loop recursion equals the explicit BFGS inverse update
    /// H⁺ = (I − ρ s yᵀ) H (I − ρ y sᵀ) + ρ s sᵀ applied pair by pair from H₀ = K₀⁻¹.
    #[test]
    fn two_loop_matches_explicit_inverse_update() {
        let n = 7;
        let mut seed = 12345u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        // K₀ SPD: B Bᵀ + n I.
        let b: Vec<Vec<f64>> = (0..n).map(|_| (0..n).map(|_| rnd()).collect()).collect();
        let k0: Vec<Vec<f64>> = (0..n)
            .map(|i| {
                (0..n)
                    .map(|j| {
                        (0..n).map(|l| b[i][l] * b[j][l]).sum::<f64>()
                            + if i == j { n as f64 } else { 0.0 }
                    })
                    .collect()
            })
            .collect();
        // Explicit H₀ = K₀⁻¹.
        let mut h: Vec<Vec<f64>> = vec![vec![0.0; n]; n];
        for j in 0..n {
            let mut e = vec![0.0; n];
            e[j] = 1.0;
            let col = solve_dense(&k0, &e);
            for i in 0..n {
                h[i][j] = col[i];
            }
        }
        // Pairs from a different SPD "true" Jacobian (so curvature holds).
        let kt: Vec<Vec<f64>> = (0..n)
            .map(|i| {
                (0..n)
                    .map(|j| k0[i][j] * if i == j { 1.7 } else { 0.6 })
                    .collect()
            })
            .collect();
        let mut pairs = Pairs::default();
        let comm = SerialComm;
        for _ in 0..4 {
            let s: Vec<f64> = (0..n).map(|_| rnd()).collect();
            let y: Vec<f64> = (0..n).map(|i| dot(&kt[i], &s)).collect();
            let rho = 1.0 / dot(&s, &y);
            // H ← (I − ρ s yᵀ) H (I − ρ y sᵀ) + ρ s sᵀ
            let mut a1 = vec![vec![0.0; n]; n]; // (I − ρ s yᵀ) H
            for i in 0..n {
                for j in 0..n {
                    let yh: f64 = (0..n).map(|l| y[l] * h[l][j]).sum();
                    a1[i][j] = h[i][j] - rho * s[i] * yh;
                }
            }
            let mut hn = vec![vec![0.0; n]; n];
            for i in 0..n {
                let a1y: f64 = (0..n).map(|l| a1[i][l] * y[l]).sum();
                for j in 0..n {
                    hn[i][j] = a1[i][j] - rho * a1y * s[j] + rho * s[i] * s[j];
                }
            }
            h = hn;
            let dummy = vec![0.0; n];
            let (_, kept, _) = pairs.offer(&comm, s, y, &dummy);
            assert!(kept);
        }
        let r: Vec<f64> = (0..n).map(|_| rnd()).collect();
        let a: Vec<f64> = pairs.s.iter().map(|s| dot(s, &r)).collect();
        let mut q = vec![0.0; n];
        let alpha = pairs.first_loop(&a, &r, &mut q);
        let mut z = solve_dense(&k0, &q);
        let rhr = pairs.second_loop(&comm, &alpha, &a, &r, &mut z);
        assert!((rhr - dot(&r, &z)).abs() <= 1e-12 * rhr.abs());
        let hr: Vec<f64> = (0..n).map(|i| dot(&h[i], &r)).collect();
        let scale = hr.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for i in 0..n {
            assert!(
                (z[i] - hr[i]).abs() <= 1e-12 * scale,
                "component {i}: {} vs {}",
                z[i],
                hr[i]
            );
        }
        // The secant condition for the last pair: H y = s.
        let m = pairs.len() - 1;
        let hy: Vec<f64> = (0..n).map(|i| dot(&h[i], &pairs.y[m])).collect();
        for i in 0..n {
            assert!((hy[i] - pairs.s[m][i]).abs() <= 1e-10);
        }
    }

    #[test]
    fn pair_without_curvature_is_skipped() {
        let mut pairs = Pairs::default();
        let (sn, kept, a) = pairs.offer(&SerialComm, vec![1.0, 0.0], vec![-1.0, 0.5], &[2.0, 3.0]);
        assert_eq!(sn, 1.0);
        assert!(!kept);
        assert!(a.is_empty() && pairs.is_empty());
    }
}
