//! `alfe check` and `alfe partition`: what a deck builds into (model size, elements,
//! unknowns, walls and their initial gaps, partition quality), without running it.

use crate::model::def::ModelDef;
use crate::partition::{cache, quality};
use crate::scene::{RunSettings, Scene};
use crate::solve::Analysis;
use crate::{Error, Result};

/// `alfe check`: validate and report the model size and partition quality (serial).
pub fn check(target: &str, ranks: usize, o: &crate::scene::Overrides) -> Result<String> {
    check_source(&crate::scene::load(target)?, ranks, o)
}

/// [`check`] of a deck's text (the deck fuzzer calls it for thousands of decks).
pub fn check_source(
    src: &crate::scene::Source,
    ranks: usize,
    o: &crate::scene::Overrides,
) -> Result<String> {
    let scene = crate::scene::read_with(src, o)?;
    let def = &scene.model;
    let mut s = describe(def, &scene.run);
    if ranks > 1 {
        let edges = def.coupling_edges();
        let part = def.partition_request(&edges).compute(ranks)?;
        s.push_str(&describe_partition(def, &part, ranks)?);
    }
    Ok(s)
}

fn describe(def: &ModelDef, run: &RunSettings) -> String {
    let m = &def.mesh;
    let mut kinds = std::collections::BTreeMap::new();
    for k in &m.kinds {
        *kinds.entry(k.name()).or_insert(0usize) += 1;
    }
    let kinds: Vec<String> = kinds.iter().map(|(k, n)| format!("{n} {k}")).collect();
    let extra: usize = def
        .contributions
        .iter()
        .map(|c| c.kind().extra_unknowns())
        .sum();
    // A hybrid element's pressure takes a block of three unknowns (one used), and so
    // does a hybrid tet4 patch's.
    let hybrid_elements = (0..m.n_elems())
        .filter(|&e| {
            let form = def.elem_formulation(e);
            form.is_hybrid() && crate::fem::element::kernel(m.kinds[e], form).own_blocks() > 0
        })
        .count();
    let hybrid_patches: std::collections::BTreeSet<u32> = (0..m.n_elems())
        .filter(|&e| def.elem_formulation(e).is_hybrid())
        .filter_map(|e| def.elem_patch.get(e).copied().filter(|&p| p != u32::MAX))
        .collect();
    let hybrid = hybrid_elements + hybrid_patches.len();
    let mut parts_of = Vec::new();
    if extra > 0 {
        parts_of.push(format!("{extra} multipliers and reference-point DOFs"));
    }
    if hybrid > 0 {
        parts_of.push(format!(
            "{} element pressure blocks ({hybrid} pressures)",
            3 * hybrid
        ));
    }
    let unknowns = if parts_of.is_empty() {
        format!("{} (3 per node)", 3 * m.n_nodes())
    } else {
        format!(
            "{} ({} node displacements, {})",
            3 * m.n_nodes() + extra + 3 * hybrid,
            3 * m.n_nodes(),
            parts_of.join(", ")
        )
    };
    // Each part's element types and the formulation each gets (scene/parts.rs).
    let parts: String = run.parts.iter().map(|p| format!("\n    {p}")).collect();
    let mut s = format!(
        "scene {}: valid\n  units: {}\n  parts:{}\n  nodes: {}\n  elements: {} ({})\n  unknowns: {unknowns}\n  supports: {}\n  node sets: {}\n  surfaces: {}\n  steps: {}\n",
        run.name,
        run.units.describe(),
        parts,
        m.n_nodes(),
        m.n_elems(),
        kinds.join(", "),
        def.constraints.len(),
        or_none(def.node_sets.iter().map(|(k, v)| format!("{k} ({} nodes)", v.len())).collect()),
        or_none(def.surfaces.iter().map(|(k, v)| format!("{k} ({} faces)", v.len())).collect()),
        nominal_steps(&run.analysis),
    );
    for w in &run.warnings {
        s.push_str(&format!("  warning: {w}\n"));
    }
    s.push_str(&format!("  contributions: {}\n", def.contributions.len()));
    for c in &def.contributions {
        s.push_str(&format!("    {}\n", c.kind().describe()));
        if let Some(more) = c.kind().initial_state(&m.coords) {
            s.push_str(&format!("      {more}\n"));
        }
    }
    s
}

/// A list joined by commas, or "none".
fn or_none(items: Vec<String>) -> String {
    if items.is_empty() {
        "none".into()
    } else {
        items.join(", ")
    }
}

/// Steps at the deck's step size ("from the mesh" for explicit runs without one).
pub(super) fn nominal_steps(a: &Analysis) -> String {
    if !a.stages.is_empty() {
        let each: Vec<usize> = a
            .stages
            .iter()
            .map(|s| crate::solve::control::step_times(s.end - s.start, s.step).len())
            .collect();
        let names: Vec<String> = a
            .stages
            .iter()
            .zip(&each)
            .map(|(s, n)| format!("{} {n}", s.name))
            .collect();
        return format!("{} ({})", each.iter().sum::<usize>(), names.join(", "));
    }
    if a.step > 0.0 {
        crate::solve::control::step_times(a.end_time, a.step)
            .len()
            .to_string()
    } else {
        "(time step from the mesh)".into()
    }
}

fn describe_partition(def: &ModelDef, part: &[u32], ranks: usize) -> Result<String> {
    let q = quality(&def.mesh, part, ranks)?;
    let owner = crate::partition::node_owner(&def.mesh, part);
    let mut s = format!("partition over {ranks} ranks ({}):\n  edge cut: {} faces\n  imbalance: {:.3} (max/mean elements)\n", def.partition.describe(), q.edge_cut, q.imbalance);
    for r in 0..ranks {
        s.push_str(&format!(
            "  rank {r}: {} elements, {} owned nodes ({} unknowns), {} ghost nodes\n",
            q.elements_per_rank[r],
            q.owned_nodes_per_rank[r],
            3 * q.owned_nodes_per_rank[r],
            q.ghost_nodes_per_rank[r]
        ));
    }
    for (name, faces) in &def.surfaces {
        let mut rs: Vec<u32> = faces.iter().map(|f| part[f.elem]).collect();
        rs.sort_unstable();
        rs.dedup();
        s.push_str(&format!(
            "  surface {name} on rank(s) {}\n",
            rs.iter()
                .map(|r| r.to_string())
                .collect::<Vec<_>>()
                .join(",")
        ));
    }
    for c in &def.contributions {
        let nodes = c.kind().nodes();
        if nodes.is_empty() {
            continue;
        }
        let mut rs: Vec<u32> = nodes.iter().map(|&n| owner[n]).collect();
        rs.sort_unstable();
        rs.dedup();
        s.push_str(&format!(
            "  {} {}: nodes owned by rank(s) {}\n",
            c.kind().kind_name(),
            c.kind().name(),
            rs.iter()
                .map(|r| r.to_string())
                .collect::<Vec<_>>()
                .join(",")
        ));
    }
    for (name, nodes) in &def.node_sets {
        let mut rs: Vec<u32> = nodes.iter().map(|&n| owner[n]).collect();
        rs.sort_unstable();
        rs.dedup();
        s.push_str(&format!(
            "  set {name} owned by rank(s) {}\n",
            rs.iter()
                .map(|r| r.to_string())
                .collect::<Vec<_>>()
                .join(",")
        ));
    }
    Ok(s)
}

/// `alfe partition`: compute the METIS partition and write it to the cache directory.
pub fn partition(target: &str, ranks: usize, dir: &std::path::Path) -> Result<String> {
    if ranks < 2 {
        return Err(Error::input(
            "--ranks: expected 2 or more (one rank needs no partition)",
        ));
    }
    let src = crate::scene::load(target)?;
    let Scene { model: def, run } = crate::scene::read(&src)?;
    let edges = def.coupling_edges();
    let req = def.partition_request(&edges);
    let part = req.compute(ranks)?;
    let file = cache::path(dir, &run.name, ranks, &req);
    cache::write(&file, &req, ranks, &part)?;
    Ok(format!(
        "wrote {}\n{}",
        file.display(),
        describe_partition(&def, &part, ranks)?
    ))
}
