//! `alfe import FILE.k`: an LS-DYNA keyword deck as an alfe TOML deck (issue 36).
//!
//! The mesh stays in the file (`mesh = { kind = "lsdyna", file, pid }`: one alfe part per
//! LS-DYNA part with solids, each with its material and section). Translated:
//! `*TITLE`; `*MAT_ELASTIC`, `*MAT_MOONEY-RIVLIN_RUBBER`, `*MAT_HYPERELASTIC_RUBBER`
//! (C10, C01), `*MAT_PIECEWISE_LINEAR_PLASTICITY` (LCSS, the EPS/ES table or ETAN),
//! `*MAT_PLASTIC_KINEMATIC` (isotropic); `*PART`; `*SECTION_SOLID` (ELFORM 1 reduced,
//! 2/−1/−2 F-bar, 18 EAS, 10/16/15 standard tet4/tet10/wedge), `*SECTION_SHELL` (a
//! shell-only file becomes a sheet of thickness T1); node and segment sets;
//! `*DEFINE_CURVE` (SFA, SFO, OFFA, OFFO); `*BOUNDARY_SPC_SET`,
//! `*BOUNDARY_PRESCRIBED_MOTION_SET` (displacement), `*LOAD_NODE_SET`,
//! `*LOAD_SEGMENT_SET`; `*RIGIDWALL_GEOMETRIC_FLAT/PRISM/CYLINDER/SPHERE(_MOTION)` and
//! `*RIGIDWALL_PLANAR(_FINITE)`; `*INITIAL_VELOCITY`, `*INITIAL_VELOCITY_GENERATION`
//! (by part or node set); `*CONTROL_TERMINATION`, `*CONTROL_IMPLICIT_GENERAL/AUTO/
//! DYNAMICS/SOLUTION`. `$alfe key = value` lines (what `alfe export` writes where LS-DYNA
//! has no field) set that key. Every other keyword or field that matters is listed with
//! its line, in the deck's header and on stderr.
//!
//! Wall geometry follows LS-DYNA's convention: the normal runs from the tail (XT, YT,
//! ZT) to the head; a flat wall's or prism's tail is a corner, its edge l points from the
//! tail towards (XHEV, YHEV, ZHEV) (projected into the wall), m = n × l, and a prism
//! extends LENP behind the wall; a cylinder's tail is on its axis at one end, a sphere's
//! its centre.

use super::abaqus::{relative, toml_str, Imported, XYZ};
use super::keyword_blocks::{blocks, Block};
use super::lsdyna_model::{Model, Section};
use crate::mesh::abaqus::Loader;
use crate::mesh::lsdyna::{int, read_lines_k, real, split};
use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::Path;

/// Import `path` (an LS-DYNA keyword deck) into the deck at `deck_path`.
pub fn import_k(path: &Path, deck_path: &Path, load: &Loader) -> Result<Imported, String> {
    let lines = read_lines_k(path, load)?;
    let bs = blocks(&lines);
    let mut m = Model::default();
    // Definitions first (sets, curves, parts), then what refers to them.
    for b in &bs {
        define(&mut m, b)?;
    }
    let curve_names: BTreeMap<i64, String> =
        m.curves.iter().map(|(k, c)| (*k, c.0.clone())).collect();
    let extra = super::lsdyna_pairs::translate(
        &bs,
        &super::lsdyna_pairs::Ctx {
            node_sets: &m.node_sets,
            segment_sets: &m.segment_sets,
            curves: &curve_names,
        },
    )?;
    for (k, b) in bs.iter().enumerate() {
        if !extra.handled.contains(&k) {
            model_keyword(&mut m, b)?;
        }
    }
    entities(&mut m)?;
    for s in std::mem::take(&mut m.record_sets) {
        if m.node_sets.values().any(|n| *n == s) && !m.used_sets.contains(&s) {
            m.used_sets.push(s);
        }
    }
    merge(&mut m, extra);
    if m.solid_pids.is_empty() && m.shell_pids.is_empty() {
        return Err(format!(
            "{}: the file has no *ELEMENT_SOLID or *ELEMENT_SHELL",
            path.display()
        ));
    }
    // The mesh must read as the deck will read it.
    if !m.solid_pids.is_empty() {
        crate::mesh::lsdyna::read_k(path, 0, None, load)?;
    } else {
        crate::mesh::lsdyna::read_surface_k(path, load)?;
    }
    write_deck(&m, path, deck_path)
}

/// Pairs, bolts, couplings and steps (see [`super::lsdyna_pairs`]) into the model.
fn merge(m: &mut Model, extra: super::lsdyna_pairs::Out) {
    for (list, names) in [
        (&mut m.used_sets, extra.sets),
        (&mut m.used_surfaces, extra.surfaces),
    ] {
        for n in names {
            if !list.contains(&n) {
                list.push(n);
            }
        }
    }
    for c in extra.curves {
        if !m.used_curves.contains(&c) {
            m.used_curves.push(c);
        }
    }
    m.tables.extend(extra.tables);
    m.untranslated.extend(extra.untranslated);
}

/// Title, parts, sections, sets, curves, materials and element part numbers.
fn define(m: &mut Model, b: &Block) -> Result<(), String> {
    if m.entities.define(b)? {
        return Ok(());
    }
    let kw = b.kw.as_str();
    let titled = kw.ends_with("_TITLE");
    match kw.trim_end_matches("_TITLE") {
        "TITLE" => {
            m.title = b
                .data
                .first()
                .map(|l| l.text.trim().to_string())
                .unwrap_or_default();
            m.units = b.note("units").map(|u| u.trim_matches('"').to_string());
            // What the run reports, as top-level keys (before any table header).
            for (k, v) in &b.notes {
                match k.as_str() {
                    "output" => {
                        m.record.push(format!("output = {v}"));
                        m.record_sets = record_sets(v);
                    }
                    "quantity" => m.quantities.push(v.clone()),
                    _ => {}
                }
            }
        }
        "PART" => {
            for pair in b.data.chunks(2) {
                let [title, card] = pair else {
                    return Err(format!(
                        "{}: *PART: a title line and a card per part",
                        b.at()
                    ));
                };
                let f = split(&card.text, &[10]);
                let get = |j: usize| int(f.get(j).copied().unwrap_or(""), card, "a number");
                let pid = get(0)?;
                let name = Some(title.text.trim().to_string())
                    .filter(|s| !s.is_empty())
                    .unwrap_or(format!("part-{pid}"));
                m.parts.push((pid, name, get(1)?, get(2)?, card.at()));
            }
        }
        "SECTION_SOLID" => {
            b.need(1)?;
            let (secid, elform) = (b.int(0, 0)?, b.int(0, 1)?);
            let form = b
                .note("formulation")
                .map(|s| s.trim_matches('"').to_string())
                .or_else(|| {
                    match elform {
                        1 => Some("reduced"),
                        2 | -1 | -2 => Some("fbar"),
                        18 => Some("eas"),
                        10 | 16 | 15 | 17 => Some("standard"),
                        _ => None,
                    }
                    .map(str::to_string)
                });
            if form.is_none() {
                m.skip(
                    b,
                    &format!(
                        "ELFORM {elform} has no alfe twin: the part takes formulation = \"auto\""
                    ),
                );
            }
            let hg = b.note("hourglass").map(str::to_string);
            m.sections.insert(
                secid,
                Section {
                    formulation: form,
                    hourglass: hg,
                    thickness: None,
                },
            );
        }
        "SECTION_SHELL" => {
            b.need(2)?;
            let thickness = Some(b.real(1, 0)?);
            m.sections.insert(
                b.int(0, 0)?,
                Section {
                    thickness,
                    ..Section::default()
                },
            );
        }
        "SET_NODE_LIST" | "SET_NODE" | "SET_SEGMENT" => {
            let (title, header) = if titled {
                (b.data.first(), 1)
            } else {
                (None, 0)
            };
            b.need(header + 1)?;
            let sid = b.int(header, 0)?;
            let name = title
                .map(|l| l.text.trim().to_string())
                .filter(|s| !s.is_empty())
                .unwrap_or(format!("set-{sid}"));
            if kw.starts_with("SET_SEGMENT") {
                m.segment_sets.insert(sid, name);
            } else {
                m.node_sets.insert(sid, name);
            }
        }
        "DEFINE_CURVE" => define_curve(m, b, titled)?,
        "ELEMENT_SOLID" | "ELEMENT_SOLID_TET4TOTET10" | "ELEMENT_SHELL" => {
            let shell = kw.starts_with("ELEMENT_SHELL");
            let mut pending = false;
            for l in &b.data {
                let f = split(&l.text, &[if b.long { 20 } else { 8 }]);
                let nonzero = f.iter().filter(|s| !s.is_empty() && **s != "0").count();
                if pending {
                    pending = false;
                    continue;
                }
                if !shell && nonzero <= 2 {
                    pending = true;
                }
                let pid = int(f.get(1).copied().unwrap_or(""), l, "a part number")?;
                let list = if shell {
                    &mut m.shell_pids
                } else {
                    &mut m.solid_pids
                };
                if !list.contains(&pid) {
                    list.push(pid);
                }
            }
        }
        _ => {}
    }
    if kw.starts_with("MAT_") {
        material(m, b)?;
    }
    Ok(())
}

fn define_curve(m: &mut Model, b: &Block, titled: bool) -> Result<(), String> {
    let first = usize::from(titled);
    b.need(first + 1)?;
    let lcid = b.int(first, 0)?;
    let or1 = |v: f64| if v == 0.0 { 1.0 } else { v };
    let (sfa, sfo) = (or1(b.real(first, 2)?), or1(b.real(first, 3)?));
    let (offa, offo) = (b.real(first, 4)?, b.real(first, 5)?);
    let mut pts = Vec::new();
    for l in b.data.iter().skip(first + 1) {
        let f = split(&l.text, &[20]);
        let a = real(f.first().copied().unwrap_or(""), l)?;
        let o = real(f.get(1).copied().unwrap_or(""), l)?;
        pts.push([sfa * a + offa, sfo * o + offo]);
    }
    if pts.is_empty() {
        return Err(format!("{}: curve {lcid} has no points", b.at()));
    }
    let name = titled
        .then(|| b.data[0].text.trim().to_string())
        .filter(|s| !s.is_empty())
        .unwrap_or(format!("curve-{lcid}"));
    m.curves.insert(lcid, (name, pts));
    Ok(())
}

/// A `*MAT_*` card as an alfe material (see [`super::lsdyna_materials`]).
fn material(m: &mut Model, b: &Block) -> Result<(), String> {
    match super::lsdyna_materials::material(b)? {
        Ok(mat) => {
            for why in &mat.notes {
                m.skip(b, why);
            }
            if let Some(lcss) = mat.lcss {
                m.plastic_curves.push((mat.mid, lcss));
            }
            m.materials
                .insert(mat.mid, (mat.name, mat.body, mat.modulus));
        }
        Err(why) => m.skip(b, &why),
    }
    Ok(())
}

/// Supports, motions, loads, walls, velocities and controls.
fn model_keyword(m: &mut Model, b: &Block) -> Result<(), String> {
    let kw = b.kw.as_str();
    if kw.starts_with("RIGIDWALL_GEOMETRIC_") || kw.starts_with("RIGIDWALL_PLANAR") {
        return rigidwall(m, b);
    }
    if supports_and_loads(m, b)?
        || initial_velocity(m, b)?
        || controls(m, b)?
        || m.entities.keyword(b)?
    {
        return Ok(());
    }
    match kw {
        "KEYWORD"
        | "END"
        | "TITLE"
        | "NODE"
        | "PART"
        | "PART_INERTIA"
        | "SECTION_SOLID"
        | "SECTION_SHELL"
        | "ELEMENT_SOLID"
        | "ELEMENT_SOLID_TET4TOTET10"
        | "ELEMENT_SHELL" => {}
        _ if kw.starts_with("SET_") || kw.starts_with("DEFINE_CURVE") || kw.starts_with("MAT_") => {
        }
        _ => m.skip(b, "not translated"),
    }
    Ok(())
}

/// `*BOUNDARY_*` and `*LOAD_*` cards; false for another keyword.
fn supports_and_loads(m: &mut Model, b: &Block) -> Result<bool, String> {
    match b.kw.as_str() {
        "BOUNDARY_SPC_SET" => {
            for k in 0..b.data.len() {
                let set = m.set(b.int(k, 0)?, b)?;
                if b.int(k, 1)? != 0 {
                    m.skip(
                        b,
                        "CID ≠ 0 (a local system) is not translated: global axes used",
                    );
                }
                let comps: Vec<String> = (0..3)
                    .filter(|&j| b.int(k, 2 + j).is_ok_and(|v| v != 0))
                    .map(|j| format!("\"{}\"", XYZ[j]))
                    .collect();
                if !comps.is_empty() {
                    m.tables.push(format!(
                        "[[boundary]]\ntype = \"fixed\"\nset = {}\ncomponents = [{}]\n",
                        toml_str(&set),
                        comps.join(", ")
                    ));
                }
            }
        }
        "BOUNDARY_PRESCRIBED_MOTION_SET" => {
            for k in 0..b.data.len() {
                let (dof, vad, lcid, sf) =
                    (b.int(k, 1)?, b.int(k, 2)?, b.int(k, 3)?, b.real(k, 4)?);
                if !(1..=3).contains(&dof) || vad != 2 {
                    m.skip(b, &format!("DOF {dof}, VAD {vad}: only displacements (VAD = 2) of DOF 1–3 are translated"));
                    continue;
                }
                let set = m.set(b.int(k, 0)?, b)?;
                let curve = m.curve(lcid, b)?;
                m.tables.push(format!("[[boundary]]\ntype = \"displacement\"\nset = {}\ncomponents = [\"{}\"]\nvalue = {sf:e}\ncurve = {}\n", toml_str(&set), XYZ[dof as usize - 1], toml_str(&curve)));
            }
        }
        "LOAD_NODE_SET" => {
            for k in 0..b.data.len() {
                let (dof, lcid, sf) = (b.int(k, 1)?, b.int(k, 2)?, b.real(k, 3)?);
                if !(1..=3).contains(&dof) {
                    m.skip(
                        b,
                        &format!("DOF {dof}: only forces along x, y, z are translated"),
                    );
                    continue;
                }
                let set = m.set(b.int(k, 0)?, b)?;
                let curve = m.curve(lcid, b)?;
                let mut f = [0.0; 3];
                f[dof as usize - 1] = sf;
                m.tables.push(format!("[[loads]]\ntype = \"nodal\"\nset = {}\nforce = [{:e}, {:e}, {:e}]\ncurve = {}\n", toml_str(&set), f[0], f[1], f[2], toml_str(&curve)));
            }
        }
        "LOAD_SEGMENT_SET" => {
            for k in 0..b.data.len() {
                let (ssid, lcid, sf) = (b.int(k, 0)?, b.int(k, 1)?, b.real(k, 2)?);
                let surface = m
                    .segment_sets
                    .get(&ssid)
                    .cloned()
                    .ok_or_else(|| format!("{}: segment set {ssid} is not defined", b.at()))?;
                if !m.used_surfaces.contains(&surface) {
                    m.used_surfaces.push(surface.clone());
                }
                let curve = m.curve(lcid, b)?;
                m.tables.push(format!(
                    "[[loads]]\ntype = \"pressure\"\nsurface = {}\npressure = {sf:e}\ncurve = {}\n",
                    toml_str(&surface),
                    toml_str(&curve)
                ));
            }
        }
        _ => return Ok(false),
    }
    Ok(true)
}

/// `*INITIAL_VELOCITY(_GENERATION)`; false for another keyword.
fn initial_velocity(m: &mut Model, b: &Block) -> Result<bool, String> {
    match b.kw.as_str() {
        "INITIAL_VELOCITY" => {
            b.need(2)?;
            let v = [b.real(1, 0)?, b.real(1, 1)?, b.real(1, 2)?];
            let nsid = b.int(0, 0)?;
            let target = if nsid == 0 {
                "part = \"*\"".to_string()
            } else {
                format!("set = {}", toml_str(&m.set(nsid, b)?))
            };
            push_velocity(m, &target, v);
        }
        "INITIAL_VELOCITY_GENERATION" => {
            b.need(1)?;
            let (id, styp) = (b.int(0, 0)?, b.int(0, 1)?);
            if b.real(0, 2)? != 0.0 {
                m.skip(b, "OMEGA ≠ 0 (a spin) is not translated");
            }
            let v = [b.real(0, 3)?, b.real(0, 4)?, b.real(0, 5)?];
            let target = match styp {
                2 => match m.parts.iter().find(|p| p.0 == id) {
                    Some(p) => format!("part = {}", toml_str(&p.1)),
                    None => return Err(format!("{}: part {id} is not defined", b.at())),
                },
                3 => format!("set = {}", toml_str(&m.set(id, b)?)),
                _ => {
                    m.skip(b, "STYP 1 (part sets) is not translated");
                    return Ok(true);
                }
            };
            push_velocity(m, &target, v);
        }
        _ => return Ok(false),
    }
    Ok(true)
}

/// `*CONTROL_*` cards; false for another keyword.
fn controls(m: &mut Model, b: &Block) -> Result<bool, String> {
    match b.kw.as_str() {
        "CONTROL_TERMINATION" => m.end_time = Some(b.real(0, 0)?),
        "CONTROL_IMPLICIT_GENERAL" => m.implicit = Some((b.int(0, 0)?, b.real(0, 1)?)),
        "CONTROL_IMPLICIT_AUTO" => m.auto = Some((b.real(0, 3)?, b.real(0, 4)?)),
        "CONTROL_IMPLICIT_DYNAMICS" => {
            if b.int(0, 0)? == 1 {
                let scheme = b
                    .note("scheme")
                    .map_or("\"newmark\"".to_string(), str::to_string);
                if b.note("scheme").is_none()
                    && (b.real(0, 1)?, b.real(0, 2)?) != (0.5, 0.25)
                    && (b.real(0, 1)?, b.real(0, 2)?) != (0.0, 0.0)
                {
                    m.skip(
                        b,
                        "GAMMA, BETA other than 1/2, 1/4: taken as the trapezoidal Newmark rule",
                    );
                }
                m.dynamics = Some((scheme, b.note("rho_inf").map(str::to_string)));
            }
        }
        "CONTROL_IMPLICIT_SOLUTION" => {
            let ilimit = b.int(0, 1)?;
            let kind = b.note("nonlinear").map_or(
                if ilimit == 1 {
                    "\"newton\""
                } else {
                    "\"bfgs\""
                }
                .to_string(),
                str::to_string,
            );
            m.solver = Some((kind, b.int(0, 2)?));
            for key in SOLVER_NOTES {
                if let Some(v) = b.note(key) {
                    m.solver_notes.push(format!("{key} = {v}"));
                }
            }
        }
        _ => return Ok(false),
    }
    Ok(true)
}

/// A `*RIGIDWALL_*` keyword (see [`super::lsdyna_walls`]).
fn rigidwall(m: &mut Model, b: &Block) -> Result<(), String> {
    let t = super::lsdyna_walls::wall(m_sets(m), b)?;
    match t {
        Ok((table, set, lcid)) => {
            if let Some(s) = set {
                if !m.used_sets.contains(&s) {
                    m.used_sets.push(s);
                }
            }
            if let Some(c) = lcid {
                m.curve(c, b)?;
            }
            let table = match lcid {
                Some(c) => table.replace("@CURVE", &toml_str(&m.curves[&c].0)),
                None => table,
            };
            m.tables.push(table);
        }
        Err(why) => m.skip(b, &why),
    }
    Ok(())
}

/// The node sets an `output = {…}` note names (reactions, displacements).
fn record_sets(v: &str) -> Vec<String> {
    let Ok(t) = format!("o = {v}").parse::<toml::Table>() else {
        return Vec::new();
    };
    ["reactions", "displacements"]
        .iter()
        .filter_map(|k| t.get("o")?.get(k)?.as_array().cloned())
        .flatten()
        .filter_map(|x| x.as_str().map(str::to_string))
        .collect()
}

/// The `[solver]` settings `alfe export` writes as notes.
const SOLVER_NOTES: [&str; 6] = [
    "line_search",
    "residual_rtol",
    "increment_rtol",
    "energy_rtol",
    "fd_delta",
    "bfgs_reform",
];

/// The contact entities' tables, their node sets and curves named (see
/// [`super::lsdyna_entities`]).
fn entities(m: &mut Model) -> Result<(), String> {
    let (tables, skipped) = std::mem::take(&mut m.entities).tables();
    m.untranslated.extend(skipped);
    for t in tables {
        let set = m.node_sets.get(&t.nsid).cloned().ok_or_else(|| {
            format!(
                "{}: *CONTACT_ENTITY names node set {}, which the file does not define",
                t.at, t.nsid
            )
        })?;
        if !m.used_sets.contains(&set) {
            m.used_sets.push(set.clone());
        }
        let mut text = t.text.replace("@NODES", &toml_str(&set));
        for c in t.lcids {
            let name = m.curves.get(&c).map(|x| x.0.clone()).ok_or_else(|| {
                format!("{}: a rigid-body motion or load of this entity names curve {c}, which no *DEFINE_CURVE defines", t.at)
            })?;
            if !m.used_curves.contains(&c) {
                m.used_curves.push(c);
            }
            text = text.replace(&format!("@CURVE{c}@"), &toml_str(&name));
        }
        m.tables.push(text);
    }
    Ok(())
}

/// The node sets by number and the parts, for the wall reader.
fn m_sets(m: &Model) -> super::lsdyna_walls::Context<'_> {
    super::lsdyna_walls::Context {
        node_sets: &m.node_sets,
        parts: m
            .parts
            .iter()
            .filter(|p| m.solid_pids.contains(&p.0))
            .map(|p| p.1.as_str())
            .collect(),
    }
}

fn push_velocity(m: &mut Model, target: &str, v: [f64; 3]) {
    if target == "part = \"*\"" {
        let parts: Vec<String> = m
            .parts
            .iter()
            .filter(|p| m.solid_pids.contains(&p.0))
            .map(|p| p.1.clone())
            .collect();
        for p in parts {
            m.tables.push(format!(
                "[[initial_velocity]]\npart = {}\nvelocity = [{:e}, {:e}, {:e}]\n",
                toml_str(&p),
                v[0],
                v[1],
                v[2]
            ));
        }
        return;
    }
    m.tables.push(format!(
        "[[initial_velocity]]\n{target}\nvelocity = [{:e}, {:e}, {:e}]\n",
        v[0], v[1], v[2]
    ));
}

fn write_deck(m: &Model, path: &Path, deck_path: &Path) -> Result<Imported, String> {
    let mut untranslated = m.untranslated.clone();
    let file = relative(path, deck_path);
    let stem = path
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("imported");
    let name = if m.title.is_empty() {
        stem
    } else {
        m.title.as_str()
    };
    let modulus = m.materials.values().map(|x| x.2).fold(0.0, f64::max);
    let units = m
        .units
        .clone()
        .unwrap_or_else(|| if modulus > 1e7 { "m-kg-s" } else { "mm-t-s" }.to_string());
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# Imported by `alfe import` from {} ({}).",
        path.display(),
        crate::VERSION
    );
    if m.units.is_none() {
        let _ = writeln!(out, "# Numbers are the file's: units = \"{units}\" is a label chosen from E = {modulus:e} (check it).");
    }
    let mut body = String::new();
    for l in &m.record {
        let _ = writeln!(body, "\n{l}");
    }
    if !m.quantities.is_empty() {
        let _ = writeln!(
            body,
            "\nquantities = [\n  {},\n]",
            m.quantities.join(",\n  ")
        );
    }
    let _ = writeln!(
        body,
        "\n[scene]\nname = {}\nunits = \"{units}\"",
        toml_str(name)
    );
    write_parts(m, &file, &mut body, &mut untranslated)?;
    for lcid in &m.used_curves {
        let (n, pts) = &m.curves[lcid];
        let p: Vec<String> = pts.iter().map(|[a, b]| format!("[{a:e}, {b:e}]")).collect();
        let _ = writeln!(
            body,
            "\n[[curves]]\nname = {}\npoints = [{}]",
            toml_str(n),
            p.join(", ")
        );
    }
    for s in &m.used_sets {
        let _ = writeln!(
            body,
            "\n[[node_sets]]\nname = {}\ngroup = {}",
            toml_str(s),
            toml_str(s)
        );
    }
    for s in &m.used_surfaces {
        let _ = writeln!(
            body,
            "\n[[surfaces]]\nname = {}\ngroup = {}",
            toml_str(s),
            toml_str(s)
        );
    }
    for t in &m.tables {
        let _ = write!(body, "\n{t}");
    }
    write_analysis(m, &mut body, &mut untranslated);
    if untranslated.is_empty() {
        let _ = writeln!(out, "# Every keyword was translated.");
    } else {
        let _ = writeln!(out, "# Not translated ({}):", untranslated.len());
        for u in &untranslated {
            let _ = writeln!(out, "#   {u}");
        }
    }
    out += &body;
    Ok(Imported {
        deck: out,
        companion: None,
        untranslated,
    })
}

/// One alfe part per LS-DYNA part with solids (a shell-only file: one sheet).
fn write_parts(
    m: &Model,
    file: &str,
    out: &mut String,
    untranslated: &mut Vec<String>,
) -> Result<(), String> {
    let shells_only = m.solid_pids.is_empty();
    let pids = if shells_only {
        &m.shell_pids
    } else {
        &m.solid_pids
    };
    let mut written_mats: Vec<i64> = Vec::new();
    let mut parts = String::new();
    for (k, pid) in pids.iter().enumerate() {
        let (_, name, secid, mid, at) = m
            .parts
            .iter()
            .find(|p| p.0 == *pid)
            .ok_or_else(|| format!("{file}: elements of part {pid}, which no *PART defines"))?;
        let (mat_name, body, _) = m.materials.get(mid).ok_or_else(|| format!("{at}: part {pid} uses material {mid}, which the file does not define or alfe does not translate"))?;
        if !written_mats.contains(mid) {
            written_mats.push(*mid);
            let body = match m.plastic_curves.iter().find(|(x, _)| x == mid) {
                Some((_, lcss)) => {
                    let pts = &m
                        .curves
                        .get(lcss)
                        .ok_or_else(|| format!("{at}: LCSS {lcss} is not defined"))?
                        .1;
                    let p: Vec<String> =
                        pts.iter().map(|[a, b]| format!("[{a:e}, {b:e}]")).collect();
                    let table = if body.contains("hardening = ") {
                        String::new()
                    } else {
                        format!(
                            "hardening = {{ type = \"table\", points = [{}] }}\n",
                            p.join(", ")
                        )
                    };
                    body.replace(
                        "@LCSS\n",
                        &format!("yield_stress = {:e}\n{table}", pts[0][1]),
                    )
                }
                None => body.clone(),
            };
            let _ = writeln!(
                out,
                "\n[[materials]]\nname = {}\n{}",
                toml_str(mat_name),
                body.trim_end()
            );
        }
        let Section {
            formulation: form,
            hourglass: hg,
            thickness: thick,
        } = m.sections.get(secid).cloned().unwrap_or_default();
        let _ = writeln!(
            parts,
            "\n[[parts]]\nname = {}\nmaterial = {}",
            toml_str(name),
            toml_str(mat_name)
        );
        if shells_only {
            let t = thick.ok_or_else(|| {
                format!("{at}: a shell part needs a *SECTION_SHELL with its thickness T1")
            })?;
            let _ = writeln!(
                parts,
                "mesh = {{ kind = \"sheet\", file = {}, thickness = {t:e} }}",
                toml_str(file)
            );
            if k > 0 {
                untranslated.push(format!("{at}: shell part {pid}: a sheet reads every shell of the file; only the first part is kept"));
                break;
            }
            break;
        }
        if let Some(f) = form {
            let _ = writeln!(parts, "formulation = \"{}\"", f.trim_matches('"'));
        }
        if let Some(h) = hg {
            let _ = writeln!(parts, "hourglass = {h}");
        }
        let pid_field = if pids.len() > 1 {
            format!(", pid = {pid}")
        } else {
            String::new()
        };
        let _ = writeln!(
            parts,
            "mesh = {{ kind = \"lsdyna\", file = {}{pid_field} }}",
            toml_str(file)
        );
    }
    *out += &parts;
    Ok(())
}

fn write_analysis(m: &Model, out: &mut String, untranslated: &mut Vec<String>) {
    let end = m.end_time.unwrap_or_else(|| {
        untranslated.push("no *CONTROL_TERMINATION: end_time = 1".into());
        1.0
    });
    let kind = match (m.implicit, &m.dynamics) {
        (Some((1, _)), Some(_)) => "implicit",
        (Some((1, _)), None) => "static",
        _ => "explicit",
    };
    let _ = writeln!(out, "\n[analysis]\ntype = \"{kind}\"\nend_time = {end:e}");
    if let Some((_, dt0)) = m.implicit.filter(|_| kind != "explicit") {
        let dt0 = if dt0 > 0.0 { dt0 } else { end / 10.0 };
        let _ = writeln!(out, "step = {dt0:e}");
        if let Some((dtmin, dtmax)) = m.auto {
            if dtmin > 0.0 {
                let _ = writeln!(out, "min_step = {dtmin:e}");
            }
            if dtmax > 0.0 {
                let _ = writeln!(out, "max_step = {dtmax:e}");
            }
        }
    }
    if let Some((scheme, rho)) = &m.dynamics {
        let _ = writeln!(out, "scheme = {scheme}");
        if let Some(r) = rho {
            let _ = writeln!(out, "rho_inf = {r}");
        }
    }
    if let Some((kind, maxit)) = &m.solver {
        let _ = writeln!(out, "\n[solver]\nnonlinear = {kind}");
        if *maxit > 0 {
            let _ = writeln!(out, "max_iterations = {maxit}");
        }
        for l in &m.solver_notes {
            let _ = writeln!(out, "{l}");
        }
    }
}
