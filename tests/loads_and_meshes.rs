//! Loads and mesh sources at scene level: a follower pressure at large strain (its load
//! stiffness must keep Newton quadratic), nodal loads, and a Gmsh file whose physical
//! groups drive the deck, against the same model built from a generated block.

mod common;
use common::*;

const CUBE: &str = r#"
[scene]
name = "cube"
units = "mm-t-s"
[[materials]]
name = "rubber"
model = "neo-hookean"
E = 3.0
nu = 0.3
[[parts]]
name = "cube"
material = "rubber"
mesh = { kind = "box", size = [1, 1, 1], cells = [2, 2, 2] }
[[node_sets]]
name = "x0"
group = "xmin"
[[node_sets]]
name = "y0"
group = "ymin"
[[node_sets]]
name = "z0"
group = "zmin"
[[surfaces]]
name = "x1"
group = "xmax"
[[boundary]]
type = "fixed"
set = "x0"
components = ["x"]
[[boundary]]
type = "fixed"
set = "y0"
components = ["y"]
[[boundary]]
type = "fixed"
set = "z0"
components = ["z"]
LOADS
[analysis]
type = "static"
end_time = 1.0
step = 0.25
[solver]
residual_rtol = 1e-12
[output]
reactions = ["x0"]
"#;

/// A suction (negative follower pressure) pulls the cube: the Cauchy stress is
/// σ_xx = −p exactly, whatever the stretch, and the reaction is σ_xx times the current
/// area λy·λz. The load stiffness makes Newton converge quadratically.
#[test]
fn follower_pressure_gives_exact_cauchy_stress_at_large_strain() {
    let deck = CUBE.replace(
        "LOADS",
        "[[loads]]\ntype = \"pressure\"\nsurface = \"x1\"\npressure = -1.2\n",
    );
    let out = run_deck("pressure", &deck);
    let sig = out
        .model
        .field(&alfe::parallel::SerialComm, &out.u, 1.0, "stress")
        .unwrap();
    for s in sig.chunks(6) {
        assert!((s[0] - 1.2).abs() < 1e-9, "σ_xx {} ≠ 1.2", s[0]);
        for v in &s[1..] {
            assert!(v.abs() < 1e-9, "{s:?}");
        }
    }
    // Current lateral stretch from a node on the far corner.
    let (_, _, u) = out
        .displacement_by_node()
        .into_iter()
        .find(|(_, x, _)| x[0] == 1.0 && x[1] == 1.0 && x[2] == 1.0)
        .unwrap();
    let (lx, ly, lz) = (1.0 + u[0], 1.0 + u[1], 1.0 + u[2]);
    assert!(lx > 1.3, "large strain expected, λx = {lx}");
    let last = out.steps.last().unwrap();
    assert!(
        rel_err(-last.reactions[0][0], 1.2 * ly * lz) < 1e-9,
        "reaction {:?} vs σ·a = {}",
        last.reactions[0],
        1.2 * ly * lz
    );
    // Quadratic convergence: the last residual ratios drop at least like r_{k+1} ≤ C r_k².
    for rec in &out.steps {
        let h = &rec.stats.residual_history;
        assert!(
            rec.stats.iterations <= 7,
            "step {}: {} iterations {h:?}",
            rec.step,
            rec.stats.iterations
        );
        let n = h.len();
        assert!(n >= 3, "{h:?}");
        let (a, b) = (h[n - 3], h[n - 2]);
        assert!(
            b < 10.0 * a * a || b < 1e-10,
            "step {}: not quadratic without the load stiffness? {h:?}",
            rec.step
        );
    }
}

/// Nodal forces: the supports carry their sum exactly (linear elastic).
#[test]
fn nodal_loads_are_carried_by_the_supports() {
    let deck = CUBE
        .replace(
            "LOADS",
            "[[loads]]\ntype = \"nodal\"\nset = \"x1\"\nforce = [0.05, 0.0, 0.0]\n",
        )
        .replace("model = \"neo-hookean\"", "model = \"linear-elastic\"")
        .replace("residual_rtol = 1e-12", "residual_rtol = 1e-10");
    let out = run_deck("nodal", &deck);
    // x1 (a surface) has 9 nodes on a 2×2 face.
    let last = out.steps.last().unwrap();
    assert!(
        rel_err(-last.reactions[0][0], 9.0 * 0.05) < 1e-9,
        "{:?}",
        last.reactions[0]
    );
}

/// Write a generated block as a Gmsh 4.1 file with physical groups, run the same model
/// from both, and get the same answer (node numbering differs: compare by position).
#[test]
fn gmsh_file_with_physical_groups_matches_generated_block() {
    use alfe::mesh::generate::{box_mesh, BoxSpec};
    use alfe::mesh::ElemKind;
    let m = box_mesh(
        &BoxSpec {
            origin: [0.0; 3],
            size: [1.0; 3],
            cells: [2, 2, 2],
            grading: [1.0; 3],
            kind: ElemKind::Tet4,
        },
        0,
    );
    // Nodes get tags 101.. (non-contiguous on purpose), volume elements type 4 (tet4).
    let mut s = String::from("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n3\n2 1 \"left\"\n2 2 \"right\"\n3 3 \"solid\"\n$EndPhysicalNames\n");
    s += "$Entities\n0 0 2 1\n1 0 0 0 0 1 1 1 1 1 0\n2 1 0 0 1 1 1 1 2 0\n1 0 0 0 1 1 1 1 3 0\n$EndEntities\n";
    let xmin = &m.face_groups["xmin"];
    let xmax = &m.face_groups["xmax"];
    s += &format!(
        "$Nodes\n1 {n} 101 {}\n3 1 0 {n}\n",
        100 + m.n_nodes(),
        n = m.n_nodes()
    );
    for i in 0..m.n_nodes() {
        s += &format!("{}\n", 101 + i);
    }
    for c in &m.coords {
        s += &format!("{} {} {}\n", c[0], c[1], c[2]);
    }
    s += "$EndNodes\n";
    let ne = m.n_elems() + xmin.len() + xmax.len();
    s += &format!("$Elements\n3 {ne} 1 {ne}\n");
    let mut tag = 1;
    for (ent, faces) in [(1, xmin), (2, xmax)] {
        s += &format!("2 {ent} 2 {}\n", faces.len());
        for f in faces {
            let nodes: Vec<String> = m
                .face_nodes(*f)
                .iter()
                .map(|n| (101 + n).to_string())
                .collect();
            s += &format!("{tag} {}\n", nodes.join(" "));
            tag += 1;
        }
    }
    s += &format!("3 1 4 {}\n", m.n_elems());
    for e in 0..m.n_elems() {
        let nodes: Vec<String> = m
            .elem_nodes(e)
            .iter()
            .map(|n| (101 + n).to_string())
            .collect();
        s += &format!("{tag} {}\n", nodes.join(" "));
        tag += 1;
    }
    s += "$EndElements\n";
    let dir = temp_dir("gmsh-src");
    std::fs::write(dir.join("block.msh"), &s).unwrap();
    let base = r#"
[scene]
name = "g"
units = "mm-t-s"
[[materials]]
name = "m"
model = "neo-hookean"
E = 10.0
nu = 0.3
[[parts]]
name = "p"
material = "m"
MESH
[[node_sets]]
name = "left"
group = LEFT
[[surfaces]]
name = "right"
group = RIGHT
[[boundary]]
type = "fixed"
set = "left"
[[loads]]
type = "traction"
surface = "right"
traction = [0.3, 0.2, -0.5]
[analysis]
type = "static"
end_time = 1.0
step = 0.5
"#;
    let gen = base
        .replace(
            "MESH",
            "mesh = { kind = \"box\", size = [1, 1, 1], cells = [2, 2, 2], element = \"tet4\" }",
        )
        .replace("LEFT", "\"xmin\"")
        .replace("RIGHT", "\"xmax\"");
    let msh = base
        .replace(
            "MESH",
            &format!(
                "mesh = {{ kind = \"gmsh\", file = \"{}\" }}",
                dir.join("block.msh").display()
            ),
        )
        .replace("LEFT", "\"left\"")
        .replace("RIGHT", "\"right\"");
    let a = run_deck("gen", &gen);
    let b = run_deck("msh", &msh);
    let key = |x: [f64; 3]| x.map(|v| (v * 1e6).round() as i64);
    let mut ua: Vec<_> = a
        .displacement_by_node()
        .into_iter()
        .map(|(_, x, u)| (key(x), u))
        .collect();
    let mut ub: Vec<_> = b
        .displacement_by_node()
        .into_iter()
        .map(|(_, x, u)| (key(x), u))
        .collect();
    ua.sort_by_key(|p| p.0);
    ub.sort_by_key(|p| p.0);
    assert_eq!(ua.len(), ub.len());
    let scale = ua
        .iter()
        .flat_map(|p| p.1)
        .fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(scale > 0.01);
    for ((ka, va), (kb, vb)) in ua.iter().zip(&ub) {
        assert_eq!(ka, kb);
        for c in 0..3 {
            assert!(
                (va[c] - vb[c]).abs() < 1e-9 * scale,
                "{ka:?}: {va:?} vs {vb:?}"
            );
        }
    }
}

/// A `blocks` mesh: a bar of two boxes that meet at x = 10 (one lattice: their nodes are
/// shared), under a traction σ at its end and held at the other with ν = 0, carries a
/// uniform stress: every element's von Mises stress is σ, `bar.max_von_mises` reports it
/// in the history and summary.json, and the end moves by σ L / E. A bar whose second box
/// leaves a gap would not be one body: the end would not be held.
#[test]
fn blocks_bar_carries_a_uniform_stress() {
    let deck = r#"
[scene]
name = "blocks-bar"
units = "mm-t-s"
[[materials]]
name = "m"
model = "linear-elastic"
E = 1000.0
nu = 0.0
[[parts]]
name = "bar"
material = "m"
mesh = { kind = "blocks", cell_size = 1.5, solids = [[[0, 0, 0], [10, 4, 3]], [[10, 0, 0], [20, 4, 3]]] }
[[node_sets]]
name = "root"
box = { min = [0, 0, 0], max = [0, 4, 3] }
[[node_sets]]
name = "root_edge"
box = { min = [0, 0, 0], max = [0, 4, 0] }
[[node_sets]]
name = "root_corner"
box = { min = [0, 0, 0], max = [0, 0, 0] }
[[surfaces]]
name = "end"
box = { min = [20, 0, 0], max = [20, 4, 3] }
[[boundary]]
type = "fixed"
set = "root"
components = ["x"]
[[boundary]]
type = "fixed"
set = "root_edge"
components = ["z"]
[[boundary]]
type = "fixed"
set = "root_corner"
components = ["y"]
[[loads]]
type = "traction"
surface = "end"
traction = [25, 0, 0]
[analysis]
type = "static"
end_time = 1.0
step = 1.0
[output]
peak_stress = ["bar"]
displacements = ["end"]
"#;
    let out = run_deck("blocks-bar", deck);
    assert_eq!(out.summary.elements, 7 * 3 * 2 * 2);
    let vm = field(&out, "von_mises");
    assert!(vm.iter().all(|v| (v - 25.0).abs() < 1e-9), "{vm:?}");
    assert!((column(&out, "bar.max_von_mises")[0] - 25.0).abs() < 1e-9);
    let s = serde_json::to_value(&out.summary).unwrap();
    assert!(
        (s["bar.max_von_mises"].as_f64().unwrap() - 25.0).abs() < 1e-9,
        "{s}"
    );
    assert!((column(&out, "end.ux")[0] - 25.0 * 20.0 / 1000.0).abs() < 1e-9);
    let bad = deck.replace("peak_stress = [\"bar\"]", "peak_stress = [\"bra\"]");
    let e = try_run_deck("blocks-bar-bad", &bad)
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("output.peak_stress[0]: unknown part `bra` (parts: bar)"),
        "{e}"
    );
    // Placed: turned 90° about z and moved; the same answer along the bar's new axis.
    let mut placed = deck.replace(
        "solids = [[[0, 0, 0], [10, 4, 3]], [[10, 0, 0], [20, 4, 3]]] }",
        "solids = [[[0, 0, 0], [10, 4, 3]], [[10, 0, 0], [20, 4, 3]]] }\nrotate = { axis = [0, 0, 2], angle = 90 }\ntranslate = [5, -1, 2]",
    );
    for (from, to) in [
        (
            "min = [0, 0, 0], max = [0, 4, 3]",
            "min = [1, -1, 2], max = [5, -1, 5]",
        ),
        (
            "min = [0, 0, 0], max = [0, 4, 0]",
            "min = [1, -1, 2], max = [5, -1, 2]",
        ),
        (
            "min = [0, 0, 0], max = [0, 0, 0]",
            "min = [5, -1, 2], max = [5, -1, 2]",
        ),
        (
            "min = [20, 0, 0], max = [20, 4, 3]",
            "min = [1, 19, 2], max = [5, 19, 5]",
        ),
        (
            "set = \"root\"\ncomponents = [\"x\"]",
            "set = \"root\"\ncomponents = [\"y\"]",
        ),
        (
            "set = \"root_corner\"\ncomponents = [\"y\"]",
            "set = \"root_corner\"\ncomponents = [\"x\"]",
        ),
        ("traction = [25, 0, 0]", "traction = [0, 25, 0]"),
    ] {
        placed = edit(&placed, from, to);
    }
    let out = run_deck("blocks-bar-placed", &placed);
    assert!(field(&out, "von_mises")
        .iter()
        .all(|v| (v - 25.0).abs() < 1e-9));
    assert!((column(&out, "end.uy")[0] - 0.5).abs() < 1e-9);
    assert!(column(&out, "end.ux")[0].abs() < 1e-9);
    let e = try_run_deck(
        "blocks-bar-bad-axis",
        &placed.replace("axis = [0, 0, 2]", "axis = [0, 0, 0]"),
    )
    .err()
    .unwrap()
    .to_string();
    assert!(
        e.contains("parts[0].rotate.axis: expected a non-zero finite vector"),
        "{e}"
    );
    let bad = deck.replace("cell_size = 1.5", "cell_size = 1e-6");
    let e = try_run_deck("blocks-bar-bad2", &bad)
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("parts[0].mesh.cell_size"), "{e}");
}
