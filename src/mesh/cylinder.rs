//! Round generated meshes, hex8: a solid cylinder (butterfly / O-grid layout, full or a
//! quarter for symmetry models) and an annular ring sector, both extruded along z.
//!
//! Both are built as a 2D quadrilateral mesh in the x–y plane from structured blocks
//! whose seams are merged (conforming, no duplicate nodes), then extruded into layers of
//! hex8. Quads are counter-clockwise seen from +z, so every hex has the Gmsh/VTK order
//! and a positive Jacobian.

use super::generate::axis_coords;
use super::{ElemKind, FaceRef, Mesh};
use std::collections::{BTreeMap, HashMap};

/// A solid circular cylinder along z: radius `radius`, z from `z0` to `z0 + length`.
///
/// The cross-section is a butterfly (O-grid): a central block, a square with slightly
/// bulged sides, surrounded by four blocks whose radial lines run straight to the circle.
/// `cells_radial` = n counts the cells from the axis to the surface: ⌊n/2⌋ in the
/// central block's half-width, the rest in the outer blocks; the circumference gets
/// 8⌊n/2⌋ cells (2⌊n/2⌋ on a quarter).
#[derive(Debug, Clone, PartialEq)]
pub struct CylinderSpec {
    pub radius: f64,
    pub length: f64,
    pub z0: f64,
    pub cells_radial: usize,
    pub cells_axial: usize,
    /// Last / first cell length along z (geometric), 1 = uniform.
    pub axial_grading: f64,
    /// Only the x ≥ 0, y ≥ 0 quadrant (adds the groups `xmin` and `ymin`).
    pub quarter: bool,
}

/// An annular sector extruded along z: radii `inner_radius`..`outer_radius` about
/// `center`, polar angles `angles[0]`..`angles[1]` in degrees (counter-clockwise from +x),
/// z from `z0` to `z0 + thickness`; `cells` = [radial, circumferential, through-thickness].
#[derive(Debug, Clone, PartialEq)]
pub struct RingSpec {
    pub inner_radius: f64,
    pub outer_radius: f64,
    pub thickness: f64,
    pub z0: f64,
    pub angles: [f64; 2],
    pub cells: [usize; 3],
    pub center: [f64; 2],
}

/// Sides bulge out by this fraction of the central block's half-width at their middle
/// (a parabola); < 1/2 keeps the map's Jacobian positive at the corners.
const BULGE: f64 = 0.2;

fn positive(v: f64) -> bool {
    v > 0.0 && v.is_finite()
}

impl CylinderSpec {
    /// The deck-level checks: `Err((field, why))`, the field as named in the deck.
    pub fn check(&self) -> Result<(), (&'static str, String)> {
        if !positive(self.radius) {
            return Err((
                "radius",
                format!("expected a positive length, got {}", self.radius),
            ));
        }
        if !positive(self.length) {
            return Err((
                "length",
                format!("expected a positive length, got {}", self.length),
            ));
        }
        if !self.z0.is_finite() {
            return Err(("z0", format!("expected a finite number, got {}", self.z0)));
        }
        if self.cells_radial < 2 {
            return Err((
                "cells_radial",
                format!(
                    "expected at least 2 (the central block and the outer blocks need one each), got {}",
                    self.cells_radial
                ),
            ));
        }
        if self.cells_axial < 1 {
            return Err(("cells_axial", "expected at least 1, got 0".into()));
        }
        if !positive(self.axial_grading) {
            return Err((
                "axial_grading",
                format!("expected a positive ratio, got {}", self.axial_grading),
            ));
        }
        Ok(())
    }
}

impl RingSpec {
    /// True if the sector closes on itself (360°): its seam is merged, no start/end.
    pub fn is_full(&self) -> bool {
        (self.angles[1] - self.angles[0] - 360.0).abs() <= 1e-9 * 360.0
    }

    /// The deck-level checks: `Err((field, why))`, the field as named in the deck.
    pub fn check(&self) -> Result<(), (&'static str, String)> {
        let (ri, ro) = (self.inner_radius, self.outer_radius);
        if !positive(ri) {
            return Err((
                "inner_radius",
                format!("expected a positive length, got {ri}"),
            ));
        }
        if !positive(ro) {
            return Err((
                "outer_radius",
                format!("expected a positive length, got {ro}"),
            ));
        }
        if ri >= ro {
            return Err((
                "inner_radius",
                format!("must be smaller than outer_radius, got {ri} ≥ {ro}"),
            ));
        }
        if !positive(self.thickness) {
            return Err((
                "thickness",
                format!("expected a positive length, got {}", self.thickness),
            ));
        }
        if !self.z0.is_finite() {
            return Err(("z0", format!("expected a finite number, got {}", self.z0)));
        }
        if self.center.iter().any(|c| !c.is_finite()) {
            return Err((
                "center",
                format!("expected finite coordinates, got {:?}", self.center),
            ));
        }
        let [a0, a1] = self.angles;
        if !(a0.is_finite() && a1.is_finite() && a1 > a0) {
            return Err((
                "angles",
                format!("expected [a0, a1] in degrees with a1 > a0, got [{a0}, {a1}]"),
            ));
        }
        if a1 - a0 > 360.0 && !self.is_full() {
            return Err((
                "angles",
                format!("expected a1 − a0 ≤ 360 degrees, got {}", a1 - a0),
            ));
        }
        if self.cells.contains(&0) {
            return Err((
                "cells",
                format!(
                    "expected three counts ≥ 1 [radial, circumferential, through-thickness], got {:?}",
                    self.cells
                ),
            ));
        }
        if (a1 - a0) / self.cells[1] as f64 >= 180.0 {
            return Err((
                "cells",
                format!(
                    "{} circumferential cells over {} degrees: each must span less than 180 degrees",
                    self.cells[1],
                    a1 - a0
                ),
            ));
        }
        Ok(())
    }
}

/// A 2D quad mesh under construction: structured blocks whose coincident nodes merge.
struct Quads {
    pts: Vec<[f64; 2]>,
    quads: Vec<[usize; 4]>,
    /// Boundary edges by group: (quad, local edge e from corner e to e + 1).
    edges: BTreeMap<&'static str, Vec<(usize, u8)>>,
    /// Nodes closer than this are one node.
    tol: f64,
    bins: HashMap<(i64, i64), Vec<usize>>,
}

impl Quads {
    fn new(tol: f64) -> Quads {
        Quads {
            pts: Vec::new(),
            quads: Vec::new(),
            edges: BTreeMap::new(),
            tol,
            bins: HashMap::new(),
        }
    }

    fn bin(&self, p: [f64; 2]) -> (i64, i64) {
        (
            (p[0] / self.tol).floor() as i64,
            (p[1] / self.tol).floor() as i64,
        )
    }

    /// The node at p: an existing one within `tol`, else a new one.
    fn node(&mut self, p: [f64; 2]) -> usize {
        let (bx, by) = self.bin(p);
        for dx in -1..=1 {
            for dy in -1..=1 {
                if let Some(list) = self.bins.get(&(bx + dx, by + dy)) {
                    for &n in list {
                        let q = self.pts[n];
                        if (q[0] - p[0]).abs() <= self.tol && (q[1] - p[1]).abs() <= self.tol {
                            return n;
                        }
                    }
                }
            }
        }
        let n = self.pts.len();
        self.pts.push(p);
        self.bins.entry((bx, by)).or_default().push(n);
        n
    }

    /// A structured ni × nj block: node (i, j) at `at(i, j)`, which must map (i, j)
    /// right-handed (counter-clockwise quads). `sides` names the groups of its sides
    /// [j = 0, i = ni, j = nj, i = 0] (None: an interior seam).
    fn block(
        &mut self,
        ni: usize,
        nj: usize,
        at: impl Fn(usize, usize) -> [f64; 2],
        sides: [Option<&'static str>; 4],
    ) {
        let mut ids = vec![0usize; (ni + 1) * (nj + 1)];
        for j in 0..=nj {
            for i in 0..=ni {
                ids[i + (ni + 1) * j] = self.node(at(i, j));
            }
        }
        let id = |i: usize, j: usize| ids[i + (ni + 1) * j];
        for j in 0..nj {
            for i in 0..ni {
                let q = self.quads.len();
                self.quads
                    .push([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
                let on = [j == 0, i == ni - 1, j == nj - 1, i == 0];
                for (e, name) in sides.iter().enumerate() {
                    if let (Some(name), true) = (name, on[e]) {
                        self.edges.entry(name).or_default().push((q, e as u8));
                    }
                }
            }
        }
    }

    /// Extrude through the layers `zs` into hex8: quad (a, b, c, d) at layer k becomes
    /// the hex (a, b, c, d) at z_k and (a, b, c, d) at z_{k+1}. Groups: the named edge
    /// groups become lateral face groups, plus `zmin` and `zmax`; each face group's nodes
    /// are the node group of the same name.
    fn extrude(&self, zs: &[f64], part: u32) -> Mesh {
        let np = self.pts.len();
        let nq = self.quads.len();
        let layers = zs.len() - 1;
        let mut mesh = Mesh {
            offsets: vec![0],
            ..Default::default()
        };
        mesh.coords.reserve(np * zs.len());
        for &z in zs {
            mesh.coords.extend(self.pts.iter().map(|p| [p[0], p[1], z]));
        }
        for k in 0..layers {
            for q in &self.quads {
                let lo = q.map(|n| n + np * k);
                let hi = q.map(|n| n + np * (k + 1));
                let nodes = [lo[0], lo[1], lo[2], lo[3], hi[0], hi[1], hi[2], hi[3]];
                mesh.push_elem(ElemKind::Hex8, &nodes, part);
            }
        }
        let mut faces: BTreeMap<String, Vec<FaceRef>> = BTreeMap::new();
        // Hex8 faces (ElemKind::faces): 0 bottom, 1 top, 2 + e the side over quad edge e.
        faces.insert(
            "zmin".into(),
            (0..nq).map(|q| FaceRef { elem: q, face: 0 }).collect(),
        );
        faces.insert(
            "zmax".into(),
            (0..nq)
                .map(|q| FaceRef {
                    elem: q + nq * (layers - 1),
                    face: 1,
                })
                .collect(),
        );
        for (name, list) in &self.edges {
            let mut fs: Vec<FaceRef> = (0..layers)
                .flat_map(|k| {
                    list.iter().map(move |&(q, e)| FaceRef {
                        elem: q + nq * k,
                        face: 2 + e,
                    })
                })
                .collect();
            fs.sort_unstable();
            faces.insert(name.to_string(), fs);
        }
        for (name, fs) in faces {
            let mut ns: Vec<usize> = fs.iter().flat_map(|&f| mesh.face_nodes(f)).collect();
            ns.sort_unstable();
            ns.dedup();
            mesh.node_groups.insert(name.clone(), ns);
            mesh.face_groups.insert(name, fs);
        }
        mesh
    }
}

/// Cells in the central block's half-width and in the outer blocks, from `cells_radial`.
fn butterfly_split(cells_radial: usize) -> (usize, usize) {
    let nc = (cells_radial / 2).max(1);
    (nc, cells_radial - nc)
}

/// A solid cylinder along z (see [`CylinderSpec`]). Groups: `zmin`, `zmax`, `outer` (the
/// lateral surface) and, for a quarter, `xmin` (x = 0) and `ymin` (y = 0). Elements get
/// part index `part`.
///
/// # Panics
/// If `spec.check()` fails: decks are validated before they get here.
pub fn cylinder_mesh(spec: &CylinderSpec, part: u32) -> Mesh {
    if let Err((field, why)) = spec.check() {
        panic!("cylinder: {field}: {why}");
    }
    let r = spec.radius;
    let (nc, nr) = butterfly_split(spec.cells_radial);
    // Central block: (u, v) ∈ [-1, 1]² ↦ a (u (1 + β(1 − v²)), v (1 + β(1 − u²))), sides
    // bulged to a(1 + β) at their middles; a is set so the central cells and the outer
    // blocks' radial cells have the same length along the axes.
    let a = r * nc as f64 / (spec.cells_radial as f64 * (1.0 + BULGE));
    let central = |u: f64, v: f64| {
        [
            a * u * (1.0 + BULGE * (1.0 - v * v)),
            a * v * (1.0 + BULGE * (1.0 - u * u)),
        ]
    };
    // Outer block on the +x side, t ∈ [-1, 1] along the side (counter-clockwise), s ∈
    // [0, 1] outwards: straight from the central block's side to the circle at the same
    // fraction of the 90° arc. The other three are quarter turns of it.
    let side = |t: f64, s: f64| {
        let inner = central(1.0, t);
        let th = t * std::f64::consts::FRAC_PI_4;
        let outer = [r * th.cos(), r * th.sin()];
        [
            (1.0 - s) * inner[0] + s * outer[0],
            (1.0 - s) * inner[1] + s * outer[1],
        ]
    };
    // Exact quarter turns (no trigonometric round-off on the symmetry planes).
    let turn = |p: [f64; 2], k: usize| match k % 4 {
        0 => p,
        1 => [-p[1], p[0]],
        2 => [-p[0], -p[1]],
        _ => [p[1], -p[0]],
    };
    let frac = |i: usize, n: usize| i as f64 / n as f64;
    let mut q = Quads::new(1e-9 * r);
    if spec.quarter {
        // u, v ∈ [0, 1]: i, j count nc cells from the axis.
        q.block(
            nc,
            nc,
            |i, j| central(frac(i, nc), frac(j, nc)),
            [Some("ymin"), None, None, Some("xmin")],
        );
        // +x block over t ∈ [0, 1]; +y block over t ∈ [-1, 0] (its t = 0 end on x = 0).
        q.block(
            nr,
            nc,
            |i, j| side(frac(j, nc), frac(i, nr)),
            [Some("ymin"), Some("outer"), None, None],
        );
        q.block(
            nr,
            nc,
            |i, j| turn(side(frac(j, nc) - 1.0, frac(i, nr)), 1),
            [None, Some("outer"), Some("xmin"), None],
        );
    } else {
        q.block(
            2 * nc,
            2 * nc,
            |i, j| central(frac(i, nc) - 1.0, frac(j, nc) - 1.0),
            [None; 4],
        );
        for k in 0..4 {
            q.block(
                nr,
                2 * nc,
                |i, j| turn(side(frac(j, nc) - 1.0, frac(i, nr)), k),
                [None, Some("outer"), None, None],
            );
        }
    }
    let zs = axis_coords(spec.z0, spec.length, spec.cells_axial, spec.axial_grading);
    q.extrude(&zs, part)
}

/// An annular sector extruded along z (see [`RingSpec`]). Groups: `inner`, `outer`,
/// `zmin`, `zmax` and, unless the ring is a full 360° (whose seam is merged), `start`
/// (the face at angles[0]) and `end` (at angles[1]). Elements get part index `part`.
///
/// # Panics
/// If `spec.check()` fails: decks are validated before they get here.
pub fn ring_mesh(spec: &RingSpec, part: u32) -> Mesh {
    if let Err((field, why)) = spec.check() {
        panic!("ring: {field}: {why}");
    }
    let [nr, nt, nz] = spec.cells;
    let (ri, ro) = (spec.inner_radius, spec.outer_radius);
    let [a0, a1] = spec.angles.map(f64::to_radians);
    let [cx, cy] = spec.center;
    let full = spec.is_full();
    let (start, end) = if full {
        (None, None)
    } else {
        (Some("start"), Some("end"))
    };
    let mut q = Quads::new(1e-9 * (ro - ri).min(ri));
    q.block(
        nr,
        nt,
        |i, j| {
            let rad = ri + (ro - ri) * i as f64 / nr as f64;
            // The closing column of a full ring is the first one (exactly).
            let th = if full && j == nt {
                a0
            } else {
                a0 + (a1 - a0) * j as f64 / nt as f64
            };
            [cx + rad * th.cos(), cy + rad * th.sin()]
        },
        [start, Some("outer"), end, Some("inner")],
    );
    let zs = axis_coords(spec.z0, spec.thickness, nz, 1.0);
    q.extrude(&zs, part)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::measure::check_reference;
    use std::f64::consts::PI;

    fn cyl(n: usize, quarter: bool) -> CylinderSpec {
        CylinderSpec {
            radius: 2.0,
            length: 3.0,
            z0: -1.0,
            cells_radial: n,
            cells_axial: 3,
            axial_grading: 2.0,
            quarter,
        }
    }

    fn ring(angles: [f64; 2], cells: [usize; 3]) -> RingSpec {
        RingSpec {
            inner_radius: 4.0,
            outer_radius: 5.5,
            thickness: 0.7,
            z0: 0.25,
            angles,
            cells,
            center: [1.5, -2.0],
        }
    }

    fn total_volume(m: &Mesh) -> f64 {
        (0..m.n_elems()).map(|e| m.elem_volume(e)).sum()
    }

    /// Every element positive (volume, and det J at Gauss points and corners, not tiny),
    /// no two nodes at the same place, every node used, and the boundary faces exactly
    /// the union of the face groups with no face in two groups; node groups are the nodes
    /// of the face groups. Returns the smallest scaled corner Jacobian.
    fn check_mesh(m: &Mesh, groups: &[&str]) -> f64 {
        let mut min_scaled = f64::INFINITY;
        for e in 0..m.n_elems() {
            assert!(m.elem_volume(e) > 0.0, "element {e}");
            let x: Vec<[f64; 3]> = m.elem_nodes(e).iter().map(|&n| m.coords[n]).collect();
            check_reference(ElemKind::Hex8, &x).unwrap_or_else(|w| panic!("element {e}: {w}"));
            min_scaled = min_scaled.min(scaled_jacobian(&x));
        }
        // No duplicate coordinates: sorted by x, compare each with its x-neighbours.
        let mut c = m.coords.clone();
        c.sort_by(|a, b| a[0].partial_cmp(&b[0]).unwrap());
        for i in 0..c.len() {
            for j in i + 1..c.len() {
                if c[j][0] - c[i][0] > 1e-9 {
                    break;
                }
                let d = (0..3)
                    .map(|k| (c[i][k] - c[j][k]).abs())
                    .fold(0.0, f64::max);
                assert!(d > 1e-9, "duplicate node at {:?}", c[i]);
            }
        }
        let mut used = vec![false; m.n_nodes()];
        m.conn.iter().for_each(|&n| used[n] = true);
        assert!(used.iter().all(|&u| u), "unused nodes");
        let names: Vec<&str> = m.face_groups.keys().map(|k| k.as_str()).collect();
        let mut want: Vec<&str> = groups.to_vec();
        want.sort_unstable();
        assert_eq!(names, want);
        let bf = m.boundary_faces();
        let mut grouped: Vec<FaceRef> = m.face_groups.values().flatten().copied().collect();
        let n_grouped = grouped.len();
        grouped.sort_unstable();
        grouped.dedup();
        assert_eq!(grouped.len(), n_grouped, "a face is in two groups");
        assert_eq!(bf.len(), n_grouped, "boundary faces vs grouped faces");
        assert_eq!(bf, grouped);
        for (name, fs) in &m.face_groups {
            let mut ns: Vec<usize> = fs.iter().flat_map(|&f| m.face_nodes(f)).collect();
            ns.sort_unstable();
            ns.dedup();
            assert_eq!(m.node_groups[name], ns, "{name}");
        }
        min_scaled
    }

    /// Smallest corner det of the three unit edge vectors (1 for a cube).
    fn scaled_jacobian(x: &[[f64; 3]]) -> f64 {
        const CORNER: [[usize; 4]; 8] = [
            [0, 1, 3, 4],
            [1, 2, 0, 5],
            [2, 3, 1, 6],
            [3, 0, 2, 7],
            [4, 7, 5, 0],
            [5, 4, 6, 1],
            [6, 5, 7, 2],
            [7, 6, 4, 3],
        ];
        let unit = |a: usize, b: usize| {
            let d = [x[b][0] - x[a][0], x[b][1] - x[a][1], x[b][2] - x[a][2]];
            let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            d.map(|c| c / l)
        };
        CORNER
            .iter()
            .map(|&[c, a, b, d]| {
                let (p, q, r) = (unit(c, a), unit(c, b), unit(c, d));
                (p[1] * q[2] - p[2] * q[1]) * r[0]
                    + (p[2] * q[0] - p[0] * q[2]) * r[1]
                    + (p[0] * q[1] - p[1] * q[0]) * r[2]
            })
            .fold(f64::INFINITY, f64::min)
    }

    fn radius(p: [f64; 3], c: [f64; 2]) -> f64 {
        (p[0] - c[0]).hypot(p[1] - c[1])
    }

    #[test]
    fn cylinder_is_valid_and_grouped() {
        for quarter in [false, true] {
            for n in [2, 3, 4, 5, 7, 10, 16, 25] {
                let s = cyl(n, quarter);
                let m = cylinder_mesh(&s, 3);
                assert!(m.elem_part.iter().all(|&p| p == 3));
                let groups: &[&str] = if quarter {
                    &["outer", "xmin", "ymin", "zmax", "zmin"]
                } else {
                    &["outer", "zmax", "zmin"]
                };
                let q = check_mesh(&m, groups);
                assert!(q > 0.7, "n = {n} quarter {quarter}: scaled Jacobian {q}");
                // Counts: (nc² + nr nc) per quarter of the cross-section.
                let (nc, nr) = butterfly_split(n);
                let per_quarter = nc * nc + 2 * nr * nc;
                let quads = if quarter {
                    per_quarter
                } else {
                    4 * per_quarter
                };
                assert_eq!(m.n_elems(), quads * 3, "n = {n}");
                let nodes_2d = if quarter {
                    (nc + 1) * (nc + 1) + 2 * nr * (nc + 1) - nr
                } else {
                    (2 * nc + 1) * (2 * nc + 1) + 4 * nr * 2 * nc
                };
                assert_eq!(m.n_nodes(), nodes_2d * 4, "n = {n} quarter {quarter}");
                for &v in &m.node_groups["outer"] {
                    assert!((radius(m.coords[v], [0.0; 2]) - 2.0).abs() < 1e-12);
                }
                for (name, z) in [("zmin", -1.0), ("zmax", 2.0)] {
                    assert_eq!(m.node_groups[name].len(), nodes_2d);
                    for &v in &m.node_groups[name] {
                        assert_eq!(m.coords[v][2], z, "{name}");
                    }
                }
                let inside = m.coords.iter().all(|p| radius(*p, [0.0; 2]) <= 2.0 + 1e-12);
                assert!(inside);
                if quarter {
                    for (name, k) in [("xmin", 0), ("ymin", 1)] {
                        assert_eq!(m.node_groups[name].len(), (n + 1) * 4, "{name}");
                        for &v in &m.node_groups[name] {
                            assert_eq!(m.coords[v][k], 0.0, "{name}");
                        }
                    }
                    assert!(m.coords.iter().all(|p| p[0] >= 0.0 && p[1] >= 0.0));
                    assert_eq!(m.face_groups["xmin"].len(), n * 3);
                    assert_eq!(m.face_groups["outer"].len(), 2 * nc * 3);
                } else {
                    assert_eq!(m.face_groups["outer"].len(), 8 * nc * 3);
                }
            }
        }
    }

    #[test]
    fn cylinder_volume_converges() {
        for quarter in [false, true] {
            let exact = PI * 4.0 * 3.0 / if quarter { 4.0 } else { 1.0 };
            let errs: Vec<f64> = [2, 4, 8, 16]
                .iter()
                .map(|&n| {
                    let v = total_volume(&cylinder_mesh(&cyl(n, quarter), 0));
                    // Inscribed polygons: always a little less than the circle.
                    assert!(v < exact, "n = {n}: {v} ≥ {exact}");
                    (v - exact).abs() / exact
                })
                .collect();
            for w in errs.windows(2) {
                assert!(w[1] < 0.3 * w[0], "{errs:?}");
            }
            assert!(errs[2] < 0.01, "{errs:?}");
            // The only error is the chords of the outer polygon: 8 nc sides.
            for (k, n) in [2usize, 4, 8, 16].iter().enumerate() {
                let sides = 8.0 * (n / 2) as f64;
                let polygon = sides / 2.0 * (2.0 * PI / sides).sin() / PI;
                assert!((1.0 - errs[k] - polygon).abs() < 1e-12, "{errs:?}");
            }
        }
    }

    #[test]
    fn cylinder_axial_grading() {
        let m = cylinder_mesh(&cyl(4, true), 0);
        let mut zs: Vec<f64> = m.coords.iter().map(|p| p[2]).collect();
        zs.sort_by(|a, b| a.partial_cmp(b).unwrap());
        zs.dedup();
        assert_eq!(zs.len(), 4);
        let h: Vec<f64> = zs.windows(2).map(|w| w[1] - w[0]).collect();
        assert!((h[2] / h[0] - 2.0).abs() < 1e-12, "{h:?}");
        assert!((zs[0] + 1.0).abs() < 1e-15 && (zs[3] - 2.0).abs() < 1e-15);
    }

    #[test]
    fn ring_is_valid_and_grouped() {
        let c = [1.5, -2.0];
        for (angles, cells) in [
            ([0.0, 360.0], [2, 24, 2]),
            ([-30.0, 330.0], [1, 3, 1]),
            ([10.0, 100.0], [3, 6, 2]),
            ([-45.0, 200.0], [2, 10, 1]),
        ] {
            let s = ring(angles, cells);
            let m = ring_mesh(&s, 1);
            let full = s.is_full();
            let groups: &[&str] = if full {
                &["inner", "outer", "zmax", "zmin"]
            } else {
                &["end", "inner", "outer", "start", "zmax", "zmin"]
            };
            check_mesh(&m, groups);
            let [nr, nt, nz] = cells;
            let cols = if full { nt } else { nt + 1 };
            assert_eq!(m.n_nodes(), (nr + 1) * cols * (nz + 1), "{angles:?}");
            assert_eq!(m.n_elems(), nr * nt * nz);
            for (name, r) in [("inner", 4.0), ("outer", 5.5)] {
                assert_eq!(m.face_groups[name].len(), nt * nz);
                for &v in &m.node_groups[name] {
                    assert!((radius(m.coords[v], c) - r).abs() < 1e-12, "{name}");
                }
            }
            for (name, z) in [("zmin", 0.25), ("zmax", 0.95)] {
                for &v in &m.node_groups[name] {
                    assert!((m.coords[v][2] - z).abs() < 1e-15, "{name}");
                }
            }
            if !full {
                for (name, a) in [("start", angles[0]), ("end", angles[1])] {
                    let (sn, cs) = a.to_radians().sin_cos();
                    assert_eq!(m.face_groups[name].len(), nr * nz);
                    for &v in &m.node_groups[name] {
                        let (dx, dy) = (m.coords[v][0] - c[0], m.coords[v][1] - c[1]);
                        // On the half-plane from the center at angle a.
                        assert!((dx * sn - dy * cs).abs() < 1e-12, "{name}");
                        assert!(dx * cs + dy * sn > 3.9, "{name}");
                    }
                }
            }
        }
    }

    #[test]
    fn ring_volume_converges() {
        for angles in [[0.0, 360.0], [20.0, 110.0]] {
            let frac = (angles[1] - angles[0]) / 360.0;
            let exact = PI * (5.5f64.powi(2) - 16.0) * 0.7 * frac;
            let errs: Vec<f64> = [4, 8, 16, 32]
                .iter()
                .map(|&nt| {
                    let v = total_volume(&ring_mesh(&ring(angles, [2, nt, 1]), 0));
                    assert!(v < exact);
                    // Exactly the area between the inscribed polygons, times thickness.
                    let dth = (angles[1] - angles[0]).to_radians() / nt as f64;
                    let polygons = nt as f64 / 2.0 * (5.5f64.powi(2) - 16.0) * dth.sin() * 0.7;
                    assert!((v - polygons).abs() < 1e-12 * v, "{v} vs {polygons}");
                    (v - exact).abs() / exact
                })
                .collect();
            for w in errs.windows(2) {
                assert!(w[1] < 0.3 * w[0], "{errs:?}");
            }
            // Under 1 % from 32 cells around a full turn (11.25° per cell).
            assert!(errs[3] < 0.01, "{errs:?}");
        }
    }

    #[test]
    fn full_ring_merges_its_seam_and_partial_keeps_it() {
        let full = ring_mesh(&ring([90.0, 450.0], [1, 8, 1]), 0);
        assert_eq!(full.n_nodes(), 2 * 8 * 2);
        let open = ring_mesh(&ring([90.0, 449.0], [1, 8, 1]), 0);
        assert_eq!(open.n_nodes(), 2 * 9 * 2);
        assert_eq!(open.face_groups["start"].len(), 1);
    }

    #[test]
    fn bad_specs_name_their_field() {
        let field = |r: Result<(), (&'static str, String)>| r.unwrap_err().0;
        let mut s = ring([0.0, 360.0], [1, 8, 1]);
        s.inner_radius = 6.0;
        let (f, why) = s.check().unwrap_err();
        assert_eq!(f, "inner_radius");
        assert!(why.contains("smaller than outer_radius"), "{why}");
        let mut s = ring([0.0, 360.0], [1, 8, 1]);
        s.angles = [10.0, 5.0];
        assert_eq!(field(s.check()), "angles");
        s.angles = [0.0, 400.0];
        assert_eq!(field(s.check()), "angles");
        s.angles = [0.0, 360.0];
        s.cells = [1, 2, 1];
        assert_eq!(field(s.check()), "cells");
        s.cells = [1, 0, 1];
        assert_eq!(field(s.check()), "cells");
        s.cells = [1, 3, 1];
        s.thickness = 0.0;
        assert_eq!(field(s.check()), "thickness");
        let mut c = cyl(1, false);
        assert_eq!(field(c.check()), "cells_radial");
        c.cells_radial = 2;
        c.radius = -1.0;
        assert_eq!(field(c.check()), "radius");
        c.radius = 1.0;
        c.axial_grading = 0.0;
        assert_eq!(field(c.check()), "axial_grading");
        c.axial_grading = 1.0;
        c.cells_axial = 0;
        assert_eq!(field(c.check()), "cells_axial");
    }
}
