//! Pointwise contact laws of one tracked node in the local frame [n, t1, t2] of the
//! surface point it projects to: the augmented-Lagrangian residual of the paper (§2.1,
//! DESIGN.md "Contact: the formulation") and the penalty baseline. Gaps and multipliers
//! are lengths; the caller scales by κ. Derivatives are the generalized (semi-smooth)
//! Jacobian used by Newton and by the preconditioners.

// Index loops over 3×3 frames read like the formulas.
#![allow(clippy::needless_range_loop)]

/// h(g, λ) of one node with its generalized derivatives. g = (g_N, g_T1, g_T2): the
/// normal gap and the tangential slip over the step; λ = (λ_N, λ_T1, λ_T2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AlmPoint {
    pub h: [f64; 3],
    /// ∂h/∂g, row i = component of h.
    pub dh_dg: [[f64; 3]; 3],
    /// ∂h/∂λ.
    pub dh_dl: [[f64; 3]; 3],
    /// The normal branch of min(g_N, λ_N) is the gap (ties count as active).
    pub active: bool,
    /// Active and inside the Coulomb cone (γ = 1).
    pub sticking: bool,
}

/// h_N = min(g_N, λ_N);  h_T = λ_T − γ (λ_T − g_T),  γ = s / max(s, ‖λ_T − g_T‖),
/// s = μ max(λ_N, 0) (paper §2.1; λ_N < 0 only happens mid-iteration and carries no
/// friction). At h = 0: g_N ≥ 0, λ_N ≥ 0, g_N λ_N = 0, and λ_T in the cone of radius
/// μ λ_N, opposing the slip.
pub fn alm(g: [f64; 3], lam: [f64; 3], mu: f64) -> AlmPoint {
    let mut p = AlmPoint {
        h: [0.0; 3],
        dh_dg: [[0.0; 3]; 3],
        dh_dl: [[0.0; 3]; 3],
        active: false,
        sticking: false,
    };
    if g[0] <= lam[0] {
        p.h[0] = g[0];
        p.dh_dg[0][0] = 1.0;
        p.active = true;
    } else {
        p.h[0] = lam[0];
        p.dh_dl[0][0] = 1.0;
    }
    let s = mu * lam[0].max(0.0);
    let q = [lam[1] - g[1], lam[2] - g[2]];
    let qn = (q[0] * q[0] + q[1] * q[1]).sqrt();
    if s <= 0.0 {
        // γ = 0: no friction, h_T = λ_T drives λ_T to zero.
        p.h[1] = lam[1];
        p.h[2] = lam[2];
        p.dh_dl[1][1] = 1.0;
        p.dh_dl[2][2] = 1.0;
    } else if qn <= s {
        // γ = 1: stick, h_T = g_T (no slip over the step).
        p.h[1] = g[1];
        p.h[2] = g[2];
        p.dh_dg[1][1] = 1.0;
        p.dh_dg[2][2] = 1.0;
        p.sticking = p.active;
    } else {
        // Slip: h_T = λ_T − s q/‖q‖; d(s q/‖q‖)/dq = (s/‖q‖)(I − q̂ q̂ᵀ).
        let gam = s / qn;
        let qh = [q[0] / qn, q[1] / qn];
        for i in 0..2 {
            p.h[1 + i] = lam[1 + i] - gam * q[i];
            for j in 0..2 {
                let d = gam * (if i == j { 1.0 } else { 0.0 } - qh[i] * qh[j]);
                p.dh_dl[1 + i][1 + j] = if i == j { 1.0 } else { 0.0 } - d;
                p.dh_dg[1 + i][1 + j] = d;
            }
            if lam[0] > 0.0 {
                p.dh_dl[1 + i][0] = -mu * qh[i];
            }
        }
    }
    p
}

/// Penalty force of one node in the local frame with its derivative.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PenaltyPoint {
    /// (f_N ≥ 0 along the outward normal, f_T1, f_T2): the force on the node.
    pub f: [f64; 3],
    /// ∂f/∂g.
    pub df_dg: [[f64; 3]; 3],
    pub active: bool,
    pub sticking: bool,
}

/// f_N = k_N max(−g_N, 0) (active for g_N ≤ 0); tangentially an elastic stick spring k_T on the slip over the
/// step added to the force carried from the last step, returned onto the Coulomb cone
/// ‖f_T‖ ≤ μ f_N (regularized Coulomb, Wriggers, Computational Contact Mechanics §5.2).
pub fn penalty(g: [f64; 3], ft_old: [f64; 2], kn: f64, kt: f64, mu: f64) -> PenaltyPoint {
    let mut p = PenaltyPoint {
        f: [0.0; 3],
        df_dg: [[0.0; 3]; 3],
        active: false,
        sticking: false,
    };
    // A node exactly on the wall is active (with zero force): its stiffness k_N holds a
    // body that rests on the wall before any penetration (as ALM's tie rule does).
    if g[0] > 0.0 {
        return p;
    }
    p.active = true;
    let fnrm = -kn * g[0];
    p.f[0] = fnrm;
    p.df_dg[0][0] = -kn;
    let cap = mu * fnrm;
    if cap <= 0.0 {
        return p;
    }
    let tr = [ft_old[0] - kt * g[1], ft_old[1] - kt * g[2]];
    let tn = (tr[0] * tr[0] + tr[1] * tr[1]).sqrt();
    if tn <= cap {
        p.f[1] = tr[0];
        p.f[2] = tr[1];
        p.df_dg[1][1] = -kt;
        p.df_dg[2][2] = -kt;
        p.sticking = true;
    } else {
        let th = [tr[0] / tn, tr[1] / tn];
        for i in 0..2 {
            p.f[1 + i] = cap * th[i];
            // d(cap t̂)/dg_T = (cap/‖tr‖)(I − t̂ t̂ᵀ)(−k_T); d/dg_N = μ (−k_N) t̂.
            for j in 0..2 {
                let proj = if i == j { 1.0 } else { 0.0 } - th[i] * th[j];
                p.df_dg[1 + i][1 + j] = -kt * cap / tn * proj;
            }
            p.df_dg[1 + i][0] = -mu * kn * th[i];
        }
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fd_check_alm(g: [f64; 3], l: [f64; 3], mu: f64) {
        let p = alm(g, l, mu);
        let e = 1e-7;
        for j in 0..3 {
            let (mut gp, mut gm) = (g, g);
            gp[j] += e;
            gm[j] -= e;
            let (hp, hm) = (alm(gp, l, mu).h, alm(gm, l, mu).h);
            let (mut lp, mut lm) = (l, l);
            lp[j] += e;
            lm[j] -= e;
            let (kp, km) = (alm(g, lp, mu).h, alm(g, lm, mu).h);
            for i in 0..3 {
                let d = (hp[i] - hm[i]) / (2.0 * e);
                assert!(
                    (d - p.dh_dg[i][j]).abs() < 1e-6,
                    "dh{i}/dg{j} {d} vs {:?}",
                    p
                );
                let d = (kp[i] - km[i]) / (2.0 * e);
                assert!(
                    (d - p.dh_dl[i][j]).abs() < 1e-6,
                    "dh{i}/dl{j} {d} vs {:?}",
                    p
                );
            }
        }
    }

    #[test]
    fn alm_derivatives_match_differences_on_every_branch() {
        // open, stick, slip, frictionless active
        fd_check_alm([0.3, 0.01, -0.02], [0.1, 0.0, 0.0], 0.3);
        fd_check_alm([-0.01, 0.001, 0.002], [0.5, 0.01, 0.02], 0.3);
        fd_check_alm([-0.01, 0.4, -0.2], [0.5, 0.01, 0.02], 0.3);
        fd_check_alm([-0.01, 0.4, -0.2], [0.5, 0.01, 0.02], 0.0);
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

    #[test]
    fn penalty_force_and_derivatives() {
        let (kn, kt, mu) = (100.0, 50.0, 0.3);
        assert!(!penalty([0.1, 0.0, 0.0], [0.0; 2], kn, kt, mu).active);
        let st = penalty([-0.01, 0.001, 0.0], [0.0; 2], kn, kt, mu);
        assert!((st.f[0] - 1.0).abs() < 1e-12 && st.sticking);
        assert!((st.f[1] + 0.05).abs() < 1e-12);
        let sl = penalty([-0.01, 0.1, 0.0], [0.0; 2], kn, kt, mu);
        assert!(!sl.sticking && (sl.f[1] + 0.3).abs() < 1e-12);
        for (g, fo) in [
            ([-0.01, 0.001, -0.002], [0.05, 0.0]),
            ([-0.01, 0.1, -0.05], [0.01, 0.02]),
        ] {
            let p = penalty(g, fo, kn, kt, mu);
            for j in 0..3 {
                let e = 1e-8;
                let (mut gp, mut gm) = (g, g);
                gp[j] += e;
                gm[j] -= e;
                let (fp, fm) = (penalty(gp, fo, kn, kt, mu).f, penalty(gm, fo, kn, kt, mu).f);
                for i in 0..3 {
                    let d = (fp[i] - fm[i]) / (2.0 * e);
                    assert!((d - p.df_dg[i][j]).abs() < 1e-5 * kn, "{i}{j}: {d} {:?}", p);
                }
            }
        }
    }
}
