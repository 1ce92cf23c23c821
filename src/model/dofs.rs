//! The unknown map: every unknown of the distributed problem, numbered in triples
//! ("blocks", the 3×3 blocks of the matrix) in the PETSc convention: each rank owns one
//! contiguous range of global blocks,
//!
//! ```text
//!   [ owned nodes | owned extras of contribution 1 | of contribution 2 | ... ]
//! ```
//!
//! where a contribution's extras are its per-node or per-element unknowns (a wall's
//! multipliers, owned with their node; a hybrid element's pressure block, with its
//! element) followed, on the rank that owns them, by its global unknowns (a reference
//! point's or a rigid body's six DOFs: two blocks). A rank's *local* vectors
//! hold every block it evaluates with:
//!
//! ```text
//!   [ owned nodes | ghost nodes | owned extras | ghost extras ]
//! ```
//!
//! so a local node's index is its local block (element kernels index `3·node + c`),
//! ghost nodes are those of the rank's elements and of the contributions' stencils, and
//! ghost extras are the global unknowns of contributions this rank reads. One halo plan
//! refreshes all ghosts and sums ghost contributions on their owners (dolfinx's index
//! map with arbitrary ghosts, blocked by 3).

use crate::parallel::{Comm, HaloPlan, Layout};

/// The unknowns a contribution adds, declared before the map is built.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Unknowns {
    /// Blocks this rank owns for the contribution alone (per-node multipliers of its
    /// owned nodes).
    pub owned: usize,
    /// Global unknowns: `blocks` blocks owned by rank `owner`, the same on every rank.
    pub global: usize,
    pub owner: usize,
    /// This rank reads the global unknowns (they become ghosts here if owned elsewhere).
    pub reads_global: bool,
}

/// Where a contribution's unknowns are.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Placed {
    /// Local block of its first owned per-node block, and how many.
    pub owned_local: usize,
    pub owned: usize,
    /// Global block of its first global unknown (valid on every rank), and how many.
    pub global_first: usize,
    pub global: usize,
}

/// See the module documentation.
#[derive(Debug, Clone)]
pub struct DofMap {
    /// Block ownership: rank r owns global blocks `[starts[r], starts[r + 1])`.
    pub blocks: Layout,
    /// Scalar ownership (3 per block).
    pub dofs: Layout,
    /// Node ownership (global node numbers are rank-contiguous too).
    nodes: Layout,
    n_owned_nodes: usize,
    n_local_nodes: usize,
    n_owned_extra: usize,
    /// Global block of every local block.
    global: Vec<usize>,
    /// Ghost blocks sorted by global block, with their local block.
    ghost_sorted: Vec<(usize, usize)>,
    /// Ghost exchange of the scalar dofs of the ghost blocks (in `ghost_sorted` order).
    halo: HaloPlan,
    /// The ghosts in `ghost_sorted` order are the ghost nodes in local order (no ghost
    /// extras): the halo then reads and writes the local ghost-node slice directly.
    ghosts_are_nodes: bool,
    placed: Vec<Placed>,
}

impl DofMap {
    /// Collective. `owned_nodes_per_rank` and `ghost_nodes` (global node numbers, sorted)
    /// describe the nodes; `unknowns[c]` is contribution c's declaration (the same list,
    /// in the same order, on every rank).
    pub fn new(
        comm: &dyn Comm,
        owned_nodes_per_rank: &[usize],
        ghost_nodes: &[usize],
        unknowns: &[Unknowns],
    ) -> Self {
        let rank = comm.rank();
        let size = comm.size();
        let nodes = Layout::from_counts(owned_nodes_per_rank, rank);
        let n_owned_nodes = nodes.owned_len();
        let n_local_nodes = n_owned_nodes + ghost_nodes.len();
        // Owned extras, contribution by contribution: per-node blocks, then the global
        // ones where this rank owns them. `offsets[c]` is relative to the owned range.
        let mut offset = n_owned_nodes;
        let mut owned_at = Vec::with_capacity(unknowns.len());
        let mut global_at = vec![0u64; unknowns.len()];
        for (c, u) in unknowns.iter().enumerate() {
            owned_at.push(offset);
            offset += u.owned;
            if u.global > 0 && u.owner == rank {
                global_at[c] = offset as u64;
                offset += u.global;
            }
        }
        let blocks = Layout::gather(comm, offset);
        let dofs = Layout::from_counts(
            &(0..size)
                .map(|r| 3 * (blocks.starts[r + 1] - blocks.starts[r]))
                .collect::<Vec<_>>(),
            rank,
        );
        // Every rank learns where each contribution's global unknowns start.
        for (c, u) in unknowns.iter().enumerate() {
            if u.global > 0 && u.owner == rank {
                global_at[c] += blocks.start() as u64;
            }
        }
        if unknowns.iter().any(|u| u.global > 0) {
            comm.allreduce_sum_u64(&mut global_at);
        }
        let n_owned_extra = offset - n_owned_nodes;
        let node_block = |g: usize| -> usize {
            let q = nodes.owner(g);
            blocks.starts[q] + g - nodes.starts[q]
        };
        let mut global: Vec<usize> = (0..n_owned_nodes).map(|i| blocks.start() + i).collect();
        global.extend(ghost_nodes.iter().map(|&g| node_block(g)));
        global.extend((0..n_owned_extra).map(|k| blocks.start() + n_owned_nodes + k));
        // Ghost extras: global unknowns read here and owned elsewhere.
        let mut ghost_extra: Vec<usize> = Vec::new();
        let mut placed = Vec::with_capacity(unknowns.len());
        for (c, u) in unknowns.iter().enumerate() {
            let first = global_at[c] as usize;
            if u.global > 0 && u.owner != rank && u.reads_global {
                ghost_extra.extend(first..first + u.global);
            }
            placed.push(Placed {
                owned_local: n_local_nodes + owned_at[c] - n_owned_nodes,
                owned: u.owned,
                global_first: first,
                global: u.global,
            });
        }
        ghost_extra.sort_unstable();
        ghost_extra.dedup();
        global.extend(ghost_extra.iter().copied());
        let first_ghost_extra = n_local_nodes + n_owned_extra;
        let mut ghost_sorted: Vec<(usize, usize)> = (n_owned_nodes..n_local_nodes)
            .map(|l| (global[l], l))
            .chain(
                ghost_extra
                    .iter()
                    .enumerate()
                    .map(|(k, &g)| (g, first_ghost_extra + k)),
            )
            .collect();
        ghost_sorted.sort_unstable();
        let ghosts_are_nodes = ghost_extra.is_empty();
        let ghost_dofs: Vec<usize> = ghost_sorted
            .iter()
            .flat_map(|&(b, _)| (0..3).map(move |c| 3 * b + c))
            .collect();
        let halo = HaloPlan::new(comm, &dofs, ghost_dofs);
        Self {
            blocks,
            dofs,
            nodes,
            n_owned_nodes,
            n_local_nodes,
            n_owned_extra,
            global,
            ghost_sorted,
            halo,
            ghosts_are_nodes,
            placed,
        }
    }

    /// Unknowns owned here (scalar).
    pub fn n_owned_dofs(&self) -> usize {
        self.dofs.owned_len()
    }
    /// Owned node unknowns: the first `3 · n_owned_nodes` entries of an owned vector.
    pub fn n_node_dofs(&self) -> usize {
        3 * self.n_owned_nodes
    }
    pub fn n_owned_nodes(&self) -> usize {
        self.n_owned_nodes
    }
    pub fn n_local_nodes(&self) -> usize {
        self.n_local_nodes
    }
    /// Local blocks (nodes, owned and ghost extras).
    pub fn n_local_blocks(&self) -> usize {
        self.global.len()
    }
    /// Length of a local vector.
    pub fn n_local_dofs(&self) -> usize {
        3 * self.global.len()
    }
    /// The owned unknowns that are not node displacements (multipliers, hybrid
    /// pressures, global unknowns), as a range of an owned vector.
    pub fn extra_range(&self) -> std::ops::Range<usize> {
        self.n_node_dofs()..self.n_owned_dofs()
    }
    /// The global block of a local block.
    pub fn global_block(&self, local: usize) -> usize {
        self.global[local]
    }
    /// The global block of a global node number.
    pub fn node_block(&self, node: usize) -> usize {
        let q = self.nodes.owner(node);
        self.blocks.starts[q] + node - self.nodes.starts[q]
    }
    /// The local block of a global block, if this rank holds it.
    pub fn local_block(&self, global: usize) -> Option<usize> {
        if self.blocks.owns(global) {
            let k = global - self.blocks.start();
            return Some(if k < self.n_owned_nodes {
                k
            } else {
                self.n_local_nodes + k - self.n_owned_nodes
            });
        }
        self.ghost_sorted
            .binary_search_by_key(&global, |&(g, _)| g)
            .ok()
            .map(|i| self.ghost_sorted[i].1)
    }
    /// The owned-vector index of a local scalar unknown, if it is owned here.
    pub fn owned_index(&self, local_dof: usize) -> Option<usize> {
        let (b, c) = (local_dof / 3, local_dof % 3);
        if b < self.n_owned_nodes {
            Some(local_dof)
        } else if b >= self.n_local_nodes && b < self.n_local_nodes + self.n_owned_extra {
            Some(3 * (self.n_owned_nodes + b - self.n_local_nodes) + c)
        } else {
            None
        }
    }
    /// The global block of an owned-vector index (owned blocks are numbered
    /// contiguously: nodes, then extras).
    pub fn owned_global_block(&self, owned: usize) -> usize {
        self.blocks.start() + owned / 3
    }
    /// Where contribution `c`'s unknowns are.
    pub fn placed(&self, c: usize) -> Placed {
        self.placed[c]
    }
    /// The global blocks of every contribution's global unknowns (sorted; the same on
    /// every rank).
    pub fn global_blocks(&self) -> Vec<usize> {
        let mut g: Vec<usize> = self
            .placed
            .iter()
            .flat_map(|p| p.global_first..p.global_first + p.global)
            .collect();
        g.sort_unstable();
        g
    }
    /// Neighbour ranks of the ghost exchange (diagnostics).
    pub fn halo(&self) -> &HaloPlan {
        &self.halo
    }

    /// Collective: the local vector of an owned vector (ghosts refreshed from their
    /// owners).
    pub fn gather(&self, comm: &dyn Comm, owned: &[f64], local: &mut Vec<f64>) {
        let (nn, nl) = (3 * self.n_owned_nodes, 3 * self.n_local_nodes);
        local.resize(self.n_local_dofs(), 0.0);
        local[..nn].copy_from_slice(&owned[..nn]);
        let ne = 3 * self.n_owned_extra;
        local[nl..nl + ne].copy_from_slice(&owned[nn..nn + ne]);
        if self.ghosts_are_nodes {
            self.halo.forward(comm, owned, &mut local[nn..nl]);
        } else {
            let mut g = vec![0.0; 3 * self.ghost_sorted.len()];
            self.halo.forward(comm, owned, &mut g);
            for (k, &(_, l)) in self.ghost_sorted.iter().enumerate() {
                local[3 * l..3 * l + 3].copy_from_slice(&g[3 * k..3 * k + 3]);
            }
        }
    }

    /// Collective: the owned vector of a local one, ghost entries summed on their
    /// owners. `owned` is overwritten.
    pub fn sum_to_owned(&self, comm: &dyn Comm, local: &[f64], owned: &mut [f64]) {
        let (nn, nl) = (3 * self.n_owned_nodes, 3 * self.n_local_nodes);
        let ne = 3 * self.n_owned_extra;
        owned[..nn].copy_from_slice(&local[..nn]);
        owned[nn..nn + ne].copy_from_slice(&local[nl..nl + ne]);
        if self.ghosts_are_nodes {
            self.halo.reverse_add(comm, &local[nn..nl], owned);
        } else {
            let mut g = vec![0.0; 3 * self.ghost_sorted.len()];
            for (k, &(_, l)) in self.ghost_sorted.iter().enumerate() {
                g[3 * k..3 * k + 3].copy_from_slice(&local[3 * l..3 * l + 3]);
            }
            self.halo.reverse_add(comm, &g, owned);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parallel::run_ranks;

    /// Two ranks with 3 and 2 owned nodes; rank 0 ghosts node 3, rank 1 ghosts node 2;
    /// contribution 0 has one multiplier per rank, contribution 1 a two-block global
    /// unknown owned by rank 1 and read by both.
    #[test]
    fn numbering_gather_and_sum_on_two_ranks() {
        let out = run_ranks(2, |c| {
            let r = c.rank();
            let ghosts = if r == 0 { vec![3] } else { vec![2] };
            let unknowns = [
                Unknowns {
                    owned: 1,
                    ..Default::default()
                },
                Unknowns {
                    owned: 0,
                    global: 2,
                    owner: 1,
                    reads_global: true,
                },
            ];
            let m = DofMap::new(c, &[3, 2], &ghosts, &unknowns);
            // Rank 0 owns [n0 n1 n2 | m0] = blocks 0..4; rank 1 [n3 n4 | m1 | g g] = 4..9.
            assert_eq!(m.blocks.starts, vec![0, 4, 9]);
            assert_eq!(m.placed(1).global_first, 7);
            assert_eq!(m.node_block(3), 4);
            // An owned vector holding 10·global block + component.
            let owned: Vec<f64> = (m.dofs.start()..m.dofs.end())
                .map(|d| 10.0 * (d / 3) as f64 + (d % 3) as f64)
                .collect();
            let mut local = Vec::new();
            m.gather(c, &owned, &mut local);
            for l in 0..m.n_local_blocks() {
                let g = m.global_block(l);
                assert_eq!(local[3 * l], 10.0 * g as f64);
                assert_eq!(m.local_block(g), Some(l));
            }
            // Every local entry contributes 1: owners receive 1 + (number of ghost copies).
            let ones = vec![1.0; m.n_local_dofs()];
            let mut sum = vec![0.0; m.n_owned_dofs()];
            m.sum_to_owned(c, &ones, &mut sum);
            (r, m.global.clone(), sum)
        });
        assert_eq!(out[0].1, vec![0, 1, 2, 4, 3, 7, 8]);
        assert_eq!(out[1].1, vec![4, 5, 2, 6, 7, 8]);
        // Rank 0: n2 is ghosted by rank 1, and rank 0 reads the global unknowns.
        assert_eq!(
            out[0].2,
            vec![1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 2.0, 2.0, 2.0, 1.0, 1.0, 1.0]
        );
        assert_eq!(
            out[1].2,
            vec![2.0, 2.0, 2.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 2.0, 2.0, 2.0, 2.0, 2.0, 2.0]
        );
    }
}
