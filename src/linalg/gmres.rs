//! Restarted GMRES with right preconditioning, for distributed vectors.
//!
//! Right preconditioning (`A M⁻¹ u = b`, `x = M⁻¹ u`) keeps the Krylov residual equal to
//! the true residual `b − A x`, so the stopping test `‖b − A x‖ ≤ max(rtol·‖b‖, atol)`
//! is on the quantity users mean; it is re-checked with an explicit `b − A x` at every
//! restart and at the end (convergence is only declared on that true residual).
//!
//! Arnoldi uses classical Gram–Schmidt with one re-orthogonalisation (CGS2). Each pass's
//! dot products are batched in one `allreduce`; the second pass also carries `‖w₁‖²`, and
//! `‖w₂‖² = ‖w₁‖² − ‖h₂‖²` (exact for an orthonormal basis) gives the new norm without
//! a third reduction. When that difference cancels badly (`‖w₂‖² < 10⁻⁴‖w₁‖²`, i.e. near
//! breakdown) the norm is recomputed explicitly. So an iteration costs two reductions;
//! a restart cycle adds one (the true residual norm).
//!
//! Only the Krylov basis `V` is stored (`restart + 1` vectors, allocated once); the
//! update `x += M⁻¹ (V y)` costs one extra preconditioner application per cycle.

use super::{LinearOperator, Preconditioner};
use crate::parallel::Comm;
use crate::Error;
use std::time::Instant;

#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GmresOptions {
    /// Relative tolerance on the true residual: ‖b − A x‖ ≤ rtol·‖b‖.
    pub rtol: f64,
    /// Absolute tolerance on the true residual (the larger of the two applies).
    pub atol: f64,
    /// Krylov vectors per cycle before a restart.
    pub restart: usize,
    /// Total Arnoldi iterations (operator applications in the Krylov loop).
    pub max_iterations: usize,
}

impl Default for GmresOptions {
    fn default() -> Self {
        Self {
            rtol: 1e-8,
            atol: 0.0,
            restart: 60,
            max_iterations: 1000,
        }
    }
}

#[derive(Debug, Clone, Default, PartialEq)]
pub struct GmresStats {
    /// The true residual met the tolerance.
    pub converged: bool,
    /// Arnoldi iterations done.
    pub iterations: usize,
    /// Restarts done (cycles after the first).
    pub restarts: usize,
    /// Final true residual norm ‖b − A x‖.
    pub residual_norm: f64,
    /// ‖b‖.
    pub rhs_norm: f64,
    /// Reductions (allreduce calls) made by GMRES itself (not by the operator).
    pub reductions: usize,
    pub seconds_in_operator: f64,
    pub seconds_in_preconditioner: f64,
}

/// Relative size of `h_{k+1,k}` against ‖A M⁻¹ v_k‖ below which the Krylov space is
/// taken as invariant (breakdown; "lucky" if the residual is then small).
const BREAKDOWN: f64 = 1e-14;

/// Solves A x = b; `x` holds the initial guess on entry and the solution on exit.
///
/// Collective. Returns `Ok` with `converged == false` when the iteration budget runs
/// out, a restart cycle gains less than 1 %, or the iteration stagnates after a breakdown; `Err` when the operator fails (its
/// error is propagated) or the residual becomes non-finite.
pub fn gmres(
    comm: &dyn Comm,
    a: &mut dyn LinearOperator,
    pc: &dyn Preconditioner,
    b: &[f64],
    x: &mut [f64],
    opts: &GmresOptions,
) -> crate::Result<GmresStats> {
    let n = b.len();
    assert_eq!(x.len(), n, "gmres: x has {} entries, b has {n}", x.len());
    let m = opts.restart.max(1);
    let mut st = GmresStats::default();

    // ‖b‖ and ‖x₀‖ in one reduction (a zero guess saves an operator application).
    let mut s = [dot_local(b, b), dot_local(x, x)];
    comm.allreduce_sum(&mut s);
    st.reductions += 1;
    let bnorm = s[0].sqrt();
    let x_is_zero = s[1] == 0.0;
    st.rhs_norm = bnorm;
    if !bnorm.is_finite() || !s[1].is_finite() {
        return Err(Error::convergence(format!(
            "GMRES: non-finite right-hand side or initial guess (‖b‖ = {bnorm}, ‖x₀‖² = {})",
            s[1]
        )));
    }
    if bnorm == 0.0 {
        x.fill(0.0);
        st.converged = true;
        return Ok(st);
    }
    let tol = (opts.rtol * bnorm).max(opts.atol);

    let mut ws = Workspace::new(n, m, tol, opts.max_iterations);
    let mut first = true;
    let mut last_cycle: Option<(f64, bool)> = None; // (β at cycle start, breakdown)
    loop {
        let beta = ws.true_residual(comm, a, b, x, first && x_is_zero, &mut st)?;
        if beta <= tol {
            st.converged = true;
            break;
        }
        if st.iterations >= opts.max_iterations {
            break;
        }
        if let Some((beta0, breakdown)) = last_cycle {
            // After a breakdown the space was invariant: restarting only helps if the
            // cycle made real progress (otherwise A M⁻¹ is singular on it).
            if breakdown && beta > 0.5 * beta0 {
                break;
            }
            // A whole cycle that gained less than 1 %: GMRES(m) has stagnated (or the
            // residual sits at the attainable accuracy of an ill-conditioned system);
            // more cycles would burn the budget for nothing.
            if beta > 0.99 * beta0 {
                break;
            }
        }
        if !first {
            st.restarts += 1;
        }
        first = false;
        let (k, breakdown) = ws.cycle(comm, a, pc, beta, &mut st)?;
        ws.update_solution(comm, pc, x, (k, breakdown), &mut st);
        last_cycle = Some((beta, breakdown));
    }
    Ok(st)
}

/// The work space of a GMRES solve, allocated once: the Krylov basis, the Hessenberg
/// matrix with its Givens rotations, and the vectors of a cycle.
struct Workspace {
    n: usize,
    /// Krylov vectors per cycle.
    m: usize,
    /// The absolute tolerance on the residual and the iteration budget.
    tol: f64,
    max_iterations: usize,
    v: Vec<f64>,
    /// Column-major, column k has m+1 rows.
    h: Vec<f64>,
    cs: Vec<f64>,
    sn: Vec<f64>,
    g: Vec<f64>,
    y: Vec<f64>,
    hbuf: Vec<f64>,
    /// ‖A M⁻¹ v_k‖.
    colnorm: Vec<f64>,
    r: Vec<f64>,
    z: Vec<f64>,
}

impl Workspace {
    fn new(n: usize, m: usize, tol: f64, max_iterations: usize) -> Self {
        Self {
            n,
            m,
            tol,
            max_iterations,
            v: vec![0.0; (m + 1) * n],
            h: vec![0.0; (m + 1) * m],
            cs: vec![0.0; m],
            sn: vec![0.0; m],
            g: vec![0.0; m + 1],
            y: vec![0.0; m],
            hbuf: vec![0.0; m + 2],
            colnorm: vec![0.0; m],
            r: vec![0.0; n],
            z: vec![0.0; n],
        }
    }

    /// The true residual r = b − A x (b itself for a zero guess) and its norm β, also
    /// recorded as the statistics' residual norm. `Err` when β is not finite.
    fn true_residual(
        &mut self,
        comm: &dyn Comm,
        a: &mut dyn LinearOperator,
        b: &[f64],
        x: &[f64],
        zero_guess: bool,
        st: &mut GmresStats,
    ) -> crate::Result<f64> {
        let r = &mut self.r;
        if zero_guess {
            r.copy_from_slice(b);
        } else {
            let t = Instant::now();
            a.apply(comm, x, r)?;
            st.seconds_in_operator += t.elapsed().as_secs_f64();
            for (ri, bi) in r.iter_mut().zip(b) {
                *ri = bi - *ri;
            }
        }
        let mut s = [dot_local(r, r)];
        comm.allreduce_sum(&mut s);
        st.reductions += 1;
        let beta = s[0].sqrt();
        st.residual_norm = beta;
        if !beta.is_finite() {
            return Err(Error::convergence(format!(
                "GMRES: the residual became non-finite after {} iterations",
                st.iterations
            )));
        }
        Ok(beta)
    }

    /// One Arnoldi cycle from the residual `r` of norm `beta`: columns until the cycle
    /// is full, the budget is spent, the residual estimate meets the tolerance or the
    /// space breaks down. Returns the columns done and whether it broke down.
    fn cycle(
        &mut self,
        comm: &dyn Comm,
        a: &mut dyn LinearOperator,
        pc: &dyn Preconditioner,
        beta: f64,
        st: &mut GmresStats,
    ) -> crate::Result<(usize, bool)> {
        let n = self.n;
        for (vi, ri) in self.v[..n].iter_mut().zip(&self.r) {
            *vi = ri / beta;
        }
        self.g.fill(0.0);
        self.g[0] = beta;
        let mut k = 0; // columns done
        let mut breakdown = false;
        while k < self.m && st.iterations < self.max_iterations {
            let (hnext, az_norm) = self.arnoldi(comm, a, pc, k, st)?;
            self.rotate(k);
            k += 1;

            if hnext <= BREAKDOWN * az_norm {
                breakdown = true;
                break;
            }
            let inv = 1.0 / hnext;
            for wi in self.v[k * n..(k + 1) * n].iter_mut() {
                *wi *= inv;
            }
            if self.g[k].abs() <= self.tol {
                break;
            }
        }
        Ok((k, breakdown))
    }

    /// The Arnoldi step of column `k`: w = A M⁻¹ v_k orthogonalised against the basis by
    /// CGS2 (unnormalised, in the basis's next slot), the column `h_k` with
    /// `h_{k+1,k} = ‖w‖`. Returns ‖w‖ and ‖A M⁻¹ v_k‖.
    fn arnoldi(
        &mut self,
        comm: &dyn Comm,
        a: &mut dyn LinearOperator,
        pc: &dyn Preconditioner,
        k: usize,
        st: &mut GmresStats,
    ) -> crate::Result<(f64, f64)> {
        let (n, m) = (self.n, self.m);
        let hbuf = &mut self.hbuf;
        let (basis, rest) = self.v.split_at_mut((k + 1) * n);
        let w = &mut rest[..n];
        let vk = &basis[k * n..];
        let t = Instant::now();
        pc.apply(comm, vk, &mut self.z);
        st.seconds_in_preconditioner += t.elapsed().as_secs_f64();
        let t = Instant::now();
        a.apply(comm, &self.z, w)?;
        st.seconds_in_operator += t.elapsed().as_secs_f64();
        st.iterations += 1;

        // CGS pass 1: h₁ = Vᵀw, w ← w − V h₁.
        for (i, hi) in hbuf[..=k].iter_mut().enumerate() {
            *hi = dot_local(&basis[i * n..(i + 1) * n], w);
        }
        comm.allreduce_sum(&mut hbuf[..=k]);
        st.reductions += 1;
        let hk = &mut self.h[k * (m + 1)..(k + 1) * (m + 1)];
        hk[..=k].copy_from_slice(&hbuf[..=k]);
        let h1_sq: f64 = hbuf[..=k].iter().map(|x| x * x).sum();
        subtract_combination(w, basis, &hbuf[..=k], n);

        // CGS pass 2 with ‖w₁‖² in the same reduction.
        for (i, hi) in hbuf[..=k].iter_mut().enumerate() {
            *hi = dot_local(&basis[i * n..(i + 1) * n], w);
        }
        hbuf[k + 1] = dot_local(w, w);
        comm.allreduce_sum(&mut hbuf[..=k + 1]);
        st.reductions += 1;
        let w1_sq = hbuf[k + 1];
        let h2_sq: f64 = hbuf[..=k].iter().map(|x| x * x).sum();
        for (hi, h2) in hk[..=k].iter_mut().zip(&hbuf[..=k]) {
            *hi += h2;
        }
        subtract_combination(w, basis, &hbuf[..=k], n);
        let mut w2_sq = w1_sq - h2_sq;
        if w2_sq < 1e-4 * w1_sq {
            let mut s = [dot_local(w, w)];
            comm.allreduce_sum(&mut s);
            st.reductions += 1;
            w2_sq = s[0];
        }
        let hnext = w2_sq.max(0.0).sqrt();
        let az_norm = (h1_sq + w1_sq).sqrt();
        if !hnext.is_finite() || !az_norm.is_finite() {
            return Err(Error::convergence(format!(
                "GMRES: non-finite Arnoldi vector at iteration {}",
                st.iterations
            )));
        }
        hk[k + 1] = hnext;
        self.colnorm[k] = az_norm;
        Ok((hnext, az_norm))
    }

    /// Apply the previous Givens rotations to column `k`, then a new one that zeroes
    /// its subdiagonal, and rotate the residual vector `g` with it.
    fn rotate(&mut self, k: usize) {
        let m = self.m;
        let (cs, sn, g) = (&mut self.cs, &mut self.sn, &mut self.g);
        let hk = &mut self.h[k * (m + 1)..(k + 1) * (m + 1)];
        for i in 0..k {
            let t = cs[i] * hk[i] + sn[i] * hk[i + 1];
            hk[i + 1] = -sn[i] * hk[i] + cs[i] * hk[i + 1];
            hk[i] = t;
        }
        let (p, q) = (hk[k], hk[k + 1]);
        let rho = p.hypot(q);
        let (c, s) = if rho == 0.0 {
            (1.0, 0.0)
        } else {
            (p / rho, q / rho)
        };
        cs[k] = c;
        sn[k] = s;
        hk[k] = rho;
        hk[k + 1] = 0.0;
        g[k + 1] = -s * g[k];
        g[k] *= c;
    }

    /// The end of a cycle of `k` columns: y = R⁻¹ g and x += M⁻¹ (V y).
    fn update_solution(
        &mut self,
        comm: &dyn Comm,
        pc: &dyn Preconditioner,
        x: &mut [f64],
        (k, breakdown): (usize, bool),
        st: &mut GmresStats,
    ) {
        let (n, m) = (self.n, self.m);
        let (h, g, y) = (&self.h, &self.g, &mut self.y);
        // y = R⁻¹ g (upper triangular, k×k). Only the column of a breakdown can have a
        // negligible pivot (A M⁻¹ singular on the Krylov space): drop it.
        let mut kk = k;
        if breakdown && h[(k - 1) * (m + 1) + k - 1].abs() <= BREAKDOWN * self.colnorm[k - 1] {
            kk -= 1;
        }
        for i in (0..kk).rev() {
            let mut s = g[i];
            for j in i + 1..kk {
                s -= h[j * (m + 1) + i] * y[j];
            }
            y[i] = s / h[i * (m + 1) + i];
        }
        // x += M⁻¹ (V y); r is free until the next true residual.
        let r = &mut self.r;
        r.fill(0.0);
        for (j, &yj) in y[..kk].iter().enumerate() {
            for (ri, vi) in r.iter_mut().zip(&self.v[j * n..(j + 1) * n]) {
                *ri += yj * vi;
            }
        }
        let t = Instant::now();
        pc.apply(comm, r, &mut self.z);
        st.seconds_in_preconditioner += t.elapsed().as_secs_f64();
        for (xi, zi) in x.iter_mut().zip(&self.z) {
            *xi += zi;
        }
    }
}

#[inline]
fn dot_local(a: &[f64], b: &[f64]) -> f64 {
    // Four accumulators: vectorises and is slightly more accurate than one.
    let mut acc = [0.0f64; 4];
    let (ca, ra) = (a.chunks_exact(4), a.chunks_exact(4).remainder());
    let rb = b.chunks_exact(4).remainder();
    for (x, y) in ca.zip(b.chunks_exact(4)) {
        acc[0] += x[0] * y[0];
        acc[1] += x[1] * y[1];
        acc[2] += x[2] * y[2];
        acc[3] += x[3] * y[3];
    }
    let tail: f64 = ra.iter().zip(rb).map(|(x, y)| x * y).sum();
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// w ← w − Σᵢ cᵢ Vᵢ.
#[inline]
fn subtract_combination(w: &mut [f64], basis: &[f64], c: &[f64], n: usize) {
    for (i, &ci) in c.iter().enumerate() {
        for (wj, vj) in w.iter_mut().zip(&basis[i * n..(i + 1) * n]) {
            *wj -= ci * vj;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::{BlockJacobi, DistMatrix, Factorization, Identity};
    use crate::parallel::{run_ranks, Layout, SerialComm};

    /// 3D grid of `nx·ny·nz` blocks, 7-point stencil: A = L ⊗ K + shift·I, assembled from
    /// 2-node edge elements [[K, −K], [−K, K]] (elements assigned by the owner of the
    /// first node, so some rows are off-rank). `skew` adds a non-symmetric convection
    /// term ±skew·I on x-neighbours.
    fn grid_matrix(
        comm: &dyn Comm,
        dims: (usize, usize, usize),
        counts: &[usize],
        shift: f64,
        skew: f64,
    ) -> DistMatrix {
        let (nx, ny, nz) = dims;
        let id = |i: usize, j: usize, k: usize| i + nx * (j + ny * k);
        let layout = Layout::from_counts(counts, comm.rank());
        let mut edges = Vec::new();
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let a = id(i, j, k);
                    if i + 1 < nx {
                        edges.push((a, id(i + 1, j, k), true));
                    }
                    if j + 1 < ny {
                        edges.push((a, id(i, j + 1, k), false));
                    }
                    if k + 1 < nz {
                        edges.push((a, id(i, j, k + 1), false));
                    }
                }
            }
        }
        // Edges whose first node's owner is this rank; rows of the second may be off-rank.
        let mine: Vec<(usize, usize, bool)> = edges
            .into_iter()
            .filter(|&(a, _, _)| layout.owner(a) == comm.rank())
            .collect();
        let pairs: Vec<(usize, usize)> = mine
            .iter()
            .flat_map(|&(a, b, _)| [(a, a), (a, b), (b, a), (b, b)])
            .collect();
        let mut m = DistMatrix::new(comm, layout.clone(), &pairs);
        let kk = [[2.0, 0.5, 0.1], [0.5, 1.5, 0.2], [0.1, 0.2, 1.0]];
        let mut ke = vec![0.0; 36];
        for p in 0..2 {
            for q in 0..2 {
                let sign = if p == q { 1.0 } else { -1.0 };
                for i in 0..3 {
                    for j in 0..3 {
                        ke[(3 * p + i) * 6 + 3 * q + j] = sign * kk[i][j];
                    }
                }
            }
        }
        for &(a, b, along_x) in &mine {
            m.add_element(&[a, b], &ke);
            if along_x && skew != 0.0 {
                let s = |v: f64| [v, 0.0, 0.0, 0.0, v, 0.0, 0.0, 0.0, v];
                m.add_block(a, b, &s(skew));
                m.add_block(b, a, &s(-skew));
            }
        }
        for g in layout.start()..layout.end() {
            m.add_block(g, g, &[shift, 0.0, 0.0, 0.0, shift, 0.0, 0.0, 0.0, shift]);
        }
        m.finish_assembly(comm);
        m
    }

    fn rhs(layout: &Layout) -> Vec<f64> {
        (3 * layout.start()..3 * layout.end())
            .map(|i| 1.0 + ((i * 7919) % 13) as f64 * 0.1)
            .collect()
    }

    fn true_rel_residual(comm: &dyn Comm, m: &DistMatrix, b: &[f64], x: &[f64]) -> f64 {
        let mut ax = vec![0.0; b.len()];
        m.spmv(comm, x, &mut ax);
        let r: Vec<f64> = b.iter().zip(&ax).map(|(b, a)| b - a).collect();
        comm.norm2(&r) / comm.norm2(b)
    }

    const DIMS: (usize, usize, usize) = (12, 12, 12); // 1728 blocks, 5184 unknowns

    fn counts(p: usize) -> Vec<usize> {
        let n = DIMS.0 * DIMS.1 * DIMS.2;
        match p {
            1 => vec![n],
            3 => vec![600, 500, n - 1100],
            _ => unreachable!(),
        }
    }

    #[test]
    fn one_rank_block_jacobi_is_exact_so_one_iteration() {
        let c = SerialComm;
        let mut m = grid_matrix(&c, DIMS, &counts(1), 0.01, 0.0);
        for kind in [Factorization::Auto, Factorization::Lu] {
            let bj = BlockJacobi::with_factorization(&m, kind).unwrap();
            let b = rhs(m.layout());
            let mut x = vec![0.0; b.len()];
            let st = gmres(&c, &mut m, &bj, &b, &mut x, &GmresOptions::default()).unwrap();
            assert!(st.converged, "{kind:?} {st:?}");
            assert_eq!(st.iterations, 1, "{kind:?} {st:?}");
            assert!(true_rel_residual(&c, &m, &b, &x) <= 1e-8);
        }
    }

    #[test]
    fn block_jacobi_on_three_ranks_matches_one_rank() {
        let opts = GmresOptions {
            rtol: 1e-10,
            ..Default::default()
        };
        let serial = {
            let c = SerialComm;
            let mut m = grid_matrix(&c, DIMS, &counts(1), 0.01, 0.0);
            let bj = BlockJacobi::new(&m).unwrap();
            let b = rhs(m.layout());
            let mut x = vec![0.0; b.len()];
            gmres(&c, &mut m, &bj, &b, &mut x, &opts).unwrap();
            x
        };
        let out = run_ranks(3, |c| {
            let mut m = grid_matrix(c, DIMS, &counts(3), 0.01, 0.0);
            let bj = BlockJacobi::new(&m).unwrap();
            let b = rhs(m.layout());
            let mut x = vec![0.0; b.len()];
            let st = gmres(c, &mut m, &bj, &b, &mut x, &opts).unwrap();
            assert!(st.converged, "{st:?}");
            let rel = true_rel_residual(c, &m, &b, &x);
            assert!(rel <= 1e-10, "true residual {rel:e}");
            assert!((st.residual_norm / st.rhs_norm - rel).abs() <= 1e-3 * rel + 1e-15);
            // 2 reductions per iteration, plus ‖b‖ and one per cycle (+ rare fallbacks).
            assert!(
                st.reductions <= 2 * st.iterations + st.restarts + 4,
                "{st:?}"
            );
            assert!(st.iterations > 1 && st.iterations < 200, "{st:?}");
            (x, st)
        });
        let x3: Vec<f64> = out.iter().flat_map(|(x, _)| x.clone()).collect();
        let diff = x3
            .iter()
            .zip(&serial)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
            .sqrt();
        let norm = serial.iter().map(|a| a * a).sum::<f64>().sqrt();
        assert!(diff <= 1e-8 * norm, "{diff:e} vs {norm:e}");
        eprintln!("3-rank block Jacobi GMRES: {:?}", out[0].1);
    }

    #[test]
    fn non_symmetric_system_converges_on_three_ranks() {
        run_ranks(3, |c| {
            let mut m = grid_matrix(c, DIMS, &counts(3), 0.05, 0.8);
            let bj = BlockJacobi::new(&m).unwrap();
            let b = rhs(m.layout());
            let mut x = vec![0.0; b.len()];
            let st = gmres(c, &mut m, &bj, &b, &mut x, &GmresOptions::default()).unwrap();
            assert!(st.converged, "{st:?}");
            assert!(true_rel_residual(c, &m, &b, &x) <= 1e-8);
        });
    }

    #[test]
    fn restarts_with_identity_preconditioner() {
        let c = SerialComm;
        let mut m = grid_matrix(&c, (10, 10, 10), &[1000], 0.05, 0.3);
        let b = rhs(m.layout());
        let mut x = vec![0.0; b.len()];
        let opts = GmresOptions {
            restart: 10,
            max_iterations: 5000,
            ..Default::default()
        };
        let st = gmres(&c, &mut m, &Identity, &b, &mut x, &opts).unwrap();
        assert!(st.converged, "{st:?}");
        assert!(
            st.restarts >= 2 && st.iterations > 2 * opts.restart,
            "{st:?}"
        );
        assert!(true_rel_residual(&c, &m, &b, &x) <= 1e-8);
        assert!(
            st.reductions <= 2 * st.iterations + st.restarts + 4,
            "{st:?}"
        );

        // Budget exhausted: not converged, but Ok and x improved.
        let mut x = vec![0.0; b.len()];
        let opts = GmresOptions {
            restart: 10,
            max_iterations: 15,
            ..Default::default()
        };
        let st = gmres(&c, &mut m, &Identity, &b, &mut x, &opts).unwrap();
        assert!(!st.converged && st.iterations == 15, "{st:?}");
        assert!(st.residual_norm < st.rhs_norm);
    }

    #[test]
    fn zero_rhs_and_initial_guess_and_operator_error() {
        let c = SerialComm;
        let mut m = grid_matrix(&c, (4, 4, 4), &[64], 0.1, 0.0);
        let b = vec![0.0; 192];
        let mut x = vec![1.0; 192];
        let st = gmres(&c, &mut m, &Identity, &b, &mut x, &GmresOptions::default()).unwrap();
        assert!(st.converged && st.iterations == 0);
        assert!(x.iter().all(|&v| v == 0.0));

        // An exact initial guess: no iterations.
        let bj = BlockJacobi::new(&m).unwrap();
        let b = rhs(m.layout());
        let mut x = vec![0.0; 192];
        gmres(
            &c,
            &mut m,
            &bj,
            &b,
            &mut x,
            &GmresOptions {
                rtol: 1e-12,
                ..Default::default()
            },
        )
        .unwrap();
        let st = gmres(&c, &mut m, &bj, &b, &mut x, &GmresOptions::default()).unwrap();
        assert!(st.converged && st.iterations == 0, "{st:?}");

        struct Failing(usize);
        impl LinearOperator for Failing {
            fn apply(&mut self, _: &dyn Comm, x: &[f64], y: &mut [f64]) -> crate::Result<()> {
                self.0 += 1;
                if self.0 > 3 {
                    return Err(Error::convergence("element inverted"));
                }
                for (i, (yi, xi)) in y.iter_mut().zip(x).enumerate() {
                    *yi = (1.0 + i as f64) * xi;
                }
                Ok(())
            }
        }
        let mut x = vec![0.0; 192];
        let e = gmres(
            &c,
            &mut Failing(0),
            &Identity,
            &b,
            &mut x,
            &GmresOptions::default(),
        )
        .unwrap_err();
        assert_eq!(e.message, "element inverted");
    }

    #[test]
    fn singular_operator_stops_without_converging() {
        // diag(1, 1, ..., 0): b with a component in the null direction cannot be matched.
        struct Diag;
        impl LinearOperator for Diag {
            fn apply(&mut self, _: &dyn Comm, x: &[f64], y: &mut [f64]) -> crate::Result<()> {
                y.copy_from_slice(x);
                *y.last_mut().unwrap() = 0.0;
                Ok(())
            }
        }
        let b = vec![1.0; 30];
        let mut x = vec![0.0; 30];
        let st = gmres(
            &SerialComm,
            &mut Diag,
            &Identity,
            &b,
            &mut x,
            &GmresOptions::default(),
        )
        .unwrap();
        assert!(!st.converged, "{st:?}");
        assert!(st.iterations < 10, "{st:?}");
        assert!((st.residual_norm - 1.0).abs() < 1e-12, "{st:?}");
    }
}
