//! Elements that do not lie (issue 35): `alfe check` names every part's element types
//! and the formulation each actually gets; a formulation that does not apply to an
//! element type is an input error naming the part; a choice known to lock (tet4 or
//! standard hex8 with ν > 0.45, a sheet of elements that lock in bending) is a warning
//! in `check` and in the run's log; `auto` on a sheet takes EAS, and a 60 × 20 × 1
//! plate extruded from a Gmsh quad surface bends as beam theory says.

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

/// A 40 × 20 × 20 block of `element` (Mooney–Rivlin, ν as given), fixed at its base.
fn block(element: &str, nu: f64, formulation: Option<&str>) -> String {
    let form = formulation.map_or(String::new(), |f| format!("formulation = \"{f}\"\n"));
    format!(
        r#"
[scene]
name = "seal"
units = "mm-t-s"
[[materials]]
name = "rubber"
model = "mooney-rivlin"
C10 = 0.5
C01 = 0.125
nu = {nu}
[[parts]]
name = "block"
material = "rubber"
{form}mesh = {{ kind = "box", size = [40, 20, 20], cells = [4, 2, 2], element = "{element}" }}
[[node_sets]]
name = "bottom"
group = "zmin"
[[boundary]]
type = "fixed"
set = "bottom"
[analysis]
type = "static"
end_time = 1.0
step = 1.0
"#
    )
}

/// EAS and reduced on a tet4 part are refused, naming the part and field; `standard`,
/// `fbar` (the F-bar patch), `hybrid` (with a pressure per patch) and `auto` are
/// accepted.
#[test]
fn a_formulation_that_does_not_apply_to_tet4_is_an_error() {
    let dir = temp_dir("tet4-formulations");
    for form in ["eas", "reduced"] {
        let e = check(&dir, &block("tet4", 0.3, Some(form)))
            .expect_err(form)
            .to_string();
        assert!(
            e.contains(&format!(
                "parts[0].formulation: \"{form}\" does not apply to tet4 elements (part `block`: its 96 elements are tet4); tet4 has only the standard, fbar, hybrid formulations; set formulation = \"auto\" or \"standard\""
            )),
            "{form}: {e}"
        );
    }
    for form in [Some("standard"), Some("auto"), None] {
        let s = check(&dir, &block("tet4", 0.3, form)).unwrap();
        assert!(s.contains("\n    block: 96 tet4, standard\n"), "{s}");
        assert!(!s.contains("warning"), "{s}");
    }
    let s = check(&dir, &block("tet4", 0.3, Some("fbar"))).unwrap();
    assert!(
        s.contains("\n    block: 96 tet4, F-bar patch (8 tets share one volume ratio)\n"),
        "{s}"
    );
    let s = check(&dir, &block("tet4", 0.3, Some("hybrid"))).unwrap();
    assert!(
        s.contains("\n    block: 96 tet4, hybrid F-bar patch (8 tets share one volume ratio and a pressure unknown)\n"),
        "{s}"
    );
    // 12 patches of 8: 12 pressure blocks.
    assert!(
        s.contains("36 element pressure blocks (12 pressures)"),
        "{s}"
    );
    // An hourglass spring under auto on a tet4 part has no element to act on.
    let e = check(
        &dir,
        &edit(
            &block("tet4", 0.4995, None),
            "mesh = {",
            "hourglass = 1.0\nmesh = {",
        ),
    )
    .expect_err("hourglass on tet4")
    .to_string();
    assert!(
        e.contains("parts[0].hourglass: part `block` has no element with an hourglass spring"),
        "{e}"
    );
}

/// A nearly incompressible tet4 part under auto is the hybrid F-bar patch and quiet; with
/// `standard` check says "tet4, standard", warns and names auto's choice; hex8 under
/// auto is hybrid and quiet; hex8 with `standard` warns.
#[test]
fn nearly_incompressible_standard_elements_warn_in_check() {
    let dir = temp_dir("locking-check");
    let s = check(&dir, &block("tet4", 0.4995, None)).unwrap();
    assert!(
        s.contains("\n    block: 96 tet4, hybrid F-bar patch (8 tets share one volume ratio and a pressure unknown)\n"),
        "{s}"
    );
    assert!(!s.contains("warning"), "{s}");
    let s = check(&dir, &block("tet4", 0.4995, Some("standard"))).unwrap();
    assert!(
        s.contains("\n    block: 96 tet4, standard (locks: nu = 0.4995 > 0.45)\n"),
        "{s}"
    );
    assert!(
        s.contains("  warning: part `block` (parts[0]): 96 tet4 with the standard formulation lock at nu = 0.4995 > 0.45"),
        "{s}"
    );
    assert!(
        s.contains("use formulation = \"auto\" (here hybrid F-bar patch (8 tets share one volume ratio and a pressure unknown))"),
        "{s}"
    );
    let s = check(&dir, &block("hex8", 0.4995, None)).unwrap();
    assert!(s.contains("\n    block: 16 hex8, hybrid\n"), "{s}");
    assert!(!s.contains("warning"), "{s}");
    let s = check(&dir, &block("hex8", 0.4995, Some("standard"))).unwrap();
    assert!(
        s.contains("\n    block: 16 hex8, standard (locks: nu = 0.4995 > 0.45)\n"),
        "{s}"
    );
    assert!(
        s.contains("  warning: part `block` (parts[0]): 16 hex8 with the standard formulation lock at nu = 0.4995 > 0.45"),
        "{s}"
    );
    assert!(
        s.contains("use formulation = \"auto\" (here hybrid)"),
        "{s}"
    );
    // At the threshold and below: no warning.
    let s = check(&dir, &block("tet4", 0.45, None)).unwrap();
    assert!(!s.contains("warning"), "{s}");
}

/// The warning reaches the run's log (and stderr) once, at the start of `alfe run`.
#[test]
fn a_locking_choice_is_warned_in_the_run_log() {
    let name = "locking-run";
    let out = run_deck(name, &block("tet4", 0.4995, Some("standard")));
    drop(out);
    let dir = std::env::temp_dir().join(format!("alfe-test-{}-{name}", std::process::id()));
    let log = std::fs::read_to_string(dir.join("out").join("log.txt")).unwrap();
    let warns: Vec<&str> = log
        .lines()
        .filter(|l| l.starts_with("alfe: warning: "))
        .collect();
    assert_eq!(warns.len(), 1, "{log}");
    assert!(
        warns[0].contains("part `block` (parts[0]): 96 tet4 with the standard formulation lock at nu = 0.4995 > 0.45"),
        "{log}"
    );
    let record = std::fs::read_to_string(dir.join("out").join("deck.toml")).unwrap();
    assert!(
        record.contains("block: 96 tet4, standard (locks: nu = 0.4995 > 0.45)"),
        "{record}"
    );
}

/// The plate: a Gmsh quad4 mesh of the middle surface 60 × 20 (nx × ny quads), physical
/// curves `root` (x = 0) and `tip` (x = 60), physical surface `plate`.
fn plate_msh(nx: usize, ny: usize) -> String {
    plate_msh_of(nx, ny, false)
}

/// [`plate_msh`], its cells quads or (`tris`) each cut into two triangles, the diagonals
/// alternating like a chessboard's colours (Gmsh's transfinite "Alternate").
fn plate_msh_of(nx: usize, ny: usize, tris: bool) -> String {
    let id = |i: usize, j: usize| 1 + j * (nx + 1) + i;
    let mut s = String::from(
        "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n3\n1 1 \"root\"\n1 2 \"tip\"\n2 3 \"plate\"\n$EndPhysicalNames\n",
    );
    s += "$Entities\n0 2 1 0\n1 0 0 0 0 20 0 1 1 0\n2 60 0 0 60 20 0 1 2 0\n1 0 0 0 60 20 0 1 3 0\n$EndEntities\n";
    let nn = (nx + 1) * (ny + 1);
    s += &format!("$Nodes\n1 {nn} 1 {nn}\n2 1 0 {nn}\n");
    for k in 1..=nn {
        s += &format!("{k}\n");
    }
    for j in 0..=ny {
        for i in 0..=nx {
            s += &format!(
                "{:.17e} {:.17e} 0\n",
                60.0 * i as f64 / nx as f64,
                20.0 * j as f64 / ny as f64
            );
        }
    }
    s += "$EndNodes\n";
    let quads: Vec<[usize; 4]> = (0..ny)
        .flat_map(|j| (0..nx).map(move |i| (i, j)))
        .map(|(i, j)| [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)])
        .collect();
    let root: Vec<[usize; 2]> = (0..ny).map(|j| [id(0, j), id(0, j + 1)]).collect();
    let tip: Vec<[usize; 2]> = (0..ny).map(|j| [id(nx, j), id(nx, j + 1)]).collect();
    let facets: Vec<Vec<usize>> = if tris {
        quads
            .iter()
            .enumerate()
            .flat_map(|(k, q)| {
                if (k % nx + k / nx).is_multiple_of(2) {
                    [vec![q[0], q[1], q[2]], vec![q[0], q[2], q[3]]]
                } else {
                    [vec![q[0], q[1], q[3]], vec![q[1], q[2], q[3]]]
                }
            })
            .collect()
    } else {
        quads.iter().map(|q| q.to_vec()).collect()
    };
    let total = facets.len() + root.len() + tip.len();
    s += &format!("$Elements\n3 {total} 1 {total}\n");
    let mut tag = 0;
    s += &format!("1 1 1 {}\n", root.len());
    for e in &root {
        tag += 1;
        s += &format!("{tag} {} {}\n", e[0], e[1]);
    }
    s += &format!("1 2 1 {}\n", tip.len());
    for e in &tip {
        tag += 1;
        s += &format!("{tag} {} {}\n", e[0], e[1]);
    }
    s += &format!("2 1 {} {}\n", if tris { 2 } else { 3 }, facets.len());
    for q in &facets {
        tag += 1;
        let ns: Vec<String> = q.iter().map(|n| n.to_string()).collect();
        s += &format!("{tag} {}\n", ns.join(" "));
    }
    s + "$EndElements\n"
}

/// E and ν of the plate: steel's E and ν = 0, beam theory's assumption (with ν = 0.3 the
/// 20 mm wide plate is stiffened by its anticlastic curvature held at the root).
const PLATE_E: f64 = 210_000.0;

/// The plate deck: the sheet of `plate.msh` 1 mm thick with the sheet's defaults (one
/// element through the thickness, the surface in the middle), clamped at `root`, 14 N
/// along z at `tip` (a traction of 14 / (20 × 1) N/mm²).
fn plate(dir: &Path, formulation: Option<&str>) -> String {
    let file = dir.join("plate.msh");
    if !file.exists() {
        std::fs::write(&file, plate_msh(24, 8)).unwrap();
    }
    let form = formulation.map_or(String::new(), |f| format!("formulation = \"{f}\"\n"));
    format!(
        r#"
[scene]
name = "plate"
units = "mm-t-s"
[[materials]]
name = "steel"
model = "linear-elastic"
E = {PLATE_E}
nu = 0.0
[[parts]]
name = "plate"
material = "steel"
{form}mesh = {{ kind = "sheet", file = "{}", thickness = 1.0 }}
[[node_sets]]
name = "root"
group = "root"
[[surfaces]]
name = "tip"
group = "tip"
[[boundary]]
type = "fixed"
set = "root"
[[loads]]
type = "traction"
surface = "tip"
traction = [0, 0, 0.7]
[analysis]
type = "static"
end_time = 1.0
step = 1.0
[output]
displacements = ["tip"]
"#,
        file.display()
    )
}

/// The 60 × 20 × 1 plate (24 × 8 quads, the sheet's defaults: one layer) under a 14 N
/// tip load: `auto` takes EAS and deflects within 3 % of δ = F L³ / (3 E I) = 2.88 mm;
/// standard hex8 locks and `check` warns. Measured (printed): every formulation's tip
/// deflection against beam theory.
#[test]
fn a_sheet_takes_eas_by_default_and_bends_as_beam_theory_says() {
    let dir = temp_dir("plate-sheet");
    let i = 20.0 * 1.0f64.powi(3) / 12.0;
    let exact = 14.0 * 60.0f64.powi(3) / (3.0 * PLATE_E * i);
    let tip = |form: Option<&str>| {
        let out = run_deck(
            &format!("plate-{}", form.unwrap_or("auto")),
            &plate(&dir, form),
        );
        *column(&out, "tip.uz").last().unwrap()
    };
    let auto = tip(None);
    let mut measured = vec![format!("auto {auto:.4}")];
    for form in ["eas", "standard", "fbar", "hybrid", "reduced"] {
        if form == "hybrid" {
            continue; // linear-elastic: the hybrid element is refused
        }
        let d = tip(Some(form));
        measured.push(format!("{form} {d:.4} ({:.1} %)", 100.0 * d / exact));
        if form == "eas" {
            assert_eq!(d, auto, "auto on a sheet is EAS");
        }
        if form == "standard" {
            assert!(d < 0.3 * exact, "standard hex8 should lock: {d}");
        }
    }
    eprintln!("plate tip deflection, beam theory {exact:.4}: {measured:?}");
    assert!(
        rel_err(auto, exact) < 0.03,
        "auto {auto} vs beam theory {exact}"
    );
    // What check says of it: EAS, quiet; standard (and the others): a warning each.
    let s = check(&dir, &plate(&dir, None)).unwrap();
    assert!(
        s.contains("\n    plate: 192 hex8 (sheet, 1 through the thickness), EAS\n"),
        "{s}"
    );
    assert!(!s.contains("warning"), "{s}");
    for (form, said) in [
        ("standard", "standard"),
        ("fbar", "F-bar"),
        ("reduced", "reduced, hourglass 1"),
    ] {
        let s = check(&dir, &plate(&dir, Some(form))).unwrap();
        assert!(
            s.contains(&format!(
                "\n    plate: 192 hex8 (sheet, 1 through the thickness), {said} (locks: in bending, a sheet)\n"
            )),
            "{s}"
        );
        assert!(
            s.contains(&format!("  warning: part `plate` (parts[0]): a sheet of 192 hex8 (1 through the thickness) with the {said} formulation locks in bending")),
            "{s}"
        );
        assert!(s.contains("use formulation = \"auto\" or \"eas\""), "{s}");
    }
}

/// Issue 35: the plate meshed in triangles (24 × 8 cells cut in two) extrudes into
/// solid-shell wedges under `auto`: they bend far better than standard wedges
/// (measured 69 % and 28 % of beam theory) but, unlike the EAS hex8, not as beam theory
/// (the three-node triangle's shear locking), and `check` says so in a warning.
#[test]
fn a_sheet_of_triangles_gets_solid_shell_wedges_and_a_warning() {
    let dir = temp_dir("plate-triangles");
    std::fs::write(dir.join("plate.msh"), plate_msh_of(24, 8, true)).unwrap();
    let exact = 14.0 * 60.0f64.powi(3) / (3.0 * PLATE_E * 20.0 / 12.0);
    let s = check(&dir, &plate(&dir, None)).unwrap();
    assert!(
        s.contains("\n    plate: 384 wedge6 (sheet, 1 through the thickness), EAS (solid-shell wedge, 12 modes)\n"),
        "{s}"
    );
    assert!(
        s.contains("warning: part `plate` (parts[0]): 384 of the sheet's 384 elements are wedge6 extruded from triangles"),
        "{s}"
    );
    let tip = |form: Option<&str>| {
        let out = run_deck(
            &format!("plate-tri-{}", form.unwrap_or("auto")),
            &plate(&dir, form),
        );
        *column(&out, "tip.uz").last().unwrap()
    };
    let (auto, standard) = (tip(None), tip(Some("standard")));
    eprintln!(
        "plate of triangles: auto {:.3}, standard {:.3} of beam theory",
        auto / exact,
        standard / exact
    );
    assert!(auto > 0.6 * exact && auto < 0.8 * exact, "{auto}");
    assert!(auto > 2.0 * standard, "{auto} vs {standard}");
}

/// Quadratic tets and prisms under `auto` at ν = 0.4995 are hybrid (mean dilatation with
/// a pressure unknown) and quiet; `standard` warns; `eas` is refused naming the part.
#[test]
fn tet10_and_wedge6_parts_get_and_print_their_formulations() {
    let dir = temp_dir("quadratic-check");
    let s = check(&dir, &block("tet10", 0.4995, None)).unwrap();
    assert!(
        s.contains(
            "\n    block: 96 tet10, hybrid (P2/P0: mean dilatation with its pressure an unknown)\n"
        ),
        "{s}"
    );
    assert!(!s.contains("warning"), "{s}");
    let s = check(&dir, &block("wedge6", 0.4995, None)).unwrap();
    assert!(
        s.contains(
            "\n    block: 32 wedge6, hybrid (mean dilatation with its pressure an unknown)\n"
        ),
        "{s}"
    );
    let s = check(&dir, &block("wedge6", 0.4995, Some("standard"))).unwrap();
    assert!(
        s.contains("32 wedge6 with the standard formulation lock at nu = 0.4995 > 0.45"),
        "{s}"
    );
    let e = check(&dir, &block("tet10", 0.3, Some("eas")))
        .expect_err("eas on tet10")
        .to_string();
    assert!(
        e.contains("parts[0].formulation: \"eas\" does not apply to tet10 elements (part `block`"),
        "{e}"
    );
}

/// Issue 36: the plate's middle surface as an Abaqus/CalculiX shell mesh (S4R, the same
/// 24 × 8 grid, node sets `ROOT` and `TIP`) extrudes into the same sheet as the Gmsh
/// file: clamped at the root and pulled down by 14 N spread over the tip's nodes, both
/// give the same tip deflection to round-off.
#[test]
fn a_sheet_reads_an_abaqus_shell_mesh() {
    let dir = temp_dir("plate-inp");
    let (nx, ny) = (24, 8);
    let id = |i: usize, j: usize| 1 + j * (nx + 1) + i;
    let mut inp = String::from("*NODE\n");
    for j in 0..=ny {
        for i in 0..=nx {
            inp += &format!(
                "{}, {}, {}, 0\n",
                id(i, j),
                60.0 * i as f64 / nx as f64,
                20.0 * j as f64 / ny as f64
            );
        }
    }
    inp += "*ELEMENT, TYPE=S4R, ELSET=PLATE\n";
    for j in 0..ny {
        for i in 0..nx {
            inp += &format!(
                "{}, {}, {}, {}, {}\n",
                1 + j * nx + i,
                id(i, j),
                id(i + 1, j),
                id(i + 1, j + 1),
                id(i, j + 1)
            );
        }
    }
    inp += "*NSET, NSET=ROOT\n";
    inp += &(0..=ny)
        .map(|j| id(0, j).to_string())
        .collect::<Vec<_>>()
        .join(", ");
    inp += "\n*NSET, NSET=TIP\n";
    inp += &(0..=ny)
        .map(|j| id(nx, j).to_string())
        .collect::<Vec<_>>()
        .join(", ");
    inp += "\n*SHELL SECTION, ELSET=PLATE, MATERIAL=STEEL\n1.0\n";
    std::fs::write(dir.join("plate.inp"), inp).unwrap();
    std::fs::write(dir.join("plate.msh"), plate_msh(nx, ny)).unwrap();
    let deck = |file: &str, root: &str, tip: &str| {
        format!(
            "[scene]\nname = \"p\"\nunits = \"mm-t-s\"\n[[materials]]\nname = \"steel\"\nmodel = \"linear-elastic\"\nE = {PLATE_E}\nnu = 0.0\n[[parts]]\nname = \"plate\"\nmaterial = \"steel\"\nmesh = {{ kind = \"sheet\", file = \"{}\", thickness = 1.0 }}\n[[node_sets]]\nname = \"root\"\ngroup = \"{root}\"\n[[node_sets]]\nname = \"tip\"\ngroup = \"{tip}\"\n[[boundary]]\ntype = \"fixed\"\nset = \"root\"\n[[loads]]\ntype = \"nodal\"\nset = \"tip\"\nforce = [0, 0, {}]\n[analysis]\ntype = \"static\"\nend_time = 1.0\nstep = 1.0\n[output]\ndisplacements = [\"tip\"]\n",
            dir.join(file).display(),
            -14.0 / (2.0 * (ny + 1) as f64)
        )
    };
    let tip = |name: &str, d: String| *column(&run_deck(name, &d), "tip.uz").last().unwrap();
    let from_inp = tip("plate-inp-run", deck("plate.inp", "ROOT", "TIP"));
    let from_msh = tip("plate-msh-run", deck("plate.msh", "root", "tip"));
    eprintln!("plate tip: .inp {from_inp}, .msh {from_msh}");
    assert!(from_inp < -2.0, "{from_inp}");
    assert!(
        (from_inp - from_msh).abs() < 1e-9 * from_msh.abs(),
        "{from_inp} vs {from_msh}"
    );
}
