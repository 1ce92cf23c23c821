//! What the nonlinear solvers test with: the constraint algebra, a residual evaluation's
//! norms and the convergence test ([`Monitor`]). The loop, the linear solve and the line
//! search that use them are the solver context's (`context.rs`).

use super::{Failure, NonlinearOptions};
use crate::parallel::Comm;

/// A step that makes the residual this many times larger than the step's force scale
/// has diverged.
pub const DIVERGENCE_FACTOR: f64 = 1e8;

/// The prescribed dofs of a step: owned local dof → target value.
pub struct Constraints<'a> {
    pub prescribed: &'a [(usize, f64)],
    pub is_c: Vec<bool>,
    pub dofs: Vec<usize>,
}

impl<'a> Constraints<'a> {
    pub fn new(n: usize, prescribed: &'a [(usize, f64)]) -> Self {
        let mut is_c = vec![false; n];
        for &(d, _) in prescribed {
            is_c[d] = true;
        }
        Self {
            prescribed,
            is_c,
            dofs: prescribed.iter().map(|p| p.0).collect(),
        }
    }
    /// g − u on the constrained dofs, zero elsewhere.
    pub fn gap_vector(&self, u: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|x| *x = 0.0);
        for &(d, g) in self.prescribed {
            out[d] = g - u[d];
        }
    }
    /// Zero the constrained entries (project onto the free dofs).
    pub fn zero_constrained(&self, v: &mut [f64]) {
        for &d in &self.dofs {
            v[d] = 0.0;
        }
    }
}

/// One residual evaluation with the norms every solver needs (one extra reduction).
#[derive(Debug, Clone, Copy)]
pub struct Eval {
    /// ‖r‖ over the free dofs.
    pub rn: f64,
    pub f_ref: f64,
    /// ‖g − u_c‖ over the constrained dofs.
    pub gap: f64,
    /// ‖u‖.
    pub un: f64,
}

impl Eval {
    pub fn relative(&self) -> f64 {
        if self.f_ref > 0.0 {
            self.rn / self.f_ref
        } else {
            self.rn
        }
    }
}

/// What to do after an evaluation.
pub enum Verdict {
    Converged,
    Continue,
    Fail(Failure, String),
}

/// Iterations over which the residual must fall by 10% before a solve is stagnating:
/// half the iteration budget, at least this many (BFGS's residual can plateau for ~10
/// iterations on the cantilever and then converge).
pub const STAGNATION_WINDOW: usize = 8;

/// What the convergence test remembers across the iterations of one step: the last
/// correction's norm and energy, the largest correction energy, and the best residual
/// (for stagnation).
#[derive(Debug, Clone)]
pub struct Monitor {
    last_du: f64,
    last_energy: f64,
    max_energy: f64,
    best: f64,
    best_at: usize,
    /// The force scale of the divergence test, fixed at the first point without a
    /// pending prescribed increment.
    divergence_scale: Option<f64>,
}

impl Default for Monitor {
    fn default() -> Self {
        Self {
            last_du: f64::INFINITY,
            last_energy: f64::INFINITY,
            max_energy: 0.0,
            best: f64::INFINITY,
            divergence_scale: None,
            best_at: 0,
        }
    }
}

/// How far below the increment and energy tolerances a correction counts as round-off.
const ROUNDOFF_SCALE: f64 = 1e-3;
/// The largest residual, in units of `residual_rtol·f_ref`, accepted at round-off.
const ROUNDOFF_RESIDUAL: f64 = 100.0;

impl Monitor {
    /// ‖du‖ and the energy |du_free · r_free| of a full correction `du` taken from a point
    /// whose residual is `r` (one reduction). Pass the result to [`Monitor::record`].
    pub fn measure(comm: &dyn Comm, du: &[f64], r: &[f64], is_c: &[bool]) -> (f64, f64) {
        let mut s = [0.0, 0.0];
        for i in 0..du.len() {
            s[0] += du[i] * du[i];
            if !is_c[i] {
                s[1] += du[i] * r[i];
            }
        }
        comm.allreduce_sum(&mut s);
        (s[0].sqrt(), s[1].abs())
    }
    /// The correction actually taken was `lambda` times the measured one.
    pub fn record(&mut self, measured: (f64, f64), lambda: f64) {
        self.last_du = lambda * measured.0;
        self.last_energy = lambda * measured.1;
        self.max_energy = self.max_energy.max(self.last_energy);
    }

    /// The convergence test. Converged when all hold: ‖r_free‖ ≤ residual_rtol·f_ref, the
    /// last correction ‖Δu‖ ≤ increment_rtol·‖u‖, its energy |Δu·r| ≤ energy_rtol times
    /// the largest correction energy of the step, and the prescribed values are reached
    /// (a zero residual before any correction needs none). Fails on a non-finite or
    /// diverging residual, on stagnation (no 10% decrease in max([`STAGNATION_WINDOW`],
    /// max_iterations/2) iterations) and at the iteration budget.
    pub fn verdict(
        &mut self,
        ev: &Eval,
        it: usize,
        scale: f64,
        opts: &NonlinearOptions,
    ) -> Verdict {
        // Overflow (a load of 1e200, a modulus of 1e300) is a failure, never convergence:
        // an infinite reference force would pass any relative test.
        if !(ev.rn.is_finite() && ev.f_ref.is_finite() && ev.un.is_finite()) {
            return Verdict::Fail(Failure::NonFinite, format!(
                "the residual is not finite (|r| = {:.3e}, reference force {:.3e}, |u| = {:.3e}): a load or material constant overflows",
                ev.rn, ev.f_ref, ev.un
            ));
        }
        let small_r = ev.rn <= opts.residual_rtol * ev.f_ref;
        let small_du = it == 0 || self.last_du <= opts.increment_rtol * ev.un;
        // The energy test is relative to the step's largest correction energy; a step
        // driven only by prescribed displacements can have zero energy in its first
        // correction (r_free = 0 at the start), so an energy below what the residual and
        // increment tolerances allow, |Δu·r| ≤ rtol_r f_ref · rtol_u ‖u‖, also passes.
        let floor = opts.residual_rtol * ev.f_ref * opts.increment_rtol * ev.un;
        let small_e = it == 0
            || self.last_energy <= opts.energy_rtol * self.max_energy
            || self.last_energy <= floor;
        if small_r && small_du && small_e && ev.gap == 0.0 {
            return Verdict::Converged;
        }
        // Round-off: a nearly incompressible solid (K/μ in the thousands) evaluates its
        // residual no better than ε·K·‖∇u‖, which can sit above residual_rtol·f_ref while
        // Newton's corrections have fallen to round-off (PETSc's SNES_CONVERGED_SNORM).
        // Accepted when the corrections are far below both tolerances and the residual is
        // within ROUNDOFF_RESIDUAL of its own.
        let at_roundoff = it > 0
            && self.last_du <= ROUNDOFF_SCALE * opts.increment_rtol * ev.un
            && self.last_energy <= ROUNDOFF_SCALE * opts.energy_rtol * self.max_energy
            && ev.rn <= ROUNDOFF_RESIDUAL * opts.residual_rtol * ev.f_ref;
        if at_roundoff && ev.gap == 0.0 {
            return Verdict::Converged;
        }
        // A step driven by prescribed displacements starts from a state whose forces
        // are round-off (a body at rest): its scale also takes the force scale where
        // the increment has been applied, or a first correction of ordinary size would
        // read as divergence.
        if ev.gap == 0.0 && self.divergence_scale.is_none() {
            self.divergence_scale = Some(scale.max(ev.f_ref));
        }
        let scale = self.divergence_scale.unwrap_or(0.0);
        if it > 0 && scale > 0.0 && ev.rn > DIVERGENCE_FACTOR * scale {
            return Verdict::Fail(
                Failure::Diverged,
                format!(
                    "diverged: residual grew to {:.3e} (force scale {scale:.3e})",
                    ev.rn
                ),
            );
        }
        if it >= opts.max_iterations {
            return Verdict::Fail(
                Failure::IterationLimit,
                format!(
                    "no convergence in {} iterations (relative residual {:.3e})",
                    opts.max_iterations,
                    ev.relative()
                ),
            );
        }
        // Stagnation, counted from the first point without a pending prescribed increment.
        let window = opts
            .stagnation_window
            .unwrap_or(STAGNATION_WINDOW.max(opts.max_iterations / 2));
        // `auto`'s early window follows the relative residual, the measure of
        // convergence: where the force scale grows with the iterate (the cantilever's
        // first increment under JFNK) ‖r‖ stays flat for 6 iterations while ‖r‖/f_ref
        // falls 5× and the solve converges at 12.
        let progress = match opts.stagnation_window {
            Some(_) => ev.relative(),
            None => ev.rn,
        };
        if ev.gap == 0.0 {
            if progress < 0.9 * self.best {
                self.best = progress;
                self.best_at = it;
            } else if self.best.is_finite() && it >= self.best_at + window && !small_r {
                return Verdict::Fail(Failure::Stagnated, format!(
                    "stagnated: the residual did not fall by 10% in {window} iterations (relative residual {:.3e})",
                    ev.relative()
                ));
            }
        }
        Verdict::Continue
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::gmres::GmresOptions;
    use crate::solve::nonlinear::{FdRule, SolverKind};

    fn opts() -> NonlinearOptions {
        NonlinearOptions {
            kind: SolverKind::Newton,
            max_iterations: 25,
            residual_rtol: 1e-8,
            increment_rtol: 1e-6,
            energy_rtol: 1e-8,
            linear: GmresOptions::default(),
            preconditioner: crate::linalg::PcKind::BlockJacobi,
            pc_lag: 0,
            condense: true,
            pc_overlap: 1,
            rigid_body_modes: false,
            bfgs_reform: 11,
            fd_delta: 1e-4,
            fd_rule: FdRule::Element,
            char_length: 1.0,
            line_search: crate::solve::nonlinear::LineSearch::Off,
            stagnation_window: None,
            export_system: None,
        }
    }
    fn ev(rn: f64) -> Eval {
        Eval {
            rn,
            f_ref: 1.0,
            gap: 0.0,
            un: 1.0,
        }
    }

    #[test]
    fn all_three_criteria_must_hold() {
        let o = opts();
        let mut m = Monitor::default();
        m.record((1.0, 1.0), 1.0);
        // Small residual and increment, but the last correction's energy is the largest.
        m.record((1e-9, 1.0), 1.0);
        assert!(matches!(
            m.verdict(&ev(1e-10), 2, 1.0, &o),
            Verdict::Continue
        ));
        m.record((1e-9, 1e-12), 1.0);
        assert!(matches!(
            m.verdict(&ev(1e-10), 3, 1.0, &o),
            Verdict::Converged
        ));
        // A pending prescribed increment is never converged.
        let mut g = ev(0.0);
        g.gap = 1e-3;
        assert!(matches!(
            Monitor::default().verdict(&g, 0, 1.0, &o),
            Verdict::Continue
        ));
    }

    /// A residual stuck above the tolerance is accepted only when the corrections have
    /// reached round-off and the residual is within ROUNDOFF_RESIDUAL of the tolerance
    /// (the ν = 0.4999 tet10 cantilever: 2e-8 against 1e-8, ‖Δu‖/‖u‖ 3e-11).
    #[test]
    fn roundoff_floor_is_accepted_only_at_roundoff() {
        let o = opts();
        let rn = 3.0 * o.residual_rtol;
        let mut m = Monitor::default();
        m.record((1.0, 1.0), 1.0);
        // Corrections at the increment tolerance, not at round-off: go on.
        m.record((1e-7, 1e-12), 1.0);
        assert!(matches!(m.verdict(&ev(rn), 5, 1.0, &o), Verdict::Continue));
        // At round-off: accepted.
        m.record((1e-11, 1e-22), 1.0);
        assert!(matches!(m.verdict(&ev(rn), 6, 1.0, &o), Verdict::Converged));
        // The same corrections with a residual far above the tolerance: not accepted.
        let far = 1e3 * o.residual_rtol;
        assert!(matches!(m.verdict(&ev(far), 7, 1.0, &o), Verdict::Continue));
    }

    #[test]
    fn overflow_is_a_failure() {
        let o = opts();
        for (rn, f_ref) in [
            (f64::INFINITY, f64::INFINITY),
            (f64::NAN, 1.0),
            (0.0, f64::NAN),
        ] {
            let e = Eval {
                rn,
                f_ref,
                gap: 0.0,
                un: 0.0,
            };
            match Monitor::default().verdict(&e, 0, 1.0, &o) {
                Verdict::Fail(kind, why) => {
                    assert!(why.contains("not finite"), "{why}");
                    assert_eq!(kind, Failure::NonFinite);
                }
                _ => panic!("{rn} / {f_ref} must fail"),
            }
        }
    }

    #[test]
    fn stagnation_and_divergence_end_the_solve() {
        let first_fail = |o: &NonlinearOptions| {
            let mut m = Monitor::default();
            (0..20)
                .position(|it| {
                    m.record((1.0, 1.0), 1.0);
                    matches!(
                        m.verdict(&ev(0.5), it, 1.0, o),
                        Verdict::Fail(Failure::Stagnated, _)
                    )
                })
                .unwrap()
        };
        let mut o = opts();
        assert_eq!(
            first_fail(&o),
            12,
            "half the budget of 25 iterations without a 10% decrease"
        );
        o.stagnation_window = Some(6);
        assert_eq!(first_fail(&o), 6, "a window set by `auto`");
        let mut m = Monitor::default();
        assert!(
            matches!(m.verdict(&ev(1e9), 1, 1.0, &o), Verdict::Fail(Failure::Diverged, w) if w.contains("diverged"))
        );
        assert!(matches!(
            m.verdict(&ev(f64::NAN), 1, 1.0, &o),
            Verdict::Fail(Failure::NonFinite, _)
        ));
    }
}
