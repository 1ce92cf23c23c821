//! A distributed square sparse matrix of 3×3 blocks.
//!
//! Rows are distributed by a block [`Layout`]: rank r owns block rows `[start, end)`;
//! scalar dof `3·block + c`; an owned scalar vector slice has length `3·owned_len`.
//!
//! Storage (per rank): the owned block rows in block CSR, each row's block columns sorted
//! by global index. Because the owned columns `[start, end)` are one contiguous range,
//! a sorted row splits into `[ghost cols < start | owned cols | ghost cols ≥ end]`; the
//! middle run (the *diagonal part*) is indexed by local column directly, the outer runs
//! (the *off-diagonal part*) by their position in the sorted ghost-column list, which is
//! also the position of their values in the halo buffer. So spmv does no lookup.
//!
//! Contributions to rows owned elsewhere go to a *stash* whose entries are sorted by
//! (row, col), hence grouped by owner; the owner learned at construction where each
//! incoming entry lands, so [`DistMatrix::finish_assembly`] is one `alltoallv` of values.

use crate::parallel::{Comm, HaloPlan, Layout};

/// Distributed block-sparse matrix (3×3 blocks, row-major within a block).
#[derive(Debug, Clone)]
pub struct DistMatrix {
    layout: Layout,
    /// Block CSR of the owned rows: `row_ptr[i]..row_ptr[i+1]` for local row i.
    pub(crate) row_ptr: Vec<usize>,
    /// Global block column of each entry (sorted within a row).
    cols: Vec<usize>,
    /// Per local row, the entry range of owned columns (the diagonal part).
    pub(crate) diag_begin: Vec<usize>,
    pub(crate) diag_end: Vec<usize>,
    /// Local index of each entry's column: `col - start` for owned columns, the position
    /// in `ghost_blocks` for the others.
    pub(crate) lcol: Vec<u32>,
    /// 9 values per entry.
    pub(crate) vals: Vec<f64>,
    /// Sorted global block columns of owned rows not owned here.
    ghost_blocks: Vec<usize>,
    /// Halo plan over the scalar dofs of `ghost_blocks`.
    halo: HaloPlan,
    /// Off-rank entries (row, col), sorted; values 9 per entry.
    stash_keys: Vec<(usize, usize)>,
    stash_vals: Vec<f64>,
    /// Stash entries sent to each rank.
    stash_send_counts: Vec<usize>,
    /// Entries received from each rank in `finish_assembly`, and where each lands.
    recv_counts: Vec<usize>,
    recv_pos: Vec<usize>,
    /// Owned local block rows that belong to one element alone (a hybrid hex8's pressure
    /// block, coupled to its 8 nodes): a factorization may eliminate them element by
    /// element ([`super::condense`]).
    element_rows: std::ops::Range<usize>,
    /// Owned block rows that are displacement nodes: the first `node_blocks` (all of
    /// them unless told otherwise, [`DistMatrix::set_block_kinds`]).
    node_blocks: Option<usize>,
    /// Global blocks of the problem's global unknowns (a rigid body's DOFs, a coupling's
    /// reference point: dense rows), sorted; the same on every rank.
    global_blocks: Vec<usize>,
    /// The body (part) of each owned node block, if told.
    node_bodies: Vec<u32>,
}

impl DistMatrix {
    /// Say which blocks are what, for preconditioners that build on the geometry (the
    /// coarse space, [`super::coarse`]): the first `node_blocks` owned block rows are
    /// displacement nodes, and `global_blocks` (global block indices, the same on every
    /// rank) are global unknowns coupled to many nodes; `node_bodies` (one per node block,
    /// or empty) says which body each node belongs to.
    pub fn set_block_kinds(
        &mut self,
        node_blocks: usize,
        mut global_blocks: Vec<usize>,
        node_bodies: Vec<u32>,
    ) {
        assert!(node_blocks <= self.layout.owned_len());
        assert!(node_bodies.is_empty() || node_bodies.len() == node_blocks);
        global_blocks.sort_unstable();
        global_blocks.dedup();
        self.node_blocks = Some(node_blocks);
        self.global_blocks = global_blocks;
        self.node_bodies = node_bodies;
    }

    /// The body of owned node block `i` (0 if not told).
    pub fn node_body(&self, i: usize) -> u32 {
        self.node_bodies.get(i).copied().unwrap_or(0)
    }

    /// Owned block rows that are displacement nodes (the first ones).
    pub fn node_blocks(&self) -> usize {
        self.node_blocks.unwrap_or(self.layout.owned_len())
    }

    /// Global blocks of global unknowns (sorted).
    pub fn global_blocks(&self) -> &[usize] {
        &self.global_blocks
    }

    /// Mark owned local block rows `rows` as element blocks (see the field).
    pub fn set_element_rows(&mut self, rows: std::ops::Range<usize>) {
        self.element_rows = rows;
    }

    /// Whether owned local block row `i` is an element block.
    pub fn is_element_row(&self, i: usize) -> bool {
        self.element_rows.contains(&i)
    }

    /// The owned local block rows marked as element blocks.
    pub fn element_rows(&self) -> std::ops::Range<usize> {
        self.element_rows.clone()
    }

    /// Collective. `pairs` are the (global block row, global block col) couplings this
    /// rank will add, rows possibly owned by other ranks (they are sent to their owners).
    /// Every owned diagonal block is always in the pattern. Duplicates are fine.
    pub fn new(comm: &dyn Comm, layout: Layout, pairs: &[(usize, usize)]) -> Self {
        let p = comm.size();
        assert_eq!(
            layout.size(),
            p,
            "layout has {} ranks, comm {}",
            layout.size(),
            p
        );
        assert_eq!(layout.rank, comm.rank(), "layout is for another rank");
        let n_global = layout.global_len();
        assert!(
            n_global <= u32::MAX as usize,
            "too many block rows for u32 local indices"
        );
        let (start, end) = (layout.start(), layout.end());
        let n_own = end - start;

        let mut owned_pairs: Vec<(usize, usize)> = Vec::with_capacity(pairs.len() + n_own);
        let mut stash_keys: Vec<(usize, usize)> = Vec::new();
        for &(r, c) in pairs {
            assert!(
                r < n_global && c < n_global,
                "pair ({r}, {c}) out of range {n_global}"
            );
            if r >= start && r < end {
                owned_pairs.push((r, c));
            } else {
                stash_keys.push((r, c));
            }
        }
        owned_pairs.extend((start..end).map(|i| (i, i)));
        stash_keys.sort_unstable();
        stash_keys.dedup();

        // Send the off-rank pairs to their owners (sorted by row, so grouped by owner).
        let mut stash_send_counts = vec![0usize; p];
        for &(r, _) in &stash_keys {
            stash_send_counts[layout.owner(r)] += 1;
        }
        let recv_counts = comm.alltoall_counts(&stash_send_counts);
        let send: Vec<u64> = stash_keys
            .iter()
            .flat_map(|&(r, c)| [r as u64, c as u64])
            .collect();
        let sc2: Vec<usize> = stash_send_counts.iter().map(|c| 2 * c).collect();
        let rc2: Vec<usize> = recv_counts.iter().map(|c| 2 * c).collect();
        let recv = comm.alltoallv_u64(&send, &sc2, &rc2);
        let incoming: Vec<(usize, usize)> = recv
            .chunks_exact(2)
            .map(|rc| (rc[0] as usize, rc[1] as usize))
            .collect();
        owned_pairs.extend_from_slice(&incoming);
        owned_pairs.sort_unstable();
        owned_pairs.dedup();

        // Block CSR of owned rows.
        let mut row_ptr = vec![0usize; n_own + 1];
        for &(r, _) in &owned_pairs {
            row_ptr[r - start + 1] += 1;
        }
        for i in 0..n_own {
            row_ptr[i + 1] += row_ptr[i];
        }
        let cols: Vec<usize> = owned_pairs.iter().map(|&(_, c)| c).collect();
        drop(owned_pairs);
        let mut diag_begin = Vec::with_capacity(n_own);
        let mut diag_end = Vec::with_capacity(n_own);
        for i in 0..n_own {
            let row = &cols[row_ptr[i]..row_ptr[i + 1]];
            diag_begin.push(row_ptr[i] + row.partition_point(|&c| c < start));
            diag_end.push(row_ptr[i] + row.partition_point(|&c| c < end));
        }
        let mut ghost_blocks: Vec<usize> = cols
            .iter()
            .copied()
            .filter(|&c| c < start || c >= end)
            .collect();
        ghost_blocks.sort_unstable();
        ghost_blocks.dedup();
        let lcol: Vec<u32> = cols
            .iter()
            .map(|&c| {
                if c >= start && c < end {
                    (c - start) as u32
                } else {
                    ghost_blocks.binary_search(&c).unwrap() as u32
                }
            })
            .collect();
        let nnzb = cols.len();

        let recv_pos: Vec<usize> = incoming
            .iter()
            .map(|&(r, c)| {
                let i = r - start;
                row_ptr[i] + cols[row_ptr[i]..row_ptr[i + 1]].binary_search(&c).unwrap()
            })
            .collect();

        let scalar_layout = scalar_layout(&layout);
        let ghost_dofs: Vec<usize> = ghost_blocks
            .iter()
            .flat_map(|&g| [3 * g, 3 * g + 1, 3 * g + 2])
            .collect();
        let halo = HaloPlan::new(comm, &scalar_layout, ghost_dofs);

        let n_stash = stash_keys.len();
        Self {
            layout,
            row_ptr,
            cols,
            diag_begin,
            diag_end,
            lcol,
            vals: vec![0.0; 9 * nnzb],
            ghost_blocks,
            halo,
            stash_keys,
            stash_vals: vec![0.0; 9 * n_stash],
            stash_send_counts,
            recv_counts,
            recv_pos,
            element_rows: 0..0,
            node_blocks: None,
            global_blocks: Vec::new(),
            node_bodies: Vec::new(),
        }
    }

    /// Set every stored value (owned rows and stash) to zero; the pattern stays.
    pub fn zero(&mut self) {
        self.vals.fill(0.0);
        self.stash_vals.fill(0.0);
    }

    /// Position (entry index) of block (row, col) in owned storage.
    #[inline]
    fn owned_pos(&self, local_row: usize, col: usize) -> Option<usize> {
        let (a, b) = (self.row_ptr[local_row], self.row_ptr[local_row + 1]);
        self.cols[a..b].binary_search(&col).ok().map(|k| a + k)
    }

    #[inline]
    fn stash_pos(&self, row: usize, col: usize) -> Option<usize> {
        self.stash_keys.binary_search(&(row, col)).ok()
    }

    /// Where block (row, col) accumulates: owned storage or the stash.
    #[inline]
    fn slot(&mut self, row: usize, col: usize) -> &mut [f64] {
        if self.layout.owns(row) {
            let i = row - self.layout.start();
            match self.owned_pos(i, col) {
                Some(e) => &mut self.vals[9 * e..9 * e + 9],
                None => not_in_pattern(row, col),
            }
        } else {
            match self.stash_pos(row, col) {
                Some(e) => &mut self.stash_vals[9 * e..9 * e + 9],
                None => not_in_pattern(row, col),
            }
        }
    }

    /// Add an element matrix: `blocks` are global block indices (n of them), `ke` is
    /// 3n×3n row-major. Rows owned elsewhere go to the stash.
    ///
    /// Panics if a (row, col) block is not in the pattern (in release builds too: a
    /// silently dropped contribution would be a wrong answer).
    pub fn add_element(&mut self, blocks: &[usize], ke: &[f64]) {
        let n = blocks.len();
        let w = 3 * n;
        assert_eq!(ke.len(), w * w, "element matrix must be {w}×{w}");
        for (a, &row) in blocks.iter().enumerate() {
            for (b, &col) in blocks.iter().enumerate() {
                let dst = self.slot(row, col);
                for i in 0..3 {
                    let src = &ke[(3 * a + i) * w + 3 * b..(3 * a + i) * w + 3 * b + 3];
                    dst[3 * i] += src[0];
                    dst[3 * i + 1] += src[1];
                    dst[3 * i + 2] += src[2];
                }
            }
        }
    }

    /// Add one 3×3 block (row-major) at global block (row, col).
    pub fn add_block(&mut self, row: usize, col: usize, b: &[f64; 9]) {
        let dst = self.slot(row, col);
        for (d, s) in dst.iter_mut().zip(b) {
            *d += s;
        }
    }

    /// Collective: send stash values to their owners, add them there, zero the stash.
    pub fn finish_assembly(&mut self, comm: &dyn Comm) {
        let sc: Vec<usize> = self.stash_send_counts.iter().map(|c| 9 * c).collect();
        let rc: Vec<usize> = self.recv_counts.iter().map(|c| 9 * c).collect();
        let recv = comm.alltoallv_f64(&self.stash_vals, &sc, &rc);
        for (&e, v) in self.recv_pos.iter().zip(recv.chunks_exact(9)) {
            for (d, s) in self.vals[9 * e..9 * e + 9].iter_mut().zip(v) {
                *d += s;
            }
        }
        self.stash_vals.fill(0.0);
    }

    /// Collective Dirichlet elimination: `owned_dofs_local` are owned scalar dofs (local
    /// indices in `0..3·owned_len`). Zeroes those rows and the matching columns in every
    /// rank's rows (ghost columns learn their flags through one halo exchange) and puts
    /// 1.0 on their diagonals. Call after [`DistMatrix::finish_assembly`]. The caller
    /// keeps the right-hand side consistent (e.g. zero increments on constrained dofs).
    pub fn constrain(&mut self, comm: &dyn Comm, owned_dofs_local: &[usize]) {
        let n = self.n_owned_dofs();
        let mut flag = vec![0.0f64; n];
        for &d in owned_dofs_local {
            assert!(d < n, "constrained dof {d} not owned (owned: {n})");
            flag[d] = 1.0;
        }
        let mut gflag = vec![0.0f64; 3 * self.ghost_blocks.len()];
        self.halo.forward(comm, &flag, &mut gflag);
        if owned_dofs_local.is_empty() && gflag.iter().all(|&f| f == 0.0) {
            return;
        }
        let block_any = |f: &[f64], k: usize| f[3 * k] + f[3 * k + 1] + f[3 * k + 2] != 0.0;
        for i in 0..self.layout.owned_len() {
            let row_flagged = block_any(&flag, i);
            for e in self.row_ptr[i]..self.row_ptr[i + 1] {
                let diag = e >= self.diag_begin[i] && e < self.diag_end[i];
                let k = self.lcol[e] as usize;
                let cf = if diag {
                    &flag[3 * k..3 * k + 3]
                } else {
                    &gflag[3 * k..3 * k + 3]
                };
                if !row_flagged && cf.iter().all(|&f| f == 0.0) {
                    continue;
                }
                let v = &mut self.vals[9 * e..9 * e + 9];
                for a in 0..3 {
                    let rf = flag[3 * i + a] != 0.0;
                    for b in 0..3 {
                        if rf || cf[b] != 0.0 {
                            v[3 * a + b] = 0.0;
                        }
                    }
                    if rf && diag && k == i {
                        v[3 * a + a] = 1.0;
                    }
                }
            }
        }
    }

    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// Scalar dofs owned by this rank (3 per owned block row).
    pub fn n_owned_dofs(&self) -> usize {
        3 * self.layout.owned_len()
    }

    /// Scalar dofs in total.
    pub fn n_global_dofs(&self) -> usize {
        3 * self.layout.global_len()
    }

    /// Global block columns of owned block row `local_row` (sorted).
    pub fn cols_of_row(&self, local_row: usize) -> &[usize] {
        &self.cols[self.row_ptr[local_row]..self.row_ptr[local_row + 1]]
    }

    /// The 3×3 block (row-major) at owned block row `local_row`, global block column
    /// `col`, if it is in the pattern.
    pub fn block(&self, local_row: usize, col: usize) -> Option<&[f64]> {
        let row = self.cols_of_row(local_row);
        let k = row.binary_search(&col).ok()? + self.row_ptr[local_row];
        Some(&self.vals[9 * k..9 * k + 9])
    }

    /// Ghost block columns (sorted global block indices).
    pub fn ghost_blocks(&self) -> &[usize] {
        &self.ghost_blocks
    }

    /// The halo plan over the scalar dofs of [`Self::ghost_blocks`] (3 per block, in
    /// that order).
    pub fn halo(&self) -> &HaloPlan {
        &self.halo
    }

    /// y = A x on owned scalar slices (one halo exchange inside).
    pub fn spmv(&self, comm: &dyn Comm, x: &[f64], y: &mut [f64]) {
        let n = self.n_owned_dofs();
        assert_eq!(x.len(), n, "spmv: x has {} entries, expected {n}", x.len());
        assert_eq!(y.len(), n, "spmv: y has {} entries, expected {n}", y.len());
        let mut ghost = vec![0.0; 3 * self.ghost_blocks.len()];
        self.halo.forward(comm, x, &mut ghost);
        for (i, yi) in y.chunks_exact_mut(3).enumerate() {
            let mut acc = [0.0f64; 3];
            let (a, db, de, b) = (
                self.row_ptr[i],
                self.diag_begin[i],
                self.diag_end[i],
                self.row_ptr[i + 1],
            );
            self.block_row_product(a, db, &ghost, &mut acc);
            self.block_row_product(db, de, x, &mut acc);
            self.block_row_product(de, b, &ghost, &mut acc);
            yi.copy_from_slice(&acc);
        }
    }

    #[inline(always)]
    fn block_row_product(&self, from: usize, to: usize, xs: &[f64], acc: &mut [f64; 3]) {
        for e in from..to {
            let k = 3 * self.lcol[e] as usize;
            let v = &self.vals[9 * e..9 * e + 9];
            let x = &xs[k..k + 3];
            acc[0] += v[0] * x[0] + v[1] * x[1] + v[2] * x[2];
            acc[1] += v[3] * x[0] + v[4] * x[1] + v[5] * x[2];
            acc[2] += v[6] * x[0] + v[7] * x[1] + v[8] * x[2];
        }
    }

    /// Scalar nonzeros stored in owned rows (9 per block).
    pub fn nnz_local(&self) -> usize {
        self.vals.len()
    }

    /// Block nonzeros stored in owned rows.
    pub fn nnz_blocks_local(&self) -> usize {
        self.cols.len()
    }

    /// Owned rows in scalar CSR with global scalar column indices, sorted within rows
    /// (for export to PETSc and for tests).
    pub fn local_csr(&self) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
        let n_own = self.layout.owned_len();
        let mut ptr = Vec::with_capacity(3 * n_own + 1);
        let mut cols = Vec::with_capacity(self.vals.len());
        let mut vals = Vec::with_capacity(self.vals.len());
        ptr.push(0);
        for i in 0..n_own {
            for a in 0..3 {
                for e in self.row_ptr[i]..self.row_ptr[i + 1] {
                    for b in 0..3 {
                        cols.push(3 * self.cols[e] + b);
                        vals.push(self.vals[9 * e + 3 * a + b]);
                    }
                }
                ptr.push(cols.len());
            }
        }
        (ptr, cols, vals)
    }
}

/// The scalar layout (3 dofs per block) of a block layout.
pub fn scalar_layout(block: &Layout) -> Layout {
    Layout {
        starts: block.starts.iter().map(|s| 3 * s).collect(),
        rank: block.rank,
    }
}

#[cold]
#[inline(never)]
fn not_in_pattern(row: usize, col: usize) -> ! {
    panic!("DistMatrix: block ({row}, {col}) is not in the sparsity pattern")
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::parallel::{run_ranks, SerialComm};

    /// Deterministic pseudo-random numbers in [-1, 1).
    pub(crate) struct Lcg(pub u64);
    impl Lcg {
        pub(crate) fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        }
    }

    /// A mesh of "elements" (lists of block indices) with a non-symmetric random matrix
    /// per element, and the dense scalar reference matrix.
    struct Problem {
        n_blocks: usize,
        elements: Vec<Vec<usize>>,
        kes: Vec<Vec<f64>>,
    }

    impl Problem {
        fn dense(&self) -> Vec<Vec<f64>> {
            let n = 3 * self.n_blocks;
            let mut a = vec![vec![0.0; n]; n];
            for (el, ke) in self.elements.iter().zip(&self.kes) {
                let w = 3 * el.len();
                for (p, &bp) in el.iter().enumerate() {
                    for (q, &bq) in el.iter().enumerate() {
                        for i in 0..3 {
                            for j in 0..3 {
                                a[3 * bp + i][3 * bq + j] += ke[(3 * p + i) * w + 3 * q + j];
                            }
                        }
                    }
                }
            }
            a
        }
        fn pairs_of(&self, els: &[usize]) -> Vec<(usize, usize)> {
            let mut v = Vec::new();
            for &e in els {
                for &a in &self.elements[e] {
                    for &b in &self.elements[e] {
                        v.push((a, b));
                    }
                }
            }
            v
        }
    }

    fn with_random_kes(n_blocks: usize, elements: Vec<Vec<usize>>, seed: u64) -> Problem {
        let mut rng = Lcg(seed);
        let kes = elements
            .iter()
            .map(|el| (0..9 * el.len() * el.len()).map(|_| rng.next()).collect())
            .collect();
        Problem {
            n_blocks,
            elements,
            kes,
        }
    }

    fn chain_1d(n_blocks: usize) -> Problem {
        let els = (0..n_blocks - 1).map(|i| vec![i, i + 1]).collect();
        with_random_kes(n_blocks, els, 7)
    }

    fn hex_3d(nx: usize, ny: usize, nz: usize) -> Problem {
        let id = |i: usize, j: usize, k: usize| i + (nx + 1) * (j + (ny + 1) * k);
        let mut els = Vec::new();
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    els.push(vec![
                        id(i, j, k),
                        id(i + 1, j, k),
                        id(i + 1, j + 1, k),
                        id(i, j + 1, k),
                        id(i, j, k + 1),
                        id(i + 1, j, k + 1),
                        id(i + 1, j + 1, k + 1),
                        id(i, j + 1, k + 1),
                    ]);
                }
            }
        }
        with_random_kes((nx + 1) * (ny + 1) * (nz + 1), els, 11)
    }

    fn split(n: usize, p: usize) -> Vec<usize> {
        // Uneven on purpose; the middle rank of 3 gets few rows.
        match p {
            1 => vec![n],
            2 => vec![n / 3, n - n / 3],
            3 => vec![n / 2, n / 10, n - n / 2 - n / 10],
            _ => unreachable!(),
        }
    }

    /// Assemble on `p` ranks, element e by rank e % p (so most rows are off-rank for
    /// some contributions), optionally constrain, and return each rank's local CSR and
    /// spmv result.
    fn assemble_and_check(prob: &Problem, p: usize, constrained: &[usize]) {
        let dense = {
            let mut a = prob.dense();
            for &d in constrained {
                a[d].fill(0.0);
                for row in a.iter_mut() {
                    row[d] = 0.0;
                }
                a[d][d] = 1.0;
            }
            a
        };
        let n = 3 * prob.n_blocks;
        let xg: Vec<f64> = (0..n)
            .map(|i| ((i * 37) % 17) as f64 - 8.0 + 0.25 * i as f64)
            .collect();
        let yg: Vec<f64> = dense
            .iter()
            .map(|r| r.iter().zip(&xg).map(|(a, x)| a * x).sum())
            .collect();
        let counts = split(prob.n_blocks, p);
        run_ranks(p, |c| {
            let layout = Layout::from_counts(&counts, c.rank());
            let mine: Vec<usize> = (0..prob.elements.len())
                .filter(|e| e % p == c.rank())
                .collect();
            let mut m = DistMatrix::new(c, layout.clone(), &prob.pairs_of(&mine));
            // Assemble twice with a zero in between: zero() must reset the stash too.
            for round in 0..2 {
                m.zero();
                for &e in &mine {
                    m.add_element(&prob.elements[e], &prob.kes[e]);
                }
                if round == 0 {
                    // Leave some junk in the stash / rows to be zeroed.
                    for &e in &mine {
                        m.add_element(&prob.elements[e], &prob.kes[e]);
                    }
                }
            }
            m.finish_assembly(c);
            let s = 3 * layout.start();
            let local_c: Vec<usize> = constrained
                .iter()
                .filter(|&&d| d >= s && d < s + m.n_owned_dofs())
                .map(|d| d - s)
                .collect();
            m.constrain(c, &local_c);
            let (ptr, cols, vals) = m.local_csr();
            assert_eq!(ptr.len(), m.n_owned_dofs() + 1);
            assert_eq!(vals.len(), m.nnz_local());
            for r in 0..m.n_owned_dofs() {
                let grow = s + r;
                let mut row = vec![0.0; n];
                let rc = &cols[ptr[r]..ptr[r + 1]];
                assert!(
                    rc.windows(2).all(|w| w[0] < w[1]),
                    "row {grow} columns not sorted"
                );
                for (&cc, &v) in rc.iter().zip(&vals[ptr[r]..ptr[r + 1]]) {
                    row[cc] = v;
                }
                for k in 0..n {
                    assert!(
                        (row[k] - dense[grow][k]).abs() < 1e-12,
                        "p={p} A[{grow}][{k}] = {} expected {}",
                        row[k],
                        dense[grow][k]
                    );
                }
            }
            let x = &xg[s..s + m.n_owned_dofs()];
            let mut y = vec![0.0; m.n_owned_dofs()];
            m.spmv(c, x, &mut y);
            for (r, v) in y.iter().enumerate() {
                assert!(
                    (v - yg[s + r]).abs() < 1e-10 * (1.0 + yg[s + r].abs()),
                    "p={p} y[{}]",
                    s + r
                );
            }
        });
    }

    #[test]
    fn chain_1d_matches_dense_on_1_2_3_ranks() {
        let prob = chain_1d(20);
        for p in 1..=3 {
            assemble_and_check(&prob, p, &[]);
        }
    }

    #[test]
    fn hex_3d_matches_dense_on_1_2_3_ranks() {
        let prob = hex_3d(3, 2, 2);
        for p in 1..=3 {
            assemble_and_check(&prob, p, &[]);
        }
    }

    #[test]
    fn constrain_leaves_identity_rows_and_columns() {
        let prob = hex_3d(2, 2, 2);
        let n = 3 * prob.n_blocks;
        // Some dofs on every rank, including whole blocks and single components.
        let constrained: Vec<usize> = (0..n).filter(|d| d % 7 == 0 || (d / 3) % 9 == 4).collect();
        for p in 1..=3 {
            assemble_and_check(&prob, p, &constrained);
        }
    }

    #[test]
    fn finish_assembly_sums_off_rank_contributions() {
        // Every rank adds 1·I to every diagonal block of a 6-block layout: each owner must
        // end with p·I, whichever rank owns it (rank 1 owns none).
        let out = run_ranks(3, |c| {
            let layout = Layout::from_counts(&[4, 0, 2], c.rank());
            let pairs: Vec<(usize, usize)> =
                (0..6).map(|i| (i, i)).chain([(0, 5), (5, 0)]).collect();
            let mut m = DistMatrix::new(c, layout, &pairs);
            let eye = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
            for i in 0..6 {
                m.add_block(i, i, &eye);
            }
            m.add_block(0, 5, &[2.0; 9]);
            m.add_block(5, 0, &[3.0; 9]);
            m.finish_assembly(c);
            // A second finish without adds must not add again (the stash was cleared).
            m.finish_assembly(c);
            m.local_csr()
        });
        let (ptr0, cols0, vals0) = &out[0];
        assert_eq!(ptr0.len(), 13);
        // Row 0 (block 0): blocks 0 and 5.
        assert_eq!(&cols0[ptr0[0]..ptr0[1]], &[0, 1, 2, 15, 16, 17]);
        assert_eq!(&vals0[ptr0[0]..ptr0[1]], &[3.0, 0.0, 0.0, 6.0, 6.0, 6.0]);
        assert_eq!(out[1].0, vec![0]);
        let (ptr2, cols2, vals2) = &out[2];
        // Row 15 (block 5, first scalar row): blocks 0 and 5.
        assert_eq!(&cols2[ptr2[3]..ptr2[4]], &[0, 1, 2, 15, 16, 17]);
        assert_eq!(&vals2[ptr2[3]..ptr2[4]], &[9.0, 9.0, 9.0, 3.0, 0.0, 0.0]);
    }

    #[test]
    #[should_panic(expected = "not in the sparsity pattern")]
    fn adding_outside_the_pattern_panics() {
        let layout = Layout::from_counts(&[3], 0);
        let mut m = DistMatrix::new(&SerialComm, layout, &[(0, 1)]);
        m.add_block(0, 2, &[1.0; 9]);
    }
}
