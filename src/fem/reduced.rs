//! The uniformly reduced hex8: one integration point with hourglass stiffness
//! (Flanagan & Belytschko, IJNME 17 (1981) 679; LS-DYNA's default solid, ELFORM 1 with a
//! stiffness hourglass control), total Lagrangian.
//!
//! * The point uses the mean gradients b_a = (1/V) ∫ ∇_X N_a dV (exact under 2×2×2), so
//!   F = I + Σ u_a ⊗ b_a is the element's mean deformation gradient, f_a = V τ F⁻ᵀ b_a,
//!   and the patch test passes on any hex.
//! * The four hourglass modes the point cannot see are held by a linear spring on their
//!   amplitudes q_α = Σ_a γ_α,a x_a, with the Flanagan–Belytschko vectors
//!   γ_α = h_α − (h_α · X) b (h_α: ξη, ηζ, ζξ, ξηζ at the nodes; γ_α annihilates every
//!   affine field). The energy ½ Σ k_α |q_α|² is objective: q(Rx + c) = R q(x).
//! * k_α is the element's own deviatoric stiffness in mode α at the reference state,
//!   k_α = (10/9) G ∫ |∇ũ_α|² dV / (γ_α · h_α)² with ũ_α the mode without its mean
//!   gradient (the direction-averaged ∫ 2G ε_dev : ε_dev of full integration), so on a
//!   rectangular element the hourglass modes are as stiff as the F-bar element's at small
//!   strain. There is no user coefficient to tune.
//!
//! Why it exists: under large compression the pressure's geometric stiffness makes the
//! hourglass modes of an F-bar (or mean-dilatation, or EAS) hex8 negative (Wriggers &
//! Reese 1996), and rubber under an indenter folds element by element. Here the pressure
//! acts only through the mean F, which cannot see those modes, and the hourglass spring
//! stays positive at any strain. The volumetric part is one constant per element, so
//! nearly incompressible materials do not lock.

use super::error::{material_at, At, ElementError};
use super::kernel::{nodes, ElementData, ElementKernel, ElementOutput};
use super::kinematics::{
    add_force, add_tangent, cofactor, deformation_gradient, reference_point, transform_gradients,
    LocalTangent,
};
use super::shape::{HEX8, HEX8_NODES};
use crate::material::{Kinematics, Material};

/// Number of hourglass modes of a hex8.
const MODES: usize = 4;

/// What the element needs from its reference configuration.
struct Reference {
    /// Mean gradients b_a.
    b: [[f64; 3]; 8],
    /// Reference volume V.
    vol: f64,
    /// Flanagan–Belytschko hourglass vectors γ_α.
    gamma: [[f64; 8]; MODES],
    /// Hourglass stiffness per mode.
    k: [f64; MODES],
}

/// h_α at node a: ξη, ηζ, ζξ, ξηζ of its natural coordinates.
fn base_vector(alpha: usize) -> [f64; 8] {
    std::array::from_fn(|a| {
        let [x, y, z] = HEX8_NODES[a];
        match alpha {
            0 => x * y,
            1 => y * z,
            2 => z * x,
            _ => x * y * z,
        }
    })
}

fn reference(x0: &[[f64; 3]; 8], shear_modulus: f64) -> Result<Reference, ElementError> {
    let mut grads = [[[0.0; 3]; 8]; 8];
    let mut w = [0.0; 8];
    let mut b = [[0.0; 3]; 8];
    let mut vol = 0.0;
    for g in 0..8 {
        let (grad0, det0) = reference_point(x0, &HEX8.dn[g], g)?;
        w[g] = HEX8.weights[g] * det0;
        vol += w[g];
        for (ba, ga) in b.iter_mut().zip(&grad0) {
            for c in 0..3 {
                ba[c] += w[g] * ga[c];
            }
        }
        grads[g] = grad0;
    }
    for ba in &mut b {
        for c in ba.iter_mut() {
            *c /= vol;
        }
    }
    let mut gamma = [[0.0; 8]; MODES];
    let mut k = [0.0; MODES];
    for alpha in 0..MODES {
        let h = base_vector(alpha);
        // h · X (a vector) and the mode's mean gradient Σ h_a b_a.
        let mut hx = [0.0; 3];
        let mut hb = [0.0; 3];
        for a in 0..8 {
            for c in 0..3 {
                hx[c] += h[a] * x0[a][c];
                hb[c] += h[a] * b[a][c];
            }
        }
        let mut gh = 0.0;
        let mut mode = [0.0; 8];
        for a in 0..8 {
            gamma[alpha][a] = h[a] - dot(&hx, &b[a]);
            gh += gamma[alpha][a] * h[a];
            mode[a] = h[a] - dot(&hb, &x0[a]);
        }
        let mut energy = 0.0;
        for g in 0..8 {
            let mut grad = [0.0; 3];
            for a in 0..8 {
                for c in 0..3 {
                    grad[c] += mode[a] * grads[g][a][c];
                }
            }
            energy += w[g] * dot(&grad, &grad);
        }
        if gh.is_nan() || gh.abs() < 1e-3 {
            return Err(ElementError::DegenerateHourglass {
                mode: alpha,
                gamma_h: gh,
            });
        }
        k[alpha] = 10.0 / 9.0 * shear_modulus * energy / (gh * gh);
    }
    Ok(Reference { b, vol, gamma, k })
}

#[inline]
fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The one point: F, the gradients the force uses (F⁻ᵀ b_a finite, b_a small).
fn point(
    r: &Reference,
    kin: Kinematics,
    u: &[[f64; 3]; 8],
) -> Result<(nalgebra::Matrix3<f64>, [[f64; 3]; 8]), ElementError> {
    let f = deformation_gradient(u, &r.b);
    match kin {
        Kinematics::Small => Ok((f, r.b)),
        Kinematics::Finite => {
            let j = f.determinant();
            if j.is_nan() || j <= 0.0 {
                return Err(ElementError::Inverted {
                    at: At::Centre,
                    det: j,
                });
            }
            Ok((f, transform_gradients(&(cofactor(&f) / j), &r.b)))
        }
    }
}

/// The reduced hex8 with its hourglass spring scaled by `hourglass`; history holds one
/// point.
#[derive(Debug, Clone, Copy)]
pub struct Reduced {
    pub hourglass: f64,
}

impl ElementKernel for Reduced {
    fn n_nodes(&self) -> usize {
        8
    }
    fn n_points(&self) -> usize {
        1
    }
    fn force(&self, e: &ElementData, out: ElementOutput) -> Result<(), ElementError> {
        force(e, self.hourglass, out)
    }
    fn stress(&self, e: &ElementData) -> Result<[f64; 6], ElementError> {
        stress(nodes(e.x0), nodes(e.u), e.mat, e.state_old)
    }
}

/// Internal force and optionally tangent with the spring scaled by `hourglass`.
fn force(e: &ElementData, hourglass: f64, out: ElementOutput) -> Result<(), ElementError> {
    let (mat, state_old) = (e.mat, e.state_old);
    let ElementOutput { state_new, f, k } = out;
    let u = nodes(e.u);
    assert_eq!(f.len(), 24, "force slice length");
    assert!(
        state_old.len() == mat.n_state() && state_new.len() == mat.n_state(),
        "history length must be n_state (one point)"
    );
    let r = reference(nodes(e.x0), mat.shear_modulus())?;
    let kin = mat.kinematics();
    let (fm, grad) = point(&r, kin, u)?;
    let merr = material_at(At::Centre);
    f.fill(0.0);
    let k = match k {
        Some(k) => {
            assert_eq!(k.len(), 576, "tangent slice length");
            let sp = e
                .evaluate(&fm, 0..state_old.len(), state_new)
                .map_err(merr)?;
            add_force(&grad, &sp.stress, r.vol, f);
            let mut kloc: LocalTangent<8> = [[[[0.0; 3]; 8]; 3]; 8];
            add_tangent(&grad, &sp, kin == Kinematics::Finite, r.vol, &mut kloc);
            k.copy_from_slice(kloc.as_flattened().as_flattened().as_flattened());
            Some(k)
        }
        None => {
            let s = e
                .evaluate_stress(&fm, 0..state_old.len(), state_new)
                .map_err(merr)?;
            add_force(&grad, &s, r.vol, f);
            None
        }
    };
    spring(&r, hourglass, u, f, k);
    Ok(())
}

/// Adds the hourglass spring scaled by `scale` to an element force and tangent (the
/// stabilized F-bar).
pub(super) fn add_hourglass(
    x0: &[[f64; 3]; 8],
    u: &[[f64; 3]; 8],
    shear_modulus: f64,
    scale: f64,
    f: &mut [f64],
    k: Option<&mut [f64]>,
) -> Result<(), ElementError> {
    spring(&reference(x0, shear_modulus)?, scale, u, f, k);
    Ok(())
}

/// f_a += Σ_α s k_α γ_α,a q_α and K_ab += Σ_α s k_α γ_α,a γ_α,b I, with
/// q_α = Σ_a γ_α,a u_a (γ_α annihilates X, so u or x alike).
fn spring(r: &Reference, scale: f64, u: &[[f64; 3]; 8], f: &mut [f64], k: Option<&mut [f64]>) {
    for (ga, &ka) in r.gamma.iter().zip(&r.k) {
        let ka = scale * ka;
        let mut q = [0.0; 3];
        for (g, ua) in ga.iter().zip(u) {
            for (qc, uc) in q.iter_mut().zip(ua) {
                *qc += g * uc;
            }
        }
        for (fa, g) in f.chunks_exact_mut(3).zip(ga) {
            for (fc, qc) in fa.iter_mut().zip(&q) {
                *fc += ka * g * qc;
            }
        }
    }
    if let Some(k) = k {
        for (ga, &ka) in r.gamma.iter().zip(&r.k) {
            let ka = scale * ka;
            for a in 0..8 {
                for b in 0..8 {
                    let v = ka * ga[a] * ga[b];
                    for i in 0..3 {
                        k[(3 * a + i) * 24 + 3 * b + i] += v;
                    }
                }
            }
        }
    }
}

/// Cauchy stress at the centre (the hourglass spring carries no stress).
fn stress(
    x0: &[[f64; 3]; 8],
    u: &[[f64; 3]; 8],
    mat: &dyn Material,
    state_old: &[f64],
) -> Result<[f64; 6], ElementError> {
    let r = reference(x0, mat.shear_modulus())?;
    let kin = mat.kinematics();
    let (fm, _) = point(&r, kin, u)?;
    let mut scratch = vec![0.0; mat.n_state()];
    let s = mat
        .evaluate_stress(&fm, state_old, &mut scratch)
        .map_err(material_at(At::Centre))?;
    let j = match kin {
        Kinematics::Finite => fm.determinant(),
        Kinematics::Small => 1.0,
    };
    Ok(s.map(|v| v / j))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::element::{element_force, Formulation};
    use crate::material::MooneyRivlin;
    use crate::mesh::ElemKind;
    use nalgebra::{DMatrix, Matrix3, Vector3};

    fn cube(h: f64) -> Vec<[f64; 3]> {
        HEX8_NODES
            .iter()
            .map(|p| {
                [
                    0.5 * h * (p[0] + 1.0),
                    0.5 * h * (p[1] + 1.0),
                    0.5 * h * (p[2] + 1.0),
                ]
            })
            .collect()
    }

    fn tangent(
        form: Formulation,
        x0: &[[f64; 3]],
        u: &[[f64; 3]],
        mat: &dyn Material,
    ) -> DMatrix<f64> {
        let mut f = [0.0; 24];
        let mut k = vec![0.0; 576];
        let ns = mat.n_state();
        let (old, mut new) = (vec![0.0; 8 * ns], vec![0.0; 8 * ns]);
        let n = if matches!(form, Formulation::Reduced { .. }) {
            ns
        } else {
            8 * ns
        };
        element_force(
            ElemKind::Hex8,
            form,
            &ElementData::new(x0, u, mat, &old[..n]),
            ElementOutput::new(&mut new[..n], &mut f, Some(&mut k)),
        )
        .unwrap();
        let k = DMatrix::from_row_slice(24, 24, &k);
        (&k + k.transpose()) * 0.5
    }

    /// The smallest eigenvalues of the symmetric tangent, sorted.
    fn lowest(k: &DMatrix<f64>) -> Vec<f64> {
        let mut e: Vec<f64> = k.clone().symmetric_eigenvalues().iter().cloned().collect();
        e.sort_by(|a, b| a.partial_cmp(b).unwrap());
        e
    }

    /// Eigenvalues of K restricted to the deformation modes: the six rigid modes (whose
    /// geometric stiffness is negative in any prestressed free element) projected out.
    fn deformation_eigenvalues(k: &DMatrix<f64>, x0: &[[f64; 3]]) -> Vec<f64> {
        let mut rigid = DMatrix::zeros(24, 6);
        for (a, x) in x0.iter().enumerate() {
            for i in 0..3 {
                rigid[(3 * a + i, i)] = 1.0;
            }
            let r = [[0.0, -x[2], x[1]], [x[2], 0.0, -x[0]], [-x[1], x[0], 0.0]];
            for (j, rj) in r.iter().enumerate() {
                for i in 0..3 {
                    rigid[(3 * a + i, 3 + j)] = rj[i];
                }
            }
        }
        let q = rigid.qr().q();
        let p = DMatrix::identity(24, 24) - &q * q.transpose();
        let e = lowest(&(&p * k * &p));
        // Six zeros belong to the projected-out modes: drop the six values nearest 0.
        let mut by_size: Vec<(f64, usize)> =
            e.iter().enumerate().map(|(i, v)| (v.abs(), i)).collect();
        by_size.sort_by(|a, b| a.0.partial_cmp(&b.0).unwrap());
        let drop: Vec<usize> = by_size[..6].iter().map(|v| v.1).collect();
        e.into_iter()
            .enumerate()
            .filter(|(i, _)| !drop.contains(i))
            .map(|(_, v)| v)
            .collect()
    }

    fn homogeneous(x0: &[[f64; 3]], fdef: &Matrix3<f64>) -> Vec<[f64; 3]> {
        x0.iter()
            .map(|x| {
                let v = (fdef - Matrix3::identity()) * Vector3::from(*x);
                [v[0], v[1], v[2]]
            })
            .collect()
    }

    /// Why the formulation exists: a nearly incompressible rubber element squeezed
    /// isochorically to 40 % of its height. F-bar's hourglass modes pick up the pressure's
    /// geometric stiffness and one turns negative (the element can fold on its own);
    /// the reduced element's stay at their reference stiffness.
    #[test]
    fn compression_leaves_the_reduced_element_stable_where_fbar_is_not() {
        let x0 = cube(1.0);
        let mat = MooneyRivlin::new(0.5508, 0.1377, 0.4995, 1.0);
        let min = |form, lz: f64| {
            let lx = 1.0 / lz.sqrt();
            let u = homogeneous(&x0, &Matrix3::from_diagonal(&Vector3::new(lx, lx, lz)));
            deformation_eigenvalues(&tangent(form, &x0, &u, &mat), &x0)[0]
        };
        let g = mat.shear_modulus();
        assert!(min(Formulation::FBAR, 1.0) > 0.1 * g);
        assert!(min(Formulation::REDUCED, 1.0) > 0.1 * g);
        assert!(
            min(Formulation::FBAR, 0.4) < -0.3 * g,
            "{}",
            min(Formulation::FBAR, 0.4)
        );
        assert!(
            min(Formulation::REDUCED, 0.4) > 0.1 * g,
            "{}",
            min(Formulation::REDUCED, 0.4)
        );
    }
}
