//! Small-sliding pairs, a bolt, a coupling and two analysis steps through an LS-DYNA
//! `.k` (`alfe export`, then `alfe import`): the imported deck has the same entries and
//! its run the same history (bolt force, pair forces, coupling displacement) to 1e-9.

mod common;
use common::*;

/// bolt-bar (`tests/bolt-bar.toml`: a tied pair and a bolt) with a coupling loaded in the
/// second of two steps (the bolt's force in the first). The frictional pair is
/// bolted-bracket's `joint`, checked entry by entry in `lsdyna_roundtrip.rs`.
const DECK: &str = r#"
[scene]
name = "pairs-k"
units = "mm-t-s"
[[materials]]
name = "m"
model = "linear-elastic"
E = 1000.0
nu = 0.0
[[parts]]
name = "p1"
material = "m"
mesh = { kind = "box", origin = [0, 0, 0], size = [4, 4, 10], cells = [2, 2, 3] }
[[parts]]
name = "p2"
material = "m"
mesh = { kind = "box", origin = [0, 0, 10], size = [4, 4, 10], cells = [2, 2, 3] }
[[parts]]
name = "p3"
material = "m"
mesh = { kind = "box", origin = [0, 0, 20], size = [4, 4, 20], cells = [3, 3, 5] }
[[node_sets]]
name = "bottom"
group = "zmin"
part = "p1"
[[node_sets]]
name = "top"
group = "zmax"
part = "p3"
[[surfaces]]
name = "p1_top"
group = "zmax"
part = "p1"
[[surfaces]]
name = "p2_bottom"
group = "zmin"
part = "p2"
[[surfaces]]
name = "p2_top"
group = "zmax"
part = "p2"
[[surfaces]]
name = "p3_bottom"
group = "zmin"
part = "p3"
[[boundary]]
type = "fixed"
set = "bottom"
[[boundary]]
type = "fixed"
set = "top"
[[curves]]
name = "up"
points = [[0, 0], [1, 1]]
[[steps]]
name = "pre"
duration = 1.0
[[steps]]
name = "pull"
duration = 1.0
step = 0.5
[[pairs]]
name = "glue"
tracked = "p2_bottom"
reference = "p1_top"
tied = true
[[bolts]]
name = "bolt1"
tracked = "p3_bottom"
reference = "p2_top"
force = 1000.0
step = "pre"
[[couplings]]
name = "head"
nodes = "p1_top"
force = { z = { value = 400.0, curve = "up", step = "pull" }, x = { value = 10.0, curve = "up", step = "pull" } }
[analysis]
type = "static"
step = 0.5
"#;

#[test]
fn pairs_bolt_coupling_and_steps_round_trip_through_a_keyword_file() {
    let dir = temp_dir("pairs-k");
    let src = dir.join("original.toml");
    std::fs::write(&src, DECK).unwrap();
    let k = dir.join("pairs.k");
    let left = alfe::app::export::export(src.to_str().unwrap(), &k).unwrap();
    assert!(left.is_empty(), "{left:?}");
    let back = dir.join("back.toml");
    alfe::app::import::import(&k, &back).unwrap();
    let text = std::fs::read_to_string(&back).unwrap();
    for want in [
        "[[pairs]]\nname = \"glue\"",
        "tied = true",
        "[[bolts]]\nname = \"bolt1\"\ntracked = \"p3_bottom\"\nreference = \"p2_top\"\nforce = 1e3",
        "lock_at = 1e0",
        "[[couplings]]\nname = \"head\"\nnodes = \"p1_top\"",
        "name = \"pre\"",
        "name = \"pull\"",
        "Every keyword was translated",
    ] {
        assert!(text.contains(want), "`{want}` not in\n{text}");
    }
    let a = run_deck("pairs-k-a", DECK);
    let b = run_deck_file("pairs-k-b", &back);
    for c in [
        "time",
        "analysis_step",
        "bolt1.force",
        "glue.fz",
        "head.uz",
        "head.ux",
    ] {
        let (x, y) = (column(&a, c), column(&b, c));
        assert_eq!(x.len(), y.len(), "{c}");
        let scale = x.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-30);
        for (p, q) in x.iter().zip(&y) {
            assert!((p - q).abs() <= 1e-9 * scale, "{c}: {p} vs {q}");
        }
    }
}
