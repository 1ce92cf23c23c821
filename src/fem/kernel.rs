//! The element-kernel seam: one trait, [`ElementKernel`], through which every solid
//! formulation (standard, F-bar, reduced, EAS, hybrid) is evaluated, in the manner of
//! MFEM's nonlinear-form integrators. [`super::element::kernel`] picks the kernel for an
//! element kind and [`super::element::Formulation`]; `model/solids.rs` asks for it and
//! calls it, with no formulation-specific branch.
//!
//! A kernel sees one element: its reference coordinates, displacements, material and
//! history ([`ElementData`]), and writes its residual rows, tangent and new history
//! ([`ElementOutput`]). An element may own unknowns besides its nodes' displacements
//! (the hybrid element's pressure): [`ElementKernel::own_blocks`] blocks of three, whose
//! rows come after the nodes' rows, and whose values it reads from
//! [`ElementData::own`].
//!
//! To add an element (issue 35: tet10, wedge6, ...): its shape functions and quadrature
//! in `shape.rs`, a type implementing [`ElementKernel`] (the generic
//! [`super::solid::Standard`] serves any kind with a tabulated rule), and its arm in
//! [`super::element::kernel`].

use super::error::ElementError;
use crate::material::{Material, MaterialError, StressPoint};
use nalgebra::Matrix3;
use std::ops::Range;

/// What a kernel reads: one element's nodes, its own unknowns, material and committed
/// history.
#[derive(Clone, Copy)]
pub struct ElementData<'a> {
    /// Reference coordinates of the element's nodes.
    pub x0: &'a [[f64; 3]],
    /// Nodal displacements.
    pub u: &'a [[f64; 3]],
    /// The element's own unknowns, `3 * own_blocks()` values (empty for most kernels).
    pub own: &'a [f64],
    pub mat: &'a dyn Material,
    /// Committed history, [`ElementKernel::state_len`] values.
    pub state_old: &'a [f64],
    /// JFNK's frozen products: the trial history of the last natural evaluation at the
    /// Newton iterate (same layout as `state_old`). Each point then takes the branch it
    /// took there ([`Material::evaluate_on`]) and an EAS element starts its enhanced
    /// solve from the α found there.
    pub branch: Option<&'a [f64]>,
}

impl<'a> ElementData<'a> {
    /// An element without own unknowns.
    pub fn new(
        x0: &'a [[f64; 3]],
        u: &'a [[f64; 3]],
        mat: &'a dyn Material,
        state_old: &'a [f64],
    ) -> Self {
        Self {
            x0,
            u,
            own: &[],
            mat,
            state_old,
            branch: None,
        }
    }

    /// The same element with its own unknowns.
    pub fn with_own(self, own: &'a [f64]) -> Self {
        Self { own, ..self }
    }

    /// The same element on the branches of a natural evaluation's trial history.
    pub fn on_branch(self, branch: Option<&'a [f64]>) -> Self {
        Self { branch, ..self }
    }

    /// Stress and tangent at the point whose history is `at` (a range of `state_old`),
    /// on the frozen branch if there is one.
    pub(super) fn evaluate(
        &self,
        f: &Matrix3<f64>,
        at: Range<usize>,
        new: &mut [f64],
    ) -> Result<StressPoint, MaterialError> {
        let old = &self.state_old[at.clone()];
        match self.branch {
            Some(b) => self.mat.evaluate_on(f, old, &b[at], new),
            None => self.mat.evaluate(f, old, new),
        }
    }

    /// The stress alone at the point whose history is `at` (see [`Self::evaluate`]).
    pub(super) fn evaluate_stress(
        &self,
        f: &Matrix3<f64>,
        at: Range<usize>,
        new: &mut [f64],
    ) -> Result<[f64; 6], MaterialError> {
        let old = &self.state_old[at.clone()];
        match self.branch {
            Some(b) => self.mat.evaluate_stress_on(f, old, &b[at], new),
            None => self.mat.evaluate_stress(f, old, new),
        }
    }
}

/// What a force evaluation writes (overwritten, not accumulated).
pub struct ElementOutput<'a> {
    /// Trial history ([`ElementKernel::state_len`] values).
    pub state_new: &'a mut [f64],
    /// Residual rows, [`ElementKernel::n_dofs`] values, node-major (`f[3a+i]`), the own
    /// blocks' rows last.
    pub f: &'a mut [f64],
    /// If `Some`, the consistent tangent, n_dofs × n_dofs row-major.
    pub k: Option<&'a mut [f64]>,
}

impl<'a> ElementOutput<'a> {
    pub fn new(state_new: &'a mut [f64], f: &'a mut [f64], k: Option<&'a mut [f64]>) -> Self {
        Self { state_new, f, k }
    }
}

/// One element formulation on one element kind.
///
/// Finite kinematics: det F ≤ 0 at a point is an error. Small kinematics never checks
/// det F: a linear model is defined for any displacement, and Newton's first trial on a
/// linear problem may overshoot without meaning anything.
///
/// Slice lengths that do not match the kernel panic (a caller bug, not a model
/// condition).
pub trait ElementKernel: Send + Sync + std::fmt::Debug {
    /// Nodes of the element.
    fn n_nodes(&self) -> usize;
    /// Integration points (material history is stored per point).
    fn n_points(&self) -> usize;
    /// Blocks of three unknowns the element owns besides its nodes (the hybrid
    /// pressure).
    fn own_blocks(&self) -> usize {
        0
    }
    /// Residual rows: the nodes' and the own blocks'.
    fn n_dofs(&self) -> usize {
        3 * (self.n_nodes() + self.own_blocks())
    }
    /// History values of one element for a material with `n_state` per point.
    fn state_len(&self, n_state: usize) -> usize {
        self.n_points() * n_state
    }
    /// Internal force (residual rows) and, if `out.k`, the consistent tangent.
    fn force(&self, e: &ElementData, out: ElementOutput) -> Result<(), ElementError>;
    /// Volume-averaged Cauchy stress σ (Voigt) at the committed history.
    fn stress(&self, e: &ElementData) -> Result<[f64; 6], ElementError>;
    /// The displacement-only kernel with the own unknowns condensed (the hybrid element
    /// as F-bar, p = U'(J̄)); `None`: the kernel has none and is its own.
    fn condensed(&self) -> Option<&dyn ElementKernel> {
        None
    }
}

/// View a node slice as a fixed-size array; a length mismatch is a caller bug.
#[inline]
pub(super) fn nodes<const N: usize>(x: &[[f64; 3]]) -> &[[f64; 3]; N] {
    x.try_into()
        .unwrap_or_else(|_| panic!("element has {} nodes, kind needs {N}", x.len()))
}
