//! Small-sliding contact between deformable parts (issue 14, the paper's §3.7): the
//! contact patch test on non-matching meshes (mortar weights pass it, node-to-face
//! weights do not), stick under a shear below μ p, the generalized Jacobian of every
//! pair law against finite differences, and deck mistakes. The 1 vs 2 rank comparison
//! with every pair across ranks is in `cli_mpi.rs`.

mod common;
use common::*;

/// The `contact-patch` deck ending after the pressure phase, with its weights.
fn pressed(weights: &str) -> String {
    edit(
        &edit(
            &builtin("contact-patch"),
            "friction = 0.5",
            &format!("friction = 0.5\nweights = \"{weights}\""),
        ),
        "end_time = 2.0",
        "end_time = 1.0",
    )
}

/// The pressure p = 1 passes the non-matching interface exactly with mortar weights:
/// every tracked node's pressure is p to 1e-8 (measured 9e-13; 1e-10 with the model
/// moved 1000 mm from the origin, where the closest-point search once lost nodes),
/// nothing penetrates, and the interface carries p A. Node-to-face weights put the same forces on the slave
/// nodes but spread them over the reference nodes by shape functions at 25 points,
/// which a uniform stress does not balance: their pressures spread by more than 5 %
/// (measured 0.83–1.10), the known failure of single-pass node-to-segment contact.
#[test]
fn contact_patch_pressure_passes_exactly_with_mortar_weights() {
    let far = edit(
        &edit(
            &pressed("mortar"),
            "origin = [0, 0, 0]",
            "origin = [1000, 1000, 1000]",
        ),
        "origin = [0, 0, 5]",
        "origin = [1000, 1000, 1005]",
    );
    for (name, deck) in [
        ("pairs-patch-mortar", pressed("mortar")),
        ("pairs-patch-far", far),
    ] {
        let out = run_deck(name, &deck);
        let gap = field(&out, "contact_gap");
        let p = field(&out, "contact_pressure");
        let tracked: Vec<f64> = p
            .iter()
            .zip(&gap)
            .filter(|(_, g)| !g.is_nan())
            .map(|(p, _)| *p)
            .collect();
        assert_eq!(tracked.len(), 25, "{name}");
        for pi in &tracked {
            assert!((pi - 1.0).abs() < 1e-8, "{name}: pressure {pi}");
        }
        assert!((column(&out, "interface.fz").last().unwrap() - 100.0).abs() < 1e-8);
        assert!(column(&out, "max_penetration").iter().all(|&g| g < 1e-9));
    }

    let out = run_deck("pairs-patch-node", &pressed("node"));
    let gap = field(&out, "contact_gap");
    let p = field(&out, "contact_pressure");
    let spread = p
        .iter()
        .zip(&gap)
        .filter(|(_, g)| !g.is_nan())
        .fold(0.0f64, |m, (p, _)| m.max((p - 1.0).abs()));
    assert!(spread > 0.05, "node-to-face pressures within {spread} of p");
}

/// Issue 35: the same patch test with the lower block in tet10 (tri6 reference faces,
/// 3 × 3 × 2 cells cut into tets) under the upper hex8 block's 4 × 4 tracked quads:
/// mortar weights with the reference side's quadratic shape functions give every
/// tracked node the pressure p to 1e-8 (measured ~1e-12), nothing penetrates, and the
/// interface carries p A. Tracking the tet10 block's faces instead is refused naming
/// the part (its corners have no positive dual weight).
#[test]
fn contact_patch_passes_on_tri6_reference_faces() {
    let lower = "cells = [3, 3, 2] }";
    let deck = edit(
        &pressed("mortar"),
        lower,
        "cells = [3, 3, 2], element = \"tet10\" }",
    );
    let out = run_deck("pairs-patch-tet10", &deck);
    let gap = field(&out, "contact_gap");
    let p = field(&out, "contact_pressure");
    let tracked: Vec<f64> = p
        .iter()
        .zip(&gap)
        .filter(|(_, g)| !g.is_nan())
        .map(|(p, _)| *p)
        .collect();
    assert_eq!(tracked.len(), 25);
    let worst = tracked.iter().fold(0.0f64, |m, p| m.max((p - 1.0).abs()));
    eprintln!("tet10 reference, hex8 tracked: pressures within {worst:.2e} of p");
    assert!(worst < 1e-8, "{tracked:?}");
    assert!((column(&out, "interface.fz").last().unwrap() - 100.0).abs() < 1e-8);
    assert!(column(&out, "max_penetration").iter().all(|&g| g < 1e-9));

    let swapped = edit(
        &deck,
        "tracked = \"upper_bottom\"\nreference = \"lower_top\"",
        "tracked = \"lower_top\"\nreference = \"upper_bottom\"",
    );
    let e = try_run_deck("pairs-patch-tet10-tracked", &swapped)
        .err()
        .expect("a tracked tri6 surface must be refused")
        .to_string();
    assert!(
        e.contains("pairs[0].tracked: `lower_top` lies on tet10 elements (part `lower`)"),
        "{e}"
    );
}

/// Sheared by a mean 0.2 p (the top moved along x), below μ p = 0.5 p everywhere
/// (measured at most 0.30 p at a node): every pair sticks at every step and nothing
/// slips (max_slip at round-off).
#[test]
fn contact_patch_sticks_under_a_shear_below_mu() {
    let out = run_deck("pairs-patch-shear", &builtin("contact-patch"));
    assert_eq!(column(&out, "time").last().copied(), Some(2.0));
    for s in column(&out, "contact_sticking") {
        assert_eq!(s, 25.0);
    }
    assert!(column(&out, "interface.max_slip")
        .iter()
        .all(|&s| s < 1e-10));
    let (fx, fz) = (
        *column(&out, "interface.fx").last().unwrap(),
        *column(&out, "interface.fz").last().unwrap(),
    );
    let ratio = -fx / fz;
    assert!(ratio > 0.15 && ratio < 0.5, "shear / normal {ratio}");
}

/// The generalized Jacobian with pairs (mortar weights over several faces, the frame
/// of the node's face) against central differences, at perturbed states of converged
/// runs: ALM with friction (sticking), penalty without friction (with friction a
/// converged penalty state sits on the cone's kink), tied ALM and tied penalty, and a
/// locked bolt section (its shortening's row and column).
#[test]
fn pair_jacobian_matches_finite_differences() {
    let base = builtin("contact-patch");
    let cases = [
        ("alm", base.clone()),
        (
            "penalty",
            edit(
                &base,
                "friction = 0.5",
                "friction = 0.0\nmethod = \"penalty\"",
            ),
        ),
        ("tied", edit(&base, "friction = 0.5", "tied = true")),
        (
            "tied-penalty",
            edit(&base, "friction = 0.5", "tied = true\nmethod = \"penalty\""),
        ),
    ];
    let cases = cases
        .into_iter()
        .chain([("bolt", include_str!("bolt-bar.toml").to_string())]);
    for (name, deck) in cases {
        let mut out = run_deck(&format!("pairs-jac-{name}"), &deck);
        for seed in [1, 2] {
            let err = jacobian_fd_error(&mut out, seed, 1e-5);
            eprintln!("{name}, seed {seed}: {err:e}");
            assert!(err < 1e-6, "{name}: Jacobian off by {err:e}");
        }
    }
}

/// Deck mistakes about pairs name the field.
#[test]
fn bad_pair_decks_name_the_field() {
    let base = builtin("contact-patch");
    let cases = [
        (
            edit(&base, "reference = \"lower_top\"", "reference = \"nope\""),
            "pairs[0].reference: unknown surface `nope`".to_string(),
        ),
        (
            edit(&base, "friction = 0.5", "friction = 0.5\ntied = true"),
            "pairs[0].friction: a tied pair does not slip".to_string(),
        ),
        (
            edit(&base, "tracked = \"upper_bottom\"", "tracked = \"top\"")
                .replace("friction = 0.5", "friction = 0.5\nweights = \"mortar\""),
            "pairs[0].weights: mortar weights integrate over the tracked faces".to_string(),
        ),
        (
            edit(
                &base,
                "tracked = \"upper_bottom\"",
                "tracked = \"upper_top\"",
            ),
            "pairs[0]: `interface`: none of the 25 tracked nodes of `upper_top` lies within"
                .to_string(),
        ),
        (
            edit(&base, "friction = 0.5", "friction = -0.5"),
            "pairs[0].friction: expected a coefficient ≥ 0".to_string(),
        ),
    ];
    let bolt = include_str!("bolt-bar.toml");
    let cases = cases.into_iter().chain([
        (
            format!("{base}\n[solver.linear]\npreconditioner = \"amg\"\n"),
            "[solver.linear] preconditioner: \"amg\" needs an elliptic matrix".to_string(),
        ),
        (
            edit(bolt, "type = \"static\"", "type = \"implicit\"")
                .replace("nu = 0.0", "nu = 0.0\ndensity = 1e-9"),
            "bolts[0]: bolt sections take part in static analyses".to_string(),
        ),
        (
            edit(bolt, "lock_at = 1.0", "lock_at = 5.0"),
            "bolts[0].lock_at: expected a time in (0, 2]".to_string(),
        ),
        (
            edit(bolt, "name = \"bolt1\"", "name = \"glue\""),
            "bolts[0].name: `glue` is also the name of pairs[0]".to_string(),
        ),
    ]);
    for (deck, want) in cases {
        let e = try_run_deck("pairs-bad", &deck).err().expect("refused");
        let msg = e.to_string();
        assert!(msg.contains(&want), "expected `{want}` in: {msg}");
    }
}

/// `two-body-hertz`: Hertz's line contact between two deformable cylinders of different
/// materials (E* from both bodies, R* = R/2), from the measured force per length F':
/// the peak pressure within 3 % of p₀ = √(F' E*/(π R*)) (measured +1.7 %), every
/// tracked node's pressure within 0.03 p₀ of p₀ √(1 − x²/b²) where it is in contact
/// (measured −0.006 … +0.017 p₀), the half-width b between the last node in contact and the
/// first open one, and no penetration.
#[test]
fn two_body_hertz_line_contact() {
    let out = run_deck("pairs-hertz", &builtin("two-body-hertz"));
    let es = 1.0 / ((1.0 - 0.09) / 1000.0 + (1.0 - 0.0625) / 3000.0);
    let rs = 5.0;
    let f = *column(&out, "contact.fy").last().unwrap();
    let p0 = (f * es / (std::f64::consts::PI * rs)).sqrt();
    let b = (4.0 * f * rs / (std::f64::consts::PI * es)).sqrt();
    let gap = field(&out, "contact_gap");
    let p = field(&out, "contact_pressure");
    let nodes = out.displacement_by_node();
    let mut peak = 0.0f64;
    let (mut last_in, mut first_out) = (0.0f64, f64::INFINITY);
    for ((g, pi), n) in gap.iter().zip(&p).zip(&nodes) {
        if g.is_nan() {
            continue;
        }
        let x = n.1[0].abs();
        peak = peak.max(*pi);
        if *pi > 0.0 {
            last_in = last_in.max(x);
            let want = p0 * (1.0 - (x / b).powi(2)).max(0.0).sqrt();
            assert!(
                (pi - want).abs() < 0.03 * p0,
                "pressure {pi} at x = {x}, Hertz {want}"
            );
        } else {
            first_out = first_out.min(x);
        }
    }
    assert!((peak / p0 - 1.0).abs() < 0.03, "peak {peak} vs p0 {p0}");
    assert!(
        last_in < b && b < first_out,
        "b = {b}: in to {last_in}, open from {first_out}"
    );
    assert!(f > 30.0, "force per length {f}");
    assert!(column(&out, "max_penetration").iter().all(|&g| g < 1e-10));
}

/// A bolt's pretension section (`tests/bolt-bar.toml`): a bar (E = 1000, ν = 0, A = 16,
/// L = 40) clamped at both ends, in three parts joined by a tied pair at z = a = 10 and by
/// the section at z = 20. The section pulls with F = 1000 × a ramp to t = 1, where it
/// locks; then a force P = 400 along +z on the glued joint (a traction on its face)
/// over t ∈ [1, 2]. Exact (1-D) answers: during pretension the bolt force is the
/// prescribed one and the section shortens by F L/(EA) = 2.5; locked, it keeps that
/// length and the bolt force falls to F − P a/L = 900 (the joint's load shared by the two
/// segments in proportion to their stiffness).
#[test]
fn bolt_pretension_then_locked_section() {
    let out = run_deck("pairs-bolt", include_str!("bolt-bar.toml"));
    let t = column(&out, "time");
    let force = column(&out, "bolt1.force");
    let short = column(&out, "bolt1.shortening");
    assert_eq!(t, vec![0.5, 1.0, 1.5, 2.0]);
    for (k, &ti) in t.iter().enumerate() {
        let want = if ti <= 1.0 {
            1000.0 * ti
        } else {
            1000.0 - 400.0 * (ti - 1.0) * 10.0 / 40.0
        };
        assert!(
            rel_err(force[k], want) < 1e-6,
            "force {} at t = {ti}, want {want}",
            force[k]
        );
        let s = if ti <= 1.0 { 2.5 * ti } else { 2.5 };
        assert!(
            rel_err(short[k], s) < 1e-6,
            "shortening {} at t = {ti}",
            short[k]
        );
    }
    let base = column(&out, "bottom.fz");
    assert!(rel_err(*base.last().unwrap(), -1300.0) < 1e-6, "{base:?}");
}

/// `tests/bolt-bar.toml` written as analysts write it: a `pretension` step (the bolt ramps
/// over it and locks at its end) and a `service` step (the traction ramps over it, in
/// quarter increments), with no curves. It gives the answers of the one-step deck with
/// curves in the analysis' time at the shared times (the model is linear), lands on both
/// steps' increments, numbers the rows by step and reports each step in summary.json.
#[test]
fn two_analysis_steps_are_the_one_step_deck() {
    let one = run_deck("steps-one", include_str!("bolt-bar.toml"));
    let staged = include_str!("bolt-bar.toml")
        .replace(
            "[[curves]]\nname = \"pre\"\npoints = [[0, 0], [1, 1], [2, 1]]\n",
            "",
        )
        .replace(
            "[[curves]]\nname = \"service\"\npoints = [[0, 0], [1, 0], [2, 1]]\n",
            "",
        );
    let staged = edit(&staged, "curve = \"service\"", "step = \"service\"");
    let staged = edit(
        &staged,
        "curve = \"pre\"\nlock_at = 1.0",
        "step = \"pretension\"",
    );
    let staged = edit(&staged, "end_time = 2.0\n", "");
    let staged = format!(
        "{staged}\n[[steps]]\nname = \"pretension\"\nduration = 1.0\n\
         [[steps]]\nname = \"service\"\nduration = 1.0\nstep = 0.25\noutput_every = 3\n"
    );
    let two = run_deck("steps-two", &staged);
    let t = column(&two, "time");
    assert_eq!(t, vec![0.5, 1.0, 1.25, 1.5, 1.75, 2.0]);
    assert_eq!(
        column(&two, "analysis_step"),
        vec![1.0, 1.0, 2.0, 2.0, 2.0, 2.0]
    );
    let t1 = column(&one, "time");
    for name in ["bolt1.force", "bolt1.shortening", "bottom.fz", "top.fz"] {
        let (a, b) = (column(&one, name), column(&two, name));
        for (k, ti) in t1.iter().enumerate() {
            let j = t.iter().position(|x| x == ti).unwrap();
            assert!(
                (a[k] - b[j]).abs() <= 1e-9 * a[k].abs().max(1.0),
                "{name} at t = {ti}: {} vs {}",
                a[k],
                b[j]
            );
        }
    }
    let (ua, ub) = (&one.u, &two.u);
    let scale = ua.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(ua
        .iter()
        .zip(ub)
        .all(|(a, b)| (a - b).abs() <= 1e-9 * scale));
    let summary = serde_json::to_value(&two.summary).unwrap();
    let steps = summary["analysis_steps"].as_array().unwrap();
    assert_eq!(steps.len(), 2);
    assert_eq!(steps[1]["name"], "service");
    assert_eq!(steps[1]["end_time"], 2.0);
    assert_eq!(steps[0]["increments"], 2);
    assert_eq!(steps[1]["increments"], 4);
    assert_eq!(steps[1]["completed"], true);
    let its: u64 = steps
        .iter()
        .map(|s| s["nonlinear_iterations"].as_u64().unwrap())
        .sum();
    assert_eq!(Some(its), summary["nonlinear_iterations"].as_u64());
    // Fields: every increment of the first step; every third of the second, and its last.
    let xmf =
        std::fs::read_to_string(std::path::Path::new(&two.summary.output_dir).join("bolt-bar.xmf"))
            .unwrap();
    // The first block's grids (every block has the same steps), the state at t = 0 first.
    let first = xmf.split("CollectionType=\"Temporal\"").nth(1).unwrap();
    let first = first.split("CollectionType=\"Temporal\"").next().unwrap();
    let times: Vec<&str> = first
        .split("<Time Value=\"")
        .skip(1)
        .map(|s| s.split('"').next().unwrap())
        .collect();
    assert_eq!(times, vec!["0.0", "0.5", "1.0", "1.75", "2.0"], "{xmf}");
}

/// Step mistakes name their field.
#[test]
fn bad_step_decks_name_the_field() {
    let bolt = include_str!("bolt-bar.toml");
    let steps =
        "\n[[steps]]\nname = \"a\"\nduration = 1.0\n[[steps]]\nname = \"b\"\nduration = 1.0\n";
    let cases = [
        (
            format!(
                "{}{steps}",
                edit(
                    bolt,
                    "curve = \"service\"",
                    "curve = \"service\"\nstep = \"c\""
                )
            ),
            "loads[0].step: unknown step `c` (steps: a, b)",
        ),
        (
            format!("{}{steps}", edit(bolt, "end_time = 2.0", "end_time = 3.0")),
            "analysis.end_time: 3 differs from the steps' total duration 2",
        ),
        (
            format!(
                "{}{steps}\n[[curves]]\nname = \"one\"\npoints = [[0, 1]]\n",
                edit(bolt, "curve = \"service\"", "curve = \"one\"\nstep = \"b\"")
            ),
            "loads[0].curve: the curve is 1 at the start of step `b`",
        ),
        (
            format!(
                "{}{}",
                edit(bolt, "lock_at = 1.0", "lock_at = \"z\""),
                steps
            ),
            "bolts[0].lock_at: unknown step `z`",
        ),
        (
            format!(
                "{bolt}{}",
                steps.replace("duration = 1.0\n[[steps]]", "duration = -1.0\n[[steps]]")
            ),
            "steps[0].duration: expected a positive time",
        ),
        (
            edit(bolt, "lock_at = 1.0", "step = \"a\""),
            "bolts[0].step: unknown step `a` (the deck has no [[steps]])",
        ),
    ];
    for (deck, want) in cases {
        let e = try_run_deck("steps-bad", &deck).err().expect("refused");
        let msg = e.to_string();
        assert!(msg.contains(want), "expected `{want}` in: {msg}");
    }
}
