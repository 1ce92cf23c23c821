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
pub use crate::solve::record::DynResume;
use crate::solve::record::{Flow, Resume, StepRecord};
use crate::Result;

/// The state at a step: displacement, velocity, acceleration on owned dofs.
#[derive(Debug, Clone, Default)]
pub struct DynState {
    pub u: Vec<f64>,
    pub v: Vec<f64>,
    pub a: Vec<f64>,
}

/// Called with every step (the initial state as step 0), its state, the model and how
/// to resume after it (built only when asked for; explicit runs cannot be resumed).
pub type DynObserver<'a> =
    dyn FnMut(&StepRecord, &DynState, &Model, Option<&dyn Fn() -> Resume>) -> Result<Flow> + 'a;

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
