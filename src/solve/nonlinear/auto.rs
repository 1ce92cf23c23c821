//! `solver = "auto"`: per increment, start from the method that has been cheapest so far
//! and fall back along a chain instead of cutting the increment (PETSc's composite
//! SNES and its fallbacks; Abaqus/Standard's and LS-DYNA's automatic strategies):
//!
//! * JFNK → JFNK with line search → Newton with line search;
//! * BFGS → BFGS reformed every iteration → Newton with line search;
//! * Newton → Newton with line search.
//!
//! Each fallback starts again from the increment's start point. Only when the whole chain
//! fails is the increment cut. **Cost is measured wall time** (the slowest rank's, so
//! every rank chooses alike), not a count. `scripts/auto-calibration` fitted work =
//! residual evaluations + w_f factorizations + w_g GMRES iterations to the wall times of
//! the three methods on ten scenes: the best constants (w_f 20-30, w_g 2) rank whole
//! runs right, but a factorization costs 5 to 40 residual evaluations depending on the
//! scene (an entity's rigid DOFs couple every contact node; plasticity makes residuals
//! dear), and comparing increments with them `auto` took Newton and JFNK as equals on
//! sphere-roll, where JFNK is twice as fast: 1.55x the fastest method's time there and
//! 1.95x on taylor-bar, against 1.24x and 1.18x timed. The price: two runs of one deck
//! can choose differently, so their answers agree to the solver's tolerance, not bit
//! for bit (name a solver for that). The state is in
//! [`crate::solve::record::Resume`], so a restart goes on with what was learned.
//!
//! The first increment (contact closing, the first factorization) is JFNK's and not
//! recorded; the next two try JFNK and BFGS; then the smallest moving average of cost per
//! increment starts. Another method starts as a probe after [`RUNNER_UP_EVERY`]
//! increments if it is unknown (Newton) or within [`RUNNER_UP_WITHIN`] of the cheapest;
//! each probe that loses doubles that method's interval, and what a method was measured
//! at fades ([`FORGET`]) while it is not run. A probe that fails falls back to the
//! cheapest method's chain before Newton with line search. A start whose chain had to
//! fall back is charged the whole chain's cost, but one increment enters an average at
//! no more than [`OUTLIER_CAP`] times it. The cheapest method's clean increments (no
//! fallback) measure the problem's own drift, and the other averages move with them
//! ([`AutoState::record`]). A link that would repeat an earlier one is skipped
//! ([`distinct`]); a full-step Newton or JFNK link with a fallback behind it stagnates
//! early ([`EARLY_WINDOW`]); a clean probe's cost replaces its method's stale average;
//! an exploring or probing method that runs past [`PROBE_BUDGET`] times the cheapest's
//! average increment gives way to the cheapest's chain. An element that cannot be
//! evaluated ends the chain (the step is cut).

use super::{LineSearch, NonlinearOptions, SolveStats, SolverKind};

/// One link of a fallback chain: a named method or one of its robust variants.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Variant {
    Named(SolverKind),
    /// Newton with the backtracking line search on every correction.
    NewtonLs,
    /// JFNK with it: full JFNK steps fail where the residual is not monotone along them
    /// (b-pillar's contact closing on the sheet, bolted-bracket's load reversal), and
    /// Newton with line search there costs a factorization per iteration.
    JfnkLs,
    /// BFGS reformed every iteration (Newton's direction with BFGS's line search).
    BfgsReformed,
}

impl Variant {
    pub fn name(self) -> &'static str {
        match self {
            Variant::Named(k) => k.name(),
            Variant::NewtonLs => "newton+ls",
            Variant::JfnkLs => "jfnk+ls",
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
            Variant::JfnkLs => {
                o.kind = SolverKind::Jfnk;
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
        SolverKind::Jfnk => vec![Variant::Named(kind), Variant::JfnkLs, Variant::NewtonLs],
        SolverKind::Bfgs => vec![
            Variant::Named(kind),
            Variant::BfgsReformed,
            Variant::NewtonLs,
        ],
        _ => vec![Variant::Named(SolverKind::Newton), Variant::NewtonLs],
    }
}

/// The links an increment tries: `first`'s chain, then (a probe failing) the chain of
/// `incumbent`, the cheapest so far, before Newton with line search: a probe never
/// costs a cut that the incumbent would not have.
pub fn links(first: SolverKind, incumbent: SolverKind) -> Vec<Variant> {
    let mut l = chain(first);
    l.pop();
    for v in chain(incumbent) {
        if !l.contains(&v) {
            l.push(v);
        }
    }
    l
}

/// The links an increment tries with their options, without a link that repeats an
/// earlier one: with `line_search = true` in the deck Newton already is Newton with line
/// search, and running it again from the same start point fails the same way. A
/// full-step Newton or JFNK link with another behind it stagnates after
/// [`EARLY_WINDOW`] iterations ([`early`]).
pub fn distinct(links: &[Variant], base: &NonlinearOptions) -> Vec<(Variant, NonlinearOptions)> {
    let mut out: Vec<(Variant, NonlinearOptions)> = Vec::new();
    for &v in links {
        let o = v.options(base);
        if !out.iter().any(|(_, p)| same_method(p, &o)) {
            out.push((v, o));
        }
    }
    let last = out.len().saturating_sub(1);
    for (_, o) in &mut out[..last] {
        if early(o) {
            o.stagnation_window = Some(EARLY_WINDOW.min(o.max_iterations));
        }
    }
    out
}

/// Iterations without a 10 % fall of the relative residual after which a full-step
/// Newton or JFNK link gives way to the next link (the named solvers wait max(8, half
/// the budget)). Measured on the `--iterations` histories of the ten calibration scenes
/// and of b-pillar (JFNK, 288 solves): a window of 6 never stopped a full-step Newton or
/// JFNK solve that went on to converge, 5 stopped one on b-pillar, and with backtracking
/// (Armijo) or BFGS 6 stopped solves that would have converged (b-pillar, seal,
/// sphere-roll, clip-tensile), so those keep the named solvers' window. On clip-tensile's
/// first increment JFNK wanders near a relative residual of 1 for 20 iterations before
/// the named window gives up.
pub const EARLY_WINDOW: usize = 6;

/// Whether a link takes full Newton steps (no Armijo on every correction, not BFGS):
/// such a solve that has not gained 10 % in [`EARLY_WINDOW`] iterations seldom
/// converges. Named Newton on b-pillar's contact closing is the exception (6 of its 235
/// converged solves have 6 to 8 iterations without a 10 % gain), but with the named
/// window there `auto`'s full Newton steps wander to iterates where the EAS sheet
/// elements fail, and the run took longer (182 s against 80 s from 60 to 65 mm).
fn early(o: &NonlinearOptions) -> bool {
    matches!(o.kind, SolverKind::Newton | SolverKind::Jfnk) && o.line_search != LineSearch::On
}

/// Where the incumbent's chain starts among an increment's `links` (a probe over its
/// budget goes on there).
pub fn incumbent_link(
    links: &[(Variant, NonlinearOptions)],
    incumbent: SolverKind,
) -> Option<usize> {
    let c = chain(incumbent);
    links.iter().position(|(v, _)| c.contains(v))
}

/// Whether two option sets run the same iteration (BFGS always searches its line).
fn same_method(a: &NonlinearOptions, b: &NonlinearOptions) -> bool {
    a.kind == b.kind
        && match a.kind {
            SolverKind::Bfgs => a.bfgs_reform == b.bfgs_reform,
            _ => a.line_search == b.line_search,
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

/// The methods `auto` chooses among, in the order ties are broken.
pub const METHODS: [SolverKind; 3] = [SolverKind::Jfnk, SolverKind::Bfgs, SolverKind::Newton];
/// The methods tried first, in this order, on the increments after the first. Newton,
/// the most expensive per increment on every scene measured, waits for its first probe:
/// a run of a few increments does not pay for it.
pub const EXPLORE: [SolverKind; 2] = [SolverKind::Jfnk, SolverKind::Bfgs];
/// The first increment (contact closing, the first factorization) is solved by
/// `EXPLORE[0]` and not recorded: it would rank the method that happened to take it.
pub const WARM_UP: usize = 1;
/// Per increment, the excess of a method's average over the cheapest's shrinks by this
/// factor while it is not run: what was measured long ago is not held against it for
/// ever (with [`RUNNER_UP_WITHIN`], a method twice as expensive is probed again after
/// about 17 increments, and the backoff keeps such probes rare). 0.93 (about ten) had
/// the seal's BFGS, 2.3 times JFNK's increment, probed again at its 19th of 20
/// increments: 1.30x the fastest named solver there, 1.05x with 0.96 (medians of three
/// calibration runs; the other nine scenes within the runs' noise).
pub const FORGET: f64 = 0.96;
/// Weight of the newest increment in the moving average of cost.
pub const EMA: f64 = 0.3;
/// An increment enters a known average at no more than this multiple of it: one hard
/// increment (a fallback chain) does not dethrone a method, a run of them does.
pub const OUTLIER_CAP: f64 = 2.0;
/// A method other than the cheapest starts an increment (a probe: costs drift with the
/// problem) after this many increments; the interval doubles each time a probe loses.
pub const RUNNER_UP_EVERY: usize = 10;
/// ... and only if its moving average is at most this multiple of the cheapest's.
pub const RUNNER_UP_WITHIN: f64 = 1.5;
/// A method other than the cheapest (exploring, or a probe) gives up its increment when
/// it has taken this many of the cheapest method's average increments, and the
/// increment goes on with the cheapest's chain: having cost twice what
/// [`RUNNER_UP_WITHIN`] allows, it has lost, and the rest of its own chain could only add
/// to the loss. On bolted-bracket (2 ranks) BFGS's exploring increment took 20.5 s
/// (17 iterations) against JFNK's 2-8 s, 15 % of the run.
pub const PROBE_BUDGET: f64 = 3.0;
/// What `auto` has learned over the run (saved in restart files).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct AutoState {
    /// Moving average of the wall seconds of the increments each of [`METHODS`] started.
    pub work: [Option<f64>; 3],
    /// Increments solved so far.
    pub increments: usize,
    /// The increment from which each method may start as a probe, and its interval.
    pub probe_at: [usize; 3],
    pub probe_every: [usize; 3],
}

impl Default for AutoState {
    fn default() -> Self {
        Self {
            work: [None; 3],
            increments: 0,
            probe_at: [RUNNER_UP_EVERY; 3],
            probe_every: [RUNNER_UP_EVERY; 3],
        }
    }
}

impl AutoState {
    fn index(kind: SolverKind) -> usize {
        METHODS.iter().position(|&k| k == kind).unwrap_or(2)
    }

    /// The method with the smallest moving average (none before any is known).
    fn cheapest(&self) -> Option<usize> {
        (0..METHODS.len())
            .filter_map(|i| self.work[i].map(|w| (w, i)))
            .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
            .map(|(_, i)| i)
    }

    /// The method that starts the next increment: an unexplored one, a probe that is
    /// due, or the cheapest.
    pub fn choose(&self) -> SolverKind {
        if self.increments < WARM_UP + EXPLORE.len() {
            return EXPLORE[self.increments.saturating_sub(WARM_UP)];
        }
        let Some(best) = self.cheapest() else {
            return METHODS[0];
        };
        let limit = RUNNER_UP_WITHIN * self.work[best].unwrap_or(f64::INFINITY);
        let probe = (0..METHODS.len())
            .filter(|&i| i != best && self.increments >= self.probe_at[i])
            .filter(|&i| self.work[i].is_none_or(|w| w <= limit))
            .min_by(|&a, &b| {
                // The unknown first, then the cheaper.
                let w = |i: usize| self.work[i].unwrap_or(f64::NEG_INFINITY);
                w(a).total_cmp(&w(b)).then(a.cmp(&b))
            });
        METHODS[probe.unwrap_or(best)]
    }

    /// The cheapest method so far (the incumbent a failed probe falls back to).
    pub fn incumbent(&self) -> SolverKind {
        self.cheapest().map_or(EXPLORE[0], |i| METHODS[i])
    }

    /// The seconds an increment started by `first` may take before it gives way to the
    /// incumbent's chain: [`PROBE_BUDGET`] times the cheapest method's average when
    /// `first` is another method (an exploration or a probe), else none.
    pub fn budget(&self, first: SolverKind) -> Option<f64> {
        let best = self.cheapest().filter(|&b| b != Self::index(first))?;
        self.work[best].map(|w| PROBE_BUDGET * w)
    }

    /// The increment started by `kind` cost `work` seconds (its whole chain's; `clean`:
    /// its first link converged). A probe that cost more than the cheapest's average
    /// doubles its method's probe interval; a method that loses first place waits a full
    /// interval before its probe. A clean probe's cost replaces its method's average,
    /// which is stale: on b-pillar Newton's probes of 0.65-1.0 s against BFGS's 1.2 s
    /// increments moved an average raised by the contact closing's fallbacks too little,
    /// and BFGS kept 50 increments Newton would have taken cheaper. When the cheapest
    /// method's clean increments grow dearer or cheaper, the problem did (sphere-roll's
    /// rolling costs four times its pressing), so the other methods' averages, measured
    /// earlier, move by the same factor: compared with the pressing's cheap increments,
    /// BFGS and Newton looked cheaper than JFNK rolling and started 9 of its 24 rolling
    /// increments.
    pub fn record(&mut self, kind: SolverKind, work: f64, clean: bool) {
        if self.increments < WARM_UP {
            self.increments += 1;
            return;
        }
        let i = Self::index(kind);
        let best = self.cheapest();
        if self.increments >= WARM_UP + EXPLORE.len() && best.is_some_and(|b| b != i) {
            let lost = best.and_then(|b| self.work[b]).is_some_and(|w| work > w);
            self.probe_every[i] = if lost {
                2 * self.probe_every[i]
            } else {
                RUNNER_UP_EVERY
            };
            self.probe_at[i] = self.increments + 1 + self.probe_every[i];
        }
        let before = self.work[i];
        let probe = clean && best.is_some_and(|b| b != i);
        let after = match before {
            Some(old) if !probe => (1.0 - EMA) * old + EMA * work.min(OUTLIER_CAP * old),
            _ => work,
        };
        self.work[i] = Some(after);
        if let (true, Some(old)) = (clean && best == Some(i), before.filter(|&o| o > 0.0)) {
            for (j, w) in self.work.iter_mut().enumerate() {
                if let Some(w) = w.as_mut().filter(|_| j != i) {
                    *w *= after / old;
                }
            }
        }
        if let Some(old) = best.filter(|&b| Some(b) != self.cheapest()) {
            let at = self.increments + 1 + self.probe_every[old];
            self.probe_at[old] = self.probe_at[old].max(at);
        }
        if let Some(b) = self.cheapest().filter(|&b| b == i) {
            let wb = self.work[b].unwrap_or(0.0);
            for (j, w) in self.work.iter_mut().enumerate() {
                if let Some(w) = w.as_mut().filter(|_| j != b) {
                    *w = wb + (*w - wb) * FORGET;
                }
            }
        }
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
    total.assembled_directions += s.assembled_directions;
    total.method = s.method;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_chain_ends_in_newton_with_line_search() {
        for k in METHODS {
            let c = chain(k);
            assert_eq!(c[0], Variant::Named(k));
            assert_eq!(*c.last().unwrap(), Variant::NewtonLs);
        }
        assert_eq!(chain(SolverKind::Bfgs)[1], Variant::BfgsReformed);
        assert_eq!(chain(SolverKind::Jfnk)[1], Variant::JfnkLs);
    }

    /// Runs `n` increments whose work is `cost(method)`; the methods that started them.
    fn drive(s: &mut AutoState, n: usize, cost: impl Fn(SolverKind) -> f64) -> Vec<SolverKind> {
        drive_as(s, n, cost, true)
    }

    /// As [`drive`], every increment having fallen back (not clean).
    fn drive_chains(
        s: &mut AutoState,
        n: usize,
        cost: impl Fn(SolverKind) -> f64,
    ) -> Vec<SolverKind> {
        drive_as(s, n, cost, false)
    }

    fn drive_as(
        s: &mut AutoState,
        n: usize,
        cost: impl Fn(SolverKind) -> f64,
        clean: bool,
    ) -> Vec<SolverKind> {
        (0..n)
            .map(|_| {
                let k = s.choose();
                s.record(k, cost(k), clean);
                k
            })
            .collect()
    }

    fn costs(jfnk: f64, bfgs: f64, newton: f64) -> impl Fn(SolverKind) -> f64 {
        move |k| match k {
            SolverKind::Jfnk => jfnk,
            SolverKind::Bfgs => bfgs,
            _ => newton,
        }
    }

    #[test]
    fn explores_then_takes_the_cheapest_and_probes_newton_then_the_runner_up() {
        use SolverKind::*;
        let mut s = AutoState::default();
        let picks = drive(&mut s, 12, costs(20.0, 25.0, 26.0));
        // The warm-up increment, then JFNK and BFGS explored, JFNK cheapest; at 10 the
        // unknown Newton is probed (it loses), at 11 BFGS, within 1.5x (it loses too).
        let mut want = vec![Jfnk, Jfnk, Bfgs];
        want.extend([Jfnk; 7]);
        want.extend([Newton, Bfgs]);
        assert_eq!(picks, want);
        // Lost probes come back after twice the interval: BFGS at 11 + 1 + 20 = 32.
        assert_eq!(s.probe_at[AutoState::index(Bfgs)], 32);
        let later = drive(&mut s, 40, costs(20.0, 25.0, 26.0));
        let at = |k| (12..52).filter(|&i| later[i - 12] == k).collect::<Vec<_>>();
        assert_eq!(at(Newton), [31]);
        assert_eq!(at(Bfgs), [32]);
        // A method whose increments turn expensive (a fallback's whole chain) is dropped
        // for one within the 30 % one such increment adds (BFGS at 25 against 20).
        let picks = drive_chains(&mut s, 3, costs(500.0, 25.0, 26.0));
        assert_eq!(picks[0], Jfnk);
        assert!(!picks[1..].contains(&Jfnk), "{picks:?}");
    }

    /// A method far behind is probed again only as its excess is forgotten, and never
    /// more often: a few probes in 200 increments, each method's gaps not shrinking (a
    /// lost probe's cost replaces the faded average, so the fade sets the gap: about 45
    /// increments at 4 times the cheapest's cost, more than twice the interval).
    #[test]
    fn a_method_far_behind_is_probed_rarely() {
        use SolverKind::*;
        let mut s = AutoState::default();
        let picks = drive(&mut s, 200, costs(20.0, 80.0, 41.0));
        for k in [Bfgs, Newton] {
            let at: Vec<usize> = (3..200).filter(|&i| picks[i] == k).collect();
            assert!(!at.is_empty() && at.len() <= 4, "{k:?} at {at:?}");
            for w in at.windows(3) {
                assert!(w[2] - w[1] + 2 >= w[1] - w[0], "{k:?} at {at:?}");
            }
            for w in at.windows(2) {
                assert!(w[1] - w[0] >= 2 * RUNNER_UP_EVERY, "{k:?} at {at:?}");
            }
        }
    }

    /// One increment at 25 times the average (a fallback chain) raises it by 30 %, not
    /// 7.2 times: the method keeps its place.
    #[test]
    fn one_hard_increment_does_not_dethrone_a_method() {
        use SolverKind::*;
        let mut s = AutoState::default();
        drive(&mut s, 5, costs(20.0, 30.0, 30.0));
        s.record(Jfnk, 500.0, false);
        assert_eq!(s.work[AutoState::index(Jfnk)], Some(26.0));
        assert_eq!(s.choose(), Jfnk);
    }

    /// The problem grows four times dearer for every method (sphere-roll from pressing
    /// to rolling): JFNK stays the cheapest and the others start only their scheduled
    /// probes (3 of 24 increments), not every increment their stale, cheaper averages
    /// would win (9 of 24 before the averages moved with the problem).
    #[test]
    fn costs_that_drift_with_the_problem_keep_the_ranking() {
        use SolverKind::*;
        let mut s = AutoState::default();
        drive(&mut s, 20, costs(10.0, 25.0, 30.0));
        let picks = drive(&mut s, 24, costs(40.0, 100.0, 120.0));
        let others = picks.iter().filter(|&&k| k != Jfnk).count();
        assert!(others <= 3, "{picks:?}");
        assert_eq!(s.choose(), Jfnk);
    }

    /// A probe that wins is taken from then on.
    #[test]
    fn a_probe_that_wins_takes_over() {
        use SolverKind::*;
        let mut s = AutoState::default();
        drive(&mut s, 10, costs(20.0, 40.0, 15.0));
        let picks = drive(&mut s, 5, costs(20.0, 40.0, 15.0));
        assert_eq!(picks, [Newton; 5]);
    }

    /// A method whose average was raised long ago (b-pillar's contact closing, where
    /// Newton's increments fell back) is taken at its first clean probe that beats the
    /// incumbent, not after its old average has faded.
    #[test]
    fn a_clean_probe_replaces_a_stale_average() {
        use SolverKind::*;
        let mut s = AutoState::default();
        drive(&mut s, 12, costs(10.0, 12.0, 50.0));
        // Newton's average, raised long ago, has faded to within reach of a probe.
        s.work[2] = Some(14.0);
        s.probe_at[2] = s.increments;
        let picks = drive(&mut s, 10, costs(10.0, 12.0, 6.0));
        assert_eq!(picks, [Newton; 10], "taken at its first probe");
        // A chain (not clean) is averaged as before: one cheap chain does not crown it.
        let mut s = AutoState::default();
        drive(&mut s, 12, costs(10.0, 12.0, 50.0));
        s.work[2] = Some(14.0);
        s.probe_at[2] = s.increments;
        assert_eq!(s.choose(), Newton);
        drive_chains(&mut s, 1, |_| 6.0);
        assert!(s.work[2].unwrap() > 10.0, "{:?}", s.work);
        assert_eq!(s.choose(), Jfnk);
    }

    /// Newton and JFNK diverge on the atan spring from d = 3 (a full Newton step
    /// overshoots to growing |d|); `auto` falls back to the method with line search,
    /// which converges, instead of failing the increment. Named Newton alone fails.
    #[test]
    fn newton_and_jfnk_fall_back_to_their_line_search() {
        use crate::parallel::SerialComm;
        use crate::solve::nonlinear::testing::{equilibrium, options, solve, solver, Toy};
        use crate::solve::nonlinear::Start;
        let named = options(SolverKind::Newton);
        let mut toy = Toy::new(0.0, 1.0, 0.5);
        let st = solve(&named, &mut toy, &mut [0.0, 3.0, 6.0], 0.0, Start::Tangent);
        assert!(!st.converged);
        let opts = options(SolverKind::Auto);
        let mut s = solver(&opts);
        for first in ["jfnk", "newton"] {
            if first == "newton" {
                // Newton starts once it is known to be the cheapest.
                s.auto.work = [Some(10.0), Some(10.0), Some(1.0)];
                s.auto.increments = WARM_UP + EXPLORE.len();
            }
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
            let to = if first == "jfnk" {
                "jfnk+ls"
            } else {
                "newton+ls"
            };
            assert_eq!((st.switches[0].from, st.switches[0].to), (first, to));
            assert_eq!(st.method, to);
            let e = equilibrium(&toy, 0.0);
            assert!((u[2] - e[2]).abs() < 1e-8, "{first}: {u:?} against {e:?}");
        }
        assert_eq!(s.auto.increments, WARM_UP + EXPLORE.len() + 1);
    }

    /// An element that cannot be evaluated (past the first iteration here, however
    /// short the step) ends the chain: one link, no switch, the increment is cut.
    #[test]
    fn an_element_failure_ends_the_chain() {
        use crate::solve::nonlinear::testing::{options, solve, Toy};
        use crate::solve::nonlinear::Start;
        let mut toy = Toy::new(0.0, 1.0, 0.5);
        toy.fail_after = 2;
        let opts = options(SolverKind::Auto);
        let st = solve(&opts, &mut toy, &mut [0.0, 3.0, 6.0], 0.0, Start::Tangent);
        assert!(!st.converged);
        assert_eq!(
            st.failure,
            Some(super::super::Failure::Element),
            "{}",
            st.reason
        );
        assert!(st.switches.is_empty(), "{:?}", st.switches);
        assert_eq!(st.method, "jfnk");
    }

    /// A probe's chain falls back to the incumbent's method before Newton with line
    /// search.
    #[test]
    fn a_probe_falls_back_to_the_incumbent() {
        use SolverKind::*;
        let names = |l: Vec<Variant>| l.iter().map(|v| v.name()).collect::<Vec<_>>();
        assert_eq!(
            names(links(Newton, Jfnk)),
            ["newton", "jfnk", "jfnk+ls", "newton+ls"]
        );
        assert_eq!(
            names(links(Bfgs, Jfnk)),
            ["bfgs", "bfgs-reformed", "jfnk", "jfnk+ls", "newton+ls"]
        );
        assert_eq!(names(links(Jfnk, Jfnk)), ["jfnk", "jfnk+ls", "newton+ls"]);
    }

    /// With `line_search = true` Newton with line search repeats Newton and is dropped;
    /// with BFGS reformed every iteration in the deck, the reformed link repeats BFGS.
    #[test]
    fn links_that_repeat_an_earlier_one_are_dropped() {
        use SolverKind::*;
        let names = |l: Vec<(Variant, NonlinearOptions)>| {
            l.iter().map(|(v, _)| v.name()).collect::<Vec<_>>()
        };
        let mut base = crate::solve::nonlinear::testing::options(Jfnk);
        base.line_search = LineSearch::Auto;
        assert_eq!(
            names(distinct(&links(Newton, Jfnk), &base)),
            ["newton", "jfnk", "jfnk+ls", "newton+ls"]
        );
        base.line_search = LineSearch::On;
        assert_eq!(
            names(distinct(&links(Newton, Jfnk), &base)),
            ["newton", "jfnk"]
        );
        assert_eq!(
            names(distinct(&links(Bfgs, Bfgs), &base)),
            ["bfgs", "bfgs-reformed", "newton+ls"]
        );
        base.bfgs_reform = 1;
        assert_eq!(
            names(distinct(&links(Bfgs, Bfgs), &base)),
            ["bfgs", "newton+ls"]
        );
    }

    /// Full-step Newton and JFNK links with a link behind them give way after
    /// [`EARLY_WINDOW`] iterations; backtracking links, BFGS and the last link keep the
    /// named solvers' window.
    #[test]
    fn full_step_links_with_a_fallback_stagnate_early() {
        use SolverKind::*;
        let windows = |first, base: &NonlinearOptions| {
            distinct(&links(first, Jfnk), base)
                .iter()
                .map(|(v, o)| (v.name(), o.stagnation_window))
                .collect::<Vec<_>>()
        };
        let mut base = crate::solve::nonlinear::testing::options(Jfnk);
        base.line_search = LineSearch::Auto;
        let e = Some(EARLY_WINDOW);
        assert_eq!(
            windows(Jfnk, &base),
            [("jfnk", e), ("jfnk+ls", None), ("newton+ls", None)]
        );
        assert_eq!(
            windows(Newton, &base),
            [
                ("newton", e),
                ("jfnk", e),
                ("jfnk+ls", None),
                ("newton+ls", None)
            ]
        );
        assert_eq!(
            windows(Bfgs, &base)[..2],
            [("bfgs", None), ("bfgs-reformed", None)]
        );
        base.line_search = LineSearch::On;
        assert_eq!(windows(Newton, &base), [("newton", None), ("jfnk", None)]);
        // A budget below the window bounds it.
        base.line_search = LineSearch::Off;
        base.max_iterations = 4;
        assert_eq!(windows(Jfnk, &base)[0], ("jfnk", Some(4)));
    }

    /// Only a start by another method than the cheapest has a budget, three of the
    /// cheapest's average increments; over it, the increment goes on with the cheapest's
    /// chain, skipping the rest of the probe's own.
    #[test]
    fn a_probe_gives_way_to_the_incumbent_past_its_budget() {
        use SolverKind::*;
        let mut s = AutoState::default();
        assert_eq!(s.budget(Jfnk), None, "nothing known");
        drive(&mut s, 2, costs(2.0, 20.0, 30.0));
        assert_eq!(s.choose(), Bfgs, "exploring");
        assert_eq!(s.budget(Bfgs), Some(PROBE_BUDGET * 2.0));
        assert_eq!(s.budget(Jfnk), None, "the cheapest has no budget");
        let base = crate::solve::nonlinear::testing::options(Jfnk);
        let l = distinct(&links(Bfgs, Jfnk), &base);
        let at = incumbent_link(&l, Jfnk).unwrap();
        assert_eq!(l[at].0, Variant::Named(Jfnk));
        assert_eq!(at, 2, "after bfgs and bfgs-reformed");
        let l = distinct(&links(Newton, Bfgs), &base);
        assert_eq!(l[incumbent_link(&l, Bfgs).unwrap()].0, Variant::Named(Bfgs));
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
