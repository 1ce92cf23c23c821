//! LS-DYNA's rigid walls as alfe walls: `*RIGIDWALL_GEOMETRIC_FLAT/PRISM/CYLINDER/
//! SPHERE` with `_MOTION`, `_ID`, `_DISPLAY`, and `*RIGIDWALL_PLANAR(_FINITE)(_ID)`.
//! LS-DYNA's geometry (see the import module): the normal runs from the tail to the head;
//! a flat wall's or prism's tail is a corner and its edge l points towards HEV; a prism
//! extends LENP behind its face; a cylinder's tail is on its axis at one end (LENCYL 0:
//! infinite); a sphere's tail is its centre.

use super::abaqus::toml_str;
use super::keyword_blocks::Block;
use crate::contact::vec3::{cross, norm, sub};
use std::collections::BTreeMap;
use std::fmt::Write;

/// What a wall may name.
pub struct Context<'a> {
    pub node_sets: &'a BTreeMap<i64, String>,
    pub parts: Vec<&'a str>,
}

/// A translated wall: its `[[walls]]` table (with `@CURVE` for its motion curve), the
/// node set it tracks and its motion curve; Err(why) for a wall not translated.
pub type Wall = (String, Option<String>, Option<i64>);

fn unit(a: [f64; 3]) -> Option<[f64; 3]> {
    let n = norm(a);
    (n > 0.0).then(|| a.map(|x| x / n))
}

fn v3(a: [f64; 3]) -> String {
    format!("[{:e}, {:e}, {:e}]", a[0], a[1], a[2])
}

/// `p + Σ s_k d_k`.
fn along(p: [f64; 3], steps: &[(f64, [f64; 3])]) -> [f64; 3] {
    let mut x = p;
    for (s, d) in steps {
        for k in 0..3 {
            x[k] += s * d[k];
        }
    }
    x
}

/// The in-plane edge l of a flat wall or prism: HEV − tail, its normal part removed.
fn edge(t: [f64; 3], hev: [f64; 3], n: [f64; 3]) -> Option<[f64; 3]> {
    let v = sub(hev, t);
    let d = v[0] * n[0] + v[1] * n[1] + v[2] * n[2];
    unit(along(v, &[(-d, n)]))
}

/// The shape's lines of a `[[walls]]` table: LS-DYNA's `shape` ("PLANAR", "FLAT",
/// "PRISM", "CYLINDER", "SPHERE") from tail `t` with unit normal `n`, its shape card at
/// data line `s`; Ok(Err(why)) where alfe has no such wall.
fn shape_lines(
    b: &Block,
    shape: &str,
    s: usize,
    t: [f64; 3],
    n: [f64; 3],
) -> Result<Result<String, String>, String> {
    let plane = || format!("shape = \"plane\"\npoint = {}\nnormal = {}\n", v3(t), v3(n));
    Ok(Ok(match shape {
        "PLANAR" => plane(),
        "FLAT" => {
            let hev = [b.real(s, 0)?, b.real(s, 1)?, b.real(s, 2)?];
            let (ll, lm) = (b.real(s, 3)?, b.real(s, 4)?);
            match edge(t, hev, n).filter(|_| ll > 0.0 && lm > 0.0) {
                None => plane(),
                Some(l) => {
                    let p = along(t, &[(0.5 * ll, l), (0.5 * lm, cross(n, l))]);
                    format!(
                        "shape = \"finite-plane\"\npoint = {}\nnormal = {}\nx_axis = {}\nsize = [{ll:e}, {lm:e}]\n",
                        v3(p),
                        v3(n),
                        v3(l)
                    )
                }
            }
        }
        "PRISM" => {
            let hev = [b.real(s, 0)?, b.real(s, 1)?, b.real(s, 2)?];
            let (ll, lm, lp) = (b.real(s, 3)?, b.real(s, 4)?, b.real(s, 5)?);
            let Some(l) = edge(t, hev, n) else {
                return Err(format!(
                    "{}: the prism's edge vector HEV lies along its normal",
                    b.at()
                ));
            };
            let p = along(t, &[(0.5 * ll, l), (0.5 * lm, cross(n, l)), (-0.5 * lp, n)]);
            format!(
                "shape = \"prism\"\npoint = {}\nnormal = {}\nx_axis = {}\nsize = [{ll:e}, {lm:e}, {lp:e}]\n",
                v3(p),
                v3(n),
                v3(l)
            )
        }
        "CYLINDER" => {
            let (rad, len, nsegs) = (b.real(s, 0)?, b.real(s, 1)?, b.int(s, 2)?);
            if nsegs != 0 {
                return Ok(Err(format!(
                    "NSEGS = {nsegs} (a cylinder of varying radius) is not translated"
                )));
            }
            if len <= 0.0 {
                return Ok(Err(
                    "an infinite cylinder (LENCYL = 0): alfe's cylinders have a length".into(),
                ));
            }
            let p = along(t, &[(0.5 * len, n)]);
            format!(
                "shape = \"cylinder\"\npoint = {}\nnormal = {}\nradius = {rad:e}\nlength = {len:e}\n",
                v3(p),
                v3(n)
            )
        }
        "SPHERE" => format!(
            "shape = \"sphere\"\npoint = {}\nradius = {:e}\n",
            v3(t),
            b.real(s, 0)?
        ),
        other => return Ok(Err(format!("wall shape {other} is not translated"))),
    }))
}

/// LS-DYNA's shape name of a wall keyword.
fn shape_of(kw: &str) -> &str {
    match kw.strip_prefix("RIGIDWALL_GEOMETRIC_") {
        Some(rest) => rest.split('_').next().unwrap_or(""),
        None if kw.contains("_FINITE") => "FLAT",
        None => "PLANAR",
    }
}

/// Read one wall keyword.
pub fn wall(ctx: Context, b: &Block) -> Result<Result<Wall, String>, String> {
    let kw = b.kw.as_str();
    for bad in ["_DEFORM", "_INTERIOR", "_MOVING", "_ORTHO"] {
        if kw.contains(bad) {
            return Ok(Err(format!("the {bad} option is not translated")));
        }
    }
    let c = usize::from(kw.contains("_ID"));
    let title = (c == 1)
        .then(|| {
            b.data
                .first()
                .map(|l| l.text.get(10..).unwrap_or("").trim().to_string())
        })
        .flatten()
        .filter(|s| !s.is_empty());
    let name = b
        .note("name")
        .map(|s| s.trim_matches('"').to_string())
        .or(title)
        .unwrap_or(format!("rigidwall-{}", b.line.number));
    b.need(c + 2)?;
    if b.int(c, 1)? != 0 || b.int(c, 2)? != 0 {
        return Ok(Err(
            "NSIDEX or BOXID (excluded nodes, a box) is not translated".into(),
        ));
    }
    let t = [b.real(c + 1, 0)?, b.real(c + 1, 1)?, b.real(c + 1, 2)?];
    let h = [b.real(c + 1, 3)?, b.real(c + 1, 4)?, b.real(c + 1, 5)?];
    let Some(n) = unit(sub(h, t)) else {
        return Err(format!(
            "{}: the wall's normal is zero (head = tail)",
            b.at()
        ));
    };
    let shape = shape_of(kw);
    let lines = match shape_lines(b, shape, c + 2, t, n)? {
        Ok(l) => l,
        Err(why) => return Ok(Err(why)),
    };
    let mut out = format!("[[walls]]\nname = {}\n{lines}", toml_str(&name));
    let nsid = b.int(c, 0)?;
    let set = if nsid == 0 {
        match ctx.parts.as_slice() {
            [p] => {
                let _ = writeln!(out, "part = {}", toml_str(p));
                None
            }
            _ => {
                return Ok(Err(
                    "NSID = 0 (every node) with several parts: name a node set".into(),
                ))
            }
        }
    } else {
        let s = ctx
            .node_sets
            .get(&nsid)
            .cloned()
            .ok_or_else(|| format!("{}: node set {nsid} is not defined", b.at()))?;
        let _ = writeln!(out, "nodes = {}", toml_str(&s));
        Some(s)
    };
    let fric = b.real(c + 1, 6)?;
    if fric != 0.0 {
        let _ = writeln!(out, "friction = {fric}");
    }
    for key in ["method", "penalty_scale"] {
        if let Some(v) = b.note(key) {
            let _ = writeln!(out, "{key} = {v}");
        }
    }
    let mut lcid = None;
    if kw.contains("_MOTION") {
        let mc = c + 2 + usize::from(shape != "PLANAR");
        b.need(mc + 1)?;
        let Some(d) = unit([b.real(mc, 2)?, b.real(mc, 3)?, b.real(mc, 4)?]) else {
            return Err(format!(
                "{}: the motion's direction (VX, VY, VZ) is zero",
                b.at()
            ));
        };
        let kind = if b.int(mc, 1)? == 0 {
            ", type = \"velocity\""
        } else {
            ""
        };
        let _ = writeln!(
            out,
            "motion = {{ translation = {}, curve = @CURVE{kind} }}",
            v3(d)
        );
        lcid = Some(b.int(mc, 0)?);
    }
    Ok(Ok((out, set, lcid)))
}
