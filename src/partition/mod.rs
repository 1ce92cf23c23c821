//! Partitioning: METIS on the element coupling graph (the dual graph of shared faces,
//! plus the edges of contribution stencils; fixed seed, so the same mesh, couplings and
//! rank count always give the same partition), or slabs along an axis when the deck asks
//! (LS-DYNA's decomposition along a direction); ownership of nodes; and a cache of
//! partitions in `partitions/` keyed by a hash of the mesh and its couplings. It knows
//! the mesh and a list of element couplings, not what made them.

pub mod cache;

use crate::mesh::{ElemKind, Mesh};
use crate::{Error, Result};
use serde::{Deserialize, Serialize};

/// How elements are split over ranks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Method {
    /// METIS k-way on the coupling graph (fewest cut faces, balanced elements).
    #[default]
    Metis,
    /// Equal slabs of elements along an axis (0, 1, 2 = x, y, z) by element centroid:
    /// for steering where the cuts go (a model that must be split across a surface).
    Slabs { axis: usize },
}

impl Method {
    pub fn describe(self) -> String {
        match self {
            Method::Metis => "METIS k-way on the element dual graph, seed 0".into(),
            Method::Slabs { axis } => {
                format!("slabs along {} by element centroid", ["x", "y", "z"][axis])
            }
        }
    }
}

/// What a partition is computed from: the mesh, the element couplings beyond shared
/// faces, and the method.
#[derive(Debug, Clone, Copy)]
pub struct Request<'a> {
    pub mesh: &'a Mesh,
    pub edges: &'a [(usize, usize)],
    pub method: Method,
    /// Element → group that must stay on one rank ([`NO_GROUP`]: none; empty: no
    /// groups), see [`keep_groups_whole`].
    pub groups: &'a [u32],
}

/// An element in no group.
pub const NO_GROUP: u32 = u32::MAX;

impl Request<'_> {
    /// The partition over `ranks`.
    pub fn compute(&self, ranks: usize) -> Result<Vec<u32>> {
        let mut part = partition_elements(self.mesh, ranks, self.method, self.edges)?;
        keep_groups_whole(&mut part, self.groups);
        Ok(part)
    }

    /// The cache key: the mesh's hash, folded with the couplings and the method when
    /// they are not the defaults (so plain meshes keep their keys).
    pub fn key(&self) -> u64 {
        let mut h = self.mesh.hash();
        if self.edges.is_empty() && self.method == Method::Metis && self.groups.is_empty() {
            return h;
        }
        let mut eat = |x: u64| {
            for b in x.to_le_bytes() {
                h ^= b as u64;
                h = h.wrapping_mul(0x100000001b3);
            }
        };
        for &(a, b) in self.edges {
            eat(a as u64);
            eat(b as u64);
        }
        eat(match self.method {
            Method::Metis => u64::MAX,
            Method::Slabs { axis } => axis as u64,
        });
        for &g in self.groups {
            eat(g as u64);
        }
        h
    }
}

/// Move every group's elements to the rank that holds most of them (ties: the lowest),
/// so that a group evaluated as one unit (an F-bar patch) is on one rank. Idempotent;
/// the imbalance it adds is at most a group's size per cut group.
pub fn keep_groups_whole(part: &mut [u32], groups: &[u32]) {
    if groups.is_empty() {
        return;
    }
    let mut votes: std::collections::HashMap<u32, Vec<(u32, usize)>> = Default::default();
    for (&g, &p) in groups.iter().zip(part.iter()) {
        if g == NO_GROUP {
            continue;
        }
        let v = votes.entry(g).or_default();
        match v.iter_mut().find(|c| c.0 == p) {
            Some(c) => c.1 += 1,
            None => v.push((p, 1)),
        }
    }
    let winner: std::collections::HashMap<u32, u32> = votes
        .into_iter()
        .map(|(g, v)| {
            let best = v
                .iter()
                .max_by(|a, b| a.1.cmp(&b.1).then(b.0.cmp(&a.0)))
                .map_or(0, |c| c.0);
            (g, best)
        })
        .collect();
    for (p, g) in part.iter_mut().zip(groups) {
        if let Some(&w) = winner.get(g) {
            *p = w;
        }
    }
}

/// Element pairs coupled by node stencils (a contribution that evaluates nodes of
/// several elements together): each stencil's first node's element with each other
/// node's element (the first element holding a node stands for it).
pub fn stencil_edges(mesh: &Mesh, stencils: &[Vec<usize>]) -> Vec<(usize, usize)> {
    if stencils.is_empty() {
        return Vec::new();
    }
    let mut elem_of = vec![usize::MAX; mesh.n_nodes()];
    for e in (0..mesh.n_elems()).rev() {
        for &n in mesh.elem_nodes(e) {
            elem_of[n] = e;
        }
    }
    let mut edges: Vec<(usize, usize)> = Vec::new();
    for s in stencils {
        let Some(&first) = s.first() else { continue };
        let a = elem_of[first];
        for &n in &s[1..] {
            let b = elem_of[n];
            if a != b && a != usize::MAX && b != usize::MAX {
                edges.push((a.min(b), a.max(b)));
            }
        }
    }
    edges.sort_unstable();
    edges.dedup();
    edges
}

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

/// Element → rank: METIS k-way on the dual graph plus the coupling `edges` (seed 0),
/// or slabs along an axis.
pub fn partition_elements(
    mesh: &Mesh,
    nparts: usize,
    method: Method,
    edges: &[(usize, usize)],
) -> Result<Vec<u32>> {
    let ne = mesh.n_elems();
    if nparts <= 1 {
        return Ok(vec![0; ne]);
    }
    if ne < nparts {
        return Err(Error::input(format!(
            "cannot split {ne} elements over {nparts} ranks: use fewer ranks"
        )));
    }
    if let Method::Slabs { axis } = method {
        return Ok(slabs(mesh, nparts, axis));
    }
    let (xadj, adjncy) = with_edges(dual_graph(mesh)?, edges);
    let mut part = vec![0i32; ne];
    let g = metis::Graph::new(1, nparts as i32, &xadj, &adjncy)
        .map_err(|e| Error::runtime(format!("METIS graph: {e}")))?;
    g.set_option(metis::option::Seed(0))
        .part_kway(&mut part)
        .map_err(|e| Error::runtime(format!("METIS k-way partition: {e}")))?;
    Ok(part.into_iter().map(|p| p as u32).collect())
}

/// The CSR graph with the extra undirected `edges` added (none: unchanged).
fn with_edges(
    (xadj, adjncy): (Vec<i32>, Vec<i32>),
    edges: &[(usize, usize)],
) -> (Vec<i32>, Vec<i32>) {
    if edges.is_empty() {
        return (xadj, adjncy);
    }
    let n = xadj.len() - 1;
    let mut adj: Vec<Vec<i32>> = (0..n)
        .map(|e| adjncy[xadj[e] as usize..xadj[e + 1] as usize].to_vec())
        .collect();
    for &(a, b) in edges {
        adj[a].push(b as i32);
        adj[b].push(a as i32);
    }
    let mut x = vec![0i32];
    let mut out = Vec::new();
    for (e, mut l) in adj.into_iter().enumerate() {
        l.sort_unstable();
        l.dedup();
        l.retain(|&k| k as usize != e);
        out.extend(l);
        x.push(out.len() as i32);
    }
    (x, out)
}

/// Equal slabs of elements by centroid coordinate along `axis` (ties by element
/// number, so the split is deterministic).
fn slabs(mesh: &Mesh, nparts: usize, axis: usize) -> Vec<u32> {
    let ne = mesh.n_elems();
    let centroid = |e: usize| {
        let nodes = mesh.elem_nodes(e);
        nodes.iter().map(|&n| mesh.coords[n][axis]).sum::<f64>() / nodes.len() as f64
    };
    let mut order: Vec<(f64, usize)> = (0..ne).map(|e| (centroid(e), e)).collect();
    order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut part = vec![0u32; ne];
    for (k, &(_, e)) in order.iter().enumerate() {
        part[e] = (k * nparts / ne) as u32;
    }
    part
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

/// A node is owned by the lowest rank that has an element touching it (docs/src/design.md).
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
        let a = partition_elements(&m, 2, Method::Metis, &[]).unwrap();
        let b = partition_elements(&m, 2, Method::Metis, &[]).unwrap();
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
        assert!(partition_elements(&m, 2, Method::Metis, &[]).is_err());
    }

    /// Slabs across the bar's width put each cross-section on both ranks; coupling
    /// edges pull coupled elements onto one rank.
    #[test]
    fn slabs_and_coupling_edges() {
        let m = bar();
        let p = partition_elements(&m, 2, Method::Slabs { axis: 1 }, &[]).unwrap();
        let q = quality(&m, &p, 2).unwrap();
        assert_eq!(q.elements_per_rank, vec![32, 32]);
        for (e, &r) in p.iter().enumerate() {
            let y: f64 = m.elem_nodes(e).iter().map(|&n| m.coords[n][1]).sum::<f64>() / 8.0;
            assert_eq!(r, (y > 0.5) as u32);
        }
        // Without edges METIS cuts the bar in the middle: its two end elements are on
        // different ranks; strong coupling edges between the ends keep them together.
        let a = partition_elements(&m, 2, Method::Metis, &[]).unwrap();
        let (first, last) = (0, m.n_elems() - 1);
        assert_ne!(a[first], a[last]);
        let ends: Vec<Vec<usize>> = (0..4)
            .map(|k| vec![m.elem_nodes(k)[0], m.elem_nodes(m.n_elems() - 1 - k)[6]])
            .collect();
        let edges = stencil_edges(&m, &ends);
        assert!(!edges.is_empty());
        let b = partition_elements(&m, 2, Method::Metis, &edges).unwrap();
        assert_eq!(b[first], b[last], "coupled ends on one rank");
    }
}
