//! Gmsh's own binary MSH 4.1 output reads as the same mesh as its ASCII twin, both
//! written from one meshing by `scripts/gmsh-binary-fixture`: the hand-written binary
//! files of the unit tests could share a misreading of the format with the reader, Gmsh's
//! writer cannot.

mod common;

use alfe::mesh::{gmsh, Mesh};
use common::run_deck;
use std::path::PathBuf;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/meshes")
        .join(name)
}

fn read(name: &str) -> Mesh {
    let bytes = std::fs::read(fixture(name)).unwrap();
    gmsh::read_msh_bytes(&bytes, 0).unwrap_or_else(|e| panic!("{name}: {e}"))
}

#[test]
fn gmsh_binary_and_ascii_twins_read_alike() {
    let bytes = std::fs::read(fixture("box-binary.msh")).unwrap();
    assert!(bytes.starts_with(b"$MeshFormat\n4.1 1 8\n\x01\0\0\0\n"));
    let (bin, ascii) = (read("box-binary.msh"), read("box-ascii.msh"));
    assert!(bin.n_elems() > 100, "{} tets", bin.n_elems());
    assert!(bin.kinds.iter().all(|&k| k == alfe::mesh::ElemKind::Tet4));
    // ASCII has the coordinates to 16 digits (%.16g), one short of a double's.
    assert_eq!(bin.coords.len(), ascii.coords.len());
    for (p, q) in bin.coords.iter().zip(&ascii.coords) {
        assert!((0..3).all(|k| (p[k] - q[k]).abs() <= 2e-15), "{p:?} {q:?}");
    }
    assert_eq!(bin.kinds, ascii.kinds);
    assert_eq!(bin.offsets, ascii.offsets);
    assert_eq!(bin.conn, ascii.conn);
    assert_eq!(bin.node_groups, ascii.node_groups);
    assert_eq!(bin.face_groups, ascii.face_groups);
    assert_eq!(bin.elem_groups, ascii.elem_groups);
    let names: Vec<&str> = bin.node_groups.keys().map(String::as_str).collect();
    assert_eq!(names, ["block", "bottom", "front edge", "origin", "top"]);
    assert_eq!(bin.elem_groups["block"].len(), bin.n_elems());
    for (group, z) in [("bottom", 0.0), ("top", 1.0)] {
        let faces = &bin.face_groups[group];
        assert!(!faces.is_empty());
        for &f in faces {
            assert!(bin.face_nodes(f).iter().all(|&n| bin.coords[n][2] == z));
        }
    }
    assert_eq!(bin.node_groups["origin"].len(), 1);
    assert_eq!(bin.coords[bin.node_groups["origin"][0]], [0.0; 3]);
}

const DECK: &str = r#"
[scene]
name = "box"
units = "mm-t-s"
[[materials]]
name = "m"
model = "linear-elastic"
E = 100.0
nu = 0.3
[[parts]]
name = "block"
material = "m"
mesh = { kind = "gmsh", file = "FILE" }
[[node_sets]]
name = "z0"
group = "bottom"
[[node_sets]]
name = "z1"
group = "top"
[[boundary]]
type = "fixed"
set = "z0"
components = ["x", "y", "z"]
[[boundary]]
type = "displacement"
set = "z1"
components = ["z"]
value = 0.01
[analysis]
type = "static"
end_time = 1.0
step = 1.0
"#;

/// A deck reads the binary file through its mesh path like the ASCII one: the same
/// displacements at every node.
#[test]
fn a_deck_runs_on_the_binary_file_as_on_the_ascii_one() {
    let run = |name: &str| {
        let deck = DECK.replace("FILE", fixture(name).to_str().unwrap());
        run_deck(&format!("gmsh-binary-run-{name}"), &deck).displacement_by_node()
    };
    let (bin, ascii) = (run("box-binary.msh"), run("box-ascii.msh"));
    assert_eq!(bin.len(), ascii.len());
    let scale = bin.iter().map(|(_, _, u)| u[2].abs()).fold(0.0, f64::max);
    assert!((scale - 0.01).abs() < 1e-12, "{scale}");
    for ((_, _, u), (_, _, v)) in bin.iter().zip(&ascii) {
        assert!(
            (0..3).all(|k| (u[k] - v[k]).abs() < 1e-12 * scale),
            "{u:?} {v:?}"
        );
    }
}
