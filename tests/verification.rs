//! Verification against closed-form solutions, in process on one rank: patch tests on
//! distorted meshes, a homogeneous large stretch, a cantilever against beam theory
//! with its order of mesh convergence, and the large-deflection elastica.

mod common;
use common::*;

/// Homogeneous deformation check: every node's displacement is (λ_i − 1) X_i.
fn assert_homogeneous(out: &alfe::app::RunOutcome, stretch: [f64; 3], tol: f64) -> f64 {
    let mut worst = 0.0f64;
    let mut scale = 0.0f64;
    for (_, x, u) in out.displacement_by_node() {
        for i in 0..3 {
            let exact = (stretch[i] - 1.0) * x[i];
            worst = worst.max((u[i] - exact).abs());
            scale = scale.max(exact.abs());
        }
    }
    let rel = worst / scale;
    assert!(
        rel < tol,
        "homogeneous field not reproduced: max error {worst:e} (relative {rel:e})"
    );
    rel
}

/// Neo-Hookean (Bonet & Wood 6.28) first Piola–Kirchhoff stress for F = diag(l).
fn neo_hookean_p(l: [f64; 3], e: f64, nu: f64) -> [f64; 3] {
    let mu = e / (2.0 * (1.0 + nu));
    let lam = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let j = l[0] * l[1] * l[2];
    [0, 1, 2].map(|i| mu * (l[i] - 1.0 / l[i]) + lam * j.ln() / l[i])
}

/// Solve P(diag(l)) = target for l by Newton with a finite-difference Jacobian.
fn neo_hookean_stretch(target: [f64; 3], e: f64, nu: f64) -> [f64; 3] {
    let mut l = [1.0; 3];
    for _ in 0..100 {
        let p = neo_hookean_p(l, e, nu);
        let r: Vec<f64> = (0..3).map(|i| p[i] - target[i]).collect();
        if r.iter().map(|v| v.abs()).fold(0.0, f64::max) < 1e-14 * e {
            break;
        }
        let mut jac = [[0.0; 3]; 3];
        for k in 0..3 {
            let mut lp = l;
            lp[k] += 1e-7;
            let pp = neo_hookean_p(lp, e, nu);
            for i in 0..3 {
                jac[i][k] = (pp[i] - p[i]) / 1e-7;
            }
        }
        let m = nalgebra::Matrix3::from_fn(|i, k| jac[i][k]);
        let d = m
            .lu()
            .solve(&nalgebra::Vector3::new(r[0], r[1], r[2]))
            .unwrap();
        for i in 0..3 {
            l[i] -= d[i];
        }
    }
    l
}

const PATCH_TRACTION: [f64; 3] = [10.0, -4.0, 6.0];

#[test]
fn patch_hex8_linear_elastic_distorted() {
    let out = run_deck(
        "patch-hex8-le",
        &edit(
            &builtin("patch-hex8"),
            "step = 1.0\n",
            "step = 1.0\n[solver]\nresidual_rtol = 1e-10\n",
        ),
    );
    let (e, nu) = (200000.0, 0.3);
    let s = PATCH_TRACTION;
    let eps = [0, 1, 2].map(|i| (s[i] - nu * (s[(i + 1) % 3] + s[(i + 2) % 3])) / e);
    assert_homogeneous(&out, eps.map(|x| 1.0 + x), 1e-9);
    // Element stresses: σ = diag(10, −4, 6) in every element.
    let sig = field(&out, "stress");
    for st in sig.chunks(6) {
        for i in 0..3 {
            assert!((st[i] - s[i]).abs() < 1e-8 * 10.0, "element stress {st:?}");
        }
        for v in &st[3..] {
            assert!(v.abs() < 1e-8 * 10.0, "shear stress {st:?}");
        }
    }
}

#[test]
fn patch_hex8_neo_hookean_distorted() {
    let text = edit(
        &builtin("patch-hex8"),
        "model = \"linear-elastic\"\nE = 200000.0",
        "model = \"neo-hookean\"\nE = 100.0",
    );
    let text = edit(
        &text,
        "step = 1.0\n",
        "step = 0.5\n[solver]\nresidual_rtol = 1e-12\n",
    );
    let out = run_deck("patch-hex8-nh", &text);
    assert_homogeneous(&out, neo_hookean_stretch(PATCH_TRACTION, 100.0, 0.3), 1e-9);
}

#[test]
fn patch_tet4_neo_hookean_distorted() {
    let text = edit(
        &builtin("patch-tet4"),
        "step = 1.0\n",
        "step = 0.5\n[solver]\nresidual_rtol = 1e-12\n",
    );
    let out = run_deck("patch-tet4-nh", &text);
    let l = neo_hookean_stretch(PATCH_TRACTION, 100.0, 0.3);
    assert!(
        l.iter().any(|&x| (x - 1.0).abs() > 0.05),
        "the patch should be at large strain: {l:?}"
    );
    assert_homogeneous(&out, l, 1e-9);
}

/// The F-bar-patch tet4 (issue 35) passes the same finite-strain patch test: under a
/// homogeneous state every patch's J̄ is every tet's J, so F̄ = F.
#[test]
fn patch_tet4_fbar_patch_neo_hookean_distorted() {
    let text = edit(
        &builtin("patch-tet4"),
        "step = 1.0\n",
        "step = 0.5\n[solver]\nresidual_rtol = 1e-12\n",
    );
    let text = edit(
        &text,
        "material = \"rubber\"\n",
        "material = \"rubber\"\nformulation = \"fbar\"\n",
    );
    let out = run_deck("patch-tet4-fbar", &text);
    let dir =
        std::env::temp_dir().join(format!("alfe-test-{}-patch-tet4-fbar", std::process::id()));
    let record = std::fs::read_to_string(dir.join("out").join("deck.toml")).unwrap();
    assert!(record.contains("F-bar patch"), "{record}");
    assert_homogeneous(&out, neo_hookean_stretch(PATCH_TRACTION, 100.0, 0.3), 1e-9);
}

#[test]
fn patch_tet4_linear_elastic_distorted() {
    let text = edit(
        &builtin("patch-tet4"),
        "model = \"neo-hookean\"\nE = 100.0",
        "model = \"linear-elastic\"\nE = 200000.0",
    );
    let text = edit(
        &text,
        "step = 1.0\n",
        "step = 1.0\n[solver]\nresidual_rtol = 1e-10\n",
    );
    let out = run_deck("patch-tet4-le", &text);
    let (e, nu) = (200000.0, 0.3);
    let s = PATCH_TRACTION;
    let eps = [0, 1, 2].map(|i| (s[i] - nu * (s[(i + 1) % 3] + s[(i + 2) % 3])) / e);
    assert_homogeneous(&out, eps.map(|x| 1.0 + x), 1e-9);
}

/// The cube pulled to λ = 2 between rollers: F = diag(2, λt, λt) with P_yy = 0; the
/// reaction on x = 0 is −P_xx · A0 at every step (λ = 1 + t).
#[test]
fn neo_hookean_cube_large_stretch_matches_closed_form() {
    let text = edit(
        &builtin("cube-stretch"),
        "step = 0.25\n",
        "step = 0.25\n[solver]\nresidual_rtol = 1e-12\n",
    );
    let out = run_deck("cube-stretch", &text);
    let (e, nu) = (3.0, 0.4);
    assert_eq!(out.steps.len(), 4);
    for rec in &out.steps {
        let lx = 1.0 + rec.time;
        // Lateral stretch from P_yy = 0 (bisection on a monotone function).
        let (mut a, mut b) = (0.2, 1.0);
        for _ in 0..200 {
            let m = 0.5 * (a + b);
            if neo_hookean_p([lx, m, m], e, nu)[1] > 0.0 {
                b = m
            } else {
                a = m
            }
        }
        let lt = 0.5 * (a + b);
        let pxx = neo_hookean_p([lx, lt, lt], e, nu)[0];
        let fx0 = rec.reactions[0][0];
        let fx1 = rec.reactions[1][0];
        assert!(
            rel_err(-fx0, pxx) < 1e-8,
            "t = {}: reaction {fx0} vs −P_xx·A0 = {}",
            rec.time,
            -pxx
        );
        assert!(
            rel_err(fx1, pxx) < 1e-8,
            "t = {}: reaction {fx1} vs P_xx·A0 = {pxx}",
            rec.time
        );
        if rec.time == 1.0 {
            assert_homogeneous(&out, [lx, lt, lt], 1e-9);
        }
    }
}

fn cantilever_deck(cells: [usize; 3]) -> String {
    format!(
        r#"
[scene]
name = "beam-{0}"
units = "mm-t-s"
[[materials]]
name = "m"
model = "linear-elastic"
E = 1000.0
nu = 0.0
[[parts]]
name = "beam"
material = "m"
mesh = {{ kind = "box", size = [10, 1, 1], cells = [{0}, {1}, {2}] }}
[[node_sets]]
name = "clamp"
group = "xmin"
[[surfaces]]
name = "tip"
group = "xmax"
[[boundary]]
type = "fixed"
set = "clamp"
[[loads]]
type = "traction"
surface = "tip"
traction = [0.0, 0.0, -0.01]
[analysis]
type = "static"
end_time = 1.0
step = 1.0
"#,
        cells[0], cells[1], cells[2]
    )
}

fn mean_tip_deflection(out: &alfe::app::RunOutcome) -> f64 {
    let tip: Vec<f64> = out
        .displacement_by_node()
        .into_iter()
        .filter(|(_, x, _)| x[0] > 10.0 - 1e-9)
        .map(|(_, _, u)| u[2])
        .collect();
    tip.iter().sum::<f64>() / tip.len() as f64
}

/// Tip-loaded cantilever (L/h = 10, ν = 0) against Timoshenko beam theory
/// δ = PL³/3EI + PL/κGA (κ = 5/6). Fully integrated hex8 converge at second order in
/// the mesh size; Richardson extrapolation of three meshes lands on the closed form
/// (the remaining gap is the 3D clamp and end effects, O(h/L) of the shear term).
#[test]
fn cantilever_converges_to_beam_theory_at_second_order() {
    let (e, l, p): (f64, f64, f64) = (1000.0, 10.0, 0.01);
    let i = 1.0 / 12.0;
    let g = e / 2.0;
    let exact = p * l.powi(3) / (3.0 * e * i) + p * l / (5.0 / 6.0 * g * 1.0);
    let d: Vec<f64> = [2usize, 4, 8]
        .iter()
        .map(|&k| {
            -mean_tip_deflection(&run_deck(
                &format!("beam{k}"),
                &cantilever_deck([10 * k, k, k]),
            ))
        })
        .collect();
    let order = ((d[1] - d[0]) / (d[2] - d[1])).log2();
    let extrapolated = d[2] + (d[2] - d[1]) / (2f64.powf(order) - 1.0);
    eprintln!(
        "tip deflections {d:?}, exact {exact}, order {order:.3}, extrapolated {extrapolated}"
    );
    assert!(
        d[0] < d[1] && d[1] < d[2],
        "monotone convergence from below (stiff hex8): {d:?}"
    );
    assert!((1.7..2.3).contains(&order), "observed order {order}");
    assert!(
        rel_err(extrapolated, exact) < 0.01,
        "extrapolated {extrapolated} vs closed form {exact}"
    );
    assert!(
        rel_err(d[2], exact) < 0.05,
        "finest mesh {} vs closed form {exact}",
        d[2]
    );
}

/// The built-in large-deflection cantilever against the inextensible elastica
/// (EI θ'' = −P cos θ, θ(0) = 0, θ'(L) = 0) solved here by shooting: the tip moves
/// about 0.6 L down and 0.25 L back at PL²/EI = 3.
#[test]
fn cantilever_large_deflection_matches_elastica() {
    let out = run_deck("cantilever", &builtin("cantilever"));
    // Elastica with α = PL²/EI = 30·100/(12000/12) = 3, by RK4 shooting on θ'(0).
    let alpha = 3.0;
    let shoot = |k0: f64| -> (f64, f64, f64) {
        let n = 4000;
        let h = 1.0 / n as f64;
        let (mut th, mut k, mut x, mut z) = (0.0f64, k0, 0.0f64, 0.0f64);
        let f = |th: f64, k: f64| (k, -alpha * th.cos());
        for _ in 0..n {
            let (a1, b1) = f(th, k);
            let (a2, b2) = f(th + 0.5 * h * a1, k + 0.5 * h * b1);
            let (a3, b3) = f(th + 0.5 * h * a2, k + 0.5 * h * b2);
            let (a4, b4) = f(th + h * a3, k + h * b3);
            // Position by the trapezoid rule on the midpoint angle.
            let th_new = th + h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
            x += h * (0.5 * (th + th_new)).cos();
            z += h * (0.5 * (th + th_new)).sin();
            k += h / 6.0 * (b1 + 2.0 * b2 + 2.0 * b3 + b4);
            th = th_new;
        }
        (k, x, z)
    };
    let (mut a, mut b) = (0.0, 10.0);
    for _ in 0..100 {
        let m = 0.5 * (a + b);
        if shoot(m).0 > 0.0 {
            b = m
        } else {
            a = m
        }
    }
    let (_, x, z) = shoot(0.5 * (a + b));
    let (ux_exact, uz_exact) = ((x - 1.0) * 10.0, -z * 10.0);
    let tip: Vec<[f64; 3]> = out
        .displacement_by_node()
        .into_iter()
        .filter(|(_, x, _)| x[0] > 10.0 - 1e-9)
        .map(|(_, _, u)| u)
        .collect();
    let ux = tip.iter().map(|u| u[0]).sum::<f64>() / tip.len() as f64;
    let uz = tip.iter().map(|u| u[2]).sum::<f64>() / tip.len() as f64;
    eprintln!("tip ({ux}, {uz}) vs elastica ({ux_exact}, {uz_exact})");
    assert!(
        rel_err(uz, uz_exact) < 0.03,
        "vertical tip deflection {uz} vs elastica {uz_exact}"
    );
    assert!(
        rel_err(ux, ux_exact) < 0.05,
        "horizontal tip displacement {ux} vs elastica {ux_exact}"
    );
    // Equilibrium: the clamp carries the whole tip load at every step.
    for rec in &out.steps {
        assert!(
            rel_err(rec.reactions[0][2], 30.0 * rec.time) < 1e-8,
            "step {}: {:?}",
            rec.step,
            rec.reactions[0]
        );
    }
}
