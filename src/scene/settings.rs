//! `[analysis]`, `[solver]`, `[partition]` and `[output]`: checked, with their defaults
//! filled in, into the run settings; the `"auto"` preconditioner's problem-class test;
//! the quantities of interest.

use super::check::{err, unique_names};
use super::deck::*;
use super::steps::Timeline;
use super::{OutputSettings, RunSettings};
use crate::linalg::GmresOptions;
use crate::solve::nonlinear::NonlinearOptions;
use crate::solve::Analysis;
use crate::Result;

/// The `[solver]` numbers a user can get wrong, each checked against its range.
pub(super) fn check_solver(deck: &Deck) -> Result<()> {
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
    Ok(())
}

/// `[partition]`: METIS (the default) or slabs along an axis.
pub(super) fn partition_method(deck: &Deck) -> Result<crate::partition::Method> {
    Ok(match &deck.partition {
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
    })
}

/// `[output] peak_stress`: each named part with its index.
pub(super) fn peak_stress_parts(deck: &Deck) -> Result<Vec<(String, u32)>> {
    deck.output
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
        .collect::<Result<Vec<_>>>()
}

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
fn curve_breakpoints(deck: &Deck, timeline: &Timeline) -> Vec<f64> {
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

/// `[analysis]`, `[solver]` and `[output]` with their defaults filled in (validated).
pub(super) fn run_settings(deck: &Deck, timeline: &Timeline) -> RunSettings {
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
            line_search: s.line_search.map(|l| l.setting()).unwrap_or_default(),
            stagnation_window: None,
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
        parts: Vec::new(),
        warnings: Vec::new(),
    }
}

/// The deck's quantities of interest, each expression parsed; errors name the field.
pub(super) fn quantities(deck: &Deck) -> Result<Vec<crate::output::quantities::QuantityDef>> {
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
