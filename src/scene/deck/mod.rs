//! The scene deck: TOML, parsed with serde. Unknown keys are errors
//! (`deny_unknown_fields` everywhere) and every error names its field path, e.g.
//! `parts[0].mesh.cells: invalid length 2, expected an array of length 3`.

pub mod coupling;
pub mod pairs;
pub mod solver;
pub mod steps;
pub mod walls;

pub use crate::linalg::PcKind;
pub use crate::solve::nonlinear::{FdRule, SolverKind};
pub use crate::solve::{AnalysisKind, MassKind, Predictor, Scheme};
pub use coupling::{Amount, Components, CouplingDeck, WeightsDeck};
pub use pairs::{BoltDeck, LockAt, PairsDeck, Weights};
use serde::{Deserialize, Serialize};
pub use solver::{LineSearchDeck, LineSearchWord, LinearDeck, SolverDeck};
pub use steps::StepDeck;
pub use walls::{DofDeck, DofType, SegmentDeck, ShapeKind, TraceDeck, WallDeck, WallMotionDeck};

#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Deck {
    pub scene: SceneInfo,
    /// Materials, each named for the parts that use it.
    #[serde(default)]
    pub materials: Vec<MaterialDeck>,
    /// The parts: each a mesh (generated or read from a file) of one material.
    pub parts: Vec<PartDeck>,
    /// Named node selections (a box, a mesh group, node numbers), optionally within one part.
    #[serde(default)]
    pub node_sets: Vec<NodeSetDeck>,
    /// Named boundary-face selections (a box or a mesh group), optionally within one part.
    #[serde(default)]
    pub surfaces: Vec<SurfaceDeck>,
    /// Named piecewise-linear time curves that scale loads and motions.
    #[serde(default)]
    pub curves: Vec<CurveDeck>,
    /// Supports and prescribed displacements or rotations of node sets.
    #[serde(default)]
    pub boundary: Vec<BoundaryDeck>,
    /// Nodal forces, pressures and body loads.
    #[serde(default)]
    pub loads: Vec<LoadDeck>,
    pub analysis: AnalysisDeck,
    /// Analysis steps in sequence (Abaqus `*STEP`): loads, motions and bolts may name
    /// one (see `scene::steps`).
    #[serde(default)]
    pub steps: Vec<StepDeck>,
    #[serde(default)]
    pub solver: SolverDeck,
    #[serde(default)]
    pub output: OutputDeck,
    /// Initial velocities of dynamic analyses (later entries win where sets overlap).
    #[serde(default)]
    pub initial_velocity: Vec<InitialVelocityDeck>,
    /// Quantities of interest: the scene's answers, with references where known
    /// (`output::quantities`).
    #[serde(default)]
    pub quantities: Vec<QuantityDeck>,
    /// Rigid walls (contact, docs/src/design.md "Contact kinds").
    #[serde(default)]
    pub walls: Vec<WallDeck>,
    /// Contact entities: rigid bodies with analytical shapes whose DOFs are prescribed or
    /// free (the paper's §3.5–3.6); the same table as a wall.
    #[serde(default)]
    pub entities: Vec<WallDeck>,
    /// Distributing couplings (a reference point tied to nodes, RBE3).
    #[serde(default)]
    pub couplings: Vec<CouplingDeck>,
    /// Small-sliding contact between deformable parts (the paper's §3.7).
    #[serde(default)]
    pub pairs: Vec<PairsDeck>,
    /// Bolt pretension sections (tied across a cut, pretensioned, then locked).
    #[serde(default)]
    pub bolts: Vec<BoltDeck>,
    /// How the elements are split over ranks (default METIS).
    #[serde(default)]
    pub partition: Option<PartitionDeck>,
}

/// `[partition]`: `method = "metis"` (default: fewest cut faces) or `"slabs"` with
/// `axis = "x" | "y" | "z"` (equal slabs of elements along that axis, LS-DYNA's
/// decomposition along a direction: for steering where the cuts go).
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PartitionDeck {
    /// "metis" (default) or "slabs" (equal slabs along `axis`).
    pub method: PartitionMethodDeck,
    /// Slabs: the axis they are cut along ("x", "y" or "z").
    #[serde(default)]
    pub axis: Option<Comp>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum PartitionMethodDeck {
    Metis,
    Slabs,
}

/// An initial velocity on a part or a node set (exactly one of `part`, `set`).
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct InitialVelocityDeck {
    /// Every node of this part ...
    #[serde(default)]
    pub part: Option<String>,
    /// ... or of this node set.
    #[serde(default)]
    pub set: Option<String>,
    /// The initial velocity [vx, vy, vz] (length / time).
    pub velocity: [f64; 3],
}

#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SceneInfo {
    /// The scene's name: 1–64 letters, digits, `-`, `_`, `.` (it names the result files).
    pub name: String,
    /// One line on what the scene is.
    #[serde(default)]
    pub description: String,
    /// The consistent unit system every number in the deck is in.
    pub units: Units,
}

/// Consistent unit systems (length, mass, time → force, stress, density).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, schemars::JsonSchema)]
pub enum Units {
    /// m, kg, s → N, Pa, kg/m³
    #[serde(rename = "m-kg-s")]
    MKgS,
    /// mm, tonne, s → N, MPa, t/mm³ (steel: 7.85e-9)
    #[serde(rename = "mm-t-s")]
    MmTS,
    /// mm, kg, ms → kN, GPa, kg/mm³ (steel: 7.85e-6)
    #[serde(rename = "mm-kg-ms")]
    MmKgMs,
    /// mm, g, ms → N, MPa, g/mm³ (steel: 7.85e-3)
    #[serde(rename = "mm-g-ms")]
    MmGMs,
}

impl Units {
    pub fn describe(self) -> &'static str {
        match self {
            Units::MKgS => "length m, mass kg, time s, force N, stress Pa",
            Units::MmTS => "length mm, mass t, time s, force N, stress MPa",
            Units::MmKgMs => "length mm, mass kg, time ms, force kN, stress GPa",
            Units::MmGMs => "length mm, mass g, time ms, force N, stress MPa",
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum MaterialModel {
    /// Small-strain isotropic Hooke's law: `E`, `nu`.
    LinearElastic,
    /// Compressible neo-Hookean (Bonet & Wood eq. 6.28), finite strain: `E`, `nu`.
    NeoHookean,
    /// LS-DYNA's hyperelastic rubber: `C10`, `C01`, `nu`; G = 2(C10 + C01), K from G
    /// and ν; W = C10(Ī₁−3) + C01(Ī₂−3) + K/2 (J−1)².
    MooneyRivlin,
    /// Finite-strain J2 plasticity (Hencky elasticity, exponential-map return):
    /// `E`, `nu`, `yield_stress`, `hardening`.
    J2,
}

impl MaterialModel {
    pub fn name(self) -> &'static str {
        match self {
            MaterialModel::LinearElastic => "linear-elastic",
            MaterialModel::NeoHookean => "neo-hookean",
            MaterialModel::MooneyRivlin => "mooney-rivlin",
            MaterialModel::J2 => "j2",
        }
    }
}

/// A material. Which fields apply depends on `model`; a field the model does not use
/// is an error (so a typo in the model name cannot silently drop a parameter).
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MaterialDeck {
    /// The material's name, for `parts[].material`.
    pub name: String,
    /// The constitutive model: "linear-elastic", "neo-hookean", "mooney-rivlin" or "j2".
    pub model: MaterialModel,
    /// Young's modulus (stress units): linear-elastic, neo-hookean, j2.
    #[serde(default, rename = "E")]
    pub e: Option<f64>,
    /// Poisson's ratio (all models).
    pub nu: f64,
    /// Mooney–Rivlin constants (stress units).
    #[serde(default, rename = "C10")]
    pub c10: Option<f64>,
    /// Mooney–Rivlin's second constant (stress units; default 0, neo-Hookean).
    #[serde(default, rename = "C01")]
    pub c01: Option<f64>,
    /// Initial yield stress σ_y0 (j2).
    #[serde(default)]
    pub yield_stress: Option<f64>,
    /// Isotropic hardening (j2; default perfectly plastic).
    #[serde(default)]
    pub hardening: Option<HardeningDeck>,
    /// Mass density (mass / length³); only dynamics needs it.
    #[serde(default)]
    pub density: f64,
}

/// Isotropic hardening of the yield stress with equivalent plastic strain ε̄p.
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum HardeningDeck {
    /// σ_y = σ_y0 + `modulus` · ε̄p.
    Linear { modulus: f64 },
    /// σ_y = σ_y0 + `k` · ε̄p^`n`.
    Power { k: f64, n: f64 },
    /// σ_y(ε̄p) piecewise linear through `points` = [[ε̄p, σ_y], ...] (first ε̄p = 0,
    /// σ_y there equal to `yield_stress`), or through the named `[[curves]]` entry.
    Table {
        #[serde(default)]
        points: Option<Vec<[f64; 2]>>,
        #[serde(default)]
        curve: Option<String>,
    },
}

/// How a part's elements treat volume change. A formulation named must apply to every
/// element type of the part (an error names the type otherwise); `alfe check` prints
/// what each part got.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Default, schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum FormulationDeck {
    /// EAS for a part meshed as a sheet; hybrid where the material is nearly
    /// incompressible (ν ≥ 0.45) and hyperelastic in a static or implicit analysis;
    /// F-bar there in explicit runs and for plastic parts (isochoric flow); standard
    /// otherwise (and for tet4 always).
    #[default]
    Auto,
    /// Full integration of F: locks for ν → 0.5 and in plastic flow.
    Standard,
    /// F-bar (mean-dilatation J̄; B-bar for small strain).
    Fbar,
    /// One point and hourglass stiffness (LS-DYNA's ELFORM 1): for large compression.
    Reduced,
    /// Enhanced assumed strains (Simo–Armero Q1/E9): thin walls bend with one element
    /// through the thickness.
    Eas,
    /// Displacements and one pressure unknown per element (Abaqus' C3D8H): mean
    /// dilatation with the pressure solved for; static and implicit analyses.
    Hybrid,
}

#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PartDeck {
    /// The part's name (output blocks, selections).
    pub name: String,
    /// The name of its material (`[[materials]]`).
    pub material: String,
    /// The mesh: generated (box, extruded-quad, cylinder, ring, blocks), read (gmsh, abaqus, lsdyna, file) or a sheet extruded from a surface mesh.
    pub mesh: MeshDeck,
    /// Volume treatment of hex8 elements (default auto).
    #[serde(default)]
    pub formulation: FormulationDeck,
    /// Hourglass spring coefficient (F-bar: default 0; reduced: default 1).
    #[serde(default)]
    pub hourglass: Option<f64>,
    /// Placement of the mesh (an Abaqus instance): rotated about the origin, then
    /// translated. Groups keep their names; selections by box see the placed part.
    #[serde(default)]
    pub rotate: Option<RotateDeck>,
    /// Translation [x, y, z] applied after `rotate`.
    #[serde(default)]
    pub translate: Option<[f64; 3]>,
}

/// A rotation by `angle` degrees about `axis` through the origin (right-hand rule).
#[derive(Debug, Clone, Copy, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RotateDeck {
    /// Rotation axis [x, y, z] through the origin.
    pub axis: [f64; 3],
    /// Rotation angle in degrees (right hand).
    pub angle: f64,
}

#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Default, schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum ElementDeck {
    #[default]
    Hex8,
    Tet4,
    /// Tet4 cells with a node at the middle of every edge.
    Tet10,
    /// Each cell two prisms (its z-faces split on a diagonal).
    Wedge6,
}

#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum MeshDeck {
    /// A generated block; its six sides are groups `xmin`, `xmax`, `ymin`, ... .
    Box {
        #[serde(default)]
        origin: [f64; 3],
        size: [f64; 3],
        cells: [usize; 3],
        /// Per axis: last cell size / first cell size (geometric); 1 = uniform.
        #[serde(default = "ones")]
        grading: [f64; 3],
        #[serde(default)]
        element: ElementDeck,
        /// Move interior nodes by up to this fraction of the local edge (patch tests).
        #[serde(default)]
        distort: f64,
    },
    /// A quadrilateral in the x–y plane extruded along z: the unit square mapped
    /// bilinearly onto `corners` (counter-clockwise, the first at the `xmin`/`ymin`
    /// corner), z from `z0` to `z0 + thickness`. The sides are groups `xmin`, `xmax`,
    /// `ymin`, `ymax` (in the square's parameters: `xmin` is the edge from corner 0 to
    /// corner 3), `zmin`, `zmax`.
    #[serde(rename = "extruded-quad")]
    ExtrudedQuad {
        corners: [[f64; 2]; 4],
        #[serde(default)]
        z0: f64,
        thickness: f64,
        cells: [usize; 3],
        #[serde(default)]
        element: ElementDeck,
    },
    /// A solid hex8 cylinder along z, z from `z0` to `z0 + length`: a butterfly
    /// (O-grid) cross-section, `cells_radial` (≥ 2) cells from the axis to the surface,
    /// 8⌊cells_radial/2⌋ around. Groups `zmin`, `zmax`, `outer` and, for the x ≥ 0,
    /// y ≥ 0 `quarter`, `xmin` (x = 0) and `ymin` (y = 0).
    Cylinder {
        radius: f64,
        length: f64,
        #[serde(default)]
        z0: f64,
        cells_radial: usize,
        cells_axial: usize,
        /// Last / first cell length along z (geometric); 1 = uniform.
        #[serde(default = "one_f64")]
        axial_grading: f64,
        #[serde(default)]
        sector: SectorDeck,
    },
    /// A hex8 annular sector about `center`, polar angles `angles` = [a0, a1] in degrees
    /// (a full 360° ring is closed), z from `z0` to `z0 + thickness`; `cells` = [radial,
    /// circumferential, through-thickness]. Groups `inner`, `outer`, `zmin`, `zmax` and,
    /// unless closed, `start` (at a0) and `end` (at a1).
    Ring {
        inner_radius: f64,
        outer_radius: f64,
        thickness: f64,
        #[serde(default)]
        z0: f64,
        #[serde(default = "full_turn")]
        angles: [f64; 2],
        cells: [usize; 3],
        #[serde(default)]
        center: [f64; 2],
    },
    /// Hex8 cells of a lattice whose centres lie in one of the `solids` boxes and in none
    /// of the `holes` ([[min], [max]] each); the lattice lines are the boxes' faces, spans
    /// split into cells no longer than `cell_size`. No groups: select surfaces by box.
    Blocks {
        solids: Vec<[[f64; 3]; 2]>,
        #[serde(default)]
        holes: Vec<[[f64; 3]; 2]>,
        cell_size: f64,
        /// Finer slabs of the lattice: `{ axis = "x", from, to, cell_size }`.
        #[serde(default)]
        refine: Vec<SlabDeck>,
    },
    /// A Gmsh MSH 4.1 or 2.2 file, ASCII or binary (hex8, tet4, tet10, wedge6; physical groups become
    /// groups). A relative path is taken from the deck's directory.
    Gmsh { file: String },
    /// An Abaqus/CalculiX input file (`.inp`): its `*NODE`, `*ELEMENT` (C3D8, C3D4,
    /// C3D10, C3D6 and variants), `*NSET`, `*ELSET`, `*SURFACE` and `*INCLUDE`; sets and
    /// surfaces become groups under the file's names. Its model keywords are not read
    /// here (`alfe import` translates them). `elset`: only that element set's elements
    /// (a file holding more than this part); default all of them.
    Abaqus {
        file: String,
        #[serde(default)]
        elset: Option<String>,
    },
    /// An LS-DYNA keyword file (`.k`): `*NODE`, `*ELEMENT_SOLID` (hex8, degenerate
    /// tets and wedges, 10-node tets), `*PART` (groups by title), `*SET_NODE_LIST`,
    /// `*SET_SEGMENT`, `*INCLUDE`. `pid`: only that LS-DYNA part's solids (one alfe part
    /// per LS-DYNA part, each with its own material); default all of them.
    #[serde(rename = "lsdyna")]
    LsDyna {
        file: String,
        #[serde(default)]
        pid: Option<i64>,
    },
    /// A mesh file of the kind its extension says: `.msh` Gmsh, `.inp` Abaqus, `.k`
    /// (`.key`, `.dyn`) LS-DYNA.
    File { file: String },
    /// A thin wall: a Gmsh MSH 4.1 ASCII surface mesh of quad4 and tri3 elements
    /// extruded by `thickness` into `layers` elements through it (hex8 from quads,
    /// wedge6 from triangles), along the surface's normal (the right-hand normal of the
    /// first facet in the file; facets are oriented alike). Groups:
    /// `top`, `bottom` (faces on the normal's side and the other); per physical surface
    /// S element and node group S and faces `S.top`, `S.bottom`; per physical curve the
    /// nodes through the thickness and, along the sheet's edge, its edge faces; per
    /// physical point its nodes through the thickness.
    Sheet {
        file: String,
        thickness: f64,
        #[serde(default = "one_usize")]
        layers: usize,
        /// Where the surface lies: `middle` (default), `along-normal` (the sheet grows
        /// along the normal from it) or `against-normal`.
        #[serde(default)]
        offset: SheetOffsetDeck,
    },
}

#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Default, schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum SheetOffsetDeck {
    #[default]
    Middle,
    AlongNormal,
    AgainstNormal,
}

fn one_usize() -> usize {
    1
}

/// A slab of a `blocks` lattice, `from` ≤ `axis` ≤ `to`, meshed at its own cell size.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SlabDeck {
    /// The axis the slab spans ("x", "y" or "z").
    pub axis: Comp,
    /// The slab's start along `axis`.
    pub from: f64,
    /// The slab's end along `axis`.
    pub to: f64,
    /// Largest cell length inside the slab.
    pub cell_size: f64,
}

/// How much of a generated cylinder: all of it, or the x ≥ 0, y ≥ 0 quadrant.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Default, schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum SectorDeck {
    #[default]
    Full,
    Quarter,
}

fn one_f64() -> f64 {
    1.0
}

fn full_turn() -> [f64; 2] {
    [0.0, 360.0]
}

fn ones() -> [f64; 3] {
    [1.0; 3]
}

#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BoxSel {
    /// The box's lowest corner [x, y, z].
    pub min: [f64; 3],
    /// The box's highest corner [x, y, z].
    pub max: [f64; 3],
}

/// A node set: exactly one of `box`, `group`, `nodes`; `part` restricts it to a part.
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct NodeSetDeck {
    /// The set's name, for the sections that select nodes.
    pub name: String,
    /// Select within this part only.
    #[serde(default)]
    pub part: Option<String>,
    /// Every node inside this box { min, max } (with a tolerance of 1e-9 of the model's size).
    #[serde(default, rename = "box")]
    pub bbox: Option<BoxSel>,
    /// A mesh group: a box side (`xmin`, ...) or a Gmsh physical group name.
    #[serde(default)]
    pub group: Option<String>,
    /// Node numbers (0-based, in the order of the part meshes).
    #[serde(default)]
    pub nodes: Option<Vec<usize>>,
}

/// A surface (boundary faces): exactly one of `box`, `group`; `part` restricts it.
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SurfaceDeck {
    /// The surface's name, for walls, pairs, pressures and couplings.
    pub name: String,
    /// Select within this part only.
    #[serde(default)]
    pub part: Option<String>,
    /// The boundary faces inside this box { min, max }.
    #[serde(default, rename = "box")]
    pub bbox: Option<BoxSel>,
    /// A mesh group of faces: a box side (`xmin`, ...) or a Gmsh physical group name.
    #[serde(default)]
    pub group: Option<String>,
}

/// A piecewise-linear time curve, constant beyond its ends.
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CurveDeck {
    /// The curve's name, for the loads and motions that use it.
    pub name: String,
    /// [[t0, v0], [t1, v1], ...] with strictly increasing t.
    pub points: Vec<[f64; 2]>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Comp {
    X,
    Y,
    Z,
}

#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum BoundaryDeck {
    /// Zero displacement on the listed components (default all three).
    Fixed {
        set: String,
        #[serde(default = "all_comps")]
        components: Vec<Comp>,
    },
    /// Prescribed displacement `value × curve(t)` on the listed components.
    Displacement {
        set: String,
        components: Vec<Comp>,
        value: f64,
        /// Default: a ramp from 0 at t = 0 to 1 at the end time (or over `step`).
        #[serde(default)]
        curve: Option<String>,
        /// An analysis step: the curve runs in its time (the set is held at 0 before it).
        #[serde(default)]
        step: Option<String>,
    },
    /// Rigid rotation of the set by `angle × curve(t)` (radians, right-hand rule) about
    /// the line through `center` along `axis`; all three components are prescribed.
    Rotation {
        set: String,
        axis: [f64; 3],
        #[serde(default)]
        center: [f64; 3],
        angle: f64,
        #[serde(default)]
        curve: Option<String>,
        #[serde(default)]
        step: Option<String>,
    },
}

fn all_comps() -> Vec<Comp> {
    vec![Comp::X, Comp::Y, Comp::Z]
}

impl BoundaryDeck {
    pub fn set(&self) -> &str {
        match self {
            BoundaryDeck::Fixed { set, .. }
            | BoundaryDeck::Displacement { set, .. }
            | BoundaryDeck::Rotation { set, .. } => set,
        }
    }
}

#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum LoadDeck {
    /// The same force on every node of a set: `force × curve(t)` per node.
    Nodal {
        set: String,
        force: [f64; 3],
        #[serde(default)]
        curve: Option<String>,
        /// An analysis step: the curve runs in its time (absent before, held after).
        #[serde(default)]
        step: Option<String>,
    },
    /// A dead traction (force per reference area) on a surface.
    Traction {
        surface: String,
        traction: [f64; 3],
        #[serde(default)]
        curve: Option<String>,
        #[serde(default)]
        step: Option<String>,
    },
    /// A follower pressure (positive pushes into the body) on a surface.
    Pressure {
        surface: String,
        pressure: f64,
        #[serde(default)]
        curve: Option<String>,
        #[serde(default)]
        step: Option<String>,
    },
}

#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AnalysisDeck {
    #[serde(rename = "type")]
    pub kind: AnalysisKind,
    /// Pseudo-time at the end of the load path; with `[[steps]]` their total duration
    /// (which may be left out).
    #[serde(default)]
    pub end_time: f64,
    /// Static: pseudo-time step; implicit: the time step Δt (the first, and the largest
    /// unless `max_step` says); explicit: an optional fixed Δt (0 = not given: the stable
    /// step from the mesh times `dt_factor`). Required unless explicit.
    #[serde(default)]
    pub step: f64,
    /// Smallest step a failing step may be cut to before the run ends (default step/1000).
    #[serde(default)]
    pub min_step: Option<f64>,
    /// Largest step after growth (default `step`).
    #[serde(default)]
    pub max_step: Option<f64>,
    /// Implicit: the scheme (default generalized-alpha).
    #[serde(default)]
    pub scheme: Option<Scheme>,
    /// Implicit generalized-α / HHT: spectral radius at infinite frequency (default 0.9).
    #[serde(default)]
    pub rho_inf: Option<f64>,
    /// Implicit: consistent (default) or lumped mass.
    #[serde(default)]
    pub mass: Option<MassKind>,
    /// Explicit: Δt = dt_factor × the stable step (default 0.9, LS-DYNA's TSSFAC).
    #[serde(default)]
    pub dt_factor: Option<f64>,
    /// Static: "linear" (default) starts each step from the last increment extrapolated
    /// (Abaqus's default); "none" from the last converged state.
    #[serde(default)]
    pub predictor: Option<Predictor>,
}

#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OutputDeck {
    /// Write fields every n-th converged step (the last step is always written).
    #[serde(default = "one")]
    pub every: usize,
    /// Node sets whose reaction forces go to the history; default: every constrained set.
    #[serde(default)]
    pub reactions: Option<Vec<String>>,
    /// Dynamic runs: write fields at every multiple of this time (and the last step);
    /// default end_time / 100.
    #[serde(default)]
    pub interval: Option<f64>,
    /// Node sets whose mean displacement goes to the history (`<set>.ux, .uy, .uz`).
    #[serde(default)]
    pub displacements: Vec<String>,
    /// Parts whose largest element von Mises stress goes to the history
    /// (`<part>.max_von_mises`) and, its largest over the run, to summary.json.
    #[serde(default)]
    pub peak_stress: Vec<String>,
    /// Write every nonlinear iteration's residual, failed attempts included, to
    /// `iterations.csv` (also `alfe run --iterations`).
    #[serde(default)]
    pub iterations: bool,
}

/// One quantity of interest: `expression` over the history's columns, taken `at` a time or
/// `over` the run (`last`, the default; `max`, `min`, `max_abs`), with an optional
/// `reference` and relative `tolerance`.
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct QuantityDeck {
    /// The quantity's name (in summary.json and the study).
    pub name: String,
    /// What to evaluate: an expression of history columns (e.g. `-upper_pin.fy`).
    pub expression: String,
    /// Evaluate at this time (default: the end).
    #[serde(default)]
    pub at: Option<f64>,
    /// Or a reduction over the run: "last", "max", "min" or "max_abs".
    #[serde(default)]
    pub over: Option<OverDeck>,
    /// The known answer, if any (analytic, published, a peer's).
    #[serde(default)]
    pub reference: Option<f64>,
    /// Relative tolerance against `reference` (absolute against 0).
    #[serde(default)]
    pub tolerance: Option<f64>,
    /// What the quantity is, in words (units included).
    #[serde(default)]
    pub description: String,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum OverDeck {
    Last,
    Max,
    Min,
    MaxAbs,
}

pub(super) fn yes() -> bool {
    true
}
pub(super) fn one() -> usize {
    1
}

impl Default for OutputDeck {
    fn default() -> Self {
        Self {
            every: 1,
            reactions: None,
            interval: None,
            displacements: Vec::new(),
            peak_stress: Vec::new(),
            iterations: false,
        }
    }
}

/// Parse a deck, naming the field path and line of the first error.
pub fn parse(text: &str) -> Result<Deck, String> {
    let deck = parse_fields(text)?;
    // serde reads a fixed-size array's first n entries and toml does not object to more:
    // compare every array with what the deck read back.
    if let (Ok(given), Ok(read)) = (text.parse::<toml::Table>(), toml::Value::try_from(&deck)) {
        extra_entries(&toml::Value::Table(given), &read, &mut String::new())?;
    }
    Ok(deck)
}

/// The first array in `given` longer than the same array as read (`read`), by path.
fn extra_entries(given: &toml::Value, read: &toml::Value, path: &mut String) -> Result<(), String> {
    use toml::Value as V;
    match (given, read) {
        (V::Table(g), V::Table(r)) => {
            for (k, gv) in g {
                if let Some(rv) = r.get(k) {
                    let len = path.len();
                    if !path.is_empty() {
                        path.push('.');
                    }
                    path.push_str(k);
                    extra_entries(gv, rv, path)?;
                    path.truncate(len);
                }
            }
        }
        (V::Array(g), V::Array(r)) => {
            if g.len() > r.len() {
                return Err(format!(
                    "{path}: expected {} entries, got {} ({})",
                    r.len(),
                    g.len(),
                    given
                ));
            }
            for (i, (gv, rv)) in g.iter().zip(r).enumerate() {
                let len = path.len();
                path.push_str(&format!("[{i}]"));
                extra_entries(gv, rv, path)?;
                path.truncate(len);
            }
        }
        _ => {}
    }
    Ok(())
}

/// The value at a serde path (`parts[0].mesh.cells[1]`), if there is one.
fn value_at<'a>(root: &'a toml::Value, path: &str) -> Option<&'a toml::Value> {
    let mut node = root;
    for part in path.split('.').filter(|p| !p.is_empty()) {
        let (key, idx) = match part.find('[') {
            Some(i) => (&part[..i], Some(&part[i..])),
            None => (part, None),
        };
        if !key.is_empty() {
            node = node.as_table()?.get(key)?;
        }
        for i in idx
            .into_iter()
            .flat_map(|s| s.split(['[', ']']))
            .filter(|s| !s.is_empty())
        {
            node = node.as_array()?.get(i.parse::<usize>().ok()?)?;
        }
    }
    Some(node)
}

/// The path to the one value under `path` that an error message quotes (an array of
/// the named length, the unknown variant, the offending number or string), if exactly
/// one matches.
fn deeper_path(root: &toml::Value, path: &str, msg: &str) -> Option<String> {
    use toml::Value as V;
    let node = value_at(root, path)?;
    if !node.is_table() {
        return None;
    }
    let quoted = |after: &str| -> Option<String> {
        let rest = &msg[msg.find(after)? + after.len()..];
        let rest = rest.trim_start();
        let (open, close) = match rest.chars().next()? {
            '`' => ('`', '`'),
            '"' => ('"', '"'),
            _ => return None,
        };
        let rest = &rest[open.len_utf8()..];
        Some(rest[..rest.find(close)?].to_string())
    };
    let matches: Box<dyn Fn(&V) -> bool> = if let Some(n) = msg
        .strip_prefix("invalid length ")
        .and_then(|r| r.split(',').next())
        .and_then(|n| n.trim().parse::<usize>().ok())
    {
        Box::new(move |v: &V| v.as_array().is_some_and(|a| a.len() == n))
    } else if let Some(name) = quoted("unknown variant") {
        Box::new(move |v: &V| v.as_str() == Some(name.as_str()))
    } else if let Some(i) = quoted("integer").and_then(|s| s.parse::<i64>().ok()) {
        Box::new(move |v: &V| v.as_integer() == Some(i))
    } else if let Some(x) = quoted("floating point").and_then(|s| s.parse::<f64>().ok()) {
        Box::new(move |v: &V| v.as_float() == Some(x))
    } else if let Some(t) = quoted("invalid type: string") {
        Box::new(move |v: &V| v.as_str() == Some(t.as_str()))
    } else {
        return None;
    };
    fn find(v: &V, here: &mut String, m: &dyn Fn(&V) -> bool, out: &mut Vec<String>) {
        if m(v) {
            out.push(here.clone());
        }
        match v {
            V::Table(t) => {
                for (k, x) in t {
                    let len = here.len();
                    here.push('.');
                    here.push_str(k);
                    find(x, here, m, out);
                    here.truncate(len);
                }
            }
            V::Array(a) => {
                for (i, x) in a.iter().enumerate() {
                    let len = here.len();
                    here.push_str(&format!("[{i}]"));
                    find(x, here, m, out);
                    here.truncate(len);
                }
            }
            _ => {}
        }
    }
    let mut out = Vec::new();
    find(node, &mut String::new(), &*matches, &mut out);
    match out.as_slice() {
        [one] if !one.is_empty() => Some(format!("{path}{one}")),
        _ => None,
    }
}

fn parse_fields(text: &str) -> Result<Deck, String> {
    // TOML allows a carriage return only before a newline; its parser then reports an
    // empty message.
    if let Some(i) = text
        .match_indices('\r')
        .map(|m| m.0)
        .find(|&i| !text[i + 1..].starts_with('\n'))
    {
        let line = text[..i].lines().count().max(1);
        return Err(format!(
            "a carriage return (\\r) that does not end a line (line {line}): save the deck with LF \
             or CRLF line endings"
        ));
    }
    let de = toml::Deserializer::new(text);
    serde_path_to_error::deserialize(de).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.into_inner();
        let line = inner
            .span()
            .map(|s| text[..s.start.min(text.len())].lines().count().max(1));
        let mut msg = inner.message().trim().replace('\n', " ");
        if msg.is_empty() {
            msg = "not valid TOML here".into();
        }
        let at = line.map(|l| format!(" (line {l})")).unwrap_or_default();
        let table = text.parse::<toml::Table>().ok().map(toml::Value::Table);
        // The toml crate hands a date-time to serde as a private map: say what it is.
        let is_datetime = table
            .as_ref()
            .and_then(|t| value_at(t, &path))
            .is_some_and(|v| v.is_datetime());
        if msg.contains("$__toml_private_datetime") {
            msg = "a date-time where a table is expected".into();
        } else if is_datetime && msg.starts_with("invalid type: map") {
            msg = msg.replacen("map", "date-time", 1);
        }
        // Inside an internally tagged table (`kind = ...`, `type = ...`) serde loses the
        // key: find the value the message names in that table.
        let path = match &table {
            Some(t) => deeper_path(t, &path, &msg).unwrap_or(path),
            None => path,
        };
        if path.is_empty() || path == "." {
            format!("{msg}{at}")
        } else {
            format!("{path}: {msg}{at}")
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const MIN: &str = r#"
[scene]
name = "t"
units = "mm-t-s"
[[materials]]
name = "m"
model = "neo-hookean"
E = 1.0
nu = 0.3
[[parts]]
name = "p"
material = "m"
mesh = { kind = "box", size = [1, 1, 1], cells = [1, 1, 1] }
[analysis]
type = "static"
end_time = 1.0
step = 0.5
"#;

    #[test]
    fn minimal_deck_parses_with_defaults() {
        let d = parse(MIN).unwrap();
        assert_eq!(d.solver.max_iterations, 25);
        assert_eq!(d.output.every, 1);
        match &d.parts[0].mesh {
            MeshDeck::Box {
                grading, element, ..
            } => {
                assert_eq!(*grading, [1.0; 3]);
                assert_eq!(*element, ElementDeck::Hex8);
            }
            _ => panic!("expected a box"),
        }
    }

    #[test]
    fn unknown_key_names_its_path() {
        let bad = MIN.replace("nu = 0.3", "nu = 0.3\nyoungs = 3");
        let e = parse(&bad).unwrap_err();
        assert!(e.contains("materials[0]") && e.contains("youngs"), "{e}");
    }

    #[test]
    fn missing_field_is_reported() {
        let bad = MIN.replace("type = \"static\"\n", "");
        let e = parse(&bad).unwrap_err();
        assert!(e.contains("analysis") && e.contains("type"), "{e}");
    }

    #[test]
    fn unknown_key_in_tagged_mesh_is_an_error() {
        let bad = MIN.replace("cells = [1, 1, 1]", "cells = [1, 1, 1], celz = 2");
        let e = parse(&bad).unwrap_err();
        assert!(e.contains("celz"), "{e}");
    }
}
