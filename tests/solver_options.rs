//! Solver options at scene level: a block-Jacobi factorization kept (lagged) across
//! Newton iterations and load steps gives the same converged answer with far fewer
//! factorizations; the unpreconditioned path converges too.

mod common;
use common::*;

fn max_diff(a: &alfe::app::RunOutcome, b: &alfe::app::RunOutcome) -> (f64, f64) {
    let ua = a.displacement_by_node();
    let ub = b.displacement_by_node();
    let mut d = 0.0f64;
    let mut s = 0.0f64;
    for ((na, _, x), (nb, _, y)) in ua.iter().zip(&ub) {
        assert_eq!(na, nb);
        for c in 0..3 {
            d = d.max((x[c] - y[c]).abs());
            s = s.max(x[c].abs());
        }
    }
    (d, s)
}

#[test]
fn lagged_block_jacobi_same_answer_fewer_factorizations() {
    let base = builtin("cantilever");
    let fresh = run_deck("lag0", &base);
    let lagged = run_deck(
        "lag100",
        &edit(
            &base,
            "max_iterations = 25\n",
            "max_iterations = 25\n[solver.linear]\nlag = 100\n",
        ),
    );
    let (d, s) = max_diff(&fresh, &lagged);
    assert!(
        d <= 1e-7 * s,
        "lagged preconditioner changed the answer: {d:e} of {s:e}"
    );
    let (f0, f1) = (fresh.summary.factorizations, lagged.summary.factorizations);
    assert_eq!(
        f0, fresh.summary.nonlinear_iterations,
        "lag 0 refactors at every Newton iteration"
    );
    assert!(f1 * 10 <= f0, "lag 100 should factor rarely: {f1} vs {f0}");
    assert!(
        lagged.summary.linear_iterations > fresh.summary.linear_iterations,
        "an older factorization costs GMRES iterations"
    );
    eprintln!(
        "factorizations {f0} -> {f1}, GMRES iterations {} -> {}, Newton {} -> {}",
        fresh.summary.linear_iterations,
        lagged.summary.linear_iterations,
        fresh.summary.nonlinear_iterations,
        lagged.summary.nonlinear_iterations
    );
}

#[test]
fn unpreconditioned_gmres_reaches_the_same_answer() {
    let text = edit(&builtin("patch-hex8"), "step = 1.0\n", "step = 1.0\n[solver]\nresidual_rtol = 1e-10\n[solver.linear]\npreconditioner = \"none\"\nrestart = 200\n");
    let plain = run_deck("nopc", &text);
    let bj = run_deck(
        "bj",
        &edit(
            &builtin("patch-hex8"),
            "step = 1.0\n",
            "step = 1.0\n[solver]\nresidual_rtol = 1e-10\n",
        ),
    );
    let (d, s) = max_diff(&plain, &bj);
    assert!(d <= 1e-7 * s, "{d:e} of {s:e}");
    assert_eq!(plain.summary.factorizations, 0);
    assert!(plain.summary.linear_iterations > bj.summary.linear_iterations);
}

/// The whole cantilever load in one step with a budget of 8 iterations cannot converge;
/// step control halves it (counted retries), grows it back after easy steps, and the run
/// ends at the same answer as ten even steps.
#[test]
fn a_too_large_first_step_is_rescued_by_retries() {
    let base = builtin("cantilever");
    let reference = run_deck("even", &base);
    let one = edit(&base, "step = 0.1\n", "step = 1.0\n");
    let one = edit(&one, "max_iterations = 25", "max_iterations = 8");
    let out = run_deck("onestep", &one);
    assert!(out.summary.converged);
    assert!(
        out.summary.retries >= 1,
        "the first attempt must fail: {:?}",
        out.summary.retries
    );
    let last = out.steps.last().unwrap();
    assert_eq!(last.time, 1.0);
    assert!(out.steps.iter().any(|s| s.retries > 0));
    let (d, s) = max_diff(&reference, &out);
    assert!(d <= 1e-6 * s, "{d:e} of {s:e}");
    eprintln!(
        "steps {} retries {} times {:?}",
        out.steps.len(),
        out.summary.retries,
        out.steps.iter().map(|s| s.time).collect::<Vec<_>>()
    );
}

/// AMG needs an elliptic matrix: a deck whose couplings add multipliers that cannot be
/// condensed is refused before the run, naming the deck field (exit code 2), not left
/// to fail in the middle of a step.
#[test]
fn amg_with_couplings_is_refused_naming_the_field() {
    let text = edit(
        &builtin("coupled-cantilever"),
        "[solver.linear]\n",
        "[solver.linear]\npreconditioner = \"amg\"\n",
    );
    let e = try_run_deck("amg-coupling", &text)
        .err()
        .expect("must fail");
    let msg = e.to_string();
    assert_eq!(e.exit_code(), 2, "{msg}");
    assert!(
        msg.contains("[solver.linear] preconditioner") && msg.contains("couplings"),
        "{msg}"
    );
}

/// The linear predictor (the default) starts each step from the last increment
/// extrapolated: the same converged answer as starting from the last state, in far fewer
/// iterations on a load path that goes on as it went (sliding-block: 158 → 88 Newton
/// iterations when measured).
#[test]
fn linear_predictor_same_answer_fewer_iterations() {
    let base = builtin("sliding-block");
    let with = run_deck("predictor-linear", &base);
    let without = run_deck(
        "predictor-none",
        &edit(&base, "[analysis]\n", "[analysis]\npredictor = \"none\"\n"),
    );
    for out in [&with, &without] {
        assert!(out.summary.converged);
    }
    let (fw, fo) = (column(&with, "floor.fx"), column(&without, "floor.fx"));
    let (nw, no) = (column(&with, "floor.fz"), column(&without, "floor.fz"));
    let scale = nw.last().unwrap().abs();
    assert!(
        (fw.last().unwrap() - fo.last().unwrap()).abs() < 1e-6 * scale
            && (nw.last().unwrap() - no.last().unwrap()).abs() < 1e-6 * scale,
        "final floor force differs: ({}, {}) vs ({}, {})",
        fw.last().unwrap(),
        nw.last().unwrap(),
        fo.last().unwrap(),
        no.last().unwrap()
    );
    let (iw, io) = (
        with.summary.nonlinear_iterations,
        without.summary.nonlinear_iterations,
    );
    eprintln!("newton iterations: predictor {iw}, none {io}");
    assert!(3 * iw < 2 * io, "predictor {iw} vs none {io}");
}

#[test]
fn bad_predictor_names_the_field() {
    let base = builtin("sliding-block");
    let bad = edit(
        &base,
        "[analysis]\n",
        "[analysis]\npredictor = \"quadratic\"\n",
    );
    let e = try_run_deck("predictor-bad", &bad).err().expect("refused");
    let msg = e.to_string();
    assert!(msg.contains("predictor") && msg.contains("linear"), "{msg}");
}
