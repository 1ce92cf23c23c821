//! Parts made of boxes: the hex8 cells of one rectilinear lattice whose centres lie in a
//! `solid` box and in no `hole` box. The lattice lines are every box's faces, each span
//! between two split into cells no longer than `cell_size`; so an L-bracket with square
//! bolt holes, a bolt with its head, or a plate with clearance holes is a few boxes, and
//! its nodes are shared wherever its cells meet.

use super::{ElemKind, Mesh};

/// An axis-aligned box `[min, max]`.
pub type Aabb = [[f64; 3]; 2];

#[derive(Debug, Clone, PartialEq)]
pub struct BlocksSpec {
    pub solids: Vec<Aabb>,
    pub holes: Vec<Aabb>,
    pub cell_size: f64,
    /// Finer slabs (axis, [from, to], cell size): spans of that axis within [from, to]
    /// take the finer size (a lattice refines whole slabs).
    pub refine: Vec<Slab>,
}

/// A slab of the lattice with its own cell size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slab {
    pub axis: usize,
    pub range: [f64; 2],
    pub cell_size: f64,
}

/// The spans between consecutive cuts along one axis (the boxes' faces and the slabs'
/// ends) with the cell count of each, ⌈span / h⌉, h the smallest cell size of the slabs
/// holding it. Counts are reals: an absurd deck is measured before anything is allocated.
fn spans(spec: &BlocksSpec, axis: usize) -> Vec<(f64, f64, f64)> {
    let mut cuts: Vec<f64> = spec
        .solids
        .iter()
        .chain(&spec.holes)
        .flat_map(|b| [b[0][axis], b[1][axis]])
        .chain(
            spec.refine
                .iter()
                .filter(|r| r.axis == axis)
                .flat_map(|r| r.range),
        )
        .collect();
    cuts.sort_by(f64::total_cmp);
    let tol = 1e-9 * cuts.iter().fold(0.0f64, |m, x| m.max(x.abs())).max(1.0);
    cuts.dedup_by(|a, b| (*a - *b).abs() <= tol);
    cuts.windows(2)
        .map(|w| {
            let h = spec
                .refine
                .iter()
                .filter(|r| r.axis == axis && r.range[0] <= w[0] + tol && w[1] <= r.range[1] + tol)
                .fold(spec.cell_size, |h, r| h.min(r.cell_size));
            (w[0], w[1], ((w[1] - w[0]) / h - 1e-9).ceil().max(1.0))
        })
        .collect()
}

/// The lattice lines along one axis: every span split evenly into its cells.
fn lines(spec: &BlocksSpec, axis: usize) -> Vec<f64> {
    let sp = spans(spec, axis);
    let mut out = vec![sp.first().map_or(0.0, |s| s.0)];
    for (a, b, n) in sp {
        let n = n as usize;
        out.extend((1..=n).map(|i| a + (b - a) * i as f64 / n as f64));
    }
    out
}

/// The number of lattice cells (to refuse absurd sizes before allocating).
pub fn lattice_cells(spec: &BlocksSpec) -> f64 {
    (0..3)
        .map(|a| spans(spec, a).iter().map(|s| s.2).sum::<f64>())
        .product()
}

/// The part's mesh (element part index `part`); nodes no cell uses are dropped. Groups
/// none: select its surfaces with boxes.
pub fn blocks_mesh(spec: &BlocksSpec, part: u32) -> Mesh {
    let l: [Vec<f64>; 3] = std::array::from_fn(|a| lines(spec, a));
    let [nx, ny, nz] = [l[0].len() - 1, l[1].len() - 1, l[2].len() - 1];
    let inside = |b: &Aabb, c: [f64; 3]| (0..3).all(|a| c[a] > b[0][a] && c[a] < b[1][a]);
    let lattice = |i: usize, j: usize, k: usize| i + (nx + 1) * (j + (ny + 1) * k);
    let mut number = vec![usize::MAX; (nx + 1) * (ny + 1) * (nz + 1)];
    let mut mesh = Mesh {
        offsets: vec![0],
        ..Default::default()
    };
    // Hex8 corners as (di, dj, dk), Gmsh/VTK order.
    const C: [[usize; 3]; 8] = [
        [0, 0, 0],
        [1, 0, 0],
        [1, 1, 0],
        [0, 1, 0],
        [0, 0, 1],
        [1, 0, 1],
        [1, 1, 1],
        [0, 1, 1],
    ];
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let c = [
                    0.5 * (l[0][i] + l[0][i + 1]),
                    0.5 * (l[1][j] + l[1][j + 1]),
                    0.5 * (l[2][k] + l[2][k + 1]),
                ];
                if !spec.solids.iter().any(|b| inside(b, c))
                    || spec.holes.iter().any(|b| inside(b, c))
                {
                    continue;
                }
                let nodes: Vec<usize> = C
                    .iter()
                    .map(|d| {
                        let (a, b, e) = (i + d[0], j + d[1], k + d[2]);
                        let id = &mut number[lattice(a, b, e)];
                        if *id == usize::MAX {
                            *id = mesh.coords.len();
                            mesh.coords.push([l[0][a], l[1][b], l[2][e]]);
                        }
                        *id
                    })
                    .collect();
                mesh.push_elem(ElemKind::Hex8, &nodes, part);
            }
        }
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An L of two boxes with a square hole: the cells, the shared nodes and the volume
    /// are those of the solid; every element is right-handed.
    #[test]
    fn an_l_with_a_hole() {
        let spec = BlocksSpec {
            solids: vec![
                [[0.0, 0.0, 0.0], [10.0, 4.0, 2.0]],
                [[8.0, 0.0, 0.0], [10.0, 4.0, 6.0]],
            ],
            holes: vec![[[2.0, 1.0, -1.0], [4.0, 3.0, 3.0]]],
            cell_size: 1.0,
            refine: vec![],
        };
        let m = blocks_mesh(&spec, 3);
        let vol: f64 = (0..m.n_elems()).map(|e| m.elem_volume(e)).sum();
        let want = 10.0 * 4.0 * 2.0 + 2.0 * 4.0 * 4.0 - 2.0 * 2.0 * 2.0;
        assert!((vol - want).abs() < 1e-9, "{vol}");
        assert!((0..m.n_elems()).all(|e| m.elem_volume(e) > 0.0));
        assert_eq!(m.n_elems(), want as usize);
        assert!(m.elem_part.iter().all(|&p| p == 3));
        // Nodes are shared: a conforming lattice has no duplicate coordinates.
        let mut c: Vec<[i64; 3]> = m
            .coords
            .iter()
            .map(|x| x.map(|v| (v * 1e6) as i64))
            .collect();
        c.sort();
        c.dedup();
        assert_eq!(c.len(), m.n_nodes());
        // The hole's four walls are boundary faces: 2 x 2 x 4 sides... every boundary
        // face count is even and the boundary is closed (each edge shared twice).
        let faces = m.boundary_faces();
        let mut edges = std::collections::BTreeMap::new();
        for f in &faces {
            let n = m.face_nodes(*f);
            for a in 0..4 {
                let (p, q) = (n[a], n[(a + 1) % 4]);
                *edges.entry((p.min(q), p.max(q))).or_insert(0) += 1;
            }
        }
        assert!(edges.values().all(|&k| k == 2));
    }

    #[test]
    fn spans_are_split_no_longer_than_the_cell_size() {
        let mut spec = BlocksSpec {
            solids: vec![[[0.0, 0.0, 0.0], [3.0, 1.0, 1.0]]],
            holes: vec![],
            cell_size: 0.7,
            refine: vec![],
        };
        let l = lines(&spec, 0);
        assert_eq!(l.len(), 6);
        assert!(l.windows(2).all(|w| w[1] - w[0] <= 0.7 + 1e-12));
        assert_eq!(lattice_cells(&spec), 5.0 * 2.0 * 2.0);
        // A slab x in [0, 1] at 0.25: 4 cells there, 3 beyond; y and z as before.
        spec.refine = vec![Slab {
            axis: 0,
            range: [0.0, 1.0],
            cell_size: 0.25,
        }];
        let l = lines(&spec, 0);
        assert_eq!(l.len(), 8, "{l:?}");
        assert!((l[4] - 1.0).abs() < 1e-12 && (l[1] - 0.25).abs() < 1e-12);
        assert!(l[4..]
            .windows(2)
            .all(|w| (w[1] - w[0] - 2.0 / 3.0).abs() < 1e-12));
        assert_eq!(lattice_cells(&spec), 7.0 * 2.0 * 2.0);
    }
}
