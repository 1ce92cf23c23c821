//! `solver = "auto"`: per increment, start from the method that has been cheapest so far
//! and fall back along a chain instead of cutting the increment (PETSc's composite
//! SNES and its fallbacks; Abaqus/Standard's and LS-DYNA's automatic strategies):
//!
//! * JFNK → Newton with line search;
//! * BFGS → BFGS reformed every iteration → Newton with line search;
//! * Newton → Newton with line search.
//!
//! Each fallback starts again from the increment's start point. Only when the whole chain
//! fails is the increment cut. **Work is counted, not timed** — residual evaluations
//! (finite-difference products included) + w_f × factorizations + 0.1 × GMRES
//! iterations, w_f = (largest owned unknowns per rank)/1000 clamped to [2, 100] — so the
//! same deck on the same partition takes the same path on any machine, and a restart
//! (the state is in [`crate::solve::record::Resume`]) goes on as the uninterrupted run.
//! The first three increments try Newton, JFNK and BFGS; then the smallest moving
//! average of work per increment starts, the runner-up every [`RUNNER_UP_EVERY`]th.
//! A start whose chain had to fall back is charged the whole chain's work.

use super::{LineSearch, NonlinearOptions, SolveStats, SolverKind};

/// One link of a fallback chain: a named method or one of its robust variants.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Variant {
    Named(SolverKind),
    /// Newton with the backtracking line search on every correction.
    NewtonLs,
    /// BFGS reformed every iteration (Newton's direction with BFGS's line search).
    BfgsReformed,
}

impl Variant {
    pub fn name(self) -> &'static str {
        match self {
            Variant::Named(k) => k.name(),
            Variant::NewtonLs => "newton+ls",
            Variant::BfgsReformed => "bfgs-reformed",
        }
    }

    /// The options of this variant from the run's.
    pub fn options(self, base: &NonlinearOptions) -> NonlinearOptions {
        let mut o = base.clone();
        match self {
            Variant::Named(k) => o.kind = k,
            Variant::NewtonLs => {
                o.kind = SolverKind::Newton;
                o.line_search = LineSearch::On;
            }
            Variant::BfgsReformed => {
                o.kind = SolverKind::Bfgs;
                o.bfgs_reform = 1;
            }
        }
        o
    }
}

/// The fallback chain that starts with `kind`.
pub fn chain(kind: SolverKind) -> Vec<Variant> {
    match kind {
        SolverKind::Jfnk => vec![Variant::Named(kind), Variant::NewtonLs],
        SolverKind::Bfgs => vec![
            Variant::Named(kind),
            Variant::BfgsReformed,
            Variant::NewtonLs,
        ],
        _ => vec![Variant::Named(SolverKind::Newton), Variant::NewtonLs],
    }
}

/// A change of method within an increment, and why.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Switch {
    pub from: &'static str,
    pub to: &'static str,
    pub reason: String,
    /// The first entry of the increment's residual history that is `to`'s.
    pub at: usize,
}

/// The methods tried first, in this order, on the first increments.
pub const EXPLORE: [SolverKind; 3] = [SolverKind::Newton, SolverKind::Jfnk, SolverKind::Bfgs];
/// Weight of the newest increment in the moving average of work.
pub const EMA: f64 = 0.3;
/// The runner-up starts every this many increments (its cost drifts with the problem).
pub const RUNNER_UP_EVERY: usize = 10;
/// GMRES iterations' weight in the work count.
pub const GMRES_WEIGHT: f64 = 0.1;

/// What `auto` has learned over the run (saved in restart files).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct AutoState {
    /// Moving average of work per increment started by each of [`EXPLORE`].
    pub work: [Option<f64>; 3],
    /// Increments solved so far.
    pub increments: usize,
    /// A factorization's weight in residual evaluations.
    pub factor_weight: f64,
}

impl AutoState {
    /// For a run whose largest rank owns `max_owned` unknowns.
    pub fn new(max_owned: usize) -> Self {
        Self {
            factor_weight: (max_owned as f64 / 1000.0).clamp(2.0, 100.0),
            ..Default::default()
        }
    }

    fn index(kind: SolverKind) -> usize {
        EXPLORE.iter().position(|&k| k == kind).unwrap_or(0)
    }

    /// The method that starts the next increment.
    pub fn choose(&self) -> SolverKind {
        if self.increments < EXPLORE.len() {
            return EXPLORE[self.increments];
        }
        let mut ranked: Vec<(f64, usize)> = (0..EXPLORE.len())
            .map(|i| (self.work[i].unwrap_or(f64::INFINITY), i))
            .collect();
        ranked.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let runner_up = self.increments.is_multiple_of(RUNNER_UP_EVERY) && ranked[1].0.is_finite();
        EXPLORE[ranked[usize::from(runner_up)].1]
    }

    /// The work count of a solve's statistics.
    pub fn work_of(&self, s: &SolveStats) -> f64 {
        s.residual_evaluations as f64
            + self.factor_weight * s.factorizations as f64
            + GMRES_WEIGHT * s.linear_iterations as f64
    }

    /// The increment started by `kind` cost `work` (its whole chain's).
    pub fn record(&mut self, kind: SolverKind, work: f64) {
        let w = &mut self.work[Self::index(kind)];
        *w = Some(match *w {
            Some(old) => (1.0 - EMA) * old + EMA * work,
            None => work,
        });
        self.increments += 1;
    }
}

/// Add a fallback attempt's statistics `s` to the increment's `total`: counts and times
/// summed, histories appended, the outcome `s`'s.
pub fn merge(total: &mut SolveStats, s: SolveStats) {
    total.converged = s.converged;
    total.iterations += s.iterations;
    total.linear_iterations += s.linear_iterations;
    total.residual_evaluations += s.residual_evaluations;
    total.factorizations += s.factorizations;
    total.residual_history.extend(s.residual_history);
    total.reason = s.reason;
    total.failure = s.failure;
    total.seconds_assembly += s.seconds_assembly;
    total.seconds_linear += s.seconds_linear;
    total.seconds_pc_setup += s.seconds_pc_setup;
    total.coarse = s.coarse.or(total.coarse);
    total.fd_products += s.fd_products;
    total.predictor_solves += s.predictor_solves;
    total.backtracks += s.backtracks;
    total.reforms += s.reforms;
    total.method = s.method;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_chain_ends_in_newton_with_line_search() {
        for k in EXPLORE {
            let c = chain(k);
            assert_eq!(c[0], Variant::Named(k));
            assert_eq!(*c.last().unwrap(), Variant::NewtonLs);
        }
        assert_eq!(chain(SolverKind::Bfgs)[1], Variant::BfgsReformed);
    }

    #[test]
    fn explores_then_takes_the_cheapest_and_the_runner_up_every_tenth() {
        let mut s = AutoState::new(10_000);
        assert_eq!(s.factor_weight, 10.0);
        let costs = [
            (SolverKind::Newton, 50.0),
            (SolverKind::Jfnk, 20.0),
            (SolverKind::Bfgs, 80.0),
        ];
        for (k, w) in costs {
            assert_eq!(s.choose(), k);
            s.record(k, w);
        }
        let mut picks = Vec::new();
        for _ in 3..12 {
            let k = s.choose();
            picks.push(k);
            let w = costs.iter().find(|c| c.0 == k).unwrap().1;
            s.record(k, w);
        }
        // Increment 10 (0-based) goes to the runner-up, Newton; the others to JFNK.
        assert_eq!(picks[7], SolverKind::Newton, "{picks:?}");
        assert!(picks
            .iter()
            .enumerate()
            .all(|(i, &k)| i == 7 || k == SolverKind::Jfnk));
        // A method whose increments turn expensive (a fallback's whole chain) is dropped.
        for _ in 0..6 {
            s.record(SolverKind::Jfnk, 500.0);
        }
        assert_ne!(s.choose(), SolverKind::Jfnk);
    }

    /// Newton and JFNK diverge on the atan spring from d = 3 (a full Newton step
    /// overshoots to growing |d|); `auto` falls back to Newton with line search, which
    /// converges, instead of failing the increment. Named Newton alone fails.
    #[test]
    fn newton_and_jfnk_fall_back_to_newton_with_line_search() {
        use crate::parallel::SerialComm;
        use crate::solve::nonlinear::testing::{equilibrium, options, solve, solver, Toy};
        use crate::solve::nonlinear::Start;
        let named = options(SolverKind::Newton);
        let mut toy = Toy::new(0.0, 1.0, 0.5);
        let st = solve(&named, &mut toy, &mut [0.0, 3.0, 6.0], 0.0, Start::Tangent);
        assert!(!st.converged);
        let opts = options(SolverKind::Auto);
        let mut s = solver(&opts);
        for first in ["newton", "jfnk"] {
            let mut toy = Toy::new(0.0, 1.0, 0.5);
            let (mut u, mut r) = ([0.0, 3.0, 6.0], [0.0; 3]);
            let st = s
                .solve(
                    &SerialComm,
                    &mut toy,
                    &mut u,
                    &mut r,
                    &[(0, 0.0)],
                    Start::Tangent,
                )
                .unwrap();
            assert!(st.converged, "{first}: {}", st.reason);
            assert_eq!(st.switches.len(), 1, "{first}");
            assert_eq!(
                (st.switches[0].from, st.switches[0].to),
                (first, "newton+ls")
            );
            assert_eq!(st.method, "newton+ls");
            let e = equilibrium(&toy, 0.0);
            assert!((u[2] - e[2]).abs() < 1e-8, "{first}: {u:?} against {e:?}");
        }
        assert_eq!(s.auto.increments, 2);
    }

    #[test]
    fn variants_set_their_options() {
        let base = crate::solve::nonlinear::testing::options(SolverKind::Jfnk);
        let o = Variant::NewtonLs.options(&base);
        assert_eq!(
            (o.kind, o.line_search),
            (SolverKind::Newton, LineSearch::On)
        );
        let o = Variant::BfgsReformed.options(&base);
        assert_eq!((o.kind, o.bfgs_reform), (SolverKind::Bfgs, 1));
    }
}
