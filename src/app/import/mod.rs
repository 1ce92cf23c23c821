//! `alfe import`: other codes' input decks as alfe decks (issue 36). A reader emits the
//! deck's text (and a companion mesh file where the model names nodes or elements by
//! number); the command writes them and then builds the scene from them, so a deck it
//! writes is one `alfe run` takes.

pub mod abaqus;
mod abaqus_contact;
mod abaqus_notes;
mod keyword_blocks;
pub mod lsdyna;
mod lsdyna_entities;
mod lsdyna_materials;
mod lsdyna_model;
mod lsdyna_pairs;
mod lsdyna_walls;

use crate::scene::{read, Source};
use crate::{Error, Result};
use std::path::Path;

/// What `import` wrote and what it could not translate.
#[derive(Debug)]
pub struct Report {
    /// Files written (the deck first).
    pub written: Vec<String>,
    /// Every keyword, option or line not translated, with its file and line.
    pub untranslated: Vec<String>,
}

/// Import `file` into the deck `out` (and `out` with extension `.sets.inp` when needed).
pub fn import(file: &Path, out: &Path) -> Result<Report> {
    let ext = file
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let load = |p: &Path| -> std::result::Result<String, String> {
        std::fs::read_to_string(p).map_err(|e| format!("cannot read `{}`: {e}", p.display()))
    };
    let imported = match ext.as_deref() {
        Some("inp") => abaqus::import_inp(file, out, &load).map_err(Error::input)?,
        Some("k" | "key" | "dyn") => lsdyna::import_k(file, out, &load).map_err(Error::input)?,
        _ => {
            return Err(Error::input(format!(
                "`{}`: alfe imports Abaqus/CalculiX input files (.inp) and LS-DYNA keyword files (.k, .key, .dyn), by their extension",
                file.display()
            )))
        }
    };
    let mut written = Vec::new();
    if let Some(c) = &imported.companion {
        let p = out.with_extension("sets.inp");
        std::fs::write(&p, c)
            .map_err(|e| Error::input(format!("cannot write `{}`: {e}", p.display())))?;
        written.push(p.display().to_string());
    }
    std::fs::write(out, &imported.deck)
        .map_err(|e| Error::input(format!("cannot write `{}`: {e}", out.display())))?;
    written.insert(0, out.display().to_string());
    // The deck must build: a deck `import` writes is one `run` takes.
    let dir = out
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    read(&Source {
        text: imported.deck.clone(),
        dir: dir.to_path_buf(),
        label: out.display().to_string(),
    })
    .map_err(|e| e.context(format!("the deck imported from {}", file.display())))?;
    Ok(Report {
        written,
        untranslated: imported.untranslated,
    })
}
