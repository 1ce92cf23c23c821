//! Split a [`ModelDef`] into per-rank [`LocalModel`]s (on rank 0) and send each rank its
//! piece. Nodes are renumbered rank by rank so that every rank owns one contiguous
//! range of global node numbers; elements likewise (DESIGN.md, "Distributed conventions").

use super::node_owner;
use crate::mesh::ElemKind;
use crate::model::def::{Constraint, Load, MaterialDef, ModelDef, Settings};
use crate::parallel::Comm;
use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// What one rank knows of the model.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct LocalModel {
    pub rank: usize,
    pub ranks: usize,
    /// Owned node count of every rank (gives the node [`crate::parallel::Layout`]).
    pub owned_nodes_per_rank: Vec<usize>,
    /// Element count of every rank (elements are numbered rank by rank too).
    pub elems_per_rank: Vec<usize>,
    /// Global numbers of the ghost nodes (touched by our elements, owned elsewhere), sorted.
    pub ghosts: Vec<usize>,
    /// Reference coordinates of local nodes: owned first, then ghosts.
    pub coords: Vec<[f64; 3]>,
    /// Node number in the user's mesh, for each owned node.
    pub orig_node: Vec<u64>,
    pub kinds: Vec<ElemKind>,
    pub offsets: Vec<usize>,
    /// Element connectivity in local node indices.
    pub conn: Vec<usize>,
    pub elem_material: Vec<u32>,
    /// Hex8 volume treatment of each local element.
    pub elem_formulation: Vec<crate::fem::element::Formulation>,
    /// Element number in the user's mesh, for each local element.
    pub orig_elem: Vec<u64>,
    /// Named node sets restricted to local nodes (owned and ghost), local indices.
    pub node_sets: BTreeMap<String, Vec<usize>>,
    /// Named surfaces restricted to local elements: (local element, face).
    pub surfaces: BTreeMap<String, Vec<(usize, u8)>>,
    pub materials: Vec<(String, MaterialDef)>,
    pub constraints: Vec<Constraint>,
    pub loads: Vec<Load>,
    pub reaction_sets: Vec<String>,
    /// Rigid walls with this rank's owned tracked nodes (local indices).
    pub walls: Vec<crate::contact::wall::WallDef>,
    pub settings: Settings,
    pub n_nodes_global: usize,
    pub n_elems_global: usize,
}

impl LocalModel {
    pub fn n_owned(&self) -> usize {
        self.owned_nodes_per_rank[self.rank]
    }
    pub fn n_local_nodes(&self) -> usize {
        self.coords.len()
    }
    pub fn n_elems(&self) -> usize {
        self.kinds.len()
    }
    pub fn elem_nodes(&self, e: usize) -> &[usize] {
        &self.conn[self.offsets[e]..self.offsets[e + 1]]
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
}

/// Build every rank's piece from the whole model and an element partition.
pub fn split(def: &ModelDef, part: &[u32], ranks: usize) -> Vec<LocalModel> {
    let mesh = &def.mesh;
    let owner = node_owner(mesh, part);
    let mut owned_nodes_per_rank = vec![0usize; ranks];
    for &o in &owner {
        owned_nodes_per_rank[o as usize] += 1;
    }
    let mut starts = vec![0usize; ranks];
    for r in 1..ranks {
        starts[r] = starts[r - 1] + owned_nodes_per_rank[r - 1];
    }
    // New global node numbers: rank by rank, in the user's order within a rank.
    let mut next = starts.clone();
    let new_id: Vec<usize> = owner
        .iter()
        .map(|&o| {
            let id = next[o as usize];
            next[o as usize] += 1;
            id
        })
        .collect();
    let mut elems_of: Vec<Vec<usize>> = vec![Vec::new(); ranks];
    for (e, &p) in part.iter().enumerate() {
        elems_of[p as usize].push(e);
    }
    let elems_per_rank: Vec<usize> = elems_of.iter().map(|v| v.len()).collect();

    let mut out = Vec::with_capacity(ranks);
    let mut local_of = vec![usize::MAX; mesh.n_nodes()];
    for r in 0..ranks {
        // Local nodes: owned (in new-number order) then ghosts (sorted by new number).
        let mut owned: Vec<usize> = Vec::with_capacity(owned_nodes_per_rank[r]);
        let mut ghosts: Vec<usize> = Vec::new();
        for &e in &elems_of[r] {
            for &n in mesh.elem_nodes(e) {
                if local_of[n] == usize::MAX {
                    local_of[n] = 0; // mark seen
                    if owner[n] as usize == r {
                        owned.push(n);
                    } else {
                        ghosts.push(n);
                    }
                }
            }
        }
        owned.sort_by_key(|&n| new_id[n]);
        ghosts.sort_by_key(|&n| new_id[n]);
        debug_assert_eq!(owned.len(), owned_nodes_per_rank[r]);
        for (i, &n) in owned.iter().chain(ghosts.iter()).enumerate() {
            local_of[n] = i;
        }
        let coords: Vec<[f64; 3]> = owned
            .iter()
            .chain(ghosts.iter())
            .map(|&n| mesh.coords[n])
            .collect();
        let mut kinds = Vec::with_capacity(elems_of[r].len());
        let mut offsets = vec![0usize];
        let mut conn = Vec::new();
        let mut elem_material = Vec::new();
        let mut elem_formulation = Vec::new();
        let mut local_elem = BTreeMap::new();
        for (le, &e) in elems_of[r].iter().enumerate() {
            kinds.push(mesh.kinds[e]);
            conn.extend(mesh.elem_nodes(e).iter().map(|&n| local_of[n]));
            offsets.push(conn.len());
            elem_material.push(def.elem_material(e) as u32);
            elem_formulation.push(def.elem_formulation(e));
            local_elem.insert(e, le);
        }
        let node_sets = def
            .node_sets
            .iter()
            .map(|(k, v)| {
                (
                    k.clone(),
                    v.iter()
                        .filter(|&&n| local_of[n] != usize::MAX)
                        .map(|&n| local_of[n])
                        .collect(),
                )
            })
            .collect();
        let surfaces = def
            .surfaces
            .iter()
            .map(|(k, v)| {
                (
                    k.clone(),
                    v.iter()
                        .filter_map(|f| local_elem.get(&f.elem).map(|&le| (le, f.face)))
                        .collect(),
                )
            })
            .collect();
        // Walls: each rank tracks the nodes it owns (contact forces act on the node only).
        let walls = def
            .walls
            .iter()
            .map(|w| {
                let mut lw = w.clone();
                lw.nodes.clear();
                lw.areas.clear();
                let mut mine: Vec<(usize, f64)> = w
                    .nodes
                    .iter()
                    .zip(&w.areas)
                    .filter(|(&n, _)| owner[n] as usize == r)
                    .map(|(&n, &a)| (local_of[n], a))
                    .collect();
                mine.sort_by_key(|p| p.0);
                for (n, a) in mine {
                    lw.nodes.push(n);
                    lw.areas.push(a);
                }
                lw
            })
            .collect();
        out.push(LocalModel {
            rank: r,
            ranks,
            owned_nodes_per_rank: owned_nodes_per_rank.clone(),
            elems_per_rank: elems_per_rank.clone(),
            ghosts: ghosts.iter().map(|&n| new_id[n]).collect(),
            coords,
            orig_node: owned.iter().map(|&n| n as u64).collect(),
            kinds,
            offsets,
            conn,
            elem_material,
            elem_formulation,
            orig_elem: elems_of[r].iter().map(|&e| e as u64).collect(),
            node_sets,
            surfaces,
            materials: def.materials.clone(),
            constraints: def.constraints.clone(),
            loads: def.loads.clone(),
            reaction_sets: def.reaction_sets.clone(),
            walls,
            settings: def.settings.clone(),
            n_nodes_global: mesh.n_nodes(),
            n_elems_global: mesh.n_elems(),
        });
        for &n in owned.iter().chain(ghosts.iter()) {
            local_of[n] = usize::MAX;
        }
    }
    out
}

/// Collective: rank 0 passes `Some(pieces)` (one per rank), every rank gets its own.
pub fn scatter(comm: &dyn Comm, pieces: Option<Vec<LocalModel>>) -> Result<LocalModel> {
    let p = comm.size();
    let (send, counts) = match pieces {
        Some(pieces) if comm.rank() == 0 => {
            let mut send = Vec::new();
            let mut counts = Vec::with_capacity(p);
            for piece in &pieces {
                let bytes = bincode::serialize(piece)
                    .map_err(|e| Error::runtime(format!("serialising a model piece: {e}")))?;
                counts.push(bytes.len());
                send.extend_from_slice(&bytes);
            }
            (send, counts)
        }
        _ => (Vec::new(), vec![0; p]),
    };
    let recv_counts = comm.alltoall_counts(&counts);
    let recv = comm.alltoallv_bytes(&send, &counts, &recv_counts);
    bincode::deserialize(&recv)
        .map_err(|e| Error::runtime(format!("receiving this rank's model piece: {e}")))
}
