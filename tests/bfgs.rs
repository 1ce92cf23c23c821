//! BFGS at scene level: on the twisted block (large rotation, prescribed increments) and
//! the cantilever (dead load) it converges every step to Newton's answer with fewer
//! factorizations; the reform policy works (reform every iteration = factor every
//! iteration); distributed over two in-process ranks it reaches the serial answer.

mod common;
use alfe::app::{setup, Phases, RunOptions, Setup};
use alfe::parallel::{run_ranks, Comm, SerialComm};
use alfe::solve::nonlinear::SolverKind;
use alfe::solve::stepping::{run_static, RunTotals, StepRecord};
use common::*;

struct Outcome {
    totals: RunTotals,
    steps: Vec<StepRecord>,
    /// (user node number, displacement) of the owned nodes.
    u: Vec<(usize, [f64; 3])>,
}

/// Run a deck text with the given solver in this process (on `comm`), calling the
/// stepping loop directly (the CLI path hard-codes Newton).
fn solve_with(
    comm: &dyn Comm,
    dir: &std::path::Path,
    text: &str,
    kind: SolverKind,
    reform: usize,
) -> Outcome {
    let deck = dir.join("deck.toml");
    if comm.rank() == 0 {
        std::fs::write(&deck, text).unwrap();
    }
    comm.barrier();
    let ro = RunOptions {
        target: deck.display().to_string(),
        out: Some(dir.join("out")),
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
    let Setup { mut model, run, .. } = setup(comm, &ro, &mut Phases::default()).unwrap();
    let mut opts = run.solver.clone();
    opts.kind = kind;
    opts.bfgs_reform = reform;
    let mut u = Vec::new();
    let mut steps = Vec::new();
    let totals = run_static(
        comm,
        &mut model,
        &mut u,
        &run.analysis,
        &opts,
        None,
        &mut |rec, _, _, _| {
            steps.push(rec.clone());
            Ok(alfe::solve::stepping::Flow::Continue)
        },
    )
    .unwrap();
    let l = &model.mesh;
    let u = (0..l.n_owned())
        .map(|i| {
            (
                l.orig_node[i] as usize,
                [u[3 * i], u[3 * i + 1], u[3 * i + 2]],
            )
        })
        .collect();
    Outcome { totals, steps, u }
}

fn serial(name: &str, text: &str, kind: SolverKind, reform: usize) -> Outcome {
    let dir = temp_dir(name);
    solve_with(&SerialComm, &dir, text, kind, reform)
}

/// max |a − b| and max |b| over all displacement components (by user node number).
fn max_diff(a: &[(usize, [f64; 3])], b: &[(usize, [f64; 3])]) -> (f64, f64) {
    let mut a = a.to_vec();
    let mut b = b.to_vec();
    a.sort_by_key(|x| x.0);
    b.sort_by_key(|x| x.0);
    assert_eq!(a.len(), b.len());
    let (mut d, mut s) = (0.0f64, 0.0f64);
    for ((na, x), (nb, y)) in a.iter().zip(&b) {
        assert_eq!(na, nb);
        for c in 0..3 {
            d = d.max((x[c] - y[c]).abs());
            s = s.max(y[c].abs());
        }
    }
    (d, s)
}

fn per_step(o: &Outcome) -> String {
    o.steps
        .iter()
        .map(|s| format!("{}/{}", s.stats.iterations, s.stats.factorizations))
        .collect::<Vec<_>>()
        .join(" ")
}

/// BFGS against Newton on one deck: both converge every step, same answer, BFGS
/// factors less often (and usually iterates more).
fn compare(name: &str, text: &str) {
    let newton = serial(&format!("{name}-newton"), text, SolverKind::Newton, 11);
    let bfgs = serial(&format!("{name}-bfgs"), text, SolverKind::Bfgs, 11);
    for (o, what) in [(&newton, "newton"), (&bfgs, "bfgs")] {
        assert!(
            o.totals.converged,
            "{name}: {what} failed: {:?}",
            o.totals.failure
        );
        for s in &o.steps {
            assert!(s.stats.converged, "{name}: {what} step {}", s.step);
        }
    }
    // Both end at the end time; their step sequences may differ (with the linear
    // predictor Newton cuts steps of the small twisted block that BFGS does not).
    assert_eq!(
        newton.steps.last().map(|s| s.time),
        Some(1.0),
        "{name}: newton"
    );
    assert_eq!(bfgs.steps.last().map(|s| s.time), Some(1.0), "{name}: bfgs");
    let (d, s) = max_diff(&bfgs.u, &newton.u);
    eprintln!(
        "{name}: newton {} iterations, {} factorizations, {} residuals, {} GMRES; \
         bfgs {} iterations, {} factorizations, {} residuals, {} GMRES; \
         max |u_bfgs − u_newton| = {d:.3e} of max |u| = {s:.3e}\n  \
         per step (iterations/factorizations) newton: {}\n  bfgs: {}",
        newton.totals.nonlinear_iterations,
        newton.totals.factorizations,
        newton.totals.residual_evaluations,
        newton.totals.linear_iterations,
        bfgs.totals.nonlinear_iterations,
        bfgs.totals.factorizations,
        bfgs.totals.residual_evaluations,
        bfgs.totals.linear_iterations,
        per_step(&newton),
        per_step(&bfgs),
    );
    assert!(d <= 1e-6 * s, "{name}: BFGS answer differs: {d:e} of {s:e}");
    assert!(
        bfgs.totals.factorizations < newton.totals.factorizations,
        "{name}: BFGS should factor less: {} vs {}",
        bfgs.totals.factorizations,
        newton.totals.factorizations
    );
    assert!(
        bfgs.totals.factorizations < bfgs.totals.nonlinear_iterations,
        "{name}: BFGS reuses its factorization"
    );
}

fn small_twisted_block() -> String {
    edit(
        &builtin("twisted-block"),
        "cells = [8, 8, 32]",
        "cells = [4, 4, 16]",
    )
}

#[test]
fn bfgs_matches_newton_on_twisted_block() {
    compare("bfgs-twist", &small_twisted_block());
}

#[test]
fn bfgs_matches_newton_on_cantilever() {
    compare("bfgs-cantilever", &builtin("cantilever"));
}

#[test]
fn reform_every_iteration_factors_every_iteration() {
    let text = builtin("cantilever");
    let o = serial("bfgs-reform1", &text, SolverKind::Bfgs, 1);
    assert!(o.totals.converged, "{:?}", o.totals.failure);
    for s in &o.steps {
        assert!(s.stats.converged);
        assert!(
            s.stats.factorizations >= s.stats.iterations && s.stats.iterations > 0,
            "step {}: {} factorizations for {} iterations",
            s.step,
            s.stats.factorizations,
            s.stats.iterations
        );
    }
    let every11 = serial("bfgs-reform11", &text, SolverKind::Bfgs, 11);
    let (d, s) = max_diff(&o.u, &every11.u);
    assert!(d <= 1e-6 * s, "{d:e} of {s:e}");
    eprintln!(
        "cantilever bfgs reform=1: {} iterations, {} factorizations; reform=11: {} iterations, {} factorizations",
        o.totals.nonlinear_iterations,
        o.totals.factorizations,
        every11.totals.nonlinear_iterations,
        every11.totals.factorizations
    );
}

#[test]
fn bfgs_on_two_ranks_reaches_the_serial_answer() {
    let text = small_twisted_block();
    let one = serial("bfgs-ranks1", &text, SolverKind::Bfgs, 11);
    assert!(one.totals.converged, "{:?}", one.totals.failure);
    let dir = temp_dir("bfgs-ranks2");
    let parts = run_ranks(2, |c| {
        let o = solve_with(c, &dir, &text, SolverKind::Bfgs, 11);
        assert!(o.totals.converged, "{:?}", o.totals.failure);
        (o.u, o.totals.nonlinear_iterations)
    });
    let u2: Vec<(usize, [f64; 3])> = parts.iter().flat_map(|p| p.0.clone()).collect();
    let (d, s) = max_diff(&u2, &one.u);
    eprintln!(
        "two ranks: {} iterations (serial {}), max diff {d:.3e} of {s:.3e}",
        parts[0].1, one.totals.nonlinear_iterations
    );
    assert!(d <= 1e-6 * s, "{d:e} of {s:e}");
}
