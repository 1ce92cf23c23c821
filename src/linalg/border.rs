//! Dense block rows set aside before a local factorization and solved as a border.
//!
//! A block row coupled to a large part of the matrix (a rigid body's translation and
//! rotation, coupled to every node the body tracks) is harmless to a Cholesky factor
//! ordered by nested dissection, but a sparse LU's structure is bounded by the Cholesky
//! factor of AᵀA (`nd_lu`), and one dense row makes AᵀA dense: on `panel-dent` (961
//! tracked nodes) each LU took 0.73 s with the body's rows against 0.20 s for the same
//! sphere as a wall. So the dense rows `b` are split off, the rest `i` is factored as
//! before, and the system is solved by block elimination (the bordered system of
//! Golub & Van Loan §4.5; MUMPS and PARDISO set dense rows aside the same way):
//!
//! ```text
//! [K_ii K_ib] [x_i]   [r_i]     W = K_ii⁻¹ K_ib,  S = K_bb − K_bi W   (at factorization)
//! [K_bi K_bb] [x_b] = [r_b]  ⇒  y = K_ii⁻¹ r_i,  x_b = S⁻¹ (r_b − K_bi y),  x_i = y − W x_b
//! ```
//!
//! exactly, at the price of 3·(border blocks) extra interior solves per factorization
//! and a dense LU of S.

use super::block_pattern::LocalBlockPattern;
use nalgebra::{DMatrix, DVector};

/// Block rows with more blocks than max([`MIN_DENSE`], 10 √n) are set aside.
pub const MIN_DENSE: usize = 100;

/// The split of a local block pattern into an interior and a border of dense block
/// rows, and the border's factorization.
#[derive(Debug, Clone)]
pub struct Border {
    /// Interior node → node of the full pattern; border likewise.
    interior: Vec<usize>,
    border: Vec<usize>,
    /// The interior pattern (its entries index the full pattern's value array).
    inner: LocalBlockPattern,
    /// Blocks (i, b), (b, i), (b, b): (interior or border row, column, entry).
    ib: Vec<(usize, usize, usize)>,
    bi: Vec<(usize, usize, usize)>,
    bb: Vec<(usize, usize, usize)>,
    /// K_bi's values from the last factorization (9 per block of `bi`).
    bi_vals: Vec<f64>,
    /// W = K_ii⁻¹ K_ib, column-major (3·interior rows, 3·border columns).
    w: Vec<f64>,
    /// The LU of S = K_bb − K_bi W.
    s_lu: Option<nalgebra::LU<f64, nalgebra::Dyn, nalgebra::Dyn>>,
}

impl Border {
    /// The dense block rows of `pat`, or `None` if there are none (or nothing else).
    pub fn find(pat: &LocalBlockPattern) -> Option<Self> {
        let n = pat.n_nodes;
        let limit = (10.0 * (n as f64).sqrt()).max(MIN_DENSE as f64) as usize;
        let dense: Vec<bool> = (0..n)
            .map(|i| pat.row_ptr[i + 1] - pat.row_ptr[i] > limit)
            .collect();
        let border: Vec<usize> = (0..n).filter(|&i| dense[i]).collect();
        if border.is_empty() || border.len() == n {
            return None;
        }
        let interior: Vec<usize> = (0..n).filter(|&i| !dense[i]).collect();
        let mut at = vec![0usize; n];
        for (k, &i) in interior.iter().enumerate() {
            at[i] = k;
        }
        for (k, &i) in border.iter().enumerate() {
            at[i] = k;
        }
        let mut inner = LocalBlockPattern {
            n_nodes: interior.len(),
            row_ptr: vec![0],
            cols: Vec::with_capacity(pat.cols.len()),
            entries: Vec::with_capacity(pat.cols.len()),
            element_rows: interior.iter().map(|&i| pat.is_element_row(i)).collect(),
        };
        let (mut ib, mut bi, mut bb) = (Vec::new(), Vec::new(), Vec::new());
        for i in 0..n {
            for q in pat.row_ptr[i]..pat.row_ptr[i + 1] {
                let (k, e) = (pat.cols[q], pat.entries[q]);
                match (dense[i], dense[k]) {
                    (false, false) => {
                        inner.cols.push(at[k]);
                        inner.entries.push(e);
                    }
                    (false, true) => ib.push((at[i], at[k], e)),
                    (true, false) => bi.push((at[i], at[k], e)),
                    (true, true) => bb.push((at[i], at[k], e)),
                }
            }
            if !dense[i] {
                inner.row_ptr.push(inner.cols.len());
            }
        }
        Some(Self {
            interior,
            border,
            inner,
            ib,
            bi,
            bb,
            bi_vals: Vec::new(),
            w: Vec::new(),
            s_lu: None,
        })
    }

    /// The pattern left to factor as before (entries index the full value array).
    pub fn inner(&self) -> &LocalBlockPattern {
        &self.inner
    }
    /// Block rows set aside.
    pub fn n_border(&self) -> usize {
        self.border.len()
    }

    /// Factor the border for the values `vals` of the full pattern, the interior being
    /// factored already (`solve_inner` solves with it in place). Err if S is singular.
    pub fn factor(
        &mut self,
        vals: &[f64],
        mut solve_inner: impl FnMut(&mut [f64]),
    ) -> Result<(), String> {
        let (ni, nb) = (3 * self.interior.len(), 3 * self.border.len());
        self.w.clear();
        self.w.resize(ni * nb, 0.0);
        for &(i, b, e) in &self.ib {
            for a in 0..3 {
                for c in 0..3 {
                    self.w[(3 * b + c) * ni + 3 * i + a] += vals[9 * e + 3 * a + c];
                }
            }
        }
        for col in self.w.chunks_mut(ni) {
            solve_inner(col);
        }
        let mut s = DMatrix::<f64>::zeros(nb, nb);
        for &(b, c, e) in &self.bb {
            for a in 0..3 {
                for d in 0..3 {
                    s[(3 * b + a, 3 * c + d)] += vals[9 * e + 3 * a + d];
                }
            }
        }
        self.bi_vals.clear();
        for &(b, i, e) in &self.bi {
            let blk = &vals[9 * e..9 * e + 9];
            self.bi_vals.extend_from_slice(blk);
            for (col, wc) in self.w.chunks(ni).enumerate() {
                for a in 0..3 {
                    let kw: f64 = (0..3).map(|k| blk[3 * a + k] * wc[3 * i + k]).sum();
                    s[(3 * b + a, col)] -= kw;
                }
            }
        }
        let lu = s.lu();
        if !lu.is_invertible() || !lu.u().diagonal().iter().all(|d| d.is_finite()) {
            self.s_lu = None;
            return Err(format!(
                "the Schur complement of its {} dense block row(s) is singular",
                self.border.len()
            ));
        }
        self.s_lu = Some(lu);
        Ok(())
    }

    /// x ← K⁻¹ x (3 per node of the full pattern), the interior solved by `solve_inner`.
    pub fn solve(&self, x: &mut [f64], mut solve_inner: impl FnMut(&mut [f64])) {
        let Some(lu) = &self.s_lu else { return };
        let ni = 3 * self.interior.len();
        let gather = |nodes: &[usize]| -> Vec<f64> {
            nodes
                .iter()
                .flat_map(|&i| [x[3 * i], x[3 * i + 1], x[3 * i + 2]])
                .collect()
        };
        let mut y = gather(&self.interior);
        let mut t = DVector::from_vec(gather(&self.border));
        solve_inner(&mut y);
        for (k, &(b, i, _)) in self.bi.iter().enumerate() {
            let blk = &self.bi_vals[9 * k..9 * k + 9];
            for a in 0..3 {
                t[3 * b + a] -= (0..3).map(|c| blk[3 * a + c] * y[3 * i + c]).sum::<f64>();
            }
        }
        let Some(xb) = lu.solve(&t) else { return };
        for (col, wc) in self.w.chunks(ni).enumerate() {
            let v = xb[col];
            for (yi, wi) in y.iter_mut().zip(wc) {
                *yi -= wi * v;
            }
        }
        for (k, &i) in self.interior.iter().enumerate() {
            x[3 * i..3 * i + 3].copy_from_slice(&y[3 * k..3 * k + 3]);
        }
        for (k, &i) in self.border.iter().enumerate() {
            x[3 * i..3 * i + 3].copy_from_slice(&xb.as_slice()[3 * k..3 * k + 3]);
        }
    }
}
