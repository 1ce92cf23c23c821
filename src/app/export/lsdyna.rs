//! A built scene as an LS-DYNA keyword file (`.k`): nodes, solids by part (tets and
//! wedges as LS-DYNA's degenerate hexes, tet10 in the two-card layout), parts with a
//! section and a material each, node and segment sets under their names (`_TITLE`),
//! supports (`*BOUNDARY_SPC_SET`), prescribed displacements
//! (`*BOUNDARY_PRESCRIBED_MOTION_SET`), nodal loads and pressures, curves, initial
//! velocities, rigid walls as `*RIGIDWALL_GEOMETRIC_*` (with `_MOTION` for a translating
//! wall) and the implicit controls. Cards that carry reals are written in long format
//! (`+`, 20 columns: 13 significant digits), so `alfe import` gives the scene back.
//!
//! Where LS-DYNA has no field for an alfe choice (the element formulation, the contact
//! method, the time integrator), the exporter writes it on an `$alfe key = value` line
//! after the card: LS-DYNA reads a comment, `alfe import` the value. Small-sliding
//! pairs, bolts, couplings and steps are written by [`super::lsdyna_pairs`]. What has no
//! equivalent at all (tractions, rotations, entities, ellipsoid and torus walls, turning
//! walls) is listed in the header and returned.

// Index loops over xyz components read like the formulas.
#![allow(clippy::needless_range_loop)]

use super::abaqus::Exported;
use super::lsdyna_cards::{card, r, Numbering};
use crate::contact::motion::MotionKind;
use crate::contact::wall::{ContactMethod, ShapeDef};
use crate::curve::Curve;
use crate::fem::element::Formulation;
use crate::mesh::{ElemKind, Mesh};
use crate::model::def::{ContributionDef, MaterialDef, Motion};
use crate::model::loads::LoadDef;
use crate::model::walls::WallDef;
use crate::scene::Scene;
use crate::solve::analysis::AnalysisKind;
use std::collections::BTreeMap;
use std::fmt::Write;

/// A unit enum's deck spelling (its serde name).
fn deck_name<T: serde::Serialize>(t: &T) -> String {
    serde_json::to_value(t)
        .ok()
        .and_then(|v| v.as_str().map(str::to_string))
        .unwrap_or_default()
}

fn i(n: usize) -> String {
    n.to_string()
}

/// Numbers (1-based) 8 to a line, 10 columns each.
fn id_lines(out: &mut String, ids: impl Iterator<Item = usize>) {
    let v: Vec<usize> = ids.map(|n| n + 1).collect();
    for chunk in v.chunks(8) {
        for n in chunk {
            let _ = write!(out, "{n:>10}");
        }
        out.push('\n');
    }
}

/// Numbered node sets and curves, created as the model asks for them.
#[derive(Default)]
struct Ids {
    sets: BTreeMap<String, usize>,
    set_text: String,
    curves: Vec<Curve>,
    curve_text: String,
}

impl Ids {
    /// The number of node set `name` (written on first use).
    fn set(&mut self, name: &str, nodes: &[usize]) -> usize {
        if let Some(&s) = self.sets.get(name) {
            return s;
        }
        let sid = self.sets.len() + 1;
        self.sets.insert(name.to_string(), sid);
        let _ = writeln!(self.set_text, "*SET_NODE_LIST_TITLE\n{name}\n{sid:>10}");
        id_lines(&mut self.set_text, nodes.iter().copied());
        sid
    }

    /// The number of a curve (one per distinct curve).
    fn curve(&mut self, c: &Curve) -> usize {
        if let Some(k) = self.curves.iter().position(|x| x == c) {
            return k + 1;
        }
        self.curves.push(c.clone());
        let lcid = self.curves.len();
        let _ = writeln!(self.curve_text, "*DEFINE_CURVE_TITLE +\ncurve-{lcid}");
        card(&mut self.curve_text, &[i(lcid)]);
        for [t, v] in &c.points {
            card(&mut self.curve_text, &[r(*t), r(*v)]);
        }
        lcid
    }
}

impl Numbering for Ids {
    fn set(&mut self, name: &str, nodes: &[usize]) -> usize {
        Ids::set(self, name, nodes)
    }
    fn curve(&mut self, c: &Curve) -> usize {
        Ids::curve(self, c)
    }
}

/// An LS-DYNA solid's node list (1-based) from an alfe element: tets and wedges as
/// degenerate hexes, the tet10's midside nodes in LS-DYNA's edge order.
fn solid_nodes(kind: ElemKind, n: &[usize]) -> Vec<usize> {
    let v: Vec<usize> = match kind {
        ElemKind::Hex8 => n.to_vec(),
        ElemKind::Tet4 => vec![n[0], n[1], n[2], n[3], n[3], n[3], n[3], n[3]],
        // The reader's triangles n1-n2-n5 and n4-n3-n6 (n5 = n6, n7 = n8).
        ElemKind::Wedge6 => vec![n[0], n[1], n[4], n[3], n[2], n[2], n[5], n[5]],
        // alfe's edges 01 12 20 03 23 13 → LS-DYNA's 12 23 31 14 24 34.
        ElemKind::Tet10 => vec![n[0], n[1], n[2], n[3], n[4], n[5], n[6], n[7], n[9], n[8]],
    };
    v.into_iter().map(|x| x + 1).collect()
}

/// ELFORM for an element kind and formulation, and whether alfe's choice needs its note.
fn elform(kind: ElemKind, f: Formulation) -> (i32, bool) {
    match (kind, f) {
        (ElemKind::Hex8, Formulation::Reduced { .. }) => (1, true),
        (ElemKind::Hex8, Formulation::FBar { .. } | Formulation::Hybrid { .. }) => (2, true),
        (ElemKind::Hex8, Formulation::Eas) => (18, true),
        (ElemKind::Hex8, Formulation::Standard) => (2, true),
        (ElemKind::Tet4, Formulation::Standard) => (10, false),
        (ElemKind::Tet4, _) => (13, true),
        (ElemKind::Tet10, _) => (16, f != Formulation::Standard),
        (ElemKind::Wedge6, _) => (15, f != Formulation::Standard),
    }
}

fn alfe_formulation(f: Formulation) -> String {
    match f {
        Formulation::FBar { hourglass }
        | Formulation::Reduced { hourglass }
        | Formulation::Hybrid { hourglass } => format!(
            "$alfe formulation = \"{}\"\n$alfe hourglass = {hourglass:e}\n",
            f.deck_name()
        ),
        _ => format!("$alfe formulation = \"{}\"\n", f.deck_name()),
    }
}

fn write_material(out: &mut String, mid: usize, name: &str, m: &MaterialDef, ids: &mut Ids) {
    match m {
        MaterialDef::LinearElastic { e, nu, density } => {
            let _ = writeln!(out, "*MAT_ELASTIC_TITLE +\n{name}");
            card(out, &[i(mid), r(*density), r(*e), r(*nu)]);
        }
        MaterialDef::NeoHookean { e, nu, density } => {
            // 077_H with C10 = μ/2 only; PR gives the bulk modulus.
            let mu = e / (2.0 * (1.0 + nu));
            let _ = writeln!(out, "*MAT_HYPERELASTIC_RUBBER_TITLE +\n{name}");
            card(out, &[i(mid), r(*density), r(*nu), i(0)]);
            card(out, &[r(mu / 2.0), r(0.0)]);
            out.push_str("$alfe model = \"neo-hookean\"\n");
        }
        MaterialDef::MooneyRivlin {
            c10,
            c01,
            nu,
            density,
        } => {
            let _ = writeln!(out, "*MAT_MOONEY-RIVLIN_RUBBER_TITLE +\n{name}");
            card(out, &[i(mid), r(*density), r(*nu), r(*c10), r(*c01)]);
        }
        MaterialDef::J2 {
            e,
            nu,
            hardening,
            density,
        } => {
            let pts: Vec<[f64; 2]> = match hardening {
                crate::material::Hardening::Linear { sigma_y0, h } => {
                    vec![[0.0, *sigma_y0], [1.0, sigma_y0 + h]]
                }
                crate::material::Hardening::Power { sigma_y0, k, n } => (0..=40)
                    .map(|j| {
                        let ep = (j as f64 / 40.0).powi(2);
                        [ep, sigma_y0 + k * ep.powf(*n)]
                    })
                    .collect(),
                crate::material::Hardening::Tabulated { points } => points.clone(),
            };
            let lcss = ids.curve(&Curve { points: pts });
            let _ = writeln!(out, "*MAT_PIECEWISE_LINEAR_PLASTICITY_TITLE +\n{name}");
            card(out, &[i(mid), r(*density), r(*e), r(*nu), r(0.0), r(0.0)]);
            card(out, &[r(0.0), r(0.0), i(lcss)]);
            // LS-DYNA gets the power law as a table; alfe gets it back exactly.
            if let crate::material::Hardening::Power { k, n, .. } = hardening {
                let _ = writeln!(
                    out,
                    "$alfe hardening = {{ type = \"power\", k = {k:e}, n = {n:e} }}"
                );
            }
        }
    }
}

/// Export `scene` as a `.k`.
pub fn export_k(scene: &Scene) -> Exported {
    let m = &scene.model;
    let mesh: &Mesh = &m.mesh;
    let mut notes = Vec::new();
    let mut ids = Ids::default();
    let mut out = String::new();
    let _ = writeln!(out, "*TITLE\n{}", scene.run.name);
    let _ = writeln!(out, "$alfe units = \"{}\"", deck_name(&scene.run.units));
    write_record_notes(&mut out, scene);
    out.push_str("*NODE +\n");
    for (n, x) in mesh.coords.iter().enumerate() {
        card(&mut out, &[i(n + 1), r(x[0]), r(x[1]), r(x[2])]);
    }
    for (k, (name, mat)) in m.materials.iter().enumerate() {
        write_material(&mut out, k + 1, name, mat, &mut ids);
    }
    write_parts(&mut out, scene);
    for (name, nodes) in &m.node_sets {
        ids.set(name, nodes);
    }
    write_segments(&mut out, scene);
    let mut model = String::new();
    write_entities(&mut out, &mut model, scene, &mut ids, &mut notes);
    write_constraints(&mut model, scene, &mut ids, &mut notes);
    write_loads(&mut model, scene, &mut ids, &mut notes);
    let surface_ids: BTreeMap<&str, usize> = m
        .surfaces
        .keys()
        .enumerate()
        .map(|(k, n)| (n.as_str(), k + 1))
        .collect();
    super::lsdyna_pairs::write(&mut model, scene, &surface_ids, &mut ids);
    write_walls(&mut model, scene, &mut ids, &mut notes);
    write_initial_velocity(&mut model, scene, &mut ids);
    write_controls(&mut model, scene);
    notes.sort();
    notes.dedup();
    let mut text = String::from("*KEYWORD\n");
    let _ = writeln!(text, "$ written by alfe {}", crate::VERSION);
    for n in &notes {
        let _ = writeln!(text, "$ not exported: {n}");
    }
    text += &out;
    text += &ids.set_text;
    text += &ids.curve_text;
    text += &model;
    text.push_str("*END\n");
    Exported {
        text,
        left_out: notes,
    }
}

/// What the run reports (`[output]`, `[[quantities]]`) as `$alfe` notes in TOML: LS-DYNA's
/// `*DATABASE` cards ask for other things.
fn write_record_notes(out: &mut String, scene: &Scene) {
    let Ok(deck) = scene.run.echo.parse::<toml::Table>() else {
        return;
    };
    if let Some(o) = deck.get("output") {
        let _ = writeln!(out, "$alfe output = {o}");
    }
    if let Some(toml::Value::Array(qs)) = deck.get("quantities") {
        for q in qs {
            let _ = writeln!(out, "$alfe quantity = {q}");
        }
    }
}

fn write_parts(out: &mut String, scene: &Scene) {
    let m = &scene.model;
    let mesh = &m.mesh;
    for (p, name) in m.part_names.iter().enumerate() {
        let kind = (0..mesh.n_elems())
            .find(|&e| mesh.elem_part[e] as usize == p)
            .map_or(ElemKind::Hex8, |e| mesh.kinds[e]);
        let form = m.part_formulation[p];
        let (el, note) = elform(kind, form);
        let _ = writeln!(out, "*PART\n{name}");
        let _ = writeln!(
            out,
            "{:>10}{:>10}{:>10}",
            p + 1,
            p + 1,
            m.part_material[p] + 1
        );
        let _ = writeln!(out, "*SECTION_SOLID\n{:>10}{el:>10}", p + 1);
        if note {
            out.push_str(&alfe_formulation(form));
        }
    }
    let (mut one, mut ten) = (String::new(), String::new());
    for e in 0..mesh.n_elems() {
        let pid = mesh.elem_part[e] + 1;
        let ns = solid_nodes(mesh.kinds[e], mesh.elem_nodes(e));
        if ns.len() == 10 {
            let _ = writeln!(ten, "{:>8}{pid:>8}", e + 1);
            for n in &ns {
                let _ = write!(ten, "{n:>8}");
            }
            ten.push('\n');
        } else {
            let _ = write!(one, "{:>8}{pid:>8}", e + 1);
            for n in &ns {
                let _ = write!(one, "{n:>8}");
            }
            one.push('\n');
        }
    }
    if !one.is_empty() {
        out.push_str("*ELEMENT_SOLID\n");
        out.push_str(&one);
    }
    if !ten.is_empty() {
        out.push_str("*ELEMENT_SOLID (ten nodes format)\n");
        out.push_str(&ten);
    }
}

/// Surfaces as segment sets (corner nodes; a triangle repeats its third).
fn write_segments(out: &mut String, scene: &Scene) {
    let m = &scene.model;
    for (k, (name, faces)) in m.surfaces.iter().enumerate() {
        let _ = writeln!(out, "*SET_SEGMENT_TITLE\n{name}\n{:>10}", k + 1);
        for f in faces {
            let en = m.mesh.elem_nodes(f.elem);
            let c: Vec<usize> = m.mesh.kinds[f.elem]
                .face_corners(f.face as usize)
                .iter()
                .map(|&a| en[a] + 1)
                .collect();
            let c4 = [c[0], c[1], c[2], *c.get(3).unwrap_or(&c[2])];
            for n in c4 {
                let _ = write!(out, "{n:>10}");
            }
            out.push('\n');
        }
    }
}

fn set_of(scene: &Scene, ids: &mut Ids, name: &str) -> usize {
    let nodes = scene.model.node_sets.get(name).cloned().unwrap_or_default();
    ids.set(name, &nodes)
}

fn write_constraints(out: &mut String, scene: &Scene, ids: &mut Ids, notes: &mut Vec<String>) {
    for c in &scene.model.constraints {
        let Motion::Uniform { value } = &c.motion else {
            notes.push(format!("the rotation prescribed on `{}`", c.set));
            continue;
        };
        let sid = set_of(scene, ids, &c.set);
        let fixed: Vec<bool> = (0..3).map(|k| c.comps[k] && value[k] == 0.0).collect();
        if fixed.iter().any(|&f| f) {
            out.push_str("*BOUNDARY_SPC_SET\n");
            let _ = write!(out, "{sid:>10}{:>10}", 0);
            for f in &fixed {
                let _ = write!(out, "{:>10}", i32::from(*f));
            }
            out.push('\n');
        }
        for k in 0..3 {
            if c.comps[k] && value[k] != 0.0 {
                let lcid = ids.curve(&c.curve);
                out.push_str("*BOUNDARY_PRESCRIBED_MOTION_SET +\n");
                card(out, &[i(sid), i(k + 1), i(2), i(lcid), r(value[k])]);
            }
        }
    }
}

fn write_loads(out: &mut String, scene: &Scene, ids: &mut Ids, notes: &mut Vec<String>) {
    let m = &scene.model;
    let surface_ids: BTreeMap<&str, usize> = m
        .surfaces
        .keys()
        .enumerate()
        .map(|(k, n)| (n.as_str(), k + 1))
        .collect();
    for c in &m.contributions {
        match c {
            ContributionDef::Load(LoadDef::Nodal { set, force, curve }) => {
                let sid = set_of(scene, ids, set);
                let lcid = ids.curve(curve);
                for k in 0..3 {
                    if force[k] != 0.0 {
                        out.push_str("*LOAD_NODE_SET +\n");
                        card(out, &[i(sid), i(k + 1), i(lcid), r(force[k])]);
                    }
                }
            }
            ContributionDef::Load(LoadDef::Pressure {
                surface,
                pressure,
                curve,
            }) => {
                let lcid = ids.curve(curve);
                out.push_str("*LOAD_SEGMENT_SET +\n");
                card(
                    out,
                    &[i(surface_ids[surface.as_str()]), i(lcid), r(*pressure)],
                );
            }
            ContributionDef::Load(LoadDef::Traction { surface, .. }) => notes.push(format!(
                "the traction on `{surface}` (LS-DYNA's segment loads are pressures)"
            )),
            // Written by `lsdyna_pairs` and `write_walls`.
            ContributionDef::Wall(_) | ContributionDef::Coupling(_) | ContributionDef::Pairs(_) => {
            }
        }
    }
}

/// A wall's LS-DYNA shape (the keyword's), the tail and head of its normal (or axis),
/// and its shape card.
type Geometry = (&'static str, [f64; 3], [f64; 3], Vec<String>);

/// The wall's [`Geometry`]; None for shapes LS-DYNA has no geometric wall for.
fn wall_geometry(w: &WallDef) -> Option<Geometry> {
    let p = w.motion.pose(0.0);
    let at = |x: [f64; 3]| p.to_global(x);
    let (ex, ez) = (
        p.dir_to_global([1.0, 0.0, 0.0]),
        p.dir_to_global([0.0, 0.0, 1.0]),
    );
    let plus = |a: [f64; 3], b: [f64; 3]| std::array::from_fn::<f64, 3, _>(|k| a[k] + b[k]);
    match w.shape {
        ShapeDef::Plane { .. } => {
            let t = at([0.0; 3]);
            Some(("FLAT", t, plus(t, ez), vec![]))
        }
        ShapeDef::FinitePlane { lx, ly } => {
            let t = at([-0.5 * lx, -0.5 * ly, 0.0]);
            let hev = plus(t, ex);
            Some((
                "FLAT",
                t,
                plus(t, ez),
                vec![r(hev[0]), r(hev[1]), r(hev[2]), r(lx), r(ly)],
            ))
        }
        ShapeDef::Prism { size } => {
            let t = at([-0.5 * size[0], -0.5 * size[1], 0.5 * size[2]]);
            let hev = plus(t, ex);
            let card = [hev[0], hev[1], hev[2], size[0], size[1], size[2]].map(r);
            Some(("PRISM", t, plus(t, ez), card.to_vec()))
        }
        ShapeDef::Cylinder { radius, length } => {
            let t = at([0.0, 0.0, -0.5 * length]);
            Some(("CYLINDER", t, plus(t, ez), vec![r(radius), r(length)]))
        }
        ShapeDef::Sphere { radius } => {
            let t = at([0.0; 3]);
            Some(("SPHERE", t, plus(t, ez), vec![r(radius)]))
        }
        ShapeDef::Ellipsoid { .. } | ShapeDef::Torus { .. } => None,
    }
}

/// The wall's translation as one direction and one curve (LS-DYNA's `_MOTION` card):
/// (OPT, direction, curve scaled by the magnitude); Err where it is not one.
fn wall_motion(w: &WallDef) -> Result<Option<(i32, [f64; 3], Curve)>, String> {
    if w.motion.dofs[3..].iter().any(Option::is_some) {
        return Err("a turning wall".into());
    }
    let ds: Vec<_> = w.motion.dofs[..3].iter().flatten().collect();
    let Some(first) = ds.first() else {
        return Ok(None);
    };
    if ds
        .iter()
        .any(|d| d.curve != first.curve || d.kind != first.kind)
    {
        return Err("a motion whose components follow different curves".into());
    }
    let s: [f64; 3] = std::array::from_fn(|k| w.motion.dofs[k].as_ref().map_or(0.0, |d| d.scale));
    let mag = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
    let curve = Curve {
        points: first
            .curve
            .points
            .iter()
            .map(|&[t, v]| [t, v * mag])
            .collect(),
    };
    let opt = i32::from(first.kind == MotionKind::Displacement);
    Ok(Some((opt, s.map(|x| x / mag), curve)))
}

fn write_walls(out: &mut String, scene: &Scene, ids: &mut Ids, notes: &mut Vec<String>) {
    let m = &scene.model;
    for c in &m.contributions {
        let ContributionDef::Wall(w) = c else {
            continue;
        };
        if w.body.is_some() {
            continue;
        }
        let Some((shape, t, h, shape_card)) = wall_geometry(w) else {
            notes.push(format!(
                "rigid wall `{}`: no LS-DYNA geometric wall of its shape",
                w.name
            ));
            continue;
        };
        let motion = match wall_motion(w) {
            Ok(mo) => mo,
            Err(why) => {
                notes.push(format!("rigid wall `{}`: {why}", w.name));
                continue;
            }
        };
        if w.friction >= 1.0 {
            notes.push(format!(
                "rigid wall `{}`: μ ≥ 1 reads as LS-DYNA's FRIC = 1, no sliding",
                w.name
            ));
        }
        let nsid = ids.set(&format!("{}-tracked", w.name), &w.nodes);
        // No `_ID` card (its layout in long format is not LS-DYNA's documented one):
        // the name rides on an `$alfe` line.
        let _ = writeln!(
            out,
            "*RIGIDWALL_GEOMETRIC_{shape}{} +\n$alfe name = \"{}\"",
            if motion.is_some() { "_MOTION" } else { "" },
            w.name
        );
        card(out, &[i(nsid), i(0), i(0), r(0.0), r(1e20)]);
        card(
            out,
            &[
                r(t[0]),
                r(t[1]),
                r(t[2]),
                r(h[0]),
                r(h[1]),
                r(h[2]),
                r(w.friction),
            ],
        );
        if !shape_card.is_empty() {
            card(out, &shape_card);
        }
        if let Some((opt, d, curve)) = motion {
            let lcid = ids.curve(&curve);
            card(out, &[i(lcid), opt.to_string(), r(d[0]), r(d[1]), r(d[2])]);
        }
        if w.method == ContactMethod::Penalty {
            let _ = writeln!(
                out,
                "$alfe method = \"penalty\"\n$alfe penalty_scale = {:e}",
                w.penalty_scale
            );
        }
    }
}

/// Contact entities as rigid parts numbered after the model's parts and materials (see
/// [`super::lsdyna_entities`]).
fn write_entities(
    defs: &mut String,
    model: &mut String,
    scene: &Scene,
    ids: &mut Ids,
    notes: &mut Vec<String>,
) {
    let m = &scene.model;
    // LS-DYNA's rigid contact stiffness: the stiffest material's E = 9KG / (3K + G).
    let e = m.materials.iter().fold(0.0_f64, |a, (_, d)| {
        let law = d.build();
        let (k, g) = (law.bulk_modulus(), law.shear_modulus());
        a.max(9.0 * k * g / (3.0 * k + g))
    });
    let mut next = (m.part_names.len(), m.materials.len());
    for c in &m.contributions {
        let ContributionDef::Wall(w) = c else {
            continue;
        };
        let Some(b) = &w.body else {
            continue;
        };
        next = (next.0 + 1, next.1 + 1);
        if b.mass == 0.0 {
            notes.push(format!(
                "contact entity `{}`: massless (alfe's static body): *PART_INERTIA TM = 0, which an LS-DYNA run needs set",
                w.name
            ));
        }
        let r = super::lsdyna_entities::write_entity(w, (next.0, next.1, e), ids, defs, model);
        if let Err(why) = r {
            notes.push(format!("contact entity `{}`: {why}", w.name));
        }
    }
}

/// Initial velocities on node sets (a part's as a set of its nodes).
fn write_initial_velocity(out: &mut String, scene: &Scene, ids: &mut Ids) {
    let m = &scene.model;
    for (set, v) in &m.initial_velocity {
        let nodes = match set.strip_prefix("part:") {
            Some(part) => m.part_nodes(part),
            None => m.node_sets.get(set).cloned().unwrap_or_default(),
        };
        let sid = ids.set(&set.replace(':', "-"), &nodes);
        out.push_str("*INITIAL_VELOCITY +\n");
        card(out, &[i(sid), i(0), i(0), i(0), i(0)]);
        card(out, &[r(v[0]), r(v[1]), r(v[2]), r(0.0), r(0.0), r(0.0)]);
    }
}

fn write_controls(out: &mut String, scene: &Scene) {
    let a = &scene.run.analysis;
    out.push_str("*CONTROL_TERMINATION +\n");
    card(out, &[r(a.end_time)]);
    super::lsdyna_pairs::write_steps(out, scene);
    if a.kind == AnalysisKind::Explicit {
        return;
    }
    out.push_str("*CONTROL_IMPLICIT_GENERAL +\n");
    card(out, &[i(1), r(a.step)]);
    out.push_str("*CONTROL_IMPLICIT_AUTO +\n");
    card(out, &[i(1), i(11), i(5), r(a.min_step), r(a.max_step)]);
    if a.kind == AnalysisKind::Implicit {
        out.push_str("*CONTROL_IMPLICIT_DYNAMICS +\n");
        card(out, &[i(1), r(0.5), r(0.25)]);
        let _ = writeln!(
            out,
            "$alfe scheme = \"{}\"\n$alfe rho_inf = {:e}",
            deck_name(&a.scheme),
            a.rho_inf
        );
    }
    let s = &scene.run.solver;
    out.push_str("*CONTROL_IMPLICIT_SOLUTION +\n");
    let ilimit = if s.kind.name() == "newton" { 1 } else { 11 };
    card(out, &[i(12), i(ilimit), i(s.max_iterations)]);
    let _ = writeln!(out, "$alfe nonlinear = \"{}\"", s.kind.name());
    // The settings LS-DYNA's cards do not say as alfe means them, where not alfe's
    // defaults.
    let d = crate::scene::deck::SolverDeck::default();
    if s.line_search != crate::solve::nonlinear::LineSearch::default() {
        let _ = writeln!(
            out,
            "$alfe line_search = {}",
            line_search_text(s.line_search)
        );
    }
    for (key, v, dv) in [
        ("residual_rtol", s.residual_rtol, d.residual_rtol),
        ("increment_rtol", s.increment_rtol, d.increment_rtol),
        ("energy_rtol", s.energy_rtol, d.energy_rtol),
        ("fd_delta", s.fd_delta, d.fd_delta),
    ] {
        if v != dv {
            let _ = writeln!(out, "$alfe {key} = {v:e}");
        }
    }
    if s.bfgs_reform != d.bfgs_reform {
        let _ = writeln!(out, "$alfe bfgs_reform = {}", s.bfgs_reform);
    }
}

/// `line_search` as the deck writes it.
fn line_search_text(l: crate::solve::nonlinear::LineSearch) -> &'static str {
    match l {
        crate::solve::nonlinear::LineSearch::Auto => "\"auto\"",
        other => other.name(),
    }
}
