//! The resolved deck every section builder reads: the mesh and its parts, the named
//! node sets and surfaces, the time line with its curves, the analysis. Built once by
//! [`super::build::build`] from the deck's first sections, then handed to the walls,
//! entities, couplings, pairs, bolts, constraints and loads, so no section resolves a
//! name differently from another.

use super::check::{err, known};
use super::steps::Timeline;
use crate::curve::Curve;
use crate::mesh::select::nodes_of_faces;
use crate::mesh::{FaceRef, Mesh};
use crate::solve::AnalysisKind;
use crate::Result;
use std::collections::{BTreeMap, BTreeSet};

/// See the module documentation.
pub(super) struct Context<'a> {
    pub mesh: &'a Mesh,
    /// The mesh's boundary faces, sorted.
    pub boundary: &'a [FaceRef],
    pub part_names: &'a [String],
    /// The nodes of each part.
    pub part_nodes: &'a [BTreeSet<usize>],
    pub node_sets: &'a BTreeMap<String, Vec<usize>>,
    pub surfaces: &'a BTreeMap<String, Vec<FaceRef>>,
    pub timeline: &'a Timeline<'a>,
    pub analysis: AnalysisKind,
    pub end_time: f64,
    /// Geometric tolerance of contact set-up: 10⁻⁸ of the model's diagonal.
    pub tol: f64,
}

impl Context<'_> {
    /// The nodes a node set or a surface (its nodes) named at `field` stands for.
    pub fn set_nodes(&self, field: String, name: &str) -> Result<Vec<usize>> {
        if let Some(n) = self.node_sets.get(name) {
            return Ok(n.clone());
        }
        if let Some(fs) = self.surfaces.get(name) {
            return Ok(nodes_of_faces(self.mesh, fs));
        }
        Err(err(
            field,
            format!(
                "unknown node set `{name}` (node sets: {}; surfaces: {})",
                known(self.node_sets),
                known(self.surfaces)
            ),
        ))
    }

    /// The curve named at `field` for an entry without a step (walls' motions); none
    /// is a ramp 0 → 1 over the analysis.
    pub fn curve(&self, field: String, name: &Option<String>) -> Result<Curve> {
        match name {
            None => Ok(Curve::ramp(self.end_time)),
            Some(n) => self.timeline.named(&field, n),
        }
    }
}
