//! A wall's definition: what the deck says of it, in global node numbers until localized.

use crate::contact::law::Threshold;
use crate::contact::motion::RigidMotion;
use crate::contact::wall::{ContactMethod, ShapeDef};
use crate::model::body::BodyDef;
use serde::{Deserialize, Serialize};

/// A rigid wall of the model: shape, placement and prescribed motion, friction, the
/// enforcement method and the tracked nodes (node-to-surface, one way, as the paper's
/// rigid walls). `nodes` are global node numbers in a [`crate::model::def::ModelDef`] and
/// owned local nodes once localized.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct WallDef {
    pub name: String,
    pub shape: ShapeDef,
    pub motion: RigidMotion,
    /// Coulomb friction coefficient μ.
    pub friction: f64,
    pub method: ContactMethod,
    /// ALM scale κ (force per length); None = from the stiffness at each node.
    pub kappa: Option<f64>,
    /// Penalty stiffness as a multiple of the nodal stiffness (LS-DYNA's SLSFAC idea).
    pub penalty_scale: f64,
    /// ALM's tangential augmentation α ([`AlmLaw::alpha`]).
    pub tangential_augmentation: f64,
    /// ALM's friction threshold.
    pub friction_threshold: Threshold,
    /// Stick/slip flips of one node within a step after which it is locked in stick
    /// ([`Decision::Locked`]; MOOSE's `stick_lock_iterations`); 0: never.
    pub stick_lock_flips: u32,
    /// The tracked node set's name (for messages).
    pub set: String,
    pub nodes: Vec<usize>,
    /// Tributary area of each tracked node on the tracked surface (0 where unknown).
    pub areas: Vec<f64>,
    /// The mean size of the tracked faces (their mean edge length, over the whole wall
    /// before localizing): penalty friction's allowable elastic slip is
    /// [`crate::contact::penalty::SLIP_TOLERANCE`] of it.
    #[serde(default)]
    pub face_size: f64,
    /// A contact entity's body (free DOFs, loads, traced points); None for a wall.
    #[serde(default)]
    pub body: Option<BodyDef>,
}
