//! The step controller shared by static load stepping and implicit dynamics: the next
//! step lands exactly on the end time (no sliver of a last step); a step that does not
//! converge is retried from the last converged state with half the step (a counted
//! retry; the caller refreshes its preconditioner); after a step that converged in at
//! most `easy_iterations` without retries the step grows by `growth` up to `max_step`.
//! Below `min_step` the run ends, keeping everything converged so far. With analysis
//! steps (`Analysis::stages`) each step starts from its own increment and bounds.

use super::{Analysis, Stage};

/// What a restart needs of the controller: where the stepping stands.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ControlState {
    pub t_done: f64,
    pub dt: f64,
    pub steps: usize,
    pub stage: usize,
}

#[derive(Debug, Clone)]
pub struct StepControl {
    pub min_step: f64,
    pub max_step: f64,
    pub growth: f64,
    pub easy_iterations: usize,
    end: f64,
    /// Times a step must end on, ascending (`Analysis::stops`).
    stops: Vec<f64>,
    /// The end of the last converged step.
    t_done: f64,
    /// The step the next attempt tries.
    dt: f64,
    /// Converged steps so far.
    steps: usize,
    /// Failed attempts of the step being tried.
    retries: usize,
    stages: Vec<Stage>,
    /// The stage the next increment belongs to.
    stage: usize,
}

impl StepControl {
    /// From the analysis; a solver budget of `max_iterations` per step makes steps that
    /// converged in a quarter of it (at least 3) easy.
    pub fn new(a: &Analysis, max_iterations: usize) -> Self {
        Self {
            min_step: a.min_step,
            max_step: a.max_step,
            growth: 1.5,
            easy_iterations: (max_iterations / 4).max(3),
            end: a.end_time,
            stops: a.stops.clone(),
            t_done: 0.0,
            dt: a.step.min(a.max_step),
            steps: 0,
            retries: 0,
            stages: a.stages.clone(),
            stage: 0,
        }
        .entering(0)
    }

    /// Take the increment bounds of stage `k` (if there are stages).
    fn entering(mut self, k: usize) -> Self {
        self.enter(k);
        self
    }

    fn enter(&mut self, k: usize) {
        self.stage = k;
        if let Some(s) = self.stages.get(k) {
            self.min_step = s.min_step;
            self.max_step = s.max_step;
            self.dt = s.step.min(s.max_step);
        }
    }

    /// Where the stepping stands (after an accepted step: for a restart).
    pub fn state(&self) -> ControlState {
        ControlState {
            t_done: self.t_done,
            dt: self.dt,
            steps: self.steps,
            stage: self.stage,
        }
    }

    /// Continue from `s` (a restart).
    pub fn resume(&mut self, s: &ControlState) {
        self.enter(s.stage);
        self.t_done = s.t_done;
        self.dt = s.dt;
        self.steps = s.steps;
        self.retries = 0;
    }

    /// The stage the next increment belongs to (0 without stages).
    pub fn stage(&self) -> usize {
        self.stage
    }

    /// True before the first increment of a stage after the first: what was learnt from
    /// the last increments (a predictor's extrapolation) belongs to another load path.
    pub fn at_stage_start(&self) -> bool {
        self.stage > 0
            && (self.t_done - self.stages[self.stage].start).abs() <= 1e-9 * self.end.abs().max(1.0)
    }

    /// The next attempt `(t_n, t_{n+1})`, or `None` once the end time is reached.
    pub fn next(&self) -> Option<(f64, f64)> {
        if self.t_done >= self.end * (1.0 - 1e-12) {
            return None;
        }
        let mut t = snap(self.t_done + self.dt, self.end);
        if t <= self.t_done {
            // A step below the snapping grain (12 digits of the end time): unsnapped.
            t = self.t_done + self.dt;
        }
        if t > self.end * (1.0 - 1e-9) || self.end - t < 1e-3 * self.dt {
            t = self.end;
        }
        // The next stop after this step's start, if the step would reach or pass it.
        let eps = 1e-9 * self.end.abs().max(1.0);
        if let Some(&s) = self.stops.iter().find(|&&s| s > self.t_done + eps) {
            if t > s - 1e-3 * self.dt {
                t = s;
            }
        }
        Some((self.t_done, t))
    }

    /// The attempt ending at `t1` failed because of `reason`: halve the step, or, below
    /// the minimum, the run's failure message (`what` names the step: "step" or "time
    /// step").
    pub fn reject(&mut self, t1: f64, reason: &str, what: &str) -> Result<(), String> {
        let tried = t1 - self.t_done;
        self.dt = 0.5 * tried;
        if self.dt < self.min_step {
            return Err(format!(
                "step {} (t = {t1}) did not converge: {reason}; the {what} was {tried:.3e} after {} retry(ies) of this {what}, and the minimum is {:.3e}",
                self.steps + 1,
                self.retries,
                self.min_step
            ));
        }
        self.retries += 1;
        Ok(())
    }

    /// The attempt ending at `t1` converged in `iterations`: returns the step's number and
    /// how many retries it took, and grows the next step after an easy one.
    pub fn accept(&mut self, t1: f64, iterations: usize) -> (usize, usize) {
        self.steps += 1;
        let retries = self.retries;
        if iterations <= self.easy_iterations && retries == 0 {
            self.dt = (self.dt * self.growth).min(self.max_step);
        }
        self.t_done = t1;
        self.retries = 0;
        let eps = 1e-9 * self.end.abs().max(1.0);
        if self.stage + 1 < self.stages.len() && t1 >= self.stages[self.stage].end - eps {
            self.enter(self.stage + 1);
        }
        (self.steps, retries)
    }
}

/// `t` to 12 significant digits of the end time's decade, so sums of steps land on the
/// times a user reads (0.3, not 0.30000000000000004; issue 16): the nearest multiple of
/// 10^(e − 12) with 10^e ≥ |end|, computed as an integer over an exact power of ten.
pub fn snap(t: f64, end: f64) -> f64 {
    let e = end.abs().max(f64::MIN_POSITIVE).log10().ceil() as i32;
    if !(-280..=280).contains(&e) {
        return t;
    }
    // 10^(12 − e) is exact as a double for 12 − e ≤ 22; beyond, multiply by its inverse.
    let k = 12 - e;
    if (0..=22).contains(&k) {
        let s = 10f64.powi(k);
        let q = (t * s).round();
        if q.abs() < 9.0e15 {
            return q / s;
        }
    } else if (-22..0).contains(&k) {
        let s = 10f64.powi(-k);
        let q = (t / s).round();
        if q.abs() < 9.0e15 {
            return q * s;
        }
    }
    t
}

/// The pseudo-times of the steps at a constant step `dt` (for reports).
pub fn step_times(end: f64, dt: f64) -> Vec<f64> {
    let n = ((end / dt) - 1e-9).ceil().max(1.0) as usize;
    (1..=n)
        .map(|i| if i == n { end } else { i as f64 * dt })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solve::{AnalysisKind, MassKind, Scheme};

    fn analysis(step: f64, min: f64, max: f64) -> Analysis {
        Analysis {
            kind: AnalysisKind::Static,
            end_time: 1.0,
            step,
            min_step: min,
            max_step: max,
            scheme: Scheme::Newmark,
            rho_inf: 1.0,
            mass: MassKind::Consistent,
            dt_factor: 0.9,
            predictor: crate::solve::Predictor::Linear,
            stops: Vec::new(),
            stages: Vec::new(),
        }
    }

    /// Steps of 0.1 land on 0.3 and 0.7 exactly as a user writes them; steps that are
    /// not decimal (cuts by half) keep their binary values; any end time's decade.
    #[test]
    fn step_times_do_not_drift() {
        let mut c = StepControl::new(&analysis(0.1, 0.001, 0.1), 20);
        let mut times = Vec::new();
        while let Some((_, t)) = c.next() {
            c.accept(t, 10);
            times.push(t);
        }
        assert_eq!(times[2], 0.3);
        assert_eq!(times[6], 0.7);
        assert_eq!(times.len(), 10);
        assert_eq!(snap(0.1 + 0.2, 1.0), 0.3);
        assert_eq!(snap(0.125, 1.0), 0.125);
        assert_eq!(snap(3.0 * 0.1e-3, 2e-3), 0.3e-3);
        assert_eq!(snap(7.0 * 0.1e6, 1e6), 0.7e6);
        assert_eq!(snap(1.0 / 3.0, 1.0), 0.333333333333);
        // A step below the grain still moves on.
        let mut c = StepControl::new(&analysis(1e-14, 1e-16, 1e-14), 20);
        for _ in 0..3 {
            let (t0, t1) = c.next().unwrap();
            assert!(t1 > t0, "{t0} -> {t1}");
            c.accept(t1, 10);
        }
    }

    /// A controller resumed from another's state takes the same steps from there on.
    #[test]
    fn a_resumed_controller_continues_alike() {
        let a = analysis(0.2, 0.01, 0.4);
        let mut c = StepControl::new(&a, 20);
        for _ in 0..3 {
            let (_, t) = c.next().unwrap();
            c.accept(t, 2);
        }
        let mut d = StepControl::new(&a, 20);
        d.resume(&c.state());
        assert_eq!(d.state(), c.state());
        while let Some((t0, t1)) = c.next() {
            assert_eq!(d.next(), Some((t0, t1)));
            c.accept(t1, 2);
            d.accept(t1, 2);
        }
        assert_eq!(d.next(), None);
    }

    #[test]
    fn step_times_land_on_the_end() {
        assert_eq!(step_times(1.0, 0.25), vec![0.25, 0.5, 0.75, 1.0]);
        let t = step_times(1.0, 0.3);
        assert_eq!(t.len(), 4);
        assert_eq!(*t.last().unwrap(), 1.0);
        assert_eq!(step_times(1.0, 0.1).len(), 10);
    }

    #[test]
    fn cut_grow_and_give_up() {
        let mut c = StepControl::new(&analysis(0.5, 0.1, 0.5), 20);
        let (t0, t1) = c.next().unwrap();
        assert_eq!((t0, t1), (0.0, 0.5));
        // Fail twice: 0.25, then 0.125.
        c.reject(t1, "x", "step").unwrap();
        assert_eq!(c.next().unwrap().1, 0.25);
        c.reject(0.25, "x", "step").unwrap();
        assert_eq!(c.next().unwrap().1, 0.125);
        assert_eq!(c.accept(0.125, 2), (1, 2));
        // No growth after a step that needed retries; then growth by 1.5 after easy ones.
        assert_eq!(c.next().unwrap(), (0.125, 0.25));
        assert_eq!(c.accept(0.25, 2), (2, 0));
        let (_, t) = c.next().unwrap();
        assert!((t - (0.25 + 0.1875)).abs() < 1e-15);
        // A hard step does not grow it.
        assert_eq!(c.accept(t, 10), (3, 0));
        let (_, t2) = c.next().unwrap();
        assert!((t2 - t - 0.1875).abs() < 1e-15);
        // Below the minimum the run ends with the reason.
        let mut c = StepControl::new(&analysis(0.15, 0.1, 0.15), 20);
        let (_, t1) = c.next().unwrap();
        let e = c.reject(t1, "stagnated", "step").unwrap_err();
        assert!(e.contains("step 1") && e.contains("stagnated"), "{e}");
    }

    #[test]
    fn the_last_step_lands_on_the_end() {
        let mut c = StepControl::new(&analysis(0.3, 0.01, 0.3), 20);
        let mut times = Vec::new();
        while let Some((_, t1)) = c.next() {
            times.push(t1);
            c.accept(t1, 10);
        }
        assert_eq!(times.len(), 4);
        assert_eq!(*times.last().unwrap(), 1.0);
    }

    /// Steps end on the stops (a load reversal at t = 0.5 is reached exactly), also after
    /// a cut and regrowth that would step over it, and leave no sliver before one.
    #[test]
    fn steps_land_on_the_stops() {
        let mut a = analysis(0.3, 0.01, 0.3);
        a.stops = vec![0.5, 0.7];
        let mut c = StepControl::new(&a, 20);
        let mut times = Vec::new();
        while let Some((_, t1)) = c.next() {
            times.push(t1);
            c.accept(t1, 10);
        }
        assert_eq!(times, vec![0.3, 0.5, 0.7, 1.0]);
        // After a cut to 0.15 (0.15, 0.3) the step grows to 0.225: from 0.3 it would
        // pass 0.5; it stops on 0.5 instead.
        let mut c = StepControl::new(&a, 20);
        c.reject(0.3, "x", "step").unwrap();
        let (_, t) = c.next().unwrap();
        c.accept(t, 2);
        let (_, t) = c.next().unwrap();
        assert!((t - 0.3).abs() < 1e-15);
        c.accept(t, 2);
        assert_eq!(c.next().unwrap().1, 0.5);
        // Within 1e-3 of a step of a stop the step takes it (no sliver).
        let mut a = analysis(0.4999, 0.01, 0.4999);
        a.stops = vec![0.5];
        let c = StepControl::new(&a, 20);
        assert_eq!(c.next().unwrap().1, 0.5);
    }

    /// Each stage starts from its own increment and keeps to its bounds; its end is a
    /// stop (the scene adds it); `at_stage_start` holds before a later stage's first
    /// increment only.
    #[test]
    fn stages_have_their_own_increments() {
        let mut a = analysis(0.5, 0.01, 0.5);
        let stage = |name: &str, start: f64, end: f64, step: f64| Stage {
            name: name.into(),
            start,
            end,
            step,
            min_step: step / 100.0,
            max_step: step,
        };
        a.stages = vec![stage("a", 0.0, 0.5, 0.5), stage("b", 0.5, 1.0, 0.1)];
        a.stops = vec![0.5];
        let mut c = StepControl::new(&a, 20);
        let mut times = Vec::new();
        let mut starts = Vec::new();
        while let Some((_, t1)) = c.next() {
            starts.push(c.at_stage_start());
            times.push((c.stage(), t1));
            c.accept(t1, 2);
        }
        let want = [0.5, 0.6, 0.7, 0.8, 0.9, 1.0];
        assert_eq!(times.len(), want.len(), "{times:?}");
        for ((k, t), w) in times.iter().zip(want) {
            assert!((t - w).abs() < 1e-12, "{times:?}");
            assert_eq!(*k, usize::from(w > 0.5));
        }
        assert_eq!(starts, vec![false, true, false, false, false, false]);
        assert_eq!(a.stage_at(0.5), 0);
        assert_eq!(a.stage_at(0.55), 1);
    }
}
