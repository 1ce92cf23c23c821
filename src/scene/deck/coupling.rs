//! `[[couplings]]`: distributing couplings as the deck says them;
//! [`crate::scene::coupling`] checks them and builds the model's definitions.

use serde::de::{self, MapAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize};

/// A distributing coupling (RBE3): `nodes` names a surface (weights: tributary areas)
/// or a node set (equal weights); `point` is the reference point (default: the weighted
/// centroid). Per component x, y, z: `force` and `moment` load free DOFs, `displacement`
/// and `rotation` (radians) prescribe them; each component is a number (scaling a ramp
/// 0 → 1 over the analysis) or `{ value, curve }`.
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CouplingDeck {
    /// The coupling's name (history columns of its reference point).
    pub name: String,
    /// The coupled nodes: a node set or surface name.
    pub nodes: String,
    /// How the reference point's load is spread over the nodes: "area" (tributary areas, a surface's default) or "uniform".
    #[serde(default)]
    pub weights: Option<WeightsDeck>,
    /// The reference point (default: the coupled nodes' centroid).
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

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum WeightsDeck {
    /// Tributary areas on a surface.
    Area,
    /// Equal weights.
    Uniform,
}

#[derive(Debug, Clone, Default, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Components {
    /// Along x: a number, or { value, curve, step }.
    #[serde(default)]
    pub x: Option<Amount>,
    /// Along y: a number, or { value, curve, step }.
    #[serde(default)]
    pub y: Option<Amount>,
    /// Along z: a number, or { value, curve, step }.
    #[serde(default)]
    pub z: Option<Amount>,
}

impl Components {
    pub(crate) fn get(&self) -> [Option<&Amount>; 3] {
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

/// The deck schema of an [`Amount`] (its deserializer is written by hand).
impl schemars::JsonSchema for Amount {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "Amount".into()
    }
    fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        schemars::json_schema!({
            "description": "A number, or { value, curve, step }: the value scaled by the named curve, run in the named analysis step's time.",
            "anyOf": [
                { "type": "number" },
                {
                    "type": "object",
                    "properties": {
                        "value": { "type": "number" },
                        "curve": { "type": "string" },
                        "step": { "type": "string" }
                    },
                    "required": ["value"],
                    "additionalProperties": false
                }
            ]
        })
    }
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
