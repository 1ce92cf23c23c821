//! `alfe import` of Abaqus/CalculiX input files (issue 36): a bar written as CalculiX
//! would have it (sets by GENERATE, a boundary on node numbers, concentrated and
//! distributed loads) imports to a deck whose run gives the bar's analytic stretch;
//! keywords it does not translate are listed with their lines; and a seeded fuzzer over
//! the file finds no panic and no refusal without a line. `scripts/ccx-compare` compares
//! imports of CalculiX's own test suite with its reference answers.

mod common;
use alfe::app::import::abaqus::import_inp;
use common::*;
use std::path::Path;

/// A 10 × 1 × 1 bar of ten C3D8 along x: nodes 1–44 (x = i, corners (y, z) in the
/// order (0,0), (1,0), (1,1), (0,1)), element i between x = i−1 and i. Rollers: the x = 0
/// end held along x (a set by GENERATE), the y = 0 side along y, the z = 0 side along z
/// (node numbers, so the importer writes a companion set file). Pulled at x = 10 by a
/// CLOAD of F/4 on each end node, then (the `DLOAD` variant) by a tension on face S4 of
/// element 10.
fn bar(load: &str) -> String {
    let mut s = String::from("*HEADING\na bar in tension\n*NODE, NSET=NALL\n");
    let corners = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    for i in 0..=10 {
        for (k, c) in corners.iter().enumerate() {
            s += &format!("{}, {}, {}, {}\n", 4 * i + k + 1, i, c[0], c[1]);
        }
    }
    s += "*ELEMENT, TYPE=C3D8, ELSET=EALL\n";
    for i in 0..10 {
        let n = |x: usize, k: usize| 4 * x + k + 1;
        // Bottom z = 0: (x0,0,0) (x1,0,0) (x1,1,0) (x0,1,0); top z = 1 likewise.
        s += &format!(
            "{}, {}, {}, {}, {}, {}, {}, {}, {}\n",
            i + 1,
            n(i, 0),
            n(i + 1, 0),
            n(i + 1, 1),
            n(i, 1),
            n(i, 3),
            n(i + 1, 3),
            n(i + 1, 2),
            n(i, 2)
        );
    }
    s += "*NSET, NSET=END0, GENERATE\n1, 4\n*NSET, NSET=END\n41, 42, 43, 44\n";
    s += "*MATERIAL, NAME=STEEL\n*ELASTIC\n200000., 0.3\n*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL\n";
    s += "*STEP\n*STATIC\n0.5, 1.0\n*BOUNDARY\nEND0, 1, 1\n";
    // y = 0: corners 0 and 3 of every section; z = 0: corners 0 and 1.
    for i in 0..=10 {
        s += &format!(
            "{}, 2\n{}, 2\n{}, 3\n{}, 3\n",
            4 * i + 1,
            4 * i + 4,
            4 * i + 1,
            4 * i + 2
        );
    }
    s += load;
    s += "*NODE PRINT, NSET=NALL\nU\n*END STEP\n";
    s
}

fn import_and_run(name: &str, text: &str) -> (alfe::app::RunOutcome, String) {
    let dir = temp_dir(name);
    let inp = dir.join("bar.inp");
    std::fs::write(&inp, text).unwrap();
    let deck = dir.join("bar.toml");
    let r = alfe::app::import::import(&inp, &deck).unwrap();
    assert!(
        r.written.iter().any(|w| w.ends_with("bar.sets.inp")),
        "{:?}",
        r.written
    );
    let deck_text = std::fs::read_to_string(&deck).unwrap();
    let out = run_deck_file(name, &deck);
    (out, deck_text)
}

/// The stretch of the end: F L / (E A) = 1000 × 10 / 200 000 = 0.05, every end node
/// (uniaxial stress on rollers: exact for hex8), pulled by nodal forces. Pulled by a
/// tension on the element faces instead, alfe's pressure follows the face, whose area
/// shrinks by (1 − ν ε)²: ε = (p/E)(1 − ν ε)², 0.3 % less (Abaqus without NLGEOM keeps
/// the reference area; the importer says so).
#[test]
fn an_imported_calculix_bar_stretches_as_the_formula_says() {
    let (nu, eps): (f64, f64) = (0.3, 0.005);
    // ε = (p / E) (1 − ν ε)², by fixed-point iteration.
    let mut e = eps;
    for _ in 0..50 {
        e = eps * (1.0 - nu * e).powi(2);
    }
    for (name, load, want) in [
        ("import-cload", "*CLOAD\nEND, 1, 250.\n", 10.0 * eps),
        ("import-dload", "*DLOAD\n10, P4, -1000.\n", 10.0 * e),
    ] {
        let (out, deck) = import_and_run(name, &bar(load));
        assert!(
            deck.contains("description = \"a bar in tension\""),
            "{deck}"
        );
        assert!(deck.contains("formulation = \"standard\""), "{deck}");
        assert!(
            deck.contains("bar.inp:"),
            "not-translated lines name the file: {deck}"
        );
        let mut worst: f64 = 0.0;
        let mut seen = 0;
        for (_, x, u) in out.displacement_by_node() {
            if x[0] == 10.0 {
                worst = worst.max((u[0] - want).abs());
                seen += 1;
            }
        }
        assert_eq!(seen, 4, "{name}");
        assert!(worst < 1e-9, "{name}: end displacement off by {worst}");
    }
}

/// What is not translated is listed with its file and line, in the deck and in the
/// report; nothing is dropped silently.
#[test]
fn untranslated_keywords_are_listed_with_their_lines() {
    let text = bar("*CLOAD\nEND, 1, 250.\n*TEMPERATURE\nNALL, 100.\n")
        .replace("*STEP\n", "*EXPANSION\n1.2e-5\n*STEP\n");
    let dir = temp_dir("import-untranslated");
    let inp = dir.join("bar.inp");
    std::fs::write(&inp, &text).unwrap();
    let r = alfe::app::import::import(&inp, &dir.join("bar.toml")).unwrap();
    let find = |s: &str| r.untranslated.iter().any(|u| u.contains(s));
    let line_of = |kw: &str| text.lines().position(|l| l == kw).unwrap() + 1;
    assert!(
        find(&format!(
            "bar.inp:{}: `*EXPANSION`: keyword not translated",
            line_of("*EXPANSION")
        )),
        "{:?}",
        r.untranslated
    );
    assert!(
        find(&format!(
            "bar.inp:{}: `*TEMPERATURE`",
            line_of("*TEMPERATURE")
        )),
        "{:?}",
        r.untranslated
    );
    assert!(find("`NALL, 100.`: data of a keyword not translated"));
    assert!(find("*NODE PRINT"));
    let deck = std::fs::read_to_string(dir.join("bar.toml")).unwrap();
    assert!(deck.contains(&format!("# Not translated ({}):", r.untranslated.len())));
}

/// splitmix64.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// One mutation of a line list: garble a number, cut a line, delete, double, insert an
/// unknown keyword, rename a set reference, or empty a field.
fn mutate(lines: &mut Vec<String>, rng: &mut Rng) {
    let i = rng.below(lines.len());
    match rng.below(7) {
        0 => {
            let l = &lines[i];
            let cut = rng.below(l.len() + 1);
            lines[i] = l[..l.floor_char_boundary(cut)].to_string();
        }
        1 => {
            lines.remove(i);
        }
        2 => {
            let l = lines[i].clone();
            lines.insert(i, l);
        }
        3 => lines.insert(i, "*FROBNICATE, X=1".into()),
        4 => lines[i] = lines[i].replace("END", "NOWHERE"),
        5 => {
            let garbage = ["1e999", "nan", "x", "-", "", "1.2.3", "99999"];
            let g = garbage[rng.below(garbage.len())];
            let mut f: Vec<String> = lines[i].split(',').map(String::from).collect();
            let k = rng.below(f.len());
            f[k] = g.into();
            lines[i] = f.join(",");
        }
        _ => lines[i] = lines[i].replace(',', ""),
    }
}

/// The fuzzer's seed and case count (`ALFE_FUZZ_SEED`, `ALFE_FUZZ_CASES`).
fn fuzz_settings() -> (u64, usize) {
    let seed = std::env::var("ALFE_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(36);
    let cases = std::env::var("ALFE_FUZZ_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(400);
    (seed, cases)
}

/// Mutate `base` `cases` times; `read` each text as file `name`: no panic, and every
/// refusal names `name:` and a line. Returns (accepted, refused).
fn fuzz(
    base: &str,
    name: &str,
    read: &dyn Fn(&Loader) -> Vec<Result<(), String>>,
) -> (usize, usize) {
    let (seed, cases) = fuzz_settings();
    let base: Vec<String> = base.lines().map(String::from).collect();
    let mut rng = Rng(seed);
    let (mut refused, mut accepted) = (0, 0);
    for case in 0..cases {
        let mut lines = base.clone();
        for _ in 0..1 + rng.below(3) {
            mutate(&mut lines, &mut rng);
        }
        let text = lines.join("\n") + "\n";
        let load = |p: &Path| -> Result<String, String> {
            if p == Path::new(name) {
                Ok(text.clone())
            } else {
                Err(format!("{}: no such file", p.display()))
            }
        };
        let got = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| read(&load)));
        let Ok(results) = got else {
            panic!("case {case} (seed {seed}) panicked on:\n{text}");
        };
        for r in results {
            match r {
                Ok(()) => accepted += 1,
                Err(e) => {
                    refused += 1;
                    assert!(
                        e.contains(&format!("{name}:")),
                        "case {case} (seed {seed}): `{e}` names no line:\n{text}"
                    );
                }
            }
        }
    }
    eprintln!("{name} fuzz: {cases} files, {accepted} accepted, {refused} refused with a line");
    assert!(refused > cases / 10 && accepted > cases / 10);
    (accepted, refused)
}

type Loader<'a> = dyn Fn(&Path) -> Result<String, String> + 'a;

/// A seeded fuzzer over `.inp` files: every mutated file is read as a mesh and imported
/// without a panic, and every refusal names the file and a line (`bar.inp:N:`).
#[test]
fn fuzzed_input_files_never_panic_and_refusals_name_a_line() {
    let base = bar("*CLOAD\nEND, 1, 250.\n*DLOAD\n10, P4, -1000.\n");
    fuzz(&base, "bar.inp", &|load| {
        vec![
            alfe::mesh::abaqus::read_inp(Path::new("bar.inp"), 0, load).map(|_| ()),
            import_inp(Path::new("bar.inp"), Path::new("bar.toml"), load).map(|_| ()),
        ]
    });
}

/// A small LS-DYNA file: the cube and apex of `mesh::lsdyna`'s tests, a part title, a
/// node set, a segment set, both layouts of `*ELEMENT_SOLID`.
const K_FILE: &str = "*KEYWORD
*NODE
       1             0.0             0.0             0.0       0       0
       2             1.0             0.0             0.0       0       0
       3             1.0             1.0             0.0       0       0
       4             0.0             1.0             0.0       0       0
       5             0.0             0.0             1.0       0       0
       6             1.0             0.0             1.0       0       0
       7             1.0             1.0             1.0       0       0
       8             0.0             1.0             1.0       0       0
       9             0.5             0.5             2.0       0       0
*PART
cube
       1       1       1
*ELEMENT_SOLID
       1       1       1       2       3       4       5       6       7       8
*ELEMENT_SOLID (ten nodes format)
       2       1
       5       6       7       9       9       9       9       9       0       0
*SET_NODE_LIST_TITLE
bottom
         7
         1         2         3         4
*SET_SEGMENT
         8
         1         2         3         4
*END
";

/// The same fuzzer over LS-DYNA keyword files (`bar.k:N:`), read as solids and as a
/// sheet's surface.
#[test]
fn fuzzed_keyword_files_never_panic_and_refusals_name_a_line() {
    fuzz(K_FILE, "bar.k", &|load| {
        vec![alfe::mesh::lsdyna::read_k(Path::new("bar.k"), 0, None, load).map(|_| ())]
    });
}

/// The real LS-PrePost files of `../shared/data/lsdyna/` (`SOURCE.md` there; not copied
/// here): the Taylor bar's 768 hex8 (two-card layout) and the beer can's 3320 shells
/// as a sheet. Skipped, saying so, where that directory is not beside the repository
/// (`ALFE_LSDYNA_DATA` names another).
#[test]
fn real_lsdyna_files_read() {
    let dir = std::env::var("ALFE_LSDYNA_DATA")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|_| Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/lsdyna"));
    if !dir.join("taylor_bar_mesh.k").exists() {
        eprintln!("skipped: no LS-DYNA files at {}", dir.display());
        return;
    }
    let load = |p: &Path| std::fs::read_to_string(p).map_err(|e| format!("{}: {e}", p.display()));
    let bar = alfe::mesh::lsdyna::read_k(&dir.join("taylor_bar_mesh.k"), 0, None, &load).unwrap();
    assert_eq!(bar.n_elems(), 768);
    assert!(bar.kinds.iter().all(|&k| k == alfe::mesh::ElemKind::Hex8));
    let vol: f64 = (0..bar.n_elems()).map(|e| bar.elem_volume(e)).sum();
    // A quarter of a cylinder of radius 4 and length 30 (faceted: a little less).
    let full = std::f64::consts::PI * 16.0 * 30.0 / 4.0;
    assert!(vol < full && vol > 0.99 * full, "{vol} vs {full}");
    let can = alfe::mesh::lsdyna::read_surface_k(&dir.join("beer_can_mesh.k"), &load).unwrap();
    assert_eq!(can.quads.len(), 3320);
    assert!(can.quads.iter().all(|q| q.len() == 4));
}

/// `alfe export` then `alfe import` is the same model: the linear cantilever (its tip
/// traction exported as consistent nodal forces, its supports and sets by name) gives
/// the same displacements, node by node (matched by position), to round-off.
/// `scripts/ccx-export-compare` runs the exported file in CalculiX (5e-8 linear).
#[test]
fn export_then_import_is_the_same_model() {
    let dir = temp_dir("export-roundtrip");
    let text = edit(
        &edit(
            &builtin("cantilever"),
            "model = \"neo-hookean\"",
            "model = \"linear-elastic\"",
        ),
        "traction = [0.0, 0.0, -30.0]",
        "traction = [0.0, 0.0, -0.03]",
    );
    let deck = dir.join("cantilever.toml");
    std::fs::write(&deck, &text).unwrap();
    let inp = dir.join("cantilever.inp");
    let left = alfe::app::export::export(deck.to_str().unwrap(), &inp).unwrap();
    assert!(left.is_empty(), "{left:?}");
    let back = dir.join("back.toml");
    alfe::app::import::import(&inp, &back).unwrap();
    let a = run_deck("export-original", &text);
    let b = run_deck_file("export-back", &back);
    let key = |x: [f64; 3]| x.map(|c| (c * 1e6).round() as i64);
    let ub: std::collections::HashMap<_, _> = b
        .displacement_by_node()
        .into_iter()
        .map(|(_, x, u)| (key(x), u))
        .collect();
    let (mut worst, mut umax) = (0.0f64, 0.0f64);
    for (_, x, u) in a.displacement_by_node() {
        let v = ub[&key(x)];
        for k in 0..3 {
            worst = worst.max((u[k] - v[k]).abs());
            umax = umax.max(u[k].abs());
        }
    }
    assert!(umax > 1e-3 && worst < 1e-9 * umax, "{worst} of {umax}");
}

/// A shell model (S4R with a *SHELL SECTION) imports as a sheet of that thickness under
/// `auto` (EAS): a 60 × 20 plate, 1 thick, clamped at x = 0 (a node set by GENERATE) and
/// loaded by 14 N spread over the 9 tip nodes, deflects within 3 % of beam theory
/// F L³ / (3 E I) = 2.88 mm (the end nodes' equal shares are not the consistent load: a
/// little off the 0.03 % of the traction-loaded plate).
#[test]
fn a_shell_model_imports_as_a_sheet() {
    let (nx, ny) = (24, 8);
    let id = |i: usize, j: usize| 1 + j * (nx + 1) + i;
    let mut inp = String::from("*NODE, NSET=NALL\n");
    for j in 0..=ny {
        for i in 0..=nx {
            inp += &format!("{}, {}, {}, 0\n", id(i, j), 2.5 * i as f64, 2.5 * j as f64);
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
    inp += &format!("*NSET, NSET=ROOT, GENERATE\n1, {}, {}\n", id(0, ny), nx + 1);
    inp += &format!(
        "*NSET, NSET=TIP, GENERATE\n{}, {}, {}\n",
        id(nx, 0),
        id(nx, ny),
        nx + 1
    );
    inp += "*MATERIAL, NAME=STEEL\n*ELASTIC\n210000., 0.\n*SHELL SECTION, ELSET=PLATE, MATERIAL=STEEL\n1.0, 5\n";
    inp += &format!(
        "*STEP\n*STATIC\n*BOUNDARY\nROOT, 1, 6\n*CLOAD\nTIP, 3, {}\n*END STEP\n",
        -14.0 / (2.0 * (ny + 1) as f64)
    );
    let dir = temp_dir("import-shells");
    std::fs::write(dir.join("plate.inp"), &inp).unwrap();
    let deck = dir.join("plate.toml");
    let r = alfe::app::import::import(&dir.join("plate.inp"), &deck).unwrap();
    let text = std::fs::read_to_string(&deck).unwrap();
    assert!(
        text.contains("kind = \"sheet\"") && text.contains("thickness = 1"),
        "{text}"
    );
    assert!(!text.contains("formulation"), "{text}");
    assert!(
        r.untranslated
            .iter()
            .any(|u| u.contains("degrees of freedom above 3")),
        "{:?}",
        r.untranslated
    );
    let out = run_deck_file("import-shells", &deck);
    let uz = out
        .displacement_by_node()
        .into_iter()
        .filter(|(_, x, _)| x[0] == 60.0)
        .map(|(_, _, u)| u[2])
        .sum::<f64>()
        / (2.0 * (ny + 1) as f64);
    let beam = 14.0 * 60.0f64.powi(3) / (3.0 * 210000.0 * 20.0 / 12.0);
    eprintln!("imported shell plate: tip {uz}, beam theory {beam}");
    assert!((-uz - beam).abs() < 0.03 * beam, "{uz} vs {beam}");
}

/// A rigid wall exports as a rigid C3D8 layer in a penalty contact pair (CalculiX has no
/// analytical rigid sphere): hertz-sphere's sphere becomes facets on the sphere (outer
/// nodes at R, inner ones inside), near the block only, all moved by the wall's 1 mm;
/// the slave surface is the block's faces under the tracked nodes.
/// `scripts/ccx-export-compare` runs it in CalculiX: 531 N against alfe's 534 N.
#[test]
fn a_rigid_wall_exports_as_a_rigid_layer_in_contact() {
    let dir = temp_dir("export-wall");
    let inp = dir.join("hertz.inp");
    let left = alfe::app::export::export("hertz-sphere", &inp).unwrap();
    assert!(left.iter().all(|l| !l.contains("sphere")), "{left:?}");
    let text = std::fs::read_to_string(&inp).unwrap();
    let block = |head: &str| -> Vec<Vec<String>> {
        let start = text.find(head).unwrap_or_else(|| panic!("no {head}")) + head.len();
        text[start..]
            .lines()
            .skip(1)
            .take_while(|l| !l.starts_with('*'))
            .map(|l| l.split(',').map(|f| f.trim().to_string()).collect())
            .collect()
    };
    let nodes = block("*NODE, NSET=W_sphere_N");
    let (r, c) = (50.0, [0.0, 0.0, 50.0]);
    let mut on_surface = 0;
    for n in &nodes {
        let x: Vec<f64> = n[1..4].iter().map(|v| v.parse().unwrap()).collect();
        let d = (0..3).map(|k| (x[k] - c[k]).powi(2)).sum::<f64>().sqrt();
        assert!(
            d < r + 1e-9 && d > r - 2.0,
            "node {n:?} at {d} from the centre"
        );
        assert!(x[2] < 20.0, "a facet far from the block: {x:?}");
        on_surface += usize::from((d - r).abs() < 1e-9);
    }
    assert!(on_surface > 1000 && on_surface < nodes.len());
    let slave = block("*SURFACE, NAME=W_sphere_SLAVE, TYPE=ELEMENT");
    assert!(
        !slave.is_empty() && slave.iter().all(|f| f[1] == "S2"),
        "{slave:?}"
    );
    assert!(text.contains("*CONTACT PAIR, INTERACTION=W_sphere_I, TYPE=NODE TO SURFACE\nW_sphere_SLAVE, W_sphere_MASTER"));
    assert!(text.contains("*BOUNDARY, AMPLITUDE=W_sphere_A3\nW_sphere_N, 3, 3, 1.0"));
    assert!(text.contains("*AMPLITUDE, NAME=W_sphere_A3\n0, -0, 0.125, -0.125"));
    assert!(text.contains("*NODE PRINT, NSET=W_sphere_N, TOTALS=ONLY\nRF"));
}
