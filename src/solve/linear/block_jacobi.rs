//! Block-Jacobi preconditioner: this rank's diagonal block (owned rows × owned columns,
//! scalar) factored exactly with faer's sparse LU (COLAMD ordering, partial pivoting).
//!
//! The symbolic factorization (ordering, elimination structure) is computed once in
//! [`BlockJacobi::new`]; [`BlockJacobi::refactor`] copies the new values of the same
//! pattern through a precomputed gather map into the CSC value array and refactors
//! numerically only. The preconditioner is local: applying it needs no communication.
//!
//! faer's numeric LU does not report an exactly zero pivot (it divides by it), so after
//! each factorization a check solve `A z = A·1` is run: a non-finite or far-off `z`
//! means the block is singular to working precision and is reported as an `Err`.
//! Factorization is local: callers agree on failure across ranks with `Comm::all_ok`.

use super::{DistMatrix, Preconditioner};
use crate::Error;
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Lu as SparseLu, SymbolicLu};
use faer::sparse::linalg::LuError;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use std::time::Instant;

pub struct BlockJacobi {
    n: usize,
    /// Pattern of the diagonal block (scalar CSC, sorted row indices).
    pattern: SymbolicSparseColMat<usize>,
    /// For each CSC position, the index into the matrix's block value array.
    src: Vec<usize>,
    csc_vals: Vec<f64>,
    nnz_blocks: usize,
    symbolic: Option<SymbolicLu<usize>>,
    lu: Option<SparseLu<usize, f64>>,
    factorizations: usize,
    symbolic_factorizations: usize,
    symbolic_seconds: f64,
    last_factor_seconds: f64,
}

impl std::fmt::Debug for BlockJacobi {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BlockJacobi")
            .field("n", &self.n)
            .field("nnz", &self.src.len())
            .field("factorizations", &self.factorizations)
            .finish()
    }
}

impl BlockJacobi {
    /// Symbolic and numeric factorization of `mat`'s local diagonal block.
    pub fn new(mat: &DistMatrix) -> crate::Result<Self> {
        let n_own = mat.layout().owned_len();
        let n = 3 * n_own;
        // Column counts: every diagonal-part block entry in block column k puts 3 entries
        // in each of the scalar columns 3k, 3k+1, 3k+2.
        let mut col_ptr = vec![0usize; n + 1];
        for i in 0..n_own {
            for e in mat.diag_begin[i]..mat.diag_end[i] {
                let k = mat.lcol[e] as usize;
                for b in 0..3 {
                    col_ptr[3 * k + b + 1] += 3;
                }
            }
        }
        for j in 0..n {
            col_ptr[j + 1] += col_ptr[j];
        }
        let nnz = col_ptr[n];
        let mut next = col_ptr[..n].to_vec();
        let mut row_idx = vec![0usize; nnz];
        let mut src = vec![0usize; nnz];
        // Rows in increasing order, so each column's row indices come out sorted.
        for i in 0..n_own {
            for a in 0..3 {
                for e in mat.diag_begin[i]..mat.diag_end[i] {
                    let k = mat.lcol[e] as usize;
                    for b in 0..3 {
                        let p = next[3 * k + b];
                        next[3 * k + b] += 1;
                        row_idx[p] = 3 * i + a;
                        src[p] = 9 * e + 3 * a + b;
                    }
                }
            }
        }
        let pattern = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let mut bj = Self {
            n,
            pattern,
            src,
            csc_vals: vec![0.0; nnz],
            nnz_blocks: mat.nnz_blocks_local(),
            symbolic: None,
            lu: None,
            factorizations: 0,
            symbolic_factorizations: 0,
            symbolic_seconds: 0.0,
            last_factor_seconds: 0.0,
        };
        if n > 0 {
            let t = Instant::now();
            let sym = SymbolicLu::try_new(bj.pattern.as_ref()).map_err(|e| {
                Error::runtime(format!(
                    "block Jacobi: symbolic LU of the local {n}×{n} block failed: {e:?}"
                ))
            })?;
            bj.symbolic = Some(sym);
            bj.symbolic_factorizations += 1;
            bj.symbolic_seconds = t.elapsed().as_secs_f64();
        }
        bj.refactor(mat)?;
        Ok(bj)
    }

    /// Numeric refactorization for new values of the same pattern (symbolic reused).
    pub fn refactor(&mut self, mat: &DistMatrix) -> crate::Result<()> {
        if mat.n_owned_dofs() != self.n || mat.nnz_blocks_local() != self.nnz_blocks {
            return Err(Error::runtime(format!(
                "block Jacobi: refactor with a different pattern ({} dofs, {} blocks; factored \
                 {} dofs, {} blocks)",
                mat.n_owned_dofs(),
                mat.nnz_blocks_local(),
                self.n,
                self.nnz_blocks
            )));
        }
        let t = Instant::now();
        self.lu = None;
        if self.n == 0 {
            self.factorizations += 1;
            self.last_factor_seconds = 0.0;
            return Ok(());
        }
        for (v, &s) in self.csc_vals.iter_mut().zip(&self.src) {
            *v = mat.vals[s];
        }
        let a = SparseColMatRef::new(self.pattern.as_ref(), &self.csc_vals);
        let sym = self
            .symbolic
            .clone()
            .expect("symbolic factorization present");
        let lu = SparseLu::try_new_with_symbolic(sym, a).map_err(|e| match e {
            LuError::SymbolicSingular { index } => Error::runtime(format!(
                "block Jacobi: the local {}×{} diagonal block is singular (no pivot at step \
                 {index}); check constraints and contact multiplier rows",
                self.n, self.n
            )),
            LuError::Generic(g) => Error::runtime(format!("block Jacobi: sparse LU failed: {g:?}")),
        })?;
        self.check_nonsingular(&lu, a)?;
        self.lu = Some(lu);
        self.factorizations += 1;
        self.last_factor_seconds = t.elapsed().as_secs_f64();
        Ok(())
    }

    /// Solve A z = A·1 and require z ≈ 1: catches zero pivots (inf/NaN) and blocks that
    /// are singular to working precision (error ≥ 1 means cond ≳ 1/ε).
    fn check_nonsingular(
        &self,
        lu: &SparseLu<usize, f64>,
        a: SparseColMatRef<'_, usize, f64>,
    ) -> crate::Result<()> {
        let mut z = vec![0.0; self.n];
        let (sym, vals) = a.parts();
        let (cp, ri) = (sym.col_ptr(), sym.row_idx());
        for j in 0..self.n {
            for p in cp[j]..cp[j + 1] {
                z[ri[p]] += vals[p];
            }
        }
        lu.solve_in_place(faer::ColMut::from_slice_mut(&mut z));
        let err = z.iter().map(|v| (v - 1.0).abs()).fold(0.0f64, |m, e| {
            if e.is_nan() {
                f64::INFINITY
            } else {
                m.max(e)
            }
        });
        if !err.is_finite() || err > 1.0 {
            return Err(Error::runtime(format!(
                "block Jacobi: the local {}×{} diagonal block is numerically singular (check \
                 solve error {err:.3e}); check constraints and contact multiplier rows",
                self.n, self.n
            )));
        }
        Ok(())
    }

    /// Size of the factored block (owned scalar dofs).
    pub fn n(&self) -> usize {
        self.n
    }
    /// Scalar nonzeros of the factored block.
    pub fn nnz(&self) -> usize {
        self.src.len()
    }
    /// Numeric factorizations done (the first one included).
    pub fn factorizations(&self) -> usize {
        self.factorizations
    }
    /// Symbolic factorizations done (1 unless the block is empty).
    pub fn symbolic_factorizations(&self) -> usize {
        self.symbolic_factorizations
    }
    /// Wall time of the symbolic factorization (ordering and structure).
    pub fn symbolic_seconds(&self) -> f64 {
        self.symbolic_seconds
    }
    /// Wall time of the last numeric factorization (value gather, LU, check solve).
    pub fn last_factor_seconds(&self) -> f64 {
        self.last_factor_seconds
    }
}

impl Preconditioner for BlockJacobi {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        z.copy_from_slice(r);
        if let Some(lu) = &self.lu {
            lu.solve_in_place(faer::ColMut::from_slice_mut(z));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parallel::{Comm, Layout, SerialComm};
    use crate::solve::linear::matrix::tests::Lcg;

    /// A small 1-rank block tridiagonal matrix with random non-symmetric blocks and a
    /// dominant diagonal.
    fn tridiag(n: usize, seed: u64, diag: f64) -> DistMatrix {
        let pairs: Vec<(usize, usize)> = (0..n)
            .flat_map(|i| [(i, i), (i, (i + 1) % n), ((i + 1) % n, i)])
            .collect();
        let mut m = DistMatrix::new(&SerialComm, Layout::from_counts(&[n], 0), &pairs);
        let mut rng = Lcg(seed);
        for i in 0..n {
            let mut d = [0.0; 9];
            for (k, v) in d.iter_mut().enumerate() {
                *v = 0.3 * rng.next() + if k % 4 == 0 { diag } else { 0.0 };
            }
            m.add_block(i, i, &d);
            let o: [f64; 9] = std::array::from_fn(|_| rng.next());
            m.add_block(i, (i + 1) % n, &o);
            let o: [f64; 9] = std::array::from_fn(|_| rng.next());
            m.add_block((i + 1) % n, i, &o);
        }
        m.finish_assembly(&SerialComm);
        m
    }

    fn residual(m: &DistMatrix, z: &[f64], r: &[f64]) -> f64 {
        let mut az = vec![0.0; r.len()];
        m.spmv(&SerialComm, z, &mut az);
        let e: f64 = az
            .iter()
            .zip(r)
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            .sqrt();
        e / SerialComm.norm2(r)
    }

    #[test]
    fn exact_solve_on_one_rank_and_refactor_with_new_values() {
        let m1 = tridiag(50, 1, 6.0);
        let mut bj = BlockJacobi::new(&m1).unwrap();
        let r: Vec<f64> = (0..150).map(|i| (i as f64).sin()).collect();
        let mut z = vec![0.0; 150];
        bj.apply(&r, &mut z);
        assert!(residual(&m1, &z, &r) < 1e-13);

        // Same pattern, other values: the old factors no longer solve it, the new ones do.
        let m2 = tridiag(50, 2, 4.0);
        bj.apply(&r, &mut z);
        assert!(residual(&m2, &z, &r) > 1e-3);
        bj.refactor(&m2).unwrap();
        bj.apply(&r, &mut z);
        assert!(residual(&m2, &z, &r) < 1e-13);
        assert_eq!(bj.factorizations(), 2);
        assert_eq!(bj.symbolic_factorizations(), 1);
        assert!(bj.last_factor_seconds() > 0.0);
    }

    #[test]
    fn singular_block_is_an_error_not_a_panic() {
        // All zero: no pivot at all.
        let mut m = tridiag(10, 3, 5.0);
        m.zero();
        let e = BlockJacobi::new(&m).unwrap_err();
        assert!(e.message.contains("singular"), "{}", e.message);

        // Two equal scalar rows (dofs 0 and 1 of block 0 coincide): numerically singular.
        let mut m = tridiag(10, 3, 5.0);
        let mut bj = BlockJacobi::new(&m).unwrap();
        for e in m.row_ptr[0]..m.row_ptr[1] {
            let v = &mut m.vals[9 * e..9 * e + 9];
            for b in 0..3 {
                v[3 + b] = v[b];
            }
        }
        let e = bj.refactor(&m).unwrap_err();
        assert!(e.message.contains("singular"), "{}", e.message);
    }

    #[test]
    fn pattern_change_is_refused() {
        let m1 = tridiag(10, 1, 6.0);
        let m2 = tridiag(11, 1, 6.0);
        let mut bj = BlockJacobi::new(&m1).unwrap();
        assert!(bj.refactor(&m2).is_err());
    }

    /// Stiffness of a trilinear hex8 cube of side `h` (isotropic linear elasticity,
    /// 2×2×2 Gauss), nodes in the usual order (bottom face counter-clockwise, then top).
    pub(crate) fn hex8_stiffness(h: f64, e: f64, nu: f64) -> Vec<f64> {
        let lam = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let mu = e / (2.0 * (1.0 + nu));
        let corners = [
            [-1.0, -1.0, -1.0],
            [1.0, -1.0, -1.0],
            [1.0, 1.0, -1.0],
            [-1.0, 1.0, -1.0],
            [-1.0, -1.0, 1.0],
            [1.0, -1.0, 1.0],
            [1.0, 1.0, 1.0],
            [-1.0, 1.0, 1.0],
        ];
        let gp = 1.0 / 3f64.sqrt();
        let det = (h / 2.0).powi(3);
        let mut ke = vec![0.0; 24 * 24];
        for q in &corners {
            let x = [q[0] * gp, q[1] * gp, q[2] * gp];
            let grad: Vec<[f64; 3]> = corners
                .iter()
                .map(|c| {
                    let f = [
                        (1.0 + c[0] * x[0]),
                        (1.0 + c[1] * x[1]),
                        (1.0 + c[2] * x[2]),
                    ];
                    let s = 2.0 / h / 8.0;
                    [
                        s * c[0] * f[1] * f[2],
                        s * c[1] * f[0] * f[2],
                        s * c[2] * f[0] * f[1],
                    ]
                })
                .collect();
            for a in 0..8 {
                for b in 0..8 {
                    let gg: f64 = (0..3).map(|k| grad[a][k] * grad[b][k]).sum();
                    for i in 0..3 {
                        for j in 0..3 {
                            let mut v =
                                lam * grad[a][i] * grad[b][j] + mu * grad[a][j] * grad[b][i];
                            if i == j {
                                v += mu * gg;
                            }
                            ke[(3 * a + i) * 24 + 3 * b + j] += v * det;
                        }
                    }
                }
            }
        }
        ke
    }

    /// A cube of `ne³` hex8 elasticity elements, clamped on z = 0, rows split by `counts`
    /// (node blocks, numbered x fastest). Elements are assembled by the owner of their
    /// first node.
    pub(crate) fn elasticity_cube(comm: &dyn Comm, ne: usize, counts: &[usize]) -> DistMatrix {
        let nn = ne + 1;
        let id = |i: usize, j: usize, k: usize| i + nn * (j + nn * k);
        let layout = Layout::from_counts(counts, comm.rank());
        let mut els = Vec::new();
        for k in 0..ne {
            for j in 0..ne {
                for i in 0..ne {
                    let el = [
                        id(i, j, k),
                        id(i + 1, j, k),
                        id(i + 1, j + 1, k),
                        id(i, j + 1, k),
                        id(i, j, k + 1),
                        id(i + 1, j, k + 1),
                        id(i + 1, j + 1, k + 1),
                        id(i, j + 1, k + 1),
                    ];
                    if layout.owner(el[0]) == comm.rank() {
                        els.push(el);
                    }
                }
            }
        }
        let pairs: Vec<(usize, usize)> = els
            .iter()
            .flat_map(|el| el.iter().flat_map(|&a| el.iter().map(move |&b| (a, b))))
            .collect();
        let mut m = DistMatrix::new(comm, layout.clone(), &pairs);
        let ke = hex8_stiffness(1.0 / ne as f64, 1.0, 0.3);
        for el in &els {
            m.add_element(el, &ke);
        }
        m.finish_assembly(comm);
        let s = layout.start();
        let clamped: Vec<usize> = (s..layout.end().min(nn * nn).max(s))
            .flat_map(|g| (0..3).map(move |c| 3 * (g - s) + c))
            .collect();
        m.constrain(comm, &clamped);
        m
    }

    #[test]
    fn hex8_stiffness_has_rigid_body_null_space() {
        let ke = hex8_stiffness(0.5, 200.0, 0.3);
        for dir in 0..3 {
            let u: Vec<f64> = (0..24)
                .map(|k| if k % 3 == dir { 1.0 } else { 0.0 })
                .collect();
            for r in 0..24 {
                let f: f64 = (0..24).map(|c| ke[r * 24 + c] * u[c]).sum();
                assert!(f.abs() < 1e-10, "translation {dir} row {r}: {f}");
            }
        }
        for r in 0..24 {
            for c in 0..24 {
                assert!((ke[r * 24 + c] - ke[c * 24 + r]).abs() < 1e-10);
            }
        }
    }

    /// Timing of faer's LU (COLAMD) on a ~100k-unknown elasticity block, and block
    /// Jacobi GMRES on 2 thread ranks. Run with
    /// `cargo test --release --lib timing_elasticity_100k -- --ignored --nocapture`.
    #[test]
    #[ignore]
    fn timing_elasticity_100k() {
        use crate::parallel::run_ranks;
        use crate::solve::linear::{gmres, GmresOptions};
        faer::set_global_parallelism(faer::Par::Seq);
        let ne = 31; // 32³ nodes = 98304 unknowns
        let n_blocks = (ne + 1) * (ne + 1) * (ne + 1);
        let t = Instant::now();
        let mut m = elasticity_cube(&SerialComm, ne, &[n_blocks]);
        let t_asm = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let mut bj = BlockJacobi::new(&m).unwrap();
        let t_first = t.elapsed().as_secs_f64();
        let t = Instant::now();
        bj.refactor(&m).unwrap();
        let t_refactor = t.elapsed().as_secs_f64();
        let b: Vec<f64> = (0..m.n_owned_dofs())
            .map(|i| if i % 3 == 2 { -1.0 } else { 0.1 })
            .collect();
        let mut z = vec![0.0; b.len()];
        let t = Instant::now();
        bj.apply(&b, &mut z);
        let t_solve = t.elapsed().as_secs_f64();
        let mut x = vec![0.0; b.len()];
        let st = gmres(
            &SerialComm,
            &mut m,
            &bj,
            &b,
            &mut x,
            &GmresOptions::default(),
        )
        .unwrap();
        eprintln!(
            "1 rank: n = {}, nnz = {}; assembly {t_asm:.2} s; symbolic {:.2} s; first numeric {:.2} s \
             (new total {t_first:.2} s); refactor {t_refactor:.2} s; one solve {t_solve:.3} s; \
             GMRES {} it",
            bj.n(),
            bj.nnz(),
            bj.symbolic_seconds(),
            t_first - bj.symbolic_seconds(),
            st.iterations
        );
        assert!(st.converged && st.iterations == 1);

        // For comparison: sparse Cholesky (AMD ordering) of the same SPD block.
        {
            use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
            let t = Instant::now();
            let sym = SymbolicLlt::try_new(bj.pattern.as_ref(), faer::Side::Lower).unwrap();
            let t_sym = t.elapsed().as_secs_f64();
            let t = Instant::now();
            let a = SparseColMatRef::new(bj.pattern.as_ref(), &bj.csc_vals);
            let llt = Llt::try_new_with_symbolic(sym, a, faer::Side::Lower).unwrap();
            let t_num = t.elapsed().as_secs_f64();
            let mut z2 = b.clone();
            let t = Instant::now();
            llt.solve_in_place(faer::ColMut::from_slice_mut(&mut z2));
            let t_sol = t.elapsed().as_secs_f64();
            let diff = z
                .iter()
                .zip(&z2)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            eprintln!(
                "1 rank Cholesky (AMD) for comparison: symbolic {t_sym:.2} s, numeric {t_num:.2} s, \
                 solve {t_sol:.3} s, max |z_lu - z_llt| = {diff:.1e}"
            );
        }

        for p in [2usize, 4] {
            let counts: Vec<usize> = (0..p)
                .map(|r| n_blocks * (r + 1) / p - n_blocks * r / p)
                .collect();
            let out = run_ranks(p, |c| {
                let mut m = elasticity_cube(c, ne, &counts);
                let t = Instant::now();
                let bj = BlockJacobi::new(&m).unwrap();
                let t_fac = t.elapsed().as_secs_f64();
                let b: Vec<f64> = (0..m.n_owned_dofs())
                    .map(|i| if i % 3 == 2 { -1.0 } else { 0.1 })
                    .collect();
                let mut x = vec![0.0; b.len()];
                let t = Instant::now();
                let st = gmres(c, &mut m, &bj, &b, &mut x, &GmresOptions::default()).unwrap();
                (t_fac, t.elapsed().as_secs_f64(), st)
            });
            let (_, t_gm, st) = &out[0];
            let facs: Vec<String> = out.iter().map(|o| format!("{:.2}", o.0)).collect();
            eprintln!(
                "{p} thread ranks (on 2 cores): factor per rank [{}] s; GMRES {} it, {:.2} s, \
                 converged {}, {} reductions",
                facs.join(", "),
                st.iterations,
                t_gm,
                st.converged,
                st.reductions
            );
        }
    }
}
