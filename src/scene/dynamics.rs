//! Deck validation of the analysis table (static, implicit and explicit dynamics), the
//! dynamic output keys and initial velocities. Errors name the deck field.

use super::check::{err, MAX_STEPS};
use super::context::Context;
use super::deck::*;
use crate::Result;
use std::collections::BTreeMap;

fn kind_name(k: AnalysisKind) -> &'static str {
    k.name()
}

/// `[analysis]` and the output keys that depend on it.
pub fn check_analysis(deck: &Deck) -> Result<()> {
    let a = &deck.analysis;
    let kind = kind_name(a.kind);
    if !(a.end_time > 0.0 && a.end_time.is_finite()) {
        return Err(err(
            "analysis.end_time",
            format!("expected a positive time, got {}", a.end_time),
        ));
    }
    let explicit = a.kind == AnalysisKind::Explicit;
    let step_given = a.step != 0.0;
    if (!explicit || step_given) && !(a.step > 0.0 && a.step <= a.end_time) {
        if !step_given {
            return Err(err(
                "analysis.step",
                format!("missing field `step` (required for type = \"{kind}\")"),
            ));
        }
        return Err(err(
            "analysis.step",
            format!(
                "expected 0 < step ≤ end_time ({}), got {}",
                a.end_time, a.step
            ),
        ));
    }
    if step_given && a.end_time / a.step > MAX_STEPS {
        return Err(err(
            "analysis.step",
            format!(
                "{:e} makes {:.3e} steps of end_time {:e}; expected at most {MAX_STEPS:.0e}",
                a.step,
                a.end_time / a.step,
                a.end_time
            ),
        ));
    }
    let only = |field: &str, given: bool, allowed: &[AnalysisKind]| -> Result<()> {
        if given && !allowed.contains(&a.kind) {
            let names: Vec<String> = allowed
                .iter()
                .map(|k| format!("\"{}\"", kind_name(*k)))
                .collect();
            return Err(err(
                format!("analysis.{field}"),
                format!(
                    "only for type = {} (this analysis is \"{kind}\")",
                    names.join(" or ")
                ),
            ));
        }
        Ok(())
    };
    use AnalysisKind::*;
    only("min_step", a.min_step.is_some(), &[Static, Implicit])?;
    only("max_step", a.max_step.is_some(), &[Static, Implicit])?;
    only("scheme", a.scheme.is_some(), &[Implicit])?;
    only("rho_inf", a.rho_inf.is_some(), &[Implicit])?;
    only("mass", a.mass.is_some(), &[Implicit])?;
    only("dt_factor", a.dt_factor.is_some(), &[Explicit])?;
    if let Some(m) = a.min_step {
        if !(m > 0.0 && m <= a.step) {
            return Err(err(
                "analysis.min_step",
                format!("expected 0 < min_step ≤ step ({}), got {m}", a.step),
            ));
        }
    }
    if let Some(m) = a.max_step {
        if !(m >= a.step && m <= a.end_time) {
            return Err(err(
                "analysis.max_step",
                format!("expected step ≤ max_step ≤ end_time, got {m}"),
            ));
        }
    }
    if let Some(r) = a.rho_inf {
        let lo = if a.scheme == Some(Scheme::HhtAlpha) {
            0.5
        } else {
            0.0
        };
        if a.scheme == Some(Scheme::Newmark) {
            return Err(err(
                "analysis.rho_inf",
                "not used by scheme = \"newmark\" (the trapezoidal rule has ρ∞ = 1)",
            ));
        }
        if !(r >= lo && r <= 1.0) {
            return Err(err(
                "analysis.rho_inf",
                format!("expected {lo} ≤ rho_inf ≤ 1, got {r}"),
            ));
        }
    }
    if let Some(f) = a.dt_factor {
        if !(f > 0.0 && f <= 1.0) {
            return Err(err(
                "analysis.dt_factor",
                format!("expected 0 < dt_factor ≤ 1, got {f}"),
            ));
        }
    }
    if let Some(i) = deck.output.interval {
        if a.kind == Static {
            return Err(err(
                "output.interval",
                "only for dynamic analyses (type = \"implicit\" or \"explicit\"); static runs use `every`",
            ));
        }
        if !(i > 0.0 && i.is_finite()) {
            return Err(err(
                "output.interval",
                format!("expected a positive time, got {i}"),
            ));
        }
    }
    if !deck.initial_velocity.is_empty() && a.kind == Static {
        return Err(err(
            "initial_velocity",
            "only for dynamic analyses (type = \"implicit\" or \"explicit\")",
        ));
    }
    Ok(())
}

/// Resolve `[[initial_velocity]]` entries to (node set, velocity); a part becomes the
/// node set `part:<name>` (added to `sets`).
pub fn initial_velocities(
    deck: &Deck,
    ctx: &Context,
    sets: &mut BTreeMap<String, Vec<usize>>,
) -> Result<Vec<(String, [f64; 3])>> {
    let mut out = Vec::new();
    for (i, iv) in deck.initial_velocity.iter().enumerate() {
        let f = format!("initial_velocity[{i}]");
        if iv.velocity.iter().any(|v| !v.is_finite()) {
            return Err(err(format!("{f}.velocity"), "expected finite numbers"));
        }
        let name = match (&iv.part, &iv.set) {
            (Some(p), None) => {
                let Some(pi) = deck.parts.iter().position(|q| q.name == *p) else {
                    let names: Vec<&str> = deck.parts.iter().map(|q| q.name.as_str()).collect();
                    return Err(err(
                        format!("{f}.part"),
                        format!("unknown part `{p}` (parts: {})", names.join(", ")),
                    ));
                };
                let name = format!("part:{p}");
                sets.insert(name.clone(), ctx.part_nodes[pi].iter().copied().collect());
                name
            }
            (None, Some(s)) => {
                let nodes = ctx.set_nodes(format!("{f}.set"), s)?;
                sets.insert(s.clone(), nodes);
                s.clone()
            }
            _ => return Err(err(&f, "expected exactly one of `part`, `set`")),
        };
        out.push((name, iv.velocity));
    }
    Ok(out)
}

/// Density of every material a part uses must be positive in a dynamic analysis, and
/// `[output] displacements` must name node sets.
pub fn check_dynamic_inputs(
    deck: &Deck,
    part_material: &[usize],
    ctx: &Context,
    sets: &mut BTreeMap<String, Vec<usize>>,
) -> Result<()> {
    if deck.analysis.kind != AnalysisKind::Static {
        for &mi in part_material {
            let m = &deck.materials[mi];
            if m.density.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
                return Err(err(
                    format!("materials[{mi}].density"),
                    format!(
                        "material `{}`: a dynamic analysis needs a density > 0, got {}",
                        m.name, m.density
                    ),
                ));
            }
        }
    }
    for (i, n) in deck.output.displacements.iter().enumerate() {
        let nodes = ctx.set_nodes(format!("output.displacements[{i}]"), n)?;
        sets.insert(n.clone(), nodes);
    }
    Ok(())
}
