//! What an LS-DYNA keyword file's model keywords say, gathered by number for
//! [`super::lsdyna`] to write as an alfe deck.

use super::keyword_blocks::Block;
use std::collections::BTreeMap;

/// A section: the formulation and hourglass coefficient (deck text) of a solid's, the
/// thickness of a shell's.
#[derive(Clone, Default)]
pub(super) struct Section {
    pub(super) formulation: Option<String>,
    pub(super) hourglass: Option<String>,
    pub(super) thickness: Option<f64>,
}

/// What the file's model keywords say, by LS-DYNA number.
#[derive(Default)]
pub(super) struct Model {
    pub(super) title: String,
    pub(super) units: Option<String>,
    /// mid → (name, TOML body, modulus for the unit label).
    pub(super) materials: BTreeMap<i64, (String, String, f64)>,
    /// secid → its section.
    pub(super) sections: BTreeMap<i64, Section>,
    /// (pid, name, secid, mid, where).
    pub(super) parts: Vec<(i64, String, i64, i64, String)>,
    pub(super) solid_pids: Vec<i64>,
    pub(super) shell_pids: Vec<i64>,
    pub(super) node_sets: BTreeMap<i64, String>,
    pub(super) segment_sets: BTreeMap<i64, String>,
    /// lcid → (name, points).
    pub(super) curves: BTreeMap<i64, (String, Vec<[f64; 2]>)>,
    pub(super) used_sets: Vec<String>,
    pub(super) used_surfaces: Vec<String>,
    pub(super) used_curves: Vec<i64>,
    /// TOML tables in order: boundary, loads, walls, initial velocities.
    pub(super) tables: Vec<String>,
    /// (mid, lcid) of plasticity curves, resolved when written.
    pub(super) plastic_curves: Vec<(i64, i64)>,
    pub(super) end_time: Option<f64>,
    /// (IMFLAG, DT0)
    pub(super) implicit: Option<(i64, f64)>,
    /// (DTMIN, DTMAX)
    pub(super) auto: Option<(f64, f64)>,
    /// (scheme, rho_inf)
    pub(super) dynamics: Option<(String, Option<String>)>,
    /// (nonlinear, max iterations)
    pub(super) solver: Option<(String, i64)>,
    pub(super) entities: super::lsdyna_entities::Entities,
    /// `output = {…}` from an `$alfe` note, and the `[[quantities]]` entries.
    pub(super) record: Vec<String>,
    pub(super) quantities: Vec<String>,
    /// Node sets `[output]` names (declared in the deck though nothing else uses them).
    pub(super) record_sets: Vec<String>,
    /// `[solver]` lines from `$alfe` notes.
    pub(super) solver_notes: Vec<String>,
    pub(super) untranslated: Vec<String>,
}

impl Model {
    pub(super) fn skip(&mut self, b: &Block, why: &str) {
        self.untranslated
            .push(format!("{}: *{}: {why}", b.at(), b.kw));
    }
    pub(super) fn set(&mut self, sid: i64, b: &Block) -> Result<String, String> {
        let name = self.node_sets.get(&sid).cloned().ok_or_else(|| {
            format!(
                "{}: *{} names node set {sid}, which the file does not define",
                b.at(),
                b.kw
            )
        })?;
        if !self.used_sets.contains(&name) {
            self.used_sets.push(name.clone());
        }
        Ok(name)
    }
    pub(super) fn curve(&mut self, lcid: i64, b: &Block) -> Result<String, String> {
        let name = self.curves.get(&lcid).map(|c| c.0.clone()).ok_or_else(|| {
            format!(
                "{}: *{} names curve {lcid}, which no *DEFINE_CURVE defines",
                b.at(),
                b.kw
            )
        })?;
        if !self.used_curves.contains(&lcid) {
            self.used_curves.push(lcid);
        }
        Ok(name)
    }
}
