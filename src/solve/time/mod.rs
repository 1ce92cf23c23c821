//! Time integration of the equations of motion M ü + f_int(u) = f_ext(t):
//! implicit ([`implicit`], the generalized-α family of [`alpha`], each step a
//! [`crate::solve::nonlinear::NonlinearProblem`] in u_{n+1}) and explicit central
//! difference ([`explicit`]), with the energy bookkeeping of [`energy`].

// Index loops over several dof vectors at once read like the formulas.
#![allow(clippy::needless_range_loop)]

pub mod alpha;
pub mod energy;
pub mod explicit;
pub mod implicit;

use crate::model::dynamics::MassMatrix;
use crate::model::Model;
use crate::parallel::Comm;
use crate::solve::stepping::StepRecord;
use crate::Result;

/// The state at a step: displacement, velocity, acceleration on owned dofs.
#[derive(Debug, Clone, Default)]
pub struct DynState {
    pub u: Vec<f64>,
    pub v: Vec<f64>,
    pub a: Vec<f64>,
}

/// What implicit dynamics needs to resume after a step besides the solution: velocity,
/// acceleration, the last residual (the force-averaged schemes use it) and the energy
/// account.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct DynResume {
    pub v: Vec<f64>,
    pub a: Vec<f64>,
    pub r_old: Vec<f64>,
    pub energy: energy::EnergyAccount,
}

/// Called with every step (the initial state as step 0), its state, the model and how
/// to resume after it (built only when asked for; explicit runs cannot be resumed).
pub type DynObserver<'a> = dyn FnMut(
        &StepRecord,
        &DynState,
        &Model,
        Option<&dyn Fn() -> crate::solve::stepping::Resume>,
    ) -> Result<crate::solve::stepping::Flow>
    + 'a;

/// Velocity and acceleration of the prescribed dofs at t by central differences of
/// the prescribed displacement with spacing h: (dof, g, ġ, g̈).
pub fn prescribed_motion(model: &Model, t: f64, h: f64) -> Vec<(usize, f64, f64, f64)> {
    let g0 = model.prescribed(t);
    let gm = model.prescribed(t - h);
    let gp = model.prescribed(t + h);
    g0.iter()
        .zip(&gm)
        .zip(&gp)
        .map(|((&(d, g), &(_, m)), &(_, p))| {
            (d, g, (p - m) / (2.0 * h), (p - 2.0 * g + m) / (h * h))
        })
        .collect()
}

/// Forces at the supports after a step: `r` = M a + f_int − f_ext on every owned dof
/// (the reaction on constrained rows), and the external force with the reactions added
/// on constrained rows (what does work on the body). Also returns M a.
pub fn support_forces(
    comm: &dyn Comm,
    model: &Model,
    mass: &MassMatrix,
    a: &[f64],
    f_int: &[f64],
    f_ext: &[f64],
) -> (Vec<f64>, Vec<f64>) {
    let n = a.len();
    let mut r = vec![0.0; n];
    model.apply_mass(comm, mass, a, &mut r);
    for i in 0..n {
        r[i] += f_int[i] - f_ext[i];
    }
    let mut g = f_ext.to_vec();
    for &d in model.prescribed_dofs() {
        g[d] += r[d];
    }
    (r, g)
}

/// Kinetic energy pieces: M v.
pub fn momentum(comm: &dyn Comm, model: &Model, mass: &MassMatrix, v: &[f64]) -> Vec<f64> {
    let mut mv = vec![0.0; v.len()];
    model.apply_mass(comm, mass, v, &mut mv);
    mv
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
    #[test]
    fn output_clock_hits_each_interval_once() {
        let mut c = super::OutputClock::new(0.25, 1.0);
        let times: Vec<f64> = (0..=20).map(|i| i as f64 * 0.05).collect();
        let hits: Vec<f64> = times.into_iter().filter(|&t| c.due(t)).collect();
        assert_eq!(hits.len(), 5, "{hits:?}");
        assert!((hits[1] - 0.25).abs() < 1e-12 && (hits[4] - 1.0).abs() < 1e-12);
    }
}
