//! LS-DYNA's contact entities as alfe `[[entities]]`: a `*CONTACT_ENTITY` (the
//! analytical shape and its tracked node set) on a rigid part (`*PART_INERTIA` with a
//! `*MAT_RIGID`), its DOFs prescribed by `*BOUNDARY_PRESCRIBED_MOTION_RIGID`, loaded by
//! `*LOAD_RIGID_BODY`, fixed by `*MAT_RIGID`'s CON1/CON2, free otherwise. Geometry as
//! [`crate::app::export::lsdyna_entities`] writes it: (XC, YC, ZC) the shape's centre, A
//! its axis, B its x axis. The tables carry `@NODES` and `@CURVE{lcid}@` for the caller
//! to fill with the names of the file's sets and curves.

use super::abaqus::toml_str;
use super::keyword_blocks::Block;
use std::collections::BTreeMap;
use std::fmt::Write;

/// The rigid part of an entity (`*PART_INERTIA`).
struct Body {
    mid: i64,
    mass: f64,
    inertia: f64,
    velocity: [f64; 3],
    spin: [f64; 3],
    centre: [f64; 3],
}

/// What drives one DOF of a rigid part.
enum Drive {
    /// VAD (0 velocity, 2 displacement), curve, scale.
    Prescribed(i64, i64, f64),
    /// Load curve and scale.
    Load(i64, f64),
}

/// One `*CONTACT_ENTITY`: its rigid part, tracked node set, table text so far and line.
struct Contact {
    pid: i64,
    nsid: i64,
    text: String,
    at: String,
    centre: [f64; 3],
}

/// A translated entity: its `[[entities]]` table, the node set and curves it names.
pub struct Table {
    pub text: String,
    pub nsid: i64,
    pub lcids: Vec<i64>,
    pub at: String,
}

/// The entity keywords of a file, gathered over both passes.
#[derive(Default)]
pub struct Entities {
    bodies: BTreeMap<i64, Body>,
    /// mid → fixed [ux, uy, uz, rx, ry, rz].
    rigid: BTreeMap<i64, [bool; 6]>,
    contacts: Vec<Contact>,
    drives: BTreeMap<i64, BTreeMap<usize, Drive>>,
    untranslated: Vec<String>,
}

/// ux … rz of LS-DYNA's DOF code (1–3, 5–7).
fn dof_index(code: i64) -> Option<usize> {
    match code {
        1..=3 => Some(code as usize - 1),
        5..=7 => Some(code as usize - 2),
        _ => None,
    }
}

/// The fixed (x, y, z) of a `*MAT_RIGID` constraint code.
fn fixed_of(code: i64) -> Option<[bool; 3]> {
    Some(match code {
        0 => [false, false, false],
        1 => [true, false, false],
        2 => [false, true, false],
        3 => [false, false, true],
        4 => [true, true, false],
        5 => [false, true, true],
        6 => [true, false, true],
        7 => [true, true, true],
        _ => return None,
    })
}

fn v3(a: [f64; 3]) -> String {
    format!("[{:e}, {:e}, {:e}]", a[0], a[1], a[2])
}

impl Entities {
    fn skip(&mut self, b: &Block, why: &str) {
        self.untranslated
            .push(format!("{}: *{}: {why}", b.at(), b.kw));
    }

    /// Definitions: `*PART_INERTIA`, `*MAT_RIGID`; false for another keyword.
    pub fn define(&mut self, b: &Block) -> Result<bool, String> {
        match b.kw.trim_end_matches("_TITLE") {
            "PART_INERTIA" => {
                b.need(5)?;
                let centre = [b.real(2, 0)?, b.real(2, 1)?, b.real(2, 2)?];
                let (ixx, iyy, izz) = (b.real(3, 0)?, b.real(3, 3)?, b.real(3, 5)?);
                if (ixx - iyy).abs() > 1e-12 * ixx.abs() || (ixx - izz).abs() > 1e-12 * ixx.abs() {
                    self.skip(b, "an anisotropic inertia tensor: alfe's bodies take one moment of inertia, IXX");
                }
                let body = Body {
                    mid: b.int(1, 2)?,
                    mass: b.real(2, 3)?,
                    inertia: ixx,
                    velocity: [b.real(4, 0)?, b.real(4, 1)?, b.real(4, 2)?],
                    spin: [b.real(4, 3)?, b.real(4, 4)?, b.real(4, 5)?],
                    centre,
                };
                self.bodies.insert(b.int(1, 0)?, body);
            }
            "MAT_RIGID" => {
                let c = usize::from(b.kw.ends_with("_TITLE"));
                b.need(c + 2)?;
                let cmo = b.real(c + 1, 0)?;
                let codes = [b.real(c + 1, 1)? as i64, b.real(c + 1, 2)? as i64];
                let mut fixed = [false; 6];
                if cmo == 1.0 {
                    for (k, code) in codes.into_iter().enumerate() {
                        let Some(f) = fixed_of(code) else {
                            self.skip(b, &format!("CON{} = {code}: expected 0–7", k + 1));
                            continue;
                        };
                        fixed[3 * k..3 * k + 3].copy_from_slice(&f);
                    }
                } else if cmo != 0.0 {
                    self.skip(b, "CMO = −1 (constraints in a local system) is not translated: the DOFs are left free");
                }
                self.rigid.insert(b.int(c, 0)?, fixed);
            }
            _ => return Ok(false),
        }
        Ok(true)
    }

    /// `*CONTACT_ENTITY`, `*BOUNDARY_PRESCRIBED_MOTION_RIGID`, `*LOAD_RIGID_BODY`;
    /// false for another keyword.
    pub fn keyword(&mut self, b: &Block) -> Result<bool, String> {
        match b.kw.as_str() {
            "CONTACT_ENTITY" => self.contact(b)?,
            "BOUNDARY_PRESCRIBED_MOTION_RIGID" | "LOAD_RIGID_BODY" => {
                let load = b.kw.starts_with("LOAD");
                for k in 0..b.data.len() {
                    let (pid, code) = (b.int(k, 0)?, b.int(k, 1)?);
                    let Some(d) = dof_index(code) else {
                        self.skip(
                            b,
                            &format!("DOF {code}: only 1–3 and 5–7 (global axes) are translated"),
                        );
                        continue;
                    };
                    let drive = if load {
                        Drive::Load(b.int(k, 2)?, b.real(k, 3)?)
                    } else {
                        let vad = b.int(k, 2)?;
                        if vad != 0 && vad != 2 {
                            self.skip(b, &format!("VAD {vad}: only velocities (0) and displacements (2) are translated"));
                            continue;
                        }
                        Drive::Prescribed(vad, b.int(k, 3)?, b.real(k, 4)?)
                    };
                    self.drives.entry(pid).or_default().insert(d, drive);
                }
            }
            _ => return Ok(false),
        }
        Ok(true)
    }

    fn contact(&mut self, b: &Block) -> Result<(), String> {
        b.need(5)?;
        let (pid, geotyp, nsid, sstyp) = (b.int(0, 0)?, b.int(0, 1)?, b.int(0, 2)?, b.int(0, 3)?);
        if sstyp != 2 {
            self.skip(
                b,
                &format!("SSTYP {sstyp}: only a node set (2) of tracked nodes is translated"),
            );
            return Ok(());
        }
        if b.int(4, 0)? != 0 {
            self.skip(b, "INOUT ≠ 0 (nodes inside the shape) is not translated");
            return Ok(());
        }
        let g = [b.real(4, 1)?, b.real(4, 2)?, b.real(4, 3)?];
        let shape = match geotyp {
            1 => "shape = \"plane\"\n".to_string(),
            2 => format!("shape = \"sphere\"\nradius = {:e}\n", g[0]),
            3 => format!(
                "shape = \"cylinder\"\nradius = {:e}\nlength = {:e}\n",
                g[0], g[1]
            ),
            4 => format!("shape = \"ellipsoid\"\nradii = {}\n", v3(g)),
            5 => format!("shape = \"torus\"\nradii = [{:e}, {:e}]\n", g[0], g[1]),
            9 => format!(
                "shape = \"finite-plane\"\nsize = [{:e}, {:e}]\n",
                g[0], g[1]
            ),
            _ => {
                self.skip(b, &format!("GEOTYP {geotyp} has no alfe shape"));
                return Ok(());
            }
        };
        let name = b
            .note("name")
            .map(|s| s.trim_matches('"').to_string())
            .unwrap_or(format!("entity-{}", b.line.number));
        let centre = [b.real(2, 0)?, b.real(2, 1)?, b.real(2, 2)?];
        let mut text = format!("[[entities]]\nname = {}\n{shape}", toml_str(&name));
        let _ = writeln!(text, "point = {}", v3(centre));
        let _ = writeln!(
            text,
            "normal = {}",
            v3([b.real(2, 3)?, b.real(2, 4)?, b.real(2, 5)?])
        );
        let _ = writeln!(
            text,
            "x_axis = {}",
            v3([b.real(3, 0)?, b.real(3, 1)?, b.real(3, 2)?])
        );
        text.push_str("nodes = @NODES\n");
        let fric = b.real(0, 6)?;
        if fric != 0.0 {
            let _ = writeln!(text, "friction = {fric:e}");
        }
        for key in [
            "method",
            "penalty_scale",
            "kappa",
            "tangential_augmentation",
            "friction_threshold",
            "stick_lock_flips",
        ] {
            if let Some(v) = b.note(key) {
                let _ = writeln!(text, "{key} = {v}");
            }
        }
        let traces: Vec<&str> = b
            .notes
            .iter()
            .filter(|(k, _)| k == "trace")
            .map(|(_, v)| v.as_str())
            .collect();
        if !traces.is_empty() {
            let _ = writeln!(text, "trace = [{}]", traces.join(", "));
        }
        self.contacts.push(Contact {
            pid,
            nsid,
            text,
            at: b.at(),
            centre,
        });
        Ok(())
    }

    /// The `[[entities]]` tables, and what was not translated.
    pub fn tables(self) -> (Vec<Table>, Vec<String>) {
        let mut untranslated = self.untranslated;
        let mut out = Vec::new();
        for c in self.contacts {
            let Some(body) = self.bodies.get(&c.pid) else {
                untranslated.push(format!("{}: *CONTACT_ENTITY: part {} is not a *PART_INERTIA rigid body (an element-meshed rigid part is not translated)", c.at, c.pid));
                continue;
            };
            let fixed = self.rigid.get(&body.mid).copied().unwrap_or_default();
            if body.centre != c.centre {
                untranslated.push(format!("{}: *CONTACT_ENTITY: the body turns about the entity's centre, not part {}'s centre of mass", c.at, c.pid));
            }
            let mut text = c.text;
            for (key, v) in [("mass", body.mass), ("inertia", body.inertia)] {
                if v > 0.0 {
                    let _ = writeln!(text, "{key} = {v:e}");
                }
            }
            for (key, v) in [("velocity", body.velocity), ("spin", body.spin)] {
                if v != [0.0; 3] {
                    let _ = writeln!(text, "{key} = {}", v3(v));
                }
            }
            let none = BTreeMap::new();
            let drives = self.drives.get(&c.pid).unwrap_or(&none);
            let (dofs, lcids) = motion(drives, fixed);
            if !dofs.is_empty() {
                let _ = writeln!(text, "motion = {{ {} }}", dofs.join(", "));
            }
            out.push(Table {
                text,
                nsid: c.nsid,
                lcids,
                at: c.at,
            });
        }
        (out, untranslated)
    }
}

/// The motion's per-DOF entries and the curves they name.
fn motion(drives: &BTreeMap<usize, Drive>, fixed: [bool; 6]) -> (Vec<String>, Vec<i64>) {
    const NAMES: [&str; 6] = ["ux", "uy", "uz", "rx", "ry", "rz"];
    let (mut dofs, mut lcids) = (Vec::new(), Vec::new());
    for (k, name) in NAMES.iter().enumerate() {
        let entry = match drives.get(&k) {
            Some(Drive::Prescribed(vad, lcid, sf)) => {
                lcids.push(*lcid);
                let kind = if *vad == 0 {
                    ", type = \"velocity\""
                } else {
                    ""
                };
                format!("{name} = {{ curve = @CURVE{lcid}@, scale = {sf:e}{kind} }}")
            }
            Some(Drive::Load(lcid, sf)) => {
                lcids.push(*lcid);
                format!("{name} = {{ type = \"force\", curve = @CURVE{lcid}@, scale = {sf:e} }}")
            }
            None if fixed[k] => continue,
            None => format!("{name} = {{ type = \"free\" }}"),
        };
        dofs.push(entry);
    }
    (dofs, lcids)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::app::export::lsdyna_entities::{constraint_code, DOF_CODES};

    #[test]
    fn codes_read_back() {
        for m in 0..8u8 {
            let f = [m & 1 != 0, m & 2 != 0, m & 4 != 0];
            assert_eq!(fixed_of(constraint_code(f)), Some(f));
        }
        for (k, c) in DOF_CODES.iter().enumerate() {
            assert_eq!(dof_index(*c), Some(k));
        }
        assert_eq!(dof_index(4), None);
    }

    #[test]
    fn free_fixed_prescribed_and_loaded() {
        let mut d = BTreeMap::new();
        d.insert(2, Drive::Prescribed(2, 7, -40.0));
        d.insert(4, Drive::Load(3, 2.5));
        let fixed = [true, false, false, false, false, true];
        let (dofs, lcids) = motion(&d, fixed);
        assert_eq!(
            dofs,
            [
                "uy = { type = \"free\" }",
                "uz = { curve = @CURVE7@, scale = -4e1 }",
                "rx = { type = \"free\" }",
                "ry = { type = \"force\", curve = @CURVE3@, scale = 2.5e0 }",
            ]
        );
        assert_eq!(lcids, [7, 3]);
    }
}
