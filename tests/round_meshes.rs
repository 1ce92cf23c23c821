//! The generated round meshes (`kind = "cylinder"`, `kind = "ring"`) at deck level: they
//! build, their groups drive node sets, surfaces and constraints, a quarter cylinder in
//! uniaxial compression carries the exact load, and bad fields are named.

mod common;
use alfe::scene::{build, deck, read, Source};

fn model(src: &Source) -> alfe::Result<alfe::model::def::ModelDef> {
    read(src).map(|s| s.model)
}
use common::*;
use std::f64::consts::PI;
use std::path::PathBuf;

const QUARTER_BAR: &str = r#"
[scene]
name = "quarter-bar"
units = "mm-t-s"
[[materials]]
name = "copper"
model = "linear-elastic"
E = 100.0
nu = 0.3
[[parts]]
name = "bar"
material = "copper"
mesh = { kind = "cylinder", radius = 2.0, length = 6.0, z0 = 1.0, cells_radial = 4, cells_axial = 5, axial_grading = 0.5, sector = "quarter" }
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
[[surfaces]]
name = "lid"
group = "zmax"
[[surfaces]]
name = "skin"
group = "outer"
[[boundary]]
type = "fixed"
set = "bottom"
components = ["z"]
[[boundary]]
type = "fixed"
set = "x0"
components = ["x"]
[[boundary]]
type = "fixed"
set = "y0"
components = ["y"]
[[loads]]
type = "traction"
surface = "lid"
traction = [0.0, 0.0, -1.0]
[analysis]
type = "static"
end_time = 1.0
step = 1.0
[output]
reactions = ["bottom"]
"#;

const RING: &str = r#"
[scene]
name = "clip"
units = "mm-t-s"
[[materials]]
name = "pom"
model = "neo-hookean"
E = 3000.0
nu = 0.35
[[parts]]
name = "clip"
material = "pom"
mesh = { kind = "ring", inner_radius = 4.0, outer_radius = 5.0, thickness = 2.0, angles = [-60.0, 240.0], cells = [2, 30, 2], center = [10.0, 0.0] }
[[surfaces]]
name = "pin"
group = "inner"
[[node_sets]]
name = "cut"
group = "start"
[[boundary]]
type = "fixed"
set = "cut"
[analysis]
type = "static"
end_time = 1.0
step = 1.0
"#;

fn src(text: &str) -> Source {
    Source {
        text: text.to_string(),
        dir: PathBuf::from("."),
        label: "test".into(),
    }
}

#[test]
fn cylinder_and_ring_decks_build() {
    let m = model(&src(QUARTER_BAR)).unwrap();
    // cells_radial 4: 2 in the central block's half-width, 2 outside; 2×2 + 2·2·2 quads.
    assert_eq!(m.mesh.n_elems(), 12 * 5);
    assert_eq!(m.surfaces["skin"].len(), 4 * 5);
    assert!(m.node_sets["x0"]
        .iter()
        .all(|&n| m.mesh.coords[n][0] == 0.0));
    assert!(m.node_sets["top"]
        .iter()
        .all(|&n| m.mesh.coords[n][2] == 7.0));

    let m = model(&src(RING)).unwrap();
    assert_eq!(m.mesh.n_elems(), 2 * 30 * 2);
    assert_eq!(m.surfaces["pin"].len(), 30 * 2);
    assert_eq!(m.node_sets["cut"].len(), 3 * 3);
    for &n in &m.node_sets["cut"] {
        let p = m.mesh.coords[n];
        // On the ray from the center at −60°.
        let (s, c) = (-60f64).to_radians().sin_cos();
        assert!(((p[0] - 10.0) * s - p[1] * c).abs() < 1e-12, "{p:?}");
    }
    // Closed ring: no start or end.
    let closed = RING.replace("angles = [-60.0, 240.0], ", "");
    let e = model(&src(&closed)).unwrap_err();
    assert!(
        e.message.contains("node_sets[0].group") && e.message.contains("start"),
        "{e}"
    );
}

/// Rollers on the symmetry planes and the bottom, a unit pressure on the top: uniaxial
/// stress σ_zz = −1 on the mesh's cross-section (the inscribed polygon, 16 sides for the
/// full circle), strain −1/E, lateral expansion ν r / E on the outer surface.
///
/// (Loaded by a traction: a linear problem driven only by a prescribed displacement does
/// not pass the solver's correction-energy test, on a box as well.)
#[test]
fn quarter_cylinder_in_uniaxial_compression_carries_the_exact_load() {
    let out = run_deck("quarter-bar", QUARTER_BAR);
    let area = 16.0 / 2.0 * 4.0 * (2.0 * PI / 16.0).sin() / 4.0;
    let r = out.steps.last().unwrap().reactions[0];
    assert!(rel_err(r[2], area) < 1e-9, "{r:?} vs {area}");
    assert!(r[0].abs() < 1e-9 && r[1].abs() < 1e-9, "{r:?}");
    let mut outer = 0;
    for (_, x, u) in out.displacement_by_node() {
        assert!((u[2] + (x[2] - 1.0) / 100.0).abs() < 1e-9, "{x:?} {u:?}");
        let rad = x[0].hypot(x[1]);
        if (rad - 2.0).abs() < 1e-12 {
            let ur = (u[0] * x[0] + u[1] * x[1]) / rad;
            assert!((ur - 0.3 * 2.0 / 100.0).abs() < 1e-9, "{ur}");
            outer += 1;
        }
    }
    assert_eq!(outer, 5 * 6);
}

#[test]
fn bad_round_mesh_fields_are_named() {
    let bad = RING.replace("inner_radius = 4.0", "inner_radius = 6.0");
    let e = model(&src(&bad)).unwrap_err();
    assert_eq!(e.exit_code(), 2);
    assert!(
        e.message
            .contains("parts[0].mesh.inner_radius: must be smaller than outer_radius"),
        "{e}"
    );
    for (from, to, field) in [
        ("angles = [-60.0, 240.0]", "angles = [10.0, 0.0]", "angles"),
        ("angles = [-60.0, 240.0]", "angles = [0.0, 370.0]", "angles"),
        ("cells = [2, 30, 2]", "cells = [2, 0, 2]", "cells"),
        ("thickness = 2.0", "thickness = -2.0", "thickness"),
    ] {
        let e = model(&src(&RING.replace(from, to))).unwrap_err();
        let want = format!("parts[0].mesh.{field}:");
        assert!(e.message.contains(&want), "{to}: {e}");
    }
    for (from, to, field) in [
        ("cells_radial = 4", "cells_radial = 1", "cells_radial"),
        ("radius = 2.0", "radius = 0.0", "radius"),
        ("cells_axial = 5", "cells_axial = 0", "cells_axial"),
        (
            "axial_grading = 0.5",
            "axial_grading = -1.0",
            "axial_grading",
        ),
    ] {
        let text = QUARTER_BAR.replace(from, to);
        let d = deck::parse(&text).unwrap();
        let e = build::build(&d, std::path::Path::new(".")).unwrap_err();
        let want = format!("parts[0].mesh.{field}:");
        assert!(e.message.contains(&want), "{to}: {e}");
    }
    // Deserialization errors: an unknown sector and a misspelt key.
    let e = deck::parse(&QUARTER_BAR.replace("\"quarter\"", "\"half\"")).unwrap_err();
    assert!(e.contains("parts[0]") && e.contains("half"), "{e}");
    let e = deck::parse(&RING.replace("thickness", "thicknes")).unwrap_err();
    assert!(e.contains("parts[0]") && e.contains("thicknes"), "{e}");
}
