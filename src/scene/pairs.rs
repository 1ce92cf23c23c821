//! `[[pairs]]`: small-sliding contact between deformable parts (paper §3.7) in a deck.
//! Each tracked node is paired once, here on rank 0 before partitioning, with the
//! closest point on the reference surface's faces; the pairs and their face
//! coordinates never change (docs/src/design.md, "small-sliding surface-to-surface").

use super::check::err;
use super::context::Context;
use super::deck::{BoltDeck, LockAt, PairsDeck, Weights};
use crate::contact::law::{Threshold, DEFAULT_TANGENTIAL_AUGMENTATION};
use crate::contact::wall::ContactMethod;
use crate::mesh::select::{mean_face_size, tributary_areas};
use crate::mesh::ElemKind;
use crate::model::pairing::{mortar_integrals, pair_nodes};
use crate::model::pairs::{PairsDef, Pretension};
use crate::Result;

/// Every `[[bolts]]` entry: tied mortar pairs across the cut with a pretension.
pub(super) fn build_bolts(decks: &[BoltDeck], ctx: &Context) -> Result<Vec<PairsDef>> {
    decks
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let f = format!("bolts[{i}]");
            if ctx.analysis != crate::solve::AnalysisKind::Static {
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
                (Some(LockAt::Step(s)), _) => ctx
                    .timeline
                    .end_of(&f, s)
                    .map_err(|_| err(format!("{f}.lock_at"), format!("unknown step `{s}`")))?,
                (None, Some(s)) => ctx.timeline.end_of(&f, s)?,
                (None, None) => {
                    return Err(err(
                        format!("{f}.lock_at"),
                        "expected a time or a step's name (or give the bolt a `step`: it locks at its end)",
                    ))
                }
            };
            if !(lock_at > 0.0 && lock_at <= ctx.end_time) {
                return Err(err(
                    format!("{f}.lock_at"),
                    format!(
                        "expected a time in (0, {}] (the analysis' end), got {}",
                        ctx.end_time, lock_at
                    ),
                ));
            }
            ctx.timeline.mark(lock_at);
            // Without a curve the pretension ramps up to the lock (over its step) and holds.
            let curve = match (&b.curve, &b.step) {
                (None, None) => crate::curve::Curve::ramp(lock_at),
                _ => ctx.timeline.curve(&f, &b.curve, &b.step)?,
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
            let mut def = build_one(&pairs, &f, ctx)?;
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

/// Every `[[pairs]]` entry, paired.
pub(super) fn build_pairs(decks: &[PairsDeck], ctx: &Context) -> Result<Vec<PairsDef>> {
    decks
        .iter()
        .enumerate()
        .map(|(i, d)| build_one(d, &format!("pairs[{i}]"), ctx))
        .collect()
}

/// Issue 35: tri6 faces (tet10) may be the reference side, whose quadratic shape
/// functions the pair weights and mortar integrals use as they are (a uniform pressure
/// gives the reference nodes their consistent loads, ∫ N_a, and the patch test passes).
/// A tracked tri6 surface is refused, never guessed: its dual functions would need the
/// modified quadratic basis of Popp, Wohlmuth, Gee & Wall (SISC 2012), since
/// D_t = ∫ N_t is zero at a tri6's corners, and that is not built.
fn refuse_quadratic(
    f: &str,
    name: &str,
    mut elems: impl Iterator<Item = usize>,
    ctx: &Context,
) -> Result<()> {
    match elems.find(|&e| ctx.mesh.kinds[e] == ElemKind::Tet10) {
        Some(e) => Err(err(
            format!("{f}.tracked"),
            format!(
                "`{name}` lies on tet10 elements (part `{}`): a tracked surface must have \
                 linear faces (tri6 faces have no positive dual weights at their corners); \
                 make the tet10 part's surface the `reference` and the other the `tracked`",
                ctx.part_names[ctx.mesh.elem_part[e] as usize]
            ),
        )),
        None => Ok(()),
    }
}

fn build_one(d: &PairsDeck, f: &str, ctx: &Context) -> Result<PairsDef> {
    let mesh = ctx.mesh;
    let faces = ctx.surfaces.get(&d.reference).ok_or_else(|| {
        err(
            format!("{f}.reference"),
            format!(
                "unknown surface `{}` (surfaces: {})",
                d.reference,
                ctx.surfaces.keys().cloned().collect::<Vec<_>>().join(", ")
            ),
        )
    })?;
    let nodes = ctx.set_nodes(format!("{f}.tracked"), &d.tracked)?;
    let mut sorted = nodes.clone();
    sorted.sort_unstable();
    let tracked_elems = (0..mesh.n_elems()).filter(|e| {
        mesh.elem_nodes(*e)
            .iter()
            .any(|n| sorted.binary_search(n).is_ok())
    });
    refuse_quadratic(f, &d.tracked, tracked_elems, ctx)?;
    let areas = ctx
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
    let tracked_faces = ctx.surfaces.get(&d.tracked);
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
        (Weights::Mortar, Some(tf)) => Some(
            mortar_integrals(mesh, tf, &face_nodes, &face_x, reach).map_err(|why| err(f, why))?,
        ),
        _ => None,
    };
    let (pairs, unpaired) = pair_nodes(
        mesh,
        &nodes,
        &face_nodes,
        &face_x,
        reach,
        &areas,
        mortar.as_ref(),
    );
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
        search_distance: d.search_distance,
        mortar: weights == Weights::Mortar,
        pretension: None,
        // The tracked side's faces where it is a surface, else the reference faces.
        face_size: match tracked_faces {
            Some(tf) if !tf.is_empty() => mean_face_size(mesh, tf),
            _ => mean_face_size(mesh, faces),
        },
    })
}
