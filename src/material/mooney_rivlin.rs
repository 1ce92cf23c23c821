//! Compressible Mooney–Rivlin rubber with a decoupled (isochoric/volumetric) energy,
//! parametrised as LS-DYNA's hyperelastic rubber takes it (C10, C01, ν):
//!
//! W = C10 (Ī₁ − 3) + C01 (Ī₂ − 3) + K/2 (J − 1)²,
//! Ī₁ = tr b̄, Ī₂ = ½(Ī₁² − tr b̄²), b̄ = J^{-2/3} b, b = F Fᵀ,
//! G = 2(C10 + C01), K = 2G(1 + ν) / (3(1 − 2ν)).
//!
//! Kirchhoff stress (Holzapfel, *Nonlinear Solid Mechanics*, §6.4, eqs. 6.98–6.103
//! times J): τ = dev τ̄ + J p I with the fictitious stress
//! τ̄ = 2[(C10 + Ī₁ C01) b̄ − C01 b̄²] and p = K(J − 1).
//!
//! Spatial tangent of the Lie derivative of τ (Holzapfel §6.6, eqs. 6.165–6.168 times J):
//! c = c_iso + c_vol,
//! c_vol = J(p + J K) I⊗I − 2 J p 𝕀,
//! c_iso = ℙ:c̄:ℙ + ⅔ tr(τ̄) ℙ − ⅔ (I⊗τ_iso + τ_iso⊗I),
//! c̄ = 4 C01 (b̄⊗b̄ − 𝕀_b̄), (𝕀_b̄)_abcd = ½(b̄_ac b̄_bd + b̄_ad b̄_bc),
//! ℙ = 𝕀 − ⅓ I⊗I. With C01 = 0 this is a neo-Hookean deviatoric response.

use super::tensor::{axpby, check_f, ddot, outer, sym_box, t4_to_voigt, to_voigt};
use super::{Kinematics, Material, MaterialError, StressPoint};
use nalgebra::Matrix3;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MooneyRivlin {
    pub c10: f64,
    pub c01: f64,
    /// Poisson's ratio that sets the bulk modulus from G.
    pub nu: f64,
    /// Mass density.
    pub density: f64,
}

impl MooneyRivlin {
    /// No validation here: the deck checks G = 2(C10 + C01) > 0 and −1 < ν < 1/2.
    pub fn new(c10: f64, c01: f64, nu: f64, density: f64) -> Self {
        Self {
            c10,
            c01,
            nu,
            density,
        }
    }

    fn g(&self) -> f64 {
        2.0 * (self.c10 + self.c01)
    }

    fn k(&self) -> f64 {
        2.0 * self.g() * (1.0 + self.nu) / (3.0 * (1.0 - 2.0 * self.nu))
    }
}

impl MooneyRivlin {
    /// τ and, if `want_tangent`, c (zero otherwise).
    fn update(&self, f: &Matrix3<f64>, want_tangent: bool) -> Result<StressPoint, MaterialError> {
        let j = check_f("Mooney-Rivlin", f)?;
        let (c10, c01, kb) = (self.c10, self.c01, self.k());
        let id = Matrix3::<f64>::identity();
        let bbar = (f * f.transpose()) * j.powf(-2.0 / 3.0);
        let bbar2 = bbar * bbar;
        let i1 = bbar.trace();
        let i2 = 0.5 * (i1 * i1 - bbar2.trace());
        let tbar = 2.0 * ((c10 + i1 * c01) * bbar - c01 * bbar2);
        let tr_tbar = tbar.trace();
        let tiso = tbar - id * (tr_tbar / 3.0);
        let p = kb * (j - 1.0);
        let tau = tiso + id * (j * p);
        debug_assert!((tr_tbar - 2.0 * (c10 * i1 + 2.0 * c01 * i2)).abs() <= 1e-9 * tr_tbar.abs());
        if !want_tangent {
            let stress = to_voigt(&tau);
            if stress.iter().any(|x| !x.is_finite()) {
                return Err(MaterialError::NonFinite {
                    model: "Mooney-Rivlin",
                    what: "stress",
                });
            }
            return Ok(StressPoint {
                stress,
                tangent: [[0.0; 6]; 6],
            });
        }

        let ii = outer(&id, &id);
        let sym_i = sym_box(&id, &id);
        let proj = axpby(1.0, &sym_i, -1.0 / 3.0, &ii);
        // Fictitious tangent c̄ and its deviatoric projection ℙ:c̄:ℙ.
        let mut c = if c01 != 0.0 {
            let cbar = axpby(
                4.0 * c01,
                &outer(&bbar, &bbar),
                -4.0 * c01,
                &sym_box(&bbar, &bbar),
            );
            ddot(&proj, &ddot(&cbar, &proj))
        } else {
            [[[[0.0; 3]; 3]; 3]; 3]
        };
        c = axpby(1.0, &c, 2.0 / 3.0 * tr_tbar, &proj);
        let it = axpby(1.0, &outer(&id, &tiso), 1.0, &outer(&tiso, &id));
        c = axpby(1.0, &c, -2.0 / 3.0, &it);
        c = axpby(1.0, &c, j * (p + j * kb), &ii);
        c = axpby(1.0, &c, -2.0 * j * p, &sym_i);

        let stress = to_voigt(&tau);
        let tangent = t4_to_voigt(&c);
        if stress
            .iter()
            .chain(tangent.iter().flatten())
            .any(|x| !x.is_finite())
        {
            return Err(MaterialError::NonFinite {
                model: "Mooney-Rivlin",
                what: "stress or tangent",
            });
        }
        Ok(StressPoint { stress, tangent })
    }
}

impl Material for MooneyRivlin {
    fn kinematics(&self) -> Kinematics {
        Kinematics::Finite
    }

    fn evaluate(
        &self,
        f: &Matrix3<f64>,
        _state_old: &[f64],
        _state_new: &mut [f64],
    ) -> Result<StressPoint, MaterialError> {
        self.update(f, true)
    }

    fn evaluate_stress(
        &self,
        f: &Matrix3<f64>,
        _state_old: &[f64],
        _state_new: &mut [f64],
    ) -> Result<[f64; 6], MaterialError> {
        Ok(self.update(f, false)?.stress)
    }

    /// U = K/2 (J − 1)²: U' = K (J − 1), U'' = K.
    fn volumetric(&self, j: f64) -> Option<(f64, f64)> {
        let k = self.k();
        Some((k * (j - 1.0), k))
    }

    fn shear_modulus(&self) -> f64 {
        self.g()
    }

    fn bulk_modulus(&self) -> f64 {
        self.k()
    }

    fn density(&self) -> f64 {
        self.density
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::{asymmetry, objectivity_error, tangent_error, tau};
    use super::super::{LinearElastic, NeoHookean};
    use super::*;
    use nalgebra::Vector3;

    fn test_fs() -> Vec<Matrix3<f64>> {
        let diag = |a: f64, b: f64, c: f64| Matrix3::from_diagonal(&Vector3::new(a, b, c));
        let mut shear = Matrix3::identity();
        shear[(0, 1)] = 0.8;
        vec![
            Matrix3::identity(),
            diag(2.0, 1.0 / 2f64.sqrt(), 1.0 / 2f64.sqrt()),
            diag(0.5, 2f64.sqrt(), 2f64.sqrt()),
            diag(2.0, 1.0, 1.0),
            diag(0.5, 0.9, 1.1),
            shear,
            Matrix3::new(1.3, 0.2, -0.1, 0.15, 0.8, 0.3, -0.05, 0.1, 1.1),
        ]
    }

    #[test]
    fn zero_stress_at_identity_and_moduli() {
        let m = MooneyRivlin::new(0.3, 0.1, 0.45, 1.0);
        let s = tau(&m, &Matrix3::identity(), &[]);
        assert!(s.iter().all(|x| x.abs() < 1e-14), "{s:?}");
        assert_eq!(m.n_state(), 0);
        assert!((m.shear_modulus() - 0.8).abs() < 1e-15);
        let k = 2.0 * 0.8 * 1.45 / (3.0 * 0.1);
        assert!((m.bulk_modulus() - k).abs() < 1e-12 * k);
    }

    #[test]
    fn tangent_matches_finite_difference() {
        for (c10, c01, nu) in [(0.3, 0.1, 0.45), (0.5, 0.0, 0.3), (0.2, 0.3, 0.49)] {
            let m = MooneyRivlin::new(c10, c01, nu, 1.0);
            for f in test_fs() {
                let err = tangent_error(&m, &f, &[]);
                let sp = m.evaluate(&f, &[], &mut []).unwrap();
                assert!(asymmetry(&sp.tangent) < 1e-12, "tangent not symmetric");
                assert!(err < 1e-6, "C10={c10} C01={c01} F={f}: rel err {err:.2e}");
            }
        }
    }

    #[test]
    fn objectivity() {
        let m = MooneyRivlin::new(0.3, 0.1, 0.45, 1.0);
        for f in test_fs().into_iter().skip(1) {
            let e = objectivity_error(&m, &f, &[]);
            assert!(e < 1e-12, "F={f}: {e:.2e}");
        }
    }

    #[test]
    fn small_strain_limit_is_hooke() {
        let m = MooneyRivlin::new(0.3, 0.1, 0.3, 1.0);
        let (g, k) = (m.shear_modulus(), m.bulk_modulus());
        let e = 9.0 * k * g / (3.0 * k + g);
        let nu = (3.0 * k - 2.0 * g) / (2.0 * (3.0 * k + g));
        assert!((nu - 0.3).abs() < 1e-14);
        let le = LinearElastic::new(e, nu, 1.0);
        let mut f = Matrix3::identity();
        f[(0, 0)] += 1e-7;
        f[(1, 1)] -= 3e-8;
        f[(0, 1)] += 2e-7;
        f[(1, 0)] += 1e-7;
        f[(2, 1)] += 5e-8;
        let a = m.evaluate(&f, &[], &mut []).unwrap();
        let b = le.evaluate(&f, &[], &mut []).unwrap();
        for (x, y) in a.stress.iter().zip(&b.stress) {
            assert!((x - y).abs() < 1e-12, "{:?} vs {:?}", a.stress, b.stress);
        }
        let c0 = m.evaluate(&Matrix3::identity(), &[], &mut []).unwrap();
        for (x, y) in c0
            .tangent
            .iter()
            .flatten()
            .zip(le.tangent().iter().flatten())
        {
            assert!((x - y).abs() < 1e-13, "{:?}", c0.tangent);
        }
    }

    /// With C01 = 0 the deviatoric part equals neo-Hookean's isochoric part: compare at
    /// an isochoric F (J = 1) with NeoHookean of the same shear modulus, where the two
    /// volumetric terms vanish and the deviatoric stresses must coincide up to the
    /// pressure (NeoHookean's μ(b − I) is not deviatoric, so compare deviators).
    #[test]
    fn c01_zero_is_neo_hookean_deviator() {
        let mr = MooneyRivlin::new(0.5, 0.0, 0.3, 1.0);
        let nh = NeoHookean::new(2.0 * 1.0 * 1.3, 0.3, 1.0); // μ = 1
        let f = Matrix3::<f64>::new(1.3, 0.4, 0.0, 0.0, 1.0 / 1.3, 0.2, 0.0, 0.0, 1.0);
        assert!((f.determinant() - 1.0).abs() < 1e-14);
        let dev = |s: [f64; 6]| {
            let p = (s[0] + s[1] + s[2]) / 3.0;
            [s[0] - p, s[1] - p, s[2] - p, s[3], s[4], s[5]]
        };
        let a = dev(tau(&mr, &f, &[]));
        let b = dev(tau(&nh, &f, &[]));
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() < 1e-13, "{a:?} vs {b:?}");
        }
    }

    /// Energy W(λ1, λ2, λ3) for a diagonal F.
    fn energy(m: &MooneyRivlin, l: [f64; 3]) -> f64 {
        let j = l[0] * l[1] * l[2];
        let sq = l.map(|x| x * x * j.powf(-2.0 / 3.0));
        let i1 = sq[0] + sq[1] + sq[2];
        let i2 = sq[0] * sq[1] + sq[1] * sq[2] + sq[0] * sq[2];
        m.c10 * (i1 - 3.0) + m.c01 * (i2 - 3.0) + 0.5 * m.k() * (j - 1.0) * (j - 1.0)
    }

    /// Homogeneous uniaxial stress: solve the lateral stretch for τ_yy = 0 (Newton),
    /// then compare the axial nominal stress P = τ_xx/λ with (i) ∂W/∂λ₁ of the decoupled
    /// energy (central difference, tight) and (ii) the incompressible closed form
    /// P = 2(λ − λ⁻²)(C10 + C01/λ), within 0.5 % at ν = 0.4995, λ ∈ [0.5, 2].
    #[test]
    fn uniaxial_stress_closed_form() {
        let m = MooneyRivlin::new(0.4, 0.15, 0.4995, 1.0);
        let mut worst = 0.0_f64;
        for i in 0..=30 {
            let lam = 0.5 + 1.5 * i as f64 / 30.0;
            if (lam - 1.0).abs() < 1e-12 {
                continue;
            }
            let mut mu = 1.0 / lam.sqrt();
            let diag = |mu: f64| Matrix3::from_diagonal(&Vector3::new(lam, mu, mu));
            let mut converged = false;
            for _ in 0..50 {
                let sp = m.evaluate(&diag(mu), &[], &mut []).unwrap();
                let r = sp.stress[1];
                // Round-off floor: the pressure is of order K (≈ 1000 G here).
                if r.abs() < 1e-12 * m.bulk_modulus() {
                    converged = true;
                    break;
                }
                // dτ_yy/dμ for F = diag(λ, μ, μ): d = (δμ/μ)(e2⊗e2 + e3⊗e3), l = d:
                // τ̇_yy = (c_yy,yy + c_yy,zz) δμ/μ + 2 τ_yy δμ/μ.
                let dr = (sp.tangent[1][1] + sp.tangent[1][2] + 2.0 * r) / mu;
                mu -= r / dr;
            }
            assert!(converged, "lateral Newton did not converge at λ = {lam}");
            let sp = m.evaluate(&diag(mu), &[], &mut []).unwrap();
            let p = sp.stress[0] / lam;
            let h = 1e-6;
            let dw = (energy(&m, [lam + h, mu, mu]) - energy(&m, [lam - h, mu, mu])) / (2.0 * h);
            assert!(
                (p - dw).abs() < 1e-7 * dw.abs(),
                "λ={lam}: P={p} ∂W/∂λ={dw}"
            );
            let closed = 2.0 * (lam - lam.powi(-2)) * (m.c10 + m.c01 / lam);
            let rel = (p - closed).abs() / closed.abs();
            worst = worst.max(rel);
            assert!(
                rel < 5e-3,
                "λ={lam}: P={p} closed form {closed} ({rel:.2e})"
            );
        }
        // The K → ∞ formula must not be matched trivially either: at ν = 0.4995 the
        // finite bulk modulus leaves a small but nonzero deviation.
        assert!(worst > 1e-6, "worst {worst:.2e}");
    }

    #[test]
    fn inverted_or_non_finite_is_error() {
        let m = MooneyRivlin::new(0.3, 0.1, 0.45, 1.0);
        let f = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -0.5));
        assert!(m.evaluate(&f, &[], &mut []).is_err());
        let mut f = Matrix3::identity();
        f[(0, 1)] = f64::NAN;
        assert!(m.evaluate(&f, &[], &mut []).is_err());
        f[(0, 1)] = f64::INFINITY;
        assert!(m.evaluate(&f, &[], &mut []).is_err());
    }
}
