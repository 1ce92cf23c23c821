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
    let m = model.lumped_mass(comm);
    let n = model.n_owned_dofs();
    let mut tot = RunTotals::default();
    let mut t0 = Instant::now();
    let mut is_c = vec![false; n];
    for &d in model.prescribed_dofs() {
        is_c[d] = true;
    }
    // Algebraic unknowns are held: ALM walls act kinematically here.
    for d in model.extra_range() {
        is_c[d] = true;
    }
    model.start_explicit()?;

    let motion = prescribed_motion(model, 0.0, dt);
    state.u = vec![0.0; n];
    state.v = model.initial_velocity();
    state.a = vec![0.0; n];
    let mut fi = vec![0.0; n];
    let mut fe = vec![0.0; n];
    for &(d, g, gd, _) in &motion {
        state.u[d] = g;
        state.v[d] = gd;
    }
    let ta = Instant::now();
    model.forces(comm, &state.u, 0.0, &mut fi, &mut fe)?;
    tot.seconds_assembly += ta.elapsed().as_secs_f64();
    tot.residual_evaluations += 1;
    for i in 0..n {
        if !is_c[i] {
            state.a[i] = (fe[i] - fi[i]) / m[i];
        }
    }
    for &(d, _, _, gdd) in &motion {
        state.a[d] = gdd;
    }
    let mass = MassMatrix::Lumped(m);
    let (react, g) = support_forces(comm, model, &mass, &state.a, &fi, &fe);
    let mv = momentum(comm, model, &mass, &state.v);
    let mut energy = EnergyAccount::new(fi.clone(), g, 0.5 * comm.dot(&state.v, &mv));
    let stats = |evals: usize| SolveStats {
        converged: true,
        residual_evaluations: evals,
        ..SolveStats::default()
    };
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
    let MassMatrix::Lumped(m) = &mass else {
        unreachable!()
    };
    let mut t = 0.0;
    let mut step = 0;
    let mut du = vec![0.0; n];
    t0 = Instant::now();
    while t < end * (1.0 - 1e-12) {
        if step > 0 {
            let now = model.current_stable_time_step(comm, &state.u, stable);
            if !fixed {
                dt = factor * now;
            } else if dt > now {
                tot.failure_reason = Some(crate::solve::nonlinear::Failure::TimeStep);
                tot.failure = Some(format!(
                    "step {} (t = {t}): the fixed analysis.step {dt:.4e} is above the stable step {now:.4e} of the deformed mesh",
                    step + 1
                ));
                return Ok(tot);
            }
            if dt.is_nan() || dt <= 1e-12 * end {
                tot.failure_reason = Some(crate::solve::nonlinear::Failure::TimeStep);
                tot.failure = Some(format!(
                    "step {} (t = {t}): the stable step collapsed to {dt:.3e} (an element is squashed flat)",
                    step + 1
                ));
                return Ok(tot);
            }
        }
        let mut t1 = t + dt;
        if t1 > end * (1.0 - 1e-9) || end - t1 < 1e-3 * dt {
            t1 = end;
        }
        let h = t1 - t;
        for i in 0..n {
            let vh = state.v[i] + 0.5 * h * state.a[i];
            du[i] = h * vh;
            state.v[i] = vh;
        }
        let motion = prescribed_motion(model, t1, h);
        for &(d, g, _, _) in &motion {
            du[d] = g - state.u[d];
        }
        for i in 0..n {
            state.u[i] += du[i];
        }
        // Rigid walls enforced kinematically: a penetrating node is put back on the wall
        // and its approach velocity removed (the explicit reference, as LS-DYNA's
        // *RIGIDWALL in explicit).
        model.kinematic(&mut state.u, &mut state.v, m, t1, h);
        let ta = Instant::now();
        if let Err(e) = model.forces(comm, &state.u, t1, &mut fi, &mut fe) {
            tot.seconds_assembly += ta.elapsed().as_secs_f64();
            tot.failure_reason = Some(crate::solve::nonlinear::Failure::Element);
            tot.failure = Some(format!("step {} (t = {t1}): {}", step + 1, e.message));
            return Ok(tot);
        }
        tot.seconds_assembly += ta.elapsed().as_secs_f64();
        tot.residual_evaluations += 1;
        for i in 0..n {
            if !is_c[i] {
                state.a[i] = (fe[i] - fi[i]) / m[i];
                state.v[i] += 0.5 * h * state.a[i];
            }
        }
        for &(d, _, gd, gdd) in &motion {
            state.a[d] = gdd;
            state.v[d] = gd;
        }
        model.commit();
        let (react, g) = support_forces(comm, model, &mass, &state.a, &fi, &fe);
        let mv = momentum(comm, model, &mass, &state.v);
        let en = energy.step(comm, &du, &fi, &g, &state.v, &mv);
        step += 1;
        tot.steps += 1;
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
            tot.stopped = true;
            return Ok(tot);
        }
        t = t1;
        t0 = Instant::now();
    }
    tot.converged = true;
    Ok(tot)
}
