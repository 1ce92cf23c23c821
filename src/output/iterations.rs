//! `iterations.csv` (on request: `[output] iterations = true` or `alfe run
//! --iterations`): every nonlinear iteration of every attempt at every step, failed
//! attempts included, so convergence can be plotted (`scripts/plot`) and a failure read
//! iteration by iteration. Rank 0 writes it.
//!
//! Columns: `step` (the step being attempted), `attempt` (1, 2, … within the step),
//! `t_start`, `t_end` (the attempt's interval), `iteration` (0 is the residual before
//! the first correction), `relative_residual` (‖r_free‖ / force scale), `outcome` (on an
//! attempt's last row: `converged`, or why it failed; with `solver = "auto"`, on a
//! method's last row within an attempt, `switch to <method>: <why>`), `method` (the
//! method, or the fallback variant, that made the row).

use crate::solve::stepping::Attempt;
use std::fs::File;
use std::io::Write;
use std::path::Path;

pub struct IterationLog {
    file: Option<File>,
}

impl IterationLog {
    /// Rank 0's `iterations.csv` in `dir` if `on`; an inert log otherwise. Like the run's
    /// log it gives up quietly on a write error: the results report a failing disk.
    pub fn open(dir: &Path, on: bool, is_root: bool) -> Self {
        let file = (on && is_root)
            .then(|| File::create(dir.join("iterations.csv")).ok())
            .flatten()
            .and_then(|mut f| {
                writeln!(
                    f,
                    "step,attempt,t_start,t_end,iteration,relative_residual,outcome,method"
                )
                .ok()
                .map(|_| f)
            });
        Self { file }
    }

    /// The attempts at step `step`, in order (the last one converged if `converged`).
    pub fn step(&mut self, step: usize, attempts: &[&Attempt], converged: bool) {
        if self.write(step, attempts, converged).is_err() {
            self.file = None;
        }
    }

    fn write(
        &mut self,
        step: usize,
        attempts: &[&Attempt],
        converged: bool,
    ) -> std::io::Result<()> {
        let Some(f) = &mut self.file else {
            return Ok(());
        };
        for (k, a) in attempts.iter().enumerate() {
            let last_ok = converged && k + 1 == attempts.len();
            let (h, sw) = (&a.stats.residual_history, &a.stats.switches);
            for (i, r) in h.iter().enumerate() {
                // The switch whose method made this row, if it is not the last method.
                let from = sw.iter().find(|s| i < s.at);
                let method = from.map_or(a.stats.method, |s| s.from);
                let outcome = if let Some(s) = from.filter(|s| i + 1 == s.at) {
                    csv_text(&format!("switch to {}: {}", s.to, s.reason))
                } else if i + 1 < h.len() {
                    String::new()
                } else if last_ok {
                    "converged".into()
                } else {
                    csv_text(&a.stats.reason)
                };
                writeln!(
                    f,
                    "{step},{},{:.15e},{:.15e},{i},{r:.6e},{outcome},{method}",
                    k + 1,
                    a.t_start,
                    a.t_end
                )?;
            }
        }
        f.flush()
    }
}

/// A CSV field: quoted, inner quotes doubled.
fn csv_text(s: &str) -> String {
    format!("\"{}\"", s.replace('"', "\"\""))
}
