//! The model's rigid-wall contact pass on one rank: every owned tracked node is
//! projected onto its wall, the ALM or penalty law ([`crate::contact::law`]) gives its
//! force (and, for ALM, the residual rows of its multipliers, which this rank owns), and
//! the generalized Jacobian blocks go into the distributed matrix. Wall reactions are
//! summed over ranks with one reduction.

// Index loops over 3×3 frames read like the formulas.
#![allow(clippy::needless_range_loop)]

use crate::contact::law::{alm, penalty};
use crate::contact::motion::Pose;
use crate::contact::shape::Shape;
use crate::contact::wall::{project, ContactMethod, WallDef};
use crate::parallel::Comm;
use crate::solve::linear::matrix::DistMatrix;

/// Jacobian-only regularization of the multiplier rows (relative to κ).
const JACOBIAN_REG: f64 = 1e-8;

/// What one tracked node did at the last evaluation.
#[derive(Debug, Clone, Copy, Default)]
pub struct NodeContact {
    /// Signed normal gap (NaN where the node cannot reach the wall).
    pub gap: f64,
    /// Force the wall exerts on the node (global).
    pub force: [f64; 3],
    /// Multipliers (λ_N, λ_T1, λ_T2), lengths (zero for penalty).
    pub lambda: [f64; 3],
    /// Normal component of `force` (along the wall's outward normal; > 0 pushes the
    /// node out of the wall).
    pub normal_force: f64,
    pub active: bool,
    pub sticking: bool,
}

/// One wall on this rank.
#[derive(Debug)]
pub struct WallContact {
    pub def: WallDef,
    pub shape: Box<dyn Shape>,
    /// Local dof index of the first multiplier (ALM), else None.
    pub mult_offset: Option<usize>,
    /// Global block of the first multiplier (ALM).
    pub mult_block: usize,
    /// κ of each tracked node (force per length), ALM's scale.
    pub kappa: Vec<f64>,
    /// The diagonal stiffness of each tracked node (the penalty's base).
    pub k_node: Vec<f64>,
    /// Node positions at the start of the step (committed).
    x_old: Vec<[f64; 3]>,
    x_new: Vec<[f64; 3]>,
    /// Outward normal of each node's projection at the start of the step (the hint that
    /// keeps a penetrating node on the face it came through) and at the last evaluation.
    n_old: Vec<Option<[f64; 3]>>,
    n_new: Vec<Option<[f64; 3]>>,
    /// Penalty tangential force carried over steps (global vector).
    ft_old: Vec<[f64; 3]>,
    ft_new: Vec<[f64; 3]>,
    pub last: Vec<NodeContact>,
}

/// Per wall force and moment on the wall and its prescribed displacement.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct WallReport {
    pub force: [f64; 3],
    pub moment: [f64; 3],
    pub displacement: [f64; 3],
}

/// Contact quantities of a converged step (same on every rank).
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct ContactReport {
    pub walls: Vec<WallReport>,
    /// max(0, −g_N) over all tracked nodes of all walls.
    pub max_penetration: f64,
    pub active: usize,
    pub sticking: usize,
}

/// Nodal contact fields of the owned nodes at the last evaluation (for output).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ContactFields {
    /// Smallest gap over the walls tracking the node; NaN where no wall tracks it or
    /// none can reach it.
    pub gap: Vec<f64>,
    /// Σ over walls of the normal force / the node's tributary area (0 where the area
    /// is 0 or no wall tracks the node).
    pub pressure: Vec<f64>,
    /// Σ over walls of the force on the node, 3 per node (global).
    pub force: Vec<f64>,
    /// λ of the first ALM wall tracking the node, 3 per node (0 elsewhere).
    pub lambda: Vec<f64>,
}

/// All walls on this rank.
#[derive(Debug, Default)]
pub struct Contact {
    pub walls: Vec<WallContact>,
    /// Start time of the step (committed) and the time of the last evaluation.
    t_old: f64,
    t_new: f64,
    /// Explicit runs enforce ALM walls kinematically: their residual pass is skipped.
    pub explicit: bool,
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Local residual and Jacobian blocks of one tracked node (force on the node is minus
/// the node rows; see [`Contact::node`]).
struct NodeEval {
    c: NodeContact,
    /// r_node contribution (minus the force on the node).
    r_node: [f64; 3],
    /// r_λ rows (ALM).
    r_mult: [f64; 3],
    k_xx: [[f64; 3]; 3],
    k_xl: [[f64; 3]; 3],
    k_lx: [[f64; 3]; 3],
    k_ll: [[f64; 3]; 3],
    ft_new: [f64; 3],
    normal: Option<[f64; 3]>,
}

impl Contact {
    /// Build from the rank's walls; multipliers of ALM walls are numbered from local dof
    /// `first_mult_dof` and global block `first_mult_block`.
    pub fn new(
        defs: &[WallDef],
        coords: &[[f64; 3]],
        first_mult_dof: usize,
        first_mult_block: usize,
    ) -> Self {
        let mut dof = first_mult_dof;
        let mut block = first_mult_block;
        let walls = defs
            .iter()
            .map(|d| {
                let n = d.nodes.len();
                let (mult_offset, mult_block) = if d.method == ContactMethod::Alm {
                    let r = (Some(dof), block);
                    dof += 3 * n;
                    block += n;
                    r
                } else {
                    (None, 0)
                };
                let x0: Vec<[f64; 3]> = d.nodes.iter().map(|&i| coords[i]).collect();
                WallContact {
                    shape: d.shape.build(),
                    def: d.clone(),
                    mult_offset,
                    mult_block,
                    kappa: vec![d.kappa.unwrap_or(1.0); n],
                    k_node: vec![1.0; n],
                    x_old: x0.clone(),
                    x_new: x0,
                    n_old: vec![None; n],
                    n_new: vec![None; n],
                    ft_old: vec![[0.0; 3]; n],
                    ft_new: vec![[0.0; 3]; n],
                    last: vec![NodeContact::default(); n],
                }
            })
            .collect();
        Self {
            walls,
            t_old: 0.0,
            t_new: 0.0,
            explicit: false,
        }
    }

    /// Number of multiplier blocks (3 dofs each) on this rank.
    pub fn n_mult_blocks(defs: &[WallDef]) -> usize {
        defs.iter()
            .filter(|d| d.method == ContactMethod::Alm)
            .map(|d| d.nodes.len())
            .sum()
    }

    pub fn is_empty(&self) -> bool {
        self.walls.is_empty()
    }

    /// Set the nodal stiffness of every tracked node from the model's stiffness:
    /// `stiffness(node)` = (mean diagonal of the node's block, E/(λ+2μ) factor). The
    /// penalty stiffness is `penalty_scale` times the diagonal (bulk-dominated, as
    /// LS-DYNA's k = f K A²/V); κ of ALM (without a deck value) is the diagonal times
    /// the factor (see `Model::set_contact_scales`).
    pub fn set_kappa(&mut self, stiffness: impl Fn(usize) -> (f64, f64)) {
        for w in &mut self.walls {
            for (j, &n) in w.def.nodes.iter().enumerate() {
                let (d, f) = stiffness(n);
                w.k_node[j] = d.max(f64::MIN_POSITIVE);
                if w.def.kappa.is_none() {
                    w.kappa[j] = (f * d).max(f64::MIN_POSITIVE);
                }
            }
        }
    }

    /// The (row, col) block couplings the contact adds (all rows owned here).
    pub fn pattern(&self, node_block: &[usize]) -> Vec<(usize, usize)> {
        let mut p = Vec::new();
        for w in &self.walls {
            if w.mult_offset.is_some() {
                for (j, &n) in w.def.nodes.iter().enumerate() {
                    let (a, m) = (node_block[n], w.mult_block + j);
                    p.extend_from_slice(&[(a, m), (m, a), (m, m)]);
                }
            }
        }
        p
    }

    /// One tracked node of wall `w` placed at `pose` (`pose_old` at the step's start).
    fn node(
        w: &WallContact,
        j: usize,
        x: [f64; 3],
        lam: [f64; 3],
        pose: &Pose,
        pose_old: &Pose,
    ) -> NodeEval {
        let mut e = NodeEval {
            c: NodeContact {
                gap: f64::NAN,
                lambda: lam,
                ..NodeContact::default()
            },
            r_node: [0.0; 3],
            r_mult: [0.0; 3],
            k_xx: [[0.0; 3]; 3],
            k_xl: [[0.0; 3]; 3],
            k_lx: [[0.0; 3]; 3],
            k_ll: [[0.0; 3]; 3],
            ft_new: [0.0; 3],
            normal: None,
        };
        let kappa = w.kappa[j];
        let alm_wall = w.mult_offset.is_some();
        let Some(wp) = project(w.shape.as_ref(), pose, pose_old, x, w.n_old[j]) else {
            // Out of the wall's reach: multipliers driven to zero, no force.
            if alm_wall {
                for i in 0..3 {
                    e.r_mult[i] = -kappa * lam[i];
                    e.k_ll[i][i] = -kappa;
                }
            }
            return e;
        };
        let p = wp.frame;
        let xo = w.x_old[j];
        // Slip over the step, on the tangent plane: t·(wall point's old position − x_old)
        // (t·(x − point) = 0), DESIGN.md "g_T".
        let d = [
            wp.point_old[0] - xo[0],
            wp.point_old[1] - xo[1],
            wp.point_old[2] - xo[2],
        ];
        let g = [
            wp.gap,
            p[0][1] * d[0] + p[1][1] * d[1] + p[2][1] * d[2],
            p[0][2] * d[0] + p[1][2] * d[1] + p[2][2] * d[2],
        ];
        e.c.gap = wp.gap;
        e.normal = Some([p[0][0], p[1][0], p[2][0]]);
        let mu = w.def.friction;
        // f_local (force on the node in the frame), ∂f_local/∂g, and for ALM ∂f/∂λ.
        let (fl, dfdg) = if alm_wall {
            let pt = alm(g, lam, mu);
            e.c.active = pt.active;
            e.c.sticking = pt.sticking;
            let mut fl = [0.0; 3];
            let mut dfdg = [[0.0; 3]; 3];
            for i in 0..3 {
                fl[i] = kappa * (lam[i] - pt.h[i]);
                e.r_mult[i] = -kappa * pt.h[i];
                for k in 0..3 {
                    dfdg[i][k] = -kappa * pt.dh_dg[i][k];
                    let id = if i == k { 1.0 } else { 0.0 };
                    // r_λ = −κ h: ∂/∂λ = −κ ∂h/∂λ, ∂/∂x = −κ ∂h/∂g Pᵀ.
                    // A stick or active row has no λ term; where the node's own dof
                    // along that direction is prescribed (a symmetry plane) the row
                    // would then be empty. A −10⁻⁸ κ diagonal in the Jacobian only
                    // (the residual stays exact) keeps the matrix regular; the row's
                    // residual is then zero, so λ there does not move.
                    e.k_ll[i][k] =
                        -kappa * (pt.dh_dl[i][k] + if i == k { JACOBIAN_REG } else { 0.0 });
                    // ∂(κ(λ − h))/∂λ in the frame; mapped to global rows below.
                    e.k_xl[i][k] = kappa * (id - pt.dh_dl[i][k]);
                }
            }
            (fl, dfdg)
        } else {
            let fo = w.ft_old[j];
            let t1 = [p[0][1], p[1][1], p[2][1]];
            let t2 = [p[0][2], p[1][2], p[2][2]];
            let fo_l = [
                t1[0] * fo[0] + t1[1] * fo[1] + t1[2] * fo[2],
                t2[0] * fo[0] + t2[1] * fo[1] + t2[2] * fo[2],
            ];
            let kp = w.def.penalty_scale * w.k_node[j];
            let pt = penalty(g, fo_l, kp, kp, mu);
            e.c.active = pt.active;
            e.c.sticking = pt.sticking;
            for i in 0..3 {
                e.ft_new[i] = t1[i] * pt.f[1] + t2[i] * pt.f[2];
            }
            (pt.f, pt.df_dg)
        };
        // Global force on the node f = P f_local; r_node = −f.
        let mut f = [0.0; 3];
        for i in 0..3 {
            for k in 0..3 {
                f[i] += p[i][k] * fl[k];
            }
            e.r_node[i] = -f[i];
        }
        e.c.force = f;
        e.c.normal_force = fl[0];
        // ∂r_node/∂x = −P (∂f/∂g) Pᵀ − f_N H (the normal turns with x on curved walls;
        // the tangents' turning is left out).
        let mut a = [[0.0; 3]; 3];
        for i in 0..3 {
            for k in 0..3 {
                for l in 0..3 {
                    a[i][k] += p[i][l] * dfdg[l][k];
                }
            }
        }
        for i in 0..3 {
            for k in 0..3 {
                let mut s = 0.0;
                for l in 0..3 {
                    s += a[i][l] * p[k][l];
                }
                e.k_xx[i][k] = -s - fl[0] * wp.hessian[i][k];
            }
        }
        if alm_wall {
            // Node rows: ∂r_node/∂λ = −P ∂f/∂λ; multiplier rows: ∂r_λ/∂x = −κ ∂h/∂g Pᵀ
            // = (∂f/∂g) Pᵀ.
            let fl_l = e.k_xl;
            let mut k_lx = [[0.0; 3]; 3];
            let mut k_xl = [[0.0; 3]; 3];
            for i in 0..3 {
                for k in 0..3 {
                    for l in 0..3 {
                        k_xl[i][k] -= p[i][l] * fl_l[l][k];
                        k_lx[i][k] += dfdg[i][l] * p[k][l];
                    }
                }
            }
            e.k_xl = k_xl;
            e.k_lx = k_lx;
        }
        e
    }

    /// Add the contact residual at displacement `u_local` (owned node dofs first, as the
    /// model's local vectors) and time t: node rows into `r_node_out` (to be subtracted
    /// as external force: it receives the force on the node), multiplier rows read from
    /// and written to `u_owned`/`r_mult` by local dof index. Also keeps each node's
    /// state for reporting and the commit.
    #[allow(clippy::too_many_arguments)]
    pub fn residual(
        &mut self,
        coords: &[[f64; 3]],
        u_local: &[f64],
        u_owned: &[f64],
        t: f64,
        f_ext: &mut [f64],
        r_owned: &mut [f64],
        mut k: Option<&mut DistMatrix>,
        node_block: &[usize],
    ) {
        self.t_new = t;
        let explicit = self.explicit;
        let mut walls = std::mem::take(&mut self.walls);
        for w in &mut walls {
            if explicit && w.mult_offset.is_some() {
                continue;
            }
            let (pose, pose_old) = (w.def.motion.pose(t), w.def.motion.pose(self.t_old));
            for j in 0..w.def.nodes.len() {
                let n = w.def.nodes[j];
                let x = [
                    coords[n][0] + u_local[3 * n],
                    coords[n][1] + u_local[3 * n + 1],
                    coords[n][2] + u_local[3 * n + 2],
                ];
                let lam = match w.mult_offset {
                    Some(o) => [
                        u_owned[o + 3 * j],
                        u_owned[o + 3 * j + 1],
                        u_owned[o + 3 * j + 2],
                    ],
                    None => [0.0; 3],
                };
                let e = Self::node(w, j, x, lam, &pose, &pose_old);
                for c in 0..3 {
                    f_ext[3 * n + c] -= e.r_node[c];
                }
                if let Some(o) = w.mult_offset {
                    for c in 0..3 {
                        r_owned[o + 3 * j + c] = e.r_mult[c];
                    }
                }
                if let Some(km) = k.as_deref_mut() {
                    let a = node_block[n];
                    km.add_block(a, a, &flat(e.k_xx));
                    if w.mult_offset.is_some() {
                        let m = w.mult_block + j;
                        km.add_block(a, m, &flat(e.k_xl));
                        km.add_block(m, a, &flat(e.k_lx));
                        km.add_block(m, m, &flat(e.k_ll));
                    }
                }
                w.x_new[j] = x;
                w.ft_new[j] = e.ft_new;
                w.n_new[j] = e.normal;
                w.last[j] = e.c;
            }
        }
        self.walls = walls;
    }

    /// Kinematic enforcement of the ALM walls for explicit runs (owned node dofs `u`, mid-
    /// step velocities `v`, lumped masses `m`, the step ending at t of length h): a
    /// penetrating node is moved onto the wall along the normal and its normal velocity
    /// relative to the wall is set to zero if it approaches; with friction the tangential
    /// relative velocity is reduced by at most μ times the normal velocity jump (Coulomb
    /// on impulses). The force on the node is reported as m Δv / h.
    pub fn kinematic(
        &mut self,
        coords: &[[f64; 3]],
        u: &mut [f64],
        v: &mut [f64],
        m: &[f64],
        t: f64,
        h: f64,
    ) {
        self.t_new = t;
        for w in &mut self.walls {
            if w.mult_offset.is_none() {
                continue;
            }
            let (pose, pose_old) = (w.def.motion.pose(t), w.def.motion.pose(t - h));
            for j in 0..w.def.nodes.len() {
                let n = w.def.nodes[j];
                let x = [
                    coords[n][0] + u[3 * n],
                    coords[n][1] + u[3 * n + 1],
                    coords[n][2] + u[3 * n + 2],
                ];
                let mut c = NodeContact {
                    gap: f64::NAN,
                    ..NodeContact::default()
                };
                if let Some(wp) = project(w.shape.as_ref(), &pose, &pose_old, x, w.n_old[j]) {
                    c.gap = wp.gap;
                    w.n_new[j] = Some([wp.frame[0][0], wp.frame[1][0], wp.frame[2][0]]);
                    if wp.gap < 0.0 {
                        let nrm = [wp.frame[0][0], wp.frame[1][0], wp.frame[2][0]];
                        let vr: [f64; 3] = std::array::from_fn(|i| {
                            v[3 * n + i] - (wp.point[i] - wp.point_old[i]) / h
                        });
                        let vn = vr[0] * nrm[0] + vr[1] * nrm[1] + vr[2] * nrm[2];
                        let mut dv = [0.0; 3];
                        if vn < 0.0 {
                            let vt: [f64; 3] = std::array::from_fn(|i| vr[i] - vn * nrm[i]);
                            let vtn = (vt[0] * vt[0] + vt[1] * vt[1] + vt[2] * vt[2]).sqrt();
                            let cut = if vtn > 0.0 {
                                (w.def.friction * (-vn) / vtn).min(1.0)
                            } else {
                                0.0
                            };
                            for i in 0..3 {
                                dv[i] = -vn * nrm[i] - cut * vt[i];
                            }
                            c.sticking = cut >= 1.0;
                        }
                        for i in 0..3 {
                            u[3 * n + i] -= wp.gap * nrm[i];
                            v[3 * n + i] += dv[i];
                            c.force[i] = m[3 * n + i] * dv[i] / h;
                        }
                        c.normal_force =
                            c.force[0] * nrm[0] + c.force[1] * nrm[1] + c.force[2] * nrm[2];
                        c.gap = 0.0;
                        c.active = true;
                    }
                }
                w.x_new[j] = [
                    coords[n][0] + u[3 * n],
                    coords[n][1] + u[3 * n + 1],
                    coords[n][2] + u[3 * n + 2],
                ];
                w.last[j] = c;
            }
        }
    }

    /// Persistency of contact in implicit dynamics (Laursen & Chawla 1997): for each node
    /// in contact at the last evaluation (active, pressed: normal force > 0), the normal
    /// component of its velocity relative to the wall is set to zero and its normal
    /// acceleration to the wall's (zero for walls moving at constant speed). The impact's
    /// normal kinetic energy of these nodes is dissipated, as in a perfectly inelastic
    /// node-wall impact.
    pub fn persistency(&self, v: &mut [f64], a: &mut [f64], t: f64, h: f64) {
        for w in &self.walls {
            let (pose, pose_old) = (w.def.motion.pose(t), w.def.motion.pose(t - h));
            for (j, &n) in w.def.nodes.iter().enumerate() {
                let c = &w.last[j];
                if !(c.active && c.normal_force > 0.0) {
                    continue;
                }
                let Some(nrm) = w.n_new[j] else { continue };
                let x = w.x_new[j];
                let before = pose_old.to_global(pose.to_local(x));
                let vn: f64 = (0..3)
                    .map(|i| (v[3 * n + i] - (x[i] - before[i]) / h) * nrm[i])
                    .sum();
                let an: f64 = (0..3).map(|i| a[3 * n + i] * nrm[i]).sum();
                for i in 0..3 {
                    v[3 * n + i] -= vn * nrm[i];
                    a[3 * n + i] -= an * nrm[i];
                }
            }
        }
    }

    /// The last evaluation becomes the start of the next step.
    pub fn commit(&mut self) {
        self.t_old = self.t_new;
        for w in &mut self.walls {
            w.x_old.copy_from_slice(&w.x_new);
            w.ft_old.copy_from_slice(&w.ft_new);
            w.n_old.copy_from_slice(&w.n_new);
        }
    }

    /// Forces and moments on the walls (about each wall's current origin), the walls'
    /// prescribed displacements, the largest penetration and active/sticking counts at
    /// the last evaluation. Collective (one reduction).
    pub fn report(&self, comm: &dyn Comm, n_walls_global: usize) -> ContactReport {
        let t = self.t_new;
        let mut s = vec![0.0; 6 * n_walls_global + 2];
        let mut pen = [0.0f64];
        for (wi, w) in self.walls.iter().enumerate() {
            let c = w.def.motion.pose(t).origin;
            for (j, nc) in w.last.iter().enumerate() {
                let on_wall = [-nc.force[0], -nc.force[1], -nc.force[2]];
                let x = w.x_new[j];
                let m = cross([x[0] - c[0], x[1] - c[1], x[2] - c[2]], on_wall);
                for i in 0..3 {
                    s[6 * wi + i] += on_wall[i];
                    s[6 * wi + 3 + i] += m[i];
                }
                if nc.active {
                    s[6 * n_walls_global] += 1.0;
                }
                if nc.sticking {
                    s[6 * n_walls_global + 1] += 1.0;
                }
                if nc.gap < 0.0 {
                    pen[0] = pen[0].max(-nc.gap);
                }
            }
        }
        comm.allreduce_sum(&mut s);
        comm.allreduce_max(&mut pen);
        let walls = (0..n_walls_global)
            .map(|wi| WallReport {
                force: [s[6 * wi], s[6 * wi + 1], s[6 * wi + 2]],
                moment: [s[6 * wi + 3], s[6 * wi + 4], s[6 * wi + 5]],
                displacement: self
                    .walls
                    .get(wi)
                    .map(|w| w.def.motion.displacement(t))
                    .unwrap_or_default(),
            })
            .collect();
        ContactReport {
            walls,
            max_penetration: pen[0],
            active: s[6 * n_walls_global] as usize,
            sticking: s[6 * n_walls_global + 1] as usize,
        }
    }
}

impl Contact {
    /// Gap, pressure, force and multipliers of the first `n_owned` local nodes at the
    /// last evaluation (local, no communication).
    pub fn nodal_fields(&self, n_owned: usize) -> ContactFields {
        let mut f = ContactFields {
            gap: vec![f64::NAN; n_owned],
            pressure: vec![0.0; n_owned],
            force: vec![0.0; 3 * n_owned],
            lambda: vec![0.0; 3 * n_owned],
        };
        let mut has_lambda = vec![false; n_owned];
        for w in &self.walls {
            for (j, (&n, c)) in w.def.nodes.iter().zip(&w.last).enumerate() {
                if n >= n_owned {
                    continue;
                }
                if !c.gap.is_nan() && (f.gap[n].is_nan() || c.gap < f.gap[n]) {
                    f.gap[n] = c.gap;
                }
                let area = w.def.areas.get(j).copied().unwrap_or(0.0);
                if area > 0.0 {
                    f.pressure[n] += c.normal_force / area;
                }
                for i in 0..3 {
                    f.force[3 * n + i] += c.force[i];
                }
                if w.mult_offset.is_some() && !has_lambda[n] {
                    has_lambda[n] = true;
                    f.lambda[3 * n..3 * n + 3].copy_from_slice(&c.lambda);
                }
            }
        }
        f
    }
}

fn flat(a: [[f64; 3]; 3]) -> [f64; 9] {
    [
        a[0][0], a[0][1], a[0][2], a[1][0], a[1][1], a[1][2], a[2][0], a[2][1], a[2][2],
    ]
}
