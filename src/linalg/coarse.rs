//! The second level of the two-level Schwarz preconditioner ([`super::two_level`]): a
//! coarse space that carries the rigid-body modes between subdomains, so that GMRES
//! iterations do not grow with the number of ranks.
//!
//! One-level Schwarz (block Jacobi, RAS) exchanges information only between neighbours,
//! once per iteration, and nothing in it removes error that is nearly rigid on each
//! subdomain: its iteration count grows with the number of subdomains (alfe on 2 ranks:
//! 10–120× one rank's; issue 33). A coarse space Φ, a few columns per subdomain, with the
//! Galerkin matrix A₀ = Φᵀ A Φ removes that error if Φ holds the rigid-body modes locally
//! and each column has low energy (Toselli & Widlund, *Domain Decomposition Methods*,
//! 2005, ch. 3 and 5).
//!
//! **The construction** follows GDSW (Dohrmann, Klawonn & Widlund, 2008; Trilinos'
//! FROSch): basis functions are the rigid-body modes on interface *components* (nodes
//! grouped by the set of subdomains that share them: faces, edges, vertices), zero on the
//! other components, extended into the subdomains by local Dirichlet solves. GDSW extends
//! with the interior matrix A_II, which is not the first level's matrix, so FROSch factors
//! it as well: a second factorization per setup. Here the interface is instead the
//! *Dirichlet ring* of each first-level subdomain, the blocks just outside its local
//! system that its rows couple to (block Jacobi: the ghost blocks of the owned rows; RAS:
//! the blocks beyond the overlap that its received rows reach), and a subdomain's values
//! solve its own local system with the ring values as Dirichlet data:
//!
//! ```text
//!   Φ_p = R_p⁰ (−A_loc⁻¹ A_loc,ring Φ_ring)
//! ```
//!
//! one solve with the factor the first level already has per basis function that reaches
//! the ring, of which the owned part is kept (each unknown computed by its owner, as RAS
//! keeps it). Every ring node lies in exactly one component, so the basis functions of a
//! rigid-body mode r sum to r on every ring, and where a subdomain's rows see no
//! Dirichlet condition or contact (A r = 0 row by row) their extensions sum to r: the
//! rigid-body modes are in the coarse space, the null-space property GDSW's bound rests on.
//!
//! Components are keyed by their sharing set (the node's owner and the ranks whose local
//! system or ring holds it), without splitting a set into connected pieces. A component's
//! modes (three translations; three rotations about its centroid, scaled by its radius)
//! are orthonormalized over its nodes: a single node keeps its translations, a straight
//! line loses its axial rotation. Global unknowns (a rigid body's six DOFs, a coupling's
//! reference point: dense rows) are coarse unknowns of their own, one per scalar, extended
//! the same way; where such a block is inside a rank's local system the extension with the
//! block prescribed is x = Y Y_g⁻¹, Y = A_loc⁻¹ E_g. Unknowns that are neither (contact
//! multipliers, hybrid pressures) are zero on rings: a rigid motion has no pressure.
//!
//! **Application** ([`CoarseMode`]): multiplicative, coarse first,
//! x₀ = A₀⁻¹ Φᵀ r and z = Φ x₀ + M⁻¹ (r − A Φ x₀), with A Φ kept from the setup, so one
//! reduction of the coarse vector per application on top of the first level; or additive,
//! z = Φ x₀ + M⁻¹ r. A₀ is small and dense; every rank holds it, factors it (LU: friction
//! makes A non-symmetric) and solves with it redundantly. Functions that vanish (a
//! component whose ring nodes are all clamped) are dropped from A₀ by their diagonal.

use super::DistMatrix;
use crate::parallel::{Comm, HaloPlan, Layout};
use crate::Error;
use faer::linalg::solvers::Solve;
use std::collections::BTreeSet;
use std::time::Instant;

/// One coupling of a local system's row to a block outside it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RingCoupling {
    /// Local block row of the local system.
    pub row: usize,
    /// Global block column, outside the local system.
    pub col: usize,
    /// Entry whose 9 values (row-major) are the block, in [`LocalSolver::ring_values`].
    pub entry: usize,
}

/// What the coarse space needs of a first-level local solver.
pub trait LocalSolver {
    /// Global blocks of the local system in its order: the rank's owned blocks first
    /// (in order), then any others.
    fn local_blocks(&self) -> &[usize];
    /// The couplings of the local system's rows to blocks outside it (its Dirichlet ring).
    fn ring_couplings(&self) -> &[RingCoupling];
    /// The values (9 per entry) that [`RingCoupling::entry`] indexes, from the last setup
    /// on `k`.
    fn ring_values<'a>(&'a self, k: &'a DistMatrix) -> &'a [f64];
    /// x ← A_loc⁻¹ x on a local vector (3 unknowns per local block).
    fn solve_local(&self, x: &mut [f64]);
    /// The same for `ncols` local vectors one after the other.
    fn solve_local_many(&self, x: &mut [f64], ncols: usize) {
        let n = x.len() / ncols.max(1);
        for col in x.chunks_exact_mut(n.max(1)) {
            self.solve_local(col);
        }
    }
}

/// How the coarse correction is combined with the first level.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CoarseMode {
    /// Coarse first, then the first level on the remaining residual.
    #[default]
    Multiplicative,
    /// Both on the same residual, summed.
    Additive,
}

/// The kinds of blocks (see the module documentation), known on every rank.
struct Kinds {
    starts: Vec<usize>,
    nodes: Vec<usize>,
    global: Vec<usize>,
}

impl Kinds {
    /// Collective.
    fn new(comm: &dyn Comm, k: &DistMatrix) -> Self {
        let mut nodes = vec![0u64; comm.size()];
        nodes[comm.rank()] = k.node_blocks() as u64;
        comm.allreduce_sum_u64(&mut nodes);
        Self {
            starts: k.layout().starts.clone(),
            nodes: nodes.into_iter().map(|v| v as usize).collect(),
            global: k.global_blocks().to_vec(),
        }
    }
    fn owner(&self, g: usize) -> usize {
        self.starts.partition_point(|&s| s <= g) - 1
    }
    fn is_node(&self, g: usize) -> bool {
        let q = self.owner(g);
        g - self.starts[q] < self.nodes[q]
    }
    fn global_index(&self, g: usize) -> Option<usize> {
        self.global.binary_search(&g).ok()
    }
}

/// The rigid-body modes at `x` about `c`, rotations scaled by 1/`s`: 3 rows × 6 modes
/// (translations x, y, z; rotations about x, y, z).
fn modes(x: &[f64; 3], c: &[f64; 3], s: f64) -> [[f64; 6]; 3] {
    let d = [(x[0] - c[0]) / s, (x[1] - c[1]) / s, (x[2] - c[2]) / s];
    [
        [1.0, 0.0, 0.0, 0.0, d[2], -d[1]],
        [0.0, 1.0, 0.0, -d[2], 0.0, d[0]],
        [0.0, 0.0, 1.0, d[1], -d[0], 0.0],
    ]
}

/// An interface component: its modes, orthonormalized over its nodes.
#[derive(Debug, Clone)]
struct Component {
    centroid: [f64; 3],
    scale: f64,
    /// Each function's mode coefficients.
    basis: Vec<[f64; 6]>,
    /// Its first coarse function.
    first: usize,
}

impl Component {
    /// Values of its functions at `x`: `out[a][j]`, row a of function j.
    fn values(&self, x: &[f64; 3], out: &mut Vec<[f64; 3]>) {
        let r = modes(x, &self.centroid, self.scale);
        out.clear();
        out.extend(
            self.basis
                .iter()
                .map(|t| std::array::from_fn(|a| (0..6).map(|q| r[a][q] * t[q]).sum::<f64>())),
        );
    }
}

/// A ring coupling of a component's node: (local row block, ring block index, entry).
type RingEntry = (usize, usize, usize);

/// What a ring block carries.
#[derive(Debug, Clone, Copy)]
enum RingData {
    None,
    /// A node of component `comp` at `x`.
    Node {
        comp: usize,
        x: [f64; 3],
    },
    /// A global unknown whose three coarse functions start at `first`.
    Global {
        first: usize,
    },
}

/// Sizes and times of a coarse space, for the run's summary and the scaling study.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct CoarseStats {
    /// Coarse unknowns (the same on every rank), of them kept in A₀.
    pub dimension: usize,
    pub kept: usize,
    /// Interface components.
    pub components: usize,
    /// Basis functions this rank extended (local solves per setup).
    pub local_functions: usize,
    /// Columns of this rank's Φ and A Φ rows.
    pub columns: usize,
    /// Seconds of the last setup: extension solves, A Φ and A₀, A₀'s factorization.
    pub extension_seconds: f64,
    pub galerkin_seconds: f64,
    pub factor_seconds: f64,
    /// Seconds of the symbolic build (components, bases, exchanges), once.
    pub symbolic_seconds: f64,
    /// Setups done, and their seconds in all (extension, A₀, its factorization).
    pub setups: usize,
    pub total_seconds: f64,
}

/// A coarse space on the rings of a first-level local solver; see the module
/// documentation.
pub struct CoarseSpace {
    mode: CoarseMode,
    n_own_dofs: usize,
    /// Coarse dimension m.
    m: usize,
    components: Vec<Component>,
    /// Ring couplings kept, grouped by what their ring block carries: per group the
    /// couplings (local row, ring data index, entry).
    ring: Vec<RingData>,
    comp_couplings: Vec<(usize, Vec<RingEntry>)>,
    global_ring: Vec<(usize, Vec<(usize, usize)>)>,
    /// Global unknowns inside the local system: (local block, first coarse function).
    global_local: Vec<(usize, usize)>,
    /// The functions this rank extends (sorted): the columns of its rows of Φ.
    mine: Vec<usize>,
    /// The coarse functions this rank's rows of A Φ can be nonzero in (sorted): its own
    /// and those of every rank it receives ghost rows from.
    cols: Vec<usize>,
    /// Positions in `cols` of `mine`.
    own: Vec<usize>,
    /// Per rank, positions in `cols` of the functions whose Φ rows it sends us.
    recv_cols: Vec<Vec<usize>>,
    /// Φ's owned rows over `mine`, row-major.
    phi: Vec<f64>,
    /// The owned block rows where A Φ can be nonzero: those coupled to ghost blocks, and
    /// global unknowns'. Elsewhere a row of A Φ is a row of the local system the
    /// extension solved, A_loc x = 0 (to the factor's accuracy: the δ of condensed
    /// multipliers, [`super::condense`]).
    boundary: Vec<usize>,
    /// A Φ on the boundary rows (3 per block), row-major over `cols`.
    aphi: Vec<f64>,
    /// Coarse functions kept in A₀, and A₀'s LU over them.
    kept: Vec<usize>,
    lu: Option<faer::linalg::solvers::PartialPivLu<f64>>,
    stats: CoarseStats,
    #[cfg(test)]
    a0: Vec<f64>,
}

impl std::fmt::Debug for CoarseSpace {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CoarseSpace")
            .field("mode", &self.mode)
            .field("stats", &self.stats)
            .finish()
    }
}

impl CoarseSpace {
    /// Collective: components, bases and exchange plans for the first level `local` on
    /// `k`'s pattern; `points` are the owned nodes' reference coordinates (the first
    /// [`DistMatrix::node_blocks`] owned blocks); without them the components carry
    /// translations only. Numeric work is in [`CoarseSpace::setup`].
    pub fn new(
        comm: &dyn Comm,
        k: &DistMatrix,
        local: &dyn LocalSolver,
        points: Option<&[[f64; 3]]>,
        mode: CoarseMode,
    ) -> crate::Result<Self> {
        let t = Instant::now();
        let kinds = Kinds::new(comm, k);
        let layout = k.layout();
        let n_own = layout.owned_len();
        let blocks = local.local_blocks();
        let bad_points = points.is_some_and(|p| p.len() != k.node_blocks());
        if !comm.all_ok(!bad_points) {
            return Err(Error::runtime(format!(
                "coarse space: {} node coordinates for {} node blocks (here or on another rank)",
                points.map_or(0, |p| p.len()),
                k.node_blocks()
            )));
        }
        // The ring: columns of the local rows that are not global unknowns' (dense) rows.
        let mut ring_blocks: Vec<usize> = local
            .ring_couplings()
            .iter()
            .filter(|c| kinds.global_index(blocks[c.row]).is_none())
            .map(|c| c.col)
            .collect();
        ring_blocks.sort_unstable();
        ring_blocks.dedup();

        let mut keys = sharing_sets(comm, &kinds, layout, blocks, n_own, &ring_blocks);
        // A component lies in one body: bodies touching only through contact move apart.
        for (b, key) in &mut keys {
            key.push(usize::MAX - k.node_body(*b) as usize);
        }
        let mut comps_keys = all_keys(comm, &keys);
        if let Some(pts) = points {
            split_into_patches(comm, &mut keys, &comps_keys, pts);
            comps_keys = all_keys(comm, &keys);
        }
        let comp_of: Vec<(usize, usize)> = keys
            .iter()
            .map(|(b, key)| (*b, comps_keys.binary_search(key).expect("gathered")))
            .collect();
        let mut components = component_bases(comm, comps_keys.len(), &comp_of, points);
        let mut m = 0;
        for c in &mut components {
            c.first = m;
            m += c.basis.len();
        }
        let first_global = m;
        m += 3 * kinds.global.len();
        // What each ring block carries: component and coordinates from its owner.
        let ring = ring_data(comm, layout, &ring_blocks, &comp_of, points)
            .into_iter()
            .zip(&ring_blocks)
            .map(|(d, &b)| match (kinds.global_index(b), d) {
                (Some(gi), _) => RingData::Global {
                    first: first_global + 3 * gi,
                },
                (None, Some((comp, x))) => RingData::Node { comp, x },
                (None, None) => RingData::None,
            })
            .collect::<Vec<_>>();
        let mut comp_couplings: Vec<(usize, Vec<RingEntry>)> = Vec::new();
        let mut global_ring: Vec<(usize, Vec<(usize, usize)>)> = Vec::new();
        for c in local.ring_couplings() {
            if kinds.global_index(blocks[c.row]).is_some() {
                continue;
            }
            let ri = ring_blocks.binary_search(&c.col).expect("ring block");
            match ring[ri] {
                RingData::Node { comp, .. } => {
                    push_group(&mut comp_couplings, comp, (c.row, ri, c.entry))
                }
                RingData::Global { first } => push_group(&mut global_ring, first, (c.row, c.entry)),
                RingData::None => {}
            }
        }
        comp_couplings.sort_by_key(|g| g.0);
        global_ring.sort_by_key(|g| g.0);
        let global_local: Vec<(usize, usize)> = if comm.size() > 1 {
            blocks
                .iter()
                .enumerate()
                .filter_map(|(l, &b)| kinds.global_index(b).map(|gi| (l, first_global + 3 * gi)))
                .collect()
        } else {
            Vec::new()
        };

        // This rank's functions, and the columns of its rows of Φ and A Φ.
        let mut mine: Vec<usize> = Vec::new();
        for (c, _) in &comp_couplings {
            let comp = &components[*c];
            mine.extend(comp.first..comp.first + comp.basis.len());
        }
        for &(first, _) in &global_ring {
            mine.extend(first..first + 3);
        }
        for &(_, first) in &global_local {
            mine.extend(first..first + 3);
        }
        mine.sort_unstable();
        mine.dedup();
        let (cols, own, recv_cols) = exchange_columns(comm, k, &mine);
        let n_own_dofs = 3 * n_own;
        let boundary: Vec<usize> = (0..n_own)
            .filter(|&i| {
                k.diag_begin[i] > k.row_ptr[i]
                    || k.diag_end[i] < k.row_ptr[i + 1]
                    || kinds.global_index(layout.start() + i).is_some()
            })
            .collect();
        let stats = CoarseStats {
            dimension: m,
            components: components.len(),
            local_functions: mine.len(),
            columns: cols.len(),
            symbolic_seconds: t.elapsed().as_secs_f64(),
            ..Default::default()
        };
        Ok(Self {
            mode,
            n_own_dofs,
            m,
            components,
            ring,
            comp_couplings,
            global_ring,
            global_local,
            phi: vec![0.0; n_own_dofs * mine.len()],
            aphi: vec![0.0; 3 * boundary.len() * cols.len()],
            boundary,
            mine,
            cols,
            own,
            recv_cols,
            kept: Vec::new(),
            lu: None,
            stats,
            #[cfg(test)]
            a0: Vec::new(),
        })
    }

    /// Sizes and times.
    pub fn stats(&self) -> CoarseStats {
        self.stats
    }

    /// Φ's owned rows over [`Self::columns`] (row-major), from the last setup.
    pub fn phi(&self) -> &[f64] {
        &self.phi
    }

    /// The coarse functions Φ's rows are stored over (the ones this rank extends).
    pub fn columns(&self) -> &[usize] {
        &self.mine
    }

    /// Coarse dimension.
    pub fn dimension(&self) -> usize {
        self.m
    }

    /// Collective: extend the basis with the first level's current factor, form A Φ and
    /// A₀ = Φᵀ A Φ, and factor A₀. A failure (a singular A₀) is agreed on every rank.
    pub fn setup(
        &mut self,
        comm: &dyn Comm,
        k: &DistMatrix,
        local: &dyn LocalSolver,
    ) -> crate::Result<()> {
        self.lu = None;
        let t = Instant::now();
        self.extend(k, local);
        self.stats.extension_seconds = t.elapsed().as_secs_f64();
        let t = Instant::now();
        self.form_aphi(comm, k);
        let a0 = self.galerkin(comm);
        self.stats.galerkin_seconds = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let res = self.factor(a0);
        self.stats.factor_seconds = t.elapsed().as_secs_f64();
        self.stats.setups += 1;
        self.stats.total_seconds +=
            self.stats.extension_seconds + self.stats.galerkin_seconds + self.stats.factor_seconds;
        // A₀ is the same on every rank, so is the verdict; agreed all the same.
        if !comm.all_ok(res.is_ok()) {
            self.lu = None;
            return Err(res.err().unwrap_or_else(|| {
                Error::runtime("coarse space: A₀ is singular on another rank")
            }));
        }
        Ok(())
    }

    /// Φ's owned rows: one local solve per function that reaches the ring, in batches of
    /// [`BATCH`] right-hand sides.
    fn extend(&mut self, k: &DistMatrix, local: &dyn LocalSolver) {
        let nc = self.mine.len();
        let nd = self.n_own_dofs;
        let n3 = 3 * local.local_blocks().len();
        let vals = local.ring_values(k);
        self.phi.iter_mut().for_each(|v| *v = 0.0);
        let mine = &self.mine;
        let pos = |f: usize| mine.binary_search(&f).expect("own column");
        let mut batch = Batch::new(n3);
        let phi = &mut self.phi;
        let mut flush = |batch: &mut Batch| {
            local.solve_local_many(&mut batch.x, batch.ids.len());
            for (&f, x) in batch.ids.iter().zip(batch.x.chunks_exact(n3.max(1))) {
                let p = pos(f);
                for (r, v) in x[..nd].iter().enumerate() {
                    phi[r * nc + p] = *v;
                }
            }
            batch.clear();
        };
        let mut val = Vec::new();
        for (c, couplings) in &self.comp_couplings {
            let comp = &self.components[*c];
            let kc = comp.basis.len();
            if batch.ids.len() + kc > BATCH {
                flush(&mut batch);
            }
            let at = batch.ids.len();
            for j in 0..kc {
                batch.column(comp.first + j);
            }
            for &(row, ri, e) in couplings {
                let RingData::Node { x, .. } = self.ring[ri] else {
                    unreachable!("grouped by component")
                };
                comp.values(&x, &mut val);
                let a = &vals[9 * e..9 * e + 9];
                for (j, v) in val.iter().enumerate() {
                    let col = &mut batch.x[(at + j) * n3..(at + j + 1) * n3];
                    for i in 0..3 {
                        col[3 * row + i] -=
                            a[3 * i] * v[0] + a[3 * i + 1] * v[1] + a[3 * i + 2] * v[2];
                    }
                }
            }
        }
        for (first, couplings) in &self.global_ring {
            if batch.ids.len() + 3 > BATCH {
                flush(&mut batch);
            }
            for d in 0..3 {
                let col = batch.column(first + d);
                for &(row, e) in couplings {
                    let a = &vals[9 * e..9 * e + 9];
                    for i in 0..3 {
                        col[3 * row + i] -= a[3 * i + d];
                    }
                }
            }
        }
        if !batch.ids.is_empty() {
            flush(&mut batch);
        }
        // A global unknown inside the local system: Y = A_loc⁻¹ E_g, x = Y Y_g⁻¹ (the
        // local rows solved with the block prescribed to the identity).
        for &(l, first) in &self.global_local {
            let mut y = vec![0.0; 3 * n3];
            for d in 0..3 {
                y[d * n3 + 3 * l + d] = 1.0;
            }
            local.solve_local_many(&mut y, 3);
            let yg = nalgebra::Matrix3::from_fn(|i, d| y[d * n3 + 3 * l + i]);
            let Some(inv) = yg.try_inverse() else {
                continue;
            };
            for d in 0..3 {
                let p = pos(first + d);
                for r in 0..nd {
                    phi[r * nc + p] = (0..3).map(|q| y[q * n3 + r] * inv[(q, d)]).sum();
                }
            }
        }
    }

    /// A Φ on the boundary rows: Φ's rows of the ghost blocks come from their owners.
    fn form_aphi(&mut self, comm: &dyn Comm, k: &DistMatrix) {
        let nc = self.cols.len();
        let nf = self.mine.len();
        let halo = k.halo();
        let mut send = Vec::with_capacity(halo.send_indices().len() * nf);
        for &i in halo.send_indices() {
            send.extend_from_slice(&self.phi[i * nf..(i + 1) * nf]);
        }
        let sc: Vec<usize> = halo.send_counts().iter().map(|c| c * nf).collect();
        let rc: Vec<usize> = halo
            .recv_counts()
            .iter()
            .zip(&self.recv_cols)
            .map(|(c, cols)| c * cols.len())
            .collect();
        let recv = comm.alltoallv_f64(&send, &sc, &rc);
        let n_ghost = 3 * k.ghost_blocks().len();
        let mut ghost = vec![0.0; n_ghost * nc];
        let (mut t, mut at) = (0, 0);
        for (q, &count) in halo.recv_counts().iter().enumerate() {
            let cols = &self.recv_cols[q];
            for _ in 0..count {
                for &p in cols {
                    ghost[t * nc + p] = recv[at];
                    at += 1;
                }
                t += 1;
            }
        }
        let aphi = &mut self.aphi;
        aphi.iter_mut().for_each(|v| *v = 0.0);
        for (b, &i) in self.boundary.iter().enumerate() {
            for e in k.row_ptr[i]..k.row_ptr[i + 1] {
                let col = k.lcol[e] as usize;
                let diag = e >= k.diag_begin[i] && e < k.diag_end[i];
                let a = &k.vals[9 * e..9 * e + 9];
                for r in 0..3 {
                    let dst = &mut aphi[(3 * b + r) * nc..(3 * b + r + 1) * nc];
                    for s in 0..3 {
                        let v = a[3 * r + s];
                        if v == 0.0 {
                            continue;
                        }
                        if diag {
                            let src = &self.phi[(3 * col + s) * nf..(3 * col + s + 1) * nf];
                            for (&p, x) in self.own.iter().zip(src) {
                                dst[p] += v * x;
                            }
                        } else {
                            let src = &ghost[(3 * col + s) * nc..(3 * col + s + 1) * nc];
                            for (d, x) in dst.iter_mut().zip(src) {
                                *d += v * x;
                            }
                        }
                    }
                }
            }
        }
    }

    /// A₀ = Φᵀ A Φ, summed over the ranks (dense, m × m, the same on every rank): the
    /// boundary rows carry all of this rank's share.
    fn galerkin(&self, comm: &dyn Comm) -> Vec<f64> {
        let (nc, nf, m) = (self.cols.len(), self.mine.len(), self.m);
        let nb = 3 * self.boundary.len();
        let mut a0 = vec![0.0; m * m];
        if nc > 0 && nf > 0 && nb > 0 {
            let mut pb = Vec::with_capacity(nb * nf);
            for &i in &self.boundary {
                pb.extend_from_slice(&self.phi[3 * i * nf..(3 * i + 3) * nf]);
            }
            let phi = faer::MatRef::from_row_major_slice(&pb, nb, nf);
            let aphi = faer::MatRef::from_row_major_slice(&self.aphi, nb, nc);
            let local = phi.transpose() * aphi;
            for (a, &fa) in self.mine.iter().enumerate() {
                for (b, &fb) in self.cols.iter().enumerate() {
                    a0[fa * m + fb] += local[(a, b)];
                }
            }
        }
        comm.allreduce_sum(&mut a0);
        a0
    }

    /// Factor A₀ ([`factor_coarse`]).
    fn factor(&mut self, a0: Vec<f64>) -> crate::Result<()> {
        self.lu = None;
        self.kept.clear();
        self.stats.kept = 0;
        let res = factor_coarse(&a0, self.m);
        #[cfg(test)]
        {
            self.a0 = a0;
        }
        let (kept, lu) = res?;
        self.stats.kept = kept.len();
        self.kept = kept;
        self.lu = lu;
        Ok(())
    }

    /// A₀ of the last setup (m × m, row-major).
    #[cfg(test)]
    pub fn coarse_matrix(&self) -> &[f64] {
        &self.a0
    }

    /// Collective: z = Φ x₀ + first(r − A Φ x₀) (multiplicative) or z = Φ x₀ + first(r)
    /// (additive), x₀ = A₀⁻¹ Φᵀ r. Before a successful setup, the first level alone.
    pub fn apply(
        &self,
        comm: &dyn Comm,
        r: &[f64],
        z: &mut [f64],
        first: &dyn Fn(&[f64], &mut [f64]),
    ) {
        let Some(lu) = &self.lu else {
            first(r, z);
            return;
        };
        let (nc, nf, m) = (self.cols.len(), self.mine.len(), self.m);
        let mut c = vec![0.0; m];
        for (i, &ri) in r.iter().enumerate() {
            if ri != 0.0 {
                let row = &self.phi[i * nf..(i + 1) * nf];
                for (&f, v) in self.mine.iter().zip(row) {
                    c[f] += v * ri;
                }
            }
        }
        comm.allreduce_sum(&mut c);
        let mut x = faer::Col::<f64>::from_fn(self.kept.len(), |i| c[self.kept[i]]);
        lu.solve_in_place(x.as_mut());
        let mut x0 = vec![0.0; m];
        for (i, &f) in self.kept.iter().enumerate() {
            x0[f] = x[i];
        }
        let dot =
            |row: &[f64], idx: &[usize]| row.iter().zip(idx).map(|(a, &f)| a * x0[f]).sum::<f64>();
        match self.mode {
            CoarseMode::Multiplicative => {
                let mut rr = r.to_vec();
                for (b, &i) in self.boundary.iter().enumerate() {
                    for a in 0..3 {
                        let row = &self.aphi[(3 * b + a) * nc..(3 * b + a + 1) * nc];
                        rr[3 * i + a] -= dot(row, &self.cols);
                    }
                }
                first(&rr, z);
            }
            CoarseMode::Additive => first(r, z),
        }
        for (i, zi) in z.iter_mut().enumerate() {
            *zi += dot(&self.phi[i * nf..(i + 1) * nf], &self.mine);
        }
    }
}

/// The LU of the dense coarse matrix `a0` (m × m, row-major) over the functions it keeps:
/// those whose diagonal is not zero (a component whose ring nodes are all clamped), and
/// of those, if A₀ is singular there, the largest well-conditioned set a fully pivoted
/// LU finds. A₀ can be singular where A is not: a body held only through contact
/// multipliers has rigid modes whose displacement-only energy is zero (two-body-hertz
/// before its first contact); the coarse correction then leaves them to the first level.
pub fn factor_coarse(
    a0: &[f64],
    m: usize,
) -> crate::Result<(Vec<usize>, Option<faer::linalg::solvers::PartialPivLu<f64>>)> {
    let dmax = (0..m).map(|f| a0[f * m + f].abs()).fold(0.0, f64::max);
    let mut kept: Vec<usize> = (0..m)
        .filter(|&f| a0[f * m + f].abs() > 1e-12 * dmax)
        .collect();
    if kept.is_empty() {
        return Ok((kept, None));
    }
    let sub = |kept: &[usize]| {
        faer::Mat::<f64>::from_fn(kept.len(), kept.len(), |i, j| a0[kept[i] * m + kept[j]])
    };
    let well_conditioned = |lu: &faer::linalg::solvers::PartialPivLu<f64>| {
        let u = lu.U();
        let (lo, hi) = (0..u.nrows())
            .map(|i| u[(i, i)].abs())
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            });
        lo > 1e-12 * hi
    };
    let lu = sub(&kept).partial_piv_lu();
    if well_conditioned(&lu) {
        return Ok((kept, Some(lu)));
    }
    let full = sub(&kept).full_piv_lu();
    let u = full.U();
    let top = u[(0, 0)].abs();
    let r = (0..u.nrows())
        .take_while(|&i| u[(i, i)].abs() > 1e-10 * top)
        .count();
    let (fwd, _) = full.Q().arrays();
    let mut sel: Vec<usize> = fwd[..r].iter().map(|&q| kept[q]).collect();
    sel.sort_unstable();
    kept = sel;
    let lu = sub(&kept).partial_piv_lu();
    if kept.is_empty() || !well_conditioned(&lu) {
        return Err(Error::runtime(format!(
            "coarse space: the {m}×{m} coarse matrix has no well-conditioned part ({r} pivots \
             above 1e-10 of the largest)"
        )));
    }
    Ok((kept, Some(lu)))
}

/// Right-hand sides solved together in one pass through the local factor.
const BATCH: usize = 24;

/// A batch of extension right-hand sides (columns of a local vector's length) and the
/// coarse functions they belong to.
struct Batch {
    n: usize,
    x: Vec<f64>,
    ids: Vec<usize>,
}

impl Batch {
    fn new(n: usize) -> Self {
        Self {
            n,
            x: Vec::new(),
            ids: Vec::new(),
        }
    }
    /// A new zero column for function `f`.
    fn column(&mut self, f: usize) -> &mut [f64] {
        self.ids.push(f);
        let at = self.x.len();
        self.x.resize(at + self.n, 0.0);
        &mut self.x[at..]
    }
    fn clear(&mut self) {
        self.x.clear();
        self.ids.clear();
    }
}

fn push_group<T>(groups: &mut Vec<(usize, Vec<T>)>, key: usize, item: T) {
    match groups.iter_mut().find(|g| g.0 == key) {
        Some(g) => g.1.push(item),
        None => groups.push((key, vec![item])),
    }
}

/// Collective: the sharing set of every owned node block that lies in some rank's ring
/// (its owner, and every rank whose local system or ring holds it), as (owned block
/// index, sorted ranks).
fn sharing_sets(
    comm: &dyn Comm,
    kinds: &Kinds,
    layout: &Layout,
    blocks: &[usize],
    n_own: usize,
    ring: &[usize],
) -> Vec<(usize, Vec<usize>)> {
    let p = comm.size();
    let start = layout.start();
    // Tell the owners: 2b + 1 for a ring block, 2b for one of the local system.
    let mut msgs: Vec<(usize, u64)> = blocks[n_own..]
        .iter()
        .filter(|&&b| kinds.is_node(b))
        .map(|&b| (kinds.owner(b), 2 * b as u64))
        .chain(
            ring.iter()
                .filter(|&&b| kinds.is_node(b))
                .map(|&b| (kinds.owner(b), 2 * b as u64 + 1)),
        )
        .collect();
    msgs.sort_unstable();
    let mut counts = vec![0usize; p];
    for &(q, _) in &msgs {
        counts[q] += 1;
    }
    let send: Vec<u64> = msgs.iter().map(|m| m.1).collect();
    let rc = comm.alltoall_counts(&counts);
    let recv = comm.alltoallv_u64(&send, &counts, &rc);
    // (owned block, holder rank, in its ring), grouped by block.
    let mut held: Vec<(usize, usize, bool)> = Vec::with_capacity(recv.len());
    let mut at = 0;
    for (src, &c) in rc.iter().enumerate() {
        for &v in &recv[at..at + c] {
            held.push(((v / 2) as usize - start, src, v % 2 == 1));
        }
        at += c;
    }
    held.sort_unstable();
    let me = comm.rank();
    let mut out = Vec::new();
    for group in held.chunk_by(|a, b| a.0 == b.0) {
        if !group.iter().any(|h| h.2) {
            continue;
        }
        let mut key: Vec<usize> = group.iter().map(|h| h.1).collect();
        key.push(me);
        key.sort_unstable();
        key.dedup();
        out.push((group[0].0, key));
    }
    out
}

/// Collective: split every component into patches no longer than the subdomains that
/// share it are thick: the cells of a grid over its bounding box whose side is the
/// smallest of those ranks' sizes (the cube root of the volume of the bounding box of
/// their owned nodes). A long interface between long subdomains (a beam cut along its
/// length) then carries rigid modes patch by patch, enough to represent the bending that
/// one set of rigid modes for the whole interface cannot (coupled-cantilever on 2 ranks:
/// 444 GMRES iterations with one patch, 207 with eight); blocky subdomains keep one patch
/// per component. The cell goes into each node's key.
fn split_into_patches(
    comm: &dyn Comm,
    keys: &mut [(usize, Vec<usize>)],
    comps: &[Vec<usize>],
    points: &[[f64; 3]],
) {
    let p = comm.size();
    // Each rank's size, from the bounding box of its owned nodes.
    let mut bb = vec![f64::NEG_INFINITY; 6 * p];
    let me = comm.rank();
    for x in points {
        for d in 0..3 {
            bb[6 * me + d] = bb[6 * me + d].max(-x[d]);
            bb[6 * me + 3 + d] = bb[6 * me + 3 + d].max(x[d]);
        }
    }
    comm.allreduce_max(&mut bb);
    let size: Vec<f64> = (0..p)
        .map(|r| {
            let v: f64 = (0..3)
                .map(|d| (bb[6 * r + 3 + d] + bb[6 * r + d]).max(0.0))
                .product();
            v.cbrt()
        })
        .collect();
    let nc = comps.len();
    let mut lo = vec![f64::NEG_INFINITY; 3 * nc];
    let mut hi = vec![f64::NEG_INFINITY; 3 * nc];
    let comp: Vec<usize> = keys
        .iter()
        .map(|(_, k)| comps.binary_search(k).expect("gathered"))
        .collect();
    for ((b, _), &c) in keys.iter().zip(&comp) {
        for d in 0..3 {
            lo[3 * c + d] = lo[3 * c + d].max(-points[*b][d]);
            hi[3 * c + d] = hi[3 * c + d].max(points[*b][d]);
        }
    }
    comm.allreduce_max(&mut lo);
    comm.allreduce_max(&mut hi);
    for ((b, key), &c) in keys.iter_mut().zip(&comp) {
        // The sharing ranks come first in the key (the body marker after them is large).
        let cell = key
            .iter()
            .filter(|&&r| r < p)
            .map(|&r| size[r])
            .fold(f64::INFINITY, f64::min);
        let mut cells = [0usize; 3];
        for d in 0..3 {
            let ext = hi[3 * c + d] + lo[3 * c + d];
            if cell.is_finite() && cell > 0.0 && ext > cell {
                let n = (ext / cell).ceil();
                let i = ((points[*b][d] + lo[3 * c + d]) / ext * n).floor();
                cells[d] = (i.max(0.0) as usize).min(n as usize - 1);
            }
        }
        key.extend_from_slice(&cells);
    }
}

/// Collective: every rank's distinct keys, gathered, sorted and deduplicated (the
/// components, in the same order on every rank).
fn all_keys(comm: &dyn Comm, keys: &[(usize, Vec<usize>)]) -> Vec<Vec<usize>> {
    let mine: BTreeSet<&Vec<usize>> = keys.iter().map(|k| &k.1).collect();
    let mut buf: Vec<u64> = Vec::new();
    for k in mine {
        buf.push(k.len() as u64);
        buf.extend(k.iter().map(|&r| r as u64));
    }
    let p = comm.size();
    let send: Vec<u64> = (0..p).flat_map(|_| buf.iter().copied()).collect();
    let sc = vec![buf.len(); p];
    let rc = comm.alltoall_counts(&sc);
    let recv = comm.alltoallv_u64(&send, &sc, &rc);
    let mut all: BTreeSet<Vec<usize>> = BTreeSet::new();
    let mut i = 0;
    while i < recv.len() {
        let n = recv[i] as usize;
        all.insert(recv[i + 1..i + 1 + n].iter().map(|&r| r as usize).collect());
        i += 1 + n;
    }
    all.into_iter().collect()
}

/// Collective: each component's centroid, radius and orthonormalized modes, from the
/// owned nodes of each (`comp_of`: owned block index, component).
fn component_bases(
    comm: &dyn Comm,
    n_comp: usize,
    comp_of: &[(usize, usize)],
    points: Option<&[[f64; 3]]>,
) -> Vec<Component> {
    let Some(points) = points else {
        let basis: Vec<[f64; 6]> = (0..3)
            .map(|d| std::array::from_fn(|q| if q == d { 1.0 } else { 0.0 }))
            .collect();
        return vec![
            Component {
                centroid: [0.0; 3],
                scale: 1.0,
                basis,
                first: 0,
            };
            n_comp
        ];
    };
    let mut sums = vec![0.0; 4 * n_comp];
    for &(b, c) in comp_of {
        let x = points[b];
        sums[4 * c] += 1.0;
        for d in 0..3 {
            sums[4 * c + 1 + d] += x[d];
        }
    }
    comm.allreduce_sum(&mut sums);
    let centroid = |c: usize| -> [f64; 3] {
        let n = sums[4 * c].max(1.0);
        std::array::from_fn(|d| sums[4 * c + 1 + d] / n)
    };
    let mut radius = vec![0.0; n_comp];
    for &(b, c) in comp_of {
        let (x, o) = (points[b], centroid(c));
        let d2: f64 = (0..3).map(|d| (x[d] - o[d]).powi(2)).sum();
        radius[c] = f64::max(radius[c], d2.sqrt());
    }
    comm.allreduce_max(&mut radius);
    let mut gram = vec![0.0; 36 * n_comp];
    for &(b, c) in comp_of {
        let r = modes(&points[b], &centroid(c), radius[c].max(f64::MIN_POSITIVE));
        for i in 0..6 {
            for j in 0..6 {
                gram[36 * c + 6 * i + j] += (0..3).map(|a| r[a][i] * r[a][j]).sum::<f64>();
            }
        }
    }
    comm.allreduce_sum(&mut gram);
    (0..n_comp)
        .map(|c| {
            let g = nalgebra::Matrix6::from_row_slice(&gram[36 * c..36 * c + 36]);
            let eig = g.symmetric_eigen();
            let lmax = eig.eigenvalues.iter().cloned().fold(0.0, f64::max);
            let mut order: Vec<usize> = (0..6).collect();
            order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
            let basis = order
                .into_iter()
                .filter(|&i| eig.eigenvalues[i] > 1e-8 * lmax)
                .map(|i| {
                    let s = eig.eigenvalues[i].sqrt();
                    std::array::from_fn(|q| eig.eigenvectors[(q, i)] / s)
                })
                .collect();
            Component {
                centroid: centroid(c),
                scale: radius[c].max(f64::MIN_POSITIVE),
                basis,
                first: 0,
            }
        })
        .collect()
}

/// Collective: for every ring block, its component and coordinates from its owner (None
/// for a block in no component).
fn ring_data(
    comm: &dyn Comm,
    layout: &Layout,
    ring: &[usize],
    comp_of: &[(usize, usize)],
    points: Option<&[[f64; 3]]>,
) -> Vec<Option<(usize, [f64; 3])>> {
    // Four values per block: the component + 1 (0: none) and the coordinates.
    let counts: Vec<usize> = (0..layout.size())
        .map(|q| 4 * (layout.starts[q + 1] - layout.starts[q]))
        .collect();
    let wide = Layout::from_counts(&counts, layout.rank);
    let mut own = vec![0.0; 4 * layout.owned_len()];
    for &(b, c) in comp_of {
        own[4 * b] = (c + 1) as f64;
        if let Some(p) = points {
            own[4 * b + 1..4 * b + 4].copy_from_slice(&p[b]);
        }
    }
    let ghosts: Vec<usize> = ring.iter().flat_map(|&b| 4 * b..4 * b + 4).collect();
    let plan = HaloPlan::new(comm, &wide, ghosts);
    let mut got = vec![0.0; 4 * ring.len()];
    plan.forward(comm, &own, &mut got);
    got.chunks_exact(4)
        .map(|v| (v[0] > 0.0).then(|| (v[0] as usize - 1, [v[1], v[2], v[3]])))
        .collect()
}

/// Collective: the columns of this rank's Φ and A Φ rows (its own functions `mine` and
/// those of every rank it receives ghost rows from), the positions of its own in them,
/// and per sending rank the positions of that rank's functions.
fn exchange_columns(
    comm: &dyn Comm,
    k: &DistMatrix,
    mine: &[usize],
) -> (Vec<usize>, Vec<usize>, Vec<Vec<usize>>) {
    let halo = k.halo();
    let p = comm.size();
    let to: Vec<bool> = halo.send_counts().iter().map(|&c| c > 0).collect();
    let send: Vec<u64> = (0..p)
        .filter(|&q| to[q])
        .flat_map(|_| mine.iter().map(|&f| f as u64))
        .collect();
    let sc: Vec<usize> = to.iter().map(|&t| if t { mine.len() } else { 0 }).collect();
    let rc = comm.alltoall_counts(&sc);
    let recv = comm.alltoallv_u64(&send, &sc, &rc);
    let mut lists: Vec<Vec<usize>> = Vec::with_capacity(p);
    let mut at = 0;
    for &c in &rc {
        lists.push(recv[at..at + c].iter().map(|&f| f as usize).collect());
        at += c;
    }
    let mut cols: Vec<usize> = mine.to_vec();
    for l in &lists {
        cols.extend_from_slice(l);
    }
    cols.sort_unstable();
    cols.dedup();
    let pos = |f: &usize| cols.binary_search(f).expect("column");
    let own = mine.iter().map(pos).collect();
    // Only ranks that send ghost rows matter; a list from a rank that sends none is
    // dropped (its functions do not reach our rows).
    let recv_cols = lists
        .iter()
        .enumerate()
        .map(|(q, l)| {
            if halo.recv_counts()[q] > 0 {
                l.iter().map(pos).collect()
            } else {
                Vec::new()
            }
        })
        .collect();
    (cols, own, recv_cols)
}
