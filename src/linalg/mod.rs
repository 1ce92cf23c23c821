//! Distributed sparse linear algebra: block-sparse matrix, GMRES, block Jacobi,
//! restricted additive Schwarz and algebraic multigrid (hypre's BoomerAMG)
//! preconditioners. It knows the parallel layer, no physics.
//!
//! Vectors are distributed by their owned parts (the scalar slice of the rank's
//! contiguous range). The seams are [`LinearOperator`] (an assembled matrix, or a
//! matrix-free Jacobian product that evaluates a residual and may fail) and
//! [`Preconditioner`] (block Jacobi is local; restricted additive Schwarz does one halo
//! exchange per application; AMG's V-cycle communicates on every level).

pub mod amg;
pub mod asm;
pub mod block_jacobi;
pub mod block_pattern;
pub mod border;
pub mod coarse;
pub mod condense;
pub mod export;
pub mod gmres;
mod hypre;
pub mod matrix;
mod nd_lu;
pub mod ordering;
pub mod two_level;

pub use amg::{BoomerAmg, NodePoints};

pub use asm::RestrictedSchwarz;
pub use block_jacobi::{BlockJacobi, FactorOptions, Factorization, FillOrdering, LocalFactor};
pub use block_pattern::LocalBlockPattern;
pub use coarse::{CoarseMode, CoarseStats};
pub use gmres::{gmres, GmresOptions, GmresStats};
pub use two_level::TwoLevel;

pub use matrix::DistMatrix;

use crate::parallel::Comm;

/// y = A x for distributed vectors given by their owned parts.
///
/// Collective. An implementation that can fail (e.g. a matrix-free product whose
/// residual evaluation meets an inverted element) must agree on failure across ranks
/// (e.g. with [`Comm::all_ok`]) so that every rank returns `Err` together.
pub trait LinearOperator {
    fn apply(&mut self, comm: &dyn Comm, x: &[f64], y: &mut [f64]) -> crate::Result<()>;
}

impl LinearOperator for DistMatrix {
    fn apply(&mut self, comm: &dyn Comm, x: &[f64], y: &mut [f64]) -> crate::Result<()> {
        self.spmv(comm, x, y);
        Ok(())
    }
}

impl LinearOperator for &DistMatrix {
    fn apply(&mut self, comm: &dyn Comm, x: &[f64], y: &mut [f64]) -> crate::Result<()> {
        self.spmv(comm, x, y);
        Ok(())
    }
}

/// A preconditioner: set up on an assembled matrix, then applied in the Krylov solves
/// (z ≈ A⁻¹ r). Created by name ([`preconditioner`]) before there is a matrix; the first
/// [`Preconditioner::setup`] of a factored one does the symbolic work (ordering,
/// elimination structure), later ones only refactor numerically for new values of the
/// same pattern (faer's symbolic/numeric split). When to set up again (every Newton
/// iteration, or lagged) is the nonlinear solver's policy, not the preconditioner's.
///
/// Collective: every rank sets up and applies together (an implementation may
/// communicate, e.g. [`RestrictedSchwarz`] gathers its overlap). A failed setup is
/// returned on the ranks where it failed; callers agree on it with [`Comm::all_ok`].
pub trait Preconditioner {
    /// Factor (or refactor) for the matrix `k`.
    fn setup(&mut self, comm: &dyn Comm, k: &DistMatrix) -> crate::Result<()>;
    /// z = M⁻¹ r on owned parts.
    fn apply(&self, comm: &dyn Comm, r: &[f64], z: &mut [f64]);
    /// Whether `setup` factors a matrix (worth lagging, counted as a factorization);
    /// false for the identity.
    fn is_factored(&self) -> bool {
        true
    }
    /// A two-level preconditioner's coarse space: its sizes and setup times.
    fn coarse_stats(&self) -> Option<CoarseStats> {
        None
    }
}

/// Which preconditioner the Krylov solves use (deck `[solver.linear] preconditioner`).
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum PcKind {
    /// Chosen by size and rank count ([`PcKind::resolve`]): on one rank block Jacobi (the
    /// direct solve) for small systems, AMG for large ones; on more, AMG for large
    /// systems, two-level Schwarz for small ones. The deck's default; the scene turns it
    /// into [`PcKind::AutoFactored`] for problem classes AMG does not suit (nearly
    /// incompressible or plastic solids, friction, coupling constraints).
    #[default]
    Auto,
    /// Chosen by rank count among the factored ones: block Jacobi on one rank (the direct
    /// solve), two-level Schwarz on more (deck "auto-factored"; README "Linear solves"
    /// has the measurements: one-level ASM's GMRES iterations grow with the ranks, the
    /// two-level method's do not).
    AutoFactored,
    /// Block Jacobi ([`BlockJacobi`]): each rank's diagonal block factored exactly.
    BlockJacobi,
    /// Restricted additive Schwarz with one layer of overlap (the ghost nodes,
    /// [`RestrictedSchwarz`]).
    Asm,
    /// Two-level Schwarz ([`TwoLevel`]): RAS with a coarse space of interface
    /// rigid-body modes extended by RAS's own factor ([`coarse`]).
    TwoLevel,
    /// Two-level with block Jacobi as its first level.
    TwoLevelBj,
    /// Algebraic multigrid ([`BoomerAmg`], hypre): one V-cycle on the condensed
    /// displacement matrix (systems AMG; the rigid-body rotations on request).
    Amg,
    /// None: z = r.
    None,
}

/// [`PcKind::Auto`] takes AMG from this many unknowns, on any rank count: below it a
/// direct factor of the whole system is cheap (hertz-sphere, 28k unknowns, 2 ranks:
/// AMG 7.1 s against block Jacobi's 14.0 s; README "Linear solves").
pub const AUTO_AMG_MIN_UNKNOWNS: usize = 20_000;
/// ... and on one rank only from this many: one rank's block Jacobi is a full sparse
/// Cholesky, faster than AMG's iterations until its fill grows. hertz-sphere refined,
/// first step, 1 rank (`scripts/amg-scaling --ranks 1 --pc block-jacobi,amg --cells N`):
/// block Jacobi / AMG 8.5 / 9.4 s at 53k unknowns, 25.2 / 19.1 s at 99k; the whole run at
/// 28k: 9.2 / 11.9 s; the elastic block at 273k: 38.3 / 8.6 s.
pub const AUTO_AMG_MIN_UNKNOWNS_ONE_RANK: usize = 75_000;

impl PcKind {
    /// What [`PcKind::Auto`] means for `unknowns` global unknowns on `ranks` ranks; any
    /// other kind is itself.
    pub fn resolve(self, ranks: usize, unknowns: usize) -> Self {
        match self {
            Self::Auto => {
                let min = if ranks > 1 {
                    AUTO_AMG_MIN_UNKNOWNS
                } else {
                    AUTO_AMG_MIN_UNKNOWNS_ONE_RANK
                };
                if unknowns >= min {
                    Self::Amg
                } else if ranks > 1 {
                    Self::TwoLevel
                } else {
                    Self::BlockJacobi
                }
            }
            Self::AutoFactored if ranks > 1 => Self::TwoLevel,
            Self::AutoFactored => Self::BlockJacobi,
            k => k,
        }
    }

    /// Whether it builds on the node coordinates (the coarse space's rigid-body modes).
    pub fn wants_points(self) -> bool {
        matches!(self, Self::TwoLevel | Self::TwoLevelBj)
    }

    /// Every kind, in the order the deck's documentation lists them.
    pub const ALL: [Self; 8] = [
        Self::Auto,
        Self::AutoFactored,
        Self::BlockJacobi,
        Self::Asm,
        Self::TwoLevel,
        Self::TwoLevelBj,
        Self::Amg,
        Self::None,
    ];

    /// The kind named `s` (its [`PcKind::name`], as in the deck), if any.
    pub fn parse(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == s)
    }

    pub fn name(self) -> &'static str {
        match self {
            PcKind::Auto => "auto",
            PcKind::AutoFactored => "auto-factored",
            PcKind::BlockJacobi => "block-jacobi",
            PcKind::Asm => "asm",
            PcKind::TwoLevel => "two-level",
            PcKind::TwoLevelBj => "two-level-bj",
            PcKind::Amg => "amg",
            PcKind::None => "none",
        }
    }
}

/// A preconditioner of the given kind, to be set up on a matrix; a factored one
/// factors its local matrix as `opts` says; AMG builds its near-null space from `points`
/// (the owned nodes' coordinates, when the unknowns are displacements).
/// [`PcKind::Auto`] should be resolved first ([`PcKind::resolve`]); unresolved it is block
/// Jacobi.
pub fn preconditioner(
    kind: PcKind,
    opts: FactorOptions,
    points: Option<NodePoints>,
) -> Box<dyn Preconditioner> {
    match kind {
        // `Auto` is resolved by whoever knows the system's size (`PcKind::resolve`);
        // unresolved it is the safe choice.
        PcKind::Auto | PcKind::AutoFactored | PcKind::BlockJacobi => {
            Box::new(OnFirstSetup::<BlockJacobi>(None, opts))
        }
        PcKind::Asm => Box::new(OnFirstSetup::<RestrictedSchwarz>(None, opts)),
        PcKind::TwoLevel => Box::new(two_level::TwoLevelOnFirstSetup::<RestrictedSchwarz> {
            built: None,
            opts,
            points,
            mode: CoarseMode::Multiplicative,
        }),
        PcKind::TwoLevelBj => Box::new(two_level::TwoLevelOnFirstSetup::<BlockJacobi> {
            built: None,
            opts,
            points,
            mode: CoarseMode::Multiplicative,
        }),
        PcKind::Amg => Box::new(BoomerAmg::new(points)),
        PcKind::None => Box::new(Identity),
    }
}

/// A factored preconditioner built from its first matrix.
trait Build: Preconditioner + Sized {
    fn build(comm: &dyn Comm, k: &DistMatrix, opts: FactorOptions) -> crate::Result<Self>;
}

impl Build for BlockJacobi {
    fn build(_comm: &dyn Comm, k: &DistMatrix, opts: FactorOptions) -> crate::Result<Self> {
        BlockJacobi::with_factor_options(k, opts)
    }
}

impl Build for RestrictedSchwarz {
    fn build(comm: &dyn Comm, k: &DistMatrix, opts: FactorOptions) -> crate::Result<Self> {
        RestrictedSchwarz::with_factor_options(comm, k, opts)
    }
}

/// Built (symbolic and numeric) at the first setup, refactored at the next ones.
struct OnFirstSetup<P>(Option<P>, FactorOptions);

impl<P: Build> Preconditioner for OnFirstSetup<P> {
    fn setup(&mut self, comm: &dyn Comm, k: &DistMatrix) -> crate::Result<()> {
        match &mut self.0 {
            Some(p) => p.setup(comm, k),
            None => {
                self.0 = Some(P::build(comm, k, self.1)?);
                Ok(())
            }
        }
    }
    fn apply(&self, comm: &dyn Comm, r: &[f64], z: &mut [f64]) {
        match &self.0 {
            Some(p) => p.apply(comm, r, z),
            None => z.copy_from_slice(r),
        }
    }
}

/// No preconditioning: z = r.
#[derive(Debug, Default, Clone, Copy)]
pub struct Identity;

impl Preconditioner for Identity {
    fn setup(&mut self, _comm: &dyn Comm, _k: &DistMatrix) -> crate::Result<()> {
        Ok(())
    }
    fn apply(&self, _comm: &dyn Comm, r: &[f64], z: &mut [f64]) {
        z.copy_from_slice(r);
    }
    fn is_factored(&self) -> bool {
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_takes_amg_from_a_size_that_depends_on_the_ranks() {
        let r = |ranks, n| PcKind::Auto.resolve(ranks, n);
        assert_eq!(r(1, 27_975), PcKind::BlockJacobi);
        assert_eq!(r(1, AUTO_AMG_MIN_UNKNOWNS_ONE_RANK), PcKind::Amg);
        assert_eq!(r(2, 27_975), PcKind::Amg);
        assert_eq!(r(16, AUTO_AMG_MIN_UNKNOWNS - 1), PcKind::TwoLevel);
        assert_eq!(r(1, AUTO_AMG_MIN_UNKNOWNS - 1), PcKind::BlockJacobi);
        for k in [
            PcKind::BlockJacobi,
            PcKind::Asm,
            PcKind::TwoLevel,
            PcKind::TwoLevelBj,
            PcKind::Amg,
            PcKind::None,
        ] {
            assert_eq!(k.resolve(4, 1 << 20), k);
            assert_eq!(PcKind::parse(k.name()), Some(k));
        }
        assert_eq!(PcKind::parse("auto"), Some(PcKind::Auto));
        // Where AMG does not suit: the direct solve on one rank, two-level on more.
        assert_eq!(
            PcKind::AutoFactored.resolve(1, 1 << 20),
            PcKind::BlockJacobi
        );
        assert_eq!(PcKind::AutoFactored.resolve(2, 100), PcKind::TwoLevel);
        assert_eq!(PcKind::parse("auto-factored"), Some(PcKind::AutoFactored));
    }
}
