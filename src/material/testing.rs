//! Test helpers shared by the material tests: finite-difference tangents through the
//! Lie-derivative formula, rotations, and comparisons.

use super::tensor::{from_voigt, to_voigt, VOIGT};
use super::Material;
use nalgebra::{Matrix3, Rotation3};

/// Symmetric direction D for Voigt column `jv`: e_k⊗e_k, or (e_k⊗e_l + e_l⊗e_k)/2,
/// i.e. unit engineering shear strain.
pub(crate) fn direction(jv: usize) -> Matrix3<f64> {
    let (k, l) = VOIGT[jv];
    let mut d = Matrix3::zeros();
    d[(k, l)] += 0.5;
    d[(l, k)] += 0.5;
    d
}

/// τ(F) in Voigt form with trial history written to a scratch buffer.
pub(crate) fn tau(m: &dyn Material, f: &Matrix3<f64>, old: &[f64]) -> [f64; 6] {
    let mut scratch = vec![0.0; old.len()];
    m.evaluate(f, old, &mut scratch).unwrap().stress
}

/// Central-difference spatial tangent: c:D = [τ((I+hD)F) − τ((I−hD)F)]/(2h) − (Dτ + τD).
pub(crate) fn fd_tangent(m: &dyn Material, f: &Matrix3<f64>, old: &[f64], h: f64) -> [[f64; 6]; 6] {
    let t0 = from_voigt(&tau(m, f, old));
    let mut c = [[0.0; 6]; 6];
    for jv in 0..6 {
        let d = direction(jv);
        let id = Matrix3::identity();
        let tp = from_voigt(&tau(m, &((id + d * h) * f), old));
        let tm = from_voigt(&tau(m, &((id - d * h) * f), old));
        let col = to_voigt(&((tp - tm) / (2.0 * h) - d * t0 - t0 * d));
        for (row, x) in c.iter_mut().zip(col) {
            row[jv] = x;
        }
    }
    c
}

/// max |a − b| / max |b|.
pub(crate) fn rel_err(a: &[[f64; 6]; 6], b: &[[f64; 6]; 6]) -> f64 {
    let scale = b.iter().flatten().fold(0.0_f64, |s, x| s.max(x.abs()));
    let diff = a
        .iter()
        .flatten()
        .zip(b.iter().flatten())
        .fold(0.0_f64, |s, (x, y)| s.max((x - y).abs()));
    diff / scale
}

/// Checks the returned tangent against the central difference (symmetric directions)
/// and, for a general velocity gradient L (with spin), that
/// τ̇ = c:sym(L) + Lτ + τLᵀ. Returns the larger relative error.
pub(crate) fn tangent_error(m: &dyn Material, f: &Matrix3<f64>, old: &[f64]) -> f64 {
    let mut scratch = vec![0.0; old.len()];
    let sp = m.evaluate(f, old, &mut scratch).unwrap();
    let h = 1e-6;
    let fd = fd_tangent(m, f, old, h);
    let e1 = rel_err(&sp.tangent, &fd);
    // General L, non-symmetric.
    let l = Matrix3::new(0.3, -0.7, 0.2, 0.5, -0.1, 0.9, -0.4, 0.6, 0.25);
    let id = Matrix3::identity();
    let t0 = from_voigt(&sp.stress);
    let tp = from_voigt(&tau(m, &((id + l * h) * f), old));
    let tm = from_voigt(&tau(m, &((id - l * h) * f), old));
    let rate = (tp - tm) / (2.0 * h);
    let dv = to_voigt(&(0.5 * (l + l.transpose())));
    // Engineering shear: the Voigt strain vector doubles the shear components.
    let dv = [dv[0], dv[1], dv[2], 2.0 * dv[3], 2.0 * dv[4], 2.0 * dv[5]];
    let mut cd = [0.0; 6];
    for (x, row) in cd.iter_mut().zip(&sp.tangent) {
        *x = row.iter().zip(&dv).map(|(a, b)| a * b).sum();
    }
    let pred = from_voigt(&cd) + l * t0 + t0 * l.transpose();
    let scale = sp
        .tangent
        .iter()
        .flatten()
        .fold(0.0_f64, |s, x| s.max(x.abs()));
    let e2 = (pred - rate).abs().max() / scale;
    e1.max(e2)
}

pub(crate) fn rotation() -> Matrix3<f64> {
    Rotation3::from_euler_angles(0.3, -0.5, 1.1).into_inner()
}

/// max |Q τ(F) Qᵀ − τ(QF)| / max |τ(F)|, with the same history.
pub(crate) fn objectivity_error(m: &dyn Material, f: &Matrix3<f64>, old: &[f64]) -> f64 {
    let q = rotation();
    let t = from_voigt(&tau(m, f, old));
    let tq = from_voigt(&tau(m, &(q * f), old));
    (q * t * q.transpose() - tq).abs().max() / t.abs().max()
}

/// max |c − cᵀ| / max |c|: the Voigt tangents here are major-symmetric.
pub(crate) fn asymmetry(c: &[[f64; 6]; 6]) -> f64 {
    let mut ct = *c;
    for (i, row) in ct.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = c[j][i];
        }
    }
    rel_err(c, &ct)
}
