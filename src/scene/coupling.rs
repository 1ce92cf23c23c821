//! `[[couplings]]`: distributing couplings in a deck (a reference point tied to a node
//! set or surface, loaded or driven per DOF) turned into [`CouplingDef`]s, with the
//! checks an analyst needs: the set exists and spans a plane or a volume (a moment must
//! be distributable), no DOF is both loaded and prescribed, numbers are finite.

use crate::curve::Curve;
use crate::mesh::select::tributary_areas;
use crate::mesh::{FaceRef, Mesh};
use crate::model::coupling::{inertia, invert3, CouplingDef, Dof};
use crate::solve::AnalysisKind;
use crate::{Error, Result};
use serde::de::{self, MapAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize};
use std::collections::BTreeMap;

/// A distributing coupling (RBE3): `nodes` names a surface (weights: tributary areas)
/// or a node set (equal weights); `point` is the reference point (default: the weighted
/// centroid). Per component x, y, z: `force` and `moment` load free DOFs, `displacement`
/// and `rotation` (radians) prescribe them; each component is a number (scaling a ramp
/// 0 → 1 over the analysis) or `{ value, curve }`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CouplingDeck {
    pub name: String,
    pub nodes: String,
    #[serde(default)]
    pub weights: Option<WeightsDeck>,
    #[serde(default)]
    pub point: Option<[f64; 3]>,
    #[serde(default)]
    pub force: Components,
    #[serde(default)]
    pub moment: Components,
    #[serde(default)]
    pub displacement: Components,
    #[serde(default)]
    pub rotation: Components,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum WeightsDeck {
    /// Tributary areas on a surface.
    Area,
    /// Equal weights.
    Uniform,
}

#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Components {
    #[serde(default)]
    pub x: Option<Amount>,
    #[serde(default)]
    pub y: Option<Amount>,
    #[serde(default)]
    pub z: Option<Amount>,
}

impl Components {
    fn get(&self) -> [Option<&Amount>; 3] {
        [self.x.as_ref(), self.y.as_ref(), self.z.as_ref()]
    }
}

/// A number, or `{ value, curve, step }` (the curve's name; the analysis step whose time
/// it runs in).
#[derive(Debug, Clone, Serialize)]
pub struct Amount {
    pub value: f64,
    pub curve: Option<String>,
    pub step: Option<String>,
}

impl<'de> Deserialize<'de> for Amount {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Amount;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number or a table { value, curve, step }")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> std::result::Result<Amount, E> {
                Ok(Amount {
                    value: v,
                    curve: None,
                    step: None,
                })
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> std::result::Result<Amount, E> {
                self.visit_f64(v as f64)
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> std::result::Result<Amount, E> {
                self.visit_f64(v as f64)
            }
            fn visit_map<M: MapAccess<'de>>(
                self,
                mut m: M,
            ) -> std::result::Result<Amount, M::Error> {
                let (mut value, mut curve, mut step) = (None, None, None);
                while let Some(k) = m.next_key::<String>()? {
                    match k.as_str() {
                        "value" => value = Some(m.next_value::<f64>()?),
                        "curve" => curve = Some(m.next_value::<String>()?),
                        "step" => step = Some(m.next_value::<String>()?),
                        other => {
                            return Err(de::Error::unknown_field(
                                other,
                                &["value", "curve", "step"],
                            ))
                        }
                    }
                }
                let value = value.ok_or_else(|| de::Error::missing_field("value"))?;
                Ok(Amount { value, curve, step })
            }
        }
        d.deserialize_any(V)
    }
}

fn err(field: impl std::fmt::Display, msg: impl std::fmt::Display) -> Error {
    Error::input(format!("{field}: {msg}"))
}

/// What a coupling needs from the rest of the deck.
pub struct CouplingInputs<'a> {
    pub mesh: &'a Mesh,
    pub node_sets: &'a BTreeMap<String, Vec<usize>>,
    pub surfaces: &'a BTreeMap<String, Vec<FaceRef>>,
    pub set_nodes: &'a dyn Fn(String, &str) -> Result<Vec<usize>>,
    pub timeline: &'a super::steps::Timeline<'a>,
    pub analysis: AnalysisKind,
}

/// Validate and build every `[[couplings]]` entry.
pub fn build_couplings(decks: &[CouplingDeck], inp: &CouplingInputs) -> Result<Vec<CouplingDef>> {
    super::build::unique_names("couplings", decks.iter().map(|d| d.name.as_str()))?;
    let mut out = Vec::new();
    for (i, c) in decks.iter().enumerate() {
        let f = format!("couplings[{i}]");
        if inp.analysis == AnalysisKind::Explicit {
            return Err(err(
                &f,
                format!(
                    "coupling `{}`: distributing couplings need type = \"static\" or \"implicit\" (the reference point carries no mass for the explicit update)",
                    c.name
                ),
            ));
        }
        out.push(build_coupling(c, &f, inp)?);
    }
    Ok(out)
}

fn build_coupling(c: &CouplingDeck, f: &str, inp: &CouplingInputs) -> Result<CouplingDef> {
    let nodes = (inp.set_nodes)(format!("{f}.nodes"), &c.nodes)?;
    let is_surface = !inp.node_sets.contains_key(&c.nodes) && inp.surfaces.contains_key(&c.nodes);
    let weights: Vec<f64> = match (c.weights, is_surface) {
        (Some(WeightsDeck::Area), false) => {
            return Err(err(
                format!("{f}.weights"),
                format!(
                    "\"area\" needs a surface, and `{}` is a node set (use \"uniform\" or name a surface)",
                    c.nodes
                ),
            ))
        }
        (Some(WeightsDeck::Uniform), _) | (None, false) => vec![1.0; nodes.len()],
        (Some(WeightsDeck::Area), true) | (None, true) => {
            let area = tributary_areas(inp.mesh, &inp.surfaces[&c.nodes]);
            nodes.iter().map(|n| area.get(n).copied().unwrap_or(0.0)).collect()
        }
    };
    let x: Vec<[f64; 3]> = nodes.iter().map(|&n| inp.mesh.coords[n]).collect();
    let (total, centroid, j) = inertia(&x, &weights);
    let Some(j_inv) = invert3(j).filter(|_| total > 0.0) else {
        return Err(err(
            format!("{f}.nodes"),
            format!(
                "coupling `{}`: the {} nodes of `{}` lie on a line or at a point, so a moment about that line cannot be distributed; couple a surface or a set spanning a plane",
                c.name,
                nodes.len(),
                c.nodes
            ),
        ));
    };
    let length = ((j[0][0] + j[1][1] + j[2][2]) / (2.0 * total)).sqrt();
    let point = match c.point {
        Some(p) if p.iter().all(|v| v.is_finite()) => p,
        Some(_) => return Err(err(format!("{f}.point"), "expected finite numbers")),
        None => centroid,
    };
    let amount = |field: String, a: &Amount| -> Result<(f64, Curve)> {
        if !a.value.is_finite() {
            return Err(err(&field, "expected a finite number"));
        }
        Ok((a.value, inp.timeline.curve(&field, &a.curve, &a.step)?))
    };
    let mut dofs: [Dof; 6] = std::array::from_fn(|_| Dof::Free { load: None });
    for (k, axis) in ["x", "y", "z"].into_iter().enumerate() {
        for (h, (load, fixed, lname, fname)) in [
            (&c.force, &c.displacement, "force", "displacement"),
            (&c.moment, &c.rotation, "moment", "rotation"),
        ]
        .into_iter()
        .enumerate()
        {
            let (l, p) = (load.get()[k], fixed.get()[k]);
            dofs[3 * h + k] = match (l, p) {
                (Some(_), Some(_)) => {
                    return Err(err(
                        format!("{f}.{lname}.{axis}"),
                        format!("the {axis} {fname} is prescribed too: a DOF is either loaded or prescribed"),
                    ))
                }
                (Some(a), None) => Dof::Free {
                    load: Some(amount(format!("{f}.{lname}.{axis}"), a)?),
                },
                (None, Some(a)) => {
                    let (value, curve) = amount(format!("{f}.{fname}.{axis}"), a)?;
                    Dof::Prescribed { value, curve }
                }
                (None, None) => Dof::Free { load: None },
            };
        }
    }
    Ok(CouplingDef {
        name: c.name.clone(),
        set: c.nodes.clone(),
        point,
        nodes,
        weights,
        dofs,
        total_weight: total,
        centroid,
        j_inv,
        length,
        owner: 0,
    })
}
