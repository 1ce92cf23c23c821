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
//! * **Prescribed values** hold before the first residual (the solver context's
//!   predictor), so the first reform is at the new pose and every vector lives on the
//!   free dofs (constrained entries zero).
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
//! * **Line search**: always (whatever `opts.line_search` says). A length is accepted when ‖r_free‖
//!   decreases sufficiently (Armijo, the test of `SolverContext::line_search`) or when the
//!   energy slope along d has dropped, |dᵀ r(u + λ d)| ≤ ½ |dᵀ r(u)| (Matthies & Strang's
//!   line search, also that of ADINA and LS-DYNA); overshoot is corrected by regula
//!   falsi on the slope. The energy test matters: on the cantilever the Newton step
//!   itself raises ‖r‖ at the start of every step, and the pure Armijo search on ‖r‖
//!   (`SolverContext::line_search`) then creeps on with λ = 1/64 and does not converge.
//! * **Reform policy**: reassemble K at the current u, refactor and clear the pairs
//!   (i) after `opts.bfgs_reform` search directions since the last reform (0 counts as
//!   1: a reform every iteration, i.e. Newton with a line search), and (ii) when the line
//!   search accepts no length (or cannot evaluate the residual) along a quasi-Newton
//!   direction, or that direction is not a descent direction (dᵀ r ≥ 0): the iteration
//!   is then discarded (u back to the last accepted point) and a fresh Newton direction
//!   is taken from there. Along a direction computed
//!   with a fresh K and no pairs (Newton's) that no length satisfies, the full step is
//!   taken, as Newton without a line search does; (iii) automatically, when two
//!   accepted iterations in a row each reduce ‖r_free‖ by less than
//!   1 − [`SLOW_CONTRACTION`] (LS-DYNA's automatic reformation on a stalled BFGS; the
//!   fixed `bfgs_reform` alone stalled on the B-pillar). More than [`MAX_REFORMS`]
//!   reforms in one solve end it as stagnated: by then it is a costlier Newton.
//!
//! Convergence, failure reasons and statistics are those of the other solvers
//! ([`super::context::SolverContext`], `common::Monitor`); `iterations` counts search
//! directions.

use super::common::Eval;
use super::context::{Next, NonlinearSolver, SolverContext};
use super::Failure;
use crate::parallel::Comm;
use crate::Result;
use std::time::Instant;

/// A pair (s, y) is kept only if sᵀy > CURVATURE_EPS · ‖s‖ ‖y‖.
pub const CURVATURE_EPS: f64 = 1e-8;

/// Trial lengths after the first in the line search.
const MAX_TRIALS: usize = 6;

/// Energy tolerance of the line search: |dᵀ r(u + λ d)| ≤ STOL |dᵀ r(u)|
/// (Matthies & Strang recommend 0.5).
pub const STOL: f64 = 0.5;

/// An accepted iteration with ‖r_{k+1}‖ > SLOW_CONTRACTION ‖r_k‖ is slow; two in a row
/// reform.
pub const SLOW_CONTRACTION: f64 = 0.8;
/// Reforms allowed in one solve before it is stagnated.
pub const MAX_REFORMS: usize = 12;

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
/// ‖r_free‖ decreases sufficiently (Armijo, as [`SolverContext::line_search`]) or when
/// the energy slope G(λ) = dᵀ r(u + λ d) satisfies |G(λ)| ≤ STOL |g0| (Matthies & Strang
/// 1979). A positive slope (overshoot past the minimum of the energy along d) gives the
/// next λ by regula falsi on G; a negative one means that the energy still decreases
/// past λ, which is accepted; an element that cannot be evaluated halves λ. On an
/// accepted return (`true`) `u`, `r` hold that point; otherwise (`false`, the last
/// evaluated trial, or `Ok(None)`: none could be evaluated) they hold no useful point.
fn search(
    cx: &mut SolverContext,
    d: &[f64],
    ev0: &Eval,
    g0: f64,
) -> Result<Option<(Eval, f64, bool)>> {
    let base = cx.u.to_vec();
    let (lo, glo) = (0.0, g0);
    let mut lambda = 1.0;
    let mut last = None;
    for trial in 0..=MAX_TRIALS {
        for i in 0..cx.u.len() {
            cx.u[i] = base[i] + lambda * d[i];
        }
        let Some(ev) = cx.evaluate()? else {
            lambda = lo + 0.5 * (lambda - lo);
            continue;
        };
        let g = cx.comm.dot(d, cx.r);
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

/// BFGS (module doc): the pairs, the reform state and the work vectors of one solve.
/// `iterations` counts search directions.
pub struct Bfgs {
    reform_every: usize,
    rhs: Vec<f64>,
    d: Vec<f64>,
    pairs: Pairs,
    /// s_iᵀ r at the current point for the stored pairs (first loop).
    a: Vec<f64>,
    /// r on the free dofs at the current accepted point (set at the first iteration).
    rf: Vec<f64>,
    /// K not yet assembled for this step.
    need_reform: bool,
    /// Directions computed since the last reform.
    since_reform: usize,
    /// K was assembled at the current point and there are no pairs: d is Newton's.
    k_at_current: bool,
    /// The preconditioner's lag outside the solve.
    lag: usize,
    /// Slow accepted iterations in a row ([`SLOW_CONTRACTION`]).
    slow: usize,
}

impl Bfgs {
    /// For `n` owned dofs, reforming every `reform` directions (0 counts as 1).
    pub fn new(n: usize, reform: usize) -> Self {
        Self {
            reform_every: reform.max(1),
            rhs: vec![0.0; n],
            d: vec![0.0; n],
            pairs: Pairs::default(),
            a: Vec::new(),
            rf: Vec::new(),
            need_reform: true,
            since_reform: 0,
            k_at_current: false,
            lag: 0,
            slow: 0,
        }
    }

    /// Reassemble K at `u`, constrain and factor it; clear the pairs. `Ok(false)`:
    /// failed (reason set: beyond [`MAX_REFORMS`], stagnated).
    fn reform(&mut self, cx: &mut SolverContext) -> Result<bool> {
        if cx.stats.reforms >= MAX_REFORMS {
            cx.stats.fail(
                Failure::Stagnated,
                format!("stagnated: {MAX_REFORMS} reforms of the BFGS stiffness in one increment"),
            );
            return Ok(false);
        }
        let t1 = Instant::now();
        if !cx.jacobian()? {
            cx.stats.seconds_assembly += t1.elapsed().as_secs_f64();
            return Ok(false);
        }
        cx.constrain();
        cx.stats.seconds_assembly += t1.elapsed().as_secs_f64();
        if cx.pc.is_factored() && !cx.refactor() {
            return Ok(false);
        }
        cx.stats.reforms += 1;
        self.pairs.clear();
        self.a.clear();
        self.need_reform = false;
        self.since_reform = 0;
        self.slow = 0;
        self.k_at_current = true;
        Ok(true)
    }

    /// A quasi-Newton iteration: d = −H r_f by the two-loop recursion with H₀ = K₀⁻¹, the
    /// line search along it, the new pair. A failure along a quasi-Newton direction
    /// discards the iteration and reforms.
    fn quasi_newton(&mut self, cx: &mut SolverContext, ev: &Eval) -> Result<Next> {
        let rn_before = ev.rn;
        let alpha = self.pairs.first_loop(&self.a, &self.rf, &mut self.rhs);
        self.d.iter_mut().for_each(|x| *x = 0.0);
        if cx.linear_solve(&self.rhs, &mut self.d)?.is_none() {
            return Ok(Next::Stop);
        }
        cx.cons.zero_constrained(&mut self.d);
        // H r and g0 = dᵀ r (d = −H r), the second loop's reduction carrying both.
        let g0 = -self
            .pairs
            .second_loop(cx.comm, &alpha, &self.a, &self.rf, &mut self.d);
        self.d.iter_mut().for_each(|x| *x = -*x);
        cx.stats.iterations += 1;
        self.since_reform += 1;

        let u_base = cx.u.to_vec();
        let r_base = cx.r.to_vec();
        let ls = if g0 < 0.0 {
            search(cx, &self.d, ev, g0)?
        } else {
            // Not a descent direction: H (or K₀) is not positive definite here.
            None
        };
        let accepted = match ls {
            Some((e, lambda, true)) => Some((e, lambda)),
            _ if self.k_at_current => {
                // Newton's direction with no acceptable length: the full step, as
                // Newton takes it.
                for ((x, b), di) in cx.u.iter_mut().zip(&u_base).zip(&self.d) {
                    *x = b + di;
                }
                match cx.evaluate()? {
                    Some(e) => Some((e, 1.0)),
                    None => return Ok(Next::Stop),
                }
            }
            _ => None,
        };
        let Some((ev, lambda)) = accepted else {
            cx.u.copy_from_slice(&u_base);
            cx.r.copy_from_slice(&r_base);
            self.need_reform = true;
            return Ok(Next::Again);
        };
        let s: Vec<f64> = self.d.iter().map(|x| lambda * x).collect();
        let mut y = cx.r.to_vec();
        cx.cons.zero_constrained(&mut y);
        for (rfi, yi) in self.rf.iter_mut().zip(y.iter_mut()) {
            std::mem::swap(rfi, yi);
            *yi = *rfi - *yi;
        }
        // The pair, ‖s‖ and the first loop's s_iᵀ r in one reduction.
        let (sn, _, a_new) = self.pairs.offer(cx.comm, s, y, &self.rf);
        self.a = a_new;
        // ‖s‖ = λ‖d‖ and the energy λ|dᵀr| of the correction taken.
        cx.monitor.record((sn / lambda, g0.abs()), lambda);
        self.k_at_current = false;
        self.slow = if ev.rn > SLOW_CONTRACTION * rn_before {
            self.slow + 1
        } else {
            0
        };
        if self.slow >= 2 {
            self.need_reform = true;
        }
        Ok(Next::Moved(ev))
    }
}

impl NonlinearSolver for Bfgs {
    /// The factorization lives from one reform to the next: no refactor on the lag count.
    fn setup(&mut self, cx: &mut SolverContext) -> Result<bool> {
        self.lag = cx.pc.lag;
        cx.pc.lag = usize::MAX;
        Ok(true)
    }

    fn iterate(&mut self, cx: &mut SolverContext, ev: &Eval) -> Result<Next> {
        if self.rf.len() != cx.n() {
            // r on the free dofs at the start point.
            self.rf = cx.r.to_vec();
            cx.cons.zero_constrained(&mut self.rf);
        }
        let reform = self.need_reform || self.since_reform >= self.reform_every;
        if reform && !self.reform(cx)? {
            return Ok(Next::Stop);
        }
        self.quasi_newton(cx, ev)
    }

    fn finish(&mut self, cx: &mut SolverContext) {
        cx.pc.lag = self.lag;
        cx.pc.invalidate();
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
