//! Constitutive models behind one seam, [`Material`].
//!
//! Finite-strain models return the Kirchhoff stress τ and the spatial tangent c of its
//! Lie derivative (Simo & Hughes, *Computational Inelasticity*, §7; Bonet & Wood,
//! *Nonlinear Continuum Mechanics for FEA*, §5–6), so that one element kernel serves
//! hyperelastic and, later, multiplicative plastic models and F-bar. Small-strain
//! models return the Cauchy stress and elasticity tensor from ε = sym(F − I).
//!
//! Voigt order everywhere: xx, yy, zz, xy, yz, xz (engineering shear strains in B).

mod error;
pub mod hardening;
pub mod j2;
pub mod linear_elastic;
pub mod mooney_rivlin;
pub mod neo_hookean;
mod tensor;
#[cfg(test)]
mod testing;

pub use error::MaterialError;
pub use hardening::Hardening;
pub use j2::J2Plasticity;
pub use linear_elastic::LinearElastic;
pub use mooney_rivlin::MooneyRivlin;
pub use neo_hookean::NeoHookean;

use nalgebra::Matrix3;

/// Which strain measure the element uses with this material.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kinematics {
    /// ε = sym(∇u); no geometric stiffness; reference configuration throughout.
    Small,
    /// Total-Lagrangian finite strain with F = I + ∇_X u.
    Finite,
}

/// Stress and tangent at one integration point.
#[derive(Debug, Clone, Copy)]
pub struct StressPoint {
    /// Kirchhoff stress τ = Jσ (finite) or Cauchy stress σ (small), Voigt order.
    pub stress: [f64; 6],
    /// Spatial tangent c (finite) or elasticity tensor C (small), 6×6 Voigt.
    pub tangent: [[f64; 6]; 6],
}

pub trait Material: Send + Sync + std::fmt::Debug {
    fn kinematics(&self) -> Kinematics;
    /// Number of history variables per integration point (0 for elastic models).
    fn n_state(&self) -> usize {
        0
    }
    /// Stress and tangent for deformation gradient `f`, given the converged history
    /// `state_old`; writes the updated history into `state_new` (same length).
    fn evaluate(
        &self,
        f: &Matrix3<f64>,
        state_old: &[f64],
        state_new: &mut [f64],
    ) -> Result<StressPoint, MaterialError>;
    /// The stress alone (same history update as [`Material::evaluate`]): what a residual
    /// evaluation needs. Models whose tangent is costly override it.
    fn evaluate_stress(
        &self,
        f: &Matrix3<f64>,
        state_old: &[f64],
        state_new: &mut [f64],
    ) -> Result<[f64; 6], MaterialError> {
        Ok(self.evaluate(f, state_old, state_new)?.stress)
    }
    /// [`Material::evaluate`] on a fixed branch of a model with branches (J2's elastic
    /// and plastic return): `branch` is the trial history of the last natural
    /// evaluation at the Newton iterate, and the point takes the branch it took there.
    /// JFNK's difference products evaluate so (the model's frozen evaluations):
    /// a perturbation that crosses the yield surface would otherwise make J·v nonlinear
    /// in v. Models without branches ignore `branch`.
    fn evaluate_on(
        &self,
        f: &Matrix3<f64>,
        state_old: &[f64],
        _branch: &[f64],
        state_new: &mut [f64],
    ) -> Result<StressPoint, MaterialError> {
        self.evaluate(f, state_old, state_new)
    }
    /// The stress alone on a fixed branch (see [`Material::evaluate_on`]).
    fn evaluate_stress_on(
        &self,
        f: &Matrix3<f64>,
        state_old: &[f64],
        _branch: &[f64],
        state_new: &mut [f64],
    ) -> Result<[f64; 6], MaterialError> {
        self.evaluate_stress(f, state_old, state_new)
    }
    /// The volumetric part of an energy that splits as W = W₁(F) + U(J), for the hybrid
    /// element (`fem::hybrid`): U'(J) (the Cauchy pressure it makes, τ_vol =
    /// J U'(J) I) and U''(J). `None` for a model without that split (the small-strain
    /// ones). W₁ need not be isochoric: the split only has to carry the bulk modulus.
    fn volumetric(&self, _j: f64) -> Option<(f64, f64)> {
        None
    }
    /// Small-strain shear modulus: scales penalty and ALM stiffnesses.
    fn shear_modulus(&self) -> f64;
    /// Small-strain bulk modulus.
    fn bulk_modulus(&self) -> f64;
    /// Mass density (mass per volume in the deck's unit system).
    fn density(&self) -> f64;
    /// Equivalent plastic strain stored in one point's history `state`, for models
    /// that have one (None for elastic models).
    fn equivalent_plastic_strain(&self, _state: &[f64]) -> Option<f64> {
        None
    }
}

/// Lamé constants from Young's modulus and Poisson's ratio.
pub fn lame(e: f64, nu: f64) -> (f64, f64) {
    let mu = e / (2.0 * (1.0 + nu));
    let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    (lambda, mu)
}

#[cfg(test)]
mod stress_only_tests {
    use super::*;
    use nalgebra::Matrix3;

    /// `evaluate_stress` gives exactly `evaluate`'s stress and history, elastic and
    /// plastic, for every model.
    #[test]
    fn stress_only_path_matches_evaluate() {
        let models: Vec<Box<dyn Material>> = vec![
            Box::new(LinearElastic::new(10.0, 0.3, 1.0)),
            Box::new(NeoHookean::new(10.0, 0.3, 1.0)),
            Box::new(MooneyRivlin::new(0.55, 0.14, 0.4995, 1.0)),
            Box::new(J2Plasticity::new(
                210000.0,
                0.3,
                Hardening::Linear {
                    sigma_y0: 250.0,
                    h: 1000.0,
                },
                1.0,
            )),
        ];
        let f = Matrix3::new(1.1, 0.05, 0.0, -0.02, 0.97, 0.01, 0.03, 0.0, 0.95);
        for m in &models {
            let old = vec![0.0; m.n_state()];
            let (mut a, mut b) = (vec![0.0; m.n_state()], vec![0.0; m.n_state()]);
            let full = m.evaluate(&f, &old, &mut a).unwrap();
            let s = m.evaluate_stress(&f, &old, &mut b).unwrap();
            assert_eq!(full.stress, s, "{m:?}");
            assert_eq!(a, b, "{m:?}");
            if m.n_state() > 0 {
                // Plastic from a committed plastic state too.
                let f2 = f * Matrix3::new(1.05, 0.0, 0.02, 0.0, 1.0, 0.0, 0.0, 0.01, 0.98);
                let (mut c, mut d) = (vec![0.0; m.n_state()], vec![0.0; m.n_state()]);
                let full = m.evaluate(&f2, &a, &mut c).unwrap();
                let s = m.evaluate_stress(&f2, &a, &mut d).unwrap();
                assert_eq!(full.stress, s);
                assert_eq!(c, d);
                assert!(m.equivalent_plastic_strain(&c).unwrap() > 0.0);
            }
        }
    }
}
