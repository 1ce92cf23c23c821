//! Changes a study makes to a deck without editing it (`alfe run --refine K
//! --step-scale F --contact M --penalty-scale S`, issue 17): the same scene on a finer
//! mesh, with other increments, another contact enforcement or penalty stiffness. They
//! are made to the deck, so the run's `deck.toml` is the deck as run and a restart from
//! it builds the same model.

use super::deck::{Deck, MeshDeck};
use crate::contact::wall::ContactMethod;
use crate::{Error, Result};

/// What to change; the default changes nothing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Overrides {
    /// Cells of every generated mesh multiplied by this (1: none). A direction with one
    /// cell keeps it (a plane-strain slice, one element through a thin wall); `blocks`
    /// divide their cell sizes, sheets from a surface mesh multiply their layers only
    /// where they have more than one, Gmsh volumes cannot be refined.
    pub refine: usize,
    /// `[analysis]` and every `[[steps]]` increment (step, min_step, max_step) times this.
    pub step_scale: f64,
    /// The penalty stiffness of every wall, entity and pair (`penalty_scale`), where set.
    pub penalty_scale: Option<f64>,
    /// The enforcement of every wall, entity and pair (`--contact`), where set; a bolt's
    /// section stays ALM (a penalty tie lets the section creep: 6 % on
    /// `tests/bolt-bar.toml`).
    pub contact: Option<ContactMethod>,
    /// `[solver.linear] preconditioner` and `overlap`, where set (`--preconditioner`,
    /// `--overlap`): the scaling study runs one deck with each.
    pub preconditioner: Option<crate::linalg::PcKind>,
    pub overlap: Option<usize>,
}

impl Default for Overrides {
    fn default() -> Self {
        Self {
            refine: 1,
            step_scale: 1.0,
            penalty_scale: None,
            contact: None,
            preconditioner: None,
            overlap: None,
        }
    }
}

impl Overrides {
    /// Check the values themselves (the flags that set them are named).
    pub fn validate(&self) -> Result<()> {
        if self.refine == 0 || self.refine > 64 {
            return Err(Error::input(format!(
                "--refine: expected a factor from 1 to 64, got {}",
                self.refine
            )));
        }
        if !(self.step_scale.is_finite() && self.step_scale > 0.0) {
            return Err(Error::input(format!(
                "--step-scale: expected a positive factor, got {}",
                self.step_scale
            )));
        }
        if let Some(p) = self.penalty_scale {
            if !(p.is_finite() && p > 0.0) {
                return Err(Error::input(format!(
                    "--penalty-scale: expected a positive factor, got {p}"
                )));
            }
        }
        Ok(())
    }

    /// Apply to a parsed deck. Refining a deck that has a Gmsh volume mesh is refused:
    /// its mesh is the user's.
    pub fn apply(&self, deck: &mut Deck) -> Result<()> {
        self.validate()?;
        let k = self.refine;
        let up = |n: &mut usize| {
            if *n > 1 {
                // Saturating: the model-size check refuses what does not fit.
                *n = n.saturating_mul(k);
            }
        };
        if k > 1 {
            for (i, p) in deck.parts.iter_mut().enumerate() {
                match &mut p.mesh {
                    MeshDeck::Box { cells, .. }
                    | MeshDeck::ExtrudedQuad { cells, .. }
                    | MeshDeck::Ring { cells, .. } => cells.iter_mut().for_each(up),
                    MeshDeck::Cylinder {
                        cells_radial,
                        cells_axial,
                        ..
                    } => {
                        *cells_radial = cells_radial.saturating_mul(k);
                        up(cells_axial);
                    }
                    MeshDeck::Blocks {
                        cell_size, refine, ..
                    } => {
                        *cell_size /= k as f64;
                        for r in refine {
                            r.cell_size /= k as f64;
                        }
                    }
                    MeshDeck::Sheet { layers, .. } => up(layers),
                    MeshDeck::Gmsh { .. }
                    | MeshDeck::Abaqus { .. }
                    | MeshDeck::LsDyna { .. }
                    | MeshDeck::File { .. } => {
                        return Err(Error::input(format!(
                        "--refine: parts[{i}] is read from a mesh file, which alfe cannot refine"
                    )))
                    }
                }
            }
        }
        if self.step_scale != 1.0 {
            let f = self.step_scale;
            let a = &mut deck.analysis;
            a.step *= f;
            a.min_step = a.min_step.map(|x| x * f);
            a.max_step = a.max_step.map(|x| x * f);
            for s in &mut deck.steps {
                s.step = s.step.map(|x| x * f);
                s.min_step = s.min_step.map(|x| x * f);
                s.max_step = s.max_step.map(|x| x * f);
            }
        }
        if let Some(pc) = self.preconditioner {
            deck.solver.linear.preconditioner = pc;
        }
        if let Some(o) = self.overlap {
            deck.solver.linear.overlap = o;
        }
        let (m, p) = (self.contact, self.penalty_scale);
        for w in deck.walls.iter_mut().chain(deck.entities.iter_mut()) {
            w.method = m.unwrap_or(w.method);
            w.penalty_scale = p.unwrap_or(w.penalty_scale);
        }
        for pr in &mut deck.pairs {
            pr.method = m.unwrap_or(pr.method);
            pr.penalty_scale = p.unwrap_or(pr.penalty_scale);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::def::ContributionDef;

    /// `--contact penalty` is made to the deck: the echo (`deck.toml`) says it, so a
    /// restart from it builds the same model; a bolt's section stays ALM.
    #[test]
    fn contact_is_set_in_the_deck_and_bolts_stay_alm() {
        let src = crate::scene::load("bolted-bracket").unwrap();
        let o = Overrides {
            contact: Some(ContactMethod::Penalty),
            ..Default::default()
        };
        let scene = crate::scene::read_with(&src, &o).unwrap();
        let echo = crate::scene::deck::parse(&scene.run.echo).unwrap();
        assert!(!echo.pairs.is_empty() && !echo.bolts.is_empty());
        assert!(echo
            .pairs
            .iter()
            .all(|p| p.method == ContactMethod::Penalty));
        let (mut bolts, mut pairs) = (0, 0);
        for c in &scene.model.contributions {
            if let ContributionDef::Pairs(p) = c {
                if p.pretension.is_some() {
                    bolts += 1;
                    assert_eq!(p.method, ContactMethod::Alm, "{}", p.name);
                } else {
                    pairs += 1;
                    assert_eq!(p.method, ContactMethod::Penalty, "{}", p.name);
                }
            }
        }
        assert_eq!((bolts, pairs), (echo.bolts.len(), echo.pairs.len()));
    }
}
