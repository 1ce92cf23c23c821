//! Contact pairs, bolts, couplings and steps of an LS-DYNA `.k` as `[[pairs]]`,
//! `[[bolts]]`, `[[couplings]]` and `[[steps]]` (what `alfe export` writes, see
//! `app::export::lsdyna_pairs`).
//!
//! `*CONTACT_(CONSTRAINT_|AUTOMATIC_)SURFACE_TO_SURFACE(_MORTAR)` is a frictional
//! small-sliding pair (μ = FS), `*CONTACT_TIED_SURFACE_TO_SURFACE` and
//! `*CONTACT_TIED_NODES_TO_SURFACE` a tied one: the slave side (a segment set, or a node
//! set with SSTYP 4) is tracked, the master segment set the reference; SFS is the
//! penalty scale. alfe pairs once at the start: LS-DYNA's sliding contact becomes small
//! sliding. A bolt needs alfe's definition (a force, its cut's two surfaces, its lock) on
//! the `$alfe` notes of an `*INITIAL_STRESS_SECTION`, whose LCID is its curve; without
//! them the section is listed as untranslated. `*CONSTRAINED_INTERPOLATION` with a node
//! set (ITYP 1) is a distributing coupling at its dependent node, whose
//! `*LOAD_NODE_POINT` and `*BOUNDARY_PRESCRIBED_MOTION_NODE` (VAD 2) cards load or drive
//! it. `$alfe step` notes on `*CONTROL_TERMINATION` are the steps (the curves are on the
//! global time line already).

use super::keyword_blocks::Block;
use crate::mesh::lsdyna::{int, real, split};
use std::collections::BTreeMap;
use std::fmt::Write;

/// What the file defines, by number.
pub struct Ctx<'a> {
    pub node_sets: &'a BTreeMap<i64, String>,
    pub segment_sets: &'a BTreeMap<i64, String>,
    /// lcid → its name.
    pub curves: &'a BTreeMap<i64, String>,
}

/// The deck entries found and what they use.
#[derive(Default)]
pub struct Out {
    pub tables: Vec<String>,
    pub sets: Vec<String>,
    pub surfaces: Vec<String>,
    pub curves: Vec<i64>,
    /// Indices of the blocks translated here.
    pub handled: Vec<usize>,
    pub untranslated: Vec<String>,
}

const PAIR_NOTES: &[&str] = &[
    "method",
    "kappa",
    "tangential_augmentation",
    "friction_threshold",
    "search_distance",
    "weights",
];

fn q(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

/// A note's value as TOML (checked: a bad value names its line).
fn value(b: &Block, key: &str) -> Result<Option<String>, String> {
    let Some(v) = b.note(key) else {
        return Ok(None);
    };
    toml::from_str::<toml::Table>(&format!("x = {v}"))
        .map_err(|_| format!("{}: *{}: `$alfe {key} = {v}` is not a value", b.at(), b.kw))?;
    Ok(Some(v.to_string()))
}

fn note_str(b: &Block, key: &str) -> Result<Option<String>, String> {
    match value(b, key)? {
        None => Ok(None),
        Some(v) => match toml::from_str::<toml::Table>(&format!("x = {v}")) {
            Ok(t) => match t.get("x") {
                Some(toml::Value::String(s)) => Ok(Some(s.clone())),
                _ => Err(format!(
                    "{}: *{}: `$alfe {key}` must be a string",
                    b.at(),
                    b.kw
                )),
            },
            Err(_) => Ok(None),
        },
    }
}

impl Out {
    fn surface(&mut self, ctx: &Ctx, id: i64, b: &Block) -> Result<String, String> {
        let s = ctx
            .segment_sets
            .get(&id)
            .cloned()
            .ok_or_else(|| format!("{}: *{}: segment set {id} is not defined", b.at(), b.kw))?;
        if !self.surfaces.contains(&s) {
            self.surfaces.push(s.clone());
        }
        Ok(s)
    }
    fn set(&mut self, ctx: &Ctx, id: i64, b: &Block) -> Result<String, String> {
        let s = ctx
            .node_sets
            .get(&id)
            .cloned()
            .ok_or_else(|| format!("{}: *{}: node set {id} is not defined", b.at(), b.kw))?;
        if !self.sets.contains(&s) {
            self.sets.push(s.clone());
        }
        Ok(s)
    }
    /// A set or surface named on a note: whichever the file defines under that name.
    fn named(&mut self, ctx: &Ctx, name: &str, b: &Block) -> Result<(), String> {
        if ctx.segment_sets.values().any(|s| s == name) {
            if !self.surfaces.iter().any(|s| s == name) {
                self.surfaces.push(name.to_string());
            }
        } else if ctx.node_sets.values().any(|s| s == name) {
            if !self.sets.iter().any(|s| s == name) {
                self.sets.push(name.to_string());
            }
        } else {
            return Err(format!(
                "{}: *{}: `{name}` is neither a segment set nor a node set of the file",
                b.at(),
                b.kw
            ));
        }
        Ok(())
    }
    fn curve(&mut self, ctx: &Ctx, lcid: i64, b: &Block) -> Result<String, String> {
        let name = ctx.curves.get(&lcid).cloned().ok_or_else(|| {
            format!(
                "{}: *{} names curve {lcid}, which no *DEFINE_CURVE defines",
                b.at(),
                b.kw
            )
        })?;
        if !self.curves.contains(&lcid) {
            self.curves.push(lcid);
        }
        Ok(name)
    }
    fn skip(&mut self, b: &Block, why: &str) {
        self.untranslated
            .push(format!("{}: *{}: {why}", b.at(), b.kw));
    }
}

/// Every pair, bolt, coupling and step of the file.
pub fn translate(bs: &[Block], ctx: &Ctx) -> Result<Out, String> {
    let mut out = Out::default();
    let mut sections: Vec<i64> = Vec::new();
    // Couplings first: their loads may come before them.
    let mut couplings: BTreeMap<i64, Coupling> = BTreeMap::new();
    for (k, b) in bs.iter().enumerate() {
        if b.kw == "CONSTRAINED_INTERPOLATION" {
            if let Some((dnid, c)) = coupling(&mut out, ctx, bs, b)? {
                couplings.insert(dnid, c);
                out.handled.push(k);
            }
        }
    }
    for (k, b) in bs.iter().enumerate() {
        let kw = b.kw.as_str();
        let done = match kw {
            "CONTACT_SURFACE_TO_SURFACE"
            | "CONTACT_CONSTRAINT_SURFACE_TO_SURFACE"
            | "CONTACT_AUTOMATIC_SURFACE_TO_SURFACE"
            | "CONTACT_AUTOMATIC_SURFACE_TO_SURFACE_MORTAR" => contact(&mut out, ctx, b, false)?,
            "CONTACT_TIED_SURFACE_TO_SURFACE" | "CONTACT_TIED_NODES_TO_SURFACE" => {
                contact(&mut out, ctx, b, true)?
            }
            "INITIAL_STRESS_SECTION" => bolt(&mut out, ctx, b, &mut sections)?,
            "LOAD_NODE_POINT" | "BOUNDARY_PRESCRIBED_MOTION_NODE" => {
                coupling_loads(&mut out, ctx, b, &mut couplings)?
            }
            "CONTROL_TERMINATION" => {
                steps(&mut out, b)?;
                false
            }
            _ => false,
        };
        if done {
            out.handled.push(k);
        }
    }
    for (k, b) in bs.iter().enumerate() {
        if b.kw == "DATABASE_CROSS_SECTION_SET" && sections.contains(&b.int(0, 0)?) {
            out.handled.push(k);
        }
    }
    for c in couplings.into_values() {
        out.tables.push(c.table());
    }
    Ok(out)
}

/// A contact card as a `[[pairs]]` entry; false if not translated.
fn contact(out: &mut Out, ctx: &Ctx, b: &Block, tied: bool) -> Result<bool, String> {
    if b.note("section").is_some() {
        return Ok(true); // a bolt's cut: the bolt carries it
    }
    b.need(1)?;
    let (ssid, msid, sstyp, mstyp) = (b.int(0, 0)?, b.int(0, 1)?, b.int(0, 2)?, b.int(0, 3)?);
    if !matches!(sstyp, 0 | 4) || mstyp != 0 {
        out.skip(b, &format!("SSTYP {sstyp}, MSTYP {mstyp}: only a segment or node set (0, 4) against a segment set (0) is translated"));
        return Ok(false);
    }
    let tracked = if sstyp == 0 {
        out.surface(ctx, ssid, b)?
    } else {
        out.set(ctx, ssid, b)?
    };
    let reference = out.surface(ctx, msid, b)?;
    let name = note_str(b, "name")?.unwrap_or(format!("contact-{}", b.line.number));
    let mut t = format!(
        "[[pairs]]\nname = {}\ntracked = {}\nreference = {}\n",
        q(&name),
        q(&tracked),
        q(&reference)
    );
    if tied {
        t += "tied = true\n";
    } else {
        let (fs, fd) = (b.real(1, 0)?, b.real(1, 1)?);
        if fd != fs && fd != 0.0 {
            out.skip(b, "FD ≠ FS: alfe's Coulomb law has one coefficient, FS");
        }
        if fs != 0.0 {
            let _ = writeln!(t, "friction = {fs:e}");
        }
    }
    let sfs = b.real(2, 0)?;
    if sfs != 0.0 && sfs != 1.0 {
        let _ = writeln!(t, "penalty_scale = {sfs:e}");
    }
    for key in PAIR_NOTES {
        if let Some(v) = value(b, key)? {
            let _ = writeln!(t, "{key} = {v}");
        }
    }
    out.tables.push(t);
    Ok(true)
}

/// An `*INITIAL_STRESS_SECTION` with alfe's notes as a `[[bolts]]` entry.
fn bolt(out: &mut Out, ctx: &Ctx, b: &Block, sections: &mut Vec<i64>) -> Result<bool, String> {
    let (Some(name), Some(tracked), Some(reference), Some(force), Some(lock)) = (
        note_str(b, "name")?,
        note_str(b, "tracked")?,
        note_str(b, "reference")?,
        value(b, "force")?,
        value(b, "lock_at")?,
    ) else {
        out.skip(b, "a preload stress on a cross section: alfe's bolt needs its cut's two surfaces, a force and a lock time (`$alfe` notes)");
        return Ok(false);
    };
    b.need(1)?;
    sections.push(b.int(0, 1)?);
    let curve = out.curve(ctx, b.int(0, 2)?, b)?;
    out.named(ctx, &tracked, b)?;
    out.named(ctx, &reference, b)?;
    let mut t = format!(
        "[[bolts]]\nname = {}\ntracked = {}\nreference = {}\nforce = {force}\ncurve = {}\nlock_at = {lock}\n",
        q(&name),
        q(&tracked),
        q(&reference),
        q(&curve)
    );
    for key in ["kappa", "search_distance"] {
        if let Some(v) = value(b, key)? {
            let _ = writeln!(t, "{key} = {v}");
        }
    }
    out.tables.push(t);
    Ok(true)
}

/// A coupling being read: its fields, and per DOF (1–6) the load or motion.
struct Coupling {
    head: String,
    dofs: [Option<(bool, f64, String)>; 6],
}

impl Coupling {
    fn table(&self) -> String {
        let mut t = self.head.clone();
        for (field, motion, base) in [
            ("force", false, 0),
            ("moment", false, 3),
            ("displacement", true, 0),
            ("rotation", true, 3),
        ] {
            let parts: Vec<String> = (0..3)
                .filter_map(|k| match &self.dofs[base + k] {
                    Some((m, v, c)) if *m == motion => Some(format!(
                        "{} = {{ value = {v:e}, curve = {} }}",
                        ["x", "y", "z"][k],
                        q(c)
                    )),
                    _ => None,
                })
                .collect();
            if !parts.is_empty() {
                let _ = writeln!(t, "{field} = {{ {} }}", parts.join(", "));
            }
        }
        t
    }
}

fn coupling(
    out: &mut Out,
    ctx: &Ctx,
    bs: &[Block],
    b: &Block,
) -> Result<Option<(i64, Coupling)>, String> {
    b.need(2)?;
    let (icid, dnid, ityp) = (b.int(0, 0)?, b.int(0, 1)?, b.int(0, 4)?);
    if ityp != 1 {
        out.skip(b, "ITYP ≠ 1: only an independent node set is translated");
        return Ok(None);
    }
    let nodes = match note_str(b, "nodes")? {
        Some(n) => {
            out.named(ctx, &n, b)?;
            n
        }
        None => out.set(ctx, b.int(1, 0)?, b)?,
    };
    let point = node_point(bs, dnid).ok_or_else(|| {
        format!(
            "{}: *{}: dependent node {dnid} is not in a *NODE card",
            b.at(),
            b.kw
        )
    })??;
    let name = note_str(b, "name")?.unwrap_or(format!("coupling-{icid}"));
    let weights = note_str(b, "weights")?.unwrap_or("uniform".into());
    let head = format!(
        "[[couplings]]\nname = {}\nnodes = {}\nweights = {}\npoint = [{:e}, {:e}, {:e}]\n",
        q(&name),
        q(&nodes),
        q(&weights),
        point[0],
        point[1],
        point[2]
    );
    Ok(Some((
        dnid,
        Coupling {
            head,
            dofs: Default::default(),
        },
    )))
}

/// Node `nid`'s coordinates from the `*NODE` cards.
fn node_point(bs: &[Block], nid: i64) -> Option<Result<[f64; 3], String>> {
    for b in bs.iter().filter(|b| b.kw == "NODE") {
        for l in &b.data {
            let widths: &[usize] = if b.long { &[20] } else { &[8, 16] };
            let f = split(&l.text, widths);
            if int(f.first().copied().unwrap_or(""), l, "a node number").ok() == Some(nid) {
                let x = |j: usize| real(f.get(j).copied().unwrap_or(""), l);
                return Some((|| Ok([x(1)?, x(2)?, x(3)?]))());
            }
        }
    }
    None
}

/// Loads and motions of couplings' dependent nodes; false if the block has others.
fn coupling_loads(
    out: &mut Out,
    ctx: &Ctx,
    b: &Block,
    couplings: &mut BTreeMap<i64, Coupling>,
) -> Result<bool, String> {
    let motion = b.kw == "BOUNDARY_PRESCRIBED_MOTION_NODE";
    for k in 0..b.data.len() {
        if !couplings.contains_key(&b.int(k, 0)?) {
            return Ok(false);
        }
    }
    for k in 0..b.data.len() {
        let (nid, dof) = (b.int(k, 0)?, b.int(k, 1)?);
        let (lcid, sf) = if motion {
            if b.int(k, 2)? != 2 {
                out.skip(b, "VAD ≠ 2: only displacements are translated");
                continue;
            }
            (b.int(k, 3)?, b.real(k, 4)?)
        } else {
            (b.int(k, 2)?, b.real(k, 3)?)
        };
        let d = match dof {
            1..=3 => dof as usize - 1,
            5..=7 => dof as usize - 2,
            _ => {
                out.skip(b, &format!("DOF {dof}: only 1–3 and 5–7 are translated"));
                continue;
            }
        };
        let curve = out.curve(ctx, lcid, b)?;
        if let Some(c) = couplings.get_mut(&nid) {
            c.dofs[d] = Some((motion, sf, curve));
        }
    }
    Ok(true)
}

/// `$alfe step = { … }` notes as `[[steps]]` entries.
fn steps(out: &mut Out, b: &Block) -> Result<(), String> {
    for (k, v) in &b.notes {
        if k != "step" {
            continue;
        }
        let t: toml::Table = toml::from_str(&format!("x = {v}"))
            .ok()
            .and_then(|t: toml::Table| t.get("x").and_then(|x| x.as_table()).cloned())
            .ok_or_else(|| {
                format!(
                    "{}: *{}: `$alfe step = {v}` is not a table {{ name, duration, … }}",
                    b.at(),
                    b.kw
                )
            })?;
        let mut s = String::from("[[steps]]\n");
        for (key, val) in &t {
            let _ = writeln!(s, "{key} = {val}");
        }
        out.tables.push(s);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::abaqus::Line;
    use crate::mesh::lsdyna::keyword;

    fn lines(text: &str) -> Vec<Line> {
        let file = std::rc::Rc::new(std::path::PathBuf::from("t.k"));
        text.lines()
            .enumerate()
            .filter(|(_, t)| keyword(t).is_some() || !t.starts_with('$') || t.starts_with("$alfe"))
            .map(|(i, t)| Line {
                file: file.clone(),
                number: i + 1,
                text: t.to_string(),
            })
            .collect()
    }

    /// The card layouts: a frictional contact (long format), a tied one (short), a
    /// coupling with its loads, a bolt and the steps.
    #[test]
    fn cards_read_as_deck_entries() {
        let text = "*NODE
     100             1.5             2.0            -3.0
*CONTACT_SURFACE_TO_SURFACE +
$alfe name = \"joint\"
$alfe method = \"penalty\"
                   1                   2                   0                   0
                 0.3                 0.3
                 2.0
*CONTACT_TIED_NODES_TO_SURFACE
         5         2         4         0
*CONSTRAINED_INTERPOLATION
         1       100    123456         0         1         0
         5       123
*LOAD_NODE_POINT
       100         2         7     250.0
*INITIAL_STRESS_SECTION
$alfe name = \"b\"
$alfe tracked = \"top\"
$alfe reference = \"bottom\"
$alfe force = 1e3
$alfe lock_at = 1.0
         1         1         7
*CONTROL_TERMINATION
       2.0
$alfe step = { name = \"a\", duration = 1.0 }
$alfe step = { name = \"b\", duration = 1.0, step = 0.5 }
";
        let ls = lines(text);
        let bs = super::super::keyword_blocks::blocks(&ls);
        let sets = BTreeMap::from([(5, "tip".to_string())]);
        let segs = BTreeMap::from([(1, "top".to_string()), (2, "bottom".to_string())]);
        let curves = BTreeMap::from([(7, "ramp".to_string())]);
        let ctx = Ctx {
            node_sets: &sets,
            segment_sets: &segs,
            curves: &curves,
        };
        let out = translate(&bs, &ctx).unwrap();
        let all = out.tables.join("\n");
        for want in [
            "name = \"joint\"\ntracked = \"top\"\nreference = \"bottom\"\nfriction = 3e-1\npenalty_scale = 2e0\nmethod = \"penalty\"",
            "tracked = \"tip\"\nreference = \"bottom\"\ntied = true",
            "force = 1e3\ncurve = \"ramp\"\nlock_at = 1.0",
            "nodes = \"tip\"\nweights = \"uniform\"\npoint = [1.5e0, 2e0, -3e0]\nforce = { y = { value = 2.5e2, curve = \"ramp\" } }",
            "[[steps]]\nduration = 1.0\nname = \"b\"\nstep = 0.5",
        ] {
            assert!(all.contains(want), "{want}\nnot in\n{all}");
        }
        assert_eq!(out.handled.len(), 5, "{:?}", out.untranslated);
        assert_eq!(out.curves, vec![7]);
    }
}
