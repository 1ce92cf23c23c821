//! What a run records of its steps and what it resumes from: the records the step
//! controller (`stepping`, `time`), the observers in `app` and the restart files in
//! `output` share. A leaf of `solve/`: it uses none of the solvers.

use crate::solve::control::ControlState;
use crate::solve::nonlinear::SolveStats;
use crate::solve::time::energy::{Energies, EnergyAccount};

/// One converged (or the failed last) step.
#[derive(Debug, Clone)]
pub struct StepRecord {
    pub step: usize,
    pub time: f64,
    /// The analysis step (`Analysis::stages`) it belongs to, 0-based (0 without stages).
    pub stage: usize,
    pub stats: SolveStats,
    pub retries: usize,
    /// Reaction force of each reaction set (model order).
    pub reactions: Vec<[f64; 3]>,
    pub wall_seconds: f64,
    /// Mean displacement of each `[output] displacements` set.
    pub displacements: Vec<[f64; 3]>,
    /// Energies of dynamic runs (None for static ones).
    pub energies: Option<Energies>,
    /// The contributions' history columns ([`Model::columns`]), reduced over ranks.
    pub columns: Vec<f64>,
    /// The attempts at this step that failed before it converged (cut and retried).
    pub failed: Vec<Attempt>,
}

/// One attempt at a step: from `t_start` to `t_end`, its solver's counts, residual
/// history and, if it failed, why.
#[derive(Debug, Clone)]
pub struct Attempt {
    pub t_start: f64,
    pub t_end: f64,
    pub stats: SolveStats,
}

/// Totals over the run.
#[derive(Debug, Clone, Default)]
pub struct RunTotals {
    pub steps: usize,
    pub converged: bool,
    /// The observer stopped the run (`Flow::Stop`) before the end.
    pub stopped: bool,
    pub nonlinear_iterations: usize,
    pub linear_iterations: usize,
    pub residual_evaluations: usize,
    pub factorizations: usize,
    pub retries: usize,
    /// The solver's counts beyond iterations (predictor solves, backtracks, reforms).
    pub counts: SolverCounts,
    pub seconds_assembly: f64,
    pub seconds_linear: f64,
    /// Of `seconds_linear`, the preconditioner's setups.
    pub seconds_pc_setup: f64,
    /// The two-level preconditioner's coarse space after the last setup.
    pub coarse: Option<crate::linalg::CoarseStats>,
    /// Why the run stopped early, if it did.
    pub failure: Option<String>,
    /// The kind of that failure (of the last attempt at the step that stopped the run).
    pub failure_reason: Option<crate::solve::nonlinear::Failure>,
    /// The failed attempts at the step that stopped the run.
    pub failed_last: Vec<Attempt>,
    /// Counts by analysis step (`Analysis::stages`; one entry without stages), failed
    /// attempts included.
    pub by_stage: Vec<StageTotals>,
}

/// What the nonlinear solves did besides their iterations (`summary.json` `solver_counts`).
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct SolverCounts {
    /// Tangent predictor solves that imposed prescribed values (also iterations).
    pub predictor_solves: usize,
    /// Line-search trials beyond the full step.
    pub line_search_backtracks: usize,
    /// BFGS stiffness reforms.
    pub bfgs_reforms: usize,
    /// JFNK directions solved on the Jacobian assembled at the iterate because GMRES
    /// failed on the finite-difference products (also counted as factorizations).
    pub jfnk_assembled_directions: usize,
    /// `auto`'s changes of method within increments, in all and by "from → to".
    pub solver_switches: usize,
    pub switches: std::collections::BTreeMap<String, usize>,
    /// Converged increments by the method (variant) that converged them.
    pub increments_by_method: std::collections::BTreeMap<String, usize>,
}

/// One analysis step's share of [`RunTotals`].
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct StageTotals {
    pub increments: usize,
    pub nonlinear_iterations: usize,
    pub linear_iterations: usize,
    pub retries: usize,
}

impl RunTotals {
    /// [`RunTotals::add`], also counted for analysis step `stage`; `converged` counts an
    /// increment, otherwise a retry.
    pub fn add_in(&mut self, stage: usize, s: &SolveStats) {
        self.add(s);
        if self.by_stage.len() <= stage {
            self.by_stage.resize(stage + 1, StageTotals::default());
        }
        let b = &mut self.by_stage[stage];
        b.nonlinear_iterations += s.iterations;
        b.linear_iterations += s.linear_iterations;
        if s.converged {
            b.increments += 1;
        } else {
            b.retries += 1;
        }
    }

    /// Add one nonlinear solve's counts and times.
    pub fn add(&mut self, s: &SolveStats) {
        self.nonlinear_iterations += s.iterations;
        self.linear_iterations += s.linear_iterations;
        self.residual_evaluations += s.residual_evaluations;
        self.factorizations += s.factorizations;
        self.counts.predictor_solves += s.predictor_solves;
        self.counts.line_search_backtracks += s.backtracks;
        self.counts.bfgs_reforms += s.reforms;
        self.counts.jfnk_assembled_directions += s.assembled_directions;
        self.counts.solver_switches += s.switches.len();
        for w in &s.switches {
            *self
                .counts
                .switches
                .entry(format!("{} → {}", w.from, w.to))
                .or_default() += 1;
        }
        if s.converged && !s.method.is_empty() {
            *self
                .counts
                .increments_by_method
                .entry(s.method.to_string())
                .or_default() += 1;
        }
        self.seconds_assembly += s.seconds_assembly;
        self.seconds_linear += s.seconds_linear;
        self.seconds_pc_setup += s.seconds_pc_setup;
        if s.coarse.is_some() {
            self.coarse = s.coarse;
        }
    }
}

/// Where a run resumes from a restart file (`output::checkpoint`): the step controller,
/// the static predictor's last increment, and implicit dynamics' state. With the
/// solution and the contributions' committed states, the run goes on as if it had not
/// stopped (a lagged preconditioner, `[solver.linear] lag`, starts fresh).
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Resume {
    pub control: ControlState,
    pub last_increment: Option<(Vec<f64>, f64)>,
    pub dynamic: Option<DynResume>,
    /// What `solver = "auto"` had learned.
    pub auto: Option<crate::solve::nonlinear::auto::AutoState>,
    /// Whether Armijo backtracking was on (`line_search = "auto"`).
    pub armijo: crate::solve::armijo::ArmijoState,
}

/// What an observer wants after a step: go on, or stop here (`alfe run --stop-after`:
/// the run ends as if interrupted, resumable from its restart file).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flow {
    Continue,
    Stop,
}

/// What implicit dynamics needs to resume after a step besides the solution: velocity,
/// acceleration, the last residual (the force-averaged schemes use it) and the energy
/// account.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct DynResume {
    pub v: Vec<f64>,
    pub a: Vec<f64>,
    pub r_old: Vec<f64>,
    pub energy: EnergyAccount,
}
