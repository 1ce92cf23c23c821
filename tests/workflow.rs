//! The analyst's workflow (issue 16), through the `alfe` binary as users run it: the
//! command line, the run's record and log, progress lines, the per-iteration history,
//! times without drift, and restarts on 1 and 2 ranks.

mod common;
use common::*;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const ALFE: &str = env!("CARGO_BIN_EXE_alfe");

/// One launch at a time (2-rank jobs on a 2-core machine starve each other).
static LAUNCH: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// `alfe ARGS` in `dir` on `ranks` ranks (1: no mpirun), with a time limit.
fn alfe(dir: &Path, ranks: usize, args: &[&str]) -> Output {
    let _one = LAUNCH.lock().unwrap_or_else(|e| e.into_inner());
    let mut cmd = Command::new("timeout");
    cmd.arg("180");
    if ranks > 1 {
        cmd.args(["mpirun", "--oversubscribe", "-n", &ranks.to_string()]);
    }
    cmd.arg(ALFE).args(args).current_dir(dir);
    cmd.env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .env("OMPI_MCA_mpi_yield_when_idle", "1");
    let out = cmd.output().expect("cannot launch alfe");
    assert_ne!(out.status.code(), Some(124), "alfe {args:?} hung");
    out
}

fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).to_string(),
        String::from_utf8_lossy(&o.stderr).to_string(),
    )
}

fn ok(o: Output) -> String {
    let (so, se) = text(&o);
    assert!(
        o.status.success(),
        "alfe failed ({:?}):\n{so}\n{se}",
        o.status.code()
    );
    so
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// history.csv as a header and rows of numbers, without the wall-time columns.
fn numbers(dir: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = read(&dir.join("history.csv"));
    let mut lines = text.lines();
    let head: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let keep: Vec<usize> = (0..head.len())
        .filter(|&i| !head[i].ends_with("_s"))
        .collect();
    let rows = lines
        .map(|l| {
            let v: Vec<&str> = l.split(',').collect();
            keep.iter().map(|&i| v[i].parse().unwrap()).collect()
        })
        .collect();
    (keep.iter().map(|&i| head[i].clone()).collect(), rows)
}

/// The largest difference between two runs' history rows (matched by step number),
/// relative to each column's largest value, over the rows of `b`.
fn history_gap(a: &Path, b: &Path) -> f64 {
    let (ha, ra) = numbers(a);
    let (hb, rb) = numbers(b);
    assert_eq!(ha, hb, "history columns differ");
    let mut worst = 0.0f64;
    for row in &rb {
        let other = ra
            .iter()
            .find(|r| r[0] == row[0])
            .unwrap_or_else(|| panic!("step {} missing", row[0]));
        for c in 1..row.len() {
            let scale = ra.iter().map(|r| r[c].abs()).fold(1e-300, f64::max);
            worst = worst.max((row[c] - other[c]).abs() / scale.max(1e-12));
        }
    }
    worst
}

fn scratch(name: &str) -> PathBuf {
    temp_dir(&format!("workflow-{name}"))
}

/// A run leaves its record: `deck.toml` (the deck as read, with alfe's version and
/// commit, the command line and the date) that runs again as it stands to the same
/// answers, `log.txt` with the progress lines and the final line, and summary.json's
/// `run`.
#[test]
fn a_run_leaves_its_record_and_log() {
    let dir = scratch("record");
    let first = ok(alfe(&dir, 1, &["sliding-block", "--out=a"]));
    let deck = read(&dir.join("a/deck.toml"));
    assert!(
        deck.contains(&format!("alfe {}", env!("CARGO_PKG_VERSION"))),
        "{deck}"
    );
    assert!(
        deck.contains("commit ") && deck.contains("# command: "),
        "{deck}"
    );
    assert!(deck.contains("sliding-block --out=a"), "{deck}");
    assert!(
        deck.contains("friction_threshold = \"multiplier\""),
        "defaults filled in:\n{deck}"
    );
    let log = read(&dir.join("a/log.txt"));
    let last = first.lines().last().unwrap();
    assert!(
        log.ends_with(&format!("{last}\n")),
        "log:\n{log}\nstdout ends {last}"
    );
    assert!(log.contains("step    1"), "{log}");
    let summary: serde_json::Value =
        serde_json::from_str(&read(&dir.join("a/summary.json"))).unwrap();
    let run = &summary["run"];
    assert_eq!(run["ranks"], 1);
    assert_eq!(run["version"], env!("CARGO_PKG_VERSION"));
    assert!(run["started"].as_str().unwrap().ends_with('Z'), "{run}");
    assert!(!run["commit"].as_str().unwrap().is_empty());
    // The echo runs to the same answers.
    ok(alfe(&dir, 1, &["a/deck.toml", "-q", "-o", "b"]));
    assert!(history_gap(&dir.join("a"), &dir.join("b")) == 0.0);
}

/// The command line as users write it: `alfe DECK`, `--out=DIR` and `-o DIR`, short
/// flags, help per subcommand, the version with its commit, and one clear line with
/// exit code 2 for a mistake.
#[test]
fn command_line_forms() {
    let dir = scratch("cli");
    std::fs::write(dir.join("my.toml"), builtin("cube-stretch")).unwrap();
    ok(alfe(&dir, 1, &["my.toml", "-q", "-o", "x", "-s", "jfnk"]));
    let s: serde_json::Value = serde_json::from_str(&read(&dir.join("x/summary.json"))).unwrap();
    assert_eq!(s["solver"], "jfnk");
    let help = ok(alfe(&dir, 1, &["check", "--help"]));
    assert!(
        help.contains("--ranks") && help.contains("Usage: alfe check"),
        "{help}"
    );
    let help = ok(alfe(&dir, 1, &["help", "run"]));
    assert!(
        help.contains("--restart") && help.contains("--stop-after"),
        "{help}"
    );
    let v = ok(alfe(&dir, 1, &["--version"]));
    assert!(
        v.starts_with(&format!("alfe {} (", env!("CARGO_PKG_VERSION"))),
        "{v}"
    );
    for (args, want) in [
        (vec!["run", "--bogus"], "unexpected argument '--bogus'"),
        (vec!["run", "-s", "gauss"], "invalid value 'gauss'"),
        (vec!["check", "--ranks", "0"], "--ranks"),
        (vec!["scene", "show"], "<NAME>"),
    ] {
        let o = alfe(&dir, 1, &args);
        let (_, se) = text(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {se}");
        let lines: Vec<&str> = se.lines().filter(|l| !l.trim().is_empty()).collect();
        assert_eq!(lines.len(), 1, "{args:?}: {se}");
        assert!(
            lines[0].starts_with("alfe: error: ") && lines[0].contains(want),
            "{se}"
        );
    }
}

/// Progress lines give each wall's force and the time left; step times are the decimal
/// times a user reads (0.3, not 0.30000000000000004).
#[test]
fn progress_shows_wall_forces_and_times_do_not_drift() {
    let dir = scratch("progress");
    let out = ok(alfe(&dir, 1, &["cylinder-press", "-o", "p"]));
    let step3 = out.lines().find(|l| l.starts_with("step    3")).unwrap();
    assert!(
        step3.contains("roller=(") && step3.contains("base=("),
        "{step3}"
    );
    assert!(step3.contains("eta "), "{step3}");
    let hist = read(&dir.join("p/history.csv"));
    let times: Vec<&str> = hist
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(1).unwrap())
        .collect();
    assert_eq!(&times[..4], &["0.1", "0.2", "0.3", "0.4"], "{times:?}");
    assert!(times.iter().all(|t| t.len() <= 4), "{times:?}");
}

/// `--iterations` writes every iteration of every attempt, failed ones with why, and
/// the iterations add up to the summary's count.
#[test]
fn iterations_csv_has_every_attempt() {
    let dir = scratch("iterations");
    // Too few iterations for the first, large step: it fails and is cut.
    let deck = edit(
        &edit(&builtin("cylinder-press"), "step = 0.1", "step = 0.5"),
        "nonlinear = \"newton\"",
        "nonlinear = \"newton\"\nmax_iterations = 4",
    );
    std::fs::write(dir.join("d.toml"), deck).unwrap();
    ok(alfe(&dir, 1, &["d.toml", "-q", "-o", "i", "--iterations"]));
    let csv = read(&dir.join("i/iterations.csv"));
    let rows: Vec<Vec<String>> = csv
        .lines()
        .skip(1)
        .map(|l| {
            let (l, method) = l.rsplit_once(',').unwrap();
            assert_eq!(method, "newton", "{l}");
            let (head, outcome) = l.split_at(l.match_indices(',').nth(5).unwrap().0);
            let mut v: Vec<String> = head.split(',').map(String::from).collect();
            v.push(outcome[1..].to_string());
            v
        })
        .collect();
    let failed: Vec<&Vec<String>> = rows.iter().filter(|r| r[6].starts_with('"')).collect();
    assert!(!failed.is_empty(), "a failed attempt expected:\n{csv}");
    assert!(
        failed[0][6].contains("no convergence in 4 iterations"),
        "{:?}",
        failed[0]
    );
    assert!(
        rows.iter().any(|r| r[1] == "2"),
        "a second attempt expected"
    );
    let converged = rows.iter().filter(|r| r[6] == "converged").count();
    let s: serde_json::Value = serde_json::from_str(&read(&dir.join("i/summary.json"))).unwrap();
    assert_eq!(converged as u64, s["steps"].as_u64().unwrap());
    // Rows per attempt = iterations + 1 (the residual before the first correction).
    let attempts = rows.iter().filter(|r| r[4] == "0").count();
    assert_eq!(
        (rows.len() - attempts) as u64,
        s["nonlinear_iterations"].as_u64().unwrap()
    );
}

/// The times of an `.xmf`'s first block (every block has the same steps).
fn block_times(xmf: &str) -> Vec<String> {
    let first = xmf
        .split("CollectionType=\"Temporal\"")
        .nth(1)
        .unwrap_or("");
    let first = first.split("CollectionType=\"Temporal\"").next().unwrap();
    first
        .split("<Time Value=\"")
        .skip(1)
        .map(|s| s.split('"').next().unwrap().to_string())
        .collect()
}

/// A run stopped after step k and restarted gives the uninterrupted run's answers (the
/// history from step k + 1 on within 1e-10), static with frictional contact and hybrid
/// elements, and implicit dynamics with a J2 bar against a wall; on 2 ranks too; its
/// `.xmf` shows the whole run. A restart with another deck, into its own directory, or
/// with nothing to restart from is refused with the reason.
#[test]
fn a_restarted_run_gives_the_uninterrupted_answer() {
    let dir = scratch("restart");
    for (scene, k, ranks) in [
        ("cylinder-press", "4", 1),
        ("cylinder-press", "6", 2),
        ("taylor-bar", "20", 1),
    ] {
        let tag = format!("{scene}-{ranks}");
        let full = format!("{tag}-full");
        let part = format!("{tag}-part");
        ok(alfe(
            &dir,
            ranks,
            &[scene, "-q", "-o", &full, "--partitions", "parts"],
        ));
        let stopped = ok(alfe(
            &dir,
            ranks,
            &[
                scene,
                "-q",
                "-o",
                &part,
                "--stop-after",
                k,
                "--partitions",
                "parts",
            ],
        ));
        assert!(
            stopped.contains(&format!("stopped after step {k}")),
            "{stopped}"
        );
        ok(alfe(
            &dir,
            ranks,
            &["run", "--restart", &part, "-q", "--partitions", "parts"],
        ));
        let again = dir.join(format!("{part}-restart"));
        // The history goes on from the earlier run's rows: every step once.
        let (_, rows) = numbers(&again);
        let (_, whole) = numbers(&dir.join(&full));
        let steps: Vec<f64> = rows.iter().map(|r| r[0]).collect();
        let want: Vec<f64> = whole.iter().map(|r| r[0]).collect();
        assert_eq!(steps, want, "{tag}: steps of the restarted history");
        // Its .xmf covers the whole run: the earlier run's output steps (in that run's
        // file, by a relative path), then its own, at the uninterrupted run's times.
        let xmf = |d: &std::path::Path| read(&d.join(format!("{scene}.xmf")));
        let (carried, whole_xmf) = (xmf(&again), xmf(&dir.join(&full)));
        assert_eq!(
            block_times(&carried),
            block_times(&whole_xmf),
            "{tag}: times of the restarted .xmf"
        );
        assert!(
            carried.contains(&format!(
                ">../{part}/{scene}.h5:/steps/000000/displacement<"
            )),
            "{tag}: {carried}"
        );
        let gap = history_gap(&dir.join(&full), &again);
        eprintln!("{tag}: restart differs by {gap:e}");
        assert!(gap < 1e-10, "{tag}: restart differs by {gap:e}");
        let s: serde_json::Value =
            serde_json::from_str(&read(&again.join("summary.json"))).unwrap();
        let s_full: serde_json::Value =
            serde_json::from_str(&read(&dir.join(&full).join("summary.json"))).unwrap();
        assert_eq!(
            s["restarted_from"]["step"].as_u64(),
            Some(k.parse().unwrap())
        );
        // Quantities over the run (peaks included) match the uninterrupted run's.
        let q = |s: &serde_json::Value| -> Vec<f64> {
            s["quantities"]
                .as_array()
                .unwrap()
                .iter()
                .map(|q| q["value"].as_f64().unwrap_or(f64::NAN))
                .collect()
        };
        let (qa, qb) = (q(&s_full), q(&s));
        assert!(!qa.is_empty(), "{tag}: the scene declares quantities");
        for (a, b) in qa.iter().zip(&qb) {
            assert!(
                (a - b).abs() <= 1e-8 * a.abs().max(1e-12),
                "{tag}: quantities {qa:?} vs {qb:?}"
            );
        }
    }
    // Refusals: another deck, the same directory, nothing to restart from.
    let part = "cylinder-press-1-part";
    for (args, want) in [
        (vec!["cube-stretch", "--restart", part], "another deck"),
        (
            vec!["run", "--restart", part, "-o", part],
            "another directory",
        ),
        (
            vec!["cylinder-press", "--restart", "parts"],
            "no restart files",
        ),
    ] {
        let o = alfe(&dir, 1, &args);
        let (_, se) = text(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {se}");
        assert!(se.contains(want), "{args:?}: {se}");
    }
    // Another rank count is refused too.
    let o = alfe(
        &dir,
        2,
        &[
            "run",
            "--restart",
            part,
            "-o",
            "two",
            "--partitions",
            "parts",
        ],
    );
    let (_, se) = text(&o);
    assert_eq!(o.status.code(), Some(2), "{se}");
    assert!(se.contains("rank"), "{se}");
}

/// Penalty friction's state survives a restart: `sliding-block --contact penalty`
/// (elastic slip carried between steps; step 11 is retried and softens the stick of the
/// nodes that cycled there) stopped after step 12 and restarted gives the uninterrupted
/// run's history within 1e-10, on 1 and 2 ranks. The restart is not told `--contact`:
/// the run's `deck.toml` says `method = "penalty"` (it used to keep the deck's ALM, and
/// the restart was refused as "another partition of the model").
#[test]
fn a_restarted_penalty_run_keeps_its_elastic_slip() {
    let dir = scratch("restart-penalty");
    for ranks in [1, 2] {
        let (full, part) = (format!("full-{ranks}"), format!("part-{ranks}"));
        let parts = ["--partitions", "parts"];
        let pen = ["sliding-block", "--contact", "penalty", "-q"];
        ok(alfe(
            &dir,
            ranks,
            &[&pen[..], &["-o", &full], &parts[..]].concat(),
        ));
        let stop = ["-o", &part, "--stop-after", "12"];
        ok(alfe(
            &dir,
            ranks,
            &[&pen[..], &stop[..], &parts[..]].concat(),
        ));
        let record = read(&dir.join(&part).join("deck.toml"));
        assert!(record.contains("method = \"penalty\""), "{record}");
        ok(alfe(
            &dir,
            ranks,
            &[&["run", "--restart", &part, "-q"], &parts[..]].concat(),
        ));
        let gap = history_gap(&dir.join(&full), &dir.join(format!("{part}-restart")));
        eprintln!("penalty on {ranks} rank(s): restart differs by {gap:e}");
        assert!(gap < 1e-10, "{ranks} rank(s): restart differs by {gap:e}");
    }
}

/// A panel of forces.png as plots.json describes it: title, x label, y label, x range.
type Panel = (String, String, String, [f64; 2]);

/// The panels `scripts/plot` drew into `plots/forces.png` of `run` (its plots.json).
fn force_panels(run: &Path) -> Vec<Panel> {
    let js: serde_json::Value = serde_json::from_str(&read(&run.join("plots/plots.json"))).unwrap();
    js["charts"]["forces.png"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            let s = |k: &str| p[k].as_str().unwrap().to_string();
            let x = |i: usize| p["x_range"][i].as_f64().unwrap();
            (s("title"), s("xlabel"), s("ylabel"), [x(0), x(1)])
        })
        .collect()
}

/// `scripts/plot RUN_DIR` draws the forces and the convergence of any run (here a deck
/// of the user's, with its iterations) without code, with the deck's units on the axes;
/// a wall that moves is drawn against its displacement along each phase of its motion
/// (the floor at rest, then sliding along +x; the seal's roller pressed 5 mm along −z,
/// then slid 10 mm along +x, where against `ux` alone the press was a vertical line).
#[test]
fn plot_draws_any_run() {
    let dir = scratch("plot");
    std::fs::write(dir.join("mine.toml"), builtin("sliding-block")).unwrap();
    ok(alfe(
        &dir,
        1,
        &["mine.toml", "-q", "-o", "r", "--iterations"],
    ));
    let seal = read(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/seal.toml"));
    let coarse = edit(&seal, "cells = [16, 8, 8]", "cells = [8, 4, 4]");
    std::fs::write(dir.join("seal.toml"), coarse).unwrap();
    ok(alfe(&dir, 1, &["seal.toml", "-q", "-o", "s"]));
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/plot");
    for run in ["r", "s"] {
        let o = Command::new("/usr/bin/python3")
            .arg(&script)
            .arg(dir.join(run))
            .output()
            .expect("cannot run scripts/plot");
        let (so, se) = text(&o);
        assert!(o.status.success(), "scripts/plot failed:\n{so}\n{se}");
        for png in ["forces.png", "convergence.png"] {
            let p = dir.join(run).join("plots").join(png);
            assert!(so.contains(png), "{so}");
            let bytes = std::fs::read(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            assert!(
                bytes.starts_with(b"\x89PNG") && bytes.len() > 20_000,
                "{png}: {} bytes",
                bytes.len()
            );
        }
    }
    let js: serde_json::Value =
        serde_json::from_str(&read(&dir.join("r/plots/plots.json"))).unwrap();
    assert_eq!(js["charts"]["convergence.png"][0]["xlabel"], "time [s]");
    let (r, s) = (force_panels(&dir.join("r")), force_panels(&dir.join("s")));
    assert!(
        r.iter().chain(&s).all(|p| p.2 == "force [N]"),
        "{r:?}\n{s:?}"
    );
    let range = |panels: &[Panel], title: &str, xlabel: &str| {
        panels
            .iter()
            .find(|p| p.0.starts_with(title) && p.1 == xlabel)
            .unwrap_or_else(|| panic!("no panel {title} against {xlabel}: {panels:?}"))
            .3
    };
    // Reaction sets against time; the floor at rest while the block is pressed, then
    // sliding 0.5 mm; the roller pressed 5 mm, then slid 10 mm from where the press ended.
    range(&r, "top", "time [s]");
    range(&s, "base", "time [s]");
    range(&r, "floor at rest", "time [s]");
    let x = range(&r, "floor moving", "floor displacement along +x [mm]");
    assert!(x[0].abs() < 1e-9 && (x[1] - 0.5).abs() < 1e-9, "{x:?}");
    let x = range(&s, "roller moving", "roller displacement along −z [mm]");
    assert!((x[1] - 5.0).abs() < 1e-9, "{x:?}");
    let x = range(&s, "roller moving", "roller displacement along +x [mm]");
    assert!(x[0].abs() < 1e-9 && (x[1] - 10.0).abs() < 1e-9, "{x:?}");
}

/// An element that inverts on one rank is named by every rank (it used to be "an
/// element on another rank failed" on 2 ranks): the cantilever's far end is pushed
/// 20 mm back into it, in slabs along x, so the far end's elements are on rank 1.
#[test]
fn an_inverted_element_is_named_on_two_ranks() {
    let dir = scratch("crush");
    let deck = edit(&builtin("cantilever"), "step = 0.1\n", "step = 0.1\nmin_step = 0.1\n")
        + "\n[[node_sets]]\nname = \"far_end\"\ngroup = \"xmax\"\n\n[[boundary]]\ntype = \"displacement\"\n\
           set = \"far_end\"\ncomponents = [\"x\"]\nvalue = -20.0\n\n[partition]\nmethod = \"slabs\"\naxis = \"x\"\n";
    std::fs::write(dir.join("crush.toml"), deck).unwrap();
    for ranks in [1, 2] {
        let o = alfe(
            &dir,
            ranks,
            &[
                "crush.toml",
                "-q",
                "-o",
                &format!("o{ranks}"),
                "--partitions",
                "p",
            ],
        );
        let (_, se) = text(&o);
        assert_eq!(o.status.code(), Some(3), "{ranks} ranks: {se}");
        let line = se
            .lines()
            .find(|l| l.starts_with("alfe: error"))
            .unwrap_or_default();
        assert!(
            line.contains("element ") && line.contains("det F") && !line.contains("another rank"),
            "{ranks} ranks: {line}"
        );
    }
}
