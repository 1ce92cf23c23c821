//! Small-sliding pairs, bolts, couplings and analysis steps in an LS-DYNA `.k`.
//!
//! A frictional pair is a `*CONTACT_SURFACE_TO_SURFACE` (FS = FD = μ, SFS the penalty
//! scale), a tied one a `*CONTACT_TIED_SURFACE_TO_SURFACE`: the tracked side is the slave
//! (a segment set, or a node set with SSTYP 4), the reference side the master segment
//! set. A bolt is its cut tied across (`*CONTACT_TIED_SURFACE_TO_SURFACE`) plus an
//! `*INITIAL_STRESS_SECTION` on a `*DATABASE_CROSS_SECTION_SET` of the cut's nodes whose
//! LCID is the pretension's curve; LS-DYNA's preload is a stress, alfe's a force, so the
//! force, the lock time and the cut's two surfaces ride on `$alfe` notes. A coupling is a
//! `*CONSTRAINED_INTERPOLATION` (its dependent node a new node at the reference point,
//! independent the coupled nodes) with `*LOAD_NODE_POINT` and
//! `*BOUNDARY_PRESCRIBED_MOTION_NODE` on that node. LS-DYNA has one time line: the
//! model's curves are already on it (a step-relative curve was resolved when the scene
//! was built), and the steps (names, durations, increments) ride on `$alfe step` notes
//! after `*CONTROL_TERMINATION`. What alfe chooses and LS-DYNA has no field for (the
//! contact method, κ, tangential augmentation, friction threshold, search distance,
//! node-to-face weights) is written on `$alfe` notes only when it is not the default.

use super::lsdyna_cards::{card, r, Numbering};
use crate::contact::law::{Threshold, DEFAULT_TANGENTIAL_AUGMENTATION};
use crate::contact::wall::ContactMethod;
use crate::model::coupling::{CouplingDef, Dof};
use crate::model::def::ContributionDef;
use crate::model::pairs::PairsDef;
use crate::scene::Scene;
use std::collections::BTreeMap;
use std::fmt::Write;

fn ints(out: &mut String, v: &[i64]) {
    for x in v {
        let _ = write!(out, "{x:>10}");
    }
    out.push('\n');
}

/// A deck string, quoted as TOML (names may hold any character).
fn q(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

/// Pairs, bolts and couplings of `scene`; `surface_ids` numbers the segment sets.
pub fn write(
    out: &mut String,
    scene: &Scene,
    surface_ids: &BTreeMap<&str, usize>,
    ids: &mut dyn Numbering,
) {
    let m = &scene.model;
    let mut section = 0;
    let mut coupling = 0;
    for c in &m.contributions {
        match c {
            ContributionDef::Pairs(p) if p.pretension.is_some() => {
                section += 1;
                write_bolt(out, scene, p, section, surface_ids, ids);
            }
            ContributionDef::Pairs(p) => write_contact(out, scene, p, surface_ids, ids, None),
            ContributionDef::Coupling(cp) => {
                coupling += 1;
                let nid = m.mesh.n_nodes() + coupling;
                write_coupling(out, cp, coupling, nid, ids);
            }
            _ => {}
        }
    }
}

/// The contact card of a pair (the tie of a bolt's cut with `bolt` its name).
fn write_contact(
    out: &mut String,
    scene: &Scene,
    p: &PairsDef,
    surface_ids: &BTreeMap<&str, usize>,
    ids: &mut dyn Numbering,
    bolt: Option<&str>,
) {
    let m = &scene.model;
    let (ssid, sstyp) = match surface_ids.get(p.tracked.as_str()) {
        Some(&s) if !m.node_sets.contains_key(&p.tracked) => (s, 0),
        _ => {
            let nodes = m.node_sets.get(&p.tracked).cloned().unwrap_or_default();
            (ids.set(&p.tracked, &nodes), 4)
        }
    };
    let msid = surface_ids.get(p.reference.as_str()).copied().unwrap_or(0);
    let kw = if p.tied {
        "TIED_SURFACE_TO_SURFACE"
    } else {
        "SURFACE_TO_SURFACE"
    };
    let _ = writeln!(out, "*CONTACT_{kw} +");
    match bolt {
        Some(b) => {
            let _ = writeln!(out, "$alfe section = {}", q(b));
        }
        None => {
            let _ = writeln!(out, "$alfe name = {}", q(&p.name));
            pair_notes(out, p, sstyp == 0);
        }
    }
    card(
        out,
        &[ssid, msid, sstyp, 0, 0, 0, 1, 1].map(|x| x.to_string()),
    );
    let mu = r(p.friction);
    let zero = r(0.0);
    card(
        out,
        &[
            mu.clone(),
            mu,
            zero.clone(),
            zero.clone(),
            zero.clone(),
            "0".into(),
            zero,
            r(1e20),
        ],
    );
    card(out, &[r(p.penalty_scale), r(p.penalty_scale)]);
}

/// `$alfe` notes for a pair's choices LS-DYNA has no field for (defaults left out).
fn pair_notes(out: &mut String, p: &PairsDef, tracked_surface: bool) {
    if p.method == ContactMethod::Penalty {
        out.push_str("$alfe method = \"penalty\"\n");
    }
    if let Some(k) = p.kappa {
        let _ = writeln!(out, "$alfe kappa = {k:e}");
    }
    if p.tangential_augmentation != DEFAULT_TANGENTIAL_AUGMENTATION {
        let _ = writeln!(
            out,
            "$alfe tangential_augmentation = {:e}",
            p.tangential_augmentation
        );
    }
    if p.friction_threshold != Threshold::default() {
        let _ = writeln!(
            out,
            "$alfe friction_threshold = {}",
            serde_json::to_string(&p.friction_threshold).unwrap_or_default()
        );
    }
    if let Some(s) = p.search_distance {
        let _ = writeln!(out, "$alfe search_distance = {s:e}");
    }
    if tracked_surface && !p.mortar {
        out.push_str("$alfe weights = \"node\"\n");
    }
}

fn write_bolt(
    out: &mut String,
    scene: &Scene,
    p: &PairsDef,
    k: usize,
    surface_ids: &BTreeMap<&str, usize>,
    ids: &mut dyn Numbering,
) {
    let Some(pre) = &p.pretension else { return };
    write_contact(out, scene, p, surface_ids, ids, Some(&p.name));
    let mut cut: Vec<usize> = p.pairs.iter().map(|x| x.node).collect();
    cut.sort_unstable();
    let nsid = ids.set(&format!("{}-section", p.name), &cut);
    out.push_str("*DATABASE_CROSS_SECTION_SET\n");
    ints(out, &[k as i64, nsid as i64, 0, 0, 0, 0, 0, 0, 0]);
    let lcid = ids.curve(&pre.curve);
    out.push_str("*INITIAL_STRESS_SECTION\n");
    let _ = writeln!(
        out,
        "$ alfe's pretension is a force (below): LCID is its curve, not a stress"
    );
    let _ = writeln!(
        out,
        "$alfe name = {}\n$alfe tracked = {}\n$alfe reference = {}\n$alfe force = {:e}\n$alfe lock_at = {:e}",
        q(&p.name),
        q(&p.tracked),
        q(&p.reference),
        pre.force,
        pre.lock_at
    );
    if let Some(kappa) = p.kappa {
        let _ = writeln!(out, "$alfe kappa = {kappa:e}");
    }
    if let Some(s) = p.search_distance {
        let _ = writeln!(out, "$alfe search_distance = {s:e}");
    }
    ints(out, &[k as i64, k as i64, lcid as i64, 0, 0, 0, 0]);
}

fn write_coupling(
    out: &mut String,
    c: &CouplingDef,
    k: usize,
    nid: usize,
    ids: &mut dyn Numbering,
) {
    out.push_str("*NODE +\n");
    card(
        out,
        &[nid.to_string(), r(c.point[0]), r(c.point[1]), r(c.point[2])],
    );
    let inid = ids.set(&format!("{}-coupled", c.name), &c.nodes);
    out.push_str("*CONSTRAINED_INTERPOLATION\n");
    // Equal weights: "uniform" (on a surface of equal areas the same coupling).
    let uniform = c.weights.iter().all(|&w| w == 1.0);
    let _ = writeln!(
        out,
        "$alfe name = {}\n$alfe nodes = {}\n$alfe weights = \"{}\"",
        q(&c.name),
        q(&c.set),
        if uniform { "uniform" } else { "area" }
    );
    ints(out, &[k as i64, nid as i64, 123456, 0, 1, 0]);
    out.push_str(&format!("{inid:>10}{:>10}", 123));
    for _ in 0..6 {
        out.push_str(&format!("{:>10}", "1.0"));
    }
    out.push('\n');
    for (d, dof) in c.dofs.iter().enumerate() {
        // LS-DYNA's DOF: 1-3 translations, 5-7 rotations.
        let ldof = if d < 3 { d + 1 } else { d + 2 };
        match dof {
            Dof::Free {
                load: Some((v, curve)),
            } => {
                let lcid = ids.curve(curve);
                out.push_str("*LOAD_NODE_POINT +\n");
                card(
                    out,
                    &[nid.to_string(), ldof.to_string(), lcid.to_string(), r(*v)],
                );
            }
            Dof::Prescribed { value, curve } => {
                let lcid = ids.curve(curve);
                out.push_str("*BOUNDARY_PRESCRIBED_MOTION_NODE +\n");
                card(
                    out,
                    &[
                        nid.to_string(),
                        ldof.to_string(),
                        "2".into(),
                        lcid.to_string(),
                        r(*value),
                    ],
                );
            }
            Dof::Free { load: None } => {}
        }
    }
}

/// The analysis steps as `$alfe step` notes (to follow `*CONTROL_TERMINATION`).
pub fn write_steps(out: &mut String, scene: &Scene) {
    let run = &scene.run;
    for (k, s) in run.analysis.stages.iter().enumerate() {
        let every = run
            .output
            .stage_every
            .get(k)
            .copied()
            .unwrap_or(run.output.every);
        let _ = writeln!(
            out,
            "$alfe step = {{ name = {}, duration = {:e}, step = {:e}, min_step = {:e}, max_step = {:e}, output_every = {every} }}",
            q(&s.name),
            s.end - s.start,
            s.step,
            s.min_step,
            s.max_step
        );
    }
}
