//! Static load stepping over pseudo-time: t = step, 2·step, ..., end_time (the last
//! step shortened to land on end_time). Each step is one nonlinear solve from the
//! previous converged state. A step that fails ends the run (retries come with the
//! step controller of the solver issue); everything converged before it is kept.

use crate::model::Model;
use crate::parallel::Comm;
use crate::solve::linear::lagged::LaggedBlockJacobi;
use crate::solve::linear::matrix::DistMatrix;
use crate::solve::nonlinear::{solve, NonlinearOptions, NonlinearProblem, SolveStats};
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
    fn jacobian(&mut self, comm: &dyn Comm, u: &[f64], k: &mut DistMatrix) -> Result<()> {
        self.model.jacobian(comm, u, self.time, k)
    }
}

/// One converged (or the failed last) step.
#[derive(Debug, Clone)]
pub struct StepRecord {
    pub step: usize,
    pub time: f64,
    pub stats: SolveStats,
    pub retries: usize,
    /// Reaction force of each reaction set (model order).
    pub reactions: Vec<[f64; 3]>,
    pub wall_seconds: f64,
    /// Mean displacement of each `[output] displacements` set.
    pub displacements: Vec<[f64; 3]>,
    /// Energies of dynamic runs (None for static ones).
    pub energies: Option<crate::solve::time::energy::Energies>,
    /// Wall forces, penetration and contact counts (None for models without walls).
    pub contact: Option<crate::model::contact::ContactReport>,
}

/// Totals over the run.
#[derive(Debug, Clone, Default)]
pub struct RunTotals {
    pub steps: usize,
    pub converged: bool,
    pub nonlinear_iterations: usize,
    pub linear_iterations: usize,
    pub residual_evaluations: usize,
    pub factorizations: usize,
    pub retries: usize,
    pub seconds_assembly: f64,
    pub seconds_linear: f64,
    /// Why the run stopped early, if it did.
    pub failure: Option<String>,
}

/// The pseudo-times of the steps.
pub fn step_times(end: f64, dt: f64) -> Vec<f64> {
    let n = ((end / dt) - 1e-9).ceil().max(1.0) as usize;
    (1..=n)
        .map(|i| if i == n { end } else { i as f64 * dt })
        .collect()
}

/// Called with every converged step, its solution and the model (output, progress).
pub type StepObserver<'a> = dyn FnMut(&StepRecord, &[f64], &Model) -> Result<()> + 'a;

/// Step-size control: a step that fails is retried from the last converged state with
/// half the step (a counted retry; the lagged preconditioner is refreshed); after a step
/// that converged in at most `easy_iterations`, the step grows by `growth` up to
/// `max_step`. Below `min_step` the run ends (everything converged so far is kept).
#[derive(Debug, Clone)]
pub struct StepControl {
    pub step: f64,
    pub min_step: f64,
    pub max_step: f64,
    pub growth: f64,
    pub easy_iterations: usize,
}

impl StepControl {
    pub fn from_analysis(a: &crate::scene::deck::AnalysisDeck, max_iterations: usize) -> Self {
        Self {
            step: a.step,
            min_step: a.min_step.unwrap_or(a.step * 1e-3),
            max_step: a.max_step.unwrap_or(a.step),
            growth: 1.5,
            easy_iterations: (max_iterations / 4).max(3),
        }
    }
}

/// Run the static analysis; `on_step` sees every converged step with the solution.
pub fn run_static(
    comm: &dyn Comm,
    model: &mut Model,
    u: &mut Vec<f64>,
    opts: &NonlinearOptions,
    on_step: &mut StepObserver,
) -> Result<RunTotals> {
    let a = model.local.settings.analysis.clone();
    let ctl = StepControl::from_analysis(&a, opts.max_iterations);
    let n = model.n_owned_dofs();
    u.resize(n, 0.0);
    let mut r = vec![0.0; n];
    let mut k = model.new_matrix(comm);
    let mut pc = LaggedBlockJacobi::new(opts.pc_lag);
    let mut tot = RunTotals::default();
    let end = a.end_time;
    let mut t_done = 0.0;
    let mut dt = ctl.step.min(ctl.max_step);
    let mut step = 0;
    let mut retries = 0;
    let mut t0 = Instant::now();
    while t_done < end * (1.0 - 1e-12) {
        // Land exactly on the end time; avoid a sliver of a last step.
        let mut t = t_done + dt;
        if t > end * (1.0 - 1e-9) || end - t < 1e-3 * dt {
            t = end;
        }
        let g = model.prescribed(t);
        let mut trial = u.clone();
        let stats = {
            let mut prob = StaticProblem { model, time: t };
            solve(
                comm, &mut prob, &mut trial, &mut r, &g, &mut k, &mut pc, opts,
            )?
        };
        tot.nonlinear_iterations += stats.iterations;
        tot.linear_iterations += stats.linear_iterations;
        tot.residual_evaluations += stats.residual_evaluations;
        tot.factorizations += stats.factorizations;
        tot.seconds_assembly += stats.seconds_assembly;
        tot.seconds_linear += stats.seconds_linear;
        if !stats.converged {
            if std::env::var("ALFE_DEBUG").is_ok() {
                eprintln!(
                    "DEBUG failed step t={t}: {:?} {}",
                    stats.residual_history, stats.reason
                );
            }
            let tried = t - t_done;
            dt = 0.5 * tried;
            pc.invalidate();
            if dt < ctl.min_step {
                tot.failure = Some(format!(
                    "step {} (t = {t}) did not converge: {}; the step was cut {retries} time(s) to {tried:.3e}, the minimum is {:.3e}",
                    step + 1,
                    stats.reason,
                    ctl.min_step
                ));
                return Ok(tot);
            }
            retries += 1;
            tot.retries += 1;
            continue;
        }
        model.commit();
        *u = trial;
        step += 1;
        tot.steps += 1;
        let easy = stats.iterations <= ctl.easy_iterations;
        let rec = StepRecord {
            step,
            time: t,
            reactions: model.reactions(comm, &r),
            stats,
            retries,
            wall_seconds: t0.elapsed().as_secs_f64(),
            displacements: model.mean_displacements(
                comm,
                u,
                &model.local.settings.output.displacements,
            ),
            energies: None,
            contact: model.contact_report(comm),
        };
        on_step(&rec, u, model)?;
        if easy && retries == 0 {
            dt = (dt * ctl.growth).min(ctl.max_step);
        }
        t_done = t;
        retries = 0;
        t0 = Instant::now();
    }
    tot.converged = true;
    Ok(tot)
}

#[cfg(test)]
mod tests {
    #[test]
    fn step_times_land_on_the_end() {
        assert_eq!(super::step_times(1.0, 0.25), vec![0.25, 0.5, 0.75, 1.0]);
        let t = super::step_times(1.0, 0.3);
        assert_eq!(t.len(), 4);
        assert_eq!(*t.last().unwrap(), 1.0);
        assert_eq!(super::step_times(1.0, 0.1).len(), 10);
    }
}
