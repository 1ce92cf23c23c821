//! `[[pairs]]`: small-sliding contact between deformable parts (paper §3.7) in a deck.
//! Each tracked node is paired once, here on rank 0 before partitioning, with the
//! closest point on the reference surface's faces; the pairs and their face
//! coordinates never change (DESIGN.md, "small-sliding surface-to-surface").

use super::build::err;
use crate::contact::law::{Threshold, DEFAULT_TANGENTIAL_AUGMENTATION};
use crate::contact::mortar::{dual_coefficients, overlap_integrals};
use crate::contact::pair::{face_shape, on_face, project_on_face};
use crate::contact::search::{bounds, Bounds, BoxGrid};
use crate::contact::wall::ContactMethod;
use crate::mesh::select::tributary_areas;
use crate::mesh::{FaceRef, Mesh};
use crate::model::pairs::{Pair, PairsDef, Pretension};
use crate::Result;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// One `[[pairs]]` entry.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PairsDeck {
    pub name: String,
    /// The tracked side: a surface (its nodes, with tributary areas for the pressure)
    /// or a node set.
    pub tracked: String,
    /// The reference side: a surface of another part.
    pub reference: String,
    #[serde(default)]
    pub method: ContactMethod,
    /// Bonded in all directions from the start (no separation, no slip).
    #[serde(default)]
    pub tied: bool,
    #[serde(default)]
    pub friction: f64,
    #[serde(default)]
    pub kappa: Option<f64>,
    #[serde(default = "one")]
    pub penalty_scale: f64,
    #[serde(default)]
    pub tangential_augmentation: Option<f64>,
    #[serde(default)]
    pub friction_threshold: Threshold,
    /// How far (along the normal) a tracked node may be from the reference surface
    /// at the start to be paired; default: half the reference faces' mean size.
    #[serde(default)]
    pub search_distance: Option<f64>,
    /// How a node's reference point is weighted: "mortar" (dual mortar integrals over
    /// the tracked faces: passes the contact patch test on any meshes; the default for a
    /// tracked surface) or "node" (the face's shape functions at the node's closest
    /// point: node-to-face; the default for a tracked node set).
    #[serde(default)]
    pub weights: Option<Weights>,
}

/// See [`PairsDeck::weights`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Weights {
    Mortar,
    Node,
}

fn one() -> f64 {
    1.0
}

/// M_ta = ∫ Φ_t N_a of every tracked node t with every reference node a (by global
/// number), and D_t = ∫ N_t, over the tracked faces ([`crate::contact::mortar`]).
#[allow(clippy::type_complexity)]
fn mortar_integrals(
    f: &str,
    mesh: &Mesh,
    tracked: &[FaceRef],
    ref_nodes: &[Vec<usize>],
    ref_x: &[Vec<[f64; 3]>],
    reach: f64,
) -> Result<(BTreeMap<usize, BTreeMap<usize, f64>>, BTreeMap<usize, f64>)> {
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
                err(
                    f,
                    format!(
                        "mortar integrals of the tracked face with nodes {tn:?} over the reference face with nodes {:?}: {why}",
                        ref_nodes[k]
                    ),
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

/// One `[[bolts]]` entry: a bolt's pretension section, the two faces of a cut through
/// its shank (two parts meeting there, or a part split in two), tied by mortar pairs
/// whose normal gap is shifted by the section's shortening (see
/// [`crate::model::pairs::Pretension`]).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BoltDeck {
    pub name: String,
    /// The cut's two faces: surfaces of the two sides (the tension pulls `tracked`
    /// toward `reference`).
    pub tracked: String,
    pub reference: String,
    /// The pretension (a force), times `curve` (default: a ramp up to the lock).
    pub force: f64,
    #[serde(default)]
    pub curve: Option<String>,
    /// The analysis step of the pretension: the curve runs in its time (default a ramp
    /// over it) and the section locks at its end unless `lock_at` says otherwise.
    #[serde(default)]
    pub step: Option<String>,
    /// From this time (a number, or a step's name: its end) on the section keeps the
    /// length it has then. Required without `step`.
    #[serde(default)]
    pub lock_at: Option<LockAt>,
    #[serde(default)]
    pub kappa: Option<f64>,
    #[serde(default)]
    pub search_distance: Option<f64>,
}

/// When a bolt locks: a time, or the end of a named analysis step.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(untagged)]
pub enum LockAt {
    Time(f64),
    Step(String),
}

/// What building pairs needs from the rest of the deck.
pub struct PairInputs<'a> {
    pub mesh: &'a Mesh,
    pub surfaces: &'a BTreeMap<String, Vec<FaceRef>>,
    pub set_nodes: &'a dyn Fn(String, &str) -> Result<Vec<usize>>,
    pub timeline: &'a super::steps::Timeline<'a>,
    pub end_time: f64,
    pub analysis: crate::solve::AnalysisKind,
}

/// Every `[[bolts]]` entry: tied mortar pairs across the cut with a pretension.
pub fn build_bolts(decks: &[BoltDeck], inp: &PairInputs) -> Result<Vec<PairsDef>> {
    decks
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let f = format!("bolts[{i}]");
            if inp.analysis != crate::solve::AnalysisKind::Static {
                return Err(err(
                    &f,
                    "bolt sections take part in static analyses (their lock must end a step, which only static stepping guarantees)",
                ));
            }
            if !b.force.is_finite() {
                return Err(err(format!("{f}.force"), "expected a finite force"));
            }
            let lock_at = match (&b.lock_at, &b.step) {
                (Some(LockAt::Time(t)), _) => *t,
                (Some(LockAt::Step(s)), _) => inp
                    .timeline
                    .end_of(&f, s)
                    .map_err(|_| err(format!("{f}.lock_at"), format!("unknown step `{s}`")))?,
                (None, Some(s)) => inp.timeline.end_of(&f, s)?,
                (None, None) => {
                    return Err(err(
                        format!("{f}.lock_at"),
                        "expected a time or a step's name (or give the bolt a `step`: it locks at its end)",
                    ))
                }
            };
            if !(lock_at > 0.0 && lock_at <= inp.end_time) {
                return Err(err(
                    format!("{f}.lock_at"),
                    format!(
                        "expected a time in (0, {}] (the analysis' end), got {}",
                        inp.end_time, lock_at
                    ),
                ));
            }
            inp.timeline.mark(lock_at);
            // Without a curve the pretension ramps up to the lock (over its step) and holds.
            let curve = match (&b.curve, &b.step) {
                (None, None) => crate::curve::Curve::ramp(lock_at),
                _ => inp.timeline.curve(&f, &b.curve, &b.step)?,
            };
            let pairs = PairsDeck {
                name: b.name.clone(),
                tracked: b.tracked.clone(),
                reference: b.reference.clone(),
                method: ContactMethod::Alm,
                tied: true,
                friction: 0.0,
                kappa: b.kappa,
                penalty_scale: 1.0,
                tangential_augmentation: None,
                friction_threshold: Threshold::default(),
                search_distance: b.search_distance,
                weights: None,
            };
            let mut def = build_one(&pairs, &f, inp)?;
            def.pretension = Some(Pretension {
                force: b.force,
                curve,
                lock_at,
                owner: 0,
            });
            Ok(def)
        })
        .collect()
}

/// The mortar pair of a node whose node-to-face pair is `nts`, from its row of M
/// (reference node → M_ta) and its D_t: the weights M_ta / Σ_a M_ta over every
/// reference node its dual function overlaps, the frame still from its face at ξ. None
/// for a node whose dual function is only partly covered (at the rim of the reference
/// surface), which would get weights well outside [0, 1] (dual functions change sign):
/// it keeps node-to-face weights.
fn mortar_pair(nts: &Pair, row: Option<&BTreeMap<usize, f64>>, full: Option<f64>) -> Option<Pair> {
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

/// Every `[[pairs]]` entry, paired.
pub fn build_pairs(decks: &[PairsDeck], inp: &PairInputs) -> Result<Vec<PairsDef>> {
    decks
        .iter()
        .enumerate()
        .map(|(i, d)| build_one(d, &format!("pairs[{i}]"), inp))
        .collect()
}

fn build_one(d: &PairsDeck, f: &str, inp: &PairInputs) -> Result<PairsDef> {
    let mesh = inp.mesh;
    let faces = inp.surfaces.get(&d.reference).ok_or_else(|| {
        err(
            format!("{f}.reference"),
            format!(
                "unknown surface `{}` (surfaces: {})",
                d.reference,
                inp.surfaces.keys().cloned().collect::<Vec<_>>().join(", ")
            ),
        )
    })?;
    let nodes = (inp.set_nodes)(format!("{f}.tracked"), &d.tracked)?;
    let areas = inp
        .surfaces
        .get(&d.tracked)
        .map(|fs| tributary_areas(mesh, fs))
        .unwrap_or_default();
    if !(d.friction >= 0.0 && d.friction.is_finite()) {
        return Err(err(
            format!("{f}.friction"),
            format!("expected a coefficient ≥ 0, got {}", d.friction),
        ));
    }
    if d.tied && d.friction > 0.0 {
        return Err(err(
            format!("{f}.friction"),
            "a tied pair does not slip: give no friction with `tied = true`",
        ));
    }
    for (key, v) in [
        ("kappa", d.kappa),
        ("penalty_scale", Some(d.penalty_scale)),
        ("search_distance", d.search_distance),
    ] {
        if let Some(v) = v.filter(|v| !(v.is_finite() && *v > 0.0)) {
            return Err(err(
                format!("{f}.{key}"),
                format!("expected a positive number, got {v}"),
            ));
        }
    }
    let alpha = d
        .tangential_augmentation
        .unwrap_or(DEFAULT_TANGENTIAL_AUGMENTATION);
    if !(alpha > 0.0 && alpha <= 1.0) {
        return Err(err(
            format!("{f}.tangential_augmentation"),
            format!("expected a value in (0, 1], got {alpha}"),
        ));
    }
    // Each reference face: its nodes, positions and size.
    let face_nodes: Vec<Vec<usize>> = faces.iter().map(|&fr| mesh.face_nodes(fr)).collect();
    let face_x: Vec<Vec<[f64; 3]>> = face_nodes
        .iter()
        .map(|ns| ns.iter().map(|&n| mesh.coords[n]).collect())
        .collect();
    let size = |x: &[[f64; 3]]| -> f64 {
        let m = x.len();
        (0..m)
            .map(|k| {
                let (a, b) = (x[k], x[(k + 1) % m]);
                ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
            })
            .sum::<f64>()
            / m as f64
    };
    let mean_size = face_x.iter().map(|x| size(x)).sum::<f64>() / face_x.len() as f64;
    let reach = d.search_distance.unwrap_or(0.5 * mean_size);
    let tracked_faces = inp.surfaces.get(&d.tracked);
    let weights = match (d.weights, tracked_faces) {
        (Some(Weights::Mortar), None) => {
            return Err(err(
                format!("{f}.weights"),
                format!(
                    "mortar weights integrate over the tracked faces, but `{}` is a node set; name a surface or use weights = \"node\"",
                    d.tracked
                ),
            ))
        }
        (Some(w), _) => w,
        (None, Some(_)) => Weights::Mortar,
        (None, None) => Weights::Node,
    };
    let mortar = match (weights, tracked_faces) {
        (Weights::Mortar, Some(tf)) => {
            Some(mortar_integrals(f, mesh, tf, &face_nodes, &face_x, reach)?)
        }
        _ => None,
    };
    let mut pairs = Vec::new();
    let mut unpaired = 0;
    // Candidates: the faces whose bounding box grown by the reach holds the node.
    let grid = BoxGrid::new(&face_x.iter().map(|x| bounds(x)).collect::<Vec<_>>(), reach);
    for &n in &nodes {
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
                let mortar = mortar
                    .as_ref()
                    .and_then(|(m, d_t)| mortar_pair(&nts, m.get(&n), d_t.get(&n).copied()));
                pairs.push(mortar.unwrap_or(nts));
            }
            None => unpaired += 1,
        }
    }
    if pairs.is_empty() {
        return Err(err(
            f,
            format!(
                "`{}`: none of the {} tracked nodes of `{}` lies within {reach:.3e} of a face of `{}` (raise `search_distance` or check the surfaces)",
                d.name,
                nodes.len(),
                d.tracked,
                d.reference
            ),
        ));
    }
    Ok(PairsDef {
        name: d.name.clone(),
        method: d.method,
        tied: d.tied,
        friction: d.friction,
        kappa: d.kappa,
        penalty_scale: d.penalty_scale,
        tangential_augmentation: alpha,
        friction_threshold: d.friction_threshold,
        tracked: d.tracked.clone(),
        reference: d.reference.clone(),
        pairs,
        unpaired,
        pretension: None,
    })
}
