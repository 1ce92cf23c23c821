//! Geometric selection of nodes and faces, for boundary conditions given as boxes.

use super::{FaceRef, Mesh};

fn inside(x: &[f64; 3], min: &[f64; 3], max: &[f64; 3], tol: f64) -> bool {
    (0..3).all(|k| x[k] >= min[k] - tol && x[k] <= max[k] + tol)
}

/// Nodes with every coordinate in [min - tol, max + tol].
pub fn nodes_in_box(mesh: &Mesh, min: [f64; 3], max: [f64; 3], tol: f64) -> Vec<usize> {
    (0..mesh.n_nodes())
        .filter(|&n| inside(&mesh.coords[n], &min, &max, tol))
        .collect()
}

/// Of the given faces, those whose nodes all lie in the box.
pub fn faces_in_box(
    mesh: &Mesh,
    faces: &[FaceRef],
    min: [f64; 3],
    max: [f64; 3],
    tol: f64,
) -> Vec<FaceRef> {
    faces
        .iter()
        .copied()
        .filter(|&f| {
            mesh.face_nodes(f)
                .iter()
                .all(|&n| inside(&mesh.coords[n], &min, &max, tol))
        })
        .collect()
}

/// Sorted unique nodes of a list of faces.
pub fn nodes_of_faces(mesh: &Mesh, faces: &[FaceRef]) -> Vec<usize> {
    let mut out: Vec<usize> = faces.iter().flat_map(|&f| mesh.face_nodes(f)).collect();
    out.sort_unstable();
    out.dedup();
    out
}

/// Area of a flat boundary face from its corners (quad: half the diagonals' cross
/// product; triangle: half the edges').
pub fn face_area(x: &[[f64; 3]]) -> f64 {
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let cross_norm = |a: [f64; 3], b: [f64; 3]| {
        let c = [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ];
        (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt()
    };
    match x.len() {
        4 => 0.5 * cross_norm(sub(x[2], x[0]), sub(x[3], x[1])),
        3 => 0.5 * cross_norm(sub(x[1], x[0]), sub(x[2], x[0])),
        _ => 0.0,
    }
}

/// The mean size of the given faces: each face's mean corner-to-corner edge length (a
/// tri6's corners only), averaged over the faces; 0 for none.
pub fn mean_face_size<'a>(mesh: &Mesh, faces: impl IntoIterator<Item = &'a FaceRef>) -> f64 {
    let (mut sum, mut count) = (0.0, 0usize);
    for &f in faces {
        let nodes = mesh.face_nodes(f);
        let corners = if nodes.len() == 6 { 3 } else { nodes.len() };
        let x = |k: usize| mesh.coords[nodes[k % corners]];
        let edges: f64 = (0..corners)
            .map(|k| {
                let (a, b) = (x(k), x(k + 1));
                ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
            })
            .sum();
        sum += edges / corners as f64;
        count += 1;
    }
    if count == 0 {
        0.0
    } else {
        sum / count as f64
    }
}

/// Each node's tributary area on the given faces: every face's area split equally
/// among its nodes; a tri6 face is split into its four sub-triangles through the
/// midside nodes first (corners get a twelfth of a flat face, midside nodes a quarter),
/// as contact codes treat quadratic segments: the consistent weights ∫N_a dA of a tri6
/// are zero at its corners, which node-based contact cannot use.
pub fn tributary_areas<'a>(
    mesh: &Mesh,
    faces: impl IntoIterator<Item = &'a FaceRef>,
) -> std::collections::BTreeMap<usize, f64> {
    const TRI6_SUB: [[usize; 3]; 4] = [[0, 3, 5], [3, 1, 4], [5, 4, 2], [3, 4, 5]];
    let mut area = std::collections::BTreeMap::new();
    let mut share = |nodes: &[usize]| {
        let x: Vec<[f64; 3]> = nodes.iter().map(|&n| mesh.coords[n]).collect();
        let a = face_area(&x) / nodes.len() as f64;
        for &n in nodes {
            *area.entry(n).or_default() += a;
        }
    };
    for &f in faces {
        let nodes = mesh.face_nodes(f);
        if nodes.len() == 6 {
            for sub in TRI6_SUB {
                share(&sub.map(|i| nodes[i]));
            }
        } else {
            share(&nodes);
        }
    }
    area
}

/// The bounding box of the mesh (zeros for an empty mesh).
pub fn bounding_box(mesh: &Mesh) -> ([f64; 3], [f64; 3]) {
    if mesh.coords.is_empty() {
        return ([0.0; 3], [0.0; 3]);
    }
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for x in &mesh.coords {
        for k in 0..3 {
            lo[k] = lo[k].min(x[k]);
            hi[k] = hi[k].max(x[k]);
        }
    }
    (lo, hi)
}

/// A length scale for geometric tolerances: the bounding-box diagonal.
pub fn length_scale(mesh: &Mesh) -> f64 {
    let (lo, hi) = bounding_box(mesh);
    (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::{box_mesh, BoxSpec};
    use crate::mesh::ElemKind;

    fn unit_box(kind: ElemKind) -> Mesh {
        box_mesh(
            &BoxSpec {
                origin: [0.0; 3],
                size: [2.0, 1.0, 1.0],
                cells: [4, 2, 2],
                grading: [1.0; 3],
                kind,
            },
            0,
        )
    }

    #[test]
    fn bbox_and_scale() {
        let m = unit_box(ElemKind::Hex8);
        assert_eq!(bounding_box(&m), ([0.0; 3], [2.0, 1.0, 1.0]));
        assert!((length_scale(&m) - 6f64.sqrt()).abs() < 1e-12);
        assert_eq!(bounding_box(&Mesh::default()), ([0.0; 3], [0.0; 3]));
    }

    #[test]
    fn nodes_and_faces_in_a_box() {
        for kind in [ElemKind::Hex8, ElemKind::Tet4] {
            let m = unit_box(kind);
            let tol = 1e-9 * length_scale(&m);
            // The plane x = 2 is the xmax side.
            let ns = nodes_in_box(&m, [2.0, 0.0, 0.0], [2.0, 1.0, 1.0], tol);
            assert_eq!(ns, m.node_groups["xmax"]);
            let bf = m.boundary_faces();
            let fs = faces_in_box(&m, &bf, [2.0, 0.0, 0.0], [2.0, 1.0, 1.0], tol);
            let mut want = m.face_groups["xmax"].clone();
            want.sort();
            assert_eq!(fs, want);
            assert_eq!(nodes_of_faces(&m, &fs), ns);
            // Half of the bottom: faces whose nodes all have x <= 1.
            let half = faces_in_box(
                &m,
                &m.face_groups["zmin"],
                [-1.0, -1.0, -1.0],
                [1.0, 2.0, 0.0],
                tol,
            );
            assert_eq!(half.len(), m.face_groups["zmin"].len() / 2);
            assert_eq!(nodes_of_faces(&m, &half).len(), 3 * 3);
            // Without tolerance a box just short of the plane misses it.
            assert!(nodes_in_box(&m, [2.0 + 1e-6, 0.0, 0.0], [3.0, 1.0, 1.0], 0.0).is_empty());
            assert_eq!(
                nodes_in_box(&m, [2.0 + 1e-6, 0.0, 0.0], [3.0, 1.0, 1.0], 1e-5).len(),
                9
            );
        }
    }
}
