//! A factored preconditioner (block Jacobi or restricted additive Schwarz) that can be
//! kept (lagged) across Newton iterations and load steps: the Krylov solve always uses
//! the fresh Jacobian, only the preconditioner is from an older one (DESIGN.md: "block
//! Jacobi of a lagged stiffness").

use super::asm::RestrictedSchwarz;
use super::block_jacobi::BlockJacobi;
use super::matrix::DistMatrix;
use super::{PcKind, Preconditioner};
use crate::parallel::Comm;

enum Factored {
    BlockJacobi(Box<BlockJacobi>),
    Asm(Box<RestrictedSchwarz>),
}

impl Factored {
    fn kind(&self) -> PcKind {
        match self {
            Factored::BlockJacobi(_) => PcKind::BlockJacobi,
            Factored::Asm(_) => PcKind::Asm,
        }
    }
}

pub struct LaggedPreconditioner {
    pc: Option<Factored>,
    /// Reuses allowed after a factorization before the next one (0 = refactor every time).
    pub lag: usize,
    uses: usize,
    pub factorizations: usize,
}

/// The former name, from when block Jacobi was the only factored preconditioner.
pub type LaggedBlockJacobi = LaggedPreconditioner;

impl LaggedPreconditioner {
    pub fn new(lag: usize) -> Self {
        Self {
            pc: None,
            lag,
            uses: 0,
            factorizations: 0,
        }
    }

    /// Collective. Make a factorization of the `kind` of preconditioner available for
    /// `k`: refactor if there is none (or one of another kind) or it has been reused
    /// `lag` times, keep it otherwise. Returns whether it factored. A failure on any rank
    /// is a failure on all (no rank is left waiting in GMRES). [`PcKind::None`] drops
    /// any factorization and never factors.
    pub fn update(
        &mut self,
        comm: &dyn Comm,
        k: &DistMatrix,
        kind: PcKind,
    ) -> Result<bool, String> {
        if kind == PcKind::None {
            self.pc = None;
            return Ok(false);
        }
        let same_kind = self.pc.as_ref().is_some_and(|p| p.kind() == kind);
        if same_kind && self.uses < self.lag {
            self.uses += 1;
            return Ok(false);
        }
        if !same_kind {
            self.pc = None;
        }
        let res = match (self.pc.as_mut(), kind) {
            (Some(Factored::BlockJacobi(p)), _) => p.refactor(k),
            (Some(Factored::Asm(p)), _) => p.refactor(comm, k),
            (None, PcKind::Asm) => {
                RestrictedSchwarz::new(comm, k).map(|p| self.pc = Some(Factored::Asm(Box::new(p))))
            }
            (None, _) => {
                BlockJacobi::new(k).map(|p| self.pc = Some(Factored::BlockJacobi(Box::new(p))))
            }
        };
        let ok = comm.all_ok(res.is_ok());
        if !ok {
            self.pc = None;
            let what = match kind {
                PcKind::Asm => "ASM",
                _ => "block-Jacobi",
            };
            return Err(match res {
                Err(e) => format!("{what} factorization failed: {e}"),
                Ok(()) => format!("{what} factorization failed on another rank"),
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

    /// The current factorization, if any.
    pub fn get(&self) -> Option<&dyn Preconditioner> {
        self.pc.as_ref().map(|p| -> &dyn Preconditioner {
            match p {
                Factored::BlockJacobi(b) => b.as_ref(),
                Factored::Asm(a) => a.as_ref(),
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parallel::run_ranks;
    use crate::solve::linear::block_jacobi::tests::elasticity_cube;

    /// The lag applies to either kind; changing the kind refactors at once; `None`
    /// drops the factorization.
    #[test]
    fn lag_and_kind_changes() {
        run_ranks(2, |c| {
            let m = elasticity_cube(c, 3, &[32, 32]);
            let mut pc = LaggedPreconditioner::new(1);
            assert!(pc.get().is_none());
            assert_eq!(pc.update(c, &m, PcKind::Asm), Ok(true));
            assert_eq!(pc.update(c, &m, PcKind::Asm), Ok(false));
            assert_eq!(pc.update(c, &m, PcKind::Asm), Ok(true));
            pc.invalidate();
            assert_eq!(pc.update(c, &m, PcKind::Asm), Ok(true));
            assert_eq!(pc.update(c, &m, PcKind::BlockJacobi), Ok(true));
            assert_eq!(pc.update(c, &m, PcKind::BlockJacobi), Ok(false));
            assert_eq!(pc.factorizations, 4);
            // Block Jacobi and ASM differ on 2 ranks.
            let n = m.n_owned_dofs();
            let r: Vec<f64> = (0..n).map(|i| (i as f64).cos()).collect();
            let (mut z_bj, mut z_asm) = (vec![0.0; n], vec![0.0; n]);
            pc.get().unwrap().apply(c, &r, &mut z_bj);
            assert_eq!(pc.update(c, &m, PcKind::Asm), Ok(true));
            pc.get().unwrap().apply(c, &r, &mut z_asm);
            let d = c.norm2(
                &z_bj
                    .iter()
                    .zip(&z_asm)
                    .map(|(a, b)| a - b)
                    .collect::<Vec<_>>(),
            );
            assert!(d > 1e-6 * c.norm2(&z_bj));
            assert_eq!(pc.update(c, &m, PcKind::None), Ok(false));
            assert!(pc.get().is_none());
        });
    }
}
