//! Contact entities (the paper's §3.5–3.6) as LS-DYNA writes them: the analytical shape
//! is a `*CONTACT_ENTITY` attached to a rigid part (`*PART_INERTIA` with `*MAT_RIGID`,
//! no elements), whose prescribed DOFs are `*BOUNDARY_PRESCRIBED_MOTION_RIGID`, whose
//! loaded free DOFs are `*LOAD_RIGID_BODY`, and whose fixed DOFs are `*MAT_RIGID`'s
//! constraints (CMO = 1, CON1/CON2); DOFs named by none of these are free.
//!
//! `*CONTACT_ENTITY` geometry as alfe writes and reads it: (XC, YC, ZC) is the shape's
//! centre (alfe's `point`; a cylinder is centred on it), A its axis (alfe's `normal`),
//! B its x axis; GEOTYP 1 plane, 2 sphere, 3 cylinder (G1 radius, G2 length), 4
//! ellipsoid (G1–G3 semi-axes along B, A × B, A), 5 torus (G1, G2), 9 rectangle (G1 ×
//! G2). SSTYP 2: the tracked nodes are a node set. What LS-DYNA has no field for (the
//! ALM settings, traced points, the name) rides on `$alfe` lines.

use super::lsdyna_cards::{card, r, Numbering};
use crate::contact::law::Threshold;
use crate::contact::motion::MotionKind;
use crate::contact::wall::{ContactMethod, ShapeDef};
use crate::model::walls::WallDef;
use std::fmt::Write;

/// LS-DYNA's DOF codes of ux, uy, uz, rx, ry, rz.
pub const DOF_CODES: [i64; 6] = [1, 2, 3, 5, 6, 7];

/// `*MAT_RIGID`'s constraint code of a fixed (x, y, z) triple: 0 none, 1 x, 2 y, 3 z,
/// 4 x and y, 5 y and z, 6 z and x, 7 all; None for no code (never: every triple has one).
pub fn constraint_code(fixed: [bool; 3]) -> i64 {
    match fixed {
        [false, false, false] => 0,
        [true, false, false] => 1,
        [false, true, false] => 2,
        [false, false, true] => 3,
        [true, true, false] => 4,
        [false, true, true] => 5,
        [true, false, true] => 6,
        [true, true, true] => 7,
    }
}

/// GEOTYP and G1…G3 of a shape; Err(why) for shapes `*CONTACT_ENTITY` has not.
fn geometry(s: &ShapeDef) -> Result<(i64, [f64; 3]), String> {
    Ok(match *s {
        ShapeDef::Plane { .. } => (1, [0.0; 3]),
        ShapeDef::Sphere { radius } => (2, [radius, 0.0, 0.0]),
        ShapeDef::Cylinder { radius, length } => (3, [radius, length, 0.0]),
        ShapeDef::Ellipsoid { radii } => (4, radii),
        ShapeDef::Torus { radius, tube } => (5, [radius, tube, 0.0]),
        ShapeDef::FinitePlane { lx, ly } => (9, [lx, ly, 0.0]),
        ShapeDef::Prism { .. } => return Err("a prism (no *CONTACT_ENTITY geometry)".into()),
    })
}

/// One entity with its rigid part `pid` and material `mid`: the part and material cards
/// go to `defs`, the contact, motions and loads to `model`; `e` is E for `*MAT_RIGID`
/// (LS-DYNA takes the contact stiffness from it). Err(why) where it cannot be written.
pub fn write_entity(
    w: &WallDef,
    (pid, mid, e): (usize, usize, f64),
    ids: &mut dyn Numbering,
    defs: &mut String,
    model: &mut String,
) -> Result<(), String> {
    let Some(b) = &w.body else {
        return Err("not an entity".into());
    };
    let (geotyp, g) = geometry(&w.shape)?;
    let m = &w.motion;
    let c = m.origin;
    let _ = writeln!(defs, "*PART_INERTIA +\n{}", w.name);
    card(defs, &[pid, 0, mid].map(|x| x.to_string()));
    card(
        defs,
        &[r(c[0]), r(c[1]), r(c[2]), r(b.mass), "0".into(), "0".into()],
    );
    let j = b.inertia;
    card(defs, &[j, 0.0, 0.0, j, 0.0, j].map(r));
    let (v, s) = (b.velocity, b.spin);
    card(defs, &[v[0], v[1], v[2], s[0], s[1], s[2]].map(r));
    // Fixed: neither prescribed nor free.
    let fixed: [bool; 6] = std::array::from_fn(|k| m.dofs[k].is_none() && !b.free[k]);
    let (con1, con2) = (
        constraint_code([fixed[0], fixed[1], fixed[2]]),
        constraint_code([fixed[3], fixed[4], fixed[5]]),
    );
    let _ = writeln!(defs, "*MAT_RIGID_TITLE +\n{}-rigid", w.name);
    card(defs, &[mid.to_string(), r(0.0), r(e), r(0.3)]);
    card(
        defs,
        &[
            r(f64::from(u8::from(con1 + con2 > 0))),
            r(con1 as f64),
            r(con2 as f64),
        ],
    );
    card(defs, &[r(0.0)]);
    let nsid = ids.set(&format!("{}-tracked", w.name), &w.nodes);
    let _ = writeln!(model, "*CONTACT_ENTITY +\n$alfe name = \"{}\"", w.name);
    write_alm_notes(model, w);
    for (name, p) in &b.trace {
        let _ = writeln!(
            model,
            "$alfe trace = {{ name = \"{name}\", point = [{:e}, {:e}, {:e}] }}",
            p[0], p[1], p[2]
        );
    }
    let fields = [pid as f64, geotyp as f64, nsid as f64, 2.0, 1.0, 0.0];
    let mut c1: Vec<String> = fields.iter().map(|&x| (x as i64).to_string()).collect();
    c1.extend([r(w.friction), "0".into()]);
    card(model, &c1);
    card(
        model,
        &[
            r(0.0),
            r(1e20),
            "0".into(),
            "0".into(),
            "0".into(),
            "0".into(),
        ],
    );
    let [ex, _, ez] = m.axes;
    card(model, &[c[0], c[1], c[2], ez[0], ez[1], ez[2]].map(r));
    card(model, &ex.map(r));
    card(model, &["0".into(), r(g[0]), r(g[1]), r(g[2])]);
    write_dofs(w, pid, ids, model);
    Ok(())
}

/// ALM and penalty settings where they are not the defaults.
fn write_alm_notes(out: &mut String, w: &WallDef) {
    if w.method == ContactMethod::Penalty {
        let _ = writeln!(
            out,
            "$alfe method = \"penalty\"\n$alfe penalty_scale = {:e}",
            w.penalty_scale
        );
    }
    if let Some(k) = w.kappa {
        let _ = writeln!(out, "$alfe kappa = {k:e}");
    }
    let _ = writeln!(
        out,
        "$alfe tangential_augmentation = {:e}",
        w.tangential_augmentation
    );
    if w.friction_threshold == Threshold::Augmented {
        out.push_str("$alfe friction_threshold = \"augmented\"\n");
    }
    if w.stick_lock_flips > 0 {
        let _ = writeln!(out, "$alfe stick_lock_flips = {}", w.stick_lock_flips);
    }
}

/// Prescribed DOFs (VAD 2 displacement, 0 velocity) and loads on free DOFs.
fn write_dofs(w: &WallDef, pid: usize, ids: &mut dyn Numbering, out: &mut String) {
    let Some(b) = &w.body else { return };
    for (k, code) in DOF_CODES.into_iter().enumerate() {
        if let Some(d) = &w.motion.dofs[k] {
            let lcid = ids.curve(&d.curve);
            let vad = if d.kind == MotionKind::Displacement {
                2
            } else {
                0
            };
            out.push_str("*BOUNDARY_PRESCRIBED_MOTION_RIGID +\n");
            let head = [pid as i64, code, vad, lcid as i64].map(|x| x.to_string());
            card(out, &[&head[..], &[r(d.scale)]].concat());
        } else if let Some((scale, curve)) = &b.loads[k] {
            let lcid = ids.curve(curve);
            out.push_str("*LOAD_RIGID_BODY +\n");
            let head = [pid as i64, code, lcid as i64].map(|x| x.to_string());
            card(out, &[&head[..], &[r(*scale)]].concat());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constraint_codes_are_distinct() {
        let mut seen = std::collections::BTreeSet::new();
        for m in 0..8u8 {
            let f = [m & 1 != 0, m & 2 != 0, m & 4 != 0];
            assert!(seen.insert(constraint_code(f)));
        }
        assert_eq!(constraint_code([true, false, true]), 6);
    }
}
