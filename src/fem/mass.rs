//! Element mass matrices and the element's highest frequency (for the explicit stable
//! time step). Pure functions of element data, like the rest of `fem`.
//!
//! * Consistent mass M_ab = ρ ∫ N_a N_b dV (the same for each displacement component,
//!   so it is stored as the n×n scalar matrix). Hex8: the 2×2×2 Gauss rule (exact for a
//!   parallelepiped, where det J₀ is constant and N_a N_b is cubic per direction);
//!   tet4: the exact formula ρV/20 (1 + δ_ab) (Zienkiewicz & Taylor, vol. 1, §16.2).
//! * Lumped mass: row sums of the consistent matrix, ρ ∫ N_a dV. For hex8 and tet4
//!   the shape functions are non-negative, so every lumped mass is positive.

use super::element::{element_force, ElementError, Formulation};
use super::kernel::{ElementData, ElementOutput};
use super::kinematics::reference_gradients;
use super::shape::{tet10_dn, tet10_n, HEX8, TET4, WEDGE6};
use crate::material::Material;
use crate::mesh::ElemKind;

/// Consistent mass of one element as an n×n scalar matrix (row-major, n nodes):
/// the 3n×3n matrix is this ⊗ I₃.
pub fn consistent_mass(kind: ElemKind, x0: &[[f64; 3]], rho: f64, m: &mut [f64]) {
    match kind {
        ElemKind::Hex8 => {
            let x: &[[f64; 3]; 8] = x0.try_into().expect("hex8 has 8 nodes");
            assert_eq!(m.len(), 64);
            m.fill(0.0);
            for g in 0..8 {
                let det = reference_gradients(x, &HEX8.dn[g]).1;
                let w = rho * HEX8.weights[g] * det;
                let n = &HEX8.n[g];
                for a in 0..8 {
                    for b in a..8 {
                        let v = w * n[a] * n[b];
                        m[8 * a + b] += v;
                        if b != a {
                            m[8 * b + a] += v;
                        }
                    }
                }
            }
        }
        ElemKind::Tet10 => {
            tet10_consistent_mass(x0.try_into().expect("tet10 has 10 nodes"), rho, m)
        }
        // The 3 × 2 rule: exact for a right prism (det J₀ constant, N_a N_b quadratic in
        // (ξ, η) and in ζ).
        ElemKind::Wedge6 => {
            let x: &[[f64; 3]; 6] = x0.try_into().expect("wedge6 has 6 nodes");
            assert_eq!(m.len(), 36);
            m.fill(0.0);
            for g in 0..6 {
                let det = reference_gradients(x, &WEDGE6.dn[g]).1;
                let w = rho * WEDGE6.weights[g] * det;
                let n = &WEDGE6.n[g];
                for a in 0..6 {
                    for b in 0..6 {
                        m[6 * a + b] += w * n[a] * n[b];
                    }
                }
            }
        }
        ElemKind::Tet4 => {
            let x: &[[f64; 3]; 4] = x0.try_into().expect("tet4 has 4 nodes");
            assert_eq!(m.len(), 16);
            let v = reference_gradients(x, &TET4.dn[0]).1 / 6.0;
            for a in 0..4 {
                for b in 0..4 {
                    m[4 * a + b] = rho * v / 20.0 * if a == b { 2.0 } else { 1.0 };
                }
            }
        }
    }
}

/// The tet10's consistent mass by a 4×4×4 collapsed (Duffy) Gauss rule on the unit
/// tet (the Gauss–Legendre points in each collapsed direction), exact for polynomials of
/// degree 5 in ξ: N_a N_b det J₀ is of degree 4 on a straight-sided element (det J₀
/// constant); with curved edges det J₀ is cubic and the rule is accurate, not exact.
fn tet10_consistent_mass(x: &[[f64; 3]; 10], rho: f64, m: &mut [f64]) {
    const P: [f64; 4] = [
        -0.861_136_311_594_052_6,
        -0.339_981_043_584_856_3,
        0.339_981_043_584_856_3,
        0.861_136_311_594_052_6,
    ];
    const W: [f64; 4] = [
        0.347_854_845_137_453_9,
        0.652_145_154_862_546_1,
        0.652_145_154_862_546_1,
        0.347_854_845_137_453_9,
    ];
    assert_eq!(m.len(), 100);
    m.fill(0.0);
    for (i, &pu) in P.iter().enumerate() {
        for (j, &pv) in P.iter().enumerate() {
            for (k, &pw) in P.iter().enumerate() {
                let (u, v, w) = (0.5 * (pu + 1.0), 0.5 * (pv + 1.0), 0.5 * (pw + 1.0));
                // ξ = u, η = v(1 − u), ζ = w(1 − u)(1 − v); dξdηdζ = (1 − u)²(1 − v).
                let xi = [u, v * (1.0 - u), w * (1.0 - u) * (1.0 - v)];
                let jac = (1.0 - u) * (1.0 - u) * (1.0 - v) * W[i] * W[j] * W[k] / 8.0;
                let det = reference_gradients(x, &tet10_dn(xi)).1;
                let n = tet10_n(xi);
                let s = rho * jac * det;
                for a in 0..10 {
                    for b in 0..10 {
                        m[10 * a + b] += s * n[a] * n[b];
                    }
                }
            }
        }
    }
}

/// Lumped mass of each node of one element: row sums of the consistent matrix (hex8,
/// tet4); for the tet10, whose corner rows sum to a negative mass, the diagonal scaled
/// to the element's mass (Hinton, Rock & Zienkiewicz 1976), positive at every node.
pub fn lumped_mass(kind: ElemKind, x0: &[[f64; 3]], rho: f64, m: &mut [f64]) {
    let n = x0.len();
    let mut full = [0.0; crate::mesh::MAX_NODES * crate::mesh::MAX_NODES];
    consistent_mass(kind, x0, rho, &mut full[..n * n]);
    if kind == ElemKind::Tet10 {
        let total: f64 = full[..n * n].iter().sum();
        let diag: f64 = (0..n).map(|a| full[a * n + a]).sum();
        for a in 0..n {
            m[a] = full[a * n + a] * total / diag;
        }
        return;
    }
    for a in 0..n {
        m[a] = full[a * n..(a + 1) * n].iter().sum();
    }
}

/// The highest natural frequency ω_e of one unconstrained element with its lumped mass,
/// linearised at the reference state (the material's tangent at F = I and the given
/// history): the largest eigenvalue of M_l^{-1/2} K_e M_l^{-1/2}, square-rooted.
/// By the element eigenvalue inequality (Irons; Hughes, *The FEM*, §9.1.4) the mesh's
/// highest frequency is at most max_e ω_e, so Δt ≤ 2 / max_e ω_e is stable for the
/// linearised problem whatever the element shape.
pub fn max_frequency(
    kind: ElemKind,
    form: Formulation,
    x0: &[[f64; 3]],
    mat: &dyn Material,
    state: &[f64],
) -> Result<f64, ElementError> {
    let n = x0.len();
    let w = 3 * n;
    let zero = [[0.0; 3]; crate::mesh::MAX_NODES];
    let mut scratch = state.to_vec();
    let mut f = [0.0; 3 * crate::mesh::MAX_NODES];
    let mut k = vec![0.0; w * w];
    element_force(
        kind,
        form,
        &ElementData::new(x0, &zero[..n], mat, state),
        ElementOutput::new(&mut scratch, &mut f[..w], Some(&mut k)),
    )?;
    let mut ml = [0.0; crate::mesh::MAX_NODES];
    lumped_mass(kind, x0, mat.density(), &mut ml[..n]);
    let s: Vec<f64> = (0..w).map(|i| 1.0 / ml[i / 3].sqrt()).collect();
    let a = nalgebra::DMatrix::from_fn(w, w, |i, j| {
        0.5 * (k[i * w + j] + k[j * w + i]) * s[i] * s[j]
    });
    let lmax = a
        .symmetric_eigenvalues()
        .iter()
        .cloned()
        .fold(0.0, f64::max);
    Ok(lmax.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{LinearElastic, Material};

    fn hex(sx: f64, sy: f64, sz: f64, skew: f64) -> Vec<[f64; 3]> {
        crate::fem::shape::HEX8_NODES
            .iter()
            .map(|p| {
                let (x, y, z) = (0.5 * (p[0] + 1.0), 0.5 * (p[1] + 1.0), 0.5 * (p[2] + 1.0));
                [sx * x + skew * z * y, sy * y + 0.1 * skew * x, sz * z]
            })
            .collect()
    }

    fn tet() -> Vec<[f64; 3]> {
        vec![
            [0.1, 0.0, 0.0],
            [1.3, 0.2, 0.0],
            [0.2, 0.9, 0.1],
            [0.3, 0.2, 1.1],
        ]
    }

    fn volume(kind: ElemKind, x: &[[f64; 3]]) -> f64 {
        crate::fem::measure::element_volume(kind, x)
    }

    #[test]
    fn consistent_mass_totals_rho_v_and_is_symmetric() {
        let rho = 7.5;
        for (kind, x) in [
            (ElemKind::Hex8, hex(2.0, 1.0, 0.5, 0.0)),
            (ElemKind::Hex8, hex(1.0, 1.5, 0.7, 0.3)),
            (ElemKind::Tet4, tet()),
        ] {
            let n = x.len();
            let mut m = vec![0.0; n * n];
            consistent_mass(kind, &x, rho, &mut m);
            let total: f64 = m.iter().sum();
            let v = volume(kind, &x);
            assert!(
                (total - rho * v).abs() < 1e-12 * rho * v,
                "{total} vs {}",
                rho * v
            );
            for a in 0..n {
                for b in 0..n {
                    assert_eq!(m[a * n + b], m[b * n + a]);
                }
                assert!(m[a * n + a] > 0.0);
            }
        }
    }

    #[test]
    fn lumped_mass_is_positive_and_conserves_total_and_momentum() {
        let rho = 2.0;
        for (kind, x) in [
            (ElemKind::Hex8, hex(1.0, 1.5, 0.7, 0.3)),
            (ElemKind::Tet4, tet()),
        ] {
            let n = x.len();
            let mut ml = vec![0.0; n];
            let mut mc = vec![0.0; n * n];
            lumped_mass(kind, &x, rho, &mut ml);
            consistent_mass(kind, &x, rho, &mut mc);
            assert!(ml.iter().all(|&m| m > 0.0), "{ml:?}");
            // Rigid translation v = (1, -2, 3) at every node: both masses give the same
            // nodal momenta (M v)_a = m_a v and the same kinetic energy ½ ρ V |v|².
            let v = [1.0, -2.0, 3.0];
            let vv: f64 = v.iter().map(|x| x * x).sum();
            let mut ke_c = 0.0;
            let mut ke_l = 0.0;
            for a in 0..n {
                let row: f64 = mc[a * n..(a + 1) * n].iter().sum();
                assert!((row - ml[a]).abs() < 1e-14 * row);
                ke_l += 0.5 * ml[a] * vv;
                for b in 0..n {
                    ke_c += 0.5 * mc[a * n + b] * vv;
                }
            }
            let exact = 0.5 * rho * volume(kind, &x) * vv;
            assert!((ke_c - exact).abs() < 1e-12 * exact);
            assert!((ke_l - exact).abs() < 1e-12 * exact);
        }
    }

    #[test]
    fn cube_highest_frequency_is_2c_over_h_at_nu_zero() {
        // ν = 0, lumped mass, 2×2×2 rule: ω_max = 2c/h exactly (the 1-D bar value), so
        // the element length 2c/ω_max equals the edge. At ν = 0.3 it is shorter
        // (0.734 h): V/A_max, exact at ν = 0, would not be conservative there.
        let (e, rho, h) = (210e3, 7.85e-9, 2.0);
        let x = hex(h, h, h, 0.0);
        for (nu, ratio) in [(0.0, 1.0), (0.3, 0.7338)] {
            let mat = LinearElastic::new(e, nu, rho);
            let w = max_frequency(ElemKind::Hex8, Formulation::Standard, &x, &mat, &[]).unwrap();
            let cd = ((mat.bulk_modulus() + 4.0 / 3.0 * mat.shear_modulus()) / rho).sqrt();
            let l = 2.0 * cd / w;
            assert!((l / h - ratio).abs() < 1e-4, "nu {nu}: L/h = {}", l / h);
        }
    }
}
