//! Helpers shared by the scene-level tests.
#![allow(dead_code)]

use alfe::app::{run, RunOptions, RunOutcome};
use alfe::parallel::SerialComm;
use std::path::{Path, PathBuf};

/// A fresh directory for one test.
pub fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("alfe-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The text of a built-in scene.
pub fn builtin(name: &str) -> String {
    alfe::scene::BUILTIN
        .iter()
        .find(|s| s.0 == name)
        .unwrap()
        .2
        .to_string()
}

/// Run a deck text in this process on one rank; results go to a temp dir.
pub fn run_deck(name: &str, text: &str) -> RunOutcome {
    try_run_deck(name, text).unwrap_or_else(|e| panic!("{name}: {e}"))
}

pub fn try_run_deck(name: &str, text: &str) -> alfe::Result<RunOutcome> {
    let dir = temp_dir(name);
    let deck = dir.join("deck.toml");
    std::fs::write(&deck, text).unwrap();
    try_run_deck_file(&dir, &deck)
}

/// Run a deck file where it lies (its relative mesh paths from its directory); results
/// go to a fresh temp dir.
pub fn run_deck_file(name: &str, deck: &std::path::Path) -> RunOutcome {
    let dir = temp_dir(&format!("{name}-run"));
    try_run_deck_file(&dir, deck).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn try_run_deck_file(dir: &std::path::Path, deck: &std::path::Path) -> alfe::Result<RunOutcome> {
    let opts = RunOptions {
        target: deck.display().to_string(),
        out: Some(dir.join("out")),
        partitions: dir.join("partitions"),
        repartition: false,
        quiet: true,
        solver: None,
        iterations: false,
        restart: None,
        stop_after: None,
        overrides: alfe::scene::Overrides::default(),
        export_system: None,
    };
    run(&SerialComm, &opts)
}

/// Replace exactly one occurrence of `from` (so a changed built-in scene fails loudly).
pub fn edit(text: &str, from: &str, to: &str) -> String {
    assert_eq!(
        text.matches(from).count(),
        1,
        "expected one `{from}` in the deck"
    );
    text.replacen(from, to, 1)
}

pub fn rel_err(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(f64::MIN_POSITIVE)
}

/// A published output field of a finished run (one rank: every row), at its last step.
pub fn field(out: &RunOutcome, name: &str) -> Vec<f64> {
    let t = out.steps.last().map_or(0.0, |s| s.time);
    out.model
        .field(&SerialComm, &out.u, t, name)
        .unwrap_or_else(|| panic!("no field {name}"))
}

/// Max over columns of ‖K e_j − (r(u + ε e_j) − r(u − ε e_j))/2ε‖ / ‖K‖_max, at a
/// perturbed state of a converged run (so nodes sit in several branches of the law).
pub fn jacobian_fd_error(out: &mut RunOutcome, seed: u64, amp: f64) -> f64 {
    let comm = SerialComm;
    let n = out.u.len();
    let mut s = seed;
    let mut rnd = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    };
    let u: Vec<f64> = out.u.iter().map(|&x| x + amp * rnd()).collect();
    let t = out.steps.last().unwrap().time;
    let mut k = out.model.new_matrix(&comm);
    out.model.jacobian(&comm, &u, t, &mut k).unwrap();
    let (mut worst, mut scale) = (0.0f64, 0.0f64);
    let eps = 1e-7;
    let mut rp = vec![0.0; n];
    let mut rm = vec![0.0; n];
    let mut e = vec![0.0; n];
    let mut ke = vec![0.0; n];
    for j in 0..n {
        e.iter_mut().for_each(|x| *x = 0.0);
        e[j] = 1.0;
        k.spmv(&comm, &e, &mut ke);
        let mut up = u.clone();
        up[j] += eps;
        out.model.residual(&comm, &up, t, &mut rp).unwrap();
        let mut um = u.clone();
        um[j] -= eps;
        out.model.residual(&comm, &um, t, &mut rm).unwrap();
        for i in 0..n {
            let fd = (rp[i] - rm[i]) / (2.0 * eps);
            worst = worst.max((fd - ke[i]).abs());
            scale = scale.max(ke[i].abs());
        }
    }
    worst / scale
}

/// A column of a run's history by name.
pub fn column(out: &RunOutcome, name: &str) -> Vec<f64> {
    let path = std::path::Path::new(&out.summary.output_dir).join("history.csv");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let i = head
        .iter()
        .position(|c| *c == name)
        .unwrap_or_else(|| panic!("no column {name} in {head:?}"));
    lines
        .map(|l| l.split(',').nth(i).unwrap().parse().unwrap())
        .collect()
}

/// A Gmsh 4.1 ASCII file of volume elements `volumes` (one physical volume "solid") and
/// physical surfaces (one entity each, a block per face type): element types follow the
/// node counts (faces: 3 tri3, 4 quad4, 6 tri6; volumes: 4 tet4, 6 prism6, 8 hex8, 10
/// tet10). Node tags are indices + 1.
pub fn gmsh_text(
    coords: &[[f64; 3]],
    surfaces: &[(&str, Vec<Vec<usize>>)],
    volumes: &[Vec<usize>],
) -> String {
    let face_type = |n: usize| match n {
        3 => 2,
        4 => 3,
        6 => 9,
        _ => panic!("no Gmsh face of {n} nodes"),
    };
    let volume_type = |n: usize| match n {
        4 => 4,
        6 => 6,
        8 => 5,
        10 => 11,
        _ => panic!("no Gmsh volume of {n} nodes"),
    };
    let mut blocks: Vec<(usize, usize, usize, Vec<&Vec<usize>>)> = Vec::new();
    for (i, (_, fs)) in surfaces.iter().enumerate() {
        for nn in [3, 4, 6] {
            let of: Vec<&Vec<usize>> = fs.iter().filter(|f| f.len() == nn).collect();
            if !of.is_empty() {
                blocks.push((2, i + 1, face_type(nn), of));
            }
        }
    }
    blocks.push((
        3,
        1,
        volume_type(volumes[0].len()),
        volumes.iter().collect(),
    ));
    let ns = surfaces.len();
    let mut s = format!(
        "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n{}\n",
        ns + 1
    );
    for (i, (g, _)) in surfaces.iter().enumerate() {
        s += &format!("2 {} \"{g}\"\n", i + 1);
    }
    s += &format!("3 9 \"solid\"\n$EndPhysicalNames\n$Entities\n0 0 {ns} 1\n");
    for i in 1..=ns {
        s += &format!("{i} 0 0 0 1 1 1 1 {i} 0\n");
    }
    s += "1 0 0 0 1 1 1 1 9 0\n$EndEntities\n";
    let n = coords.len();
    s += &format!("$Nodes\n1 {n} 1 {n}\n3 1 0 {n}\n");
    for i in 0..n {
        s += &format!("{}\n", i + 1);
    }
    for c in coords {
        s += &format!("{:.17e} {:.17e} {:.17e}\n", c[0], c[1], c[2]);
    }
    s += "$EndNodes\n";
    let ne: usize = blocks.iter().map(|b| b.3.len()).sum();
    s += &format!("$Elements\n{} {ne} 1 {ne}\n", blocks.len());
    let mut tag = 1;
    for (dim, entity, ty, es) in &blocks {
        s += &format!("{dim} {entity} {ty} {}\n", es.len());
        for e in es {
            let v: Vec<String> = e.iter().map(|n| (n + 1).to_string()).collect();
            s += &format!("{tag} {}\n", v.join(" "));
            tag += 1;
        }
    }
    s + "$EndElements\n"
}

/// The deck schema's verdict on each deck file (`alfe schema`, checked by Python's
/// `jsonschema` on the TOML read by `tomllib`): `Ok`, or the first error's message;
/// `Err("not TOML: ...")` where Python cannot read the file as TOML.
pub fn schema_verdicts(dir: &Path, decks: &[PathBuf]) -> Vec<Result<(), String>> {
    let schema = dir.join("deck.schema.json");
    std::fs::write(&schema, alfe::app::schema::deck_schema()).unwrap();
    let script = r#"
import json, sys, tomllib, jsonschema
schema = json.load(open(sys.argv[1]))
v = jsonschema.Draft202012Validator(schema)
for path in sys.argv[2:]:
    try:
        deck = tomllib.load(open(path, "rb"))
    except Exception as e:
        print(json.dumps(f"not TOML: {e}"))
        continue
    errors = sorted(v.iter_errors(deck), key=lambda e: list(e.path))
    print(json.dumps(None if not errors else f"{list(errors[0].path)}: {errors[0].message}"))
"#;
    let out = std::process::Command::new("/usr/bin/python3")
        .arg("-c")
        .arg(script)
        .arg(&schema)
        .args(decks)
        .output()
        .expect("python3");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(
            |l| match serde_json::from_str::<Option<String>>(l).unwrap() {
                None => Ok(()),
                Some(e) => Err(e),
            },
        )
        .collect()
}
