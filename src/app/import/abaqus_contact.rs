//! Contact and coupling keywords of a foreign `.inp` (one without `** alfe` notes), as
//! `[[pairs]]` and `[[couplings]]`: `*TIE` (tied pairs), `*CONTACT PAIR` with `SMALL
//! SLIDING` (frictional pairs, μ from the interaction's `*FRICTION`), `*COUPLING` with
//! `*DISTRIBUTING` (a coupling on the surface, its point the reference node's
//! coordinates, `*CLOAD` and `*BOUNDARY` on the reference node its force, moment,
//! displacement and rotation). The keywords are gathered as they come and resolved at the
//! end, so an interaction may follow the pair that names it. What has no alfe meaning
//! (finite sliding, penalty stiffness, kinematic couplings, pretension sections) is
//! listed with its line. The reference node, in no element, is dropped from the part's
//! mesh when it is read (nodes no element uses carry no stiffness).

use crate::mesh::abaqus::{fields, flag, keyword, param, Line};
use std::collections::BTreeMap;
use std::fmt::Write;

/// Output requests of the `.inp` importer (listed once: alfe writes every field).
pub(super) const OUTPUT_KEYWORDS: &[&str] = &[
    "NODE PRINT",
    "EL PRINT",
    "NODE FILE",
    "EL FILE",
    "OUTPUT",
    "NODE OUTPUT",
    "ELEMENT OUTPUT",
    "CONTACT PRINT",
    "CONTACT FILE",
    "CONTACT OUTPUT",
    "SECTION PRINT",
    "ENERGY PRINT",
];

/// The keywords this module reads.
pub(super) const KEYWORDS: &[&str] = &[
    "TIE",
    "CONTACT PAIR",
    "SURFACE INTERACTION",
    "FRICTION",
    "SURFACE BEHAVIOR",
    "COUPLING",
    "DISTRIBUTING",
    "KINEMATIC",
    "PRE-TENSION SECTION",
];

#[derive(Debug, Default, Clone, Copy, PartialEq)]
enum Data {
    Tie,
    Pair,
    Friction,
    Distributing,
    /// Each data line listed with this reason.
    List(&'static str),
    #[default]
    Quiet,
}

#[derive(Debug)]
struct Pair {
    at: String,
    name: String,
    tied: bool,
    interaction: Option<String>,
    search: Option<f64>,
    sides: Option<(String, String)>,
}

#[derive(Debug)]
struct Coupling {
    at: String,
    name: String,
    reference: String,
    surface: String,
    distributing: bool,
    uniform: bool,
}

/// Loads and motions on a reference node: force, moment, displacement, rotation.
type Motion = [[Option<f64>; 3]; 4];

#[derive(Debug, Default)]
pub(super) struct Contact {
    data: Data,
    pairs: Vec<Pair>,
    /// Interaction name (upper case) → μ.
    friction: BTreeMap<String, f64>,
    interaction: Option<String>,
    couplings: Vec<Coupling>,
    /// Reference node key → its coordinates, where the file gives them.
    points: BTreeMap<String, [f64; 3]>,
    motions: BTreeMap<String, Motion>,
}

/// A node number or set name as a key: the number as written, a name in upper case.
fn key(s: &str) -> String {
    match s.trim().parse::<u64>() {
        Ok(n) => n.to_string(),
        Err(_) => s.trim().to_ascii_uppercase(),
    }
}

fn number(s: &str, line: &Line) -> Result<f64, String> {
    s.parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| format!("{}: expected a number, got `{s}`", line.at()))
}

fn note(notes: &mut Vec<String>, line: &Line, why: &str) {
    notes.push(format!("{}: `{}`: {why}", line.at(), line.text));
}

impl Contact {
    /// Read ahead for the couplings' reference nodes and their coordinates (from `*NODE`,
    /// or the one node of a `*NSET` so named), so that loads on them are known as they come.
    pub(super) fn new(lines: &[Line]) -> Contact {
        let mut refs: BTreeMap<String, String> = BTreeMap::new();
        for l in lines {
            if keyword(&l.text).as_deref() == Some("COUPLING") {
                if let Some(r) = param(&l.text, "REF NODE") {
                    refs.insert(key(&r), key(&r));
                }
            }
        }
        let mut coords: BTreeMap<String, [f64; 3]> = BTreeMap::new();
        let mut kw = String::new();
        let mut nset = String::new();
        for l in lines {
            if let Some(k) = keyword(&l.text) {
                nset = param(&l.text, "NSET").map_or(String::new(), |s| key(&s));
                kw = k;
                continue;
            }
            let f = fields(&l.text);
            if kw == "NODE" {
                let x = |k: usize| f.get(k).and_then(|s| s.parse::<f64>().ok()).unwrap_or(0.0);
                coords.insert(key(f.first().unwrap_or(&"")), [x(1), x(2), x(3)]);
            } else if kw == "NSET" && refs.contains_key(&nset) && f.len() == 1 {
                refs.insert(nset.clone(), key(f[0]));
            }
        }
        let points = refs
            .iter()
            .filter_map(|(r, n)| coords.get(n).map(|x| (r.clone(), *x)))
            .collect();
        let motions = refs
            .keys()
            .map(|r| (r.clone(), Motion::default()))
            .collect();
        Contact {
            points,
            motions,
            ..Default::default()
        }
    }

    /// Open keyword `kw` (one of [`KEYWORDS`]) on `line`.
    pub(super) fn open(&mut self, line: &Line, kw: &str, notes: &mut Vec<String>) {
        let t = &line.text;
        self.data = match kw {
            "TIE" => {
                if param(t, "ADJUST").is_some_and(|v| !v.eq_ignore_ascii_case("NO")) {
                    note(notes, line, "ADJUST: alfe ties the nodes where they are");
                }
                self.pairs.push(Pair {
                    at: line.at(),
                    name: param(t, "NAME").unwrap_or(format!("tie-{}", self.pairs.len() + 1)),
                    tied: true,
                    interaction: None,
                    search: param(t, "POSITION TOLERANCE").and_then(|s| s.parse().ok()),
                    sides: None,
                });
                Data::Tie
            }
            "CONTACT PAIR" => {
                if !flag(t, "SMALL SLIDING") {
                    note(notes, line, "finite sliding between deformable bodies has no alfe equivalent (alfe's pairs are small sliding)");
                    return self.data = Data::List("data of a finite-sliding contact pair");
                }
                if param(t, "TYPE").is_some_and(|v| v.eq_ignore_ascii_case("NODE TO SURFACE")) {
                    note(notes, line, "TYPE=NODE TO SURFACE: alfe's pair weights a tracked surface by mortar integrals");
                }
                if param(t, "ADJUST").is_some() {
                    note(notes, line, "ADJUST: alfe pairs the nodes where they are");
                }
                self.pairs.push(Pair {
                    at: line.at(),
                    name: format!("contact-{}", self.pairs.len() + 1),
                    tied: false,
                    interaction: param(t, "INTERACTION").map(|s| s.to_ascii_uppercase()),
                    search: None,
                    sides: None,
                });
                Data::Pair
            }
            "SURFACE INTERACTION" => {
                self.interaction = param(t, "NAME").map(|s| s.to_ascii_uppercase());
                Data::List("surface interaction data (thickness) not translated")
            }
            "FRICTION" => {
                if self.interaction.is_none() {
                    note(notes, line, "*FRICTION outside a *SURFACE INTERACTION");
                    return self.data = Data::Quiet;
                }
                if t.split(',').count() > 1 {
                    note(
                        notes,
                        line,
                        "options of *FRICTION: alfe's friction is Coulomb's, stick by ALM",
                    );
                }
                Data::Friction
            }
            "SURFACE BEHAVIOR" => {
                if param(t, "PRESSURE-OVERCLOSURE").is_some_and(|v| !v.eq_ignore_ascii_case("HARD"))
                {
                    note(
                        notes,
                        line,
                        "penalty stiffness not translated: alfe enforces zero penetration by ALM",
                    );
                    return self.data = Data::List(
                        "penalty stiffness not translated: alfe enforces zero penetration by ALM",
                    );
                }
                Data::Quiet
            }
            "COUPLING" => {
                let (Some(reference), Some(surface)) = (param(t, "REF NODE"), param(t, "SURFACE"))
                else {
                    note(notes, line, "a coupling needs REF NODE= and SURFACE=");
                    return self.data = Data::Quiet;
                };
                self.couplings.push(Coupling {
                    at: line.at(),
                    name: param(t, "CONSTRAINT NAME")
                        .unwrap_or(format!("coupling-{}", self.couplings.len() + 1)),
                    reference: key(&reference),
                    surface,
                    distributing: false,
                    uniform: false,
                });
                Data::Quiet
            }
            "DISTRIBUTING" => match self.couplings.last_mut() {
                Some(c) => {
                    c.distributing = true;
                    c.uniform =
                        param(t, "WEIGHTING").is_some_and(|v| v.eq_ignore_ascii_case("UNIFORM"));
                    Data::Distributing
                }
                None => {
                    note(notes, line, "*DISTRIBUTING without a *COUPLING");
                    Data::Quiet
                }
            },
            "KINEMATIC" => {
                note(
                    notes,
                    line,
                    "kinematic coupling not translated: alfe's couplings are distributing",
                );
                Data::List("data of a kinematic coupling")
            }
            _ => {
                note(notes, line, "pretension section not translated: alfe's bolt is a cut between two surfaces tied across, Abaqus' section a surface and a node");
                Data::List("data of a pretension section")
            }
        };
    }

    /// A data line of the open keyword.
    pub(super) fn data(&mut self, line: &Line, notes: &mut Vec<String>) -> Result<(), String> {
        let f = fields(&line.text);
        match self.data {
            Data::Tie | Data::Pair => {
                let p = self.pairs.last_mut().expect("opened");
                if f.len() != 2 || p.sides.is_some() {
                    note(
                        notes,
                        line,
                        "a pair's data is one line `slave, master`: ignored",
                    );
                } else {
                    p.sides = Some((f[0].to_string(), f[1].to_string()));
                }
            }
            Data::Friction => {
                let mu = number(f.first().unwrap_or(&""), line)?;
                let i = self.interaction.clone().expect("opened");
                if self.friction.insert(i, mu).is_some() || f.len() > 1 {
                    note(
                        notes,
                        line,
                        "only the first line's first value (μ) is translated",
                    );
                }
            }
            Data::Distributing => {
                let dof = |k: usize| f.get(k).and_then(|s| s.parse::<usize>().ok());
                if dof(0) != Some(1) || dof(1).is_some_and(|d| d < 3) || f.len() > 2 {
                    note(notes, line, "alfe's coupling carries all the reference node's degrees of freedom, weighted as the WEIGHTING says");
                }
            }
            Data::List(why) => note(notes, line, why),
            Data::Quiet => {}
        }
        Ok(())
    }

    /// Whether a `*CLOAD` (`boundary` false) or `*BOUNDARY` line acts on a coupling's
    /// reference node: then it is the coupling's, read here.
    pub(super) fn reference_line(
        &mut self,
        f: &[&str],
        line: &Line,
        boundary: bool,
    ) -> Result<bool, String> {
        let Some(m) = f.first().and_then(|t| self.motions.get_mut(&key(t))) else {
            return Ok(false);
        };
        let dof = |k: usize| -> Result<Option<usize>, String> {
            f.get(k)
                .filter(|s| !s.is_empty())
                .map(|s| number(s, line).map(|v| v as usize))
                .transpose()
        };
        let err = || format!("{}: degrees of freedom of `{}`", line.at(), line.text);
        let first = dof(1)?.filter(|d| (1..=6).contains(d)).ok_or_else(err)?;
        let (last, value) = if boundary {
            let v = f
                .get(3)
                .map(|s| number(s, line))
                .transpose()?
                .unwrap_or(0.0);
            (dof(2)?.unwrap_or(first), v)
        } else {
            (first, number(f.get(2).unwrap_or(&""), line)?)
        };
        if last < first || last > 6 {
            return Err(err());
        }
        for d in first..=last {
            let slot = &mut m[usize::from(boundary) * 2 + (d - 1) / 3][(d - 1) % 3];
            *slot = Some(slot.unwrap_or(0.0) * f64::from(!boundary) + value);
        }
        Ok(true)
    }

    /// The `[[pairs]]` and `[[couplings]]` TOML; the surfaces and node sets they name
    /// join the deck's (`faces`, `nodes`: the mesh's face and node groups).
    pub(super) fn resolve(
        &self,
        faces: &[String],
        nodes: &[String],
        surfaces: &mut BTreeMap<String, String>,
        node_sets: &mut BTreeMap<String, String>,
        notes: &mut Vec<String>,
    ) -> String {
        let find = |g: &[String], s: &str| g.iter().find(|k| k.eq_ignore_ascii_case(s)).cloned();
        let mut out = String::new();
        for p in &self.pairs {
            let Some((slave, master)) = &p.sides else {
                notes.push(format!("{}: a pair without its `slave, master` line", p.at));
                continue;
            };
            let Some(reference) = find(faces, master) else {
                notes.push(format!(
                    "{}: `{master}` is not a surface of the mesh: pair not translated",
                    p.at
                ));
                continue;
            };
            let tracked = if let Some(s) = find(faces, slave) {
                surfaces.insert(s.clone(), s.clone());
                s
            } else if let Some(s) = find(nodes, slave) {
                node_sets.insert(s.clone(), s.clone());
                s
            } else {
                notes.push(format!("{}: `{slave}` is neither a surface nor a node set of the mesh: pair not translated", p.at));
                continue;
            };
            surfaces.insert(reference.clone(), reference.clone());
            let _ = write!(
                out,
                "\n[[pairs]]\nname = {:?}\ntracked = {tracked:?}\nreference = {reference:?}\n",
                p.name
            );
            if p.tied {
                out += "tied = true\n";
            } else {
                let mu = p.interaction.as_ref().and_then(|i| self.friction.get(i));
                if p.interaction.is_some() && mu.is_none() {
                    notes.push(format!(
                        "{}: interaction with no *FRICTION: frictionless",
                        p.at
                    ));
                }
                let _ = writeln!(out, "friction = {}", mu.copied().unwrap_or(0.0));
            }
            if let Some(d) = p.search {
                let _ = writeln!(out, "search_distance = {d:e}");
            }
        }
        for c in &self.couplings {
            self.coupling(c, faces, nodes, surfaces, node_sets, notes, &mut out);
        }
        out
    }

    #[allow(clippy::too_many_arguments)]
    fn coupling(
        &self,
        c: &Coupling,
        faces: &[String],
        nodes: &[String],
        surfaces: &mut BTreeMap<String, String>,
        node_sets: &mut BTreeMap<String, String>,
        notes: &mut Vec<String>,
        out: &mut String,
    ) {
        let find = |g: &[String]| {
            g.iter()
                .find(|k| k.eq_ignore_ascii_case(&c.surface))
                .cloned()
        };
        if !c.distributing {
            notes.push(format!("{}: a coupling without *DISTRIBUTING not translated (alfe's couplings are distributing)", c.at));
            return;
        }
        let set = if let Some(s) = find(faces) {
            surfaces.insert(s.clone(), s.clone());
            s
        } else if let Some(s) = find(nodes) {
            node_sets.insert(s.clone(), s.clone());
            s
        } else {
            notes.push(format!(
                "{}: `{}` is not a surface of the mesh: coupling not translated",
                c.at, c.surface
            ));
            return;
        };
        let _ = write!(
            out,
            "\n[[couplings]]\nname = {:?}\nnodes = {set:?}\n",
            c.name
        );
        if c.uniform {
            out.push_str("weights = \"uniform\"\n");
        }
        match self.points.get(&c.reference) {
            Some(x) => {
                let _ = writeln!(out, "point = [{:e}, {:e}, {:e}]", x[0], x[1], x[2]);
            }
            None => notes.push(format!("{}: reference node `{}` has no coordinates in the file: the coupling's point is the surface's weighted centroid", c.at, c.reference)),
        }
        let m = self.motions.get(&c.reference).copied().unwrap_or_default();
        for (k, what) in ["force", "moment", "displacement", "rotation"]
            .iter()
            .enumerate()
        {
            let comps: Vec<String> = (0..3)
                .filter_map(|i| {
                    m[k][i].map(|v| format!("{} = {{ value = {v:e} }}", ["x", "y", "z"][i]))
                })
                .collect();
            if !comps.is_empty() {
                let _ = writeln!(out, "{what} = {{ {} }}", comps.join(", "));
            }
        }
    }
}
