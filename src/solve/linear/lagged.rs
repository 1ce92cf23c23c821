//! A block-Jacobi preconditioner that can be kept (lagged) across Newton iterations and
//! load steps: the Krylov solve always uses the fresh Jacobian, only the preconditioner
//! is from an older one (DESIGN.md: "block Jacobi of a lagged stiffness").

use super::block_jacobi::BlockJacobi;
use super::matrix::DistMatrix;
use crate::parallel::Comm;

pub struct LaggedBlockJacobi {
    pc: Option<BlockJacobi>,
    /// Reuses allowed after a factorization before the next one (0 = refactor every time).
    pub lag: usize,
    uses: usize,
    pub factorizations: usize,
}

impl LaggedBlockJacobi {
    pub fn new(lag: usize) -> Self {
        Self {
            pc: None,
            lag,
            uses: 0,
            factorizations: 0,
        }
    }

    /// Collective. Make a factorization available for `k`: refactor if there is none or
    /// it has been reused `lag` times, keep it otherwise. Returns whether it factored.
    /// A failure on any rank is a failure on all (no rank is left waiting in GMRES).
    pub fn update(&mut self, comm: &dyn Comm, k: &DistMatrix) -> Result<bool, String> {
        if self.pc.is_some() && self.uses < self.lag {
            self.uses += 1;
            return Ok(false);
        }
        let res = match self.pc.as_mut() {
            Some(p) => p.refactor(k),
            None => BlockJacobi::new(k).map(|p| self.pc = Some(p)),
        };
        let ok = comm.all_ok(res.is_ok());
        if !ok {
            self.pc = None;
            return Err(match res {
                Err(e) => format!("block-Jacobi factorization failed: {e}"),
                Ok(()) => "block-Jacobi factorization failed on another rank".into(),
            });
        }
        self.uses = 0;
        self.factorizations += 1;
        Ok(true)
    }

    /// Force a refactorization at the next `update` (e.g. GMRES stalled on a stale one).
    pub fn invalidate(&mut self) {
        self.uses = self.lag;
    }

    pub fn get(&self) -> Option<&BlockJacobi> {
        self.pc.as_ref()
    }
}
