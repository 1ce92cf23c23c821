//! Structured mesh generators: graded boxes of hex8, tet4 or wedge6, and interior distortion for
//! patch tests.

use super::{ElemKind, FaceRef, Mesh};
use nalgebra::Vector3;

/// A structured block. `grading[a]` is the ratio last cell size / first cell size along
/// axis a (geometric progression, 1.0 = uniform).
#[derive(Debug, Clone, PartialEq)]
pub struct BoxSpec {
    pub origin: [f64; 3],
    pub size: [f64; 3],
    pub cells: [usize; 3],
    pub grading: [f64; 3],
    pub kind: ElemKind,
}

/// Cell corners as bit codes x + 2y + 4z, in hex8 node order.
const HEX_CORNERS: [usize; 8] = [0, 1, 3, 2, 4, 5, 7, 6];

const SIDE_NAMES: [[&str; 2]; 3] = [["xmin", "xmax"], ["ymin", "ymax"], ["zmin", "zmax"]];

/// The elements of one cell as corner codes: one hex, or the six Kuhn tets around the
/// diagonal 0-7. Every cell uses the same diagonal, so the split conforms across cells.
fn cell_template(kind: ElemKind) -> Vec<Vec<usize>> {
    match kind {
        ElemKind::Hex8 => vec![HEX_CORNERS.to_vec()],
        ElemKind::Tet4 => {
            // Path 0 -> e_a -> e_a + e_b -> 7; the volume sign is the permutation's sign.
            let perms = [
                [0, 1, 2, 1],
                [1, 2, 0, 1],
                [2, 0, 1, 1],
                [0, 2, 1, -1],
                [1, 0, 2, -1],
                [2, 1, 0, -1],
            ];
            perms
                .iter()
                .map(|&[a, b, _, sign]| {
                    let (p1, p2) = (1 << a, (1 << a) | (1 << b));
                    if sign > 0 {
                        vec![0, p1, p2, 7]
                    } else {
                        vec![0, p2, p1, 7]
                    }
                })
                .collect()
        }
        // Two prisms on the base diagonal 0-3 (every cell alike: conforming).
        ElemKind::Wedge6 => vec![vec![0, 1, 3, 4, 5, 7], vec![0, 3, 2, 4, 7, 6]],
        ElemKind::Tet10 => unreachable!("box meshes are hex8, tet4 or wedge6"),
    }
}

/// Node coordinates along one axis: geometric progression with last/first = `grading`.
pub(crate) fn axis_coords(origin: f64, size: f64, n: usize, grading: f64) -> Vec<f64> {
    let q = if n > 1 {
        grading.powf(1.0 / (n as f64 - 1.0))
    } else {
        1.0
    };
    let mut x: Vec<f64> = if (q - 1.0).abs() < 1e-12 {
        (0..=n)
            .map(|i| origin + size * i as f64 / n as f64)
            .collect()
    } else {
        let h0 = size * (q - 1.0) / (q.powi(n as i32) - 1.0);
        (0..=n)
            .map(|i| origin + h0 * (q.powi(i as i32) - 1.0) / (q - 1.0))
            .collect()
    };
    x[n] = origin + size;
    x
}

/// A structured block: nodes on a (possibly graded) grid, hex8 cells or each cell split
/// into 6 tet4 (Kuhn split around the main diagonal, conforming across cells). Elements
/// get part index `part`. node_groups and face_groups are filled for the six sides, named
/// "xmin","xmax","ymin","ymax","zmin","zmax".
///
/// # Panics
/// If a cell count is 0, a size is not positive or a grading is not positive: decks are
/// validated before they get here.
pub fn box_mesh(spec: &BoxSpec, part: u32) -> Mesh {
    for a in 0..3 {
        assert!(
            spec.cells[a] > 0,
            "box: cells along axis {a} must be at least 1"
        );
        assert!(
            spec.size[a] > 0.0 && spec.size[a].is_finite(),
            "box: size along axis {a} must be positive"
        );
        assert!(
            spec.grading[a] > 0.0 && spec.grading[a].is_finite(),
            "box: grading along axis {a} must be positive"
        );
    }
    let [nx, ny, nz] = spec.cells;
    let xs: Vec<Vec<f64>> = (0..3)
        .map(|a| axis_coords(spec.origin[a], spec.size[a], spec.cells[a], spec.grading[a]))
        .collect();
    let node = |i: usize, j: usize, k: usize| i + (nx + 1) * (j + (ny + 1) * k);

    let mut mesh = Mesh {
        offsets: vec![0],
        ..Default::default()
    };
    mesh.coords.reserve((nx + 1) * (ny + 1) * (nz + 1));
    for k in 0..=nz {
        for j in 0..=ny {
            for i in 0..=nx {
                mesh.coords.push([xs[0][i], xs[1][j], xs[2][k]]);
            }
        }
    }

    let template = cell_template(spec.kind);
    // For each template element and face: the side (axis, 0 = min / 1 = max) it lies on.
    let mut side_faces: Vec<(usize, u8, usize, usize)> = Vec::new();
    for (t, corners) in template.iter().enumerate() {
        for (f, local) in spec.kind.faces().iter().enumerate() {
            for a in 0..3 {
                let bits: Vec<usize> = local.iter().map(|&l| (corners[l] >> a) & 1).collect();
                if bits.iter().all(|&b| b == bits[0]) {
                    side_faces.push((t, f as u8, a, bits[0]));
                }
            }
        }
    }

    let mut groups: [[Vec<FaceRef>; 2]; 3] = Default::default();
    let mut nodes = Vec::with_capacity(8);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let ijk = [i, j, k];
                let first = mesh.n_elems();
                for corners in &template {
                    nodes.clear();
                    nodes.extend(
                        corners
                            .iter()
                            .map(|&c| node(i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2))),
                    );
                    mesh.push_elem(spec.kind, &nodes, part);
                }
                for &(t, face, a, side) in &side_faces {
                    let on_side = if side == 0 {
                        ijk[a] == 0
                    } else {
                        ijk[a] == spec.cells[a] - 1
                    };
                    if on_side {
                        groups[a][side].push(FaceRef {
                            elem: first + t,
                            face,
                        });
                    }
                }
            }
        }
    }

    for a in 0..3 {
        for side in 0..2 {
            let faces = std::mem::take(&mut groups[a][side]);
            let mut ns: Vec<usize> = faces.iter().flat_map(|&f| mesh.face_nodes(f)).collect();
            ns.sort_unstable();
            ns.dedup();
            mesh.node_groups.insert(SIDE_NAMES[a][side].to_string(), ns);
            mesh.face_groups
                .insert(SIDE_NAMES[a][side].to_string(), faces);
        }
    }
    mesh
}

/// Hex8 corner neighbours along local xi, eta, zeta: det of the three edge vectors is the
/// corner Jacobian.
const HEX_CORNER_EDGES: [[usize; 4]; 8] = [
    [0, 1, 3, 4],
    [1, 2, 0, 5],
    [2, 3, 1, 6],
    [3, 0, 2, 7],
    [4, 7, 5, 0],
    [5, 4, 6, 1],
    [6, 5, 7, 2],
    [7, 6, 4, 3],
];

const HEX_EDGES: [[usize; 2]; 12] = [
    [0, 1],
    [1, 2],
    [2, 3],
    [3, 0],
    [4, 5],
    [5, 6],
    [6, 7],
    [7, 4],
    [0, 4],
    [1, 5],
    [2, 6],
    [3, 7],
];
/// Each wedge6 corner with its three neighbours, right-handed (as [`HEX_CORNER_EDGES`]).
const WEDGE_CORNER_EDGES: [[usize; 4]; 6] = [
    [0, 1, 2, 3],
    [1, 2, 0, 4],
    [2, 0, 1, 5],
    [3, 5, 4, 0],
    [4, 3, 5, 1],
    [5, 4, 3, 2],
];

const WEDGE_EDGES: [[usize; 2]; 9] = [
    [0, 1],
    [1, 2],
    [2, 0],
    [3, 4],
    [4, 5],
    [5, 3],
    [0, 3],
    [1, 4],
    [2, 5],
];

const TET_EDGES: [[usize; 2]; 6] = [[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]];

/// (b − a) × (c − a) · (d − a): six times the signed volume of the tet a b c d
/// (nalgebra's cross and dot: the same products and sums, in the same order, as the
/// hand-written triple product it replaced).
fn triple(a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3]) -> f64 {
    let a = Vector3::from(a);
    (Vector3::from(b) - a)
        .cross(&(Vector3::from(c) - a))
        .dot(&(Vector3::from(d) - a))
}

/// Smallest corner Jacobian (hex8) or 6 x volume (tet4): what must stay positive.
fn min_corner_det(mesh: &Mesh, e: usize) -> f64 {
    let en = mesh.elem_nodes(e);
    let x = |l: usize| mesh.coords[en[l]];
    match mesh.kinds[e] {
        ElemKind::Tet4 | ElemKind::Tet10 => triple(x(0), x(1), x(2), x(3)),
        ElemKind::Wedge6 => WEDGE_CORNER_EDGES
            .iter()
            .map(|&[c, a, b, d]| triple(x(c), x(a), x(b), x(d)))
            .fold(f64::INFINITY, f64::min),
        ElemKind::Hex8 => HEX_CORNER_EDGES
            .iter()
            .map(|&[c, a, b, d]| triple(x(c), x(a), x(b), x(d)))
            .fold(f64::INFINITY, f64::min),
    }
}

/// xorshift64*: deterministic across platforms, no dependency.
struct Rng(u64);

impl Rng {
    fn new(seed: u64) -> Rng {
        // splitmix64 of the seed, so seeds 0, 1, 2 give unrelated streams (and never 0).
        let mut z = seed.wrapping_add(0x9e3779b97f4a7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d049bb133111eb);
        Rng((z ^ (z >> 31)) | 1)
    }
    /// Uniform in [-1, 1).
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let r = self.0.wrapping_mul(0x2545f4914f6cdd1d);
        (r >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
    /// Uniform in the unit ball (rejection sampling).
    fn in_ball(&mut self) -> [f64; 3] {
        loop {
            let p = [self.next(), self.next(), self.next()];
            if p[0] * p[0] + p[1] * p[1] + p[2] * p[2] <= 1.0 {
                return p;
            }
        }
    }
}

/// Move interior nodes (those on no boundary face) by up to `amount` x the smallest
/// incident edge length, in a deterministic pseudo-random direction. For patch tests on
/// distorted meshes. Any element whose corner Jacobian would fall below a fifth of its
/// original value gets its nodes' moves halved until it does not, so elements stay valid
/// for any `amount` (and untouched for large ones only where needed).
pub fn distort_interior(mesh: &mut Mesh, amount: f64, seed: u64) {
    let n = mesh.n_nodes();
    let mut fixed = vec![false; n];
    for f in mesh.boundary_faces() {
        for v in mesh.face_nodes(f) {
            fixed[v] = true;
        }
    }
    let mut h = vec![f64::INFINITY; n];
    for e in 0..mesh.n_elems() {
        let en = mesh.elem_nodes(e);
        let edges: &[[usize; 2]] = match mesh.kinds[e] {
            ElemKind::Hex8 => &HEX_EDGES,
            ElemKind::Tet4 | ElemKind::Tet10 => &TET_EDGES,
            ElemKind::Wedge6 => &WEDGE_EDGES,
        };
        for &[a, b] in edges {
            let len =
                (Vector3::from(mesh.coords[en[a]]) - Vector3::from(mesh.coords[en[b]])).norm();
            h[en[a]] = h[en[a]].min(len);
            h[en[b]] = h[en[b]].min(len);
        }
    }
    let mut rng = Rng::new(seed);
    let disp: Vec<[f64; 3]> = (0..n)
        .map(|v| {
            let p = rng.in_ball();
            if fixed[v] || !h[v].is_finite() {
                [0.0; 3]
            } else {
                p.map(|c| c * amount * h[v])
            }
        })
        .collect();
    let orig = mesh.coords.clone();
    let q0: Vec<f64> = (0..mesh.n_elems())
        .map(|e| min_corner_det(mesh, e))
        .collect();
    let mut scale = vec![1.0f64; n];
    for round in 0..=40 {
        for v in 0..n {
            for k in 0..3 {
                mesh.coords[v][k] = orig[v][k] + scale[v] * disp[v][k];
            }
        }
        let bad: Vec<usize> = (0..mesh.n_elems())
            .filter(|&e| q0[e] > 0.0 && min_corner_det(mesh, e) < 0.2 * q0[e])
            .collect();
        if bad.is_empty() {
            return;
        }
        for e in bad {
            for &v in mesh.elem_nodes(e) {
                scale[v] = if round == 39 { 0.0 } else { 0.5 * scale[v] };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(kind: ElemKind, cells: [usize; 3], grading: [f64; 3]) -> BoxSpec {
        BoxSpec {
            origin: [1.0, -2.0, 0.5],
            size: [2.0, 1.0, 3.0],
            cells,
            grading,
            kind,
        }
    }

    /// Signed volume computed independently of `Mesh::elem_volume`: tets directly, hexes
    /// as 6 tets around the 0-6 diagonal (exact for planar faces).
    fn volume(mesh: &Mesh, e: usize) -> f64 {
        let en = mesh.elem_nodes(e);
        let x = |l: usize| mesh.coords[en[l]];
        let tet = |a: usize, b: usize, c: usize, d: usize| triple(x(a), x(b), x(c), x(d)) / 6.0;
        match mesh.kinds[e] {
            ElemKind::Tet4 | ElemKind::Tet10 => tet(0, 1, 2, 3),
            // The prism's three tets.
            ElemKind::Wedge6 => tet(0, 1, 2, 5) + tet(0, 1, 5, 4) + tet(0, 4, 5, 3),
            ElemKind::Hex8 => {
                tet(0, 1, 2, 6)
                    + tet(0, 2, 3, 6)
                    + tet(0, 3, 7, 6)
                    + tet(0, 7, 4, 6)
                    + tet(0, 4, 5, 6)
                    + tet(0, 5, 1, 6)
            }
        }
    }

    #[test]
    fn hex_box_counts_volumes_groups() {
        let m = box_mesh(&spec(ElemKind::Hex8, [3, 4, 5], [1.0, 1.0, 1.0]), 2);
        assert_eq!(m.n_nodes(), 4 * 5 * 6);
        assert_eq!(m.n_elems(), 60);
        assert!(m.elem_part.iter().all(|&p| p == 2));
        let mut total = 0.0;
        for e in 0..m.n_elems() {
            let v = volume(&m, e);
            assert!(v > 0.0 && min_corner_det(&m, e) > 0.0, "element {e}");
            assert!((v - m.elem_volume(e)).abs() < 1e-12);
            total += v;
        }
        assert!((total - 6.0).abs() < 1e-12);
        assert_eq!(m.boundary_faces().len(), 2 * (12 + 15 + 20));
        let sizes = [
            ("xmin", 20),
            ("xmax", 20),
            ("ymin", 15),
            ("ymax", 15),
            ("zmin", 12),
            ("zmax", 12),
        ];
        for (name, n) in sizes {
            assert_eq!(m.face_groups[name].len(), n, "{name}");
        }
        assert_eq!(m.node_groups["xmin"].len(), 5 * 6);
        assert_eq!(m.node_groups["zmax"].len(), 4 * 5);
        // Faces are on their side and point outwards.
        for (name, axis, val, sign) in [
            ("xmin", 0, 1.0, -1.0),
            ("ymax", 1, -1.0, 1.0),
            ("zmax", 2, 3.5, 1.0),
        ] {
            for &f in &m.face_groups[name] {
                let ns = m.face_nodes(f);
                assert!(
                    ns.iter().all(|&v| (m.coords[v][axis] - val).abs() < 1e-12),
                    "{name}"
                );
                let x = |i: usize| m.coords[ns[i]];
                let p = |i: usize| Vector3::from(x(i));
                let nrm = (p(1) - p(0)).cross(&(p(2) - p(0)));
                assert!(nrm[axis] * sign > 0.0, "{name} normal");
            }
        }
    }

    #[test]
    fn tet_box_is_conforming_and_positive() {
        let m = box_mesh(&spec(ElemKind::Tet4, [2, 3, 4], [1.0, 2.0, 0.5]), 0);
        assert_eq!(m.n_nodes(), 3 * 4 * 5);
        assert_eq!(m.n_elems(), 6 * 24);
        let mut total = 0.0;
        for e in 0..m.n_elems() {
            let v = volume(&m, e);
            assert!(v > 0.0, "tet {e} has volume {v}");
            total += v;
        }
        assert!((total - 6.0).abs() < 1e-12);
        // Conforming: only the 2 triangles per boundary quad are unshared.
        let quads = 2 * (2 * 3 + 3 * 4 + 2 * 4);
        assert_eq!(m.boundary_faces().len(), 2 * quads);
        let in_groups: usize = m.face_groups.values().map(|v| v.len()).sum();
        assert_eq!(in_groups, 2 * quads);
        assert_eq!(m.face_groups["zmin"].len(), 2 * 2 * 3);
        assert_eq!(m.node_groups["zmin"].len(), 3 * 4);
        let mut bf = m.boundary_faces();
        let mut grouped: Vec<FaceRef> = m.face_groups.values().flatten().copied().collect();
        bf.sort();
        grouped.sort();
        assert_eq!(bf, grouped);
    }

    #[test]
    fn grading_is_geometric() {
        let m = box_mesh(&spec(ElemKind::Hex8, [4, 1, 1], [8.0, 1.0, 1.0]), 0);
        let xs: Vec<f64> = (0..5).map(|i| m.coords[i][0]).collect();
        let h: Vec<f64> = xs.windows(2).map(|w| w[1] - w[0]).collect();
        assert!((h[3] / h[0] - 8.0).abs() < 1e-9);
        assert!((h[1] / h[0] - 2.0).abs() < 1e-9);
        assert!((xs[0] - 1.0).abs() < 1e-15 && (xs[4] - 3.0).abs() < 1e-15);
        let m = box_mesh(&spec(ElemKind::Hex8, [1, 3, 1], [5.0, 0.25, 1.0]), 0);
        let y: Vec<f64> = (0..4).map(|j| m.coords[2 * j][1]).collect();
        assert!(((y[3] - y[2]) / (y[1] - y[0]) - 0.25).abs() < 1e-9);
    }

    #[test]
    fn distortion_keeps_boundary_and_validity() {
        for kind in [ElemKind::Hex8, ElemKind::Tet4, ElemKind::Wedge6] {
            for seed in 0..5 {
                let s = spec(kind, [4, 4, 4], [1.0, 3.0, 1.0]);
                let m0 = box_mesh(&s, 0);
                let mut m = m0.clone();
                distort_interior(&mut m, 0.3, seed);
                let bnodes: std::collections::BTreeSet<usize> =
                    m.node_groups.values().flatten().copied().collect();
                let mut moved = 0;
                for v in 0..m.n_nodes() {
                    let len = (Vector3::from(m.coords[v]) - Vector3::from(m0.coords[v])).norm();
                    if bnodes.contains(&v) {
                        assert_eq!(len, 0.0);
                    } else if len > 0.0 {
                        moved += 1;
                    }
                }
                assert!(moved > 20, "{kind:?} only {moved} nodes moved");
                let mut total = 0.0;
                for e in 0..m.n_elems() {
                    assert!(
                        min_corner_det(&m, e) > 0.0 && m.elem_volume(e) > 0.0,
                        "{kind:?} seed {seed} elem {e}"
                    );
                    total += m.elem_volume(e);
                }
                // Tets fill the box exactly; the prisms' quads are not planar once moved.
                if kind == ElemKind::Tet4 {
                    assert!((total - 6.0).abs() < 1e-10, "{kind:?}: {total}");
                }
                let mut again = m0.clone();
                distort_interior(&mut again, 0.3, seed);
                assert_eq!(again.coords, m.coords, "deterministic");
            }
        }
    }

    /// Wedge boxes: two prisms a cell, valid and filling the box, each side's faces
    /// covering it (quads on x and y sides, two triangles a cell on z sides).
    #[test]
    fn wedge_box_fills_and_groups_its_sides() {
        // A graded 2 × 1 × 3 box.
        let m = box_mesh(&spec(ElemKind::Wedge6, [2, 3, 2], [1.0, 1.5, 0.5]), 0);
        assert_eq!(m.n_elems(), 24);
        let total: f64 = (0..m.n_elems())
            .map(|e| {
                let v = volume(&m, e);
                assert!(v > 0.0 && min_corner_det(&m, e) > 0.0, "element {e}");
                assert!((v - m.elem_volume(e)).abs() < 1e-12);
                v
            })
            .sum();
        assert!((total - 6.0).abs() < 1e-12);
        let area = |g: &str| -> f64 {
            m.face_groups[g]
                .iter()
                .map(|f| {
                    let x: Vec<_> = m.face_nodes(*f).iter().map(|&n| m.coords[n]).collect();
                    crate::mesh::select::face_area(&x)
                })
                .sum()
        };
        assert_eq!(m.face_groups["zmin"].len(), 12);
        assert_eq!(m.face_groups["xmax"].len(), 6);
        assert!((area("zmax") - 2.0).abs() < 1e-12 && (area("ymin") - 6.0).abs() < 1e-12);
    }

    #[test]
    fn distortion_stays_valid_when_large() {
        let mut m = box_mesh(&spec(ElemKind::Tet4, [3, 3, 3], [1.0; 3]), 0);
        distort_interior(&mut m, 2.0, 7);
        assert!((0..m.n_elems()).all(|e| min_corner_det(&m, e) > 0.0));
    }
}
