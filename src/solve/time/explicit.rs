//! Explicit central difference with the lumped mass, in velocity-Verlet form (the same
//! scheme, with full-step velocities for the kinetic energy):
//!
//!   v_{n+½} = v_n + ½Δt a_n,   u_{n+1} = u_n + Δt v_{n+½},
//!   a_{n+1} = M_l⁻¹ (f_ext(t_{n+1}) − f_int(u_{n+1})),   v_{n+1} = v_{n+½} + ½Δt a_{n+1}.
//!
//! One residual evaluation (collective: the halo sum of the element forces) per step.
//! Prescribed dofs follow their constraint: u = g(t), with ġ and g̈ by central
//! differences. Δt = dt_factor × the current stable step, recomputed every step as the
//! elements deform ([`Model::current_stable_time_step`]), or the deck's fixed `step`
//! while it is not above the stable step (the run ends cleanly when it becomes so).

// Index loops over several dof vectors at once read like the formulas.
#![allow(clippy::needless_range_loop)]

use super::energy::EnergyAccount;
use super::{momentum, prescribed_motion, support_forces, DynObserver, DynState};
use crate::model::dynamics::{MassMatrix, StableStep};
use crate::model::Model;
use crate::parallel::Comm;
use crate::solve::nonlinear::SolveStats;
use crate::solve::stepping::{RunTotals, StepRecord};
use crate::solve::Analysis;
use crate::{Error, Result};
use std::time::Instant;

/// LS-DYNA's default time-step scale factor (TSSFAC).
pub const DEFAULT_DT_FACTOR: f64 = 0.9;

/// The time step of an explicit run and the stable step it derives from. A deck `step`
/// above the stable step is an input error naming `analysis.step`.
pub fn explicit_time_step(
    comm: &dyn Comm,
    model: &Model,
    a: &Analysis,
) -> Result<(f64, StableStep)> {
    let stable = model.stable_time_step(comm)?;
    if a.step > 0.0 {
        if a.step > stable.dt {
            return Err(Error::input(format!(
                "analysis.step: {:.6e} is above the stable time step {:.6e} (min L_e/c_d: L_e = {:.4e}, c_d = {:.4e}); use a smaller step or leave it out",
                a.step, stable.dt, stable.length, stable.wave_speed
            )));
        }
        Ok((a.step, stable))
    } else {
        Ok((a.dt_factor * stable.dt, stable))
    }
}

/// Run the explicit analysis from step `dt` (from [`explicit_time_step`]); `on_step` sees
/// the initial state (step 0) and every step.
pub fn run_explicit(
    comm: &dyn Comm,
    model: &mut Model,
    state: &mut DynState,
    analysis: &Analysis,
    dt: f64,
    stable: &StableStep,
    on_step: &mut DynObserver,
) -> Result<RunTotals> {
    let fixed = analysis.step > 0.0;
    let factor = analysis.dt_factor;
    let mut dt = dt;
    let end = analysis.end_time;
    let mut run = Explicit::new(comm, model)?;
    let mut energy = run.initial_state(model, state, dt, on_step)?;
    let mut t = 0.0;
    let mut step = 0;
    let mut t0 = Instant::now();
    while t < end * (1.0 - 1e-12) {
        if step > 0 {
            let now = model.current_stable_time_step(comm, &state.u, stable);
            if !fixed {
                dt = factor * now;
            } else if dt > now {
                run.tot.failure_reason = Some(crate::solve::nonlinear::Failure::TimeStep);
                run.tot.failure = Some(format!(
                    "step {} (t = {t}): the fixed analysis.step {dt:.4e} is above the stable step {now:.4e} of the deformed mesh",
                    step + 1
                ));
                return Ok(run.tot);
            }
            if dt.is_nan() || dt <= 1e-12 * end {
                run.tot.failure_reason = Some(crate::solve::nonlinear::Failure::TimeStep);
                run.tot.failure = Some(format!(
                    "step {} (t = {t}): the stable step collapsed to {dt:.3e} (an element is squashed flat)",
                    step + 1
                ));
                return Ok(run.tot);
            }
        }
        let mut t1 = t + dt;
        if t1 > end * (1.0 - 1e-9) || end - t1 < 1e-3 * dt {
            t1 = end;
        }
        if let Err(e) = run.advance(model, state, (t, t1)) {
            run.tot.failure_reason = Some(crate::solve::nonlinear::Failure::Element);
            run.tot.failure = Some(format!("step {} (t = {t1}): {}", step + 1, e.message));
            return Ok(run.tot);
        }
        let (react, en) = run.balance(model, state, &mut energy);
        step += 1;
        run.tot.steps += 1;
        let rec = StepRecord {
            step,
            time: t1,
            stage: analysis.stage_at(t1),
            stats: stats(1),
            retries: 0,
            reactions: model.reactions(comm, &react),
            wall_seconds: t0.elapsed().as_secs_f64(),
            displacements: model.mean_displacements(comm, &state.u),
            energies: Some(en),
            columns: model.column_values(comm, &state.u, t1),
            failed: Vec::new(),
        };
        if on_step(&rec, state, model, None)? == crate::solve::stepping::Flow::Stop {
            run.tot.stopped = true;
            return Ok(run.tot);
        }
        t = t1;
        t0 = Instant::now();
    }
    run.tot.converged = true;
    Ok(run.tot)
}

/// The statistics of an explicit step: `evals` residual evaluations, converged.
fn stats(evals: usize) -> SolveStats {
    SolveStats {
        converged: true,
        residual_evaluations: evals,
        ..SolveStats::default()
    }
}

/// What an explicit run keeps from step to step besides the dynamic state.
struct Explicit<'a> {
    comm: &'a dyn Comm,
    /// The lumped mass.
    mass: MassMatrix,
    /// Dofs not integrated: prescribed ones and the held algebraic unknowns.
    is_c: Vec<bool>,
    tot: RunTotals,
    /// Internal and external forces at the current state.
    fi: Vec<f64>,
    fe: Vec<f64>,
    /// The last step's increment.
    du: Vec<f64>,
    /// The prescribed motion (dof, g, ġ, g̈) at the end of the last step.
    motion: Vec<(usize, f64, f64, f64)>,
}

impl<'a> Explicit<'a> {
    fn new(comm: &'a dyn Comm, model: &mut Model) -> Result<Self> {
        let m = model.lumped_mass(comm);
        let n = model.n_owned_dofs();
        let mut is_c = vec![false; n];
        for &d in model.prescribed_dofs() {
            is_c[d] = true;
        }
        // Algebraic unknowns are held: ALM walls act kinematically here.
        for d in model.extra_range() {
            is_c[d] = true;
        }
        model.start_explicit()?;
        Ok(Self {
            comm,
            mass: MassMatrix::Lumped(m),
            is_c,
            tot: RunTotals::default(),
            fi: vec![0.0; n],
            fe: vec![0.0; n],
            du: vec![0.0; n],
            motion: Vec::new(),
        })
    }

    /// The state at t = 0 (u = g(0) on prescribed dofs, v from the deck, a = M_l⁻¹
    /// (f_ext − f_int)), reported as step 0; its energy account.
    fn initial_state(
        &mut self,
        model: &mut Model,
        state: &mut DynState,
        dt: f64,
        on_step: &mut DynObserver,
    ) -> Result<EnergyAccount> {
        let (comm, n, t0) = (self.comm, self.is_c.len(), Instant::now());
        let motion = prescribed_motion(model, 0.0, dt);
        state.u = vec![0.0; n];
        state.v = model.initial_velocity();
        state.a = vec![0.0; n];
        for &(d, g, gd, _) in &motion {
            state.u[d] = g;
            state.v[d] = gd;
        }
        let ta = Instant::now();
        model.forces(comm, &state.u, 0.0, &mut self.fi, &mut self.fe)?;
        self.tot.seconds_assembly += ta.elapsed().as_secs_f64();
        self.tot.residual_evaluations += 1;
        let (fi, fe, m) = (&self.fi, &self.fe, lumped(&self.mass));
        for i in 0..n {
            if !self.is_c[i] {
                state.a[i] = (fe[i] - fi[i]) / m[i];
            }
        }
        for &(d, _, _, gdd) in &motion {
            state.a[d] = gdd;
        }
        let (react, g) = support_forces(comm, model, &self.mass, &state.a, fi, fe);
        let mv = momentum(comm, model, &self.mass, &state.v);
        let energy = EnergyAccount::new(self.fi.clone(), g, 0.5 * comm.dot(&state.v, &mv));
        on_step(
            &StepRecord {
                step: 0,
                time: 0.0,
                stage: 0,
                stats: stats(1),
                retries: 0,
                reactions: model.reactions(comm, &react),
                wall_seconds: t0.elapsed().as_secs_f64(),
                displacements: model.mean_displacements(comm, &state.u),
                energies: Some(energy.current),
                columns: model.column_values(comm, &state.u, 0.0),
                failed: Vec::new(),
            },
            state,
            model,
            None,
        )?;
        Ok(energy)
    }

    /// One velocity-Verlet step from `t` to `t1`: the half-step velocities, the new
    /// displacements (walls enforced kinematically), the forces there and the new
    /// accelerations and velocities. `Err`: the forces could not be evaluated.
    fn advance(
        &mut self,
        model: &mut Model,
        state: &mut DynState,
        (t, t1): (f64, f64),
    ) -> Result<()> {
        let (n, h) = (self.is_c.len(), t1 - t);
        let du = &mut self.du;
        for i in 0..n {
            let vh = state.v[i] + 0.5 * h * state.a[i];
            du[i] = h * vh;
            state.v[i] = vh;
        }
        self.motion = prescribed_motion(model, t1, h);
        for &(d, g, _, _) in &self.motion {
            du[d] = g - state.u[d];
        }
        for i in 0..n {
            state.u[i] += du[i];
        }
        // Rigid walls enforced kinematically: a penetrating node is put back on the wall
        // and its approach velocity removed (the explicit reference, as LS-DYNA's
        // *RIGIDWALL in explicit).
        model.kinematic(&mut state.u, &mut state.v, lumped(&self.mass), t1, h);
        let ta = Instant::now();
        let res = model.forces(self.comm, &state.u, t1, &mut self.fi, &mut self.fe);
        self.tot.seconds_assembly += ta.elapsed().as_secs_f64();
        res?;
        self.tot.residual_evaluations += 1;
        let (fi, fe, m) = (&self.fi, &self.fe, lumped(&self.mass));
        for i in 0..n {
            if !self.is_c[i] {
                state.a[i] = (fe[i] - fi[i]) / m[i];
                state.v[i] += 0.5 * h * state.a[i];
            }
        }
        for &(d, _, gd, gdd) in &self.motion {
            state.a[d] = gdd;
            state.v[d] = gd;
        }
        Ok(())
    }

    /// Commit the step just advanced: its support forces and energies.
    fn balance(
        &mut self,
        model: &mut Model,
        state: &DynState,
        energy: &mut EnergyAccount,
    ) -> (Vec<f64>, super::energy::Energies) {
        let comm = self.comm;
        model.commit();
        let (react, g) = support_forces(comm, model, &self.mass, &state.a, &self.fi, &self.fe);
        let mv = momentum(comm, model, &self.mass, &state.v);
        let en = energy.step(comm, &self.du, &self.fi, &g, &state.v, &mv);
        (react, en)
    }
}

/// The lumped mass of an explicit run.
fn lumped(mass: &MassMatrix) -> &[f64] {
    let MassMatrix::Lumped(m) = mass else {
        unreachable!("explicit runs use the lumped mass")
    };
    m
}
