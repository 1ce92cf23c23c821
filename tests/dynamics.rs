//! Dynamics on the `bar-vibration` scene (fixed-free steel bar, 40 hex8, ν = 0, uniform
//! initial axial velocity): energy conservation of the trapezoidal rule, the period
//! against 4L/c, explicit against implicit, and the deck checks of the dynamic keys.
//! One rank, in process; 1 vs 2 ranks is in `cli_mpi.rs`.

mod common;
use alfe::ErrorKind;
use common::*;

const L: f64 = 400.0;
const E: f64 = 210000.0;
const RHO: f64 = 7.85e-9;
const V0: f64 = 1000.0;

fn period() -> f64 {
    4.0 * L / (E / RHO).sqrt()
}

/// Columns of the history by name, every row (step 0, the initial state, included).
fn history(out: &RunOutcome) -> impl Fn(&str) -> Vec<f64> {
    let dir = std::path::PathBuf::from(&out.summary.output_dir);
    let text = std::fs::read_to_string(dir.join("history.csv")).unwrap();
    let rows: Vec<Vec<String>> = text
        .lines()
        .map(|l| l.split(',').map(|s| s.to_string()).collect())
        .collect();
    move |name: &str| {
        let i = rows[0]
            .iter()
            .position(|c| c == name)
            .unwrap_or_else(|| panic!("no column {name} in {:?}", rows[0]));
        rows[1..].iter().map(|r| r[i].parse().unwrap()).collect()
    }
}
use alfe::app::RunOutcome;

/// Times where the signal crosses zero downwards or upwards (linear interpolation),
/// skipping t = 0.
fn zero_crossings(t: &[f64], u: &[f64]) -> Vec<f64> {
    let mut z = Vec::new();
    for i in 1..t.len() {
        if t[i - 1] > 0.0 && u[i - 1] * u[i] < 0.0 {
            z.push(t[i - 1] - u[i - 1] * (t[i] - t[i - 1]) / (u[i] - u[i - 1]));
        }
    }
    z
}

fn bar(analysis: &str, end: f64, interval: f64) -> String {
    let text = builtin("bar-vibration");
    let a = text.find("[analysis]").unwrap();
    format!(
        "{}[analysis]\n{analysis}\nend_time = {end:e}\n\n[output]\ninterval = {interval:e}\ndisplacements = [\"tip\"]\n",
        &text[..a]
    )
}

#[test]
fn trapezoidal_rule_conserves_energy_over_100_periods() {
    // 20 steps per period (the trapezoidal rule conserves energy at any step size);
    // the factorization is reused (the Jacobian is constant) to keep this quick.
    let t = period();
    let deck = bar(
        &format!(
            "type = \"implicit\"\nscheme = \"newmark\"\nstep = {:e}",
            t / 20.0
        ),
        100.0 * t,
        50.0 * t,
    ) + "\n[solver.linear]\nlag = 100000\n";
    let out = run_deck("bar-energy", &deck);
    let h = history(&out);
    let (ke, wi, bal) = (
        h("kinetic_energy"),
        h("internal_energy"),
        h("energy_balance"),
    );
    assert!(out.summary.steps >= 2000);
    let e0 = ke[0];
    let worst = ke
        .iter()
        .zip(&wi)
        .map(|(k, w)| ((k + w) - e0).abs() / e0)
        .fold(0.0, f64::max);
    eprintln!("trapezoidal, 100 periods: max |KE + W_int − KE0|/KE0 = {worst:.3e}");
    assert!(worst < 1e-3, "energy drift {worst:e}");
    assert!(bal.iter().all(|&b| b < 1e-3));
    // Not vacuous: energy really moves between the two forms.
    let min_ke = ke.iter().cloned().fold(f64::INFINITY, f64::min);
    assert!(min_ke < 0.5 * e0, "the bar should store strain energy");
}

#[test]
fn bar_period_matches_4l_over_c() {
    // The built-in scene: ~40 steps per period, ~10 periods. Expected period error:
    // trapezoidal elongation (ωΔt)²/12 = 2.0e-3 at ωΔt = 2π·7.5e-6/3.09e-4, minus the
    // consistent-mass stiffening (kh)²/24 = 6.4e-5 of the first mode (kh = π/80):
    // about +0.19 %, within the 0.5 % bound.
    let out = run_deck("bar-period", &builtin("bar-vibration"));
    let h = history(&out);
    let (t, u) = (h("time"), h("tip.ux"));
    let z = zero_crossings(&t, &u);
    assert!(z.len() >= 18, "{} crossings", z.len());
    // Crossings every half period: fit the spacing from the first to the last.
    let measured = 2.0 * (z[z.len() - 1] - z[0]) / (z.len() - 1) as f64;
    let exact = period();
    let wdt = 2.0 * std::f64::consts::PI / exact * 7.5e-6;
    let predicted = exact * (1.0 + wdt * wdt / 12.0 - (std::f64::consts::PI / 80.0).powi(2) / 24.0);
    let err = measured / exact - 1.0;
    eprintln!(
        "period: measured {measured:.6e}, 4L/c {exact:.6e} (error {:.3} %), predicted {predicted:.6e} ({:.3} % off)",
        100.0 * err,
        100.0 * (measured / predicted - 1.0)
    );
    assert!(err.abs() < 5e-3, "period error {err:e}");
    // The first mode's prediction; the triangle wave's crossings also carry the higher
    // modes (each with its own elongation), measured 0.08 % from it.
    assert!((measured / predicted - 1.0).abs() < 1.5e-3);
    // Amplitude of the triangle wave: v₀ L / c (its corners are rounded by the
    // dispersion of the higher modes: measured 0.943 of it).
    let amp = u.iter().map(|x| x.abs()).fold(0.0, f64::max);
    let expect = V0 * L / (E / RHO).sqrt();
    assert!(rel_err(amp, expect) < 0.08, "amplitude {amp} vs {expect}");
}

/// Linear interpolation of (t, y) at s.
fn interp(t: &[f64], y: &[f64], s: f64) -> f64 {
    let i = t.partition_point(|&x| x < s).clamp(1, t.len() - 1);
    let w = (s - t[i - 1]) / (t[i] - t[i - 1]);
    y[i - 1] + w * (y[i] - y[i - 1])
}

#[test]
fn explicit_agrees_with_implicit_on_the_bar() {
    let t = period();
    let end = 2.0 * t;
    let ex = run_deck("bar-explicit", &bar("type = \"explicit\"", end, end));
    let im = run_deck(
        "bar-implicit-fine",
        &bar(
            &format!(
                "type = \"implicit\"\nscheme = \"newmark\"\nmass = \"lumped\"\nstep = {:e}",
                t / 400.0
            ),
            end,
            end,
        ),
    );
    let (he, hi) = (history(&ex), history(&im));
    let (te, ue) = (he("time"), he("tip.ux"));
    let (ti, ui) = (hi("time"), hi("tip.ux"));
    let mut num = 0.0;
    let mut den = 0.0;
    for (s, y) in te.iter().zip(&ue) {
        let z = interp(&ti, &ui, *s);
        num += (y - z).powi(2);
        den += z * z;
    }
    let rel = (num / den).sqrt();
    let steps = ex.summary.steps;
    let stable = ex.summary.stable_time_step.unwrap();
    eprintln!("explicit ({steps} steps, dt {:.4e} = 0.9 × {stable:.4e}) vs implicit lumped trapezoidal (T/400): relative L2 of the tip displacement {rel:.3e}", ex.summary.time_step);
    // The stable step of a ν = 0 cube of edge h is h/c (ω_max = 2c/h).
    let h = 10.0;
    assert!(rel_err(stable, h / (E / RHO).sqrt()) < 1e-6);
    assert!(rel < 0.03, "explicit vs implicit differ by {rel:e}");
    let bal = he("energy_balance");
    let worst = bal.iter().cloned().fold(0.0, f64::max);
    eprintln!("explicit energy balance error: max {worst:.3e}");
    assert!(worst < 1e-2);
}

#[test]
fn generalized_alpha_keeps_the_fundamental_and_dissipates_a_little() {
    // ρ∞ = 0.5 on the bar at 40 steps per period: the total energy only decreases,
    // and by far less than the high-mode share would allow to vanish at once.
    let t = period();
    let deck = bar(
        &format!(
            "type = \"implicit\"\nscheme = \"generalized-alpha\"\nrho_inf = 0.5\nstep = {:e}",
            t / 40.0
        ),
        5.0 * t,
        5.0 * t,
    );
    let out = run_deck("bar-galpha", &deck);
    let h = history(&out);
    let (ke, wi) = (h("kinetic_energy"), h("internal_energy"));
    let e: Vec<f64> = ke.iter().zip(&wi).map(|(k, w)| k + w).collect();
    let loss = 1.0 - e[e.len() - 1] / e[0];
    eprintln!(
        "generalized-α ρ∞ = 0.5, 5 periods: energy lost {:.3} %",
        100.0 * loss
    );
    assert!(loss > 0.0 && loss < 0.15, "loss {loss}");
    // The tip still swings with the fundamental's amplitude.
    let u = h("tip.ux");
    let amp = u.iter().rev().take(40).map(|x| x.abs()).fold(0.0, f64::max);
    let expect = V0 * L / (E / RHO).sqrt();
    assert!(amp > 0.8 * expect, "amplitude {amp} vs {expect}");
}

#[test]
fn velocity_and_acceleration_fields_are_written() {
    let t = period();
    let out = run_deck("bar-fields", &bar("type = \"explicit\"", 0.1 * t, 0.05 * t));
    assert_eq!(out.summary.analysis, "explicit");
    let dir = std::path::PathBuf::from(&out.summary.output_dir);
    let xmf = std::fs::read_to_string(dir.join("bar-vibration.xmf")).unwrap();
    assert!(xmf.contains("Name=\"velocity\"") && xmf.contains("Name=\"acceleration\""));
    // Initial state, one intermediate output and the last step.
    assert_eq!(xmf.matches("Name=\"velocity\"").count(), 3, "{xmf}");
}

#[test]
fn bad_dynamic_input_names_the_field() {
    let good = builtin("bar-vibration");
    let cases: Vec<(String, &str)> = vec![
        (
            edit(&good, "density = 7.85e-9", "density = 0.0"),
            "materials[0].density",
        ),
        (
            edit(&good, "scheme = \"newmark\"", "scheme = \"leapfrog\""),
            "analysis.scheme",
        ),
        (
            edit(
                &good,
                "scheme = \"newmark\"",
                "scheme = \"generalized-alpha\"\nrho_inf = 1.5",
            ),
            "analysis.rho_inf",
        ),
        (
            edit(&good, "mass = \"consistent\"", "mass = \"diagonal\""),
            "analysis.mass",
        ),
        (edit(&good, "step = 7.5e-6\n", ""), "analysis.step"),
        (
            edit(&good, "interval = 3.0e-5", "interval = -1.0"),
            "output.interval",
        ),
        (
            edit(&good, "part = \"bar\"", "part = \"rod\""),
            "initial_velocity[0].part",
        ),
        (
            edit(&good, "part = \"bar\"", "part = \"bar\"\nset = \"tip\""),
            "initial_velocity[0]",
        ),
        (
            edit(
                &good,
                "velocity = [1000.0, 0.0, 0.0]",
                "velocity = [1000.0, 0.0]",
            ),
            "initial_velocity[0].velocity",
        ),
        (
            edit(
                &good,
                "displacements = [\"tip\"]",
                "displacements = [\"nose\"]",
            ),
            "output.displacements[0]",
        ),
        (
            edit(
                &good,
                "type = \"implicit\"\nscheme = \"newmark\"\nmass = \"consistent\"",
                "type = \"explicit\"\ndt_factor = 1.5",
            ),
            "analysis.dt_factor",
        ),
        (
            edit(&good, "type = \"implicit\"", "type = \"explicit\""),
            "analysis.scheme",
        ),
        (
            edit(&good, "type = \"implicit\"", "type = \"quasi-static\""),
            "analysis.type",
        ),
        // A fixed explicit step above the stable one (h/c = 1.93e-6) is refused.
        (
            edit(
                &edit(
                    &good,
                    "type = \"implicit\"\nscheme = \"newmark\"\nmass = \"consistent\"",
                    "type = \"explicit\"",
                ),
                "step = 7.5e-6",
                "step = 2.0e-6",
            ),
            "analysis.step: 2.000000e-6 is above the stable time step",
        ),
    ];
    for (i, (deck, field)) in cases.iter().enumerate() {
        let e = match try_run_deck(&format!("bad-dyn-{i}"), deck) {
            Ok(_) => panic!("case {i} ({field}) ran"),
            Err(e) => e,
        };
        assert_eq!(e.kind, ErrorKind::Input, "case {i}: {}", e.message);
        assert!(
            e.message.contains(field),
            "case {i}: expected `{field}` in: {}",
            e.message
        );
    }
    // A fixed explicit step below the stable one runs.
    let ok_deck = edit(
        &edit(
            &good,
            "type = \"implicit\"\nscheme = \"newmark\"\nmass = \"consistent\"",
            "type = \"explicit\"",
        ),
        "end_time = 3.0e-3\nstep = 7.5e-6",
        "end_time = 2.0e-5\nstep = 1.0e-6",
    );
    let out = run_deck("dyn-fixed-step", &ok_deck);
    assert_eq!(out.summary.steps, 20);
}

/// A copper bar (J2, F-bar) hitting a frictionless support at 227 m/s, coarse quarter
/// model: the impact squashes the foot elements, so the explicit step must shrink as
/// they do. With a step fixed at the start the run is refused cleanly once the deformed
/// mesh needs less, instead of blowing up (a Taylor-like bar did, energy error 140 %).
fn impact_deck(analysis: &str) -> String {
    format!(
        r#"[scene]
name = "impact"
units = "mm-t-s"
[[materials]]
name = "copper"
model = "j2"
E = 117000.0
nu = 0.35
yield_stress = 400.0
hardening = {{ type = "linear", modulus = 100.0 }}
density = 8.93e-9
[[parts]]
name = "bar"
material = "copper"
mesh = {{ kind = "box", size = [3.2, 3.2, 32.4], cells = [2, 2, 16] }}
[[node_sets]]
name = "foot"
group = "zmin"
[[node_sets]]
name = "sx"
group = "xmin"
[[node_sets]]
name = "sy"
group = "ymin"
[[boundary]]
type = "fixed"
set = "foot"
components = ["z"]
[[boundary]]
type = "fixed"
set = "sx"
components = ["x"]
[[boundary]]
type = "fixed"
set = "sy"
components = ["y"]
[[initial_velocity]]
part = "bar"
velocity = [0.0, 0.0, -227000.0]
[analysis]
{analysis}
end_time = 8.0e-5
[output]
interval = 1.0e-5
"#
    )
}

#[test]
fn explicit_impact_shrinks_its_step_with_the_squashed_elements() {
    let out = run_deck("impact-explicit", &impact_deck("type = \"explicit\""));
    assert!(out.summary.converged);
    let h = history(&out);
    let (t, bal) = (h("time"), h("energy_balance"));
    let first = t[1] - t[0];
    let last = t[t.len() - 2] - t[t.len() - 3];
    assert!(
        last < 0.2 * first,
        "step {first:e} → {last:e}: it must shrink"
    );
    let worst = bal.iter().cloned().fold(0.0, f64::max);
    assert!(worst < 1e-2, "energy balance error {worst}");
    // The bar is shortened by about a third (L/L0 ≈ 0.66 on this coarse mesh).
    let top = out
        .displacement_by_node()
        .iter()
        .filter(|(_, x, _)| (x[2] - 32.4).abs() < 1e-9)
        .map(|(_, _, u)| u[2])
        .sum::<f64>()
        / 9.0;
    let ratio = (32.4 + top) / 32.4;
    assert!((0.6..0.72).contains(&ratio), "L/L0 = {ratio}");
    // The same run with the first step fixed: ends cleanly, naming the cause.
    let fixed = impact_deck(&format!("type = \"explicit\"\nstep = {first:e}"));
    let e = try_run_deck("impact-fixed", &fixed)
        .err()
        .expect("must stop");
    assert_eq!(e.kind, ErrorKind::Convergence, "{e}");
    assert!(
        e.message.contains("above the stable step") && e.message.contains("of the deformed mesh"),
        "{e}"
    );
}
