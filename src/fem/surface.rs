//! Surface loads on element faces (quad4, tri3 or tri6, nodes in the face's outward order as
//! in [`crate::mesh::ElemKind::faces`]), so x,ξ × x,η points out of the body.
//!
//! * Dead traction: f_a = ∫ N_a t dA, t per reference area (Hughes §3.9).
//! * Follower pressure (Bonet & Wood, *Nonlinear Continuum Mechanics for FEA*, §8.4.2
//!   and §9.5): f_a = −p ∫ N_a (x,ξ × x,η) dξ dη on the deformed face; its derivative
//!   ∂f_a/∂x_b = −p ∫ N_a (N_b,η [x,ξ]× − N_b,ξ [x,η]×) dξ dη is the non-symmetric
//!   load stiffness ([v]× w = v × w).
//!
//! nalgebra's `cross` and `norm` compute the same products and sums in the same order as
//! the hand-written ones they replaced (results bit for bit unchanged).

use super::shape::{Tabulated, QUAD4, TRI3, TRI6};
use nalgebra::Vector3;

/// Consistent nodal forces of a dead traction `t` (force per reference area) on a face.
/// `f` (len 3n) is overwritten.
pub fn traction_face(x0: &[[f64; 3]], t: [f64; 3], f: &mut [f64]) {
    fn go<const N: usize, const G: usize>(
        tab: &Tabulated<2, N, G>,
        x0: &[[f64; 3]; N],
        t: [f64; 3],
        f: &mut [f64],
    ) {
        assert_eq!(f.len(), 3 * N, "force slice length");
        f.fill(0.0);
        for g in 0..G {
            let (a, b) = tangents(x0, &tab.dn[g]);
            let da = tab.weights[g] * a.cross(&b).norm();
            for (fa, na) in f.chunks_exact_mut(3).zip(&tab.n[g]) {
                for i in 0..3 {
                    fa[i] += na * t[i] * da;
                }
            }
        }
    }
    match x0.len() {
        4 => go(&QUAD4, nodes(x0), t, f),
        3 => go(&TRI3, nodes(x0), t, f),
        6 => go(&TRI6, nodes(x0), t, f),
        n => panic!("face with {n} nodes: only quad4, tri3 and tri6 faces"),
    }
}

/// Follower pressure `p` (positive pushes against the outward normal, into the body) on
/// the deformed face x = x0 + u: f_a = −p ∫ N_a (x,ξ × x,η) dξ dη, and, if `k` is
/// `Some`, its tangent ∂f/∂u (3n×3n row-major, `k[(3a+i)*3n + 3b+j]`, non-symmetric).
/// This is an external force: the residual's Jacobian gets −k. `f`, `k` overwritten.
pub fn pressure_face(
    x0: &[[f64; 3]],
    u: &[[f64; 3]],
    p: f64,
    f: &mut [f64],
    k: Option<&mut [f64]>,
) {
    fn go<const N: usize, const G: usize>(
        tab: &Tabulated<2, N, G>,
        x0: &[[f64; 3]; N],
        u: &[[f64; 3]; N],
        p: f64,
        f: &mut [f64],
        mut k: Option<&mut [f64]>,
    ) {
        assert_eq!(f.len(), 3 * N, "force slice length");
        f.fill(0.0);
        if let Some(k) = k.as_deref_mut() {
            assert_eq!(k.len(), 9 * N * N, "tangent slice length");
            k.fill(0.0);
        }
        let mut x = [[0.0; 3]; N];
        for ((xa, xa0), ua) in x.iter_mut().zip(x0).zip(u) {
            *xa = [xa0[0] + ua[0], xa0[1] + ua[1], xa0[2] + ua[2]];
        }
        let n3 = 3 * N;
        for g in 0..G {
            let w = -p * tab.weights[g];
            let (a, b) = tangents(&x, &tab.dn[g]);
            let n = a.cross(&b);
            for (fa, na) in f.chunks_exact_mut(3).zip(&tab.n[g]) {
                for i in 0..3 {
                    fa[i] += w * na * n[i];
                }
            }
            if let Some(k) = k.as_deref_mut() {
                let (sa, sb) = (skew(&a), skew(&b));
                for (ia, na) in tab.n[g].iter().enumerate() {
                    for (ib, d) in tab.dn[g].iter().enumerate() {
                        for i in 0..3 {
                            for j in 0..3 {
                                k[(3 * ia + i) * n3 + 3 * ib + j] +=
                                    w * na * (d[1] * sa[i][j] - d[0] * sb[i][j]);
                            }
                        }
                    }
                }
            }
        }
    }
    match x0.len() {
        4 => go(&QUAD4, nodes(x0), nodes(u), p, f, k),
        3 => go(&TRI3, nodes(x0), nodes(u), p, f, k),
        6 => go(&TRI6, nodes(x0), nodes(u), p, f, k),
        n => panic!("face with {n} nodes: only quad4, tri3 and tri6 faces"),
    }
}

/// Reference area of a face.
pub fn face_area(x0: &[[f64; 3]]) -> f64 {
    fn go<const N: usize, const G: usize>(tab: &Tabulated<2, N, G>, x0: &[[f64; 3]; N]) -> f64 {
        (0..G)
            .map(|g| {
                let (a, b) = tangents(x0, &tab.dn[g]);
                tab.weights[g] * a.cross(&b).norm()
            })
            .sum()
    }
    match x0.len() {
        4 => go(&QUAD4, nodes(x0)),
        3 => go(&TRI3, nodes(x0)),
        6 => go(&TRI6, nodes(x0)),
        n => panic!("face with {n} nodes: only quad4, tri3 and tri6 faces"),
    }
}

#[inline]
fn nodes<const N: usize>(x: &[[f64; 3]]) -> &[[f64; 3]; N] {
    x.try_into()
        .unwrap_or_else(|_| panic!("face has {} nodes, expected {N}", x.len()))
}

/// Covariant tangents x,ξ and x,η.
#[inline]
fn tangents<const N: usize>(x: &[[f64; 3]; N], dn: &[[f64; 2]; N]) -> (Vector3<f64>, Vector3<f64>) {
    let (mut a, mut b) = (Vector3::zeros(), Vector3::zeros());
    for (xa, d) in x.iter().zip(dn) {
        for i in 0..3 {
            a[i] += xa[i] * d[0];
            b[i] += xa[i] * d[1];
        }
    }
    (a, b)
}

/// [v]×, the matrix with [v]× w = v × w.
#[inline]
fn skew(v: &Vector3<f64>) -> [[f64; 3]; 3] {
    [[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::shape::HEX8_NODES;
    use crate::mesh::ElemKind;

    /// A warped quad (not planar) and a tri, both generic.
    fn warped_quad() -> Vec<[f64; 3]> {
        vec![
            [0.0, 0.0, 0.0],
            [1.3, 0.1, 0.2],
            [1.1, 0.9, -0.15],
            [-0.1, 1.2, 0.1],
        ]
    }
    fn tri() -> Vec<[f64; 3]> {
        vec![[0.1, 0.0, 0.3], [1.2, 0.2, 0.0], [0.3, 0.8, 0.5]]
    }
    /// The tri above with its midside nodes off the edges: a curved tri6.
    fn tri6() -> Vec<[f64; 3]> {
        let c = tri();
        let mut x = c.clone();
        for (e, [i, j]) in [[0, 1], [1, 2], [2, 0]].into_iter().enumerate() {
            x.push(std::array::from_fn(|k| {
                0.5 * (c[i][k] + c[j][k]) + 0.05 * ((3 * e + k) as f64).sin()
            }));
        }
        x
    }
    fn wiggle(n: usize, amp: f64) -> Vec<[f64; 3]> {
        (0..n)
            .map(|a| {
                [
                    amp * (a as f64 + 0.3).sin(),
                    amp * (2.0 * a as f64).cos(),
                    amp * (0.7 * a as f64 + 1.0).sin(),
                ]
            })
            .collect()
    }
    fn sum3(f: &[f64]) -> [f64; 3] {
        let mut s = [0.0; 3];
        for fa in f.chunks_exact(3) {
            for i in 0..3 {
                s[i] += fa[i];
            }
        }
        s
    }

    #[test]
    fn traction_sums_to_t_times_area() {
        let t = [1.5, -2.0, 0.7];
        for x0 in [warped_quad(), tri(), tri6()] {
            let mut f = vec![0.0; 3 * x0.len()];
            traction_face(&x0, t, &mut f);
            let (s, a) = (sum3(&f), face_area(&x0));
            for i in 0..3 {
                assert!((s[i] - t[i] * a).abs() < 1e-13, "{s:?} vs {a} {t:?}");
            }
        }
        // Areas of flat shapes: unit square scaled (2 × 0.5), right triangle legs 2 and 3.
        let sq = [
            [0.0, 0.0, 1.0],
            [2.0, 0.0, 1.0],
            [2.0, 0.5, 1.0],
            [0.0, 0.5, 1.0],
        ];
        assert!((face_area(&sq) - 1.0).abs() < 1e-14);
        assert!((face_area(&[[0.0; 3], [2.0, 0.0, 0.0], [0.0, 3.0, 0.0]]) - 3.0).abs() < 1e-14);
        // On a rectangle each node carries a quarter.
        let mut f = vec![0.0; 12];
        traction_face(&sq, [0.0, 0.0, 4.0], &mut f);
        assert!(f.chunks_exact(3).all(|fa| (fa[2] - 1.0).abs() < 1e-14));
        // On a straight-sided tri6 the corners carry nothing and each midside node a third.
        let c = [[0.0; 3], [2.0, 0.0, 0.0], [0.0, 3.0, 0.0]];
        let mut t6 = c.to_vec();
        for [i, j] in [[0, 1], [1, 2], [2, 0]] {
            t6.push(std::array::from_fn(|k| 0.5 * (c[i][k] + c[j][k])));
        }
        let mut f = vec![0.0; 18];
        traction_face(&t6, [0.0, 0.0, 1.0], &mut f);
        for (a, fa) in f.chunks_exact(3).enumerate() {
            let want = if a < 3 { 0.0 } else { 1.0 };
            assert!((fa[2] - want).abs() < 1e-14, "node {a}: {}", fa[2]);
        }
    }

    #[test]
    fn pressure_on_flat_face_is_minus_p_n_a() {
        // Flat trapezoid and triangle in a tilted plane, translated rigidly.
        let p = 3.0;
        let (e1, e2) = ([0.6, 0.8, 0.0], [0.0, 0.0, 1.0]);
        let n = Vector3::from(e1).cross(&Vector3::from(e2));
        let plane = |s: f64, t: f64| {
            [
                s * e1[0] + t * e2[0],
                s * e1[1] + t * e2[1],
                s * e1[2] + t * e2[2],
            ]
        };
        let quad = vec![
            plane(0.0, 0.0),
            plane(2.0, 0.0),
            plane(1.5, 1.0),
            plane(0.2, 1.2),
        ];
        let tri = vec![plane(0.0, 0.0), plane(2.0, 0.3), plane(0.5, 1.5)];
        for x0 in [quad, tri] {
            let u = vec![[0.5, -0.2, 0.1]; x0.len()];
            let mut f = vec![0.0; 3 * x0.len()];
            pressure_face(&x0, &u, p, &mut f, None);
            let (s, a) = (sum3(&f), face_area(&x0));
            for i in 0..3 {
                assert!((s[i] + p * n[i] * a).abs() < 1e-13, "{s:?}");
            }
        }
    }

    #[test]
    fn pressure_points_into_the_body_and_closes() {
        // Pressure on all faces of a distorted hex (and a tet) sums to zero: ∮ n dA = 0,
        // and the 2×2 rule integrates x,ξ × x,η exactly. The top face pushes down.
        let hex: Vec<[f64; 3]> = HEX8_NODES
            .iter()
            .enumerate()
            .map(|(a, p)| {
                [
                    p[0] + 0.1 * (a as f64).sin(),
                    p[1] + 0.15 * (2.0 * a as f64).cos(),
                    p[2] + 0.1 * (a as f64).cos(),
                ]
            })
            .collect();
        let tet = vec![
            [0.0, 0.1, 0.0],
            [1.2, 0.0, 0.1],
            [0.1, 0.9, -0.1],
            [0.2, 0.3, 1.0],
        ];
        // The tet with curved edges as a tet10: its tri6 faces close as well.
        let mut tet10 = tet.clone();
        for (e, [i, j]) in crate::fem::shape::TET10_EDGES.into_iter().enumerate() {
            tet10.push(std::array::from_fn(|k| {
                0.5 * (tet[i][k] + tet[j][k]) + 0.04 * ((5 * e + 2 * k) as f64).cos()
            }));
        }
        for (kind, x) in [
            (ElemKind::Hex8, hex),
            (ElemKind::Tet4, tet),
            (ElemKind::Tet10, tet10),
        ] {
            let u = wiggle(x.len(), 0.1);
            let mut total = [0.0; 3];
            for (fi, face) in kind.faces().iter().enumerate() {
                let x0: Vec<_> = face.iter().map(|&i| x[i]).collect();
                let uf: Vec<_> = face.iter().map(|&i| u[i]).collect();
                let mut f = vec![0.0; 3 * face.len()];
                pressure_face(&x0, &uf, 2.0, &mut f, None);
                let s = sum3(&f);
                if kind == ElemKind::Hex8 && fi == 1 {
                    assert!(s[2] < -1.0, "top face must push down: {s:?}");
                }
                for i in 0..3 {
                    total[i] += s[i];
                }
            }
            assert!(total.iter().all(|v| v.abs() < 1e-13), "{kind:?}: {total:?}");
        }
    }

    #[test]
    fn pressure_tangent_matches_central_difference() {
        for x0 in [warped_quad(), tri(), tri6()] {
            let nn = x0.len();
            let n = 3 * nn;
            let u = wiggle(nn, 0.15);
            let p = 1.7;
            let mut f = vec![0.0; n];
            let mut k = vec![0.0; n * n];
            pressure_face(&x0, &u, p, &mut f, Some(&mut k));
            let kmax = k.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            assert!(kmax > 0.1);
            let h = 1e-6;
            for col in 0..n {
                let (mut up, mut um) = (u.clone(), u.clone());
                up[col / 3][col % 3] += h;
                um[col / 3][col % 3] -= h;
                let (mut fp, mut fm) = (vec![0.0; n], vec![0.0; n]);
                pressure_face(&x0, &up, p, &mut fp, None);
                pressure_face(&x0, &um, p, &mut fm, None);
                for row in 0..n {
                    let fd = (fp[row] - fm[row]) / (2.0 * h);
                    assert!(
                        (fd - k[row * n + col]).abs() < 1e-7 * kmax,
                        "K[{row},{col}] = {}, fd {fd}",
                        k[row * n + col]
                    );
                }
            }
        }
    }
}
