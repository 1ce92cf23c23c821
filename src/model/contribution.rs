//! The seam of the model: a [`Contribution`] is one piece of the discrete problem on one
//! rank — the solid elements, a load, a rigid wall, a distributing coupling — and the
//! model is the list of them (MFEM: a form is a list of integrators). Each one
//!
//! * **declares** the unknowns it adds ([`Unknowns`]: per-node multipliers it owns, or
//!   global unknowns such as a reference point's six DOFs owned by one rank) and, through
//!   its definition's stencils (`def.rs`), the node couplings that partitioning and the
//!   ghost sets follow; after the unknown map is built it is told where its unknowns
//!   are ([`Contribution::bind`]) and lists the matrix blocks it will fill
//!   ([`Contribution::pattern`]);
//! * **evaluates** its residual (and, on request, its generalized Jacobian) from local
//!   data only ([`Evaluation`]): it adds into local vectors that hold owned and ghost
//!   blocks, and the model sums all ghost entries on their owners once, after every
//!   contribution has been evaluated. Physics never touches MPI;
//! * **commits** its state when a step has converged (and gives it to, and takes it back
//!   from, a restart file).
//!
//! That is the core, [`Contribution`]. What only some contributions do is a capability
//! trait, reached through an accessor of the core that returns `None` unless the
//! contribution has it (`fn outputs(&self) -> Option<&dyn Outputs> { Some(self) }`), so
//! the model's loops call only the contributions that have it:
//!
//! * [`Scaled`]: scales from the reference stiffness (walls, pairs, couplings);
//! * [`Outputs`]: history columns (reduced over ranks by the model), a summary entry,
//!   nodal or element fields and moving geometry for the HDF5/XDMF output (solids,
//!   walls, pairs, couplings);
//! * [`Dynamics`]: masses, initial velocities and contact persistency (walls: an
//!   entity's body, contact persistency);
//! * [`Explicit`]: the check that it can take part in an explicit run and kinematic
//!   corrections (solids, walls, pairs, couplings: all but walls only refuse);
//! * [`Recovery`]: a diagnosis after a failed step and adapting before the cut step is
//!   tried (walls: stick/slip cycling).
//!
//! # Adding a kind of contribution
//!
//! One module under `model/` and one deck section under `scene/`; the distributing
//! coupling (`model/coupling.rs`, `scene/coupling.rs`) is the worked example:
//!
//! 1. **Definition** (serial, global node numbers): a serde type with what the deck says
//!    (`CouplingDef`: the coupled nodes and weights, the reference point, each DOF free
//!    with an optional load curve or prescribed by a curve, the set's centroid and
//!    inertia). Implement [`super::kind::ContributionKind`] for it: `localize` gives one
//!    rank's share with local node indices (the coupling keeps the coupled nodes the
//!    rank owns, and every rank agrees that the reference point belongs to the rank with
//!    most of the coupled weight), `stencils` lists nodes that must be evaluated
//!    together on one rank (none for the coupling: its nodes reach it through its
//!    global unknowns; a node-to-face pair would list its node and the face's nodes, and
//!    the face's nodes become ghosts there), `build` makes the runtime contribution.
//!    Register it with one line in `def.rs` (`Coupling(super::coupling::CouplingDef)`).
//! 2. **Runtime**: a struct implementing [`Contribution`] and the capabilities it has.
//!    The coupling declares four global blocks (the point's translation and rotation,
//!    and their multipliers) owned by that rank and read by every rank with coupled
//!    nodes ([`Unknowns`]); `bind`
//!    learns their global and local blocks; `pattern` lists node–multiplier and
//!    point–multiplier blocks; `evaluate` adds κCᵢᵀλ to its nodes' rows and κCᵢuᵢ to the
//!    multiplier rows (partial sums: the ghost summation completes them on the owner),
//!    and the owner adds the point's rows and its applied load; `prescribed` returns the
//!    driven DOFs. Its [`Scaled::setup`] takes κ from the mean stiffness; its
//!    [`Outputs`] are the columns `tip.ux … tip.mz`, a `couplings` summary entry and the
//!    point as a grid for ParaView; its [`Explicit::start_explicit`] refuses explicit
//!    runs (the definition's `explicit_ok` says why).
//! 3. **Deck section**: a `[[couplings]]` table (`scene/deck.rs`) validated in
//!    `scene/coupling.rs`, which resolves names and curves into the definition; errors
//!    name the field.
//!
//! Nothing else changes: the unknown map, the partition graph, the ghost sets, the
//! matrix pattern, the solvers, the output and `alfe check` read the list.

use super::dofs::{DofMap, Unknowns};
use crate::linalg::DistMatrix;

/// One evaluation of a contribution at a state. Vectors are local (3 entries per local
/// block, see [`DofMap`]); a contribution may add to any entry it holds, ghosts
/// included.
pub struct Evaluation<'a> {
    /// (Pseudo-)time of the state.
    pub t: f64,
    /// Reference coordinates of the local nodes.
    pub coords: &'a [[f64; 3]],
    pub dofs: &'a DofMap,
    /// Unknowns at the state: displacements of the local nodes, then extras.
    pub u: &'a [f64],
    /// Internal forces (and constraint rows) and external forces, when a residual is
    /// wanted: r = f_int − f_ext.
    pub forces: Option<(&'a mut [f64], &'a mut [f64])>,
    /// The Jacobian ∂r/∂u, when wanted: blocks by global index (rows owned elsewhere
    /// are sent to their owners by the matrix).
    pub jacobian: Option<&'a mut DistMatrix>,
    /// A perturbed state of a finite-difference product (JFNK): a contribution with
    /// branches (contact's active and stick/slip sets, the solids' elastic and plastic
    /// points) evaluates on the branch of its last evaluation and changes no state, so
    /// J·v does not straddle a kink.
    pub frozen: bool,
}

/// What the reference stiffness says about each local node, for contributions whose
/// scale comes from the mesh (a contact κ, a penalty stiffness).
pub struct Reference<'a> {
    /// Mean diagonal entry of each owned node's 3×3 stiffness block at the reference
    /// state (0 for ghost nodes).
    pub k_diag: &'a [f64],
    /// (1 + ν)(1 − 2ν)/(1 − ν), the smallest over the node's materials: scales the
    /// P-wave modulus that dominates `k_diag` down to Young's modulus.
    pub e_factor: &'a [f64],
    /// Mean of `k_diag` over every owned node of the model (all ranks).
    pub k_mean: f64,
}

impl Reference<'_> {
    /// A contact's scales at local node n: its stiffness diagonal (the penalty's base)
    /// and κ, the diagonal scaled from the P-wave modulus that dominates it down to
    /// Young's modulus (see [`super::walls`]'s setup).
    pub fn contact_scales(&self, n: usize) -> (f64, f64) {
        let (d, f) = (self.k_diag[n], self.e_factor[n]);
        (d.max(f64::MIN_POSITIVE), (f * d).max(f64::MIN_POSITIVE))
    }
}

/// How a history column's per-rank values combine.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reduce {
    /// Summed over ranks (forces: each rank adds its nodes' share).
    Sum,
    /// The largest over ranks.
    Max,
    /// The same on every rank (a prescribed motion); taken as is.
    Replicated,
}

/// A history column a contribution publishes.
#[derive(Debug, Clone, PartialEq)]
pub struct Column {
    pub name: String,
    pub reduce: Reduce,
    /// Shared columns (`max_penetration`, contact counts) may come from several
    /// contributions: they are combined by `reduce` into one column placed after all
    /// the others.
    pub shared: bool,
    /// The run's summary carries the largest value over the steps under this name.
    pub run_max: bool,
    /// An integer count (written as one).
    pub count: bool,
}

impl Column {
    pub fn sum(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            reduce: Reduce::Sum,
            shared: false,
            run_max: false,
            count: false,
        }
    }
    pub fn replicated(name: impl Into<String>) -> Self {
        Self {
            reduce: Reduce::Replicated,
            ..Self::sum(name)
        }
    }
}

/// Where a field lives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Center {
    /// One row per owned node.
    Node,
    /// One row per local element.
    Cell,
}

/// How values of a field that several contributions publish combine, entry by entry.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Combine {
    Sum,
    Min,
    /// The first contribution (in model order) that has a value.
    First,
}

/// An output field a contribution publishes.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldSpec {
    pub name: String,
    pub center: Center,
    /// Components per row: 1, 3 or 6 (Voigt xx, yy, zz, xy, yz, xz).
    pub width: usize,
    pub combine: Combine,
    /// The value of rows no contribution sets.
    pub empty: f64,
}

/// What a contribution's field or column values are computed from.
pub struct State<'a> {
    pub t: f64,
    pub coords: &'a [[f64; 3]],
    pub dofs: &'a DofMap,
    /// The converged unknowns, local.
    pub u: &'a [f64],
}

/// Moving geometry drawn beside the mesh (a wall's surface, a reference point): cells
/// of 1 (points), 2 (segments) or 3 (triangles) point indices, written once, and points
/// written at every output step.
#[derive(Debug, Clone, PartialEq)]
pub struct GridSpec {
    /// HDF5 group path, e.g. `walls/floor` (`/walls/floor/cells`, and per step
    /// `/steps/NNNNNN/walls/floor/points`).
    pub name: String,
    /// The XDMF grid's name (the block name ParaView shows), e.g. `wall_floor`.
    pub label: String,
    /// String attributes of the HDF5 group.
    pub attrs: Vec<(String, String)>,
    pub cells: Vec<Vec<usize>>,
    pub n_points: usize,
    /// Also draw each point's path through the output steps so far, as a polyline
    /// grid `<label>_path` (a traced body-fixed point, paper §3.5).
    pub paths: bool,
}

/// A summary entry: `summary.json[group][name] = value`.
pub type SummaryEntry = (&'static str, String, serde_json::Value);

/// The core of a contribution (see the module documentation): assembly and state. Every
/// method but `name` and `evaluate` has a default for contributions without that
/// aspect; what only some contributions do is a capability trait ([`Scaled`],
/// [`Outputs`], [`Dynamics`], [`Explicit`], [`Recovery`]) reached through the accessors
/// at the end, which return `None` by default, so the model's loops call only the
/// contributions that have it.
pub trait Contribution {
    /// The deck name (or kind) of this contribution, for messages and outputs.
    fn name(&self) -> &str;

    /// The unknowns it adds (called once, before the unknown map exists).
    fn unknowns(&self) -> Unknowns {
        Unknowns::default()
    }
    /// Where its unknowns landed; `index` is its position in the model's list.
    fn bind(&mut self, _dofs: &DofMap, _index: usize) {}
    /// The (row, column) global blocks its Jacobian fills on this rank.
    fn pattern(&self, _dofs: &DofMap, _out: &mut Vec<(usize, usize)>) {}

    /// Add the residual and/or Jacobian at the state. `Err` says why the state cannot be
    /// evaluated (an inverted element): the model agrees on it across ranks.
    fn evaluate(&mut self, ev: &mut Evaluation) -> Result<(), String>;

    /// Prescribed values at time t of unknowns it owns here: (owned index, value).
    fn prescribed(&self, _t: f64, _dofs: &DofMap, _out: &mut Vec<(usize, f64)>) {}

    /// The last evaluation becomes the start of the next step.
    fn commit(&mut self) {}

    /// Its committed state, flattened (a restart file keeps it): what `commit` keeps
    /// between steps (material history, wall and pair memories, a body's pose). Empty
    /// for contributions without state.
    fn saved_state(&self) -> Vec<f64> {
        Vec::new()
    }
    /// Take back a state from [`Contribution::saved_state`] as the committed one; `Err` if it
    /// does not fit this contribution (another deck or partition).
    fn restore_state(&mut self, s: &[f64]) -> Result<(), String> {
        if s.is_empty() {
            Ok(())
        } else {
            Err(format!(
                "{} values for a contribution without state",
                s.len()
            ))
        }
    }

    /// Scales from the reference stiffness (contact κ, penalty stiffness), if it has any.
    fn scaled(&mut self) -> Option<&mut dyn Scaled> {
        None
    }
    /// History columns, fields, moving geometry and a summary entry, if it publishes any.
    fn outputs(&self) -> Option<&dyn Outputs> {
        None
    }
    /// Masses, initial velocities and contact persistency of dynamic runs, if it has any.
    fn dynamics(&self) -> Option<&dyn Dynamics> {
        None
    }
    /// Its part in an explicit run (a check, kinematic corrections), if it has one;
    /// without, it takes part as it is.
    fn explicit(&mut self) -> Option<&mut dyn Explicit> {
        None
    }
    /// What it says about, and does after, a failed attempt ([`Recovery`]), if anything.
    fn recovery(&self) -> Option<&dyn Recovery> {
        None
    }
    /// [`Contribution::recovery`], to adapt.
    fn recovery_mut(&mut self) -> Option<&mut dyn Recovery> {
        None
    }
}

/// A contribution whose scale comes from the mesh: it is set up once from the reference
/// stiffness, which the model assembles (collectively) only if some contribution on
/// some rank wants it.
pub trait Scaled {
    /// Whether [`Scaled::setup`] needs the reference stiffness (it is called on every
    /// `Scaled` contribution anyway once the reference exists).
    fn wants_reference(&self) -> bool {
        true
    }
    /// Scales from the reference stiffness.
    fn setup(&mut self, r: &Reference);
}

/// What a contribution publishes: history columns (reduced over ranks by the model), a
/// summary entry, nodal or element fields and moving geometry for the HDF5/XDMF output.
pub trait Outputs {
    /// History columns (the same on every rank).
    fn columns(&self) -> Vec<Column> {
        Vec::new()
    }
    /// This rank's values of its columns at the last evaluation, combined over ranks by
    /// each column's [`Reduce`].
    fn column_values(&self, _s: &State, _out: &mut [f64]) {}
    /// Its summary entry, from its reduced column values at the last step.
    fn summary(&self, _values: &[f64]) -> Option<SummaryEntry> {
        None
    }

    /// Output fields (the same on every rank).
    fn fields(&self) -> Vec<FieldSpec> {
        Vec::new()
    }
    /// Its fields' rows on this rank, `out[i]` for field i: each has the field's shape
    /// and holds NaN where this contribution sets nothing.
    fn field_values(&self, _s: &State, _out: &mut [Vec<f64>]) {}

    /// Moving geometry (the same on every rank).
    fn grids(&self) -> Vec<GridSpec> {
        Vec::new()
    }
    /// Grid `i`'s points at time t (rank 0 writes them), from the contribution's
    /// reduced column values at that step.
    fn grid_points(&self, _i: usize, _t: f64, _values: &[f64]) -> Vec<[f64; 3]> {
        Vec::new()
    }
}

/// What a contribution adds to a dynamic run besides its forces.
pub trait Dynamics {
    /// The diagonal mass of the unknowns it owns here (owned index, mass; a rigid body's
    /// translations and rotations). Unknowns without mass stay algebraic.
    fn masses(&self, _dofs: &DofMap) -> Vec<(usize, f64)> {
        Vec::new()
    }
    /// Initial velocities of the unknowns it owns here (owned index, value).
    fn initial_velocities(&self, _dofs: &DofMap) -> Vec<(usize, f64)> {
        Vec::new()
    }
    /// Implicit dynamics, after a converged step ending at t: corrections of owned
    /// velocities and accelerations (contact persistency).
    fn persistency(&self, _v: &mut [f64], _a: &mut [f64], _t: f64, _h: f64) {}
}

/// A contribution's part in an explicit run.
pub trait Explicit {
    /// An explicit run is starting: a contribution that cannot take part says why.
    fn start_explicit(&mut self) -> Result<(), String> {
        Ok(())
    }
    /// After the displacement update of a step ending at t (length h): kinematic
    /// corrections of owned node displacements `u` and mid-step velocities `v` (owned
    /// vectors; `m` the lumped mass).
    fn kinematic(&mut self, _k: Kinematic) {}
}

/// What [`Explicit::kinematic`] corrects, and from what.
pub struct Kinematic<'a> {
    /// Reference coordinates of the local nodes.
    pub coords: &'a [[f64; 3]],
    pub u: &'a mut [f64],
    pub v: &'a mut [f64],
    pub m: &'a [f64],
    pub t: f64,
    pub h: f64,
}

/// What a contribution says about a failed attempt, and how it adapts.
pub trait Recovery {
    /// After a step failed to converge: what this contribution saw go wrong in it, in an
    /// analyst's words (a wall: nodes that kept switching between stick and slip), or
    /// `None`.
    fn diagnose(&self) -> Option<String> {
        None
    }

    /// After a failed attempt, before the cut step is tried: adapt what made it fail (a
    /// wall softens the stick of nodes that cycled). Returns whether anything changed.
    /// Must not change the converged answer.
    fn after_failed_attempt(&mut self) -> bool {
        false
    }
}
