//! Compressible neo-Hookean solid (Bonet & Wood, *Nonlinear Continuum Mechanics for
//! FEA*, 2nd ed., §6.4.3, eq. 6.28): W = μ/2 (I₁ − 3) − μ ln J + λ/2 (ln J)².
//!
//! Returns the Kirchhoff stress τ = μ(b − I) + λ ln J I (B&W eq. 6.29 times J) and the
//! spatial tangent of its Lie derivative c = λ I⊗I + 2(μ − λ ln J) 𝕀 (B&W eq. 6.40
//! times J), so the element integrates over the reference volume.

use super::{lame, Kinematics, Material, MaterialError, StressPoint};
use nalgebra::Matrix3;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NeoHookean {
    /// Small-strain Young's modulus.
    pub e: f64,
    /// Small-strain Poisson's ratio.
    pub nu: f64,
    /// Mass density.
    pub density: f64,
}

impl NeoHookean {
    /// No validation here: the deck checks E > 0 and −1 < ν < 1/2 with field paths.
    pub fn new(e: f64, nu: f64, density: f64) -> Self {
        Self { e, nu, density }
    }
}

impl Material for NeoHookean {
    fn kinematics(&self) -> Kinematics {
        Kinematics::Finite
    }

    fn evaluate(
        &self,
        f: &Matrix3<f64>,
        _state_old: &[f64],
        _state_new: &mut [f64],
    ) -> Result<StressPoint, MaterialError> {
        let j = f.determinant();
        if j.is_nan() || j <= 0.0 {
            return Err(MaterialError::Inverted {
                model: "neo-Hookean",
                det: j,
            });
        }
        let (lambda, mu) = lame(self.e, self.nu);
        let lnj = j.ln();
        let b = f * f.transpose();
        let p = lambda * lnj - mu;
        let stress = [
            mu * b[(0, 0)] + p,
            mu * b[(1, 1)] + p,
            mu * b[(2, 2)] + p,
            mu * b[(0, 1)],
            mu * b[(1, 2)],
            mu * b[(0, 2)],
        ];
        let mut tangent = [[0.0; 6]; 6];
        let d = mu - lambda * lnj;
        for (i, row) in tangent.iter_mut().enumerate() {
            if i < 3 {
                row[..3].fill(lambda);
                row[i] += 2.0 * d;
            } else {
                row[i] = d;
            }
        }
        Ok(StressPoint { stress, tangent })
    }

    /// U = λ/2 (ln J)²: U' = λ ln J / J, U'' = λ (1 − ln J) / J² (the rest,
    /// μ/2 (I₁ − 3) − μ ln J, carries only the shear modulus).
    fn volumetric(&self, j: f64) -> Option<(f64, f64)> {
        let lambda = lame(self.e, self.nu).0;
        let l = j.ln();
        Some((lambda * l / j, lambda * (1.0 - l) / (j * j)))
    }

    fn shear_modulus(&self) -> f64 {
        lame(self.e, self.nu).1
    }

    fn bulk_modulus(&self) -> f64 {
        self.e / (3.0 * (1.0 - 2.0 * self.nu))
    }

    fn density(&self) -> f64 {
        self.density
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_stress_at_identity() {
        let m = NeoHookean::new(10.0, 0.45, 1.0);
        let sp = m.evaluate(&Matrix3::identity(), &[], &mut []).unwrap();
        assert!(sp.stress.iter().all(|s| s.abs() < 1e-14));
    }

    #[test]
    fn homogeneous_stretch_closed_form() {
        let (e, nu) = (10.0, 0.3);
        let (lambda, mu) = lame(e, nu);
        let m = NeoHookean::new(e, nu, 1.0);
        let (l1, l2, l3) = (1.3, 0.9, 0.8);
        let f = Matrix3::from_diagonal(&nalgebra::Vector3::new(l1, l2, l3));
        let sp = m.evaluate(&f, &[], &mut []).unwrap();
        let lnj = (l1 * l2 * l3).ln();
        for (i, l) in [l1, l2, l3].iter().enumerate() {
            let want = mu * (l * l - 1.0) + lambda * lnj;
            assert!(
                (sp.stress[i] - want).abs() < 1e-12,
                "{i}: {} vs {want}",
                sp.stress[i]
            );
        }
        assert!(sp.stress[3..].iter().all(|s| s.abs() < 1e-14));
        // Rotated stretch: τ must rotate with it (objectivity).
        let r = nalgebra::Rotation3::from_euler_angles(0.3, -0.5, 1.1).into_inner();
        let sr = m.evaluate(&(r * f), &[], &mut []).unwrap();
        let tau = Matrix3::from_diagonal(&nalgebra::Vector3::new(
            sp.stress[0],
            sp.stress[1],
            sp.stress[2],
        ));
        let want = r * tau * r.transpose();
        let got = [
            sr.stress[0],
            sr.stress[1],
            sr.stress[2],
            sr.stress[3],
            sr.stress[4],
            sr.stress[5],
        ];
        let w = [
            want[(0, 0)],
            want[(1, 1)],
            want[(2, 2)],
            want[(0, 1)],
            want[(1, 2)],
            want[(0, 2)],
        ];
        for (a, b) in got.iter().zip(&w) {
            assert!((a - b).abs() < 1e-12);
        }
    }

    #[test]
    fn small_strain_limit_is_hooke() {
        let m = NeoHookean::new(100.0, 0.3, 1.0);
        let le = super::super::linear_elastic::LinearElastic::new(100.0, 0.3, 1.0);
        let mut f = Matrix3::identity();
        f[(0, 0)] += 1e-7;
        f[(0, 1)] += 2e-7;
        f[(1, 0)] += 2e-7;
        let a = m.evaluate(&f, &[], &mut []).unwrap();
        let b = le.evaluate(&f, &[], &mut []).unwrap();
        for (x, y) in a.stress.iter().zip(&b.stress) {
            assert!((x - y).abs() < 1e-11, "{:?} vs {:?}", a.stress, b.stress);
        }
        let c0 = m
            .evaluate(&Matrix3::identity(), &[], &mut [])
            .unwrap()
            .tangent;
        assert_eq!(c0, le.tangent());
    }

    #[test]
    fn inverted_is_error() {
        let m = NeoHookean::new(10.0, 0.3, 1.0);
        let f = Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, 1.0, -0.5));
        assert!(m.evaluate(&f, &[], &mut []).is_err());
    }
}
