//! The rigid body of a contact entity (the paper's §3.5–3.6, LS-DYNA `*CONTACT_ENTITY`):
//! a wall whose pose is not a prescribed function of time but six global unknowns, the
//! translation U of its reference point (the wall's origin) and its rotation, each
//! prescribed by the wall's motion curves or free (optionally loaded by a force or a
//! moment curve). The contact forces of its tracked nodes and their moments about the
//! reference point enter the body's equilibrium rows.
//!
//! **Rotations** are incremental: the unknowns hold Θ = L ψ (L the shape's size, so
//! every unknown is a length and every row a force, as JFNK's finite-difference step
//! and the block scaling assume), and the pose is R = exp([ψ − ψₙ]) Rₙ with ψₙ, Rₙ the
//! committed values of the last converged step (Simo & Vu-Quoc's update on SO(3)): the
//! increment within a step is small whatever the accumulated rotation, so rolling many
//! turns has no singularity. ψ is the accumulated incremental rotation vector; for a
//! rotation about one fixed axis it is the rotation vector itself, and a prescribed
//! rotation DOF prescribes ψ.
//!
//! **Coupling** (node j at x with the force f on it, r = x − c, c the reference point's
//! position): the contact law sees the body's motion as the opposite motion of the node,
//! δx_eq = δx − δU − δθ × r, and its frame turns with the body (δf gains δθ × f), so
//! with B = [−I, [r]ₓ] the node's force depends on the body through
//! ∂r_node/∂q = K_xx B + [0, [f]ₓ]; the body's rows are r_q = Σ [f; r_c × f] (minus the
//! applied load) with r_c the lever arm of the contact point, which follows the node
//! through the projection's derivative I − n nᵀ − g H. (r and r_c differ by the gap:
//! zero at a converged ALM contact, the penetration for penalty.) The rotation columns
//! carry the tangent of the exponential map, δθ = T(ψ − ψₙ) δψ.

// Index loops over 3×3 frames read like the formulas.
#![allow(clippy::needless_range_loop)]

use super::contribution::Evaluation;
use super::dofs::DofMap;
use crate::contact::motion::{exp_map, Pose, RigidMotion};
use crate::curve::Curve;
use serde::{Deserialize, Serialize};

/// Jacobian-only stiffness on free DOFs (relative to the model's mean nodal stiffness):
/// keeps the matrix regular while a free body touches nothing, or nothing resists a
/// DOF (a frictionless sphere's rotation). The residual stays exact.
const JACOBIAN_REG: f64 = 1e-8;

/// What the deck says about a contact entity's body.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct BodyDef {
    /// Which of ux, uy, uz, rx, ry, rz are free; the others follow the wall's motion.
    pub free: [bool; 6],
    /// Load on a free DOF: scale × curve(t), a force or a moment about the reference
    /// point.
    pub loads: [Option<(f64, Curve)>; 6],
    /// L of Θ = L ψ.
    pub length: f64,
    /// Body-fixed points traced in the history: name and reference position.
    pub trace: Vec<(String, [f64; 3])>,
    /// Dynamics: mass of the translations and moment of inertia J about the reference
    /// point (isotropic: a sphere's 2/5 m R², see [`Body::masses`]); 0 leaves those
    /// DOFs algebraic (massless).
    pub mass: f64,
    pub inertia: f64,
    /// Dynamics: initial velocity of the reference point and angular velocity.
    pub velocity: [f64; 3],
    pub spin: [f64; 3],
    /// The rank that owns the six unknowns (set when localized).
    pub owner: usize,
}

use super::mat3::{add, cross, flat, mul, skew, ID, M3};

/// The tangent of the exponential map (SO(3)'s left Jacobian): δ(exp[φ]) exp[φ]ᵀ =
/// [T(φ) δφ]ₓ, T = I + (1 − cos φ)/φ² [φ]ₓ + (φ − sin φ)/φ³ [φ]ₓ².
pub fn exp_tangent(phi: [f64; 3]) -> M3 {
    let a = (phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2]).sqrt();
    let s = skew(phi);
    let (c1, c2) = if a < 1e-4 {
        (0.5 - a * a / 24.0, 1.0 / 6.0 - a * a / 120.0)
    } else {
        ((1.0 - a.cos()) / (a * a), (a - a.sin()) / (a * a * a))
    };
    add(&add(&ID, &s, c1), &mul(&s, &s), c2)
}

/// A contact entity's body on one rank (every rank reads its unknowns).
#[derive(Debug)]
pub struct Body {
    pub def: BodyDef,
    owner: bool,
    kappa: f64,
    /// Global blocks of U and Θ, and their local blocks.
    global: [usize; 2],
    local: [usize; 2],
    /// Placement at t = 0.
    origin: [f64; 3],
    axes: M3,
    /// Committed (ψₙ, Rₙ) and those of the last evaluation.
    psi_old: [f64; 3],
    q_old: M3,
    u_old: [f64; 3],
    psi_new: [f64; 3],
    q_new: M3,
    u_new: [f64; 3],
}

/// What a tracked node's contact gives its body: the node's position, the contact
/// point on the body and its derivative by the node's position relative to the body
/// (I − n nᵀ − g H), and the force on the node.
pub struct Contact {
    pub node: [f64; 3],
    pub point: [f64; 3],
    pub dpoint: M3,
    pub force: [f64; 3],
}

/// The body's pose at one evaluation, with what the Jacobian needs.
pub struct BodyState {
    pub pose: Pose,
    psi: [f64; 3],
    q: M3,
    u: [f64; 3],
    /// T(ψ − ψₙ) / L: δθ per unit of δΘ.
    dtheta: M3,
}

impl Body {
    pub fn new(def: BodyDef, rank: usize, motion: &RigidMotion) -> Self {
        Self {
            owner: def.owner == rank,
            def,
            kappa: 1.0,
            global: [0; 2],
            local: [0; 2],
            origin: motion.origin,
            axes: motion.axes,
            psi_old: [0.0; 3],
            q_old: ID,
            u_old: [0.0; 3],
            psi_new: [0.0; 3],
            q_new: ID,
            u_new: [0.0; 3],
        }
    }

    pub fn is_owner(&self) -> bool {
        self.owner
    }

    /// Two global blocks, owned by `def.owner`, read everywhere (every rank draws the
    /// body and reports its pose).
    pub fn bind(&mut self, dofs: &DofMap, global_first: usize) {
        for k in 0..2 {
            self.global[k] = global_first + k;
            self.local[k] = dofs
                .local_block(global_first + k)
                .expect("every rank reads a body's unknowns");
        }
    }

    pub fn blocks(&self) -> [usize; 2] {
        self.global
    }

    pub fn set_kappa(&mut self, k: f64) {
        self.kappa = k;
    }

    fn pose_of(&self, u: [f64; 3], q: &M3) -> Pose {
        let r: M3 = std::array::from_fn(|i| {
            std::array::from_fn(|j| (0..3).map(|k| q[i][k] * self.axes[j][k]).sum())
        });
        Pose {
            origin: [
                self.origin[0] + u[0],
                self.origin[1] + u[1],
                self.origin[2] + u[2],
            ],
            r,
        }
    }

    /// The pose at the unknowns `u` (local vector).
    pub fn state(&self, u: &[f64]) -> BodyState {
        let (bu, bt) = (3 * self.local[0], 3 * self.local[1]);
        let l = self.def.length;
        let disp = [u[bu], u[bu + 1], u[bu + 2]];
        let psi = [u[bt] / l, u[bt + 1] / l, u[bt + 2] / l];
        let inc = [
            psi[0] - self.psi_old[0],
            psi[1] - self.psi_old[1],
            psi[2] - self.psi_old[2],
        ];
        let q = mul(&exp_map(inc), &self.q_old);
        let t = exp_tangent(inc);
        BodyState {
            pose: self.pose_of(disp, &q),
            psi,
            q,
            u: disp,
            dtheta: std::array::from_fn(|i| std::array::from_fn(|j| t[i][j] / l)),
        }
    }

    /// The committed pose (the start of the step).
    pub fn pose_old(&self) -> Pose {
        self.pose_of(self.u_old, &self.q_old)
    }

    /// The pose of the last evaluation (after a commit: the converged one).
    pub fn pose_new(&self) -> Pose {
        self.pose_of(self.u_new, &self.q_new)
    }

    /// Translation and accumulated rotation vector of the last evaluation.
    pub fn displacement(&self) -> [f64; 3] {
        self.u_new
    }
    pub fn rotation(&self) -> [f64; 3] {
        self.psi_new
    }

    pub fn remember(&mut self, s: &BodyState) {
        self.psi_new = s.psi;
        self.q_new = s.q;
        self.u_new = s.u;
    }

    pub fn commit(&mut self) {
        self.psi_old = self.psi_new;
        self.q_old = self.q_new;
        self.u_old = self.u_new;
    }

    /// The committed pose (ψ, Q, u: 15 values) for a restart file.
    pub fn saved_state(&self) -> Vec<f64> {
        let mut s = self.psi_old.to_vec();
        s.extend(self.q_old.iter().flatten());
        s.extend(self.u_old);
        s
    }

    /// Take back [`Body::saved_state`]'s 15 values as the committed pose.
    pub fn restore_state(&mut self, s: &[f64]) {
        self.psi_old = [s[0], s[1], s[2]];
        self.q_old = std::array::from_fn(|i| std::array::from_fn(|j| s[3 + 3 * i + j]));
        self.u_old = [s[12], s[13], s[14]];
        self.psi_new = self.psi_old;
        self.q_new = self.q_old;
        self.u_new = self.u_old;
    }

    /// Where a body-fixed point (reference position X) is now.
    pub fn point(&self, x: [f64; 3]) -> [f64; 3] {
        let p0 = self.pose_of([0.0; 3], &ID);
        self.pose_new().to_global(p0.to_local(x))
    }

    /// A tracked node's coupling with the body (`node`, `mult`: its global blocks, mult
    /// for ALM; `k`: its own blocks ∂r_node/∂x, ∂r_node/∂λ, ∂r_λ/∂x). Adds the body's
    /// rows (residual: its share of Σ [f; r_c × f / L], r_c = x_c − c the lever arm of
    /// the contact point) and the node–body and body–body Jacobian blocks.
    pub fn couple(
        &self,
        ev: &mut Evaluation,
        s: &BodyState,
        c: Contact,
        node: usize,
        mult: Option<usize>,
        k: [&M3; 3],
    ) {
        let [k_xx, k_xl, k_lx] = k;
        let l = self.def.length;
        let o = s.pose.origin;
        let f = c.force;
        let rc = [c.point[0] - o[0], c.point[1] - o[1], c.point[2] - o[2]];
        if let Some((_, f_ext)) = ev.forces.as_mut() {
            let m = cross(rc, f);
            let (bu, bt) = (3 * self.local[0], 3 * self.local[1]);
            for i in 0..3 {
                f_ext[bu + i] -= f[i];
                f_ext[bt + i] -= m[i] / l;
            }
        }
        let Some(jac) = ev.jacobian.as_deref_mut() else {
            return;
        };
        let [gu, gt] = self.global;
        // The node moves relative to the body by δx − δU − δθ × r_x (r_x = x − c, its own
        // lever arm); the contact point by D that motion plus the body's own (D = ∂p/∂x,
        // the projection's derivative), so δr_c = D (δx − δU) + (D [r_x]ₓ − [r_c]ₓ) δθ.
        // r_x and r_c differ by the gap along n: a penalty contact's penetration.
        let rx = [c.node[0] - o[0], c.node[1] - o[1], c.node[2] - o[2]];
        let (sr, sx, sf) = (skew(rc), skew(rx), skew(f));
        let d = &c.dpoint;
        let tt = &s.dtheta;
        // ∂r_node/∂U = −K_xx; ∂r_node/∂θ = K_xx [r_x]ₓ + [f]ₓ (the frame turns with the
        // body, so a rigid motion of node and body together turns f with them; on a
        // curved shape K_xx leaves out the tangents' turning with x, as for walls).
        let g_th = add(&mul(k_xx, &sx), &sf, 1.0);
        let g_t = mul(&g_th, tt);
        jac.add_block(node, gu, &flat(k_xx, -1.0));
        jac.add_block(node, gt, &flat(&g_t, 1.0));
        if let Some(m) = mult {
            jac.add_block(m, gu, &flat(k_lx, -1.0));
            jac.add_block(m, gt, &flat(&mul(&mul(k_lx, &sx), tt), 1.0));
            jac.add_block(gu, m, &flat(k_xl, -1.0));
            jac.add_block(gt, m, &flat(&mul(&sr, k_xl), -1.0 / l));
        }
        // U rows: r_U = Σ f = −Σ r_node.
        jac.add_block(gu, node, &flat(k_xx, -1.0));
        jac.add_block(gu, gu, &flat(k_xx, 1.0));
        jac.add_block(gu, gt, &flat(&g_t, -1.0));
        // Θ rows: r_Θ = Σ r_c × f / L; δ(r_c × f) = −[f]ₓ δr_c − [r_c]ₓ δr_node.
        let a = add(&mul(&sf, d), &mul(&sr, k_xx), 1.0);
        jac.add_block(gt, node, &flat(&a, -1.0 / l));
        jac.add_block(gt, gu, &flat(&a, 1.0 / l));
        let d_rc = add(&mul(d, &sx), &sr, -1.0);
        let b = add(&mul(&sf, &d_rc), &mul(&sr, &g_th), 1.0);
        jac.add_block(gt, gt, &flat(&mul(&b, tt), -1.0 / l));
    }

    /// The owner's own rows: the loads on free DOFs, and the Jacobian-only stiffness of
    /// free DOFs.
    pub fn own_rows(&self, ev: &mut Evaluation) {
        if !self.owner {
            return;
        }
        let l = self.def.length;
        if let Some((_, f_ext)) = ev.forces.as_mut() {
            for (k, load) in self.def.loads.iter().enumerate() {
                if let Some((v, c)) = load {
                    let b = 3 * self.local[k / 3] + k % 3;
                    f_ext[b] += v * c.eval(ev.t) / if k < 3 { 1.0 } else { l };
                }
            }
        }
        if let Some(m) = ev.jacobian.as_deref_mut() {
            for h in 0..2 {
                let d: M3 = std::array::from_fn(|i| {
                    std::array::from_fn(|j| {
                        if i == j && self.def.free[3 * h + i] {
                            JACOBIAN_REG * self.kappa
                        } else {
                            0.0
                        }
                    })
                });
                m.add_block(self.global[h], self.global[h], &flat(&d, 1.0));
            }
        }
    }

    /// Dynamics, on the owner: the body's diagonal mass, m on U and J / L² on Θ = L ψ
    /// (its rows are moments / L). Euler's equations J ω̇ + ω × J ω = M, with ψ̇ = ω
    /// (ψ accumulates spatial rotation increments): the gyroscopic term vanishes for an
    /// isotropic J, which is why J is one number here.
    pub fn masses(&self, dofs: &DofMap) -> Vec<(usize, f64)> {
        self.owned_values(dofs, |k| {
            let l = self.def.length;
            if k < 3 {
                self.def.mass
            } else {
                self.def.inertia / (l * l)
            }
        })
    }

    /// Dynamics, on the owner: U̇ = v₀ and Θ̇ = L ω₀.
    pub fn initial_velocities(&self, dofs: &DofMap) -> Vec<(usize, f64)> {
        self.owned_values(dofs, |k| {
            if k < 3 {
                self.def.velocity[k]
            } else {
                self.def.length * self.def.spin[k - 3]
            }
        })
    }

    /// (owned index, value) of the six DOFs with a nonzero value, on the owner.
    fn owned_values(&self, dofs: &DofMap, value: impl Fn(usize) -> f64) -> Vec<(usize, f64)> {
        if !self.owner {
            return Vec::new();
        }
        (0..6)
            .filter(|&k| value(k) != 0.0)
            .map(|k| {
                let i = dofs
                    .owned_index(3 * self.local[k / 3] + k % 3)
                    .expect("the owner owns its unknowns");
                (i, value(k))
            })
            .collect()
    }

    /// The pattern of a tracked node's coupling (`node`, `mult` global blocks).
    pub fn pattern(&self, node: usize, mult: Option<usize>, out: &mut Vec<(usize, usize)>) {
        let [gu, gt] = self.global;
        for b in [gu, gt] {
            out.extend_from_slice(&[(node, b), (b, node)]);
            if let Some(m) = mult {
                out.extend_from_slice(&[(m, b), (b, m)]);
            }
        }
    }

    /// The body–body blocks: on the owner (its own rows), and on every rank with tracked
    /// nodes (their coupling adds to them; sent to the owner).
    pub fn own_pattern(&self, has_nodes: bool, out: &mut Vec<(usize, usize)>) {
        if self.owner || has_nodes {
            let [gu, gt] = self.global;
            out.extend_from_slice(&[(gu, gu), (gu, gt), (gt, gu), (gt, gt)]);
        }
    }

    /// The prescribed DOFs at t, on the owner: U = d(t), Θ = L θ(t).
    pub fn prescribed(
        &self,
        motion: &RigidMotion,
        t: f64,
        dofs: &DofMap,
        out: &mut Vec<(usize, f64)>,
    ) {
        if !self.owner {
            return;
        }
        let (d, th) = (motion.displacement(t), motion.rotation(t));
        for k in 0..6 {
            if self.def.free[k] {
                continue;
            }
            let value = if k < 3 {
                d[k]
            } else {
                self.def.length * th[k - 3]
            };
            let i = dofs
                .owned_index(3 * self.local[k / 3] + k % 3)
                .expect("the owner owns its unknowns");
            out.push((i, value));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// T(φ) is the derivative of exp: exp[φ + ε e] exp[φ]ᵀ ≈ I + ε [T e]ₓ.
    #[test]
    fn exp_tangent_is_the_derivative_of_the_exponential_map() {
        for phi in [[0.3, -0.4, 1.2], [1e-6, 2e-6, 0.0], [2.0, 1.0, -2.5]] {
            let t = exp_tangent(phi);
            let q0 = exp_map(phi);
            for e in 0..3 {
                let eps = 1e-6;
                let mut pp = phi;
                pp[e] += eps;
                let mut pm = phi;
                pm[e] -= eps;
                let (qp, qm) = (exp_map(pp), exp_map(pm));
                // (Q₊ − Q₋)/2ε · Q₀ᵀ = [T e]ₓ.
                let d: M3 = std::array::from_fn(|i| {
                    std::array::from_fn(|j| {
                        (0..3)
                            .map(|k| (qp[i][k] - qm[i][k]) / (2.0 * eps) * q0[j][k])
                            .sum()
                    })
                });
                let w = [d[2][1], d[0][2], d[1][0]];
                for i in 0..3 {
                    assert!((w[i] - t[i][e]).abs() < 1e-8, "{phi:?} {e}: {w:?}");
                }
            }
        }
    }
}
