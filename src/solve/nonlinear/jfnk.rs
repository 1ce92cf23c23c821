//! JFNK (being written).
use super::{NonlinearOptions, NonlinearProblem, SolveStats};
use crate::parallel::Comm;
use crate::solve::linear::lagged::LaggedBlockJacobi;
use crate::solve::linear::matrix::DistMatrix;
use crate::Result;

#[allow(clippy::too_many_arguments)]
pub fn jfnk(
    comm: &dyn Comm,
    problem: &mut dyn NonlinearProblem,
    u: &mut [f64],
    r: &mut [f64],
    prescribed: &[(usize, f64)],
    k: &mut DistMatrix,
    pc: &mut LaggedBlockJacobi,
    opts: &NonlinearOptions,
) -> Result<SolveStats> {
    super::newton::newton(comm, problem, u, r, prescribed, k, pc, opts)
}
