//! Rigid-wall contact: the generalized Jacobian against finite differences, and the
//! scene-level checks of issue 5 (zero penetration, contact patch test, Hertz, sliding
//! block, initial penetration).

mod common;
use alfe::parallel::SerialComm;
use common::*;

/// Max over columns of ‖K e_j − (r(u + ε e_j) − r(u − ε e_j))/2ε‖ / ‖K‖_max, at a
/// perturbed state of a converged run (so nodes sit in several branches of the law).
fn jacobian_fd_error(out: &mut alfe::app::RunOutcome, seed: u64, amp: f64) -> f64 {
    let comm = SerialComm;
    let n = out.u.len();
    let mut s = seed;
    let mut rnd = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    };
    let u: Vec<f64> = out.u.iter().map(|&x| x + amp * rnd()).collect();
    let t = out.steps.last().unwrap().time;
    let mut k = out.model.new_matrix(&comm);
    out.model.jacobian(&comm, &u, t, &mut k).unwrap();
    let (mut worst, mut scale) = (0.0f64, 0.0f64);
    let eps = 1e-7;
    let mut rp = vec![0.0; n];
    let mut rm = vec![0.0; n];
    let mut e = vec![0.0; n];
    let mut ke = vec![0.0; n];
    for j in 0..n {
        e.iter_mut().for_each(|x| *x = 0.0);
        e[j] = 1.0;
        k.spmv(&comm, &e, &mut ke);
        let mut up = u.clone();
        up[j] += eps;
        out.model.residual(&comm, &up, t, &mut rp).unwrap();
        let mut um = u.clone();
        um[j] -= eps;
        out.model.residual(&comm, &um, t, &mut rm).unwrap();
        for i in 0..n {
            let fd = (rp[i] - rm[i]) / (2.0 * eps);
            worst = worst.max((fd - ke[i]).abs());
            scale = scale.max(ke[i].abs());
        }
    }
    worst / scale
}

fn small_sliding_block(method: &str) -> String {
    let d = builtin("sliding-block");
    let d = edit(&d, "cells = [8, 4, 4]", "cells = [2, 1, 1]");
    edit(
        &d,
        "friction = 0.3",
        &format!("friction = 0.3\nmethod = \"{method}\""),
    )
}

#[test]
fn contact_jacobian_matches_finite_differences() {
    for method in ["alm", "penalty"] {
        let mut out = run_deck(&format!("jac-{method}"), &small_sliding_block(method));
        for (seed, amp) in [(1, 1e-4), (2, 1e-3), (3, 1e-2)] {
            let err = jacobian_fd_error(&mut out, seed, amp);
            eprintln!("{method} seed {seed} amp {amp}: {err:e}");
            assert!(
                err < 1e-6,
                "{method}: Jacobian off by {err:e} (seed {seed})"
            );
        }
    }
}
