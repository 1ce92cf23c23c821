//! A three-unknown problem for the solver context's unit tests: a chain of two nonlinear
//! springs s(d) = k d + a atan(d), fixed by its first unknown (prescribed) and loaded by
//! f at its last. It records every point it is evaluated at.

use super::{NonlinearOptions, NonlinearProblem, Preconditioning, Solver, SolverKind, Start};
use crate::linalg::matrix::DistMatrix;
use crate::linalg::{FactorOptions, PcKind};
use crate::parallel::{Comm, Layout, SerialComm};
use crate::Result;

/// The chain; `residuals` and `jacobians` are the points evaluated, in order.
pub struct Toy {
    pub k: f64,
    pub a: f64,
    pub f: f64,
    /// The Jacobian returned is this multiple of the true one (a wrong tangent).
    pub jscale: f64,
    /// An "element" that cannot be evaluated from this many residual evaluations on.
    pub fail_after: usize,
    pub residuals: Vec<[f64; 3]>,
    pub jacobians: Vec<[f64; 3]>,
}

impl Toy {
    pub fn new(k: f64, a: f64, f: f64) -> Self {
        Self {
            k,
            a,
            f,
            jscale: 1.0,
            fail_after: usize::MAX,
            residuals: Vec::new(),
            jacobians: Vec::new(),
        }
    }
    fn s(&self, d: f64) -> f64 {
        self.k * d + self.a * d.atan()
    }
    fn ds(&self, d: f64) -> f64 {
        self.k + self.a / (1.0 + d * d)
    }
}

fn point(u: &[f64]) -> [f64; 3] {
    [u[0], u[1], u[2]]
}

impl NonlinearProblem for Toy {
    fn residual(&mut self, _: &dyn Comm, u: &[f64], r: &mut [f64]) -> Result<f64> {
        self.residuals.push(point(u));
        if self.residuals.len() > self.fail_after {
            return Err(crate::Error::convergence(
                "the toy's spring is overstretched",
            ));
        }
        let (s1, s2) = (self.s(u[1] - u[0]), self.s(u[2] - u[1]));
        r[0] = -s1;
        r[1] = s1 - s2;
        r[2] = s2 - self.f;
        Ok(self.f.abs().max(1.0))
    }
    fn jacobian(&mut self, comm: &dyn Comm, u: &[f64], k: &mut DistMatrix) -> Result<()> {
        self.jacobians.push(point(u));
        let a = self.jscale * self.ds(u[1] - u[0]);
        let b = self.jscale * self.ds(u[2] - u[1]);
        k.zero();
        k.add_block(0, 0, &[a, -a, 0.0, -a, a + b, -b, 0.0, -b, b]);
        k.finish_assembly(comm);
        Ok(())
    }
}

/// Options for the toy: tight tolerances, block Jacobi (exact on one block).
pub fn options(kind: SolverKind) -> NonlinearOptions {
    NonlinearOptions {
        kind,
        max_iterations: 40,
        residual_rtol: 1e-10,
        increment_rtol: 1e-10,
        energy_rtol: 1e-16,
        linear: crate::linalg::gmres::GmresOptions::default(),
        preconditioner: PcKind::BlockJacobi,
        pc_lag: 0,
        condense: false,
        pc_overlap: 0,
        rigid_body_modes: false,
        bfgs_reform: 11,
        fd_delta: 1e-6,
        fd_rule: super::FdRule::Element,
        char_length: 1.0,
        line_search: super::LineSearch::Off,
        stagnation_window: None,
        export_system: None,
    }
}

/// A solver for the toy on one rank.
pub fn solver(opts: &NonlinearOptions) -> Solver<'_> {
    let k = DistMatrix::new(&SerialComm, Layout::from_counts(&[1], 0), &[(0, 0)]);
    let pc = Preconditioning::new(opts.preconditioner, 0, FactorOptions::default());
    Solver::new(opts, k, pc)
}

/// Solve the toy from `u` with u₀ = `g`; the statistics.
pub fn solve(
    opts: &NonlinearOptions,
    toy: &mut Toy,
    u: &mut [f64; 3],
    g: f64,
    start: Start,
) -> super::SolveStats {
    let mut r = [0.0; 3];
    solver(opts)
        .solve(&SerialComm, toy, u, &mut r, &[(0, g)], start)
        .unwrap()
}

/// The equilibrium of the toy's chain: both springs carry f.
pub fn equilibrium(toy: &Toy, g: f64) -> [f64; 3] {
    // Invert s by Newton's method in one variable.
    let mut d = 0.0;
    for _ in 0..100 {
        d -= (toy.s(d) - toy.f) / toy.ds(d);
    }
    [g, g + d, g + 2.0 * d]
}
