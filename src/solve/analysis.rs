//! What kind of analysis a run is and its time stepping: the model-independent settings
//! the step controller and the time integrators read (the scene parses `[analysis]`
//! into [`Analysis`], with its defaults filled in).

use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum AnalysisKind {
    /// Load stepping over pseudo-time.
    Static,
    /// Implicit dynamics (generalized-α family).
    Implicit,
    /// Explicit central difference with lumped mass.
    Explicit,
}

impl AnalysisKind {
    pub fn name(self) -> &'static str {
        match self {
            AnalysisKind::Static => "static",
            AnalysisKind::Implicit => "implicit",
            AnalysisKind::Explicit => "explicit",
        }
    }
}

/// Implicit time integration schemes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum Scheme {
    /// Newmark trapezoidal rule (β = 1/4, γ = 1/2): no numerical damping.
    Newmark,
    /// Chung & Hulbert (1993) generalized-α with parameters from `rho_inf`.
    GeneralizedAlpha,
    /// Hilber–Hughes–Taylor α (α_m = 0) with α_f from `rho_inf` ∈ [1/2, 1].
    HhtAlpha,
    /// Wood–Bossak–Zienkiewicz α (α_f = 0: forces at t_{n+1}, for contact) from `rho_inf`.
    Bossak,
}

/// Mass matrix of implicit dynamics.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum MassKind {
    Consistent,
    Lumped,
}

/// Where a static step's Newton iterations start (Abaqus/Standard `*STATIC`,
/// `EXTRAPOLATION=`).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Default, schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum Predictor {
    /// From the last converged state extrapolated along the last converged increment,
    /// scaled to the step: u_n + (Δt/Δt_prev)(u_n − u_{n−1}) (Abaqus's default). On a
    /// monotone load path the first residual is then second-order small in Δt instead
    /// of first-order; contact nodes arrive near the wall with their multipliers.
    #[default]
    Linear,
    /// From the last converged state.
    None,
}

/// The analysis of a run, defaults resolved.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Analysis {
    pub kind: AnalysisKind,
    /// (Pseudo-)time at the end of the run.
    pub end_time: f64,
    /// Static: the pseudo-time step; implicit: Δt (the first, and the largest unless
    /// `max_step` says); explicit: a fixed Δt, or 0 for the stable step of the mesh times
    /// `dt_factor`.
    pub step: f64,
    /// The smallest step a failing step may be cut to before the run ends.
    pub min_step: f64,
    /// The largest step after growth.
    pub max_step: f64,
    /// Implicit: the scheme and its spectral radius at infinite frequency.
    pub scheme: Scheme,
    pub rho_inf: f64,
    /// Implicit: consistent or lumped mass.
    pub mass: MassKind,
    /// Explicit: Δt = dt_factor × the stable step.
    pub dt_factor: f64,
    /// Static: the first iterate of a step.
    pub predictor: Predictor,
    /// Static: times a step must end on (the load curves' breakpoints), so a peak or a
    /// reversal of the loading is reached exactly and not stepped over.
    #[serde(default)]
    pub stops: Vec<f64>,
    /// The analyst's steps (the deck's `[[steps]]`, Abaqus `*STEP`), in order: empty for
    /// a run that is one step. Their ends are among the stops.
    #[serde(default)]
    pub stages: Vec<Stage>,
}

/// One analysis step (a `[[steps]]` entry): a named interval of the (pseudo-)time line
/// with its own increment sizes. Loads and prescribed motions that name it follow their
/// curves in its step time and hold their final value after it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Stage {
    pub name: String,
    /// Start and end on the analysis' time line.
    pub start: f64,
    pub end: f64,
    /// The first increment, the smallest a failing one may be cut to, the largest after
    /// growth.
    pub step: f64,
    pub min_step: f64,
    pub max_step: f64,
}

impl Analysis {
    pub fn is_dynamic(&self) -> bool {
        self.kind != AnalysisKind::Static
    }

    /// The index of the stage an increment ending at `t` belongs to (the first whose end
    /// is not before `t`); 0 without stages.
    pub fn stage_at(&self, t: f64) -> usize {
        let eps = 1e-9 * self.end_time.abs().max(1.0);
        self.stages
            .iter()
            .position(|s| t <= s.end + eps)
            .unwrap_or(self.stages.len().saturating_sub(1))
    }
}
