//! Two-level Schwarz: the first level is the rank's factored local system (block
//! Jacobi's owned block or RAS's overlapping subdomain, of the lagged stiffness: the
//! user's design), the second a coarse space of interface rigid-body modes extended with
//! that same factor ([`super::coarse`]). Both are set up together, so a lagged
//! preconditioner lags its coarse space with its factors.
//!
//! On one rank there is no interface and it is the first level alone (the direct solve).

use super::block_jacobi::FactorOptions;
use super::coarse::{CoarseMode, CoarseSpace, CoarseStats, LocalSolver};
use super::{DistMatrix, NodePoints, Preconditioner};
use crate::parallel::Comm;

/// A first level that a two-level preconditioner can be built on.
pub trait FirstLevel: Preconditioner + LocalSolver + Sized {
    /// Collective: factor `k` (symbolic and numeric).
    fn build(comm: &dyn Comm, k: &DistMatrix, opts: FactorOptions) -> crate::Result<Self>;
}

impl FirstLevel for super::BlockJacobi {
    fn build(_comm: &dyn Comm, k: &DistMatrix, opts: FactorOptions) -> crate::Result<Self> {
        Self::with_factor_options(k, opts)
    }
}

impl FirstLevel for super::RestrictedSchwarz {
    fn build(comm: &dyn Comm, k: &DistMatrix, opts: FactorOptions) -> crate::Result<Self> {
        Self::with_factor_options(comm, k, opts)
    }
}

/// The first level and its coarse space; see the module documentation.
pub struct TwoLevel<L> {
    first: L,
    coarse: CoarseSpace,
}

impl<L: FirstLevel> TwoLevel<L> {
    /// Collective: factor `k`, build the coarse space on the factor and set it up.
    pub fn new(
        comm: &dyn Comm,
        k: &DistMatrix,
        opts: FactorOptions,
        points: Option<&[[f64; 3]]>,
        mode: CoarseMode,
    ) -> crate::Result<Self> {
        let first = L::build(comm, k, opts);
        if !comm.all_ok(first.is_ok()) {
            return Err(first.err().unwrap_or_else(|| {
                crate::Error::runtime("the first level failed on another rank")
            }));
        }
        let first = first?;
        let mut coarse = CoarseSpace::new(comm, k, &first, points, mode)?;
        coarse.setup(comm, k, &first)?;
        Ok(Self { first, coarse })
    }

    /// The coarse space's sizes and times.
    pub fn coarse_stats(&self) -> CoarseStats {
        self.coarse.stats()
    }

    /// The coarse space.
    pub fn coarse(&self) -> &CoarseSpace {
        &self.coarse
    }

    /// The first level.
    pub fn first(&self) -> &L {
        &self.first
    }
}

impl<L: FirstLevel> Preconditioner for TwoLevel<L> {
    fn coarse_stats(&self) -> Option<CoarseStats> {
        Some(self.coarse.stats())
    }
    fn setup(&mut self, comm: &dyn Comm, k: &DistMatrix) -> crate::Result<()> {
        let res = self.first.setup(comm, k);
        if !comm.all_ok(res.is_ok()) {
            return Err(res.err().unwrap_or_else(|| {
                crate::Error::runtime("the first level failed on another rank")
            }));
        }
        self.coarse.setup(comm, k, &self.first)
    }
    fn apply(&self, comm: &dyn Comm, r: &[f64], z: &mut [f64]) {
        self.coarse.apply(comm, r, z, &|r: &[f64], z: &mut [f64]| {
            self.first.apply(comm, r, z)
        });
    }
}

/// Built at the first setup (with its node coordinates), set up again at the next ones.
pub(super) struct TwoLevelOnFirstSetup<L> {
    pub built: Option<TwoLevel<L>>,
    pub opts: FactorOptions,
    pub points: Option<NodePoints>,
    pub mode: CoarseMode,
}

impl<L: FirstLevel> Preconditioner for TwoLevelOnFirstSetup<L> {
    fn coarse_stats(&self) -> Option<CoarseStats> {
        self.built.as_ref().map(|p| p.coarse_stats())
    }
    fn setup(&mut self, comm: &dyn Comm, k: &DistMatrix) -> crate::Result<()> {
        match &mut self.built {
            Some(p) => p.setup(comm, k),
            None => {
                let points = self.points.as_deref().map(|p| p.as_slice());
                self.built = Some(TwoLevel::new(comm, k, self.opts, points, self.mode)?);
                Ok(())
            }
        }
    }
    fn apply(&self, comm: &dyn Comm, r: &[f64], z: &mut [f64]) {
        match &self.built {
            Some(p) => p.apply(comm, r, z),
            None => z.copy_from_slice(r),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::block_jacobi::tests::{elasticity_cube, hex8_stiffness};
    use crate::linalg::coarse::factor_coarse;
    use crate::linalg::{gmres, BlockJacobi, GmresOptions, RestrictedSchwarz};
    use crate::parallel::{run_ranks, Comm, Layout};

    fn split(n: usize, p: usize) -> Vec<usize> {
        (0..p).map(|r| n * (r + 1) / p - n * r / p).collect()
    }

    /// The cube's node coordinates owned by this rank (nodes numbered x fastest).
    fn cube_points(ne: usize, k: &DistMatrix) -> Vec<[f64; 3]> {
        let nn = ne + 1;
        let h = 1.0 / ne as f64;
        (k.layout().start()..k.layout().start() + k.node_blocks())
            .map(|g| {
                let (i, j, l) = (g % nn, (g / nn) % nn, g / (nn * nn));
                [i as f64 * h, j as f64 * h, l as f64 * h]
            })
            .collect()
    }

    /// A unit cube of ne³ hex8 cells, clamped at z = 0, split into boxes (`parts` along x,
    /// y, z): elements by box, a node to the lowest box that touches it, nodes numbered
    /// box by box. Returns the matrix and this rank's node coordinates.
    fn elasticity_boxes(c: &dyn Comm, ne: usize, parts: [usize; 3]) -> (DistMatrix, Vec<[f64; 3]>) {
        let nn = ne + 1;
        let part_of = |e: [usize; 3]| -> usize {
            let b: Vec<usize> = (0..3).map(|d| e[d] * parts[d] / ne).collect();
            b[0] + parts[0] * (b[1] + parts[1] * b[2])
        };
        let mut owner = vec![usize::MAX; nn * nn * nn];
        let node = |i: usize, j: usize, k: usize| i + nn * (j + nn * k);
        let mut els = Vec::new();
        for k in 0..ne {
            for j in 0..ne {
                for i in 0..ne {
                    let p = part_of([i, j, k]);
                    let el = [
                        node(i, j, k),
                        node(i + 1, j, k),
                        node(i + 1, j + 1, k),
                        node(i, j + 1, k),
                        node(i, j, k + 1),
                        node(i + 1, j, k + 1),
                        node(i + 1, j + 1, k + 1),
                        node(i, j + 1, k + 1),
                    ];
                    for &a in &el {
                        owner[a] = owner[a].min(p);
                    }
                    els.push((p, el));
                }
            }
        }
        let np = parts.iter().product::<usize>();
        let mut order: Vec<usize> = (0..owner.len()).collect();
        order.sort_by_key(|&a| (owner[a], a));
        let mut new_id = vec![0; owner.len()];
        for (n, &a) in order.iter().enumerate() {
            new_id[a] = n;
        }
        let counts: Vec<usize> = (0..np)
            .map(|p| owner.iter().filter(|&&o| o == p).count())
            .collect();
        let layout = Layout::from_counts(&counts, c.rank());
        let mine: Vec<[usize; 8]> = els
            .iter()
            .filter(|(p, _)| *p == c.rank())
            .map(|(_, el)| el.map(|a| new_id[a]))
            .collect();
        let pairs: Vec<(usize, usize)> = mine
            .iter()
            .flat_map(|el| el.iter().flat_map(|&a| el.iter().map(move |&b| (a, b))))
            .collect();
        let mut m = DistMatrix::new(c, layout.clone(), &pairs);
        let ke = hex8_stiffness(1.0 / ne as f64, 1.0, 0.3);
        for el in &mine {
            m.add_element(el, &ke);
        }
        m.finish_assembly(c);
        let h = 1.0 / ne as f64;
        let pts: Vec<[f64; 3]> = order[layout.start()..layout.end()]
            .iter()
            .map(|&a| {
                [
                    (a % nn) as f64 * h,
                    ((a / nn) % nn) as f64 * h,
                    (a / (nn * nn)) as f64 * h,
                ]
            })
            .collect();
        let clamped: Vec<usize> = pts
            .iter()
            .enumerate()
            .filter(|(_, x)| x[2] == 0.0)
            .flat_map(|(i, _)| (0..3).map(move |d| 3 * i + d))
            .collect();
        m.constrain(c, &clamped);
        (m, pts)
    }

    fn load(n: usize) -> Vec<f64> {
        (0..n)
            .map(|i| if i % 3 == 2 { -1.0 } else { 0.1 })
            .collect()
    }

    fn opts() -> GmresOptions {
        GmresOptions {
            rtol: 1e-8,
            ..Default::default()
        }
    }

    /// The null-space property GDSW's bound rests on: on every rank whose local system
    /// sees no clamped node, the rigid-body modes are combinations of Φ's columns there,
    /// for both first levels and overlaps of 1 and 2 layers.
    #[test]
    fn rigid_body_modes_lie_in_the_coarse_space() {
        let ne = 8;
        let nn = ne + 1;
        let nb = nn * nn * nn;
        for (p, overlap) in [(2usize, 1usize), (3, 1), (2, 2)] {
            for bj in [false, true] {
                run_ranks(p, |c| {
                    let m = elasticity_cube(c, ne, &split(nb, p));
                    let pts = cube_points(ne, &m);
                    let fo = FactorOptions {
                        overlap,
                        ..FactorOptions::default()
                    };
                    let (cs, local): (&CoarseSpace, Vec<usize>);
                    let tl_ras;
                    let tl_bj;
                    if bj {
                        tl_bj = TwoLevel::<BlockJacobi>::new(
                            c,
                            &m,
                            fo,
                            Some(&pts),
                            CoarseMode::Multiplicative,
                        )
                        .unwrap();
                        cs = tl_bj.coarse();
                        local = tl_bj.first().local_blocks().to_vec();
                    } else {
                        tl_ras = TwoLevel::<RestrictedSchwarz>::new(
                            c,
                            &m,
                            fo,
                            Some(&pts),
                            CoarseMode::Multiplicative,
                        )
                        .unwrap();
                        cs = tl_ras.coarse();
                        local = tl_ras.first().local_blocks().to_vec();
                    }
                    // A clamped node (z = 0) in the local system or next to it.
                    if local.iter().any(|&g| g < 2 * nn * nn) {
                        return;
                    }
                    let n = m.n_owned_dofs();
                    let nc = cs.columns().len();
                    assert!(nc >= 6, "rank {}: {nc} functions", c.rank());
                    let phi = nalgebra::DMatrix::from_row_slice(n, nc, cs.phi());
                    let svd = phi.clone().svd(true, true);
                    for k in 0..6 {
                        let r = nalgebra::DVector::from_fn(n, |i, _| {
                            let x = pts[i / 3];
                            let rows = [
                                [1.0, 0.0, 0.0, 0.0, x[2], -x[1]],
                                [0.0, 1.0, 0.0, -x[2], 0.0, x[0]],
                                [0.0, 0.0, 1.0, x[1], -x[0], 0.0],
                            ];
                            rows[i % 3][k]
                        });
                        let a = svd.solve(&r, 1e-12).unwrap();
                        let e = (&phi * a - &r).norm() / r.norm();
                        assert!(
                            e < 1e-9,
                            "p {p} overlap {overlap} bj {bj} rank {} mode {k}: {e:e}",
                            c.rank()
                        );
                    }
                });
            }
        }
    }

    /// GMRES iterations: the two-level method beats one-level RAS on 2, 4 and 8 box
    /// subdomains of one cube (about half RAS's) and does not grow with them.
    #[test]
    fn iterations_do_not_grow_with_the_subdomains() {
        let ne = 12;
        let mut ras_its = Vec::new();
        let mut two_its = Vec::new();
        for parts in [[2, 1, 1], [2, 2, 1], [2, 2, 2]] {
            let p = parts.iter().product();
            let out = run_ranks(p, |c| {
                let (mut m, pts) = elasticity_boxes(c, ne, parts);
                let b = load(m.n_owned_dofs());
                let ras = RestrictedSchwarz::new(c, &m).unwrap();
                let mut x1 = vec![0.0; b.len()];
                let s1 = gmres(c, &mut m, &ras, &b, &mut x1, &opts()).unwrap();
                let tl = TwoLevel::<RestrictedSchwarz>::new(
                    c,
                    &m,
                    FactorOptions::default(),
                    Some(&pts),
                    CoarseMode::Multiplicative,
                )
                .unwrap();
                let mut x2 = vec![0.0; b.len()];
                let s2 = gmres(c, &mut m, &tl, &b, &mut x2, &opts()).unwrap();
                assert!(s1.converged && s2.converged);
                let d: f64 = x1.iter().zip(&x2).map(|(a, b)| (a - b).powi(2)).sum();
                let d = c.allgather_f64(d).iter().sum::<f64>().sqrt();
                assert!(d <= 1e-6 * c.norm2(&x1), "{d:e}");
                (s1.iterations, s2.iterations, tl.coarse_stats().dimension)
            });
            let (r, t, dim) = out[0];
            eprintln!("{parts:?}: RAS {r}, two-level {t} (coarse dimension {dim})");
            assert!(t < r, "{parts:?}: two-level {t} vs RAS {r}");
            ras_its.push(r);
            two_its.push(t);
        }
        assert!(
            two_its[2] as f64 <= 1.25 * two_its[0] as f64,
            "two-level {two_its:?}"
        );
    }

    /// On one rank there is no interface: the first level alone, the exact solve.
    #[test]
    fn one_rank_is_the_first_level() {
        run_ranks(1, |c| {
            let ne = 4;
            let m = elasticity_cube(c, ne, &[(ne + 1).pow(3)]);
            let pts = cube_points(ne, &m);
            let tl = TwoLevel::<RestrictedSchwarz>::new(
                c,
                &m,
                FactorOptions::default(),
                Some(&pts),
                CoarseMode::Multiplicative,
            )
            .unwrap();
            assert_eq!(tl.coarse_stats().dimension, 0);
            let r = load(m.n_owned_dofs());
            let (mut z1, mut z2) = (vec![0.0; r.len()], vec![0.0; r.len()]);
            tl.apply(c, &r, &mut z1);
            tl.first().apply(c, &r, &mut z2);
            assert_eq!(z1, z2);
        });
    }

    /// A₀ as the coarse space forms it on the boundary rows is Φᵀ A Φ with every row of
    /// A Φ (the other rows vanish: they are the extension's own equations).
    #[test]
    fn the_galerkin_matrix_is_phi_t_a_phi() {
        run_ranks(3, |c| {
            let (m, pts) = elasticity_boxes(c, 6, [3, 1, 1]);
            let tl = TwoLevel::<RestrictedSchwarz>::new(
                c,
                &m,
                FactorOptions::default(),
                Some(&pts),
                CoarseMode::Multiplicative,
            )
            .unwrap();
            let cs = tl.coarse();
            let dim = cs.dimension();
            let n = m.n_owned_dofs();
            let nf = cs.columns().len();
            let column = |f: usize| -> Vec<f64> {
                match cs.columns().binary_search(&f) {
                    Ok(j) => (0..n).map(|i| cs.phi()[i * nf + j]).collect(),
                    Err(_) => vec![0.0; n],
                }
            };
            let mut full = vec![0.0; dim * dim];
            for g in 0..dim {
                let mut ag = vec![0.0; n];
                m.spmv(c, &column(g), &mut ag);
                for f in 0..dim {
                    full[f * dim + g] = column(f).iter().zip(&ag).map(|(a, b)| a * b).sum();
                }
            }
            c.allreduce_sum(&mut full);
            let scale = full.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            for (a, b) in full.iter().zip(cs.coarse_matrix()) {
                assert!((a - b).abs() <= 1e-10 * scale, "{a} vs {b}");
            }
        });
    }

    /// A singular coarse matrix keeps its largest well-conditioned part: a zero function
    /// and a repeated one are dropped, the rest is solved exactly.
    #[test]
    fn a_singular_coarse_matrix_keeps_a_well_conditioned_part() {
        // Functions 0, 1, 2 independent; 3 a copy of 1; 4 zero.
        let base = [[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 2.0]];
        let pick = [0usize, 1, 2, 1];
        let m = 5;
        let mut a0 = vec![0.0; m * m];
        for i in 0..4 {
            for j in 0..4 {
                a0[i * m + j] = base[pick[i]][pick[j]];
            }
        }
        let (kept, lu) = factor_coarse(&a0, m).unwrap();
        assert_eq!(kept.len(), 3);
        assert!(!kept.contains(&4));
        assert!(kept.contains(&0) && kept.contains(&2));
        let lu = lu.unwrap();
        let mut x = faer::Col::<f64>::from_fn(3, |i| (i + 1) as f64);
        let b = x.clone();
        use faer::linalg::solvers::Solve;
        lu.solve_in_place(x.as_mut());
        for i in 0..3 {
            let ax: f64 = (0..3).map(|j| a0[kept[i] * m + kept[j]] * x[j]).sum();
            assert!((ax - b[i]).abs() < 1e-12);
        }
        // Nothing well-conditioned: refused.
        assert!(factor_coarse(&[0.0; 4], 2).unwrap().0.is_empty());
    }

    /// A global unknown coupled to the cube's top face by springs (a reference point) is a
    /// coarse unknown: the two-level method solves the system it makes, on 2 and 3 ranks,
    /// in fewer iterations than RAS.
    #[test]
    fn a_global_unknown_is_a_coarse_unknown() {
        let ne = 6;
        let nn = ne + 1;
        let nb = nn * nn * nn;
        for p in [2usize, 3] {
            let out = run_ranks(p, |c| {
                let mut counts = split(nb, p);
                counts[p - 1] += 1;
                let g = nb; // the last block of the last rank
                let layout = Layout::from_counts(&counts, c.rank());
                let base = elasticity_cube(c, ne, &split(nb, p));
                let top: Vec<usize> = (nb - nn * nn..nb).collect();
                let mut pairs: Vec<(usize, usize)> = Vec::new();
                for i in 0..base.layout().owned_len() {
                    let row = base.layout().start() + i;
                    pairs.extend(base.cols_of_row(i).iter().map(|&col| (row, col)));
                }
                if c.rank() == 0 {
                    for &a in &top {
                        pairs.extend([(a, g), (g, a), (g, g), (a, a)]);
                    }
                }
                let mut m = DistMatrix::new(c, layout.clone(), &pairs);
                for i in 0..base.layout().owned_len() {
                    let row = base.layout().start() + i;
                    for &col in base.cols_of_row(i) {
                        let v: [f64; 9] = base.block(i, col).unwrap().try_into().unwrap();
                        m.add_block(row, col, &v);
                    }
                }
                let k = 10.0;
                let eye = |s: f64| -> [f64; 9] {
                    std::array::from_fn(|q| if q % 4 == 0 { s } else { 0.0 })
                };
                if c.rank() == 0 {
                    for &a in &top {
                        m.add_block(a, a, &eye(k));
                        m.add_block(g, g, &eye(k));
                        m.add_block(a, g, &eye(-k));
                        m.add_block(g, a, &eye(-k));
                    }
                }
                m.finish_assembly(c);
                let n_nodes = layout.owned_len() - (c.rank() == p - 1) as usize;
                m.set_block_kinds(n_nodes, vec![g], Vec::new());
                let pts = cube_points(ne, &m);
                // A load on the reference point only.
                let mut b = vec![0.0; m.n_owned_dofs()];
                if c.rank() == p - 1 {
                    let l = b.len();
                    b[l - 3..].copy_from_slice(&[1.0, -2.0, 0.5]);
                }
                let bj = BlockJacobi::new(&m).unwrap();
                let mut x0 = vec![0.0; b.len()];
                let o = GmresOptions {
                    rtol: 1e-10,
                    max_iterations: 5000,
                    ..Default::default()
                };
                let s0 = gmres(c, &mut m, &bj, &b, &mut x0, &o).unwrap();
                let ras = RestrictedSchwarz::new(c, &m).unwrap();
                let mut x1 = vec![0.0; b.len()];
                let s1 = gmres(c, &mut m, &ras, &b, &mut x1, &o).unwrap();
                let tl = TwoLevel::<RestrictedSchwarz>::new(
                    c,
                    &m,
                    FactorOptions::default(),
                    Some(&pts),
                    CoarseMode::Multiplicative,
                )
                .unwrap();
                let mut x2 = vec![0.0; b.len()];
                let s2 = gmres(c, &mut m, &tl, &b, &mut x2, &o).unwrap();
                assert!(s0.converged && s1.converged && s2.converged);
                let d: f64 = x0.iter().zip(&x2).map(|(a, b)| (a - b).powi(2)).sum();
                let d = c.allgather_f64(d).iter().sum::<f64>().sqrt();
                assert!(d <= 1e-7 * c.norm2(&x0), "{d:e}");
                let st = tl.coarse_stats();
                (s1.iterations, s2.iterations, st.dimension, st.kept)
            });
            let (r, t, dim, kept) = out[0];
            eprintln!("{p} ranks: RAS {r}, two-level {t}, coarse {kept} of {dim}");
            assert!(t < r, "{p} ranks: two-level {t} vs RAS {r}");
            assert!(dim >= 3 && kept >= 3);
        }
    }
}
