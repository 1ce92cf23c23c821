//! Block-Jacobi preconditioner: this rank's diagonal block (owned rows × owned columns,
//! scalar) factored exactly with faer's sparse direct solvers.
//!
//! Two factorizations:
//! * **LU** (partial pivoting): any nonsingular block, including non-symmetric ones
//!   (friction, F-bar) and saddle points (contact multiplier rows, when
//!   [`FactorOptions::condense`] is off; by default they are eliminated node by node
//!   first, [`super::condense`]).
//! * **Cholesky** LLᵀ: symmetric positive definite blocks (a stiffness with Dirichlet
//!   rows).
//!
//! Both are ordered by default with METIS nested dissection
//! ([`FillOrdering::NestedDissection`], see [`super::ordering`]). Cholesky dissects the
//! node graph; on a 3D hex8 elasticity block of ~100k unknowns that halves the factor
//! and makes the numeric factorization ~3× faster than faer's AMD. LU's fill is bounded
//! by the Cholesky factor of AᵀA, so its column order dissects the *squared* node graph
//! and drives faer's supernodal LU kernels directly ([`super::nd_lu`]): on the 98k
//! elasticity block 2.2× faster and 3× less memory than faer's COLAMD
//! ([`FillOrdering::Amd`]), which fills badly on 3D meshes.
//!
//! [`Factorization::Auto`] (the default) uses Cholesky while the block is numerically
//! symmetric and the factorization succeeds, and otherwise switches to LU for good
//! (it never retries Cholesky after a failure, so an indefinite block costs one failed
//! attempt, not one per refactorization).
//!
//! The ordering and the symbolic factorization (elimination structure) are computed once
//! per kind; [`BlockJacobi::refactor`] copies the new values of the same pattern through a
//! precomputed gather map into the CSC value array and refactors numerically only. The
//! preconditioner is local: applying it needs no communication.
//!
//! faer's numeric LU does not report an exactly zero pivot (it divides by it), so after
//! each factorization a check solve `A z = A·1` is run: a non-finite or far-off `z`
//! means the block is singular to working precision and is reported as an `Err`.
//! Factorization is local: callers agree on failure across ranks with `Comm::all_ok`.

use super::block_pattern::LocalBlockPattern;
use super::border::Border;
use super::coarse::{LocalSolver, RingCoupling};
use super::condense::Condensation;
use super::nd_lu::NdLu;
use super::ordering::{self, Graph};
use super::{DistMatrix, Preconditioner};
use crate::parallel::Comm;
use crate::Error;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::solvers::Solve;
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
    SymmetricOrdering,
};
use faer::sparse::linalg::solvers::{Lu as SparseLu, SymbolicLu};
use faer::sparse::linalg::LuError;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, Side};

/// The local factor's kernels run on one thread: MPI gives one rank per core, and a
/// thread pool would make results depend on scheduling.
const LOCAL_PAR: faer::Par = faer::Par::Seq;
use std::time::Instant;

/// Which sparse factorization block Jacobi uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Factorization {
    /// Cholesky while the block is symmetric positive definite, else LU.
    #[default]
    Auto,
    /// Always LU.
    Lu,
    /// Always Cholesky; a block that is not SPD is an error.
    Cholesky,
}

/// Fill-reducing ordering used by the symbolic factorizations.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FillOrdering {
    /// METIS nested dissection (one vertex per 3×3 block, expanded to the dofs): of the
    /// node graph for Cholesky, of the squared node graph for LU's column order.
    #[default]
    NestedDissection,
    /// faer's defaults: AMD (Cholesky), COLAMD (LU).
    Amd,
}

/// How a [`LocalFactor`] factors: the kind of factorization, the fill-reducing
/// ordering, and whether attached blocks (contact multipliers) are condensed first
/// ([`super::condense`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FactorOptions {
    pub factorization: Factorization,
    pub ordering: FillOrdering,
    pub condense: bool,
    /// Layers of overlap of a restricted additive Schwarz subdomain (block Jacobi has
    /// none).
    pub overlap: usize,
}

impl Default for FactorOptions {
    fn default() -> Self {
        Self {
            factorization: Factorization::Auto,
            ordering: FillOrdering::NestedDissection,
            condense: true,
            overlap: 1,
        }
    }
}

enum Factor {
    None,
    Lu(Box<SparseLu<usize, f64>>),
    /// Values in `LocalFactor::nd_lu`.
    NdLu,
    /// Values in `BlockJacobi::llt_values`, structure in `symbolic_llt`.
    Llt,
}

/// The exact sparse factorization of a local block matrix ([`LocalBlockPattern`]): the
/// machinery shared by [`BlockJacobi`] (the diagonal block) and
/// [`super::asm::RestrictedSchwarz`] (the overlapping subdomain matrix).
pub struct LocalFactor {
    /// Prefix of error messages ("block Jacobi", "ASM").
    label: &'static str,
    /// Size of the factored (condensed) matrix.
    n: usize,
    /// Size of the block (before condensation).
    n_full: usize,
    /// Attached blocks eliminated before factoring, if any.
    cond: Option<Box<Condensation>>,
    /// Size after the condensation, before the border is set aside.
    n_mid: usize,
    /// Dense block rows set aside and solved as a border, if any.
    border: Option<Box<Border>>,
    /// Length of the value array the pattern indexes.
    vals_len: usize,
    choice: Factorization,
    ordering: FillOrdering,
    /// In `Auto` mode, set once Cholesky failed or the block was non-symmetric.
    cholesky_ruled_out: bool,
    /// Pattern of the diagonal block (scalar CSC, sorted row indices).
    pattern: SymbolicSparseColMat<usize>,
    /// For each CSC position, the index into the matrix's block value array.
    src: Vec<usize>,
    /// For each CSC position (i, j), the position of (j, i), or `usize::MAX`.
    transpose_pos: Vec<usize>,
    csc_vals: Vec<f64>,
    /// Node graph of the block (for the nested dissection ordering).
    node_graph: Graph,
    /// Scalar fill-reducing permutation (`perm[new] = old`), computed once.
    dof_perm: Option<(Vec<usize>, Vec<usize>)>,
    symbolic_lu: Option<SymbolicLu<usize>>,
    /// LU with the nested dissection column order (symbolic part, and the numeric
    /// factor once [`Factor::NdLu`]).
    nd_lu: Option<Box<NdLu>>,
    symbolic_llt: Option<SymbolicCholesky<usize>>,
    llt_values: Vec<f64>,
    factor: Factor,
    factorizations: usize,
    symbolic_factorizations: usize,
    symbolic_seconds: f64,
    ordering_seconds: f64,
    last_factor_seconds: f64,
}

impl std::fmt::Debug for LocalFactor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LocalFactor")
            .field("label", &self.label)
            .field("n", &self.n)
            .field("n_full", &self.n_full)
            .field("nnz", &self.src.len())
            .field("kind", &self.kind())
            .field("ordering", &self.ordering)
            .field("factorizations", &self.factorizations)
            .finish()
    }
}

/// Block Jacobi: this rank's diagonal block (owned rows × owned columns) factored by a
/// [`LocalFactor`] (whose accessors it derefs to).
#[derive(Debug)]
pub struct BlockJacobi {
    f: LocalFactor,
    /// The owned blocks (global), and the owned rows' couplings to ghost blocks: what
    /// a coarse space extends with ([`super::coarse::LocalSolver`]).
    blocks: Vec<usize>,
    ring: Vec<RingCoupling>,
}

impl std::ops::Deref for BlockJacobi {
    type Target = LocalFactor;
    fn deref(&self) -> &LocalFactor {
        &self.f
    }
}

impl BlockJacobi {
    /// Factor `mat`'s local diagonal block ([`Factorization::Auto`]).
    pub fn new(mat: &DistMatrix) -> crate::Result<Self> {
        Self::with_factorization(mat, Factorization::Auto)
    }

    /// Factor `mat`'s local diagonal block with the given kind of factorization.
    pub fn with_factorization(mat: &DistMatrix, choice: Factorization) -> crate::Result<Self> {
        Self::with_options(mat, choice, FillOrdering::default())
    }

    /// Factor `mat`'s local diagonal block with the given kind of factorization and
    /// fill-reducing ordering.
    pub fn with_options(
        mat: &DistMatrix,
        choice: Factorization,
        ordering: FillOrdering,
    ) -> crate::Result<Self> {
        Self::with_factor_options(
            mat,
            FactorOptions {
                factorization: choice,
                ordering,
                ..FactorOptions::default()
            },
        )
    }

    /// Factor `mat`'s local diagonal block as `opts` says.
    pub fn with_factor_options(mat: &DistMatrix, opts: FactorOptions) -> crate::Result<Self> {
        let pat = diagonal_pattern(mat);
        let f = LocalFactor::new("block Jacobi", &pat, &mat.vals, opts)?;
        let layout = mat.layout();
        let ghosts = mat.ghost_blocks();
        let mut ring = Vec::new();
        for i in 0..layout.owned_len() {
            for e in (mat.row_ptr[i]..mat.diag_begin[i]).chain(mat.diag_end[i]..mat.row_ptr[i + 1])
            {
                ring.push(RingCoupling {
                    row: i,
                    col: ghosts[mat.lcol[e] as usize],
                    entry: e,
                });
            }
        }
        Ok(Self {
            f,
            blocks: (layout.start()..layout.end()).collect(),
            ring,
        })
    }

    /// Numeric refactorization for new values of the same pattern (symbolic reused).
    pub fn refactor(&mut self, mat: &DistMatrix) -> crate::Result<()> {
        if mat.n_owned_dofs() != self.f.n_full || mat.vals.len() != self.f.vals_len {
            return Err(Error::runtime(format!(
                "block Jacobi: refactor with a different pattern ({} dofs, {} blocks; factored \
                 {} dofs, {} blocks)",
                mat.n_owned_dofs(),
                mat.nnz_blocks_local(),
                self.f.n_full,
                self.f.vals_len / 9
            )));
        }
        self.f.refactor(&mat.vals)
    }
}

/// The owned diagonal block of `k` as a local block pattern over its value array.
pub(crate) fn diagonal_pattern(k: &DistMatrix) -> LocalBlockPattern {
    let n_own = k.layout().owned_len();
    let mut pat = LocalBlockPattern {
        n_nodes: n_own,
        row_ptr: Vec::with_capacity(n_own + 1),
        cols: Vec::new(),
        entries: Vec::new(),
        element_rows: (0..n_own).map(|i| k.is_element_row(i)).collect(),
    };
    pat.row_ptr.push(0);
    for i in 0..n_own {
        for e in k.diag_begin[i]..k.diag_end[i] {
            pat.cols.push(k.lcol[e] as usize);
            pat.entries.push(e);
        }
        pat.row_ptr.push(pat.cols.len());
    }
    pat
}

impl LocalFactor {
    /// Factor the local block matrix `pat` with values `vals` (9 per entry, see
    /// [`LocalBlockPattern`]). `label` prefixes error messages.
    pub fn new(
        label: &'static str,
        pat: &LocalBlockPattern,
        vals: &[f64],
        opts: FactorOptions,
    ) -> crate::Result<Self> {
        let n_full = 3 * pat.n_nodes;
        let cond = if opts.condense {
            Condensation::find(pat).map(Box::new)
        } else {
            None
        };
        let pat = cond.as_ref().map_or(pat, |c| c.reduced());
        let n_mid = 3 * pat.n_nodes;
        let border = Border::find(pat).map(Box::new);
        let pat = border.as_ref().map_or(pat, |b| b.inner());
        let (choice, ordering) = (opts.factorization, opts.ordering);
        let n_nodes = pat.n_nodes;
        let n = 3 * n_nodes;
        // Column counts: every block entry in block column k puts 3 entries in each of
        // the scalar columns 3k, 3k+1, 3k+2.
        let mut col_ptr = vec![0usize; n + 1];
        for &k in &pat.cols {
            for b in 0..3 {
                col_ptr[3 * k + b + 1] += 3;
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
        for i in 0..n_nodes {
            for a in 0..3 {
                for q in pat.row_ptr[i]..pat.row_ptr[i + 1] {
                    let (k, e) = (pat.cols[q], pat.entries[q]);
                    for b in 0..3 {
                        let p = next[3 * k + b];
                        next[3 * k + b] += 1;
                        row_idx[p] = 3 * i + a;
                        src[p] = 9 * e + 3 * a + b;
                    }
                }
            }
        }
        let transpose_pos: Vec<usize> = (0..n)
            .flat_map(|j| {
                let (cp, ri) = (&col_ptr, &row_idx);
                (cp[j]..cp[j + 1]).map(move |p| {
                    let i = ri[p];
                    match ri[cp[i]..cp[i + 1]].binary_search(&j) {
                        Ok(q) => cp[i] + q,
                        Err(_) => usize::MAX,
                    }
                })
            })
            .collect();
        let pattern = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let node_graph = Graph::symmetrized(n_nodes, &pat.row_ptr, &pat.cols);
        let mut f = Self {
            label,
            n,
            n_full,
            cond,
            n_mid,
            border,
            vals_len: vals.len(),
            choice,
            ordering,
            cholesky_ruled_out: false,
            pattern,
            src,
            transpose_pos,
            csc_vals: vec![0.0; nnz],
            node_graph,
            dof_perm: None,
            symbolic_lu: None,
            nd_lu: None,
            symbolic_llt: None,
            llt_values: Vec::new(),
            factor: Factor::None,
            factorizations: 0,
            symbolic_factorizations: 0,
            symbolic_seconds: 0.0,
            ordering_seconds: 0.0,
            last_factor_seconds: 0.0,
        };
        f.refactor(vals)?;
        Ok(f)
    }

    /// Numeric refactorization for new values (`vals`, indexed by the same pattern; the
    /// symbolic factorization is reused).
    pub fn refactor(&mut self, vals: &[f64]) -> crate::Result<()> {
        if vals.len() != self.vals_len {
            return Err(Error::runtime(format!(
                "{}: refactor with {} values, the pattern indexes {}",
                self.label,
                vals.len(),
                self.vals_len
            )));
        }
        let t = Instant::now();
        self.factor = Factor::None;
        if let Some(c) = self.cond.as_deref_mut() {
            c.reduce(vals, super::condense::REGULARIZATION)
                .map_err(|e| Error::runtime(format!("{}: {e}", self.label)))?;
        }
        if self.n == 0 {
            self.factorizations += 1;
            self.last_factor_seconds = 0.0;
            return Ok(());
        }
        {
            let reduced = self.cond.as_deref().map_or(vals, |c| c.values());
            for (v, &s) in self.csc_vals.iter_mut().zip(&self.src) {
                *v = reduced[s];
            }
        }
        let try_cholesky = match self.choice {
            Factorization::Lu => false,
            Factorization::Cholesky => true,
            Factorization::Auto => {
                if !self.cholesky_ruled_out && !self.is_symmetric() {
                    self.cholesky_ruled_out = true;
                }
                !self.cholesky_ruled_out
            }
        };
        if try_cholesky {
            match self.factor_cholesky() {
                Ok(()) => {}
                Err(e) if self.choice == Factorization::Cholesky => return Err(e),
                Err(_) => {
                    self.cholesky_ruled_out = true;
                    // Never retried: release the Cholesky factor's memory.
                    self.symbolic_llt = None;
                    self.llt_values = Vec::new();
                    self.factor_lu()?;
                }
            }
        } else {
            self.factor_lu()?;
        }
        self.check_nonsingular()?;
        if let Some(mut b) = self.border.take() {
            let reduced = self.cond.as_deref().map_or(vals, |c| c.values());
            let res = b.factor(reduced, |z| self.solve_factored(z));
            self.border = Some(b);
            if let Err(e) = res {
                self.factor = Factor::None;
                return Err(Error::runtime(format!(
                    "{}: the local {}×{} block: {e}",
                    self.label, self.n_mid, self.n_mid
                )));
            }
        }
        self.factorizations += 1;
        self.last_factor_seconds = t.elapsed().as_secs_f64();
        Ok(())
    }

    /// Numerically symmetric within round-off (entries with no transpose must be zero).
    fn is_symmetric(&self) -> bool {
        let scale = self.csc_vals.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let v = &self.csc_vals;
        self.transpose_pos.iter().enumerate().all(|(p, &q)| {
            let t = if q == usize::MAX { 0.0 } else { v[q] };
            (v[p] - t).abs() <= 1e-10 * v[p].abs().max(t.abs()) + 1e-14 * scale
        })
    }

    /// The scalar nested dissection permutation (`perm[new] = old`, inverse), computed on
    /// first use from the node graph.
    fn nd_perm(&mut self) -> crate::Result<()> {
        if self.dof_perm.is_none() {
            let t = Instant::now();
            let node_perm = ordering::nested_dissection(&self.node_graph)?;
            let fwd = ordering::expand_to_dofs(&node_perm, 3);
            let inv = ordering::inverse(&fwd);
            self.dof_perm = Some((fwd, inv));
            let dt = t.elapsed().as_secs_f64();
            self.ordering_seconds += dt;
            self.symbolic_seconds += dt;
        }
        Ok(())
    }

    fn factor_cholesky(&mut self) -> crate::Result<()> {
        if self.symbolic_llt.is_none() {
            if self.ordering == FillOrdering::NestedDissection {
                self.nd_perm()?;
            }
            let t = Instant::now();
            let ord = match (&self.ordering, &self.dof_perm) {
                (FillOrdering::NestedDissection, Some((fwd, inv))) => {
                    SymmetricOrdering::Custom(PermRef::new_checked(fwd, inv, self.n))
                }
                _ => SymmetricOrdering::Amd,
            };
            let sym = factorize_symbolic_cholesky(
                self.pattern.as_ref(),
                Side::Lower,
                ord,
                CholeskySymbolicParams::default(),
            )
            .map_err(|e| {
                Error::runtime(format!("{}: symbolic Cholesky failed: {e:?}", self.label))
            })?;
            self.llt_values = Vec::new();
            self.llt_values
                .try_reserve_exact(sym.len_val())
                .map_err(|_| {
                    Error::runtime(format!(
                        "{}: out of memory for the Cholesky factor ({} values)",
                        self.label,
                        sym.len_val()
                    ))
                })?;
            self.llt_values.resize(sym.len_val(), 0.0);
            self.symbolic_llt = Some(sym);
            self.symbolic_factorizations += 1;
            self.symbolic_seconds += t.elapsed().as_secs_f64();
        }
        let sym = self
            .symbolic_llt
            .as_ref()
            .expect("symbolic Cholesky present");
        let a = SparseColMatRef::new(self.pattern.as_ref(), &self.csc_vals);
        let par = LOCAL_PAR;
        let mut mem =
            MemBuffer::try_new(sym.factorize_numeric_llt_scratch::<f64>(par, Default::default()))
                .map_err(|_| {
                Error::runtime(format!(
                    "{}: out of memory for the Cholesky workspace",
                    self.label
                ))
            })?;
        sym.factorize_numeric_llt(
            &mut self.llt_values,
            a,
            Side::Lower,
            Default::default(),
            par,
            MemStack::new(&mut mem),
            Default::default(),
        )
        .map_err(|e| {
            Error::runtime(format!(
                "{}: the local {}×{} block is not positive definite ({e:?})",
                self.label, self.n, self.n
            ))
        })?;
        self.factor = Factor::Llt;
        Ok(())
    }

    fn factor_lu(&mut self) -> crate::Result<()> {
        if self.ordering == FillOrdering::NestedDissection {
            return self.factor_nd_lu();
        }
        if self.symbolic_lu.is_none() {
            let t = Instant::now();
            let sym = SymbolicLu::try_new(self.pattern.as_ref()).map_err(|e| {
                Error::runtime(format!("{}: symbolic LU failed: {e:?}", self.label))
            })?;
            self.symbolic_lu = Some(sym);
            self.symbolic_factorizations += 1;
            self.symbolic_seconds += t.elapsed().as_secs_f64();
        }
        let a = SparseColMatRef::new(self.pattern.as_ref(), &self.csc_vals);
        let sym = self.symbolic_lu.clone().expect("symbolic LU present");
        let label = self.label;
        let lu = SparseLu::try_new_with_symbolic(sym, a).map_err(|e| match e {
            LuError::SymbolicSingular { index } => Error::runtime(format!(
                "{label}: the local {}×{} block is singular (no pivot at step {index}); check \
                 constraints and contact multiplier rows",
                self.n, self.n
            )),
            LuError::Generic(g) => Error::runtime(format!("{label}: sparse LU failed: {g:?}")),
        })?;
        self.factor = Factor::Lu(Box::new(lu));
        Ok(())
    }

    /// LU with a nested dissection column order ([`NdLu`]), symbolic analysis once. The
    /// order dissects the *squared* node graph: LU's fill is bounded by the Cholesky
    /// factor of AᵀA, whose pattern is A²'s, and separators of A alone are too thin for
    /// it (measured: dissecting A's graph fills 2.5× slower than COLAMD, A²'s 2.2× faster).
    fn factor_nd_lu(&mut self) -> crate::Result<()> {
        if self.nd_lu.is_none() {
            let t = Instant::now();
            let node_perm = ordering::nested_dissection(&self.node_graph.squared())?;
            let fwd = ordering::expand_to_dofs(&node_perm, 3);
            self.ordering_seconds += t.elapsed().as_secs_f64();
            let lu = NdLu::new(self.pattern.as_ref(), &fwd)
                .map_err(|e| Error::runtime(format!("{}: {e}", self.label)))?;
            self.nd_lu = Some(Box::new(lu));
            self.symbolic_factorizations += 1;
            self.symbolic_seconds += t.elapsed().as_secs_f64();
        }
        let a = SparseColMatRef::new(self.pattern.as_ref(), &self.csc_vals);
        let lu = self.nd_lu.as_mut().expect("symbolic LU present");
        lu.factor(a).map_err(|e| {
            Error::runtime(format!(
                "{}: the local {}×{} block: {e}",
                self.label, self.n, self.n
            ))
        })?;
        self.factor = Factor::NdLu;
        Ok(())
    }

    /// z ← A⁻¹ z (length [`Self::n_full`]); no-op before a successful factorization.
    pub fn solve_in_place(&self, z: &mut [f64]) {
        match self.cond.as_deref() {
            None => self.solve_reduced(z),
            Some(c) => {
                if matches!(self.factor, Factor::None) && self.n > 0 {
                    return;
                }
                let mut x = Vec::with_capacity(self.n_mid);
                c.rhs(z, &mut x);
                self.solve_reduced(&mut x);
                c.recover(&x, z);
            }
        }
    }

    /// x ← M⁻¹ x for the condensed matrix M (length `n_mid`): the factored matrix, or
    /// the factored interior and the border ([`super::border`]).
    fn solve_reduced(&self, x: &mut [f64]) {
        match self.border.as_deref() {
            None => self.solve_factored(x),
            Some(b) => b.solve(x, |y| self.solve_factored(y)),
        }
    }

    /// x ← M⁻¹ x for the factored (condensed) matrix M (length [`Self::n`]).
    fn solve_factored(&self, z: &mut [f64]) {
        self.solve_factored_many(z, 1);
    }

    /// X ← M⁻¹ X for `ncols` columns of length [`Self::n`], one after the other.
    fn solve_factored_many(&self, z: &mut [f64], ncols: usize) {
        if ncols == 0 || self.n == 0 {
            return;
        }
        match &self.factor {
            Factor::None => {}
            Factor::Lu(lu) => {
                lu.solve_in_place(faer::MatMut::from_column_major_slice_mut(z, self.n, ncols))
            }
            Factor::NdLu => self
                .nd_lu
                .as_ref()
                .expect("ND LU present")
                .solve_many(z, ncols),
            Factor::Llt => {
                let sym = self
                    .symbolic_llt
                    .as_ref()
                    .expect("symbolic Cholesky present");
                let par = LOCAL_PAR;
                let mut mem = MemBuffer::new(sym.solve_in_place_scratch::<f64>(ncols, par));
                LltRef::new(sym, &self.llt_values).solve_in_place_with_conj(
                    Conj::No,
                    faer::MatMut::from_column_major_slice_mut(z, self.n, ncols),
                    par,
                    MemStack::new(&mut mem),
                );
            }
        }
    }

    /// X ← A⁻¹ X for `ncols` columns of length [`Self::n_full`], one after the other:
    /// one pass through the factor for all of them (the supernodal solves work on
    /// blocks of columns).
    pub fn solve_many(&self, z: &mut [f64], ncols: usize) {
        let nf = self.n_full;
        if ncols == 0 || nf == 0 {
            return;
        }
        if self.border.is_some() || (matches!(self.factor, Factor::None) && self.n > 0) {
            for col in z.chunks_exact_mut(nf) {
                self.solve_in_place(col);
            }
            return;
        }
        match self.cond.as_deref() {
            None => self.solve_factored_many(z, ncols),
            Some(c) => {
                let mut x = Vec::with_capacity(self.n_mid * ncols);
                let mut one = Vec::with_capacity(self.n_mid);
                for col in z.chunks_exact(nf) {
                    c.rhs(col, &mut one);
                    x.extend_from_slice(&one);
                }
                self.solve_factored_many(&mut x, ncols);
                for (col, xc) in z.chunks_exact_mut(nf).zip(x.chunks_exact(self.n_mid)) {
                    c.recover(xc, col);
                }
            }
        }
    }

    /// Solve A z = A·1 and require z ≈ 1: catches zero pivots (inf/NaN) and blocks that
    /// are singular to working precision (error ≥ 1 means cond ≳ 1/ε).
    fn check_nonsingular(&mut self) -> crate::Result<()> {
        let mut z = vec![0.0; self.n];
        let (cp, ri) = (self.pattern.col_ptr(), self.pattern.row_idx());
        for j in 0..self.n {
            for p in cp[j]..cp[j + 1] {
                z[ri[p]] += self.csc_vals[p];
            }
        }
        self.solve_factored(&mut z);
        let err = z.iter().map(|v| (v - 1.0).abs()).fold(0.0f64, |m, e| {
            if e.is_nan() {
                f64::INFINITY
            } else {
                m.max(e)
            }
        });
        if !err.is_finite() || err > 1.0 {
            self.factor = Factor::None;
            return Err(Error::runtime(format!(
                "{}: the local {}×{} block is numerically singular (check solve error \
                 {err:.3e}); check constraints and contact multiplier rows",
                self.label, self.n, self.n
            )));
        }
        Ok(())
    }

    /// The factorization in use: `Lu` or `Cholesky` (`Auto` only before any
    /// factorization or for an empty block).
    pub fn kind(&self) -> Factorization {
        match self.factor {
            Factor::None => Factorization::Auto,
            Factor::Lu(_) | Factor::NdLu => Factorization::Lu,
            Factor::Llt => Factorization::Cholesky,
        }
    }
    /// Size of the factored block (scalar dofs, after condensation).
    pub fn n(&self) -> usize {
        self.n
    }
    /// Size of the block (scalar dofs, before condensation).
    pub fn n_full(&self) -> usize {
        self.n_full
    }
    /// Dense block rows set aside as a border ([`super::border`]).
    pub fn border_blocks(&self) -> usize {
        self.border.as_ref().map_or(0, |b| b.n_border())
    }
    /// Block rows eliminated by the condensation ([`super::condense`]).
    pub fn condensed_blocks(&self) -> usize {
        self.cond.as_ref().map_or(0, |c| c.n_condensed())
    }
    /// Scalar nonzeros of the factored block.
    pub fn nnz(&self) -> usize {
        self.src.len()
    }
    /// Numeric factorizations done (the first one included).
    pub fn factorizations(&self) -> usize {
        self.factorizations
    }
    /// Symbolic factorizations done (one per kind used; 0 for an empty block).
    pub fn symbolic_factorizations(&self) -> usize {
        self.symbolic_factorizations
    }
    /// Wall time of the symbolic factorizations (ordering and structure).
    pub fn symbolic_seconds(&self) -> f64 {
        self.symbolic_seconds
    }
    /// The fill-reducing ordering requested.
    pub fn ordering(&self) -> FillOrdering {
        self.ordering
    }
    /// Wall time of the nested dissection ordering (included in
    /// [`Self::symbolic_seconds`]).
    pub fn ordering_seconds(&self) -> f64 {
        self.ordering_seconds
    }
    /// Nonzeros of the Cholesky factor L (0 before a Cholesky symbolic factorization).
    pub fn cholesky_factor_nnz(&self) -> usize {
        self.symbolic_llt.as_ref().map_or(0, |s| s.len_val())
    }
    /// Wall time of the last numeric factorization (value gather, factorization, check
    /// solve; on the first call also the symbolic factorization).
    pub fn last_factor_seconds(&self) -> f64 {
        self.last_factor_seconds
    }
}

impl LocalSolver for BlockJacobi {
    fn local_blocks(&self) -> &[usize] {
        &self.blocks
    }
    fn ring_couplings(&self) -> &[RingCoupling] {
        &self.ring
    }
    fn ring_values<'a>(&'a self, k: &'a DistMatrix) -> &'a [f64] {
        &k.vals
    }
    fn solve_local(&self, x: &mut [f64]) {
        self.f.solve_in_place(x);
    }
    fn solve_local_many(&self, x: &mut [f64], ncols: usize) {
        self.f.solve_many(x, ncols);
    }
}

impl Preconditioner for BlockJacobi {
    fn setup(&mut self, _comm: &dyn Comm, k: &DistMatrix) -> crate::Result<()> {
        self.refactor(k)
    }
    fn apply(&self, _comm: &dyn Comm, r: &[f64], z: &mut [f64]) {
        z.copy_from_slice(r);
        self.f.solve_in_place(z);
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::linalg::matrix::tests::Lcg;
    use crate::parallel::{Comm, Layout, SerialComm};

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
        bj.apply(&SerialComm, &r, &mut z);
        assert!(residual(&m1, &z, &r) < 1e-13);

        // Same pattern, other values: the old factors no longer solve it, the new ones do.
        let m2 = tridiag(50, 2, 4.0);
        bj.apply(&SerialComm, &r, &mut z);
        assert!(residual(&m2, &z, &r) > 1e-3);
        bj.refactor(&m2).unwrap();
        bj.apply(&SerialComm, &r, &mut z);
        assert!(residual(&m2, &z, &r) < 1e-13);
        assert_eq!(bj.factorizations(), 2);
        assert_eq!(bj.symbolic_factorizations(), 1);
        assert_eq!(bj.kind(), Factorization::Lu);
        assert!(bj.last_factor_seconds() > 0.0);
    }

    #[test]
    fn auto_uses_cholesky_while_spd_and_switches_to_lu() {
        let mut m = elasticity_cube(&SerialComm, 3, &[64]);
        let r: Vec<f64> = (0..192).map(|i| (i as f64 * 0.37).cos()).collect();
        let mut z = vec![0.0; 192];
        let mut bj = BlockJacobi::new(&m).unwrap();
        assert_eq!(bj.kind(), Factorization::Cholesky);
        bj.apply(&SerialComm, &r, &mut z);
        assert!(residual(&m, &z, &r) < 1e-12);

        // Symmetric but indefinite (one diagonal entry flipped): Cholesky fails, LU works.
        let e = m.row_ptr[40] + m.cols_of_row(40).binary_search(&40).unwrap();
        m.vals[9 * e] = -m.vals[9 * e];
        bj.refactor(&m).unwrap();
        assert_eq!(bj.kind(), Factorization::Lu);
        bj.apply(&SerialComm, &r, &mut z);
        assert!(residual(&m, &z, &r) < 1e-12);
        assert!(BlockJacobi::with_factorization(&m, Factorization::Cholesky).is_err());

        // Back to SPD: Auto stays with LU (no retry after a failure).
        m.vals[9 * e] = -m.vals[9 * e];
        bj.refactor(&m).unwrap();
        assert_eq!(bj.kind(), Factorization::Lu);
        assert_eq!(bj.symbolic_factorizations(), 2);
        assert_eq!(bj.factorizations(), 3);

        // Non-symmetric values from the start: LU directly, one symbolic factorization.
        m.vals[9 * e + 1] += 0.5;
        let bj = BlockJacobi::new(&m).unwrap();
        assert_eq!(bj.kind(), Factorization::Lu);
        assert_eq!(bj.symbolic_factorizations(), 1);
        bj.apply(&SerialComm, &r, &mut z);
        assert!(residual(&m, &z, &r) < 1e-12);
    }

    #[test]
    fn nested_dissection_matches_amd_for_cholesky_and_lu() {
        use crate::parallel::run_ranks;
        // 7³ nodes (1029 unknowns): large enough for METIS to dissect, not just MMD.
        for p in [1usize, 2] {
            let counts: Vec<usize> = (0..p).map(|r| 343 * (r + 1) / p - 343 * r / p).collect();
            run_ranks(p, |c| {
                let m = elasticity_cube(c, 6, &counts);
                let n = m.n_owned_dofs();
                let r: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).cos()).collect();
                let solve = |kind, ord| {
                    let bj = BlockJacobi::with_options(&m, kind, ord).unwrap();
                    assert_eq!(bj.kind(), kind);
                    assert_eq!(bj.ordering(), ord);
                    let mut z = vec![0.0; n];
                    bj.apply(&SerialComm, &r, &mut z);
                    (bj, z)
                };
                let (amd, z_amd) = solve(Factorization::Cholesky, FillOrdering::Amd);
                let (nd, z_nd) = solve(Factorization::Cholesky, FillOrdering::NestedDissection);
                let (_, z_lu_amd) = solve(Factorization::Lu, FillOrdering::Amd);
                let (lu_nd, z_lu_nd) = solve(Factorization::Lu, FillOrdering::NestedDissection);
                let zmax = z_amd.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                for z in [&z_nd, &z_lu_amd, &z_lu_nd] {
                    let d = z_amd
                        .iter()
                        .zip(z)
                        .map(|(a, b)| (a - b).abs())
                        .fold(0.0, f64::max);
                    assert!(d < 1e-10 * zmax, "{d} vs {zmax}");
                }
                assert_eq!(amd.ordering_seconds(), 0.0);
                assert!(amd.dof_perm.is_none());
                // LU orders columns by its own dissection (of the squared graph).
                let lu_cols = lu_nd.nd_lu.as_ref().unwrap().col_order();
                assert!(ordering::is_permutation(lu_cols) && lu_cols.len() == n);
                assert!(lu_nd.dof_perm.is_none());
                let (fwd, inv) = nd.dof_perm.as_ref().unwrap();
                assert!(ordering::is_permutation(fwd));
                assert_eq!(fwd.len(), n);
                assert!((0..n).all(|k| inv[fwd[k]] == k));
                // The three dofs of a node stay together, in order.
                assert!(fwd
                    .chunks(3)
                    .all(|d| d[0] % 3 == 0 && d[1] == d[0] + 1 && d[2] == d[0] + 2));
                // Nested dissection is not the identity and fills about as little as AMD
                // on this small cube (it wins on large 3D blocks).
                let (fwd, _) = nd.dof_perm.as_ref().unwrap();
                assert!(fwd.iter().enumerate().any(|(k, &i)| k != i));
                assert!(
                    nd.cholesky_factor_nnz() < amd.cholesky_factor_nnz() * 11 / 10,
                    "nd {} amd {}",
                    nd.cholesky_factor_nnz(),
                    amd.cholesky_factor_nnz()
                );
                // Default: Auto with nested dissection.
                let bj = BlockJacobi::new(&m).unwrap();
                assert_eq!(bj.kind(), Factorization::Cholesky);
                assert_eq!(bj.ordering(), FillOrdering::NestedDissection);
            });
        }
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

    type Mat3 = [[f64; 3]; 3];

    /// `base` (one rank) grown by `extra` block rows with the extra `pairs` in its
    /// pattern, `base`'s blocks copied in; assembly not finished.
    fn extended(base: &DistMatrix, extra: usize, pairs: &[(usize, usize)]) -> DistMatrix {
        let n0 = base.layout().owned_len();
        let mut all: Vec<(usize, usize)> = (0..n0)
            .flat_map(|i| base.cols_of_row(i).iter().map(move |&k| (i, k)))
            .collect();
        all.extend_from_slice(pairs);
        let mut m = DistMatrix::new(&SerialComm, Layout::from_counts(&[n0 + extra], 0), &all);
        for i in 0..n0 {
            for (q, &k) in base.cols_of_row(i).iter().enumerate() {
                let e = base.row_ptr[i] + q;
                let v: [f64; 9] = std::array::from_fn(|c| base.vals[9 * e + c]);
                m.add_block(i, k, &v);
            }
        }
        m
    }

    /// `base` (one rank, SPD) with three multipliers attached to each of `nodes`, as an
    /// ALM wall assembles them (walls.rs): in the frame P of a tilted normal, the
    /// law's ∂h/∂g = `hg` and ∂h/∂λ = `hl` give B = −κ P (I − hl), C = −κ hg Pᵀ and
    /// D = −κ (hl + 10⁻⁸ I). `kinds[j % kinds.len()]` picks each node's (hg, hl).
    fn with_multipliers(base: &DistMatrix, nodes: &[usize], kinds: &[(Mat3, Mat3)]) -> DistMatrix {
        let n0 = base.layout().owned_len();
        let pairs: Vec<(usize, usize)> = nodes
            .iter()
            .enumerate()
            .flat_map(|(j, &a)| [(a, n0 + j), (n0 + j, a), (n0 + j, n0 + j)])
            .collect();
        let mut m = extended(base, nodes.len(), &pairs);
        let kappa = 7.0 * (0..n0).map(|i| base.block(i, i).unwrap()[0]).sum::<f64>() / n0 as f64;
        let (c, s) = (0.8f64, 0.6f64);
        // Columns: normal, t1, t2.
        let p = [[c, -s, 0.0], [0.0, 0.0, 1.0], [s, c, 0.0]];
        let mul = |a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]| -> [[f64; 3]; 3] {
            std::array::from_fn(|i| {
                std::array::from_fn(|k| (0..3).map(|l| a[i][l] * b[l][k]).sum())
            })
        };
        let pt: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|k| p[k][i]));
        let flat =
            |a: [[f64; 3]; 3], f: f64| -> [f64; 9] { std::array::from_fn(|q| f * a[q / 3][q % 3]) };
        for (j, &a) in nodes.iter().enumerate() {
            let (hg, hl) = kinds[j % kinds.len()];
            let i_hl: [[f64; 3]; 3] =
                std::array::from_fn(|i| std::array::from_fn(|k| f64::from(i == k) - hl[i][k]));
            let d: [[f64; 3]; 3] = std::array::from_fn(|i| {
                std::array::from_fn(|k| hl[i][k] + 1e-8 * f64::from(i == k))
            });
            m.add_block(a, n0 + j, &flat(mul(&p, &i_hl), -kappa));
            m.add_block(n0 + j, a, &flat(mul(&hg, &pt), -kappa));
            m.add_block(n0 + j, n0 + j, &flat(d, -kappa));
        }
        m.finish_assembly(&SerialComm);
        m
    }

    const I3: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    const Z3: [[f64; 3]; 3] = [[0.0; 3]; 3];
    const NORMAL: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]];
    const FREE_T: [[f64; 3]; 3] = [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

    /// GMRES iterations to a relative residual of 1e-12 with `bj` on `m`.
    fn gmres_iterations(m: &DistMatrix, bj: &BlockJacobi, r: &[f64]) -> usize {
        let mut x = vec![0.0; r.len()];
        let opts = crate::linalg::GmresOptions {
            rtol: 1e-12,
            ..Default::default()
        };
        let st = crate::linalg::gmres(&SerialComm, &mut { m }, bj, r, &mut x, &opts).unwrap();
        assert!(st.converged, "{st:?}");
        st.iterations
    }

    #[test]
    fn attached_multipliers_are_condensed_to_a_cholesky_factor() {
        let base = elasticity_cube(&SerialComm, 3, &[64]);
        let nodes: Vec<usize> = (48..64).collect();
        // Sticking (h = g), open (h = λ), active and frictionless (normal h = g,
        // tangential h = λ).
        let kinds = [(I3, Z3), (Z3, I3), (NORMAL, FREE_T)];
        let m = with_multipliers(&base, &nodes, &kinds);
        let n = 3 * (64 + nodes.len());
        let r: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).cos()).collect();

        let bj = BlockJacobi::new(&m).unwrap();
        assert_eq!(bj.condensed_blocks(), nodes.len());
        assert_eq!((bj.n(), bj.n_full()), (192, n));
        assert_eq!(bj.kind(), Factorization::Cholesky);
        // Exact but for the regularization δ of the constraint directions and round-off.
        let mut z = vec![0.0; n];
        bj.apply(&SerialComm, &r, &mut z);
        let res = residual(&m, &z, &r);
        assert!(res < 1e-4, "{res:e}");
        assert!(gmres_iterations(&m, &bj, &r) <= 3);

        // As assembled: a saddle point, factored by LU, one iteration.
        let opts = FactorOptions {
            condense: false,
            ..FactorOptions::default()
        };
        let full = BlockJacobi::with_factor_options(&m, opts).unwrap();
        assert_eq!((full.condensed_blocks(), full.n()), (0, n));
        assert_eq!(full.kind(), Factorization::Lu);
        full.apply(&SerialComm, &r, &mut z);
        assert!(residual(&m, &z, &r) < 1e-10);
        // The same solution.
        let mut zc = vec![0.0; n];
        bj.apply(&SerialComm, &r, &mut zc);
        let diff = z
            .iter()
            .zip(&zc)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let size = z.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(diff < 1e-4 * size, "{diff:e} vs {size:e}");
    }

    #[test]
    fn slipping_multipliers_condense_to_a_nonsymmetric_block() {
        let base = elasticity_cube(&SerialComm, 3, &[64]);
        let nodes: Vec<usize> = (48..64).collect();
        // Slip: the tangential rows depend on λ_N through the threshold and turn with
        // the slip direction; ∂h/∂g is not ∂h/∂λ's complement (non-symmetric).
        let hl = [[0.0, 0.0, 0.0], [-0.1, 0.7, 0.2], [0.05, 0.2, 0.9]];
        let hg = [[1.0, 0.0, 0.0], [0.0, 0.3, -0.2], [0.0, -0.2, 0.1]];
        let m = with_multipliers(&base, &nodes, &[(hg, hl), (I3, Z3)]);
        let n = 3 * (64 + nodes.len());
        let r: Vec<f64> = (0..n).map(|i| (i as f64 * 0.11).sin()).collect();
        let bj = BlockJacobi::new(&m).unwrap();
        assert_eq!(bj.condensed_blocks(), nodes.len());
        assert_eq!(bj.kind(), Factorization::Lu);
        assert!(gmres_iterations(&m, &bj, &r) <= 3);
    }

    #[test]
    fn rows_coupled_to_more_than_one_node_are_not_condensed() {
        // Every row of the tridiagonal matrix couples to two others.
        assert_eq!(
            BlockJacobi::new(&tridiag(10, 1, 6.0))
                .unwrap()
                .condensed_blocks(),
            0
        );
        // A multiplier block coupled to two nodes (as a rigid body's DOFs would be).
        let base = elasticity_cube(&SerialComm, 2, &[27]);
        let pairs = [(27, 27), (27, 3), (3, 27), (27, 5), (5, 27)];
        let mut m = extended(&base, 1, &pairs);
        m.add_block(27, 27, &[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
        m.finish_assembly(&SerialComm);
        assert_eq!(BlockJacobi::new(&m).unwrap().condensed_blocks(), 0);
    }

    /// A block row coupled to every node (a rigid body's DOFs) is set aside as a border
    /// and the system still solved exactly, also when the border rows are not the
    /// transpose of its columns (the interior keeps its Cholesky factor).
    #[test]
    fn dense_rows_are_solved_as_a_border() {
        let base = elasticity_cube(&SerialComm, 5, &[216]);
        for non_symmetric in [false, true] {
            let pairs: Vec<(usize, usize)> = std::iter::once((216, 216))
                .chain((0..216).flat_map(|i| [(216, i), (i, 216)]))
                .collect();
            let mut m = extended(&base, 1, &pairs);
            // A soft spring from every node to the hub: SPD; skewed when asked.
            let k = 0.01 * base.block(0, 0).unwrap()[0];
            let mut rng = Lcg(3);
            for i in 0..216 {
                let c: [f64; 9] = std::array::from_fn(|q| if q % 4 == 0 { -k } else { 0.0 });
                let d = c.map(|v| -v);
                m.add_block(i, 216, &c);
                if non_symmetric {
                    let skew: [f64; 9] = std::array::from_fn(|_| 0.3 * k * rng.next());
                    m.add_block(216, i, &skew);
                } else {
                    m.add_block(216, i, &c);
                }
                m.add_block(i, i, &d);
                m.add_block(216, 216, &d);
            }
            m.finish_assembly(&SerialComm);
            let bj = BlockJacobi::new(&m).unwrap();
            assert_eq!(bj.border_blocks(), 1);
            assert_eq!(bj.n(), 3 * 216);
            // The interior is the cube's SPD stiffness either way: only the border is
            // non-symmetric, and it is solved apart.
            assert_eq!(bj.kind(), Factorization::Cholesky);
            let r: Vec<f64> = (0..3 * 217).map(|i| (i as f64 * 0.17).cos()).collect();
            let mut z = vec![0.0; r.len()];
            bj.apply(&SerialComm, &r, &mut z);
            let res = residual(&m, &z, &r);
            assert!(res < 1e-10, "non-symmetric {non_symmetric}: {res:e}");
        }
    }

    /// A multiplier block coupled to two nodes that are coupled to each other (a node
    /// tracked by a rigid body and the body's block) is eliminated without fill, and
    /// the condensed factor solves the system exactly.
    #[test]
    fn rows_coupled_to_coupled_nodes_are_condensed_exactly() {
        let base = elasticity_cube(&SerialComm, 2, &[27]);
        assert!(base.cols_of_row(3).contains(&4));
        let pairs = [(27, 27), (27, 3), (3, 27), (27, 4), (4, 27)];
        let mut m = extended(&base, 1, &pairs);
        let mut rng = Lcg(5);
        let k = base.block(3, 3).unwrap()[0];
        for (i, j) in [(27, 3), (3, 27), (27, 4), (4, 27)] {
            let v: [f64; 9] = std::array::from_fn(|_| k * rng.next());
            m.add_block(i, j, &v);
        }
        let d: [f64; 9] = std::array::from_fn(|q| k * (0.2 * rng.next() - f64::from(q % 4 == 0)));
        m.add_block(27, 27, &d);
        m.finish_assembly(&SerialComm);
        let opts = FactorOptions {
            factorization: Factorization::Lu,
            ..FactorOptions::default()
        };
        let bj = BlockJacobi::with_factor_options(&m, opts).unwrap();
        assert_eq!((bj.condensed_blocks(), bj.n()), (1, 81));
        let r: Vec<f64> = (0..84).map(|i| (i as f64 * 0.29).sin()).collect();
        let mut z = vec![0.0; 84];
        bj.apply(&SerialComm, &r, &mut z);
        // Exact but for the regularization δ = 1e-6 of the eliminated block.
        let res = residual(&m, &z, &r);
        assert!(res < 1e-4, "{res:e}");
        assert!(gmres_iterations(&m, &bj, &r) <= 2);
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
}
