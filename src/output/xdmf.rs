//! The XDMF3 text file beside the HDF5 file: what ParaView opens (`Xdmf3ReaderS`).
//!
//! One temporal collection, one uniform grid per output step. Every grid repeats the
//! Geometry and Topology `DataItem`s, pointing at the same HDF5 datasets: the data
//! live once on disk (the XDMF only references them), and plain repetition is read by
//! every XDMF reader, where `xpointer` references are not (DESIGN: robustness over a
//! few hundred bytes of text per step).
//!
//! Datasets the mesh part refers to, by convention (see [`COORDINATES`],
//! [`CONNECTIVITY`]): `/mesh/coordinates`, f64 `(n_nodes, 3)`, and
//! `/mesh/connectivity`, i64 `(n_elems, 8)` for hexahedra, `(n_elems, 4)` for
//! tetrahedra, or 1-D `(n_entries)` for a mixed mesh (per cell: the XDMF type id,
//! [`XDMF_HEXAHEDRON`] or [`XDMF_TETRAHEDRON`], then its node ids). Node ids are 0-based.

use crate::{Error, Result};
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

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Center {
    Node,
    Cell,
}

/// Shape of one attribute row: 1, 3 or 6 components.
/// `Tensor6` is xx, yy, zz, xy, yz, xz (XDMF's order, alfe's Voigt order).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
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
            AttrKind::Tensor6 => "Tensor6",
        }
    }
}

/// One attribute of a grid: a dataset of `n_rows` rows (nodes or cells) of `n_cols`.
#[derive(Debug, Clone, PartialEq)]
pub struct XdmfAttr {
    pub name: String,
    pub center: Center,
    pub kind: AttrKind,
    /// Absolute path inside the HDF5 file, e.g. "/steps/000003/displacement".
    pub h5_path: String,
    pub n_rows: u64,
    pub n_cols: u64,
    /// "Float" (precision 8) or "Int" (precision 4 or 8).
    pub number_type: &'static str,
    pub precision: u8,
}

/// One output step: its time and its attributes.
#[derive(Debug, Clone, PartialEq)]
pub struct XdmfStep {
    pub time: f64,
    pub attrs: Vec<XdmfAttr>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum XdmfTopology {
    Hexahedron,
    Tetrahedron,
    /// A 1-D mixed connectivity array of `n_entries` integers.
    Mixed { n_entries: u64 },
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
    let bad = |why: String| Err(Error::runtime(format!("XDMF attribute '{}': {why}", a.name)));
    let want_rows = match a.center {
        Center::Node => mesh.n_nodes,
        Center::Cell => mesh.n_elems,
    };
    if a.n_rows != want_rows {
        return bad(format!("{} rows, the mesh has {want_rows} {:?}s", a.n_rows, a.center));
    }
    if a.n_cols != a.kind.n_cols() {
        return bad(format!("{} columns for a {}", a.n_cols, a.kind.xdmf()));
    }
    match (a.number_type, a.precision) {
        ("Float", 4 | 8) | ("Int", 4 | 8) | ("UInt", 4 | 8) => {}
        (t, p) => return bad(format!("number type {t} precision {p}")),
    }
    if a.name.is_empty() || !a.h5_path.starts_with('/') {
        return bad(format!("empty name or relative HDF5 path {:?}", a.h5_path));
    }
    Ok(())
}

fn attribute(out: &mut String, h5: &str, a: &XdmfAttr) {
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
    data_item(
        out,
        "          ",
        h5,
        &a.h5_path,
        &dims(a.n_rows, a.n_cols),
        a.number_type,
        a.precision,
    );
    out.push_str("        </Attribute>\n");
}

/// The whole XDMF document for `steps` (pure: no I/O).
pub fn xdmf_text(mesh: &XdmfMesh, steps: &[XdmfStep]) -> Result<String> {
    for a in mesh.static_cell_attrs.iter().chain(steps.iter().flat_map(|s| &s.attrs)) {
        check_attr(mesh, a)?;
    }
    if let Some(s) = steps.iter().find(|s| !s.time.is_finite()) {
        return Err(Error::runtime(format!("XDMF: step time {} is not finite", s.time)));
    }
    let h5 = mesh.h5_file_name.as_str();
    let (topo_type, topo_dims) = match mesh.topology {
        XdmfTopology::Hexahedron => ("Hexahedron", dims(mesh.n_elems, 8)),
        XdmfTopology::Tetrahedron => ("Tetrahedron", dims(mesh.n_elems, 4)),
        XdmfTopology::Mixed { n_entries } => ("Mixed", dims(n_entries, 1)),
    };
    let mut out = String::new();
    out.push_str("<?xml version=\"1.0\" encoding=\"utf-8\"?>\n");
    out.push_str("<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n");
    out.push_str("<Xdmf xmlns:xi=\"http://www.w3.org/2001/XInclude\" Version=\"3.0\">\n");
    out.push_str("  <Domain>\n");
    out.push_str("    <Grid Name=\"TimeSeries\" GridType=\"Collection\" CollectionType=\"Temporal\">\n");
    for (i, s) in steps.iter().enumerate() {
        let _ = writeln!(out, "      <Grid Name=\"step_{i:06}\" GridType=\"Uniform\">");
        let _ = writeln!(out, "        <Time Value=\"{:?}\"/>", s.time);
        out.push_str("        <Geometry GeometryType=\"XYZ\">\n");
        data_item(&mut out, "          ", h5, COORDINATES, &dims(mesh.n_nodes, 3), "Float", 8);
        out.push_str("        </Geometry>\n");
        let _ = writeln!(
            out,
            "        <Topology TopologyType=\"{topo_type}\" NumberOfElements=\"{}\">",
            mesh.n_elems
        );
        data_item(&mut out, "          ", h5, CONNECTIVITY, &topo_dims, "Int", 8);
        out.push_str("        </Topology>\n");
        for a in &mesh.static_cell_attrs {
            attribute(&mut out, h5, a);
        }
        for a in &s.attrs {
            attribute(&mut out, h5, a);
        }
        out.push_str("      </Grid>\n");
    }
    out.push_str("    </Grid>\n  </Domain>\n</Xdmf>\n");
    Ok(out)
}

/// Write (atomically: a temporary file beside it, then rename) the whole `.xmf` for
/// the steps so far. Called by rank 0 after each output step, so that a run that
/// stops early still leaves a valid file describing what was written.
pub fn write_xdmf(path: &Path, mesh: &XdmfMesh, steps: &[XdmfStep]) -> Result<()> {
    let text = xdmf_text(mesh, steps)?;
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
