//! Progress lines of a run, printed by rank 0 (unless `--quiet`) and kept in the run's
//! log: one per converged step (static) or per output time (dynamic) with its
//! iterations, residual and wall time, the reaction of every reaction set and the force
//! of every wall, contact entity, pair and coupling, and an estimate of the time left.

use crate::model::Model;
use crate::output::log::Log;
use crate::solve::stepping::StepRecord;
use std::time::Instant;

pub struct Progress {
    pub log: Log,
    started: Instant,
    /// Analysis time at the start and end of the stepping.
    t_start: f64,
    t_end: f64,
    /// `(name, column of fx)` of every contribution force (fx, fy, fz in a row).
    forces: Vec<(String, usize)>,
}

impl Progress {
    pub fn new(log: Log, model: &Model, t_start: f64, t_end: f64) -> Self {
        let names: Vec<&str> = model.columns().iter().map(|c| c.name.as_str()).collect();
        let forces = (0..names.len().saturating_sub(2))
            .filter_map(|i| {
                let p = names[i].strip_suffix(".fx")?;
                (names[i + 1] == format!("{p}.fy") && names[i + 2] == format!("{p}.fz"))
                    .then(|| (p.to_string(), i))
            })
            .collect();
        Self {
            log,
            started: Instant::now(),
            t_start,
            t_end,
            forces,
        }
    }

    /// ` name=(fx, fy, fz)` for every reaction set and contribution force.
    fn forces(&self, rec: &StepRecord, sets: &[String]) -> String {
        let v = |f: [f64; 3]| format!("({:.4e}, {:.4e}, {:.4e})", f[0], f[1], f[2]);
        let mut s: String = sets
            .iter()
            .zip(&rec.reactions)
            .map(|(n, f)| format!(" {n}={}", v(*f)))
            .collect();
        for (n, i) in &self.forces {
            if let Some(c) = rec.columns.get(*i..*i + 3) {
                s.push_str(&format!(" {n}={}", v([c[0], c[1], c[2]])));
            }
        }
        s
    }

    /// The time left at the rate so far, `eta 1m05s` (empty before any progress).
    fn eta(&self, t: f64) -> String {
        let f = (t - self.t_start) / (self.t_end - self.t_start);
        if !(f > 0.0 && f < 1.0) {
            return String::new();
        }
        let left = self.started.elapsed().as_secs_f64() * (1.0 - f) / f;
        format!("  eta {}", duration(left))
    }

    /// A static increment.
    pub fn static_step(&mut self, rec: &StepRecord, solver: &str, sets: &[String]) {
        // `auto`: every change of method, then the method that converged.
        let attempts = rec.failed.iter().map(|a| &a.stats).chain([&rec.stats]);
        for s in attempts.flat_map(|s| &s.switches) {
            let line = format!(
                "step {:>4}  solver {} → {}: {}",
                rec.step, s.from, s.to, s.reason
            );
            self.log.line(&line);
        }
        let solver = match rec.stats.method {
            m if solver == "auto" && !m.is_empty() => m,
            _ => solver,
        };
        let retry = if rec.retries > 0 {
            format!("  retries {}", rec.retries)
        } else {
            String::new()
        };
        let line = format!(
            "step {:>4}  t={:<10.4e} ({:>3.0}%)  {} {:>2}  gmres {:>4}  |r|/f={:.2e}  {:.2}s{retry}{}{}",
            rec.step,
            rec.time,
            100.0 * rec.time / self.t_end,
            solver,
            rec.stats.iterations,
            rec.stats.linear_iterations,
            rec.stats.residual_history.last().copied().unwrap_or(0.0),
            rec.wall_seconds,
            self.eta(rec.time),
            self.forces(rec, sets),
        );
        self.log.line(&line);
    }

    /// A dynamic step at an output time.
    pub fn dynamic_step(&mut self, rec: &StepRecord, sets: &[String]) {
        let e = rec.energies.unwrap_or_default();
        let line = format!(
            "step {:>6}  t={:<10.4e} ({:>3.0}%)  its {:>2}  KE={:.4e}  W_int={:.4e}  W_ext={:.4e}  balance={:.1e}{}{}",
            rec.step,
            rec.time,
            100.0 * rec.time / self.t_end,
            rec.stats.iterations,
            e.kinetic,
            e.internal,
            e.external,
            e.balance,
            self.eta(rec.time),
            self.forces(rec, sets),
        );
        self.log.line(&line);
    }
}

/// Seconds as `42s`, `3m07s` or `2h05m`.
pub fn duration(s: f64) -> String {
    let s = s.max(0.0).round() as u64;
    if s < 60 {
        format!("{s}s")
    } else if s < 3600 {
        format!("{}m{:02}s", s / 60, s % 60)
    } else {
        format!("{}h{:02}m", s / 3600, (s / 60) % 60)
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn durations_read_as_a_clock() {
        assert_eq!(super::duration(4.4), "4s");
        assert_eq!(super::duration(187.0), "3m07s");
        assert_eq!(super::duration(7500.0), "2h05m");
    }
}
