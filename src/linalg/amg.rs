//! Algebraic multigrid: hypre's BoomerAMG on the condensed displacement matrix (issue
//! 12's scalable preconditioner).
//!
//! Block Jacobi factors a rank's whole diagonal block: its cost grows faster than the
//! mesh, and its GMRES iterations grow with the rank count because the blocks do not
//! talk. One AMG V-cycle costs O(unknowns) and its coarse levels couple the ranks, so the
//! iteration count stays nearly flat in the rank count and the mesh size for compressible
//! solids (hertz-sphere at 312k unknowns: 42 GMRES iterations per Newton iteration on 2
//! ranks, 44 on 16). The default is unknown-based systems AMG (three functions per node);
//! with node coordinates it adds the rigid-body rotations as near-null space, nodal
//! coarsening and GM-2 interpolation (Baker, Kolev, Yang, *Numer. Linear Algebra Appl.* 17,
//! 2010; MFEM's `SetElasticityOptions`), which measured slower on every scene tried.
//!
//! AMG needs an elliptic matrix, not a saddle point: the attached multiplier blocks of
//! ALM walls are first eliminated node by node ([`super::condense`], always on here), and
//! a matrix that still has a non-positive diagonal after that (a sliding frictional node,
//! a coupling's multipliers) is refused with an error naming the row, on every rank
//! together, so that the step is retried or the analyst picks block Jacobi or ASM. Each
//! setup builds hypre's ParCSR matrix of the kept rows (hypre numbers them
//! rank-contiguously, as alfe does) and a new hierarchy.

use super::block_jacobi::diagonal_pattern;
use super::condense::Condensation;
use super::hypre::{big, Amg, HYPRE_BigInt, HYPRE_Int, IjMatrix, IjVector};
use super::{DistMatrix, Preconditioner};
use crate::parallel::Comm;
use crate::Error;
use std::cell::RefCell;
use std::sync::Arc;

/// The relative regularization δ of the condensed multiplier blocks for AMG
/// ([`Condensation::reduce`]). A factorization takes δ = 10⁻⁶, which makes each active
/// contact direction a spring 10⁶ times the node's stiffness; pointwise smoothing and
/// unknown-based coarsening cannot handle such a spring when it is not aligned with an
/// axis (a sphere's normal), and GMRES stalled (steps retried). A soft spring costs a few
/// GMRES iterations instead. `hertz-sphere`, first step, 1 rank, GMRES iterations over 4
/// Newton iterations: δ = 10⁻⁶ stalls, 10⁻³: 204, 10⁻²: 128, **10⁻¹: 109**, 0.3: 107,
/// 1: 104 (penalty contact with the same AMG: 75 over 3).
pub const AMG_REGULARIZATION: f64 = 0.1;

/// Reference coordinates of the nodes whose displacements are the first owned blocks
/// (an owned vector's first `3 · len` unknowns): what the rigid-body modes are made of.
pub type NodePoints = Arc<Vec<[f64; 3]>>;

/// BoomerAMG preconditioner; see the module documentation.
pub struct BoomerAmg {
    points: Option<NodePoints>,
    state: Option<State>,
}

/// What one setup built. Field order is drop order: the hierarchy goes before the
/// matrix and vectors it points to.
struct State {
    amg: Amg,
    a: IjMatrix,
    b: IjVector,
    x: IjVector,
    cond: Option<Condensation>,
    n_full: usize,
    work: RefCell<(Vec<f64>, Vec<f64>)>,
}

impl BoomerAmg {
    /// A preconditioner to be set up on a matrix. With `points`, the rigid-body rotations
    /// are its near-null space (GM-2 interpolation, nodal coarsening); without, it is
    /// unknown-based systems AMG, which measured faster on every scene tried (README,
    /// "Linear solves").
    pub fn new(points: Option<NodePoints>) -> Self {
        Self {
            points,
            state: None,
        }
    }

    fn build(&self, comm: &dyn Comm, k: &DistMatrix) -> Result<State, String> {
        let raw = comm.raw_mpi().ok_or(
            "AMG (hypre BoomerAMG) needs an MPI communicator; use two-level, asm or block-jacobi here",
        )?;
        let n_own = k.layout().owned_len();
        let pat = diagonal_pattern(k);
        let mut cond = Condensation::find(&pat);
        let reduced = match cond.as_mut() {
            Some(c) => c.reduce(&k.vals, AMG_REGULARIZATION),
            None => Ok(()),
        };
        // Every local failure is agreed on before the next collective (no rank may be
        // left waiting in hypre's or alfe's collectives for one that returned).
        if !comm.all_ok(reduced.is_ok()) {
            return Err(reduced
                .err()
                .unwrap_or_else(|| "the condensation failed on another rank".into()));
        }
        // Kept blocks (reduced numbering) and hypre's block number of every owned block.
        let kept: Vec<usize> = match &cond {
            Some(c) => c.kept().to_vec(),
            None => (0..n_own).collect(),
        };
        let (first, _) = comm.exclusive_scan(kept.len() as u64);
        let first = first as usize;
        let mut gid = vec![-1.0; 3 * n_own];
        for (r, &i) in kept.iter().enumerate() {
            gid[3 * i..3 * i + 3].fill((first + r) as f64);
        }
        let mut ghost_gid = vec![0.0; 3 * k.ghost_blocks().len()];
        k.halo().forward(comm, &gid, &mut ghost_gid);

        // The kept rows in scalar CSR with hypre's global columns.
        let n = 3 * kept.len();
        let csr = (|| -> Result<_, String> {
            let mut ptr = Vec::with_capacity(n + 1);
            let mut cols: Vec<HYPRE_BigInt> = Vec::new();
            let mut vals = Vec::new();
            let mut diag: Vec<HYPRE_Int> = Vec::with_capacity(n);
            ptr.push(0);
            let red = cond.as_ref().map(|c| (c.reduced(), c.values()));
            for (r, &i) in kept.iter().enumerate() {
                for a in 0..3 {
                    let row = 3 * (first + r) + a;
                    let mut d = 0.0;
                    // Owned columns: the (condensed) diagonal block.
                    let mut push_owned = |col_red: usize, blk: &[f64]| -> Result<(), String> {
                        for b in 0..3 {
                            let c = 3 * (first + col_red) + b;
                            if c == row {
                                d = blk[3 * a + b];
                            }
                            cols.push(big(c)?);
                            vals.push(blk[3 * a + b]);
                        }
                        Ok(())
                    };
                    match red {
                        Some((rp, rv)) => {
                            for q in rp.row_ptr[r]..rp.row_ptr[r + 1] {
                                let e = rp.entries[q];
                                push_owned(rp.cols[q], &rv[9 * e..9 * e + 9])?;
                            }
                        }
                        None => {
                            for e in k.diag_begin[i]..k.diag_end[i] {
                                push_owned(k.lcol[e] as usize, &k.vals[9 * e..9 * e + 9])?;
                            }
                        }
                    }
                    diag.push((cols.len() - ptr[ptr.len() - 1]) as HYPRE_Int);
                    // Columns owned elsewhere.
                    let outer =
                        (k.row_ptr[i]..k.diag_begin[i]).chain(k.diag_end[i]..k.row_ptr[i + 1]);
                    for e in outer {
                        let g = ghost_gid[3 * k.lcol[e] as usize];
                        if g < 0.0 {
                            continue;
                        }
                        for b in 0..3 {
                            cols.push(big(3 * g as usize + b)?);
                            vals.push(k.vals[9 * e + 3 * a + b]);
                        }
                    }
                    ptr.push(cols.len());
                    if d.is_nan() || d <= 0.0 {
                        let global = k.layout().start() + i;
                        return Err(format!(
                            "AMG needs a positive diagonal, but unknown {a} of block {global} \
                         has {d:e} after the contact multipliers are condensed (a sliding \
                         frictional node, or multipliers that cannot be condensed); \
                         two-level, asm and block-jacobi take any matrix"
                        ));
                    }
                }
            }
            Ok((ptr, cols, vals, diag))
        })();
        if !comm.all_ok(csr.is_ok()) {
            return Err(csr
                .err()
                .unwrap_or_else(|| "AMG refused the matrix on another rank".into()));
        }
        let (ptr, cols, vals, diag) = csr?;
        let a = IjMatrix::new(raw, 3 * first, &ptr, &cols, &vals, &diag)?;
        let b = IjVector::new(raw, 3 * first, 3 * first + n, None)?;
        let x = IjVector::new(raw, 3 * first, 3 * first + n, None)?;
        // Rotations about the axes (MFEM's RecomputeRBMs): z × X, x × X, y × X.
        let mut rbms = Vec::new();
        if let Some(p) = &self.points {
            let mut v = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
            for (r, &i) in kept.iter().enumerate() {
                if let Some(&[x0, y0, z0]) = p.get(i) {
                    v[0][3 * r..3 * r + 3].copy_from_slice(&[y0, -x0, 0.0]);
                    v[1][3 * r..3 * r + 3].copy_from_slice(&[0.0, z0, -y0]);
                    v[2][3 * r..3 * r + 3].copy_from_slice(&[-z0, 0.0, x0]);
                }
            }
            for vi in &v {
                rbms.push(IjVector::new(raw, 3 * first, 3 * first + n, Some(vi))?);
            }
        }
        let amg = Amg::setup(&a, &b, &x, rbms)?;
        Ok(State {
            amg,
            a,
            b,
            x,
            cond,
            n_full: 3 * n_own,
            work: RefCell::new((Vec::with_capacity(n), vec![0.0; n])),
        })
    }
}

impl Preconditioner for BoomerAmg {
    fn setup(&mut self, comm: &dyn Comm, k: &DistMatrix) -> crate::Result<()> {
        self.state = None;
        let s = self.build(comm, k).map_err(Error::runtime)?;
        self.state = Some(s);
        Ok(())
    }

    fn apply(&self, _comm: &dyn Comm, r: &[f64], z: &mut [f64]) {
        let Some(s) = &self.state else {
            z.copy_from_slice(r);
            return;
        };
        debug_assert_eq!(r.len(), s.n_full);
        let mut w = s.work.borrow_mut();
        let (rhs, sol) = &mut *w;
        match &s.cond {
            Some(c) => c.rhs(r, rhs),
            None => {
                rhs.clear();
                rhs.extend_from_slice(r);
            }
        }
        sol.iter_mut().for_each(|v| *v = 0.0);
        // Local writes and reads of owned entries cannot fail for vectors built here.
        let ok = s.b.set(rhs).and_then(|_| s.x.set(sol)).is_ok();
        debug_assert!(ok);
        s.amg.solve(&s.a, &s.b, &s.x);
        let ok = s.x.get(sol).is_ok();
        debug_assert!(ok);
        match &s.cond {
            Some(c) => {
                z.copy_from_slice(r);
                c.recover(sol, z);
            }
            None => z.copy_from_slice(sol),
        }
    }
}
