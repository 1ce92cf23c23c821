//! Node-by-node condensation of attached blocks before a local factorization.
//!
//! A block row `m` whose only entries are `(m, m)` and `(m, a)`, and whose block column
//! has only the rows `m` and `a`, is *attached* to the node `a`: an ALM wall's three
//! multipliers of a tracked node are (owned with it, coupled to nothing else). Their
//! unknowns are eliminated exactly, one 3×3 block at a time (Kratos' mixed ULM solver
//! does this for its contact multipliers):
//!
//! ```text
//! [K  B] [x]   [f]        (K − B D̃⁻¹ C) x = f − B D̃⁻¹ g,
//! [C  D] [y] = [g]   ⇒    y = D̃⁻¹ (g − C x),
//! ```
//!
//! where `B`, `C`, `D` are the blocks `(a, m)`, `(m, a)`, `(m, m)`. What is left to
//! factor has only the displacement nodes and the element pattern, no zero diagonal: a
//! frictionless or sticking ALM block condenses to a symmetric positive definite matrix,
//! so it is factored by the nested-dissection Cholesky instead of the LU of the saddle
//! point (issue 12: 3–10× less time and memory).
//!
//! `D` is singular where a multiplier is a pure constraint (an active or sticking
//! direction: h = g, ∂h/∂λ = 0). The condensation then uses `D̃ = D − σ δ s I`, with s
//! the size of the pair's blocks, δ = [`REGULARIZATION`] and σ the sign of `tr D` (the
//! multiplier rows are quasi-definite, `D ≼ 0`, when assembled as the walls assemble
//! them): it turns each constraint into a stiff spring `s/δ`, as a penalty would, and the
//! factorization is that of the matrix with `D̃` in place of `D`, a relative change of δ
//! that the Krylov solve corrects in an iteration or two. δ balances that change against
//! round-off in the stiff springs (and in `g − C x`): on `hertz-sphere` (13 Newton
//! iterations, GMRES to 1e-10) the GMRES iterations were 37 with δ = 0 (the walls' own
//! 10⁻⁸ κ only), 36 at 10⁻⁸, 33 at 10⁻⁶, 26 at 10⁻⁵, 39 at 10⁻⁴, 53 at 10⁻² and 82 at
//! 10⁻¹ (the uncondensed LU: 13).
//!
//! Kept general on purpose: any block row with the attached pattern is condensed, so
//! multipliers of later contact kinds (deformable faces, one multiplier block per slave
//! node) are too, and so is a hybrid hex8's pressure block (`fem/hybrid.rs`), attached
//! to its 8 nodes: what is factored is then F-bar's matrix. A row may have a few neighbours instead of one node, as long as they
//! are already coupled to each other, so the elimination fills nothing: the multipliers
//! of a node tracked by a contact entity couple to the node and to the body's two
//! blocks, which the node couples to already (without this, an entity's multipliers
//! stayed in the matrix and forced an LU: `hertz-sphere` as an entity 29 s against 8 s
//! as a wall). Unknowns coupled to many nodes (a rigid body's six DOFs, a coupling's
//! reference node) are not attached and stay in the factored matrix: eliminating them
//! would fill the block of every node they touch.

use super::block_pattern::LocalBlockPattern;

/// The relative regularization δ of singular attached diagonal blocks before an exact
/// factorization (see the module documentation).
pub const REGULARIZATION: f64 = 1e-6;

/// The most neighbours an attached block row may have (a multiplier of a node tracked
/// by a rigid body: the node and the body's translation and rotation blocks)...
const MAX_NEIGHBOURS: usize = 4;
/// ... or, for a row marked as an element's own ([`LocalBlockPattern::element_rows`]: a
/// hybrid element's pressure block), up to its nodes (those this block holds: 8 for a
/// hex8, 10 for a tet10, 6 for a wedge6, the union of a hybrid tet4 patch's, about 15
/// for 8 tets and rarely above 30). Only marked rows: a corner node of a hex mesh
/// that a rigid body also couples to has 8 mutually coupled neighbours too, and is no
/// algebraic unknown (eliminating it would only perturb the factor by δ). Marked rows are
/// not regularized: their D is definite. (At 8, tet10 pressure blocks stayed in the
/// factored matrix: the seal's LU cost 3.3× hex8's on the same nodes.)
const ELEMENT_NEIGHBOURS: usize = 48;

/// One attached block row `m`: its diagonal entry and its neighbours
/// (`nbrs[nb.clone()]`), whose mutual entries are the fill of its elimination.
#[derive(Debug, Clone)]
struct Pair {
    m: usize,
    /// Entry (value-array index, 9 values) of (m, m).
    e_mm: usize,
    /// This pair's range in [`Condensation::nbrs`] (and in its `bdinv`, `c`).
    nb: std::ops::Range<usize>,
    /// This pair's start in [`Condensation::fill`]: k × k reduced entries (x, y) for
    /// its k neighbours, row-major.
    fill: usize,
    /// An element's own block (a pressure block): D is never singular, so it is not
    /// regularized, and what is factored is the condensed element exactly.
    element: bool,
}

/// A neighbour `x` of an attached row `m`.
#[derive(Debug, Clone, Copy)]
struct Nbr {
    /// `x` in the reduced numbering.
    x_red: usize,
    /// Entries of (x, m) and (m, x).
    e_xm: usize,
    e_mx: usize,
}

/// The condensation of a local block pattern: which block rows are eliminated, the
/// pattern of what is left, and the blocks needed to form its values and to solve.
#[derive(Debug, Clone)]
pub struct Condensation {
    n_nodes: usize,
    pairs: Vec<Pair>,
    nbrs: Vec<Nbr>,
    /// Reduced entries of the fill (x, y), see [`Pair::fill`].
    fill: Vec<usize>,
    /// Reduced node → original node.
    kept: Vec<usize>,
    /// The pattern over the kept nodes; its entries index [`Self::values`] (9 each).
    reduced: LocalBlockPattern,
    /// For each reduced entry, the original entry.
    red_src: Vec<usize>,
    values: Vec<f64>,
    /// Per pair D̃⁻¹; per neighbour B_x D̃⁻¹ and C_x (row-major 3×3), from the last
    /// [`Self::reduce`].
    dinv: Vec<[f64; 9]>,
    bdinv: Vec<[f64; 9]>,
    c: Vec<[f64; 9]>,
}

impl Condensation {
    /// The attached block rows of `pat`, or `None` if there are none.
    ///
    /// A block row `m` is attached if its row and column have the same blocks (its
    /// diagonal and at most [`MAX_NEIGHBOURS`] neighbours, an element row's at most
    /// [`ELEMENT_NEIGHBOURS`]), every pair of its
    /// neighbours is already coupled (so eliminating it fills nothing new), and no
    /// neighbour is eliminated itself (rows are taken from the highest index down, so
    /// of two rows attached to each other the lower one stays).
    pub fn find(pat: &LocalBlockPattern) -> Option<Self> {
        let n = pat.n_nodes;
        let row = |i: usize| pat.row_ptr[i]..pat.row_ptr[i + 1];
        // Block rows in each block column (counted; each pair appears at most once).
        let mut col_count = vec![0usize; n];
        for &k in &pat.cols {
            col_count[k] += 1;
        }
        let mut taken = vec![false; n];
        let mut pairs = Vec::new();
        // Per taken pair: its neighbours (original index, e_xm, e_mx).
        let mut pair_nbrs: Vec<(usize, usize, usize)> = Vec::new();
        let mut pair_ranges = Vec::new();
        let mut nb: Vec<(usize, usize)> = Vec::with_capacity(ELEMENT_NEIGHBOURS);
        'rows: for m in (0..n).rev() {
            let len = row(m).len();
            // An element row sees only the nodes of its element this block holds (5 to
            // 8 where the element straddles ranks).
            let sized = (2..=MAX_NEIGHBOURS + 1).contains(&len)
                || (pat.is_element_row(m) && (2..=ELEMENT_NEIGHBOURS + 1).contains(&len));
            if !sized || col_count[m] != len {
                continue;
            }
            nb.clear();
            let mut e_mm = None;
            for q in row(m) {
                let x = pat.cols[q];
                if x == m {
                    e_mm = Some(pat.entries[q]);
                } else if taken[x] {
                    continue 'rows;
                } else {
                    nb.push((x, pat.entries[q]));
                }
            }
            let Some(e_mm) = e_mm else { continue };
            // Each neighbour's row: (x, m) and (x, y) for every neighbour y.
            let start = pair_nbrs.len();
            for &(x, e_mx) in &nb {
                let (mut e_xm, mut found) = (None, 0);
                for q in row(x) {
                    let k = pat.cols[q];
                    if k == m {
                        e_xm = Some(pat.entries[q]);
                    } else if nb.iter().any(|&(y, _)| y == k) {
                        found += 1;
                    }
                }
                match e_xm {
                    Some(e_xm) if found == nb.len() => pair_nbrs.push((x, e_xm, e_mx)),
                    _ => {
                        pair_nbrs.truncate(start);
                        continue 'rows;
                    }
                }
            }
            taken[m] = true;
            pairs.push((m, e_mm));
            pair_ranges.push(start..pair_nbrs.len());
        }
        if pairs.is_empty() {
            return None;
        }
        let mut red_of = vec![usize::MAX; n];
        let kept: Vec<usize> = (0..n).filter(|&i| !taken[i]).collect();
        for (r, &i) in kept.iter().enumerate() {
            red_of[i] = r;
        }
        let mut reduced = LocalBlockPattern {
            n_nodes: kept.len(),
            row_ptr: Vec::with_capacity(kept.len() + 1),
            cols: Vec::with_capacity(pat.cols.len()),
            entries: Vec::with_capacity(pat.cols.len()),
            element_rows: kept.iter().map(|&i| pat.is_element_row(i)).collect(),
        };
        reduced.row_ptr.push(0);
        let mut red_src = Vec::with_capacity(pat.cols.len());
        for &i in &kept {
            for q in row(i) {
                let k = red_of[pat.cols[q]];
                if k == usize::MAX {
                    continue;
                }
                reduced.cols.push(k);
                reduced.entries.push(red_src.len());
                red_src.push(pat.entries[q]);
            }
            reduced.row_ptr.push(reduced.cols.len());
        }
        let nbrs: Vec<Nbr> = pair_nbrs
            .iter()
            .map(|&(x, e_xm, e_mx)| Nbr {
                x_red: red_of[x],
                e_xm,
                e_mx,
            })
            .collect();
        // The fill entries (x, y), looked up in the reduced rows.
        let mut fill = Vec::new();
        let mut out = Vec::with_capacity(pairs.len());
        for (&(m, e_mm), range) in pairs.iter().zip(pair_ranges) {
            let at = fill.len();
            for xi in range.clone() {
                let x = nbrs[xi].x_red;
                let r = reduced.row_ptr[x]..reduced.row_ptr[x + 1];
                for yi in range.clone() {
                    let y = nbrs[yi].x_red;
                    let q = r.clone().find(|&q| reduced.cols[q] == y)?;
                    fill.push(reduced.entries[q]);
                }
            }
            out.push(Pair {
                m,
                e_mm,
                nb: range,
                fill: at,
                element: pat.is_element_row(m),
            });
        }
        let (np, nn) = (out.len(), nbrs.len());
        Some(Self {
            n_nodes: n,
            values: vec![0.0; 9 * red_src.len()],
            pairs: out,
            nbrs,
            fill,
            kept,
            reduced,
            red_src,
            dinv: vec![[0.0; 9]; np],
            bdinv: vec![[0.0; 9]; nn],
            c: vec![[0.0; 9]; nn],
        })
    }

    /// The pattern left to factor (entries index [`Self::values`]).
    pub fn reduced(&self) -> &LocalBlockPattern {
        &self.reduced
    }
    /// The kept block rows (reduced index → original index).
    pub fn kept(&self) -> &[usize] {
        &self.kept
    }
    /// Block rows eliminated.
    pub fn n_condensed(&self) -> usize {
        self.pairs.len()
    }
    /// Values of the reduced matrix from the last [`Self::reduce`].
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Form the reduced matrix K − B D̃⁻¹ C for the values `vals` of the original
    /// pattern, with the relative regularization δ = `delta` ([`REGULARIZATION`] for a
    /// factorization, [`super::amg::AMG_REGULARIZATION`] for AMG). Err names the local
    /// block row whose D̃ is singular.
    pub fn reduce(&mut self, vals: &[f64], delta: f64) -> Result<(), String> {
        for (e, &s) in self.red_src.iter().enumerate() {
            self.values[9 * e..9 * e + 9].copy_from_slice(&vals[9 * s..9 * s + 9]);
        }
        let blk = |e: usize| -> [f64; 9] { std::array::from_fn(|i| vals[9 * e + i]) };
        let absmax = |b: &[f64; 9]| b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (k, p) in self.pairs.iter().enumerate() {
            let mut d = blk(p.e_mm);
            let mut s = absmax(&d);
            for nb in &self.nbrs[p.nb.clone()] {
                s = s.max(absmax(&blk(nb.e_xm))).max(absmax(&blk(nb.e_mx)));
            }
            let sigma = if d[0] + d[4] + d[8] > 0.0 { 1.0 } else { -1.0 };
            if !p.element {
                for i in 0..3 {
                    d[4 * i] += sigma * delta * s;
                }
            }
            let dinv = inverse3(&d).ok_or_else(|| {
                format!(
                    "the 3×3 diagonal block of the attached local block row {} is singular",
                    p.m
                )
            })?;
            self.dinv[k] = dinv;
            for xi in p.nb.clone() {
                let nb = self.nbrs[xi];
                self.bdinv[xi] = mul3(&blk(nb.e_xm), &dinv);
                self.c[xi] = blk(nb.e_mx);
            }
            let kn = p.nb.len();
            for (i, xi) in p.nb.clone().enumerate() {
                for (j, yi) in p.nb.clone().enumerate() {
                    let bdc = mul3(&self.bdinv[xi], &self.c[yi]);
                    let e = self.fill[p.fill + i * kn + j];
                    for (v, w) in self.values[9 * e..9 * e + 9].iter_mut().zip(&bdc) {
                        *v -= w;
                    }
                }
            }
        }
        Ok(())
    }

    /// The reduced right-hand side f − B D̃⁻¹ g of the full vector `r` (3 per node).
    pub fn rhs(&self, r: &[f64], out: &mut Vec<f64>) {
        debug_assert_eq!(r.len(), 3 * self.n_nodes);
        out.clear();
        out.extend(
            self.kept
                .iter()
                .flat_map(|&i| [r[3 * i], r[3 * i + 1], r[3 * i + 2]]),
        );
        for p in &self.pairs {
            let g = &r[3 * p.m..3 * p.m + 3];
            for xi in p.nb.clone() {
                let (bd, x) = (&self.bdinv[xi], self.nbrs[xi].x_red);
                for i in 0..3 {
                    out[3 * x + i] -=
                        bd[3 * i] * g[0] + bd[3 * i + 1] * g[1] + bd[3 * i + 2] * g[2];
                }
            }
        }
    }

    /// The full solution from the reduced one `x` and the right-hand side: `z` ← r on
    /// entry, the solution on exit.
    pub fn recover(&self, x: &[f64], z: &mut [f64]) {
        for (k, p) in self.pairs.iter().enumerate() {
            let mut w: [f64; 3] = std::array::from_fn(|i| z[3 * p.m + i]);
            for xi in p.nb.clone() {
                let (c, a) = (&self.c[xi], self.nbrs[xi].x_red);
                let xa = &x[3 * a..3 * a + 3];
                for (i, wi) in w.iter_mut().enumerate() {
                    *wi -= c[3 * i] * xa[0] + c[3 * i + 1] * xa[1] + c[3 * i + 2] * xa[2];
                }
            }
            let di = &self.dinv[k];
            for i in 0..3 {
                z[3 * p.m + i] = di[3 * i] * w[0] + di[3 * i + 1] * w[1] + di[3 * i + 2] * w[2];
            }
        }
        for (r, &i) in self.kept.iter().enumerate() {
            z[3 * i..3 * i + 3].copy_from_slice(&x[3 * r..3 * r + 3]);
        }
    }
}

fn mul3(a: &[f64; 9], b: &[f64; 9]) -> [f64; 9] {
    std::array::from_fn(|k| {
        let (i, j) = (k / 3, k % 3);
        a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j]
    })
}

/// The inverse of a row-major 3×3 matrix by cofactors, or None if it is exactly
/// singular or the inverse overflows (a regularized D̃ may be legitimately tiny in
/// constraint directions, so no relative threshold).
fn inverse3(m: &[f64; 9]) -> Option<[f64; 9]> {
    let cof = [
        m[4] * m[8] - m[5] * m[7],
        m[5] * m[6] - m[3] * m[8],
        m[3] * m[7] - m[4] * m[6],
    ];
    let det = m[0] * cof[0] + m[1] * cof[1] + m[2] * cof[2];
    if !det.is_finite() || det == 0.0 {
        return None;
    }
    let inv = [
        cof[0],
        m[2] * m[7] - m[1] * m[8],
        m[1] * m[5] - m[2] * m[4],
        cof[1],
        m[0] * m[8] - m[2] * m[6],
        m[2] * m[3] - m[0] * m[5],
        cof[2],
        m[1] * m[6] - m[0] * m[7],
        m[0] * m[4] - m[1] * m[3],
    ];
    let inv = inv.map(|v| v / det);
    inv.iter().all(|v| v.is_finite()).then_some(inv)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pattern of `n` fully coupled blocks (one element's nodes), plus `extra`
    /// blocks each coupled to all of them and to itself alone.
    fn element_pattern(n: usize, extra: usize) -> LocalBlockPattern {
        let total = n + extra;
        let mut pat = LocalBlockPattern {
            n_nodes: total,
            row_ptr: vec![0],
            cols: Vec::new(),
            entries: Vec::new(),
            element_rows: (0..total).map(|i| i >= n).collect(),
        };
        for i in 0..total {
            let cols: Vec<usize> = if i < n {
                (0..n).chain(n..total).collect()
            } else {
                (0..n).chain(std::iter::once(i)).collect()
            };
            for c in cols {
                pat.cols.push(c);
                pat.entries.push(pat.entries.len());
            }
            pat.row_ptr.push(pat.cols.len());
        }
        pat
    }

    /// A hybrid hex8's pressure block (an element row, 8 neighbours) is eliminated, and a
    /// tet10's (10) and a wedge6's (6); the
    /// corner nodes of a lone hex8 (7 mutually coupled neighbours each) are not, nor an
    /// unmarked row with 8, while a lone tet's (3 neighbours) are attached as before.
    #[test]
    fn pressure_blocks_are_attached_and_hex_corner_nodes_are_not() {
        let c = Condensation::find(&element_pattern(8, 1)).expect("the pressure block");
        assert_eq!(c.n_condensed(), 1);
        assert_eq!(c.kept(), &(0..8).collect::<Vec<_>>()[..]);
        assert!(Condensation::find(&element_pattern(8, 0)).is_none());
        // Two blocks on the same 8 nodes: each is attached to the nodes alone.
        assert_eq!(
            Condensation::find(&element_pattern(8, 2))
                .unwrap()
                .n_condensed(),
            2
        );
        let mut unmarked = element_pattern(8, 1);
        unmarked.element_rows.clear();
        assert!(Condensation::find(&unmarked).is_none());
        // A hybrid tet10's and wedge6's pressure block (10 and 6 neighbours).
        for n in [10, 6] {
            let c = Condensation::find(&element_pattern(n, 1)).expect("the pressure block");
            assert_eq!(c.n_condensed(), 1, "{n} nodes");
            assert_eq!(c.kept(), &(0..n).collect::<Vec<_>>()[..]);
        }
        // 4 nodes of a tet: 3 neighbours each, attached as before (the highest first).
        assert_eq!(
            Condensation::find(&element_pattern(4, 0))
                .unwrap()
                .n_condensed(),
            1
        );
    }

    #[test]
    fn inverse3_inverts() {
        let m = [4.0, 1.0, 0.5, -1.0, 3.0, 0.2, 0.3, -0.7, 5.0];
        let p = mul3(&m, &inverse3(&m).unwrap());
        for (k, v) in p.iter().enumerate() {
            let id = if k % 4 == 0 { 1.0 } else { 0.0 };
            assert!((v - id).abs() < 1e-14, "{p:?}");
        }
        assert!(inverse3(&[1.0, 2.0, 3.0, 2.0, 4.0, 6.0, 0.0, 0.0, 1.0]).is_none());
    }
}
