//! Prescribed rigid motion of a wall: a placement (origin and axes at t = 0) moved by a
//! translation d(t) and a rotation θ(t) about a fixed global axis through the wall's
//! current origin, each given as a displacement or as a velocity (integrated exactly:
//! curves are piecewise linear).

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
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum MotionKind {
    #[default]
    Displacement,
    Velocity,
}

/// d(t) = value · c(t) (displacement) or value · ∫₀ᵗ c (velocity).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Translation {
    pub kind: MotionKind,
    pub value: [f64; 3],
    pub curve: Curve,
}

/// θ(t) = angle · c(t) or angle · ∫₀ᵗ c, right-hand rule about the unit `axis`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Rotation {
    pub kind: MotionKind,
    pub axis: [f64; 3],
    pub angle: f64,
    pub curve: Curve,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RigidMotion {
    pub origin: [f64; 3],
    /// Local axes at t = 0 (columns of R₀), orthonormal and right-handed.
    pub axes: [[f64; 3]; 3],
    pub translation: Option<Translation>,
    pub rotation: Option<Rotation>,
}

fn scale(kind: MotionKind, c: &Curve, t: f64) -> f64 {
    match kind {
        MotionKind::Displacement => c.eval(t),
        MotionKind::Velocity => c.integral(t),
    }
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

impl RigidMotion {
    /// The prescribed translation d(t) of the wall's origin.
    pub fn displacement(&self, t: f64) -> [f64; 3] {
        match &self.translation {
            Some(tr) => {
                let s = scale(tr.kind, &tr.curve, t);
                [tr.value[0] * s, tr.value[1] * s, tr.value[2] * s]
            }
            None => [0.0; 3],
        }
    }
    pub fn pose(&self, t: f64) -> Pose {
        let d = self.displacement(t);
        let origin = [
            self.origin[0] + d[0],
            self.origin[1] + d[1],
            self.origin[2] + d[2],
        ];
        let mut r = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                r[i][j] = self.axes[j][i];
            }
        }
        if let Some(rot) = &self.rotation {
            let q = rotation_matrix(rot.axis, rot.angle * scale(rot.kind, &rot.curve, t));
            let mut rr = [[0.0; 3]; 3];
            for i in 0..3 {
                for j in 0..3 {
                    for k in 0..3 {
                        rr[i][j] += q[i][k] * r[k][j];
                    }
                }
            }
            r = rr;
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
            translation: Some(Translation {
                kind: MotionKind::Velocity,
                value: [0.0, 0.0, -2.0],
                curve: Curve {
                    points: vec![[0.0, 1.0], [10.0, 1.0]],
                },
            }),
            rotation: Some(Rotation {
                kind: MotionKind::Displacement,
                axis: [0.0, 0.0, 1.0],
                angle: std::f64::consts::FRAC_PI_2,
                curve: Curve::ramp(1.0),
            }),
        };
        let p = m.pose(1.0);
        let x = p.to_global([1.0, 0.0, 0.0]);
        assert!((x[0] - 1.0).abs() < 1e-14 && (x[1] - 1.0).abs() < 1e-14);
        assert!((x[2] + 2.0).abs() < 1e-14);
        let back = p.to_local(x);
        assert!((back[0] - 1.0).abs() < 1e-14 && back[1].abs() < 1e-14);
    }
}
