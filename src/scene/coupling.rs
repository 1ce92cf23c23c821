//! `[[couplings]]`: distributing couplings in a deck (a reference point tied to a node
//! set or surface, loaded or driven per DOF) turned into [`CouplingDef`]s, with the
//! checks an analyst needs: the set exists and spans a plane or a volume (a moment must
//! be distributable), no DOF is both loaded and prescribed, numbers are finite.

use super::check::{err, unique_names};
use super::context::Context;
use super::deck::{Amount, CouplingDeck, WeightsDeck};
use crate::curve::Curve;
use crate::mesh::select::tributary_areas;
use crate::model::coupling::{inertia, invert3, CouplingDef, Dof};
use crate::solve::AnalysisKind;
use crate::Result;

/// Validate and build every `[[couplings]]` entry.
pub(super) fn build_couplings(decks: &[CouplingDeck], ctx: &Context) -> Result<Vec<CouplingDef>> {
    unique_names("couplings", decks.iter().map(|d| d.name.as_str()))?;
    let mut out = Vec::new();
    for (i, c) in decks.iter().enumerate() {
        let f = format!("couplings[{i}]");
        if ctx.analysis == AnalysisKind::Explicit {
            return Err(err(
                &f,
                format!(
                    "coupling `{}`: distributing couplings need type = \"static\" or \"implicit\" (the reference point carries no mass for the explicit update)",
                    c.name
                ),
            ));
        }
        out.push(build_coupling(c, &f, ctx)?);
    }
    Ok(out)
}

fn build_coupling(c: &CouplingDeck, f: &str, ctx: &Context) -> Result<CouplingDef> {
    let nodes = ctx.set_nodes(format!("{f}.nodes"), &c.nodes)?;
    let is_surface = !ctx.node_sets.contains_key(&c.nodes) && ctx.surfaces.contains_key(&c.nodes);
    let weights: Vec<f64> = match (c.weights, is_surface) {
        (Some(WeightsDeck::Area), false) => {
            return Err(err(
                format!("{f}.weights"),
                format!(
                    "\"area\" needs a surface, and `{}` is a node set (use \"uniform\" or name a surface)",
                    c.nodes
                ),
            ))
        }
        (Some(WeightsDeck::Uniform), _) | (None, false) => vec![1.0; nodes.len()],
        (Some(WeightsDeck::Area), true) | (None, true) => {
            let area = tributary_areas(ctx.mesh, &ctx.surfaces[&c.nodes]);
            nodes.iter().map(|n| area.get(n).copied().unwrap_or(0.0)).collect()
        }
    };
    let x: Vec<[f64; 3]> = nodes.iter().map(|&n| ctx.mesh.coords[n]).collect();
    let (total, centroid, j) = inertia(&x, &weights);
    let Some(j_inv) = invert3(j).filter(|_| total > 0.0) else {
        return Err(err(
            format!("{f}.nodes"),
            format!(
                "coupling `{}`: the {} nodes of `{}` lie on a line or at a point, so a moment about that line cannot be distributed; couple a surface or a set spanning a plane",
                c.name,
                nodes.len(),
                c.nodes
            ),
        ));
    };
    let length = ((j[0][0] + j[1][1] + j[2][2]) / (2.0 * total)).sqrt();
    let point = match c.point {
        Some(p) if p.iter().all(|v| v.is_finite()) => p,
        Some(_) => return Err(err(format!("{f}.point"), "expected finite numbers")),
        None => centroid,
    };
    let amount = |field: String, a: &Amount| -> Result<(f64, Curve)> {
        if !a.value.is_finite() {
            return Err(err(&field, "expected a finite number"));
        }
        Ok((a.value, ctx.timeline.curve(&field, &a.curve, &a.step)?))
    };
    let mut dofs: [Dof; 6] = std::array::from_fn(|_| Dof::Free { load: None });
    for (k, axis) in ["x", "y", "z"].into_iter().enumerate() {
        for (h, (load, fixed, lname, fname)) in [
            (&c.force, &c.displacement, "force", "displacement"),
            (&c.moment, &c.rotation, "moment", "rotation"),
        ]
        .into_iter()
        .enumerate()
        {
            let (l, p) = (load.get()[k], fixed.get()[k]);
            dofs[3 * h + k] = match (l, p) {
                (Some(_), Some(_)) => {
                    return Err(err(
                        format!("{f}.{lname}.{axis}"),
                        format!("the {axis} {fname} is prescribed too: a DOF is either loaded or prescribed"),
                    ))
                }
                (Some(a), None) => Dof::Free {
                    load: Some(amount(format!("{f}.{lname}.{axis}"), a)?),
                },
                (None, Some(a)) => {
                    let (value, curve) = amount(format!("{f}.{fname}.{axis}"), a)?;
                    Dof::Prescribed { value, curve }
                }
                (None, None) => Dof::Free { load: None },
            };
        }
    }
    Ok(CouplingDef {
        name: c.name.clone(),
        set: c.nodes.clone(),
        point,
        nodes,
        weights,
        dofs,
        total_weight: total,
        centroid,
        j_inv,
        length,
        owner: 0,
    })
}
