//! Quadratic meshes from linear ones: a tet4 mesh with a node at the middle of every
//! edge becomes a tet10 mesh (Gmsh's `SetOrder 2` on straight edges).

use super::{ElemKind, Mesh, TET10_EDGES};
use std::collections::{BTreeMap, BTreeSet};

/// `m` with every tet4 turned into a tet10: one new node at the midpoint of each edge,
/// shared by the elements around it, numbered after the existing nodes in order of first
/// use. Hex8 elements are kept. Faces keep their numbers (a tet10's faces are its tet4's
/// plus midside nodes); a midside node joins every node group holding both its edge's
/// ends, so a group of the nodes on a flat side gets the midside nodes on that side.
pub fn tet4_to_tet10(m: &Mesh) -> Mesh {
    let mut coords = m.coords.clone();
    let mut mid: BTreeMap<(usize, usize), usize> = BTreeMap::new();
    let (mut kinds, mut offsets, mut conn) = (Vec::new(), vec![0], Vec::new());
    for e in 0..m.n_elems() {
        let c = m.elem_nodes(e);
        conn.extend_from_slice(c);
        if m.kinds[e] == ElemKind::Tet4 {
            for [i, j] in TET10_EDGES {
                let key = (c[i].min(c[j]), c[i].max(c[j]));
                let id = *mid.entry(key).or_insert_with(|| {
                    let (a, b) = (coords[key.0], coords[key.1]);
                    coords.push(std::array::from_fn(|k| 0.5 * (a[k] + b[k])));
                    coords.len() - 1
                });
                conn.push(id);
            }
            kinds.push(ElemKind::Tet10);
        } else {
            kinds.push(m.kinds[e]);
        }
        offsets.push(conn.len());
    }
    let node_groups = m
        .node_groups
        .iter()
        .map(|(name, nodes)| {
            let inside: BTreeSet<usize> = nodes.iter().copied().collect();
            let mut out = nodes.clone();
            out.extend(
                mid.iter()
                    .filter(|((a, b), _)| inside.contains(a) && inside.contains(b))
                    .map(|(_, &n)| n),
            );
            (name.clone(), out)
        })
        .collect();
    Mesh {
        coords,
        kinds,
        offsets,
        conn,
        elem_part: m.elem_part.clone(),
        node_groups,
        face_groups: m.face_groups.clone(),
        elem_groups: m.elem_groups.clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::measure::element_volume;
    use crate::mesh::generate::{box_mesh, BoxSpec};

    /// A 2×1×1 tet4 box as tet10: the node count is corners + edges, volumes are kept,
    /// shared edges get one node, and the `xmax` group gains exactly its face's midside
    /// nodes (all at x = size).
    #[test]
    fn tet10_box_keeps_volume_groups_and_faces() {
        let spec = BoxSpec {
            origin: [0.0; 3],
            size: [2.0, 1.0, 1.0],
            cells: [2, 1, 1],
            grading: [1.0; 3],
            kind: ElemKind::Tet4,
        };
        let m4 = box_mesh(&spec, 0);
        let m = tet4_to_tet10(&m4);
        let mut edges = BTreeSet::new();
        for e in 0..m4.n_elems() {
            let c = m4.elem_nodes(e);
            for [i, j] in TET10_EDGES {
                edges.insert((c[i].min(c[j]), c[i].max(c[j])));
            }
        }
        assert_eq!(m.n_nodes(), m4.n_nodes() + edges.len());
        let vol = |m: &Mesh| -> f64 {
            (0..m.n_elems())
                .map(|e| {
                    let x: Vec<_> = m.elem_nodes(e).iter().map(|&n| m.coords[n]).collect();
                    element_volume(m.kinds[e], &x)
                })
                .sum()
        };
        assert!((vol(&m) - 2.0).abs() < 1e-12 && (vol(&m4) - 2.0).abs() < 1e-12);
        let xmax = &m.node_groups["xmax"];
        assert!(xmax.iter().all(|&n| (m.coords[n][0] - 2.0).abs() < 1e-12));
        let on_face = (0..m.n_nodes())
            .filter(|&n| (m.coords[n][0] - 2.0).abs() < 1e-12)
            .count();
        assert_eq!(xmax.len(), on_face);
        for f in &m.face_groups["xmax"] {
            let nodes = m.face_nodes(*f);
            assert_eq!(nodes.len(), 6);
            assert!(nodes.iter().all(|n| xmax.contains(n)));
        }
    }
}
