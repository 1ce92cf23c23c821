//! `[[pairs]]` and `[[bolts]]`: small-sliding contact between deformable parts and bolt
//! pretension as the deck says them; [`crate::scene::pairs`] pairs the nodes and builds
//! the model's definitions.

use crate::contact::law::Threshold;
use crate::contact::wall::ContactMethod;
use serde::{Deserialize, Serialize};

/// One `[[pairs]]` entry.
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PairsDeck {
    /// The pair list's name (history columns `<name>.fx/.fy/.fz`, `<name>.active`, `<name>.max_slip`).
    pub name: String,
    /// The tracked side: a surface (its nodes, with tributary areas for the pressure)
    /// or a node set.
    pub tracked: String,
    /// The reference side: a surface of another part.
    pub reference: String,
    /// Contact enforcement: "alm" (default) or "penalty".
    #[serde(default)]
    pub method: ContactMethod,
    /// Bonded in all directions from the start (no separation, no slip).
    #[serde(default)]
    pub tied: bool,
    /// Coulomb friction coefficient μ (default 0).
    #[serde(default)]
    pub friction: f64,
    /// ALM scale κ (force/length); default: each node's stiffness diagonal.
    #[serde(default)]
    pub kappa: Option<f64>,
    /// Penalty stiffness / nodal stiffness (default 1).
    #[serde(default = "one")]
    pub penalty_scale: f64,
    /// ALM's tangential augmentation α (stick stiffness α κ).
    #[serde(default)]
    pub tangential_augmentation: Option<f64>,
    /// ALM's friction threshold: "multiplier" (default) or "augmented".
    #[serde(default)]
    pub friction_threshold: Threshold,
    /// How far (along the normal) a tracked node may be from the reference surface
    /// at the start to be paired; default: half the reference faces' mean size.
    #[serde(default)]
    pub search_distance: Option<f64>,
    /// How a node's reference point is weighted: "mortar" (dual mortar integrals over
    /// the tracked faces: passes the contact patch test on any meshes; the default for a
    /// tracked surface) or "node" (the face's shape functions at the node's closest
    /// point: node-to-face; the default for a tracked node set).
    #[serde(default)]
    pub weights: Option<Weights>,
}

/// See [`PairsDeck::weights`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Weights {
    Mortar,
    Node,
}

fn one() -> f64 {
    1.0
}

/// One `[[bolts]]` entry: a bolt's pretension section, the two faces of a cut through
/// its shank (two parts meeting there, or a part split in two), tied by mortar pairs
/// whose normal gap is shifted by the section's shortening (see
/// [`crate::model::pairs::Pretension`]).
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BoltDeck {
    /// The bolt's name (history column `<name>.force`).
    pub name: String,
    /// The cut's two faces: surfaces of the two sides (the tension pulls `tracked`
    /// toward `reference`).
    pub tracked: String,
    /// The other face of the cut (see `tracked`).
    pub reference: String,
    /// The pretension (a force), times `curve` (default: a ramp up to the lock).
    pub force: f64,
    /// The curve that scales the pretension (default: a ramp up to the lock).
    #[serde(default)]
    pub curve: Option<String>,
    /// The analysis step of the pretension: the curve runs in its time (default a ramp
    /// over it) and the section locks at its end unless `lock_at` says otherwise.
    #[serde(default)]
    pub step: Option<String>,
    /// From this time (a number, or a step's name: its end) on the section keeps the
    /// length it has then. Required without `step`.
    #[serde(default)]
    pub lock_at: Option<LockAt>,
    /// ALM scale κ of the section's tie (force/length); default: each node's stiffness diagonal.
    #[serde(default)]
    pub kappa: Option<f64>,
    /// How far a tracked node may be from the reference face to be paired; default half the reference faces' mean size.
    #[serde(default)]
    pub search_distance: Option<f64>,
}

/// When a bolt locks: a time, or the end of a named analysis step.
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(untagged)]
pub enum LockAt {
    Time(f64),
    Step(String),
}
