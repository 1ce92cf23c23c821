//! Reader for Gmsh MSH 4.1 and 2.2 files, ASCII and binary.
//!
//! Volume elements (hex8, tet4) become the mesh; lower-dimensional elements only define
//! groups: every physical group gives a node group, physical surfaces also give face
//! groups (matched to volume-element faces by node set), physical volumes element groups.
//! A surface mesh of quads is read instead as a [`Surface`] that `mesh::sheet` extrudes.
//!
//! A binary file keeps the ASCII section lines and `$PhysicalNames` but writes the
//! `$Entities`, `$Nodes` and `$Elements` data as raw ints, size_ts and doubles (the int 1
//! after the `$MeshFormat` line gives their byte order). Both encodings are parsed into
//! the same `Raw`, so everything after parsing is shared. Messages place a problem by
//! line in an ASCII file and by byte offset (from 0) in a binary one, whose newline bytes
//! are data.

use std::collections::{BTreeMap, HashMap, HashSet};

use super::sheet::Surface;
use super::{ElemKind, FaceRef, Mesh};

mod ascii;
mod binary;
mod lexer;
#[cfg(test)]
mod tests;

use ascii::*;
use binary::*;
use lexer::*;

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

/// The refusal of an element type alfe does not read; `what` is "element 7 has" or "an
/// element block has".
fn unsupported_type(at: Loc, what: &str, ty: u64) -> String {
    format!(
        "{at}: {what} {}, which alfe does not read; use hex8, tet4, tet10 (Mesh.ElementOrder = 2) or wedge6 volumes, or quad4/tri3 sheets",
        elem_type_name(ty)
    )
}

/// Record that node `tag` has index `index`; a tag seen before is an error.
fn new_node(
    node_index: &mut HashMap<u64, usize>,
    tag: u64,
    index: usize,
    at: Loc,
) -> Result<(), String> {
    if node_index.insert(tag, index).is_some() {
        return Err(format!("{at}: node tag {tag} appears twice in $Nodes"));
    }
    Ok(())
}

/// Record element tag `etag`; a tag seen before is an error.
fn new_elem(seen: &mut HashSet<u64>, etag: u64, at: Loc) -> Result<(), String> {
    if !seen.insert(etag) {
        return Err(format!(
            "{at}: element tag {etag} appears twice in $Elements"
        ));
    }
    Ok(())
}

/// The index of node `ntag` of element `etag`.
fn node_of(
    node_index: &HashMap<u64, usize>,
    etag: u64,
    ntag: u64,
    at: Loc,
    seen_nodes: bool,
) -> Result<usize, String> {
    node_index.get(&ntag).copied().ok_or_else(|| {
        let hint = if seen_nodes {
            ""
        } else {
            " ($Nodes must come before $Elements)"
        };
        format!("{at}: element {etag} has node tag {ntag} that is not in $Nodes{hint}")
    })
}

/// One element as read: its entity's dimension and tag, element tag, place in the file,
/// node count and where its (renumbered) nodes start in [`Raw::conn`].
struct RawElem {
    pub(super) dim: usize,
    pub(super) entity: i64,
    pub(super) tag: u64,
    pub(super) loc: Loc,
    pub(super) nn: usize,
    pub(super) at: usize,
}

/// A parsed file before it becomes a volume or a sheet mesh.
struct Raw {
    pub(super) coords: Vec<[f64; 3]>,
    /// Physical groups: (dim, tag) -> name.
    pub(super) phys_names: HashMap<(usize, i64), String>,
    /// (dim, entity tag) -> physical tags.
    pub(super) entity_phys: HashMap<(usize, i64), Vec<i64>>,
    pub(super) elems: Vec<RawElem>,
    pub(super) conn: Vec<usize>,
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

/// Parse a Gmsh MSH 4.1 or 2.2 file, ASCII or (when `allow_binary`) binary; nodes are
/// renumbered 0..n in order of appearance.
fn parse(data: &[u8], allow_binary: bool) -> Result<Raw, String> {
    let mut lx = Lexer {
        b: data,
        pos: 0,
        line: 1,
        section: "MeshFormat",
        binary: false,
        big_endian: false,
        size_t: 8,
    };
    let v2 = header(&mut lx, allow_binary)?;
    let mut raw = Raw {
        coords: Vec::new(),
        phys_names: HashMap::new(),
        entity_phys: HashMap::new(),
        elems: Vec::new(),
        conn: Vec::new(),
    };
    let mut node_index: HashMap<u64, usize> = HashMap::new();
    let (mut seen_nodes, mut seen_elems) = (false, false);

    while let Some((t, at)) = lx.next() {
        let Some(name) = t.strip_prefix('$') else {
            return Err(format!(
                "{at}: expected a section header such as $Nodes, found \"{t}\""
            ));
        };
        lx.section = name;
        match name {
            "PhysicalNames" => physical_names(&mut lx, &mut raw)?,
            "Entities" | "Nodes" | "Elements" => {
                mesh_section(&mut lx, &mut raw, &mut node_index, v2, seen_nodes)?;
                seen_nodes |= name == "Nodes";
                seen_elems |= name == "Elements";
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

/// `$Entities`, `$Nodes` or `$Elements` (the section in `lx`), in the file's version
/// and encoding.
fn mesh_section(
    lx: &mut Lexer,
    raw: &mut Raw,
    node_index: &mut HashMap<u64, usize>,
    v2: bool,
    seen_nodes: bool,
) -> Result<(), String> {
    let name = lx.section;
    if !lx.binary {
        return match (name, v2) {
            ("Entities", _) => entities(lx, raw),
            ("Nodes", true) => nodes_v2(lx, raw, node_index),
            ("Nodes", false) => nodes(lx, raw, node_index),
            ("Elements", true) => elements_v2(lx, raw, node_index, seen_nodes),
            _ => elements(lx, raw, node_index, seen_nodes),
        };
    }
    if v2 {
        // Binary 2.2: an ASCII count line before each binary block.
        return match name {
            "Nodes" => nodes_v2_bin(lx, raw, node_index),
            "Elements" => elements_v2_bin(lx, raw, node_index, seen_nodes),
            _ => Err(format!(
                "{}: $Entities is not part of MSH 2.2; expected $Nodes or $Elements",
                lx.here()
            )),
        };
    }
    lx.line_end()?;
    match name {
        "Entities" => entities_bin(lx, raw),
        "Nodes" => nodes_bin(lx, raw, node_index),
        _ => elements_bin(lx, raw, node_index, seen_nodes),
    }
}

/// Read a Gmsh MSH 4.1 or 2.2 volume mesh from a file's bytes, ASCII or binary (the
/// `$MeshFormat` line tells); volume elements get part index `part`.
pub fn read_msh_bytes(data: &[u8], part: u32) -> Result<Mesh, String> {
    volume_mesh(parse(data, true)?, part)
}

/// Read an ASCII Gmsh MSH 4.1 or 2.2 volume mesh; volume elements get part index `part`.
/// Text cannot hold a binary file's raw blocks: read those with [`read_msh_bytes`].
pub fn read_msh(text: &str, part: u32) -> Result<Mesh, String> {
    volume_mesh(parse(text.as_bytes(), false)?, part)
}

/// The volume mesh of a parsed file, with node, face and element groups.
fn volume_mesh(mut raw: Raw, part: u32) -> Result<Mesh, String> {
    let mut mesh = Mesh {
        coords: std::mem::take(&mut raw.coords),
        offsets: vec![0],
        ..Default::default()
    };
    let mut node_groups: BTreeMap<String, Vec<usize>> = BTreeMap::new();
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
                "{}: element {} ({}) has zero or negative volume; its node order is inverted or it is degenerate",
                re.loc,
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
    let mut face_groups = boundary_groups(&raw, &mesh, &mut node_groups)?;

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

/// The groups of a volume mesh's physical points, curves and surfaces: their nodes go
/// into `node_groups`; a physical surface's elements are matched (by node set) to faces
/// of the volume elements, which are returned as face groups.
fn boundary_groups(
    raw: &Raw,
    mesh: &Mesh,
    node_groups: &mut BTreeMap<String, Vec<usize>>,
) -> Result<BTreeMap<String, Vec<FaceRef>>, String> {
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
    let mut face_groups: BTreeMap<String, Vec<FaceRef>> = BTreeMap::new();
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
                        "{}: element {} of physical surface \"{name}\" is not a face of any hex8, tet4, tet10 or wedge6 element",
                        re.loc, re.tag
                    ));
                };
                face_groups.entry(name).or_default().push(f);
            }
        }
    }
    Ok(face_groups)
}

/// Read a Gmsh MSH 4.1 or 2.2 surface mesh of quad4 and tri3 elements (a sheet's middle
/// or outer surface) from a file's bytes, ASCII or binary, with its physical surfaces,
/// curves and points, for [`super::sheet`].
pub fn read_surface_bytes(data: &[u8]) -> Result<Surface, String> {
    surface(parse(data, true)?)
}

/// Read an ASCII Gmsh MSH 4.1 or 2.2 surface mesh (see [`read_surface_bytes`]).
pub fn read_surface(text: &str) -> Result<Surface, String> {
    surface(parse(text.as_bytes(), false)?)
}

/// The sheet surface of a parsed file.
fn surface(mut raw: Raw) -> Result<Surface, String> {
    if let Some(v) = raw.elems.iter().find(|e| e.dim == 3) {
        return Err(format!(
            "{}: element {} is a volume element; a sheet is read from a surface mesh of quad4 and tri3 elements (read volume meshes with kind = \"gmsh\")",
            v.loc, v.tag
        ));
    }
    if let Some(t) = raw
        .elems
        .iter()
        .find(|e| e.dim == 2 && e.nn != 4 && e.nn != 3)
    {
        return Err(format!(
            "{}: element {} is a surface element of {} nodes; a sheet is extruded from quad4 and tri3 elements (Mesh.ElementOrder = 1)",
            t.loc, t.tag, t.nn
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
                s.quad_lines.push((re.loc.line(), re.tag));
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
