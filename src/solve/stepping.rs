//! Static load stepping over pseudo-time up to the end time, each step one nonlinear
//! solve from the previous converged state, the step size from [`StepControl`] (cut on
//! failure, grown after easy steps). A run that cannot go on keeps everything
//! converged before it.

use crate::linalg::matrix::DistMatrix;
use crate::model::Model;
use crate::parallel::Comm;
use crate::solve::armijo::ArmijoMemory;
use crate::solve::control::StepControl;
use crate::solve::nonlinear::{NonlinearOptions, NonlinearProblem, Preconditioning, Solver, Start};
pub use crate::solve::record::{Attempt, Flow, Resume, RunTotals, StageTotals, StepRecord};
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

/// The nonlinear solver of a run on `model`: its Jacobian's storage and the
/// preconditioner `opts` ask for (given the node points when it needs them).
pub fn model_solver<'o>(comm: &dyn Comm, model: &Model, opts: &'o NonlinearOptions) -> Solver<'o> {
    let k = model.new_matrix(comm);
    let mut pc = Preconditioning::new(opts.preconditioner, opts.pc_lag, opts.factor_options());
    if opts.rigid_body_modes || opts.preconditioner.wants_points() || opts.export_system.is_some() {
        pc = pc.with_points(model.node_points(), opts.rigid_body_modes);
    }
    Solver::new(opts, k, pc)
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
    // Where line search is left to `auto`: Armijo after failures (`armijo.rs`; for
    // every method in the retries of a step that failed with stick/slip cycling, where
    // full Newton steps carry nodes across the friction cone and back: penalty friction
    // on the seal finishes only so).
    let mut armijo = ArmijoMemory::new(opts, true);
    let with_armijo = ArmijoMemory::options(opts);
    let mut solver = model_solver(comm, model, opts);
    if let Some(r) = resume {
        if let Some(a) = &r.auto {
            solver.auto = a.clone();
        }
        armijo.resume(r.armijo);
        solver.opts = armijo.pick(opts, &with_armijo);
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
        let mut predicted = false;
        if let (Predictor::Linear, Some((du, dt)), false) = (analysis.predictor, &last, failed) {
            let s = (t - t_n) / dt;
            for (x, d) in trial.iter_mut().zip(du) {
                *x += s * d;
            }
            predicted = true;
        }
        let stats = {
            let mut prob = StaticProblem { model, time: t };
            let start = if predicted {
                Start::Predicted(u.as_slice())
            } else {
                Start::Tangent
            };
            solver.solve(comm, &mut prob, &mut trial, &mut r, &g, start)?
        };
        tot.add_in(stage, &stats);
        if !stats.converged {
            let mut stats = stats;
            if let Some(why) = model.diagnose(comm) {
                stats.reason = format!("{}; {why}", stats.reason);
                stats.failure = Some(crate::solve::nonlinear::Failure::StickSlipCycling);
            }
            model.after_failed_attempt();
            solver.pc.invalidate();
            armijo.failed(stats.failure);
            solver.opts = armijo.pick(opts, &with_armijo);
            failed = true;
            let reason = stats.reason.clone();
            let kind = stats.failure;
            pending.push(Attempt {
                t_start: t_n,
                t_end: t,
                stats,
            });
            if let Err(why) = ctl.reject(t, &reason, "step") {
                tot.failure = Some(why);
                tot.failure_reason = kind;
                tot.failed_last = pending;
                return Ok(tot);
            }
            tot.retries += 1;
            continue;
        }
        model.commit();
        armijo.converged(stats.backtracks);
        solver.opts = armijo.pick(opts, &with_armijo);
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
            auto: Some(solver.auto.clone()),
            armijo: armijo.state(),
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
