//! What one rank holds of the mesh: its nodes (owned, then ghosts), its node sets and
//! surfaces, and its elements, in local indices. Contributions are built from these.

use crate::fem::element::Formulation;
use crate::mesh::ElemKind;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// What one rank knows of the mesh: its nodes (owned, then ghosts) and sets.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct LocalMesh {
    pub rank: usize,
    pub ranks: usize,
    /// Owned node count of every rank (gives the node [`crate::parallel::Layout`]).
    pub owned_nodes_per_rank: Vec<usize>,
    /// Element count of every rank (elements are numbered rank by rank too).
    pub elems_per_rank: Vec<usize>,
    /// Global numbers of the ghost nodes (owned elsewhere, touched by this rank's
    /// elements or stencils), sorted.
    pub ghosts: Vec<usize>,
    /// Reference coordinates of local nodes: owned first, then ghosts.
    pub coords: Vec<[f64; 3]>,
    /// Node number in the user's mesh, for each owned node.
    pub orig_node: Vec<u64>,
    /// Named node sets restricted to local nodes (owned and ghost), local indices.
    pub node_sets: BTreeMap<String, Vec<usize>>,
    /// Named surfaces restricted to local elements: (local element, face).
    pub surfaces: BTreeMap<String, Vec<(usize, u8)>>,
    pub n_nodes_global: usize,
    pub n_elems_global: usize,
}

impl LocalMesh {
    pub fn n_owned(&self) -> usize {
        self.owned_nodes_per_rank[self.rank]
    }
    pub fn n_local_nodes(&self) -> usize {
        self.coords.len()
    }
    pub fn node_start(&self) -> usize {
        self.owned_nodes_per_rank[..self.rank].iter().sum()
    }
    pub fn elem_start(&self) -> usize {
        self.elems_per_rank[..self.rank].iter().sum()
    }
    /// Global node number of a local node.
    pub fn global_node(&self, local: usize) -> usize {
        if local < self.n_owned() {
            self.node_start() + local
        } else {
            self.ghosts[local - self.n_owned()]
        }
    }
    /// The local nodes of a node set (empty if the set has none here).
    pub fn set(&self, name: &str) -> &[usize] {
        self.node_sets
            .get(name)
            .map(|v| v.as_slice())
            .unwrap_or(&[])
    }
}

/// This rank's elements (local node indices).
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct LocalElements {
    pub kinds: Vec<ElemKind>,
    /// Element e's nodes are `conn[offsets[e]..offsets[e + 1]]`.
    pub offsets: Vec<usize>,
    pub conn: Vec<usize>,
    /// Material index and hex8 volume treatment of each element.
    pub material: Vec<u32>,
    pub formulation: Vec<Formulation>,
    /// Element number in the user's mesh.
    pub orig: Vec<u64>,
    /// Part index (deck order) of each element.
    #[serde(default)]
    pub part: Vec<u32>,
    /// The F-bar patch of each element, numbered densely on this rank (`u32::MAX`:
    /// none; empty: no patches). A patch's elements are all on one rank.
    #[serde(default)]
    pub patch: Vec<u32>,
}

impl LocalElements {
    pub fn len(&self) -> usize {
        self.kinds.len()
    }
    pub fn is_empty(&self) -> bool {
        self.kinds.is_empty()
    }
    pub fn nodes(&self, e: usize) -> &[usize] {
        &self.conn[self.offsets[e]..self.offsets[e + 1]]
    }
    /// The local nodes of face `face` of element `e`, outward normal by the right hand.
    pub fn face_nodes(&self, e: usize, face: u8) -> Vec<usize> {
        let en = self.nodes(e);
        self.kinds[e].faces()[face as usize]
            .iter()
            .map(|&i| en[i])
            .collect()
    }
}
