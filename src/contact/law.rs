//! The pointwise augmented-Lagrangian contact law of one tracked node in the local frame
//! [n, t1, t2] of the surface point it projects to: the residual of the paper (§2.1,
//! docs/src/design.md "Contact: the formulation"); the penalty law is [`super::penalty`]. Gaps
//! and multipliers are lengths; the caller scales by κ. Derivatives are the generalized
//! (semi-smooth) Jacobian used by Newton and by the preconditioners.

// Index loops over 3×3 frames read like the formulas.
#![allow(clippy::needless_range_loop)]

/// The tangential branch of the friction law.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Tangential {
    /// No friction threshold (open node or μ = 0): h_T = λ_T drives λ_T to zero.
    #[default]
    Free,
    /// Inside the cone: no slip over the step.
    Stick,
    /// On the cone: λ_T opposes the slip with magnitude s.
    Slip,
}

/// Which branch of the semi-smooth law a node is on: the normal min() and the
/// tangential case. JFNK's difference products evaluate the law on the branch of the
/// base point (MOOSE does not change contact state in its FD residuals), so J·v does
/// not straddle a kink.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Branch {
    /// The normal branch of min(g_N, λ_N) is the gap (ties count as active).
    pub active: bool,
    pub tangential: Tangential,
}

/// Where the friction threshold s comes from.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum Threshold {
    /// s = μ max(λ_N − g_N, 0): the augmented normal multiplier (Alart–Curnier, GetFEM's
    /// variant). It is μ λ_N at a solution and does not vanish mid-iteration where λ_N
    /// is still negative on a penetrating node; measured slower than the paper's on
    /// clip-tensile (README "Friction law options").
    Augmented,
    /// s = μ max(λ_N, 0): the paper's §2.1.
    #[default]
    Multiplier,
}

/// α when the deck gives none (see the closing measurements of issue 11 in the README's
/// contact section).
pub const DEFAULT_TANGENTIAL_AUGMENTATION: f64 = 1.0;

/// The parameters of the pointwise ALM law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AlmLaw {
    /// Coulomb coefficient μ.
    pub mu: f64,
    /// Tangential augmentation α: the stick stiffness is α κ and the trial tangential
    /// multiplier q = λ_T − α g_T. The solutions (h = 0) do not depend on α; the
    /// iteration does (a stiff stick spring flips nodes across the cone).
    pub alpha: f64,
    pub threshold: Threshold,
}

/// How the stick/slip case is chosen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Decision {
    /// By the law: stick iff ‖q‖ ≤ s.
    Natural,
    /// A node that flipped too often this step: stick while ‖q‖ ≤ (1 + margin) s,
    /// released to slip when its force leaves the cone clearly (MOOSE's stick lock,
    /// Kratos' hysteresis). The converged λ_T may exceed the cone by the margin.
    Locked { margin: f64 },
    /// The branch is given (JFNK's frozen products); the formulas of that branch are
    /// evaluated whatever the state.
    Forced(Branch),
}

/// h(g, λ) of one node with its generalized derivatives. g = (g_N, g_T1, g_T2): the
/// normal gap and the tangential slip over the step; λ = (λ_N, λ_T1, λ_T2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AlmPoint {
    pub h: [f64; 3],
    /// ∂h/∂g, row i = component of h.
    pub dh_dg: [[f64; 3]; 3],
    /// ∂h/∂λ.
    pub dh_dl: [[f64; 3]; 3],
    pub branch: Branch,
    /// The normal branch is the gap (ties count as active).
    pub active: bool,
    /// Active and inside the Coulomb cone.
    pub sticking: bool,
    /// ‖q‖ / s − 1 where s > 0: how far the trial force lies outside the cone (< 0
    /// inside).
    pub cone_excess: f64,
}

/// The paper's law (§2.1) with s = μ max(λ_N, 0) and α = 1.
pub fn alm(g: [f64; 3], lam: [f64; 3], mu: f64) -> AlmPoint {
    let law = AlmLaw {
        mu,
        alpha: 1.0,
        threshold: Threshold::Multiplier,
    };
    alm_law(g, lam, &law, Decision::Natural)
}

/// h_N = min(g_N, λ_N);  h_T = λ_T − γ (λ_T − α g_T) with q = λ_T − α g_T,
/// γ = min(1, s/‖q‖) and s the threshold ([`Threshold`]); stick (γ = 1) is h_T = α g_T.
/// At h = 0: g_N ≥ 0, λ_N ≥ 0, g_N λ_N = 0, and λ_T in the cone of radius μ λ_N,
/// opposing the slip.
pub fn alm_law(g: [f64; 3], lam: [f64; 3], law: &AlmLaw, decision: Decision) -> AlmPoint {
    let mut p = AlmPoint {
        h: [0.0; 3],
        dh_dg: [[0.0; 3]; 3],
        dh_dl: [[0.0; 3]; 3],
        branch: Branch::default(),
        active: false,
        sticking: false,
        cone_excess: f64::NEG_INFINITY,
    };
    let active = match decision {
        Decision::Forced(b) => b.active,
        _ => g[0] <= lam[0],
    };
    if active {
        p.h[0] = g[0];
        p.dh_dg[0][0] = 1.0;
    } else {
        p.h[0] = lam[0];
        p.dh_dl[0][0] = 1.0;
    }
    // s and its derivatives (∂s/∂g_N, ∂s/∂λ_N).
    let (mu, alpha) = (law.mu, law.alpha);
    let (s_arg, ds_dg) = match law.threshold {
        Threshold::Augmented => (lam[0] - g[0], -mu),
        Threshold::Multiplier => (lam[0], 0.0),
    };
    let (s, ds_dg, ds_dl) = if s_arg > 0.0 {
        (mu * s_arg, ds_dg, mu)
    } else {
        (0.0, 0.0, 0.0)
    };
    let q = [lam[1] - alpha * g[1], lam[2] - alpha * g[2]];
    let qn = (q[0] * q[0] + q[1] * q[1]).sqrt();
    if s > 0.0 {
        p.cone_excess = qn / s - 1.0;
    }
    let tangential = match decision {
        Decision::Forced(b) => b.tangential,
        _ if s <= 0.0 => Tangential::Free,
        Decision::Locked { margin } if qn <= (1.0 + margin) * s => Tangential::Stick,
        _ if qn <= s => Tangential::Stick,
        _ => Tangential::Slip,
    };
    // A forced slip without a direction degenerates to the free branch.
    let tangential = if tangential == Tangential::Slip && qn == 0.0 {
        Tangential::Free
    } else {
        tangential
    };
    match tangential {
        Tangential::Free => {
            p.h[1] = lam[1];
            p.h[2] = lam[2];
            p.dh_dl[1][1] = 1.0;
            p.dh_dl[2][2] = 1.0;
        }
        Tangential::Stick => {
            p.h[1] = alpha * g[1];
            p.h[2] = alpha * g[2];
            p.dh_dg[1][1] = alpha;
            p.dh_dg[2][2] = alpha;
        }
        Tangential::Slip => {
            // h_T = λ_T − s q̂; d(s q̂)/dq = (s/‖q‖)(I − q̂ q̂ᵀ), dq/dλ_T = I,
            // dq/dg_T = −α I; and q̂ ds/d(g_N, λ_N).
            let gam = s / qn;
            let qh = [q[0] / qn, q[1] / qn];
            for i in 0..2 {
                p.h[1 + i] = lam[1 + i] - gam * q[i];
                for j in 0..2 {
                    let d = gam * (if i == j { 1.0 } else { 0.0 } - qh[i] * qh[j]);
                    p.dh_dl[1 + i][1 + j] = if i == j { 1.0 } else { 0.0 } - d;
                    p.dh_dg[1 + i][1 + j] = alpha * d;
                }
                p.dh_dl[1 + i][0] = -ds_dl * qh[i];
                p.dh_dg[1 + i][0] = -ds_dg * qh[i];
            }
        }
    }
    p.branch = Branch { active, tangential };
    p.active = active;
    p.sticking = active && tangential == Tangential::Stick;
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fd_check(g: [f64; 3], l: [f64; 3], law: &AlmLaw) {
        let f = |g, l| alm_law(g, l, law, Decision::Natural);
        let p = f(g, l);
        let e = 1e-7;
        for j in 0..3 {
            let (mut gp, mut gm) = (g, g);
            gp[j] += e;
            gm[j] -= e;
            let (hp, hm) = (f(gp, l).h, f(gm, l).h);
            let (mut lp, mut lm) = (l, l);
            lp[j] += e;
            lm[j] -= e;
            let (kp, km) = (f(g, lp).h, f(g, lm).h);
            for i in 0..3 {
                let d = (hp[i] - hm[i]) / (2.0 * e);
                assert!(
                    (d - p.dh_dg[i][j]).abs() < 1e-6,
                    "dh{i}/dg{j} {d} vs {:?} ({law:?})",
                    p
                );
                let d = (kp[i] - km[i]) / (2.0 * e);
                assert!(
                    (d - p.dh_dl[i][j]).abs() < 1e-6,
                    "dh{i}/dl{j} {d} vs {:?} ({law:?})",
                    p
                );
            }
        }
        // The branch's own formulas, forced, give the same point.
        let forced = alm_law(g, l, law, Decision::Forced(p.branch));
        assert_eq!(forced.h, p.h);
        assert_eq!(forced.dh_dg, p.dh_dg);
    }

    #[test]
    fn alm_derivatives_match_differences_on_every_branch() {
        for threshold in [Threshold::Multiplier, Threshold::Augmented] {
            for alpha in [1.0, 0.1] {
                let law = |mu| AlmLaw {
                    mu,
                    alpha,
                    threshold,
                };
                let cases = [
                    // open, no pressure
                    ([0.3, 0.01, -0.02], [-0.05, 0.0, 0.0], 0.3, Tangential::Free),
                    // stick
                    (
                        [-0.01, 0.001, 0.002],
                        [0.5, 0.01, 0.02],
                        0.3,
                        Tangential::Stick,
                    ),
                    // slip
                    ([-0.01, 4.0, -2.0], [0.5, 0.01, 0.02], 0.3, Tangential::Slip),
                    // frictionless active
                    ([-0.01, 0.4, -0.2], [0.5, 0.01, 0.02], 0.0, Tangential::Free),
                ];
                for (g, l, mu, want) in cases {
                    assert_eq!(
                        alm_law(g, l, &law(mu), Decision::Natural).branch.tangential,
                        want
                    );
                    fd_check(g, l, &law(mu));
                }
                // Mid-iteration: a penetrating node whose λ_N is still negative. The
                // paper's threshold gives it no friction; the augmented one does, since
                // λ_N − g_N > 0 (the node is pushed out).
                let (g, l) = ([-0.2, 2.0, 0.0], [-0.1, 0.01, 0.0]);
                let p = alm_law(g, l, &law(0.3), Decision::Natural);
                let want = match threshold {
                    Threshold::Multiplier => Tangential::Free,
                    Threshold::Augmented => Tangential::Slip,
                };
                assert_eq!(p.branch.tangential, want, "{threshold:?} α = {alpha}");
                fd_check(g, l, &law(0.3));
            }
        }
    }

    #[test]
    fn forced_branches_are_linear_across_kinks() {
        // A node just inside the cone, evaluated with its branch frozen, stays on the
        // stick formulas when pushed outside: h is linear in g_T.
        let law = AlmLaw {
            mu: 0.5,
            alpha: 0.1,
            threshold: Threshold::Augmented,
        };
        let (g, l) = ([0.0, 0.0, 0.0], [1.0, 0.49, 0.0]);
        let base = alm_law(g, l, &law, Decision::Natural);
        assert_eq!(base.branch.tangential, Tangential::Stick);
        let out = [0.0, -0.5, 0.0];
        assert_eq!(
            alm_law(out, l, &law, Decision::Natural).branch.tangential,
            Tangential::Slip
        );
        let frozen = alm_law(out, l, &law, Decision::Forced(base.branch));
        assert!((frozen.h[1] - 0.1 * -0.5).abs() < 1e-15);
        // A locked node stays in stick within the margin, slips beyond it.
        let edge = [0.0, -0.101, 0.0]; // ‖q‖ = 0.4999 + 0.0101 ≈ 1.02 s
        assert_eq!(
            alm_law(edge, l, &law, Decision::Natural).branch.tangential,
            Tangential::Slip
        );
        let locked = Decision::Locked { margin: 0.05 };
        assert_eq!(
            alm_law(edge, l, &law, locked).branch.tangential,
            Tangential::Stick
        );
        assert_eq!(
            alm_law(out, l, &law, locked).branch.tangential,
            Tangential::Slip
        );
    }

    #[test]
    fn both_thresholds_and_any_alpha_share_the_solutions() {
        for threshold in [Threshold::Multiplier, Threshold::Augmented] {
            for alpha in [1.0, 0.05] {
                let law = AlmLaw {
                    mu: 0.5,
                    alpha,
                    threshold,
                };
                let f = |g, l| alm_law(g, l, &law, Decision::Natural).h;
                assert_eq!(f([0.2, 0.3, 0.0], [0.0; 3]), [0.0; 3]);
                assert_eq!(f([0.0, 0.0, 0.0], [2.0, 0.3, -0.4]), [0.0; 3]);
                let h = f([0.0, 0.1, 0.0], [2.0, -1.0, 0.0]);
                assert!(h.iter().all(|h| h.abs() < 1e-15), "{h:?}");
                // λ_T along the slip is not a solution.
                assert!(f([0.0, 0.1, 0.0], [2.0, 1.0, 0.0])[1].abs() > 1e-3);
            }
        }
    }

    #[test]
    fn alm_solutions_are_the_contact_conditions() {
        // Open gap, no pressure: h = 0.
        assert_eq!(alm([0.2, 0.3, 0.0], [0.0; 3], 0.5).h, [0.0; 3]);
        // Closed gap, pressure, no slip, tangential multiplier inside the cone: h = 0.
        let p = alm([0.0, 0.0, 0.0], [2.0, 0.3, -0.4], 0.5);
        assert_eq!(p.h, [0.0; 3]);
        assert!(p.active && p.sticking);
        // Slip of 0.1 along +t1 with λ_T = −μλ_N t1 (opposing): h = 0.
        let p = alm([0.0, 0.1, 0.0], [2.0, -1.0, 0.0], 0.5);
        assert!(p.h.iter().all(|h| h.abs() < 1e-15), "{:?}", p.h);
        assert!(p.active && !p.sticking);
        // λ_T pointing along the slip is not a solution.
        assert!(alm([0.0, 0.1, 0.0], [2.0, 1.0, 0.0], 0.5).h[1].abs() > 0.05);
        // A penetrating node is not a solution whatever λ_N.
        assert!(alm([-0.1, 0.0, 0.0], [3.0, 0.0, 0.0], 0.0).h[0] < 0.0);
    }
}
