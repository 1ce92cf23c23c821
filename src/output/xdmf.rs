//! The XDMF3 text file beside the HDF5 file: what ParaView opens (its "XDMF Reader"
//! names the blocks after the parts and walls; see [`xdmf_text_with_grids`]).
//!
//! One spatial collection of blocks, each a temporal collection of one uniform grid per
//! output step. Every grid repeats the Geometry and Topology `DataItem`s, pointing at
//! the same HDF5 datasets: the data live once on disk (the XDMF only references them),
//! and plain repetition is read by every XDMF reader, where `xpointer` references are
//! not (robustness over a few hundred bytes of text per step).
//!
//! Datasets the mesh part refers to, by convention (see [`COORDINATES`],
//! [`CONNECTIVITY`]): `/mesh/coordinates`, f64 `(n_nodes, 3)`, and
//! `/mesh/connectivity`, i64 `(n_elems, 8)` for hexahedra, `(n_elems, 4)` for
//! tetrahedra, `(n_elems, 10)` for quadratic tetrahedra (VTK's node order), or 1-D `(n_entries)` for a mixed mesh (per cell: the XDMF type id,
//! [`XDMF_HEXAHEDRON`] or [`XDMF_TETRAHEDRON`], then its node ids). Node ids are 0-based.

use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;

/// HDF5 path of the node coordinates, f64 `(n_nodes, 3)`.
pub const COORDINATES: &str = "/mesh/coordinates";
/// HDF5 path of the element connectivity, i64 (see the module docs for its shape).
pub const CONNECTIVITY: &str = "/mesh/connectivity";
/// XDMF cell type id of an 8-node hexahedron in a `Mixed` connectivity array.
pub const XDMF_HEXAHEDRON: i64 = 9;
/// XDMF cell type id of a 4-node tetrahedron in a `Mixed` connectivity array.
pub const XDMF_TETRAHEDRON: i64 = 6;
/// XDMF cell type id of a 10-node tetrahedron (`Tetrahedron_10`) in a `Mixed` array.
/// Its midside nodes are in VTK's order: edges 0-1, 1-2, 2-0, 0-3, 1-3, 2-3.
pub const XDMF_TETRAHEDRON_10: i64 = 38;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Center {
    Node,
    Cell,
}

/// Shape of one attribute row: 1, 3 or 6 components.
/// `Tensor6` carries alfe's Voigt order xx, yy, zz, xy, yz, xz, which is VTK's symmetric-tensor
/// order, and is declared to XDMF as a `Matrix` of six columns: ParaView 5.11's three XDMF
/// readers then keep the columns in order and name them XX, YY, ZZ, XY, YZ, XZ (colour-by
/// menu, Calculator's `stress_XY`; the spreadsheet says `stress_0` .. `stress_5`): alfe's.
/// Declared `Tensor6` (XDMF's own symmetric tensor, whose order is xx, xy, xz, yy, yz, zz),
/// the Xdmf3 readers did the same but the legacy "XDMF Reader" expanded the columns into a
/// wrong 3x3 tensor. scripts/check-paraview checks the names in every reader.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum AttrKind {
    Scalar,
    Vector,
    Tensor6,
}

impl AttrKind {
    /// Number of columns of the dataset.
    pub fn n_cols(self) -> u64 {
        match self {
            AttrKind::Scalar => 1,
            AttrKind::Vector => 3,
            AttrKind::Tensor6 => 6,
        }
    }
    fn xdmf(self) -> &'static str {
        match self {
            AttrKind::Scalar => "Scalar",
            AttrKind::Vector => "Vector",
            AttrKind::Tensor6 => "Matrix",
        }
    }
}

/// One attribute of a grid: a dataset of `n_rows` rows (nodes or cells) of `n_cols`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct XdmfAttr {
    pub name: String,
    pub center: Center,
    pub kind: AttrKind,
    /// Absolute path inside the HDF5 file, e.g. "/steps/000003/displacement".
    pub h5_path: String,
    pub n_rows: u64,
    pub n_cols: u64,
    /// "Float" (precision 8) or "Int" (precision 4 or 8).
    pub number_type: String,
    pub precision: u8,
}

/// One output step: its time and its attributes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct XdmfStep {
    pub time: f64,
    pub attrs: Vec<XdmfAttr>,
    /// The HDF5 file of this step, relative to the `.xmf`, where it is not the mesh's
    /// (a restarted run's steps before the restart are in the earlier run's file).
    pub h5_file: Option<String>,
}

/// A part of the mesh: ParaView's block of that name. Its cells are the rows
/// `cells.0 .. cells.0 + cells.1` of every cell dataset (and, in a mixed connectivity,
/// the entries `entries.0 ..` of `entries.1`).
#[derive(Debug, Clone, PartialEq)]
pub struct XdmfPart {
    pub name: String,
    pub cells: (u64, u64),
    pub entries: (u64, u64),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum XdmfTopology {
    Hexahedron,
    Tetrahedron,
    Tetrahedron10,
    /// A 1-D mixed connectivity array of `n_entries` integers.
    Mixed {
        n_entries: u64,
    },
}

/// The mesh every step shares.
#[derive(Debug, Clone, PartialEq)]
pub struct XdmfMesh {
    /// The HDF5 file's name relative to the `.xmf` (they sit side by side).
    pub h5_file_name: String,
    pub n_nodes: u64,
    pub n_elems: u64,
    pub topology: XdmfTopology,
    /// Cell attributes written in every grid (e.g. the partition id).
    pub static_cell_attrs: Vec<XdmfAttr>,
    /// The parts, in file order; none: one block `mesh` of every cell.
    pub parts: Vec<XdmfPart>,
}

/// Escape text for an XML attribute value or element content.
fn esc(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&apos;"),
            _ => o.push(c),
        }
    }
    o
}

fn dims(n_rows: u64, n_cols: u64) -> String {
    if n_cols == 1 {
        format!("{n_rows}")
    } else {
        format!("{n_rows} {n_cols}")
    }
}

fn data_item(
    out: &mut String,
    indent: &str,
    h5: &str,
    path: &str,
    dims: &str,
    number_type: &str,
    precision: u8,
) {
    let _ = writeln!(
        out,
        "{indent}<DataItem Dimensions=\"{dims}\" NumberType=\"{number_type}\" \
         Precision=\"{precision}\" Format=\"HDF\">{}:{}</DataItem>",
        esc(h5),
        esc(path)
    );
}

fn check_attr(mesh: &XdmfMesh, a: &XdmfAttr) -> Result<()> {
    let bad = |why: String| {
        Err(Error::runtime(format!(
            "XDMF attribute '{}': {why}",
            a.name
        )))
    };
    let want_rows = match a.center {
        Center::Node => mesh.n_nodes,
        Center::Cell => mesh.n_elems,
    };
    if a.n_rows != want_rows {
        return bad(format!(
            "{} rows, the mesh has {want_rows} {:?}s",
            a.n_rows, a.center
        ));
    }
    if a.n_cols != a.kind.n_cols() {
        return bad(format!("{} columns for a {}", a.n_cols, a.kind.xdmf()));
    }
    match (a.number_type.as_str(), a.precision) {
        ("Float", 4 | 8) | ("Int", 4 | 8) | ("UInt", 4 | 8) => {}
        (t, p) => return bad(format!("number type {t} precision {p}")),
    }
    if a.name.is_empty() || !a.h5_path.starts_with('/') {
        return bad(format!("empty name or relative HDF5 path {:?}", a.h5_path));
    }
    Ok(())
}

/// Moving geometry drawn beside the mesh (a rigid wall's surface, a reference point, a
/// traced point's path so far): cells of one kind (points, segments or triangles) and
/// points at every output step. The cells may be one dataset every step shares or grow
/// from step to step (a path).
#[derive(Debug, Clone, PartialEq)]
pub struct XdmfGrid {
    /// The grid's name (ParaView's block name).
    pub name: String,
    /// 1 (Polyvertex), 2 (Polyline segments) or 3 (Triangle).
    pub nodes_per_cell: u64,
    /// Its datasets at each step (same order as the steps).
    pub steps: Vec<GridAt>,
}

/// An [`XdmfGrid`] at one step: HDF5 paths of its points, f64 `(n_points, 3)`, and of
/// its cells, i64 `(n_cells, nodes_per_cell)`, 0-based into the points.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GridAt {
    pub points: String,
    pub n_points: u64,
    pub cells: String,
    pub n_cells: u64,
}

/// The whole XDMF document for `steps` (pure: no I/O).
pub fn xdmf_text(mesh: &XdmfMesh, steps: &[XdmfStep]) -> Result<String> {
    xdmf_text_with_grids(mesh, steps, &[])
}

/// A block's rows of a dataset: the whole dataset, or (where the mesh has several parts)
/// the part's rows `[start, start + count)` of it, as an XDMF hyperslab.
#[derive(Clone, Copy)]
struct Rows {
    start: u64,
    count: u64,
    /// Rows of the whole dataset; `count == total` means the whole of it.
    total: u64,
}

impl Rows {
    fn all(total: u64) -> Self {
        Rows {
            start: 0,
            count: total,
            total,
        }
    }
}

/// A DataItem for `rows` of the `n_cols`-column dataset `path` of file `h5`.
#[allow(clippy::too_many_arguments)]
fn data_rows(
    out: &mut String,
    indent: &str,
    h5: &str,
    path: &str,
    rows: Rows,
    n_cols: u64,
    number_type: &str,
    precision: u8,
) {
    if rows.count == rows.total {
        let d = dims(rows.total, n_cols);
        return data_item(out, indent, h5, path, &d, number_type, precision);
    }
    let (sel_dims, sel) = if n_cols == 1 {
        ("3 1", format!("{} 1 {}", rows.start, rows.count))
    } else {
        (
            "3 2",
            format!("{} 0 1 1 {} {n_cols}", rows.start, rows.count),
        )
    };
    let _ = writeln!(
        out,
        "{indent}<DataItem ItemType=\"HyperSlab\" Type=\"HyperSlab\" Dimensions=\"{}\" \
         NumberType=\"{number_type}\" Precision=\"{precision}\">",
        dims(rows.count, n_cols)
    );
    let _ = writeln!(
        out,
        "{indent}  <DataItem Dimensions=\"{sel_dims}\" Format=\"XML\">{sel}</DataItem>"
    );
    let whole = dims(rows.total, n_cols);
    data_item(
        out,
        &format!("{indent}  "),
        h5,
        path,
        &whole,
        number_type,
        precision,
    );
    let _ = writeln!(out, "{indent}</DataItem>");
}

/// One attribute of a block; cell attributes take the block's `cells` rows.
fn block_attribute(out: &mut String, h5: &str, cells: Rows, a: &XdmfAttr) {
    let center = match a.center {
        Center::Node => "Node",
        Center::Cell => "Cell",
    };
    let _ = writeln!(
        out,
        "        <Attribute Name=\"{}\" AttributeType=\"{}\" Center=\"{center}\">",
        esc(&a.name),
        a.kind.xdmf()
    );
    let rows = match a.center {
        Center::Node => Rows::all(a.n_rows),
        Center::Cell => cells,
    };
    let ind = "          ";
    data_rows(
        out,
        ind,
        h5,
        &a.h5_path,
        rows,
        a.n_cols,
        &a.number_type,
        a.precision,
    );
    let _ = writeln!(out, "        </Attribute>");
}

/// Part `p`'s grid at step `s`: every node (the coordinates and node fields are whole
/// datasets), the part's cells and their rows of the cell fields.
fn part_grid(out: &mut String, mesh: &XdmfMesh, part: &XdmfPart, s: &XdmfStep) {
    let h5 = s.h5_file.as_deref().unwrap_or(&mesh.h5_file_name);
    let whole = mesh.parts.len() <= 1;
    let cells = if whole {
        Rows::all(mesh.n_elems)
    } else {
        Rows {
            start: part.cells.0,
            count: part.cells.1,
            total: mesh.n_elems,
        }
    };
    let ind = "          ";
    let _ = writeln!(
        out,
        "      <Grid Name=\"{}\" GridType=\"Uniform\">",
        esc(&part.name)
    );
    let _ = writeln!(out, "        <Time Value=\"{:?}\"/>", s.time);
    out.push_str("        <Geometry GeometryType=\"XYZ\">\n");
    data_item(
        out,
        ind,
        h5,
        COORDINATES,
        &dims(mesh.n_nodes, 3),
        "Float",
        8,
    );
    out.push_str("        </Geometry>\n");
    let (topo_type, topo_rows, cols) = match mesh.topology {
        XdmfTopology::Hexahedron => ("Hexahedron", cells, 8),
        XdmfTopology::Tetrahedron => ("Tetrahedron", cells, 4),
        XdmfTopology::Tetrahedron10 => ("Tetrahedron_10", cells, 10),
        XdmfTopology::Mixed { n_entries } if whole => ("Mixed", Rows::all(n_entries), 1),
        XdmfTopology::Mixed { n_entries } => (
            "Mixed",
            Rows {
                start: part.entries.0,
                count: part.entries.1,
                total: n_entries,
            },
            1,
        ),
    };
    let _ = writeln!(
        out,
        "        <Topology TopologyType=\"{topo_type}\" NumberOfElements=\"{}\">",
        cells.count
    );
    data_rows(out, ind, h5, CONNECTIVITY, topo_rows, cols, "Int", 8);
    out.push_str("        </Topology>\n");
    for a in mesh.static_cell_attrs.iter().chain(&s.attrs) {
        block_attribute(out, h5, cells, a);
    }
    out.push_str("      </Grid>\n");
}

/// Grid `w` (a wall's surface, a traced point) at step `i`.
fn moving_grid(out: &mut String, mesh: &XdmfMesh, w: &XdmfGrid, i: usize, s: &XdmfStep) {
    let h5 = s.h5_file.as_deref().unwrap_or(&mesh.h5_file_name);
    let at = &w.steps[i];
    let ind = "          ";
    let _ = writeln!(
        out,
        "      <Grid Name=\"{}\" GridType=\"Uniform\">",
        esc(&w.name)
    );
    let _ = writeln!(out, "        <Time Value=\"{:?}\"/>", s.time);
    let topology = match w.nodes_per_cell {
        3 => "TopologyType=\"Triangle\"",
        2 => "TopologyType=\"Polyline\" NodesPerElement=\"2\"",
        _ => "TopologyType=\"Polyvertex\" NodesPerElement=\"1\"",
    };
    let _ = writeln!(
        out,
        "        <Topology {topology} NumberOfElements=\"{}\">",
        at.n_cells
    );
    let cells = dims(at.n_cells, w.nodes_per_cell);
    data_item(out, ind, h5, &at.cells, &cells, "Int", 8);
    out.push_str("        </Topology>\n        <Geometry GeometryType=\"XYZ\">\n");
    data_item(out, ind, h5, &at.points, &dims(at.n_points, 3), "Float", 8);
    out.push_str("        </Geometry>\n      </Grid>\n");
}

fn check_grids(mesh: &XdmfMesh, steps: &[XdmfStep], grids: &[XdmfGrid]) -> Result<()> {
    for a in mesh
        .static_cell_attrs
        .iter()
        .chain(steps.iter().flat_map(|s| &s.attrs))
    {
        check_attr(mesh, a)?;
    }
    if let Some(s) = steps.iter().find(|s| !s.time.is_finite()) {
        return Err(Error::runtime(format!(
            "XDMF: step time {} is not finite",
            s.time
        )));
    }
    let covered: u64 = mesh.parts.iter().map(|p| p.cells.1).sum();
    if mesh.parts.len() > 1 && covered != mesh.n_elems {
        return Err(Error::runtime(format!(
            "XDMF: the parts have {covered} cells, the mesh {}",
            mesh.n_elems
        )));
    }
    for w in grids {
        if w.steps.len() != steps.len() {
            return Err(Error::runtime(format!(
                "XDMF grid '{}': points for {} steps, there are {}",
                w.name,
                w.steps.len(),
                steps.len()
            )));
        }
        if w.name.is_empty()
            || w.steps
                .iter()
                .any(|a| !a.cells.starts_with('/') || !a.points.starts_with('/'))
            || !(1..=3).contains(&w.nodes_per_cell)
        {
            return Err(Error::runtime(format!(
                "XDMF grid '{}': empty name, relative HDF5 path or {} points per cell",
                w.name, w.nodes_per_cell
            )));
        }
    }
    Ok(())
}

/// The document: one spatial collection of blocks, each block (a part, a wall, an
/// entity, a traced point) a temporal collection of its grids at the output steps.
///
/// Blocks over time, not time over blocks: ParaView's "XDMF Reader" then names every
/// block after its collection (the part or wall name) at every step. (Time over blocks,
/// alfe's earlier layout, made the Xdmf3 readers rename each step's grids uniquely
/// across the file, `mesh[20]`; the Xdmf3 readers leave collections unnamed in either
/// layout, and read a part's rows of a cell field only when the model has one part, so
/// the manual's ParaView chapter names "XDMF Reader".) A part's block holds every node
/// (unused ones are not drawn) and its own cells: the file keeps each part's cells
/// contiguous, so that a block is a hyperslab of each cell dataset, written once.
pub fn xdmf_text_with_grids(
    mesh: &XdmfMesh,
    steps: &[XdmfStep],
    grids: &[XdmfGrid],
) -> Result<String> {
    check_grids(mesh, steps, grids)?;
    let mut out = String::new();
    out.push_str("<?xml version=\"1.0\" encoding=\"utf-8\"?>\n");
    out.push_str("<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n");
    out.push_str("<Xdmf xmlns:xi=\"http://www.w3.org/2001/XInclude\" Version=\"3.0\">\n");
    out.push_str("  <Domain>\n");
    out.push_str("  <Grid Name=\"model\" GridType=\"Collection\" CollectionType=\"Spatial\">\n");
    let whole = [XdmfPart {
        name: "mesh".into(),
        cells: (0, mesh.n_elems),
        entries: (0, 0),
    }];
    let parts = if mesh.parts.is_empty() {
        &whole[..]
    } else {
        &mesh.parts[..]
    };
    let collection = |out: &mut String, name: &str| {
        let _ = writeln!(
            out,
            "    <Grid Name=\"{}\" GridType=\"Collection\" CollectionType=\"Temporal\">",
            esc(name)
        );
    };
    for part in parts.iter().filter(|p| p.cells.1 > 0) {
        collection(&mut out, &part.name);
        for s in steps {
            part_grid(&mut out, mesh, part, s);
        }
        out.push_str("    </Grid>\n");
    }
    for w in grids {
        collection(&mut out, &w.name);
        for (i, s) in steps.iter().enumerate() {
            moving_grid(&mut out, mesh, w, i, s);
        }
        out.push_str("    </Grid>\n");
    }
    out.push_str("  </Grid>\n  </Domain>\n</Xdmf>\n");
    Ok(out)
}

/// Write (atomically: a temporary file beside it, then rename) the whole `.xmf` for
/// the steps so far. Called by rank 0 after each output step, so that a run that
/// stops early still leaves a valid file describing what was written.
pub fn write_xdmf(path: &Path, mesh: &XdmfMesh, steps: &[XdmfStep]) -> Result<()> {
    write_xdmf_with_grids(path, mesh, steps, &[])
}

/// [`write_xdmf`] with moving geometry drawn beside the mesh ([`xdmf_text_with_grids`]).
pub fn write_xdmf_with_grids(
    path: &Path,
    mesh: &XdmfMesh,
    steps: &[XdmfStep],
    grids: &[XdmfGrid],
) -> Result<()> {
    let text = xdmf_text_with_grids(mesh, steps, grids)?;
    let name = path
        .file_name()
        .ok_or_else(|| Error::runtime(format!("XDMF path {} has no file name", path.display())))?;
    let mut tmp_name = name.to_os_string();
    tmp_name.push(".tmp");
    let tmp = path.with_file_name(tmp_name);
    let ctx = |e: std::io::Error| Error::runtime(format!("XDMF {}: {e}", path.display()));
    {
        let mut f = std::fs::File::create(&tmp).map_err(ctx)?;
        f.write_all(text.as_bytes()).map_err(ctx)?;
        f.sync_all().map_err(ctx)?;
    }
    std::fs::rename(&tmp, path).map_err(ctx)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::testutil::{python_json, temp_dir};
    use crate::output::H5File;
    use crate::parallel::SerialComm;

    fn attr(name: &str, center: Center, kind: AttrKind, path: &str, n_rows: u64) -> XdmfAttr {
        XdmfAttr {
            name: name.into(),
            center,
            kind,
            h5_path: path.into(),
            n_rows,
            n_cols: kind.n_cols(),
            number_type: "Float".into(),
            precision: 8,
        }
    }

    fn step(time: f64, attrs: Vec<XdmfAttr>) -> XdmfStep {
        XdmfStep {
            time,
            attrs,
            h5_file: None,
        }
    }

    /// Parse the .xmf as XML and resolve every DataItem in the HDF5 file it names:
    /// report the blocks (temporal collections in one spatial collection) and their
    /// grids, and for each DataItem its dataset, the rows it selects and whether the
    /// dataset exists with exactly the declared dimensions, a matching number type and
    /// (a hyperslab) the selection inside it.
    const CHECK: &str = r#"
import sys, os, json, h5py
import xml.etree.ElementTree as ET
xmf = sys.argv[1]
root = ET.parse(xmf).getroot()
assert root.tag == "Xdmf" and root.get("Version") == "3.0"
top = root.find("Domain/Grid")
def item(d):
    slab = d.get("ItemType") == "HyperSlab"
    inner = d.findall("DataItem")[1] if slab else d
    fname, path = inner.text.strip().split(":", 1)
    dims = [int(x) for x in inner.get("Dimensions").split()]
    with h5py.File(os.path.join(os.path.dirname(xmf), fname), "r") as f:
        ds = f[path]
        kind = {"Float": "f", "Int": "i", "UInt": "u"}[inner.get("NumberType")]
        ok = list(ds.shape) == dims and ds.dtype.kind == kind \
             and ds.dtype.itemsize == int(inner.get("Precision"))
    rows = [0, dims[0]]
    if slab:
        sel = [int(x) for x in d.findall("DataItem")[0].text.split()]
        n = len(dims)
        start, count = sel[0], sel[2 * n]
        out = [int(x) for x in d.get("Dimensions").split()]
        ok = ok and out[0] == count and start + count <= dims[0] and out[1:] == dims[1:]
        rows = [start, count]
    return [fname + ":" + path, rows, ok]
out = {"top": [top.get("GridType"), top.get("CollectionType")], "blocks": []}
for b in top.findall("Grid"):
    block = {"name": b.get("Name"), "type": [b.get("GridType"), b.get("CollectionType")],
             "grids": []}
    for g in b.findall("Grid"):
        block["grids"].append({
            "name": g.get("Name"), "time": float(g.find("Time").get("Value")),
            "topology": [g.find("Topology").get("TopologyType"),
                         int(g.find("Topology").get("NumberOfElements"))],
            "attrs": [[a.get("Name"), a.get("AttributeType"), a.get("Center")]
                      for a in g.findall("Attribute")],
            "items": [item(d) for d in g.iter("DataItem")
                      if d.get("Format") == "HDF" and d not in
                      [x for s in g.iter("DataItem") if s.get("ItemType") == "HyperSlab"
                       for x in s.findall("DataItem")]
                      or d.get("ItemType") == "HyperSlab"]})
    out["blocks"].append(block)
print(json.dumps(out))
"#;

    /// A file of `n_nodes` nodes and two hexahedra with two steps of displacement,
    /// stress and von Mises, and the steps.
    fn two_steps(f: &H5File, n_nodes: u64, n_elems: u64) -> Vec<XdmfStep> {
        f.write_rows_f64(COORDINATES, n_nodes, 3, 0, &vec![0.0; 3 * n_nodes as usize])
            .unwrap();
        f.write_rows_i64(CONNECTIVITY, n_elems, 8, 0, &vec![0; 8 * n_elems as usize])
            .unwrap();
        f.write_rows_i32("/mesh/partition", n_elems, 1, 0, &vec![0; n_elems as usize])
            .unwrap();
        let mut steps = Vec::new();
        for (k, t) in [0.0, 0.5].into_iter().enumerate() {
            let g = format!("/steps/{k:06}");
            let n = n_nodes as usize;
            f.write_rows_f64(
                &format!("{g}/displacement"),
                n_nodes,
                3,
                0,
                &vec![1.0; 3 * n],
            )
            .unwrap();
            let e = n_elems as usize;
            f.write_rows_f64(&format!("{g}/stress"), n_elems, 6, 0, &vec![2.0; 6 * e])
                .unwrap();
            f.write_rows_f64(&format!("{g}/von_mises"), n_elems, 1, 0, &vec![3.0; e])
                .unwrap();
            f.write_attr_f64(&g, "time", t).unwrap();
            let (node, cell) = (Center::Node, Center::Cell);
            steps.push(step(
                t,
                vec![
                    attr(
                        "displacement",
                        node,
                        AttrKind::Vector,
                        &format!("{g}/displacement"),
                        n_nodes,
                    ),
                    attr(
                        "stress",
                        cell,
                        AttrKind::Tensor6,
                        &format!("{g}/stress"),
                        n_elems,
                    ),
                    attr(
                        "von_mises",
                        cell,
                        AttrKind::Scalar,
                        &format!("{g}/von_mises"),
                        n_elems,
                    ),
                ],
            ));
        }
        steps
    }

    fn mesh(n_nodes: u64, n_elems: u64, parts: Vec<XdmfPart>) -> XdmfMesh {
        XdmfMesh {
            h5_file_name: "run.h5".into(),
            n_nodes,
            n_elems,
            topology: XdmfTopology::Hexahedron,
            static_cell_attrs: vec![XdmfAttr {
                number_type: "Int".into(),
                precision: 4,
                ..attr(
                    "partition",
                    Center::Cell,
                    AttrKind::Scalar,
                    "/mesh/partition",
                    n_elems,
                )
            }],
            parts,
        }
    }

    fn part(name: &str, cells: (u64, u64)) -> XdmfPart {
        XdmfPart {
            name: name.into(),
            cells,
            entries: (0, 0),
        }
    }

    /// One part: one block named after it, a grid per step with its time, every
    /// DataItem the whole dataset (no hyperslab: every reader reads it).
    #[test]
    fn one_part_is_one_block_of_whole_datasets() {
        let dir = temp_dir("xdmf-match");
        let f = H5File::create(&SerialComm, &dir.join("run.h5")).unwrap();
        let steps = two_steps(&f, 12, 2);
        drop(f);
        let mesh = mesh(12, 2, vec![part("block", (0, 2))]);
        let xmf = dir.join("run.xmf");
        // After the first step, then again after the second (the file is rewritten whole).
        write_xdmf(&xmf, &mesh, &steps[..1]).unwrap();
        let j = python_json(CHECK, &[xmf.to_str().unwrap()]);
        assert_eq!(j["blocks"][0]["grids"].as_array().unwrap().len(), 1);
        write_xdmf(&xmf, &mesh, &steps).unwrap();
        assert!(!dir.join("run.xmf.tmp").exists());
        let j = python_json(CHECK, &[xmf.to_str().unwrap()]);
        assert_eq!(j["top"], serde_json::json!(["Collection", "Spatial"]));
        let blocks = j["blocks"].as_array().unwrap();
        assert_eq!(blocks.len(), 1);
        assert_eq!(blocks[0]["name"], "block");
        assert_eq!(
            blocks[0]["type"],
            serde_json::json!(["Collection", "Temporal"])
        );
        let grids = blocks[0]["grids"].as_array().unwrap();
        assert_eq!(grids.len(), 2);
        for (k, g) in grids.iter().enumerate() {
            assert_eq!(g["name"], "block");
            assert_eq!(g["time"], [0.0, 0.5][k]);
            assert_eq!(g["topology"], serde_json::json!(["Hexahedron", 2]));
            assert_eq!(
                g["attrs"],
                serde_json::json!([
                    ["partition", "Scalar", "Cell"],
                    ["displacement", "Vector", "Node"],
                    ["stress", "Matrix", "Cell"],
                    ["von_mises", "Scalar", "Cell"]
                ])
            );
            let s = format!("run.h5:/steps/{k:06}");
            assert_eq!(
                g["items"],
                serde_json::json!([
                    ["run.h5:/mesh/coordinates", [0, 12], true],
                    ["run.h5:/mesh/connectivity", [0, 2], true],
                    ["run.h5:/mesh/partition", [0, 2], true],
                    [format!("{s}/displacement"), [0, 12], true],
                    [format!("{s}/stress"), [0, 2], true],
                    [format!("{s}/von_mises"), [0, 2], true]
                ])
            );
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// Two parts: a block each, named after the part at every step, each the part's rows
    /// of every cell dataset (hyperslabs inside the dataset) and every node; a step of
    /// an earlier run's file refers to that file.
    #[test]
    fn parts_are_blocks_of_their_rows() {
        let dir = temp_dir("xdmf-parts");
        let f = H5File::create(&SerialComm, &dir.join("run.h5")).unwrap();
        let mut steps = two_steps(&f, 12, 3);
        drop(f);
        let mesh = mesh(12, 3, vec![part("lower", (0, 1)), part("upper", (1, 2))]);
        let xmf = dir.join("run.xmf");
        write_xdmf(&xmf, &mesh, &steps).unwrap();
        let j = python_json(CHECK, &[xmf.to_str().unwrap()]);
        let blocks = j["blocks"].as_array().unwrap();
        assert_eq!(blocks.len(), 2);
        for (b, (name, rows)) in blocks.iter().zip([("lower", [0, 1]), ("upper", [1, 2])]) {
            assert_eq!(b["name"], name);
            for (k, g) in b["grids"].as_array().unwrap().iter().enumerate() {
                assert_eq!(g["name"], name);
                assert_eq!(g["topology"], serde_json::json!(["Hexahedron", rows[1]]));
                let s = format!("run.h5:/steps/{k:06}");
                assert_eq!(
                    g["items"],
                    serde_json::json!([
                        ["run.h5:/mesh/coordinates", [0, 12], true],
                        ["run.h5:/mesh/connectivity", rows, true],
                        ["run.h5:/mesh/partition", rows, true],
                        [format!("{s}/displacement"), [0, 12], true],
                        [format!("{s}/stress"), rows, true],
                        [format!("{s}/von_mises"), rows, true]
                    ])
                );
            }
        }
        // Parts must cover the mesh.
        let short = XdmfMesh {
            parts: vec![part("lower", (0, 1)), part("upper", (1, 1))],
            ..mesh.clone()
        };
        let e = xdmf_text(&short, &steps).unwrap_err();
        assert!(
            e.message.contains("the parts have 2 cells, the mesh 3"),
            "{e}"
        );
        // A step in another file: every DataItem of it names that file.
        steps[0].h5_file = Some("../first/run.h5".into());
        let t = xdmf_text(&mesh, &steps).unwrap();
        let first = t
            .split("<Grid Name=\"upper\" GridType=\"Uniform\">")
            .nth(1)
            .unwrap();
        let first = first.split("</Grid>").next().unwrap();
        assert_eq!(first.matches("../first/run.h5:").count(), 6, "{first}");
        assert!(!first.contains(">run.h5:"), "{first}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn walls_are_blocks_of_their_own() {
        let dir = temp_dir("xdmf-walls");
        let (n_nodes, n_elems) = (8u64, 1u64);
        let f = H5File::create(&SerialComm, &dir.join("run.h5")).unwrap();
        f.write_rows_f64(COORDINATES, n_nodes, 3, 0, &[0.0; 24])
            .unwrap();
        f.write_rows_i64(CONNECTIVITY, n_elems, 8, 0, &[0, 1, 2, 3, 4, 5, 6, 7])
            .unwrap();
        f.write_rows_i64("/walls/floor/triangles", 2, 3, 0, &[0, 1, 2, 0, 2, 3])
            .unwrap();
        let mut wall = XdmfGrid {
            name: "wall_floor".into(),
            nodes_per_cell: 3,
            steps: Vec::new(),
        };
        let mut steps = Vec::new();
        for (k, t) in [0.5, 1.0].into_iter().enumerate() {
            let g = format!("/steps/{:06}", k + 1);
            f.write_rows_f64(&format!("{g}/displacement"), n_nodes, 3, 0, &[0.0; 24])
                .unwrap();
            f.write_rows_f64(&format!("{g}/walls/floor/points"), 4, 3, 0, &[t; 12])
                .unwrap();
            wall.steps.push(GridAt {
                points: format!("{g}/walls/floor/points"),
                n_points: 4,
                cells: "/walls/floor/triangles".into(),
                n_cells: 2,
            });
            let d = format!("{g}/displacement");
            steps.push(step(
                t,
                vec![attr(
                    "displacement",
                    Center::Node,
                    AttrKind::Vector,
                    &d,
                    n_nodes,
                )],
            ));
        }
        drop(f);
        let mesh = XdmfMesh {
            static_cell_attrs: vec![],
            ..mesh(n_nodes, n_elems, vec![])
        };
        let xmf = dir.join("run.xmf");
        write_xdmf_with_grids(&xmf, &mesh, &steps, std::slice::from_ref(&wall)).unwrap();
        let j = python_json(CHECK, &[xmf.to_str().unwrap()]);
        let blocks = j["blocks"].as_array().unwrap();
        assert_eq!(blocks.len(), 2);
        assert_eq!(blocks[0]["name"], "mesh");
        assert_eq!(blocks[1]["name"], "wall_floor");
        for (k, g) in blocks[1]["grids"].as_array().unwrap().iter().enumerate() {
            let s = format!("run.h5:/steps/{:06}", k + 1);
            let time = [0.5, 1.0][k];
            assert_eq!(
                g,
                &serde_json::json!({
                    "name": "wall_floor", "time": time,
                    "topology": ["Triangle", 2], "attrs": [],
                    "items": [["run.h5:/walls/floor/triangles", [0, 2], true],
                              [format!("{s}/walls/floor/points"), [0, 4], true]]})
            );
        }
        // A wall must have points for every step.
        wall.steps.pop();
        let e = xdmf_text_with_grids(&mesh, &steps, &[wall]).unwrap_err();
        assert!(e.message.contains("points for 1 steps, there are 2"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn topologies_escaping_and_validation() {
        let mut mesh = XdmfMesh {
            h5_file_name: "a&b.h5".into(),
            n_nodes: 5,
            n_elems: 2,
            topology: XdmfTopology::Tetrahedron,
            static_cell_attrs: vec![],
            parts: vec![],
        };
        let steps = vec![step(
            2.0,
            vec![attr("p<1>", Center::Node, AttrKind::Scalar, "/s/p", 5)],
        )];
        let t = xdmf_text(&mesh, &steps).unwrap();
        assert!(
            t.contains("TopologyType=\"Tetrahedron\" NumberOfElements=\"2\""),
            "{t}"
        );
        assert!(t.contains("Dimensions=\"2 4\""), "{t}");
        assert!(
            t.contains("a&amp;b.h5:/s/p") && t.contains("Name=\"p&lt;1&gt;\""),
            "{t}"
        );
        assert!(t.contains("<Time Value=\"2.0\"/>"), "{t}");

        mesh.topology = XdmfTopology::Mixed { n_entries: 14 };
        let t = xdmf_text(&mesh, &steps).unwrap();
        assert!(
            t.contains("TopologyType=\"Mixed\" NumberOfElements=\"2\""),
            "{t}"
        );
        assert!(t.contains("Dimensions=\"14\" NumberType=\"Int\" Precision=\"8\" Format=\"HDF\">a&amp;b.h5:/mesh/connectivity"), "{t}");
        // A part of a mixed mesh: its entries of the connectivity.
        mesh.parts = vec![
            XdmfPart {
                name: "a".into(),
                cells: (0, 1),
                entries: (0, 5),
            },
            XdmfPart {
                name: "b".into(),
                cells: (1, 1),
                entries: (5, 9),
            },
        ];
        let t = xdmf_text(&mesh, &steps).unwrap();
        assert!(t.contains(">5 1 9</DataItem>"), "{t}");

        // No steps yet: still a valid document, its blocks empty.
        let t = xdmf_text(&mesh, &[]).unwrap();
        assert!(
            t.contains("CollectionType=\"Temporal\">\n    </Grid>"),
            "{t}"
        );

        let bad_rows = vec![step(
            0.0,
            vec![attr("u", Center::Node, AttrKind::Vector, "/s/u", 2)],
        )];
        let e = xdmf_text(&mesh, &bad_rows).unwrap_err();
        assert!(
            e.message.contains("'u'") && e.message.contains("2 rows"),
            "{e}"
        );
        let mut bad_cols = attr("s", Center::Cell, AttrKind::Tensor6, "/s/s", 2);
        bad_cols.n_cols = 9;
        let e = xdmf_text(&mesh, &[step(0.0, vec![bad_cols])]).unwrap_err();
        assert!(e.message.contains("9 columns"), "{e}");
        let e = xdmf_text(&mesh, &[step(f64::NAN, vec![])]).unwrap_err();
        assert!(e.message.contains("not finite"), "{e}");
    }
}
