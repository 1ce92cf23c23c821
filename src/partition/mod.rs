//! Partitioning: METIS on the element dual graph (fixed seed, so the same mesh and rank
//! count always give the same partition), a cache of partitions in `partitions/` keyed by
//! a hash of the mesh, and the split of a model into per-rank pieces ([`distribute`]).

pub mod cache;

use crate::mesh::{ElemKind, Mesh};
use crate::{Error, Result};

/// The element dual graph in CSR form: elements sharing a face are neighbours
/// (4 common nodes for an all-hex mesh, 3 as soon as there are tets).
pub fn dual_graph(mesh: &Mesh) -> Result<(Vec<i32>, Vec<i32>)> {
    let eptr: Vec<i32> = mesh.offsets.iter().map(|&o| o as i32).collect();
    let eind: Vec<i32> = mesh.conn.iter().map(|&n| n as i32).collect();
    let ncommon = if mesh.kinds.iter().all(|&k| k == ElemKind::Hex8) {
        4
    } else {
        3
    };
    let dual = metis::mesh_to_dual(&eptr, &eind, ncommon)
        .map_err(|e| Error::runtime(format!("METIS dual graph: {e}")))?;
    Ok((dual.xadj().to_vec(), dual.adjncy().to_vec()))
}

/// Element → rank, from METIS k-way on the dual graph with seed 0.
pub fn partition_elements(mesh: &Mesh, nparts: usize) -> Result<Vec<u32>> {
    let ne = mesh.n_elems();
    if nparts <= 1 {
        return Ok(vec![0; ne]);
    }
    if ne < nparts {
        return Err(Error::input(format!(
            "cannot split {ne} elements over {nparts} ranks: use fewer ranks"
        )));
    }
    let (xadj, adjncy) = dual_graph(mesh)?;
    let mut part = vec![0i32; ne];
    let g = metis::Graph::new(1, nparts as i32, &xadj, &adjncy)
        .map_err(|e| Error::runtime(format!("METIS graph: {e}")))?;
    g.set_option(metis::option::Seed(0))
        .part_kway(&mut part)
        .map_err(|e| Error::runtime(format!("METIS k-way partition: {e}")))?;
    Ok(part.into_iter().map(|p| p as u32).collect())
}

/// Partition quality as `alfe check --ranks N` prints it.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Quality {
    pub ranks: usize,
    /// Dual-graph edges (shared faces) whose two elements sit on different ranks.
    pub edge_cut: usize,
    pub elements_per_rank: Vec<usize>,
    pub owned_nodes_per_rank: Vec<usize>,
    pub ghost_nodes_per_rank: Vec<usize>,
    /// max / mean elements per rank.
    pub imbalance: f64,
}

pub fn quality(mesh: &Mesh, part: &[u32], nparts: usize) -> Result<Quality> {
    let mut elements_per_rank = vec![0; nparts];
    for &p in part {
        elements_per_rank[p as usize] += 1;
    }
    let edge_cut = if nparts > 1 {
        let (xadj, adjncy) = dual_graph(mesh)?;
        let mut cut = 0;
        for e in 0..mesh.n_elems() {
            for &n in &adjncy[xadj[e] as usize..xadj[e + 1] as usize] {
                if (n as usize) > e && part[n as usize] != part[e] {
                    cut += 1;
                }
            }
        }
        cut
    } else {
        0
    };
    let owner = node_owner(mesh, part);
    let mut owned_nodes_per_rank = vec![0; nparts];
    for &o in &owner {
        owned_nodes_per_rank[o as usize] += 1;
    }
    let mut ghost_nodes_per_rank = vec![0; nparts];
    let mut last_seen = vec![u32::MAX; mesh.n_nodes()];
    let mut order: Vec<usize> = (0..mesh.n_elems()).collect();
    order.sort_by_key(|&e| part[e]);
    for e in order {
        let r = part[e];
        for &n in mesh.elem_nodes(e) {
            if owner[n] != r && last_seen[n] != r {
                last_seen[n] = r;
                ghost_nodes_per_rank[r as usize] += 1;
            }
        }
    }
    let mean = mesh.n_elems() as f64 / nparts as f64;
    let imbalance = *elements_per_rank.iter().max().unwrap_or(&0) as f64 / mean.max(1e-300);
    Ok(Quality {
        ranks: nparts,
        edge_cut,
        elements_per_rank,
        owned_nodes_per_rank,
        ghost_nodes_per_rank,
        imbalance,
    })
}

/// A node is owned by the lowest rank that has an element touching it (DESIGN.md).
pub fn node_owner(mesh: &Mesh, part: &[u32]) -> Vec<u32> {
    let mut owner = vec![u32::MAX; mesh.n_nodes()];
    for (e, &p) in part.iter().enumerate() {
        for &n in mesh.elem_nodes(e) {
            owner[n] = owner[n].min(p);
        }
    }
    owner
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::{box_mesh, BoxSpec};

    fn bar() -> Mesh {
        box_mesh(
            &BoxSpec {
                origin: [0.0; 3],
                size: [8.0, 1.0, 1.0],
                cells: [16, 2, 2],
                grading: [1.0; 3],
                kind: ElemKind::Hex8,
            },
            0,
        )
    }

    #[test]
    fn metis_is_deterministic_and_balanced() {
        let m = bar();
        let a = partition_elements(&m, 2).unwrap();
        let b = partition_elements(&m, 2).unwrap();
        assert_eq!(a, b);
        let q = quality(&m, &a, 2).unwrap();
        assert!(q.imbalance < 1.1, "{q:?}");
        // A 16×2×2 bar split in two cuts one 2×2 cross-section: 4 faces.
        assert_eq!(q.edge_cut, 4, "{q:?}");
        assert_eq!(q.owned_nodes_per_rank.iter().sum::<usize>(), m.n_nodes());
    }

    #[test]
    fn too_many_ranks_is_an_input_error() {
        let m = box_mesh(
            &BoxSpec {
                origin: [0.0; 3],
                size: [1.0; 3],
                cells: [1, 1, 1],
                grading: [1.0; 3],
                kind: ElemKind::Hex8,
            },
            0,
        );
        assert!(partition_elements(&m, 2).is_err());
    }
}
