//! An LS-DYNA keyword file as blocks: each keyword with its data lines and its `$alfe
//! key = value` notes (what `alfe export` writes where LS-DYNA has no field).

use crate::mesh::abaqus::Line;
use crate::mesh::lsdyna::{int, is_alfe_note, keyword, real, split};

/// One keyword and its data lines (`$alfe` notes apart).
pub struct Block<'a> {
    pub kw: String,
    pub line: &'a Line,
    pub long: bool,
    pub data: Vec<&'a Line>,
    pub notes: Vec<(String, String)>,
}

impl Block<'_> {
    /// The fields of data line `k` (20 columns in long format, else `w`).
    pub fn fields(&self, k: usize, w: usize) -> Vec<&str> {
        self.data
            .get(k)
            .map(|l| split(&l.text, &[if self.long { 20 } else { w }]))
            .unwrap_or_default()
    }
    pub fn real(&self, k: usize, j: usize) -> Result<f64, String> {
        let f = self.fields(k, 10);
        match self.data.get(k) {
            Some(l) => real(f.get(j).copied().unwrap_or(""), l),
            None => Ok(0.0),
        }
    }
    pub fn int(&self, k: usize, j: usize) -> Result<i64, String> {
        let f = self.fields(k, 10);
        match self.data.get(k) {
            Some(l) => int(f.get(j).copied().unwrap_or(""), l, "an integer"),
            None => Ok(0),
        }
    }
    pub fn need(&self, cards: usize) -> Result<(), String> {
        if self.data.len() < cards {
            return Err(format!(
                "{}: *{} needs {cards} cards, the file has {}",
                self.line.at(),
                self.kw,
                self.data.len()
            ));
        }
        Ok(())
    }
    pub fn note(&self, key: &str) -> Option<&str> {
        self.notes
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }
    pub fn at(&self) -> String {
        self.line.at()
    }
}

/// Split the file into keyword blocks.
pub fn blocks(lines: &[Line]) -> Vec<Block<'_>> {
    let mut out: Vec<Block> = Vec::new();
    for l in lines {
        if let Some((kw, long)) = keyword(&l.text) {
            out.push(Block {
                kw,
                line: l,
                long,
                data: Vec::new(),
                notes: Vec::new(),
            });
        } else if let Some(b) = out.last_mut() {
            if is_alfe_note(&l.text) {
                if let Some((k, v)) = l.text["$alfe".len()..].split_once('=') {
                    b.notes.push((k.trim().to_string(), v.trim().to_string()));
                }
            } else {
                b.data.push(l);
            }
        }
    }
    out
}
