//! The `** alfe` notes of an `.inp` that `alfe export` wrote (see the exporter's
//! `abaqus_notes.rs`): a TOML fragment of the deck's own tables — walls, entities,
//! parts' formulations, materials, curves, initial velocities, analysis, solver, output,
//! units. Where a file has them, the imported deck takes those tables from them (they
//! are exact; the keywords are CalculiX's model of them), and the rigid layers between
//! `** alfe-layer` brackets — CalculiX's stand-ins for the walls — are dropped; each part
//! reads its own element set of the file. The mesh, node sets, surfaces, supports and
//! loads still come from the keywords. A file without notes imports as before.

use crate::app::export::abaqus_notes::{digest, DIGEST};
use crate::mesh::abaqus::{keyword, param, Line};
use std::path::Path;

const NOTE: &str = "** alfe ";
const LAYER_BEGIN: &str = "** alfe-layer begin";
const LAYER_END: &str = "** alfe-layer end";

/// The notes of one file and where its layers are.
pub struct Notes {
    table: toml::Table,
    file: std::path::PathBuf,
    /// Line ranges (1-based, inclusive) of the rigid layers.
    layers: Vec<(usize, usize)>,
    /// The keyword lines were changed after `alfe export` wrote the file (its digest
    /// no longer matches): the notes may say something the keywords no longer do.
    pub edited: bool,
}

/// The notes in `text` (the file `path`'s); None when it has none.
pub fn read(text: &str, path: &Path) -> Result<Option<Notes>, String> {
    let mut toml_text = String::new();
    let mut layers = Vec::new();
    let mut open: Option<usize> = None;
    for (i, raw) in text.lines().enumerate() {
        let t = raw.trim_end();
        if let Some(rest) = t.strip_prefix(NOTE) {
            toml_text.push_str(rest);
            toml_text.push('\n');
        } else if t == LAYER_BEGIN {
            open = Some(i + 1);
        } else if t == LAYER_END {
            let Some(b) = open.take() else {
                return Err(format!(
                    "{}:{}: `{LAYER_END}` without a `{LAYER_BEGIN}` before it",
                    path.display(),
                    i + 1
                ));
            };
            layers.push((b, i + 1));
        }
    }
    if let Some(b) = open {
        return Err(format!(
            "{}:{b}: `{LAYER_BEGIN}` without its `{LAYER_END}`",
            path.display()
        ));
    }
    if toml_text.is_empty() {
        return Ok(None);
    }
    let table = toml_text.parse::<toml::Table>().map_err(|e| {
        format!(
            "{}: its `** alfe` notes are not a TOML fragment: {e}",
            path.display()
        )
    })?;
    let stamp = text
        .lines()
        .find_map(|l| l.strip_prefix(DIGEST))
        .and_then(|h| u64::from_str_radix(h.trim(), 16).ok());
    Ok(Some(Notes {
        table,
        file: path.to_path_buf(),
        layers,
        edited: stamp != Some(digest(text)),
    }))
}

impl Notes {
    /// What an edited file means for the import.
    pub fn edited_warning(&self) -> String {
        format!(
            "{}: the file was changed after `alfe export` wrote it (its `{DIGEST}` no longer matches): the `** alfe` notes (walls, entities, parts, materials, pairs, bolts, couplings, steps, analysis, solver) were taken over the keywords; check them against your edits",
            self.file.display()
        )
    }

    /// Whether `line` is part of a rigid layer (dropped).
    pub fn in_layer(&self, line: &Line) -> bool {
        *line.file == self.file
            && self
                .layers
                .iter()
                .any(|&(a, b)| (a..=b).contains(&line.number))
    }

    /// Whether the notes hold what keyword `kw` says (its report as not translated is
    /// then dropped).
    pub fn covers(&self, kw: &str) -> bool {
        let key = match kw {
            "DYNAMIC" | "STATIC" => "analysis",
            "INITIAL CONDITIONS" => "initial_velocity",
            // Later steps: the noted [[steps]] hold them.
            "STEP" => "steps",
            _ => return false,
        };
        self.table.contains_key(key)
    }

    /// The deck `deck` (the keywords' translation) with the notes' tables in: each
    /// noted part reads its element set of the mesh file; node sets and surfaces are
    /// every one the file defines outside the layers (walls and outputs name them).
    pub fn apply(&self, deck: &str, lines: &[Line]) -> Result<String, String> {
        let at = || format!("{}", self.file.display());
        let mut d: toml::Table = deck
            .parse()
            .map_err(|e| format!("{}: the translated deck does not parse: {e}", at()))?;
        let mesh = d
            .get("parts")
            .and_then(|p| p.get(0))
            .and_then(|p| p.get("mesh"))
            .cloned()
            .ok_or_else(|| format!("{}: the translated deck has no part", at()))?;
        for (k, v) in &self.table {
            d.insert(k.clone(), v.clone());
        }
        if let Some(toml::Value::Array(parts)) = d.get_mut("parts") {
            for p in parts.iter_mut().filter_map(toml::Value::as_table_mut) {
                let mut m = mesh.clone();
                if let (Some(t), Some(name)) = (m.as_table_mut(), p.get("name").cloned()) {
                    t.insert("elset".into(), name);
                }
                p.insert("mesh".into(), m);
            }
        }
        self.add_groups(&mut d, lines, "node_sets", "NSET", "NSET");
        self.add_groups(&mut d, lines, "surfaces", "SURFACE", "NAME");
        let mut head: String = deck
            .lines()
            .take_while(|l| l.starts_with('#'))
            .filter(|l| !l.starts_with("# Numbers are the file's"))
            .map(|l| format!("{l}\n"))
            .collect();
        head += "# Walls, entities, parts, materials, curves, initial velocities, analysis, solver,\n# output and units from the file's `** alfe` notes (exact); its rigid layers dropped.\n\n";
        if self.edited {
            head += &format!("# WARNING: {}\n\n", self.edited_warning());
        }
        let body = toml::to_string(&d).map_err(|e| format!("{}: {e}", at()))?;
        Ok(head + &body)
    }

    /// `[[key]]` entries (name = group) for every `*kw, param=NAME` outside the layers
    /// that the deck does not list yet.
    fn add_groups(&self, d: &mut toml::Table, lines: &[Line], key: &str, kw: &str, p: &str) {
        let mut have: Vec<String> = d
            .get(key)
            .and_then(toml::Value::as_array)
            .into_iter()
            .flatten()
            .filter_map(|x| x.get("name")?.as_str().map(str::to_string))
            .collect();
        let mut add = Vec::new();
        for l in lines.iter().filter(|l| !self.in_layer(l)) {
            if keyword(&l.text).as_deref() != Some(kw) {
                continue;
            }
            let Some(name) = param(&l.text, p) else {
                continue;
            };
            if have.iter().any(|h| h.eq_ignore_ascii_case(&name)) {
                continue;
            }
            have.push(name.clone());
            let mut t = toml::Table::new();
            t.insert("name".into(), name.clone().into());
            t.insert("group".into(), name.into());
            add.push(toml::Value::Table(t));
        }
        if add.is_empty() {
            return;
        }
        let entry = d
            .entry(key)
            .or_insert_with(|| toml::Value::Array(Vec::new()));
        if let Some(a) = entry.as_array_mut() {
            a.extend(add);
        }
    }
}
