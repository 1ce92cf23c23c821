//! A deck can be valid and still wrong (issue 38): `alfe check` warns, with the numbers,
//! about material constants implausible in the deck's units, geometry in another length
//! unit, motions that end after the analysis and static models with free rigid-body
//! modes; a missing `end_time` is named as missing. No built-in scene raises them.

mod common;
use common::*;
use std::path::Path;

/// `alfe check` of a deck text (written to `dir`), in this process.
fn check(dir: &Path, text: &str) -> alfe::Result<String> {
    let deck = dir.join("deck.toml");
    std::fs::write(&deck, text).unwrap();
    alfe::app::check(
        deck.to_str().unwrap(),
        1,
        &alfe::scene::Overrides::default(),
    )
}

/// The user's seal block: 40 × 20 × 20 mm Mooney–Rivlin, fixed at its base, pressed by a
/// cylinder (R = 10) that moves down 5 mm by t = 1 and along 10 mm by t = 2.
const SEAL: &str = r#"
[scene]
name = "seal"
units = "mm-t-s"
[[materials]]
name = "rubber"
model = "mooney-rivlin"
C10 = 0.5
C01 = 0.125
nu = 0.45
[[parts]]
name = "block"
material = "rubber"
mesh = { kind = "box", size = [40, 20, 20], cells = [4, 2, 2] }
[[node_sets]]
name = "bottom"
group = "zmin"
[[node_sets]]
name = "top"
group = "zmax"
[[boundary]]
type = "fixed"
set = "bottom"
[[walls]]
name = "roller"
shape = "cylinder"
radius = 10.0
length = 30.0
normal = [0, 1, 0]
point = [20, 10, 30]
nodes = "top"
friction = 0.3
motion = { segments = [{ to = 1.0, translation = [0, 0, -5] }, { to = 2.0, translation = [10, 0, 0] }] }
[analysis]
type = "static"
end_time = 2.0
step = 0.5
"#;

fn warnings(report: &str) -> Vec<&str> {
    report
        .lines()
        .filter_map(|l| l.trim().strip_prefix("warning: "))
        .collect()
}

#[test]
fn the_seal_as_meant_has_no_warning() {
    let dir = temp_dir("warn-clean");
    let r = check(&dir, SEAL).unwrap();
    assert!(warnings(&r).is_empty(), "{r}");
    assert!(r.contains("surfaces: none"), "{r}");
}

#[test]
fn mooney_rivlin_constants_in_pa_under_mpa_are_flagged() {
    let dir = temp_dir("warn-pa");
    let deck = SEAL
        .replace("C10 = 0.5", "C10 = 5e5")
        .replace("C01 = 0.125", "C01 = 1.25e5");
    let r = check(&dir, &deck).unwrap();
    let w = warnings(&r);
    assert_eq!(w.len(), 1, "{r}");
    assert!(
        w[0].starts_with("materials[0].C10 + C01 (`rubber`) = 625000 is 1.250e12 Pa")
            && w[0].contains("length mm, mass t")
            && w[0].contains("is it in another unit?"),
        "{r}"
    );
}

#[test]
fn steel_in_mpa_under_si_units_and_a_density_in_kg_per_m3_under_mm_are_flagged() {
    let dir = temp_dir("warn-steel");
    let steel = r#"
name = "steel"
model = "j2"
E = 210000.0
nu = 0.3
yield_stress = 250.0
density = 7850.0
"#;
    let deck = SEAL.replace(
        "name = \"rubber\"\nmodel = \"mooney-rivlin\"\nC10 = 0.5\nC01 = 0.125\nnu = 0.45\n",
        steel,
    );
    let deck = deck.replace("material = \"rubber\"", "material = \"steel\"");
    // In mm-t-s: E and the yield stress are right, the density (kg/m³) is 1e12 too big.
    let r = check(&dir, &deck).unwrap();
    let w = warnings(&r);
    assert_eq!(w.len(), 1, "{r}");
    assert!(
        w[0].starts_with("materials[0].density (`steel`) = 7850 is 7.850e15 kg/m³"),
        "{r}"
    );
    // In m-kg-s with the geometry scaled to metres: E and the yield stress are MPa
    // values read as Pa (yield / E still plausible), the density right.
    let si = deck
        .replace("units = \"mm-t-s\"", "units = \"m-kg-s\"")
        .replace("size = [40, 20, 20]", "size = [0.04, 0.02, 0.02]")
        .replace("point = [20, 10, 30]", "point = [0.02, 0.01, 0.03]")
        .replace("radius = 10.0", "radius = 0.01")
        .replace("length = 30.0", "length = 0.03")
        .replace("[0, 0, -5]", "[0, 0, -0.005]")
        .replace("[10, 0, 0]", "[0.01, 0, 0]");
    let r = check(&dir, &si).unwrap();
    let w = warnings(&r);
    assert_eq!(w.len(), 2, "{r}");
    assert!(
        w[0].starts_with("materials[0].E (`steel`) = 210000 is 2.100e5 Pa"),
        "{r}"
    );
    assert!(
        w[1].starts_with("materials[0].yield_stress (`steel`) = 250 is 2.500e2 Pa"),
        "{r}"
    );
}

#[test]
fn geometry_in_metres_under_mm_is_flagged() {
    let dir = temp_dir("warn-size");
    let deck = SEAL.replace("size = [40, 20, 20]", "size = [0.04, 0.02, 0.02]");
    let r = check(&dir, &deck).unwrap();
    let w = warnings(&r);
    assert_eq!(w.len(), 1, "{r}");
    assert!(
        w[0].contains("bounding box diagonal is 4.8990e-2")
            && w[0].contains("4.899e-5 m")
            && w[0].contains("another length unit"),
        "{r}"
    );
}

#[test]
fn a_motion_that_ends_after_the_analysis_is_flagged() {
    let dir = temp_dir("warn-end");
    let deck = SEAL.replace("end_time = 2.0", "end_time = 1.5");
    let r = check(&dir, &deck).unwrap();
    let w = warnings(&r);
    assert_eq!(
        w,
        ["walls[0].motion.segments[1].to = 2 is after analysis.end_time = 1.5 (`roller`): the run ends with 50 % of this segment done"],
        "{r}"
    );
}

#[test]
fn free_rigid_body_modes_are_flagged_before_the_solve() {
    let dir = temp_dir("warn-rbm");
    // No support at all, the roller 1 mm above the block: all six modes.
    let deck = SEAL
        .replace("[[boundary]]\ntype = \"fixed\"\nset = \"bottom\"\n", "")
        .replace("point = [20, 10, 30]", "point = [20, 10, 31]");
    let r = check(&dir, &deck).unwrap();
    let w = warnings(&r);
    assert_eq!(w.len(), 1, "{r}");
    assert!(
        w[0].starts_with("supports: 0 support(s), and the walls touching at t = 0, leave 6 rigid-body mode(s) of this static model free")
            && w[0].contains("unless contact (walls) closes first"),
        "{r}"
    );
    // Touching at t = 0 along the line x = 20, the roller holds z and the rotation about
    // x (the line runs along y): four modes left.
    let deck = SEAL.replace("[[boundary]]\ntype = \"fixed\"\nset = \"bottom\"\n", "");
    let r = check(&dir, &deck).unwrap();
    assert!(
        warnings(&r)[0].contains("leave 4 rigid-body mode(s)"),
        "{r}"
    );
    // The base held in z only: it can still slide in x and y and turn about z.
    let deck = SEAL.replace(
        "set = \"bottom\"\n",
        "set = \"bottom\"\ncomponents = [\"z\"]\n",
    );
    let r = check(&dir, &deck).unwrap();
    let w = warnings(&r);
    assert_eq!(w.len(), 1, "{r}");
    assert!(w[0].contains("leave 3 rigid-body mode(s)"), "{r}");
    for m in ["translation x", "translation y", "rotation about z"] {
        assert!(w[0].contains(m), "{m}: {r}");
    }
    // Implicit dynamics: inertia holds it; no warning.
    let deck = SEAL
        .replace("[[boundary]]\ntype = \"fixed\"\nset = \"bottom\"\n", "")
        .replace("nu = 0.45\n", "nu = 0.45\ndensity = 1.1e-9\n")
        .replace("type = \"static\"", "type = \"implicit\"");
    let r = check(&dir, &deck).unwrap();
    assert!(
        warnings(&r).iter().all(|w| !w.contains("rigid-body")),
        "{r}"
    );
}

#[test]
fn a_missing_end_time_is_named_missing() {
    let dir = temp_dir("warn-missing");
    let deck = SEAL.replace("end_time = 2.0\n", "");
    let e = check(&dir, &deck).unwrap_err().to_string();
    assert!(e.contains("analysis.end_time: missing"), "{e}");
}

#[test]
fn no_built_in_scene_raises_a_sanity_warning() {
    for (name, _, _) in alfe::scene::BUILTIN {
        let r = alfe::app::check(name, 1, &alfe::scene::Overrides::default()).unwrap();
        let odd: Vec<&str> = warnings(&r)
            .into_iter()
            .filter(|w| {
                [
                    "another unit",
                    "length unit",
                    "rigid-body",
                    "after analysis.end_time",
                    "same unit",
                ]
                .iter()
                .any(|k| w.contains(k))
            })
            .collect();
        assert!(odd.is_empty(), "{name}: {odd:?}");
    }
}
