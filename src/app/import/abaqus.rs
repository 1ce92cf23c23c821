//! `alfe import FILE.inp`: an Abaqus/CalculiX input deck as an alfe TOML deck (issue 36).
//!
//! The mesh stays in the file (`mesh = { kind = "abaqus" }`, read by
//! [`crate::mesh::abaqus`]); where the model refers to a node or an element by number
//! (`*BOUNDARY` on node 3, `*DLOAD` on element 7) the importer writes a companion file,
//! `DECK.sets.inp`, that `*INCLUDE`s the original and names those as sets, and the deck
//! reads the companion. Translated: `*HEADING`, `*MATERIAL` with `*ELASTIC` (isotropic),
//! `*DENSITY`, `*PLASTIC` (isotropic hardening table → j2), `*HYPERELASTIC`
//! (NEO HOOKE, MOONEY-RIVLIN), `*SOLID SECTION`, `*STEP` with `*STATIC`,
//! `*BOUNDARY`, `*CLOAD`, `*DLOAD` (P1…P6 pressures). Every other keyword, option or data
//! line is listed with its line, in the deck's header and on stderr: nothing is dropped
//! silently. Numbers are the file's: the deck's unit label is chosen from E's size and
//! says so. A file `alfe export` wrote carries `** alfe` notes: see [`super::abaqus_notes`].

use crate::mesh::abaqus::{
    fields, flag, keyword, param, read_inp, read_lines, read_surface_inp, Line, Loader,
};

/// The node groups the model may name (a solid mesh's, or a sheet's facet and point
/// groups).
type Groups = Vec<String>;
use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::Path;

/// What `import` produced.
#[derive(Debug)]
pub struct Imported {
    /// The deck's TOML text.
    pub deck: String,
    /// The companion `.inp` (its text), when the model names nodes or elements by number.
    pub companion: Option<String>,
    /// Every keyword, option or line not translated, with where it is.
    pub untranslated: Vec<String>,
}

#[derive(Debug, Default, Clone)]
struct Material {
    name: String,
    line: String,
    e: Option<f64>,
    nu: Option<f64>,
    density: f64,
    plastic: Vec<[f64; 2]>,
    /// (C10, C01, D1) of a hyperelastic material.
    hyper: Option<(f64, f64, f64)>,
}

/// A boundary condition or load, with the set it acts on.
#[derive(Debug, Clone)]
enum Action {
    Fixed {
        set: String,
        comps: Vec<usize>,
    },
    Displacement {
        set: String,
        comps: Vec<usize>,
        value: f64,
    },
    Nodal {
        set: String,
        force: [f64; 3],
    },
    Pressure {
        surface: String,
        value: f64,
    },
}

#[derive(Debug, Default)]
struct Model {
    heading: String,
    materials: Vec<Material>,
    /// (where, element set, material) of the solid section.
    section: Option<(String, String, String)>,
    /// Element types by *ELEMENT line, for the part's formulation.
    element_types: Vec<(String, String)>,
    nlgeom: bool,
    /// (initial increment, period) of the static step.
    step: Option<(f64, f64)>,
    actions: Vec<Action>,
    untranslated: Vec<String>,
    /// The shell section's thickness: the model is a sheet.
    shell: Option<f64>,
    /// Whether the follower-pressure note was made.
    pressure_noted: bool,
    /// Companion sets: (keyword line, data lines).
    companion: Vec<(String, Vec<String>)>,
    /// Node sets the deck defines: name → mesh group.
    node_sets: BTreeMap<String, String>,
    /// Surfaces the deck defines: name → mesh group.
    surfaces: BTreeMap<String, String>,
    /// Ties, contact pairs and couplings; their TOML once resolved.
    contact: (super::abaqus_contact::Contact, String),
}

fn num(s: &str, line: &Line) -> Result<f64, String> {
    let v: f64 = s.parse().map_err(|_| {
        format!(
            "{}: expected a number, got `{s}` in `{}`",
            line.at(),
            line.text
        )
    })?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("{}: `{s}` is not finite", line.at()))
    }
}

impl Model {
    fn skip(&mut self, line: &Line, why: &str) {
        self.untranslated
            .push(format!("{}: `{}`: {why}", line.at(), line.text));
    }

    /// The mesh group a model line's target names (a set, any case) or a companion set
    /// for a node number.
    fn node_target(&mut self, target: &str, mesh: &Groups, line: &Line) -> Result<String, String> {
        if let Ok(n) = target.parse::<u64>() {
            let name = format!("node-{n}");
            if !self.node_sets.contains_key(&name) {
                self.companion
                    .push((format!("*NSET, NSET={name}"), vec![n.to_string()]));
                self.node_sets.insert(name.clone(), name.clone());
            }
            return Ok(name);
        }
        let Some(group) = mesh.iter().find(|k| k.eq_ignore_ascii_case(target)) else {
            return Err(format!(
                "{}: `{target}` is not a node set of the mesh",
                line.at()
            ));
        };
        self.node_sets.insert(group.clone(), group.clone());
        Ok(group.clone())
    }

    /// A surface for a `*DLOAD` line's element (number or set) and face.
    fn face_target(&mut self, target: &str, face: usize) -> String {
        let name = format!("dload-{}-s{face}", target.to_ascii_lowercase());
        if !self.surfaces.contains_key(&name) {
            self.companion.push((
                format!("*SURFACE, NAME={name}, TYPE=ELEMENT"),
                vec![format!("{target}, S{face}")],
            ));
            self.surfaces.insert(name.clone(), name.clone());
        }
        name
    }

    fn boundary(&mut self, f: &[&str], line: &Line, mesh: &Groups) -> Result<(), String> {
        if f.len() < 2 {
            return Err(format!(
                "{}: a *BOUNDARY line is `node or set, first dof[, last dof[, value]]`",
                line.at()
            ));
        }
        let set = self.node_target(f[0], mesh, line)?;
        let first: usize = num(f[1], line)? as usize;
        let last: usize = match f.get(2).filter(|s| !s.is_empty()) {
            Some(s) => num(s, line)? as usize,
            None => first,
        };
        let value = match f.get(3) {
            Some(s) => num(s, line)?,
            None => 0.0,
        };
        if first == 0 || last < first {
            return Err(format!(
                "{}: degrees of freedom {first} to {last}",
                line.at()
            ));
        }
        let comps: Vec<usize> = (first..=last.min(3)).map(|d| d - 1).collect();
        if last > 3 {
            self.skip(
                line,
                "degrees of freedom above 3 (rotations, temperature) have no meaning on solids",
            );
        }
        if comps.is_empty() {
            return Ok(());
        }
        self.actions.push(if value == 0.0 {
            Action::Fixed { set, comps }
        } else {
            Action::Displacement { set, comps, value }
        });
        Ok(())
    }

    fn cload(&mut self, f: &[&str], line: &Line, mesh: &Groups) -> Result<(), String> {
        if f.len() < 3 {
            return Err(format!(
                "{}: a *CLOAD line is `node or set, dof, magnitude`",
                line.at()
            ));
        }
        let set = self.node_target(f[0], mesh, line)?;
        let dof = num(f[1], line)? as usize;
        let value = num(f[2], line)?;
        if !(1..=3).contains(&dof) {
            self.skip(
                line,
                "a moment or other load on a degree of freedom above 3",
            );
            return Ok(());
        }
        let mut force = [0.0; 3];
        force[dof - 1] = value;
        self.actions.push(Action::Nodal { set, force });
        Ok(())
    }

    fn dload(&mut self, f: &[&str], line: &Line) -> Result<(), String> {
        if f.len() < 3 {
            return Err(format!(
                "{}: a *DLOAD line is `element or set, load type, magnitude`",
                line.at()
            ));
        }
        let ty = f[1].to_ascii_uppercase();
        if self.shell.is_some() {
            self.skip(line, "distributed loads on shells are not translated");
            return Ok(());
        }
        let Some(face) = ty.strip_prefix('P').and_then(|k| k.parse::<usize>().ok()) else {
            self.skip(
                line,
                "only pressures P1 to P6 on element faces are translated",
            );
            return Ok(());
        };
        let value = num(f[2], line)?;
        if !self.nlgeom && !self.pressure_noted {
            self.pressure_noted = true;
            self.skip(
                line,
                "the step has no NLGEOM, so Abaqus keeps this pressure on the reference surface; alfe's pressure follows the deformed one (answers differ at second order in the strain)",
            );
        }
        let surface = self.face_target(f[0], face);
        self.actions.push(Action::Pressure { surface, value });
        Ok(())
    }
}

/// What a keyword's data lines are.
#[derive(Clone, Copy, PartialEq)]
enum Block {
    Heading,
    Mesh,
    Elastic,
    Density,
    Plastic,
    Hyper {
        mooney: bool,
    },
    Static,
    ShellThickness,
    Boundary,
    Cload,
    Dload,
    /// Listed line by line as not translated.
    Skip,
    Contact,
    /// Output requests: listed once, data lines not.
    Quiet,
}

/// Read the keyword line `line` (keyword `kw`) into the model; its data lines' block.
fn open_keyword(m: &mut Model, line: &Line, kw: &str) -> Block {
    let t = &line.text;
    match kw {
        "HEADING" => Block::Heading,
        "ELEMENT" => {
            if let Some(ty) = param(t, "TYPE") {
                m.element_types.push((line.at(), ty.to_ascii_uppercase()));
            }
            Block::Mesh
        }
        "NODE" | "NSET" | "ELSET" | "SURFACE" => Block::Mesh,
        "MATERIAL" => {
            m.materials.push(Material {
                name: param(t, "NAME").unwrap_or_default(),
                line: line.at(),
                ..Default::default()
            });
            Block::Quiet
        }
        "ELASTIC" => {
            if param(t, "TYPE").is_some_and(|v| {
                !v.eq_ignore_ascii_case("ISO") && !v.eq_ignore_ascii_case("ISOTROPIC")
            }) {
                m.skip(line, "only isotropic elasticity is translated");
                return Block::Skip;
            }
            Block::Elastic
        }
        "DENSITY" => Block::Density,
        "PLASTIC" => {
            if param(t, "HARDENING").is_some_and(|v| !v.eq_ignore_ascii_case("ISOTROPIC")) {
                m.skip(line, "only isotropic hardening is translated");
                return Block::Skip;
            }
            Block::Plastic
        }
        "HYPERELASTIC" => {
            let mooney = flag(t, "MOONEY-RIVLIN");
            if !mooney && !flag(t, "NEO HOOKE") {
                m.skip(line, "only NEO HOOKE and MOONEY-RIVLIN are translated");
                return Block::Skip;
            }
            Block::Hyper { mooney }
        }
        "SHELL SECTION" => {
            let (Some(elset), Some(mat)) = (param(t, "ELSET"), param(t, "MATERIAL")) else {
                m.skip(line, "a shell section needs ELSET= and MATERIAL=");
                return Block::Quiet;
            };
            if m.shell.is_some() {
                m.skip(line, "a second shell section: the imported sheet has the first one's thickness and material");
                return Block::Quiet;
            }
            m.section = Some((line.at(), elset, mat));
            Block::ShellThickness
        }
        "SOLID SECTION" => {
            let (Some(elset), Some(mat)) = (param(t, "ELSET"), param(t, "MATERIAL")) else {
                m.skip(line, "a solid section needs ELSET= and MATERIAL=");
                return Block::Quiet;
            };
            if param(t, "ORIENTATION").is_some() {
                m.skip(
                    line,
                    "ORIENTATION: isotropic materials do not need one; ignored",
                );
            }
            match &m.section {
                Some((_, _, old)) if !old.eq_ignore_ascii_case(&mat) => m.skip(
                    line,
                    "a second material: the imported deck is one part of one material (the first section's)",
                ),
                _ => m.section = Some((line.at(), elset, mat)),
            }
            Block::Quiet
        }
        "STEP" => {
            if m.step.is_some() {
                m.skip(line, "a second step: only the first step is translated");
                return Block::Skip;
            }
            m.nlgeom = flag(t, "NLGEOM")
                || param(t, "NLGEOM").is_some_and(|v| v.eq_ignore_ascii_case("YES"));
            m.step = Some((1.0, 1.0));
            Block::Quiet
        }
        "STATIC" => Block::Static,
        "DYNAMIC"
        | "FREQUENCY"
        | "BUCKLE"
        | "HEAT TRANSFER"
        | "COUPLED TEMPERATURE-DISPLACEMENT"
        | "VISCO"
        | "MODAL DYNAMIC"
        | "STEADY STATE DYNAMICS"
        | "GREEN"
        | "SENSITIVITY" => {
            m.skip(
                line,
                "analysis procedure not translated: the imported deck's analysis is static",
            );
            Block::Skip
        }
        "END STEP" => Block::Quiet,
        "BOUNDARY" | "CLOAD" | "DLOAD" => {
            if param(t, "AMPLITUDE").is_some() {
                m.skip(
                    line,
                    "AMPLITUDE: the imported load ramps linearly over the step",
                );
            }
            match kw {
                "BOUNDARY" => Block::Boundary,
                "CLOAD" => Block::Cload,
                _ => Block::Dload,
            }
        }
        _ if super::abaqus_contact::KEYWORDS.contains(&kw) => {
            m.contact.0.open(line, kw, &mut m.untranslated);
            Block::Contact
        }
        _ if super::abaqus_contact::OUTPUT_KEYWORDS.contains(&kw) => {
            m.skip(
                line,
                "output request: alfe writes every field to its HDF5 file",
            );
            Block::Quiet
        }
        _ => {
            m.skip(line, "keyword not translated");
            Block::Skip
        }
    }
}

fn data_line(m: &mut Model, block: Block, line: &Line, mesh: &Groups) -> Result<(), String> {
    let f = fields(&line.text);
    let at = |k: usize| f.get(k).copied().unwrap_or("");
    let material = matches!(
        block,
        Block::Elastic | Block::Density | Block::Plastic | Block::Hyper { .. }
    );
    if material && m.materials.is_empty() {
        m.skip(line, "material data outside a *MATERIAL");
        return Ok(());
    }
    match block {
        Block::Heading => {
            if m.heading.is_empty() {
                m.heading = line.text.clone();
            }
        }
        Block::Mesh | Block::Quiet => {}
        Block::Elastic => {
            let (e, nu) = (num(at(0), line)?, num(at(1), line)?);
            let mat = m.materials.last_mut().expect("checked");
            let first = mat.e.is_none();
            if first {
                (mat.e, mat.nu) = (Some(e), Some(nu));
            }
            if !first || f.len() > 2 {
                m.skip(
                    line,
                    "temperature dependence: the first line's E and nu are taken",
                );
            }
        }
        Block::Density => {
            let rho = num(at(0), line)?;
            m.materials.last_mut().expect("checked").density = rho;
        }
        Block::Plastic => {
            let s = num(at(0), line)?;
            let e = if at(1).is_empty() {
                0.0
            } else {
                num(at(1), line)?
            };
            m.materials
                .last_mut()
                .expect("checked")
                .plastic
                .push([e, s]);
        }
        Block::Hyper { mooney } => {
            let v: Vec<f64> = f.iter().map(|s| num(s, line)).collect::<Result<_, _>>()?;
            let g = |k: usize| v.get(k).copied().unwrap_or(0.0);
            let c = if mooney {
                (g(0), g(1), g(2))
            } else {
                (g(0), 0.0, g(1))
            };
            let mat = m.materials.last_mut().expect("checked");
            if mat.hyper.is_none() {
                mat.hyper = Some(c);
            } else {
                m.skip(
                    line,
                    "temperature dependence: the first line's constants are taken",
                );
            }
        }
        Block::Static => {
            let opt = |k: usize| -> Result<Option<f64>, String> {
                f.get(k)
                    .filter(|s| !s.is_empty())
                    .map(|s| num(s, line))
                    .transpose()
            };
            let period = opt(1)?.unwrap_or(1.0);
            let init = opt(0)?.unwrap_or(period).min(period);
            m.step = Some((init, period));
            if f.len() > 2 {
                m.skip(
                    line,
                    "minimum and maximum increments: alfe's stepping chooses its own",
                );
            }
        }
        Block::ShellThickness => {
            let t = num(at(0), line)?;
            if t <= 0.0 {
                return Err(format!(
                    "{}: a shell thickness must be positive, got {t}",
                    line.at()
                ));
            }
            if m.shell.is_none() {
                m.shell = Some(t);
            }
            if f.len() > 1 {
                m.skip(
                    line,
                    "integration points and other section data: alfe's sheet has one solid layer",
                );
            }
        }
        Block::Boundary | Block::Cload
            if m.contact
                .0
                .reference_line(&f, line, block == Block::Boundary)? => {}
        Block::Boundary => m.boundary(&f, line, mesh)?,
        Block::Cload => m.cload(&f, line, mesh)?,
        Block::Contact => m.contact.0.data(line, &mut m.untranslated)?,
        Block::Dload => m.dload(&f, line)?,
        Block::Skip => m.skip(line, "data of a keyword not translated"),
    }
    Ok(())
}

/// Import `path` (an `.inp`) as the deck `deck_path` will hold: the deck text, the
/// companion file's text and what was not translated.
pub fn import_inp(path: &Path, deck_path: &Path, load: &Loader) -> Result<Imported, String> {
    let lines = read_lines(path, load)?;
    let shells = lines
        .iter()
        .any(|l| keyword(&l.text).as_deref() == Some("SHELL SECTION"));
    // Validate the mesh as what the deck will read it as; the names it may refer to.
    let (mesh, faces): (Groups, Groups) = if shells {
        let s = read_surface_inp(path, load)?;
        let g = s.point_groups.keys().chain(s.quad_groups.keys());
        (g.cloned().collect(), Vec::new())
    } else {
        let r = read_inp(path, 0, load)?;
        (
            r.node_groups.into_keys().collect(),
            r.face_groups.into_keys().collect(),
        )
    };
    let notes = super::abaqus_notes::read(&load(path)?, path)?;
    let mut m = Model::default();
    if notes.is_none() {
        m.contact.0 = super::abaqus_contact::Contact::new(&lines);
    }
    let mut block = Block::Skip;
    for line in lines
        .iter()
        .filter(|l| !notes.as_ref().is_some_and(|n| n.in_layer(l)))
    {
        if let Some(kw) = keyword(&line.text) {
            block = match &notes {
                Some(n) if n.covers(&kw) => Block::Quiet,
                _ => open_keyword(&mut m, line, &kw),
            };
            continue;
        }
        data_line(&mut m, block, line, &mesh)?;
    }
    m.contact.1 = m.contact.0.resolve(
        &faces,
        &mesh,
        &mut m.surfaces,
        &mut m.node_sets,
        &mut m.untranslated,
    );
    let mut imported = write_deck(&m, path, deck_path)?;
    if let Some(n) = &notes {
        imported.deck = n.apply(&imported.deck, &lines)?;
        if n.edited {
            imported.untranslated.push(n.edited_warning());
        }
    }
    Ok(imported)
}

/// A path as the deck should name it: relative to the deck's directory where it can be.
pub(super) fn relative(file: &Path, deck_path: &Path) -> String {
    let dir = deck_path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let file_abs = std::path::absolute(file).unwrap_or(file.to_path_buf());
    let dir_abs = std::path::absolute(dir).unwrap_or(dir.to_path_buf());
    file_abs
        .strip_prefix(&dir_abs)
        .map(|p| p.display().to_string())
        .unwrap_or_else(|_| file_abs.display().to_string())
}

pub(super) fn toml_str(s: &str) -> String {
    format!("{:?}", s)
}

/// Deck component names by index.
pub(super) const XYZ: [&str; 3] = ["x", "y", "z"];

fn write_material(
    out: &mut String,
    mat: &Material,
    nlgeom: bool,
    untranslated: &mut Vec<String>,
) -> Result<(), String> {
    let _ = writeln!(out, "\n[[materials]]\nname = {}", toml_str(&mat.name));
    if let Some((c10, c01, d1)) = mat.hyper {
        let mu = 2.0 * (c10 + c01);
        let nu = if d1 > 0.0 {
            let k = 2.0 / d1;
            (3.0 * k - 2.0 * mu) / (2.0 * (3.0 * k + mu))
        } else {
            untranslated.push(format!(
                "{}: D1 = 0 (incompressible): taken as nu = 0.4995",
                mat.line
            ));
            0.4995
        };
        if c01 != 0.0 {
            let _ = writeln!(
                out,
                "model = \"mooney-rivlin\"\nC10 = {c10:e}\nC01 = {c01:e}\nnu = {nu}"
            );
        } else {
            let e = 2.0 * mu * (1.0 + nu);
            let _ = writeln!(out, "model = \"neo-hookean\"\nE = {e:e}\nnu = {nu}");
        }
    } else {
        let (Some(e), Some(nu)) = (mat.e, mat.nu) else {
            return Err(format!(
                "{}: material `{}` has no *ELASTIC or *HYPERELASTIC data",
                mat.line, mat.name
            ));
        };
        if mat.plastic.is_empty() {
            let model = if nlgeom {
                "neo-hookean"
            } else {
                "linear-elastic"
            };
            let _ = writeln!(out, "model = \"{model}\"\nE = {e:e}\nnu = {nu}");
        } else {
            let sy = mat.plastic[0][1];
            let pts: Vec<String> = mat
                .plastic
                .iter()
                .map(|p| format!("[{:e}, {:e}]", p[0], p[1]))
                .collect();
            let _ = writeln!(
                out,
                "model = \"j2\"\nE = {e:e}\nnu = {nu}\nyield_stress = {sy:e}\nhardening = {{ type = \"table\", points = [{}] }}",
                pts.join(", ")
            );
        }
    }
    if mat.density > 0.0 {
        let _ = writeln!(out, "density = {:e}", mat.density);
    }
    Ok(())
}

/// The formulation the file's element types ask for, where they agree: C3D8R reduced
/// (alfe's has an hourglass spring, Abaqus' enhanced hourglass control differs), C3D8I
/// EAS (incompatible modes, as Abaqus' C3D8I), the H types hybrid (hyperelastic
/// materials only: alfe's hybrid element needs a volumetric split), the plain types
/// standard. None (auto) where they disagree, with a note.
fn formulation_of(
    types: &[(String, String)],
    mat: &Material,
    notes: &mut Vec<String>,
) -> Option<&'static str> {
    let form = |t: &str| -> &'static str {
        let t = t
            .trim_start_matches("C3D")
            .trim_start_matches(|c: char| c.is_ascii_digit());
        match t {
            "R" => "reduced",
            "I" => "eas",
            _ if t.contains('H') => "hybrid",
            _ => "standard",
        }
    };
    let (first_at, first) = types.first()?;
    if types.iter().any(|(_, t)| !t.starts_with("C3D")) {
        // Shells become a sheet, whose `auto` is the EAS element.
        return None;
    }
    let f = form(first);
    if let Some((at, other)) = types.iter().find(|(_, t)| form(t) != f) {
        notes.push(format!(
            "{at}: element type {other} differs from {first} ({first_at}) in formulation: the part takes formulation = \"auto\""
        ));
        return None;
    }
    if f == "hybrid" && mat.hyper.is_none() {
        notes.push(format!(
            "{first_at}: {first}: alfe's hybrid element needs a hyperelastic material; the part takes formulation = \"auto\""
        ));
        return None;
    }
    Some(f)
}

fn write_deck(m: &Model, path: &Path, deck_path: &Path) -> Result<Imported, String> {
    let mut untranslated = m.untranslated.clone();
    let name = path
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("imported")
        .to_string();
    let companion_path = deck_path.with_extension("sets.inp");
    let mesh_file = if m.companion.is_empty() {
        relative(path, deck_path)
    } else {
        relative(&companion_path, deck_path)
    };
    let mat = match &m.section {
        Some((at, _, mat)) => m
            .materials
            .iter()
            .find(|x| x.name.eq_ignore_ascii_case(mat))
            .ok_or_else(|| {
                format!("{at}: *SOLID SECTION names material `{mat}`, which no *MATERIAL defines")
            })?,
        None => m
            .materials
            .first()
            .ok_or_else(|| format!("{}: the file defines no *MATERIAL", path.display()))?,
    };
    let formulation = formulation_of(&m.element_types, mat, &mut untranslated);
    let e = mat
        .e
        .unwrap_or(2.0 * (mat.hyper.map_or(0.0, |h| h.0 + h.1)));
    let units = if e > 1e7 { "m-kg-s" } else { "mm-t-s" };
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# Imported by `alfe import` from {} ({}).",
        path.display(),
        crate::VERSION
    );
    let _ = writeln!(out, "# Numbers are the file's: units = \"{units}\" is a label chosen from E = {e:e} (check it).");
    if !m.companion.is_empty() {
        let _ = writeln!(
            out,
            "# The mesh is read through {} (the original plus the sets the model names by number).",
            mesh_file
        );
    }
    if untranslated.is_empty() {
        let _ = writeln!(out, "# Every keyword was translated.");
    } else {
        let _ = writeln!(out, "# Not translated ({}):", untranslated.len());
        for u in &untranslated {
            let _ = writeln!(out, "#   {u}");
        }
    }
    let _ = writeln!(
        out,
        "\n[scene]\nname = {}\ndescription = {}\nunits = \"{units}\"",
        toml_str(&name),
        toml_str(&m.heading)
    );
    write_material(&mut out, mat, m.nlgeom, &mut untranslated)?;
    let _ = writeln!(
        out,
        "\n[[parts]]\nname = \"model\"\nmaterial = {}{}\nmesh = {}",
        toml_str(&mat.name),
        formulation.map_or(String::new(), |f| format!("\nformulation = \"{f}\"")),
        match m.shell {
            Some(t) => format!(
                "{{ kind = \"sheet\", file = {}, thickness = {t:e} }}",
                toml_str(&mesh_file)
            ),
            None => format!("{{ kind = \"abaqus\", file = {} }}", toml_str(&mesh_file)),
        }
    );
    for (n, g) in &m.node_sets {
        let _ = writeln!(
            out,
            "\n[[node_sets]]\nname = {}\ngroup = {}",
            toml_str(n),
            toml_str(g)
        );
    }
    for (n, g) in &m.surfaces {
        let _ = writeln!(
            out,
            "\n[[surfaces]]\nname = {}\ngroup = {}",
            toml_str(n),
            toml_str(g)
        );
    }
    write_actions(&mut out, &m.actions);
    out += &m.contact.1;
    let (init, period) = m.step.unwrap_or((1.0, 1.0));
    let _ = writeln!(
        out,
        "\n[analysis]\ntype = \"static\"\nend_time = {period:e}\nstep = {init:e}"
    );
    let companion = (!m.companion.is_empty()).then(|| {
        let mut c = format!(
            "** Written by `alfe import`: {} and the sets its model names by number.\n*INCLUDE, INPUT={}\n",
            path.display(),
            relative(path, &companion_path)
        );
        for (kw, data) in &m.companion {
            c += kw;
            c.push('\n');
            for d in data {
                c += d;
                c.push('\n');
            }
        }
        c
    });
    Ok(Imported {
        deck: out,
        companion,
        untranslated,
    })
}

fn write_actions(out: &mut String, actions: &[Action]) {
    let comps = |c: &[usize]| -> String {
        c.iter()
            .map(|&k| format!("\"{}\"", XYZ[k]))
            .collect::<Vec<_>>()
            .join(", ")
    };
    for a in actions {
        match a {
            Action::Fixed { set, comps: c } => {
                let _ = writeln!(
                    out,
                    "\n[[boundary]]\ntype = \"fixed\"\nset = {}\ncomponents = [{}]",
                    toml_str(set),
                    comps(c)
                );
            }
            Action::Displacement {
                set,
                comps: c,
                value,
            } => {
                let _ = writeln!(
                    out,
                    "\n[[boundary]]\ntype = \"displacement\"\nset = {}\ncomponents = [{}]\nvalue = {value:e}",
                    toml_str(set),
                    comps(c)
                );
            }
            Action::Nodal { set, force } => {
                let _ = writeln!(
                    out,
                    "\n[[loads]]\ntype = \"nodal\"\nset = {}\nforce = [{:e}, {:e}, {:e}]",
                    toml_str(set),
                    force[0],
                    force[1],
                    force[2]
                );
            }
            Action::Pressure { surface, value } => {
                let _ = writeln!(
                    out,
                    "\n[[loads]]\ntype = \"pressure\"\nsurface = {}\npressure = {value:e}",
                    toml_str(surface)
                );
            }
        }
    }
}
