//! The generalized-α family (Chung & Hulbert 1993) in the force-averaged form
//!
//!   M a_{n+1−α_m} + (1−α_f) R(u_{n+1}, t_{n+1}) + α_f R(u_n, t_n) = 0,
//!   a_{n+1−α_m} = (1−α_m) a_{n+1} + α_m a_n,   R = f_int − f_ext,
//!
//! with the Newmark relations
//!
//!   u_{n+1} = u_n + Δt v_n + Δt² ((½ − β) a_n + β a_{n+1}),
//!   v_{n+1} = v_n + Δt ((1 − γ) a_n + γ a_{n+1}).
//!
//! The unknown is u_{n+1}; a_{n+1} and v_{n+1} follow from it, so ∂r/∂u_{n+1} =
//! c_M M + (1−α_f) K with c_M = (1−α_m)/(β Δt²). History materials are evaluated at
//! u_{n+1} only (R(u_n) is the stored value of the last step).
//!
//! Parameters from the spectral radius at infinite frequency ρ∞ ∈ [0, 1] (second-order
//! accurate, unconditionally stable, high-frequency dissipation maximal for the given
//! low-frequency dissipation): α_m = (2ρ∞ − 1)/(ρ∞ + 1), α_f = ρ∞/(ρ∞ + 1),
//! γ = ½ − α_m + α_f, β = ¼ (1 − α_m + α_f)². Newmark's trapezoidal rule is
//! α_m = α_f = 0, β = ¼, γ = ½; HHT-α is α_m = 0, α_f = (1 − ρ∞)/(1 + ρ∞) ∈ [0, ⅓],
//! γ = ½ + α_f, β = ¼ (1 + α_f)².

/// Parameters of one member of the family.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AlphaParams {
    pub alpha_m: f64,
    pub alpha_f: f64,
    pub beta: f64,
    pub gamma: f64,
}

impl AlphaParams {
    pub fn newmark() -> Self {
        Self {
            alpha_m: 0.0,
            alpha_f: 0.0,
            beta: 0.25,
            gamma: 0.5,
        }
    }
    pub fn generalized_alpha(rho_inf: f64) -> Self {
        let am = (2.0 * rho_inf - 1.0) / (rho_inf + 1.0);
        let af = rho_inf / (rho_inf + 1.0);
        Self {
            alpha_m: am,
            alpha_f: af,
            gamma: 0.5 - am + af,
            beta: 0.25 * (1.0 - am + af).powi(2),
        }
    }
    pub fn hht(rho_inf: f64) -> Self {
        let af = (1.0 - rho_inf) / (1.0 + rho_inf);
        Self {
            alpha_m: 0.0,
            alpha_f: af,
            gamma: 0.5 + af,
            beta: 0.25 * (1.0 + af).powi(2),
        }
    }
    /// Wood–Bossak–Zienkiewicz (Bossak-α): α_f = 0, α_m = (ρ∞ − 1)/(ρ∞ + 1) ∈ [−1, 0],
    /// γ = ½ − α_m, β = ¼ (1 − α_m)². Forces are taken at t_{n+1} only (no averaging),
    /// which contact needs: with α_f > 0 the last step's contact impulse re-enters the
    /// balance and an impacting foot chatters on and off the wall.
    pub fn bossak(rho_inf: f64) -> Self {
        let am = (rho_inf - 1.0) / (rho_inf + 1.0);
        Self {
            alpha_m: am,
            alpha_f: 0.0,
            gamma: 0.5 - am,
            beta: 0.25 * (1.0 - am).powi(2),
        }
    }
    /// c_M = ∂a_{n+1−α_m}/∂u_{n+1} = (1−α_m)/(β Δt²).
    pub fn c_m(&self, dt: f64) -> f64 {
        (1.0 - self.alpha_m) / (self.beta * dt * dt)
    }
    /// a_{n+1} from u_{n+1} (Newmark displacement relation solved for it).
    #[inline]
    pub fn acceleration(&self, dt: f64, u1: f64, u: f64, v: f64, a: f64) -> f64 {
        (u1 - u - dt * v) / (self.beta * dt * dt) - (0.5 / self.beta - 1.0) * a
    }
    /// v_{n+1} from a_{n+1}.
    #[inline]
    pub fn velocity(&self, dt: f64, v: f64, a: f64, a1: f64) -> f64 {
        v + dt * ((1.0 - self.gamma) * a + self.gamma * a1)
    }
    /// The α_m-point acceleration.
    #[inline]
    pub fn mid_acceleration(&self, a: f64, a1: f64) -> f64 {
        (1.0 - self.alpha_m) * a1 + self.alpha_m * a
    }
    /// A predictor for u_{n+1}: the Newmark displacement with a_{n+1} = a_n.
    #[inline]
    pub fn predict(&self, dt: f64, u: f64, v: f64, a: f64) -> f64 {
        u + dt * v + 0.5 * dt * dt * a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One step of m ü + k u = 0 with the force-averaged residual, solved exactly for
    /// u_{n+1} (it is linear), using the same update formulas as the FE integrator.
    fn step(p: &AlphaParams, w: f64, dt: f64, s: (f64, f64, f64)) -> (f64, f64, f64) {
        let (u, v, a) = s;
        let (m, k) = (1.0, w * w);
        // r(u1) = m [(1−α_m) a1(u1) + α_m a] + (1−α_f) k u1 + α_f k u, a1 affine in u1.
        let r = |u1: f64| {
            let a1 = p.acceleration(dt, u1, u, v, a);
            m * p.mid_acceleration(a, a1) + (1.0 - p.alpha_f) * k * u1 + p.alpha_f * k * u
        };
        let u0 = p.predict(dt, u, v, a);
        let slope = p.c_m(dt) * m + (1.0 - p.alpha_f) * k;
        let u1 = u0 - r(u0) / slope;
        let a1 = p.acceleration(dt, u1, u, v, a);
        (u1, p.velocity(dt, v, a, a1), a1)
    }

    /// Spectral radius of the one-step map (largest |eigenvalue| of the 3×3 amplification
    /// matrix, from its columns = steps of the unit states).
    fn spectral_radius(p: &AlphaParams, w: f64, dt: f64) -> f64 {
        let cols = [
            step(p, w, dt, (1.0, 0.0, 0.0)),
            step(p, w, dt, (0.0, 1.0, 0.0)),
            step(p, w, dt, (0.0, 0.0, 1.0)),
        ];
        let a = nalgebra::Matrix3::from_fn(|i, j| match i {
            0 => cols[j].0,
            1 => cols[j].1,
            _ => cols[j].2,
        });
        a.complex_eigenvalues()
            .iter()
            .map(|z| z.norm())
            .fold(0.0, f64::max)
    }

    /// Amplitude after `periods` free periods from u = 1, v = 0, a = −ω²: the ratio of
    /// the energy-norm amplitude √(u² + (v/ω)²).
    fn amplitude_ratio(p: &AlphaParams, w: f64, dt: f64, periods: usize) -> f64 {
        let n = (periods as f64 * 2.0 * std::f64::consts::PI / (w * dt)).round() as usize;
        let mut s = (1.0, 0.0, -w * w);
        for _ in 0..n {
            s = step(p, w, dt, s);
        }
        (s.0 * s.0 + (s.1 / w).powi(2)).sqrt()
    }

    #[test]
    fn generalized_alpha_damps_high_frequencies_to_rho_inf() {
        for rho in [0.0, 0.5, 0.9] {
            let p = AlphaParams::generalized_alpha(rho);
            // ωΔt ≫ 1: the per-step amplification approaches ρ∞.
            let r = spectral_radius(&p, 1e6, 1.0);
            assert!((r - rho).abs() < 1e-3, "rho_inf {rho}: spectral radius {r}");
            // ωΔt = 2π/200: low modes keep their amplitude (< 0.1% loss per period).
            let low = amplitude_ratio(&p, 1.0, 2.0 * std::f64::consts::PI / 200.0, 10);
            let per_period = 1.0 - low.powf(0.1);
            assert!(
                per_period < 1e-3,
                "rho_inf {rho}: {per_period:e} per period"
            );
        }
        let h = AlphaParams::hht(0.5);
        let r = spectral_radius(&h, 1e6, 1.0);
        assert!((r - 0.5).abs() < 2e-3, "HHT spectral radius {r}");
        for rho in [0.5, 0.8] {
            let b = AlphaParams::bossak(rho);
            let r = spectral_radius(&b, 1e6, 1.0);
            assert!(
                (r - rho).abs() < 2e-3,
                "Bossak rho_inf {rho}: spectral radius {r}"
            );
        }
    }

    #[test]
    fn trapezoidal_rule_conserves_amplitude_at_any_step() {
        let p = AlphaParams::newmark();
        for wdt in [0.01, 1.0, 1e3] {
            let r = spectral_radius(&p, wdt, 1.0);
            assert!((r - 1.0).abs() < 1e-9, "ωΔt {wdt}: {r}");
        }
        // ρ∞ = 1 generalized-α is non-dissipative too.
        let g = AlphaParams::generalized_alpha(1.0);
        assert!((spectral_radius(&g, 1e3, 1.0) - 1.0).abs() < 1e-6);
        // The trapezoidal rule's period elongation (ωΔt)²/12 (Hughes, Table 9.3.1): the
        // phase after one nominal period is 2π − 2π(ωΔt)²/12 to leading order.
        let (w, dt) = (1.0, 2.0 * std::f64::consts::PI / 40.0);
        let n = 40;
        let mut s = (1.0, 0.0, -1.0);
        for _ in 0..n {
            s = step(&p, w, dt, s);
        }
        let phase = (-s.1 / w).atan2(s.0);
        let expected = -2.0 * std::f64::consts::PI * (w * dt).powi(2) / 12.0;
        assert!(
            (phase - expected).abs() < 0.05 * expected.abs(),
            "phase {phase} vs {expected}"
        );
    }
}
