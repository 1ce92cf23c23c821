//! The study's ground (issue 17): every built-in scene's quantities of interest parse and
//! read columns its history has; the verification scenes meet their references within
//! the tolerances their decks declare; and `scripts/study --quick` writes its tables and
//! charts, with zero penetration in every ALM configuration that finishes.

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
