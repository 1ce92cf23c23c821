//! A distributing coupling (Nastran RBE3, Abaqus `*DISTRIBUTING COUPLING`, LS-DYNA
//! `*CONSTRAINED_INTERPOLATION`): a reference point with six DOFs tied to a set of
//! nodes of a part. The reference point moves as the weighted least-squares rigid motion
//! of its nodes, and a force or moment applied at it reaches the nodes in proportion to
//! their weights (the moment as forces ∝ weight × distance from the weighted centroid);
//! the nodes keep only their translations. Each DOF is free (optionally loaded by a
//! curve) or prescribed (then its reaction is reported).
//!
//! **Formulation** (constraint equations with multipliers, linear in the reference
//! configuration: exact for small rotations, the regime of bolted joints and stiffness
//! studies). With weights wᵢ, W = Σwᵢ, ŵᵢ = wᵢ/W, centroid X_c = Σŵᵢ Xᵢ, dᵢ = Xᵢ − X_c,
//! r = X_R − X_c and the weighted inertia J = Σ wᵢ (|dᵢ|² I − dᵢdᵢᵀ), the least-squares
//! fit of uᵢ ≈ a + θ × dᵢ gives a = Σŵᵢuᵢ and θ = Σ Bᵢuᵢ with Bᵢ = J⁻¹ wᵢ [dᵢ]ₓ, so the
//! reference point's unknowns U = [u_R; L θ_R] (L a length of the node set, so every
//! unknown is a length and every row a force) obey U = Σ Cᵢuᵢ with
//!
//! ```text
//!   Cᵢ = [ ŵᵢ I − [r]ₓ Bᵢ ;  L Bᵢ ]        (6 × 3)
//! ```
//!
//! Stationarity of Π(u) − F̃·U + κ λ·(Σ Cᵢuᵢ − U), F̃ = [F; M/L], gives the rows
//!
//! ```text
//!   node i:  + κ Cᵢᵀ λ            (internal force)
//!   U:       − κ λ − F̃            (at a solution κλ = −F̃: the load reaches the nodes
//!                                  as Cᵢᵀ F̃, the RBE3 distribution)
//!   λ:       κ (Σ Cᵢuᵢ − U)       (the constraint)
//! ```
//!
//! Multipliers rather than elimination, because a prescribed DOF is then simply a
//! prescribed unknown whose reaction is its residual, and the same rows serve the free
//! and the driven point. U and λ (four blocks) are global unknowns owned by the rank
//! holding most of the coupled weight and read by every rank with coupled nodes; each
//! rank adds its nodes' κCᵢuᵢ to the multiplier rows (ghost entries summed on the
//! owner). κ is the model's mean nodal stiffness. The Jacobian carries a −10⁻⁸κ diagonal
//! on the multiplier rows (Jacobian only, as the walls' ALM rows): it keeps a rank's
//! diagonal block regular when it owns the point but none of the coupled nodes.

// Index loops over 3×3 frames read like the formulas.
#![allow(clippy::needless_range_loop)]

use super::contribution::{
    Column, Contribution, Evaluation, Explicit, GridSpec, Outputs, Reference, Scaled, State,
    SummaryEntry,
};
use super::dofs::{DofMap, Unknowns};
use super::kind::{ContributionKind, Localizer};
use super::local::{LocalElements, LocalMesh};
use super::mat3::{flat, mul, skew, transpose, ID};
use crate::curve::Curve;
use serde::{Deserialize, Serialize};

/// Jacobian-only regularization of the multiplier rows (relative to κ).
const JACOBIAN_REG: f64 = 1e-8;

/// One of the reference point's six DOFs (ux, uy, uz, rx, ry, rz).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub enum Dof {
    /// Free, loaded by `value × curve(t)` (a force, or a moment for a rotation).
    Free { load: Option<(f64, Curve)> },
    /// Prescribed to `value × curve(t)` (a displacement, or a rotation in radians).
    Prescribed { value: f64, curve: Curve },
}

/// A distributing coupling as the deck gives it, with the coupled set's geometry
/// (computed once, on the whole set).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CouplingDef {
    pub name: String,
    /// The coupled node set or surface's name (for messages).
    pub set: String,
    /// Reference point (reference configuration).
    pub point: [f64; 3],
    /// Coupled nodes (global numbers; owned local indices once localized) and weights.
    pub nodes: Vec<usize>,
    pub weights: Vec<f64>,
    pub dofs: [Dof; 6],
    /// Σ wᵢ, the weighted centroid, J⁻¹ and the length L of the whole set.
    pub total_weight: f64,
    pub centroid: [f64; 3],
    pub j_inv: [[f64; 3]; 3],
    pub length: f64,
    /// The rank that owns the reference point's unknowns (set when localized).
    pub owner: usize,
}

/// The weighted inertia of points about their weighted centroid:
/// (Σw, centroid, J = Σ w (|d|² I − d dᵀ)).
pub fn inertia(x: &[[f64; 3]], w: &[f64]) -> (f64, [f64; 3], [[f64; 3]; 3]) {
    let total: f64 = w.iter().sum();
    let mut c = [0.0; 3];
    for (xi, &wi) in x.iter().zip(w) {
        for k in 0..3 {
            c[k] += wi * xi[k] / total;
        }
    }
    let mut j = [[0.0; 3]; 3];
    for (xi, &wi) in x.iter().zip(w) {
        let d = [xi[0] - c[0], xi[1] - c[1], xi[2] - c[2]];
        let dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        for a in 0..3 {
            for b in 0..3 {
                j[a][b] += wi * (if a == b { dd } else { 0.0 } - d[a] * d[b]);
            }
        }
    }
    (total, c, j)
}

/// The inverse of a symmetric 3×3 matrix, or None when it is singular relative to its
/// size (points on a line or at one point).
pub fn invert3(a: [[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let c = |i: usize, j: usize| {
        let (i1, i2) = ((i + 1) % 3, (i + 2) % 3);
        let (j1, j2) = ((j + 1) % 3, (j + 2) % 3);
        a[i1][j1] * a[i2][j2] - a[i1][j2] * a[i2][j1]
    };
    let det = a[0][0] * c(0, 0) + a[0][1] * c(0, 1) + a[0][2] * c(0, 2);
    let scale = (a[0][0] + a[1][1] + a[2][2]).powi(3);
    if det.is_nan() || det.abs() <= 1e-10 * scale {
        return None;
    }
    let mut inv = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            inv[i][j] = c(j, i) / det;
        }
    }
    Some(inv)
}

const NAMES: [&str; 6] = ["ux", "uy", "uz", "rx", "ry", "rz"];

impl ContributionKind for CouplingDef {
    fn kind_name(&self) -> &'static str {
        "coupling"
    }
    fn name(&self) -> &str {
        &self.name
    }
    fn describe(&self) -> String {
        let dofs: Vec<String> = self
            .dofs
            .iter()
            .zip(NAMES)
            .filter_map(|(d, n)| match d {
                Dof::Prescribed { .. } => Some(format!("{n} prescribed")),
                Dof::Free { load: Some(_) } => Some(format!("{n} loaded")),
                Dof::Free { load: None } => None,
            })
            .collect();
        format!(
            "coupling {}: reference point {:?} distributing to {} nodes of {}{}",
            self.name,
            self.point,
            self.nodes.len(),
            self.set,
            if dofs.is_empty() {
                String::new()
            } else {
                format!(" ({})", dofs.join(", "))
            }
        )
    }
    fn nodes(&self) -> Vec<usize> {
        self.nodes.clone()
    }
    fn extra_unknowns(&self) -> usize {
        12
    }
    /// Each rank keeps the coupled nodes it owns; every rank agrees that the reference
    /// point belongs to the rank with most of the coupled weight (the lowest on a tie).
    fn localize(&self, l: &Localizer) -> Self {
        let mut per_rank = vec![0.0; l.ranks];
        for (&n, &w) in self.nodes.iter().zip(&self.weights) {
            per_rank[l.owner[n] as usize] += w;
        }
        let owner = (0..l.ranks).fold(0, |b, r| if per_rank[r] > per_rank[b] { r } else { b });
        let mine: Vec<(usize, f64)> = self
            .nodes
            .iter()
            .zip(&self.weights)
            .filter_map(|(&n, &w)| l.owned(n).map(|ln| (ln, w)))
            .collect();
        CouplingDef {
            nodes: mine.iter().map(|p| p.0).collect(),
            weights: mine.iter().map(|p| p.1).collect(),
            owner,
            ..self.clone()
        }
    }
    fn build(&self, mesh: &LocalMesh, _elements: &LocalElements) -> Box<dyn Contribution> {
        Box::new(Coupling::new(self.clone(), &mesh.coords, mesh.rank))
    }
}

impl CouplingDef {
    /// Whether it can take part in an explicit analysis (else why not): the check of
    /// its runtime's [`Explicit::start_explicit`].
    fn explicit_ok(&self) -> Result<(), String> {
        Err(format!(
            "coupling `{}`: distributing couplings need a static or implicit analysis (the reference point and its constraint carry no mass for the explicit update)",
            self.name
        ))
    }
}

/// A distributing coupling on one rank (see the module documentation).
pub struct Coupling {
    def: CouplingDef,
    /// Cᵢ of each owned coupled node: translation rows and rotation rows (scaled by L).
    c_t: Vec<[[f64; 3]; 3]>,
    c_r: Vec<[[f64; 3]; 3]>,
    owner: bool,
    kappa: f64,
    /// Global blocks of U (translation, rotation) and λ (translation, rotation), and
    /// their local blocks where this rank holds them.
    global: [usize; 4],
    local: [Option<usize>; 4],
}

impl Coupling {
    pub fn new(def: CouplingDef, coords: &[[f64; 3]], rank: usize) -> Self {
        let w_total = def.total_weight;
        let r = [
            def.point[0] - def.centroid[0],
            def.point[1] - def.centroid[1],
            def.point[2] - def.centroid[2],
        ];
        let (mut c_t, mut c_r) = (Vec::new(), Vec::new());
        for (&n, &w) in def.nodes.iter().zip(&def.weights) {
            let x = coords[n];
            let d = [
                x[0] - def.centroid[0],
                x[1] - def.centroid[1],
                x[2] - def.centroid[2],
            ];
            let sd = skew(d);
            let b: [[f64; 3]; 3] =
                std::array::from_fn(|i| std::array::from_fn(|j| w * mul(&def.j_inv, &sd)[i][j]));
            let rb = mul(&skew(r), &b);
            c_t.push(std::array::from_fn(|i| {
                std::array::from_fn(|j| if i == j { w / w_total } else { 0.0 } - rb[i][j])
            }));
            c_r.push(std::array::from_fn(|i| {
                std::array::from_fn(|j| def.length * b[i][j])
            }));
        }
        Self {
            owner: def.owner == rank,
            def,
            c_t,
            c_r,
            kappa: 1.0,
            global: [0; 4],
            local: [None; 4],
        }
    }

    /// The generalized load F̃ = [F; M/L] on the free DOFs at time t.
    fn load(&self, t: f64) -> [f64; 6] {
        std::array::from_fn(|k| match &self.def.dofs[k] {
            Dof::Free { load: Some((v, c)) } => {
                v * c.eval(t) / if k < 3 { 1.0 } else { self.def.length }
            }
            _ => 0.0,
        })
    }

    fn get(u: &[f64], block: Option<usize>) -> [f64; 3] {
        block.map_or([0.0; 3], |b| [u[3 * b], u[3 * b + 1], u[3 * b + 2]])
    }
}

impl Contribution for Coupling {
    fn name(&self) -> &str {
        &self.def.name
    }

    /// Four global blocks: U translation, U rotation (× L), λ translation, λ rotation.
    fn unknowns(&self) -> Unknowns {
        Unknowns {
            owned: 0,
            global: 4,
            owner: self.def.owner,
            reads_global: self.owner || !self.def.nodes.is_empty(),
        }
    }

    fn bind(&mut self, dofs: &DofMap, index: usize) {
        let first = dofs.placed(index).global_first;
        for k in 0..4 {
            self.global[k] = first + k;
            self.local[k] = dofs.local_block(first + k);
        }
    }

    fn pattern(&self, dofs: &DofMap, out: &mut Vec<(usize, usize)>) {
        let [ut, ur, lt, lr] = self.global;
        for &n in &self.def.nodes {
            let a = dofs.global_block(n);
            for l in [lt, lr] {
                out.extend_from_slice(&[(a, l), (l, a)]);
            }
        }
        if self.owner {
            out.extend_from_slice(&[
                (ut, lt),
                (ur, lr),
                (lt, ut),
                (lr, ur),
                (lt, lt),
                (lr, lr),
                (ut, ut),
                (ur, ur),
            ]);
        }
    }

    fn evaluate(&mut self, ev: &mut Evaluation) -> Result<(), String> {
        let k = self.kappa;
        let [lt, lr] = [self.local[2], self.local[3]];
        let lam = [Self::get(ev.u, lt), Self::get(ev.u, lr)];
        if let Some((f_int, f_ext)) = ev.forces.as_mut() {
            let mut cu = [0.0; 6];
            for (i, &n) in self.def.nodes.iter().enumerate() {
                let ui = [ev.u[3 * n], ev.u[3 * n + 1], ev.u[3 * n + 2]];
                for a in 0..3 {
                    for b in 0..3 {
                        cu[a] += self.c_t[i][a][b] * ui[b];
                        cu[3 + a] += self.c_r[i][a][b] * ui[b];
                        // κ Cᵢᵀ λ on the node.
                        f_int[3 * n + a] +=
                            k * (self.c_t[i][b][a] * lam[0][b] + self.c_r[i][b][a] * lam[1][b]);
                    }
                }
            }
            if self.owner {
                let u_r = [
                    Self::get(ev.u, self.local[0]),
                    Self::get(ev.u, self.local[1]),
                ];
                let load = self.load(ev.t);
                for a in 0..3 {
                    cu[a] -= u_r[0][a];
                    cu[3 + a] -= u_r[1][a];
                }
                for (h, blk) in [self.local[0], self.local[1]].into_iter().enumerate() {
                    let b = blk.expect("the owner holds its unknowns");
                    for a in 0..3 {
                        f_int[3 * b + a] -= k * lam[h][a];
                        f_ext[3 * b + a] += load[3 * h + a];
                    }
                }
            }
            if !self.def.nodes.is_empty() || self.owner {
                for (h, blk) in [lt, lr].into_iter().enumerate() {
                    let b = blk.expect("a rank with coupled nodes reads the multipliers");
                    for a in 0..3 {
                        f_int[3 * b + a] += k * cu[3 * h + a];
                    }
                }
            }
        }
        if let Some(m) = ev.jacobian.as_deref_mut() {
            let [ut, ur, glt, glr] = self.global;
            for (i, &n) in self.def.nodes.iter().enumerate() {
                let a = ev.dofs.global_block(n);
                m.add_block(a, glt, &flat(&transpose(&self.c_t[i]), k));
                m.add_block(a, glr, &flat(&transpose(&self.c_r[i]), k));
                m.add_block(glt, a, &flat(&self.c_t[i], k));
                m.add_block(glr, a, &flat(&self.c_r[i], k));
            }
            if self.owner {
                for (u, l) in [(ut, glt), (ur, glr)] {
                    m.add_block(u, l, &flat(&ID, -k));
                    m.add_block(l, u, &flat(&ID, -k));
                    m.add_block(l, l, &flat(&ID, -JACOBIAN_REG * k));
                }
            }
        }
        Ok(())
    }

    /// The prescribed DOFs, on the owner: U = [u; L θ].
    fn prescribed(&self, t: f64, dofs: &DofMap, out: &mut Vec<(usize, f64)>) {
        if !self.owner {
            return;
        }
        for (k, d) in self.def.dofs.iter().enumerate() {
            if let Dof::Prescribed { value, curve } = d {
                let b = self.local[k / 3].expect("the owner holds its unknowns");
                let scale = if k < 3 { 1.0 } else { self.def.length };
                let i = dofs
                    .owned_index(3 * b + k % 3)
                    .expect("the owner owns its unknowns");
                out.push((i, scale * value * curve.eval(t)));
            }
        }
    }

    fn scaled(&mut self) -> Option<&mut dyn Scaled> {
        Some(self)
    }
    fn outputs(&self) -> Option<&dyn Outputs> {
        Some(self)
    }
    fn explicit(&mut self) -> Option<&mut dyn Explicit> {
        Some(self)
    }
}

impl Scaled for Coupling {
    fn wants_reference(&self) -> bool {
        true
    }

    fn setup(&mut self, r: &Reference) {
        self.kappa = r.k_mean.max(f64::MIN_POSITIVE);
    }
}

impl Outputs for Coupling {
    /// `<name>.ux … .rz`: the reference point's displacement and rotation (radians);
    /// `<name>.fx … .mz`: the force and moment it transmits to the part, −κλ: the
    /// applied load on free DOFs, the reaction on prescribed ones.
    fn columns(&self) -> Vec<Column> {
        NAMES
            .iter()
            .chain(&["fx", "fy", "fz", "mx", "my", "mz"])
            .map(|c| Column::sum(format!("{}.{c}", self.def.name)))
            .collect()
    }

    fn column_values(&self, s: &State, out: &mut [f64]) {
        if !self.owner {
            return;
        }
        let l = self.def.length;
        let u = [Self::get(s.u, self.local[0]), Self::get(s.u, self.local[1])];
        let lam = [Self::get(s.u, self.local[2]), Self::get(s.u, self.local[3])];
        for a in 0..3 {
            out[a] = u[0][a];
            out[3 + a] = u[1][a] / l;
            // (+ 0.0: no negative zeros in the history.)
            out[6 + a] = -self.kappa * lam[0][a] + 0.0;
            out[9 + a] = -self.kappa * lam[1][a] * l + 0.0;
        }
    }

    fn summary(&self, v: &[f64]) -> Option<SummaryEntry> {
        let g = |a: usize| [v[a], v[a + 1], v[a + 2]];
        Some((
            "couplings",
            self.def.name.clone(),
            serde_json::json!({
                "displacement": g(0), "rotation": g(3), "force": g(6), "moment": g(9)
            }),
        ))
    }

    /// The reference point, where it is.
    fn grids(&self) -> Vec<GridSpec> {
        vec![GridSpec {
            name: format!("couplings/{}", self.def.name),
            label: format!("coupling_{}", self.def.name),
            attrs: vec![("name".into(), self.def.name.clone())],
            cells: vec![vec![0]],
            n_points: 1,
            paths: false,
        }]
    }

    fn grid_points(&self, _i: usize, _t: f64, v: &[f64]) -> Vec<[f64; 3]> {
        let p = self.def.point;
        vec![[p[0] + v[0], p[1] + v[1], p[2] + v[2]]]
    }
}

impl Explicit for Coupling {
    fn start_explicit(&mut self) -> Result<(), String> {
        self.def.explicit_ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inertia_of_a_square_and_its_inverse() {
        // Four unit weights at (±1, ±1, 0): J = diag(4, 4, 8).
        let x = [
            [1.0, 1.0, 0.0],
            [-1.0, 1.0, 0.0],
            [-1.0, -1.0, 0.0],
            [1.0, -1.0, 0.0],
        ];
        let (w, c, j) = inertia(&x, &[1.0; 4]);
        assert_eq!(w, 4.0);
        assert_eq!(c, [0.0; 3]);
        assert_eq!(j, [[4.0, 0.0, 0.0], [0.0, 4.0, 0.0], [0.0, 0.0, 8.0]]);
        let inv = invert3(j).unwrap();
        assert!((inv[2][2] - 0.125).abs() < 1e-15);
        // Collinear points: no rotation about their line.
        let line = [[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        let (_, _, j) = inertia(&line, &[1.0; 3]);
        assert!(invert3(j).is_none());
    }

    /// A rigid motion of the nodes gives the reference point the same motion, and the
    /// distributed load of a force and moment has their resultant.
    #[test]
    fn rigid_motion_and_load_resultant() {
        let coords = vec![
            [1.0, 1.0, 0.0],
            [-1.0, 1.0, 0.0],
            [-1.0, -1.0, 0.5],
            [1.0, -1.0, 0.0],
            [0.3, 0.2, 0.1],
        ];
        let weights = vec![1.0, 2.0, 1.5, 1.0, 0.5];
        let (w, c, j) = inertia(&coords, &weights);
        let def = CouplingDef {
            name: "p".into(),
            set: "s".into(),
            point: [0.5, 0.0, 3.0],
            nodes: (0..5).collect(),
            weights,
            dofs: std::array::from_fn(|_| Dof::Free { load: None }),
            total_weight: w,
            centroid: c,
            j_inv: invert3(j).unwrap(),
            length: 2.0,
            owner: 0,
        };
        let cp = Coupling::new(def.clone(), &coords, 0);
        let (a, th) = ([0.1, -0.2, 0.3], [0.01, -0.02, 0.03]);
        let mut u_ref = [0.0; 6];
        for (i, x) in coords.iter().enumerate() {
            // u = a + θ × x: a rigid motion.
            let ui = [
                a[0] + th[1] * x[2] - th[2] * x[1],
                a[1] + th[2] * x[0] - th[0] * x[2],
                a[2] + th[0] * x[1] - th[1] * x[0],
            ];
            for r in 0..3 {
                for k in 0..3 {
                    u_ref[r] += cp.c_t[i][r][k] * ui[k];
                    u_ref[3 + r] += cp.c_r[i][r][k] * ui[k];
                }
            }
        }
        let p = def.point;
        let want_u = [
            a[0] + th[1] * p[2] - th[2] * p[1],
            a[1] + th[2] * p[0] - th[0] * p[2],
            a[2] + th[0] * p[1] - th[1] * p[0],
        ];
        for k in 0..3 {
            assert!((u_ref[k] - want_u[k]).abs() < 1e-14, "{u_ref:?}");
            assert!((u_ref[3 + k] - 2.0 * th[k]).abs() < 1e-14, "{u_ref:?}");
        }
        // The nodal forces Cᵢᵀ F̃ of F = (1, 2, 3), M = (4, 5, 6) at the point.
        let (f, m) = ([1.0, 2.0, 3.0], [4.0, 5.0, 6.0]);
        let ft = [f[0], f[1], f[2], m[0] / 2.0, m[1] / 2.0, m[2] / 2.0];
        let (mut sf, mut sm) = ([0.0; 3], [0.0; 3]);
        for (i, x) in coords.iter().enumerate() {
            let mut fi = [0.0; 3];
            for k in 0..3 {
                for r in 0..3 {
                    fi[k] += cp.c_t[i][r][k] * ft[r] + cp.c_r[i][r][k] * ft[3 + r];
                }
            }
            let d = [x[0] - p[0], x[1] - p[1], x[2] - p[2]];
            for k in 0..3 {
                sf[k] += fi[k];
            }
            sm[0] += d[1] * fi[2] - d[2] * fi[1];
            sm[1] += d[2] * fi[0] - d[0] * fi[2];
            sm[2] += d[0] * fi[1] - d[1] * fi[0];
        }
        for k in 0..3 {
            assert!((sf[k] - f[k]).abs() < 1e-12, "{sf:?}");
            assert!((sm[k] - m[k]).abs() < 1e-12, "{sm:?}");
        }
    }
}
