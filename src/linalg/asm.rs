//! Restricted additive Schwarz (RAS) with one layer of overlap (Cai & Sarkis 1999).
//!
//! Rank i's subdomain is its owned block rows plus its *ghost* blocks (the block columns
//! of its owned rows owned elsewhere, [`DistMatrix::ghost_blocks`]): the first layer of
//! overlap in the matrix graph. The subdomain matrix A_i = A[S, S], S = owned ∪ ghost, is
//! the principal submatrix of the assembled (and constrained) global matrix: the owned
//! rows as stored (all their columns are in S), and the ghost rows received from their
//! owners with the columns outside S dropped (a homogeneous Dirichlet condition on the
//! outer boundary of the overlap). It is factored exactly by a [`LocalFactor`] (Cholesky
//! while symmetric positive definite, else LU; nested dissection; symbolic reuse), so a
//! refactorization for new values costs one value exchange plus the numeric factorization.
//!
//! Application: z = R_i⁰ A_i⁻¹ R_i r: r is gathered on the ghosts (one halo exchange),
//! the subdomain system is solved, and only the owned part is kept (the *restricted*
//! prolongation R_i⁰: no sum over the overlap, hence no second exchange, and it
//! converges better than classical ASM). The preconditioner is not symmetric, which
//! GMRES does not need. On one rank there are no ghosts and it is the exact solve.
//!
//! Rows of the constrained matrix arrive already constrained: [`DistMatrix::constrain`]
//! zeroes the rows and the columns of constrained dofs in every rank's rows.

use super::block_jacobi::{FactorOptions, Factorization, FillOrdering, LocalFactor};
use super::block_pattern::LocalBlockPattern;
use super::coarse::{LocalSolver, RingCoupling};
use super::{DistMatrix, Preconditioner};
use crate::parallel::{Comm, HaloPlan};
use crate::Error;

/// Restricted additive Schwarz with one layer of overlap; see the module documentation.
#[derive(Debug)]
pub struct RestrictedSchwarz {
    /// Owned and ghost blocks.
    n_own: usize,
    n_ghost: usize,
    /// The matrix's own ghost blocks (the first layer), for the same-pattern check.
    n_matrix_ghosts: usize,
    /// The matrix's dof-level halo plan (forward: r on the ghosts).
    halo: HaloPlan,
    /// Owned local rows whose values go to each neighbour (grouped by destination).
    send_rows: Vec<usize>,
    /// f64 values sent to / received from each rank per factorization.
    send_val_counts: Vec<usize>,
    recv_val_counts: Vec<usize>,
    /// Block entries of the matrix's owned rows (the received values follow them in
    /// `vals`).
    nnz_blocks: usize,
    /// The factor's value array: the matrix's owned values, then the received rows'.
    vals: Vec<f64>,
    factor: LocalFactor,
    /// The subdomain's blocks (owned, then ghosts; global), and the received rows'
    /// couplings to blocks beyond the overlap, entries into `vals`: what a coarse space
    /// extends with ([`super::coarse::LocalSolver`]).
    blocks: Vec<usize>,
    ring: Vec<RingCoupling>,
}

impl std::ops::Deref for RestrictedSchwarz {
    type Target = LocalFactor;
    fn deref(&self) -> &LocalFactor {
        &self.factor
    }
}

impl RestrictedSchwarz {
    /// Collective: gather the ghost rows of `mat` and factor the subdomain matrix
    /// ([`Factorization::Auto`], nested dissection).
    pub fn new(comm: &dyn Comm, mat: &DistMatrix) -> crate::Result<Self> {
        Self::with_options(comm, mat, Factorization::Auto, FillOrdering::default())
    }

    /// Collective; with the given kind of factorization and fill-reducing ordering.
    /// A factorization failure is local (callers agree on it with `Comm::all_ok`).
    pub fn with_options(
        comm: &dyn Comm,
        mat: &DistMatrix,
        choice: Factorization,
        ordering: FillOrdering,
    ) -> crate::Result<Self> {
        let opts = FactorOptions {
            factorization: choice,
            ordering,
            ..FactorOptions::default()
        };
        Self::with_factor_options(comm, mat, opts)
    }

    /// Collective; factored as `opts` says, with `opts.overlap` layers (at least one).
    pub fn with_factor_options(
        comm: &dyn Comm,
        mat: &DistMatrix,
        opts: FactorOptions,
    ) -> crate::Result<Self> {
        let layout = mat.layout();
        let (start, end) = (layout.start(), layout.end());
        let n_own = layout.owned_len();
        let ghosts = overlap_blocks(comm, mat, opts.overlap.max(1));
        let n_ghost = ghosts.len();
        // Block-level plan of the ghost rows, and the dof-level plan of their unknowns.
        let rows_plan = HaloPlan::new(comm, layout, ghosts.clone());
        let send_rows: Vec<usize> = rows_plan.send_indices().to_vec();
        let send_row_counts: Vec<usize> = rows_plan.send_counts().to_vec();
        let dof_ghosts: Vec<usize> = ghosts.iter().flat_map(|&g| 3 * g..3 * g + 3).collect();
        let halo = HaloPlan::new(comm, &super::matrix::scalar_layout(layout), dof_ghosts);

        // The pattern of the rows we send: [row length, global columns...] per row.
        let p = comm.size();
        let (send_pat, send_pat_counts, send_val_counts) =
            row_patterns(mat, &send_rows, &send_row_counts);
        let recv_pat_counts = comm.alltoall_counts(&send_pat_counts);
        let recv_pat = comm.alltoallv_u64(&send_pat, &send_pat_counts, &recv_pat_counts);

        // Local numbering: owned blocks 0..n_own, then ghosts in sorted order.
        let local_of = |g: usize| -> Option<usize> {
            if g >= start && g < end {
                Some(g - start)
            } else {
                ghosts.binary_search(&g).ok().map(|q| n_own + q)
            }
        };
        let nnz_blocks = mat.nnz_blocks_local();
        let mut pat = LocalBlockPattern {
            n_nodes: n_own + n_ghost,
            row_ptr: Vec::with_capacity(n_own + n_ghost + 1),
            cols: Vec::with_capacity(nnz_blocks),
            entries: Vec::with_capacity(nnz_blocks),
            // Only owned element rows are marked: a neighbour's pressure block that is a
            // ghost here stays in the overlap's factor as it is.
            element_rows: (0..n_own + n_ghost)
                .map(|i| i < n_own && mat.is_element_row(i))
                .collect(),
        };
        pat.row_ptr.push(0);
        for i in 0..n_own {
            for e in mat.row_ptr[i]..mat.row_ptr[i + 1] {
                let k = mat.lcol[e] as usize;
                let diag = e >= mat.diag_begin[i] && e < mat.diag_end[i];
                let g = if diag {
                    start + k
                } else {
                    mat.ghost_blocks()[k]
                };
                pat.cols
                    .push(local_of(g).expect("a column of an owned row is local"));
                pat.entries.push(e);
            }
            pat.row_ptr.push(pat.cols.len());
        }
        // Received rows arrive in ghost order: sorted, so grouped by owner, and each
        // owner sends them in the order they were requested (sorted).
        let mut recv_val_counts = vec![0usize; p];
        let mut ring = Vec::new();
        let mut pos = 0;
        let mut entry = nnz_blocks;
        let mut src = 0;
        let mut from_src = 0;
        let recv_rows = rows_plan.recv_counts();
        for q in 0..n_ghost {
            while from_src == recv_rows[src] {
                src += 1;
                from_src = 0;
            }
            let len = recv_pat[pos] as usize;
            for &g in &recv_pat[pos + 1..pos + 1 + len] {
                if let Some(l) = local_of(g as usize) {
                    pat.cols.push(l);
                    pat.entries.push(entry);
                } else {
                    ring.push(RingCoupling {
                        row: n_own + q,
                        col: g as usize,
                        entry,
                    });
                }
                entry += 1;
            }
            recv_val_counts[src] += 9 * len;
            from_src += 1;
            pos += 1 + len;
            pat.row_ptr.push(pat.cols.len());
        }
        debug_assert_eq!(pos, recv_pat.len());

        let recv = Self::exchange(comm, mat, &send_rows, &send_val_counts, &recv_val_counts);
        let mut vals = Vec::with_capacity(mat.vals.len() + recv.len());
        vals.extend_from_slice(&mat.vals);
        vals.extend_from_slice(&recv);
        let factor = LocalFactor::new("ASM", &pat, &vals, opts)?;
        let blocks = (start..end).chain(ghosts.iter().copied()).collect();
        Ok(Self {
            blocks,
            ring,
            n_own,
            n_ghost,
            n_matrix_ghosts: mat.ghost_blocks().len(),
            halo,
            send_rows,
            send_val_counts,
            recv_val_counts,
            nnz_blocks,
            vals,
            factor,
        })
    }

    /// Collective: the values of the rows other ranks hold as ghosts, one `alltoallv`.
    fn exchange(
        comm: &dyn Comm,
        mat: &DistMatrix,
        send_rows: &[usize],
        send_counts: &[usize],
        recv_counts: &[usize],
    ) -> Vec<f64> {
        let mut send = Vec::with_capacity(send_counts.iter().sum());
        for &i in send_rows {
            send.extend_from_slice(&mat.vals[9 * mat.row_ptr[i]..9 * mat.row_ptr[i + 1]]);
        }
        comm.alltoallv_f64(&send, send_counts, recv_counts)
    }

    /// Collective: exchange the new values of the ghost rows and refactor numerically
    /// (symbolic reused). A matrix of another pattern is refused on every rank.
    pub fn refactor(&mut self, comm: &dyn Comm, mat: &DistMatrix) -> crate::Result<()> {
        let same = mat.layout().owned_len() == self.n_own
            && mat.ghost_blocks().len() == self.n_matrix_ghosts
            && mat.nnz_blocks_local() == self.nnz_blocks;
        if !comm.all_ok(same) {
            return Err(Error::runtime(format!(
                "ASM: refactor with a different pattern (here {} blocks, {} ghosts, {} \
                 entries; factored {}, {}, {}; or on another rank)",
                mat.layout().owned_len(),
                mat.ghost_blocks().len(),
                mat.nnz_blocks_local(),
                self.n_own,
                self.n_matrix_ghosts,
                self.nnz_blocks
            )));
        }
        let recv = Self::exchange(
            comm,
            mat,
            &self.send_rows,
            &self.send_val_counts,
            &self.recv_val_counts,
        );
        let m = mat.vals.len();
        self.vals[..m].copy_from_slice(&mat.vals);
        self.vals[m..].copy_from_slice(&recv);
        self.factor.refactor(&self.vals)
    }

    /// Ghost (overlap) blocks of the subdomain.
    pub fn n_ghost_blocks(&self) -> usize {
        self.n_ghost
    }
}

impl LocalSolver for RestrictedSchwarz {
    fn local_blocks(&self) -> &[usize] {
        &self.blocks
    }
    fn ring_couplings(&self) -> &[RingCoupling] {
        &self.ring
    }
    fn ring_values<'a>(&'a self, _k: &'a DistMatrix) -> &'a [f64] {
        &self.vals
    }
    fn solve_local(&self, x: &mut [f64]) {
        self.factor.solve_in_place(x);
    }
    fn solve_local_many(&self, x: &mut [f64], ncols: usize) {
        self.factor.solve_many(x, ncols);
    }
}

impl Preconditioner for RestrictedSchwarz {
    fn setup(&mut self, comm: &dyn Comm, k: &DistMatrix) -> crate::Result<()> {
        self.refactor(comm, k)
    }
    fn apply(&self, comm: &dyn Comm, r: &[f64], z: &mut [f64]) {
        let n = 3 * self.n_own;
        let mut w = vec![0.0; n + 3 * self.n_ghost];
        w[..n].copy_from_slice(r);
        self.halo.forward(comm, r, &mut w[n..]);
        self.factor.solve_in_place(&mut w);
        z.copy_from_slice(&w[..n]);
    }
}

/// `[row length, global block columns...]` of each owned block row in `rows` (grouped by
/// destination, `counts` rows each), the u64 count per destination, and the values per
/// destination (9 per block).
fn row_patterns(
    mat: &DistMatrix,
    rows: &[usize],
    counts: &[usize],
) -> (Vec<u64>, Vec<usize>, Vec<usize>) {
    let mut pat: Vec<u64> = Vec::new();
    let mut pat_counts = vec![0usize; counts.len()];
    let mut val_counts = vec![0usize; counts.len()];
    let mut k = 0;
    for (dest, &c) in counts.iter().enumerate() {
        for &i in &rows[k..k + c] {
            let cols = mat.cols_of_row(i);
            pat.push(cols.len() as u64);
            pat.extend(cols.iter().map(|&g| g as u64));
            pat_counts[dest] += 1 + cols.len();
            val_counts[dest] += 9 * cols.len();
        }
        k += c;
    }
    (pat, pat_counts, val_counts)
}

/// Collective: the ghost blocks of `layers` layers of overlap around the owned rows in
/// `mat`'s graph (sorted): the first layer is the owned rows' ghost columns, each next
/// one the columns of the last layer's rows (fetched from their owners) not yet held.
fn overlap_blocks(comm: &dyn Comm, mat: &DistMatrix, layers: usize) -> Vec<usize> {
    let layout = mat.layout();
    let mut ghosts: Vec<usize> = mat.ghost_blocks().to_vec();
    let mut frontier = ghosts.clone();
    for _ in 1..layers {
        // Every rank takes part in every layer's exchange, with or without a frontier.
        let plan = HaloPlan::new(comm, layout, frontier);
        let (pat, pc, _) = row_patterns(mat, plan.send_indices(), plan.send_counts());
        let rc = comm.alltoall_counts(&pc);
        let recv = comm.alltoallv_u64(&pat, &pc, &rc);
        let mut next: Vec<usize> = Vec::new();
        let mut i = 0;
        while i < recv.len() {
            let len = recv[i] as usize;
            next.extend(
                recv[i + 1..i + 1 + len]
                    .iter()
                    .map(|&g| g as usize)
                    .filter(|&g| !layout.owns(g) && ghosts.binary_search(&g).is_err()),
            );
            i += 1 + len;
        }
        next.sort_unstable();
        next.dedup();
        ghosts.extend_from_slice(&next);
        ghosts.sort_unstable();
        frontier = next;
    }
    ghosts
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::block_jacobi::tests::elasticity_cube;
    use crate::linalg::matrix::tests::Lcg;
    use crate::linalg::{gmres, BlockJacobi, GmresOptions};
    use crate::parallel::{run_ranks, SerialComm};

    fn split(n: usize, p: usize) -> Vec<usize> {
        (0..p).map(|r| n * (r + 1) / p - n * r / p).collect()
    }

    /// The global matrix as a dense row-major array, on every rank.
    fn dense(comm: &dyn Comm, m: &DistMatrix) -> Vec<f64> {
        let n = m.n_global_dofs();
        let mut d = vec![0.0; n * n];
        let (ptr, cols, vals) = m.local_csr();
        let r0 = 3 * m.layout().start();
        for i in 0..ptr.len() - 1 {
            for p in ptr[i]..ptr[i + 1] {
                d[(r0 + i) * n + cols[p]] = vals[p];
            }
        }
        comm.allreduce_sum(&mut d);
        d
    }

    /// Solve the dense system a x = b (Gaussian elimination, partial pivoting).
    fn dense_solve(mut a: Vec<f64>, mut b: Vec<f64>) -> Vec<f64> {
        let n = b.len();
        for k in 0..n {
            let p = (k..n)
                .max_by(|&i, &j| a[i * n + k].abs().total_cmp(&a[j * n + k].abs()))
                .unwrap();
            for j in 0..n {
                a.swap(k * n + j, p * n + j);
            }
            b.swap(k, p);
            for i in k + 1..n {
                let f = a[i * n + k] / a[k * n + k];
                for j in k..n {
                    a[i * n + j] -= f * a[k * n + j];
                }
                b[i] -= f * b[k];
            }
        }
        for k in (0..n).rev() {
            let s: f64 = (k + 1..n).map(|j| a[k * n + j] * b[j]).sum();
            b[k] = (b[k] - s) / a[k * n + k];
        }
        b
    }

    /// A global vector (scalar dofs), the same on every rank.
    fn global_rhs(n: usize) -> Vec<f64> {
        (0..n).map(|i| (0.37 * i as f64).cos() + 0.1).collect()
    }

    /// Add a deterministic non-symmetric perturbation to every stored block.
    fn make_non_symmetric(comm: &dyn Comm, m: &mut DistMatrix) {
        let mut rng = Lcg(7 + comm.rank() as u64);
        for v in m.vals.iter_mut() {
            if *v != 0.0 {
                *v += 0.02 * rng.next() * v.abs();
            }
        }
    }

    #[test]
    fn one_rank_is_the_exact_solve() {
        for non_symmetric in [false, true] {
            let c = SerialComm;
            let mut m = elasticity_cube(&c, 4, &[125]);
            if non_symmetric {
                make_non_symmetric(&c, &mut m);
            }
            let ras = RestrictedSchwarz::new(&c, &m).unwrap();
            assert_eq!(ras.n_ghost_blocks(), 0);
            assert_eq!(
                ras.kind(),
                if non_symmetric {
                    Factorization::Lu
                } else {
                    Factorization::Cholesky
                }
            );
            let r = global_rhs(375);
            let mut z = vec![0.0; 375];
            ras.apply(&c, &r, &mut z);
            let mut az = vec![0.0; 375];
            m.spmv(&c, &z, &mut az);
            let err = az
                .iter()
                .zip(&r)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(err < 1e-10, "{err:e}");
        }
    }

    /// On every rank, z = R⁰ A[S, S]⁻¹ R r, with A[S, S] taken from the dense global
    /// matrix: the exchanged ghost rows, the dropped outer columns and the restriction
    /// are right, for SPD (Cholesky) and non-symmetric (LU) matrices.
    #[test]
    fn applies_the_restricted_inverse_of_the_principal_submatrix() {
        for (p, overlap) in [(2usize, 1usize), (3, 1), (2, 2), (4, 3)] {
            for non_symmetric in [false, true] {
                run_ranks(p, |c| {
                    let ne = if overlap > 1 { 5 } else { 3 };
                    let nb = (ne + 1) * (ne + 1) * (ne + 1);
                    let mut m = elasticity_cube(c, ne, &split(nb, p));
                    if non_symmetric {
                        make_non_symmetric(c, &mut m);
                    }
                    let ng = m.n_global_dofs();
                    let a = dense(c, &m);
                    let r_glob = global_rhs(ng);
                    let (s0, s1) = (m.layout().start(), m.layout().end());
                    // S: the owned blocks and `overlap` layers of block neighbours in the
                    // dense matrix's graph.
                    let nbk = ng / 3;
                    // The hex8 pattern: nodes of a common element.
                    let nn = ne + 1;
                    let ijk = |b: usize| [b % nn, (b / nn) % nn, b / (nn * nn)];
                    let linked = |i: usize, j: usize| {
                        let (p, q) = (ijk(i), ijk(j));
                        (0..3).all(|d| p[d].abs_diff(q[d]) <= 1)
                    };
                    let mut inside: Vec<bool> = (0..nbk).map(|b| b >= s0 && b < s1).collect();
                    for _ in 0..overlap {
                        let before = inside.clone();
                        for j in 0..nbk {
                            if !before[j] && (0..nbk).any(|i| before[i] && linked(i, j)) {
                                inside[j] = true;
                            }
                        }
                    }
                    let ghosts: Vec<usize> = (0..nbk)
                        .filter(|&b| inside[b] && !(b >= s0 && b < s1))
                        .collect();
                    let blocks: Vec<usize> = (s0..s1).chain(ghosts.iter().copied()).collect();
                    let dofs: Vec<usize> = blocks
                        .iter()
                        .flat_map(|&b| [3 * b, 3 * b + 1, 3 * b + 2])
                        .collect();
                    let ns = dofs.len();
                    let a_s: Vec<f64> = dofs
                        .iter()
                        .flat_map(|&i| dofs.iter().map(move |&j| (i, j)))
                        .map(|(i, j)| a[i * ng + j])
                        .collect();
                    let w = dense_solve(a_s, dofs.iter().map(|&i| r_glob[i]).collect());
                    assert_eq!(ns, w.len());

                    let opts = FactorOptions {
                        overlap,
                        ..FactorOptions::default()
                    };
                    let ras = RestrictedSchwarz::with_factor_options(c, &m, opts).unwrap();
                    assert_eq!(ras.n_ghost_blocks(), ghosts.len());
                    assert_eq!(&ras.local_blocks()[s1 - s0..], &ghosts[..]);
                    let r = &r_glob[3 * s0..3 * s1];
                    let mut z = vec![0.0; r.len()];
                    ras.apply(c, r, &mut z);
                    let scale = w.iter().fold(0.0f64, |x, v| x.max(v.abs()));
                    let err = z
                        .iter()
                        .zip(&w)
                        .map(|(a, b)| (a - b).abs())
                        .fold(0.0, f64::max);
                    assert!(
                        err < 1e-10 * scale,
                        "p {p} overlap {overlap}: {err:e} vs {scale:e}"
                    );
                    // The ring: the couplings of subdomain rows to blocks outside S.
                    let ring: std::collections::BTreeSet<(usize, usize)> = ras
                        .ring_couplings()
                        .iter()
                        .map(|rc| (rc.row, rc.col))
                        .collect();
                    assert!(ring.iter().all(|&(_, j)| !inside[j]));
                    for (l, &bl) in blocks.iter().enumerate() {
                        for j in (0..nbk).filter(|&j| !inside[j] && linked(bl, j)) {
                            assert!(ring.contains(&(l, j)), "({l}, {j}) not in the ring");
                        }
                    }
                });
            }
        }
    }

    #[test]
    fn refactor_reuses_the_symbolic_factorization() {
        for overlap in [1, 2] {
            run_ranks(2, |c| {
                let opts = FactorOptions {
                    overlap,
                    ..FactorOptions::default()
                };
                let mut m = elasticity_cube(c, 4, &split(125, 2));
                let mut ras = RestrictedSchwarz::with_factor_options(c, &m, opts).unwrap();
                for v in m.vals.iter_mut() {
                    *v *= 2.0;
                }
                ras.refactor(c, &m).unwrap();
                let fresh = RestrictedSchwarz::with_factor_options(c, &m, opts).unwrap();
                let n = m.n_owned_dofs();
                let r: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
                let (mut z1, mut z2) = (vec![0.0; n], vec![0.0; n]);
                ras.apply(c, &r, &mut z1);
                fresh.apply(c, &r, &mut z2);
                assert!(z1.iter().zip(&z2).all(|(a, b)| (a - b).abs() < 1e-12));
                assert_eq!(ras.factorizations(), 2);
                assert_eq!(ras.symbolic_factorizations(), 1);
                // Another pattern is refused on every rank.
                let other = elasticity_cube(c, 3, &split(64, 2));
                assert!(ras.refactor(c, &other).is_err());
            });
        }
    }

    /// GMRES with RAS reaches the block-Jacobi solution in fewer iterations on 2 and 3
    /// ranks, for the SPD elasticity cube and a non-symmetric perturbation of it.
    #[test]
    fn gmres_with_ras_matches_block_jacobi_in_fewer_iterations() {
        let opts = GmresOptions {
            rtol: 1e-10,
            ..Default::default()
        };
        for p in [2usize, 3] {
            for non_symmetric in [false, true] {
                let ne = 8;
                let nb = (ne + 1) * (ne + 1) * (ne + 1);
                let out = run_ranks(p, |c| {
                    let mut m = elasticity_cube(c, ne, &split(nb, p));
                    if non_symmetric {
                        make_non_symmetric(c, &mut m);
                    }
                    let n = m.n_owned_dofs();
                    let b: Vec<f64> = (0..n)
                        .map(|i| if i % 3 == 2 { -1.0 } else { 0.1 })
                        .collect();
                    let bj = BlockJacobi::new(&m).unwrap();
                    let mut x_bj = vec![0.0; n];
                    let st_bj = gmres(c, &mut m, &bj, &b, &mut x_bj, &opts).unwrap();
                    let ras = RestrictedSchwarz::new(c, &m).unwrap();
                    let mut x_ras = vec![0.0; n];
                    let st_ras = gmres(c, &mut m, &ras, &b, &mut x_ras, &opts).unwrap();
                    assert!(st_bj.converged && st_ras.converged, "{st_bj:?} {st_ras:?}");
                    let d: f64 = x_bj
                        .iter()
                        .zip(&x_ras)
                        .map(|(a, b)| (a - b) * (a - b))
                        .sum();
                    let d = (c.allgather_f64(d).iter().sum::<f64>()).sqrt();
                    let xn = c.norm2(&x_bj);
                    assert!(d <= 1e-8 * xn, "{d:e} vs {xn:e}");
                    (st_bj.iterations, st_ras.iterations)
                });
                let (it_bj, it_ras) = out[0];
                eprintln!(
                    "{p} ranks, non-symmetric {non_symmetric}: GMRES iterations block \
                     Jacobi {it_bj}, RAS {it_ras}"
                );
                assert!(it_ras < it_bj, "RAS {it_ras} vs block Jacobi {it_bj}");
            }
        }
    }
}
