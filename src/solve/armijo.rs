//! `line_search = "auto"` across increments: when Armijo backtracking replaces full
//! Newton steps, for the step loops of static and implicit runs.
//!
//! * Newton and JFNK: full steps until an attempt fails because full steps do not get
//!   on (stagnation, divergence, an element that cannot be evaluated). Its retries and
//!   the increments after it then backtrack on every correction, until
//!   [`CLEAN_INCREMENTS`] increments in a row converge without a backtrack. Full steps
//!   fail the same way again and again where the residual is not monotone along them:
//!   on b-pillar's first 20 mm (contact closing on EAS sheet elements) JFNK with full
//!   steps took 107 steps and 35 retries, with Armijo 40 steps and none. Armijo with no
//!   backtrack costs nothing (the full step is its first trial), and scenes that
//!   converge with full steps (large rotations, where always-on backtracking slows
//!   Newton) never turn it on. Not after the iteration budget or a linear solve (shorter
//!   steps only converge slower), and not after stick/slip cycling beyond the retries
//!   (below): `cylinder-press` with `max_iterations = 4` then failed at the minimum step
//!   where full steps finish.
//! * Every method, static runs only (as before): the retries of an increment that
//!   failed with stick/slip cycling backtrack; the next increment starts with full
//!   steps again (`auto` has its own Newton-with-line-search fallback).

use super::nonlinear::{Failure, LineSearch, NonlinearOptions, SolverKind};

/// Increments in a row converged without a backtrack after which full steps return.
pub const CLEAN_INCREMENTS: usize = 5;

/// Where the memory stands, for a restart to go on alike.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ArmijoState {
    /// Armijo is on now.
    pub on: bool,
    /// Across increments, not only for retries.
    pub sticky: bool,
    /// Increments in a row converged without a backtrack while on.
    pub clean: usize,
}

/// What the step loop remembers of the line search (module doc).
#[derive(Debug, Clone)]
pub struct ArmijoMemory {
    /// The deck leaves the line search to `auto` (one named on or off is never changed)
    /// and the method and run take this memory.
    applies: bool,
    /// Newton or JFNK: Armijo can stay on across increments.
    persistent: bool,
    /// A static run: stick/slip cycling turns Armijo on for the increment's retries.
    static_run: bool,
    /// Armijo is on now.
    on: bool,
    /// It stays on across increments (until clean ones), not only for the retries.
    sticky: bool,
    /// Increments in a row converged without a backtrack while on.
    clean: usize,
}

impl ArmijoMemory {
    /// For a run with `opts`, static (`static_run`) or implicit.
    pub fn new(opts: &NonlinearOptions, static_run: bool) -> Self {
        let persistent = matches!(opts.kind, SolverKind::Newton | SolverKind::Jfnk);
        Self {
            applies: opts.line_search == LineSearch::Auto && (persistent || static_run),
            persistent,
            static_run,
            on: false,
            sticky: false,
            clean: 0,
        }
    }

    /// The run's options `opts` with Armijo on every correction: what
    /// [`ArmijoMemory::pick`] picks when it is on.
    pub fn options(opts: &NonlinearOptions) -> NonlinearOptions {
        NonlinearOptions {
            line_search: LineSearch::On,
            ..opts.clone()
        }
    }

    /// Armijo is in force now.
    pub fn on(&self) -> bool {
        self.on
    }

    /// Where it stands (for a restart file).
    pub fn state(&self) -> ArmijoState {
        ArmijoState {
            on: self.on,
            sticky: self.sticky,
            clean: self.clean,
        }
    }

    /// Go on from `s` (a restart).
    pub fn resume(&mut self, s: ArmijoState) {
        self.on = s.on && self.applies;
        self.sticky = s.sticky && self.on;
        self.clean = s.clean;
    }

    /// The options in force: `armijo` ([`ArmijoMemory::options`] of `given`) when on,
    /// else the run's `given`.
    pub fn pick<'a>(
        &self,
        given: &'a NonlinearOptions,
        armijo: &'a NonlinearOptions,
    ) -> &'a NonlinearOptions {
        if self.on {
            armijo
        } else {
            given
        }
    }

    /// An attempt failed with `kind`: whether Armijo is on for the retry.
    pub fn failed(&mut self, kind: Option<Failure>) -> bool {
        if !self.applies {
            return false;
        }
        match kind {
            Some(
                Failure::Stagnated | Failure::Diverged | Failure::Element | Failure::NonFinite,
            ) if self.persistent => {
                self.on = true;
                self.sticky = true;
                self.clean = 0;
            }
            Some(Failure::StickSlipCycling) if self.static_run => self.on = true,
            _ => {}
        }
        self.on
    }

    /// An increment converged after `backtracks` line-search trials.
    pub fn converged(&mut self, backtracks: usize) {
        if !self.sticky {
            self.on = false;
        } else if backtracks > 0 {
            self.clean = 0;
        } else {
            self.clean += 1;
            if self.clean >= CLEAN_INCREMENTS {
                (self.on, self.sticky, self.clean) = (false, false, 0);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solve::nonlinear::testing::options;

    fn given(kind: SolverKind, ls: LineSearch) -> NonlinearOptions {
        let mut o = options(kind);
        o.line_search = ls;
        o.max_iterations = 17;
        o
    }

    /// Newton and JFNK: stagnation turns Armijo on (every other option as given), a
    /// linear solve or the iteration budget does not; it stays on while increments
    /// backtrack and turns off after CLEAN_INCREMENTS clean ones in a row.
    #[test]
    fn newton_and_jfnk_keep_armijo_until_clean_increments() {
        for kind in [SolverKind::Newton, SolverKind::Jfnk] {
            let mut m = ArmijoMemory::new(&given(kind, LineSearch::Auto), false);
            assert!(!m.on());
            assert_eq!(
                ArmijoMemory::options(&given(kind, LineSearch::Auto)).line_search,
                LineSearch::On
            );
            assert!(ArmijoMemory::new(&given(kind, LineSearch::Auto), true)
                .failed(Some(Failure::Element)));
            assert!(!m.failed(Some(Failure::LinearSolver)));
            assert!(!m.failed(Some(Failure::IterationLimit)));
            assert!(m.failed(Some(Failure::Stagnated)));
            let g = given(kind, LineSearch::Auto);
            let a = ArmijoMemory::options(&g);
            let o = m.pick(&g, &a);
            assert_eq!(
                (o.line_search, o.kind, o.max_iterations),
                (LineSearch::On, kind, 17)
            );
            m.converged(3);
            for _ in 0..CLEAN_INCREMENTS - 1 {
                m.converged(0);
                assert!(m.on());
            }
            m.converged(2);
            for _ in 0..CLEAN_INCREMENTS - 1 {
                m.converged(0);
            }
            assert!(m.on(), "a backtrack restarts the count");
            let mut again = ArmijoMemory::new(&given(kind, LineSearch::Auto), false);
            again.resume(m.state());
            assert_eq!(again.state(), m.state(), "a restart goes on alike");
            m.converged(0);
            assert!(!m.on(), "off after clean increments");
        }
    }

    /// `auto` and BFGS: in static runs only cycling turns it on, for that increment's
    /// retries; in implicit runs nothing does. Newton and JFNK alike for cycling. A line
    /// search the deck names (on or off) is never changed.
    #[test]
    fn cycling_only_and_named_line_searches() {
        for kind in [SolverKind::Auto, SolverKind::Bfgs] {
            let mut m = ArmijoMemory::new(&given(kind, LineSearch::Auto), true);
            assert!(!m.failed(Some(Failure::Stagnated)));
            assert!(m.failed(Some(Failure::StickSlipCycling)));
            m.converged(4);
            assert!(!m.on());
            let mut m = ArmijoMemory::new(&given(kind, LineSearch::Auto), false);
            assert!(
                !m.failed(Some(Failure::StickSlipCycling)),
                "{kind:?} implicit"
            );
        }
        // Newton and JFNK too: cycling alone backtracks only in that increment's retries.
        for kind in [SolverKind::Newton, SolverKind::Jfnk] {
            let mut m = ArmijoMemory::new(&given(kind, LineSearch::Auto), true);
            assert!(m.failed(Some(Failure::StickSlipCycling)));
            m.converged(2);
            assert!(!m.on(), "{kind:?}");
            let mut m = ArmijoMemory::new(&given(kind, LineSearch::Auto), false);
            assert!(
                !m.failed(Some(Failure::StickSlipCycling)),
                "{kind:?} implicit"
            );
        }
        for kind in [SolverKind::Newton, SolverKind::Jfnk, SolverKind::Auto] {
            for named in [LineSearch::On, LineSearch::Off] {
                for static_run in [false, true] {
                    let mut m = ArmijoMemory::new(&given(kind, named), static_run);
                    assert!(!m.failed(Some(Failure::StickSlipCycling)));
                    assert!(!m.on(), "{named:?} is the deck's");
                }
            }
        }
    }
}
