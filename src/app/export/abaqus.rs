//! A built scene as an Abaqus/CalculiX `.inp`: nodes, elements by part and type, node
//! sets, surfaces (element faces S1…), materials, sections, initial velocities, one step
//! (`*STATIC` or `*DYNAMIC`, `abaqus_step.rs`) with its supports and loads at their
//! end-of-step values (ramped over the step, Abaqus' default for static steps); rigid
//! walls as rigid element layers in penalty contact (`contact.rs`). What the keywords
//! cannot hold exactly for alfe goes to `** alfe` notes (`abaqus_notes.rs`); what has
//! no equivalent for CalculiX — entities with free DOFs, turning walls, small-sliding
//! pairs, couplings, load curves other than a ramp, rotations — is listed in the
//! file's header and returned.

// Index loops over xyz components read like the formulas.
#![allow(clippy::needless_range_loop)]

use super::abaqus_step::num;
use crate::fem::element::Formulation;
use crate::fem::surface::traction_face;
use crate::mesh::abaqus::{face_number, to_abaqus_order};
use crate::mesh::{ElemKind, Mesh};
use crate::model::def::{ContributionDef, MaterialDef, Motion};
use crate::model::loads::LoadDef;
use crate::scene::Scene;
use std::collections::BTreeMap;
use std::fmt::Write;

/// The `.inp` text and what it leaves out.
pub struct Exported {
    pub text: String,
    pub left_out: Vec<String>,
}

/// The CalculiX element of an alfe one. F-bar and hybrid hex8 have no CalculiX twin: a
/// nearly incompressible part (ν > 0.45) gets C3D8R (one point, no volumetric locking;
/// C3D8 gave 1.7 × alfe's force on rubber-indent at 7–11 mm), others C3D8.
fn element_type(
    kind: ElemKind,
    form: Formulation,
    nu: f64,
    notes: &mut Vec<String>,
    part: &str,
) -> &'static str {
    match (kind, form) {
        (ElemKind::Hex8, Formulation::Eas) => "C3D8I",
        (ElemKind::Hex8, Formulation::Reduced { .. }) => "C3D8R",
        (ElemKind::Hex8, Formulation::Standard) => "C3D8",
        (ElemKind::Hex8, _) if nu > 0.45 => {
            notes.push(format!("part `{part}`: F-bar/hybrid hex8 of a nearly incompressible material written as C3D8R (reduced integration with CalculiX's hourglass control: answers differ)"));
            "C3D8R"
        }
        (ElemKind::Hex8, _) => {
            notes.push(format!("part `{part}`: F-bar/hybrid hex8 written as C3D8 (CalculiX has no F-bar element; answers differ for nearly incompressible parts)"));
            "C3D8"
        }
        (kind, f) => {
            if f != Formulation::Standard {
                notes.push(format!(
                    "part `{part}`: the {} formulation of {} written as the plain element",
                    f.deck_name(),
                    kind.name()
                ));
            }
            match kind {
                ElemKind::Tet4 => "C3D4",
                ElemKind::Tet10 => "C3D10",
                _ => "C3D6",
            }
        }
    }
}

/// Numbers 16 to a line.
fn write_list(out: &mut String, items: impl Iterator<Item = usize>) {
    let v: Vec<String> = items.map(|i| (i + 1).to_string()).collect();
    for chunk in v.chunks(16) {
        let _ = writeln!(out, "{},", chunk.join(", "));
    }
}

fn write_material(out: &mut String, name: &str, m: &MaterialDef) -> bool {
    let _ = writeln!(out, "*MATERIAL, NAME={name}");
    let (finite, density) = match m {
        MaterialDef::LinearElastic { e, nu, density } => {
            let _ = writeln!(out, "*ELASTIC\n{e:.13e}, {nu}");
            (false, *density)
        }
        MaterialDef::NeoHookean { e, nu, density } => {
            let (mu, k) = (e / (2.0 * (1.0 + nu)), e / (3.0 * (1.0 - 2.0 * nu)));
            let _ = writeln!(
                out,
                "*HYPERELASTIC, NEO HOOKE\n{:.13e}, {:.13e}",
                mu / 2.0,
                2.0 / k
            );
            (true, *density)
        }
        MaterialDef::MooneyRivlin {
            c10,
            c01,
            nu,
            density,
        } => {
            let mu = 2.0 * (c10 + c01);
            let k = 2.0 * mu * (1.0 + nu) / (3.0 * (1.0 - 2.0 * nu));
            let _ = writeln!(
                out,
                "*HYPERELASTIC, MOONEY-RIVLIN\n{c10:.13e}, {c01:.13e}, {:.13e}",
                2.0 / k
            );
            (true, *density)
        }
        MaterialDef::J2 {
            e,
            nu,
            hardening,
            density,
        } => {
            let _ = writeln!(out, "*ELASTIC\n{e:.13e}, {nu}\n*PLASTIC");
            let pts: Vec<[f64; 2]> = match hardening {
                crate::material::Hardening::Linear { sigma_y0, h } => {
                    vec![[0.0, *sigma_y0], [1.0, sigma_y0 + h]]
                }
                crate::material::Hardening::Power { sigma_y0, k, n } => (0..=20)
                    .map(|i| {
                        let ep = (i as f64 / 20.0).powi(2);
                        [ep, sigma_y0 + k * ep.powf(*n)]
                    })
                    .collect(),
                crate::material::Hardening::Tabulated { points } => points.clone(),
            };
            for [ep, sy] in pts {
                let _ = writeln!(out, "{sy:.13e}, {ep:.13e}");
            }
            (true, *density)
        }
    };
    if density > 0.0 {
        let _ = writeln!(out, "*DENSITY\n{density:.13e}");
    }
    finite
}

/// Export `scene` as an `.inp`.
pub fn export_inp(scene: &Scene) -> Exported {
    let m = &scene.model;
    let mesh: &Mesh = &m.mesh;
    let mut notes = Vec::new();
    let mut out = String::new();
    let _ = writeln!(
        out,
        "*HEADING\n{} (written by alfe {})",
        scene.run.name,
        crate::VERSION
    );
    let _ = writeln!(out, "*NODE, NSET=NALL");
    for (i, x) in mesh.coords.iter().enumerate() {
        let _ = writeln!(
            out,
            "{}, {}, {}, {}",
            i + 1,
            num(x[0]),
            num(x[1]),
            num(x[2])
        );
    }
    // Elements by part and type, numbered 1.. in mesh order.
    let mut blocks: BTreeMap<(u32, &'static str), Vec<usize>> = BTreeMap::new();
    for e in 0..mesh.n_elems() {
        let p = mesh.elem_part[e];
        let ty = element_type(
            mesh.kinds[e],
            m.part_formulation[p as usize],
            m.materials[m.part_material[p as usize]].1.nu(),
            &mut notes,
            &m.part_names[p as usize],
        );
        blocks.entry((p, ty)).or_default().push(e);
    }
    notes.sort();
    notes.dedup();
    for ((p, ty), es) in &blocks {
        let _ = writeln!(
            out,
            "*ELEMENT, TYPE={ty}, ELSET={}",
            m.part_names[*p as usize]
        );
        for &e in es {
            let mut n = mesh.elem_nodes(e).to_vec();
            to_abaqus_order(mesh.kinds[e], &mut n);
            let ns: Vec<String> = n.iter().map(|i| (i + 1).to_string()).collect();
            let _ = writeln!(out, "{}, {}", e + 1, ns.join(", "));
        }
    }
    for (name, nodes) in &m.node_sets {
        let _ = writeln!(out, "*NSET, NSET={name}");
        write_list(&mut out, nodes.iter().copied());
    }
    for (name, faces) in &m.surfaces {
        let _ = writeln!(out, "*SURFACE, NAME={name}, TYPE=ELEMENT");
        for f in faces {
            if let Some(s) = face_number(mesh, *f) {
                let _ = writeln!(out, "{}, S{s}", f.elem + 1);
            }
        }
    }
    let mut finite = false;
    for (name, mat) in &m.materials {
        finite |= write_material(&mut out, name, mat);
    }
    for (p, name) in m.part_names.iter().enumerate() {
        let _ = writeln!(
            out,
            "*SOLID SECTION, ELSET={name}, MATERIAL={}",
            m.materials[m.part_material[p]].0
        );
    }
    let walls = super::contact::write_walls(scene, &mut notes);
    out += &walls.model;
    out += &super::abaqus_step::initial_velocities(scene);
    let extra = super::abaqus_pairs::write(scene, &mut notes);
    // CalculiX's stand-ins for pairs, bolts and couplings: the notes hold them exactly.
    out += &super::abaqus_notes::layer(&extra.model);
    // One step: the analysis' own procedure (static or dynamic); several: static stages.
    let single = scene.run.analysis.stages.is_empty();
    for (k, (head, body)) in extra.steps.iter().enumerate() {
        let head = if single {
            let p = super::abaqus_step::procedure(scene, &mut notes);
            format!(
                "*STEP{{NLGEOM}}, INC=10000
{p}"
            )
        } else {
            head.clone()
        };
        out += &head.replace("{NLGEOM}", if finite { ", NLGEOM" } else { "" });
        if k == 0 {
            write_supports(&mut out, scene, &mut notes);
            write_loads(&mut out, scene);
            out += &walls.step;
        }
        out += &super::abaqus_notes::layer(body);
        let _ = writeln!(
            out,
            "*NODE PRINT, NSET=NALL
U
*END STEP"
        );
    }
    let mut text = String::new();
    for n in &notes {
        let _ = writeln!(text, "** not exported: {n}");
    }
    text += &super::abaqus_notes::notes(scene);
    text += &out;
    Exported {
        text: super::abaqus_notes::signed(text),
        left_out: notes,
    }
}

fn write_supports(out: &mut String, scene: &Scene, notes: &mut Vec<String>) {
    let end = scene.run.analysis.end_time;
    let _ = writeln!(out, "*BOUNDARY");
    for c in &scene.model.constraints {
        let Motion::Uniform { value } = &c.motion else {
            notes.push(format!("the rotation prescribed on `{}`", c.set));
            continue;
        };
        let s = c.curve.eval(end);
        if c.curve.points.len() > 2 {
            notes.push(format!(
                "the curve of `{}`'s prescribed values (its end value is ramped)",
                c.set
            ));
        }
        for k in 0..3 {
            if c.comps[k] {
                let v = value[k] * s;
                if v == 0.0 {
                    let _ = writeln!(out, "{}, {}, {}", c.set, k + 1, k + 1);
                } else {
                    let _ = writeln!(out, "{}, {}, {}, {v:.13e}", c.set, k + 1, k + 1);
                }
            }
        }
    }
}

fn write_loads(out: &mut String, scene: &Scene) {
    let m = &scene.model;
    let end = scene.run.analysis.end_time;
    // Dead tractions become consistent nodal forces, summed per node.
    let mut nodal: BTreeMap<usize, [f64; 3]> = BTreeMap::new();
    let mut set_loads: Vec<(String, [f64; 3])> = Vec::new();
    let mut pressures: Vec<(usize, usize, f64)> = Vec::new();
    for c in &m.contributions {
        let load = match c {
            ContributionDef::Load(l) => l,
            // Written by `contact::write_walls`.
            ContributionDef::Wall(_) => continue,
            // Written by `abaqus_pairs::write`.
            ContributionDef::Coupling(_) | ContributionDef::Pairs(_) => continue,
        };
        match load {
            LoadDef::Nodal { set, force, curve } => {
                let s = curve.eval(end);
                set_loads.push((set.clone(), force.map(|f| f * s)));
            }
            LoadDef::Traction {
                surface,
                traction,
                curve,
            } => {
                let s = curve.eval(end);
                for fr in m.surfaces.get(surface).into_iter().flatten() {
                    let nodes = m.mesh.face_nodes(*fr);
                    let x0: Vec<[f64; 3]> = nodes.iter().map(|&n| m.mesh.coords[n]).collect();
                    let mut f = vec![0.0; 3 * nodes.len()];
                    traction_face(&x0, traction.map(|t| t * s), &mut f);
                    for (a, &n) in nodes.iter().enumerate() {
                        let e = nodal.entry(n).or_default();
                        for k in 0..3 {
                            e[k] += f[3 * a + k];
                        }
                    }
                }
            }
            LoadDef::Pressure {
                surface,
                pressure,
                curve,
            } => {
                let s = curve.eval(end);
                for fr in m.surfaces.get(surface).into_iter().flatten() {
                    if let Some(f) = face_number(&m.mesh, *fr) {
                        pressures.push((fr.elem, f, pressure * s));
                    }
                }
            }
        }
    }
    if !set_loads.is_empty() || !nodal.is_empty() {
        let _ = writeln!(out, "*CLOAD");
        for (set, f) in &set_loads {
            for k in 0..3 {
                if f[k] != 0.0 {
                    let _ = writeln!(out, "{set}, {}, {:.13e}", k + 1, f[k]);
                }
            }
        }
        for (n, f) in &nodal {
            for k in 0..3 {
                if f[k] != 0.0 {
                    let _ = writeln!(out, "{}, {}, {:.13e}", n + 1, k + 1, f[k]);
                }
            }
        }
    }
    if !pressures.is_empty() {
        let _ = writeln!(out, "*DLOAD");
        for (e, f, p) in pressures {
            let _ = writeln!(out, "{}, P{f}, {p:.13e}", e + 1);
        }
    }
}
