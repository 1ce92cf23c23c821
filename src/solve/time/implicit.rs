//! Implicit dynamics: every step solves the force-averaged generalized-α equation
//! ([`super::alpha`]) for u_{n+1} with the chosen nonlinear solver (Newton, BFGS or
//! JFNK: the step is a [`NonlinearProblem`]). The residual is divided by (1 − α_f) so
//! that its Jacobian is K + c_M/(1−α_f) M and the model's stiffness assembly is used
//! unchanged. Prescribed dofs take u(t_{n+1}) from their constraints; their velocity
//! and acceleration follow from the Newmark relations like every other dof's.
//!
//! The time step comes from the step controller shared with static stepping
//! ([`StepControl`]): halved on failure, grown back after easy steps.

// Index loops over several dof vectors at once read like the formulas.
#![allow(clippy::needless_range_loop)]

use super::alpha::AlphaParams;
use super::energy::EnergyAccount;
use super::{momentum, prescribed_motion, support_forces, DynObserver, DynState};
use crate::linalg::matrix::DistMatrix;
use crate::model::dynamics::MassMatrix;
use crate::model::Model;
use crate::parallel::Comm;
use crate::solve::armijo::ArmijoMemory;
use crate::solve::control::StepControl;
use crate::solve::nonlinear::{
    NonlinearOptions, NonlinearProblem, SolveStats, Solver, SolverKind, Start,
};
use crate::solve::stepping::{model_solver, Attempt, Flow, Resume, RunTotals, StepRecord};
use crate::solve::{Analysis, MassKind, Scheme};
use crate::{Error, Result};
use std::time::Instant;

/// The scheme's parameters.
pub fn scheme_params(a: &Analysis) -> AlphaParams {
    let rho = a.rho_inf;
    match a.scheme {
        Scheme::Newmark => AlphaParams::newmark(),
        Scheme::GeneralizedAlpha => AlphaParams::generalized_alpha(rho),
        Scheme::HhtAlpha => AlphaParams::hht(rho),
        Scheme::Bossak => AlphaParams::bossak(rho),
    }
}

/// One implicit step as a nonlinear problem in u_{n+1}.
struct StepProblem<'a> {
    model: &'a mut Model,
    mass: &'a MassMatrix,
    p: AlphaParams,
    dt: f64,
    t1: f64,
    old: &'a DynState,
    /// R(u_n, t_n) = f_int − f_ext of the last converged state.
    r_old: &'a [f64],
    am: Vec<f64>,
    ma: Vec<f64>,
    fi: Vec<f64>,
}

impl NonlinearProblem for StepProblem<'_> {
    fn residual(&mut self, comm: &dyn Comm, u: &[f64], r: &mut [f64]) -> Result<f64> {
        self.residual_at(comm, u, r, false)
    }
    fn residual_frozen(&mut self, comm: &dyn Comm, u: &[f64], r: &mut [f64]) -> Result<f64> {
        self.residual_at(comm, u, r, true)
    }
    fn jacobian(&mut self, comm: &dyn Comm, u: &[f64], k: &mut DistMatrix) -> Result<()> {
        self.model.jacobian(comm, u, self.t1, k)?;
        let c = self.p.c_m(self.dt) / (1.0 - self.p.alpha_f);
        self.model.add_mass(comm, self.mass, c, k);
        Ok(())
    }
}

impl StepProblem<'_> {
    /// The generalized-α residual (frozen: see [`NonlinearProblem::residual_frozen`]).
    fn residual_at(
        &mut self,
        comm: &dyn Comm,
        u: &[f64],
        r: &mut [f64],
        frozen: bool,
    ) -> Result<f64> {
        let (p, dt, o) = (self.p, self.dt, self.old);
        for i in 0..u.len() {
            let a1 = p.acceleration(dt, u[i], o.u[i], o.v[i], o.a[i]);
            self.am[i] = p.mid_acceleration(o.a[i], a1);
        }
        self.model
            .apply_mass(comm, self.mass, &self.am, &mut self.ma);
        let info = self
            .model
            .forces_at(comm, u, self.t1, &mut self.fi, r, frozen)?;
        let c = 1.0 / (1.0 - p.alpha_f);
        let w = p.alpha_f * c;
        let mut s = [0.0, 0.0];
        for i in 0..u.len() {
            r[i] = c * self.ma[i] + self.fi[i] - r[i] + w * self.r_old[i];
            s[0] += (c * self.ma[i]).powi(2);
            s[1] += (w * self.r_old[i]).powi(2);
        }
        comm.allreduce_sum(&mut s);
        Ok(info.f_ref.max(s[0].sqrt()).max(s[1].sqrt()))
    }
}

/// M a = rhs on the free dofs with the given accelerations on the prescribed ones.
struct MassProblem<'a> {
    model: &'a Model,
    mass: &'a MassMatrix,
    rhs: &'a [f64],
}

impl NonlinearProblem for MassProblem<'_> {
    fn residual(&mut self, comm: &dyn Comm, a: &[f64], r: &mut [f64]) -> Result<f64> {
        self.model.apply_mass(comm, self.mass, a, r);
        let mut s = [0.0, 0.0];
        for i in 0..a.len() {
            s[0] += r[i] * r[i];
            s[1] += self.rhs[i] * self.rhs[i];
            r[i] -= self.rhs[i];
        }
        comm.allreduce_sum(&mut s);
        Ok(s[0].sqrt().max(s[1].sqrt()))
    }
    fn jacobian(&mut self, comm: &dyn Comm, _a: &[f64], k: &mut DistMatrix) -> Result<()> {
        k.zero();
        self.model.add_mass(comm, self.mass, 1.0, k);
        Ok(())
    }
}

/// The mass operator the analysis asks for.
pub fn mass_operator(comm: &dyn Comm, model: &Model, kind: MassKind) -> MassMatrix {
    match kind {
        MassKind::Consistent => MassMatrix::Consistent,
        MassKind::Lumped => MassMatrix::Lumped(model.lumped_mass(comm)),
    }
}

/// Run implicit dynamics from rest (plus the deck's initial velocities); `on_step`
/// sees the initial state (step 0) and every converged step.
pub fn run_implicit(
    comm: &dyn Comm,
    model: &mut Model,
    state: &mut DynState,
    analysis: &Analysis,
    opts: &NonlinearOptions,
    resume: Option<&Resume>,
    on_step: &mut DynObserver,
) -> Result<RunTotals> {
    let mut ctl = StepControl::new(analysis, opts.max_iterations);
    // Armijo after failures where line search is left to `auto` (`armijo.rs`).
    let mut armijo = ArmijoMemory::new(opts, false);
    let with_armijo = ArmijoMemory::options(opts);
    let mut run = Implicit::new(comm, model, analysis, opts);
    let t_start = Instant::now();
    let (mut energy, mut r_old) = match resume.and_then(|x| x.dynamic.as_ref().map(|d| (x, d))) {
        Some((x, d)) => {
            // A restart: the caller set u and the model's state; the rest is here.
            ctl.resume(&x.control);
            if let Some(a) = &x.auto {
                run.solver.auto = a.clone();
            }
            armijo.resume(x.armijo);
            run.solver.opts = armijo.pick(opts, &with_armijo);
            state.v = d.v.clone();
            state.a = d.a.clone();
            (d.energy.clone(), d.r_old.clone())
        }
        None => run.initial_state(model, state, analysis, t_start, on_step)?,
    };

    let mut trial = vec![0.0; model.n_owned_dofs()];
    let mut t0 = Instant::now();
    while let Some((t_done, t1)) = ctl.next() {
        let stage = ctl.stage();
        let h = t1 - t_done;
        let stats = run.attempt(model, state, &r_old, (t_done, t1), &mut trial)?;
        run.tot.add_in(stage, &stats);
        if !stats.converged {
            if !run.reject(model, &mut ctl, stats, (t_done, t1)) {
                return Ok(run.tot);
            }
            armijo.failed(run.pending.last().and_then(|a| a.stats.failure));
            run.solver.opts = armijo.pick(opts, &with_armijo);
            continue;
        }
        // Accept: the state at t_{n+1}, its forces, energies.
        let (react, en) = run.accept(model, state, &mut energy, &mut r_old, &trial, (h, t1))?;
        let (step, retries) = ctl.accept(t1, stats.iterations);
        armijo.converged(stats.backtracks);
        run.solver.opts = armijo.pick(opts, &with_armijo);
        run.tot.steps += 1;
        let rec = StepRecord {
            step,
            time: t1,
            stage,
            reactions: model.reactions(comm, &react),
            stats,
            retries,
            wall_seconds: t0.elapsed().as_secs_f64(),
            displacements: model.mean_displacements(comm, &state.u),
            energies: Some(en),
            columns: model.column_values(comm, &state.u, t1),
            failed: std::mem::take(&mut run.pending),
        };
        let here = || Resume {
            control: ctl.state(),
            last_increment: None,
            dynamic: Some(super::DynResume {
                v: state.v.clone(),
                a: state.a.clone(),
                r_old: r_old.clone(),
                energy: energy.clone(),
            }),
            auto: Some(run.solver.auto.clone()),
            armijo: armijo.state(),
        };
        if on_step(&rec, state, model, Some(&here))? == Flow::Stop {
            run.tot.stopped = true;
            return Ok(run.tot);
        }
        t0 = Instant::now();
    }
    run.tot.converged = true;
    Ok(run.tot)
}

/// What an implicit run keeps from step to step besides the dynamic state: the scheme,
/// the mass operator, the nonlinear solver, the totals and the failed attempts.
struct Implicit<'a> {
    comm: &'a dyn Comm,
    p: AlphaParams,
    mass: MassMatrix,
    /// Multipliers, reference points and massless body DOFs carry no mass: their
    /// "acceleration" is held at zero.
    mults: Vec<usize>,
    solver: Solver<'a>,
    tot: RunTotals,
    /// Internal and external forces of the last evaluation.
    fi: Vec<f64>,
    fe: Vec<f64>,
    r: Vec<f64>,
    /// Failed attempts at the current step.
    pending: Vec<Attempt>,
}

impl<'a> Implicit<'a> {
    fn new(
        comm: &'a dyn Comm,
        model: &Model,
        analysis: &Analysis,
        opts: &'a NonlinearOptions,
    ) -> Self {
        let p = scheme_params(analysis);
        let mass = mass_operator(comm, model, analysis.mass);
        let n = model.n_owned_dofs();
        let solver = model_solver(comm, model, opts);
        Self {
            comm,
            p,
            mass,
            mults: model.algebraic_dofs(),
            solver,
            tot: RunTotals::default(),
            fi: vec![0.0; n],
            fe: vec![0.0; n],
            r: vec![0.0; n],
            pending: Vec::new(),
        }
    }

    /// Solve the step from `t_done` to `t1` for u_{n+1} into `trial`, from the
    /// predictor.
    fn attempt(
        &mut self,
        model: &mut Model,
        state: &DynState,
        r_old: &[f64],
        (t_done, t1): (f64, f64),
        trial: &mut [f64],
    ) -> Result<SolveStats> {
        let (p, n, h) = (self.p, trial.len(), t1 - t_done);
        let g1 = model.prescribed(t1);
        for i in 0..n {
            trial[i] = p.predict(h, state.u[i], state.v[i], state.a[i]);
        }
        // Algebraic unknowns (multipliers, reference points) start from their last values
        // (they are not integrated in time).
        for &i in &self.mults {
            trial[i] = state.u[i];
        }
        let mut prob = StepProblem {
            model,
            mass: &self.mass,
            p,
            dt: h,
            t1,
            old: state,
            r_old,
            am: vec![0.0; n],
            ma: vec![0.0; n],
            fi: vec![0.0; n],
        };
        let start = Start::Predicted(&state.u);
        self.solver
            .solve(self.comm, &mut prob, trial, &mut self.r, &g1, start)
    }

    /// A failed attempt from `t_done` to `t1`: diagnosed, forgotten, the step cut.
    /// `false`: the run cannot go on (the failure is in the totals).
    fn reject(
        &mut self,
        model: &mut Model,
        ctl: &mut StepControl,
        mut stats: SolveStats,
        (t_done, t1): (f64, f64),
    ) -> bool {
        if let Some(why) = model.diagnose(self.comm) {
            stats.reason = format!("{}; {why}", stats.reason);
            stats.failure = Some(crate::solve::nonlinear::Failure::StickSlipCycling);
        }
        model.after_failed_attempt();
        self.solver.pc.invalidate();
        let reason = stats.reason.clone();
        let kind = stats.failure;
        self.pending.push(Attempt {
            t_start: t_done,
            t_end: t1,
            stats,
        });
        if let Err(why) = ctl.reject(t1, &reason, "time step") {
            self.tot.failure = Some(why);
            self.tot.failure_reason = kind;
            self.tot.failed_last = std::mem::take(&mut self.pending);
            return false;
        }
        self.tot.retries += 1;
        true
    }

    /// Accept the converged `trial` of a step of length `h` to `t1`: the state at
    /// t_{n+1}, its forces (one more evaluation, which also leaves the material history
    /// at u_{n+1} for the commit) and energies. Returns the support forces and the
    /// energies.
    fn accept(
        &mut self,
        model: &mut Model,
        state: &mut DynState,
        energy: &mut EnergyAccount,
        r_old: &mut [f64],
        trial: &[f64],
        (h, t1): (f64, f64),
    ) -> Result<(Vec<f64>, super::energy::Energies)> {
        let (p, n, comm) = (self.p, trial.len(), self.comm);
        let mut a1 = vec![0.0; n];
        let mut v1 = vec![0.0; n];
        let mut du = vec![0.0; n];
        for i in 0..n {
            a1[i] = p.acceleration(h, trial[i], state.u[i], state.v[i], state.a[i]);
            v1[i] = p.velocity(h, state.v[i], state.a[i], a1[i]);
            du[i] = trial[i] - state.u[i];
        }
        for &i in &self.mults {
            a1[i] = 0.0;
            v1[i] = 0.0;
        }
        model.forces(comm, trial, t1, &mut self.fi, &mut self.fe)?;
        self.tot.residual_evaluations += 1;
        // Persistency: a node pressed against a wall moves with it along the normal. The
        // Newmark update alone gives a node stopped within one step the reverse of its
        // approach velocity, and the Taylor bar's foot bounced off the wall.
        model.persistency(&mut v1, &mut a1, t1, h);
        model.commit();
        let (react, g) = support_forces(comm, model, &self.mass, &a1, &self.fi, &self.fe);
        let mv = momentum(comm, model, &self.mass, &v1);
        let en = energy.step(comm, &du, &self.fi, &g, &v1, &mv);
        for i in 0..n {
            r_old[i] = self.fi[i] - self.fe[i];
        }
        state.u.copy_from_slice(trial);
        state.v = v1;
        state.a = a1;
        Ok((react, en))
    }

    /// The state at t = 0 (u = g(0) on prescribed dofs, v from the deck, a from
    /// M a = f_ext − f_int) and its energy account and residual, reported as step 0.
    fn initial_state(
        &mut self,
        model: &mut Model,
        state: &mut DynState,
        analysis: &Analysis,
        t_start: Instant,
        on_step: &mut DynObserver,
    ) -> Result<(EnergyAccount, Vec<f64>)> {
        let comm = self.comm;
        let n = model.n_owned_dofs();
        // Initial state: u = g(0) on prescribed dofs, v from the deck (ġ(0) on prescribed
        // dofs), a from M a = f_ext − f_int on the free dofs (g̈(0) on prescribed ones).
        let h = 1e-6 * analysis.step;
        let motion = prescribed_motion(model, 0.0, h);
        state.u = vec![0.0; n];
        state.v = model.initial_velocity();
        for &(d, g, gd, _) in &motion {
            state.u[d] = g;
            state.v[d] = gd;
        }
        let (fi, fe) = (&mut self.fi, &mut self.fe);
        model.forces(comm, &state.u, 0.0, fi, fe)?;
        let rhs: Vec<f64> = (0..n).map(|i| fe[i] - fi[i]).collect();
        state.a = vec![0.0; n];
        let mut a_pres: Vec<(usize, f64)> = motion.iter().map(|m| (m.0, m.3)).collect();
        a_pres.extend(self.mults.iter().map(|&d| (d, 0.0)));
        let st0 = {
            let mut prob = MassProblem {
                model,
                mass: &self.mass,
                rhs: &rhs,
            };
            // A linear problem: Newton whatever the run's method.
            self.solver.solve_with(
                SolverKind::Newton,
                comm,
                &mut prob,
                &mut state.a,
                &mut self.r,
                &a_pres,
                Start::Tangent,
            )?
        };
        self.tot.add(&st0);
        self.solver.pc.invalidate();
        if !st0.converged {
            return Err(Error::runtime(format!(
                "initial acceleration M a₀ = f_ext − f_int did not converge: {}",
                st0.reason
            )));
        }
        let (fi, fe, mass) = (&self.fi, &self.fe, &self.mass);
        let (react, g) = support_forces(comm, model, mass, &state.a, fi, fe);
        let mv = momentum(comm, model, mass, &state.v);
        let ke0 = 0.5 * comm.dot(&state.v, &mv);
        let energy = EnergyAccount::new(fi.to_vec(), g, ke0);
        let r_old: Vec<f64> = (0..n).map(|i| fi[i] - fe[i]).collect();
        on_step(
            &StepRecord {
                step: 0,
                time: 0.0,
                stage: 0,
                stats: st0,
                retries: 0,
                reactions: model.reactions(comm, &react),
                wall_seconds: t_start.elapsed().as_secs_f64(),
                displacements: model.mean_displacements(comm, &state.u),
                energies: Some(energy.current),
                columns: model.column_values(comm, &state.u, 0.0),
                failed: Vec::new(),
            },
            state,
            model,
            None,
        )?;
        Ok((energy, r_old))
    }
}
