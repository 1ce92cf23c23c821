//! Deck → [`ModelDef`]: a short pipeline of sections, each in its own module, that
//! builds or reads the part meshes, resolves sets, surfaces and curves into one
//! [`Context`], and hands it to the constraints, loads, walls, entities, couplings, pairs
//! and bolts; every check names the deck field and what was expected.

use super::check::{err, unique_names};
use super::context::Context;
use super::deck::*;
use super::{coupling, dynamics, loads, pairs, parts, sanity, sets, settings, steps, walls, Scene};
use crate::mesh::select::bounding_box;
use crate::model::def::*;
use crate::Result;
use std::collections::BTreeMap;
use std::path::Path;

pub use super::settings::{amg_unsuited, AUTO_AMG_MAX_NU};

/// Build and validate the model and its run settings. `deck_dir` resolves relative
/// mesh file paths.
pub fn build(deck: &Deck, deck_dir: &Path) -> Result<Scene> {
    let deck = &steps::with_end_time(deck)?;
    check_names(deck)?;
    let materials = parts::materials(deck)?;
    let parts = parts::parts(deck, &materials, deck_dir)?;
    let (bmin, bmax) = bounding_box(&parts.mesh);
    let diag = ((0..3).map(|i| (bmax[i] - bmin[i]).powi(2)).sum::<f64>()).sqrt();
    let boundary = parts.mesh.boundary_faces();
    let node_sets = sets::node_sets(deck, &parts, 1e-9 * diag.max(1e-300), (bmin, bmax))?;
    let surfaces = sets::surfaces(deck, &parts, &boundary, 1e-9 * diag.max(1e-300))?;
    let curves = sets::curves(deck)?;
    check_end_time(deck)?;
    dynamics::check_analysis(deck)?;
    let timeline = steps::Timeline::new(steps::stages(deck)?, &curves, deck.analysis.end_time);
    let part_names: Vec<String> = deck.parts.iter().map(|p| p.name.clone()).collect();
    let ctx = Context {
        mesh: &parts.mesh,
        boundary: &boundary,
        part_names: &part_names,
        part_nodes: &parts.nodes,
        node_sets: &node_sets,
        surfaces: &surfaces,
        timeline: &timeline,
        analysis: deck.analysis.kind,
        end_time: deck.analysis.end_time,
        tol: 1e-8 * diag.max(1e-300),
    };
    // Every set a section names, resolved to its nodes, for the model.
    let mut resolved = node_sets.clone();
    let constraints = loads::constraints(deck, &ctx, &mut resolved)?;
    let load_defs = loads::loads(deck, &ctx, &mut resolved)?;
    settings::check_solver(deck)?;
    let initial_velocity = dynamics::initial_velocities(deck, &ctx, &mut resolved)?;
    dynamics::check_dynamic_inputs(deck, &parts.material, &ctx, &mut resolved)?;
    let reaction_sets = loads::reaction_sets(deck, &ctx, &constraints, &mut resolved)?;
    let walls = walls::build_walls(&deck.walls, &ctx, "walls")?;
    let entities = walls::build_walls(&deck.entities, &ctx, "entities")?;
    check_entities(deck)?;
    check_amg_refusals(deck)?;
    let couplings = coupling::build_couplings(&deck.couplings, &ctx)?;
    let pairs = pairs::build_pairs(&deck.pairs, &ctx)?;
    let bolts = pairs::build_bolts(&deck.bolts, &ctx)?;
    check_column_names(deck, &reaction_sets)?;
    let mut contributions: Vec<ContributionDef> =
        load_defs.into_iter().map(ContributionDef::Load).collect();
    contributions.extend(walls.into_iter().map(ContributionDef::Wall));
    contributions.extend(entities.into_iter().map(ContributionDef::Wall));
    contributions.extend(couplings.into_iter().map(ContributionDef::Coupling));
    contributions.extend(pairs.into_iter().map(ContributionDef::Pairs));
    contributions.extend(bolts.into_iter().map(ContributionDef::Pairs));
    let (part_descriptions, mut warnings) = (parts.descriptions, parts.warnings);
    let walls_now: Vec<crate::model::walls::WallDef> = contributions
        .iter()
        .filter_map(|c| match c {
            ContributionDef::Wall(w) => Some(w.clone()),
            _ => None,
        })
        .collect();
    warnings.extend(sanity::warnings(
        deck,
        &parts.mesh,
        &resolved,
        &constraints,
        &walls_now,
    ));
    let elem_patch = fbar_patches(&parts.mesh, &parts.formulation)?;
    let model = ModelDef {
        elem_patch,
        partition: settings::partition_method(deck)?,
        contributions,
        mesh: parts.mesh,
        part_names,
        part_material: parts.material,
        part_formulation: parts.formulation,
        materials,
        node_sets: resolved,
        surfaces,
        constraints,
        reaction_sets,
        displacement_sets: deck.output.displacements.clone(),
        peak_stress_parts: settings::peak_stress_parts(deck)?,
        initial_velocity,
    };
    let mut run = settings::run_settings(deck, &timeline);
    run.quantities = settings::quantities(deck)?;
    run.parts = part_descriptions;
    run.warnings = warnings;
    Ok(Scene { model, run })
}

/// The F-bar patches of the tet4 that take F-bar ([`crate::fem::element::in_patch`]),
/// formed on the whole mesh so that they do not depend on the rank count; empty if none.
fn fbar_patches(
    mesh: &crate::mesh::Mesh,
    part_formulation: &[crate::fem::element::Formulation],
) -> Result<Vec<u32>> {
    let member: Vec<bool> = (0..mesh.n_elems())
        .map(|e| {
            let form = part_formulation[mesh.elem_part[e] as usize];
            crate::fem::element::in_patch(mesh.kinds[e], form)
        })
        .collect();
    if !member.contains(&true) {
        return Ok(Vec::new());
    }
    use crate::mesh::patches::{form, PATCH_ELEMENTS};
    form(mesh, &member, PATCH_ELEMENTS).map_err(crate::Error::runtime)
}

/// The scene's name (it becomes file names) and every list's names, each used once.
fn check_names(deck: &Deck) -> Result<()> {
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
    unique_names("curves", deck.curves.iter().map(|m| m.name.as_str()))
}

/// `[analysis] end_time`: positive and finite.
fn check_end_time(deck: &Deck) -> Result<()> {
    let a = &deck.analysis;
    if a.end_time == 0.0 {
        return Err(err(
            "analysis.end_time",
            "missing: give the end of the load path (the pseudo-time of a static run, the time of a dynamic one), or [[steps]] whose durations add up to it",
        ));
    }
    if !(a.end_time > 0.0 && a.end_time.is_finite()) {
        return Err(err(
            "analysis.end_time",
            format!(
                "expected a positive time (or [[steps]] whose durations add up to it), got {}",
                a.end_time
            ),
        ));
    }
    Ok(())
}

/// Contact entities: in static analyses and implicit dynamics only, without inertia in
/// static ones, and not with AMG.
fn check_entities(deck: &Deck) -> Result<()> {
    if deck.entities.is_empty() {
        return Ok(());
    }
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
             unknowns coupled to all their tracked nodes; use \"two-level\" (the default on more than one rank), \"asm\" or \"block-jacobi\"",
        ));
    }
    Ok(())
}

/// `preconditioner = "amg"` refused where its matrix is not elliptic.
fn check_amg_refusals(deck: &Deck) -> Result<()> {
    if (!deck.pairs.is_empty() || !deck.bolts.is_empty())
        && deck.solver.linear.preconditioner == crate::linalg::PcKind::Amg
    {
        return Err(err(
            "[solver.linear] preconditioner",
            "\"amg\" needs an elliptic matrix, but [[pairs]] and [[bolts]] couple each \
             multiplier to a node and a reference face on another part (measured on \
             two-body-hertz: a condensed diagonal turns negative); use \"two-level\" (the default on more than one rank), \"asm\" or \"block-jacobi\"",
        ));
    }
    if !deck.couplings.is_empty() && deck.solver.linear.preconditioner == crate::linalg::PcKind::Amg
    {
        return Err(err(
            "[solver.linear] preconditioner",
            "\"amg\" needs an elliptic matrix, but the [[couplings]] add constraint \
             multipliers that cannot be condensed node by node; use \"two-level\" (the default on more than one rank), \"asm\" or \"block-jacobi\"",
        ));
    }
    Ok(())
}

/// Walls and couplings name history columns (`<name>.fx`), as reaction and displacement
/// sets do: a name may stand for one of them only.
fn check_column_names(deck: &Deck, reaction_sets: &[String]) -> Result<()> {
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
    Ok(())
}
