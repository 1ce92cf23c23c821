//! Finite-strain J2 (von Mises) plasticity with isotropic hardening: multiplicative
//! split F = Fe Fp, Hencky elastic law τ = 𝔻ᵉ : εₑ with εₑ = ½ ln bₑ, and the
//! exponential-map return mapping in principal logarithmic strains (de Souza Neto,
//! Perić & Owen, *Computational Methods for Plasticity*, Box 14.3; Simo, CMAME 99,
//! 1992):
//!
//! 1. trial bₑ = F Cₚ⁻¹ Fᵀ = Σ λᵢ² nᵢ⊗nᵢ, trial log strains εᵢ = ln λᵢ;
//! 2. small-strain radial return on (εᵢ) with 𝔻ᵉ = K 1⊗1 + 2G 𝕀_dev: q_tr − 3GΔγ −
//!    σ_y(ε̄ₚ + Δγ) = 0 by safeguarded Newton (bracket [0, q_tr/3G]);
//! 3. τ = Σ τᵢ nᵢ⊗nᵢ, bₑ = Σ exp(2εₑᵢ) nᵢ⊗nᵢ, Cₚ⁻¹ = F⁻¹ bₑ F⁻ᵀ, ε̄ₚ += Δγ.
//!
//! The flow is deviatoric in log strain, so det Cₚ⁻¹ is preserved (= 1) to round-off.
//!
//! **Tangent (analytic, consistent).** τ is the small-strain return map τ̂ applied to
//! ε_tr = ½ ln bₑ_tr, and under δF = d F (d symmetric) ḃₑ_tr = d bₑ_tr + bₑ_tr d. In
//! the eigenbasis of bₑ_tr the derivative of ½ ln (Daleckii–Krein) then gives
//! ε̇_tr,ij = θᵢⱼ dᵢⱼ with θᵢᵢ = 1, θᵢⱼ = y coth y, y = εᵢ − εⱼ (→ 1 + y²/3 for
//! coalescent eigenvalues, evaluated by series, so repeated eigenvalues need no
//! special case). With the algorithmic modulus of the radial return
//! 𝔻 = K I⊗I + 2Gβ 𝕀_dev + 6G²(Δγ/q_tr − 1/(3G + H)) N̂⊗N̂, β = 1 − 3GΔγ/q_tr,
//! N̂ = s_tr/|s_tr| (de Souza Neto eq. 7.120; elastic: β = 1, no N̂ term) and
//! τ̇ = c:d + dτ + τd, the spatial tangent in the eigenbasis is
//! c_iijj = 𝔻_iijj − 2τᵢ δᵢⱼ,  c_ijij = Gβ θᵢⱼ − ½(τᵢ + τⱼ) (i ≠ j),
//! rotated to the global frame. It is major-symmetric. Spin does not enter (the model
//! is isotropic and objective), which the tests check with a non-symmetric L.
//!
//! **History** (`n_state` = 7): Cₚ⁻¹ in Voigt order (xx, yy, zz, xy, yz, xz), then ε̄ₚ.
//! An all-zero Cₚ⁻¹ (the model's zero-initialised history) means the virgin state
//! Cₚ⁻¹ = I. An elastic evaluation copies the old history unchanged.

use super::hardening::Hardening;
use super::tensor::{check_f, from_voigt, rotate, t4_to_voigt, to_voigt, T4};
use super::{Kinematics, Material, MaterialError, StressPoint};
use nalgebra::{Matrix3, Vector3};

/// Number of history values per integration point.
pub const J2_N_STATE: usize = 7;

#[derive(Debug, Clone, PartialEq)]
pub struct J2Plasticity {
    /// Young's modulus (of the Hencky law).
    pub e: f64,
    /// Poisson's ratio.
    pub nu: f64,
    /// Flow stress as a function of ε̄ₚ.
    pub hardening: Hardening,
    /// Mass density.
    pub density: f64,
}

impl J2Plasticity {
    /// No validation here: the deck checks E > 0, −1 < ν < 1/2 and calls
    /// [`Hardening::validate`].
    pub fn new(e: f64, nu: f64, hardening: Hardening, density: f64) -> Self {
        Self {
            e,
            nu,
            hardening,
            density,
        }
    }

    fn g(&self) -> f64 {
        self.e / (2.0 * (1.0 + self.nu))
    }

    fn k(&self) -> f64 {
        self.e / (3.0 * (1.0 - 2.0 * self.nu))
    }

    /// Δγ from q_tr − 3GΔγ − σ_y(ε̄ₚ + Δγ) = 0, given Φ_tr > 0. Newton safeguarded by
    /// bisection on the bracket [0, q_tr/3G] where the residual changes sign.
    fn return_map(&self, q_tr: f64, ep_n: f64) -> Result<f64, MaterialError> {
        let g3 = 3.0 * self.g();
        let (mut lo, mut hi) = (0.0, q_tr / g3);
        let mut dg = 0.0;
        for _ in 0..200 {
            let (sy, h) = self.hardening.yield_stress(ep_n + dg);
            let r = q_tr - g3 * dg - sy;
            if r.abs() <= 1e-14 * q_tr {
                return Ok(dg);
            }
            if r > 0.0 {
                lo = dg;
            } else {
                hi = dg;
            }
            let d = g3 + h;
            let next = dg + r / d;
            dg = if d > 0.0 && next > lo && next < hi {
                next
            } else {
                0.5 * (lo + hi)
            };
            if hi - lo <= 1e-16 * hi {
                return Ok(dg);
            }
        }
        Err(MaterialError::ReturnMapping {
            model: "J2",
            q_trial: q_tr,
            plastic_strain: ep_n,
        })
    }
}

/// Whether a trial history `branch` returned to the surface from `old` (ε̄ₚ grew).
fn returned(old: &[f64], branch: &[f64]) -> bool {
    matches!((old.get(6), branch.get(6)), (Some(a), Some(b)) if b > a)
}

/// θ = y coth y (→ 1 as y → 0).
fn theta(y: f64) -> f64 {
    if y.abs() < 1e-4 {
        let y2 = y * y;
        1.0 + y2 / 3.0 - y2 * y2 / 45.0
    } else {
        y / y.tanh()
    }
}

/// Relative distance below the yield stress within which a previously plastic point
/// counts as on the surface for its tangent.
const ON_SURFACE: f64 = 1e-6;

impl J2Plasticity {
    /// Return mapping, history update, τ and, if `want_tangent`, c (zero otherwise).
    /// `forced`: the branch to take (true: plastic) instead of the one Φ_tr picks; see
    /// [`Material::evaluate_on`]. A forced plastic point below the surface takes the
    /// return map's linear extension Δγ = Φ_tr / (3G + h(ε̄ₚ)) ≤ 0, which meets the
    /// return map with its first derivative at Φ_tr = 0, so the stress is C¹ in F on
    /// either side.
    fn update(
        &self,
        f: &Matrix3<f64>,
        state_old: &[f64],
        state_new: &mut [f64],
        want_tangent: bool,
        forced: Option<bool>,
    ) -> Result<StressPoint, MaterialError> {
        check_f("J2", f)?;
        if state_old.len() < J2_N_STATE || state_new.len() < J2_N_STATE {
            return Err(MaterialError::HistoryLength {
                model: "J2",
                needs: J2_N_STATE,
                old: state_old.len(),
                new: state_new.len(),
            });
        }
        let old = &state_old[..J2_N_STATE];
        if old.iter().any(|x| !x.is_finite()) {
            return Err(MaterialError::NonFinite {
                model: "J2",
                what: "history",
            });
        }
        let cpi = if old[..6].iter().all(|&x| x == 0.0) {
            Matrix3::identity()
        } else {
            from_voigt(&old[..6])
        };
        let ep_n = old[6];
        let (kb, g) = (self.k(), self.g());

        // Trial elastic left Cauchy–Green tensor and its principal log strains.
        let be_tr = f * cpi * f.transpose();
        let be_tr = 0.5 * (be_tr + be_tr.transpose());
        let eig = be_tr.symmetric_eigen();
        let q = eig.eigenvectors;
        let lam2 = eig.eigenvalues;
        if lam2.iter().any(|&x| !(x.is_finite() && x > 0.0)) {
            return Err(MaterialError::NonPositiveStretch {
                model: "J2",
                eigenvalues: [lam2[0], lam2[1], lam2[2]],
            });
        }
        let eps_tr: Vector3<f64> = lam2.map(|x| 0.5 * x.ln());
        let vol = eps_tr.sum();
        let s_tr: Vector3<f64> = eps_tr.map(|x| 2.0 * g * (x - vol / 3.0));
        let s_norm = s_tr.norm();
        let q_tr = (1.5f64).sqrt() * s_norm;
        let (sy_n, _) = self.hardening.yield_stress(ep_n);

        let above = q_tr - sy_n > 1e-12 * sy_n.abs();
        // A forced plastic point needs a flow direction (s_tr ≠ 0).
        let plastic = forced.map_or(above, |p| p && q_tr > 1e-12 * sy_n.abs());
        let (dg, beta, coef_n, nhat) = if plastic {
            let (dg, h) = if above {
                let dg = self.return_map(q_tr, ep_n)?;
                (dg, self.hardening.yield_stress(ep_n + dg).1)
            } else {
                let (_, h) = self.hardening.yield_stress(ep_n);
                ((q_tr - sy_n) / (3.0 * g + h), h)
            };
            let beta = 1.0 - 3.0 * g * dg / q_tr;
            let coef = 6.0 * g * g * (dg / q_tr - 1.0 / (3.0 * g + h));
            (dg, beta, coef, s_tr / s_norm)
        } else if forced.is_none() && ep_n > 0.0 && q_tr >= sy_n * (1.0 - ON_SURFACE) {
            // At a converged plastic state (the first iteration of the next step starts
            // there): the stress is the trial one, but continued loading is plastic, so
            // the tangent is the elastoplastic one at Δγ = 0 (the continuum tangent)
            // rather than the elastic one, which would overshoot the first correction.
            let (_, h) = self.hardening.yield_stress(ep_n);
            let coef = -6.0 * g * g / (3.0 * g + h);
            (0.0, 1.0, coef, s_tr / s_norm)
        } else {
            (0.0, 1.0, 0.0, Vector3::zeros())
        };
        let tau_p: Vector3<f64> = s_tr.map(|s| beta * s + kb * vol);
        let tau = q * Matrix3::from_diagonal(&tau_p) * q.transpose();

        // History.
        if plastic {
            let eps_e: Vector3<f64> = s_tr.map(|s| vol / 3.0 + beta * s / (2.0 * g));
            let be = q * Matrix3::from_diagonal(&eps_e.map(|x| (2.0 * x).exp())) * q.transpose();
            let finv = f
                .try_inverse()
                .ok_or(MaterialError::SingularF { model: "J2" })?;
            let cpi_new = finv * be * finv.transpose();
            state_new[..6].copy_from_slice(&to_voigt(&cpi_new));
            state_new[6] = ep_n + dg;
        } else {
            state_new[..J2_N_STATE].copy_from_slice(old);
        }

        if !want_tangent {
            let stress = to_voigt(&tau);
            if stress.iter().any(|x| !x.is_finite()) {
                return Err(MaterialError::NonFinite {
                    model: "J2",
                    what: "stress",
                });
            }
            return Ok(StressPoint {
                stress,
                tangent: [[0.0; 6]; 6],
            });
        }

        // Tangent in the eigenbasis of the trial bₑ, then rotated.
        let mut c: T4 = [[[[0.0; 3]; 3]; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                let dev = if i == j { 2.0 / 3.0 } else { -1.0 / 3.0 };
                let mut v = kb + 2.0 * g * beta * dev + coef_n * nhat[i] * nhat[j];
                if i == j {
                    v -= 2.0 * tau_p[i];
                }
                c[i][i][j][j] = v;
                if i != j {
                    let s = g * beta * theta(eps_tr[i] - eps_tr[j]) - 0.5 * (tau_p[i] + tau_p[j]);
                    c[i][j][i][j] = s;
                    c[i][j][j][i] = s;
                }
            }
        }
        let c = rotate(&c, &q);

        let stress = to_voigt(&tau);
        let tangent = t4_to_voigt(&c);
        if stress
            .iter()
            .chain(tangent.iter().flatten())
            .any(|x| !x.is_finite())
        {
            return Err(MaterialError::NonFinite {
                model: "J2",
                what: "stress or tangent",
            });
        }
        Ok(StressPoint { stress, tangent })
    }
}

impl Material for J2Plasticity {
    fn kinematics(&self) -> Kinematics {
        Kinematics::Finite
    }

    fn n_state(&self) -> usize {
        J2_N_STATE
    }

    fn evaluate(
        &self,
        f: &Matrix3<f64>,
        state_old: &[f64],
        state_new: &mut [f64],
    ) -> Result<StressPoint, MaterialError> {
        self.update(f, state_old, state_new, true, None)
    }

    fn evaluate_stress(
        &self,
        f: &Matrix3<f64>,
        state_old: &[f64],
        state_new: &mut [f64],
    ) -> Result<[f64; 6], MaterialError> {
        Ok(self.update(f, state_old, state_new, false, None)?.stress)
    }

    /// Plastic where the last natural evaluation returned (ε̄ₚ grew), elastic elsewhere.
    fn evaluate_on(
        &self,
        f: &Matrix3<f64>,
        state_old: &[f64],
        branch: &[f64],
        state_new: &mut [f64],
    ) -> Result<StressPoint, MaterialError> {
        self.update(
            f,
            state_old,
            state_new,
            true,
            Some(returned(state_old, branch)),
        )
    }

    fn evaluate_stress_on(
        &self,
        f: &Matrix3<f64>,
        state_old: &[f64],
        branch: &[f64],
        state_new: &mut [f64],
    ) -> Result<[f64; 6], MaterialError> {
        let plastic = Some(returned(state_old, branch));
        Ok(self.update(f, state_old, state_new, false, plastic)?.stress)
    }

    fn equivalent_plastic_strain(&self, state: &[f64]) -> Option<f64> {
        state.get(6).copied()
    }

    /// Hencky's volumetric part τ_vol = K ln J I (plastic flow is isochoric, so J_e = J):
    /// U = K/2 (ln J)², U' = K ln J / J, U'' = K (1 − ln J) / J².
    fn volumetric(&self, j: f64) -> Option<(f64, f64)> {
        let k = self.k();
        let l = j.ln();
        Some((k * l / j, k * (1.0 - l) / (j * j)))
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
    use super::super::testing::{asymmetry, objectivity_error, rotation, tangent_error, tau};
    use super::super::LinearElastic;
    use super::*;

    const E: f64 = 210e3;
    const NU: f64 = 0.3;
    const SY0: f64 = 250.0;
    const H: f64 = 2000.0;

    /// At a converged plastic state the tangent is the elastoplastic one (continued
    /// loading is plastic): it matches a forward difference along the loading path,
    /// and differs from the elastic tangent.
    #[test]
    fn tangent_at_a_converged_plastic_state_is_elastoplastic() {
        let m = linear();
        let f = diag(1.01, 0.996, 0.996);
        let (_, state) = eval(&m, &f, &[0.0; J2_N_STATE]);
        assert!(state[6] > 0.0);
        let (sp, again) = eval(&m, &f, &state);
        assert_eq!(&again[..], &state[..], "no new plastic flow at the same F");
        // Forward difference along d = diag(1, −½, −½) (isochoric uniaxial loading).
        let eps = 1e-7;
        let d = diag(1.0, -0.5, -0.5);
        let (sp2, _) = eval(&m, &((Matrix3::identity() + d * eps) * f), &state);
        let t = |s: &[f64; 6]| Matrix3::new(s[0], s[3], s[5], s[3], s[1], s[4], s[5], s[4], s[2]);
        let (t0, t1) = (t(&sp.stress), t(&sp2.stress));
        let rate = (t1 - t0) / eps - (d * t0 + t0 * d);
        // c:d with engineering Voigt columns (d has no shear).
        let dv = [1.0, -0.5, -0.5];
        let cd: Vec<f64> = (0..3)
            .map(|r| (0..3).map(|c| sp.tangent[r][c] * dv[c]).sum())
            .collect();
        for r in 0..3 {
            assert!(
                (cd[r] - rate[(r, r)]).abs() < 1e-4 * E,
                "row {r}: tangent {} vs forward difference {}",
                cd[r],
                rate[(r, r)]
            );
        }
        // The elastic tangent's c_xxxx is about K + 4G/3; the elastoplastic one far less.
        assert!((sp.tangent[0][0] - (m.k() + 4.0 / 3.0 * m.g())).abs() > 0.1 * E);
    }

    /// JFNK's frozen products (`evaluate_stress_on`): on the iterate's plastic branch
    /// the stress stays on that branch past the yield surface (the return map's linear
    /// extension), so a one-sided difference across the surface is the consistent
    /// tangent's product; the natural evaluation's difference is not. At the iterate
    /// itself both agree exactly, and an elastic branch gives the trial stress.
    #[test]
    fn frozen_branch_difference_is_the_tangent_across_the_surface() {
        let m = power();
        let d = diag(1.0, -0.5, -0.5);
        let f0 = diag(1.01, 0.996, 0.996);
        let (_, old) = eval(&m, &f0, &[0.0; J2_N_STATE]);
        // A little further along the loading path: plastic, about 5 MPa over the surface.
        let f = (Matrix3::identity() + d * 2e-5) * f0;
        let (sp, branch) = eval(&m, &f, &old);
        assert!(branch[6] > old[6], "the iterate is plastic");
        let mut scratch = [0.0; J2_N_STATE];
        let on = m
            .evaluate_stress_on(&f, &old, &branch, &mut scratch)
            .unwrap();
        assert_eq!(
            on, sp.stress,
            "the frozen branch at the iterate is the natural one"
        );
        // Unloading by twice that: the natural evaluation turns elastic halfway.
        let (h, l) = (4e-5, -d);
        let fh = (Matrix3::identity() + l * h) * f;
        let (_, natural_new) = eval(&m, &fh, &old);
        assert_eq!(natural_new[6], old[6], "the perturbed state is elastic");
        let t0 = from_voigt(&sp.stress);
        let rate = |s: [f64; 6]| (from_voigt(&s) - t0) / h;
        // c:sym(L) + Lτ + τLᵀ with engineering shear (L is diagonal here).
        let lv = [l[(0, 0)], l[(1, 1)], l[(2, 2)]];
        let want = Matrix3::from_fn(|r, c| {
            if r != c {
                return 0.0;
            }
            (0..3).map(|k| sp.tangent[r][k] * lv[k]).sum::<f64>() + 2.0 * lv[r] * t0[(r, r)]
        });
        let err = |got: Matrix3<f64>| (got - want).amax() / want.amax();
        let frozen = m
            .evaluate_stress_on(&fh, &old, &branch, &mut scratch)
            .unwrap();
        assert!(
            scratch[6] < old[6],
            "below the surface the extension returns Δγ < 0"
        );
        let natural = m.evaluate_stress(&fh, &old, &mut scratch).unwrap();
        // 1e-2: the hardening modulus changes along the path (power law), a second-order
        // term (3.5e-3 here); across the kink the natural one is 32 (3200 %).
        assert!(
            err(rate(frozen)) < 1e-2,
            "frozen: {:.2e}",
            err(rate(frozen))
        );
        assert!(
            err(rate(natural)) > 0.1,
            "natural: {:.2e}",
            err(rate(natural))
        );
        // On the elastic branch (the committed history) the stress is the trial one,
        // outside the surface the natural return lands on.
        let elastic = m.evaluate_stress_on(&f, &old, &old, &mut scratch).unwrap();
        assert_eq!(scratch[6], old[6]);
        let mises = |s: &[f64; 6]| {
            let t = from_voigt(s);
            let dev = t - Matrix3::identity() * (t.trace() / 3.0);
            (1.5 * dev.norm_squared()).sqrt()
        };
        let (sy, _) = m.hardening.yield_stress(branch[6]);
        assert!((mises(&sp.stress) - sy).abs() < 1e-9 * sy);
        assert!(mises(&elastic) > sy + 1.0, "{} vs {sy}", mises(&elastic));
    }

    /// Power-law hardening σ_y = σ_y0 + 400 ε̄ₚ^0.25 (nonlinear h).
    fn power() -> J2Plasticity {
        J2Plasticity::new(
            E,
            NU,
            Hardening::Power {
                sigma_y0: SY0,
                k: 400.0,
                n: 0.25,
            },
            1.0,
        )
    }

    fn linear() -> J2Plasticity {
        J2Plasticity::new(
            E,
            NU,
            Hardening::Linear {
                sigma_y0: SY0,
                h: H,
            },
            7.8e-9,
        )
    }

    fn diag(a: f64, b: f64, c: f64) -> Matrix3<f64> {
        Matrix3::from_diagonal(&Vector3::new(a, b, c))
    }

    fn eval(m: &J2Plasticity, f: &Matrix3<f64>, old: &[f64]) -> (StressPoint, Vec<f64>) {
        let mut new = vec![f64::NAN; J2_N_STATE];
        let sp = m.evaluate(f, old, &mut new).unwrap();
        (sp, new)
    }

    /// Uniaxial stress at axial stretch `lam`: Newton on the lateral stretch μ for
    /// τ_yy = 0 (F = diag(λ, μ, μ)), from the committed history `old`. Returns
    /// (τ_xx, μ, trial history).
    fn uniaxial(m: &J2Plasticity, lam: f64, mu0: f64, old: &[f64]) -> (f64, f64, Vec<f64>) {
        let mut mu = mu0;
        for _ in 0..60 {
            let (sp, new) = eval(m, &diag(lam, mu, mu), old);
            let r = sp.stress[1];
            if r.abs() < 1e-11 * SY0 {
                return (sp.stress[0], mu, new);
            }
            let dr = (sp.tangent[1][1] + sp.tangent[1][2] + 2.0 * r) / mu;
            mu -= r / dr;
        }
        panic!("lateral Newton did not converge at λ = {lam}");
    }

    fn det_cpi(state: &[f64]) -> f64 {
        from_voigt(&state[..6]).determinant()
    }

    /// Committed state after a non-proportional plastic path (stretch, then shear).
    fn loaded_state(m: &J2Plasticity) -> (Matrix3<f64>, Vec<f64>) {
        let mut old = vec![0.0; J2_N_STATE];
        let mut f = Matrix3::identity();
        for k in 1..=10 {
            let t = k as f64 / 10.0;
            f = diag(1.0 + 0.05 * t, 1.0 - 0.01 * t, 1.0);
            f[(0, 1)] = 0.04 * t * t;
            f[(2, 0)] = -0.02 * t;
            old = eval(m, &f, &old).1;
        }
        assert!(old[6] > 0.01, "path must be plastic: ε̄p = {}", old[6]);
        (f, old)
    }

    #[test]
    fn virgin_state_and_moduli() {
        let m = linear();
        assert_eq!(m.n_state(), 7);
        let (sp, new) = eval(&m, &Matrix3::identity(), &[0.0; 7]);
        assert!(sp.stress.iter().all(|s| s.abs() < 1e-12), "{:?}", sp.stress);
        assert_eq!(new, vec![0.0; 7]);
        // All-zero history is the same as an explicit identity Cp⁻¹.
        let f = diag(1.3, 0.9, 0.95);
        let a = tau(&m, &f, &[0.0; 7]);
        let b = tau(&m, &f, &[1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0]);
        assert_eq!(a, b);
        assert_eq!(
            m.equivalent_plastic_strain(&[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.25]),
            Some(0.25)
        );
        let le = LinearElastic::new(E, NU, 1.0);
        assert!((m.shear_modulus() - le.shear_modulus()).abs() < 1e-9);
        assert!((m.bulk_modulus() - le.bulk_modulus()).abs() < 1e-9);
    }

    /// (a) Below yield: Hencky elasticity τ = K tr(ε) I + 2G dev(ε), ε = ½ ln b, and the
    /// history is unchanged.
    #[test]
    fn below_yield_is_hencky_elastic() {
        let m = linear();
        let (f0, old) = loaded_state(&m);
        // Virgin state, small finite strain with rotation.
        let f = rotation()
            * diag(1.0008, 0.9995, 1.0002)
            * Matrix3::new(1.0, 2e-4, 0.0, 0.0, 1.0, -3e-4, 0.0, 0.0, 1.0);
        let (sp, new) = eval(&m, &f, &[0.0; 7]);
        assert_eq!(new, vec![0.0; 7]);
        let b = f * f.transpose();
        let eig = b.symmetric_eigen();
        let ln = eig.eigenvectors
            * Matrix3::from_diagonal(&eig.eigenvalues.map(|x| 0.5 * x.ln()))
            * eig.eigenvectors.transpose();
        let tr = ln.trace();
        let want = Matrix3::identity() * (m.k() * tr)
            + 2.0 * m.g() * (ln - Matrix3::identity() * (tr / 3.0));
        let got = from_voigt(&sp.stress);
        let q = (1.5f64).sqrt() * (got - Matrix3::identity() * (got.trace() / 3.0)).norm();
        assert!(
            q < SY0 && q > 0.2 * SY0,
            "test must be elastic but not trivial: q = {q}"
        );
        assert!((got - want).abs().max() < 1e-9 * SY0, "{got} vs {want}");
        // From a committed plastic state, a small elastic step back keeps history.
        let fb = diag(0.9995, 1.0, 1.0) * f0;
        let (_, new) = eval(&m, &fb, &old);
        assert_eq!(new, old);
    }

    #[test]
    fn small_strain_limit_is_hooke() {
        let m = linear();
        let le = LinearElastic::new(E, NU, 1.0);
        let mut f = Matrix3::identity();
        f[(0, 0)] += 1e-7;
        f[(1, 1)] -= 3e-8;
        f[(0, 1)] += 2e-7;
        f[(1, 0)] += 1e-7;
        f[(2, 1)] += 5e-8;
        let (a, _) = eval(&m, &f, &[0.0; 7]);
        let b = le.evaluate(&f, &[], &mut []).unwrap();
        for (x, y) in a.stress.iter().zip(&b.stress) {
            assert!(
                (x - y).abs() < 1e-12 * E,
                "{:?} vs {:?}",
                a.stress,
                b.stress
            );
        }
        let (c0, _) = eval(&m, &Matrix3::identity(), &[0.0; 7]);
        for (x, y) in c0
            .tangent
            .iter()
            .flatten()
            .zip(le.tangent().iter().flatten())
        {
            assert!((x - y).abs() < 1e-12 * E, "{:?}", c0.tangent);
        }
    }

    /// (b) + (c) Uniaxial tension by an axial log-strain path to 1.0, lateral stretch
    /// solved for zero lateral stress, history committed each increment. Closed form
    /// with σ_y = σ_y0 + h ε̄p: τ_xx = σ_y(ε̄p), ε = τ_xx/E + ε̄p, so beyond yield
    /// ε̄p = (ε − σ_y0/E)/(1 + h/E) (uniaxial slope E h/(E + h)). Plastic
    /// incompressibility: det Cp⁻¹ = 1 and ln μ = −ν τ/E − ε̄p/2.
    #[test]
    fn uniaxial_tension_linear_hardening_closed_form() {
        let m = linear();
        let mut old = vec![0.0; J2_N_STATE];
        let mut mu = 1.0;
        let mut worst = 0.0_f64;
        let n = 200;
        for k in 1..=n {
            let eps = 1.0 * k as f64 / n as f64;
            let (t, mu_k, new) = uniaxial(&m, eps.exp(), mu, &old);
            mu = mu_k;
            old = new;
            let ep = ((eps - SY0 / E) / (1.0 + H / E)).max(0.0);
            let want = if ep > 0.0 { SY0 + H * ep } else { E * eps };
            let rel = (t - want).abs() / want;
            worst = worst.max(rel);
            assert!(
                rel < 1e-8,
                "ε = {eps}: τ = {t}, closed form {want} ({rel:.2e})"
            );
            assert!(
                (old[6] - ep).abs() < 1e-8 * ep.max(1e-3),
                "ε = {eps}: ε̄p = {} vs {ep}",
                old[6]
            );
            assert!(
                (mu.ln() - (-NU * t / E - 0.5 * ep)).abs() < 1e-10,
                "lateral stretch"
            );
            assert!(
                (det_cpi(&old) - 1.0).abs() < 1e-12,
                "det Cp⁻¹ = {}",
                det_cpi(&old)
            );
        }
        assert!(old[6] > 0.98, "ε̄p = {}", old[6]);
    }

    /// Same with a single huge increment from the virgin state: radial return is exact
    /// for this proportional path, whatever the step.
    #[test]
    fn uniaxial_one_step_is_exact() {
        let m = linear();
        let eps: f64 = 0.7;
        let (t, _, st) = uniaxial(&m, eps.exp(), 1.0, &[0.0; 7]);
        let ep = (eps - SY0 / E) / (1.0 + H / E);
        assert!((t - (SY0 + H * ep)).abs() < 1e-8 * t);
        assert!((st[6] - ep).abs() < 1e-8 * ep);
    }

    /// (c) Large simple shear (γ up to 3 in 300 steps): no failure, det Cp⁻¹ = 1.
    #[test]
    fn large_simple_shear_keeps_plastic_incompressibility() {
        for m in [linear(), power()] {
            let mut old = vec![0.0; J2_N_STATE];
            let n = 300;
            for k in 1..=n {
                let mut f = Matrix3::identity();
                f[(0, 1)] = 3.0 * k as f64 / n as f64;
                let (sp, new) = eval(&m, &f, &old);
                assert!(sp.stress.iter().all(|s| s.is_finite()));
                assert!(new[6] >= old[6]);
                old = new;
                assert!(
                    (det_cpi(&old) - 1.0).abs() < 1e-12,
                    "step {k}: det Cp⁻¹ = {}",
                    det_cpi(&old)
                );
            }
            // ε̄p is path-integrated: close to ∫ √(2/3)|d| dt = γ/√3 = 1.732 at γ = 3
            // (above the final equivalent log strain 2/√3 asinh(γ/2) = 1.38, since
            // the principal axes rotate), minus a small elastic part.
            let eq_rate = 3.0 / 3f64.sqrt();
            assert!(
                old[6] > 0.98 * eq_rate && old[6] < eq_rate,
                "ε̄p = {} vs {eq_rate}",
                old[6]
            );
        }
    }

    /// (e) Unloading from a plastic state is elastic: ε̄p and Cp⁻¹ unchanged, Δτ = E Δε.
    #[test]
    fn unloading_is_elastic() {
        let m = linear();
        let mut old = vec![0.0; J2_N_STATE];
        let mut mu = 1.0;
        let mut eps = 0.0;
        for _ in 0..20 {
            eps += 0.01;
            let (_, mk, new) = uniaxial(&m, f64::exp(eps), mu, &old);
            mu = mk;
            old = new;
        }
        let (t0, _, _) = uniaxial(&m, f64::exp(eps), mu, &old);
        for k in 1..=5 {
            let de = -0.0002 * k as f64;
            let (t, _, new) = uniaxial(&m, f64::exp(eps + de), mu, &old);
            assert_eq!(new, old, "history must not change on unloading");
            assert!(
                ((t - t0) - E * de).abs() < 1e-9 * t0,
                "Δτ = {} vs {}",
                t - t0,
                E * de
            );
            // The tangent on unloading is the elastic one.
            let (sp, _) = eval(&m, &diag(f64::exp(eps + de), mu, mu), &old);
            let (spe, _) = eval(
                &J2Plasticity::new(
                    E,
                    NU,
                    Hardening::Linear {
                        sigma_y0: 1e9,
                        h: 0.0,
                    },
                    1.0,
                ),
                &diag(f64::exp(eps + de), mu, mu),
                &old,
            );
            assert_eq!(sp.tangent, spe.tangent);
        }
        // Reloading past the previous maximum yields again.
        let (_, _, new) = uniaxial(&m, f64::exp(eps + 0.01), mu, &old);
        assert!(new[6] > old[6]);
    }

    #[test]
    fn tangent_matches_finite_difference_virgin() {
        let m = linear();
        let mut shear = Matrix3::identity();
        shear[(0, 1)] = 0.8;
        let fs = [
            Matrix3::identity(),
            diag(1.0005, 0.9999, 1.0),                       // elastic
            diag(2.0, 1.0 / 2f64.sqrt(), 1.0 / 2f64.sqrt()), // repeated eigenvalues
            diag(2.0, 1.0, 1.0),
            diag(0.5, 2f64.sqrt(), 2f64.sqrt()),
            diag(0.5, 0.9, 1.1),
            shear,
            Matrix3::new(1.3, 0.2, -0.1, 0.15, 0.8, 0.3, -0.05, 0.1, 1.1),
        ];
        for f in fs {
            let err = tangent_error(&m, &f, &[0.0; 7]);
            assert!(err < 1e-6, "F = {f}: rel err {err:.2e}");
        }
    }

    /// Consistent tangent during plastic loading from a non-trivial committed state
    /// (Cp⁻¹ ≠ I, not coaxial with the new step), linear and power-law hardening, and
    /// on elastic unloading from it.
    #[test]
    fn tangent_matches_finite_difference_from_committed_state() {
        let tab = J2Plasticity::new(
            E,
            NU,
            Hardening::Tabulated {
                points: vec![[0.0, SY0], [0.01, 300.0], [0.5, 450.0]],
            },
            1.0,
        );
        for m in [linear(), power(), tab] {
            let (f0, old) = loaded_state(&m);
            let mut steps = vec![];
            let mut g = Matrix3::identity();
            g[(1, 2)] = 0.01;
            steps.push(g * f0);
            steps.push(diag(1.01, 0.995, 0.998) * f0);
            steps.push(rotation() * diag(1.3, 0.85, 0.95) * f0);
            for f in steps {
                let (_, new) = eval(&m, &f, &old);
                assert!(new[6] > old[6], "step must be plastic");
                let err = tangent_error(&m, &f, &old);
                assert!(err < 1e-5, "{:?} F = {f}: rel err {err:.2e}", m.hardening);
                let (sp, _) = eval(&m, &f, &old);
                assert!(asymmetry(&sp.tangent) < 1e-12, "tangent not symmetric");
            }
            // Elastic unloading step.
            let f = diag(0.9997, 1.0, 1.0) * f0;
            let (_, new) = eval(&m, &f, &old);
            assert_eq!(new, old);
            let err = tangent_error(&m, &f, &old);
            assert!(err < 1e-6, "unloading: rel err {err:.2e}");
        }
    }

    /// The tangent check must be able to fail: the finite-difference tangent of a model
    /// with half the hardening modulus matches its own tangent but not this model's.
    #[test]
    fn tangent_check_detects_wrong_tangent() {
        let m = linear();
        let (f0, old) = loaded_state(&m);
        let f = diag(1.01, 0.995, 0.998) * f0;
        let (sp, _) = eval(&m, &f, &old);
        let other = J2Plasticity::new(
            E,
            NU,
            Hardening::Linear {
                sigma_y0: SY0,
                h: 0.5 * H,
            },
            1.0,
        );
        let (sp2, _) = eval(&other, &f, &old);
        let fd = super::super::testing::fd_tangent(&other, &f, &old, 1e-6);
        assert!(super::super::testing::rel_err(&sp2.tangent, &fd) < 1e-5);
        assert!(super::super::testing::rel_err(&sp.tangent, &fd) > 1e-5);
    }

    #[test]
    fn objectivity_with_history() {
        let m = linear();
        let (f0, old) = loaded_state(&m);
        for f in [diag(1.02, 0.99, 1.0) * f0, diag(2.0, 0.7, 0.7), f0] {
            let e = objectivity_error(&m, &f, &old);
            assert!(e < 1e-11, "F = {f}: {e:.2e}");
            let (_, a) = eval(&m, &f, &old);
            let (_, b) = eval(&m, &(rotation() * f), &old);
            for (x, y) in a.iter().zip(&b) {
                assert!(
                    (x - y).abs() < 1e-12 * x.abs().max(1.0),
                    "history {a:?} vs {b:?}"
                );
            }
        }
    }

    #[test]
    fn bad_input_is_error_not_panic() {
        let m = linear();
        let mut new = [0.0; 7];
        assert!(m
            .evaluate(&diag(1.0, 1.0, -0.5), &[0.0; 7], &mut new)
            .is_err());
        assert!(m
            .evaluate(&diag(1.0, f64::NAN, 1.0), &[0.0; 7], &mut new)
            .is_err());
        let mut bad = [0.0; 7];
        bad[6] = f64::INFINITY;
        assert!(m.evaluate(&Matrix3::identity(), &bad, &mut new).is_err());
        // Indefinite Cp⁻¹.
        let bad = [1.0, -1.0, 1.0, 0.0, 0.0, 0.0, 0.0];
        assert!(m.evaluate(&Matrix3::identity(), &bad, &mut new).is_err());
        assert!(m
            .evaluate(&Matrix3::identity(), &[0.0; 3], &mut new)
            .is_err());
    }
}
