//! LS-DYNA keyword files both ways (issue 36): `alfe export` writes a scene as a `.k`,
//! `alfe import` reads it back. hertz-sphere (a translating rigid sphere) and a block
//! under nodal loads, pressure and a prescribed displacement come back with the same
//! answers node by node; the paper scenes kept under `examples/paper/` as `.k` import to
//! the built-in models (mesh, materials, formulations, supports, walls, velocities,
//! controls). `scripts/paper-examples` regenerates them and runs the round trips of the
//! paper scenes; a seeded fuzzer over a model file finds no panic in the importer.

// Index loops over xyz components read like the formulas.
#![allow(clippy::needless_range_loop)]

mod common;
use alfe::model::def::{ContributionDef, MaterialDef, Motion};
use alfe::scene::Scene;
use common::*;
use std::collections::BTreeMap;
use std::path::Path;

/// Export `deck` (text) to a `.k`, import it; the imported deck's path.
fn round_trip(name: &str, deck: &str) -> std::path::PathBuf {
    let dir = temp_dir(name);
    let src = dir.join("original.toml");
    std::fs::write(&src, deck).unwrap();
    let k = dir.join(format!("{name}.k"));
    let left = alfe::app::export::export(src.to_str().unwrap(), &k).unwrap();
    assert!(left.is_empty(), "{left:?}");
    let back = dir.join("back.toml");
    alfe::app::import::import(&k, &back).unwrap();
    back
}

/// Same displacements, node by node (the node order survives), to `tol` of the largest.
fn same_answers(name: &str, deck: &str, tol: f64) {
    let back = round_trip(name, deck);
    let a = run_deck(&format!("{name}-a"), deck);
    let b = run_deck_file(&format!("{name}-b"), &back);
    assert_eq!(a.steps.len(), b.steps.len());
    let (ua, ub) = (a.displacement_by_node(), b.displacement_by_node());
    assert_eq!(ua.len(), ub.len());
    let umax = ua
        .iter()
        .flat_map(|x| x.2)
        .fold(0.0f64, |m, v| m.max(v.abs()));
    let worst = ua
        .iter()
        .zip(&ub)
        .flat_map(|(x, y)| (0..3).map(move |k| (x.2[k] - y.2[k]).abs()))
        .fold(0.0f64, f64::max);
    assert!(
        umax > 0.0 && worst <= tol * umax,
        "{name}: {worst} of {umax}"
    );
}

#[test]
fn hertz_sphere_round_trips_through_a_keyword_file() {
    same_answers("k-hertz", &builtin("hertz-sphere"), 1e-9);
}

/// Nodal loads, a pressure (a segment set) and a prescribed displacement on a curve.
#[test]
fn loads_and_motions_round_trip() {
    let deck = r#"
[scene]
name = "k-loads"
units = "mm-t-s"
[[materials]]
name = "steel"
model = "neo-hookean"
E = 1000.0
nu = 0.3
[[parts]]
name = "block"
material = "steel"
mesh = { kind = "box", size = [4, 1, 1], cells = [8, 2, 2] }
[[node_sets]]
name = "root"
group = "xmin"
[[node_sets]]
name = "tip"
group = "xmax"
[[node_sets]]
name = "side"
group = "ymin"
[[surfaces]]
name = "top"
group = "zmax"
[[curves]]
name = "up-down"
points = [[0, 0], [0.5, 1], [1, 0.5]]
[[boundary]]
type = "fixed"
set = "root"
[[boundary]]
type = "displacement"
set = "side"
components = ["y"]
value = 0.01
curve = "up-down"
[[loads]]
type = "nodal"
set = "tip"
force = [2.0, 0.0, -1.0]
[[loads]]
type = "pressure"
surface = "top"
pressure = 0.5
curve = "up-down"
[analysis]
type = "static"
end_time = 1.0
step = 0.25
"#;
    same_answers("k-loads", deck, 1e-9);
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-11 * (1.0 + a.abs().max(b.abs()))
}

/// The response of a material at a few strains, compared variant by variant (a linear
/// hardening comes back as its two-point table, which is the same law).
fn same_material(a: &MaterialDef, b: &MaterialDef) -> bool {
    use MaterialDef::*;
    match (a, b) {
        (
            J2 {
                e,
                nu,
                hardening,
                density,
            },
            J2 {
                e: e2,
                nu: nu2,
                hardening: h2,
                density: d2,
            },
        ) => {
            close(*e, *e2)
                && close(*nu, *nu2)
                && close(*density, *d2)
                && [0.0, 0.01, 0.1, 0.5, 1.0, 2.0]
                    .iter()
                    .all(|&ep| close(hardening.yield_stress(ep).0, h2.yield_stress(ep).0))
        }
        _ => {
            let (x, y) = (
                serde_json::to_value(a).unwrap(),
                serde_json::to_value(b).unwrap(),
            );
            approx_json(&x, &y)
        }
    }
}

fn approx_json(a: &serde_json::Value, b: &serde_json::Value) -> bool {
    use serde_json::Value::*;
    match (a, b) {
        (Number(x), Number(y)) => close(x.as_f64().unwrap(), y.as_f64().unwrap()),
        (Array(x), Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(p, q)| approx_json(p, q))
        }
        (Object(x), Object(y)) => {
            x.len() == y.len()
                && x.iter()
                    .all(|(k, v)| y.get(k).is_some_and(|w| approx_json(v, w)))
        }
        _ => a == b,
    }
}

/// (component, nodes, value at sample times) of every prescribed component.
fn prescribed(s: &Scene) -> Vec<(usize, Vec<usize>, Vec<i64>)> {
    let mut out = Vec::new();
    for c in &s.model.constraints {
        let Motion::Uniform { value } = &c.motion else {
            panic!("a rotation in an exported scene");
        };
        for k in 0..3 {
            if c.comps[k] {
                let ts = [0.0, 0.1, 0.37, 0.5, 0.8, 1.0].map(|t| t * s.run.analysis.end_time);
                let v = ts
                    .map(|t| (value[k] * c.curve.eval(t) * 1e9).round() as i64)
                    .to_vec();
                out.push((k, s.model.node_sets[&c.set].clone(), v));
            }
        }
    }
    out.sort();
    out
}

/// Node → initial velocity (later entries win, as the model applies them).
fn velocities(s: &Scene) -> BTreeMap<usize, [i64; 3]> {
    let m = &s.model;
    let mut out = BTreeMap::new();
    for (set, v) in &m.initial_velocity {
        let nodes: Vec<usize> = match set.strip_prefix("part:") {
            Some(p) => {
                let p = m.part_names.iter().position(|n| n == p).unwrap() as u32;
                (0..m.mesh.n_elems())
                    .filter(|&e| m.mesh.elem_part[e] == p)
                    .flat_map(|e| m.mesh.elem_nodes(e).to_vec())
                    .collect()
            }
            None => m.node_sets[set].clone(),
        };
        for n in nodes {
            out.insert(n, v.map(|x| (x * 1e6).round() as i64));
        }
    }
    out
}

fn same_walls(a: &Scene, b: &Scene) {
    let walls = |s: &Scene| -> Vec<alfe::model::walls::WallDef> {
        s.model
            .contributions
            .iter()
            .filter_map(|c| match c {
                ContributionDef::Wall(w) => Some(w.clone()),
                _ => None,
            })
            .collect()
    };
    let (wa, wb) = (walls(a), walls(b));
    assert_eq!(wa.len(), wb.len());
    for (x, y) in wa.iter().zip(&wb) {
        assert_eq!(x.name, y.name);
        assert!(
            approx_json(
                &serde_json::to_value(&x.shape).unwrap(),
                &serde_json::to_value(&y.shape).unwrap()
            ),
            "{}: {:?} against {:?}",
            x.name,
            x.shape,
            y.shape
        );
        assert!(
            close(x.friction, y.friction) && x.method == y.method,
            "{}",
            x.name
        );
        assert_eq!(x.friction_threshold, y.friction_threshold, "{}", x.name);
        assert!(close(x.tangential_augmentation, y.tangential_augmentation));
        match (&x.body, &y.body) {
            (None, None) => {}
            (Some(p), Some(q)) => {
                assert_eq!(p.free, q.free, "{}: free DOFs", x.name);
                assert_eq!(p.trace, q.trace, "{}: traced points", x.name);
                assert!(close(p.mass, q.mass) && close(p.inertia, q.inertia));
                assert!(close(p.length, q.length), "{}", x.name);
            }
            _ => panic!("{}: an entity on one side only", x.name),
        }
        let (mut na, mut nb) = (x.nodes.clone(), y.nodes.clone());
        na.sort_unstable();
        nb.sort_unstable();
        assert_eq!(na, nb, "{}: tracked nodes", x.name);
        for t in [0.0, 0.3, 0.5, 1.0].map(|t| t * a.run.analysis.end_time) {
            let (p, q) = (x.motion.pose(t), y.motion.pose(t));
            // The pose's frame may turn about an axis the shape does not see (a sphere's,
            // a cylinder's about its axis), so the points the wall occupies are compared:
            // the origin and the local z axis.
            for k in 0..3 {
                assert!(
                    (p.origin[k] - q.origin[k]).abs() < 1e-9,
                    "{} at {t}",
                    x.name
                );
                assert!((p.r[k][2] - q.r[k][2]).abs() < 1e-12, "{} at {t}", x.name);
            }
        }
    }
}

/// Pairs (with their bolts' pretension) and couplings: the same entries, the same pairs in
/// the same order (the order sums run in) with the same weights.
fn same_pairs_and_couplings(name: &str, a: &Scene, b: &Scene) {
    let pairs = |s: &Scene| -> Vec<alfe::model::pairs::PairsDef> {
        s.model
            .contributions
            .iter()
            .filter_map(|c| match c {
                ContributionDef::Pairs(p) => Some(p.clone()),
                _ => None,
            })
            .collect()
    };
    let (pa, pb) = (pairs(a), pairs(b));
    assert_eq!(pa.len(), pb.len(), "{name}: pairs entries");
    for (x, y) in pa.iter().zip(&pb) {
        let n = &x.name;
        assert_eq!((n, x.tied, x.method), (&y.name, y.tied, y.method), "{name}");
        assert!(close(x.friction, y.friction), "{name}: {n}");
        assert_eq!(x.unpaired, y.unpaired, "{name}: {n}");
        assert_eq!(x.pairs.len(), y.pairs.len(), "{name}: {n}");
        for (p, q) in x.pairs.iter().zip(&y.pairs) {
            assert_eq!((p.node, &p.nodes), (q.node, &q.nodes), "{name}: {n}");
            assert!(close(p.area, q.area), "{name}: {n} area");
            for (u, v) in p.w.iter().zip(&q.w) {
                assert!((u - v).abs() < 1e-12, "{name}: {n} weights");
            }
        }
        match (&x.pretension, &y.pretension) {
            (None, None) => {}
            (Some(s), Some(t)) => {
                assert!(
                    close(s.force, t.force) && close(s.lock_at, t.lock_at),
                    "{name}: {n}"
                );
                assert_eq!(s.curve, t.curve, "{name}: {n}");
            }
            _ => panic!("{name}: {n}: a bolt on one side only"),
        }
    }
    let couplings = |s: &Scene| -> Vec<alfe::model::coupling::CouplingDef> {
        s.model
            .contributions
            .iter()
            .filter_map(|c| match c {
                ContributionDef::Coupling(p) => Some(p.clone()),
                _ => None,
            })
            .collect()
    };
    let (ca, cb) = (couplings(a), couplings(b));
    assert_eq!(ca.len(), cb.len(), "{name}: couplings");
    for (x, y) in ca.iter().zip(&cb) {
        assert_eq!((&x.name, &x.nodes), (&y.name, &y.nodes), "{name}");
        for (u, v) in x.weights.iter().zip(&y.weights) {
            assert!(close(*u, *v), "{name}: {} weights", x.name);
        }
    }
}

/// The built-in scene and the model imported from its `.k` are the same model.
fn same_model(name: &str, a: &Scene, b: &Scene) {
    let (ma, mb) = (&a.model, &b.model);
    assert_eq!(ma.mesh.kinds, mb.mesh.kinds, "{name}");
    assert_eq!(ma.mesh.conn, mb.mesh.conn, "{name}");
    let scale = ma
        .mesh
        .coords
        .iter()
        .flatten()
        .fold(1.0f64, |m, x| m.max(x.abs()));
    for (x, y) in ma.mesh.coords.iter().zip(&mb.mesh.coords) {
        for k in 0..3 {
            assert!(
                (x[k] - y[k]).abs() <= 1e-11 * scale,
                "{name}: {x:?} against {y:?}"
            );
        }
    }
    assert_eq!(ma.part_formulation, mb.part_formulation, "{name}");
    for (p, q) in ma.part_material.iter().zip(&mb.part_material) {
        assert!(
            same_material(&ma.materials[*p].1, &mb.materials[*q].1),
            "{name}: {:?} against {:?}",
            ma.materials[*p],
            mb.materials[*q]
        );
    }
    assert_eq!(prescribed(a), prescribed(b), "{name}: supports and motions");
    assert_eq!(velocities(a), velocities(b), "{name}: initial velocities");
    same_walls(a, b);
    same_pairs_and_couplings(name, a, b);
    let (x, y) = (&a.run.analysis, &b.run.analysis);
    assert_eq!((x.kind, x.scheme), (y.kind, y.scheme), "{name}");
    for (p, q) in [
        (x.end_time, y.end_time),
        (x.step, y.step),
        (x.min_step, y.min_step),
        (x.max_step, y.max_step),
        (x.rho_inf, y.rho_inf),
    ] {
        assert!(close(p, q), "{name}: analysis {p} against {q}");
    }
    let (s, t) = (&a.run.solver, &b.run.solver);
    assert_eq!(
        (s.kind, s.max_iterations, s.line_search, s.bfgs_reform),
        (t.kind, t.max_iterations, t.line_search, t.bfgs_reform),
        "{name}"
    );
}

/// Every paper scene under `examples/paper/` as a file of extension `ext` imports to the
/// built-in model.
fn paper_examples_import(ext: &str) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/paper");
    for name in [
        "taylor-bar",
        "clip-tensile",
        "rubber-indent",
        "sphere-roll",
        "panel-dent",
        "bolted-bracket",
        "b-pillar",
    ] {
        let file = dir.join(format!("{name}.{ext}"));
        let deck = temp_dir(&format!("paper-{ext}-{name}")).join(format!("{name}.toml"));
        alfe::app::import::import(&file, &deck).unwrap_or_else(|e| panic!("{name}: {e}"));
        let b = alfe::scene::read(&alfe::scene::load(deck.to_str().unwrap()).unwrap()).unwrap();
        let a = alfe::scene::read(&alfe::scene::load(name).unwrap()).unwrap();
        same_model(name, &a, &b);
    }
}

/// The paper scenes as `.k` files (the entities as `*CONTACT_ENTITY` on rigid parts)
/// import to the built-in models.
#[test]
fn paper_examples_import_to_the_built_in_models() {
    paper_examples_import("k");
}

/// The paper scenes as Abaqus/CalculiX `.inp` files (rigid walls and entities as
/// CalculiX's rigid layers, pairs, bolts and couplings as its keywords, the exact entries
/// on `** alfe` notes) import to the built-in models.
#[test]
fn paper_inp_examples_import_to_the_built_in_models() {
    paper_examples_import("inp");
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/paper");
    // A file edited after export: the notes still win, and the import says so.
    let text = std::fs::read_to_string(dir.join("rubber-indent.inp")).unwrap();
    let edited = text.replacen("\n*FRICTION\n0.1, ", "\n*FRICTION\n0.3, ", 1);
    assert_ne!(text, edited);
    let d = temp_dir("paper-inp-edited");
    let (inp, deck) = (d.join("edited.inp"), d.join("edited.toml"));
    std::fs::write(&inp, edited).unwrap();
    let r = alfe::app::import::import(&inp, &deck).unwrap();
    assert!(
        r.untranslated
            .iter()
            .any(|u| u.contains("changed after `alfe export`")),
        "{:?}",
        r.untranslated
    );
    let clean = d.join("clean.inp");
    std::fs::write(&clean, &text).unwrap();
    let r = alfe::app::import::import(&clean, &d.join("clean.toml")).unwrap();
    assert!(!r.untranslated.iter().any(|u| u.contains("changed after")));
}

/// A seeded fuzzer over a keyword file with a model (materials, sets, curves, a wall,
/// controls): `alfe import` never panics, and every refusal names the file and a line.
#[test]
fn fuzzed_keyword_models_never_panic_and_refusals_name_a_line() {
    let dir = temp_dir("k-fuzz-base");
    let src = dir.join("base.toml");
    let deck = edit(
        &edit(
            &builtin("hertz-sphere"),
            "cells = [20, 20, 20]",
            "cells = [2, 2, 2]",
        ),
        "box = { min = [0, 0, 0], max = [20, 20, 0] }",
        "group = \"zmax\"",
    );
    std::fs::write(&src, deck).unwrap();
    let k = dir.join("base.k");
    alfe::app::export::export(src.to_str().unwrap(), &k).unwrap();
    let base: Vec<String> = std::fs::read_to_string(&k)
        .unwrap()
        .lines()
        .map(String::from)
        .collect();
    let mut seed: u64 = std::env::var("ALFE_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(36);
    let mut next = move |n: usize| {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed % n as u64) as usize
    };
    let (mut accepted, mut refused) = (0, 0);
    for case in 0..300 {
        let mut lines = base.clone();
        for _ in 0..1 + next(3) {
            let i = next(lines.len());
            match next(5) {
                0 => lines[i] = lines[i].replace('1', "x"),
                1 => {
                    let cut = next(lines[i].len() + 1);
                    lines[i].truncate(cut);
                }
                2 => {
                    lines.remove(i);
                }
                3 => lines.insert(i, "*NO_SUCH_KEYWORD".into()),
                _ => lines[i] = lines[i].replace("e0", "e999"),
            }
        }
        let text = lines.join("\n") + "\n";
        let load = |p: &Path| -> Result<String, String> {
            if p == Path::new("m.k") {
                Ok(text.clone())
            } else {
                Err(format!("{}: no such file", p.display()))
            }
        };
        let got = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            alfe::app::import::lsdyna::import_k(Path::new("m.k"), Path::new("m.toml"), &load)
        }));
        match got {
            Err(_) => panic!("case {case} panicked on:\n{text}"),
            Ok(Ok(_)) => accepted += 1,
            Ok(Err(e)) => {
                refused += 1;
                assert!(e.contains("m.k:"), "case {case}: `{e}` names no line");
            }
        }
    }
    eprintln!("keyword model fuzz: {accepted} accepted, {refused} refused with a line");
    assert!(
        accepted > 30 && refused > 30,
        "{accepted} accepted, {refused} refused"
    );
}
