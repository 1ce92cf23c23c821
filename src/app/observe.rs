//! One observer for every kind of run: each converged step writes its history row
//! (and, when the schedule says so, its fields and a restart file), its attempts to
//! `iterations.csv` and its progress line, and says whether the run goes on
//! (`--stop-after`, or a signal: [`super::interrupt`]).

use super::progress::Progress;
use crate::model::Model;
use crate::output::checkpoint::{self, Checkpoint};
use crate::output::iterations::IterationLog;
use crate::output::results::ResultsWriter;
use crate::output::schedule::Schedule;
use crate::parallel::Comm;
use crate::solve::record::{Attempt, Flow, Resume, StepRecord};
use crate::Result;
use std::path::Path;

/// See the module documentation.
pub(super) struct Observer<'a> {
    pub comm: &'a dyn Comm,
    pub out: &'a Path,
    pub writer: ResultsWriter,
    pub progress: Progress,
    pub iters: IterationLog,
    pub schedule: Schedule,
    /// Every step observed, in order.
    pub records: Vec<StepRecord>,
    /// The end of the last step observed (the start of the next one's first attempt).
    pub t_prev: f64,
    /// The scene's name and the deck's fingerprint, for the restart files.
    pub scene: String,
    pub deck_print: u64,
    pub stop_after: Option<usize>,
    /// The signal that stopped the run at the last observed step
    /// ([`super::interrupt`]).
    pub interrupted: Option<i32>,
    /// The nonlinear solver's name for static progress lines; `None` in dynamic runs,
    /// which print a line per output time instead of per step.
    pub solver: Option<String>,
    pub set_names: Vec<String>,
}

impl Observer<'_> {
    /// Observe one converged step with its solution `u` (and, in dynamic runs, the
    /// velocity and acceleration in `nodal`); `resume` builds the state a restart goes on
    /// from (not available in explicit runs).
    pub fn step(
        &mut self,
        rec: &StepRecord,
        u: &[f64],
        m: &Model,
        nodal: &[(&str, &[f64])],
        resume: Option<&dyn Fn() -> Resume>,
    ) -> Result<Flow> {
        let fields = self.schedule.due(rec);
        self.writer.step_with(self.comm, rec, u, m, fields, nodal)?;
        self.attempts(rec);
        self.records.push(rec.clone());
        match &self.solver {
            Some(name) => self.progress.static_step(rec, name, &self.set_names),
            None if fields => self.progress.dynamic_step(rec, &self.set_names),
            None => {}
        }
        if let Some(sig) = super::interrupt::agreed(self.comm) {
            self.interrupted.get_or_insert(sig);
        }
        let flow = match self.stop_after {
            _ if self.interrupted.is_some() => Flow::Stop,
            Some(n) if rec.step >= n => Flow::Stop,
            _ => Flow::Continue,
        };
        if let (true, Some(resume)) = (fields || flow == Flow::Stop, resume) {
            self.save(rec, u, m, resume)?;
        }
        Ok(flow)
    }

    /// The state before the first increment of a run that starts at t = 0 (not a
    /// restart): output step 0, fields only ([`ResultsWriter::initial_state`]).
    pub fn initial(&mut self, u: &[f64], m: &Model) -> Result<()> {
        let rec = StepRecord {
            failed: Vec::new(),
            step: 0,
            time: 0.0,
            stage: 0,
            stats: Default::default(),
            retries: 0,
            reactions: Vec::new(),
            wall_seconds: 0.0,
            displacements: Vec::new(),
            energies: None,
            columns: m.column_values(self.comm, u, 0.0),
        };
        self.writer.initial_state(self.comm, &rec, u, m)
    }

    /// The attempts at a converged step, its failed ones first (`iterations.csv`).
    fn attempts(&mut self, rec: &StepRecord) {
        let ok = Attempt {
            t_start: self.t_prev,
            t_end: rec.time,
            stats: rec.stats.clone(),
        };
        let all: Vec<&Attempt> = rec.failed.iter().chain(std::iter::once(&ok)).collect();
        self.iters.step(rec.step, &all, true);
        self.t_prev = rec.time;
    }

    /// A restart file after a step that writes fields (each rank its own).
    fn save(
        &self,
        rec: &StepRecord,
        u: &[f64],
        m: &Model,
        resume: &dyn Fn() -> Resume,
    ) -> Result<()> {
        checkpoint::write(
            self.comm,
            self.out,
            &Checkpoint {
                format: checkpoint::FORMAT,
                alfe: crate::VERSION.into(),
                scene: self.scene.clone(),
                deck: self.deck_print,
                ranks: self.comm.size(),
                rank: self.comm.rank(),
                first_dof: m.dofs.dofs.start(),
                n_dofs: u.len(),
                step: rec.step,
                time: rec.time,
                u: u.to_vec(),
                model: m.saved_state(),
                resume: resume(),
            },
        )
    }
}
