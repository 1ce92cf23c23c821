//! Split a [`ModelDef`] into per-rank [`LocalModel`]s (on rank 0, from an element
//! partition) and send each rank its piece. Nodes are renumbered rank by rank so that
//! every rank owns one contiguous range of global node numbers; elements likewise
//! (docs/src/design.md, "Distributed conventions"). A rank's ghost nodes are those of its
//! elements and of the contribution stencils it evaluates; each contribution
//! definition localizes itself ([`super::kind::ContributionKind::localize`]).

use super::def::{Constraint, ContributionDef, MaterialDef, ModelDef};
use super::kind::Localizer;
pub use super::local::{LocalElements, LocalMesh};
use crate::parallel::Comm;
use crate::partition::node_owner;
use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// What one rank knows of the model.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct LocalModel {
    pub mesh: LocalMesh,
    pub elements: LocalElements,
    pub materials: Vec<(String, MaterialDef)>,
    pub constraints: Vec<Constraint>,
    pub reaction_sets: Vec<String>,
    pub displacement_sets: Vec<String>,
    /// Parts whose largest von Mises stress is a history column: (name, part index).
    #[serde(default)]
    pub peak_stress_parts: Vec<(String, u32)>,
    /// The parts' names, in deck order (the output's blocks).
    #[serde(default)]
    pub part_names: Vec<String>,
    pub initial_velocity: Vec<(String, [f64; 3])>,
    /// Every contribution definition, localized to this rank (the same list, in the same
    /// order, on every rank).
    pub contributions: Vec<ContributionDef>,
}

/// Build every rank's piece from the whole model and an element partition.
pub fn split(def: &ModelDef, part: &[u32], ranks: usize) -> Vec<LocalModel> {
    let mesh = &def.mesh;
    // A partition read from a file or computed without the patches keeps them whole too.
    let part = &whole_patches(part, &def.elem_patch)[..];
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
    // Stencils evaluated on each rank (on the owner of their first node).
    let mut stencil_nodes: Vec<Vec<usize>> = vec![Vec::new(); ranks];
    for c in &def.contributions {
        for s in c.kind().stencils() {
            if let Some(&first) = s.first() {
                stencil_nodes[owner[first] as usize].extend(s);
            }
        }
    }

    let mut out = Vec::with_capacity(ranks);
    let mut local_of = vec![usize::MAX; mesh.n_nodes()];
    for r in 0..ranks {
        // Local nodes: owned (in new-number order) then ghosts (sorted by new number).
        let mut owned: Vec<usize> = Vec::with_capacity(owned_nodes_per_rank[r]);
        let mut ghosts: Vec<usize> = Vec::new();
        let elem_nodes = elems_of[r].iter().flat_map(|&e| mesh.elem_nodes(e));
        for &n in elem_nodes.chain(&stencil_nodes[r]) {
            if local_of[n] == usize::MAX {
                local_of[n] = 0; // mark seen
                if owner[n] as usize == r {
                    owned.push(n);
                } else {
                    ghosts.push(n);
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
        let mut elements = LocalElements {
            offsets: vec![0],
            ..Default::default()
        };
        let mut local_elem = BTreeMap::new();
        for (le, &e) in elems_of[r].iter().enumerate() {
            elements.kinds.push(mesh.kinds[e]);
            elements
                .conn
                .extend(mesh.elem_nodes(e).iter().map(|&n| local_of[n]));
            elements.offsets.push(elements.conn.len());
            elements.material.push(def.elem_material(e) as u32);
            elements.formulation.push(def.elem_formulation(e));
            elements.orig.push(e as u64);
            elements.part.push(mesh.elem_part[e]);
            local_elem.insert(e, le);
        }
        elements.patch = local_patches(&def.elem_patch, &elems_of[r]);
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
        let loc = Localizer {
            rank: r,
            ranks,
            owner: &owner,
            local_of: &local_of,
        };
        let contributions = def.contributions.iter().map(|c| c.localize(&loc)).collect();
        out.push(LocalModel {
            mesh: LocalMesh {
                rank: r,
                ranks,
                owned_nodes_per_rank: owned_nodes_per_rank.clone(),
                elems_per_rank: elems_per_rank.clone(),
                ghosts: ghosts.iter().map(|&n| new_id[n]).collect(),
                coords,
                orig_node: owned.iter().map(|&n| n as u64).collect(),
                node_sets,
                surfaces,
                n_nodes_global: mesh.n_nodes(),
                n_elems_global: mesh.n_elems(),
            },
            elements,
            materials: def.materials.clone(),
            constraints: def.constraints.clone(),
            reaction_sets: def.reaction_sets.clone(),
            displacement_sets: def.displacement_sets.clone(),
            peak_stress_parts: def.peak_stress_parts.clone(),
            part_names: def.part_names.clone(),
            initial_velocity: def.initial_velocity.clone(),
            contributions,
        });
        for &n in owned.iter().chain(ghosts.iter()) {
            local_of[n] = usize::MAX;
        }
    }
    out
}

/// The partition with every F-bar patch on one rank.
fn whole_patches(part: &[u32], elem_patch: &[u32]) -> Vec<u32> {
    let mut part = part.to_vec();
    crate::partition::keep_groups_whole(&mut part, elem_patch);
    part
}

/// The patches of a rank's elements, numbered densely in element order (`u32::MAX`:
/// none; empty: the model has no patches).
fn local_patches(elem_patch: &[u32], elems: &[usize]) -> Vec<u32> {
    if elem_patch.is_empty() {
        return Vec::new();
    }
    let mut local: BTreeMap<u32, u32> = BTreeMap::new();
    elems
        .iter()
        .map(|&e| match elem_patch[e] {
            u32::MAX => u32::MAX,
            g => {
                let next = local.len() as u32;
                *local.entry(g).or_insert(next)
            }
        })
        .collect()
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
