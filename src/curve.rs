//! Time curves: piecewise-linear functions of (pseudo-)time that scale loads, prescribed
//! motions and wall paths. A leaf module: every layer may use it, it uses nothing.

use serde::{Deserialize, Serialize};

/// Piecewise-linear curve through `points` = [[t, value], ...] (strictly increasing t),
/// constant beyond its ends.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Curve {
    pub points: Vec<[f64; 2]>,
}

impl Curve {
    /// The default load curve: 0 at t = 0 rising linearly to 1 at `end`.
    pub fn ramp(end: f64) -> Self {
        Self {
            points: vec![[0.0, 0.0], [end, 1.0]],
        }
    }

    /// The constant `v`.
    pub fn constant(v: f64) -> Self {
        Self {
            points: vec![[0.0, v]],
        }
    }

    pub fn eval(&self, t: f64) -> f64 {
        let p = &self.points;
        if t <= p[0][0] {
            return p[0][1];
        }
        for w in p.windows(2) {
            if t <= w[1][0] {
                let s = (t - w[0][0]) / (w[1][0] - w[0][0]);
                return w[0][1] + s * (w[1][1] - w[0][1]);
            }
        }
        p[p.len() - 1][1]
    }

    /// ∫₀ᵗ c(τ) dτ, exact for the piecewise-linear curve held constant outside its points
    /// (velocity curves integrate to displacements this way).
    pub fn integral(&self, t: f64) -> f64 {
        let p = &self.points;
        let mut s = 0.0;
        let mut prev = (0.0, self.eval(0.0));
        let mut knots: Vec<f64> = p
            .iter()
            .map(|q| q[0])
            .filter(|&x| x > 0.0 && x < t)
            .collect();
        knots.push(t);
        for x in knots {
            let y = self.eval(x);
            s += 0.5 * (prev.1 + y) * (x - prev.0);
            prev = (x, y);
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curve_interpolates_and_clamps() {
        let c = Curve {
            points: vec![[0.0, 0.0], [1.0, 2.0], [2.0, 2.0]],
        };
        assert_eq!(c.eval(-1.0), 0.0);
        assert!((c.eval(0.25) - 0.5).abs() < 1e-15);
        assert_eq!(c.eval(1.5), 2.0);
        assert_eq!(c.eval(9.0), 2.0);
    }

    #[test]
    fn integrals_are_exact() {
        let c = Curve {
            points: vec![[0.0, 0.0], [1.0, 2.0], [3.0, 2.0]],
        };
        assert!((c.integral(0.5) - 0.25).abs() < 1e-14);
        assert!((c.integral(2.0) - 3.0).abs() < 1e-14);
        assert!((c.integral(4.0) - 7.0).abs() < 1e-14);
        assert!((Curve::constant(3.0).integral(2.0) - 6.0).abs() < 1e-14);
    }
}
