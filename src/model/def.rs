//! The serial model definition: what a validated deck resolves to on rank 0 before
//! partitioning — the whole mesh, resolved sets, materials, supports, and the list of
//! contribution definitions ([`ContributionDef`]: loads, walls, couplings) that every
//! rank turns into its [`super::Contribution`]s.

pub use super::kind::{ContributionKind, Localizer};
use crate::fem::element::Formulation;
use crate::material::{Hardening, J2Plasticity, LinearElastic, Material, MooneyRivlin, NeoHookean};
use crate::mesh::{FaceRef, Mesh};
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

    /// Whether the model's energy has a volumetric part U(J) the hybrid element can take
    /// over (the finite-strain models).
    pub fn has_volumetric_split(&self) -> bool {
        !matches!(self, MaterialDef::LinearElastic { .. })
    }

    /// Whether hex8 should be hybrid by default (static and implicit analyses): a nearly
    /// incompressible hyperelastic solid (ν ≥ 0.45).
    pub fn wants_hybrid(&self) -> bool {
        self.nu() >= 0.45
            && matches!(
                self,
                MaterialDef::MooneyRivlin { .. } | MaterialDef::NeoHookean { .. }
            )
    }

    /// Whether hex8 should use F-bar by default: nearly incompressible (ν ≥ 0.45) or
    /// plastic (isochoric flow locks a fully integrated hex8 just the same).
    pub fn wants_fbar(&self) -> bool {
        self.nu() >= 0.45 || matches!(self, MaterialDef::J2 { .. })
    }
}

pub use crate::curve::Curve;

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
    /// Node sets whose reaction forces are reported, in column order.
    pub reaction_sets: Vec<String>,
    /// Node sets whose mean displacement is reported, in column order.
    pub displacement_sets: Vec<String>,
    /// Parts whose largest element von Mises stress is reported: (name, part index).
    pub peak_stress_parts: Vec<(String, u32)>,
    /// Initial velocities of dynamic runs: (node set, velocity), later entries win.
    /// A `part` in the deck is a node set named `part:<name>`.
    pub initial_velocity: Vec<(String, [f64; 3])>,
    /// Loads, walls, couplings: everything else the model is made of, in deck order by
    /// kind (global node numbers).
    pub contributions: Vec<ContributionDef>,
    /// How the elements are split over ranks.
    pub partition: crate::partition::Method,
    /// Element → F-bar patch (`mesh::patches`; `u32::MAX`: none; empty: no patches).
    #[serde(default)]
    /// The partition keeps each patch on one rank.
    pub elem_patch: Vec<u32>,
}

impl ModelDef {
    /// The nodes of part `name`'s elements, sorted (empty for an unknown part).
    pub fn part_nodes(&self, name: &str) -> Vec<usize> {
        let Some(p) = self.part_names.iter().position(|n| n == name) else {
            return Vec::new();
        };
        let mut ns: Vec<usize> = (0..self.mesh.n_elems())
            .filter(|&e| self.mesh.elem_part[e] as usize == p)
            .flat_map(|e| self.mesh.elem_nodes(e).to_vec())
            .collect();
        ns.sort_unstable();
        ns.dedup();
        ns
    }

    /// Material index of each element.
    pub fn elem_material(&self, e: usize) -> usize {
        self.part_material[self.mesh.elem_part[e] as usize]
    }
    /// Element e's formulation: its part's, as its element type takes it
    /// ([`crate::fem::element::for_kind`]).
    pub fn elem_formulation(&self, e: usize) -> Formulation {
        crate::fem::element::for_kind(
            self.mesh.kinds[e],
            self.part_formulation[self.mesh.elem_part[e] as usize],
        )
    }
    /// What its partition is computed from, with its `edges` ([`Self::coupling_edges`]).
    pub fn partition_request<'a>(
        &'a self,
        edges: &'a [(usize, usize)],
    ) -> crate::partition::Request<'a> {
        crate::partition::Request {
            mesh: &self.mesh,
            edges,
            method: self.partition,
            groups: &self.elem_patch,
        }
    }
    /// The element couplings of the contributions' stencils (partition graph edges).
    pub fn coupling_edges(&self) -> Vec<(usize, usize)> {
        let stencils: Vec<Vec<usize>> = self
            .contributions
            .iter()
            .flat_map(|c| c.kind().stencils())
            .collect();
        crate::partition::stencil_edges(&self.mesh, &stencils)
    }
}

/// Registers the kinds of contribution definitions: one line per kind.
macro_rules! contribution_kinds {
    ($($variant:ident($ty:ty)),* $(,)?) => {
        /// A contribution's definition, of any kind. (A model has a few of them: their
        /// sizes do not matter.)
        #[derive(Debug, Clone, Serialize, Deserialize)]
        #[allow(clippy::large_enum_variant)]
        pub enum ContributionDef {
            $($variant($ty)),*
        }
        impl ContributionDef {
            pub fn kind(&self) -> &dyn ContributionKind {
                match self {
                    $(ContributionDef::$variant(d) => d),*
                }
            }
            /// This rank's share (local node indices).
            pub fn localize(&self, l: &Localizer) -> Self {
                match self {
                    $(ContributionDef::$variant(d) => ContributionDef::$variant(d.localize(l))),*
                }
            }
        }
    };
}

contribution_kinds! {
    Load(super::loads::LoadDef),
    Wall(super::walls::WallDef),
    Coupling(super::coupling::CouplingDef),
    Pairs(super::pairs::PairsDef),
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
}
