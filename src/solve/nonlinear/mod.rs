//! Nonlinear solvers behind one seam. A [`NonlinearProblem`] gives residuals and
//! Jacobians on owned dofs; the solver owns the constraint algebra (prescribed dofs),
//! the linear solves and the convergence tests. A run keeps one [`Solver`] (the
//! Jacobian's storage, the lagged preconditioner); each solve is a [`SolverContext`]
//! (PETSc's SNES: `context.rs`) driving the method of [`SolverKind`], a
//! [`NonlinearSolver`] that provides only its step (`newton.rs`, `bfgs.rs`, `jfnk.rs`).

pub mod auto;
pub mod bfgs;
pub mod common;
pub mod context;
pub mod jfnk;
pub mod newton;
pub mod precond;
#[cfg(test)]
pub mod testing;

use crate::linalg::gmres::GmresOptions;
use crate::linalg::matrix::DistMatrix;
use crate::linalg::PcKind;
use crate::parallel::Comm;
use crate::Result;
pub use context::{Next, NonlinearSolver, Prediction, Solver, SolverContext, Start};
pub use precond::Preconditioning;

/// The three nonlinear solvers (docs/src/design.md, "Nonlinear solvers").
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    serde::Serialize,
    serde::Deserialize,
    Default,
    schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum SolverKind {
    /// Assembled generalized Jacobian at every iteration.
    #[default]
    Newton,
    /// Matthies–Strang BFGS on a stiffness reformed every `bfgs_reform` iterations.
    Bfgs,
    /// Jacobian-free Newton–Krylov with a lagged block-Jacobi preconditioner.
    Jfnk,
    /// Per increment the cheapest so far, with fallbacks (`auto.rs`).
    Auto,
}

impl SolverKind {
    pub fn name(self) -> &'static str {
        match self {
            SolverKind::Newton => "newton",
            SolverKind::Bfgs => "bfgs",
            SolverKind::Jfnk => "jfnk",
            SolverKind::Auto => "auto",
        }
    }
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "newton" => Some(Self::Newton),
            "bfgs" => Some(Self::Bfgs),
            "jfnk" => Some(Self::Jfnk),
            "auto" => Some(Self::Auto),
            _ => None,
        }
    }

    /// The method of this kind for a solve of `n` owned dofs (`auto` is a choice among
    /// them, made by [`Solver::solve`]; here it is Newton).
    pub fn method(self, n: usize, opts: &NonlinearOptions) -> Box<dyn NonlinearSolver> {
        match self {
            SolverKind::Newton | SolverKind::Auto => Box::new(newton::Newton::new(n)),
            SolverKind::Bfgs => Box::new(bfgs::Bfgs::new(n, opts.bfgs_reform)),
            SolverKind::Jfnk => Box::new(jfnk::Jfnk::new(n)),
        }
    }
}

/// How JFNK picks the finite-difference step ε for J v ≈ (F(u + ε v) − F(u)) / ε.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    serde::Serialize,
    serde::Deserialize,
    Default,
    schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum FdRule {
    /// ε = δ · h / ‖v‖ with h a characteristic element length: the perturbation moves
    /// nodes by δ of an element (docs/src/design.md).
    #[default]
    Element,
    /// ε = √((1 + ‖u‖) ε_mach) / ‖v‖ (Pernice & Walker 1998, NITSOL).
    WalkerPernice,
}

/// When Newton and JFNK backtrack along a correction (Dennis & Schnabel §6.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum LineSearch {
    /// Full steps always.
    Off,
    /// Armijo backtracking on every correction.
    On,
    /// Full steps, unless the full step multiplies ‖r_free‖ by more than
    /// [`context::AUTO_GROWTH`]: then Armijo backtracking from there. A full step that
    /// overshoots and then converges (large rotations, contact changes) is kept; one that
    /// throws the iterate far away is not. The static stepping retries an increment that
    /// failed with stick/slip cycling with [`LineSearch::On`]
    /// ([`crate::solve::stepping::retry_options`]).
    #[default]
    Auto,
}

impl LineSearch {
    pub fn name(self) -> &'static str {
        match self {
            LineSearch::Off => "false",
            LineSearch::On => "true",
            LineSearch::Auto => "auto",
        }
    }
}

/// Settings of a nonlinear solve (defaults documented in the deck, `[solver]`).
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct NonlinearOptions {
    pub kind: SolverKind,
    pub max_iterations: usize,
    pub residual_rtol: f64,
    pub increment_rtol: f64,
    /// Last correction energy |Δu·r| relative to the step's largest.
    pub energy_rtol: f64,
    /// GMRES settings: the tolerance for Newton and BFGS solves; JFNK's tolerance is the
    /// Eisenstat–Walker forcing term (never below this).
    pub linear: GmresOptions,
    /// The preconditioner of the Krylov solves (factored ones may be lagged).
    pub preconditioner: PcKind,
    /// Newton: iterations a factorization is kept for (0 = every iteration).
    pub pc_lag: usize,
    /// Condense contact multipliers node by node in the factored preconditioners.
    pub condense: bool,
    /// Layers of overlap of the Schwarz subdomains.
    pub pc_overlap: usize,
    /// AMG: the rigid-body rotations as near-null space (`[solver.linear]
    /// rigid_body_modes`).
    pub rigid_body_modes: bool,
    /// BFGS: reform (reassemble and refactor) the stiffness every n iterations.
    pub bfgs_reform: usize,
    /// JFNK: relative perturbation δ and the rule for ε.
    pub fd_delta: f64,
    pub fd_rule: FdRule,
    /// A characteristic element length h (mean over the model) for the FD step; set
    /// from the model at the start of a run.
    pub char_length: f64,
    /// The backtracking line search on ‖r_free‖ of Newton and JFNK (BFGS always searches).
    pub line_search: LineSearch,
    /// Iterations without a 10 % fall of the residual after which a solve stagnates;
    /// `None`: max([`common::STAGNATION_WINDOW`], max_iterations/2). `auto` shortens it
    /// for a link that has another behind it ([`auto::EARLY_WINDOW`]).
    #[serde(default)]
    pub stagnation_window: Option<usize>,
    /// Write the run's first Newton linear system here (`alfe run --export-system`:
    /// [`crate::linalg::export`]).
    pub export_system: Option<std::path::PathBuf>,
}

impl NonlinearOptions {
    /// How the factored preconditioners factor.
    pub fn factor_options(&self) -> crate::linalg::FactorOptions {
        crate::linalg::FactorOptions {
            condense: self.condense,
            overlap: self.pc_overlap,
            ..Default::default()
        }
    }
}

pub trait NonlinearProblem {
    /// r(u) on owned dofs (rows of constrained dofs hold reactions) and the force
    /// scale f_ref that relative residual tolerances refer to.
    fn residual(&mut self, comm: &dyn Comm, u: &[f64], r: &mut [f64]) -> Result<f64>;
    /// r at a perturbed point of a finite-difference product J·v ≈ (r(u + εv) − r(u))/ε:
    /// the branches of semi-smooth terms (contact) stay those of the last
    /// [`NonlinearProblem::residual`], so the product is the generalized Jacobian's.
    fn residual_frozen(&mut self, comm: &dyn Comm, u: &[f64], r: &mut [f64]) -> Result<f64> {
        self.residual(comm, u, r)
    }
    /// The unconstrained Jacobian ∂r/∂u at u, assembled into `k` (pattern fixed).
    fn jacobian(&mut self, comm: &dyn Comm, u: &[f64], k: &mut DistMatrix) -> Result<()>;
}

/// Why a nonlinear solve (or a run) failed: the kind the step controller, the log and
/// `summary.json` (`failure_reason`) report beside the message (PETSc's
/// `SNESConvergedReason`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Failure {
    /// The residual or the state overflowed.
    NonFinite,
    /// The residual grew past its divergence bound.
    Diverged,
    /// The residual did not fall by 10 % over the stagnation window.
    Stagnated,
    /// The iteration budget ran out.
    IterationLimit,
    /// An element could not be evaluated: inverted, or its material failed.
    Element,
    /// A factorization or a Krylov solve failed.
    LinearSolver,
    /// Tracked nodes kept switching between stick and slip (`diagnose`).
    StickSlipCycling,
    /// Explicit dynamics: the stable time step collapsed or fell below a fixed one.
    TimeStep,
    /// `auto`: a probe ran past its time budget ([`auto::PROBE_BUDGET`]); the
    /// increment goes on with the cheapest method's chain.
    ProbeBudget,
}

impl Failure {
    /// The name `summary.json` and the log use.
    pub fn name(self) -> &'static str {
        match self {
            Failure::NonFinite => "non-finite",
            Failure::Diverged => "diverged",
            Failure::Stagnated => "stagnated",
            Failure::IterationLimit => "iteration-limit",
            Failure::Element => "element",
            Failure::LinearSolver => "linear-solver",
            Failure::StickSlipCycling => "stick-slip-cycling",
            Failure::TimeStep => "time-step",
            Failure::ProbeBudget => "probe-budget",
        }
    }
}

/// Statistics of one nonlinear solve (one load step attempt).
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct SolveStats {
    pub converged: bool,
    /// Nonlinear iterations (linear solves).
    pub iterations: usize,
    pub linear_iterations: usize,
    pub residual_evaluations: usize,
    pub factorizations: usize,
    /// ‖r_free‖ / f_ref at every evaluation.
    pub residual_history: Vec<f64>,
    /// Why it stopped when it did not converge.
    pub reason: String,
    /// The kind of that reason.
    pub failure: Option<Failure>,
    pub seconds_assembly: f64,
    pub seconds_linear: f64,
    /// Of `seconds_linear`, the preconditioner's setups (factorizations, coarse spaces).
    pub seconds_pc_setup: f64,
    /// The two-level preconditioner's coarse space after the last setup.
    pub coarse: Option<crate::linalg::CoarseStats>,
    /// Linear-operator applications that were finite-difference residuals (JFNK).
    pub fd_products: usize,
    /// Tangent predictor solves (counted in `iterations` too).
    pub predictor_solves: usize,
    /// Line-search trials beyond the full step.
    pub backtracks: usize,
    /// BFGS reforms (stiffness reassembled and refactored).
    pub reforms: usize,
    /// JFNK directions solved on the assembled Jacobian after GMRES failed on the
    /// finite-difference products.
    pub assembled_directions: usize,
    /// The method (variant) of the last attempt: the one that converged, if any.
    pub method: &'static str,
    /// `auto`'s changes of method within the increment.
    pub switches: Vec<auto::Switch>,
}

impl SolveStats {
    /// Record a failure of kind `kind` with its message.
    pub fn fail(&mut self, kind: Failure, reason: String) {
        self.failure = Some(kind);
        self.reason = reason;
    }
}
