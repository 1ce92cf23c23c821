//! The serial model definition: what a validated deck resolves to on rank 0 before
//! partitioning (whole mesh, resolved sets, materials, constraints, loads, settings).

use crate::fem::element::Formulation;
use crate::material::{Hardening, J2Plasticity, LinearElastic, Material, MooneyRivlin, NeoHookean};
use crate::mesh::{FaceRef, Mesh};
use crate::scene::deck::{AnalysisDeck, OutputDeck, SolverDeck, Units};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

#[derive(Debug, Clone, Serialize, Deserialize)]
pub enum MaterialDef {
    LinearElastic {
        e: f64,
        nu: f64,
        density: f64,
    },
    NeoHookean {
        e: f64,
        nu: f64,
        density: f64,
    },
    MooneyRivlin {
        c10: f64,
        c01: f64,
        nu: f64,
        density: f64,
    },
    J2 {
        e: f64,
        nu: f64,
        hardening: Hardening,
        density: f64,
    },
}

impl MaterialDef {
    pub fn build(&self) -> Box<dyn Material> {
        match self {
            &MaterialDef::LinearElastic { e, nu, density } => {
                Box::new(LinearElastic::new(e, nu, density))
            }
            &MaterialDef::NeoHookean { e, nu, density } => {
                Box::new(NeoHookean::new(e, nu, density))
            }
            &MaterialDef::MooneyRivlin {
                c10,
                c01,
                nu,
                density,
            } => Box::new(MooneyRivlin::new(c10, c01, nu, density)),
            MaterialDef::J2 {
                e,
                nu,
                hardening,
                density,
            } => Box::new(J2Plasticity::new(*e, *nu, hardening.clone(), *density)),
        }
    }

    /// Poisson's ratio (the small-strain one for every model).
    pub fn nu(&self) -> f64 {
        match *self {
            MaterialDef::LinearElastic { nu, .. }
            | MaterialDef::NeoHookean { nu, .. }
            | MaterialDef::MooneyRivlin { nu, .. }
            | MaterialDef::J2 { nu, .. } => nu,
        }
    }

    /// Whether hex8 should use F-bar by default: nearly incompressible (ν ≥ 0.45) or
    /// plastic (isochoric flow locks a fully integrated hex8 just the same).
    pub fn wants_fbar(&self) -> bool {
        self.nu() >= 0.45 || matches!(self, MaterialDef::J2 { .. })
    }
}

/// Piecewise-linear curve, constant beyond its ends.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Curve {
    pub points: Vec<[f64; 2]>,
}

impl Curve {
    /// The default load curve: 0 at t = 0 rising linearly to 1 at `end`.
    pub fn ramp(end: f64) -> Self {
        Self {
            points: vec![[0.0, 0.0], [end, 1.0]],
        }
    }
    pub fn eval(&self, t: f64) -> f64 {
        let p = &self.points;
        if t <= p[0][0] {
            return p[0][1];
        }
        for w in p.windows(2) {
            if t <= w[1][0] {
                let s = (t - w[0][0]) / (w[1][0] - w[0][0]);
                return w[0][1] + s * (w[1][1] - w[0][1]);
            }
        }
        p[p.len() - 1][1]
    }
}

/// Displacement constraint on a node set: component c (where `comps[c]`) follows
/// `motion`, scaled in time by `curve`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Constraint {
    pub set: String,
    pub comps: [bool; 3],
    pub motion: Motion,
    pub curve: Curve,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub enum Motion {
    /// u = value · curve(t), the same for every node.
    Uniform { value: [f64; 3] },
    /// Rigid rotation by angle · curve(t) (radians, right-hand rule) about the line
    /// through `center` along `axis` (unit): u = R (X − c) − (X − c).
    Rotation {
        axis: [f64; 3],
        center: [f64; 3],
        angle: f64,
    },
}

impl Constraint {
    /// Prescribed displacement component `c` of a node at reference position `x`.
    pub fn value(&self, x: [f64; 3], c: usize, t: f64) -> f64 {
        let s = self.curve.eval(t);
        match &self.motion {
            Motion::Uniform { value } => value[c] * s,
            Motion::Rotation {
                axis,
                center,
                angle,
            } => {
                // Rodrigues: R d = d cos θ + (a × d) sin θ + a (a·d)(1 − cos θ).
                let th = angle * s;
                let d = [x[0] - center[0], x[1] - center[1], x[2] - center[2]];
                let a = axis;
                let cross = [
                    a[1] * d[2] - a[2] * d[1],
                    a[2] * d[0] - a[0] * d[2],
                    a[0] * d[1] - a[1] * d[0],
                ];
                let dot = a[0] * d[0] + a[1] * d[1] + a[2] * d[2];
                d[c] * th.cos() + cross[c] * th.sin() + a[c] * dot * (1.0 - th.cos()) - d[c]
            }
        }
    }
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub enum Load {
    /// Per-node force on a node set.
    Nodal {
        set: String,
        force: [f64; 3],
        curve: Curve,
    },
    /// Dead traction on a surface (per reference area).
    Traction {
        surface: String,
        traction: [f64; 3],
        curve: Curve,
    },
    /// Follower pressure on a surface.
    Pressure {
        surface: String,
        pressure: f64,
        curve: Curve,
    },
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Settings {
    pub scene: String,
    pub units: Units,
    pub analysis: AnalysisDeck,
    pub solver: SolverDeck,
    pub output: OutputDeck,
    /// Initial velocities of dynamic runs: (node set, velocity), later entries win.
    /// A `part` in the deck is a node set named `part:<name>`.
    #[serde(default)]
    pub initial_velocity: Vec<(String, [f64; 3])>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ModelDef {
    pub mesh: Mesh,
    pub part_names: Vec<String>,
    /// Material index of each part.
    pub part_material: Vec<usize>,
    /// Hex8 volume treatment of each part (resolved from `auto`).
    pub part_formulation: Vec<Formulation>,
    pub materials: Vec<(String, MaterialDef)>,
    pub node_sets: BTreeMap<String, Vec<usize>>,
    pub surfaces: BTreeMap<String, Vec<FaceRef>>,
    pub constraints: Vec<Constraint>,
    pub loads: Vec<Load>,
    /// Node sets whose reaction forces are reported, in column order.
    pub reaction_sets: Vec<String>,
    /// Rigid walls (tracked nodes by global node number).
    pub walls: Vec<crate::contact::wall::WallDef>,
    pub settings: Settings,
}

impl ModelDef {
    /// Material index of each element.
    pub fn elem_material(&self, e: usize) -> usize {
        self.part_material[self.mesh.elem_part[e] as usize]
    }
    pub fn elem_formulation(&self, e: usize) -> Formulation {
        self.part_formulation[self.mesh.elem_part[e] as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn rotation_quarter_turn_about_z() {
        let c = Constraint {
            set: "s".into(),
            comps: [true; 3],
            motion: Motion::Rotation {
                axis: [0.0, 0.0, 1.0],
                center: [1.0, 0.0, 0.0],
                angle: std::f64::consts::FRAC_PI_2,
            },
            curve: Curve::ramp(1.0),
        };
        // (2, 0, 5) is 1 from the axis along x: a quarter turn takes it to (1, 1, 5).
        let u: Vec<f64> = (0..3).map(|k| c.value([2.0, 0.0, 5.0], k, 1.0)).collect();
        assert!(
            (u[0] + 1.0).abs() < 1e-15 && (u[1] - 1.0).abs() < 1e-15 && u[2].abs() < 1e-15,
            "{u:?}"
        );
        assert!(c.value([2.0, 0.0, 5.0], 0, 0.0).abs() < 1e-15);
    }
    #[test]
    fn curve_interpolates_and_clamps() {
        let c = Curve {
            points: vec![[0.0, 0.0], [1.0, 2.0], [2.0, 2.0]],
        };
        assert_eq!(c.eval(-1.0), 0.0);
        assert!((c.eval(0.25) - 0.5).abs() < 1e-15);
        assert_eq!(c.eval(1.5), 2.0);
        assert_eq!(c.eval(9.0), 2.0);
    }
}
