//! Rigid walls as CalculiX contact: each wall a rigid layer of C3D8 (every node
//! prescribed with the wall's translation), its outer faces the master surface; the
//! boundary faces whose nodes the wall tracks the slave surface; a penalty
//! (`PRESSURE-OVERCLOSURE=LINEAR`) node-to-surface pair with Coulomb friction, one-way
//! node-to-surface as alfe's walls are (hertz-sphere with C3D8 against alfe's standard
//! hex8: −0.5 % at 1 mm; CalculiX's surface-to-surface gave +1.9 %). A
//! penalty pair stands in for alfe's ALM: its penetration is p/K, with K = 50 E/h (h the
//! slave faces' median edge), 2 % of a cell at p = E (CalculiX's guidance is 5–50 E/h).
//! The wall's translation follows `*AMPLITUDE` curves sampled from its motion. Walls that
//! turn and entities with free DOFs are left out (their notes still carry them).

// Index loops over xyz components read like the formulas.
#![allow(clippy::needless_range_loop)]

use super::abaqus_notes::layer as bracket;
use super::abaqus_step::num;
use super::rigid::rigid_layer;
use crate::mesh::abaqus::face_number;
use crate::mesh::FaceRef;
use crate::model::def::{ContributionDef, MaterialDef, ModelDef};
use crate::model::walls::WallDef;
use crate::scene::Scene;
use std::fmt::Write;

/// Penalty stiffness K = PENALTY · E / h.
const PENALTY: f64 = 50.0;

/// What the walls add: model data (before `*STEP`) and step data.
#[derive(Default)]
pub struct WallText {
    pub model: String,
    pub step: String,
}

/// Write every exportable wall; what is left out goes to `notes`.
pub fn write_walls(scene: &Scene, notes: &mut Vec<String>) -> WallText {
    let m = &scene.model;
    let mut out = WallText::default();
    let (mut next_node, mut next_elem) = (m.mesh.n_nodes(), m.mesh.n_elems());
    let boundary = m.mesh.boundary_faces();
    for c in &m.contributions {
        let ContributionDef::Wall(w) = c else {
            continue;
        };
        if let Err(why) = exportable(w, scene.run.analysis.end_time) {
            notes.push(format!("rigid wall or entity `{}`: {why}", w.name));
            continue;
        }
        let slave = slave_faces(m, &boundary, &w.nodes);
        if slave.is_empty() {
            notes.push(format!(
                "rigid wall `{}`: its tracked nodes carry no boundary face (CalculiX's slave surface is made of faces)",
                w.name
            ));
            continue;
        }
        write_wall(&mut out, scene, w, &slave, (&mut next_node, &mut next_elem));
    }
    out
}

fn exportable(w: &WallDef, end: f64) -> Result<(), String> {
    if times(w, end)
        .iter()
        .any(|&t| w.motion.rotation(t).iter().any(|r| *r != 0.0))
    {
        return Err("a turning wall (only translations are written)".into());
    }
    Ok(())
}

/// Times at which the wall's motion is sampled: its curves' points in the step, each
/// interval cut in 8 (a velocity curve's displacement is piecewise quadratic).
fn times(w: &WallDef, end: f64) -> Vec<f64> {
    let mut ts = vec![0.0, end];
    for d in w.motion.dofs.iter().flatten() {
        ts.extend(
            d.curve
                .points
                .iter()
                .map(|p| p[0])
                .filter(|&t| t > 0.0 && t < end),
        );
    }
    ts.sort_by(f64::total_cmp);
    ts.dedup();
    let mut out = vec![0.0];
    for p in ts.windows(2) {
        out.extend((1..=8).map(|k| p[0] + (p[1] - p[0]) * k as f64 / 8.0));
    }
    out
}

/// Boundary faces all of whose nodes are tracked.
fn slave_faces(m: &ModelDef, boundary: &[FaceRef], tracked: &[usize]) -> Vec<FaceRef> {
    let mut is = vec![false; m.mesh.n_nodes()];
    for &n in tracked {
        is[n] = true;
    }
    boundary
        .iter()
        .copied()
        .filter(|f| m.mesh.face_nodes(*f).iter().all(|&n| is[n]))
        .collect()
}

/// The median corner-to-corner edge of the faces.
fn median_edge(m: &ModelDef, faces: &[FaceRef]) -> f64 {
    let mut e: Vec<f64> = Vec::new();
    for f in faces {
        let kind = m.mesh.kinds[f.elem];
        let en = m.mesh.elem_nodes(f.elem);
        let c: Vec<[f64; 3]> = kind
            .face_corners(f.face as usize)
            .iter()
            .map(|&k| m.mesh.coords[en[k]])
            .collect();
        for a in 0..c.len() {
            let b = (a + 1) % c.len();
            e.push(
                (0..3)
                    .map(|k| (c[a][k] - c[b][k]).powi(2))
                    .sum::<f64>()
                    .sqrt(),
            );
        }
    }
    e.sort_by(f64::total_cmp);
    e[e.len() / 2]
}

/// A material's small-strain Young's modulus, E = 9KG / (3K + G) from the moduli the
/// material itself reports.
fn young(m: &MaterialDef) -> f64 {
    let law = m.build();
    let (k, g) = (law.bulk_modulus(), law.shear_modulus());
    9.0 * k * g / (3.0 * k + g)
}

/// The box, in the wall's frame, that the tracked nodes sweep over the step (the wall
/// translates; sampled at [`times`]), widened by 15 % of its diagonal and two facets.
fn reach(m: &ModelDef, w: &WallDef, end: f64, h: f64) -> ([f64; 3], [f64; 3]) {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for t in times(w, end) {
        let pose = w.motion.pose(t);
        for &n in &w.nodes {
            let x = pose.to_local(m.mesh.coords[n]);
            for k in 0..3 {
                lo[k] = lo[k].min(x[k]);
                hi[k] = hi[k].max(x[k]);
            }
        }
    }
    let diag = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
    let margin = 0.15 * diag + 2.0 * h;
    // An entity free to turn may meet the nodes anywhere on its surface.
    if w.body
        .as_ref()
        .is_some_and(|b| b.free[3..].iter().any(|&f| f))
    {
        return ([-1e30; 3], [1e30; 3]);
    }
    (lo.map(|x| x - margin), hi.map(|x| x + margin))
}

/// An Abaqus name from an alfe one.
fn name(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect()
}

fn write_wall(
    out: &mut WallText,
    scene: &Scene,
    w: &WallDef,
    slave: &[FaceRef],
    (next_node, next_elem): (&mut usize, &mut usize),
) {
    let m = &scene.model;
    let end = scene.run.analysis.end_time;
    let h = median_edge(m, slave);
    let (lo, hi) = reach(m, w, end, h);
    let layer = rigid_layer(&w.shape, lo, hi, h);
    let pose = w.motion.pose(0.0);
    let n = name(&w.name);
    let mut model = String::new();
    let o = &mut model;
    let _ = writeln!(
        o,
        "** rigid wall `{}`: {} facets",
        w.name,
        layer.elems.len()
    );
    let _ = writeln!(o, "*NODE, NSET=W_{n}_N");
    for (i, x) in layer.nodes.iter().enumerate() {
        let g = pose.to_global(*x);
        let _ = writeln!(
            o,
            "{}, {}, {}, {}",
            *next_node + i + 1,
            num(g[0]),
            num(g[1]),
            num(g[2])
        );
    }
    let _ = writeln!(o, "*ELEMENT, TYPE=C3D8, ELSET=W_{n}");
    for (i, e) in layer.elems.iter().enumerate() {
        let ids: Vec<String> = e.iter().map(|a| (*next_node + a + 1).to_string()).collect();
        let _ = writeln!(o, "{}, {}", *next_elem + i + 1, ids.join(", "));
    }
    *next_node += layer.nodes.len();
    *next_elem += layer.elems.len();
    // An entity: the layer a CalculiX rigid body on a reference node (translations) and
    // a rotation node, both at the entity's reference point.
    let body = w.body.as_ref().map(|_| {
        let (r, q) = (*next_node + 1, *next_node + 2);
        let x = w.motion.pose(0.0).to_global([0.0; 3]);
        for id in [r, q] {
            let _ = writeln!(
                o,
                "*NODE, NSET=W_{n}_REF\n{id}, {}, {}, {}",
                num(x[0]),
                num(x[1]),
                num(x[2])
            );
        }
        let _ = writeln!(o, "*RIGID BODY, NSET=W_{n}_N, REF NODE={r}, ROT NODE={q}");
        *next_node += 2;
        (r, q)
    });
    let e_slave = slave
        .iter()
        .map(|f| young(&m.materials[m.elem_material(f.elem)].1))
        .fold(0.0, f64::max);
    let _ = writeln!(
        o,
        "*MATERIAL, NAME=W_{n}_RIGID\n*ELASTIC\n{:.13e}, 0.3",
        1e3 * e_slave
    );
    // Dynamic steps need every material's density; the layer's motion is prescribed.
    let rho = m
        .materials
        .iter()
        .map(|x| x.1.build().density())
        .fold(0.0, f64::max);
    if rho > 0.0 {
        let _ = writeln!(o, "*DENSITY\n{rho:e}");
    }
    let _ = writeln!(o, "*SOLID SECTION, ELSET=W_{n}, MATERIAL=W_{n}_RIGID");
    let _ = writeln!(o, "*SURFACE, NAME=W_{n}_MASTER, TYPE=ELEMENT\nW_{n}, S2");
    let _ = writeln!(o, "*SURFACE, NAME=W_{n}_SLAVE, TYPE=ELEMENT");
    for f in slave {
        if let Some(s) = face_number(&m.mesh, *f) {
            let _ = writeln!(o, "{}, S{s}", f.elem + 1);
        }
    }
    let k = PENALTY * e_slave / h;
    let _ = writeln!(
        o,
        "*CONTACT PAIR, INTERACTION=W_{n}_I, TYPE=NODE TO SURFACE\nW_{n}_SLAVE, W_{n}_MASTER\n*SURFACE INTERACTION, NAME=W_{n}_I\n** penalty K = {PENALTY} E/h, E = {e_slave:.6e}, h = {h:.6e}\n*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR\n{k:.13e}"
    );
    if w.friction > 0.0 {
        // Stick slope: shear stress per slip length, a tenth of the normal stiffness.
        let _ = writeln!(o, "*FRICTION\n{}, {:.13e}", w.friction, 0.1 * k);
    }
    let mut step = String::new();
    let s = &mut step;
    let ts = times(w, end);
    if let (Some((r, q)), Some(b)) = (body, &w.body) {
        write_body(o, s, &n, (r, q), b, w, &ts);
        let _ = writeln!(s, "*NODE PRINT, NSET=W_{n}_REF, TOTALS=ONLY\nRF");
        out.model += &bracket(&model);
        out.step += &bracket(&step);
        return;
    }
    for c in 0..3 {
        let moves = ts.iter().any(|&t| w.motion.displacement(t)[c] != 0.0);
        if !moves {
            let _ = writeln!(s, "*BOUNDARY\nW_{n}_N, {}, {}", c + 1, c + 1);
            continue;
        }
        // The translation component as an amplitude (in step time) of a unit value.
        amplitude(o, &format!("W_{n}_A{}", c + 1), &ts, |t| {
            w.motion.displacement(t)[c]
        });
        let _ = writeln!(
            s,
            "*BOUNDARY, AMPLITUDE=W_{n}_A{}\nW_{n}_N, {}, {}, 1.0",
            c + 1,
            c + 1,
            c + 1
        );
    }
    let _ = writeln!(s, "*NODE PRINT, NSET=W_{n}_N, TOTALS=ONLY\nRF");
    out.model += &bracket(&model);
    out.step += &bracket(&step);
}

/// An amplitude `name` of `f` sampled at `ts`.
fn amplitude(o: &mut String, name: &str, ts: &[f64], f: impl Fn(f64) -> f64) {
    let _ = writeln!(o, "*AMPLITUDE, NAME={name}");
    let pairs: Vec<String> = ts
        .iter()
        .map(|&t| format!("{}, {}", num(t), num(f(t))))
        .collect();
    for chunk in pairs.chunks(4) {
        let _ = writeln!(o, "{}", chunk.join(", "));
    }
}

/// An entity's DOFs on its reference node `r` (translations) and rotation node `q`:
/// prescribed ones by amplitudes, free ones left free, loads on free ones as `*CLOAD`
/// (moments on the rotation node). Its mass, inertia and friction threshold have no
/// keyword here: the notes carry them.
fn write_body(
    o: &mut String,
    s: &mut String,
    n: &str,
    (r, q): (usize, usize),
    b: &crate::model::body::BodyDef,
    w: &WallDef,
    ts: &[f64],
) {
    for c in 0..6 {
        let (node, dof) = if c < 3 { (r, c + 1) } else { (q, c - 2) };
        if b.free[c] {
            if let Some((scale, curve)) = &b.loads[c] {
                amplitude(o, &format!("W_{n}_L{}", c + 1), ts, |t| curve.eval(t));
                let _ = writeln!(
                    s,
                    "*CLOAD, AMPLITUDE=W_{n}_L{}\n{node}, {dof}, {}",
                    c + 1,
                    num(*scale)
                );
            }
            continue;
        }
        let value = |t: f64| {
            if c < 3 {
                w.motion.displacement(t)[c]
            } else {
                w.motion.rotation(t)[c - 3]
            }
        };
        if ts.iter().all(|&t| value(t) == 0.0) {
            let _ = writeln!(s, "*BOUNDARY\n{node}, {dof}, {dof}");
            continue;
        }
        amplitude(o, &format!("W_{n}_A{}", c + 1), ts, value);
        let _ = writeln!(
            s,
            "*BOUNDARY, AMPLITUDE=W_{n}_A{}\n{node}, {dof}, {dof}, 1.0",
            c + 1
        );
    }
}
