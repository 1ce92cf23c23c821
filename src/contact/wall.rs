//! What a rigid surface is in contact: its shape as a deck names it, the enforcement
//! method, and the projection of a point onto the placed shape (gap, frame, the surface
//! point and where it was at the start of the step).

use super::motion::Pose;
use super::shape::{
    Cylinder, Ellipsoid, FinitePlane, Plane, Prism, Projection, Shape, Sphere, Torus,
};
use serde::{Deserialize, Serialize};

/// The shape of a wall, as a deck names it.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub enum ShapeDef {
    Plane {
        display_size: f64,
        #[serde(default)]
        display_center: [f64; 2],
    },
    FinitePlane {
        lx: f64,
        ly: f64,
    },
    Cylinder {
        radius: f64,
        length: f64,
    },
    Sphere {
        radius: f64,
    },
    Prism {
        size: [f64; 3],
    },
    Ellipsoid {
        radii: [f64; 3],
    },
    Torus {
        radius: f64,
        tube: f64,
    },
}

impl ShapeDef {
    pub fn build(&self) -> Box<dyn Shape> {
        match *self {
            ShapeDef::Plane {
                display_size,
                display_center,
            } => Box::new(Plane {
                display_size,
                display_center,
            }),
            ShapeDef::FinitePlane { lx, ly } => Box::new(FinitePlane { lx, ly }),
            ShapeDef::Cylinder { radius, length } => Box::new(Cylinder { radius, length }),
            ShapeDef::Sphere { radius } => Box::new(Sphere { radius }),
            ShapeDef::Prism { size } => Box::new(Prism { size }),
            ShapeDef::Ellipsoid { radii } => Box::new(Ellipsoid { radii }),
            ShapeDef::Torus { radius, tube } => Box::new(Torus { radius, tube }),
        }
    }
}

/// How a wall's contact is enforced (docs/src/design.md, "Contact: the formulation").
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default, schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum ContactMethod {
    /// Augmented Lagrangian: multipliers are unknowns, zero penetration at convergence.
    #[default]
    Alm,
    /// Penalty: force proportional to the penetration.
    Penalty,
}

impl ContactMethod {
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "alm" => Some(Self::Alm),
            "penalty" => Some(Self::Penalty),
            _ => None,
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            Self::Alm => "alm",
            Self::Penalty => "penalty",
        }
    }
}

/// A projection in global coordinates.
#[derive(Debug, Clone, Copy)]
pub struct WallPoint {
    pub gap: f64,
    /// Columns n, t1, t2 (global).
    pub frame: [[f64; 3]; 3],
    pub point: [f64; 3],
    pub hessian: [[f64; 3]; 3],
    /// Where the wall's material point now at `point` was at the start of the step.
    pub point_old: [f64; 3],
}

/// Project a global point onto a wall placed at `pose` (time t); `pose_old` (the start of
/// the step) gives `point_old`; `hint` is the node's outward normal at the start of the
/// step (global), if it had one. Callers compute the poses once per wall.
pub fn project(
    shape: &dyn Shape,
    pose: &Pose,
    pose_old: &Pose,
    x: [f64; 3],
    hint: Option<[f64; 3]>,
) -> Option<WallPoint> {
    let hint_local = hint.map(|n| pose.dir_to_local(n));
    let p: Projection = shape.project_hinted(pose.to_local(x), hint_local)?;
    let n = pose.dir_to_global(p.normal);
    let t1 = pose.dir_to_global(p.tangents[0]);
    let t2 = pose.dir_to_global(p.tangents[1]);
    let mut frame = [[0.0; 3]; 3];
    for i in 0..3 {
        frame[i] = [n[i], t1[i], t2[i]];
    }
    Some(WallPoint {
        gap: p.gap,
        frame,
        point: pose.to_global(p.point),
        hessian: pose.tensor_to_global(p.hessian),
        point_old: pose_old.to_global(p.point),
    })
}
