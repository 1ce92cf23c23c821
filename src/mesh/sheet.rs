//! Sheets: a surface mesh of quads and triangles extruded by a thickness into layers of
//! hex8 and wedge6 elements (paper §3.4: thin walls meshed by their surface, one or two
//! solid elements through the thickness; issue 35: the triangles Gmsh leaves in a
//! recombined mesh become solid-shell wedges).
//!
//! The facets are first oriented alike across shared edges (Gmsh gives each surface
//! entity its own orientation), starting from each connected piece's first facet in the
//! file. Each node then moves along its mitred normal: the unit sum of its quads'
//! normals, scaled by 1 / min(n · n_q) so every face keeps the full thickness at a fold
//! (a hat section's 90° bends), as an offset curve does.

use std::collections::{BTreeMap, HashMap};

use super::{ElemKind, FaceRef, Mesh};
use nalgebra::Vector3;

/// A surface mesh as read (from Gmsh): facets (quad4 or tri3, corners counter-clockwise
/// about their normal) and the physical groups on them.
#[derive(Debug, Clone, Default)]
pub struct Surface {
    pub coords: Vec<[f64; 3]>,
    /// Quads (4 corners) and triangles (3).
    pub quads: Vec<Vec<usize>>,
    /// For messages: the file line and element tag of each facet.
    pub quad_lines: Vec<(usize, u64)>,
    /// Physical surfaces: facet indices.
    pub quad_groups: BTreeMap<String, Vec<usize>>,
    /// Physical curves: line2 elements (node pairs).
    pub edge_groups: BTreeMap<String, Vec<[usize; 2]>>,
    /// Physical points.
    pub point_groups: BTreeMap<String, Vec<usize>>,
}

/// Where the surface lies in the sheet, relative to the quads' normal (the right-hand
/// normal of the first quad of each connected piece, as in the file).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Offset {
    /// The middle surface (a shell model's surface).
    #[default]
    Middle,
    /// The sheet grows along the normal from the surface.
    AlongNormal,
    /// The sheet grows against the normal.
    AgainstNormal,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SheetSpec {
    pub thickness: f64,
    pub layers: usize,
    pub offset: Offset,
}

/// Folds sharper than this (angle between neighbouring quads' normals, 120°) would need
/// an offset of more than twice the thickness: refused.
const MIN_MITRE_COS: f64 = 0.5;

/// a / |a|, or `None` for a zero or non-finite length.
fn unit(a: Vector3<f64>) -> Option<Vector3<f64>> {
    let n = a.norm();
    (n > 0.0 && n.is_finite()).then(|| a / n)
}

/// Orient every quad like its neighbours across shared edges (breadth first from each
/// connected piece's first quad). Errors on an edge shared by more than two quads and on
/// a surface that cannot be oriented (a Möbius strip).
fn orient(s: &Surface) -> Result<Vec<Vec<usize>>, String> {
    let name = |q: usize| {
        let (line, tag) = s.quad_lines.get(q).copied().unwrap_or((0, q as u64));
        format!("element {tag} (line {line})")
    };
    let mut edges: HashMap<(usize, usize), Vec<usize>> = HashMap::new();
    for (q, quad) in s.quads.iter().enumerate() {
        let n = quad.len();
        for i in 0..n {
            let (a, b) = (quad[i], quad[(i + 1) % n]);
            edges.entry((a.min(b), a.max(b))).or_default().push(q);
        }
    }
    if let Some((&(a, b), qs)) = edges.iter().filter(|(_, q)| q.len() > 2).min() {
        return Err(format!(
            "the edge between nodes at {:?} and {:?} is shared by {} facets ({}, ...); a sheet is a surface where at most two facets meet at an edge",
            s.coords[a],
            s.coords[b],
            qs.len(),
            name(qs[0])
        ));
    }
    let mut out = s.quads.clone();
    let mut done = vec![false; out.len()];
    let mut queue = std::collections::VecDeque::new();
    for seed in 0..out.len() {
        if done[seed] {
            continue;
        }
        done[seed] = true;
        queue.push_back(seed);
        while let Some(q) = queue.pop_front() {
            let n = out[q].len();
            for i in 0..n {
                let (a, b) = (out[q][i], out[q][(i + 1) % n]);
                for &r in &edges[&(a.min(b), a.max(b))] {
                    if r == q {
                        continue;
                    }
                    // Alike orientation runs a shared edge the other way round.
                    let m = out[r].len();
                    let same_way = (0..m).any(|j| out[r][j] == a && out[r][(j + 1) % m] == b);
                    if !done[r] {
                        if same_way {
                            out[r][1..].reverse();
                        }
                        done[r] = true;
                        queue.push_back(r);
                    } else if same_way {
                        return Err(format!(
                            "the surface cannot be oriented (a Möbius strip?): {} and {} disagree across their shared edge",
                            name(q),
                            name(r)
                        ));
                    }
                }
            }
        }
    }
    Ok(out)
}

/// Extrude the surface into `layers` elements through the thickness, part `part`: a
/// hex8 per quad and layer, a wedge6 per triangle and layer.
///
/// Groups: `top` and `bottom` (the outer faces on the normal's side and the other);
/// per physical surface S, element and node group S and face groups `S.top`,
/// `S.bottom`; per physical curve C, node group C (every node through the thickness)
/// and, where C runs along the sheet's edge, face group C (the edge faces); per
/// physical point P, node group P (its column of nodes).
pub fn extrude(s: &Surface, spec: &SheetSpec, part: u32) -> Result<Mesh, String> {
    // Only the nodes the quads use.
    let mut map = vec![usize::MAX; s.coords.len()];
    let mut coords = Vec::new();
    for quad in &s.quads {
        for &n in quad {
            if map[n] == usize::MAX {
                map[n] = coords.len();
                coords.push(s.coords[n]);
            }
        }
    }
    let quads: Vec<Vec<usize>> = orient(s)?
        .iter()
        .map(|q| q.iter().map(|&n| map[n]).collect())
        .collect();
    let dir = thickness_directions(s, &coords, &quads)?;
    let mut mesh = stack_layers(s, spec, &coords, &dir, &quads, part)?;
    let l = spec.layers;
    let np = coords.len();
    surface_groups(s, &mut mesh, &quads, np, l);
    let cols = Columns {
        np,
        l,
        map: &map,
        coords: &coords,
        quads: &quads,
    };
    curve_and_point_groups(s, &mut mesh, &cols)?;
    Ok(mesh)
}

/// Node n of layer k in the extruded mesh.
fn layer_node(np: usize, k: usize, n: usize) -> usize {
    k * np + n
}

/// The element of facet q, layer k.
fn layer_elem(l: usize, q: usize, k: usize) -> usize {
    q * l + k
}

/// Per node, the direction of the thickness: the corner normals' angle-weighted mean,
/// lengthened by the mitre factor 1/cos so that folds keep their thickness.
fn thickness_directions(
    s: &Surface,
    coords: &[[f64; 3]],
    quads: &[Vec<usize>],
) -> Result<Vec<[f64; 3]>, String> {
    let np = coords.len();
    // Corner normals, summed per node weighted by the corner's angle.
    let mut sum = vec![[0.0; 3]; np];
    let mut corner_normals: Vec<Vec<Vector3<f64>>> = vec![Vec::new(); np];
    for (q, quad) in quads.iter().enumerate() {
        let m = quad.len();
        for i in 0..m {
            let n = quad[i];
            let a = Vector3::from(coords[quad[(i + 1) % m]]) - Vector3::from(coords[n]);
            let b = Vector3::from(coords[quad[(i + m - 1) % m]]) - Vector3::from(coords[n]);
            let Some(nrm) = unit(a.cross(&b)) else {
                let (line, tag) = s.quad_lines.get(q).copied().unwrap_or((0, q as u64));
                return Err(format!(
                    "element {tag} (line {line}) is degenerate: two of its edges at the node at {:?} are parallel or of zero length",
                    coords[n]
                ));
            };
            let angle = (a.dot(&b) / (a.dot(&a) * b.dot(&b)).sqrt())
                .clamp(-1.0, 1.0)
                .acos();
            for k in 0..3 {
                sum[n][k] += angle * nrm[k];
            }
            corner_normals[n].push(nrm);
        }
    }
    let mut dir = vec![[0.0; 3]; np];
    for n in 0..np {
        let Some(u) = unit(Vector3::from(sum[n])) else {
            return Err(format!(
                "the facets at the node at {:?} fold back onto each other; no thickness direction",
                coords[n]
            ));
        };
        let c = corner_normals[n]
            .iter()
            .map(|m| u.dot(m))
            .fold(f64::INFINITY, f64::min);
        if c < MIN_MITRE_COS {
            return Err(format!(
                "the sheet folds by {:.0}° at the node at {:?}; alfe extrudes folds of at most 120° (refine or round the bend)",
                2.0 * c.clamp(-1.0, 1.0).acos().to_degrees(),
                coords[n]
            ));
        }
        dir[n] = u.map(|x| x / c).into();
    }
    Ok(dir)
}

/// The layers of nodes and elements (hex8 from quads, wedge6 from triangles), each
/// element checked for inversion.
fn stack_layers(
    s: &Surface,
    spec: &SheetSpec,
    coords: &[[f64; 3]],
    dir: &[[f64; 3]],
    quads: &[Vec<usize>],
    part: u32,
) -> Result<Mesh, String> {
    let np = coords.len();
    let t = spec.thickness;
    let l = spec.layers;
    let base = match spec.offset {
        Offset::Middle => -0.5 * t,
        Offset::AlongNormal => 0.0,
        Offset::AgainstNormal => -t,
    };
    let mut mesh = Mesh {
        offsets: vec![0],
        ..Default::default()
    };
    for k in 0..=l {
        let h = base + t * k as f64 / l as f64;
        for n in 0..np {
            mesh.coords
                .push([0, 1, 2].map(|i| coords[n][i] + h * dir[n][i]));
        }
    }
    // Element of facet q, layer k: q * l + k; the bottom face (face 0 of a hex8 and of
    // a wedge6) is the facet's, its normal along -n.
    let node = |k: usize, n: usize| layer_node(np, k, n);
    for quad in quads {
        let m = quad.len();
        let kind = if m == 4 {
            ElemKind::Hex8
        } else {
            ElemKind::Wedge6
        };
        for k in 0..l {
            let mut nodes = [0; 8];
            for i in 0..m {
                nodes[i] = node(k, quad[i]);
                nodes[i + m] = node(k + 1, quad[i]);
            }
            mesh.push_elem(kind, &nodes[..2 * m], part);
        }
    }
    for e in 0..mesh.n_elems() {
        if mesh.elem_volume(e) <= 0.0 {
            let q = e / l;
            let (line, tag) = s.quad_lines.get(q).copied().unwrap_or((0, q as u64));
            return Err(format!(
                "element {tag} (line {line}) extrudes into an inverted {}: the thickness {t} is too large for the surface's curvature there",
                mesh.kinds[e].name()
            ));
        }
    }
    Ok(mesh)
}

/// Face groups `bottom`, `top`, and per physical surface its element, node, `.bottom`
/// and `.top` groups.
fn surface_groups(s: &Surface, mesh: &mut Mesh, quads: &[Vec<usize>], np: usize, l: usize) {
    let elem = |q: usize, k: usize| layer_elem(l, q, k);
    let face = |e: usize, f: u8| FaceRef { elem: e, face: f };
    let column = |n: usize| (0..=l).map(move |k| layer_node(np, k, n));
    let nq = quads.len();
    mesh.face_groups.insert(
        "bottom".into(),
        (0..nq).map(|q| face(elem(q, 0), 0)).collect(),
    );
    mesh.face_groups.insert(
        "top".into(),
        (0..nq).map(|q| face(elem(q, l - 1), 1)).collect(),
    );
    for (g, qs) in &s.quad_groups {
        let mut elems: Vec<usize> = qs
            .iter()
            .flat_map(|&q| (0..l).map(move |k| elem(q, k)))
            .collect();
        elems.sort_unstable();
        let mut nodes: Vec<usize> = qs
            .iter()
            .flat_map(|&q| quads[q].iter().copied())
            .flat_map(column)
            .collect();
        nodes.sort_unstable();
        nodes.dedup();
        mesh.face_groups.insert(
            format!("{g}.bottom"),
            qs.iter().map(|&q| face(elem(q, 0), 0)).collect(),
        );
        mesh.face_groups.insert(
            format!("{g}.top"),
            qs.iter().map(|&q| face(elem(q, l - 1), 1)).collect(),
        );
        mesh.elem_groups.insert(g.clone(), elems);
        mesh.node_groups.insert(g.clone(), nodes);
    }
}

/// The extruded mesh's layout, for the groups of curves and points.
struct Columns<'a> {
    np: usize,
    l: usize,
    /// Surface node → sheet node (`usize::MAX` for nodes no facet uses).
    map: &'a [usize],
    coords: &'a [[f64; 3]],
    quads: &'a [Vec<usize>],
}

/// Per physical curve its node group (whole columns) and, on the sheet's edge, its face
/// group; per physical point its column of nodes.
fn curve_and_point_groups(s: &Surface, mesh: &mut Mesh, c: &Columns) -> Result<(), String> {
    let (np, l, map, coords, quads) = (c.np, c.l, c.map, c.coords, c.quads);
    let elem = |q: usize, k: usize| layer_elem(l, q, k);
    let face = |e: usize, f: u8| FaceRef { elem: e, face: f };
    let column = |n: usize| (0..=l).map(move |k| layer_node(np, k, n));
    // Facet edge i (nodes i, i+1) is face 2 + i of its hex8 or wedge6 (ElemKind::faces).
    let mut edge_quads: HashMap<(usize, usize), Vec<(usize, u8)>> = HashMap::new();
    for (q, quad) in quads.iter().enumerate() {
        let m = quad.len();
        for i in 0..m {
            let (a, b) = (quad[i], quad[(i + 1) % m]);
            edge_quads
                .entry((a.min(b), a.max(b)))
                .or_default()
                .push((q, 2 + i as u8));
        }
    }
    let mapped = |n: usize, what: &str| -> Result<usize, String> {
        match map.get(n) {
            Some(&m) if m != usize::MAX => Ok(m),
            _ => Err(format!(
                "physical group \"{what}\" has the node at {:?}, which no facet uses",
                s.coords[n]
            )),
        }
    };
    for (g, edges) in &s.edge_groups {
        let mut nodes = Vec::new();
        let mut faces = Vec::new();
        for &[a, b] in edges {
            let (a, b) = (mapped(a, g)?, mapped(b, g)?);
            nodes.extend(column(a).chain(column(b)));
            match edge_quads.get(&(a.min(b), a.max(b))).map(Vec::as_slice) {
                Some(&[(q, f)]) => faces.extend((0..l).map(|k| face(elem(q, k), f))),
                Some(_) => {}
                None => {
                    return Err(format!(
                        "physical curve \"{g}\" has an edge from {:?} to {:?} that is not an edge of any facet",
                        coords[a], coords[b]
                    ))
                }
            }
        }
        nodes.sort_unstable();
        nodes.dedup();
        faces.sort_unstable();
        faces.dedup();
        mesh.node_groups.insert(g.clone(), nodes);
        if !faces.is_empty() {
            mesh.face_groups.insert(g.clone(), faces);
        }
    }
    for (g, pts) in &s.point_groups {
        let mut nodes = Vec::new();
        for &p in pts {
            nodes.extend(column(mapped(p, g)?));
        }
        nodes.sort_unstable();
        nodes.dedup();
        mesh.node_groups.insert(g.clone(), nodes);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An L of two unit quads folded 90° along the y axis: one in the x–y plane
    /// (x from -1 to 0), one in the y–z plane going up; the second given the other way
    /// round, as Gmsh may.
    fn folded() -> Surface {
        Surface {
            coords: vec![
                [-1.0, 0.0, 0.0],
                [0.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [-1.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
                [0.0, 1.0, 1.0],
            ],
            quads: vec![vec![0, 1, 2, 3], vec![1, 2, 5, 4]],
            quad_lines: vec![(10, 1), (11, 2)],
            quad_groups: [("flange".to_string(), vec![0])].into(),
            edge_groups: [("free".to_string(), vec![[4, 5]])].into(),
            point_groups: [("tip".to_string(), vec![4])].into(),
        }
    }

    #[test]
    fn orients_and_keeps_the_thickness_at_a_fold() {
        let spec = SheetSpec {
            thickness: 0.1,
            layers: 2,
            offset: Offset::Middle,
        };
        let m = extrude(&folded(), &spec, 4).unwrap();
        assert_eq!((m.n_nodes(), m.n_elems()), (18, 4));
        assert_eq!(m.elem_part, vec![4; 4]);
        // Both flanges: the sheet's volume is area × t where the mitre is exact.
        let vol: f64 = (0..4).map(|e| m.elem_volume(e)).sum();
        assert!(vol > 0.0 && (0..4).all(|e| m.elem_volume(e) > 0.0));
        // Flange 1 normal is +z; the fold node moves along (-1, 0, 1)/√2 × √2 t/2.
        let fold_top = m.coords[2 * 6 + 1];
        assert!((fold_top[2] - 0.05).abs() < 1e-12, "{fold_top:?}");
        assert!((fold_top[0] + 0.05).abs() < 1e-12, "{fold_top:?}");
        let fold_bottom = m.coords[1];
        assert!((fold_bottom[2] + 0.05).abs() < 1e-12 && (fold_bottom[0] - 0.05).abs() < 1e-12);
        // Flat node far from the fold: exactly ±t/2.
        assert!((m.coords[0][2] + 0.05).abs() < 1e-12 && (m.coords[12][2] - 0.05).abs() < 1e-12);
        // Volume: the folded strip's inner and outer lengths average to the mid length 2.
        assert!((vol - 0.2).abs() < 1e-12, "{vol}");
        assert_eq!(m.face_groups["top"].len(), 2);
        assert_eq!(
            m.face_groups["flange.top"],
            vec![FaceRef { elem: 1, face: 1 }]
        );
        assert_eq!(m.elem_groups["flange"], vec![0, 1]);
        // Surface node 4 is the sixth the quads use.
        assert_eq!(m.node_groups["tip"], vec![5, 11, 17]);
        // The free edge of the upright quad: two layers of edge faces, nodes 4, 5 × 3.
        assert_eq!(m.face_groups["free"].len(), 2);
        assert_eq!(m.node_groups["free"].len(), 6);
        for f in &m.face_groups["free"] {
            let ns = m.face_nodes(*f);
            assert!(
                ns.iter().all(|n| m.node_groups["free"].contains(n)),
                "{ns:?}"
            );
        }
        // Along / against the normal: one face of the sheet is the surface.
        for (offset, z) in [
            (Offset::AlongNormal, [0.0, 0.1]),
            (Offset::AgainstNormal, [-0.1, 0.0]),
        ] {
            let m = extrude(&folded(), &SheetSpec { offset, ..spec }, 0).unwrap();
            assert!(
                (m.coords[0][2] - z[0]).abs() < 1e-12 && (m.coords[12][2] - z[1]).abs() < 1e-12
            );
            assert!((0..4).all(|e| m.elem_volume(e) > 0.0));
        }
    }

    /// A triangle beside the flat flange, given the other way round, becomes a column
    /// of wedges oriented as the quads' hexes, with its top, bottom and edge faces.
    #[test]
    fn extrudes_triangles_into_wedges() {
        let mut s = folded();
        s.coords.push([-2.0, 0.5, 0.0]);
        s.quads.push(vec![6, 3, 0]);
        s.quad_lines.push((12, 3));
        s.edge_groups.insert("tip edge".into(), vec![[6, 0]]);
        let spec = SheetSpec {
            thickness: 0.1,
            layers: 2,
            offset: Offset::Middle,
        };
        let m = extrude(&s, &spec, 0).unwrap();
        assert_eq!(m.n_elems(), 6);
        assert_eq!(&m.kinds[4..], &[ElemKind::Wedge6, ElemKind::Wedge6]);
        assert!((0..6).all(|e| m.elem_volume(e) > 0.0));
        let vol: f64 = (0..6).map(|e| m.elem_volume(e)).sum();
        assert!((vol - 0.25).abs() < 1e-12, "{vol}");
        // The top faces all point up (+z) on the flat part.
        for f in &m.face_groups["top"] {
            let ns = m.face_nodes(*f);
            let p: Vec<Vector3<f64>> = ns.iter().map(|&n| Vector3::from(m.coords[n])).collect();
            let n = (p[1] - p[0]).cross(&(p[2] - p[0]));
            if f.elem != 2 && f.elem != 3 {
                assert!(n[2] > 0.0, "{f:?}: {n}");
            }
        }
        assert_eq!(m.face_groups["top"].len(), 3);
        // The triangle's free edge: a quad face of each wedge.
        let edge = &m.face_groups["tip edge"];
        assert_eq!(edge.len(), 2);
        for f in edge {
            assert_eq!(m.face_nodes(*f).len(), 4);
            assert!(m
                .face_nodes(*f)
                .iter()
                .all(|n| m.node_groups["tip edge"].contains(n)));
        }
    }

    #[test]
    fn refuses_bad_surfaces() {
        let spec = SheetSpec {
            thickness: 0.1,
            layers: 1,
            offset: Offset::Middle,
        };
        // A third quad on the fold edge.
        let mut s = folded();
        s.coords.push([1.0, 0.0, 0.0]);
        s.coords.push([1.0, 1.0, 0.0]);
        s.quads.push(vec![1, 6, 7, 2]);
        let e = extrude(&s, &spec, 0).unwrap_err();
        assert!(e.contains("shared by 3 facets"), "{e}");
        // A fold back onto itself (180°).
        let mut s = folded();
        s.coords[4] = [-1.0, 0.0, 0.0];
        s.coords[5] = [-1.0, 1.0, 0.0];
        s.coords[0] = [-1.0, 0.0, 0.1];
        let e = extrude(&s, &spec, 0).unwrap_err();
        assert!(e.contains("fold"), "{e}");
        // Degenerate quad.
        let mut s = folded();
        s.coords[3] = s.coords[2];
        let e = extrude(&s, &spec, 0).unwrap_err();
        assert!(e.contains("element 1 (line 10) is degenerate"), "{e}");
        // A curve off the quads.
        let mut s = folded();
        s.edge_groups.insert("x".into(), vec![[0, 5]]);
        let e = extrude(&s, &spec, 0).unwrap_err();
        assert!(e.contains("physical curve \"x\""), "{e}");
    }
}
