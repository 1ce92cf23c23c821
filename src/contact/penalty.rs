//! The penalty contact law of one tracked node in the local frame [n, t1, t2] of the
//! surface point it projects to: a normal spring on the penetration and, tangentially,
//! the elastic-slip (regularized Coulomb) law that Abaqus/Standard uses by default for
//! penalty friction (Abaqus Analysis User's Guide, "Frictional behavior": the stiffness
//! method with an allowable elastic slip, the slip tolerance F_f = 0.005 of the
//! characteristic contact surface length; Wriggers, Computational Contact Mechanics,
//! §5.2, regularized Coulomb friction with a return map onto the cone).
//!
//! A node in contact sticks until its **elastic slip** e (the reversible part of its
//! slip, a length carried from step to step) reaches the allowable slip δ: the stick
//! stiffness is k_T = μ f_N / δ, so the tangential force reaches the Coulomb limit μ f_N
//! exactly at ‖e‖ = δ whatever the normal penalty stiffness. (A stick spring tied to
//! k_N, as before, grows with the penalty scale, and stiff sticking nodes flipped across
//! the cone from one Newton iterate to the next.) Beyond δ the node slips with
//! ‖f_T‖ = μ f_N and its elastic slip stays at δ along the trial direction.

// Index loops over 3×3 frames read like the formulas.
#![allow(clippy::needless_range_loop)]

use super::law::{Branch, Decision, Tangential};

/// F_f: the allowable elastic slip as a fraction of the mean size of the contact faces
/// (Abaqus/Standard's default slip tolerance).
pub const SLIP_TOLERANCE: f64 = 0.005;

/// The parameters of the penalty law at one node.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PenaltyLaw {
    /// Normal stiffness k_N (force per length).
    pub kn: f64,
    /// Coulomb coefficient μ.
    pub mu: f64,
    /// Allowable elastic slip δ (a length, > 0): [`SLIP_TOLERANCE`] × the faces' size.
    pub slip: f64,
    /// Factor on the stick stiffness μ f_N / δ: 1, lowered for a node that cycled
    /// between stick and slip in a failed attempt (its allowable slip grows by 1/factor).
    pub stick_scale: f64,
}

impl PenaltyLaw {
    /// The elastic slip at which the node starts to slip: δ / stick_scale.
    pub fn slip_limit(&self) -> f64 {
        self.slip / self.stick_scale
    }
}

/// Penalty force of one node in the local frame with its derivative.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PenaltyPoint {
    /// (f_N ≥ 0 along the outward normal, f_T1, f_T2): the force on the node.
    pub f: [f64; 3],
    /// ∂f/∂g. The trial elastic slip is e_old + g_T, so ∂f/∂e_old is the tangential
    /// columns of ∂f/∂g.
    pub df_dg: [[f64; 3]; 3],
    /// The elastic slip (e_T1, e_T2) at this point: what a commit carries to the next
    /// step (zero where the node is open or carries no friction).
    pub elastic_slip: [f64; 2],
    pub active: bool,
    pub sticking: bool,
    /// The branch taken (what a frozen evaluation repeats).
    pub branch: Branch,
}

/// f_N = k_N max(−g_N, 0) (active for g_N ≤ 0); tangentially the trial elastic slip
/// e = e_old + g_T (g_T the slip over the step, e_old the elastic slip carried from the
/// last step, both in this frame) gives f_T = −k_T e with k_T = μ f_N / δ in stick
/// (‖e‖ ≤ δ), and f_T = −μ f_N ê with e_new = δ ê in slip (the return map of
/// Wriggers §5.2 on the elastic slip). δ here is [`PenaltyLaw::slip_limit`].
///
/// `decision` as for ALM ([`Decision`]): `Locked` sticks while ‖e‖ ≤ (1 + margin) δ (the
/// tangential force then exceeds μ f_N by at most the margin), `Forced` evaluates the
/// given branch's formulas whatever g is (JFNK's frozen products, linear in g within it).
pub fn penalty(g: [f64; 3], e_old: [f64; 2], law: &PenaltyLaw, decision: Decision) -> PenaltyPoint {
    let mut p = PenaltyPoint {
        f: [0.0; 3],
        df_dg: [[0.0; 3]; 3],
        elastic_slip: [0.0; 2],
        active: false,
        sticking: false,
        branch: Branch::default(),
    };
    // A node exactly on the wall is active (with zero force): its stiffness k_N holds a
    // body that rests on the wall before any penetration (as ALM's tie rule does).
    let active = match decision {
        Decision::Forced(b) => b.active,
        _ => g[0] <= 0.0,
    };
    if !active {
        return p;
    }
    p.active = true;
    p.branch.active = true;
    let kn = law.kn;
    let fnrm = -kn * g[0];
    p.f[0] = fnrm;
    p.df_dg[0][0] = -kn;
    let cap = law.mu * fnrm;
    let e = [e_old[0] + g[1], e_old[1] + g[2]];
    let en = e[0].hypot(e[1]);
    let limit = law.slip_limit();
    let tangential = match decision {
        Decision::Forced(b) => b.tangential,
        _ if law.mu <= 0.0 || cap <= 0.0 => Tangential::Free,
        Decision::Locked { margin } if en <= (1.0 + margin) * limit => Tangential::Stick,
        _ if en <= limit => Tangential::Stick,
        _ => Tangential::Slip,
    };
    match tangential {
        Tangential::Free => {}
        Tangential::Stick => stick(&mut p, e, cap / limit, law.mu * kn / limit),
        // A forced slip without a direction has no force along any.
        Tangential::Slip if en == 0.0 => {}
        Tangential::Slip => slip(&mut p, e, en, cap, law.mu * kn, limit),
    }
    p.branch.tangential = tangential;
    p
}

/// Stick: f_T = −k_T e with k_T = μ f_N / δ; ∂f_T/∂g_T = −k_T I and, through f_N,
/// ∂f_T/∂g_N = (μ k_N / δ) e (`dkt_dn`).
fn stick(p: &mut PenaltyPoint, e: [f64; 2], kt: f64, dkt_dn: f64) {
    for i in 0..2 {
        p.f[1 + i] = -kt * e[i];
        p.df_dg[1 + i][1 + i] = -kt;
        p.df_dg[1 + i][0] = dkt_dn * e[i];
    }
    p.elastic_slip = e;
    p.sticking = true;
}

/// Slip: f_T = −μ f_N ê, e_new = δ ê; ∂f_T/∂g_T = −(μ f_N / ‖e‖)(I − ê êᵀ) and
/// ∂f_T/∂g_N = μ k_N ê (`dcap_dn` = μ k_N).
fn slip(p: &mut PenaltyPoint, e: [f64; 2], en: f64, cap: f64, dcap_dn: f64, limit: f64) {
    let eh = [e[0] / en, e[1] / en];
    for i in 0..2 {
        p.f[1 + i] = -cap * eh[i];
        for j in 0..2 {
            let proj = if i == j { 1.0 } else { 0.0 } - eh[i] * eh[j];
            p.df_dg[1 + i][1 + j] = -cap / en * proj;
        }
        p.df_dg[1 + i][0] = dcap_dn * eh[i];
        p.elastic_slip[i] = limit * eh[i];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn law(stick_scale: f64) -> PenaltyLaw {
        PenaltyLaw {
            kn: 100.0,
            mu: 0.3,
            slip: 0.01,
            stick_scale,
        }
    }

    /// ∂f/∂g and ∂f/∂e_old against central differences.
    fn fd_check(g: [f64; 3], e_old: [f64; 2], law: &PenaltyLaw) {
        let p = penalty(g, e_old, law, Decision::Natural);
        let h = 1e-9;
        for j in 0..3 {
            let (mut gp, mut gm) = (g, g);
            gp[j] += h;
            gm[j] -= h;
            let (fp, fm) = (
                penalty(gp, e_old, law, Decision::Natural).f,
                penalty(gm, e_old, law, Decision::Natural).f,
            );
            for i in 0..3 {
                let d = (fp[i] - fm[i]) / (2.0 * h);
                assert!(
                    (d - p.df_dg[i][j]).abs() < 1e-6 * law.kn,
                    "∂f{i}/∂g{j}: {d} vs {p:?}"
                );
            }
        }
        for j in 0..2 {
            let (mut ep, mut em) = (e_old, e_old);
            ep[j] += h;
            em[j] -= h;
            let (fp, fm) = (
                penalty(g, ep, law, Decision::Natural).f,
                penalty(g, em, law, Decision::Natural).f,
            );
            for i in 0..3 {
                let d = (fp[i] - fm[i]) / (2.0 * h);
                assert!(
                    (d - p.df_dg[i][1 + j]).abs() < 1e-6 * law.kn,
                    "∂f{i}/∂e{j}: {d} vs {p:?}"
                );
            }
        }
    }

    #[test]
    fn penalty_derivatives_match_differences_in_stick_slip_and_open() {
        for scale in [1.0, 0.3] {
            let l = law(scale);
            // (g, e_old, sticking, active): the carried elastic slip is never zero.
            let cases = [
                ([-0.01, 0.001, -0.002], [0.003, -0.001], true, true),
                ([-0.01, 0.02, -0.05], [0.004, 0.002], false, true),
                ([-0.02, -0.001, 0.001], [-0.006, 0.003], true, true),
                ([0.01, 0.02, 0.0], [0.004, 0.002], false, false),
            ];
            for (g, e_old, sticking, active) in cases {
                let p = penalty(g, e_old, &l, Decision::Natural);
                assert_eq!((p.sticking, p.active), (sticking, active), "{g:?} {p:?}");
                fd_check(g, e_old, &l);
            }
            // Frictionless: no tangential force, no elastic slip.
            let p = penalty(
                [-0.01, 0.5, 0.0],
                [0.003, 0.0],
                &PenaltyLaw { mu: 0.0, ..l },
                Decision::Natural,
            );
            assert_eq!((p.f[1], p.f[2], p.elastic_slip), (0.0, 0.0, [0.0; 2]));
        }
    }

    /// The elastic slip a node carries from step to step: a node in stick builds up
    /// k_T e with k_T = μ f_N / δ and carries e; once e passes δ it slips at μ f_N with
    /// e = δ along the slip, and a reversal first unloads elastically.
    #[test]
    fn elastic_slip_is_carried_across_steps() {
        let l = law(1.0);
        let gn = -0.01; // f_N = 1, μ f_N = 0.3, k_T = 30
                        // Two steps of 0.004 each: e = 0.004 then 0.008 < δ = 0.01, still sticking.
        let s1 = penalty([gn, 0.004, 0.0], [0.0; 2], &l, Decision::Natural);
        assert!(s1.sticking);
        assert!((s1.f[1] + 30.0 * 0.004).abs() < 1e-12);
        let s2 = penalty([gn, 0.004, 0.0], s1.elastic_slip, &l, Decision::Natural);
        assert!(s2.sticking && (s2.elastic_slip[0] - 0.008).abs() < 1e-15);
        assert!((s2.f[1] + 30.0 * 0.008).abs() < 1e-12);
        // A third: e would be 0.012 > δ: slip at μ f_N, e = δ.
        let s3 = penalty([gn, 0.004, 0.0], s2.elastic_slip, &l, Decision::Natural);
        assert!(!s3.sticking && s3.active);
        assert!((s3.f[1] + 0.3).abs() < 1e-12 && s3.f[2] == 0.0);
        assert!((s3.elastic_slip[0] - 0.01).abs() < 1e-15);
        // Going on slipping keeps the force at the cone.
        let s4 = penalty([gn, 0.05, 0.0], s3.elastic_slip, &l, Decision::Natural);
        assert!((s4.f[1] + 0.3).abs() < 1e-12 && (s4.elastic_slip[0] - 0.01).abs() < 1e-15);
        // A reversal of 0.005 unloads elastically: e = 0.005, f_T = −30 · 0.005.
        let s5 = penalty([gn, -0.005, 0.0], s4.elastic_slip, &l, Decision::Natural);
        assert!(s5.sticking && (s5.f[1] + 0.15).abs() < 1e-12);
        // The stick force follows f_N at the same elastic slip (k_T ∝ f_N).
        let s6 = penalty([2.0 * gn, 0.0, 0.0], s5.elastic_slip, &l, Decision::Natural);
        assert!(s6.sticking && (s6.f[1] + 0.3).abs() < 1e-12);
        // Open: no force and nothing carried.
        let s7 = penalty([0.001, 0.0, 0.0], s6.elastic_slip, &l, Decision::Natural);
        assert!(!s7.active && s7.elastic_slip == [0.0; 2] && s7.f == [0.0; 3]);
        // A softened node (stick stiffness × 0.3) sticks up to δ / 0.3.
        let soft = penalty([gn, 0.02, 0.0], [0.0; 2], &law(0.3), Decision::Natural);
        assert!(soft.sticking && (soft.f[1] + 0.3 * 30.0 * 0.02).abs() < 1e-12);
    }

    /// A locked node sticks up to (1 + margin) δ and slips beyond; a forced branch is
    /// evaluated whatever the gap says, and its derivatives still match differences.
    #[test]
    fn locked_and_forced_decisions() {
        let l = law(1.0);
        let locked = Decision::Locked { margin: 0.05 };
        // δ = 0.01: 0.0104 slips naturally, sticks locked (force 4 % above μ f_N).
        let g = [-0.01, 0.0104, 0.0];
        let natural = penalty(g, [0.0; 2], &l, Decision::Natural);
        let lock = penalty(g, [0.0; 2], &l, locked);
        assert!(!natural.sticking && lock.sticking);
        assert!(
            (lock.f[1] / (l.mu * lock.f[0]) + 1.04).abs() < 1e-12,
            "{lock:?}"
        );
        assert!(!penalty([-0.01, 0.011, 0.0], [0.0; 2], &l, locked).sticking);
        // Forced: the branch of `natural` (slip) at a point that would stick, and the
        // active branch at an open gap (a tension spring), linear in g.
        let forced = Decision::Forced(natural.branch);
        let p = penalty([-0.01, 0.002, 0.0], [0.0; 2], &l, forced);
        assert!(p.active && !p.sticking && p.branch == natural.branch);
        assert!((p.f[1] + l.mu * p.f[0]).abs() < 1e-12);
        let open = penalty([0.001, 0.0, 0.0], [0.0; 2], &l, forced);
        assert!(open.active && (open.f[0] + l.kn * 0.001).abs() < 1e-12);
        let stick = Decision::Forced(penalty([-0.01, 0.002, 0.0], [0.0; 2], &l, locked).branch);
        let far = penalty([-0.01, 0.5, 0.0], [0.0; 2], &l, stick);
        assert!(far.sticking && (far.f[1] + l.mu * l.kn * 0.01 / 0.01 * 0.5).abs() < 1e-9);
    }
}
