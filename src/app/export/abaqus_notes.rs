//! What an `.inp` has no field for, as `** alfe ` comment lines (CalculiX and Abaqus skip
//! `**` lines): the deck's own tables — walls and entities (shape, pose, motion curves,
//! friction, method), parts' formulations, materials (an `.inp` holds no power-law
//! hardening and no exact ν of a hyperelastic material), curves, initial velocities,
//! analysis, solver, output, units — as a TOML fragment, one line a note, so that
//! `alfe import` rebuilds the same deck. Numbers are written as Rust prints an f64 (the
//! shortest text that reads back as the same number): the round trip is exact.
//! The rigid layers that stand in for walls are bracketed by `** alfe-layer` lines, so
//! that the import can drop them.

use crate::scene::Scene;

/// The note prefix; the rest of the line is a line of TOML.
pub const NOTE: &str = "** alfe ";
/// Brackets of a rigid layer's lines (model data and step data apart).
pub const LAYER_BEGIN: &str = "** alfe-layer begin";
pub const LAYER_END: &str = "** alfe-layer end";

/// The deck's tables carried by the notes (the rest is in keywords).
const KEYS: &[&str] = &[
    "scene",
    "materials",
    "parts",
    "curves",
    "walls",
    "entities",
    "pairs",
    "bolts",
    "couplings",
    "steps",
    "initial_velocity",
    "analysis",
    "solver",
    "output",
    "quantities",
];

/// The notes of `scene` (empty when its deck echo is not at hand).
pub fn notes(scene: &Scene) -> String {
    let Ok(echo) = scene.run.echo.parse::<toml::Table>() else {
        return String::new();
    };
    let mut t = toml::Table::new();
    for k in KEYS {
        if let Some(v) = echo.get(*k) {
            t.insert(k.to_string(), v.clone());
        }
    }
    // The mesh is the file's, placed: its generator and placement are not notes.
    if let Some(toml::Value::Array(parts)) = t.get_mut("parts") {
        for p in parts.iter_mut().filter_map(toml::Value::as_table_mut) {
            for k in ["mesh", "rotate", "translate"] {
                p.remove(k);
            }
        }
    }
    let Ok(text) = toml::to_string_pretty(&t) else {
        return String::new();
    };
    let mut out = String::from(
        "** The alfe deck's own values where the keywords below hold none or not exactly\n** (alfe import reads them; the keywords are CalculiX's model):\n",
    );
    for l in text.lines().filter(|l| !l.trim().is_empty()) {
        out.push_str(NOTE);
        out.push_str(l);
        out.push('\n');
    }
    out
}

/// The digest line's prefix: the FNV-1a hash of the file's keyword lines (every line
/// but the `** alfe` ones), so that the import can tell a file edited after export.
pub const DIGEST: &str = "** alfe-digest ";

/// FNV-1a (64 bit) over the lines of `text` that are not `** alfe` lines.
pub fn digest(text: &str) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for l in text.lines().filter(|l| !l.starts_with("** alfe")) {
        for b in l.trim_end().bytes().chain([b'\n']) {
            h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

/// `text` with its digest line first.
pub fn signed(text: String) -> String {
    format!("{DIGEST}{:016x}\n{text}", digest(&text))
}

/// `text` bracketed as a rigid layer's.
pub fn layer(text: &str) -> String {
    if text.is_empty() {
        return String::new();
    }
    format!("{LAYER_BEGIN}\n{text}{LAYER_END}\n")
}
