//! When the nonlinear solvers set their preconditioner up again: the policy of lagging.
//! Newton refactors at every iteration unless told to keep a factorization for `lag`
//! further Jacobians (across steps); JFNK sets it up once per step; BFGS at each reform;
//! all refresh at once when GMRES fails under a kept one, or after a retried step. The
//! preconditioner itself ([`crate::linalg::Preconditioner`], created by name) only sets
//! up and applies.

use crate::linalg::{
    preconditioner, DistMatrix, FactorOptions, NodePoints, PcKind, Preconditioner,
};
use crate::parallel::Comm;

pub struct Preconditioning {
    kind: PcKind,
    opts: FactorOptions,
    points: Option<NodePoints>,
    pc: Box<dyn Preconditioner>,
    /// A successful setup is in place.
    ready: bool,
    /// Reuses allowed after a setup before the next one (0 = set up every time).
    pub lag: usize,
    uses: usize,
    /// Setups that factored a matrix.
    pub factorizations: usize,
}

impl Preconditioning {
    /// `condense`: eliminate contact multipliers node by node before factoring
    /// ([`crate::linalg::condense`]).
    pub fn new(kind: PcKind, lag: usize, condense: bool) -> Self {
        let opts = FactorOptions {
            condense,
            ..FactorOptions::default()
        };
        Self {
            kind,
            opts,
            points: None,
            pc: preconditioner(kind, opts, None),
            ready: false,
            lag,
            uses: 0,
            factorizations: 0,
        }
    }

    /// Give the owned nodes' reference coordinates (AMG's rigid-body modes).
    pub fn with_points(mut self, points: NodePoints) -> Self {
        self.points = Some(points);
        self.pc = preconditioner(self.kind, self.opts, self.points.clone());
        self
    }

    pub fn kind(&self) -> PcKind {
        self.kind
    }

    /// Whether the preconditioner factors (block Jacobi, ASM) rather than being the identity.
    pub fn is_factored(&self) -> bool {
        self.pc.is_factored()
    }

    /// Collective. Make the preconditioner usable for `k`: set it up if it is not, or if it
    /// has been reused `lag` times; keep it otherwise. Returns whether it factored. A
    /// failure on any rank is a failure on all (no rank is left waiting in GMRES); the
    /// next update then starts from a fresh preconditioner.
    pub fn update(&mut self, comm: &dyn Comm, k: &DistMatrix) -> Result<bool, String> {
        if !self.pc.is_factored() {
            return Ok(false);
        }
        if self.ready && self.uses < self.lag {
            self.uses += 1;
            return Ok(false);
        }
        let res = self.pc.setup(comm, k);
        if !comm.all_ok(res.is_ok()) {
            self.pc = preconditioner(self.kind, self.opts, self.points.clone());
            self.ready = false;
            let what = match self.kind {
                PcKind::Asm => "ASM factorization",
                PcKind::Amg => "AMG setup",
                _ => "block-Jacobi factorization",
            };
            return Err(match res {
                Err(e) => format!("{what} failed: {e}"),
                Ok(()) => format!("{what} failed on another rank"),
            });
        }
        self.ready = true;
        self.uses = 0;
        self.factorizations += 1;
        Ok(true)
    }

    /// Set up again at the next `update` (GMRES stalled on a kept factorization, a step
    /// was retried).
    pub fn invalidate(&mut self) {
        self.uses = self.lag;
    }

    /// The preconditioner to apply: the set-up one, or the identity if there is none.
    pub fn get(&self) -> &dyn Preconditioner {
        if self.ready || !self.pc.is_factored() {
            self.pc.as_ref()
        } else {
            &crate::linalg::Identity
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::block_jacobi::tests::elasticity_cube;
    use crate::parallel::run_ranks;

    /// The lag applies to either kind; `None` never factors; block Jacobi and ASM
    /// differ on 2 ranks.
    #[test]
    fn lag_and_kinds() {
        run_ranks(2, |c| {
            let m = elasticity_cube(c, 3, &[32, 32]);
            let n = m.n_owned_dofs();
            let r: Vec<f64> = (0..n).map(|i| (i as f64).cos()).collect();
            let mut z = [vec![0.0; n], vec![0.0; n]];
            for (i, kind) in [PcKind::Asm, PcKind::BlockJacobi].into_iter().enumerate() {
                let mut pc = Preconditioning::new(kind, 1, true);
                assert_eq!(pc.update(c, &m), Ok(true));
                assert_eq!(pc.update(c, &m), Ok(false));
                assert_eq!(pc.update(c, &m), Ok(true));
                pc.invalidate();
                assert_eq!(pc.update(c, &m), Ok(true));
                assert_eq!(pc.factorizations, 3);
                pc.get().apply(c, &r, &mut z[i]);
            }
            let d: Vec<f64> = z[0].iter().zip(&z[1]).map(|(a, b)| a - b).collect();
            assert!(c.norm2(&d) > 1e-6 * c.norm2(&z[1]));
            let mut none = Preconditioning::new(PcKind::None, 0, true);
            assert_eq!(none.update(c, &m), Ok(false));
            assert!(!none.is_factored());
            let mut y = vec![0.0; n];
            none.get().apply(c, &r, &mut y);
            assert_eq!(y, r);
        });
    }
}
