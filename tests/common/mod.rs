//! Helpers shared by the scene-level tests.
#![allow(dead_code)]

use alfe::app::{run, RunOptions, RunOutcome};
use alfe::parallel::SerialComm;
use std::path::PathBuf;

/// A fresh directory for one test.
pub fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("alfe-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The text of a built-in scene.
pub fn builtin(name: &str) -> String {
    alfe::scene::BUILTIN
        .iter()
        .find(|s| s.0 == name)
        .unwrap()
        .2
        .to_string()
}

/// Run a deck text in this process on one rank; results go to a temp dir.
pub fn run_deck(name: &str, text: &str) -> RunOutcome {
    try_run_deck(name, text).unwrap_or_else(|e| panic!("{name}: {e}"))
}

pub fn try_run_deck(name: &str, text: &str) -> alfe::Result<RunOutcome> {
    let dir = temp_dir(name);
    let deck = dir.join("deck.toml");
    std::fs::write(&deck, text).unwrap();
    let opts = RunOptions {
        contact: None,
        target: deck.display().to_string(),
        out: Some(dir.join("out")),
        partitions: dir.join("partitions"),
        repartition: false,
        quiet: true,
        solver: None,
    };
    run(&SerialComm, &opts)
}

/// Replace exactly one occurrence of `from` (so a changed built-in scene fails loudly).
pub fn edit(text: &str, from: &str, to: &str) -> String {
    assert_eq!(
        text.matches(from).count(),
        1,
        "expected one `{from}` in the deck"
    );
    text.replacen(from, to, 1)
}

pub fn rel_err(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(f64::MIN_POSITIVE)
}

/// A published output field of a finished run (one rank: every row), at its last step.
pub fn field(out: &RunOutcome, name: &str) -> Vec<f64> {
    let t = out.steps.last().map_or(0.0, |s| s.time);
    out.model
        .field(&SerialComm, &out.u, t, name)
        .unwrap_or_else(|| panic!("no field {name}"))
}
