//! The hybrid hex8 (F-bar with its pressure as an unknown, `fem/hybrid.rs`) in whole
//! models: the assembled Jacobian with the pressure blocks against finite differences,
//! F-bar's answers in a fraction of the Newton iterations, and the deck's refusals.
//! Rank independence is covered where `auto` takes it: `twisted-block` and
//! `cook-membrane` on 1 and 2 ranks (`tests/cli_mpi.rs`) and the baselines.

mod common;
use common::*;

/// `cylinder-press` (Mooney–Rivlin, ν = 0.4995, a frictional roller) with `formulation`
/// and the mesh coarsened to `cells`.
fn press(formulation: &str, cells: &str) -> String {
    let d = edit(
        &builtin("cylinder-press"),
        "cells = [24, 1, 16]",
        &format!("cells = {cells}"),
    );
    edit(
        &d,
        "material = \"rubber\"\n",
        &format!("material = \"rubber\"\nformulation = \"{formulation}\"\n"),
    )
}

/// The model's Jacobian, pressure rows and columns included, is the derivative of its
/// residual at perturbed states of converged runs: the twisted block (large rotations,
/// every element's pressure active) and the frictional sliding block (contact
/// multipliers beside the pressure blocks; its ν = 0.3 solid made hybrid on purpose).
#[test]
fn hybrid_jacobian_matches_finite_differences() {
    let twisted = edit(
        &builtin("twisted-block"),
        "cells = [8, 8, 32]",
        "cells = [2, 2, 3]",
    );
    let sliding = edit(
        &edit(
            &builtin("sliding-block"),
            "cells = [8, 4, 4]",
            "cells = [2, 1, 1]",
        ),
        "model = \"linear-elastic\"",
        "model = \"neo-hookean\"",
    );
    for (name, deck) in [("twisted", twisted), ("sliding", sliding)] {
        let deck = edit(
            &deck,
            "[[parts]]\n",
            "[[parts]]\nformulation = \"hybrid\"\n",
        );
        let mut out = run_deck(&format!("hybrid-jac-{name}"), &deck);
        assert!(out.summary.converged);
        assert!(
            out.model.n_owned_dofs() > out.model.n_node_dofs() + 6,
            "{name}: pressure unknowns expected"
        );
        for (seed, amp) in [(1, 1e-4), (2, 1e-3)] {
            let err = jacobian_fd_error(&mut out, seed, amp);
            eprintln!("{name} seed {seed} amp {amp}: {err:e}");
            assert!(err < 1e-6, "{name}: Jacobian off by {err:e} (seed {seed})");
        }
    }
}

/// The same forces and stresses as F-bar (a solution of one is a solution of the other),
/// and Newton needs a fraction of F-bar's iterations: nearly incompressible rubber
/// flowing round a roller (measured 38 against 179, without a retry against 1).
#[test]
fn hybrid_gives_fbar_answers_in_a_fraction_of_the_iterations() {
    let fbar = run_deck("hybrid-vs-fbar-f", &press("fbar", "[24, 1, 16]"));
    let hybrid = run_deck("hybrid-vs-fbar-h", &press("hybrid", "[24, 1, 16]"));
    assert!(fbar.summary.converged && hybrid.summary.converged);
    let (ff, fh) = (column(&fbar, "roller.fz"), column(&hybrid, "roller.fz"));
    let (a, b) = (*ff.last().unwrap(), *fh.last().unwrap());
    eprintln!(
        "roller.fz F-bar {a} ({} its, {} retries), hybrid {b} ({} its, {} retries)",
        fbar.summary.nonlinear_iterations,
        fbar.summary.retries,
        hybrid.summary.nonlinear_iterations,
        hybrid.summary.retries
    );
    assert!(a > 20.0, "the roller presses: {a}");
    assert!(rel_err(b, a) < 1e-6, "roller.fz {b} vs F-bar {a}");
    let (sf, sh) = (field(&fbar, "stress"), field(&hybrid, "stress"));
    let smax = sf.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let worst = sf
        .iter()
        .zip(&sh)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    assert!(worst < 1e-5 * smax, "stress differs by {worst} of {smax}");
    assert!(
        3 * hybrid.summary.nonlinear_iterations < fbar.summary.nonlinear_iterations,
        "hybrid {} vs F-bar {} Newton iterations",
        hybrid.summary.nonlinear_iterations,
        fbar.summary.nonlinear_iterations
    );
}

/// The hybrid element where it cannot work is refused with the field named.
#[test]
fn hybrid_refusals_name_the_field() {
    let cases = [
        (
            edit(
                &builtin("cantilever"),
                "[[parts]]\n",
                "[[parts]]\nformulation = \"hybrid\"\n",
            )
            .replace("model = \"neo-hookean\"", "model = \"linear-elastic\""),
            "parts[0].formulation",
            "linear-elastic",
        ),
        (
            edit(
                &builtin("taylor-bar"),
                "[[parts]]\n",
                "[[parts]]\nformulation = \"hybrid\"\n",
            )
            .replace("type = \"implicit\"", "type = \"explicit\""),
            "parts[0].formulation",
            "explicit",
        ),
    ];
    for (text, field, what) in cases {
        let err = match try_run_deck("hybrid-refused", &text) {
            Ok(_) => panic!("{field}: accepted"),
            Err(e) => e.to_string(),
        };
        assert!(
            err.contains(field) && err.contains(what),
            "{field}: got `{err}`"
        );
    }
}
