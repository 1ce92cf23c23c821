//! Small-sliding pairing (paper §3.7): each tracked node paired once, before
//! partitioning, with the closest point of a reference face that faces it (found through
//! a box grid), and, for mortar weights, the integrals of the tracked faces' dual
//! functions over the reference faces (`contact::mortar`) that replace a node's
//! node-to-face weights where its dual function is fully covered. Serial, geometric: the
//! deck's `[[pairs]]` and `[[bolts]]` (`scene/pairs.rs`) call it.

use super::pairs::Pair;
use crate::contact::mortar::{dual_coefficients, overlap_integrals};
use crate::contact::pair::{face_shape, on_face, project_on_face};
use crate::contact::search::{bounds, Bounds, BoxGrid};
use crate::mesh::{FaceRef, Mesh};
use std::collections::BTreeMap;

/// The mortar integrals over a surface: per tracked node its row of M (reference node →
/// M_ta) and its D_t.
pub type MortarRows = (BTreeMap<usize, BTreeMap<usize, f64>>, BTreeMap<usize, f64>);

/// Pair each of `nodes` with the closest point within `reach` of a reference face (its
/// nodes and positions) that faces it, skipping faces that contain the node; mortar
/// weights where `mortar` has a fully covered row. The pairs and the count of nodes left
/// unpaired.
pub fn pair_nodes(
    mesh: &Mesh,
    nodes: &[usize],
    face_nodes: &[Vec<usize>],
    face_x: &[Vec<[f64; 3]>],
    reach: f64,
    areas: &BTreeMap<usize, f64>,
    mortar: Option<&MortarRows>,
) -> (Vec<Pair>, usize) {
    let mut pairs = Vec::new();
    let mut unpaired = 0;
    // Candidates: the faces whose bounding box grown by the reach holds the node.
    let grid = BoxGrid::new(&face_x.iter().map(|x| bounds(x)).collect::<Vec<_>>(), reach);
    for &n in nodes {
        let x = mesh.coords[n];
        let mut best: Option<(f64, usize, [f64; 2])> = None;
        for k in grid.overlapping(x, x) {
            let xs = &face_x[k];
            if face_nodes[k].contains(&n) {
                continue;
            }
            let Some((xi, dist)) = project_on_face(x, xs) else {
                continue;
            };
            if !on_face(xs.len(), xi, 1e-8) || dist > reach {
                continue;
            }
            // The face must face the node (or the node sit just behind it): a thin part's
            // far side is not its contact surface.
            let (nv, dv) = face_shape(xs.len(), xi);
            let mut a1 = [0.0; 3];
            let mut a2 = [0.0; 3];
            let mut p = [0.0; 3];
            for (q, xq) in xs.iter().enumerate() {
                for c in 0..3 {
                    a1[c] += dv[q][0] * xq[c];
                    a2[c] += dv[q][1] * xq[c];
                    p[c] += nv[q] * xq[c];
                }
            }
            let nrm = [
                a1[1] * a2[2] - a1[2] * a2[1],
                a1[2] * a2[0] - a1[0] * a2[2],
                a1[0] * a2[1] - a1[1] * a2[0],
            ];
            let len = (nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]).sqrt();
            let side =
                (0..3).map(|c| nrm[c] * (x[c] - p[c])).sum::<f64>() / len.max(f64::MIN_POSITIVE);
            if side < -0.1 * reach {
                continue;
            }
            if best.is_none_or(|b| dist < b.0) {
                best = Some((dist, k, xi));
            }
        }
        match best {
            Some((_, k, xi)) => {
                let (w, dn) = face_shape(face_nodes[k].len(), xi);
                let nts = Pair {
                    node: n,
                    nodes: face_nodes[k].clone(),
                    w,
                    dn,
                    area: areas.get(&n).copied().unwrap_or(0.0),
                };
                let mortar =
                    mortar.and_then(|(m, d_t)| mortar_pair(&nts, m.get(&n), d_t.get(&n).copied()));
                pairs.push(mortar.unwrap_or(nts));
            }
            None => unpaired += 1,
        }
    }
    (pairs, unpaired)
}

/// M_ta = ∫ Φ_t N_a of every tracked node t with every reference node a (by global
/// number), and D_t = ∫ N_t, over the tracked faces ([`crate::contact::mortar`]).
#[allow(clippy::type_complexity)]
pub fn mortar_integrals(
    mesh: &Mesh,
    tracked: &[FaceRef],
    ref_nodes: &[Vec<usize>],
    ref_x: &[Vec<[f64; 3]>],
    reach: f64,
) -> Result<MortarRows, String> {
    let mut m: BTreeMap<usize, BTreeMap<usize, f64>> = BTreeMap::new();
    let mut d_t: BTreeMap<usize, f64> = BTreeMap::new();
    let ref_boxes: Vec<Bounds> = ref_x.iter().map(|x| bounds(x)).collect();
    let grid = BoxGrid::new(&ref_boxes, reach);
    for &tf in tracked {
        let tn = mesh.face_nodes(tf);
        let xs: Vec<[f64; 3]> = tn.iter().map(|&n| mesh.coords[n]).collect();
        let (a, d) = dual_coefficients(&xs);
        for (t, &n) in tn.iter().enumerate() {
            *d_t.entry(n).or_default() += d[t];
        }
        let (lo, hi) = bounds(&xs);
        for k in grid.overlapping(lo, hi) {
            if ref_nodes[k].iter().any(|r| tn.contains(r)) {
                continue;
            }
            let ov = overlap_integrals(&xs, &a, &ref_x[k]).map_err(|why| {
                format!(
                    "mortar integrals of the tracked face with nodes {tn:?} over the reference face with nodes {:?}: {why}",
                    ref_nodes[k]
                )
            })?;
            for (t, r, v) in ov {
                *m.entry(tn[t])
                    .or_default()
                    .entry(ref_nodes[k][r])
                    .or_default() += v;
            }
        }
    }
    Ok((m, d_t))
}

/// The mortar pair of a node whose node-to-face pair is `nts`, from its row of M
/// (reference node → M_ta) and its D_t: the weights M_ta / Σ_a M_ta over every
/// reference node its dual function overlaps, the frame still from its face at ξ. None
/// for a node whose dual function is only partly covered (at the rim of the reference
/// surface), which would get weights well outside [0, 1] (dual functions change sign):
/// it keeps node-to-face weights.
pub fn mortar_pair(
    nts: &Pair,
    row: Option<&BTreeMap<usize, f64>>,
    full: Option<f64>,
) -> Option<Pair> {
    let row = row?;
    let full = full?;
    let covered: f64 = row.values().sum();
    if !(full > 0.0 && (covered - full).abs() <= 1e-6 * full) {
        return None;
    }
    let mut nodes: Vec<usize> = row.keys().copied().collect();
    for &a in &nts.nodes {
        if !nodes.contains(&a) {
            nodes.push(a);
        }
    }
    let w = nodes
        .iter()
        .map(|a| row.get(a).copied().unwrap_or(0.0) / covered)
        .collect();
    let dn = nodes
        .iter()
        .map(|a| {
            nts.nodes
                .iter()
                .position(|b| b == a)
                .map_or([0.0; 2], |i| nts.dn[i])
        })
        .collect();
    Some(Pair {
        node: nts.node,
        nodes,
        w,
        dn,
        area: covered,
    })
}
