//! Small tensor helpers shared by the finite-strain models: symmetric 3×3 ↔ Voigt
//! (xx, yy, zz, xy, yz, xz) and fourth-order tensors with minor symmetries ↔ the 6×6
//! Voigt tangent used with engineering shear strains, i.e. `c[I][J] = c_ijkl` with
//! I = (ij), J = (kl).

// Index notation reads best as index loops here.
#![allow(clippy::needless_range_loop)]

use nalgebra::Matrix3;

/// Index pairs of the Voigt components, in order.
pub(crate) const VOIGT: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2)];

/// A fourth-order tensor in 3-D, `t[i][j][k][l]`.
pub(crate) type T4 = [[[[f64; 3]; 3]; 3]; 3];

pub(crate) fn to_voigt(m: &Matrix3<f64>) -> [f64; 6] {
    VOIGT.map(|(i, j)| 0.5 * (m[(i, j)] + m[(j, i)]))
}

pub(crate) fn from_voigt(v: &[f64]) -> Matrix3<f64> {
    Matrix3::new(v[0], v[3], v[5], v[3], v[1], v[4], v[5], v[4], v[2])
}

pub(crate) fn t4_to_voigt(t: &T4) -> [[f64; 6]; 6] {
    let mut c = [[0.0; 6]; 6];
    for (row, &(i, j)) in c.iter_mut().zip(&VOIGT) {
        for (x, &(k, l)) in row.iter_mut().zip(&VOIGT) {
            *x = t[i][j][k][l];
        }
    }
    c
}

/// `a ⊗ b`: (a⊗b)_ijkl = a_ij b_kl.
pub(crate) fn outer(a: &Matrix3<f64>, b: &Matrix3<f64>) -> T4 {
    let mut t = [[[[0.0; 3]; 3]; 3]; 3];
    for (i, ti) in t.iter_mut().enumerate() {
        for (j, tij) in ti.iter_mut().enumerate() {
            for (k, tijk) in tij.iter_mut().enumerate() {
                for (l, x) in tijk.iter_mut().enumerate() {
                    *x = a[(i, j)] * b[(k, l)];
                }
            }
        }
    }
    t
}

/// Symmetrised "box" product: ½(a_ik b_jl + a_il b_jk). With a = b = I it is the
/// symmetric fourth-order identity 𝕀.
pub(crate) fn sym_box(a: &Matrix3<f64>, b: &Matrix3<f64>) -> T4 {
    let mut t = [[[[0.0; 3]; 3]; 3]; 3];
    for (i, ti) in t.iter_mut().enumerate() {
        for (j, tij) in ti.iter_mut().enumerate() {
            for (k, tijk) in tij.iter_mut().enumerate() {
                for (l, x) in tijk.iter_mut().enumerate() {
                    *x = 0.5 * (a[(i, k)] * b[(j, l)] + a[(i, l)] * b[(j, k)]);
                }
            }
        }
    }
    t
}

/// α a + β b, element-wise.
pub(crate) fn axpby(alpha: f64, a: &T4, beta: f64, b: &T4) -> T4 {
    let mut t = *a;
    for (ti, bi) in t.iter_mut().zip(b) {
        for (tij, bij) in ti.iter_mut().zip(bi) {
            for (tijk, bijk) in tij.iter_mut().zip(bij) {
                for (x, y) in tijk.iter_mut().zip(bijk) {
                    *x = alpha * *x + beta * y;
                }
            }
        }
    }
    t
}

/// Double contraction (a : b)_ijkl = a_ijmn b_mnkl.
pub(crate) fn ddot(a: &T4, b: &T4) -> T4 {
    let mut t = [[[[0.0; 3]; 3]; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            for k in 0..3 {
                for l in 0..3 {
                    let mut s = 0.0;
                    for m in 0..3 {
                        for n in 0..3 {
                            s += a[i][j][m][n] * b[m][n][k][l];
                        }
                    }
                    t[i][j][k][l] = s;
                }
            }
        }
    }
    t
}

/// Rotate: t'_abcd = Q_ai Q_bj Q_ck Q_dl t_ijkl (one index at a time).
pub(crate) fn rotate(t: &T4, q: &Matrix3<f64>) -> T4 {
    let mut a = [[[[0.0; 3]; 3]; 3]; 3];
    // Index 1.
    for p in 0..3 {
        for j in 0..3 {
            for k in 0..3 {
                for l in 0..3 {
                    a[p][j][k][l] = (0..3).map(|i| q[(p, i)] * t[i][j][k][l]).sum();
                }
            }
        }
    }
    let mut b = [[[[0.0; 3]; 3]; 3]; 3];
    for p in 0..3 {
        for r in 0..3 {
            for k in 0..3 {
                for l in 0..3 {
                    b[p][r][k][l] = (0..3).map(|j| q[(r, j)] * a[p][j][k][l]).sum();
                }
            }
        }
    }
    for p in 0..3 {
        for r in 0..3 {
            for s in 0..3 {
                for l in 0..3 {
                    a[p][r][s][l] = (0..3).map(|k| q[(s, k)] * b[p][r][k][l]).sum();
                }
            }
        }
    }
    for p in 0..3 {
        for r in 0..3 {
            for s in 0..3 {
                for u in 0..3 {
                    b[p][r][s][u] = (0..3).map(|l| q[(u, l)] * a[p][r][s][l]).sum();
                }
            }
        }
    }
    b
}

/// Input check shared by the finite-strain models: finite F with det F > 0.
pub(crate) fn check_f(model: &'static str, f: &Matrix3<f64>) -> Result<f64, super::MaterialError> {
    if f.iter().any(|x| !x.is_finite()) {
        return Err(super::MaterialError::NonFinite {
            model,
            what: "deformation gradient",
        });
    }
    let j = f.determinant();
    if !(j.is_finite() && j > 0.0) {
        return Err(super::MaterialError::Inverted { model, det: j });
    }
    Ok(j)
}
