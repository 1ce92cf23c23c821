//! Prescribed rigid motion of a wall: a placement (origin and axes at t = 0) moved per
//! degree of freedom, a translation d(t) of the origin and a rotation vector θ(t) about
//! it, each component a curve given as a displacement or as a velocity.

// Index loops over 3×3 frames read like the formulas.
#![allow(clippy::needless_range_loop)]

use crate::curve::Curve;
use serde::{Deserialize, Serialize};

/// x_global = origin + R x_local.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    pub origin: [f64; 3],
    /// Columns are the local axes in global coordinates.
    pub r: [[f64; 3]; 3],
}

impl Pose {
    pub fn to_global(&self, x: [f64; 3]) -> [f64; 3] {
        let mut y = self.origin;
        for i in 0..3 {
            for j in 0..3 {
                y[i] += self.r[i][j] * x[j];
            }
        }
        y
    }
    pub fn to_local(&self, x: [f64; 3]) -> [f64; 3] {
        let d = [
            x[0] - self.origin[0],
            x[1] - self.origin[1],
            x[2] - self.origin[2],
        ];
        let mut y = [0.0; 3];
        for j in 0..3 {
            for i in 0..3 {
                y[j] += self.r[i][j] * d[i];
            }
        }
        y
    }
    /// A global direction in local coordinates: Rᵀ v.
    pub fn dir_to_local(&self, v: [f64; 3]) -> [f64; 3] {
        let mut y = [0.0; 3];
        for j in 0..3 {
            for i in 0..3 {
                y[j] += self.r[i][j] * v[i];
            }
        }
        y
    }
    /// A local direction in global coordinates.
    pub fn dir_to_global(&self, v: [f64; 3]) -> [f64; 3] {
        let mut y = [0.0; 3];
        for i in 0..3 {
            for j in 0..3 {
                y[i] += self.r[i][j] * v[j];
            }
        }
        y
    }
    /// A local symmetric tensor in global coordinates: R A Rᵀ.
    pub fn tensor_to_global(&self, a: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
        let mut y = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                for k in 0..3 {
                    for l in 0..3 {
                        y[i][j] += self.r[i][k] * a[k][l] * self.r[j][l];
                    }
                }
            }
        }
        y
    }
}

/// Whether a motion curve gives a displacement (angle) or a velocity (angular velocity).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default, schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum MotionKind {
    #[default]
    Displacement,
    Velocity,
}

/// One prescribed degree of freedom: q(t) = scale · c(t) (displacement) or
/// scale · ∫₀ᵗ c (velocity, integrated exactly: curves are piecewise linear).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DofMotion {
    pub kind: MotionKind,
    pub scale: f64,
    pub curve: Curve,
}

impl DofMotion {
    pub fn value(&self, t: f64) -> f64 {
        self.scale
            * match self.kind {
                MotionKind::Displacement => self.curve.eval(t),
                MotionKind::Velocity => self.curve.integral(t),
            }
    }
}

/// The names of the six rigid-body degrees of freedom, in order.
pub const DOF_NAMES: [&str; 6] = ["ux", "uy", "uz", "rx", "ry", "rz"];

/// A rigid motion given per degree of freedom, as LS-DYNA's
/// `*BOUNDARY_PRESCRIBED_MOTION_RIGID` gives it: the translation (ux, uy, uz) of the
/// reference point `origin` and the rotation vector θ = (rx, ry, rz) (global components,
/// radians) about that moving point, so that x = origin + u(t) + exp([θ(t)]) R₀ X with R₀
/// the initial axes. A DOF without a motion stays at zero. A rotation about one fixed
/// axis (the usual case: a roller, a turning tool) is θ = φ(t) a, and exp([θ]) is
/// Rodrigues' rotation by φ about a; with several components the rotation vector is the
/// total rotation, not a sequence of rotations about the axes.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RigidMotion {
    pub origin: [f64; 3],
    /// Local axes at t = 0 (columns of R₀), orthonormal and right-handed.
    pub axes: [[f64; 3]; 3],
    pub dofs: [Option<DofMotion>; 6],
}

/// Rodrigues' rotation matrix for a unit axis.
pub fn rotation_matrix(axis: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
    let (s, c) = angle.sin_cos();
    let [x, y, z] = axis;
    let t = 1.0 - c;
    [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
    ]
}

/// exp([θ]): the rotation by |θ| about θ/|θ| (the identity for θ = 0).
pub fn exp_map(theta: [f64; 3]) -> [[f64; 3]; 3] {
    let phi = (theta[0] * theta[0] + theta[1] * theta[1] + theta[2] * theta[2]).sqrt();
    if phi == 0.0 {
        return [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    }
    rotation_matrix([theta[0] / phi, theta[1] / phi, theta[2] / phi], phi)
}

impl RigidMotion {
    /// At rest in the placement `origin`, `axes`.
    pub fn fixed(origin: [f64; 3], axes: [[f64; 3]; 3]) -> Self {
        Self {
            origin,
            axes,
            dofs: Default::default(),
        }
    }

    fn dof(&self, i: usize, t: f64) -> f64 {
        self.dofs[i].as_ref().map_or(0.0, |d| d.value(t))
    }

    /// The prescribed translation d(t) of the reference point.
    pub fn displacement(&self, t: f64) -> [f64; 3] {
        [self.dof(0, t), self.dof(1, t), self.dof(2, t)]
    }

    /// The prescribed rotation vector θ(t).
    pub fn rotation(&self, t: f64) -> [f64; 3] {
        [self.dof(3, t), self.dof(4, t), self.dof(5, t)]
    }

    pub fn pose(&self, t: f64) -> Pose {
        let d = self.displacement(t);
        let origin = [
            self.origin[0] + d[0],
            self.origin[1] + d[1],
            self.origin[2] + d[2],
        ];
        let q = exp_map(self.rotation(t));
        let mut r = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                for k in 0..3 {
                    r[i][j] += q[i][k] * self.axes[j][k];
                }
            }
        }
        Pose { origin, r }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pose_moves_and_turns() {
        let m = RigidMotion {
            origin: [1.0, 0.0, 0.0],
            axes: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            dofs: [
                None,
                None,
                Some(DofMotion {
                    kind: MotionKind::Velocity,
                    scale: -2.0,
                    curve: Curve {
                        points: vec![[0.0, 1.0], [10.0, 1.0]],
                    },
                }),
                None,
                None,
                Some(DofMotion {
                    kind: MotionKind::Displacement,
                    scale: std::f64::consts::FRAC_PI_2,
                    curve: Curve::ramp(1.0),
                }),
            ],
        };
        let p = m.pose(1.0);
        let x = p.to_global([1.0, 0.0, 0.0]);
        assert!((x[0] - 1.0).abs() < 1e-14 && (x[1] - 1.0).abs() < 1e-14);
        assert!((x[2] + 2.0).abs() < 1e-14);
        let back = p.to_local(x);
        assert!((back[0] - 1.0).abs() < 1e-14 && back[1].abs() < 1e-14);
    }

    /// exp([θ]) is Rodrigues' rotation by |θ| about θ/|θ|: orthonormal, it fixes θ, and
    /// for θ along z it turns x by |θ|.
    #[test]
    fn exp_map_is_the_rotation_about_the_vector() {
        let theta = [0.3, -0.4, 1.2];
        let q = exp_map(theta);
        for i in 0..3 {
            for j in 0..3 {
                let qtq: f64 = (0..3).map(|k| q[k][i] * q[k][j]).sum();
                assert!((qtq - if i == j { 1.0 } else { 0.0 }).abs() < 1e-14);
            }
            let qt: f64 = (0..3).map(|k| q[i][k] * theta[k]).sum();
            assert!((qt - theta[i]).abs() < 1e-14);
        }
        let z = exp_map([0.0, 0.0, 0.5]);
        assert!((z[0][0] - 0.5f64.cos()).abs() < 1e-15 && (z[1][0] - 0.5f64.sin()).abs() < 1e-15);
        assert_eq!(exp_map([0.0; 3]), rotation_matrix([1.0, 0.0, 0.0], 0.0));
    }
}
