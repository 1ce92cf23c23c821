//! Abaqus/CalculiX input files (`.inp`) as meshes (issue 36): nodes, solid elements, node
//! and element sets, surfaces, `*INCLUDE`. The model keywords (materials, steps, loads)
//! are skipped here; `alfe import` translates them.
//!
//! * `*NODE` (`NSET=`), `*ELEMENT` (`TYPE=`, `ELSET=`; data lines continue after a
//!   trailing comma), `*NSET`/`*ELSET` (`GENERATE`; members are numbers or set names),
//!   `*SURFACE` (`TYPE=ELEMENT`: element or element set with face S1…S6; `TYPE=NODE`:
//!   nodes or node sets), `*INCLUDE, INPUT=` (relative to the including file).
//! * Element types: C3D8 (and its R, I, H, RH variants) → hex8, C3D4(H) → tet4,
//!   C3D10(H, M, MH, T) → tet10, C3D6(H) → wedge6. Node orders are Abaqus', which are
//!   Gmsh's but for the tet10, whose midside nodes 9 and 10 (edges 2–4, 3–4) swap.
//!   Anything else (C3D20, shells, beams, springs, masses) is refused naming the line.
//! * Names are case-insensitive in Abaqus: a set is stored under the name its first
//!   definition gives it and found under any case.
//! * Element sets also become node sets of their nodes, surfaces node sets of theirs,
//!   as Gmsh's physical groups do.
//!
//! Errors name the file, the line and the keyword.

use super::{ElemKind, FaceRef, Mesh};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Reads an included file: its path as the including file names it, resolved.
pub type Loader<'a> = dyn Fn(&Path) -> Result<String, String> + 'a;

/// One line of the input, with where it came from.
pub struct Line {
    pub file: std::rc::Rc<PathBuf>,
    pub number: usize,
    pub text: String,
}

impl Line {
    /// `file:line`, for messages.
    pub fn at(&self) -> String {
        format!("{}:{}", self.file.display(), self.number)
    }
}

/// Every line of `path` and its includes (through `load`), comments and blank lines
/// dropped, in order: what `alfe import` reads the model keywords from.
pub fn read_lines(path: &Path, load: &Loader) -> Result<Vec<Line>, String> {
    let mut out = Vec::new();
    lines(path, load, 0, &mut out)?;
    Ok(out)
}

/// Every line of `path` and its includes, comments and blank lines dropped, in order.
fn lines(path: &Path, load: &Loader, depth: usize, out: &mut Vec<Line>) -> Result<(), String> {
    if depth > 16 {
        return Err(format!(
            "{}: *INCLUDE nested more than 16 deep (a file including itself?)",
            path.display()
        ));
    }
    let text = load(path)?;
    let file = std::rc::Rc::new(path.to_path_buf());
    for (i, raw) in text.lines().enumerate() {
        let t = raw.trim();
        if t.is_empty() || t.starts_with("**") {
            continue;
        }
        let line = Line {
            file: file.clone(),
            number: i + 1,
            text: t.to_string(),
        };
        if keyword(t).as_deref() == Some("INCLUDE") {
            let Some(input) = param(t, "INPUT") else {
                return Err(format!("{}: *INCLUDE without INPUT=", line.at()));
            };
            let input = input.trim_matches('"');
            let inc = path.parent().unwrap_or(Path::new(".")).join(input);
            lines(&inc, load, depth + 1, out)
                .map_err(|e| format!("{} (included at {})", e, line.at()))?;
            continue;
        }
        out.push(line);
    }
    Ok(())
}

/// The keyword of a keyword line (`*Element, type=C3D8` → `ELEMENT`), upper case.
pub fn keyword(t: &str) -> Option<String> {
    let rest = t.strip_prefix('*')?;
    if rest.starts_with('*') {
        return None;
    }
    Some(
        rest.split(',')
            .next()
            .unwrap_or("")
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ")
            .to_ascii_uppercase(),
    )
}

/// A keyword line's parameter `key=value` (key case-insensitive), the value as written.
pub fn param(t: &str, key: &str) -> Option<String> {
    t.split(',').skip(1).find_map(|p| {
        let (k, v) = p.split_once('=')?;
        k.trim()
            .eq_ignore_ascii_case(key)
            .then(|| v.trim().to_string())
    })
}

/// Whether a keyword line has the flag `key` (a parameter without a value).
pub fn flag(t: &str, key: &str) -> bool {
    t.split(',')
        .skip(1)
        .any(|p| !p.contains('=') && p.trim().eq_ignore_ascii_case(key))
}

/// The fields of a data line, trailing empty ones dropped.
pub fn fields(t: &str) -> Vec<&str> {
    let mut f: Vec<&str> = t.split(',').map(str::trim).collect();
    while f.last() == Some(&"") {
        f.pop();
    }
    f
}

/// alfe's kind for an Abaqus solid element type, with how many nodes it lists.
fn element_kind(ty: &str) -> Result<(ElemKind, usize), String> {
    let t = ty.to_ascii_uppercase();
    let kind = match t.as_str() {
        "C3D8" | "C3D8R" | "C3D8I" | "C3D8H" | "C3D8RH" | "C3D8IH" | "C3D8T" => ElemKind::Hex8,
        "C3D4" | "C3D4H" | "C3D4T" => ElemKind::Tet4,
        "C3D10" | "C3D10H" | "C3D10M" | "C3D10MH" | "C3D10T" | "C3D10HS" => ElemKind::Tet10,
        "C3D6" | "C3D6H" | "C3D6T" => ElemKind::Wedge6,
        _ => {
            let what = if t.starts_with("C3D20") || t.starts_with("C3D15") {
                "a quadratic hex or prism, which alfe does not have"
            } else if ["SPRING", "DASHPOT", "MASS", "GAP", "DCOUP", "DASHPOTA"]
                .iter()
                .any(|p| t.starts_with(p))
            {
                "a spring, dashpot, mass or gap element"
            } else if t.starts_with('S') || t.starts_with("M3D") || t.starts_with("SC") {
                "a shell or membrane: read the file as a sheet (kind = \"sheet\", file, thickness)"
            } else if t.starts_with('B') || t.starts_with('T') {
                "a beam or truss"
            } else if t.starts_with("CPS") || t.starts_with("CPE") || t.starts_with("CAX") {
                "a plane or axisymmetric element (alfe is 3D)"
            } else {
                "not a solid element alfe has"
            };
            return Err(format!(
                "element type {ty} is {what}; alfe reads C3D8 (hex8), C3D4 (tet4), C3D10 (tet10) and C3D6 (wedge6) and their R/I/H/M variants"
            ));
        }
    };
    Ok((kind, kind.n_nodes()))
}

/// Abaqus' local node order → alfe's (the tet10's last two midside nodes swap).
fn to_alfe_order(kind: ElemKind, nodes: &mut [usize]) {
    if kind == ElemKind::Tet10 {
        nodes.swap(8, 9);
    }
}

/// alfe's node order → Abaqus' (the same swap, its own inverse).
pub fn to_abaqus_order(kind: ElemKind, nodes: &mut [usize]) {
    to_alfe_order(kind, nodes);
}

/// Abaqus' number (S1…) of an alfe face.
pub fn face_number(mesh: &Mesh, fr: FaceRef) -> Option<usize> {
    let kind = mesh.kinds[fr.elem];
    let en = mesh.elem_nodes(fr.elem);
    let corners: Vec<usize> = kind
        .face_corners(fr.face as usize)
        .iter()
        .map(|&k| en[k])
        .collect();
    abaqus_face_number(kind, en, &corners)
}

/// The Abaqus face number (1-based, S1…) of a face of an element with alfe-ordered
/// nodes `en`, given the face's corner nodes; `None` if they are not a face.
pub fn abaqus_face_number(kind: ElemKind, en: &[usize], corners: &[usize]) -> Option<usize> {
    let mut abq = en.to_vec();
    to_abaqus_order(kind, &mut abq);
    let mut want = corners.to_vec();
    want.sort_unstable();
    abaqus_faces(kind)
        .iter()
        .position(|f| {
            let mut have: Vec<usize> = f.iter().map(|&k| abq[k]).collect();
            have.sort_unstable();
            have == want
        })
        .map(|i| i + 1)
}

/// Abaqus' element faces S1… by their corner nodes (0-based, Abaqus order).
fn abaqus_faces(kind: ElemKind) -> &'static [&'static [usize]] {
    match kind {
        ElemKind::Hex8 => &[
            &[0, 1, 2, 3],
            &[4, 7, 6, 5],
            &[0, 4, 5, 1],
            &[1, 5, 6, 2],
            &[2, 6, 7, 3],
            &[3, 7, 4, 0],
        ],
        ElemKind::Tet4 | ElemKind::Tet10 => &[&[0, 1, 2], &[0, 3, 1], &[1, 3, 2], &[2, 3, 0]],
        ElemKind::Wedge6 => &[
            &[0, 1, 2],
            &[3, 4, 5],
            &[0, 1, 4, 3],
            &[1, 2, 5, 4],
            &[2, 0, 3, 5],
        ],
    }
}

/// The model as read so far: the mesh and the numbers and names the file uses.
#[derive(Default)]
struct Reader {
    mesh: Mesh,
    /// Node number → index.
    nodes: HashMap<i64, usize>,
    /// Element number → index.
    elems: HashMap<i64, usize>,
    /// Element index → its nodes in Abaqus order (for surfaces by face).
    abaqus_conn: Vec<Vec<usize>>,
    /// Upper-case name → stored name, per kind of set.
    nset_names: HashMap<String, String>,
    elset_names: HashMap<String, String>,
    surface_names: HashMap<String, String>,
    /// Each surface's nodes (a node set of its name unless one is defined).
    surface_nodes: std::collections::BTreeMap<String, Vec<usize>>,
}

type R<T> = Result<T, String>;

fn number<T: std::str::FromStr>(s: &str, line: &Line, what: &str) -> R<T> {
    s.parse().map_err(|_| {
        format!(
            "{}: expected {what}, got `{s}` in `{}`",
            line.at(),
            line.text
        )
    })
}

impl Reader {
    fn node_set(&mut self, name: &str) -> &mut Vec<usize> {
        let key = name.to_ascii_uppercase();
        let stored = self
            .nset_names
            .entry(key)
            .or_insert_with(|| name.to_string())
            .clone();
        self.mesh.node_groups.entry(stored).or_default()
    }
    fn elem_set(&mut self, name: &str) -> &mut Vec<usize> {
        let key = name.to_ascii_uppercase();
        let stored = self
            .elset_names
            .entry(key)
            .or_insert_with(|| name.to_string())
            .clone();
        self.mesh.elem_groups.entry(stored).or_default()
    }
    fn find_elset(&self, name: &str) -> Option<&Vec<usize>> {
        let stored = self.elset_names.get(&name.to_ascii_uppercase())?;
        self.mesh.elem_groups.get(stored)
    }
    fn find_nset(&self, name: &str) -> Option<&Vec<usize>> {
        let stored = self.nset_names.get(&name.to_ascii_uppercase())?;
        self.mesh.node_groups.get(stored)
    }

    fn node(&mut self, f: &[&str], line: &Line, nset: Option<&str>) -> R<()> {
        // Fields 5–7 are a shell normal's direction cosines: read past.
        if f.is_empty() || f.len() > 7 {
            return Err(format!(
                "{}: a *NODE line is `number, x, y, z[, normal]`: `{}`",
                line.at(),
                line.text
            ));
        }
        let id: i64 = number(f[0], line, "a node number")?;
        // Missing and empty coordinates are zero, as Abaqus reads them.
        let mut x = [0.0f64; 3];
        for (k, s) in f[1..]
            .iter()
            .take(3)
            .enumerate()
            .filter(|(_, s)| !s.is_empty())
        {
            x[k] = number(s, line, "a coordinate")?;
            if !x[k].is_finite() {
                return Err(format!("{}: coordinate `{s}` is not finite", line.at()));
            }
        }
        let i = self.mesh.coords.len();
        if self.nodes.insert(id, i).is_some() {
            return Err(format!("{}: node {id} is defined twice", line.at()));
        }
        self.mesh.coords.push(x);
        if let Some(s) = nset {
            self.node_set(s).push(i);
        }
        Ok(())
    }

    fn element(
        &mut self,
        ids: &[i64],
        kind: ElemKind,
        line: &Line,
        elset: Option<&str>,
        part: u32,
    ) -> R<()> {
        let id = ids[0];
        let mut conn = Vec::with_capacity(ids.len() - 1);
        for n in &ids[1..] {
            conn.push(*self.nodes.get(n).ok_or_else(|| {
                format!(
                    "{}: element {id} uses node {n}, which no *NODE defines (before it)",
                    line.at()
                )
            })?);
        }
        let abaqus = conn.clone();
        to_alfe_order(kind, &mut conn);
        let e = self.mesh.n_elems();
        if self.elems.insert(id, e).is_some() {
            return Err(format!("{}: element {id} is defined twice", line.at()));
        }
        self.mesh.push_elem(kind, &conn, part);
        if self.mesh.elem_volume(e) <= 0.0 {
            return Err(format!(
                "{}: element {id} ({}) has zero or negative volume; its node order is inverted or it is degenerate",
                line.at(),
                kind.name()
            ));
        }
        self.abaqus_conn.push(abaqus);
        if let Some(s) = elset {
            self.elem_set(s).push(e);
        }
        Ok(())
    }

    /// Members of an `*NSET`/`*ELSET` data line: numbers (or first, last, step with
    /// GENERATE) and names of sets of the same kind.
    fn set_members(&self, f: &[&str], line: &Line, generate: bool, nodes: bool) -> R<Vec<usize>> {
        let (map, what) = if nodes {
            (&self.nodes, "node")
        } else {
            (&self.elems, "element")
        };
        let lookup = |id: i64| -> R<usize> {
            map.get(&id).copied().ok_or_else(|| {
                format!(
                    "{}: {what} {id} is not defined (before this set)",
                    line.at()
                )
            })
        };
        let mut out = Vec::new();
        if generate {
            if !(2..=3).contains(&f.len()) {
                return Err(format!(
                    "{}: a GENERATE line is `first, last[, step]`, got `{}`",
                    line.at(),
                    line.text
                ));
            }
            let a: i64 = number(f[0], line, "a first number")?;
            let b: i64 = number(f[1], line, "a last number")?;
            let s: i64 = if f.len() == 3 {
                number(f[2], line, "a step")?
            } else {
                1
            };
            if s <= 0 || b < a || (b - a) / s > 100_000_000 {
                return Err(format!(
                    "{}: GENERATE {a}, {b}, {s} is not an increasing range",
                    line.at()
                ));
            }
            let mut k = a;
            while k <= b {
                // Numbers in the range that are not defined are skipped, as Abaqus does.
                if let Some(&i) = map.get(&k) {
                    out.push(i);
                }
                k += s;
            }
            return Ok(out);
        }
        for s in f {
            if let Ok(id) = s.parse::<i64>() {
                out.push(lookup(id)?);
            } else {
                let set = if nodes {
                    self.find_nset(s)
                } else {
                    self.find_elset(s)
                };
                let Some(set) = set else {
                    return Err(format!(
                        "{}: `{s}` is neither a {what} number nor a defined {} set",
                        line.at(),
                        if nodes { "node" } else { "element" }
                    ));
                };
                out.extend_from_slice(set);
            }
        }
        Ok(out)
    }

    /// alfe's face of element e that is Abaqus face `s` (1-based).
    fn face(&self, e: usize, s: usize, line: &Line) -> R<FaceRef> {
        let kind = self.mesh.kinds[e];
        let faces = abaqus_faces(kind);
        let Some(local) = s.checked_sub(1).and_then(|i| faces.get(i)) else {
            return Err(format!(
                "{}: a {} has faces S1 to S{}, not S{s}",
                line.at(),
                kind.name(),
                faces.len()
            ));
        };
        let mut want: Vec<usize> = local.iter().map(|&k| self.abaqus_conn[e][k]).collect();
        want.sort_unstable();
        let en = self.mesh.elem_nodes(e);
        for (fi, _) in kind.faces().iter().enumerate() {
            let mut have: Vec<usize> = kind.face_corners(fi).iter().map(|&k| en[k]).collect();
            have.sort_unstable();
            if have == want {
                return Ok(FaceRef {
                    elem: e,
                    face: fi as u8,
                });
            }
        }
        unreachable!("every Abaqus face is a face of the element")
    }

    fn surface_line(&mut self, f: &[&str], line: &Line, name: &str, by_node: bool) -> R<()> {
        let stored = self
            .surface_names
            .entry(name.to_ascii_uppercase())
            .or_insert_with(|| name.to_string())
            .clone();
        if by_node {
            let members = self.set_members(&f[..1.min(f.len())], line, false, true)?;
            self.surface_nodes
                .entry(stored)
                .or_default()
                .extend(members);
            return Ok(());
        }
        if f.len() < 2 {
            return Err(format!(
                "{}: a surface line is `element or element set, S<n>`, got `{}`",
                line.at(),
                line.text
            ));
        }
        let s = f[1].to_ascii_uppercase();
        let Some(k) = s.strip_prefix('S').and_then(|k| k.parse::<usize>().ok()) else {
            return Err(format!(
                "{}: face `{}` is not S1 to S6 (SPOS/SNEG and edge faces are shell faces)",
                line.at(),
                f[1]
            ));
        };
        let elems = self.set_members(&f[..1], line, false, false)?;
        let mut faces = Vec::with_capacity(elems.len());
        for e in elems {
            faces.push(self.face(e, k, line)?);
        }
        let nodes: Vec<usize> = faces
            .iter()
            .flat_map(|fr| self.mesh.face_nodes(*fr))
            .collect();
        self.surface_nodes
            .entry(stored.clone())
            .or_default()
            .extend(nodes);
        self.mesh
            .face_groups
            .entry(stored)
            .or_default()
            .extend(faces);
        Ok(())
    }
}

/// What a block of data lines is read as.
enum Block {
    Node(Option<String>),
    Element {
        kind: ElemKind,
        count: usize,
        elset: Option<String>,
    },
    Nset(String, bool),
    Elset(String, bool),
    Surface(String, bool),
    Skip,
}

fn required(line: &Line, kw: &str, key: &str) -> R<String> {
    param(&line.text, key)
        .filter(|v| !v.is_empty())
        .ok_or_else(|| format!("{}: *{kw} needs {key}=", line.at()))
}

fn block_of(line: &Line, kw: &str) -> R<Block> {
    let t = &line.text;
    Ok(match kw {
        "NODE" => {
            if let Some(sys) = param(t, "SYSTEM").filter(|s| !s.eq_ignore_ascii_case("R")) {
                return Err(format!(
                    "{}: *NODE, SYSTEM={sys}: only rectangular coordinates are read",
                    line.at()
                ));
            }
            Block::Node(param(t, "NSET"))
        }
        "ELEMENT" => {
            let ty = required(line, kw, "TYPE")?;
            let (kind, count) = element_kind(&ty).map_err(|e| format!("{}: {e}", line.at()))?;
            Block::Element {
                kind,
                count,
                elset: param(t, "ELSET"),
            }
        }
        "NSET" => Block::Nset(required(line, kw, "NSET")?, flag(t, "GENERATE")),
        "ELSET" => Block::Elset(required(line, kw, "ELSET")?, flag(t, "GENERATE")),
        "SURFACE" => {
            let by_node = param(t, "TYPE").is_some_and(|v| v.eq_ignore_ascii_case("NODE"));
            if let Some(v) = param(t, "TYPE").filter(|v| {
                !v.eq_ignore_ascii_case("NODE") && !v.eq_ignore_ascii_case("ELEMENT")
            }) {
                return Err(format!(
                    "{}: *SURFACE, TYPE={v}: alfe reads TYPE=ELEMENT and TYPE=NODE surfaces",
                    line.at()
                ));
            }
            Block::Surface(required(line, kw, "NAME")?, by_node)
        }
        "PART" | "INSTANCE" | "ASSEMBLY" => {
            return Err(format!(
                "{}: *{kw}: parts and assemblies are not read; write the input flat (Abaqus/CAE: no parts, or CalculiX's form)",
                line.at()
            ))
        }
        _ => Block::Skip,
    })
}

/// Nodes a shell or membrane element type lists, for sheets: 3 or 4.
fn shell_nodes(ty: &str) -> Option<usize> {
    match ty.to_ascii_uppercase().as_str() {
        "S3" | "S3R" | "STRI3" | "M3D3" => Some(3),
        "S4" | "S4R" | "S4R5" | "M3D4" | "M3D4R" => Some(4),
        _ => None,
    }
}

/// Read `path`'s shells (S3, S4, S4R, M3D3, M3D4 and variants) as a sheet's surface:
/// facets, element sets as facet groups, node sets as point groups. Solid elements or
/// other types are refused naming the line.
pub fn read_surface_inp(path: &Path, load: &Loader) -> Result<super::sheet::Surface, String> {
    let all = read_lines(path, load)?;
    let mut s = super::sheet::Surface::default();
    let mut ids: HashMap<i64, usize> = HashMap::new();
    let mut elems: HashMap<i64, usize> = HashMap::new();
    let mut sets: Vec<(String, Vec<i64>, bool, bool)> = Vec::new();
    let mut block: Option<(String, Option<String>, usize)> = None;
    for line in &all {
        if let Some(kw) = keyword(&line.text) {
            let t = &line.text;
            block = match kw.as_str() {
                "NODE" => Some(("NODE".into(), param(t, "NSET"), 0)),
                "ELEMENT" => {
                    let ty = param(t, "TYPE").unwrap_or_default();
                    let Some(n) = shell_nodes(&ty) else {
                        return Err(format!(
                            "{}: element type {ty}: a sheet is read from shells S3, S4, S4R or membranes M3D3, M3D4 (solids: kind = \"abaqus\")",
                            line.at()
                        ));
                    };
                    Some(("ELEMENT".into(), param(t, "ELSET"), n))
                }
                "NSET" | "ELSET" => {
                    let name = param(t, &kw).unwrap_or_default();
                    sets.push((name, Vec::new(), kw == "NSET", flag(t, "GENERATE")));
                    Some((kw.clone(), None, 0))
                }
                _ => None,
            };
            continue;
        }
        let f = fields(&line.text);
        match &block {
            Some((k, nset, _)) if k == "NODE" => {
                let id = number::<i64>(f[0], line, "a node number")?;
                let mut x = [0.0f64; 3];
                for (c, v) in f
                    .iter()
                    .skip(1)
                    .take(3)
                    .enumerate()
                    .filter(|(_, v)| !v.is_empty())
                {
                    x[c] = number(v, line, "a coordinate")?;
                }
                if ids.insert(id, s.coords.len()).is_some() {
                    return Err(format!("{}: node {id} is defined twice", line.at()));
                }
                if let Some(n) = nset {
                    s.point_groups
                        .entry(n.clone())
                        .or_default()
                        .push(s.coords.len());
                }
                s.coords.push(x);
            }
            Some((k, elset, n)) if k == "ELEMENT" => {
                if f.len() != n + 1 {
                    return Err(format!(
                        "{}: a shell of {n} nodes: `{}`",
                        line.at(),
                        line.text
                    ));
                }
                let id = number::<i64>(f[0], line, "an element number")?;
                let mut facet = Vec::with_capacity(*n);
                for v in &f[1..] {
                    let nid = number::<i64>(v, line, "a node number")?;
                    facet.push(*ids.get(&nid).ok_or_else(|| {
                        format!(
                            "{}: element {id} uses node {nid}, which no *NODE defines (before it)",
                            line.at()
                        )
                    })?);
                }
                let q = s.quads.len();
                elems.insert(id, q);
                if let Some(e) = elset {
                    s.quad_groups.entry(e.clone()).or_default().push(q);
                }
                s.quads.push(facet);
                s.quad_lines.push((line.number, id as u64));
            }
            Some((k, _, _)) if k == "NSET" || k == "ELSET" => {
                let set = sets.last_mut().expect("opened");
                for v in &f {
                    set.1.push(number(
                        v,
                        line,
                        "a number (set names in sets of a sheet are not read)",
                    )?);
                }
            }
            _ => {}
        }
    }
    for (name, members, nodes, generate) in sets {
        let list: Vec<i64> = if generate && members.len() >= 2 {
            let step = members.get(2).copied().unwrap_or(1).max(1);
            (members[0]..=members[1]).step_by(step as usize).collect()
        } else {
            members
        };
        if nodes {
            let v = list
                .iter()
                .filter_map(|n| ids.get(n).copied())
                .collect::<Vec<_>>();
            s.point_groups.entry(name).or_default().extend(v);
        } else {
            let v = list
                .iter()
                .filter_map(|e| elems.get(e).copied())
                .collect::<Vec<_>>();
            s.quad_groups.entry(name).or_default().extend(v);
        }
    }
    if s.quads.is_empty() {
        return Err(format!(
            "{}: the file has no shell elements to extrude",
            path.display()
        ));
    }
    Ok(s)
}

/// Read `path` (and what it includes, through `load`) as the mesh of deck part `part`.
pub fn read_inp(path: &Path, part: u32, load: &Loader) -> Result<Mesh, String> {
    let all = read_lines(path, load)?;
    let mut r = Reader {
        mesh: Mesh {
            offsets: vec![0],
            ..Default::default()
        },
        ..Default::default()
    };
    let mut block = Block::Skip;
    // Element data continued over lines: the numbers so far and the first line.
    let mut pending: Vec<i64> = Vec::new();
    let mut pending_line = 0usize;
    for (li, line) in all.iter().enumerate() {
        if let Some(kw) = keyword(&line.text) {
            if !pending.is_empty() {
                let l = &all[pending_line];
                return Err(format!(
                    "{}: element data line cut short: `{}`",
                    l.at(),
                    l.text
                ));
            }
            block = block_of(line, &kw)?;
            continue;
        }
        let f = fields(&line.text);
        match &block {
            Block::Skip => {}
            Block::Node(nset) => r.node(&f, line, nset.as_deref())?,
            Block::Element { kind, count, elset } => {
                if pending.is_empty() {
                    pending_line = li;
                }
                for s in &f {
                    pending.push(number(s, line, "an element or node number")?);
                }
                if pending.len() > count + 1 {
                    return Err(format!(
                        "{}: a {} lists {count} nodes after its number; this line has {}",
                        all[pending_line].at(),
                        kind.name(),
                        pending.len() - 1
                    ));
                }
                // Until the element has all its nodes, its data continue on the next line.
                if pending.len() == count + 1 {
                    let ids = std::mem::take(&mut pending);
                    r.element(&ids, *kind, &all[pending_line], elset.as_deref(), part)?;
                }
            }
            Block::Nset(name, generate) => {
                let m = r.set_members(&f, line, *generate, true)?;
                r.node_set(name).extend(m);
            }
            Block::Elset(name, generate) => {
                let m = r.set_members(&f, line, *generate, false)?;
                r.elem_set(name).extend(m);
            }
            Block::Surface(name, by_node) => {
                let (name, by_node) = (name.clone(), *by_node);
                r.surface_line(&f, line, &name, by_node)?;
            }
        }
    }
    if !pending.is_empty() {
        let l = &all[pending_line];
        return Err(format!(
            "{}: element data line cut short: `{}`",
            l.at(),
            l.text
        ));
    }
    finish(r, path)
}

/// Element sets and surfaces lend their nodes to node sets of their names where the file
/// defines no node set so named; everything sorted and deduplicated.
fn finish(mut r: Reader, path: &Path) -> Result<Mesh, String> {
    let mut mesh = std::mem::take(&mut r.mesh);
    if mesh.n_elems() == 0 {
        return Err(format!(
            "{}: the file defines no solid elements (*ELEMENT, TYPE=C3D8, C3D4, C3D10 or C3D6)",
            path.display()
        ));
    }
    let mut extra: Vec<(String, Vec<usize>)> = mesh
        .elem_groups
        .iter()
        .map(|(name, es)| {
            let nodes = es
                .iter()
                .flat_map(|&e| mesh.elem_nodes(e).to_vec())
                .collect();
            (name.clone(), nodes)
        })
        .collect();
    extra.extend(std::mem::take(&mut r.surface_nodes));
    for (name, nodes) in extra {
        if r.nset_names.contains_key(&name.to_ascii_uppercase()) {
            continue;
        }
        mesh.node_groups.entry(name).or_default().extend(nodes);
    }
    for v in mesh
        .node_groups
        .values_mut()
        .chain(mesh.elem_groups.values_mut())
    {
        v.sort_unstable();
        v.dedup();
    }
    for v in mesh.face_groups.values_mut() {
        v.sort_unstable();
        v.dedup();
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::TET10_EDGES;

    /// Files by name from a table: `read_inp` through a loader, as `scene/` gives it.
    fn read(files: &[(&str, &str)]) -> Result<Mesh, String> {
        let load = |p: &Path| -> Result<String, String> {
            files
                .iter()
                .find(|(n, _)| Path::new(n) == p)
                .map(|(_, t)| t.to_string())
                .ok_or_else(|| format!("{}: no such file", p.display()))
        };
        read_inp(Path::new(files[0].0), 3, &load)
    }

    /// Two unit hexes along x (nodes 1–12), CalculiX style.
    const TWO_HEXES: &str = "*HEADING
two hexes
** a comment
*NODE, NSET=Nall
1, 0, 0, 0
2, 1, 0, 0
3, 2, 0, 0
4, 0, 1, 0
5, 1, 1, 0
6, 2, 1, 0
7, 0, 0, 1
8, 1, 0, 1
9, 2, 0, 1
10, 0, 1, 1
11, 1, 1, 1
12, 2, 1, 1
*ELEMENT, TYPE=C3D8, ELSET=Eall
1, 1, 2, 5, 4, 7, 8, 11, 10
2, 2, 3, 6, 5,
8, 9, 12, 11
*NSET, NSET=fix, GENERATE
1, 10, 3
*NSET,NSET=Both
fix, 12
*ELSET, ELSET=second
2
*SURFACE, NAME=Top
Eall, S2
*SURFACE, NAME=endnodes, TYPE=NODE
12
*MATERIAL, NAME=steel
*ELASTIC
210000, 0.3
";

    #[test]
    fn reads_nodes_elements_sets_and_surfaces() {
        // Empty and missing coordinates are zero.
        let text = TWO_HEXES.replace("\n1, 0, 0, 0\n", "\n1, ,0\n");
        assert_ne!(text, TWO_HEXES);
        let m = read(&[("model.inp", &text)]).unwrap();
        assert_eq!((m.n_nodes(), m.n_elems()), (12, 2));
        assert_eq!(m.elem_part, vec![3, 3]);
        assert!((0..2).all(|e| (m.elem_volume(e) - 1.0).abs() < 1e-12));
        // GENERATE 1, 10, 3: nodes 1, 4, 7, 10 (indices 0, 3, 6, 9).
        assert_eq!(m.node_groups["fix"], vec![0, 3, 6, 9]);
        assert_eq!(m.node_groups["Both"], vec![0, 3, 6, 9, 11]);
        assert_eq!(m.elem_groups["second"], vec![1]);
        assert_eq!(m.elem_groups["Eall"], vec![0, 1]);
        // S2 of a hex is its top face (nodes 5-8): z = 1 for both.
        let top = &m.face_groups["Top"];
        assert_eq!(top.len(), 2);
        for f in top {
            assert!(m.face_nodes(*f).iter().all(|&n| m.coords[n][2] == 1.0));
        }
        assert_eq!(m.node_groups["Top"].len(), 6);
        assert_eq!(m.node_groups["endnodes"], vec![11]);
        // Element sets lend their nodes to node sets.
        assert_eq!(m.node_groups["second"].len(), 8);
    }

    #[test]
    fn reads_includes_and_names_in_any_case() {
        let main = "*NODE, NSET=N\n*INCLUDE, INPUT=sub/nodes.inp\n*ELEMENT, TYPE=C3D4, ELSET=tets\n1, 1, 2, 3, 4\n*SURFACE, NAME=base\nTETS, S1\n*NSET, NSET=n2\nn\n";
        let nodes = "1, 0, 0, 0\n2, 1, 0, 0\n3, 0, 1, 0\n4, 0, 0, 1\n";
        let m = read(&[("dir/main.inp", main), ("dir/sub/nodes.inp", nodes)]).unwrap();
        assert_eq!(m.n_elems(), 1);
        assert_eq!(m.node_groups["n2"], vec![0, 1, 2, 3]);
        // S1 of a tet: nodes 1-2-3, z = 0.
        let f = m.face_groups["base"][0];
        assert!(m.face_nodes(f).iter().all(|&n| m.coords[n][2] == 0.0));
    }

    /// A C3D10's midside nodes 9 and 10 (on edges 2–4 and 3–4) are alfe's 9 and 8.
    #[test]
    fn tet10_midside_nodes_land_on_their_edges() {
        let c = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        let abaqus_edges = [[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]];
        let mut text = String::from("*NODE\n");
        for (k, x) in c.iter().enumerate() {
            text += &format!("{}, {}, {}, {}\n", k + 1, x[0], x[1], x[2]);
        }
        for (k, [a, b]) in abaqus_edges.iter().enumerate() {
            let x: Vec<f64> = (0..3).map(|i| 0.5 * (c[*a][i] + c[*b][i])).collect();
            text += &format!("{}, {}, {}, {}\n", k + 5, x[0], x[1], x[2]);
        }
        text += "*ELEMENT, TYPE=C3D10\n1, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10\n";
        let m = read(&[("t.inp", &text)]).unwrap();
        let en = m.elem_nodes(0);
        for (k, [a, b]) in TET10_EDGES.iter().enumerate() {
            let mid: Vec<f64> = (0..3).map(|i| 0.5 * (c[*a][i] + c[*b][i])).collect();
            assert_eq!(m.coords[en[4 + k]].to_vec(), mid, "midside node {}", 4 + k);
        }
        assert!((m.elem_volume(0) - 1.0 / 6.0).abs() < 1e-14);
    }

    #[test]
    fn refusals_name_the_file_and_line() {
        let cases = [
            (
                TWO_HEXES.replace("TYPE=C3D8", "TYPE=C3D20R"),
                "model.inp:17: element type C3D20R is a quadratic hex",
            ),
            (
                TWO_HEXES.replace("TYPE=C3D8", "TYPE=S4R"),
                "is a shell or membrane",
            ),
            (
                TWO_HEXES.replace("5, 1, 1, 0", "5, 1, x1, 0"),
                "model.inp:9: expected a coordinate, got `x1`",
            ),
            (
                TWO_HEXES.replace("5, 1, 1, 0", "5, 1, 1, 0, 7, 8, 9, 10"),
                "model.inp:9: a *NODE line is `number, x, y, z[, normal]`",
            ),
            (
                TWO_HEXES.replace("1, 1, 2, 5, 4, 7, 8, 11, 10", "1, 1, 2, 5, 4, 7, 8, 11, 99"),
                "model.inp:18: element 1 uses node 99",
            ),
            (
                TWO_HEXES.replace("8, 9, 12, 11", "*NSET, NSET=x"),
                "model.inp:19: element data line cut short",
            ),
            (
                TWO_HEXES.replace("Eall, S2", "Eall, S9"),
                "model.inp:28: a hex8 has faces S1 to S6, not S9",
            ),
            (
                TWO_HEXES.replace("fix, 12", "nosuchset, 12"),
                "`nosuchset` is neither a node number nor a defined node set",
            ),
            (
                TWO_HEXES.replace("*MATERIAL", "*PART, NAME=p\n*MATERIAL"),
                "parts and assemblies are not read",
            ),
            (
                TWO_HEXES.replace("1, 1, 2, 5, 4, 7, 8, 11, 10", "1, 1, 4, 5, 2, 7, 10, 11, 8"),
                "element 1 (hex8) has zero or negative volume",
            ),
            (
                TWO_HEXES.replace("*NSET,NSET=Both", "*NSET"),
                "*NSET needs NSET=",
            ),
            (
                format!("{TWO_HEXES}*INCLUDE, INPUT=missing.inp\n"),
                "missing.inp: no such file (included at model.inp:",
            ),
        ];
        for (text, want) in cases {
            let e = read(&[("model.inp", &text)]).expect_err(want);
            assert!(e.contains(want), "want `{want}`, got: {e}");
        }
        let e = read(&[("a.inp", "*INCLUDE, INPUT=a.inp\n")]).unwrap_err();
        assert!(e.contains("nested more than 16 deep"), "{e}");
    }
}
