//! Static load stepping over pseudo-time up to the end time, each step one nonlinear
//! solve from the previous converged state, the step size from [`StepControl`] (cut on
//! failure, grown after easy steps). A run that cannot go on keeps everything
//! converged before it.

use crate::linalg::matrix::DistMatrix;
use crate::model::Model;
use crate::parallel::Comm;
use crate::solve::control::{ControlState, StepControl};
use crate::solve::nonlinear::{
    solve, NonlinearOptions, NonlinearProblem, Preconditioning, SolveStats,
};
use crate::solve::{Analysis, Predictor};
use crate::Result;
use std::time::Instant;

/// The model at a fixed time, seen as a nonlinear problem.
pub struct StaticProblem<'a> {
    pub model: &'a mut Model,
    pub time: f64,
}

impl NonlinearProblem for StaticProblem<'_> {
    fn residual(&mut self, comm: &dyn Comm, u: &[f64], r: &mut [f64]) -> Result<f64> {
        Ok(self.model.residual(comm, u, self.time, r)?.f_ref)
    }
    fn residual_frozen(&mut self, comm: &dyn Comm, u: &[f64], r: &mut [f64]) -> Result<f64> {
        Ok(self.model.residual_frozen(comm, u, self.time, r)?.f_ref)
    }
    fn jacobian(&mut self, comm: &dyn Comm, u: &[f64], k: &mut DistMatrix) -> Result<()> {
        self.model.jacobian(comm, u, self.time, k)
    }
}

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
    pub energies: Option<crate::solve::time::energy::Energies>,
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
    pub seconds_assembly: f64,
    pub seconds_linear: f64,
    /// Of `seconds_linear`, the preconditioner's setups.
    pub seconds_pc_setup: f64,
    /// The two-level preconditioner's coarse space after the last setup.
    pub coarse: Option<crate::linalg::CoarseStats>,
    /// Why the run stopped early, if it did.
    pub failure: Option<String>,
    /// The failed attempts at the step that stopped the run.
    pub failed_last: Vec<Attempt>,
    /// Counts by analysis step (`Analysis::stages`; one entry without stages), failed
    /// attempts included.
    pub by_stage: Vec<StageTotals>,
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
    pub dynamic: Option<crate::solve::time::DynResume>,
}

/// What an observer wants after a step: go on, or stop here (`alfe run --stop-after`:
/// the run ends as if interrupted, resumable from its restart file).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flow {
    Continue,
    Stop,
}

/// Called with every converged step, its solution, the model (output, progress) and
/// how to resume after it (built only when asked for).
pub type StepObserver<'a> =
    dyn FnMut(&StepRecord, &[f64], &Model, &dyn Fn() -> Resume) -> Result<Flow> + 'a;

/// Run the static analysis; `on_step` sees every converged step with the solution. With
/// `resume` it goes on from a restart: `u` holds its solution and the model its state.
pub fn run_static(
    comm: &dyn Comm,
    model: &mut Model,
    u: &mut Vec<f64>,
    analysis: &Analysis,
    opts: &NonlinearOptions,
    resume: Option<&Resume>,
    on_step: &mut StepObserver,
) -> Result<RunTotals> {
    let mut ctl = StepControl::new(analysis, opts.max_iterations);
    if let Some(r) = resume {
        ctl.resume(&r.control);
    }
    let n = model.n_owned_dofs();
    u.resize(n, 0.0);
    let mut r = vec![0.0; n];
    let mut k = model.new_matrix(comm);
    let mut pc = Preconditioning::new(opts.preconditioner, opts.pc_lag, opts.factor_options());
    if opts.rigid_body_modes || opts.preconditioner.wants_points() || opts.export_system.is_some() {
        pc = pc.with_points(model.node_points(), opts.rigid_body_modes);
    }
    let mut tot = RunTotals::default();
    let mut t0 = Instant::now();
    // The last converged increment and its step, for the predictor.
    let mut last: Option<(Vec<f64>, f64)> = resume.and_then(|r| r.last_increment.clone());
    let mut failed = false;
    // Failed attempts at the current step.
    let mut pending: Vec<Attempt> = Vec::new();
    while let Some((t_n, t)) = ctl.next() {
        let g = model.prescribed(t);
        let mut trial = u.clone();
        // After a failed attempt the cut step starts from the converged state: the
        // extrapolation may be what failed.
        // A new analysis step starts a new load path: no extrapolation into it.
        if ctl.at_stage_start() {
            last = None;
        }
        let stage = ctl.stage();
        if let (Predictor::Linear, Some((du, dt)), false) = (analysis.predictor, &last, failed) {
            let s = (t - t_n) / dt;
            for (x, d) in trial.iter_mut().zip(du) {
                *x += s * d;
            }
        }
        let stats = {
            let mut prob = StaticProblem { model, time: t };
            solve(
                comm, &mut prob, &mut trial, &mut r, &g, &mut k, &mut pc, opts,
            )?
        };
        tot.add_in(stage, &stats);
        if !stats.converged {
            let mut stats = stats;
            if let Some(why) = model.diagnose(comm) {
                stats.reason = format!("{}; {why}", stats.reason);
            }
            model.after_failed_attempt();
            pc.invalidate();
            failed = true;
            let reason = stats.reason.clone();
            pending.push(Attempt {
                t_start: t_n,
                t_end: t,
                stats,
            });
            if let Err(why) = ctl.reject(t, &reason, "step") {
                tot.failure = Some(why);
                tot.failed_last = pending;
                return Ok(tot);
            }
            tot.retries += 1;
            continue;
        }
        model.commit();
        let du: Vec<f64> = trial.iter().zip(u.iter()).map(|(a, b)| a - b).collect();
        last = Some((du, t - t_n));
        failed = false;
        *u = trial;
        let (step, retries) = ctl.accept(t, stats.iterations);
        tot.steps += 1;
        let rec = StepRecord {
            step,
            time: t,
            stage,
            reactions: model.reactions(comm, &r),
            stats,
            retries,
            wall_seconds: t0.elapsed().as_secs_f64(),
            displacements: model.mean_displacements(comm, u),
            energies: None,
            columns: model.column_values(comm, u, t),
            failed: std::mem::take(&mut pending),
        };
        let here = || Resume {
            control: ctl.state(),
            last_increment: last.clone(),
            dynamic: None,
        };
        if on_step(&rec, u, model, &here)? == Flow::Stop {
            tot.stopped = true;
            return Ok(tot);
        }
        t0 = Instant::now();
    }
    tot.converged = true;
    Ok(tot)
}
