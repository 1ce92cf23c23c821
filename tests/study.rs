//! The study's ground (issue 17): every built-in scene's quantities of interest parse and
//! read columns its history has; the verification scenes meet their references within
//! the tolerances their decks declare; and `scripts/study --quick` writes its tables and
//! charts, with zero penetration in every ALM configuration that finishes; on a deck
//! without quantities it compares every force's history, and its summary agrees with its
//! table (issue 38).

mod common;
use common::*;
use std::path::Path;
use std::process::Command;

/// Every built-in scene declares quantities, and every quantity with a tolerance has a
/// reference (a deck could not be read otherwise).
#[test]
fn every_builtin_scene_declares_its_quantities() {
    for (name, _, text) in alfe::scene::BUILTIN {
        let src = alfe::scene::Source {
            text: text.to_string(),
            dir: ".".into(),
            label: name.to_string(),
        };
        let scene = alfe::scene::read(&src).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(
            !scene.run.quantities.is_empty(),
            "{name} declares no quantities"
        );
    }
}

/// The verification scenes' answers, as `alfe run` reports them in summary.json, are
/// within the tolerances their decks declare (analytic solutions, published values).
#[test]
fn verification_scenes_meet_their_references() {
    for name in [
        "patch-hex8",
        "patch-tet4",
        "cube-stretch",
        "cantilever",
        "coupled-cantilever",
        "contact-patch",
        "sliding-block",
        "clip-tensile",
        "cook-membrane",
        "hertz-sphere",
        "bar-vibration",
        "scordelis-lo",
    ] {
        let out = run_deck(&format!("verify-{name}"), &builtin(name));
        let q = &out.summary.quantities;
        let checked: Vec<_> = q.iter().filter(|q| q.within.is_some()).collect();
        assert!(!checked.is_empty(), "{name}: no quantity with a reference");
        for v in checked {
            eprintln!(
                "{name}: {} = {:?} (reference {:?}, error {:?}, tolerance {:?})",
                v.name, v.value, v.reference, v.error, v.tolerance
            );
            assert_eq!(
                v.within,
                Some(true),
                "{name}: {} = {:?} is outside {:?} of {:?}",
                v.name,
                v.value,
                v.tolerance,
                v.reference
            );
        }
    }
}

/// A quantity that reads a column the run does not have is refused before the run,
/// naming the field and the columns there are; a malformed expression at reading.
#[test]
fn quantity_mistakes_name_the_field() {
    let bad_col = builtin("cube-stretch")
        + "\n[[quantities]]\nname = \"oops\"\nexpression = \"x1.fx + nowhere.fz\"\n";
    let e = try_run_deck("q-col", &bad_col).err().unwrap().to_string();
    assert!(
        e.contains("quantities[2].expression") && e.contains("`nowhere.fz`") && e.contains("x1.fx"),
        "{e}"
    );
    for (extra, field) in [
        ("expression = \"1 +\"", "quantities[2].expression"),
        (
            "expression = \"x1.fx\"\nat = 1.0\nover = \"max\"",
            "quantities[2]",
        ),
        (
            "expression = \"x1.fx\"\ntolerance = 0.1",
            "quantities[2].tolerance",
        ),
        (
            "expression = \"x1.fx\"\nover = \"mean\"",
            "quantities[2].over",
        ),
    ] {
        let deck =
            builtin("cube-stretch") + &format!("\n[[quantities]]\nname = \"oops\"\n{extra}\n");
        let e = try_run_deck("q-bad", &deck).err().unwrap().to_string();
        assert!(e.contains(field), "{extra}: {e}");
    }
}

/// `scripts/study --quick` on two contact scenes writes each scene's table, JSON and
/// charts and the summary; every ALM configuration that finishes has zero penetration
/// (within the solver's tolerance, 1e-6 mm).
#[test]
fn quick_study_writes_its_tables_and_charts() {
    let dir = temp_dir("study");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let o = Command::new("/usr/bin/python3")
        .arg(root.join("scripts/study"))
        .args(["sliding-block", "contact-patch", "--quick", "--budget", "8"])
        .arg("--out")
        .arg(&dir)
        .arg("--bin")
        .arg(env!("CARGO_BIN_EXE_alfe"))
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .output()
        .expect("cannot run scripts/study");
    let (so, se) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(o.status.success(), "scripts/study failed:\n{so}\n{se}");
    let summary = std::fs::read_to_string(dir.join("summary.md")).unwrap();
    for scene in ["sliding-block", "contact-patch"] {
        assert!(summary.contains(&format!("[{scene}]")), "{summary}");
        let d = dir.join(scene);
        for f in [
            "study.md",
            "study.json",
            "error-time.png",
            "stability.png",
            "iterations.png",
        ] {
            let p = d.join(f);
            let n = std::fs::metadata(&p).map(|m| m.len()).unwrap_or(0);
            assert!(n > 500, "{}: {n} bytes", p.display());
        }
        let js: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(d.join("study.json")).unwrap()).unwrap();
        let results = js["results"].as_array().unwrap();
        assert!(
            results.len() >= 5,
            "{scene}: {} configurations",
            results.len()
        );
        let mut alm_finished = 0;
        for r in results {
            if r["contact"] == "alm" && r["finished"] == true {
                alm_finished += 1;
                let pen = r["max_penetration"].as_f64().unwrap();
                assert!(pen <= 1e-6, "{scene} {}: penetration {pen}", r["config"]);
            }
        }
        assert!(
            alm_finished >= 3,
            "{scene}: {alm_finished} ALM runs finished"
        );
    }
    // --report rebuilds the tables from study.json alone: the same study.md.
    let before = std::fs::read_to_string(dir.join("sliding-block/study.md")).unwrap();
    std::fs::remove_file(dir.join("sliding-block/study.md")).unwrap();
    let o = Command::new("/usr/bin/python3")
        .arg(root.join("scripts/study"))
        .args(["--report", "sliding-block", "--out"])
        .arg(&dir)
        .output()
        .expect("cannot run scripts/study --report");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let after = std::fs::read_to_string(dir.join("sliding-block/study.md")).unwrap();
    assert_eq!(before, after, "--report gives another study.md");
}

/// A row of study.md's table: the configuration, whether it finished, and each
/// quantity's error in percent (None where the table shows "–").
struct Row {
    config: String,
    finished: bool,
    errors: Vec<Option<f64>>,
}

/// study.md's table: (the quantity columns' names, the rows).
fn study_table(md: &str) -> (Vec<String>, Vec<Row>) {
    let mut lines = md.lines().skip_while(|l| !l.starts_with("| config |"));
    let cells = |l: &str| -> Vec<String> {
        l.trim_matches('|')
            .split(" | ")
            .map(|c| c.trim().to_string())
            .collect()
    };
    let head = cells(lines.next().expect("no table in study.md"));
    let first_q = head.iter().position(|c| c == "max pen.").unwrap() + 1;
    let names = head[first_q..]
        .iter()
        .map(|c| c.trim_end_matches(" (err)").to_string())
        .collect();
    let rows = lines
        .skip(1)
        .take_while(|l| l.starts_with("| "))
        .map(|l| {
            let c = cells(l);
            let errors = c[first_q..]
                .iter()
                .map(|cell| {
                    let e = cell.split_once(" (")?.1.strip_suffix(" %)")?;
                    Some(e.parse::<f64>().unwrap())
                })
                .collect();
            Row {
                config: c[0].clone(),
                finished: c[1] == "yes",
                errors,
            }
        })
        .collect();
    (names, rows)
}

/// `scripts/study` on a deck without `[[quantities]]` (sliding-block's, with at most 5
/// iterations per step: measured, BFGS and JFNK then stop in their first step) compares
/// every force's history against the most refined finished run's, charts every one, keeps
/// the files of the runs that stopped, and writes a summary that agrees with its table:
/// the count of finished runs, the fastest accurate ones and the pick; penalty's forces
/// (178 N against ALM's 233 N at the peak) show their error.
#[test]
fn study_without_quantities_compares_every_force() {
    let dir = temp_dir("study-forces");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = builtin("sliding-block");
    let (deck, quantities) = text.split_at(text.find("[[quantities]]").unwrap());
    assert!(
        quantities
            .lines()
            .filter(|l| l.starts_with('['))
            .all(|l| l == "[[quantities]]"),
        "sliding-block has tables after its quantities"
    );
    std::fs::write(
        dir.join("forces.toml"),
        format!("{deck}\n[solver]\nmax_iterations = 5\n"),
    )
    .unwrap();
    let study = |args: &[&str]| {
        Command::new("/usr/bin/python3")
            .arg(root.join("scripts/study"))
            .args(args)
            .arg("--out")
            .arg(dir.join("out"))
            .arg("--bin")
            .arg(env!("CARGO_BIN_EXE_alfe"))
            .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
            .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
            .output()
            .expect("cannot run scripts/study")
    };
    let deck_path = dir.join("forces.toml");
    let o = study(&[deck_path.to_str().unwrap(), "--quick", "--budget", "3"]);
    let (so, se) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(o.status.success(), "scripts/study failed:\n{so}\n{se}");
    let d = dir.join("out/sliding-block");
    let md = std::fs::read_to_string(d.join("study.md")).unwrap();
    let js: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("study.json")).unwrap()).unwrap();
    let results = js["results"].as_array().unwrap();
    let wall = |config: &str| {
        results.iter().find(|r| r["config"] == config).unwrap()["wall_s"]
            .as_f64()
            .unwrap()
    };

    // Progress: one line per run, for people (no JSON).
    assert!(!so.lines().any(|l| l.starts_with('{')), "{so}");
    for r in results {
        let c = r["config"].as_str().unwrap();
        assert!(so.contains(&format!("] {c}: ")), "no line for {c}:\n{so}");
    }

    // The quantities are the history's forces: the reaction set and the wall.
    let (names, rows) = study_table(&md);
    assert_eq!(names, ["top.f", "floor.f"], "{md}");
    assert_eq!(rows.len(), results.len(), "{md}");

    // The summary from the table: how many finished, the fastest accurate, the pick.
    let finished: Vec<&Row> = rows.iter().filter(|r| r.finished).collect();
    let stopped: Vec<&Row> = rows.iter().filter(|r| !r.finished).collect();
    assert!(
        md.contains(&format!(
            "- Stability: {} of {} configurations finished",
            finished.len(),
            rows.len()
        )),
        "{md}"
    );
    assert!(finished.len() >= 3 && !stopped.is_empty(), "{md}");
    assert!(!md.contains("No configuration finished"), "{md}");
    let mut accurate: Vec<&Row> = finished
        .iter()
        .copied()
        .filter(|r| r.errors.iter().all(|e| e.is_some_and(|e| e <= 1.0)))
        .collect();
    accurate.sort_by(|a, b| wall(&a.config).total_cmp(&wall(&b.config)));
    let fastest_line = md
        .lines()
        .find(|l| l.starts_with("- Fastest within 1 %"))
        .unwrap_or_else(|| panic!("{md}"));
    let listed: Vec<&str> = fastest_line
        .rsplit_once(": ")
        .unwrap()
        .1
        .trim_end_matches('.')
        .split(", ")
        .map(|x| x.split(' ').next().unwrap())
        .collect();
    let expected: Vec<&str> = accurate.iter().take(3).map(|r| r.config.as_str()).collect();
    assert_eq!(listed, expected, "{md}");
    assert!(
        md.contains(&format!("- Pick: {} (ALM", expected[0])),
        "{md}"
    );

    // Penalty's forces are off by more than 10 % (its normal force), ALM's within 1 %.
    for r in &finished {
        let worst = r.errors.iter().map(|e| e.unwrap()).fold(0.0, f64::max);
        if r.config.starts_with("penalty") {
            assert!(worst > 10.0, "{}: {worst} %\n{md}", r.config);
        } else {
            assert!(worst <= 1.0, "{}: {worst} %\n{md}", r.config);
        }
    }

    // A run that stopped keeps its files, and study.md names them; the others are gone.
    for r in &rows {
        let run = d.join("runs").join(&r.config);
        if r.finished {
            assert!(!run.exists(), "{} kept", run.display());
            continue;
        }
        assert!(
            md.contains(&format!("(its files: `runs/{}/`)", r.config)),
            "{md}"
        );
        for f in ["log.txt", "stderr.txt"] {
            assert!(run.join(f).exists(), "{}: no {f}", run.display());
        }
    }

    // Every chart is drawn, and the error chart has a panel per force with every
    // finished run in it.
    for png in ["error-time.png", "stability.png", "iterations.png"] {
        let bytes = std::fs::read(d.join(png)).unwrap();
        assert!(
            bytes.starts_with(b"\x89PNG") && bytes.len() > 10_000,
            "{png}: {} bytes",
            bytes.len()
        );
    }
    let charts: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("charts.json")).unwrap()).unwrap();
    let panels = charts["error-time.png"].as_array().unwrap();
    let charted: Vec<&str> = panels
        .iter()
        .map(|p| p["quantity"].as_str().unwrap())
        .collect();
    assert_eq!(charted, names, "{charts}");
    for p in panels {
        let points: Vec<&str> = p["points"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x["config"].as_str().unwrap())
            .collect();
        let done: Vec<&str> = finished.iter().map(|r| r.config.as_str()).collect();
        assert_eq!(points, done, "{}", p["quantity"]);
    }

    // --report rebuilds the same study.md from study.json.
    std::fs::remove_file(d.join("study.md")).unwrap();
    let o = study(&["--report", "sliding-block"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(std::fs::read_to_string(d.join("study.md")).unwrap(), md);
}
