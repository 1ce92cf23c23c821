//! Small-sliding pairs, bolts, couplings and analysis steps in a CalculiX/Abaqus `.inp`.
//!
//! A frictional pair is a `*CONTACT PAIR, TYPE=SURFACE TO SURFACE, SMALL SLIDING` with
//! its `*SURFACE INTERACTION` (linear penalty K = 10 E/h, `*FRICTION`), a tied one a
//! `*TIE`; a bolt its cut tied across plus a `*PRE-TENSION SECTION` on the tracked cut
//! surface with a new reference node loaded by the force (`*CLOAD` on an amplitude)
//! until it locks, then held (`*BOUNDARY, FIXED`); a coupling a `*COUPLING` with
//! `*DISTRIBUTING` and a new reference node loaded by `*CLOAD` or driven by `*BOUNDARY`;
//! the steps several `*STEP`s, every curve an `*AMPLITUDE, TIME=TOTAL TIME`. The
//! exact alfe entry rides before each on an `** alfe` comment line (CalculiX skips
//! them; `alfe import` reads them), since CalculiX has no field for κ, the contact
//! method, the pairing or a force-driven lock.

use crate::curve::Curve;
use crate::model::coupling::{CouplingDef, Dof};
use crate::model::def::ContributionDef;
use crate::model::pairs::PairsDef;
use crate::scene::Scene;
use std::fmt::Write;

/// The model part of the file, and per analysis step what it adds to the step.
pub struct Written {
    pub model: String,
    /// Per step: its `*STEP` header lines (notes, `*STEP`, `*STATIC` and its numbers,
    /// NLGEOM to be filled in by the caller as `{NLGEOM}`), then its extra loads.
    pub steps: Vec<(String, String)>,
}

fn q(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

fn opt(key: &str, v: Option<f64>) -> String {
    v.map_or(String::new(), |x| format!(", {key} = {x:e}"))
}

/// The pair as an inline `[[pairs]]` table.
fn pair_entry(p: &PairsDef, tracked_surface: bool) -> String {
    format!(
        "{{ name = {}, tracked = {}, reference = {}, method = {}, tied = {}, friction = {:e}, penalty_scale = {:e}, tangential_augmentation = {:e}, friction_threshold = {}{}{}, weights = \"{}\" }}",
        q(&p.name),
        q(&p.tracked),
        q(&p.reference),
        serde_json::to_string(&p.method).unwrap_or_default(),
        p.tied,
        p.friction,
        p.penalty_scale,
        p.tangential_augmentation,
        serde_json::to_string(&p.friction_threshold).unwrap_or_default(),
        opt("kappa", p.kappa),
        opt("search_distance", p.search_distance),
        if p.mortar && tracked_surface { "mortar" } else { "node" }
    )
}

struct Curves(Vec<Curve>, String);

impl Curves {
    fn name(&mut self, c: &Curve) -> String {
        let k = match self.0.iter().position(|x| x == c) {
            Some(k) => k,
            None => {
                self.0.push(c.clone());
                let k = self.0.len() - 1;
                let _ = writeln!(self.1, "*AMPLITUDE, NAME=AMP-{}, TIME=TOTAL TIME", k + 1);
                for pair in c.points.chunks(4) {
                    let v: Vec<String> =
                        pair.iter().map(|[t, y]| format!("{t:e}, {y:e}")).collect();
                    let _ = writeln!(self.1, "{}", v.join(", "));
                }
                k
            }
        };
        format!("AMP-{}", k + 1)
    }
}

/// A pair entry (tied, frictional small sliding) or a bolt (tied cut with a pre-tension
/// section on a new node, loaded in step 1 and fixed at its lock).
#[allow(clippy::too_many_arguments)]
fn write_pair(
    model: &mut String,
    first: &mut String,
    locks: &mut Vec<(f64, usize)>,
    curves: &mut Curves,
    m: &crate::model::def::ModelDef,
    p: &crate::model::pairs::PairsDef,
    next: &mut usize,
    notes: &mut Vec<String>,
) {
    let surf = !m.node_sets.contains_key(&p.tracked) && m.surfaces.contains_key(&p.tracked);
    if let Some(pre) = &p.pretension {
        *next += 1;
        let next = *next;
        let amp = curves.name(&pre.curve);
        let _ = writeln!(
            model,
            "** alfe-entry bolts = {{ name = {}, tracked = {}, reference = {}, force = {:e}, curve = \"{amp}\", lock_at = {:e}{}{} }}",
            q(&p.name), q(&p.tracked), q(&p.reference), pre.force, pre.lock_at,
            opt("kappa", p.kappa), opt("search_distance", p.search_distance)
        );
        let _ = writeln!(
            model,
            "*NODE\n{next}, 0, 0, 0\n*TIE, NAME={}-CUT\n{}, {}\n*PRE-TENSION SECTION, SURFACE={}, NODE={next}",
            p.name, p.tracked, p.reference, p.tracked
        );
        let _ = writeln!(first, "*CLOAD, AMPLITUDE={amp}\n{next}, 1, {:e}", pre.force);
        locks.push((pre.lock_at, next));
        return;
    }
    let _ = writeln!(model, "** alfe-entry pairs = {}", pair_entry(p, surf));
    if !surf {
        notes.push(format!(
            "pairs `{}`: a tracked node set (CalculiX pairs surfaces)",
            p.name
        ));
    }
    if p.tied {
        let _ = writeln!(
            model,
            "*TIE, NAME={}\n{}, {}",
            p.name, p.tracked, p.reference
        );
    } else {
        // CalculiX's penalty: 10 E per unit length (a stiff contact).
        let e = m.materials.iter().map(|x| young(&x.1)).fold(0.0, f64::max);
        let k = 10.0 * e;
        let _ = writeln!(
            model,
            "*SURFACE INTERACTION, NAME={n}-I\n*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR\n{k:.6e}\n*FRICTION\n{:e}, {:.6e}\n*CONTACT PAIR, INTERACTION={n}-I, TYPE=SURFACE TO SURFACE, SMALL SLIDING\n{}, {}",
            p.friction.max(1e-6), 0.1 * k, p.tracked, p.reference, n = p.name
        );
    }
}

/// Pairs, bolts, couplings and steps of `scene` (the stages, or one step over the run).
pub fn write(scene: &Scene, notes: &mut Vec<String>) -> Written {
    let m = &scene.model;
    let a = &scene.run.analysis;
    let mut model = String::new();
    let mut curves = Curves(Vec::new(), String::new());
    // Step-1 loads, loads to re-apply after a lock (`OP=NEW` drops them), and locks.
    let (mut first, mut cloads, mut locks) = (String::new(), Vec::new(), Vec::new());
    let mut next = m.mesh.n_nodes();
    for c in &m.contributions {
        match c {
            ContributionDef::Pairs(p) => {
                write_pair(
                    &mut model,
                    &mut first,
                    &mut locks,
                    &mut curves,
                    m,
                    p,
                    &mut next,
                    notes,
                );
            }
            ContributionDef::Coupling(cp) => {
                next += 1;
                write_coupling(
                    &mut model,
                    &mut first,
                    &mut cloads,
                    &mut curves,
                    cp,
                    next,
                    notes,
                );
            }
            _ => {}
        }
    }
    let stages: Vec<(String, f64, f64, f64, f64, f64, usize)> = if a.stages.is_empty() {
        vec![(
            String::new(),
            a.step,
            a.end_time,
            a.min_step,
            a.max_step,
            a.end_time,
            1,
        )]
    } else {
        a.stages
            .iter()
            .enumerate()
            .map(|(k, s)| {
                let every = scene
                    .run
                    .output
                    .stage_every
                    .get(k)
                    .copied()
                    .unwrap_or(scene.run.output.every);
                (
                    s.name.clone(),
                    s.step,
                    s.end - s.start,
                    s.min_step,
                    s.max_step,
                    s.end,
                    every,
                )
            })
            .collect()
    };
    let mut steps = Vec::new();
    let mut prev_end = 0.0;
    for (k, (name, step, dur, min, max, end, every)) in stages.iter().enumerate() {
        let mut head = String::new();
        if !a.stages.is_empty() {
            let _ = writeln!(
                head,
                "** alfe-entry steps = {{ name = {}, duration = {dur:e}, step = {step:e}, min_step = {min:e}, max_step = {max:e}, output_every = {every} }}",
                q(name)
            );
        }
        let _ = writeln!(
            head,
            "*STEP{{NLGEOM}}, INC=10000\n*STATIC\n{step:.13e}, {dur:.13e}, {min:.13e}, {max:.13e}"
        );
        let mut body = if k == 0 { first.clone() } else { String::new() };
        let ended: Vec<usize> = locks
            .iter()
            .filter(|(t, _)| (*t - prev_end).abs() <= 1e-9 * end.abs().max(1.0) && k > 0)
            .map(|x| x.1)
            .collect();
        if !ended.is_empty() {
            body.push_str("*BOUNDARY, FIXED\n");
            for n in &ended {
                let _ = writeln!(body, "{n}, 1, 1");
            }
            body.push_str("*CLOAD, OP=NEW\n");
            for l in &cloads {
                body.push_str(l);
            }
        }
        if locks
            .iter()
            .any(|(t, _)| *t > prev_end + 1e-9 && *t < end - 1e-9)
        {
            notes.push(
                "a bolt locks inside a step: CalculiX holds its section from the next step on"
                    .into(),
            );
        }
        steps.push((head, body));
        prev_end = *end;
    }
    Written {
        model: curves.1 + &model,
        steps,
    }
}

fn write_coupling(
    model: &mut String,
    first: &mut String,
    cloads: &mut Vec<String>,
    curves: &mut Curves,
    c: &CouplingDef,
    nid: usize,
    notes: &mut Vec<String>,
) {
    let uniform = c.weights.iter().all(|&w| w == 1.0);
    let mut comps = String::new();
    let mut real = String::new();
    for (d, dof) in c.dofs.iter().enumerate() {
        let (field, axis) = (
            ["force", "moment", "displacement", "rotation"],
            ["x", "y", "z"][d % 3],
        );
        let (name, v, curve) = match dof {
            Dof::Free {
                load: Some((v, cv)),
            } => (field[d / 3], *v, cv),
            Dof::Prescribed { value, curve } => (field[2 + d / 3], *value, curve),
            Dof::Free { load: None } => continue,
        };
        let amp = curves.name(curve);
        let _ = write!(
            comps,
            ", {name}.{axis} = {{ value = {v:e}, curve = \"{amp}\" }}"
        );
        if name.starts_with('f') || name.starts_with('m') {
            let l = format!("*CLOAD, AMPLITUDE={amp}\n{nid}, {}, {v:.13e}\n", d + 1);
            real.push_str(&l);
            cloads.push(l);
        } else {
            let _ = writeln!(
                real,
                "*BOUNDARY, AMPLITUDE={amp}\n{nid}, {d1}, {d1}, {v:.13e}",
                d1 = d + 1
            );
        }
    }
    // Dotted keys inside an inline table are TOML 1.0.
    let _ = writeln!(
        model,
        "** alfe-entry couplings = {{ name = {}, nodes = {}, weights = \"{}\", point = [{:e}, {:e}, {:e}]{comps} }}",
        q(&c.name),
        q(&c.set),
        if uniform { "uniform" } else { "area" },
        c.point[0],
        c.point[1],
        c.point[2]
    );
    let _ = writeln!(
        model,
        "*NODE\n{nid}, {:.13e}, {:.13e}, {:.13e}\n*COUPLING, REF NODE={nid}, SURFACE={}, CONSTRAINT NAME={}\n*DISTRIBUTING\n1, 3",
        c.point[0], c.point[1], c.point[2], c.set, c.name
    );
    if c.dofs[3..]
        .iter()
        .any(|d| !matches!(d, Dof::Free { load: None }))
    {
        notes.push(format!("coupling `{}`: moments and rotations (CalculiX's distributing coupling carries forces)", c.name));
    }
    first.push_str(&real);
}

/// Young's modulus (initial, for a hyperelastic material) of a material.
fn young(m: &crate::model::def::MaterialDef) -> f64 {
    use crate::model::def::MaterialDef::*;
    match m {
        LinearElastic { e, .. } | NeoHookean { e, .. } | J2 { e, .. } => *e,
        MooneyRivlin { c10, c01, nu, .. } => 4.0 * (c10 + c01) * (1.0 + nu),
    }
}
