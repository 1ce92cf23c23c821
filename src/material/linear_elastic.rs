//! Isotropic linear elasticity (Hughes, *The Finite Element Method*, §2.7): σ = C : ε with
//! ε = sym(F − I). Used with [`Kinematics::Small`], so the element never forms a
//! geometric stiffness; a reference model for patch tests and small-strain parts.

use super::{lame, Kinematics, Material, MaterialError, StressPoint};
use nalgebra::Matrix3;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearElastic {
    /// Young's modulus.
    pub e: f64,
    /// Poisson's ratio.
    pub nu: f64,
    /// Mass density.
    pub density: f64,
}

impl LinearElastic {
    /// No validation here: the deck checks E > 0 and −1 < ν < 1/2 with field paths.
    pub fn new(e: f64, nu: f64, density: f64) -> Self {
        Self { e, nu, density }
    }

    /// Voigt elasticity matrix C = λ m mᵀ + μ diag(2,2,2,1,1,1) (engineering shear).
    pub fn tangent(&self) -> [[f64; 6]; 6] {
        let (lambda, mu) = lame(self.e, self.nu);
        let mut c = [[0.0; 6]; 6];
        for (i, row) in c.iter_mut().enumerate().take(3) {
            row[..3].fill(lambda);
            row[i] += 2.0 * mu;
        }
        for (i, row) in c.iter_mut().enumerate().skip(3) {
            row[i] = mu;
        }
        c
    }
}

impl Material for LinearElastic {
    fn kinematics(&self) -> Kinematics {
        Kinematics::Small
    }

    fn evaluate(
        &self,
        f: &Matrix3<f64>,
        _state_old: &[f64],
        _state_new: &mut [f64],
    ) -> Result<StressPoint, MaterialError> {
        // Engineering strain in Voigt order xx, yy, zz, xy, yz, xz.
        let eps = [
            f[(0, 0)] - 1.0,
            f[(1, 1)] - 1.0,
            f[(2, 2)] - 1.0,
            f[(0, 1)] + f[(1, 0)],
            f[(1, 2)] + f[(2, 1)],
            f[(0, 2)] + f[(2, 0)],
        ];
        let c = self.tangent();
        let mut stress = [0.0; 6];
        for (s, row) in stress.iter_mut().zip(&c) {
            *s = row.iter().zip(&eps).map(|(a, b)| a * b).sum();
        }
        Ok(StressPoint { stress, tangent: c })
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
        let m = LinearElastic::new(200e3, 0.3, 7.8e-9);
        let sp = m.evaluate(&Matrix3::identity(), &[], &mut []).unwrap();
        assert!(sp.stress.iter().all(|s| *s == 0.0));
    }

    #[test]
    fn matches_hooke() {
        let (e, nu) = (210.0, 0.3);
        let m = LinearElastic::new(e, nu, 1.0);
        let g = 0.5 * e / (1.0 + nu);
        // Uniaxial stress σxx = s: εxx = s/E, εyy = εzz = −ν s/E.
        let s = 2.0;
        let mut f = Matrix3::identity();
        f[(0, 0)] += s / e;
        f[(1, 1)] -= nu * s / e;
        f[(2, 2)] -= nu * s / e;
        // Plus a pure shear γxy = 0.01 split unevenly (only the symmetric part counts),
        // and γyz = 0.004 from one side only.
        f[(0, 1)] += 0.007;
        f[(1, 0)] += 0.003;
        f[(1, 2)] += 0.004;
        let sp = m.evaluate(&f, &[], &mut []).unwrap();
        let want = [s, 0.0, 0.0, g * 0.01, g * 0.004, 0.0];
        for (a, b) in sp.stress.iter().zip(&want) {
            assert!((a - b).abs() < 1e-12 * e, "{:?} vs {want:?}", sp.stress);
        }
        assert!((m.shear_modulus() - g).abs() < 1e-12 * e);
        // Bulk: hydrostatic strain ε I gives p = 3Kε.
        let fv = Matrix3::identity() * 1.001;
        let sp = m.evaluate(&fv, &[], &mut []).unwrap();
        assert!((sp.stress[0] - 3.0 * m.bulk_modulus() * 0.001).abs() < 1e-12 * e);
    }
}
