//! Deck → [`ModelDef`]: builds or reads the part meshes, resolves sets, surfaces,
//! constraints and loads, and validates everything a user can get wrong, naming the
//! deck field and what was expected.

use super::deck::*;
use super::{OutputSettings, RunSettings, Scene};
use crate::fem::element::{check_reference, Formulation};
use crate::linalg::GmresOptions;
use crate::material::Hardening;
use crate::mesh::cylinder::{cylinder_mesh, ring_mesh, CylinderSpec, RingSpec};
use crate::mesh::generate::{box_mesh, distort_interior, BoxSpec};
use crate::mesh::select::{bounding_box, faces_in_box, nodes_in_box, nodes_of_faces};
use crate::mesh::{gmsh, ElemKind, FaceRef, Mesh};
use crate::model::def::*;
use crate::model::loads::LoadDef;
use crate::solve::nonlinear::NonlinearOptions;
use crate::solve::Analysis;
use crate::{Error, Result};
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

pub(crate) fn err(field: impl std::fmt::Display, msg: impl std::fmt::Display) -> Error {
    Error::input(format!("{field}: {msg}"))
}

/// Every name of a list non-empty and used once (errors name `<what>[i].name`).
pub(super) fn unique_names<'a>(what: &str, names: impl Iterator<Item = &'a str>) -> Result<()> {
    let mut seen = BTreeSet::new();
    for (i, n) in names.enumerate() {
        if n.trim().is_empty() {
            return Err(err(
                format!("{what}[{i}].name"),
                "expected a non-empty name",
            ));
        }
        if !seen.insert(n) {
            return Err(err(
                format!("{what}[{i}].name"),
                format!("`{n}` is defined twice"),
            ));
        }
    }
    Ok(())
}

pub(super) fn known(names: &BTreeMap<String, impl Sized>) -> String {
    if names.is_empty() {
        "none defined".into()
    } else {
        format!(
            "defined: {}",
            names
                .keys()
                .map(|k| k.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        )
    }
}

/// Build and validate the model and its run settings. `deck_dir` resolves relative
/// mesh file paths.
pub fn build(deck: &Deck, deck_dir: &Path) -> Result<Scene> {
    let deck = &super::steps::with_end_time(deck)?;
    // The name becomes file names (`<name>.h5`, `<name>.xmf`) in the output directory.
    let name = &deck.scene.name;
    if name.is_empty()
        || name.len() > 64
        || name.starts_with('.')
        || !name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'))
    {
        return Err(err(
            "scene.name",
            format!(
                "expected 1 to 64 letters, digits, '-', '_' or '.' (not first), a file name; got {:?}{}",
                name.chars().take(80).collect::<String>(),
                if name.chars().count() > 80 { "..." } else { "" }
            ),
        ));
    }
    unique_names("materials", deck.materials.iter().map(|m| m.name.as_str()))?;
    unique_names("parts", deck.parts.iter().map(|m| m.name.as_str()))?;
    unique_names("node_sets", deck.node_sets.iter().map(|m| m.name.as_str()))?;
    unique_names("surfaces", deck.surfaces.iter().map(|m| m.name.as_str()))?;
    unique_names("curves", deck.curves.iter().map(|m| m.name.as_str()))?;

    // Materials.
    let mut materials = Vec::new();
    for (i, m) in deck.materials.iter().enumerate() {
        materials.push((
            m.name.clone(),
            material_def(m, &format!("materials[{i}]"), deck)?,
        ));
    }

    // Parts and their meshes.
    if deck.parts.is_empty() {
        return Err(err("parts", "expected at least one [[parts]] entry"));
    }
    let mut mesh = Mesh::default();
    let mut part_material = Vec::new();
    let mut part_formulation = Vec::new();
    let mut part_nodes: Vec<BTreeSet<usize>> = Vec::new();
    for (pi, p) in deck.parts.iter().enumerate() {
        let f = format!("parts[{pi}]");
        let Some(mi) = materials.iter().position(|(n, _)| *n == p.material) else {
            let names: Vec<&str> = materials.iter().map(|(n, _)| n.as_str()).collect();
            return Err(err(
                format!("{f}.material"),
                format!(
                    "unknown material `{}` (defined: {})",
                    p.material,
                    if names.is_empty() {
                        "none".into()
                    } else {
                        names.join(", ")
                    }
                ),
            ));
        };
        part_material.push(mi);
        let explicit = deck.analysis.kind == AnalysisKind::Explicit;
        part_formulation.push(part_formulation_of(p, &materials[mi].1, &f, explicit)?);
        let mut pm = part_mesh(&p.mesh, &f, pi as u32, deck_dir)?;
        place(&mut pm, p, &f)?;
        // Reference-configuration validity of every element.
        for e in 0..pm.n_elems() {
            let x0: Vec<[f64; 3]> = pm.elem_nodes(e).iter().map(|&n| pm.coords[n]).collect();
            if let Err(why) = check_reference(pm.kinds[e], &x0) {
                return Err(err(
                    format!("{f} `{}`", p.name),
                    format!(
                        "element {e} ({}) is inverted or degenerate: {why}",
                        pm.kinds[e].name()
                    ),
                ));
            }
        }
        let n0 = mesh.n_nodes();
        part_nodes.push((n0..n0 + pm.n_nodes()).collect());
        mesh.append(&pm);
    }
    let part_index = |field: &str, name: &Option<String>| -> Result<Option<usize>> {
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
    };
    let (bmin, bmax) = bounding_box(&mesh);
    let diag = ((0..3).map(|i| (bmax[i] - bmin[i]).powi(2)).sum::<f64>()).sqrt();
    let tol = 1e-9 * diag.max(1e-300);
    let boundary = mesh.boundary_faces();

    // Node sets.
    let mut node_sets: BTreeMap<String, Vec<usize>> = BTreeMap::new();
    for (i, s) in deck.node_sets.iter().enumerate() {
        let f = format!("node_sets[{i}]");
        let part = part_index(&format!("{f}.part"), &s.part)?;
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
            nodes_in_box(&mesh, b.min, b.max, tol)
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

    // Surfaces (boundary faces only).
    let mut surfaces: BTreeMap<String, Vec<FaceRef>> = BTreeMap::new();
    for (i, s) in deck.surfaces.iter().enumerate() {
        let f = format!("surfaces[{i}]");
        let part = part_index(&format!("{f}.part"), &s.part)?;
        let mut faces: Vec<FaceRef> = match (&s.bbox, &s.group) {
            (Some(b), None) => faces_in_box(&mesh, &boundary, b.min, b.max, tol),
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

    // Curves.
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
    let a = &deck.analysis;
    if !(a.end_time > 0.0 && a.end_time.is_finite()) {
        return Err(err(
            "analysis.end_time",
            format!(
                "expected a positive time (or [[steps]] whose durations add up to it), got {}",
                a.end_time
            ),
        ));
    }
    super::dynamics::check_analysis(deck)?;
    let timeline = super::steps::Timeline::new(super::steps::stages(deck)?, &curves, a.end_time);
    // Entries without a step (walls' motions): `field` is the curve field itself.
    let curve = |field: String, name: &Option<String>| -> Result<Curve> {
        match name {
            None => Ok(Curve::ramp(a.end_time)),
            Some(n) => timeline.named(&field, n),
        }
    };
    // A boundary condition or nodal load may name a node set or a surface (its nodes).
    let set_nodes = |field: String, name: &str| -> Result<Vec<usize>> {
        if let Some(n) = node_sets.get(name) {
            return Ok(n.clone());
        }
        if let Some(fs) = surfaces.get(name) {
            return Ok(nodes_of_faces(&mesh, fs));
        }
        Err(err(
            field,
            format!(
                "unknown node set `{name}` (node sets: {}; surfaces: {})",
                known(&node_sets),
                known(&surfaces)
            ),
        ))
    };

    // Constraints.
    let mut constraints = Vec::new();
    let mut resolved_sets: BTreeMap<String, Vec<usize>> = node_sets.clone();
    for (i, b) in deck.boundary.iter().enumerate() {
        let f = format!("boundary[{i}]");
        let nodes = set_nodes(format!("{f}.set"), b.set())?;
        resolved_sets.insert(b.set().to_string(), nodes);
        let (comps_list, motion, crv) = match b {
            BoundaryDeck::Fixed { components, .. } => (
                components.clone(),
                Motion::Uniform { value: [0.0; 3] },
                Curve::ramp(a.end_time),
            ),
            BoundaryDeck::Displacement {
                components,
                value,
                curve: c,
                step,
                ..
            } => {
                if !value.is_finite() {
                    return Err(err(format!("{f}.value"), "expected a finite number"));
                }
                (
                    components.clone(),
                    Motion::Uniform { value: [*value; 3] },
                    timeline.curve(&f, c, step)?,
                )
            }
            BoundaryDeck::Rotation {
                axis,
                center,
                angle,
                curve: c,
                step,
                ..
            } => {
                let n = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
                if !(n > 0.0 && n.is_finite()) {
                    return Err(err(format!("{f}.axis"), "expected a non-zero direction"));
                }
                if !angle.is_finite() || center.iter().any(|x| !x.is_finite()) {
                    return Err(err(&f, "expected finite `angle` and `center`"));
                }
                (
                    vec![Comp::X, Comp::Y, Comp::Z],
                    Motion::Rotation {
                        axis: axis.map(|x| x / n),
                        center: *center,
                        angle: *angle,
                    },
                    timeline.curve(&f, c, step)?,
                )
            }
        };
        if comps_list.is_empty() {
            return Err(err(
                format!("{f}.components"),
                "expected at least one of \"x\", \"y\", \"z\"",
            ));
        }
        let mut comps = [false; 3];
        for c in comps_list {
            comps[c as usize] = true;
        }
        constraints.push(Constraint {
            set: b.set().to_string(),
            comps,
            motion,
            curve: crv,
        });
    }

    // Loads.
    let mut loads = Vec::new();
    for (i, l) in deck.loads.iter().enumerate() {
        let f = format!("loads[{i}]");
        let finite3 = |v: &[f64; 3], name: &str| -> Result<()> {
            if v.iter().all(|x| x.is_finite()) {
                Ok(())
            } else {
                Err(err(format!("{f}.{name}"), "expected finite numbers"))
            }
        };
        let surface = |s: &str| -> Result<()> {
            if surfaces.contains_key(s) {
                Ok(())
            } else {
                Err(err(
                    format!("{f}.surface"),
                    format!("unknown surface `{s}` ({})", known(&surfaces)),
                ))
            }
        };
        loads.push(match l {
            LoadDeck::Nodal {
                set,
                force,
                curve: c,
                step,
            } => {
                finite3(force, "force")?;
                let nodes = set_nodes(format!("{f}.set"), set)?;
                resolved_sets.insert(set.clone(), nodes);
                LoadDef::Nodal {
                    set: set.clone(),
                    force: *force,
                    curve: timeline.curve(&f, c, step)?,
                }
            }
            LoadDeck::Traction {
                surface: s,
                traction,
                curve: c,
                step,
            } => {
                finite3(traction, "traction")?;
                surface(s)?;
                LoadDef::Traction {
                    surface: s.clone(),
                    traction: *traction,
                    curve: timeline.curve(&f, c, step)?,
                }
            }
            LoadDeck::Pressure {
                surface: s,
                pressure,
                curve: c,
                step,
            } => {
                if !pressure.is_finite() {
                    return Err(err(format!("{f}.pressure"), "expected a finite number"));
                }
                surface(s)?;
                LoadDef::Pressure {
                    surface: s.clone(),
                    pressure: *pressure,
                    curve: timeline.curve(&f, c, step)?,
                }
            }
        });
    }

    // Solver and output settings.
    let s = &deck.solver;
    if s.max_iterations == 0 {
        return Err(err("solver.max_iterations", "expected at least 1"));
    }
    for (name, v) in [
        ("solver.residual_rtol", s.residual_rtol),
        ("solver.increment_rtol", s.increment_rtol),
        ("solver.energy_rtol", s.energy_rtol),
        ("solver.linear.rtol", s.linear.rtol),
    ] {
        if !(v > 0.0 && v < 1.0) {
            return Err(err(
                name,
                format!("expected a tolerance in (0, 1), got {v}"),
            ));
        }
    }
    if s.bfgs_reform == 0 {
        return Err(err("solver.bfgs_reform", "expected at least 1"));
    }
    if !(s.fd_delta > 0.0 && s.fd_delta < 1.0) {
        return Err(err(
            "solver.fd_delta",
            format!("expected 0 < fd_delta < 1, got {}", s.fd_delta),
        ));
    }
    if !(1..=8).contains(&s.linear.overlap) {
        return Err(err(
            "solver.linear.overlap",
            format!("expected 1 to 8 layers, got {}", s.linear.overlap),
        ));
    }
    if s.linear.restart == 0 || s.linear.max_iterations == 0 {
        return Err(err(
            "solver.linear",
            "expected restart ≥ 1 and max_iterations ≥ 1",
        ));
    }
    if deck.output.every == 0 {
        return Err(err("output.every", "expected at least 1"));
    }
    let initial_velocity =
        super::dynamics::initial_velocities(deck, &part_nodes, &mut resolved_sets, &set_nodes)?;
    super::dynamics::check_dynamic_inputs(deck, &part_material, &set_nodes, &mut resolved_sets)?;
    let reaction_sets = match &deck.output.reactions {
        Some(list) => {
            for (i, n) in list.iter().enumerate() {
                let nodes = set_nodes(format!("output.reactions[{i}]"), n)?;
                resolved_sets.insert(n.clone(), nodes);
            }
            list.clone()
        }
        None => {
            let mut v: Vec<String> = Vec::new();
            for c in &constraints {
                if !v.contains(&c.set) {
                    v.push(c.set.clone());
                }
            }
            v
        }
    };

    let wall_inputs = super::walls::WallInputs {
        mesh: &mesh,
        boundary: &boundary,
        part_names: deck.parts.iter().map(|p| p.name.clone()).collect(),
        part_nodes: &part_nodes,
        set_nodes: &set_nodes,
        curve: &curve,
        tol: 1e-8 * diag.max(1e-300),
    };
    let walls = super::walls::build_walls(&deck.walls, &wall_inputs, "walls")?;
    let entities = super::walls::build_walls(&deck.entities, &wall_inputs, "entities")?;
    if !deck.entities.is_empty() {
        if deck.analysis.kind == AnalysisKind::Explicit {
            return Err(err(
                "entities",
                "contact entities take part in static analyses and implicit dynamics, not explicit ones (the explicit update has no kinematic enforcement for a free body); use analysis.kind = \"implicit\", or a rigid wall with a prescribed motion",
            ));
        }
        if deck.analysis.kind == AnalysisKind::Static {
            let dynamic = deck.entities.iter().enumerate().find_map(|(i, e)| {
                [
                    ("mass", e.mass.is_some()),
                    ("inertia", e.inertia.is_some()),
                    ("velocity", e.velocity.is_some()),
                    ("spin", e.spin.is_some()),
                ]
                .into_iter()
                .find(|d| d.1)
                .map(|d| (i, d.0))
            });
            if let Some((i, key)) = dynamic {
                return Err(err(
                    format!("entities[{i}].{key}"),
                    "a static analysis has no inertia; give it in implicit dynamics (analysis.kind = \"implicit\") or remove it",
                ));
            }
        }
        if deck.solver.linear.preconditioner == crate::linalg::PcKind::Amg {
            return Err(err(
                "[solver.linear] preconditioner",
                "\"amg\" needs an elliptic matrix, but the [[entities]] add rigid-body \
                 unknowns coupled to all their tracked nodes; use \"block-jacobi\" or \"asm\"",
            ));
        }
    }

    if (!deck.pairs.is_empty() || !deck.bolts.is_empty())
        && deck.solver.linear.preconditioner == crate::linalg::PcKind::Amg
    {
        return Err(err(
            "[solver.linear] preconditioner",
            "\"amg\" needs an elliptic matrix, but [[pairs]] and [[bolts]] couple each \
             multiplier to a node and a reference face on another part (measured on \
             two-body-hertz: a condensed diagonal turns negative); use \"block-jacobi\" or \"asm\"",
        ));
    }
    if !deck.couplings.is_empty() && deck.solver.linear.preconditioner == crate::linalg::PcKind::Amg
    {
        return Err(err(
            "[solver.linear] preconditioner",
            "\"amg\" needs an elliptic matrix, but the [[couplings]] add constraint \
             multipliers that cannot be condensed node by node; use \"block-jacobi\" or \"asm\"",
        ));
    }
    let couplings = super::coupling::build_couplings(
        &deck.couplings,
        &super::coupling::CouplingInputs {
            mesh: &mesh,
            node_sets: &node_sets,
            surfaces: &surfaces,
            set_nodes: &set_nodes,
            timeline: &timeline,
            analysis: deck.analysis.kind,
        },
    )?;
    let pair_inputs = super::pairs::PairInputs {
        mesh: &mesh,
        surfaces: &surfaces,
        set_nodes: &set_nodes,
        timeline: &timeline,
        end_time: deck.analysis.end_time,
        analysis: deck.analysis.kind,
    };
    let pairs = super::pairs::build_pairs(&deck.pairs, &pair_inputs)?;
    let bolts = super::pairs::build_bolts(&deck.bolts, &pair_inputs)?;
    // Walls and couplings name history columns (`<name>.fx`), as reaction and
    // displacement sets do: a name may stand for one of them only.
    let mut column_owner: BTreeMap<&str, String> = BTreeMap::new();
    for s in reaction_sets.iter().chain(&deck.output.displacements) {
        column_owner.insert(s, "a node set of [output]".to_string());
    }
    let named = [
        (
            "walls",
            deck.walls
                .iter()
                .map(|w| w.name.as_str())
                .collect::<Vec<_>>(),
        ),
        (
            "entities",
            deck.entities.iter().map(|w| w.name.as_str()).collect(),
        ),
        (
            "couplings",
            deck.couplings.iter().map(|c| c.name.as_str()).collect(),
        ),
        (
            "pairs",
            deck.pairs.iter().map(|c| c.name.as_str()).collect(),
        ),
        (
            "bolts",
            deck.bolts.iter().map(|c| c.name.as_str()).collect(),
        ),
    ];
    for (what, names) in &named {
        for (i, &n) in names.iter().enumerate() {
            if let Some(o) = column_owner.insert(n, format!("{what}[{i}]")) {
                return Err(err(
                    format!("{what}[{i}].name"),
                    format!("`{n}` is also the name of {o}: their history columns would collide"),
                ));
            }
        }
    }
    let mut contributions: Vec<ContributionDef> =
        loads.into_iter().map(ContributionDef::Load).collect();
    contributions.extend(walls.into_iter().map(ContributionDef::Wall));
    contributions.extend(entities.into_iter().map(ContributionDef::Wall));
    contributions.extend(couplings.into_iter().map(ContributionDef::Coupling));
    contributions.extend(pairs.into_iter().map(ContributionDef::Pairs));
    contributions.extend(bolts.into_iter().map(ContributionDef::Pairs));
    let partition = match &deck.partition {
        None => crate::partition::Method::Metis,
        Some(p) => match (p.method, p.axis) {
            (PartitionMethodDeck::Metis, None) => crate::partition::Method::Metis,
            (PartitionMethodDeck::Slabs, Some(a)) => {
                crate::partition::Method::Slabs { axis: a as usize }
            }
            (PartitionMethodDeck::Metis, Some(_)) => {
                return Err(err("partition.axis", "only for method = \"slabs\""))
            }
            (PartitionMethodDeck::Slabs, None) => {
                return Err(err(
                    "partition.axis",
                    "method = \"slabs\" needs an axis: \"x\", \"y\" or \"z\"",
                ))
            }
        },
    };
    let peak_stress_parts = deck
        .output
        .peak_stress
        .iter()
        .enumerate()
        .map(
            |(i, name)| match deck.parts.iter().position(|p| &p.name == name) {
                Some(k) => Ok((name.clone(), k as u32)),
                None => Err(err(
                    format!("output.peak_stress[{i}]"),
                    format!(
                        "unknown part `{name}` (parts: {})",
                        deck.parts
                            .iter()
                            .map(|p| p.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                )),
            },
        )
        .collect::<Result<Vec<_>>>()?;
    let model = ModelDef {
        partition,
        contributions,
        mesh,
        part_names: deck.parts.iter().map(|p| p.name.clone()).collect(),
        part_material,
        part_formulation,
        materials,
        node_sets: resolved_sets,
        surfaces,
        constraints,
        reaction_sets,
        displacement_sets: deck.output.displacements.clone(),
        peak_stress_parts,
        initial_velocity,
    };
    let mut run = run_settings(deck, &timeline);
    run.quantities = quantities(deck)?;
    Ok(Scene { model, run })
}

/// `[analysis]`, `[solver]` and `[output]` with their defaults filled in (validated).
/// Largest Poisson's ratio for which `preconditioner = "auto"` may take AMG. AMG's
/// iterations grow without bound as ν → ½ (cook-membrane, ν = 0.4999: ~700 GMRES
/// iterations per Newton iteration, README "Linear solves"); scenes measured fine up to
/// 0.3. The value between is a judgement, not a measurement.
pub const AUTO_AMG_MAX_NU: f64 = 0.45;

/// Why AMG does not suit this deck's problem class, if it does not. These are the
/// classes where it was measured slower than block Jacobi or failing (README "Linear
/// solves"): nearly incompressible solids, friction (sticking rows make some condensed
/// diagonals non-positive: clip-tensile 6.0 s against 3.3 s; sliding-block no gain),
/// coupling multipliers (refused), and plasticity (its isochoric flow makes the tangent
/// nearly incompressible where it yields; not measured, kept on the robust side).
pub fn amg_unsuited(deck: &Deck) -> Option<String> {
    if !deck.couplings.is_empty() {
        return Some("[[couplings]] add constraint multipliers".into());
    }
    if !deck.entities.is_empty() {
        return Some("[[entities]] add rigid-body unknowns".into());
    }
    if !deck.pairs.is_empty() || !deck.bolts.is_empty() {
        return Some(
            "[[pairs]] or [[bolts]] tie deformable parts by multipliers over several nodes".into(),
        );
    }
    if let Some(m) = deck.materials.iter().find(|m| m.nu > AUTO_AMG_MAX_NU) {
        return Some(format!(
            "material '{}' is nearly incompressible (nu = {} > {AUTO_AMG_MAX_NU})",
            m.name, m.nu
        ));
    }
    // Hybrid elements (a deck's choice, or auto's at ν ≥ 0.45): their pressure blocks are
    // condensed before AMG, which then sees F-bar's nearly incompressible matrix.
    if let Some(p) = deck.parts.iter().find(|p| {
        p.formulation == FormulationDeck::Hybrid
            || (p.formulation == FormulationDeck::Auto
                && deck
                    .materials
                    .iter()
                    .find(|m| m.name == p.material)
                    .is_some_and(|m| {
                        m.nu >= 0.45
                            && matches!(
                                m.model,
                                MaterialModel::MooneyRivlin | MaterialModel::NeoHookean
                            )
                    }))
    }) {
        return Some(format!("part '{}' has hybrid elements", p.name));
    }
    if let Some(m) = deck.materials.iter().find(|m| m.model == MaterialModel::J2) {
        return Some(format!("material '{}' is plastic (j2)", m.name));
    }
    if let Some(w) = deck.walls.iter().find(|w| w.friction > 0.0) {
        return Some(format!("wall '{}' has friction", w.name));
    }
    if let Some(w) = deck.entities.iter().find(|w| w.friction > 0.0) {
        return Some(format!("wall '{}' has friction", w.name));
    }
    None
}

/// The times where a resolved load curve or a wall motion's segment changes slope, and
/// where an analysis step ends or a bolt locks, inside the run (`Analysis::stops`).
fn curve_breakpoints(deck: &Deck, timeline: &super::steps::Timeline) -> Vec<f64> {
    let end = deck.analysis.end_time;
    let segments = deck
        .walls
        .iter()
        .chain(&deck.entities)
        .filter_map(|w| w.motion.as_ref()?.segments.as_ref())
        .flatten()
        .map(|s| s.to);
    let mut t: Vec<f64> = timeline
        .stops()
        .into_iter()
        .chain(segments)
        .filter(|&t| t > 0.0 && t < end && t.is_finite())
        .collect();
    t.sort_by(f64::total_cmp);
    t.dedup();
    t
}

fn run_settings(deck: &Deck, timeline: &super::steps::Timeline) -> RunSettings {
    let a = &deck.analysis;
    let s = &deck.solver;
    RunSettings {
        name: deck.scene.name.clone(),
        units: deck.scene.units,
        analysis: Analysis {
            kind: a.kind,
            end_time: a.end_time,
            step: a.step,
            min_step: a.min_step.unwrap_or(a.step * 1e-3),
            max_step: a.max_step.unwrap_or(a.step),
            scheme: a.scheme.unwrap_or(Scheme::GeneralizedAlpha),
            rho_inf: a.rho_inf.unwrap_or(0.9),
            mass: a.mass.unwrap_or(MassKind::Consistent),
            dt_factor: a
                .dt_factor
                .unwrap_or(crate::solve::time::explicit::DEFAULT_DT_FACTOR),
            predictor: a.predictor.unwrap_or_default(),
            stops: if a.kind == AnalysisKind::Static {
                curve_breakpoints(deck, timeline)
            } else {
                timeline
                    .stages
                    .iter()
                    .map(|s| s.end)
                    .filter(|&t| t < a.end_time)
                    .collect()
            },
            stages: timeline.stages.clone(),
        },
        solver: NonlinearOptions {
            kind: s.nonlinear,
            max_iterations: s.max_iterations,
            residual_rtol: s.residual_rtol,
            increment_rtol: s.increment_rtol,
            energy_rtol: s.energy_rtol,
            linear: GmresOptions {
                rtol: s.linear.rtol,
                atol: 0.0,
                restart: s.linear.restart,
                max_iterations: s.linear.max_iterations,
            },
            preconditioner: match s.linear.preconditioner {
                PcKind::Auto if amg_unsuited(deck).is_some() => PcKind::AutoFactored,
                k => k,
            },
            pc_lag: s.linear.lag,
            condense: s.linear.condense,
            pc_overlap: s.linear.overlap,
            rigid_body_modes: s.linear.rigid_body_modes,
            bfgs_reform: s.bfgs_reform,
            fd_delta: s.fd_delta,
            fd_rule: s.fd_step,
            char_length: 0.0,
            line_search: s.line_search.unwrap_or(false),
            export_system: None,
        },
        output: OutputSettings {
            every: deck.output.every,
            interval: deck.output.interval.unwrap_or(a.end_time / 100.0),
            stage_every: deck
                .steps
                .iter()
                .map(|s| s.output_every.unwrap_or(deck.output.every))
                .collect(),
            iterations: deck.output.iterations,
        },
        echo: String::new(),
        quantities: Vec::new(),
    }
}

/// The deck's quantities of interest, each expression parsed; errors name the field.
fn quantities(deck: &Deck) -> Result<Vec<crate::output::quantities::QuantityDef>> {
    use crate::output::quantities::{parse, QuantityDef, When};
    unique_names(
        "quantities",
        deck.quantities.iter().map(|q| q.name.as_str()),
    )?;
    deck.quantities
        .iter()
        .enumerate()
        .map(|(i, q)| {
            let f = format!("quantities[{i}]");
            let expr = parse(&q.expression).map_err(|e| err(format!("{f}.expression"), e))?;
            let when = match (q.at, q.over) {
                (Some(_), Some(_)) => {
                    return Err(err(&f, "give `at` (a time) or `over` (the run), not both"))
                }
                (Some(t), None) if t.is_finite() => When::At(t),
                (Some(t), None) => {
                    return Err(err(
                        format!("{f}.at"),
                        format!("expected a finite time, got {t}"),
                    ))
                }
                (None, Some(OverDeck::Max)) => When::Max,
                (None, Some(OverDeck::Min)) => When::Min,
                (None, Some(OverDeck::MaxAbs)) => When::MaxAbs,
                (None, Some(OverDeck::Last)) | (None, None) => When::Last,
            };
            if q.reference.is_some_and(|r| !r.is_finite()) {
                return Err(err(format!("{f}.reference"), "expected a finite number"));
            }
            if let Some(t) = q.tolerance {
                if !(t.is_finite() && t >= 0.0) {
                    return Err(err(
                        format!("{f}.tolerance"),
                        format!("expected a relative tolerance ≥ 0, got {t}"),
                    ));
                }
                if q.reference.is_none() {
                    return Err(err(
                        format!("{f}.tolerance"),
                        "a tolerance needs a `reference`",
                    ));
                }
            }
            Ok(QuantityDef {
                name: q.name.clone(),
                text: q.expression.clone(),
                expr,
                when,
                reference: q.reference,
                tolerance: q.tolerance,
                description: q.description.clone(),
            })
        })
        .collect()
}

/// The most elements a generated part may have (2e7: tens of GB before solving).
const MAX_ELEMENTS: f64 = 2e7;

/// Refuse a generated mesh of more than [`MAX_ELEMENTS`] before allocating it.
fn size_guard(field: &str, elements: f64) -> Result<()> {
    if elements > MAX_ELEMENTS {
        return Err(err(
            field,
            format!("makes {elements:.3e} elements; expected at most {MAX_ELEMENTS:.0e}"),
        ));
    }
    Ok(())
}

/// Rotate (Rodrigues) and translate a part's mesh as its deck says.
fn place(mesh: &mut Mesh, p: &PartDeck, f: &str) -> Result<()> {
    if let Some(r) = &p.rotate {
        let n = (r.axis.iter().map(|a| a * a).sum::<f64>()).sqrt();
        if !(n > 0.0 && n.is_finite()) {
            return Err(err(
                format!("{f}.rotate.axis"),
                format!("expected a non-zero finite vector, got {:?}", r.axis),
            ));
        }
        if !r.angle.is_finite() {
            return Err(err(
                format!("{f}.rotate.angle"),
                format!("expected a finite angle in degrees, got {}", r.angle),
            ));
        }
        let k = r.axis.map(|a| a / n);
        let (s, c) = r.angle.to_radians().sin_cos();
        for x in mesh.coords.iter_mut() {
            let kx = [
                k[1] * x[2] - k[2] * x[1],
                k[2] * x[0] - k[0] * x[2],
                k[0] * x[1] - k[1] * x[0],
            ];
            let kd = k[0] * x[0] + k[1] * x[1] + k[2] * x[2];
            *x = [0, 1, 2].map(|i| x[i] * c + kx[i] * s + k[i] * kd * (1.0 - c));
        }
    }
    if let Some(t) = p.translate {
        if t.iter().any(|v| !v.is_finite()) {
            return Err(err(
                format!("{f}.translate"),
                format!("expected a finite vector, got {t:?}"),
            ));
        }
        for x in mesh.coords.iter_mut() {
            *x = [0, 1, 2].map(|i| x[i] + t[i]);
        }
    }
    Ok(())
}

fn part_mesh(m: &MeshDeck, f: &str, part: u32, deck_dir: &Path) -> Result<Mesh> {
    match m {
        MeshDeck::Box {
            origin,
            size,
            cells,
            grading,
            element,
            distort,
        } => {
            if origin.iter().any(|o| !o.is_finite()) {
                return Err(err(
                    format!("{f}.mesh.origin"),
                    format!("expected three finite coordinates, got {origin:?}"),
                ));
            }
            if size.iter().any(|&s| !(s > 0.0 && s.is_finite())) {
                return Err(err(
                    format!("{f}.mesh.size"),
                    format!("expected three positive lengths, got {size:?}"),
                ));
            }
            if cells.contains(&0) {
                return Err(err(
                    format!("{f}.mesh.cells"),
                    format!("expected three counts ≥ 1, got {cells:?}"),
                ));
            }
            size_guard(
                &format!("{f}.mesh.cells"),
                cells.iter().map(|&c| c as f64).product(),
            )?;
            if grading.iter().any(|&g| !(g > 0.0 && g.is_finite())) {
                return Err(err(
                    format!("{f}.mesh.grading"),
                    format!("expected positive ratios, got {grading:?}"),
                ));
            }
            if !(0.0..=0.3).contains(distort) {
                return Err(err(
                    format!("{f}.mesh.distort"),
                    format!("expected 0 ≤ distort ≤ 0.3, got {distort}"),
                ));
            }
            let kind = match element {
                ElementDeck::Hex8 => ElemKind::Hex8,
                ElementDeck::Tet4 => ElemKind::Tet4,
            };
            let spec = BoxSpec {
                origin: *origin,
                size: *size,
                cells: *cells,
                grading: *grading,
                kind,
            };
            let mut mesh = box_mesh(&spec, part);
            if *distort > 0.0 {
                distort_interior(&mut mesh, *distort, 12345);
            }
            Ok(mesh)
        }
        MeshDeck::ExtrudedQuad {
            corners,
            z0,
            thickness,
            cells,
            element,
        } => {
            if !(*thickness > 0.0 && thickness.is_finite()) {
                return Err(err(
                    format!("{f}.mesh.thickness"),
                    format!("expected a positive length, got {thickness}"),
                ));
            }
            if cells.contains(&0) {
                return Err(err(
                    format!("{f}.mesh.cells"),
                    format!("expected three counts ≥ 1, got {cells:?}"),
                ));
            }
            size_guard(
                &format!("{f}.mesh.cells"),
                cells.iter().map(|&c| c as f64).product(),
            )?;
            // Convex and counter-clockwise: every corner turns left.
            for i in 0..4 {
                let (a, b, c) = (corners[i], corners[(i + 1) % 4], corners[(i + 2) % 4]);
                let cross = (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0]);
                if cross.is_nan() || cross <= 0.0 {
                    return Err(err(
                        format!("{f}.mesh.corners"),
                        "expected a convex quadrilateral, corners counter-clockwise",
                    ));
                }
            }
            let kind = match element {
                ElementDeck::Hex8 => ElemKind::Hex8,
                ElementDeck::Tet4 => ElemKind::Tet4,
            };
            let spec = BoxSpec {
                origin: [0.0, 0.0, *z0],
                size: [1.0, 1.0, *thickness],
                cells: *cells,
                grading: [1.0; 3],
                kind,
            };
            let mut mesh = box_mesh(&spec, part);
            // Bilinear map: corners 0..3 at (ξ, η) = (0,0), (1,0), (1,1), (0,1).
            for x in &mut mesh.coords {
                let (s, t) = (x[0], x[1]);
                let w = [(1.0 - s) * (1.0 - t), s * (1.0 - t), s * t, (1.0 - s) * t];
                x[0] = (0..4).map(|i| w[i] * corners[i][0]).sum();
                x[1] = (0..4).map(|i| w[i] * corners[i][1]).sum();
            }
            Ok(mesh)
        }
        MeshDeck::Cylinder {
            radius,
            length,
            z0,
            cells_radial,
            cells_axial,
            axial_grading,
            sector,
        } => {
            let spec = CylinderSpec {
                radius: *radius,
                length: *length,
                z0: *z0,
                cells_radial: *cells_radial,
                cells_axial: *cells_axial,
                axial_grading: *axial_grading,
                quarter: *sector == SectorDeck::Quarter,
            };
            spec.check()
                .map_err(|(field, why)| err(format!("{f}.mesh.{field}"), why))?;
            // The butterfly section has about 3 cells_radial² cells.
            let section = 3.0 * (*cells_radial as f64).powi(2);
            size_guard(&format!("{f}.mesh.cells_radial"), section)?;
            size_guard(
                &format!("{f}.mesh.cells_axial"),
                section * *cells_axial as f64,
            )?;
            Ok(cylinder_mesh(&spec, part))
        }
        MeshDeck::Ring {
            inner_radius,
            outer_radius,
            thickness,
            z0,
            angles,
            cells,
            center,
        } => {
            let spec = RingSpec {
                inner_radius: *inner_radius,
                outer_radius: *outer_radius,
                thickness: *thickness,
                z0: *z0,
                angles: *angles,
                cells: *cells,
                center: *center,
            };
            spec.check()
                .map_err(|(field, why)| err(format!("{f}.mesh.{field}"), why))?;
            size_guard(
                &format!("{f}.mesh.cells"),
                cells.iter().map(|&c| c as f64).product(),
            )?;
            Ok(ring_mesh(&spec, part))
        }
        MeshDeck::Blocks {
            solids,
            holes,
            cell_size,
            refine,
        } => {
            if solids.is_empty() {
                return Err(err(format!("{f}.mesh.solids"), "expected at least one box"));
            }
            for (what, list) in [("solids", solids), ("holes", holes)] {
                for (i, b) in list.iter().enumerate() {
                    if (0..3)
                        .any(|a| !(b[0][a] < b[1][a] && b[0][a].is_finite() && b[1][a].is_finite()))
                    {
                        return Err(err(
                            format!("{f}.mesh.{what}[{i}]"),
                            format!(
                                "expected [[min x, y, z], [max x, y, z]] with min < max, got {b:?}"
                            ),
                        ));
                    }
                }
            }
            if !(*cell_size > 0.0 && cell_size.is_finite()) {
                return Err(err(
                    format!("{f}.mesh.cell_size"),
                    format!("expected a positive length, got {cell_size}"),
                ));
            }
            for (i, r) in refine.iter().enumerate() {
                if !(r.from < r.to && r.from.is_finite() && r.to.is_finite()) {
                    return Err(err(
                        format!("{f}.mesh.refine[{i}]"),
                        format!(
                            "expected finite from < to, got from = {}, to = {}",
                            r.from, r.to
                        ),
                    ));
                }
                if !(r.cell_size > 0.0 && r.cell_size.is_finite()) {
                    return Err(err(
                        format!("{f}.mesh.refine[{i}].cell_size"),
                        format!("expected a positive length, got {}", r.cell_size),
                    ));
                }
            }
            let spec = crate::mesh::blocks::BlocksSpec {
                solids: solids.clone(),
                holes: holes.clone(),
                cell_size: *cell_size,
                refine: refine
                    .iter()
                    .map(|r| crate::mesh::blocks::Slab {
                        axis: r.axis as usize,
                        range: [r.from, r.to],
                        cell_size: r.cell_size,
                    })
                    .collect(),
            };
            let n = crate::mesh::blocks::lattice_cells(&spec);
            if n > MAX_ELEMENTS {
                return Err(err(
                    format!("{f}.mesh.cell_size"),
                    format!("{cell_size} makes a lattice of {n:.3e} cells; expected at most {MAX_ELEMENTS:.0e}"),
                ));
            }
            let mesh = crate::mesh::blocks::blocks_mesh(&spec, part);
            if mesh.n_elems() == 0 {
                return Err(err(
                    format!("{f}.mesh.solids"),
                    "no cell lies in a solid and outside every hole",
                ));
            }
            Ok(mesh)
        }
        MeshDeck::Sheet {
            file,
            thickness,
            layers,
            offset,
        } => {
            if !(*thickness > 0.0 && thickness.is_finite()) {
                return Err(err(
                    format!("{f}.mesh.thickness"),
                    format!("expected a positive length, got {thickness}"),
                ));
            }
            if !(1..=64).contains(layers) {
                return Err(err(
                    format!("{f}.mesh.layers"),
                    format!("expected 1 to 64 elements through the thickness, got {layers}"),
                ));
            }
            let (path, text) = read_mesh_file(file, f, deck_dir)?;
            let in_file = |e: String| {
                err(
                    format!("{f}.mesh.file"),
                    format!("`{}`: {e}", path.display()),
                )
            };
            let surface = gmsh::read_surface(&text).map_err(in_file)?;
            let spec = crate::mesh::sheet::SheetSpec {
                thickness: *thickness,
                layers: *layers,
                offset: match offset {
                    SheetOffsetDeck::Middle => crate::mesh::sheet::Offset::Middle,
                    SheetOffsetDeck::AlongNormal => crate::mesh::sheet::Offset::AlongNormal,
                    SheetOffsetDeck::AgainstNormal => crate::mesh::sheet::Offset::AgainstNormal,
                },
            };
            crate::mesh::sheet::extrude(&surface, &spec, part).map_err(in_file)
        }
        MeshDeck::Gmsh { file } => {
            let (path, text) = read_mesh_file(file, f, deck_dir)?;
            let mut mesh = gmsh::read_msh(&text, part).map_err(|e| {
                err(
                    format!("{f}.mesh.file"),
                    format!("`{}`: {e}", path.display()),
                )
            })?;
            compact_unused_nodes(&mut mesh);
            if mesh.n_elems() == 0 {
                return Err(err(
                    format!("{f}.mesh.file"),
                    format!("`{}` has no hex8 or tet4 elements", path.display()),
                ));
            }
            Ok(mesh)
        }
    }
}

/// A mesh file's path (relative to the deck's directory) and text.
fn read_mesh_file(file: &str, f: &str, deck_dir: &Path) -> Result<(std::path::PathBuf, String)> {
    let path = if Path::new(file).is_absolute() {
        Path::new(file).to_path_buf()
    } else {
        deck_dir.join(file)
    };
    let bytes = std::fs::read(&path).map_err(|e| {
        err(
            format!("{f}.mesh.file"),
            format!("cannot read `{}`: {e}", path.display()),
        )
    })?;
    let text = String::from_utf8(bytes).map_err(|e| {
        let why = if e.as_bytes().starts_with(b"$MeshFormat") {
            "is a binary .msh file; alfe reads ASCII MSH 4.1 (gmsh -format msh41 -bin 0, Mesh.Binary = 0)"
        } else {
            "is not a text file (expected an ASCII Gmsh MSH 4.1 file)"
        };
        err(format!("{f}.mesh.file"), format!("`{}` {why}", path.display()))
    })?;
    Ok((path, text))
}

/// Drop nodes that no element uses (geometry points in Gmsh files): they would carry
/// no stiffness and make the system singular.
fn compact_unused_nodes(mesh: &mut Mesh) {
    let mut used = vec![false; mesh.n_nodes()];
    for &n in &mesh.conn {
        used[n] = true;
    }
    if used.iter().all(|&u| u) {
        return;
    }
    let mut map = vec![usize::MAX; used.len()];
    let mut coords = Vec::new();
    for (i, &u) in used.iter().enumerate() {
        if u {
            map[i] = coords.len();
            coords.push(mesh.coords[i]);
        }
    }
    mesh.coords = coords;
    for n in mesh.conn.iter_mut() {
        *n = map[*n];
    }
    for v in mesh.node_groups.values_mut() {
        *v = v
            .iter()
            .filter(|&&n| map[n] != usize::MAX)
            .map(|&n| map[n])
            .collect();
    }
}

/// A material deck entry → its definition, checking the fields its model needs and
/// refusing the ones it does not use.
fn material_def(m: &MaterialDeck, f: &str, deck: &Deck) -> Result<MaterialDef> {
    let model = m.model.name();
    let positive = |name: &str, v: Option<f64>| -> Result<f64> {
        match v {
            None => Err(err(
                format!("{f}.{name}"),
                format!("model `{model}` needs {name}"),
            )),
            Some(v) if v > 0.0 && v.is_finite() => Ok(v),
            Some(v) => Err(err(
                format!("{f}.{name}"),
                format!("expected a positive value, got {v}"),
            )),
        }
    };
    let unused = |name: &str, given: bool| -> Result<()> {
        if given {
            Err(err(
                format!("{f}.{name}"),
                format!("is not a parameter of model `{model}`"),
            ))
        } else {
            Ok(())
        }
    };
    let nu = m.nu;
    if !(nu > -1.0 && nu < 0.5) {
        return Err(err(
            format!("{f}.nu"),
            format!("expected -1 < nu < 0.5, got {nu}"),
        ));
    }
    if !(m.density >= 0.0 && m.density.is_finite()) {
        return Err(err(
            format!("{f}.density"),
            format!("expected ≥ 0, got {}", m.density),
        ));
    }
    let density = m.density;
    let plastic_unused = || -> Result<()> {
        unused("yield_stress", m.yield_stress.is_some())?;
        unused("hardening", m.hardening.is_some())
    };
    Ok(match m.model {
        MaterialModel::LinearElastic | MaterialModel::NeoHookean => {
            let e = positive("E", m.e)?;
            unused("C10", m.c10.is_some())?;
            unused("C01", m.c01.is_some())?;
            plastic_unused()?;
            if m.model == MaterialModel::LinearElastic {
                MaterialDef::LinearElastic { e, nu, density }
            } else {
                MaterialDef::NeoHookean { e, nu, density }
            }
        }
        MaterialModel::MooneyRivlin => {
            unused("E", m.e.is_some())?;
            plastic_unused()?;
            let c10 = m
                .c10
                .ok_or_else(|| err(format!("{f}.C10"), "model `mooney-rivlin` needs C10"))?;
            let c01 = m.c01.unwrap_or(0.0);
            if !(c10.is_finite() && c01.is_finite() && c10 + c01 > 0.0 && c10 >= 0.0 && c01 >= 0.0)
            {
                return Err(err(
                    format!("{f}.C10"),
                    format!(
                        "expected C10 ≥ 0, C01 ≥ 0 and C10 + C01 > 0, got C10 = {c10}, C01 = {c01}"
                    ),
                ));
            }
            MaterialDef::MooneyRivlin {
                c10,
                c01,
                nu,
                density,
            }
        }
        MaterialModel::J2 => {
            let e = positive("E", m.e)?;
            unused("C10", m.c10.is_some())?;
            unused("C01", m.c01.is_some())?;
            let sigma_y0 = positive("yield_stress", m.yield_stress)?;
            let hf = format!("{f}.hardening");
            let hardening = match &m.hardening {
                None => Hardening::Linear { sigma_y0, h: 0.0 },
                Some(HardeningDeck::Linear { modulus }) => Hardening::Linear {
                    sigma_y0,
                    h: *modulus,
                },
                Some(HardeningDeck::Power { k, n }) => Hardening::Power {
                    sigma_y0,
                    k: *k,
                    n: *n,
                },
                Some(HardeningDeck::Table { points, curve }) => {
                    let pts = match (points, curve) {
                        (Some(p), None) => p.clone(),
                        (None, Some(name)) => deck
                            .curves
                            .iter()
                            .find(|c| &c.name == name)
                            .map(|c| c.points.clone())
                            .ok_or_else(|| {
                                err(format!("{hf}.curve"), format!("unknown curve `{name}`"))
                            })?,
                        _ => {
                            return Err(err(
                                &hf,
                                "a table needs exactly one of `points` or `curve`",
                            ))
                        }
                    };
                    if let Some(first) = pts.first() {
                        if (first[1] - sigma_y0).abs() > 1e-12 * sigma_y0 {
                            return Err(err(
                                &hf,
                                format!(
                                    "the table starts at σ_y = {} but yield_stress is {sigma_y0}",
                                    first[1]
                                ),
                            ));
                        }
                    }
                    Hardening::Tabulated { points: pts }
                }
            };
            hardening.validate().map_err(|why| err(&hf, why))?;
            MaterialDef::J2 {
                e,
                nu,
                hardening,
                density,
            }
        }
    })
}

/// A part's element formulation with its hourglass coefficient; `hourglass` is refused
/// where no hourglass spring exists (standard hex8) and must be finite and ≥ 0.
///
/// `auto` takes the hybrid element for nearly incompressible hyperelastic parts in static
/// and implicit analyses (Newton converges there as on compressible solids: rubber-indent
/// newton 412 → 144 iterations, cook-membrane 83 → 16; README "Hybrid elements"), F-bar
/// for them in explicit runs and for plastic parts (J2 gains nothing from the pressure
/// unknown: plastic-bar 113 → 130 iterations), standard hex8 otherwise.
fn part_formulation_of(
    p: &PartDeck,
    material: &MaterialDef,
    field: &str,
    explicit: bool,
) -> Result<Formulation> {
    let form = match p.formulation {
        FormulationDeck::Standard => Formulation::Standard,
        FormulationDeck::Fbar => Formulation::FBAR,
        FormulationDeck::Reduced => Formulation::REDUCED,
        FormulationDeck::Eas => Formulation::Eas,
        FormulationDeck::Hybrid => {
            if !material.has_volumetric_split() {
                return Err(err(
                    format!("{field}.formulation"),
                    "the hybrid element needs a finite-strain material with a volumetric \
                     part (neo-hookean, mooney-rivlin, j2); this part's is linear-elastic",
                ));
            }
            if explicit {
                return Err(err(
                    format!("{field}.formulation"),
                    "the hybrid element's pressure unknowns need a static or implicit \
                     analysis; an explicit run takes formulation = \"fbar\"",
                ));
            }
            Formulation::Hybrid { hourglass: 0.0 }
        }
        FormulationDeck::Auto if material.wants_hybrid() && !explicit => {
            Formulation::Hybrid { hourglass: 0.0 }
        }
        FormulationDeck::Auto if material.wants_fbar() => Formulation::FBAR,
        FormulationDeck::Auto => Formulation::Standard,
    };
    let Some(h) = p.hourglass else {
        return Ok(form);
    };
    if !(h.is_finite() && h >= 0.0) {
        return Err(err(
            format!("{field}.hourglass"),
            format!("expected a finite number ≥ 0, got {h}"),
        ));
    }
    match form {
        Formulation::FBar { .. } => Ok(Formulation::FBar { hourglass: h }),
        Formulation::Reduced { .. } => Ok(Formulation::Reduced { hourglass: h }),
        Formulation::Hybrid { .. } => Ok(Formulation::Hybrid { hourglass: h }),
        Formulation::Standard | Formulation::Eas => Err(err(
            format!("{field}.hourglass"),
            "only F-bar, hybrid and reduced hex8 have an hourglass spring; this part's \
             elements are standard or EAS (set formulation = \"fbar\", \"hybrid\" or \
             \"reduced\")",
        )),
    }
}
