//! Issue 35, wedge6 (prism): patch tests on distorted generated prisms, the same block
//! read as a Gmsh prism6 file with mixed tri3/quad4 physical surfaces, and a nearly
//! incompressible cantilever where `auto` (the hybrid mean-dilatation prism) does not
//! lock and the standard prism does.

mod common;
use alfe::mesh::generate::{box_mesh, distort_interior, BoxSpec};
use alfe::mesh::ElemKind;
use common::{gmsh_text, run_deck, temp_dir};

const DECK: &str = r#"
[scene]
name = "w6"
units = "mm-t-s"
[[materials]]
name = "m"
model = "MODEL"
E = 100.0
nu = NU
[[parts]]
name = "block"
material = "m"
MESH
[[node_sets]]
name = "x0"
group = "xmin"
[[node_sets]]
name = "x1"
group = "xmax"
[[node_sets]]
name = "y0"
group = "ymin"
[[node_sets]]
name = "z0"
group = "zmin"
BOUNDARY
[analysis]
type = "static"
end_time = 1.0
step = 1.0
"#;

/// Rollers on x = 0, y = 0, z = 0 and an end displacement 0.02 along x.
const STRETCH: &str = "[[boundary]]\ntype = \"fixed\"\nset = \"x0\"\ncomponents = [\"x\"]\n[[boundary]]\ntype = \"fixed\"\nset = \"y0\"\ncomponents = [\"y\"]\n[[boundary]]\ntype = \"fixed\"\nset = \"z0\"\ncomponents = [\"z\"]\n[[boundary]]\ntype = \"displacement\"\nset = \"x1\"\ncomponents = [\"x\"]\nvalue = 0.02\n";

fn deck(model: &str, nu: f64, mesh: &str, boundary: &str) -> String {
    DECK.replace("MODEL", model)
        .replace("NU", &nu.to_string())
        .replace("MESH", mesh)
        .replace("BOUNDARY", boundary)
}

/// The generated wedge block as a Gmsh 4.1 file: prisms (type 6) and the physical
/// surfaces xmin, xmax, ymin, zmin as tri3 and quad4 blocks of one entity each
/// ([`gmsh_text`]).
fn wedge_msh(size: [f64; 3], cells: [usize; 3], distort: f64) -> String {
    let mut m = box_mesh(
        &BoxSpec {
            origin: [0.0; 3],
            size,
            cells,
            grading: [1.0; 3],
            kind: ElemKind::Wedge6,
        },
        0,
    );
    if distort > 0.0 {
        distort_interior(&mut m, distort, 12345);
    }
    let surfaces: Vec<(&str, Vec<Vec<usize>>)> = ["xmin", "xmax", "ymin", "zmin"]
        .iter()
        .map(|g| {
            (
                *g,
                m.face_groups[*g].iter().map(|f| m.face_nodes(*f)).collect(),
            )
        })
        .collect();
    let elems: Vec<Vec<usize>> = (0..m.n_elems()).map(|e| m.elem_nodes(e).to_vec()).collect();
    gmsh_text(&m.coords, &surfaces, &elems)
}

/// Max nodal error against u = (ε x, −ν ε y, −ν ε z), ε = 0.02.
fn stretch_error(out: &alfe::app::RunOutcome, nu: f64) -> f64 {
    let eps = 0.02;
    let mut err: f64 = 0.0;
    for (_, x, u) in out.displacement_by_node() {
        let want = [eps * x[0], -nu * eps * x[1], -nu * eps * x[2]];
        for k in 0..3 {
            err = err.max((u[k] - want[k]).abs());
        }
    }
    err
}

/// Patch test: generated prisms of a distorted 1 × 1 × 1 block (every formulation a
/// prism has), and the same mesh read from a Gmsh prism file, reproduce the uniform
/// stretch exactly at every node (linear elastic).
#[test]
fn patch_test_on_distorted_prisms_generated_and_read() {
    let nu = 0.3;
    let run = |form: &str, model: &str| {
        let mesh = format!(
            "formulation = \"{form}\"\nmesh = {{ kind = \"box\", size = [1, 1, 1], cells = [2, 2, 2], element = \"wedge6\", distort = 0.2 }}"
        );
        run_deck(
            &format!("w6-patch-{form}-{model}"),
            &deck(model, nu, &mesh, STRETCH),
        )
    };
    for form in ["standard", "fbar"] {
        let err = stretch_error(&run(form, "linear-elastic"), nu);
        eprintln!("wedge6 patch test, {form}: max nodal error {err:.3e}");
        assert!(err < 1e-12, "{form}: {err}");
    }
    // Hybrid needs a volumetric split (neo-Hookean): its answers are F-bar's.
    let (a, b) = (run("fbar", "neo-hookean"), run("hybrid", "neo-hookean"));
    let mut diff: f64 = 0.0;
    for ((_, _, ua), (_, _, ub)) in a
        .displacement_by_node()
        .iter()
        .zip(b.displacement_by_node())
    {
        for k in 0..3 {
            diff = diff.max((ua[k] - ub[k]).abs());
        }
    }
    assert!(diff < 1e-10, "hybrid vs mean dilatation: {diff}");
    let dir = temp_dir("w6-msh");
    let file = dir.join("block.msh");
    std::fs::write(&file, wedge_msh([1.0; 3], [2, 2, 2], 0.2)).unwrap();
    let mesh = format!(
        "mesh = {{ kind = \"gmsh\", file = \"{}\" }}",
        file.display()
    );
    let out = run_deck("w6-gmsh", &deck("linear-elastic", nu, &mesh, STRETCH));
    let err = stretch_error(&out, nu);
    eprintln!("wedge6 patch test, Gmsh prism6 file: max nodal error {err:.3e}");
    assert!(err < 1e-12, "{err}");
    // A traction on the mixed xmax side (quads) and the z = 0 rollers on triangles.
    let traction = STRETCH.replace(
        "[[boundary]]\ntype = \"displacement\"\nset = \"x1\"\ncomponents = [\"x\"]\nvalue = 0.02\n",
        "[[surfaces]]\nname = \"end\"\ngroup = \"xmax\"\n[[loads]]\ntype = \"traction\"\nsurface = \"end\"\ntraction = [2.0, 0.0, 0.0]\n",
    );
    let out = run_deck("w6-traction", &deck("linear-elastic", nu, &mesh, &traction));
    let err = stretch_error(&out, nu);
    assert!(err < 1e-12, "traction: {err}");
}

/// A 10 × 1 × 1 cantilever of prisms (20 × 2 × 2 cells), clamped, tip load P spread on
/// its end nodes, neo-Hookean at ν = 0.4995: `auto` (hybrid, mean dilatation) bends
/// within 10 % of the hybrid hex8 on the same cells (0.87 and 0.95 of beam theory: the
/// linear prism is the stiffer in bending); the standard prism locks (0.46).
#[test]
fn nearly_incompressible_prism_cantilever_does_not_lock_under_auto() {
    let clamp = "[[boundary]]\ntype = \"fixed\"\nset = \"x0\"\n[[loads]]\ntype = \"nodal\"\nset = \"x1\"\nforce = [0.0, 0.0, 1.1111111111111112e-4]\n";
    let tip = |form: &str, element: &str| -> f64 {
        let mesh = format!(
            "formulation = \"{form}\"\nmesh = {{ kind = \"box\", size = [10, 1, 1], cells = [20, 2, 2], element = \"{element}\" }}"
        );
        let out = run_deck(
            &format!("w6-beam-{form}-{element}"),
            &deck("neo-hookean", 0.4995, &mesh, clamp),
        );
        let end: Vec<f64> = out
            .displacement_by_node()
            .iter()
            .filter(|(_, x, _)| (x[0] - 10.0).abs() < 1e-9)
            .map(|(_, _, u)| u[2])
            .collect();
        assert_eq!(end.len(), 9, "end nodes");
        end.iter().sum::<f64>() / end.len() as f64
    };
    let beam = 0.001 * 1000.0 / (3.0 * 100.0 / 12.0);
    let (auto, standard) = (tip("auto", "wedge6"), tip("standard", "wedge6"));
    let hex = tip("auto", "hex8");
    eprintln!(
        "cantilever 20 × 2 × 2 cells, nu = 0.4995: tip / beam theory: wedge6 auto (hybrid) {:.4}, standard {:.4}; hex8 auto (hybrid) {:.4}",
        auto / beam,
        standard / beam,
        hex / beam
    );
    assert!((auto / hex - 1.0).abs() < 0.1, "wedge {auto} vs hex8 {hex}");
    assert!(standard < 0.6 * auto, "standard {standard} vs auto {auto}");
}
