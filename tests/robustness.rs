//! Runs that must fail cleanly (issue 16): an overflowing load is a failure, never
//! convergence.

mod common;
use common::*;

/// A traction of 1e200 on `cantilever` overflows the residual's norm: the run fails and
/// says so (it used to end with `converged: true`, 0 iterations, u = 0).
#[test]
fn overflowing_load_is_not_convergence() {
    let deck = edit(
        &builtin("cantilever"),
        "traction = [0.0, 0.0, -30.0]",
        "traction = [0.0, 0.0, -1e200]",
    );
    match try_run_deck("overflow", &deck) {
        Ok(out) => {
            assert!(!out.summary.converged, "an overflowing load converged");
            let msg = &out.summary.message;
            assert!(msg.contains("not finite"), "{msg}");
        }
        Err(e) => assert!(e.to_string().contains("not finite"), "{e}"),
    }
}

/// The scene name becomes file names: one that leaves the output directory, or is too
/// long for Open MPI's buffers, is refused naming `scene.name`.
#[test]
fn scene_names_must_be_file_names() {
    for bad in [
        "../escaped",
        "a/b",
        "",
        ".hidden",
        &"x".repeat(300),
        "sp ace",
    ] {
        let deck = edit(
            &builtin("cantilever"),
            "name = \"cantilever\"",
            &format!("name = \"{bad}\""),
        );
        let e = try_run_deck("bad-name", &deck).err().map(|e| e.to_string());
        assert!(
            e.as_deref()
                .is_some_and(|e| e.contains("scene.name: expected 1 to 64")),
            "{bad:?}: {e:?}"
        );
    }
}

/// Fixed-size arrays with extra entries are refused by path (serde used to read the
/// first entries and drop the rest).
#[test]
fn extra_array_entries_are_refused() {
    let cases = [
        (
            "cantilever",
            "traction = [0.0, 0.0, -30.0]",
            "traction = [0.0, 0.0, -30.0, 7]",
            "loads[0]",
        ),
        (
            "scordelis-lo",
            "max = [25.0, 16.2, 19.3]",
            "max = [25.0, 16.2, 19.3, 5]",
            "node_sets[3].box.max: expected 3 entries, got 4",
        ),
        (
            "rubber-indent",
            "motion = { translation = [0, 0, -50] }",
            "motion = { segments = [{ to = 1.0, translation = [0, 0, -50, 7] }] }",
            "walls[0].motion.segments[0].translation: expected 3 entries, got 4",
        ),
    ];
    for (scene, from, to, want) in cases {
        let deck = edit(&builtin(scene), from, to);
        let e = try_run_deck("extra", &deck).err().map(|e| e.to_string());
        assert!(
            e.as_deref().is_some_and(|e| e.contains(want)),
            "{to}: {e:?}"
        );
    }
    // A curve point with a third entry.
    let deck = edit(
        &builtin("cantilever"),
        "[analysis]",
        "[[curves]]\nname = \"c\"\npoints = [[0, 0], [1, 1, 123]]\n[analysis]",
    );
    let e = try_run_deck("extra-curve", &deck)
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("curves[0].points[1]: expected 2 entries, got 3"),
        "{e}"
    );
}

/// Errors inside tagged tables (`kind = ...`, `type = ...`) name the key, not only the
/// table.
#[test]
fn errors_in_tagged_tables_name_the_key() {
    let cases = [
        (
            "cells = [40, 4, 4]",
            "cells = [40, -3, 4]",
            "parts[0].mesh.cells[1]: invalid value: integer `-3`",
        ),
        (
            "traction = [0.0, 0.0, -30.0]",
            "traction = [0.0, 0.0, -30.0, 7]",
            "loads[0].traction: invalid length 4",
        ),
    ];
    for (from, to, want) in cases {
        let deck = edit(&builtin("cantilever"), from, to);
        let e = try_run_deck("tagged", &deck).err().map(|e| e.to_string());
        assert!(
            e.as_deref().is_some_and(|e| e.contains(want)),
            "{to}: {e:?}"
        );
    }
    let deck = edit(
        &builtin("scordelis-lo"),
        "set = \"crown\"\ncomponents = [\"y\"]",
        "set = \"crown\"\ncomponents = [\"Y\"]",
    );
    let e = try_run_deck("tagged-variant", &deck)
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("boundary[2].components[0]: unknown variant `Y`"),
        "{e}"
    );
}

/// Absurd sizes are refused with the numbers before anything is allocated (they used to
/// panic with `capacity overflow` or ask for 8–192 GB).
#[test]
fn absurd_sizes_are_refused_before_allocating() {
    let cases = [
        (
            "cells = [40, 4, 4]",
            "cells = [3, 4611686018427387904, 3]",
            "parts[0].mesh.cells: makes 4.151e19 elements; expected at most 2e7",
        ),
        (
            "cells = [40, 4, 4]",
            "cells = [2000, 2000, 2000]",
            "parts[0].mesh.cells: makes 8.000e9 elements",
        ),
        (
            "step = 0.1",
            "step = 1e-300",
            "analysis.step: 1e-300 makes 1.000e300 steps",
        ),
        (
            "step = 0.1",
            "step = 1e-9",
            "analysis.step: 1e-9 makes 1.000e9 steps",
        ),
        (
            "end_time = 1.0",
            "end_time = 1e9",
            "analysis.step: 1e-1 makes 1.000e10 steps",
        ),
    ];
    for (from, to, want) in cases {
        let deck = edit(&builtin("cantilever"), from, to);
        let e = try_run_deck("sizes", &deck).err().map(|e| e.to_string());
        assert!(
            e.as_deref().is_some_and(|e| e.contains(want)),
            "{to}: {e:?}"
        );
    }
}

/// A busy output directory is refused: a second run into it says which run holds it
/// (two runs into one `--out` used to both exit 0 with one run's results lost).
#[test]
fn a_busy_output_directory_is_refused() {
    let dir = temp_dir("busy");
    let deck = dir.join("deck.toml");
    std::fs::write(&deck, builtin("cantilever")).unwrap();
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    // This test's own process holds it (alive, this host).
    let host = std::fs::read_to_string("/proc/sys/kernel/hostname").unwrap();
    std::fs::write(
        out.join(".alfe-lock"),
        format!("{} {}\n", std::process::id(), host.trim()),
    )
    .unwrap();
    let opts = alfe::app::RunOptions {
        target: deck.display().to_string(),
        out: Some(out.clone()),
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
    let e = alfe::app::run(&alfe::parallel::SerialComm, &opts)
        .err()
        .map(|e| e.to_string());
    assert!(
        e.as_deref()
            .is_some_and(|e| e.contains("another alfe run (pid") && e.contains("--out")),
        "{e:?}"
    );
    assert!(!out.join("history.csv").exists(), "nothing written");
    // Once the lock is gone, the run goes through and leaves no lock behind.
    std::fs::remove_file(out.join(".alfe-lock")).unwrap();
    alfe::app::run(&alfe::parallel::SerialComm, &opts).unwrap();
    assert!(out.join("history.csv").exists() && !out.join(".alfe-lock").exists());
}

/// A Gmsh physical surface inside the volume (between two hexes) is refused as a
/// loaded surface: a traction there acted on one side only (1 N applied instead of 4).
#[test]
fn interior_surface_groups_are_refused() {
    let id = |i: usize, j: usize, k: usize| 1 + i + 3 * (j + 2 * k);
    let mut s = String::from("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n2\n2 1 \"mid\"\n3 2 \"solid\"\n$EndPhysicalNames\n");
    s += "$Entities\n0 0 1 1\n1 1 0 0 1 1 1 1 1 0\n1 0 0 0 2 1 1 1 2 0\n$EndEntities\n";
    s += "$Nodes\n1 12 1 12\n3 1 0 12\n";
    for n in 1..=12 {
        s += &format!("{n}\n");
    }
    for k in 0..2 {
        for j in 0..2 {
            for i in 0..3 {
                s += &format!("{i} {j} {k}\n");
            }
        }
    }
    s += "$EndNodes\n$Elements\n2 3 1 3\n";
    s += &format!(
        "2 1 3 1\n1 {} {} {} {}\n",
        id(1, 0, 0),
        id(1, 1, 0),
        id(1, 1, 1),
        id(1, 0, 1)
    );
    s += "3 1 5 2\n";
    for (t, i) in [(2, 0), (3, 1)] {
        let c = [
            (0, 0, 0),
            (1, 0, 0),
            (1, 1, 0),
            (0, 1, 0),
            (0, 0, 1),
            (1, 0, 1),
            (1, 1, 1),
            (0, 1, 1),
        ];
        let ns: Vec<String> = c
            .iter()
            .map(|&(a, b, d)| id(i + a, b, d).to_string())
            .collect();
        s += &format!("{t} {}\n", ns.join(" "));
    }
    s += "$EndElements\n";
    let dir = temp_dir("interior-msh");
    let file = dir.join("two.msh");
    std::fs::write(&file, s).unwrap();
    let deck = format!(
        r#"
[scene]
name = "interior"
units = "mm-t-s"
[[materials]]
name = "m"
model = "linear-elastic"
E = 1000.0
nu = 0.3
[[parts]]
name = "p"
material = "m"
mesh = {{ kind = "gmsh", file = "{}" }}
[[surfaces]]
name = "mid"
group = "mid"
[[loads]]
type = "traction"
surface = "mid"
traction = [1, 0, 0]
[analysis]
type = "static"
end_time = 1.0
step = 1.0
"#,
        file.display()
    );
    let e = try_run_deck("interior", &deck).err().unwrap().to_string();
    assert!(
        e.contains("surfaces[0].group: surface `mid`: 1 of its 1 faces are inside the volume"),
        "{e}"
    );
}

/// A non-finite origin names `origin` (it was reported as an inverted element); a binary
/// .msh cut short after its header names the byte where it ends (binary MSH is read
/// since issue 36; it was "stream did not contain valid UTF-8").
#[test]
fn non_finite_origins_and_binary_meshes_name_the_field() {
    let deck = edit(
        &builtin("cantilever"),
        "origin = [0, 0, 0]",
        "origin = [0, 0, -inf]",
    );
    let e = try_run_deck("inf-origin", &deck).err().unwrap().to_string();
    assert!(
        e.contains("parts[0].mesh.origin: expected three finite coordinates"),
        "{e}"
    );
    let dir = temp_dir("binary-msh-file");
    let file = dir.join("b.msh");
    let mut bytes = b"$MeshFormat\n4.1 1 8\n".to_vec();
    bytes.extend_from_slice(&[1, 0, 0, 0, 0xff, 0xfe, 0x80]);
    std::fs::write(&file, bytes).unwrap();
    let deck = edit(
        &builtin("cantilever"),
        r#"mesh = { kind = "box", origin = [0, 0, 0], size = [10, 1, 1], cells = [40, 4, 4] }"#,
        &format!(r#"mesh = {{ kind = "gmsh", file = "{}" }}"#, file.display()),
    );
    let e = try_run_deck("binary-msh", &deck).err().unwrap().to_string();
    assert!(
        e.contains("parts[0].mesh.file") && e.contains("byte 24: expected $EndMeshFormat"),
        "{e}"
    );
}
