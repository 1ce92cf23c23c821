//! `[[node_sets]]`, `[[surfaces]]` and `[[curves]]`: named selections of the mesh and
//! load curves, each checked (a set that selects nothing, a surface with faces inside
//! the volume, a curve whose times do not increase are errors).

use super::check::{err, known};
use super::deck::*;
use super::parts::Parts;
use crate::curve::Curve;
use crate::mesh::select::{faces_in_box, nodes_in_box};
use crate::mesh::FaceRef;
use crate::Result;
use std::collections::BTreeMap;

/// The part a selection is restricted to (`part = "name"`), if any.
fn part_index(deck: &Deck, field: &str, name: &Option<String>) -> Result<Option<usize>> {
    match name {
        None => Ok(None),
        Some(n) => deck
            .parts
            .iter()
            .position(|p| p.name == *n)
            .map(Some)
            .ok_or_else(|| {
                err(
                    field,
                    format!(
                        "unknown part `{n}` (parts: {})",
                        deck.parts
                            .iter()
                            .map(|p| p.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                )
            }),
    }
}

/// Every `[[node_sets]]` entry's nodes (sorted, unique, not empty); `tol` is the box
/// selection's tolerance, `(bmin, bmax)` the mesh's extent for the error message.
pub(super) fn node_sets(
    deck: &Deck,
    parts: &Parts,
    tol: f64,
    (bmin, bmax): ([f64; 3], [f64; 3]),
) -> Result<BTreeMap<String, Vec<usize>>> {
    let mesh = &parts.mesh;
    let part_nodes = &parts.nodes;
    let mut node_sets: BTreeMap<String, Vec<usize>> = BTreeMap::new();
    for (i, s) in deck.node_sets.iter().enumerate() {
        let f = format!("node_sets[{i}]");
        let part = part_index(deck, &format!("{f}.part"), &s.part)?;
        let chosen = [s.bbox.is_some(), s.group.is_some(), s.nodes.is_some()]
            .iter()
            .filter(|&&b| b)
            .count();
        if chosen != 1 {
            return Err(err(
                &f,
                format!(
                    "`{}`: expected exactly one of `box`, `group`, `nodes`",
                    s.name
                ),
            ));
        }
        let mut nodes: Vec<usize> = if let Some(b) = &s.bbox {
            nodes_in_box(mesh, b.min, b.max, tol)
        } else if let Some(g) = &s.group {
            mesh.node_groups.get(g).cloned().ok_or_else(|| {
                err(
                    format!("{f}.group"),
                    format!("unknown mesh group `{g}` ({})", known(&mesh.node_groups)),
                )
            })?
        } else {
            let list = s.nodes.clone().unwrap();
            if let Some(&bad) = list.iter().find(|&&n| n >= mesh.n_nodes()) {
                return Err(err(
                    format!("{f}.nodes"),
                    format!(
                        "node {bad} does not exist (the mesh has {} nodes)",
                        mesh.n_nodes()
                    ),
                ));
            }
            list
        };
        if let Some(p) = part {
            nodes.retain(|n| part_nodes[p].contains(n));
        }
        nodes.sort_unstable();
        nodes.dedup();
        if nodes.is_empty() {
            return Err(err(
                &f,
                format!(
                    "node set `{}` selects no nodes (the mesh spans {:?} to {:?})",
                    s.name, bmin, bmax
                ),
            ));
        }
        node_sets.insert(s.name.clone(), nodes);
    }

    Ok(node_sets)
}

/// Every `[[surfaces]]` entry's faces: boundary faces only, not empty.
pub(super) fn surfaces(
    deck: &Deck,
    parts: &Parts,
    boundary: &[FaceRef],
    tol: f64,
) -> Result<BTreeMap<String, Vec<FaceRef>>> {
    let mesh = &parts.mesh;
    let mut surfaces: BTreeMap<String, Vec<FaceRef>> = BTreeMap::new();
    for (i, s) in deck.surfaces.iter().enumerate() {
        let f = format!("surfaces[{i}]");
        let part = part_index(deck, &format!("{f}.part"), &s.part)?;
        let mut faces: Vec<FaceRef> = match (&s.bbox, &s.group) {
            (Some(b), None) => faces_in_box(mesh, boundary, b.min, b.max, tol),
            (None, Some(g)) => mesh.face_groups.get(g).cloned().ok_or_else(|| {
                err(
                    format!("{f}.group"),
                    format!("unknown surface group `{g}` ({})", known(&mesh.face_groups)),
                )
            })?,
            _ => {
                return Err(err(
                    &f,
                    format!("`{}`: expected exactly one of `box`, `group`", s.name),
                ))
            }
        };
        if let Some(p) = part {
            faces.retain(|fr| mesh.elem_part[fr.elem] as usize == p);
        }
        if faces.is_empty() {
            return Err(err(
                &f,
                format!("surface `{}` selects no boundary faces", s.name),
            ));
        }
        // A group's faces may lie inside the volume (a Gmsh surface between two
        // volumes): a load or contact there would act on one side only.
        let inner: Vec<&FaceRef> = faces
            .iter()
            .filter(|fr| boundary.binary_search(fr).is_err())
            .collect();
        if let Some(first) = inner.first() {
            let ns = mesh.face_nodes(**first);
            let c = ns.iter().fold([0.0; 3], |a, &n| {
                [0, 1, 2].map(|k| a[k] + mesh.coords[n][k] / ns.len() as f64)
            });
            return Err(err(
                format!("{f}.group"),
                format!(
                    "surface `{}`: {} of its {} faces are inside the volume (shared by two elements; one at {c:.4?}); a surface for loads and contact is made of boundary faces",
                    s.name,
                    inner.len(),
                    faces.len()
                ),
            ));
        }
        surfaces.insert(s.name.clone(), faces);
    }

    Ok(surfaces)
}

/// Every `[[curves]]` entry: finite points at strictly increasing times.
pub(super) fn curves(deck: &Deck) -> Result<BTreeMap<String, Curve>> {
    let mut curves: BTreeMap<String, Curve> = BTreeMap::new();
    for (i, c) in deck.curves.iter().enumerate() {
        let f = format!("curves[{i}].points");
        if c.points.is_empty() {
            return Err(err(f, "expected at least one [t, value] point"));
        }
        if c.points
            .iter()
            .any(|p| !p[0].is_finite() || !p[1].is_finite())
        {
            return Err(err(f, "expected finite numbers"));
        }
        if c.points.windows(2).any(|w| w[1][0] <= w[0][0]) {
            return Err(err(f, "expected strictly increasing times"));
        }
        curves.insert(
            c.name.clone(),
            Curve {
                points: c.points.clone(),
            },
        );
    }
    Ok(curves)
}
