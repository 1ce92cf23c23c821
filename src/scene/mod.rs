//! Scenes: decks (TOML), the built-in ones embedded in the binary, and the builder that
//! turns a deck into a validated [`Scene`]: the model ([`crate::model::def::ModelDef`])
//! and how to run it ([`RunSettings`]). Deck types stay here: the layers below read
//! only what the scene parses the deck into.

pub mod build;
mod check;
mod context;
pub mod coupling;
pub mod deck;
mod dynamics;
mod formulation;
mod loads;
pub mod overrides;
pub mod pairs;
mod parts;
mod sanity;
mod sets;
mod settings;
pub mod steps;
pub mod walls;

use crate::model::def::ModelDef;
use crate::solve::nonlinear::NonlinearOptions;
use crate::solve::Analysis;
use crate::{Error, Result};
pub use overrides::Overrides;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

pub use deck::Units;

/// What a deck asks for: the model and how to run it.
#[derive(Debug, Clone)]
pub struct Scene {
    pub model: ModelDef,
    pub run: RunSettings,
}

/// How to run a scene: `[scene]`, `[analysis]`, `[solver]`, `[output]` resolved.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RunSettings {
    /// The scene's name (file names of its results).
    pub name: String,
    pub units: Units,
    pub analysis: Analysis,
    /// The nonlinear solver and its linear solves (`char_length` is set at run time).
    pub solver: NonlinearOptions,
    pub output: OutputSettings,
    /// The deck as read, defaults filled in (TOML), for the run's record (`deck.toml`).
    #[serde(default)]
    pub echo: String,
    /// The scene's quantities of interest.
    #[serde(default)]
    pub quantities: Vec<crate::output::quantities::QuantityDef>,
    /// Per part, its element types and the formulation each gets, truthfully (what
    /// `alfe check` prints and the run's record keeps).
    #[serde(default)]
    pub parts: Vec<String>,
    /// Choices known to lock (`parts[i]` with standard elements and ν > 0.45, a sheet
    /// of elements that lock in bending): printed by `alfe check`, and once at the start
    /// of `alfe run` on rank 0 (stderr and the log).
    #[serde(default)]
    pub warnings: Vec<String>,
}

/// When fields are written.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct OutputSettings {
    /// Static runs: every n-th converged step (the last always).
    pub every: usize,
    /// Dynamic runs: at every multiple of this time (and the initial and last states).
    pub interval: f64,
    /// Static runs with analysis steps: `every` of each step (its last increment always).
    pub stage_every: Vec<usize>,
    /// Every iteration's residual to `iterations.csv`.
    #[serde(default)]
    pub iterations: bool,
}

/// Built-in scenes: (name, one-line description, deck text).
pub const BUILTIN: &[(&str, &str, &str)] = &[
    (
        "cantilever",
        "hex8 neo-Hookean cantilever bent to large deflection by a tip load (default scene)",
        include_str!("scenes/cantilever.toml"),
    ),
    (
        "contact-patch",
        "two blocks with non-matching meshes in small-sliding contact: uniform pressure, then shear below mu (sticks)",
        include_str!("scenes/contact-patch.toml"),
    ),
    (
        "two-body-hertz",
        "two elastic cylinders of different materials pressed together: Hertz line contact through small-sliding pairs",
        include_str!("scenes/two-body-hertz.toml"),
    ),
    (
        "bolted-bracket",
        "L-bracket bolted to a base plate by four pretensioned bolts, then 1 kN out and back in X, then in Y (the paper's 3.7)",
        include_str!("scenes/bolted-bracket.toml"),
    ),
    (
        "scordelis-lo",
        "Scordelis–Lo roof: a thin cylindrical shell under its weight, one EAS hex8 through the thickness",
        include_str!("scenes/scordelis-lo.toml"),
    ),
    (
        "b-pillar",
        "hat-section steel channel pressed 100 mm by a cylindrical impactor on two supports (the paper's 3.4), EAS hex8 sheet",
        include_str!("scenes/b-pillar.toml"),
    ),
    (
        "patch-hex8",
        "patch test: distorted hex8 cube under homogeneous triaxial traction, linear elastic",
        include_str!("scenes/patch-hex8.toml"),
    ),
    (
        "patch-tet4",
        "patch test: tet4 cube under homogeneous triaxial traction, neo-Hookean",
        include_str!("scenes/patch-tet4.toml"),
    ),
    (
        "twisted-block",
        "neo-Hookean block twisted half a turn: large rotation, the solver comparison scene",
        include_str!("scenes/twisted-block.toml"),
    ),
    (
        "cube-stretch",
        "neo-Hookean cube stretched to twice its length between rollers (closed-form stress)",
        include_str!("scenes/cube-stretch.toml"),
    ),
    (
        "cook-membrane",
        "Cook's membrane, 3D finite strain, nu = 0.4999: hex8 F-bar against the published band",
        include_str!("scenes/cook-membrane.toml"),
    ),
    (
        "plastic-bar",
        "J2 steel bar pulled to 60 % elongation between clamps: large plastic strain",
        include_str!("scenes/plastic-bar.toml"),
    ),
    (
        "bar-vibration",
        "fixed-free elastic bar released with a uniform axial velocity (implicit dynamics)",
        include_str!("scenes/bar-vibration.toml"),
    ),
    (
        "sliding-block",
        "elastic block pressed on a rigid floor (mu = 0.3), then dragged: stick, then slip at mu N",
        include_str!("scenes/sliding-block.toml"),
    ),
    (
        "rubber-indent",
        "prismatic rigid indenter pushed 50 mm into a Mooney-Rivlin rubber block, mu = 0.1 (paper 3.3)",
        include_str!("scenes/rubber-indent.toml"),
    ),
    (
        "cylinder-press",
        "rigid cylinder pressed 30 % into a Mooney-Rivlin block, mu = 0.1, plane strain (refinement study)",
        include_str!("scenes/cylinder-press.toml"),
    ),
    (
        "taylor-bar",
        "copper bar at 227 m/s onto a rigid wall: implicit dynamics, ALM (paper 3.1)",
        include_str!("scenes/taylor-bar.toml"),
    ),
    (
        "clip-tensile",
        "plastic ring clip pulled by two cylindrical rigid pins with friction (paper 3.2)",
        include_str!("scenes/clip-tensile.toml"),
    ),
    (
        "coupled-cantilever",
        "cantilever loaded by a force, then a moment, through a distributing coupling (RBE3) at its tip",
        include_str!("scenes/coupled-cantilever.toml"),
    ),
    (
        "hertz-sphere",
        "rigid sphere R = 50 mm pressed 1 mm into an elastic block, frictionless (Hertz)",
        include_str!("scenes/hertz-sphere.toml"),
    ),
    (
        "sphere-roll",
        "rigid sphere entity pressed 40 mm into a rubber block, then dragged along a spiral: it rolls, mu = 0.45 (paper 3.5)",
        include_str!("scenes/sphere-roll.toml"),
    ),
    (
        "panel-dent",
        "rigid sphere entity pushed 50 mm into a curved elastic-plastic steel panel and back (paper 3.6)",
        include_str!("scenes/panel-dent.toml"),
    ),
];

/// The scene `alfe` and `alfe run` use when none is named.
pub const DEFAULT_SCENE: &str = "cantilever";

/// A deck's text and where it came from.
#[derive(Debug, Clone)]
pub struct Source {
    pub text: String,
    /// Directory relative mesh paths are resolved from.
    pub dir: PathBuf,
    /// How to refer to it in messages (scene name or file path).
    pub label: String,
}

/// Resolve a built-in scene name or a deck path.
pub fn load(name_or_path: &str) -> Result<Source> {
    if let Some((name, _, text)) = BUILTIN.iter().find(|(n, _, _)| *n == name_or_path) {
        return Ok(Source {
            text: text.to_string(),
            dir: PathBuf::from("."),
            label: name.to_string(),
        });
    }
    let p = Path::new(name_or_path);
    if p.is_file() {
        let text = std::fs::read_to_string(p)
            .map_err(|e| Error::input(format!("cannot read deck `{}`: {e}", p.display())))?;
        let dir = p
            .parent()
            .map(|d| {
                if d.as_os_str().is_empty() {
                    Path::new(".")
                } else {
                    d
                }
            })
            .unwrap_or(Path::new("."))
            .to_path_buf();
        return Ok(Source {
            text,
            dir,
            label: p.display().to_string(),
        });
    }
    let names: Vec<&str> = BUILTIN.iter().map(|(n, _, _)| *n).collect();
    Err(Error::input(format!(
        "unknown scene `{name_or_path}`: not a built-in scene ({}) and no deck file by that path",
        names.join(", ")
    )))
}

/// Parse, build and validate a scene.
pub fn read(src: &Source) -> Result<Scene> {
    read_with(src, &Overrides::default())
}

/// [`read`] with a study's changes to the deck ([`Overrides`]) made before it is built.
pub fn read_with(src: &Source, o: &Overrides) -> Result<Scene> {
    let mut deck =
        deck::parse(&src.text).map_err(|e| Error::input(format!("deck {}: {e}", src.label)))?;
    o.apply(&mut deck)?;
    let mut scene =
        build::build(&deck, &src.dir).map_err(|e| e.context(format!("deck {}", src.label)))?;
    scene.run.echo = echo(&deck, &src.dir);
    Ok(scene)
}

/// The deck as read, as TOML: every default filled in, empty lists left out, and mesh
/// files made absolute, so the echo runs as it stands from anywhere (`deck.toml` of a
/// run's record).
fn echo(deck: &deck::Deck, dir: &Path) -> String {
    let mut v = match toml::Value::try_from(deck) {
        Ok(v) => v,
        Err(e) => return format!("# (the deck as read cannot be written back: {e})\n"),
    };
    if let Some(t) = v.as_table_mut() {
        t.retain(|_, x| !matches!(x, toml::Value::Array(a) if a.is_empty()));
        let parts = t.get_mut("parts").and_then(|p| p.as_array_mut());
        for part in parts.into_iter().flatten() {
            let file = part
                .get_mut("mesh")
                .and_then(|m| m.get_mut("file"))
                .and_then(|f| match f {
                    toml::Value::String(s) => Some(s),
                    _ => None,
                });
            if let Some(f) = file {
                let p = dir.join(&*f);
                *f = std::fs::canonicalize(&p).unwrap_or(p).display().to_string();
            }
        }
    }
    toml::to_string(&v)
        .unwrap_or_else(|e| format!("# (the deck as read cannot be written back: {e})\n"))
}

#[cfg(test)]
mod tests {
    /// Every built-in scene's echo (`deck.toml` of a run) reads back as the same deck.
    #[test]
    fn echo_reads_back_as_the_same_deck() {
        for (name, _, text) in super::BUILTIN {
            let d = super::deck::parse(text).unwrap();
            let e = super::echo(&d, std::path::Path::new("."));
            let back = super::deck::parse(&e).unwrap_or_else(|err| panic!("{name}: {err}\n{e}"));
            assert_eq!(
                toml::Value::try_from(&d).unwrap(),
                toml::Value::try_from(&back).unwrap(),
                "{name}"
            );
        }
    }

    /// `preconditioner = "auto"` keeps block Jacobi for the classes AMG was measured
    /// not to suit, and names why; the others stay `auto` (AMG from a size on).
    #[test]
    fn auto_preconditioner_by_problem_class() {
        use crate::linalg::PcKind;
        let why = |name: &str| {
            let (_, _, text) = super::BUILTIN.iter().find(|b| b.0 == name).unwrap();
            let d = super::deck::parse(text).unwrap();
            (
                super::build::amg_unsuited(&d),
                super::build::build(&d, std::path::Path::new(".")).unwrap(),
            )
        };
        for name in ["hertz-sphere", "cantilever", "cube-stretch", "patch-hex8"] {
            let (reason, scene) = why(name);
            assert_eq!(reason, None, "{name}");
            // The built-in deck does not name a preconditioner; its run settings keep auto.
            assert_eq!(scene.run.solver.preconditioner, PcKind::Auto, "{name}");
        }
        for (name, expect) in [
            ("sliding-block", "wall 'floor' has friction"),
            ("rubber-indent", "nearly incompressible"),
            ("cook-membrane", "nearly incompressible"),
            ("plastic-bar", "plastic (j2)"),
            ("coupled-cantilever", "[[couplings]]"),
            ("twisted-block", "hybrid elements"),
        ] {
            let (reason, scene) = why(name);
            let reason = reason.unwrap_or_default();
            assert!(reason.contains(expect), "{name}: {reason}");
            let pc = scene.run.solver.preconditioner;
            // cook-membrane names ASM itself; "auto" elsewhere became the factored choice
            // (block Jacobi on one rank, ASM on more).
            assert!(
                matches!(pc, PcKind::AutoFactored | PcKind::Asm),
                "{name}: {pc:?}"
            );
        }
    }

    #[test]
    fn every_builtin_scene_parses() {
        for (name, _, text) in super::BUILTIN {
            let d = super::deck::parse(text).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(d.scene.name, *name);
        }
    }
}
