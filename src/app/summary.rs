//! `summary.json`: what a run reports of itself (counts, phases, the coarse space,
//! traffic, memory, the contributions' entries), gathered over the ranks.

use crate::model::Model;
use crate::output::record::RunRecord;
use crate::parallel::{Comm, Traffic};
use crate::solve::stepping::StepRecord;
use std::collections::BTreeMap;

/// What a run leaves behind besides its files (also written to `summary.json`).
#[derive(Debug, Clone, serde::Serialize)]
pub struct Summary {
    pub scene: String,
    pub units: String,
    pub ranks: usize,
    pub nodes: usize,
    pub elements: usize,
    pub unknowns: usize,
    /// The nonlinear solver used (`central-difference` for explicit runs).
    pub solver: String,
    /// The preconditioner of the linear solves ("auto" resolved; explicit runs have none).
    pub preconditioner: String,
    /// A two-level preconditioner's coarse space: its size, and what its setups cost
    /// (the largest over the ranks).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub coarse_space: Option<CoarseSummary>,
    /// `static`, `implicit` or `explicit`.
    pub analysis: String,
    /// The (first) time step: the deck's step, or the explicit step used.
    pub time_step: f64,
    /// Explicit runs: the stable step min_e L_e / c_d before the factor.
    pub stable_time_step: Option<f64>,
    pub steps: usize,
    pub converged: bool,
    pub nonlinear_iterations: usize,
    pub linear_iterations: usize,
    pub residual_evaluations: usize,
    pub factorizations: usize,
    pub retries: usize,
    /// Predictor solves, line-search backtracks, BFGS reforms.
    pub solver_counts: crate::solve::record::SolverCounts,
    /// What the model's contributions report: the largest value over the run of the
    /// history columns that ask for it (`max_penetration` with contact), and each
    /// contribution's entry at the last converged step by group (`walls`: force, moment
    /// and displacement of each wall).
    #[serde(flatten)]
    pub contributions: BTreeMap<String, serde_json::Value>,
    /// Analysis steps (the deck's `[[steps]]`), in order: name, end time and counts
    /// (failed attempts included), wall time of their converged increments. Absent
    /// without steps.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub analysis_steps: Vec<serde_json::Value>,
    pub wall_time_s: f64,
    /// Wall time by phase (max over ranks): setup, partition, assembly, linear_solve, output.
    pub phases: Phases,
    /// Messages alfe sent (hypre's own are not counted): the largest count of each kind
    /// over the ranks, and the sum over ranks.
    pub traffic: TrafficSummary,
    /// Largest peak resident set over the ranks, and every rank's.
    pub peak_rss_mb: f64,
    pub peak_rss_mb_per_rank: Vec<f64>,
    /// Where the partition came from: "cache", "computed" or "trivial".
    pub partition: String,
    pub message: String,
    /// The kind of failure when the run did not converge (`stagnated`, `diverged`,
    /// `element`, `linear-solver`, `stick-slip-cycling`, ...), null when it did.
    pub failure_reason: Option<crate::solve::nonlinear::Failure>,
    pub output_dir: String,
    /// Which alfe ran what, how and when (also the header of `deck.toml`).
    pub run: RunRecord,
    /// A restart: the directory, step and time it went on from.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub restarted_from: Option<RestartedFrom>,
    /// The run was stopped after a step on request (`--stop-after`, or a signal).
    pub stopped: bool,
    /// The signal that stopped it (`SIGINT`, `SIGTERM`), if one did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub interrupted: Option<String>,
    /// The scene's quantities of interest over this run (rank 0's summary).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub quantities: Vec<crate::output::quantities::QuantityValue>,
}

/// Where a restarted run went on from (summary.json's `restarted_from`).
#[derive(Debug, Clone, serde::Serialize)]
pub struct RestartedFrom {
    pub dir: String,
    pub step: usize,
    pub time: f64,
}

impl Summary {
    /// The number of the last step done (a restarted run counts from its start).
    fn run_steps_end(&self) -> usize {
        self.restarted_from.as_ref().map_or(0, |r| r.step) + self.steps
    }

    /// The one line a finished run ends with.
    pub fn headline(&self) -> String {
        if self.stopped {
            let how = match &self.interrupted {
                Some(sig) => format!("by {sig}"),
                None => "as asked".into(),
            };
            return format!(
                "alfe: stopped after step {} {how} ({:.2} s), everything written so far; go on with `alfe run --restart {}`",
                self.run_steps_end(),
                self.wall_time_s,
                self.output_dir
            );
        }
        format!(
            "alfe: {} steps converged in {:.2} s ({} nonlinear, {} GMRES iterations); results in {}/ ({}.h5, {}.xmf, history.csv, summary.json, deck.toml, log.txt)",
            self.steps,
            self.wall_time_s,
            self.nonlinear_iterations,
            self.linear_iterations,
            self.output_dir,
            self.scene,
            self.scene
        )
    }
}

#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct Phases {
    pub setup: f64,
    pub partition: f64,
    pub assembly: f64,
    pub linear_solve: f64,
    /// Of `linear_solve`, the preconditioner's setups (factorizations, coarse spaces);
    /// the rest is GMRES.
    pub preconditioner_setup: f64,
    pub output: f64,
}

impl Phases {
    /// Collective: each phase's largest time over the ranks.
    pub(super) fn max_over_ranks(self, comm: &dyn Comm) -> Self {
        let mut ph = [
            self.setup,
            self.partition,
            self.assembly,
            self.linear_solve,
            self.output,
            self.preconditioner_setup,
        ];
        comm.allreduce_max(&mut ph);
        Phases {
            setup: ph[0],
            partition: ph[1],
            assembly: ph[2],
            linear_solve: ph[3],
            output: ph[4],
            preconditioner_setup: ph[5],
        }
    }
}

/// summary.json's `coarse_space`: sizes, and seconds of the last setup by phase and of
/// all setups, each the largest over the ranks.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct CoarseSummary {
    pub dimension: usize,
    pub kept: usize,
    pub components: usize,
    pub setups: usize,
    pub max_local_functions: usize,
    pub max_columns: usize,
    pub extension_s: f64,
    pub galerkin_s: f64,
    pub factor_s: f64,
    pub symbolic_s: f64,
    pub total_s: f64,
}

impl CoarseSummary {
    /// Collective.
    pub(super) fn gather(comm: &dyn Comm, c: Option<crate::linalg::CoarseStats>) -> Option<Self> {
        let c = c.unwrap_or_default();
        let mut v = [
            c.local_functions as f64,
            c.columns as f64,
            c.extension_seconds,
            c.galerkin_seconds,
            c.factor_seconds,
            c.symbolic_seconds,
            c.total_seconds,
            c.dimension as f64,
        ];
        comm.allreduce_max(&mut v);
        (v[7] > 0.0).then(|| Self {
            dimension: c.dimension,
            kept: c.kept,
            components: c.components,
            setups: c.setups,
            max_local_functions: v[0] as usize,
            max_columns: v[1] as usize,
            extension_s: v[2],
            galerkin_s: v[3],
            factor_s: v[4],
            symbolic_s: v[5],
            total_s: v[6],
        })
    }
}

#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct TrafficSummary {
    pub max_per_rank: Traffic,
    pub total: Traffic,
}

impl TrafficSummary {
    /// Gather every rank's traffic (taken before the gathering reductions).
    pub(super) fn gather(comm: &dyn Comm) -> Self {
        let t = comm.traffic();
        let mine = [t.reductions, t.exchanges, t.messages, t.bytes];
        let mut max = mine;
        let mut sum = mine;
        comm.allreduce_max_u64(&mut max);
        comm.allreduce_sum_u64(&mut sum);
        let of = |v: [u64; 4]| Traffic {
            reductions: v[0],
            exchanges: v[1],
            messages: v[2],
            bytes: v[3],
        };
        Self {
            max_per_rank: of(max),
            total: of(sum),
        }
    }
}

/// The summary's entries from the contributions: for every history column that asks
/// for it, its largest value over the steps (from 0); and each contribution's entry from
/// its columns at the last step.
pub(super) fn contributions_summary(
    model: &Model,
    records: &[StepRecord],
    header: &[String],
    earlier: &[Vec<f64>],
) -> BTreeMap<String, serde_json::Value> {
    let cols = model.columns();
    let mut out = BTreeMap::new();
    for (i, c) in cols.iter().enumerate() {
        if c.run_max {
            // `earlier`: history rows of the run this one restarted from.
            let before = header.iter().position(|h| *h == c.name).map_or(0.0, |k| {
                earlier
                    .iter()
                    .filter_map(|r| r.get(k))
                    .filter(|v| v.is_finite())
                    .fold(0.0, |a: f64, &b| a.max(b))
            });
            let m = records
                .iter()
                .filter_map(|r| r.columns.get(i))
                .fold(before, |a: f64, &b| a.max(b));
            out.insert(c.name.clone(), serde_json::json!(m));
        }
    }
    let zeros = vec![0.0; cols.len()];
    let last = records.last().map_or(&zeros, |r| &r.columns);
    out.extend(model.summary(last));
    out
}
