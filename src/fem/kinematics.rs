//! The per-point pieces of the solid element kernels ([`super::solid`], [`super::eas`],
//! [`super::reduced`], [`super::hybrid`]): reference gradients, the deformation
//! gradient, the force and tangent accumulators, the kinematics of every point with F̄
//! under F-bar (de Souza Neto et al. 1996) and its extra tangent term. Total Lagrangian
//! in the spatial form of Bonet & Wood, *Nonlinear Continuum Mechanics for FEA*, §8–9.

use super::error::{At, ElementError};
use super::shape::Tabulated;
use crate::material::{Kinematics, StressPoint};
use nalgebra::Matrix3;

/// Cofactor matrix: A⁻ᵀ = cof(A) / det A without a failure branch.
#[inline]
pub(super) fn cofactor(m: &Matrix3<f64>) -> Matrix3<f64> {
    let c = |r0: usize, r1: usize, c0: usize, c1: usize| {
        m[(r0, c0)] * m[(r1, c1)] - m[(r0, c1)] * m[(r1, c0)]
    };
    Matrix3::new(
        c(1, 2, 1, 2),
        -c(1, 2, 0, 2),
        c(1, 2, 0, 1),
        -c(0, 2, 1, 2),
        c(0, 2, 0, 2),
        -c(0, 2, 0, 1),
        c(0, 1, 1, 2),
        -c(0, 1, 0, 2),
        c(0, 1, 0, 1),
    )
}

/// Reference gradients ∇_X N_a = J₀⁻ᵀ ∂N_a/∂ξ and det J₀ at one point, with
/// J₀ = Σ_a x0_a ⊗ ∂N_a/∂ξ. If det J₀ = 0 the gradients are not finite: check it first.
#[inline]
pub fn reference_gradients<const N: usize>(
    x0: &[[f64; 3]; N],
    dn: &[[f64; 3]; N],
) -> ([[f64; 3]; N], f64) {
    let mut j = Matrix3::zeros();
    for (x, d) in x0.iter().zip(dn) {
        for r in 0..3 {
            for c in 0..3 {
                j[(r, c)] += x[r] * d[c];
            }
        }
    }
    let det = j.determinant();
    (transform_gradients(&(cofactor(&j) / det), dn), det)
}

/// g_a ← M g_a for every node (M = J₀⁻ᵀ or F⁻ᵀ).
#[inline]
pub(super) fn transform_gradients<const N: usize>(
    m: &Matrix3<f64>,
    g: &[[f64; 3]; N],
) -> [[f64; 3]; N] {
    let mut out = [[0.0; 3]; N];
    for (o, d) in out.iter_mut().zip(g) {
        for r in 0..3 {
            o[r] = m[(r, 0)] * d[0] + m[(r, 1)] * d[1] + m[(r, 2)] * d[2];
        }
    }
    out
}

/// F = I + Σ_a u_a ⊗ ∇_X N_a.
#[inline]
pub fn deformation_gradient<const N: usize>(
    u: &[[f64; 3]; N],
    grad0: &[[f64; 3]; N],
) -> Matrix3<f64> {
    let mut f = Matrix3::identity();
    for (ua, g) in u.iter().zip(grad0) {
        for r in 0..3 {
            for c in 0..3 {
                f[(r, c)] += ua[r] * g[c];
            }
        }
    }
    f
}

/// f_a += w τ g_a (τ symmetric, Voigt).
#[inline]
pub(super) fn add_force<const N: usize>(g: &[[f64; 3]; N], s: &[f64; 6], w: f64, f: &mut [f64]) {
    for (fa, ga) in f.chunks_exact_mut(3).zip(g) {
        fa[0] += w * (s[0] * ga[0] + s[3] * ga[1] + s[5] * ga[2]);
        fa[1] += w * (s[3] * ga[0] + s[1] * ga[1] + s[4] * ga[2]);
        fa[2] += w * (s[5] * ga[0] + s[4] * ga[1] + s[2] * ga[2]);
    }
}

/// An element tangent on the stack, `[a][i][b][j]`: the same memory order as the
/// row-major 3n×3n output, filled without bounds checks and copied once.
pub(super) type LocalTangent<const N: usize> = [[[[f64; 3]; N]; 3]; N];

/// K_ab += w [B_aᵀ c B_b + (g_a · τ g_b) I] (geometric term only if `geometric`).
///
/// B_a rows (xx, yy, zz, xy, yz, xz) = [g1 0 0; 0 g2 0; 0 0 g3; g2 g1 0; 0 g3 g2; g3 0 g1].
#[inline]
#[allow(clippy::needless_range_loop)] // index form mirrors the B-matrix algebra
pub(super) fn add_tangent<const N: usize>(
    g: &[[f64; 3]; N],
    sp: &StressPoint,
    geometric: bool,
    w: f64,
    k: &mut LocalTangent<N>,
) {
    let c = &sp.tangent;
    let s = &sp.stress;
    // w c B_b for every b (6×3 each) and w τ g_b, so the pair loop has no extra scaling.
    let mut cb = [[[0.0; 3]; 6]; N];
    let mut tg = [[0.0; 3]; N];
    for b in 0..N {
        let [g0, g1, g2] = g[b].map(|v| w * v);
        for r in 0..6 {
            let cr = &c[r];
            cb[b][r] = [
                cr[0] * g0 + cr[3] * g1 + cr[5] * g2,
                cr[1] * g1 + cr[3] * g0 + cr[4] * g2,
                cr[2] * g2 + cr[4] * g1 + cr[5] * g0,
            ];
        }
        if geometric {
            tg[b] = [
                s[0] * g0 + s[3] * g1 + s[5] * g2,
                s[3] * g0 + s[1] * g1 + s[4] * g2,
                s[5] * g0 + s[4] * g1 + s[2] * g2,
            ];
        }
    }
    for a in 0..N {
        let [g0, g1, g2] = g[a];
        let ka = &mut k[a];
        for b in 0..N {
            let m = &cb[b];
            let geo = g0 * tg[b][0] + g1 * tg[b][1] + g2 * tg[b][2];
            for j in 0..3 {
                ka[0][b][j] += g0 * m[0][j] + g1 * m[3][j] + g2 * m[5][j];
                ka[1][b][j] += g1 * m[1][j] + g0 * m[3][j] + g2 * m[4][j];
                ka[2][b][j] += g2 * m[2][j] + g1 * m[4][j] + g0 * m[5][j];
            }
            for i in 0..3 {
                ka[i][b][i] += geo;
            }
        }
    }
}

/// Kinematics at one point.
pub(super) struct PointKinematics<const N: usize> {
    /// The F handed to the material (F̄ under F-bar).
    pub(super) f: Matrix3<f64>,
    /// Gradients the B matrix uses: ∇_x N (finite) or ∇_X N (small).
    pub(super) grad: [[f64; 3]; N],
    /// Reference volume weight w det J₀.
    pub(super) w: f64,
}

/// The kinematics of every point of one element, with F replaced by F̄ under F-bar.
/// Returns the points and, under F-bar, the volume-averaged gradients ḡ_a
/// (1/v ∫ ∇_x N_a dv, finite; 1/V ∫ ∇_X N_a dV, small) that the tangent's extra term
/// needs.
#[inline(always)]
#[allow(clippy::type_complexity)]
pub(super) fn element_kinematics<const N: usize, const G: usize>(
    tab: &Tabulated<3, N, G>,
    fbar: bool,
    kin: Kinematics,
    x0: &[[f64; 3]; N],
    u: &[[f64; 3]; N],
) -> Result<([PointKinematics<N>; G], Option<[[f64; 3]; N]>), ElementError> {
    let mut pts: [PointKinematics<N>; G] = std::array::from_fn(|_| PointKinematics {
        f: Matrix3::identity(),
        grad: [[0.0; 3]; N],
        w: 0.0,
    });
    // Volume measure per point: J (finite) or tr ε (small).
    let mut vol = [0.0; G];
    for (g, p) in pts.iter_mut().enumerate() {
        let (grad0, det0) = reference_point(x0, &tab.dn[g], g)?;
        p.w = tab.weights[g] * det0;
        p.f = deformation_gradient(u, &grad0);
        match kin {
            Kinematics::Small => {
                p.grad = grad0;
                vol[g] = p.f.trace() - 3.0;
            }
            Kinematics::Finite => {
                let j = p.f.determinant();
                if j.is_nan() || j <= 0.0 {
                    return Err(ElementError::Inverted {
                        at: At::Gauss(g),
                        det: j,
                    });
                }
                p.grad = transform_gradients(&(cofactor(&p.f) / j), &grad0);
                vol[g] = j;
            }
        }
    }
    if !fbar {
        return Ok((pts, None));
    }
    // ḡ weights: J w (finite: current volume), w (small: reference volume).
    let mut gbar = [[0.0; 3]; N];
    let (mut v, mut big_v, mut theta) = (0.0, 0.0, 0.0);
    for (p, &m) in pts.iter().zip(&vol) {
        let wt = match kin {
            Kinematics::Finite => m * p.w,
            Kinematics::Small => p.w,
        };
        v += wt;
        big_v += p.w;
        theta += m * p.w;
        for (gb, ga) in gbar.iter_mut().zip(&p.grad) {
            for c in 0..3 {
                gb[c] += wt * ga[c];
            }
        }
    }
    for gb in &mut gbar {
        for c in gb.iter_mut() {
            *c /= v;
        }
    }
    for (p, &m) in pts.iter_mut().zip(&vol) {
        match kin {
            // J̄ = v / V; F̄ = (J̄/J)^{1/3} F.
            Kinematics::Finite => p.f *= (v / big_v / m).cbrt(),
            // ε̄ = ε + (θ̄ − tr ε)/3 I.
            Kinematics::Small => {
                let d = (theta / big_v - m) / 3.0;
                for c in 0..3 {
                    p.f[(c, c)] += d;
                }
            }
        }
    }
    Ok((pts, Some(gbar)))
}

#[inline]
pub(super) fn reference_point<const N: usize>(
    x0: &[[f64; 3]; N],
    dn: &[[f64; 3]; N],
    g: usize,
) -> Result<([[f64; 3]; N], f64), ElementError> {
    let (grad0, det0) = reference_gradients(x0, dn);
    if det0.is_nan() || det0 <= 0.0 {
        return Err(ElementError::ReferenceInverted {
            at: At::Gauss(g),
            det: det0,
        });
    }
    Ok((grad0, det0))
}

/// The F-bar tangent's extra term (de Souza Neto et al. eq. 15.20, written for τ over
/// the reference volume): K_ab += w/3 (M g_a) ⊗ (ḡ_b − g_b), with M = c:I + 2τ̄
/// (finite: linearizing τ̄ = τ(F̄) along δF̄ F̄⁻¹ = δl + δθ I gives c:I δθ and the
/// Lie-derivative terms 2τ̄ δθ) or M = C:I (small strain).
#[inline]
pub(super) fn add_fbar_tangent<const N: usize>(
    g: &[[f64; 3]; N],
    gbar: &[[f64; 3]; N],
    sp: &StressPoint,
    finite: bool,
    w: f64,
    k: &mut LocalTangent<N>,
) {
    let c = &sp.tangent;
    let ci: [f64; 6] = std::array::from_fn(|r| c[r][0] + c[r][1] + c[r][2]);
    let s2 = if finite { 2.0 } else { 0.0 };
    let m: [f64; 6] = std::array::from_fn(|r| ci[r] + s2 * sp.stress[r]);
    let d: [[f64; 3]; N] = std::array::from_fn(|b| {
        [
            (gbar[b][0] - g[b][0]) * w / 3.0,
            (gbar[b][1] - g[b][1]) * w / 3.0,
            (gbar[b][2] - g[b][2]) * w / 3.0,
        ]
    });
    for a in 0..N {
        let [g0, g1, g2] = g[a];
        let mg = [
            m[0] * g0 + m[3] * g1 + m[5] * g2,
            m[3] * g0 + m[1] * g1 + m[4] * g2,
            m[5] * g0 + m[4] * g1 + m[2] * g2,
        ];
        for i in 0..3 {
            for b in 0..N {
                for j in 0..3 {
                    k[a][i][b][j] += mg[i] * d[b][j];
                }
            }
        }
    }
}
