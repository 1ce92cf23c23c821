//! Reader for ASCII Gmsh MSH 4.1 and 2.2 files.
//!
//! Volume elements (hex8, tet4) become the mesh; lower-dimensional elements only define
//! groups: every physical group gives a node group, physical surfaces also give face
//! groups (matched to volume-element faces by node set), physical volumes element groups.
//! A surface mesh of quads is read instead as a [`Surface`] that `mesh::sheet` extrudes.

use std::collections::{BTreeMap, HashMap};

use super::sheet::Surface;
use super::{ElemKind, FaceRef, Mesh};

/// Whitespace-separated tokens with line numbers; a double-quoted string is one token.
/// Lazy, so a binary file is refused at its header before its bytes are looked at.
struct Lexer<'a> {
    s: &'a str,
    pos: usize,
    line: usize,
    /// The section being read, for end-of-file messages.
    section: &'a str,
}

impl<'a> Lexer<'a> {
    fn next(&mut self) -> Option<(&'a str, usize)> {
        let b = self.s.as_bytes();
        while self.pos < b.len() && b[self.pos].is_ascii_whitespace() {
            if b[self.pos] == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
        if self.pos >= b.len() {
            return None;
        }
        let start = self.pos;
        let line = self.line;
        if b[start] == b'"' {
            self.pos += 1;
            while self.pos < b.len() && b[self.pos] != b'"' && b[self.pos] != b'\n' {
                self.pos += 1;
            }
            if self.pos < b.len() && b[self.pos] == b'"' {
                self.pos += 1;
            }
        } else {
            while self.pos < b.len() && !b[self.pos].is_ascii_whitespace() {
                self.pos += 1;
            }
        }
        Some((&self.s[start..self.pos], line))
    }

    fn tok(&mut self, what: &str) -> Result<(&'a str, usize), String> {
        self.next()
            .ok_or_else(|| format!("end of file inside ${}: expected {what}", self.section))
    }

    fn uint(&mut self, what: &str) -> Result<u64, String> {
        let (t, line) = self.tok(what)?;
        t.parse().map_err(|_| {
            format!("line {line}: expected {what} (a non-negative integer), found \"{t}\"")
        })
    }

    fn count(&mut self, what: &str) -> Result<usize, String> {
        let (t, line) = self.tok(what)?;
        let n: usize = t.parse().map_err(|_| {
            format!("line {line}: expected {what} (a non-negative integer), found \"{t}\"")
        })?;
        // Guards allocations against garbage counts: nothing in a file is bigger than it.
        if n > self.s.len() {
            return Err(format!(
                "line {line}: {what} {n} is larger than the file could hold"
            ));
        }
        Ok(n)
    }

    fn int(&mut self, what: &str) -> Result<i64, String> {
        let (t, line) = self.tok(what)?;
        t.parse()
            .map_err(|_| format!("line {line}: expected {what} (an integer), found \"{t}\""))
    }

    fn real(&mut self, what: &str) -> Result<f64, String> {
        let (t, line) = self.tok(what)?;
        match t.parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ => Err(format!(
                "line {line}: expected {what} (a finite number), found \"{t}\""
            )),
        }
    }

    fn skip(&mut self, n: usize, what: &str) -> Result<(), String> {
        for _ in 0..n {
            self.tok(what)?;
        }
        Ok(())
    }

    /// The closing `$End<section>` line.
    fn end(&mut self) -> Result<(), String> {
        let want = format!("$End{}", self.section);
        match self.next() {
            Some((t, _)) if t == want => Ok(()),
            Some((t, line)) => Err(format!("line {line}: expected {want}, found \"{t}\"")),
            None => Err(format!("end of file: expected {want}")),
        }
    }
}

/// Nodes per element for the Gmsh types alfe reads, with their dimension.
fn elem_type(t: u64) -> Option<(usize, usize)> {
    match t {
        15 => Some((0, 1)),
        1 => Some((1, 2)),
        2 => Some((2, 3)),
        3 => Some((2, 4)),
        4 => Some((3, 4)),
        5 => Some((3, 8)),
        6 => Some((3, 6)),
        8 => Some((1, 3)),
        9 => Some((2, 6)),
        11 => Some((3, 10)),
        _ => None,
    }
}

fn elem_type_name(t: u64) -> String {
    let name = match t {
        6 => "prism6",
        7 => "pyramid5",
        8 => "line3",
        9 => "tri6",
        10 => "quad9",
        11 => "tet10",
        12 => "hex27",
        13 => "prism18",
        14 => "pyramid14",
        16 => "quad8",
        17 => "hex20",
        18 => "prism15",
        19 => "pyramid13",
        _ => return format!("type {t}"),
    };
    format!("type {t} ({name})")
}

/// One element as read: its entity's dimension and tag, element tag, line, node count
/// and where its (renumbered) nodes start in [`Raw::conn`].
struct RawElem {
    dim: usize,
    entity: i64,
    tag: u64,
    line: usize,
    nn: usize,
    at: usize,
}

/// A parsed file before it becomes a volume or a sheet mesh.
struct Raw {
    coords: Vec<[f64; 3]>,
    /// Physical groups: (dim, tag) -> name.
    phys_names: HashMap<(usize, i64), String>,
    /// (dim, entity tag) -> physical tags.
    entity_phys: HashMap<(usize, i64), Vec<i64>>,
    elems: Vec<RawElem>,
    conn: Vec<usize>,
}

impl Raw {
    fn nodes(&self, e: &RawElem) -> &[usize] {
        &self.conn[e.at..e.at + e.nn]
    }
    fn group_name(&self, dim: usize, tag: i64) -> String {
        self.phys_names
            .get(&(dim, tag))
            .cloned()
            .unwrap_or_else(|| format!("group{tag}"))
    }
    /// The physical groups (names) an element's entity belongs to.
    fn groups(&self, e: &RawElem) -> Vec<String> {
        self.entity_phys
            .get(&(e.dim, e.entity))
            .into_iter()
            .flatten()
            .map(|&t| self.group_name(e.dim, t))
            .collect()
    }
}

/// Parse an ASCII Gmsh MSH 4.1 or 2.2 file; nodes are renumbered 0..n in order of appearance.
fn parse(text: &str) -> Result<Raw, String> {
    let mut lx = Lexer {
        s: text,
        pos: 0,
        line: 1,
        section: "MeshFormat",
    };
    let v2 = header(&mut lx)?;
    let mut raw = Raw {
        coords: Vec::new(),
        phys_names: HashMap::new(),
        entity_phys: HashMap::new(),
        elems: Vec::new(),
        conn: Vec::new(),
    };
    let mut node_index: HashMap<u64, usize> = HashMap::new();
    let (mut seen_nodes, mut seen_elems) = (false, false);

    while let Some((t, line)) = lx.next() {
        let Some(name) = t.strip_prefix('$') else {
            return Err(format!(
                "line {line}: expected a section header such as $Nodes, found \"{t}\""
            ));
        };
        lx.section = name;
        match name {
            "PhysicalNames" => physical_names(&mut lx, &mut raw)?,
            "Entities" => entities(&mut lx, &mut raw)?,
            "Nodes" => {
                seen_nodes = true;
                if v2 {
                    nodes_v2(&mut lx, &mut raw, &mut node_index)?;
                } else {
                    nodes(&mut lx, &mut raw, &mut node_index)?;
                }
            }
            "Elements" => {
                seen_elems = true;
                if v2 {
                    elements_v2(&mut lx, &mut raw, &node_index)?;
                } else {
                    elements(&mut lx, &mut raw, &node_index, seen_nodes)?;
                }
            }
            _ => {
                // $Periodic, $NodeData, ...: not needed.
                skip_section(&mut lx, name)?;
                continue;
            }
        }
        lx.end()?;
    }
    if !seen_nodes || !seen_elems {
        return Err(format!(
            "mesh file has no ${} section",
            if seen_nodes { "Elements" } else { "Nodes" }
        ));
    }
    Ok(raw)
}

/// `$MeshFormat`: version 4.1 or 2.2, ASCII; whether it is 2.2.
fn header(lx: &mut Lexer) -> Result<bool, String> {
    match lx.next() {
        Some(("$MeshFormat", _)) => {}
        Some((t, line)) => {
            return Err(format!(
                "line {line}: not a Gmsh .msh file: expected $MeshFormat, found \"{t}\""
            ))
        }
        None => return Err("empty mesh file: expected $MeshFormat".to_string()),
    }
    let (version, line) = lx.tok("the MSH version")?;
    let v2 = matches!(version, "2.2" | "2.1" | "2");
    if version != "4.1" && !v2 {
        return Err(format!(
            "line {line}: MSH version {version} is not supported; alfe reads MSH 4.1 and 2.2 (gmsh -format msh41)"
        ));
    }
    let (file_type, line) = lx.tok("the file type (0 = ASCII)")?;
    if file_type != "0" {
        return Err(format!("line {line}: binary .msh files are not supported; save as ASCII (gmsh -bin 0, Mesh.Binary = 0)"));
    }
    lx.tok("the data size")?;
    lx.end()?;
    Ok(v2)
}

/// MSH 2.2 `$Nodes`: a count, then `tag x y z` lines.
fn nodes_v2(
    lx: &mut Lexer,
    raw: &mut Raw,
    node_index: &mut HashMap<u64, usize>,
) -> Result<(), String> {
    let n = lx.count("the number of nodes")?;
    raw.coords.reserve(n);
    for _ in 0..n {
        let (t, line) = lx.tok("a node tag")?;
        let tag: u64 = t.parse().map_err(|_| {
            format!("line {line}: expected a node tag (a positive integer), found \"{t}\"")
        })?;
        if node_index.insert(tag, raw.coords.len()).is_some() {
            return Err(format!(
                "line {line}: node tag {tag} appears twice in $Nodes"
            ));
        }
        raw.coords.push([
            lx.real("a node coordinate")?,
            lx.real("a node coordinate")?,
            lx.real("a node coordinate")?,
        ]);
    }
    Ok(())
}

/// MSH 2.2 `$Elements`: a count, then `tag type ntags tags... nodes...` lines; the first
/// tag is the physical group, which stands in for the entity (4.1's groups are by entity).
fn elements_v2(
    lx: &mut Lexer,
    raw: &mut Raw,
    node_index: &HashMap<u64, usize>,
) -> Result<(), String> {
    let n = lx.count("the number of elements")?;
    let mut seen: std::collections::HashSet<u64> = std::collections::HashSet::new();
    for _ in 0..n {
        let (t, line) = lx.tok("an element tag")?;
        let etag: u64 = t.parse().map_err(|_| {
            format!("line {line}: expected an element tag (a positive integer), found \"{t}\"")
        })?;
        if !seen.insert(etag) {
            return Err(format!(
                "line {line}: element tag {etag} appears twice in $Elements"
            ));
        }
        let ty = lx.uint("an element type")?;
        let Some((dim, nn)) = elem_type(ty) else {
            return Err(format!(
                "line {line}: element {etag} has {}, which alfe does not read; use hex8, tet4, tet10 (Mesh.ElementOrder = 2) or wedge6 volumes, or quad4/tri3 sheets",
                elem_type_name(ty)
            ));
        };
        let ntags = lx.count("the number of tags")?;
        let mut physical = 0;
        for k in 0..ntags {
            let v = lx.int("an element tag value")?;
            if k == 0 {
                physical = v.abs();
            }
        }
        if physical != 0 {
            raw.entity_phys.insert((dim, physical), vec![physical]);
        }
        let at = raw.conn.len();
        for _ in 0..nn {
            let (t, l) = lx.tok("a node tag")?;
            let ntag: u64 = t.parse().map_err(|_| {
                format!("line {l}: element {etag}: expected a node tag (a positive integer), found \"{t}\"")
            })?;
            let Some(&v) = node_index.get(&ntag) else {
                return Err(format!(
                    "line {l}: element {etag} has node tag {ntag} that is not in $Nodes"
                ));
            };
            raw.conn.push(v);
        }
        raw.elems.push(RawElem {
            dim,
            entity: physical,
            tag: etag,
            line,
            nn,
            at,
        });
    }
    Ok(())
}

/// `$PhysicalNames`: (dimension, tag) → name.
fn physical_names(lx: &mut Lexer, raw: &mut Raw) -> Result<(), String> {
    let n = lx.count("the number of physical names")?;
    for _ in 0..n {
        let dim = lx.count("a physical group dimension")?;
        let tag = lx.int("a physical group tag")?;
        let (q, line) = lx.tok("a quoted physical group name")?;
        let Some(s) = q.strip_prefix('"').and_then(|s| s.strip_suffix('"')) else {
            return Err(format!(
                "line {line}: expected a quoted physical group name, found {q}"
            ));
        };
        raw.phys_names.insert((dim, tag), s.to_string());
    }
    Ok(())
}

/// `$Entities`: each entity's physical tags (coordinates and bounding entities skipped).
fn entities(lx: &mut Lexer, raw: &mut Raw) -> Result<(), String> {
    let counts = [
        lx.count("the number of points")?,
        lx.count("the number of curves")?,
        lx.count("the number of surfaces")?,
        lx.count("the number of volumes")?,
    ];
    for (dim, &n) in counts.iter().enumerate() {
        for _ in 0..n {
            let tag = lx.int("an entity tag")?;
            // Points: x y z; others: a bounding box.
            for _ in 0..if dim == 0 { 3 } else { 6 } {
                lx.real("an entity coordinate")?;
            }
            let np = lx.count("the number of physical tags")?;
            let mut tags = Vec::with_capacity(np);
            for _ in 0..np {
                tags.push(lx.int("a physical tag")?.abs());
            }
            if dim > 0 {
                let nb = lx.count("the number of bounding entities")?;
                lx.skip(nb, "a bounding entity tag")?;
            }
            if !tags.is_empty() {
                raw.entity_phys.insert((dim, tag), tags);
            }
        }
    }
    Ok(())
}

/// `$Nodes`: coordinates in order of appearance; `node_index` maps tags to indices.
fn nodes(
    lx: &mut Lexer,
    raw: &mut Raw,
    node_index: &mut HashMap<u64, usize>,
) -> Result<(), String> {
    let blocks = lx.count("the number of node blocks")?;
    let total = lx.count("the number of nodes")?;
    lx.skip(2, "the min and max node tags")?;
    raw.coords.reserve(total);
    let mut tags = Vec::new();
    for _ in 0..blocks {
        let edim = lx.count("an entity dimension")?;
        lx.int("an entity tag")?;
        let parametric = lx.uint("the parametric flag")? != 0;
        let n = lx.count("the number of nodes in the block")?;
        tags.clear();
        for _ in 0..n {
            let (t, line) = lx.tok("a node tag")?;
            let tag: u64 = t.parse().map_err(|_| {
                format!("line {line}: expected a node tag (a positive integer), found \"{t}\"")
            })?;
            if node_index
                .insert(tag, raw.coords.len() + tags.len())
                .is_some()
            {
                return Err(format!(
                    "line {line}: node tag {tag} appears twice in $Nodes"
                ));
            }
            tags.push(tag);
        }
        for _ in 0..n {
            let x = [
                lx.real("a node coordinate")?,
                lx.real("a node coordinate")?,
                lx.real("a node coordinate")?,
            ];
            if parametric {
                lx.skip(edim, "a parametric coordinate")?;
            }
            raw.coords.push(x);
        }
    }
    Ok(())
}

/// `$Elements`: connectivity by node index, with each element's entity, tag and line.
fn elements(
    lx: &mut Lexer,
    raw: &mut Raw,
    node_index: &HashMap<u64, usize>,
    seen_nodes: bool,
) -> Result<(), String> {
    let blocks = lx.count("the number of element blocks")?;
    let header_line = lx.line;
    let total = lx.count("the number of elements")?;
    lx.skip(2, "the min and max element tags")?;
    let first = raw.elems.len();
    let mut tags: std::collections::HashSet<u64> = std::collections::HashSet::new();
    for _ in 0..blocks {
        lx.count("an entity dimension")?;
        let entity = lx.int("an entity tag")?;
        let (t, type_line) = lx.tok("an element type")?;
        let ty: u64 = t.parse().map_err(|_| {
            format!("line {type_line}: expected an element type (an integer), found \"{t}\"")
        })?;
        let n = lx.count("the number of elements in the block")?;
        let Some((dim, nn)) = elem_type(ty) else {
            let (what, line) = match lx.next() {
                Some((t, l)) if n > 0 => (format!("element {t} has"), l),
                _ => ("an element block has".to_string(), type_line),
            };
            return Err(format!(
                "line {line}: {what} {}, which alfe does not read; use hex8, tet4, tet10 (Mesh.ElementOrder = 2) or wedge6 volumes, or quad4 sheets",
                elem_type_name(ty)
            ));
        };
        for _ in 0..n {
            let (t, line) = lx.tok("an element tag")?;
            let etag: u64 = t.parse().map_err(|_| {
                format!("line {line}: expected an element tag (a positive integer), found \"{t}\"")
            })?;
            if !tags.insert(etag) {
                return Err(format!(
                    "line {line}: element tag {etag} appears twice in $Elements"
                ));
            }
            let at = raw.conn.len();
            for _ in 0..nn {
                let (t, l) = lx.tok("a node tag")?;
                let ntag: u64 = t.parse().map_err(|_| {
                    format!("line {l}: element {etag}: expected a node tag (a positive integer), found \"{t}\"")
                })?;
                let Some(&v) = node_index.get(&ntag) else {
                    let hint = if seen_nodes {
                        ""
                    } else {
                        " ($Nodes must come before $Elements)"
                    };
                    return Err(format!(
                        "line {l}: element {etag} has node tag {ntag} that is not in $Nodes{hint}"
                    ));
                };
                raw.conn.push(v);
            }
            raw.elems.push(RawElem {
                dim,
                entity,
                tag: etag,
                line,
                nn,
                at,
            });
        }
    }
    if raw.elems.len() - first != total {
        return Err(format!(
            "line {header_line}: $Elements says {total} elements, its blocks hold {}",
            raw.elems.len() - first
        ));
    }
    Ok(())
}

/// A section alfe does not need, up to its `$End` line.
fn skip_section(lx: &mut Lexer, name: &str) -> Result<(), String> {
    let want = format!("$End{name}");
    loop {
        match lx.next() {
            Some((t, _)) if t == want => return Ok(()),
            Some(_) => {}
            None => return Err(format!("end of file: ${name} is never closed by {want}")),
        }
    }
}

/// Read an ASCII Gmsh MSH 4.1 volume mesh; volume elements get part index `part`.
pub fn read_msh(text: &str, part: u32) -> Result<Mesh, String> {
    let mut raw = parse(text)?;
    let mut mesh = Mesh {
        coords: std::mem::take(&mut raw.coords),
        offsets: vec![0],
        ..Default::default()
    };
    let mut node_groups: BTreeMap<String, Vec<usize>> = BTreeMap::new();
    let mut face_groups: BTreeMap<String, Vec<FaceRef>> = BTreeMap::new();
    let mut elem_groups: BTreeMap<String, Vec<usize>> = BTreeMap::new();

    for re in raw.elems.iter().filter(|e| e.dim == 3) {
        let kind = match re.nn {
            8 => ElemKind::Hex8,
            10 => ElemKind::Tet10,
            6 => ElemKind::Wedge6,
            _ => ElemKind::Tet4,
        };
        mesh.push_elem(kind, raw.nodes(re), part);
        let e = mesh.n_elems() - 1;
        if mesh.elem_volume(e) <= 0.0 {
            return Err(format!(
                "line {}: element {} ({}) has zero or negative volume; its node order is inverted or it is degenerate",
                re.line,
                re.tag,
                kind.name()
            ));
        }
        for name in raw.groups(re) {
            node_groups
                .entry(name.clone())
                .or_default()
                .extend_from_slice(mesh.elem_nodes(e));
            elem_groups.entry(name).or_default().push(e);
        }
    }
    if mesh.n_elems() == 0 {
        let hint = if raw.elems.iter().any(|e| e.dim == 2) {
            " (a surface mesh of a sheet is read by kind = \"sheet\")"
        } else {
            ""
        };
        return Err(format!("mesh file has no hex8, tet4, tet10 or wedge6 volume elements; add a physical volume or set Mesh.SaveAll = 1{hint}"));
    }

    let grouped: Vec<&RawElem> = raw
        .elems
        .iter()
        .filter(|e| e.dim < 3 && raw.entity_phys.contains_key(&(e.dim, e.entity)))
        .collect();
    let mut faces: HashMap<Vec<usize>, FaceRef> = HashMap::new();
    if grouped.iter().any(|g| g.dim == 2) {
        for e in 0..mesh.n_elems() {
            for f in 0..mesh.kinds[e].faces().len() {
                let fr = FaceRef {
                    elem: e,
                    face: f as u8,
                };
                let mut key = mesh.face_nodes(fr);
                key.sort_unstable();
                faces.entry(key).or_insert(fr);
            }
        }
    }
    for re in grouped {
        let nodes = raw.nodes(re);
        for name in raw.groups(re) {
            node_groups
                .entry(name.clone())
                .or_default()
                .extend_from_slice(nodes);
            if re.dim == 2 {
                let mut key = nodes.to_vec();
                key.sort_unstable();
                let Some(&f) = faces.get(&key) else {
                    return Err(format!(
                        "line {}: element {} of physical surface \"{name}\" is not a face of any hex8, tet4, tet10 or wedge6 element",
                        re.line, re.tag
                    ));
                };
                face_groups.entry(name).or_default().push(f);
            }
        }
    }

    for v in node_groups.values_mut().chain(elem_groups.values_mut()) {
        v.sort_unstable();
        v.dedup();
    }
    for v in face_groups.values_mut() {
        v.sort_unstable();
        v.dedup();
    }
    mesh.node_groups = node_groups;
    mesh.face_groups = face_groups;
    mesh.elem_groups = elem_groups;
    Ok(mesh)
}

/// Read an ASCII Gmsh MSH 4.1 surface mesh of quad4 and tri3 elements (a sheet's middle
/// or outer surface) with its physical surfaces, curves and points, for
/// [`super::sheet`].
pub fn read_surface(text: &str) -> Result<Surface, String> {
    let mut raw = parse(text)?;
    if let Some(v) = raw.elems.iter().find(|e| e.dim == 3) {
        return Err(format!(
            "line {}: element {} is a volume element; a sheet is read from a surface mesh of quad4 and tri3 elements (read volume meshes with kind = \"gmsh\")",
            v.line, v.tag
        ));
    }
    if let Some(t) = raw
        .elems
        .iter()
        .find(|e| e.dim == 2 && e.nn != 4 && e.nn != 3)
    {
        return Err(format!(
            "line {}: element {} is a surface element of {} nodes; a sheet is extruded from quad4 and tri3 elements (Mesh.ElementOrder = 1)",
            t.line, t.tag, t.nn
        ));
    }
    let mut s = Surface {
        coords: std::mem::take(&mut raw.coords),
        ..Default::default()
    };
    for re in &raw.elems {
        let nodes = raw.nodes(re);
        match re.dim {
            2 => {
                for name in raw.groups(re) {
                    s.quad_groups.entry(name).or_default().push(s.quads.len());
                }
                s.quads.push(nodes.to_vec());
                s.quad_lines.push((re.line, re.tag));
            }
            1 => {
                for name in raw.groups(re) {
                    s.edge_groups
                        .entry(name)
                        .or_default()
                        .push([nodes[0], nodes[1]]);
                }
            }
            _ => {
                for name in raw.groups(re) {
                    s.point_groups.entry(name).or_default().push(nodes[0]);
                }
            }
        }
    }
    if s.quads.is_empty() {
        return Err("mesh file has no quad4 or tri3 surface elements to extrude".to_string());
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEXES: &str = r#"$MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
3
0 3 "corner"
2 1 "bottom face"
3 2 "solid"
$EndPhysicalNames
$Comments
anything "quoted" here
$EndComments
$Entities
1 0 1 1
1 0 0 0 1 3
1 0 0 0 2 1 0 1 1 0
1 0 0 0 2 1 1 1 2 1 -1
$EndEntities
$Nodes
2 12 10 43
0 1 0 1
10
0 0 0
3 1 0 11
13
16
19
22
25
28
31
34
37
40
43
1.0e+00 0 0
2E0 0 0
0 1 0
1 1 0
2 1 0
0 0 1
1 0 1
2 0 1
0 1 1
1 1 1
2 1 1
$EndNodes
$Elements
3 5 1 5
0 1 15 1
1 10
2 1 3 2
2 10 19 22 13
3 13 22 25 16
3 1 5 2
4 10 13 22 19 28 31 40 37
5 13 16 25 22 31 34 43 40
$EndElements
"#;

    const TETS: &str = r#"$MeshFormat
4.1 0 8
$EndMeshFormat
$Entities
0 0 2 1
1 0 0 0 1 1 0 1 7 0
2 0 0 0 1 1 1 1 8 0
3 0 0 0 1 1 1 1 9 0
$EndEntities
$Nodes
1 5 1 5
3 3 0 5
1
2
3
4
5
0 0 0
1 0 0
0 1 0
0 0 1
1 1 1
$EndNodes
$Elements
3 4 1 4
2 1 2 1
1 1 2 3
2 2 2 1
2 4 3 2
3 3 4 2
3 1 2 3 4
4 2 3 4 5
$EndElements
"#;

    fn err(text: &str) -> String {
        read_msh(text, 0).expect_err("should fail")
    }

    #[test]
    fn reads_hexes_with_groups() {
        let m = read_msh(HEXES, 3).unwrap();
        assert_eq!(m.n_nodes(), 12);
        assert_eq!(m.n_elems(), 2);
        assert_eq!(m.kinds, vec![ElemKind::Hex8; 2]);
        assert_eq!(m.elem_part, vec![3, 3]);
        assert_eq!(m.coords[0], [0.0; 3]);
        assert_eq!(m.coords[1], [1.0, 0.0, 0.0]);
        assert_eq!(m.coords[2], [2.0, 0.0, 0.0]);
        assert_eq!(m.elem_nodes(0), &[0, 1, 4, 3, 6, 7, 10, 9]);
        assert!((m.elem_volume(1) - 1.0).abs() < 1e-12);
        assert_eq!(m.elem_groups["solid"], vec![0, 1]);
        assert_eq!(m.node_groups["solid"], (0..12).collect::<Vec<_>>());
        assert_eq!(m.node_groups["corner"], vec![0]);
        assert_eq!(m.node_groups["bottom face"], vec![0, 1, 2, 3, 4, 5]);
        assert_eq!(
            m.face_groups["bottom face"],
            vec![FaceRef { elem: 0, face: 0 }, FaceRef { elem: 1, face: 0 }]
        );
        assert_eq!(m.face_groups.len(), 1);
        assert_eq!(m.elem_groups.len(), 1);
    }

    #[test]
    fn reads_tets_with_unnamed_and_interior_surfaces() {
        let m = read_msh(TETS, 0).unwrap();
        assert_eq!(m.kinds, vec![ElemKind::Tet4; 2]);
        assert!(m.elem_volume(0) > 0.0 && m.elem_volume(1) > 0.0);
        let f = m.face_groups["group7"][0];
        let mut ns = m.face_nodes(f);
        ns.sort();
        assert_eq!((f.elem, ns), (0, vec![0, 1, 2]));
        assert_eq!(m.face_groups["group8"].len(), 1);
        assert_eq!(m.node_groups["group8"], vec![1, 2, 3]);
        assert_eq!(m.elem_groups["group9"], vec![0, 1]);
    }

    /// One tet10 (Gmsh node order, tags shuffled) with a tri6 physical surface on its
    /// face 0-2-1 and a line3 physical curve.
    const TET10: &str = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n3\n1 3 \"edge\"\n2 1 \"base\"\n3 2 \"body\"\n$EndPhysicalNames\n$Entities\n0 1 1 1\n1 0 0 0 1 0 0 1 3 0\n1 0 0 0 1 1 0 1 1 0\n1 0 0 0 1 1 1 1 2 0\n$EndEntities\n$Nodes\n1 10 1 10\n3 1 0 10\n1\n2\n3\n4\n5\n6\n7\n8\n9\n10\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n0.5 0 0\n0.5 0.5 0\n0 0.5 0\n0 0 0.5\n0 0.5 0.5\n0.5 0 0.5\n$EndNodes\n$Elements\n3 3 1 3\n1 1 8 1\n1 1 2 5\n2 1 9 1\n2 1 3 2 7 6 5\n3 1 11 1\n3 1 2 3 4 5 6 7 8 9 10\n$EndElements\n";

    #[test]
    fn reads_tet10_with_tri6_faces() {
        let m = read_msh(TET10, 0).unwrap();
        assert_eq!(m.kinds, vec![ElemKind::Tet10]);
        assert_eq!(m.elem_nodes(0), &[0, 1, 2, 3, 4, 5, 6, 7, 8, 9]);
        assert!((m.elem_volume(0) - 1.0 / 6.0).abs() < 1e-15);
        assert_eq!(m.face_groups["base"], vec![FaceRef { elem: 0, face: 0 }]);
        assert_eq!(
            m.face_nodes(m.face_groups["base"][0]),
            vec![0, 2, 1, 6, 5, 4]
        );
        assert_eq!(m.node_groups["edge"], vec![0, 1, 4]);
        assert_eq!(m.node_groups["body"].len(), 10);
        // Every face's midside nodes sit at the midpoints of its corners.
        for f in 0..4 {
            let ns = m.face_nodes(FaceRef { elem: 0, face: f });
            for k in 0..3 {
                let (a, b) = (m.coords[ns[k]], m.coords[ns[(k + 1) % 3]]);
                let mid = m.coords[ns[3 + k]];
                assert!((0..3).all(|c| (0.5 * (a[c] + b[c]) - mid[c]).abs() < 1e-15));
            }
        }
        assert_eq!(m.boundary_faces().len(), 4);
    }

    #[test]
    fn reads_a_quad_surface_for_a_sheet() {
        let quads = HEXES
            .replace("$Elements\n3 5 1 5\n", "$Elements\n2 3 1 3\n")
            .replace(
                "3 1 5 2\n4 10 13 22 19 28 31 40 37\n5 13 16 25 22 31 34 43 40\n",
                "",
            );
        let s = read_surface(&quads).unwrap();
        assert_eq!(s.quads, vec![[0, 3, 4, 1], [1, 4, 5, 2]]);
        assert_eq!(s.quad_lines, vec![(53, 2), (54, 3)]);
        assert_eq!(s.quad_groups["bottom face"], vec![0, 1]);
        assert_eq!(s.point_groups["corner"], vec![0]);
        let e = read_msh(&quads, 0).unwrap_err();
        assert!(e.contains("read by kind = \"sheet\""), "{e}");
        let e = read_surface(HEXES).unwrap_err();
        assert!(e.contains("element 4 is a volume element"), "{e}");
        // Triangles are facets of a sheet too (they become wedges); tri6 is refused.
        let tris = read_surface(
            &quads
                .replace("2 1 3 2", "2 1 2 2")
                .replace("2 10 19 22 13", "2 10 19 22")
                .replace("3 13 22 25 16", "3 13 22 25"),
        )
        .unwrap();
        assert_eq!(tris.quads, vec![vec![0, 3, 4], vec![1, 4, 5]]);
        let e = read_surface(
            &quads
                .replace("2 1 3 2", "2 1 9 2")
                .replace("2 10 19 22 13", "2 10 19 22 13 16 25")
                .replace("3 13 22 25 16", "3 13 22 25 16 10 19"),
        )
        .unwrap_err();
        assert!(
            e.contains("element 2 is a surface element of 6 nodes"),
            "{e}"
        );
    }

    /// MSH 2.2 (Gmsh's legacy format, still what many tools write): a hex under a
    /// physical volume, its bottom quad a physical surface, an unnamed physical curve.
    #[test]
    fn reads_msh_2_2() {
        let text = "$MeshFormat
2.2 0 8
$EndMeshFormat
$PhysicalNames
2
2 1 \"bottom face\"
3 2 \"solid\"
$EndPhysicalNames
$Nodes
8
1 0 0 0
2 1 0 0
3 1 1 0
4 0 1 0
5 0 0 1
6 1 0 1
7 1 1 1
8 0 1 1
$EndNodes
$Elements
3
1 1 2 7 3 1 2
2 3 2 1 1 1 4 3 2
3 5 2 2 1 1 2 3 4 5 6 7 8
$EndElements
";
        let m = read_msh(text, 0).unwrap();
        assert_eq!((m.n_nodes(), m.n_elems()), (8, 1));
        assert_eq!(m.elem_groups["solid"], vec![0]);
        assert_eq!(m.face_groups["bottom face"].len(), 1);
        assert_eq!(m.node_groups["group7"], vec![0, 1]);
        let bad = text.replace("3 5 2 2 1 1 2 3 4 5 6 7 8", "3 5 2 2 1 1 2 3 4 5 6 7 9");
        let e = read_msh(&bad, 0).unwrap_err();
        assert!(
            e.contains("line 24: element 3 has node tag 9 that is not in $Nodes"),
            "{e}"
        );
    }

    #[test]
    fn refuses_other_formats() {
        let e = err(&HEXES.replace("$Elements\n3 5 1 5", "$Elements\n3 4000000000000 1 5"));
        assert!(
            e.contains("4000000000000 is larger than the file could hold"),
            "{e}"
        );
        let e = err(&HEXES.replace("$Elements\n3 5 1 5", "$Elements\n3 6 1 5"));
        assert!(
            e.contains("$Elements says 6 elements, its blocks hold 5"),
            "{e}"
        );
        let e = err(&HEXES.replace("5 13 16 25 22 31 34 43 40", "4 13 16 25 22 31 34 43 40"));
        assert!(
            e.contains("element tag 4 appears twice in $Elements"),
            "{e}"
        );
        let e = err(&HEXES.replace("4.1 0 8", "3.0 0 8"));
        assert!(
            e.contains("line 2: MSH version 3.0 is not supported"),
            "{e}"
        );
        let e = err(&HEXES.replace("4.1 0 8", "4.1 1 8"));
        assert!(
            e.contains("line 2: binary .msh files are not supported"),
            "{e}"
        );
        let e = err("$Nodes\n");
        assert!(e.contains("not a Gmsh .msh file"), "{e}");
    }

    #[test]
    fn malformed_files_name_the_problem() {
        let e = err(&HEXES.replace("$EndNodes\n", ""));
        assert!(e.contains("expected $EndNodes, found \"$Elements\""), "{e}");
        let e = err(&HEXES.replace("2E0 0 0", "2E0 0 0.0.1"));
        assert!(
            e.contains("line 37: expected a node coordinate (a finite number), found \"0.0.1\""),
            "{e}"
        );
        let e = err(&HEXES.replace("5 13 16 25", "5 13 99 25"));
        assert!(
            e.contains("element 5 has node tag 99 that is not in $Nodes"),
            "{e}"
        );
        let e = err(&HEXES.replace("3 1 5 2", "3 1 12 2"));
        assert!(
            e.contains("element 4 has type 12 (hex27), which alfe does not read"),
            "{e}"
        );
        let e = err(&HEXES.replace("3 1 5 2", "3 1 7 2"));
        assert!(e.contains("type 7 (pyramid5)"), "{e}");
        let e = err(&HEXES.replace("3 13 22 25 16", "3 13 22 40 16"));
        assert!(
            e.contains("element 3 of physical surface \"bottom face\" is not a face"),
            "{e}"
        );
        let e = err(&TETS.replace("3 1 2 3 4", "3 1 3 2 4"));
        assert!(
            e.contains("element 3 (tet4) has zero or negative volume"),
            "{e}"
        );
        let e = err(&HEXES[..HEXES.find("$EndElements").unwrap()]);
        assert!(e.contains("end of file: expected $EndElements"), "{e}");
        let e = err(&HEXES[..HEXES.find("31 34 43 40").unwrap()]);
        assert!(
            e.contains("end of file inside $Elements: expected a node tag"),
            "{e}"
        );
        let e = err(&TETS.replace("3 3 0 5", "3 3 0 x5"));
        assert!(
            e.contains(
                "expected the number of nodes in the block (a non-negative integer), found \"x5\""
            ),
            "{e}"
        );
        for e in [
            err(&HEXES.replace("3 1 5 2", "3 1 2 2")),
            err(&HEXES.replace(
                "$Elements\n3 5 1 5\n",
                "$Elements\n0 0 0 0\n$EndElements\n$Foo\n",
            )),
        ] {
            assert!(!e.contains('\n'), "one line: {e}");
        }
    }
}
