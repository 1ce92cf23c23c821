//! `[[walls]]`: rigid walls in a deck (shape, placement, prescribed motion, friction,
//! ALM or penalty, tracked nodes) turned into [`WallDef`]s, with the checks an analyst
//! needs: sizes, axes, a tracked set that exists and no tracked node starting inside.
//! `[[entities]]` (contact entities, rigid bodies) are the same table where a DOF may
//! also be `type = "free"` or `type = "force"` (free, loaded by `scale × curve`), with
//! body-fixed points to `trace`.

use super::check::{err, positive, unique_names, unit};
use super::context::Context;
use super::deck::{DofType, SegmentDeck, ShapeKind, WallDeck, WallMotionDeck};
use crate::contact::law::DEFAULT_TANGENTIAL_AUGMENTATION;
use crate::contact::motion::{DofMotion, MotionKind, RigidMotion, DOF_NAMES};
use crate::contact::wall::{project, ShapeDef};
use crate::curve::Curve;
use crate::mesh::select::{mean_face_size, tributary_areas};
use crate::model::body::BodyDef;
use crate::model::walls::WallDef;
use crate::Result;
use nalgebra::Vector3;
use std::collections::BTreeSet;

/// Free DOFs of an entity and their loads.
type FreeDofs = ([bool; 6], [Option<(f64, Curve)>; 6]);

/// A wall's motion from any of the deck's three forms (see [`WallMotionDeck`]), and an
/// entity's free DOFs (`entity`; a wall refuses them).
fn build_motion(
    m: &WallMotionDeck,
    mf: &str,
    origin: [f64; 3],
    axes: [[f64; 3]; 3],
    ctx: &Context,
    entity: bool,
) -> Result<(RigidMotion, FreeDofs)> {
    let mut motion = RigidMotion::fixed(origin, axes);
    let mut free: FreeDofs = Default::default();
    let curve = |field: &str, name: &Option<String>, kind: MotionKind| -> Result<Curve> {
        match (name, kind) {
            (None, MotionKind::Velocity) => Ok(Curve::constant(1.0)),
            _ => ctx.curve(format!("{mf}.{field}"), name),
        }
    };
    let one_direction = m.translation.is_some()
        || m.curve.is_some()
        || m.axis.is_some()
        || m.angle.is_some()
        || m.rotation_curve.is_some();
    let per_dof = [&m.ux, &m.uy, &m.uz, &m.rx, &m.ry, &m.rz];
    let forms = [
        (one_direction, "translation/axis/angle"),
        (
            per_dof
                .iter()
                .filter_map(|d| d.as_ref())
                .any(|d| !matches!(d.kind, Some(DofType::Free | DofType::Force))),
            "ux … rz",
        ),
        (m.segments.is_some(), "segments"),
    ];
    let given: Vec<&str> = forms.iter().filter(|f| f.0).map(|f| f.1).collect();
    if given.len() > 1 {
        return Err(err(
            mf,
            format!(
                "give the motion in one form, not {} together",
                given.join(" and ")
            ),
        ));
    }
    if let Some(v) = m.translation {
        if v.iter().any(|x| !x.is_finite()) {
            return Err(err(format!("{mf}.translation"), "expected finite numbers"));
        }
        let c = curve("curve", &m.curve, m.kind)?;
        for (dof, &scale) in motion.dofs[..3].iter_mut().zip(&v) {
            *dof = Some(DofMotion {
                kind: m.kind,
                scale,
                curve: c.clone(),
            });
        }
    } else if m.curve.is_some() {
        return Err(err(format!("{mf}.curve"), "given without `translation`"));
    }
    match (m.axis, m.angle) {
        (Some(a), Some(angle)) => {
            if !angle.is_finite() {
                return Err(err(format!("{mf}.angle"), "expected a finite number"));
            }
            let a = unit(format!("{mf}.axis"), a)?;
            let c = curve("rotation_curve", &m.rotation_curve, m.kind)?;
            for (dof, &ai) in motion.dofs[3..].iter_mut().zip(&a) {
                *dof = Some(DofMotion {
                    kind: m.kind,
                    scale: ai * angle,
                    curve: c.clone(),
                });
            }
        }
        (None, None) if m.rotation_curve.is_some() => {
            return Err(err(
                format!("{mf}.rotation_curve"),
                "given without `axis` and `angle`",
            ))
        }
        (None, None) => {}
        _ => return Err(err(mf, "a rotation needs both `axis` and `angle`")),
    }
    for (i, d) in per_dof.iter().enumerate() {
        if let Some(d) = d {
            let field = format!("{}.scale", DOF_NAMES[i]);
            if !d.scale.is_finite() {
                return Err(err(format!("{mf}.{field}"), "expected a finite number"));
            }
            let kind = match d.kind {
                None => m.kind,
                Some(DofType::Displacement) => MotionKind::Displacement,
                Some(DofType::Velocity) => MotionKind::Velocity,
                Some(t @ (DofType::Free | DofType::Force)) => {
                    let name = DOF_NAMES[i];
                    if !entity {
                        return Err(err(
                            format!("{mf}.{name}.type"),
                            "a wall's motion is prescribed; a body with free DOFs is a contact entity: declare it under [[entities]]",
                        ));
                    }
                    free.0[i] = true;
                    if t == DofType::Force {
                        let c = ctx.curve(format!("{mf}.{name}.curve"), &d.curve)?;
                        free.1[i] = Some((d.scale, c));
                    } else if d.curve.is_some() || d.scale != 1.0 {
                        return Err(err(
                            format!("{mf}.{name}"),
                            "a free DOF takes no `curve` or `scale` (`type = \"force\"` loads it)",
                        ));
                    }
                    continue;
                }
            };
            motion.dofs[i] = Some(DofMotion {
                kind,
                scale: d.scale,
                curve: curve(&format!("{}.curve", DOF_NAMES[i]), &d.curve, kind)?,
            });
        }
    }
    if let Some(segs) = &m.segments {
        if m.kind == MotionKind::Velocity {
            return Err(err(
                format!("{mf}.type"),
                "segments give displacements (increments per segment); drop `type = \"velocity\"`",
            ));
        }
        motion.dofs = segments(segs, mf)?;
        for ((&f, dof), name) in free.0.iter().zip(&mut motion.dofs).zip(DOF_NAMES) {
            if f && dof.take().is_some() {
                return Err(err(
                    format!("{mf}.segments"),
                    format!("move the free DOF {name}; a DOF is free or prescribed"),
                ));
            }
        }
    }
    for ((&f, dof), name) in free.0.iter().zip(&motion.dofs).zip(DOF_NAMES) {
        if f && dof.is_some() {
            return Err(err(
                format!("{mf}.{name}"),
                "is free but also moved by the translation/axis form; a DOF is free or prescribed",
            ));
        }
    }
    Ok((motion, free))
}

/// Per-DOF displacement curves through the segments' cumulative increments.
fn segments(segs: &[SegmentDeck], mf: &str) -> Result<[Option<DofMotion>; 6]> {
    if segs.is_empty() {
        return Err(err(
            format!("{mf}.segments"),
            "expected at least one segment",
        ));
    }
    let mut points: Vec<Vec<[f64; 2]>> = vec![vec![[0.0, 0.0]]; 6];
    let mut t0 = 0.0;
    for (k, s) in segs.iter().enumerate() {
        let sf = format!("{mf}.segments[{k}]");
        if !(s.to.is_finite() && s.to > t0) {
            return Err(err(
                format!("{sf}.to"),
                format!(
                    "expected an end time after {t0} (the previous segment's end), got {}",
                    s.to
                ),
            ));
        }
        for (field, v) in [("translation", s.translation), ("rotation", s.rotation)] {
            if v.iter().any(|x| !x.is_finite()) {
                return Err(err(format!("{sf}.{field}"), "expected finite numbers"));
            }
        }
        let inc = [
            s.translation[0],
            s.translation[1],
            s.translation[2],
            s.rotation[0],
            s.rotation[1],
            s.rotation[2],
        ];
        for i in 0..6 {
            let last = points[i].last().unwrap()[1];
            points[i].push([s.to, last + inc[i]]);
        }
        t0 = s.to;
    }
    let mut dofs: [Option<DofMotion>; 6] = Default::default();
    for i in 0..6 {
        if points[i].iter().any(|p| p[1] != 0.0) {
            dofs[i] = Some(DofMotion {
                kind: MotionKind::Displacement,
                scale: 1.0,
                curve: Curve {
                    points: std::mem::take(&mut points[i]),
                },
            });
        }
    }
    Ok(dofs)
}

/// Validate and build every `[[walls]]` entry, or every `[[entities]]` one (`section`).
pub(super) fn build_walls(
    decks: &[WallDeck],
    ctx: &Context,
    section: &str,
) -> Result<Vec<WallDef>> {
    unique_names(section, decks.iter().map(|d| d.name.as_str()))?;
    let mut out = Vec::new();
    for (i, w) in decks.iter().enumerate() {
        let f = format!("{section}[{i}]");
        out.push(build_wall(w, &f, ctx, section == "entities")?);
    }
    Ok(out)
}

/// The size L of an entity's rotation unknowns (Θ = L ψ): the lever arm of its contact.
fn body_length(shape: &ShapeDef, model_size: f64) -> f64 {
    match *shape {
        ShapeDef::Sphere { radius } | ShapeDef::Cylinder { radius, .. } => radius,
        ShapeDef::FinitePlane { lx, ly } => 0.5 * lx.max(ly),
        ShapeDef::Prism { size } => 0.5 * size[0].max(size[1]).max(size[2]),
        ShapeDef::Plane { .. } => 0.5 * model_size,
        ShapeDef::Ellipsoid { radii } => radii[0].max(radii[1]).max(radii[2]),
        ShapeDef::Torus { radius, tube } => radius + tube,
    }
}

fn shape_def(w: &WallDeck, f: &str) -> Result<ShapeDef> {
    let size = |n: usize| -> Result<Vec<f64>> {
        match &w.size {
            Some(s) if s.len() == n && s.iter().all(|&x| x > 0.0 && x.is_finite()) => Ok(s.clone()),
            Some(s) => Err(err(
                format!("{f}.size"),
                format!("expected {n} positive lengths, got {s:?}"),
            )),
            None => Err(err(
                format!("{f}.size"),
                format!("missing ({n} lengths for this shape)"),
            )),
        }
    };
    let unused = |field: &str, given: bool| -> Result<()> {
        if given {
            Err(err(
                format!("{f}.{field}"),
                format!("is not a parameter of shape {:?}", w.shape).to_lowercase(),
            ))
        } else {
            Ok(())
        }
    };
    let radii = |n: usize| -> Result<Vec<f64>> {
        match &w.radii {
            Some(r) if r.len() == n && r.iter().all(|&x| x > 0.0 && x.is_finite()) => Ok(r.clone()),
            Some(r) => Err(err(
                format!("{f}.radii"),
                format!("expected {n} positive radii, got {r:?}"),
            )),
            None => Err(err(
                format!("{f}.radii"),
                format!("missing ({n} radii for this shape)"),
            )),
        }
    };
    if !matches!(w.shape, ShapeKind::Ellipsoid | ShapeKind::Torus) {
        unused("radii", w.radii.is_some())?;
    }
    Ok(match w.shape {
        ShapeKind::Ellipsoid => {
            for (k, given) in [("radius", w.radius.is_some()), ("size", w.size.is_some())] {
                unused(k, given)?;
            }
            unused("length", w.length.is_some())?;
            let r = radii(3)?;
            ShapeDef::Ellipsoid {
                radii: [r[0], r[1], r[2]],
            }
        }
        ShapeKind::Torus => {
            for (k, given) in [("radius", w.radius.is_some()), ("size", w.size.is_some())] {
                unused(k, given)?;
            }
            unused("length", w.length.is_some())?;
            let r = radii(2)?;
            if r[1] >= r[0] {
                return Err(err(
                    format!("{f}.radii"),
                    format!(
                        "the tube radius {} must be below the centre circle's {} (a ring torus)",
                        r[1], r[0]
                    ),
                ));
            }
            ShapeDef::Torus {
                radius: r[0],
                tube: r[1],
            }
        }
        ShapeKind::Plane => {
            unused("radius", w.radius.is_some())?;
            unused("length", w.length.is_some())?;
            let display_size = match &w.size {
                None => 0.0,
                Some(_) => size(1)?[0],
            };
            ShapeDef::Plane {
                display_size,
                display_center: [0.0; 2],
            }
        }
        ShapeKind::FinitePlane => {
            unused("radius", w.radius.is_some())?;
            unused("length", w.length.is_some())?;
            let s = size(2)?;
            ShapeDef::FinitePlane { lx: s[0], ly: s[1] }
        }
        ShapeKind::Prism => {
            unused("radius", w.radius.is_some())?;
            unused("length", w.length.is_some())?;
            let s = size(3)?;
            ShapeDef::Prism {
                size: [s[0], s[1], s[2]],
            }
        }
        ShapeKind::Sphere => {
            unused("size", w.size.is_some())?;
            unused("length", w.length.is_some())?;
            ShapeDef::Sphere {
                radius: positive(format!("{f}.radius"), w.radius, "radius")?,
            }
        }
        ShapeKind::Cylinder => {
            unused("size", w.size.is_some())?;
            ShapeDef::Cylinder {
                radius: positive(format!("{f}.radius"), w.radius, "radius")?,
                length: positive(format!("{f}.length"), w.length, "length")?,
            }
        }
    })
}

/// The wall's frame: `normal` as e_z, `x_axis` (or a default) made orthogonal to it.
fn wall_axes(w: &WallDeck, f: &str) -> Result<[[f64; 3]; 3]> {
    let ez = unit(format!("{f}.normal"), w.normal)?;
    let guess = match w.x_axis {
        Some(x) => unit(format!("{f}.x_axis"), x)?,
        None if ez[0].abs() < 0.9 => [1.0, 0.0, 0.0],
        None => [0.0, 1.0, 0.0],
    };
    let d = guess[0] * ez[0] + guess[1] * ez[1] + guess[2] * ez[2];
    let ex = [
        guess[0] - d * ez[0],
        guess[1] - d * ez[1],
        guess[2] - d * ez[2],
    ];
    if Vector3::from(ex).norm() < 1e-6 {
        return Err(err(
            format!("{f}.x_axis"),
            "must not be parallel to `normal`",
        ));
    }
    let ex = unit(format!("{f}.x_axis"), ex)?;
    let ey = Vector3::from(ez).cross(&Vector3::from(ex)).into();
    Ok([ex, ey, ez])
}

/// Friction, κ, the tangential augmentation and the penalty scale in range.
fn check_wall_numbers(w: &WallDeck, f: &str) -> Result<()> {
    if !(w.friction >= 0.0 && w.friction.is_finite()) {
        return Err(err(
            format!("{f}.friction"),
            format!("expected a coefficient ≥ 0, got {}", w.friction),
        ));
    }
    if let Some(k) = w.kappa {
        if !(k > 0.0 && k.is_finite()) {
            return Err(err(
                format!("{f}.kappa"),
                format!("expected κ > 0, got {k}"),
            ));
        }
    }
    if let Some(a) = w.tangential_augmentation {
        if !(a > 0.0 && a <= 1.0) {
            return Err(err(
                format!("{f}.tangential_augmentation"),
                format!("expected a factor in (0, 1], got {a}"),
            ));
        }
    }
    if !(w.penalty_scale > 0.0 && w.penalty_scale.is_finite()) {
        return Err(err(
            format!("{f}.penalty_scale"),
            format!("expected a positive factor, got {}", w.penalty_scale),
        ));
    }
    Ok(())
}

/// The tracked nodes (a node set, or a part's boundary), the name they go by, and each
/// node's tributary area on the tracked surface (boundary faces whose nodes are all
/// tracked).
fn tracked_nodes(w: &WallDeck, f: &str, ctx: &Context) -> Result<(String, Vec<usize>, Vec<f64>)> {
    let (set, nodes) = match (&w.nodes, &w.part) {
        (Some(s), None) => (s.clone(), ctx.set_nodes(format!("{f}.nodes"), s)?),
        (None, Some(p)) => {
            let Some(pi) = ctx.part_names.iter().position(|q| q == p) else {
                return Err(err(
                    format!("{f}.part"),
                    format!("unknown part `{p}` (parts: {})", ctx.part_names.join(", ")),
                ));
            };
            let mut v: BTreeSet<usize> = BTreeSet::new();
            for fr in ctx.boundary {
                if ctx.mesh.elem_part[fr.elem] as usize == pi {
                    v.extend(ctx.mesh.face_nodes(*fr));
                }
            }
            debug_assert!(v.iter().all(|n| ctx.part_nodes[pi].contains(n)));
            (format!("boundary of part {p}"), v.into_iter().collect())
        }
        _ => {
            return Err(err(
                f,
                format!("`{}`: expected exactly one of `nodes`, `part`", w.name),
            ))
        }
    };
    let tracked: BTreeSet<usize> = nodes.iter().copied().collect();
    let area = tributary_areas(
        ctx.mesh,
        ctx.boundary.iter().filter(|fr| {
            ctx.mesh
                .face_nodes(**fr)
                .iter()
                .all(|n| tracked.contains(n))
        }),
    );
    let areas = nodes
        .iter()
        .map(|n| area.get(n).copied().unwrap_or(0.0))
        .collect();
    Ok((set, nodes, areas))
}

/// The mean size of the tracked faces (boundary faces whose nodes are all tracked), or
/// where there are none (isolated nodes) of the boundary faces touching a tracked node,
/// or of the whole boundary: penalty friction's allowable elastic slip scales with it.
fn tracked_face_size(nodes: &[usize], ctx: &Context) -> f64 {
    let tracked: BTreeSet<usize> = nodes.iter().copied().collect();
    let tracked = &tracked;
    let faces_where = |all: bool| {
        ctx.boundary.iter().filter(move |fr| {
            let mut ns = ctx.mesh.face_nodes(**fr).into_iter();
            if all {
                ns.all(|n| tracked.contains(&n))
            } else {
                ns.any(|n| tracked.contains(&n))
            }
        })
    };
    let size = mean_face_size(ctx.mesh, faces_where(true));
    if size > 0.0 {
        return size;
    }
    let size = mean_face_size(ctx.mesh, faces_where(false));
    if size > 0.0 {
        return size;
    }
    mean_face_size(ctx.mesh, ctx.boundary)
}

fn build_wall(w: &WallDeck, f: &str, ctx: &Context, entity: bool) -> Result<WallDef> {
    let mut shape = shape_def(w, f)?;
    if w.point.iter().any(|x| !x.is_finite()) {
        return Err(err(format!("{f}.point"), "expected finite numbers"));
    }
    let [ex, ey, ez] = wall_axes(w, f)?;
    check_wall_numbers(w, f)?;
    let (set, nodes, areas) = tracked_nodes(w, f, ctx)?;
    let (motion, (free, loads)) = match &w.motion {
        None => (
            RigidMotion::fixed(w.point, [ex, ey, ez]),
            Default::default(),
        ),
        Some(m) => build_motion(
            m,
            &format!("{f}.motion"),
            w.point,
            [ex, ey, ez],
            ctx,
            entity,
        )?,
    };
    let trace = match (&w.trace, entity) {
        (Some(_), false) => return Err(err(
            format!("{f}.trace"),
            "traced points belong to contact entities ([[entities]]); a wall's path is its motion",
        )),
        (None, _) => Vec::new(),
        (Some(t), true) => {
            unique_names(&format!("{f}.trace"), t.iter().map(|p| p.name.as_str()))?;
            let mut v = Vec::new();
            for (k, p) in t.iter().enumerate() {
                let ok = !p.name.is_empty()
                    && p.name
                        .chars()
                        .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
                if !ok {
                    return Err(err(
                        format!("{f}.trace[{k}].name"),
                        format!(
                            "expected letters, digits, `_` or `-` (it names history columns), got {:?}",
                            p.name
                        ),
                    ));
                }
                if p.point.iter().any(|x| !x.is_finite()) {
                    return Err(err(
                        format!("{f}.trace[{k}].point"),
                        "expected finite numbers",
                    ));
                }
                v.push((p.name.clone(), p.point));
            }
            v
        }
    };
    let dynamic = [
        ("mass", w.mass.is_some()),
        ("inertia", w.inertia.is_some()),
        ("velocity", w.velocity.is_some()),
        ("spin", w.spin.is_some()),
    ];
    if let (Some((key, _)), false) = (dynamic.iter().find(|d| d.1), entity) {
        return Err(err(
            format!("{f}.{key}"),
            "mass, inertia and initial velocities belong to contact entities ([[entities]]); a wall follows its prescribed motion",
        ));
    }
    for (key, v) in [("mass", w.mass), ("inertia", w.inertia)] {
        if let Some(v) = v.filter(|v| !(v.is_finite() && *v > 0.0)) {
            return Err(err(
                format!("{f}.{key}"),
                format!("expected a positive number, got {v}"),
            ));
        }
    }
    for (key, v) in [("velocity", w.velocity), ("spin", w.spin)] {
        if v.is_some_and(|v| v.iter().any(|x| !x.is_finite())) {
            return Err(err(format!("{f}.{key}"), "expected finite numbers"));
        }
    }
    // A plane without a display size is drawn under the model as large as the model's
    // extent in the plane (at t = 0; a fifth larger), not around the plane's origin.
    if let ShapeDef::Plane {
        display_size,
        display_center,
    } = &mut shape
    {
        if *display_size == 0.0 {
            let pose = motion.pose(0.0);
            let (lo, hi) = crate::mesh::select::bounding_box(ctx.mesh);
            let (mut a, mut b) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
            for k in 0..8 {
                let c = std::array::from_fn(|i| if k >> i & 1 == 0 { lo[i] } else { hi[i] });
                let l = pose.to_local(c);
                for i in 0..2 {
                    a[i] = a[i].min(l[i]);
                    b[i] = b[i].max(l[i]);
                }
            }
            let extent = (b[0] - a[0]).max(b[1] - a[1]);
            *display_size = if extent > 0.0 {
                1.2 * extent
            } else {
                2e9 * ctx.tol
            };
            *display_center = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
        }
    }
    let length = body_length(&shape, 2e9 * ctx.tol);
    let def = WallDef {
        name: w.name.clone(),
        shape,
        motion,
        friction: w.friction,
        method: w.method,
        kappa: w.kappa,
        penalty_scale: w.penalty_scale,
        tangential_augmentation: w
            .tangential_augmentation
            .unwrap_or(DEFAULT_TANGENTIAL_AUGMENTATION),
        friction_threshold: w.friction_threshold,
        stick_lock_flips: w.stick_lock_flips,
        set,
        face_size: tracked_face_size(&nodes, ctx),
        nodes,
        areas,
        body: entity.then_some(BodyDef {
            free,
            loads,
            length,
            trace,
            mass: w.mass.unwrap_or(0.0),
            inertia: w.inertia.unwrap_or(0.0),
            velocity: w.velocity.unwrap_or_default(),
            spin: w.spin.unwrap_or_default(),
            owner: 0,
        }),
    };
    check_starts_outside(&def, f, ctx)?;
    Ok(def)
}

/// No tracked node may start inside the wall: the multiplier or penalty would push it out
/// with a force nobody asked for.
fn check_starts_outside(def: &WallDef, f: &str, ctx: &Context) -> Result<()> {
    let s = def.shape.build();
    let pose0 = def.motion.pose(0.0);
    for &n in &def.nodes {
        let x = ctx.mesh.coords[n];
        if let Some(p) = project(s.as_ref(), &pose0, &pose0, x, None) {
            if p.gap < -ctx.tol {
                return Err(err(
                    f,
                    format!(
                        "wall `{}`: tracked node {n} at ({:.6e}, {:.6e}, {:.6e}) starts {:.3e} inside the {} (initial penetrations are not resolved: move the wall or the part)",
                        def.name, x[0], x[1], x[2], -p.gap, s.kind()
                    ),
                ));
            }
        }
    }
    Ok(())
}
