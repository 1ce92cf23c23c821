//! Sparse LU with partial pivoting and a caller's column ordering (nested dissection).
//!
//! faer's high-level [`faer::sparse::linalg::solvers::SymbolicLu`] always orders columns
//! with COLAMD. Its supernodal kernels take any column permutation, so this module drives
//! them directly, as faer's own supernodal LU test does: the column elimination tree of
//! AᵀA under the ordering, its postorder, the column counts, the supernodal symbolic
//! factorization once, then numeric factorizations of new values on the same pattern.
//! With threshold partial pivoting the row order is chosen numerically; the fill is
//! bounded by the Cholesky factor of AᵀA in the column order (George & Ng), for which a
//! nested dissection of A's node graph is a good order on 3D meshes.

use crate::Error;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::perm::PermRef;
use faer::sparse::linalg::lu::supernodal::{
    factorize_supernodal_numeric_lu, factorize_supernodal_numeric_lu_scratch,
    factorize_supernodal_symbolic_lu, factorize_supernodal_symbolic_lu_scratch,
    solve_in_place_scratch, SupernodalLu, SymbolicSupernodalLu,
};
use faer::sparse::linalg::qr::{col_etree, column_counts_ata, postorder};
use faer::sparse::linalg::SymbolicSupernodalParams;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat, SymbolicSparseColMatRef};
use faer::{Conj, Par};

/// The symbolic factorization: pattern of A, its transpose (with the value gather map),
/// the postordered column permutation and the supernodal structure.
pub struct NdLu {
    n: usize,
    col_fwd: Vec<usize>,
    col_inv: Vec<usize>,
    /// Pattern of Aᵀ and, for each of its entries, the index of the value in A.
    at_pattern: SymbolicSparseColMat<usize>,
    at_map: Vec<usize>,
    at_vals: Vec<f64>,
    symbolic: SymbolicSupernodalLu<usize>,
    lu: SupernodalLu<usize, f64>,
    row_fwd: Vec<usize>,
    row_inv: Vec<usize>,
    factored: bool,
}

impl NdLu {
    /// Symbolic analysis of `pattern` (square, CSC, sorted rows) under the column order
    /// `fwd` (new position k holds old column `fwd[k]`).
    pub fn new(pattern: SymbolicSparseColMatRef<'_, usize>, fwd: &[usize]) -> crate::Result<Self> {
        let n = pattern.ncols();
        if pattern.nrows() != n || fwd.len() != n {
            return Err(Error::runtime(format!(
                "nested-dissection LU: a {}×{} block with an ordering of {}",
                pattern.nrows(),
                n,
                fwd.len()
            )));
        }
        let (at_pattern, at_map) = transpose_pattern(pattern);
        let mut col_fwd = fwd.to_vec();
        let mut col_inv = inverse(&col_fwd);
        // Postorder the column etree so that supernodes are contiguous.
        let mut etree = vec![0usize; n];
        let mut post = vec![0usize; n];
        {
            let perm = PermRef::new_checked(&col_fwd, &col_inv, n);
            let mut mem = MemBuffer::new(StackReq::new::<usize>(pattern.nrows() + n).array(2));
            let et = col_etree(pattern, Some(perm), &mut etree, MemStack::new(&mut mem));
            let mut mem = MemBuffer::new(StackReq::new::<usize>(n).array(3));
            postorder(&mut post, et, MemStack::new(&mut mem));
        }
        col_fwd = post.iter().map(|&k| col_fwd[k]).collect();
        col_inv = inverse(&col_fwd);
        let perm = PermRef::new_checked(&col_fwd, &col_inv, n);
        let mut min_col = vec![0usize; n];
        let mut col_counts = vec![0usize; n];
        let mut mem = MemBuffer::new(StackReq::new::<usize>(n).array(8));
        let et = col_etree(pattern, Some(perm), &mut etree, MemStack::new(&mut mem));
        postorder(&mut post, et, MemStack::new(&mut mem));
        column_counts_ata(
            &mut col_counts,
            &mut min_col,
            at_pattern.as_ref(),
            Some(perm),
            et,
            &post,
            MemStack::new(&mut mem),
        );
        let mut mem = MemBuffer::new(factorize_supernodal_symbolic_lu_scratch::<usize>(n, n));
        let symbolic = factorize_supernodal_symbolic_lu::<usize>(
            pattern,
            Some(perm),
            &min_col,
            et,
            &col_counts,
            MemStack::new(&mut mem),
            SymbolicSupernodalParams::default(),
        )
        .map_err(|e| Error::runtime(format!("nested-dissection LU: symbolic failed: {e:?}")))?;
        let nnz = at_map.len();
        Ok(Self {
            n,
            col_fwd,
            col_inv,
            at_pattern,
            at_map,
            at_vals: vec![0.0; nnz],
            symbolic,
            lu: SupernodalLu::new(),
            row_fwd: vec![0; n],
            row_inv: vec![0; n],
            factored: false,
        })
    }

    /// Numeric factorization of `a` (the pattern given to [`Self::new`]).
    pub fn factor(&mut self, a: SparseColMatRef<'_, usize, f64>) -> crate::Result<()> {
        self.factored = false;
        let vals = a.val();
        for (t, &q) in self.at_vals.iter_mut().zip(&self.at_map) {
            *t = vals[q];
        }
        let at = SparseColMatRef::new(self.at_pattern.as_ref(), &self.at_vals);
        let perm = PermRef::new_checked(&self.col_fwd, &self.col_inv, self.n);
        let mut mem = MemBuffer::new(factorize_supernodal_numeric_lu_scratch::<usize, f64>(
            &self.symbolic,
            Default::default(),
        ));
        factorize_supernodal_numeric_lu(
            &mut self.row_fwd,
            &mut self.row_inv,
            &mut self.lu,
            a,
            at,
            perm,
            &self.symbolic,
            Par::Seq,
            MemStack::new(&mut mem),
            Default::default(),
        )
        .map_err(|e| Error::runtime(format!("nested-dissection LU: numeric failed: {e:?}")))?;
        self.factored = true;
        Ok(())
    }

    /// The column order (`order[new] = old`), postordered.
    #[cfg(test)]
    pub fn col_order(&self) -> &[usize] {
        &self.col_fwd
    }

    /// X ← A⁻¹ X for `ncols` columns stored one after the other in `x`.
    pub fn solve_many(&self, x: &mut [f64], ncols: usize) {
        if !self.factored || ncols == 0 {
            return;
        }
        let rows = PermRef::new_checked(&self.row_fwd, &self.row_inv, self.n);
        let cols = PermRef::new_checked(&self.col_fwd, &self.col_inv, self.n);
        let mut mem = MemBuffer::new(solve_in_place_scratch::<usize, f64>(
            self.n,
            ncols,
            Par::Seq,
        ));
        self.lu.solve_in_place_with_conj(
            rows,
            cols,
            Conj::No,
            faer::MatMut::from_column_major_slice_mut(x, self.n, ncols),
            Par::Seq,
            MemStack::new(&mut mem),
        );
    }
}

fn inverse(p: &[usize]) -> Vec<usize> {
    let mut inv = vec![0; p.len()];
    for (k, &i) in p.iter().enumerate() {
        inv[i] = k;
    }
    inv
}

/// Pattern of Aᵀ (sorted rows) and, per entry, the index of the same entry in A's values.
fn transpose_pattern(
    a: SymbolicSparseColMatRef<'_, usize>,
) -> (SymbolicSparseColMat<usize>, Vec<usize>) {
    let (m, n) = (a.nrows(), a.ncols());
    let ptr = a.col_ptr();
    let rows = a.row_idx();
    let mut count = vec![0usize; m + 1];
    for &i in rows {
        count[i + 1] += 1;
    }
    for i in 0..m {
        count[i + 1] += count[i];
    }
    let col_ptr = count.clone();
    let mut next = count;
    let mut row_idx = vec![0usize; rows.len()];
    let mut map = vec![0usize; rows.len()];
    for j in 0..n {
        for (q, &i) in rows.iter().enumerate().take(ptr[j + 1]).skip(ptr[j]) {
            let k = next[i];
            row_idx[k] = j;
            map[k] = q;
            next[i] += 1;
        }
    }
    let pat = SymbolicSparseColMat::new_checked(n, m, col_ptr, None, row_idx);
    (pat, map)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A non-symmetric matrix on a 5×5 grid graph (3 dofs per node, zero diagonal
    /// entries so rows must be pivoted) factored under a reversed and under a shuffled
    /// column order, refactored with new values: A x = b against a dense LU.
    #[test]
    fn solves_nonsymmetric_blocks_needing_pivots_under_any_column_order() {
        let side = 5;
        let nodes = side * side;
        let n = 3 * nodes;
        let mut cols_of: Vec<Vec<usize>> = vec![Vec::new(); n];
        for a in 0..nodes {
            let (x, y) = (a % side, a / side);
            for b in 0..nodes {
                let (u, v) = (b % side, b / side);
                if x.abs_diff(u) <= 1 && y.abs_diff(v) <= 1 {
                    for i in 0..3 {
                        for j in 0..3 {
                            cols_of[3 * b + j].push(3 * a + i);
                        }
                    }
                }
            }
        }
        let mut col_ptr = vec![0];
        let mut rows = Vec::new();
        for c in &mut cols_of {
            c.sort_unstable();
            rows.extend_from_slice(c);
            col_ptr.push(rows.len());
        }
        let pat = SymbolicSparseColMat::new_checked(n, n, col_ptr.clone(), None, rows.clone());
        let values = |seed: f64| -> Vec<f64> {
            let mut v = Vec::with_capacity(rows.len());
            for j in 0..n {
                for &i in &rows[col_ptr[j]..col_ptr[j + 1]] {
                    let w = ((i * 31 + j * 17) as f64 * 0.61 + seed).sin();
                    // Every third diagonal entry is zero: pivoting is required.
                    v.push(if i == j {
                        if i % 3 == 1 {
                            0.0
                        } else {
                            8.0 + w
                        }
                    } else {
                        w
                    });
                }
            }
            v
        };
        let reversed: Vec<usize> = (0..n).rev().collect();
        let shuffled: Vec<usize> = (0..n).map(|k| (k * 7) % n).collect();
        assert!(crate::linalg::ordering::is_permutation(&shuffled));
        for order in [reversed, shuffled] {
            let mut lu = NdLu::new(pat.as_ref(), &order).unwrap();
            for seed in [0.0, 1.3] {
                let vals = values(seed);
                lu.factor(SparseColMatRef::new(pat.as_ref(), &vals))
                    .unwrap();
                let mut dense = nalgebra::DMatrix::<f64>::zeros(n, n);
                for j in 0..n {
                    for q in col_ptr[j]..col_ptr[j + 1] {
                        dense[(rows[q], j)] = vals[q];
                    }
                }
                let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).cos()).collect();
                let want = dense
                    .clone()
                    .lu()
                    .solve(&nalgebra::DVector::from_vec(b.clone()));
                let want = want.expect("dense matrix nonsingular");
                let mut x = b;
                lu.solve_many(&mut x, 1);
                let err = x
                    .iter()
                    .zip(want.iter())
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max);
                assert!(err < 1e-9 * want.amax(), "error {err}");
            }
        }
    }

    #[test]
    fn refuses_an_ordering_of_the_wrong_length() {
        let pat = SymbolicSparseColMat::new_checked(2, 2, vec![0, 1, 2], None, vec![0, 1]);
        assert!(NdLu::new(pat.as_ref(), &[0]).is_err());
    }
}
