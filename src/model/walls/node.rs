//! One wall on one rank: its owned tracked nodes, their contact state (stick/slip
//! history, augmentation, penalty's elastic slip), and the node-by-node evaluation of
//! the ALM or penalty law with its residual rows and generalized Jacobian blocks.

// Index loops over 3×3 frames read like the formulas.
#![allow(clippy::needless_range_loop)]

use super::def::WallDef;
use crate::contact::law::{alm_law, AlmLaw, Branch, Decision};
use crate::contact::motion::Pose;
use crate::contact::penalty::{penalty, PenaltyLaw, SLIP_TOLERANCE};
use crate::contact::shape::Shape;
use crate::contact::wall::{project, ContactMethod};
use crate::model::body::Body;

/// Jacobian-only regularization of the multiplier rows (relative to κ).
const JACOBIAN_REG: f64 = 1e-8;
/// How far outside the cone a locked node's trial force may lie before it slips.
pub const LOCK_MARGIN: f64 = 0.02;

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
    /// The ALM law's branch.
    pub branch: Branch,
    /// ‖q‖/s − 1 of the ALM law (−∞ without a threshold).
    pub cone_excess: f64,
}

/// Stick/slip switches of one node within a step from which a failed step is reported as
/// stick/slip cycling.
pub const CYCLING_FLIPS: u32 = 4;

/// The cut on a cycling node's stick stiffness (ALM: its tangential augmentation α;
/// penalty: μ f_N / δ) after a failed attempt, and its floor (two cuts).
pub(super) const STICK_CUT: f64 = 0.3;
pub(super) const STICK_FLOOR: f64 = 0.09;

/// After a failed attempt: each node that switched between stick and slip at least
/// [`CYCLING_FLIPS`] times gets its stick factor × [`STICK_CUT`], down to
/// [`STICK_FLOOR`], and its carried elastic slip (penalty's; zero under ALM) grows by
/// the inverse, so its stick force μ f_N (s/δ) e at the start of the step is unchanged:
/// the retry starts from the converged state's equilibrium, only the further slip meets
/// the softer spring. (Softening the spring alone dropped every softened sticking node's
/// force by 70 % at once; on `rubber-indent` with penalty the retries then started 6 %
/// out of balance whatever the step, and more nodes cycled after each cut.) Returns
/// whether any factor changed.
pub fn soften_cycling(flips: &[u32], stick_scale: &mut [f64], slip_old: &mut [[f64; 3]]) -> bool {
    let mut changed = false;
    for ((f, s), e) in flips.iter().zip(stick_scale.iter_mut()).zip(slip_old) {
        if *f >= CYCLING_FLIPS && *s > STICK_FLOOR {
            let soft = (*s * STICK_CUT).max(STICK_FLOOR);
            e.iter_mut().for_each(|x| *x *= *s / soft);
            *s = soft;
            changed = true;
        }
    }
    changed
}

/// One wall on this rank (its owned tracked nodes).
#[derive(Debug)]
pub struct Wall {
    pub def: WallDef,
    pub shape: Box<dyn Shape>,
    /// Local block of the first multiplier (ALM), else None.
    pub(super) mult: Option<usize>,
    /// κ of each tracked node (force per length), ALM's scale.
    pub kappa: Vec<f64>,
    /// The diagonal stiffness of each tracked node (the penalty's base).
    pub k_node: Vec<f64>,
    /// Start time of the step (committed) and the time of the last evaluation.
    pub(super) t_old: f64,
    pub(super) t_new: f64,
    /// Explicit runs enforce ALM walls kinematically: the residual pass is skipped.
    pub(super) explicit: bool,
    /// Node positions at the start of the step (committed) and at the last evaluation.
    pub(super) x_old: Vec<[f64; 3]>,
    pub(super) x_new: Vec<[f64; 3]>,
    /// Outward normal of each node's projection at the start of the step (the hint that
    /// keeps a penetrating node on the face it came through) and at the last evaluation.
    pub(super) n_old: Vec<Option<[f64; 3]>>,
    pub(super) n_new: Vec<Option<[f64; 3]>>,
    /// Penalty's elastic slip carried over steps (global vector, see
    /// [`crate::contact::penalty`]).
    pub(super) slip_old: Vec<[f64; 3]>,
    pub(super) slip_new: Vec<[f64; 3]>,
    pub last: Vec<NodeContact>,
    /// Stick/slip flips of each node since the last commit.
    pub(super) flips: Vec<u32>,
    /// Each node's factor on its stick stiffness (ALM: the tangential augmentation α;
    /// penalty: μ f_N / δ): 1, lowered for a node that cycled between stick and slip in
    /// a failed attempt (see
    /// [`crate::model::contribution::Recovery::after_failed_attempt`]), and kept for the
    /// rest of the run.
    pub(super) stick_scale: Vec<f64>,
    /// A contact entity's body.
    pub body: Option<Body>,
}

/// Local residual and Jacobian blocks of one tracked node.
pub(super) struct NodeEval {
    pub(super) c: NodeContact,
    /// r_node contribution (minus the force on the node).
    pub(super) r_node: [f64; 3],
    /// r_λ rows (ALM).
    pub(super) r_mult: [f64; 3],
    pub(super) k_xx: [[f64; 3]; 3],
    pub(super) k_xl: [[f64; 3]; 3],
    pub(super) k_lx: [[f64; 3]; 3],
    pub(super) k_ll: [[f64; 3]; 3],
    /// Penalty: the elastic slip at this evaluation (global).
    pub(super) slip_new: [f64; 3],
    pub(super) normal: Option<[f64; 3]>,
    /// The node's projection on the wall.
    pub(super) point: Option<[f64; 3]>,
    /// ∂point/∂x = I − n nᵀ − g H: how the closest point follows the node.
    pub(super) dpoint: [[f64; 3]; 3],
}

impl Wall {
    pub fn new(def: WallDef, coords: &[[f64; 3]], rank: usize) -> Self {
        let n = def.nodes.len();
        let body = def.body.clone().map(|b| Body::new(b, rank, &def.motion));
        let x0: Vec<[f64; 3]> = def.nodes.iter().map(|&i| coords[i]).collect();
        Self {
            shape: def.shape.build(),
            mult: None,
            kappa: vec![def.kappa.unwrap_or(1.0); n],
            k_node: vec![1.0; n],
            t_old: 0.0,
            t_new: 0.0,
            explicit: false,
            x_old: x0.clone(),
            x_new: x0,
            n_old: vec![None; n],
            n_new: vec![None; n],
            slip_old: vec![[0.0; 3]; n],
            slip_new: vec![[0.0; 3]; n],
            last: vec![NodeContact::default(); n],
            flips: vec![0; n],
            stick_scale: vec![1.0; n],
            body,
            def,
        }
    }

    /// The pose of the last evaluation (after a commit: the converged one).
    pub(super) fn pose_now(&self) -> Pose {
        match &self.body {
            Some(b) => b.pose_new(),
            None => self.def.motion.pose(self.t_new),
        }
    }

    pub(super) fn is_alm(&self) -> bool {
        self.def.method == ContactMethod::Alm
    }

    /// An ALM wall with friction: its sticking nodes have a cone to stay inside.
    pub(super) fn has_cone(&self) -> bool {
        self.is_alm() && self.def.friction > 0.0
    }

    /// The ALM law of this wall at node `j`.
    pub(super) fn law(&self, j: usize) -> AlmLaw {
        AlmLaw {
            mu: self.def.friction,
            alpha: self.def.tangential_augmentation * self.stick_scale[j],
            threshold: self.def.friction_threshold,
        }
    }

    /// How node `j`'s stick/slip case is chosen: on its last branch in a frozen
    /// evaluation, locked after too many flips.
    pub(super) fn decision(&self, j: usize, frozen: bool) -> Decision {
        if frozen {
            Decision::Forced(self.last[j].branch)
        } else if self.def.stick_lock_flips > 0 && self.flips[j] >= self.def.stick_lock_flips {
            Decision::Locked {
                margin: LOCK_MARGIN,
            }
        } else {
            Decision::Natural
        }
    }

    /// One tracked node placed at `pose` (`pose_old` at the step's start).
    pub(super) fn node(
        &self,
        j: usize,
        x: [f64; 3],
        lam: [f64; 3],
        pose: &Pose,
        pose_old: &Pose,
        decision: Decision,
    ) -> NodeEval {
        let mut e = NodeEval {
            c: NodeContact {
                gap: f64::NAN,
                lambda: lam,
                cone_excess: f64::NEG_INFINITY,
                ..NodeContact::default()
            },
            r_node: [0.0; 3],
            r_mult: [0.0; 3],
            k_xx: [[0.0; 3]; 3],
            k_xl: [[0.0; 3]; 3],
            k_lx: [[0.0; 3]; 3],
            k_ll: [[0.0; 3]; 3],
            slip_new: [0.0; 3],
            normal: None,
            point: None,
            dpoint: [[0.0; 3]; 3],
        };
        let kappa = self.kappa[j];
        let alm_wall = self.is_alm();
        let Some(wp) = project(self.shape.as_ref(), pose, pose_old, x, self.n_old[j]) else {
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
        let xo = self.x_old[j];
        // Slip over the step, on the tangent plane: t·(wall point's old position − x_old)
        // (t·(x − point) = 0), docs/src/design.md "g_T".
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
        e.point = Some(wp.point);
        let nv = [p[0][0], p[1][0], p[2][0]];
        e.dpoint = std::array::from_fn(|i| {
            std::array::from_fn(|k| {
                let id = if i == k { 1.0 } else { 0.0 };
                id - nv[i] * nv[k] - wp.gap * wp.hessian[i][k]
            })
        });
        // f_local (force on the node in the frame), ∂f_local/∂g, and for ALM ∂f/∂λ.
        let (fl, dfdg) = if alm_wall {
            self.alm_local(j, g, lam, decision, &mut e)
        } else {
            self.penalty_local(j, g, &p, [pose, pose_old], decision, &mut e)
        };
        node_rows(&mut e, &p, fl, &dfdg, &wp.hessian, alm_wall);
        e
    }

    /// The ALM law at node `j` for the gaps `g`: the local force and ∂f/∂g; fills the
    /// node's state, its multiplier rows and (in the frame) ∂f/∂λ in `e.k_xl`.
    fn alm_local(
        &self,
        j: usize,
        g: [f64; 3],
        lam: [f64; 3],
        decision: Decision,
        e: &mut NodeEval,
    ) -> ([f64; 3], [[f64; 3]; 3]) {
        let kappa = self.kappa[j];
        let pt = alm_law(g, lam, &self.law(j), decision);
        e.c.active = pt.active;
        e.c.sticking = pt.sticking;
        e.c.branch = pt.branch;
        e.c.cone_excess = pt.cone_excess;
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
                e.k_ll[i][k] = -kappa * (pt.dh_dl[i][k] + if i == k { JACOBIAN_REG } else { 0.0 });
                // ∂(κ(λ − h))/∂λ in the frame; mapped to global rows below.
                e.k_xl[i][k] = kappa * (id - pt.dh_dl[i][k]);
            }
        }
        (fl, dfdg)
    }

    /// The penalty law of this wall at node `j`: k_N from the node's stiffness, the
    /// allowable elastic slip from the tracked faces' size, the node's stick softening.
    pub(super) fn penalty_law(&self, j: usize) -> PenaltyLaw {
        PenaltyLaw {
            kn: self.def.penalty_scale * self.k_node[j],
            mu: self.def.friction,
            slip: SLIP_TOLERANCE * self.def.face_size,
            stick_scale: self.stick_scale[j],
        }
    }

    /// The penalty law at node `j` for the gaps `g` in the frame `p`: the local force and
    /// ∂f/∂g; fills the node's state and its elastic slip.
    fn penalty_local(
        &self,
        j: usize,
        g: [f64; 3],
        p: &[[f64; 3]; 3],
        [pose, pose_old]: [&Pose; 2],
        decision: Decision,
        e: &mut NodeEval,
    ) -> ([f64; 3], [[f64; 3]; 3]) {
        // The elastic slip carried from the last step turns with the wall (or body) over
        // the step: R Rₙᵀ e (objective; the entity coupling's Jacobian assumes it).
        let e0 = self.slip_old[j];
        let eo: [f64; 3] = std::array::from_fn(|i| {
            (0..3)
                .map(|k| (0..3).map(|l| pose.r[i][l] * pose_old.r[k][l]).sum::<f64>() * e0[k])
                .sum()
        });
        let t1 = [p[0][1], p[1][1], p[2][1]];
        let t2 = [p[0][2], p[1][2], p[2][2]];
        let eo_l = [
            t1[0] * eo[0] + t1[1] * eo[1] + t1[2] * eo[2],
            t2[0] * eo[0] + t2[1] * eo[1] + t2[2] * eo[2],
        ];
        let pt = penalty(g, eo_l, &self.penalty_law(j), decision);
        e.c.active = pt.active;
        e.c.sticking = pt.sticking;
        e.c.branch = pt.branch;
        let es = pt.elastic_slip;
        for i in 0..3 {
            e.slip_new[i] = t1[i] * es[0] + t2[i] * es[1];
        }
        (pt.f, pt.df_dg)
    }
}

/// A node's global rows from its local force `fl` and ∂f/∂g in the frame `p` (`hessian`
/// the wall's curvature at the projection): the force, ∂r_node/∂x and, for ALM, the
/// node–multiplier blocks (from ∂f/∂λ in the frame, left in `e.k_xl` by the law).
fn node_rows(
    e: &mut NodeEval,
    p: &[[f64; 3]; 3],
    fl: [f64; 3],
    dfdg: &[[f64; 3]; 3],
    hessian: &[[f64; 3]; 3],
    alm_wall: bool,
) {
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
            e.k_xx[i][k] = -s - fl[0] * hessian[i][k];
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
}
