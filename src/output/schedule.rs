//! Which steps write fields (and restart files): one schedule for every kind of run.
//! Static runs write every n-th increment (per analysis step, `[[steps]] output_every`,
//! and each analysis step's last); dynamic runs write at every multiple of the output
//! interval (the first step at or after it), the initial state and the last step. Every
//! step writes its history row regardless.

use crate::solve::record::StepRecord;
use crate::solve::Stage;

/// See the module documentation.
#[derive(Debug, Clone)]
pub enum Schedule {
    /// Static runs: every `every`-th increment, or per analysis step.
    Increments {
        every: usize,
        /// Per analysis step, its `output_every` (empty without steps).
        stage_every: Vec<usize>,
        stages: Vec<Stage>,
        end_time: f64,
        /// (analysis step, increments of it so far)
        seen: (usize, usize),
    },
    /// Dynamic runs: at every multiple of the interval.
    Interval(OutputClock),
}

impl Schedule {
    /// Whether the step `rec` writes fields; called once per converged step, in order.
    pub fn due(&mut self, rec: &StepRecord) -> bool {
        match self {
            Schedule::Interval(clock) => clock.due(rec.time),
            Schedule::Increments {
                every,
                stage_every,
                stages,
                end_time,
                seen,
            } => match stages.get(rec.stage) {
                Some(st) => {
                    if rec.stage != seen.0 {
                        *seen = (rec.stage, 0);
                    }
                    seen.1 += 1;
                    let n = stage_every.get(rec.stage).copied().unwrap_or(*every);
                    seen.1.is_multiple_of(n) || rec.time >= st.end - 1e-9 * end_time.max(1.0)
                }
                None => rec.step.is_multiple_of(*every) || rec.time >= *end_time,
            },
        }
    }

    /// A restart at time `t`, where the earlier run had written `seen_in_stage`
    /// increments of analysis step `stage` (static runs with analysis steps).
    pub fn resume(&mut self, t: f64, stage: usize, seen_in_stage: usize) {
        match self {
            Schedule::Interval(clock) => clock.skip_to(t),
            Schedule::Increments { seen, .. } => *seen = (stage, seen_in_stage),
        }
    }
}

/// Whether a dynamic step at time t writes fields: at every multiple of `interval`
/// (the first step at or after it), the initial state and the last step.
#[derive(Debug, Clone)]
pub struct OutputClock {
    interval: f64,
    next: f64,
    end: f64,
}

impl OutputClock {
    pub fn new(interval: f64, end: f64) -> Self {
        Self {
            interval,
            next: 0.0,
            end,
        }
    }
    /// A restart at t: the next output is the first multiple of the interval after it.
    pub fn skip_to(&mut self, t: f64) {
        self.next = ((t / self.interval + 1e-9).floor() + 1.0) * self.interval;
    }

    pub fn due(&mut self, t: f64) -> bool {
        let last = t >= self.end * (1.0 - 1e-12);
        if t >= self.next - 1e-9 * self.interval || last {
            self.next = ((t / self.interval + 1e-9).floor() + 1.0) * self.interval;
            return true;
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn output_clock_hits_each_interval_once() {
        let mut c = OutputClock::new(0.25, 1.0);
        let times: Vec<f64> = (0..=20).map(|i| i as f64 * 0.05).collect();
        let hits: Vec<f64> = times.into_iter().filter(|&t| c.due(t)).collect();
        assert_eq!(hits.len(), 5, "{hits:?}");
        assert!((hits[1] - 0.25).abs() < 1e-12 && (hits[4] - 1.0).abs() < 1e-12);
    }

    fn rec(step: usize, time: f64, stage: usize) -> StepRecord {
        StepRecord {
            step,
            time,
            stage,
            stats: Default::default(),
            retries: 0,
            reactions: Vec::new(),
            wall_seconds: 0.0,
            displacements: Vec::new(),
            energies: None,
            columns: Vec::new(),
            failed: Vec::new(),
        }
    }

    #[test]
    fn every_nth_increment_and_the_last() {
        let mut s = Schedule::Increments {
            every: 3,
            stage_every: Vec::new(),
            stages: Vec::new(),
            end_time: 1.0,
            seen: (0, 0),
        };
        let due: Vec<usize> = (1..=10)
            .filter(|&k| s.due(&rec(k, k as f64 / 10.0, 0)))
            .collect();
        assert_eq!(due, vec![3, 6, 9, 10]);
    }

    #[test]
    fn per_analysis_step_counts_restart_from_the_earlier_run() {
        let stages = vec![
            Stage {
                name: "a".into(),
                start: 0.0,
                end: 1.0,
                step: 0.25,
                min_step: 0.25,
                max_step: 0.25,
            },
            Stage {
                name: "b".into(),
                start: 1.0,
                end: 2.0,
                step: 0.25,
                min_step: 0.25,
                max_step: 0.25,
            },
        ];
        let mut s = Schedule::Increments {
            every: 1,
            stage_every: vec![2, 2],
            stages,
            end_time: 2.0,
            seen: (0, 0),
        };
        // Step b's increments 1..4 at t = 1.25 .. 2.0: the 2nd, the 4th (also its last).
        s.resume(1.0, 1, 0);
        let due: Vec<bool> = (1..=4)
            .map(|k| s.due(&rec(4 + k, 1.0 + 0.25 * k as f64, 1)))
            .collect();
        assert_eq!(due, vec![false, true, false, true]);
    }
}
