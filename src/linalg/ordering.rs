//! Fill-reducing orderings for the sparse factorizations of block Jacobi.
//!
//! [`nested_dissection`] orders the *node* graph (one vertex per 3×3 block row) with
//! METIS nested dissection (`METIS_NodeND`) and [`expand_to_dofs`] turns a node
//! permutation into a scalar one keeping each node's three dofs consecutive. Ordering the
//! node graph is 3× smaller and 9× sparser than the scalar graph and keeps the dofs of a
//! node together (supernodes), as PETSc/MUMPS do for 3D finite-element matrices, on which
//! nested dissection gives much less fill than minimum degree.

use crate::Error;
use metis_sys as m;

/// A graph in compressed adjacency form: the neighbours of vertex `v` are
/// `adj[xadj[v]..xadj[v + 1]]`. Symmetric, without self loops.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Graph {
    pub xadj: Vec<usize>,
    pub adj: Vec<usize>,
}

impl Graph {
    /// The symmetrized pattern graph of `n` vertices given by rows: row `v` lists
    /// `cols[ptr[v]..ptr[v + 1]]` (any order, duplicates and the diagonal allowed).
    /// Edges are added in both directions, self loops dropped, duplicates removed.
    pub fn symmetrized(n: usize, ptr: &[usize], cols: &[usize]) -> Self {
        let mut deg = vec![0usize; n + 1];
        for v in 0..n {
            for &w in &cols[ptr[v]..ptr[v + 1]] {
                if w != v {
                    deg[v + 1] += 1;
                    deg[w + 1] += 1;
                }
            }
        }
        for v in 0..n {
            deg[v + 1] += deg[v];
        }
        let mut next = deg[..n].to_vec();
        let mut adj = vec![0usize; deg[n]];
        for v in 0..n {
            for &w in &cols[ptr[v]..ptr[v + 1]] {
                if w != v {
                    adj[next[v]] = w;
                    next[v] += 1;
                    adj[next[w]] = v;
                    next[w] += 1;
                }
            }
        }
        // Sort and deduplicate each list, compacting in place.
        let mut xadj = vec![0usize; n + 1];
        let mut out = 0;
        for v in 0..n {
            let (b, e) = (deg[v], deg[v + 1]);
            adj[b..e].sort_unstable();
            let mut last = usize::MAX;
            for p in b..e {
                let w = adj[p];
                if w != last {
                    adj[out] = w;
                    out += 1;
                    last = w;
                }
            }
            xadj[v + 1] = out;
        }
        adj.truncate(out);
        Self { xadj, adj }
    }

    pub fn n(&self) -> usize {
        self.xadj.len() - 1
    }

    /// The graph of distance ≤ 2 (the pattern of A² for A with this pattern and a full
    /// diagonal): the graph whose elimination fills like AᵀA's.
    pub fn squared(&self) -> Self {
        let n = self.n();
        let mut ptr = vec![0usize; n + 1];
        let mut cols = Vec::new();
        let mut mark = vec![usize::MAX; n];
        for v in 0..n {
            mark[v] = v;
            for &w in &self.adj[self.xadj[v]..self.xadj[v + 1]] {
                for &u in std::iter::once(&w).chain(&self.adj[self.xadj[w]..self.xadj[w + 1]]) {
                    if mark[u] != v {
                        mark[u] = v;
                        cols.push(u);
                    }
                }
            }
            ptr[v + 1] = cols.len();
        }
        Self::symmetrized(n, &ptr, &cols)
    }
}

/// METIS nested dissection of `g`: returns `perm` with `perm[new] = old` (the vertex
/// eliminated `new`-th), a valid permutation of `0..g.n()`.
pub fn nested_dissection(g: &Graph) -> crate::Result<Vec<usize>> {
    let n = g.n();
    if n <= 2 {
        return Ok((0..n).collect());
    }
    let to_idx = |v: usize| {
        m::idx_t::try_from(v).map_err(|_| {
            Error::runtime(format!(
                "nested dissection: graph too large for 32-bit METIS ({n} vertices, {} edges)",
                g.adj.len()
            ))
        })
    };
    let mut xadj = g
        .xadj
        .iter()
        .map(|&v| to_idx(v))
        .collect::<crate::Result<Vec<_>>>()?;
    let mut adjncy = g
        .adj
        .iter()
        .map(|&v| to_idx(v))
        .collect::<crate::Result<Vec<_>>>()?;
    let mut nvtxs = to_idx(n)?;
    let mut options = [0 as m::idx_t; m::METIS_NOPTIONS as usize];
    let mut perm = vec![0 as m::idx_t; n];
    let mut iperm = vec![0 as m::idx_t; n];
    // One METIS call at a time in a process: MPI ranks are processes and never share
    // it, but thread ranks (tests) do, and concurrent calls made results differ from
    // run to run (`rigid_body_modes_lie_in_the_coarse_space` failed 1 in 6 under the
    // parallel test runner, never alone).
    static METIS: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _one = METIS.lock().unwrap_or_else(|e| e.into_inner());
    // SAFETY: the arrays have the lengths METIS expects (xadj n+1, adjncy xadj[n],
    // options METIS_NOPTIONS, perm/iperm n) and outlive the calls; METIS only reads the
    // graph (it works on internal copies) and writes perm/iperm.
    let status = unsafe {
        m::METIS_SetDefaultOptions(options.as_mut_ptr());
        m::METIS_NodeND(
            &mut nvtxs,
            xadj.as_mut_ptr(),
            adjncy.as_mut_ptr(),
            std::ptr::null_mut(),
            options.as_mut_ptr(),
            perm.as_mut_ptr(),
            iperm.as_mut_ptr(),
        )
    };
    if status != m::rstatus_et_METIS_OK {
        return Err(Error::runtime(format!(
            "nested dissection: METIS_NodeND failed (status {status}) on a graph of {n} \
             vertices"
        )));
    }
    let perm: Vec<usize> = perm.into_iter().map(|p| p as usize).collect();
    if !is_permutation(&perm) {
        return Err(Error::runtime(
            "nested dissection: METIS_NodeND returned an invalid permutation",
        ));
    }
    Ok(perm)
}

/// Whether `perm` is a permutation of `0..perm.len()`.
pub fn is_permutation(perm: &[usize]) -> bool {
    let mut seen = vec![false; perm.len()];
    perm.iter()
        .all(|&p| p < seen.len() && !std::mem::replace(&mut seen[p], true))
}

/// The inverse permutation: `inv[perm[k]] = k`.
pub fn inverse(perm: &[usize]) -> Vec<usize> {
    let mut inv = vec![0; perm.len()];
    for (k, &p) in perm.iter().enumerate() {
        inv[p] = k;
    }
    inv
}

/// Expand a node permutation to `dofs` dofs per node: node `perm[k]`'s dofs
/// `dofs·perm[k] + c` become positions `dofs·k + c`.
pub fn expand_to_dofs(perm: &[usize], dofs: usize) -> Vec<usize> {
    perm.iter()
        .flat_map(|&p| (0..dofs).map(move |c| dofs * p + c))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The squared graph joins vertices two edges apart: a path 0-1-2-3 gains 0-2, 1-3.
    #[test]
    fn squared_graph_joins_vertices_at_distance_two() {
        let path = Graph::symmetrized(4, &[0, 1, 2, 3, 3], &[1, 2, 3]);
        let sq = path.squared();
        let nbrs = |v: usize| sq.adj[sq.xadj[v]..sq.xadj[v + 1]].to_vec();
        assert_eq!(nbrs(0), vec![1, 2]);
        assert_eq!(nbrs(1), vec![0, 2, 3]);
        assert_eq!(nbrs(2), vec![0, 1, 3]);
        assert_eq!(nbrs(3), vec![1, 2]);
    }

    /// 5-point Laplacian graph of an `nx × ny` grid.
    fn grid(nx: usize, ny: usize) -> Graph {
        let mut ptr = vec![0];
        let mut cols = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let v = i + nx * j;
                cols.push(v);
                if i + 1 < nx {
                    cols.push(v + 1);
                }
                if j + 1 < ny {
                    cols.push(v + nx);
                }
                ptr.push(cols.len());
            }
        }
        Graph::symmetrized(nx * ny, &ptr, &cols)
    }

    #[test]
    fn symmetrized_graph_has_both_directions_no_loops_no_duplicates() {
        // Row 0: {0, 1, 1, 2}; row 1: {}; row 2: {0}.
        let g = Graph::symmetrized(3, &[0, 4, 4, 5], &[0, 1, 1, 2, 0]);
        assert_eq!(g.xadj, vec![0, 2, 3, 4]);
        assert_eq!(g.adj, vec![1, 2, 0, 0]);
        let g = grid(4, 3);
        assert_eq!(g.adj.len(), 2 * (3 * 3 + 4 * 2));
    }

    /// Nonzeros of the Cholesky factor of a matrix with pattern `g` eliminated in the
    /// order `perm` (row counts by the elimination tree, Liu's algorithm, simple form).
    fn factor_nnz(g: &Graph, perm: &[usize]) -> usize {
        let n = g.n();
        let inv = inverse(perm);
        let mut parent = vec![usize::MAX; n];
        let mut mark = vec![usize::MAX; n];
        let mut nnz = n;
        for k in 0..n {
            mark[k] = k;
            let v = perm[k];
            for &w in &g.adj[g.xadj[v]..g.xadj[v + 1]] {
                let mut i = inv[w];
                // Walk up the elimination tree from i to k, counting row k's entries.
                while i < k && mark[i] != k {
                    if parent[i] == usize::MAX {
                        parent[i] = k;
                    }
                    mark[i] = k;
                    nnz += 1;
                    i = parent[i];
                }
            }
        }
        nnz
    }

    #[test]
    fn nested_dissection_is_a_permutation_with_less_fill_than_natural() {
        for (nx, ny) in [(1, 1), (2, 1), (3, 1), (7, 5), (60, 60)] {
            let g = grid(nx, ny);
            let p = nested_dissection(&g).unwrap();
            assert_eq!(p.len(), nx * ny);
            assert!(is_permutation(&p), "{nx}×{ny}");
            let inv = inverse(&p);
            assert!((0..p.len()).all(|k| p[inv[k]] == k));
        }
        // 60×60 grid: natural (banded) order fills ~n·60; nested dissection O(n log n).
        let g = grid(60, 60);
        let natural: Vec<usize> = (0..3600).collect();
        let nd = nested_dissection(&g).unwrap();
        let (f_nat, f_nd) = (factor_nnz(&g, &natural), factor_nnz(&g, &nd));
        assert!(f_nat > 3600 * 55, "{f_nat}");
        assert!(
            2 * f_nd < f_nat,
            "nested dissection {f_nd}, natural {f_nat}"
        );
    }

    #[test]
    fn expand_keeps_dofs_of_a_node_together() {
        assert_eq!(
            expand_to_dofs(&[2, 0, 1], 3),
            vec![6, 7, 8, 0, 1, 2, 3, 4, 5]
        );
        assert!(!is_permutation(&[0, 2, 2]));
        assert!(!is_permutation(&[0, 3]));
        assert!(is_permutation(&[]));
    }
}
