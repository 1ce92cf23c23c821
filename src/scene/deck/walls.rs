//! `[[walls]]` and `[[entities]]`: rigid walls and contact entities as the deck says
//! them; [`crate::scene::walls`] checks them and builds the model's definitions.

use crate::contact::law::Threshold;
use crate::contact::motion::MotionKind;
use crate::contact::wall::ContactMethod;
use serde::{Deserialize, Serialize};

/// The shape keyword of a wall.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum ShapeKind {
    Plane,
    FinitePlane,
    Cylinder,
    Sphere,
    Prism,
    Ellipsoid,
    Torus,
}

/// A rigid wall. Its local frame: origin `point`, z along `normal` (plane normal,
/// cylinder axis), x along `x_axis` (made orthogonal to z). Plane and finite plane face
/// +z; the cylinder is centred on `point`; a prism is a box centred on `point`.
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct WallDeck {
    /// The wall's name (history columns `<name>.fx`, ..., output block).
    pub name: String,
    /// "plane", "finite-plane", "cylinder", "sphere", "prism", "ellipsoid" or "torus".
    pub shape: ShapeKind,
    /// The shape's origin (a plane's point, a cylinder's axis point, a sphere's centre) at t = 0.
    #[serde(default)]
    pub point: [f64; 3],
    /// A plane's outward normal; a cylinder's axis; the shape's local z (default [0, 0, 1]).
    #[serde(default = "ez")]
    pub normal: [f64; 3],
    /// The shape's local x (finite planes, prisms, ellipsoids; default: any normal to `normal`).
    #[serde(default)]
    pub x_axis: Option<[f64; 3]>,
    /// finite-plane [lx, ly]; prism [lx, ly, lz]; plane [display size].
    #[serde(default)]
    pub size: Option<Vec<f64>>,
    /// Cylinder or sphere radius.
    #[serde(default)]
    pub radius: Option<f64>,
    /// Cylinder length along its axis.
    #[serde(default)]
    pub length: Option<f64>,
    /// Ellipsoid: semi-axes [a, b, c] along x_axis, y and normal; torus: [R, r], the
    /// centre circle's radius (about `normal`) and the tube's.
    #[serde(default)]
    pub radii: Option<Vec<f64>>,
    /// Tracked nodes: a node set or surface name ...
    #[serde(default)]
    pub nodes: Option<String>,
    /// ... or every node on a part's boundary.
    #[serde(default)]
    pub part: Option<String>,
    /// Coulomb friction coefficient μ (default 0).
    #[serde(default)]
    pub friction: f64,
    /// Contact enforcement: "alm" (default) or "penalty".
    #[serde(default)]
    pub method: ContactMethod,
    /// ALM scale κ (force/length); default: each node's stiffness diagonal.
    #[serde(default)]
    pub kappa: Option<f64>,
    /// Penalty stiffness / nodal stiffness (default 1: the stiffest that converges on
    /// every wall scene; 0.1, LS-DYNA's SLSFAC default, gave 60 % less Hertz force,
    /// `scripts/study --plan penalty`).
    #[serde(default = "d_penalty_scale")]
    pub penalty_scale: f64,
    /// ALM's tangential augmentation α (stick stiffness α κ); default 1
    /// (`contact::law::DEFAULT_TANGENTIAL_AUGMENTATION`).
    #[serde(default)]
    pub tangential_augmentation: Option<f64>,
    /// ALM's friction threshold: "multiplier" (μ max(λ_N, 0), the paper's, default) or
    /// "augmented" (μ max(λ_N − g_N, 0)).
    #[serde(default)]
    pub friction_threshold: Threshold,
    /// Lock a node in stick after this many stick/slip flips within a step (0 = never,
    /// the default): ALM within a 2 % margin of the cone, penalty up to 1.02 × its
    /// allowable elastic slip (its friction force up to 2 % above μ f_N).
    #[serde(default)]
    pub stick_lock_flips: u32,
    /// Prescribed rigid motion (walls), or the entity's prescribed and free DOFs.
    #[serde(default)]
    pub motion: Option<WallMotionDeck>,
    /// Entities: body-fixed points whose paths are reported.
    #[serde(default)]
    pub trace: Option<Vec<TraceDeck>>,
    /// Entities in dynamics: the body's mass and its (isotropic) moment of inertia
    /// about the reference point; without them its free DOFs are massless.
    #[serde(default)]
    pub mass: Option<f64>,
    /// The body's (isotropic) moment of inertia about its reference point.
    #[serde(default)]
    pub inertia: Option<f64>,
    /// Entities in dynamics: initial velocity of the reference point and angular
    /// velocity (radians per unit time).
    #[serde(default)]
    pub velocity: Option<[f64; 3]>,
    /// Initial angular velocity [wx, wy, wz] (radians per unit time).
    #[serde(default)]
    pub spin: Option<[f64; 3]>,
}

/// A body-fixed point of an entity, by its position at t = 0.
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TraceDeck {
    /// The traced point's name (it names its history columns).
    pub name: String,
    /// The point [x, y, z] at t = 0, fixed to the body.
    pub point: [f64; 3],
}

/// What drives one DOF: a displacement or velocity curve (prescribed), or, for
/// entities, nothing (`free`) or a force or moment curve (`force`: free and loaded).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum DofType {
    Displacement,
    Velocity,
    Free,
    Force,
}

/// Prescribed rigid motion, in one of three forms (not mixed):
/// * one direction: translation `translation × c(t)` and a rotation by `angle × c(t)`
///   (radians, right hand) about `axis` through the wall's moving origin;
/// * per degree of freedom: `ux`, `uy`, `uz`, `rx`, `ry`, `rz`, each
///   `{ curve = "name", scale = s, type = "velocity" }` (LS-DYNA's
///   `*BOUNDARY_PRESCRIBED_MOTION_RIGID`); rx, ry, rz are the rotation vector's
///   components;
/// * `segments` in sequence, each `{ to = t, translation = [...], rotation = [...] }`
///   moving linearly in time from the previous segment's end (t = 0 for the first) by
///   those increments: press, then slide, then lift.
///
/// `type = "velocity"` integrates the curves instead. Default curves: a ramp 0 → 1 over
/// the analysis for displacements, the constant 1 for velocities.
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct WallMotionDeck {
    #[serde(default, rename = "type")]
    pub kind: MotionKind,
    /// One direction: the translation at curve value 1.
    #[serde(default, deserialize_with = "one_vector")]
    pub translation: Option<[f64; 3]>,
    /// The curve of `translation` (default: a ramp 0 → 1 over the analysis).
    #[serde(default)]
    pub curve: Option<String>,
    /// One direction: the rotation axis through the wall's moving origin.
    #[serde(default)]
    pub axis: Option<[f64; 3]>,
    /// One direction: the rotation angle (radians) at curve value 1.
    #[serde(default)]
    pub angle: Option<f64>,
    /// The curve of `angle`.
    #[serde(default)]
    pub rotation_curve: Option<String>,
    /// Per DOF: x translation.
    #[serde(default)]
    pub ux: Option<DofDeck>,
    /// Per DOF: y translation.
    #[serde(default)]
    pub uy: Option<DofDeck>,
    /// Per DOF: z translation.
    #[serde(default)]
    pub uz: Option<DofDeck>,
    /// Per DOF: rotation-vector x component.
    #[serde(default)]
    pub rx: Option<DofDeck>,
    /// Per DOF: rotation-vector y component.
    #[serde(default)]
    pub ry: Option<DofDeck>,
    /// Per DOF: rotation-vector z component.
    #[serde(default)]
    pub rz: Option<DofDeck>,
    /// In sequence: press, then slide, then lift ({ to, translation, rotation } each).
    #[serde(default)]
    pub segments: Option<Vec<SegmentDeck>>,
}

/// One DOF: `scale × c(t)`, or `scale × ∫c` with `type = "velocity"` (default: the
/// motion's `type`); for entities `type = "free"`, or `type = "force"`: free and loaded
/// by `scale × c(t)` (a force, or a moment for rx … rz).
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DofDeck {
    /// The curve of this DOF (default: a ramp 0 → 1 over the analysis for displacements, the constant 1 for velocities).
    #[serde(default)]
    pub curve: Option<String>,
    /// Scale of the curve (a displacement, velocity, rotation, force or moment).
    #[serde(default = "one")]
    pub scale: f64,
    /// "displacement", "velocity" (the curve integrated), or for entities "free" or "force" (default: the motion's `type`).
    #[serde(default, rename = "type")]
    pub kind: Option<DofType>,
}

/// One segment of a motion in sequence: by `translation` and `rotation` (rotation-vector
/// increment, radians) linearly in time until `to`.
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SegmentDeck {
    /// The time this segment ends (it starts where the previous one ended, at 0 for the first).
    pub to: f64,
    /// Translation increment [x, y, z] over the segment.
    #[serde(default)]
    pub translation: [f64; 3],
    /// Rotation-vector increment [rx, ry, rz] (radians) over the segment.
    #[serde(default)]
    pub rotation: [f64; 3],
}

fn one() -> f64 {
    1.0
}

/// `translation` is one vector; a list of vectors (a new user's way to write "press,
/// then slide") gets the form that does it.
fn one_vector<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> std::result::Result<Option<[f64; 3]>, D::Error> {
    use serde::de::Error as _;
    let v = toml::Value::deserialize(d)?;
    let num = |x: &toml::Value| x.as_float().or_else(|| x.as_integer().map(|i| i as f64));
    match &v {
        toml::Value::Array(a) if a.len() == 3 && a.iter().all(|x| num(x).is_some()) => Ok(Some([
            num(&a[0]).unwrap(),
            num(&a[1]).unwrap(),
            num(&a[2]).unwrap(),
        ])),
        toml::Value::Array(a) if a.iter().any(|x| x.is_array()) => Err(D::Error::custom(
            "expected one vector [x, y, z] (the motion's total); for motions in sequence \
             (press, then slide) write `segments = [{ to = 1.0, translation = [0, 0, -2] }, \
             { to = 2.0, translation = [20, 0, 0] }]`, or give each DOF a curve \
             (`ux = { curve = \"name\" }`)",
        )),
        other => Err(D::Error::custom(format!(
            "expected one vector [x, y, z], got {other}"
        ))),
    }
}

fn ez() -> [f64; 3] {
    [0.0, 0.0, 1.0]
}
fn d_penalty_scale() -> f64 {
    1.0
}
