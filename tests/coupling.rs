//! The distributing coupling (RBE3) at scene level: the built-in `coupled-cantilever`
//! against beam theory (a tip force, then a tip moment, applied at the reference point),
//! its driven variant (a prescribed tip rotation and its reaction moment), the
//! generalized Jacobian against finite differences, and deck mistakes. The 1 vs 2 rank
//! comparison (tip face split between ranks) is in `cli_mpi.rs`.

mod common;
use common::*;

const E: f64 = 200000.0;
const L: f64 = 100.0;
/// 10 × 10 mm section.
const I: f64 = 10.0 * 1000.0 / 12.0;
const A: f64 = 100.0;
const G: f64 = E / 2.0; // ν = 0

fn last(v: &[f64]) -> f64 {
    *v.last().unwrap()
}

/// Tip force F along −z (t ≤ 1), then a moment M about z added (t ≤ 2): the reference
/// point's displacement and rotations against Timoshenko beam theory, within 2 %.
#[test]
fn coupled_cantilever_matches_beam_theory() {
    let out = run_deck("coupled-cantilever", &builtin("coupled-cantilever"));
    assert!(out.summary.converged);
    let (f, m) = (100.0, 10000.0);
    let delta = f * L.powi(3) / (3.0 * E * I) + f * L / (5.0 / 6.0 * G * A);
    let uz = column(&out, "tip.uz");
    let ry = column(&out, "tip.ry");
    let rz = column(&out, "tip.rz");
    let uy = column(&out, "tip.uy");
    let t = column(&out, "time");
    assert_eq!(t, vec![1.0, 2.0]);
    let checks = [
        ("tip.uz at t = 1", -uz[0], delta),
        ("tip.ry at t = 1", ry[0], f * L * L / (2.0 * E * I)),
        ("tip.rz at t = 2", rz[1], m * L / (E * I)),
        ("tip.uy at t = 2", uy[1], m * L * L / (2.0 * E * I)),
        ("tip.uz at t = 2", -uz[1], delta),
    ];
    for (what, got, want) in checks {
        let e = rel_err(got, want);
        eprintln!(
            "{what}: {got:.6e} vs {want:.6e} ({:+.2} %)",
            100.0 * (got / want - 1.0)
        );
        assert!(e < 0.02, "{what}: {got} vs beam theory {want}");
    }
    // The applied load is what the point transmits, and the clamp carries it.
    assert!((last(&column(&out, "tip.fz")) + f).abs() < 1e-9 * f);
    assert!((last(&column(&out, "tip.mz")) - m).abs() < 1e-9 * m);
    for (i, rec) in out.steps.iter().enumerate() {
        assert!(
            (rec.reactions[0][2] - f).abs() < 1e-8 * f,
            "step {i}: clamp {:?}",
            rec.reactions[0]
        );
    }
    // Free and unloaded DOFs transmit nothing.
    for c in ["tip.fx", "tip.fy", "tip.mx", "tip.my"] {
        assert!(last(&column(&out, c)).abs() < 1e-9 * f, "{c}");
    }
    // The summary carries the coupling's last state.
    let s = &out.summary.contributions["couplings"]["tip"];
    assert!((s["rotation"][2].as_f64().unwrap() - rz[1]).abs() < 1e-15);
}

/// The driven variant: the tip's rotation about z prescribed (every other DOF free and
/// unloaded); the reaction moment is E I θ / L, within 2 %, and the prescribed rotation
/// is met exactly.
#[test]
fn driven_tip_rotation_reports_the_reaction_moment() {
    let deck = edit(
        &builtin("coupled-cantilever"),
        "force = { z = { value = -100.0, curve = \"force\" } }     # N\nmoment = { z = { value = 10000.0, curve = \"moment\" } }  # N·mm",
        "rotation = { z = { value = 0.006, curve = \"force\" } }",
    );
    let out = run_deck("coupled-driven", &deck);
    assert!(out.summary.converged);
    let theta = 0.006;
    let rz = column(&out, "tip.rz");
    assert!((last(&rz) - theta).abs() < 1e-12, "rz {rz:?}");
    let mz = last(&column(&out, "tip.mz"));
    let want = E * I * theta / L;
    eprintln!("reaction moment {mz:.6e} vs E I θ / L = {want:.6e}");
    assert!(rel_err(mz, want) < 0.02, "{mz} vs {want}");
    // Pure bending: no transverse reaction, and u_y = θ L / 2.
    assert!(last(&column(&out, "tip.fy")).abs() < 1e-6 * want / L);
    assert!(rel_err(last(&column(&out, "tip.uy")), theta * L / 2.0) < 0.02);
}

/// The coupling's generalized Jacobian (node–multiplier, point–multiplier blocks)
/// against central differences of the residual, on a coarse beam at a perturbed state
/// (the −10⁻⁸κ Jacobian-only diagonal of the multiplier rows is the expected
/// difference).
#[test]
fn coupling_jacobian_matches_finite_differences() {
    let deck = edit(
        &builtin("coupled-cantilever"),
        "cells = [80, 8, 8]",
        "cells = [4, 2, 2]",
    );
    for (name, deck) in [
        ("free", deck.clone()),
        (
            "driven",
            edit(
                &deck,
                "moment = { z = { value = 10000.0, curve = \"moment\" } }",
                "rotation = { y = { value = 0.001, curve = \"moment\" } }",
            ),
        ),
    ] {
        let mut out = run_deck(&format!("coupling-jac-{name}"), &deck);
        for (seed, amp) in [(1, 1e-3), (2, 1e-1)] {
            let err = jacobian_fd_error(&mut out, seed, amp);
            eprintln!("{name} seed {seed}: {err:e}");
            assert!(err < 1e-6, "{name}: Jacobian off by {err:e}");
        }
    }
}

/// Deck mistakes name the field and say what was expected.
#[test]
fn bad_coupling_decks_name_the_field() {
    let base = builtin("coupled-cantilever");
    let cases = [
        (
            edit(&base, "nodes = \"tip_face\"", "nodes = \"nope\""),
            "couplings[0].nodes",
        ),
        (
            edit(
                &base,
                "moment = { z = { value = 10000.0, curve = \"moment\" } }",
                "moment = { z = 1.0 }\nrotation = { z = 0.1 }",
            ),
            "couplings[0].moment.z",
        ),
        (
            edit(
                &base,
                "nodes = \"tip_face\"",
                "nodes = \"clamp\"\nweights = \"area\"",
            ),
            "couplings[0].weights",
        ),
        (
            edit(
                &base,
                "force = { z = { value = -100.0, curve = \"force\" } }",
                "force = { z = { value = -100.0, curve = \"nope\" } }",
            ),
            "couplings[0].force.z.curve",
        ),
        (
            edit(
                &base,
                "force = { z = { value = -100.0, curve = \"force\" } }",
                "force = { w = 1.0 }",
            ),
            "couplings[0].force",
        ),
    ];
    // History columns `<name>.fx` may not collide with a reaction set's.
    let clash = edit(
        &edit(
            &base,
            "[[surfaces]]",
            "[[node_sets]]\nname = \"tip\"\ngroup = \"xmax\"\n\n[[surfaces]]",
        ),
        "reactions = [\"clamp\"]",
        "reactions = [\"clamp\", \"tip\"]",
    );
    let mut cases = cases.to_vec();
    cases.push((clash, "couplings[0].name"));
    for (deck, field) in cases {
        let e = try_run_deck("bad-coupling", &deck)
            .err()
            .expect("must fail");
        assert_eq!(e.kind, alfe::ErrorKind::Input, "{e}");
        assert!(e.message.contains(field), "`{field}` not in: {e}");
    }
    // Nodes on a line cannot carry a moment about it.
    let line = edit(
        &edit(
            &base,
            "[[surfaces]]",
            "[[node_sets]]\nname = \"edge\"\nbox = { min = [100, 0, 0], max = [100, 10, 0] }\n\n[[surfaces]]",
        ),
        "nodes = \"tip_face\"",
        "nodes = \"edge\"",
    );
    let e = try_run_deck("bad-coupling-line", &line).err().unwrap();
    assert!(
        e.message.contains("couplings[0].nodes") && e.message.contains("on a line"),
        "{e}"
    );
    // Explicit analyses have no place for a massless reference point.
    let explicit = edit(
        &edit(&base, "type = \"static\"", "type = \"explicit\""),
        "E = 200000.0       # MPa",
        "E = 200000.0\ndensity = 7.85e-9",
    );
    let e = try_run_deck("bad-coupling-explicit", &explicit)
        .err()
        .unwrap();
    assert!(
        e.message.contains("couplings[0]") && e.message.contains("static"),
        "{e}"
    );
}
