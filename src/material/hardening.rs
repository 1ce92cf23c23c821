//! Isotropic hardening laws σ_y(ε̄_p) for [`super::J2Plasticity`].
//!
//! All laws are functions of the equivalent plastic strain ε̄_p ≥ 0 and return the
//! flow stress and its slope, which the return mapping and the consistent tangent use
//! together (value and slope are always mutually consistent, including the capped
//! power-law start, so the local Newton converges quadratically).

/// Below this ε̄_p the power law is replaced by its secant from ε̄_p = 0, so the slope
/// stays finite for n < 1 (where k n ε̄_p^(n−1) → ∞): for ε̄_p < `POWER_EP0`,
/// σ_y = σ_y0 + k POWER_EP0^n (ε̄_p / POWER_EP0), slope k POWER_EP0^(n−1). The value is
/// continuous at POWER_EP0 and differs from the pure power law by at most
/// k POWER_EP0^n (≈ 6.3e-2 k for n = 0.2, 1e-6 k for n = 1 where it is exact).
pub const POWER_EP0: f64 = 1e-6;

#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Hardening {
    /// σ_y = σ_y0 + h ε̄_p. In uniaxial tension (log strain, Kirchhoff stress) the
    /// elastic-plastic slope is E h / (E + h): the axial stress equals σ_y(ε̄_p) and
    /// the axial log strain is σ/E + ε̄_p.
    Linear { sigma_y0: f64, h: f64 },
    /// σ_y = σ_y0 + k ε̄_p^n, 0 < n ≤ 1; see [`POWER_EP0`] for the start.
    Power { sigma_y0: f64, k: f64, n: f64 },
    /// Piecewise-linear (ε̄_p, σ_y) points; the first ε̄_p must be 0. Beyond the last
    /// point the last segment's slope is extrapolated (a single point means perfectly
    /// plastic). At a breakpoint the slope of the segment to the right is used.
    Tabulated { points: Vec<[f64; 2]> },
}

impl Hardening {
    /// Flow stress and its slope dσ_y/dε̄_p at equivalent plastic strain `ep` (≥ 0;
    /// negative values are treated as 0).
    pub fn yield_stress(&self, ep: f64) -> (f64, f64) {
        let ep = ep.max(0.0);
        match self {
            Hardening::Linear { sigma_y0, h } => (sigma_y0 + h * ep, *h),
            Hardening::Power { sigma_y0, k, n } => {
                if ep < POWER_EP0 {
                    let slope = k * POWER_EP0.powf(n - 1.0);
                    (sigma_y0 + slope * ep, slope)
                } else {
                    (sigma_y0 + k * ep.powf(*n), k * n * ep.powf(n - 1.0))
                }
            }
            Hardening::Tabulated { points } => {
                let np = points.len();
                if np == 1 {
                    return (points[0][1], 0.0);
                }
                // Segment index: last i with points[i].ε ≤ ep, capped at np − 2.
                let i = points[1..np - 1].iter().take_while(|p| p[0] <= ep).count();
                let ([e0, s0], [e1, s1]) = (points[i], points[i + 1]);
                let slope = (s1 - s0) / (e1 - e0);
                (s0 + slope * (ep - e0), slope)
            }
        }
    }

    /// Checks the parameters; messages name the offending value.
    pub fn validate(&self) -> Result<(), String> {
        let finite = |name: &str, x: f64| {
            if x.is_finite() {
                Ok(())
            } else {
                Err(format!("hardening: {name} = {x} is not finite"))
            }
        };
        match self {
            Hardening::Linear { sigma_y0, h } => {
                finite("sigma_y0", *sigma_y0)?;
                finite("h", *h)?;
                if *sigma_y0 <= 0.0 {
                    return Err(format!(
                        "linear hardening: sigma_y0 = {sigma_y0} must be > 0"
                    ));
                }
                if *h < 0.0 {
                    return Err(format!(
                        "linear hardening: h = {h} < 0 (softening is not supported)"
                    ));
                }
            }
            Hardening::Power { sigma_y0, k, n } => {
                finite("sigma_y0", *sigma_y0)?;
                finite("k", *k)?;
                finite("n", *n)?;
                if *sigma_y0 <= 0.0 {
                    return Err(format!(
                        "power hardening: sigma_y0 = {sigma_y0} must be > 0"
                    ));
                }
                if *k < 0.0 {
                    return Err(format!("power hardening: k = {k} must be ≥ 0"));
                }
                if !(*n > 0.0 && *n <= 1.0) {
                    return Err(format!("power hardening: n = {n} must be in (0, 1]"));
                }
            }
            Hardening::Tabulated { points } => {
                if points.is_empty() {
                    return Err("tabulated hardening: no points".into());
                }
                for (i, p) in points.iter().enumerate() {
                    if !(p[0].is_finite() && p[1].is_finite()) {
                        return Err(format!(
                            "tabulated hardening: point {i} {p:?} is not finite"
                        ));
                    }
                    if p[1] <= 0.0 {
                        return Err(format!(
                            "tabulated hardening: point {i}: sigma_y = {} must be > 0",
                            p[1]
                        ));
                    }
                }
                if points[0][0] != 0.0 {
                    return Err(format!(
                        "tabulated hardening: the first plastic strain must be 0, got {}",
                        points[0][0]
                    ));
                }
                for (i, w) in points.windows(2).enumerate() {
                    if w[1][0] <= w[0][0] {
                        return Err(format!(
                            "tabulated hardening: plastic strain must increase strictly: \
                             point {} has {} after {}",
                            i + 1,
                            w[1][0],
                            w[0][0]
                        ));
                    }
                    if w[1][1] < w[0][1] {
                        return Err(format!(
                            "tabulated hardening: sigma_y decreases from {} to {} at point {} \
                             (softening is not supported)",
                            w[0][1],
                            w[1][1],
                            i + 1
                        ));
                    }
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * b.abs().max(1.0)
    }

    #[test]
    fn linear() {
        let h = Hardening::Linear {
            sigma_y0: 250.0,
            h: 1000.0,
        };
        h.validate().unwrap();
        assert_eq!(h.yield_stress(0.0), (250.0, 1000.0));
        assert!(close(h.yield_stress(0.1).0, 350.0));
        let bad = Hardening::Linear {
            sigma_y0: 0.0,
            h: 1.0,
        };
        assert!(bad.validate().unwrap_err().contains("sigma_y0"));
        let bad = Hardening::Linear {
            sigma_y0: 1.0,
            h: -1.0,
        };
        assert!(bad.validate().unwrap_err().contains("softening"));
    }

    #[test]
    fn power_values_slopes_and_start() {
        let (s0, k, n) = (200.0, 500.0, 0.3);
        let h = Hardening::Power { sigma_y0: s0, k, n };
        h.validate().unwrap();
        for ep in [1e-4, 0.01, 0.2, 1.5] {
            let (s, ds) = h.yield_stress(ep);
            assert!(close(s, s0 + k * ep.powf(n)), "{ep}");
            assert!(close(ds, k * n * ep.powf(n - 1.0)), "{ep}");
            // Slope is the derivative of the value.
            let d = 1e-7 * ep;
            let fd = (h.yield_stress(ep + d).0 - h.yield_stress(ep - d).0) / (2.0 * d);
            assert!((fd - ds).abs() < 1e-6 * ds, "{ep}: {fd} vs {ds}");
        }
        // Finite, consistent start: secant below POWER_EP0, continuous at it.
        let (s, ds) = h.yield_stress(0.0);
        assert_eq!(s, s0);
        assert!(ds.is_finite() && ds > 0.0);
        assert!(close(ds, k * POWER_EP0.powf(n - 1.0)));
        let (a, _) = h.yield_stress(POWER_EP0 * (1.0 - 1e-12));
        let (b, _) = h.yield_stress(POWER_EP0);
        assert!((a - b).abs() < 1e-9 * b);
        let (s, ds2) = h.yield_stress(0.5 * POWER_EP0);
        assert!(close(s, s0 + 0.5 * ds * POWER_EP0) && ds2 == ds);
        // n = 1 is linear everywhere.
        let lin = Hardening::Power {
            sigma_y0: s0,
            k,
            n: 1.0,
        };
        assert!(close(lin.yield_stress(0.0).1, k) && close(lin.yield_stress(0.3).0, s0 + 0.3 * k));
        for (n, ok) in [
            (0.0, false),
            (1.0, true),
            (1.2, false),
            (-0.5, false),
            (0.5, true),
        ] {
            let r = Hardening::Power { sigma_y0: s0, k, n }.validate();
            assert_eq!(r.is_ok(), ok, "n = {n}: {r:?}");
            if !ok {
                assert!(r.unwrap_err().contains("n = "));
            }
        }
        let bad = Hardening::Power {
            sigma_y0: -1.0,
            k,
            n,
        };
        assert!(bad.validate().unwrap_err().contains("sigma_y0"));
        let bad = Hardening::Power {
            sigma_y0: 1.0,
            k: -2.0,
            n,
        };
        assert!(bad.validate().unwrap_err().contains("k = "));
    }

    #[test]
    fn tabulated_values_slopes_extrapolation() {
        let h = Hardening::Tabulated {
            points: vec![[0.0, 100.0], [0.1, 150.0], [0.3, 170.0]],
        };
        h.validate().unwrap();
        assert_eq!(h.yield_stress(0.0), (100.0, 500.0));
        let (s, ds) = h.yield_stress(0.05);
        assert!(close(s, 125.0) && close(ds, 500.0));
        // At a breakpoint: value of the point, slope of the segment to the right.
        let (s, ds) = h.yield_stress(0.1);
        assert!(close(s, 150.0) && close(ds, 100.0));
        let (s, ds) = h.yield_stress(0.2);
        assert!(close(s, 160.0) && close(ds, 100.0));
        // Beyond the last point: last slope extrapolated.
        let (s, ds) = h.yield_stress(0.5);
        assert!(close(s, 190.0) && close(ds, 100.0));
        // One point: perfectly plastic.
        let flat = Hardening::Tabulated {
            points: vec![[0.0, 100.0]],
        };
        flat.validate().unwrap();
        assert_eq!(flat.yield_stress(3.0), (100.0, 0.0));
    }

    #[test]
    fn tabulated_validation_messages() {
        let msg = |points: Vec<[f64; 2]>| Hardening::Tabulated { points }.validate().unwrap_err();
        assert!(msg(vec![]).contains("no points"));
        assert!(msg(vec![[0.01, 100.0], [0.1, 120.0]]).contains("first plastic strain must be 0"));
        assert!(msg(vec![[0.0, 100.0], [0.1, 120.0], [0.1, 130.0]]).contains("increase strictly"));
        assert!(msg(vec![[0.0, 100.0], [0.2, 120.0], [0.1, 130.0]]).contains("increase strictly"));
        assert!(msg(vec![[0.0, 0.0], [0.1, 120.0]]).contains("must be > 0"));
        assert!(msg(vec![[0.0, 100.0], [0.1, 90.0]]).contains("softening"));
        assert!(msg(vec![[0.0, 100.0], [f64::NAN, 90.0]]).contains("not finite"));
    }
}
