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
    /// The preconditioner is built with `points`.
    give_points: bool,
    pc: Box<dyn Preconditioner>,
    /// A successful setup is in place.
    ready: bool,
    /// Reuses allowed after a setup before the next one (0 = set up every time).
    pub lag: usize,
    uses: usize,
    /// Setups that factored a matrix.
    pub factorizations: usize,
    /// Wall time of the setups so far (factorizations, coarse spaces), successful or not.
    pub seconds_setup: f64,
    /// The last coarse space set up (kept when a failed setup starts afresh).
    pub coarse: Option<crate::linalg::CoarseStats>,
}

impl Preconditioning {
    /// How the factored ones factor: `opts` (contact multipliers condensed node by node,
    /// [`crate::linalg::condense`]; Schwarz overlap).
    pub fn new(kind: PcKind, lag: usize, opts: FactorOptions) -> Self {
        Self {
            kind,
            opts,
            points: None,
            give_points: false,
            pc: preconditioner(kind, opts, None),
            ready: false,
            lag,
            uses: 0,
            factorizations: 0,
            seconds_setup: 0.0,
            coarse: None,
        }
    }

    /// Give the owned nodes' reference coordinates: the coarse space's rigid-body modes
    /// ([`PcKind::wants_points`]), AMG's if `amg_rotations` (else AMG is unknown-based),
    /// and the exported system's ([`Self::points`]).
    pub fn with_points(mut self, points: NodePoints, amg_rotations: bool) -> Self {
        let give = self.kind.wants_points() || (self.kind == PcKind::Amg && amg_rotations);
        self.points = Some(points);
        self.give_points = give;
        self.pc = preconditioner(self.kind, self.opts, self.given_points());
        self
    }

    fn given_points(&self) -> Option<NodePoints> {
        self.points.clone().filter(|_| self.give_points)
    }

    /// The owned nodes' reference coordinates, if given.
    pub fn points(&self) -> Option<&[[f64; 3]]> {
        self.points.as_deref().map(|p| p.as_slice())
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
        let t = std::time::Instant::now();
        let res = self.pc.setup(comm, k);
        let ok = comm.all_ok(res.is_ok());
        self.seconds_setup += t.elapsed().as_secs_f64();
        self.coarse = self.pc.coarse_stats().or(self.coarse);
        if !ok {
            self.pc = preconditioner(self.kind, self.opts, self.given_points());
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

    /// The coarse space of a two-level preconditioner, once set up.
    pub fn coarse_stats(&self) -> Option<crate::linalg::CoarseStats> {
        self.pc.coarse_stats()
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
                let mut pc = Preconditioning::new(kind, 1, FactorOptions::default());
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
            let mut none = Preconditioning::new(PcKind::None, 0, FactorOptions::default());
            assert_eq!(none.update(c, &m), Ok(false));
            assert!(!none.is_factored());
            let mut y = vec![0.0; n];
            none.get().apply(c, &r, &mut y);
            assert_eq!(y, r);
        });
    }
}
