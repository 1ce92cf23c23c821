//! `alfe export`: a scene as another code's input deck (issue 36), so that the same model
//! runs in CalculiX (installed here) or reaches an Abaqus user.

pub mod abaqus;
pub mod abaqus_notes;
pub mod abaqus_pairs;
pub mod abaqus_step;
pub mod contact;
pub mod lsdyna;
mod lsdyna_cards;
pub mod lsdyna_entities;
pub mod lsdyna_pairs;
pub mod rigid;

use crate::{Error, Result};
use std::path::Path;

/// Export the built-in scene or deck `target` to `out` (`.inp` or `.k`); what was left out.
pub fn export(target: &str, out: &Path) -> Result<Vec<String>> {
    let ext = out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let scene = crate::scene::read(&crate::scene::load(target)?)?;
    let e = match ext.as_deref() {
        Some("inp") => abaqus::export_inp(&scene),
        Some("k" | "key" | "dyn") => lsdyna::export_k(&scene),
        _ => {
            return Err(Error::input(format!(
                "`{}`: alfe exports Abaqus/CalculiX input files (.inp) and LS-DYNA keyword files (.k, .key, .dyn), chosen by the extension",
                out.display()
            )))
        }
    };
    std::fs::write(out, &e.text)
        .map_err(|err| Error::input(format!("cannot write `{}`: {err}", out.display())))?;
    Ok(e.left_out)
}
