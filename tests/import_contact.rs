//! `alfe import` of a foreign `.inp`'s contact and coupling keywords: three C3D8 blocks
//! stacked along z, the lower two glued by `*TIE`, the top one on the middle one in
//! small-sliding frictional contact (its interaction defined after the pair), pressed by a
//! `*CLOAD` on the reference node of a `*COUPLING` / `*DISTRIBUTING` on its top face. The
//! import has those pairs and the coupling, runs, and holds equilibrium: the base carries
//! the load, and so do the tie and the contact. Keywords with no alfe meaning (finite
//! sliding, a pretension section) are listed with their lines.

mod common;
use common::*;

const F: f64 = 100.0;

fn stack(extra: &str) -> String {
    let mut s = String::from("*HEADING\nthree blocks\n*NODE\n");
    let c = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    for b in 0..3 {
        for (lz, z) in [(0, b), (1, b + 1)] {
            for (k, xy) in c.iter().enumerate() {
                s += &format!("{}, {}, {}, {}\n", 10 * b + 4 * lz + k + 1, xy[0], xy[1], z);
            }
        }
    }
    s += "1000, 0.5, 0.5, 3.5\n";
    for (b, name) in ["EA", "EB", "EC"].iter().enumerate() {
        let n: Vec<String> = (1..=8).map(|k| (10 * b + k).to_string()).collect();
        s += &format!(
            "*ELEMENT, TYPE=C3D8, ELSET={name}\n{}, {}\n",
            b + 1,
            n.join(", ")
        );
    }
    s += "*ELSET, ELSET=ALL\nEA, EB, EC\n*NSET, NSET=BASE\n1, 2, 3, 4\n";
    for (name, e, f) in [
        ("ATOP", "EA", 2),
        ("BBOT", "EB", 1),
        ("BTOP", "EB", 2),
        ("CBOT", "EC", 1),
        ("CTOP", "EC", 2),
    ] {
        s += &format!("*SURFACE, NAME={name}, TYPE=ELEMENT\n{e}, S{f}\n");
    }
    s += "*MATERIAL, NAME=STEEL\n*ELASTIC\n100000., 0.3\n*SOLID SECTION, ELSET=ALL, MATERIAL=STEEL\n";
    s += "*TIE, NAME=GLUE\nBBOT, ATOP\n";
    s += "*CONTACT PAIR, INTERACTION=ROUGH, SMALL SLIDING, TYPE=SURFACE TO SURFACE\nCBOT, BTOP\n";
    s += "*SURFACE INTERACTION, NAME=ROUGH\n*FRICTION\n0.3\n";
    s += "*COUPLING, REF NODE=1000, SURFACE=CTOP, CONSTRAINT NAME=PRESS\n*DISTRIBUTING\n1, 3\n";
    s += extra;
    s += "*STEP\n*STATIC\n0.5, 1.0\n*BOUNDARY\nBASE, 1, 3\n1000, 1, 2\n1000, 4, 6\n";
    s += &format!("*CLOAD\n1000, 3, {}\n*END STEP\n", -F);
    s
}

fn import(name: &str, text: &str) -> (std::path::PathBuf, alfe::app::import::Report) {
    let dir = temp_dir(name);
    let inp = dir.join("stack.inp");
    std::fs::write(&inp, text).unwrap();
    let deck = dir.join("stack.toml");
    let r = alfe::app::import::import(&inp, &deck).unwrap();
    (deck, r)
}

#[test]
fn tied_and_frictional_pairs_and_a_coupling_import_and_hold_equilibrium() {
    let (deck, _) = import("import-contact-stack", &stack(""));
    let text = std::fs::read_to_string(&deck).unwrap();
    for want in [
        "[[pairs]]\nname = \"GLUE\"\ntracked = \"BBOT\"\nreference = \"ATOP\"\ntied = true\n",
        "tracked = \"CBOT\"\nreference = \"BTOP\"\nfriction = 0.3\n",
        "[[couplings]]\nname = \"PRESS\"\nnodes = \"CTOP\"\npoint = [5e-1, 5e-1, 3.5e0]\n",
        "force = { z = { value = -1e2 } }",
        "displacement = { x = { value = 0e0 }, y = { value = 0e0 } }",
        "rotation = { x = { value = 0e0 }, y = { value = 0e0 }, z = { value = 0e0 } }",
    ] {
        assert!(text.contains(want), "missing `{want}` in\n{text}");
    }
    assert!(!text.contains("keyword not translated"), "{text}");
    let out = run_deck_file("import-contact-stack", &deck);
    let base = out.steps.last().unwrap().reactions[0];
    assert!((base[2] - F).abs() < 1e-6 * F, "base reaction {base:?}");
    assert!(
        base[0].abs() < 1e-6 * F && base[1].abs() < 1e-6 * F,
        "{base:?}"
    );
    for pair in ["GLUE", "contact-2"] {
        let f = &out.summary.contributions["pairs"][pair]["force"];
        let fz = f[2].as_f64().unwrap();
        assert!((fz.abs() - F).abs() < 1e-6 * F, "{pair}: {f}");
    }
}

#[test]
fn finite_sliding_and_pretension_sections_are_listed_with_their_lines() {
    let extra = "*CONTACT PAIR, INTERACTION=ROUGH\nCBOT, BTOP\n*PRE-TENSION SECTION, SURFACE=CTOP, NODE=1000\n*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR\n1e6\n*KINEMATIC\n1, 3\n";
    let text = stack(extra);
    let (deck, r) = import("import-contact-listed", &text);
    let line_of = |kw: &str| text.lines().position(|l| l.starts_with(kw)).unwrap() + 1;
    let find = |s: String| {
        assert!(
            r.untranslated.iter().any(|u| u.contains(&s)),
            "no `{s}` in {:?}",
            r.untranslated
        )
    };
    find(format!(
        "stack.inp:{}: `*CONTACT PAIR, INTERACTION=ROUGH`: finite sliding",
        text.lines()
            .position(|l| l == "*CONTACT PAIR, INTERACTION=ROUGH")
            .unwrap()
            + 1
    ));
    find(format!(
        "stack.inp:{}: `*PRE-TENSION SECTION",
        line_of("*PRE-TENSION")
    ));
    find(format!(
        "stack.inp:{}: `*SURFACE BEHAVIOR",
        line_of("*SURFACE BEHAVIOR")
    ));
    find(format!(
        "stack.inp:{}: `1e6`: penalty stiffness",
        line_of("1e6")
    ));
    find(format!("stack.inp:{}: `*KINEMATIC`", line_of("*KINEMATIC")));
    let deck = std::fs::read_to_string(deck).unwrap();
    assert_eq!(deck.matches("[[pairs]]").count(), 2, "{deck}");
}
