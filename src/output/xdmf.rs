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
//! tetrahedra, `(n_elems, 10)` for quadratic tetrahedra (VTK's node order), or 1-D `(n_entries)` for a mixed mesh (per cell: the XDMF type id,
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
/// XDMF cell type id of a 10-node tetrahedron (`Tetrahedron_10`) in a `Mixed` array.
/// Its midside nodes are in VTK's order: edges 0-1, 1-2, 2-0, 0-3, 1-3, 2-3.
pub const XDMF_TETRAHEDRON_10: i64 = 38;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
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
            AttrKind::Tensor6 => "Matrix",
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
    match (a.number_type, a.precision) {
        ("Float", 4 | 8) | ("Int", 4 | 8) | ("UInt", 4 | 8) => {}
        (t, p) => return bad(format!("number type {t} precision {p}")),
    }
    if a.name.is_empty() || !a.h5_path.starts_with('/') {
        return bad(format!("empty name or relative HDF5 path {:?}", a.h5_path));
    }
    Ok(())
}

/// One attribute, indented by `pad` more than a grid directly in the time series.
fn attribute(out: &mut String, pad: &str, h5: &str, a: &XdmfAttr) {
    let center = match a.center {
        Center::Node => "Node",
        Center::Cell => "Cell",
    };
    let _ = writeln!(
        out,
        "{pad}        <Attribute Name=\"{}\" AttributeType=\"{}\" Center=\"{center}\">",
        esc(&a.name),
        a.kind.xdmf()
    );
    data_item(
        out,
        &format!("{pad}          "),
        h5,
        &a.h5_path,
        &dims(a.n_rows, a.n_cols),
        a.number_type,
        a.precision,
    );
    let _ = writeln!(out, "{pad}        </Attribute>");
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
#[derive(Debug, Clone, PartialEq)]
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

/// The mesh grid of one step, indented by `pad` more than a grid directly in the time
/// series; `time` is written inside it when given.
fn mesh_grid(
    out: &mut String,
    pad: &str,
    name: &str,
    time: Option<f64>,
    mesh: &XdmfMesh,
    s: &XdmfStep,
) {
    let h5 = mesh.h5_file_name.as_str();
    let (topo_type, topo_dims) = match mesh.topology {
        XdmfTopology::Hexahedron => ("Hexahedron", dims(mesh.n_elems, 8)),
        XdmfTopology::Tetrahedron => ("Tetrahedron", dims(mesh.n_elems, 4)),
        XdmfTopology::Tetrahedron10 => ("Tetrahedron_10", dims(mesh.n_elems, 10)),
        XdmfTopology::Mixed { n_entries } => ("Mixed", dims(n_entries, 1)),
    };
    let inner = format!("{pad}          ");
    let _ = writeln!(
        out,
        "{pad}      <Grid Name=\"{}\" GridType=\"Uniform\">",
        esc(name)
    );
    if let Some(t) = time {
        let _ = writeln!(out, "{pad}        <Time Value=\"{t:?}\"/>");
    }
    let _ = writeln!(out, "{pad}        <Geometry GeometryType=\"XYZ\">");
    data_item(
        out,
        &inner,
        h5,
        COORDINATES,
        &dims(mesh.n_nodes, 3),
        "Float",
        8,
    );
    let _ = writeln!(out, "{pad}        </Geometry>");
    let _ = writeln!(
        out,
        "{pad}        <Topology TopologyType=\"{topo_type}\" NumberOfElements=\"{}\">",
        mesh.n_elems
    );
    data_item(out, &inner, h5, CONNECTIVITY, &topo_dims, "Int", 8);
    let _ = writeln!(out, "{pad}        </Topology>");
    for a in &mesh.static_cell_attrs {
        attribute(out, pad, h5, a);
    }
    for a in &s.attrs {
        attribute(out, pad, h5, a);
    }
    let _ = writeln!(out, "{pad}      </Grid>");
}

/// [`xdmf_text`] with moving geometry: each step becomes a spatial collection of the
/// mesh grid and one grid per [`XdmfGrid`] at that step's position. Without grids the
/// document is exactly [`xdmf_text`]'s (one uniform grid per step).
pub fn xdmf_text_with_grids(
    mesh: &XdmfMesh,
    steps: &[XdmfStep],
    grids: &[XdmfGrid],
) -> Result<String> {
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
    let h5 = mesh.h5_file_name.as_str();
    let mut out = String::new();
    out.push_str("<?xml version=\"1.0\" encoding=\"utf-8\"?>\n");
    out.push_str("<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n");
    out.push_str("<Xdmf xmlns:xi=\"http://www.w3.org/2001/XInclude\" Version=\"3.0\">\n");
    out.push_str("  <Domain>\n");
    out.push_str(
        "    <Grid Name=\"TimeSeries\" GridType=\"Collection\" CollectionType=\"Temporal\">\n",
    );
    for (i, s) in steps.iter().enumerate() {
        let name = format!("step_{i:06}");
        if grids.is_empty() {
            mesh_grid(&mut out, "", &name, Some(s.time), mesh, s);
            continue;
        }
        let _ = writeln!(
            out,
            "      <Grid Name=\"{name}\" GridType=\"Collection\" CollectionType=\"Spatial\">"
        );
        let _ = writeln!(out, "        <Time Value=\"{:?}\"/>", s.time);
        mesh_grid(&mut out, "  ", "mesh", None, mesh, s);
        for w in grids {
            let at = &w.steps[i];
            let _ = writeln!(
                out,
                "        <Grid Name=\"{}\" GridType=\"Uniform\">",
                esc(&w.name)
            );
            let topology = match w.nodes_per_cell {
                3 => "TopologyType=\"Triangle\"",
                2 => "TopologyType=\"Polyline\" NodesPerElement=\"2\"",
                _ => "TopologyType=\"Polyvertex\" NodesPerElement=\"1\"",
            };
            let _ = writeln!(
                out,
                "          <Topology {topology} NumberOfElements=\"{}\">",
                at.n_cells
            );
            data_item(
                &mut out,
                "            ",
                h5,
                &at.cells,
                &dims(at.n_cells, w.nodes_per_cell),
                "Int",
                8,
            );
            out.push_str("          </Topology>\n");
            out.push_str("          <Geometry GeometryType=\"XYZ\">\n");
            data_item(
                &mut out,
                "            ",
                h5,
                &at.points,
                &dims(at.n_points, 3),
                "Float",
                8,
            );
            out.push_str("          </Geometry>\n");
            out.push_str("        </Grid>\n");
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
            number_type: "Float",
            precision: 8,
        }
    }

    /// Parse the .xmf as XML and resolve every DataItem in the HDF5 file beside it:
    /// report the grids, and for each DataItem whether the dataset exists with exactly
    /// the declared dimensions and a matching number type.
    const CHECK: &str = r#"
import sys, os, json, h5py
import xml.etree.ElementTree as ET
xmf = sys.argv[1]
root = ET.parse(xmf).getroot()
assert root.tag == "Xdmf" and root.get("Version") == "3.0"
coll = root.find("Domain/Grid")
out = {"collection": [coll.get("GridType"), coll.get("CollectionType")], "grids": []}
for g in coll.findall("Grid"):
    grid = {"name": g.get("Name"), "time": float(g.find("Time").get("Value")),
            "geometry": g.find("Geometry").get("GeometryType"),
            "topology": [g.find("Topology").get("TopologyType"),
                         int(g.find("Topology").get("NumberOfElements"))],
            "attrs": [], "items": []}
    for a in g.findall("Attribute"):
        grid["attrs"].append([a.get("Name"), a.get("AttributeType"), a.get("Center")])
    for d in g.iter("DataItem"):
        fname, path = d.text.strip().split(":", 1)
        dims = [int(x) for x in d.get("Dimensions").split()]
        with h5py.File(os.path.join(os.path.dirname(xmf), fname), "r") as f:
            ds = f[path]
            kind = {"Float": "f", "Int": "i", "UInt": "u"}[d.get("NumberType")]
            ok = list(ds.shape) == dims and ds.dtype.kind == kind \
                 and ds.dtype.itemsize == int(d.get("Precision"))
        grid["items"].append([path, dims, ok])
    out["grids"].append(grid)
print(json.dumps(out))
"#;

    #[test]
    fn xdmf_is_well_formed_and_matches_the_hdf5_datasets() {
        let dir = temp_dir("xdmf-match");
        let h5 = dir.join("run.h5");
        let (n_nodes, n_elems) = (12u64, 2u64);
        let f = H5File::create(&SerialComm, &h5).unwrap();
        f.write_rows_f64(COORDINATES, n_nodes, 3, 0, &vec![0.0; 36])
            .unwrap();
        f.write_rows_i64(CONNECTIVITY, n_elems, 8, 0, &[0; 16])
            .unwrap();
        f.write_rows_i32("/mesh/partition", n_elems, 1, 0, &[0, 1])
            .unwrap();
        let mut steps = Vec::new();
        for (k, t) in [0.5, 1.0e-7].into_iter().enumerate() {
            let g = format!("/steps/{k:06}");
            f.write_rows_f64(&format!("{g}/displacement"), n_nodes, 3, 0, &[1.0; 36])
                .unwrap();
            f.write_rows_f64(&format!("{g}/stress"), n_elems, 6, 0, &[2.0; 12])
                .unwrap();
            f.write_rows_f64(&format!("{g}/von_mises"), n_elems, 1, 0, &[3.0; 2])
                .unwrap();
            f.write_attr_f64(&g, "time", t).unwrap();
            steps.push(XdmfStep {
                time: t,
                attrs: vec![
                    attr(
                        "displacement",
                        Center::Node,
                        AttrKind::Vector,
                        &format!("{g}/displacement"),
                        n_nodes,
                    ),
                    attr(
                        "stress",
                        Center::Cell,
                        AttrKind::Tensor6,
                        &format!("{g}/stress"),
                        n_elems,
                    ),
                    attr(
                        "von_mises",
                        Center::Cell,
                        AttrKind::Scalar,
                        &format!("{g}/von_mises"),
                        n_elems,
                    ),
                ],
            });
        }
        drop(f);
        let mesh = XdmfMesh {
            h5_file_name: "run.h5".into(),
            n_nodes,
            n_elems,
            topology: XdmfTopology::Hexahedron,
            static_cell_attrs: vec![XdmfAttr {
                number_type: "Int",
                precision: 4,
                ..attr(
                    "partition",
                    Center::Cell,
                    AttrKind::Scalar,
                    "/mesh/partition",
                    n_elems,
                )
            }],
        };
        let xmf = dir.join("run.xmf");
        // After the first step, then again after the second (the file is rewritten whole).
        write_xdmf(&xmf, &mesh, &steps[..1]).unwrap();
        let j = python_json(CHECK, &[xmf.to_str().unwrap()]);
        assert_eq!(j["grids"].as_array().unwrap().len(), 1);
        write_xdmf(&xmf, &mesh, &steps).unwrap();
        assert!(!dir.join("run.xmf.tmp").exists());

        let j = python_json(CHECK, &[xmf.to_str().unwrap()]);
        assert_eq!(
            j["collection"],
            serde_json::json!(["Collection", "Temporal"])
        );
        let grids = j["grids"].as_array().unwrap();
        assert_eq!(grids.len(), 2);
        assert_eq!(grids[0]["time"], 0.5);
        assert_eq!(grids[1]["time"], 1.0e-7);
        for (k, g) in grids.iter().enumerate() {
            assert_eq!(g["geometry"], "XYZ");
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
            let s = format!("/steps/{k:06}");
            assert_eq!(
                g["items"],
                serde_json::json!([
                    ["/mesh/coordinates", [12, 3], true],
                    ["/mesh/connectivity", [2, 8], true],
                    ["/mesh/partition", [2], true],
                    [format!("{s}/displacement"), [12, 3], true],
                    [format!("{s}/stress"), [2, 6], true],
                    [format!("{s}/von_mises"), [2], true]
                ])
            );
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// The walls' layout: each step a spatial collection (with the time) of the mesh grid
    /// and one triangle grid per wall; every DataItem resolved in the HDF5 file.
    const CHECK_WALLS: &str = r#"
import sys, os, json, h5py
import xml.etree.ElementTree as ET
xmf = sys.argv[1]
coll = ET.parse(xmf).getroot().find("Domain/Grid")
out = []
for g in coll.findall("Grid"):
    step = {"type": [g.get("GridType"), g.get("CollectionType")],
            "time": float(g.find("Time").get("Value")), "grids": []}
    for c in g.findall("Grid"):
        items = []
        for d in c.iter("DataItem"):
            fname, path = d.text.strip().split(":", 1)
            dims = [int(x) for x in d.get("Dimensions").split()]
            with h5py.File(os.path.join(os.path.dirname(xmf), fname), "r") as f:
                ok = list(f[path].shape) == dims
            items.append([path, ok])
        step["grids"].append({"name": c.get("Name"), "type": c.get("GridType"),
            "topology": [c.find("Topology").get("TopologyType"),
                         int(c.find("Topology").get("NumberOfElements"))],
            "attrs": [a.get("Name") for a in c.findall("Attribute")],
            "time": c.find("Time") is not None, "items": items})
    out.append(step)
print(json.dumps(out))
"#;

    #[test]
    fn walls_make_each_step_a_spatial_collection() {
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
            steps.push(XdmfStep {
                time: t,
                attrs: vec![attr(
                    "displacement",
                    Center::Node,
                    AttrKind::Vector,
                    &format!("{g}/displacement"),
                    n_nodes,
                )],
            });
        }
        drop(f);
        let mesh = XdmfMesh {
            h5_file_name: "run.h5".into(),
            n_nodes,
            n_elems,
            topology: XdmfTopology::Hexahedron,
            static_cell_attrs: vec![],
        };
        // Without walls the document is the plain one.
        assert_eq!(
            xdmf_text_with_grids(&mesh, &steps, &[]).unwrap(),
            xdmf_text(&mesh, &steps).unwrap()
        );
        let xmf = dir.join("run.xmf");
        write_xdmf_with_grids(&xmf, &mesh, &steps, std::slice::from_ref(&wall)).unwrap();
        let j = python_json(CHECK_WALLS, &[xmf.to_str().unwrap()]);
        let j = j.as_array().unwrap();
        assert_eq!(j.len(), 2);
        for (k, s) in j.iter().enumerate() {
            let g = format!("/steps/{:06}", k + 1);
            assert_eq!(s["type"], serde_json::json!(["Collection", "Spatial"]));
            assert_eq!(s["time"], [0.5, 1.0][k]);
            assert_eq!(
                s["grids"],
                serde_json::json!([
                    {"name": "mesh", "type": "Uniform", "topology": ["Hexahedron", 1],
                     "attrs": ["displacement"], "time": false,
                     "items": [["/mesh/coordinates", true], ["/mesh/connectivity", true],
                               [format!("{g}/displacement"), true]]},
                    {"name": "wall_floor", "type": "Uniform", "topology": ["Triangle", 2],
                     "attrs": [], "time": false,
                     "items": [["/walls/floor/triangles", true],
                               [format!("{g}/walls/floor/points"), true]]}
                ])
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
        };
        let steps = vec![XdmfStep {
            time: 2.0,
            attrs: vec![attr("p<1>", Center::Node, AttrKind::Scalar, "/s/p", 5)],
        }];
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

        // No steps yet: still a valid, empty collection.
        let t = xdmf_text(&mesh, &[]).unwrap();
        assert!(
            t.contains("CollectionType=\"Temporal\">\n    </Grid>"),
            "{t}"
        );

        let bad_rows = vec![XdmfStep {
            time: 0.0,
            attrs: vec![attr("u", Center::Node, AttrKind::Vector, "/s/u", 2)],
        }];
        let e = xdmf_text(&mesh, &bad_rows).unwrap_err();
        assert!(
            e.message.contains("'u'") && e.message.contains("2 rows"),
            "{e}"
        );
        let mut bad_cols = attr("s", Center::Cell, AttrKind::Tensor6, "/s/s", 2);
        bad_cols.n_cols = 9;
        let e = xdmf_text(
            &mesh,
            &[XdmfStep {
                time: 0.0,
                attrs: vec![bad_cols],
            }],
        )
        .unwrap_err();
        assert!(e.message.contains("9 columns"), "{e}");
        let e = xdmf_text(
            &mesh,
            &[XdmfStep {
                time: f64::NAN,
                attrs: vec![],
            }],
        )
        .unwrap_err();
        assert!(e.message.contains("not finite"), "{e}");
    }
}
