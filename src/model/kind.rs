//! What every kind of contribution definition does, and the view of the partition it
//! localizes itself with. Definitions (`def.rs` registers them) hold global node
//! numbers; each rank's share holds local ones and builds its [`Contribution`].

use super::local::{LocalElements, LocalMesh};
use super::Contribution;

/// Every rank's view of the partition while it localizes a definition.
pub struct Localizer<'a> {
    pub rank: usize,
    pub ranks: usize,
    /// Owning rank of every global node (the user's numbering).
    pub owner: &'a [u32],
    /// This rank's local index of every global node, or `usize::MAX`.
    pub local_of: &'a [usize],
}

impl Localizer<'_> {
    /// The local index of a node this rank owns.
    pub fn owned(&self, node: usize) -> Option<usize> {
        (self.owner[node] as usize == self.rank).then(|| self.local_of[node])
    }
}

/// What a kind of contribution definition does (see [`super::contribution`] on adding
/// one). Definitions hold global node numbers; `localize` gives one rank's share with
/// local node indices, which `build` turns into the runtime contribution.
pub trait ContributionKind {
    /// What kind it is ("wall", "coupling", ...).
    fn kind_name(&self) -> &'static str;
    /// Its deck name.
    fn name(&self) -> &str;
    /// One line for `alfe check`.
    fn describe(&self) -> String;
    /// What `alfe check` adds about its state at t = 0 given the mesh's coordinates (a
    /// wall: its tracked nodes' initial gaps), if anything.
    fn initial_state(&self, _coords: &[[f64; 3]]) -> Option<String> {
        None
    }
    /// The nodes it acts on (global numbers; for `alfe check`).
    fn nodes(&self) -> Vec<usize> {
        Vec::new()
    }
    /// Scalar unknowns it adds to the model (multipliers, reference-point DOFs).
    fn extra_unknowns(&self) -> usize {
        0
    }
    /// Node stencils: nodes coupled by one piece of the contribution, evaluated on the
    /// owner of the first (global numbers). They add edges to the partition graph and
    /// ghost nodes on the evaluating rank.
    fn stencils(&self) -> Vec<Vec<usize>> {
        Vec::new()
    }
    /// This rank's share (local node indices).
    fn localize(&self, l: &Localizer) -> Self
    where
        Self: Sized;
    /// The runtime contribution on this rank, from its localized definition.
    fn build(&self, mesh: &LocalMesh, elements: &LocalElements) -> Box<dyn Contribution>;
}
