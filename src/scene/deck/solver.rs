//! `[solver]` and `[solver.linear]`: the nonlinear method, its convergence tests and the
//! linear solves, with their defaults.

use super::{one, yes, FdRule, PcKind, SolverKind};
use serde::{Deserialize, Serialize};

/// Nonlinear solver settings. Convergence (all must hold): ‖r‖ ≤ residual_rtol · f_ref
/// with f_ref = max(‖f_ext‖, ‖f_int‖) over all unknowns (so reactions count), the last
/// correction ‖Δu‖ ≤ increment_rtol · ‖u‖, and its energy |Δu·r| ≤ energy_rtol times the
/// largest correction energy of the step.
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SolverDeck {
    /// "newton" (default), "bfgs", "jfnk" or "auto" (per increment the cheapest so far, with fallbacks).
    #[serde(default)]
    pub nonlinear: SolverKind,
    /// Nonlinear iterations before an increment is cut (default 25).
    #[serde(default = "d_max_it")]
    pub max_iterations: usize,
    /// Relative residual tolerance of convergence (default 1e-8).
    #[serde(default = "d_rrtol")]
    pub residual_rtol: f64,
    /// Relative correction tolerance of convergence (default 1e-6).
    #[serde(default = "d_urtol")]
    pub increment_rtol: f64,
    /// Last correction's energy |Δu·r| relative to the largest of the step.
    #[serde(default = "d_ertol")]
    pub energy_rtol: f64,
    /// The linear solves: GMRES and its preconditioner.
    #[serde(default)]
    pub linear: LinearDeck,
    /// Backtracking (Armijo) line search on ‖r_free‖ of Newton and JFNK: `true`, `false`
    /// or `"auto"` (default: full steps unless one multiplies ‖r‖ by more than 1000;
    /// the retries of an increment that failed with stick/slip cycling backtrack on every
    /// correction). Always-on backtracking slows or stalls Newton and JFNK on large
    /// rotations, where full steps overshoot and then converge (`cantilever`,
    /// `twisted-block`).
    #[serde(default)]
    pub line_search: Option<LineSearchDeck>,
    /// JFNK: relative finite-difference perturbation δ (of an element length).
    #[serde(default = "d_fd_delta")]
    pub fd_delta: f64,
    /// JFNK: the rule for the finite-difference step.
    #[serde(default)]
    pub fd_step: FdRule,
    /// BFGS: reassemble and refactor the stiffness every n iterations (and on divergence).
    #[serde(default = "d_bfgs_reform")]
    pub bfgs_reform: usize,
}

fn d_bfgs_reform() -> usize {
    11
}

fn d_fd_delta() -> f64 {
    1e-4
}

fn d_max_it() -> usize {
    25
}
fn d_rrtol() -> f64 {
    1e-8
}
fn d_urtol() -> f64 {
    1e-6
}
fn d_ertol() -> f64 {
    1e-8
}

impl Default for SolverDeck {
    fn default() -> Self {
        Self {
            nonlinear: SolverKind::Newton,
            max_iterations: d_max_it(),
            residual_rtol: d_rrtol(),
            increment_rtol: d_urtol(),
            energy_rtol: d_ertol(),
            linear: LinearDeck::default(),
            line_search: None,
            fd_delta: d_fd_delta(),
            fd_step: FdRule::Element,
            bfgs_reform: d_bfgs_reform(),
        }
    }
}

/// GMRES settings (right-preconditioned, so `rtol` bounds the true residual).
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LinearDeck {
    /// GMRES relative tolerance of Newton's and BFGS's linear solves (JFNK: the floor of its forcing term); default 1e-10.
    #[serde(default = "d_lrtol")]
    pub rtol: f64,
    /// GMRES restart length (default 60).
    #[serde(default = "d_restart")]
    pub restart: usize,
    /// GMRES iterations before a linear solve fails (default 2000).
    #[serde(default = "d_lmax")]
    pub max_iterations: usize,
    /// "auto" (default), "auto-factored", "block-jacobi", "asm", "two-level",
    /// "two-level-bj", "amg" or "none". "auto" is "auto-factored" (block Jacobi on one
    /// rank, two-level Schwarz on more) for problem classes AMG does not suit
    /// (`scene::build::amg_unsuited`), and otherwise AMG from a size on
    /// (`linalg::PcKind::resolve`).
    #[serde(default)]
    pub preconditioner: PcKind,
    /// Reuse a block-Jacobi factorization for this many further Jacobians (Newton
    /// iterations, across steps) before refactoring; 0 = refactor every time. A kept
    /// factorization under which GMRES fails is refreshed at once.
    #[serde(default)]
    pub lag: usize,
    /// Eliminate contact multipliers node by node before factoring (block Jacobi, ASM;
    /// `linalg::condense`); false factors the saddle-point block as assembled.
    #[serde(default = "yes")]
    pub condense: bool,
    /// AMG only: give BoomerAMG the rigid-body rotations (GM-2 interpolation, nodal
    /// coarsening). Off by default: slower on every scene measured (README, "Linear
    /// solves").
    #[serde(default)]
    pub rigid_body_modes: bool,
    /// Layers of overlap of the ASM subdomains (`asm`, `two-level`): 1 (default) takes
    /// the ghost nodes, each more layer their neighbours.
    #[serde(default = "one")]
    pub overlap: usize,
}

fn d_lrtol() -> f64 {
    1e-10
}
fn d_restart() -> usize {
    60
}
fn d_lmax() -> usize {
    2000
}

impl Default for LinearDeck {
    fn default() -> Self {
        Self {
            rtol: d_lrtol(),
            restart: d_restart(),
            max_iterations: d_lmax(),
            preconditioner: PcKind::Auto,
            lag: 0,
            condense: true,
            rigid_body_modes: false,
            overlap: 1,
        }
    }
}

/// `[solver] line_search`: `true`, `false` or `"auto"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(untagged)]
pub enum LineSearchDeck {
    Flag(bool),
    Word(LineSearchWord),
}

/// The word form of `line_search`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum LineSearchWord {
    Auto,
}

impl LineSearchDeck {
    pub fn setting(self) -> crate::solve::nonlinear::LineSearch {
        use crate::solve::nonlinear::LineSearch;
        match self {
            LineSearchDeck::Flag(true) => LineSearch::On,
            LineSearchDeck::Flag(false) => LineSearch::Off,
            LineSearchDeck::Word(LineSearchWord::Auto) => LineSearch::Auto,
        }
    }
}
