//! Contact output of a run with a rigid wall: the wall columns of `history.csv`, the
//! contact nodal fields and the wall's moving surface in the HDF5 file, the XDMF's
//! spatial collections (mesh + wall per step) and the summary's contact entries.
//!
//! The deck: a linear-elastic unit cube (2×2×2 hex8) on rollers (x = 0, y = 0), its top
//! pushed down by 0.05 and its bottom face tracked against a plane 0.01 below it. After
//! the gap closes the cube is compressed uniformly: the plane carries σ = E ε over the
//! unit bottom face, and the force the body exerts on the plane equals the reaction on
//! the pushed top (both act downward: the top's supports pull the body down, the body
//! pushes the plane down).

mod common;

use alfe::app::{run, RunOptions, RunOutcome};
use alfe::contact::wall::ContactMethod;
use alfe::parallel::SerialComm;
use common::temp_dir;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

const E: f64 = 1000.0;

fn deck(wall_motion: &str) -> String {
    format!(
        r#"
[scene]
name = "wall-press"
description = "unit cube pressed onto a rigid plane"
units = "mm-t-s"

[[materials]]
name = "solid"
model = "linear-elastic"
E = {E}
nu = 0.3

[[parts]]
name = "cube"
material = "solid"
mesh = {{ kind = "box", size = [1, 1, 1], cells = [2, 2, 2] }}

[[node_sets]]
name = "bottom"
group = "zmin"
[[node_sets]]
name = "top"
group = "zmax"
[[node_sets]]
name = "x0"
group = "xmin"
[[node_sets]]
name = "y0"
group = "ymin"

[[boundary]]
type = "fixed"
set = "x0"
components = ["x"]
[[boundary]]
type = "fixed"
set = "y0"
components = ["y"]
[[boundary]]
type = "displacement"
set = "top"
components = ["z"]
value = -0.05

[[walls]]
name = "floor"
shape = "plane"
point = [0, 0, -0.01]
normal = [0, 0, 1]
nodes = "bottom"
{wall_motion}

[analysis]
type = "static"
end_time = 1.0
step = 0.5

[output]
reactions = ["top"]
"#
    )
}

/// Run a deck in this process on one rank; the results directory comes back too.
fn run_in(name: &str, text: &str, contact: Option<ContactMethod>) -> (RunOutcome, PathBuf) {
    let dir = temp_dir(name);
    let path = dir.join("deck.toml");
    std::fs::write(&path, text).unwrap();
    let out = dir.join("out");
    let opts = RunOptions {
        target: path.display().to_string(),
        out: Some(out.clone()),
        partitions: dir.join("partitions"),
        repartition: false,
        quiet: true,
        solver: None,
        iterations: false,
        restart: None,
        stop_after: None,
        overrides: alfe::scene::Overrides {
            contact,
            ..Default::default()
        },
        export_system: None,
    };
    let o = run(&SerialComm, &opts).unwrap_or_else(|e| panic!("{name}: {e}"));
    (o, out)
}

/// history.csv as (header, rows of column → value); every row must have the header's
/// number of columns.
fn history(dir: &Path) -> (Vec<String>, Vec<HashMap<String, f64>>) {
    let text = std::fs::read_to_string(dir.join("history.csv")).unwrap();
    let mut lines = text.lines();
    let head: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| {
            let v: Vec<&str> = l.split(',').collect();
            assert_eq!(v.len(), head.len(), "row and header differ:\n{l}");
            head.iter()
                .cloned()
                .zip(v.iter().map(|x| x.parse::<f64>().unwrap()))
                .collect()
        })
        .collect();
    (head, rows)
}

/// Run a Python script with `/usr/bin/python3` (Debian's h5py) printing one JSON value.
fn python_json(script: &str, args: &[&str]) -> serde_json::Value {
    let out = Command::new("/usr/bin/python3")
        .env("HDF5_USE_FILE_LOCKING", "FALSE")
        .arg("-c")
        .arg(script)
        .args(args)
        .output()
        .expect("cannot run /usr/bin/python3 (apt-get install python3-h5py)");
    assert!(
        out.status.success(),
        "python check failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// The HDF5 contact datasets (by original node id order) and the XDMF's step grids.
const READ: &str = r#"
import sys, os, json, h5py, math
import xml.etree.ElementTree as ET
d = sys.argv[1]
f = h5py.File(os.path.join(d, sys.argv[2] + ".h5"), "r")
ids = list(f["/mesh/original_node_id"][:])
order = sorted(range(len(ids)), key=lambda i: ids[i])
z0 = [float(f["/mesh/coordinates"][i, 2]) for i in order]
clean = lambda x: None if math.isnan(x) else x
out = {"has_walls": "walls" in f, "z0": z0, "steps": {}}
if "walls" in f:
    out["triangles"] = f["/walls/floor/triangles"][:].tolist()
    out["wall_attrs"] = {k: v.decode() for k, v in f["/walls/floor"].attrs.items()}
for s in f["/steps"]:
    g = f["/steps/" + s]
    st = {"time": float(g.attrs["time"]), "names": sorted(g.keys())}
    if "contact_gap" in g:
        st["shapes"] = {k: list(g[k].shape) for k in
                        ["contact_gap", "contact_pressure", "contact_force", "contact_lambda"]}
        st["gap"] = [clean(float(g["contact_gap"][i])) for i in order]
        st["pressure"] = [float(g["contact_pressure"][i]) for i in order]
        st["force"] = [[float(x) for x in g["contact_force"][i]] for i in order]
        st["lambda"] = [[float(x) for x in g["contact_lambda"][i]] for i in order]
        st["points"] = g["walls/floor/points"][:].tolist()
    out["steps"][s] = st
x = ET.parse(os.path.join(d, sys.argv[2] + ".xmf")).getroot().find("Domain/Grid")
out["xdmf"] = {"type": [x.get("GridType"), x.get("CollectionType")], "blocks": []}
for b in x.findall("Grid"):
    block = {"name": b.get("Name"), "type": [b.get("GridType"), b.get("CollectionType")],
             "grids": []}
    for c in b.findall("Grid"):
        items = []
        for di in c.iter("DataItem"):
            if di.get("Format") != "HDF":
                continue
            fname, path = di.text.strip().split(":", 1)
            dims = [int(v) for v in di.get("Dimensions").split()]
            items.append([path, list(f[path].shape) == dims])
        block["grids"].append({"name": c.get("Name"), "time": float(c.find("Time").get("Value")),
                               "topology": c.find("Topology").get("TopologyType"),
                               "items": items})
    out["xdmf"]["blocks"].append(block)
print(json.dumps(out))
"#;

fn f64s(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

#[test]
fn alm_wall_reactions_fields_and_geometry() {
    let (o, out) = run_in("contact-output-alm", &deck(""), None);
    assert!(o.summary.converged);
    assert_eq!(o.steps.len(), 2);

    // History: the wall's twelve columns, then penetration and the counts, last.
    let (head, rows) = history(&out);
    let n = head.len();
    assert_eq!(
        head[n - 15..],
        [
            "floor.fx",
            "floor.fy",
            "floor.fz",
            "floor.mx",
            "floor.my",
            "floor.mz",
            "floor.ux",
            "floor.uy",
            "floor.uz",
            "floor.rx",
            "floor.ry",
            "floor.rz",
            "max_penetration",
            "contact_active",
            "contact_sticking"
        ]
    );
    assert_eq!(rows.len(), 2);
    for (k, r) in rows.iter().enumerate() {
        // Compression after the 0.01 gap closes: 0.015 at t = 0.5, 0.04 at t = 1.
        let strain = [0.015, 0.04][k];
        let fz = r["floor.fz"];
        assert!(
            (fz + E * strain).abs() < 1e-6 * E * strain,
            "step {k}: {fz}"
        );
        assert!(
            (fz - r["top.fz"]).abs() < 1e-9 * fz.abs(),
            "step {k}: {r:?}"
        );
        assert!(r["floor.fx"].abs() < 1e-9 && r["floor.fy"].abs() < 1e-9);
        // Moment about the plane's origin (0, 0, −0.01): r × F with F = (0, 0, fz)
        // over the bottom face's centroid, near (½, ½) (it widens a little).
        assert!((r["floor.mx"] / fz - 0.5).abs() < 0.01, "{r:?}");
        assert!((r["floor.my"] / fz + 0.5).abs() < 0.01, "{r:?}");
        assert!(r["floor.mz"].abs() < 1e-9);
        for c in [
            "floor.ux", "floor.uy", "floor.uz", "floor.rx", "floor.ry", "floor.rz",
        ] {
            assert_eq!(r[c], 0.0);
        }
        // ALM: no penetration; all nine bottom nodes in contact, none sticking (μ = 0).
        assert!(r["max_penetration"] >= 0.0 && r["max_penetration"] < 1e-9);
        assert_eq!(r["contact_active"], 9.0);
        assert_eq!(r["contact_sticking"], 0.0);
    }

    // Summary: the largest penetration and the wall's final report.
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(s["max_penetration"].as_f64().unwrap() < 1e-9);
    let fw = f64s(&s["walls"]["floor"]["force"]);
    assert!((fw[2] - rows[1]["floor.fz"]).abs() < 1e-9 * E);
    assert_eq!(f64s(&s["walls"]["floor"]["displacement"]), [0.0; 3]);

    // HDF5: the four nodal fields (27 rows), the plane's two triangles and four points.
    let j = python_json(READ, &[out.to_str().unwrap(), "wall-press"]);
    assert_eq!(j["has_walls"], true);
    assert_eq!(j["triangles"], serde_json::json!([[0, 1, 2], [0, 2, 3]]));
    assert_eq!(j["wall_attrs"]["shape"], "plane");
    assert_eq!(j["wall_attrs"]["name"], "floor");
    let z0 = f64s(&j["z0"]);
    for (k, name) in ["000001", "000002"].iter().enumerate() {
        let st = &j["steps"][name];
        assert_eq!(
            st["shapes"],
            serde_json::json!({"contact_gap": [27], "contact_pressure": [27],
                               "contact_force": [27, 3], "contact_lambda": [27, 3]})
        );
        let strain = [0.015, 0.04][k];
        let mut fz_sum = 0.0;
        for i in 0..27 {
            let gap = &st["gap"][i];
            let p = st["pressure"][i].as_f64().unwrap();
            let f = f64s(&st["force"][i]);
            let lam = f64s(&st["lambda"][i]);
            if z0[i] == 0.0 {
                // Tracked: closed gap, the uniform pressure σ = E ε, a normal multiplier.
                assert!(gap.as_f64().unwrap().abs() < 1e-9, "node {i}: {gap}");
                assert!((p - E * strain).abs() < 1e-6 * E, "node {i}: {p}");
                assert!(f[2] > 0.0 && lam[0] > 0.0, "node {i}: {f:?} {lam:?}");
                fz_sum += f[2];
            } else {
                assert!(gap.is_null(), "untracked node {i}: gap {gap}");
                assert_eq!((p, f, lam), (0.0, vec![0.0; 3], vec![0.0; 3]));
            }
        }
        // The wall pushes the body up with what the body pushes it down.
        assert!((fz_sum + rows[k]["floor.fz"]).abs() < 1e-9 * E, "{fz_sum}");
        // The plane stays where it was put: z = −0.01.
        let pts = st["points"].as_array().unwrap();
        assert_eq!(pts.len(), 4);
        assert!(pts
            .iter()
            .all(|p| (p[2].as_f64().unwrap() + 0.01).abs() < 1e-15));
    }

    // XDMF: a block for the part and one for the wall, each a grid per output step (the
    // state at t = 0 first), every DataItem resolving to its dataset.
    let xd = &j["xdmf"];
    assert_eq!(xd["type"], serde_json::json!(["Collection", "Spatial"]));
    let blocks = xd["blocks"].as_array().unwrap();
    assert_eq!(blocks.len(), 2);
    assert_eq!(blocks[1]["name"], "wall_floor");
    for (b, topology) in blocks.iter().zip(["Hexahedron", "Triangle"]) {
        assert_eq!(b["type"], serde_json::json!(["Collection", "Temporal"]));
        let grids = b["grids"].as_array().unwrap();
        assert_eq!(grids.len(), 3);
        for (k, g) in grids.iter().enumerate() {
            assert_eq!(g["name"], b["name"]);
            assert_eq!(g["topology"], topology);
            assert_eq!(g["time"].as_f64().unwrap(), [0.0, 0.5, 1.0][k]);
        }
    }
    for k in 0..3 {
        let paths: Vec<&str> = blocks
            .iter()
            .flat_map(|b| b["grids"][k]["items"].as_array().unwrap())
            .map(|it| {
                assert_eq!(it[1], true, "{it}");
                it[0].as_str().unwrap()
            })
            .collect();
        let step = format!("/steps/{k:06}");
        for p in [
            "contact_gap",
            "contact_pressure",
            "contact_force",
            "contact_lambda",
            "walls/floor/points",
        ] {
            assert!(paths.contains(&format!("{step}/{p}").as_str()), "{paths:?}");
        }
    }
}

#[test]
fn moving_penalty_wall_displacement_and_penetration() {
    // The plane rises by 0.02 over the run (penalty: it lets the nodes in a little).
    let motion = "motion = { translation = [0, 0, 0.02] }";
    let (o, out) = run_in(
        "contact-output-penalty",
        &deck(motion),
        Some(ContactMethod::Penalty),
    );
    assert!(o.summary.converged);
    let (_, rows) = history(&out);
    let j = python_json(READ, &[out.to_str().unwrap(), "wall-press"]);
    let z0 = f64s(&j["z0"]);
    let mut max_pen: f64 = 0.0;
    for (k, r) in rows.iter().enumerate() {
        let t = r["time"];
        assert!((r["floor.uz"] - 0.02 * t).abs() < 1e-15, "{r:?}");
        assert!((r["floor.fz"] - r["top.fz"]).abs() < 1e-9 * r["floor.fz"].abs());
        // The largest penetration is the deepest tracked node's negative gap.
        let st = &j["steps"][format!("{:06}", k + 1)];
        let deepest = (0..27)
            .filter(|&i| z0[i] == 0.0)
            .map(|i| -st["gap"][i].as_f64().unwrap())
            .fold(0.0, f64::max);
        assert!(r["max_penetration"] > 0.0);
        assert!(
            (r["max_penetration"] - deepest).abs() < 1e-12,
            "{r:?} {deepest}"
        );
        max_pen = max_pen.max(r["max_penetration"]);
        // The surface moves with the wall.
        for p in st["points"].as_array().unwrap() {
            assert!((p[2].as_f64().unwrap() - (-0.01 + 0.02 * t)).abs() < 1e-12);
        }
        // Penalty walls carry no multipliers.
        assert!(st["lambda"]
            .as_array()
            .unwrap()
            .iter()
            .all(|l| f64s(l) == [0.0; 3]));
    }
    let col = o
        .model
        .columns()
        .iter()
        .position(|c| c.name == "max_penetration")
        .unwrap();
    let from_records = o.steps.iter().map(|r| r.columns[col]).fold(0.0, f64::max);
    assert_eq!(
        o.summary.contributions["max_penetration"].as_f64(),
        Some(from_records)
    );
    assert!((from_records - max_pen).abs() < 1e-12 * max_pen);
}

#[test]
fn no_walls_no_contact_output() {
    let text = common::builtin("cube-stretch");
    let (o, out) = run_in("contact-output-none", &text, None);
    assert!(o.summary.contributions.is_empty());
    assert!(o.steps.iter().all(|r| r.columns.is_empty()));
    let (head, _) = history(&out);
    assert!(!head
        .iter()
        .any(|c| c.contains("floor") || c.contains("contact")));
    assert!(!head.contains(&"max_penetration".to_string()));
    let s = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert!(
        !s.contains("max_penetration") && !s.contains("\"walls\""),
        "{s}"
    );
    let xmf = std::fs::read_to_string(out.join("cube-stretch.xmf")).unwrap();
    assert!(!xmf.contains("wall_") && !xmf.contains("contact_"), "{xmf}");
    let j = python_json(READ, &[out.to_str().unwrap(), "cube-stretch"]);
    assert_eq!(j["has_walls"], false);
    assert_eq!(
        j["steps"]["000002"]["names"],
        serde_json::json!(["displacement", "stress", "von_mises"])
    );
}
