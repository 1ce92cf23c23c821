//! The step's procedure of an exported `.inp` and the initial velocities: a static
//! analysis as `*STATIC`, an implicit dynamic one as `*DYNAMIC` (CalculiX's α method:
//! HHT's α = (ρ∞ − 1)/(ρ∞ + 1), held to CalculiX's range [−1/3, 0]; alfe's Bossak or
//! generalized-α with its own ρ∞ is in the notes), an explicit one as
//! `*DYNAMIC, EXPLICIT`; initial velocities as `*INITIAL CONDITIONS, TYPE=VELOCITY`.

use crate::scene::Scene;

/// A number for a data line: the shortest text that reads back as `x` (with or without
/// an exponent) where it fits CalculiX's 20-character fields, else as many digits as fit.
pub fn num(x: f64) -> String {
    let (a, b) = (format!("{x}"), format!("{x:e}"));
    let best = if a.len() <= b.len() { a } else { b.clone() };
    if best.len() <= 20 {
        return best;
    }
    (0..16)
        .rev()
        .map(|p| format!("{x:.p$e}"))
        .find(|s| s.len() <= 20)
        .unwrap_or(b)
}
use crate::solve::analysis::AnalysisKind;
use std::fmt::Write;

/// The procedure keyword and its data line; what it cannot say goes to `notes`.
pub fn procedure(scene: &Scene, notes: &mut Vec<String>) -> String {
    let a = &scene.run.analysis;
    match a.kind {
        AnalysisKind::Static => format!("*STATIC\n{}, {}\n", num(a.step), num(a.end_time)),
        AnalysisKind::Implicit => {
            let alpha = ((a.rho_inf - 1.0) / (a.rho_inf + 1.0)).max(-1.0 / 3.0);
            if (alpha * (a.rho_inf + 1.0) - (a.rho_inf - 1.0)).abs() > 1e-12 {
                notes.push(format!(
                    "the time integrator's ρ∞ = {}: CalculiX's HHT α is held to −1/3 (ρ∞ = 0.5)",
                    a.rho_inf
                ));
            }
            format!(
                "*DYNAMIC, ALPHA={}\n{}, {}, {}, {}\n",
                num(alpha),
                num(a.step),
                num(a.end_time),
                num(a.min_step),
                num(a.max_step.min(a.end_time))
            )
        }
        AnalysisKind::Explicit => format!("*DYNAMIC, EXPLICIT\n{:e}, {:e}\n", a.step, a.end_time),
    }
}

/// Node sets for initial velocities given by part (model data) and the
/// `*INITIAL CONDITIONS` keyword.
pub fn initial_velocities(scene: &Scene) -> String {
    let m = &scene.model;
    let mut out = String::new();
    let mut lines = String::new();
    for (k, (set, v)) in m.initial_velocity.iter().enumerate() {
        let name = match set.strip_prefix("part:") {
            Some(part) => {
                let ns = m.part_nodes(part);
                let name = format!("IV_{}", k + 1);
                let _ = writeln!(out, "*NSET, NSET={name}");
                for chunk in ns.chunks(16) {
                    let ids: Vec<String> = chunk.iter().map(|n| (n + 1).to_string()).collect();
                    let _ = writeln!(out, "{},", ids.join(", "));
                }
                name
            }
            None => set.clone(),
        };
        for (c, x) in v.iter().enumerate() {
            let _ = writeln!(lines, "{name}, {}, {}", c + 1, num(*x));
        }
    }
    if !lines.is_empty() {
        out += "*INITIAL CONDITIONS, TYPE=VELOCITY\n";
        out += &lines;
    }
    out
}
