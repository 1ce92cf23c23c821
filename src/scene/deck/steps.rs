//! `[[steps]]`: named intervals of the time line (Abaqus `*STEP`), as the deck says
//! them; [`crate::scene::steps`] resolves them.

use serde::{Deserialize, Serialize};

/// One `[[steps]]` entry.
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct StepDeck {
    /// The step's name, for the loads, motions and bolts that run in its time.
    pub name: String,
    /// Length of the step on the time line (Abaqus's time period).
    pub duration: f64,
    /// First increment, smallest cut and largest growth (default: `[analysis]`'s).
    #[serde(default)]
    pub step: Option<f64>,
    /// Smallest increment a failing one may be cut to in this step.
    #[serde(default)]
    pub min_step: Option<f64>,
    /// Largest increment after growth in this step.
    #[serde(default)]
    pub max_step: Option<f64>,
    /// Static runs: write fields every n-th increment of this step (default `[output]
    /// every`); a step's last increment is always written.
    #[serde(default)]
    pub output_every: Option<usize>,
}
