//! Nothing moves: the built-in scenes give the results recorded before the model became
//! a list of contributions (main 8c586b6, `tests/baseline/*.json`), on 1 and 2 ranks —
//! every history column but timings and linear-solver internals within 1e-8 of its
//! scale, the nonlinear iteration and retry counts of every step exactly, and the last
//! step's displacement field. `scripts/check-baseline` does the work; the suite runs
//! every recorded run but `rubber-indent` (about 20 s on 1 and on 2 ranks since the
//! hybrid element), which the script runs on request.

use std::process::Command;

const ALFE: &str = env!("CARGO_BIN_EXE_alfe");

#[test]
fn builtin_scenes_match_the_recorded_results() {
    let root = env!("CARGO_MANIFEST_DIR");
    let tags: Vec<String> = std::fs::read_dir(format!("{root}/tests/baseline"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .filter_map(|f| f.strip_suffix(".json").map(str::to_string))
        .filter(|t| !t.starts_with("rubber-indent."))
        .collect();
    assert!(tags.len() >= 30, "recorded runs missing: {tags:?}");
    let out = Command::new("/usr/bin/python3")
        .arg(format!("{root}/scripts/check-baseline"))
        .args(["--bin", ALFE, "--only", &tags.join(",")])
        .output()
        .expect("cannot run scripts/check-baseline with /usr/bin/python3");
    let text = String::from_utf8_lossy(&out.stdout);
    eprintln!("{text}{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "results moved:\n{text}");
    assert!(
        text.contains(&format!("{} of {} the same", tags.len(), tags.len())),
        "{text}"
    );
}
