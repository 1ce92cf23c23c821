//! `[[boundary]]`, `[[loads]]` and `[output] reactions`: prescribed displacements and
//! rotations, nodal forces, tractions and pressures on named sets and surfaces.

use super::check::{err, known};
use super::context::Context;
use super::deck::*;
use crate::curve::Curve;
use crate::model::def::*;
use crate::model::loads::LoadDef;
use crate::Result;
use std::collections::BTreeMap;

/// Every `[[boundary]]` entry; each set it names is recorded in `resolved`.
pub(super) fn constraints(
    deck: &Deck,
    ctx: &Context,
    resolved: &mut BTreeMap<String, Vec<usize>>,
) -> Result<Vec<Constraint>> {
    let end_time = ctx.end_time;
    let timeline = ctx.timeline;
    let mut constraints = Vec::new();
    for (i, b) in deck.boundary.iter().enumerate() {
        let f = format!("boundary[{i}]");
        let nodes = ctx.set_nodes(format!("{f}.set"), b.set())?;
        resolved.insert(b.set().to_string(), nodes);
        let (comps_list, motion, crv) = match b {
            BoundaryDeck::Fixed { components, .. } => (
                components.clone(),
                Motion::Uniform { value: [0.0; 3] },
                Curve::ramp(end_time),
            ),
            BoundaryDeck::Displacement {
                components,
                value,
                curve: c,
                step,
                ..
            } => {
                if !value.is_finite() {
                    return Err(err(format!("{f}.value"), "expected a finite number"));
                }
                (
                    components.clone(),
                    Motion::Uniform { value: [*value; 3] },
                    timeline.curve(&f, c, step)?,
                )
            }
            BoundaryDeck::Rotation {
                axis,
                center,
                angle,
                curve: c,
                step,
                ..
            } => {
                let n = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
                if !(n > 0.0 && n.is_finite()) {
                    return Err(err(format!("{f}.axis"), "expected a non-zero direction"));
                }
                if !angle.is_finite() || center.iter().any(|x| !x.is_finite()) {
                    return Err(err(&f, "expected finite `angle` and `center`"));
                }
                (
                    vec![Comp::X, Comp::Y, Comp::Z],
                    Motion::Rotation {
                        axis: axis.map(|x| x / n),
                        center: *center,
                        angle: *angle,
                    },
                    timeline.curve(&f, c, step)?,
                )
            }
        };
        if comps_list.is_empty() {
            return Err(err(
                format!("{f}.components"),
                "expected at least one of \"x\", \"y\", \"z\"",
            ));
        }
        let mut comps = [false; 3];
        for c in comps_list {
            comps[c as usize] = true;
        }
        constraints.push(Constraint {
            set: b.set().to_string(),
            comps,
            motion,
            curve: crv,
        });
    }

    Ok(constraints)
}

/// Every `[[loads]]` entry; each node set it names is recorded in `resolved`.
pub(super) fn loads(
    deck: &Deck,
    ctx: &Context,
    resolved: &mut BTreeMap<String, Vec<usize>>,
) -> Result<Vec<LoadDef>> {
    let timeline = ctx.timeline;
    let mut loads = Vec::new();
    for (i, l) in deck.loads.iter().enumerate() {
        let f = format!("loads[{i}]");
        let finite3 = |v: &[f64; 3], name: &str| -> Result<()> {
            if v.iter().all(|x| x.is_finite()) {
                Ok(())
            } else {
                Err(err(format!("{f}.{name}"), "expected finite numbers"))
            }
        };
        let surface = |s: &str| -> Result<()> {
            if ctx.surfaces.contains_key(s) {
                Ok(())
            } else {
                Err(err(
                    format!("{f}.surface"),
                    format!("unknown surface `{s}` ({})", known(ctx.surfaces)),
                ))
            }
        };
        loads.push(match l {
            LoadDeck::Nodal {
                set,
                force,
                curve: c,
                step,
            } => {
                finite3(force, "force")?;
                let nodes = ctx.set_nodes(format!("{f}.set"), set)?;
                resolved.insert(set.clone(), nodes);
                LoadDef::Nodal {
                    set: set.clone(),
                    force: *force,
                    curve: timeline.curve(&f, c, step)?,
                }
            }
            LoadDeck::Traction {
                surface: s,
                traction,
                curve: c,
                step,
            } => {
                finite3(traction, "traction")?;
                surface(s)?;
                LoadDef::Traction {
                    surface: s.clone(),
                    traction: *traction,
                    curve: timeline.curve(&f, c, step)?,
                }
            }
            LoadDeck::Pressure {
                surface: s,
                pressure,
                curve: c,
                step,
            } => {
                if !pressure.is_finite() {
                    return Err(err(format!("{f}.pressure"), "expected a finite number"));
                }
                surface(s)?;
                LoadDef::Pressure {
                    surface: s.clone(),
                    pressure: *pressure,
                    curve: timeline.curve(&f, c, step)?,
                }
            }
        });
    }

    Ok(loads)
}

/// `[output] reactions`, or the constrained sets in order; recorded in `resolved`.
pub(super) fn reaction_sets(
    deck: &Deck,
    ctx: &Context,
    constraints: &[Constraint],
    resolved: &mut BTreeMap<String, Vec<usize>>,
) -> Result<Vec<String>> {
    Ok(match &deck.output.reactions {
        Some(list) => {
            for (i, n) in list.iter().enumerate() {
                let nodes = ctx.set_nodes(format!("output.reactions[{i}]"), n)?;
                resolved.insert(n.clone(), nodes);
            }
            list.clone()
        }
        None => {
            let mut v: Vec<String> = Vec::new();
            for c in constraints {
                if !v.contains(&c.set) {
                    v.push(c.set.clone());
                }
            }
            v
        }
    })
}
