//! Mortar weights of small-sliding pairs (Wohlmuth's dual mortar, as Popp et al. use it
//! for finite-deformation contact): each tracked node t gets the weighted gap
//! g̃_t = ∫ Φ_t (x_tracked − x_reference) dA / D_t over the tracked surface, with Φ_t
//! the dual shape functions (∫ Φ_t N_u = δ_tu D_t, D_t = ∫ N_t). Then
//! g̃_t = x_t − Σ_a (M_ta / D_t) x_a with M_ta = ∫ Φ_t N_a, so a mortar pair is a node
//! with fixed weights over the reference nodes, like a node-to-face pair, but it passes
//! the contact patch test on any pair of meshes: a uniform pressure p (λ_t = p) gives
//! the reference nodes Σ_t M_ta p = p ∫ N_a (Σ_t Φ_t = 1), their consistent loads, and
//! a flat uniform deformation has g̃ = 0 at every node (biorthogonality).
//!
//! The integrals are computed once, in the reference configuration (small sliding):
//! each tracked face is clipped against each reference face it overlaps, in the
//! tracked face's plane (Sutherland–Hodgman), and the overlap is fanned into triangles
//! with a degree-5 rule (exact for the products of bilinear functions on parallelogram
//! faces).

// Index loops over small dense matrices read like the formulas.
#![allow(clippy::needless_range_loop)]

/// Degree-5 7-point triangle rule (Strang & Fix): barycentric points and weights
/// (summing to 1: multiply by the triangle's area).
const TRI7: [([f64; 3], f64); 7] = {
    const A1: f64 = 0.059_715_871_789_769_8;
    const B1: f64 = 0.470_142_064_105_115_1;
    const A2: f64 = 0.797_426_985_353_087_3;
    const B2: f64 = 0.101_286_507_323_456_3;
    const W0: f64 = 0.225;
    const W1: f64 = 0.132_394_152_788_506_2;
    const W2: f64 = 0.125_939_180_544_827_2;
    [
        ([1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0], W0),
        ([A1, B1, B1], W1),
        ([B1, A1, B1], W1),
        ([B1, B1, A1], W1),
        ([A2, B2, B2], W2),
        ([B2, A2, B2], W2),
        ([B2, B2, A2], W2),
    ]
};

use super::pair::{face_shape, project_on_face};
use super::vec3::{cross, dot, sub, unit};

/// A face's plane: centroid, outward normal (from its diagonals) and in-plane axes.
struct Plane {
    c: [f64; 3],
    n: [f64; 3],
    e1: [f64; 3],
    e2: [f64; 3],
}

impl Plane {
    fn of(x: &[[f64; 3]]) -> Self {
        let m = x.len() as f64;
        let c = std::array::from_fn(|i| x.iter().map(|p| p[i]).sum::<f64>() / m);
        let n = if x.len() == 4 {
            unit(cross(sub(x[2], x[0]), sub(x[3], x[1])))
        } else {
            unit(cross(sub(x[1], x[0]), sub(x[2], x[0])))
        };
        let e1 = unit(sub(x[1], x[0]));
        let e1 = unit(sub(
            e1,
            [n[0] * dot(n, e1), n[1] * dot(n, e1), n[2] * dot(n, e1)],
        ));
        Self {
            c,
            n,
            e1,
            e2: cross(n, e1),
        }
    }
    fn to2(&self, x: [f64; 3]) -> [f64; 2] {
        let d = sub(x, self.c);
        [dot(d, self.e1), dot(d, self.e2)]
    }
    fn to3(&self, p: [f64; 2]) -> [f64; 3] {
        std::array::from_fn(|i| self.c[i] + p[0] * self.e1[i] + p[1] * self.e2[i])
    }
}

fn area2(p: &[[f64; 2]]) -> f64 {
    let m = p.len();
    (0..m)
        .map(|k| {
            let (a, b) = (p[k], p[(k + 1) % m]);
            a[0] * b[1] - a[1] * b[0]
        })
        .sum::<f64>()
        * 0.5
}

/// Sutherland–Hodgman: `subject` clipped by the convex, counter-clockwise `clip`.
pub fn clip_polygon(subject: &[[f64; 2]], clip: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut out: Vec<[f64; 2]> = subject.to_vec();
    let m = clip.len();
    for k in 0..m {
        if out.is_empty() {
            break;
        }
        let (a, b) = (clip[k], clip[(k + 1) % m]);
        let side = |p: [f64; 2]| (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
        let input = std::mem::take(&mut out);
        for i in 0..input.len() {
            let (p, q) = (input[i], input[(i + 1) % input.len()]);
            let (sp, sq) = (side(p), side(q));
            if sp >= 0.0 {
                out.push(p);
            }
            if (sp >= 0.0) != (sq >= 0.0) {
                let t = sp / (sp - sq);
                out.push([p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])]);
            }
        }
    }
    out
}

/// Dual shape function coefficients of a tracked face: Φ_t = Σ_u A_tu N_u with
/// A = D M⁻¹, D = diag(∫ N_t), M = [∫ N_t N_u] (3 × 3 Gauss on the face), and D.
pub fn dual_coefficients(x: &[[f64; 3]]) -> (Vec<Vec<f64>>, Vec<f64>) {
    let nf = x.len();
    let mut m = vec![vec![0.0; nf]; nf];
    let mut d = vec![0.0; nf];
    let g = [-(0.6f64).sqrt(), 0.0, (0.6f64).sqrt()];
    let gw = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];
    let mut points: Vec<([f64; 2], f64)> = Vec::new();
    if nf == 4 {
        for i in 0..3 {
            for j in 0..3 {
                points.push(([g[i], g[j]], gw[i] * gw[j]));
            }
        }
    } else {
        for (b, w) in TRI7 {
            points.push(([b[1], b[2]], 0.5 * w));
        }
    }
    for (xi, w) in points {
        let (n, dn) = face_shape(nf, xi);
        let mut a1 = [0.0; 3];
        let mut a2 = [0.0; 3];
        for k in 0..nf {
            for c in 0..3 {
                a1[c] += dn[k][0] * x[k][c];
                a2[c] += dn[k][1] * x[k][c];
            }
        }
        let ja = dot(cross(a1, a2), cross(a1, a2)).sqrt() * w;
        for t in 0..nf {
            d[t] += n[t] * ja;
            for u in 0..nf {
                m[t][u] += n[t] * n[u] * ja;
            }
        }
    }
    // A = D M⁻¹ (M symmetric positive definite; Gauss–Jordan on [M | I]).
    let mut aug: Vec<Vec<f64>> = (0..nf)
        .map(|i| {
            let mut r = m[i].clone();
            r.extend((0..nf).map(|j| if i == j { 1.0 } else { 0.0 }));
            r
        })
        .collect();
    for col in 0..nf {
        let piv = (col..nf)
            .max_by(|&a, &b| aug[a][col].abs().total_cmp(&aug[b][col].abs()))
            .unwrap_or(col);
        aug.swap(col, piv);
        let p = aug[col][col];
        for v in aug[col].iter_mut() {
            *v /= p;
        }
        for r in 0..nf {
            if r != col {
                let f = aug[r][col];
                if f != 0.0 {
                    for c in 0..2 * nf {
                        aug[r][c] -= f * aug[col][c];
                    }
                }
            }
        }
    }
    let a = (0..nf)
        .map(|t| (0..nf).map(|u| d[t] * aug[t][nf + u]).collect())
        .collect();
    (a, d)
}

/// ∫ Φ_t N_a over the overlap of a tracked face `xs` (nodes' positions; `a` its dual
/// coefficients) with a reference face `xm`, as (t, a, value) with t, a local to the
/// faces; empty where they do not overlap or face the same way. Err if a quadrature
/// point has no parameters on one of the faces (a degenerate face).
pub fn overlap_integrals(
    xs: &[[f64; 3]],
    a: &[Vec<f64>],
    xm: &[[f64; 3]],
) -> Result<Vec<(usize, usize, f64)>, String> {
    let ps = Plane::of(xs);
    let pm = Plane::of(xm);
    if dot(ps.n, pm.n) >= 0.0 {
        return Ok(Vec::new());
    }
    let s2: Vec<[f64; 2]> = corners(xs).iter().map(|&p| ps.to2(p)).collect();
    let mut m2: Vec<[f64; 2]> = corners(xm).iter().map(|&p| ps.to2(p)).collect();
    if area2(&m2) < 0.0 {
        m2.reverse();
    }
    let mut s2c = s2.clone();
    if area2(&s2c) < 0.0 {
        s2c.reverse();
    }
    let poly = clip_polygon(&s2c, &m2);
    if poly.len() < 3 || area2(&poly).abs() <= 1e-14 * area2(&s2c).abs() {
        return Ok(Vec::new());
    }
    let (ns, nm) = (xs.len(), xm.len());
    let mut out = vec![0.0; ns * nm];
    let c: [f64; 2] = [
        poly.iter().map(|p| p[0]).sum::<f64>() / poly.len() as f64,
        poly.iter().map(|p| p[1]).sum::<f64>() / poly.len() as f64,
    ];
    for k in 0..poly.len() {
        let (p, q) = (poly[k], poly[(k + 1) % poly.len()]);
        let tri_area = 0.5 * ((p[0] - c[0]) * (q[1] - c[1]) - (p[1] - c[1]) * (q[0] - c[0]));
        if tri_area.abs() <= 0.0 {
            continue;
        }
        for (b, w) in TRI7 {
            let pt = [
                b[0] * c[0] + b[1] * p[0] + b[2] * q[0],
                b[0] * c[1] + b[1] * p[1] + b[2] * q[1],
            ];
            let x3 = ps.to3(pt);
            let (Some((eta, _)), Some((xi, _))) =
                (project_on_face(x3, xs), project_on_face(x3, xm))
            else {
                return Err(format!(
                    "no closest point on a face for the overlap point {x3:?} (a degenerate face?)"
                ));
            };
            let (nsv, _) = face_shape(ns, eta);
            let (nmv, _) = face_shape(nm, xi);
            let phi: Vec<f64> = (0..ns)
                .map(|t| (0..ns).map(|u| a[t][u] * nsv[u]).sum())
                .collect();
            // The area element of the tracked face at η (its plane's, for a flat face).
            let da = w * tri_area.abs() * area_ratio(xs, eta, &ps);
            for t in 0..ns {
                for m in 0..nm {
                    out[t * nm + m] += phi[t] * nmv[m] * da;
                }
            }
        }
    }
    Ok((0..ns)
        .flat_map(|t| (0..nm).map(move |m| (t, m)))
        .map(|(t, m)| (t, m, out[t * nm + m]))
        .filter(|e| e.2 != 0.0)
        .collect())
}

/// The tracked face's area element relative to its plane's at η: |a1 × a2| over the
/// Jacobian of the plane projection (1 for a flat face).
/// A face's corners, its outline for clipping: a tri6 (a tet10's face) by its straight
/// corner triangle, which is the face itself where it is flat.
fn corners(x: &[[f64; 3]]) -> &[[f64; 3]] {
    if x.len() == 6 {
        &x[..3]
    } else {
        x
    }
}

fn area_ratio(xs: &[[f64; 3]], eta: [f64; 2], p: &Plane) -> f64 {
    let (_, dn) = face_shape(xs.len(), eta);
    let mut a1 = [0.0; 3];
    let mut a2 = [0.0; 3];
    for k in 0..xs.len() {
        for c in 0..3 {
            a1[c] += dn[k][0] * xs[k][c];
            a2[c] += dn[k][1] * xs[k][c];
        }
    }
    let full = cross(a1, a2);
    let flat = dot(full, p.n).abs();
    if flat <= 0.0 {
        1.0
    } else {
        dot(full, full).sqrt() / flat
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Biorthogonality: ∫ Φ_t N_u = δ_tu D_t, checked with an independent quadrature
    /// on a distorted (flat) quad and a triangle. (On a warped quad |a1 × a2| is not a
    /// polynomial and 3 × 3 Gauss is only close.)
    #[test]
    fn dual_functions_are_biorthogonal() {
        for x in [
            vec![
                [0.0, 0.0, 0.0],
                [2.0, 0.2, 0.0],
                [2.3, 1.5, 0.0],
                [-0.2, 1.2, 0.0],
            ],
            vec![[0.0, 0.0, 0.0], [1.5, 0.1, 0.2], [0.2, 1.0, 0.0]],
        ] {
            let (a, d) = dual_coefficients(&x);
            let nf = x.len();
            // 4 × 4 Gauss (quad) or the 7-point rule (triangle).
            let mut pts: Vec<([f64; 2], f64)> = Vec::new();
            if nf == 4 {
                let g = [
                    (-0.861_136_311_594_053, 0.347_854_845_137_454),
                    (-0.339_981_043_584_856, 0.652_145_154_862_546),
                    (0.339_981_043_584_856, 0.652_145_154_862_546),
                    (0.861_136_311_594_053, 0.347_854_845_137_454),
                ];
                for (p, wp) in g {
                    for (q, wq) in g {
                        pts.push(([p, q], wp * wq));
                    }
                }
            } else {
                for (b, w) in TRI7 {
                    pts.push(([b[1], b[2]], 0.5 * w));
                }
            }
            let mut m = vec![vec![0.0; nf]; nf];
            for (xi, w) in pts {
                let (n, dn) = face_shape(nf, xi);
                let mut a1 = [0.0; 3];
                let mut a2 = [0.0; 3];
                for k in 0..nf {
                    for c in 0..3 {
                        a1[c] += dn[k][0] * x[k][c];
                        a2[c] += dn[k][1] * x[k][c];
                    }
                }
                let ja = dot(cross(a1, a2), cross(a1, a2)).sqrt() * w;
                for t in 0..nf {
                    let phi: f64 = (0..nf).map(|u| a[t][u] * n[u]).sum();
                    for u in 0..nf {
                        m[t][u] += phi * n[u] * ja;
                    }
                }
            }
            for t in 0..nf {
                for u in 0..nf {
                    let want = if t == u { d[t] } else { 0.0 };
                    assert!(
                        (m[t][u] - want).abs() < 1e-12,
                        "{t} {u}: {} vs {want}",
                        m[t][u]
                    );
                }
            }
        }
    }

    /// A tracked quad over four reference quads (non-matching, facing it): the weights
    /// of each tracked node sum to its D (Σ_a N_a = 1, fully covered), and Σ_t M_ta is
    /// ∫ N_a over the overlap (Σ_t Φ_t = 1). The tracked quad is not a parallelogram, so
    /// its inverse map is not polynomial and the degree-5 rule is close, not exact
    /// (measured 1.5e-9 relative; exact on the parallelograms of the patch test).
    #[test]
    fn overlap_integrals_partition_the_face() {
        let xs = [
            [0.1, 0.2, 0.0],
            [0.9, 0.15, 0.0],
            [0.95, 0.8, 0.0],
            [0.05, 0.9, 0.0],
        ];
        let (a, d) = dual_coefficients(&xs);
        let mut row = [0.0; 4];
        let mut col_total = 0.0;
        for (i0, j0) in [(0.0, 0.0), (0.5, 0.0), (0.5, 0.5), (0.0, 0.5)] {
            // Reference faces face −z (their outward normal), the tracked +z.
            let xm = [
                [i0, j0, 0.0],
                [i0, j0 + 0.5, 0.0],
                [i0 + 0.5, j0 + 0.5, 0.0],
                [i0 + 0.5, j0, 0.0],
            ];
            for (t, _, v) in overlap_integrals(&xs, &a, &xm).unwrap() {
                row[t] += v;
                col_total += v;
            }
        }
        for t in 0..4 {
            assert!(
                (row[t] - d[t]).abs() < 1e-8 * d[t],
                "{t}: {} vs {}",
                row[t],
                d[t]
            );
        }
        let area: f64 = d.iter().sum();
        assert!((col_total - area).abs() < 1e-8 * area);
    }
}
