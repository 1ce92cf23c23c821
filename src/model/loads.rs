//! Loads as contributions: a force per node on a node set, a dead traction or a follower
//! pressure on a surface, each scaled by a time curve. They add to the external forces
//! of the nodes this rank holds (a nodal load on owned nodes, a surface load on the
//! faces of local elements; the ghost summation completes shared nodes); the follower
//! pressure also adds its load stiffness −∂f_ext/∂u.

use super::contribution::{Contribution, Evaluation};
use super::dofs::DofMap;
use super::kind::{ContributionKind, Localizer};
use super::local::{LocalElements, LocalMesh};
use crate::curve::Curve;
use crate::fem::surface::{pressure_face, traction_face};
use serde::{Deserialize, Serialize};

/// A load as the deck gives it (sets by name, resolved on each rank).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub enum LoadDef {
    /// Per-node force on a node set.
    Nodal {
        set: String,
        force: [f64; 3],
        curve: Curve,
    },
    /// Dead traction on a surface (per reference area).
    Traction {
        surface: String,
        traction: [f64; 3],
        curve: Curve,
    },
    /// Follower pressure on a surface.
    Pressure {
        surface: String,
        pressure: f64,
        curve: Curve,
    },
}

impl ContributionKind for LoadDef {
    fn kind_name(&self) -> &'static str {
        "load"
    }
    fn name(&self) -> &str {
        match self {
            LoadDef::Nodal { set, .. } => set,
            LoadDef::Traction { surface, .. } | LoadDef::Pressure { surface, .. } => surface,
        }
    }
    fn describe(&self) -> String {
        match self {
            LoadDef::Nodal { set, force, .. } => format!("nodal load {force:?} per node on {set}"),
            LoadDef::Traction {
                surface, traction, ..
            } => format!("traction {traction:?} on {surface}"),
            LoadDef::Pressure {
                surface, pressure, ..
            } => format!("pressure {pressure} on {surface}"),
        }
    }
    fn localize(&self, _l: &Localizer) -> Self {
        self.clone()
    }
    fn build(&self, mesh: &LocalMesh, elements: &LocalElements) -> Box<dyn Contribution> {
        let (surface, kind, curve) = match self {
            LoadDef::Nodal { set, force, curve } => {
                let no = mesh.n_owned();
                return Box::new(NodalLoad {
                    name: set.clone(),
                    nodes: mesh.set(set).iter().copied().filter(|&n| n < no).collect(),
                    force: *force,
                    curve: curve.clone(),
                });
            }
            LoadDef::Traction {
                surface,
                traction,
                curve,
            } => (surface, SurfaceKind::Traction(*traction), curve),
            LoadDef::Pressure {
                surface,
                pressure,
                curve,
            } => (surface, SurfaceKind::Pressure(*pressure), curve),
        };
        let faces = mesh
            .surfaces
            .get(surface)
            .map(|v| v.as_slice())
            .unwrap_or(&[])
            .iter()
            .map(|&(e, f)| elements.face_nodes(e, f))
            .collect();
        Box::new(SurfaceLoad {
            name: surface.clone(),
            faces,
            kind,
            curve: curve.clone(),
        })
    }
}

/// The same force on every owned node of a set.
pub struct NodalLoad {
    name: String,
    nodes: Vec<usize>,
    force: [f64; 3],
    curve: Curve,
}

impl Contribution for NodalLoad {
    fn name(&self) -> &str {
        &self.name
    }
    fn evaluate(&mut self, ev: &mut Evaluation) -> Result<(), String> {
        if let Some((_, f)) = ev.forces.as_mut() {
            let s = self.curve.eval(ev.t);
            for &n in &self.nodes {
                for c in 0..3 {
                    f[3 * n + c] += self.force[c] * s;
                }
            }
        }
        Ok(())
    }
}

enum SurfaceKind {
    Traction([f64; 3]),
    Pressure(f64),
}

/// A traction or a follower pressure on the faces of local elements.
pub struct SurfaceLoad {
    name: String,
    /// Local nodes of each face.
    faces: Vec<Vec<usize>>,
    kind: SurfaceKind,
    curve: Curve,
}

impl Contribution for SurfaceLoad {
    fn name(&self) -> &str {
        &self.name
    }
    fn pattern(&self, dofs: &DofMap, out: &mut Vec<(usize, usize)>) {
        if let SurfaceKind::Pressure(_) = self.kind {
            for nodes in &self.faces {
                for &a in nodes {
                    for &b in nodes {
                        out.push((dofs.global_block(a), dofs.global_block(b)));
                    }
                }
            }
        }
    }
    fn evaluate(&mut self, ev: &mut Evaluation) -> Result<(), String> {
        let s = self.curve.eval(ev.t);
        // Up to a tri6 face.
        let mut fe = [0.0; 18];
        let mut ke = [0.0; 324];
        match self.kind {
            SurfaceKind::Traction(t) => {
                let Some((_, f)) = ev.forces.as_mut() else {
                    return Ok(());
                };
                let tr = [t[0] * s, t[1] * s, t[2] * s];
                for nodes in &self.faces {
                    let x0: Vec<[f64; 3]> = nodes.iter().map(|&n| ev.coords[n]).collect();
                    let m = nodes.len();
                    traction_face(&x0, tr, &mut fe[..3 * m]);
                    for (a, &n) in nodes.iter().enumerate() {
                        for c in 0..3 {
                            f[3 * n + c] += fe[3 * a + c];
                        }
                    }
                }
            }
            SurfaceKind::Pressure(p0) => {
                let p = p0 * s;
                let want_k = ev.jacobian.is_some();
                for nodes in &self.faces {
                    let m = nodes.len();
                    let x0: Vec<[f64; 3]> = nodes.iter().map(|&n| ev.coords[n]).collect();
                    let u: Vec<[f64; 3]> = nodes
                        .iter()
                        .map(|&n| [ev.u[3 * n], ev.u[3 * n + 1], ev.u[3 * n + 2]])
                        .collect();
                    pressure_face(
                        &x0,
                        &u,
                        p,
                        &mut fe[..3 * m],
                        if want_k {
                            Some(&mut ke[..9 * m * m])
                        } else {
                            None
                        },
                    );
                    if let Some((_, f)) = ev.forces.as_mut() {
                        for (a, &n) in nodes.iter().enumerate() {
                            for c in 0..3 {
                                f[3 * n + c] += fe[3 * a + c];
                            }
                        }
                    }
                    if let Some(k) = ev.jacobian.as_deref_mut() {
                        // The Jacobian of r = f_int − f_ext gets −∂f_ext/∂u.
                        let neg: Vec<f64> = ke[..9 * m * m].iter().map(|v| -v).collect();
                        let blocks: Vec<usize> =
                            nodes.iter().map(|&n| ev.dofs.global_block(n)).collect();
                        k.add_element(&blocks, &neg);
                    }
                }
            }
        }
        Ok(())
    }
}
