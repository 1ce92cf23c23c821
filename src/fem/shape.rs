//! Isoparametric shape functions and quadrature rules (Hughes, *The Finite Element
//! Method*, §3.2–3.3 and §3.8), tabulated at compile time.
//!
//! Node orderings follow Gmsh/VTK (see [`crate::mesh::ElemKind`]): hex8 bottom 0-1-2-3
//! at ζ = −1, top 4-7 at ζ = +1; tet4 at (0,0,0), (1,0,0), (0,1,0), (0,0,1); faces quad4
//! on [−1,1]² and tri3 on the unit triangle. The tables ([`HEX8`], [`TET4`], [`QUAD4`],
//! [`TRI3`]) hold N and ∂N/∂ξ at every integration point so element loops only do
//! geometry and constitutive work.

/// 1/√3: abscissa of the 2-point Gauss–Legendre rule.
pub const GAUSS2: f64 = 0.577_350_269_189_625_8;

/// Natural coordinates of the hex8 nodes (also its corners for Jacobian checks).
pub const HEX8_NODES: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];

/// Natural coordinates of the quad4 nodes.
pub const QUAD4_NODES: [[f64; 2]; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];

/// Trilinear hex8 shape functions N_a = ⅛ (1 + ξ ξ_a)(1 + η η_a)(1 + ζ ζ_a).
pub const fn hex8_n(xi: [f64; 3]) -> [f64; 8] {
    let mut n = [0.0; 8];
    let mut a = 0;
    while a < 8 {
        let p = HEX8_NODES[a];
        n[a] = 0.125 * (1.0 + xi[0] * p[0]) * (1.0 + xi[1] * p[1]) * (1.0 + xi[2] * p[2]);
        a += 1;
    }
    n
}

/// ∂N_a/∂ξ of the hex8, `[a][j]`.
pub const fn hex8_dn(xi: [f64; 3]) -> [[f64; 3]; 8] {
    let mut d = [[0.0; 3]; 8];
    let mut a = 0;
    while a < 8 {
        let p = HEX8_NODES[a];
        let (s, t, u) = (1.0 + xi[0] * p[0], 1.0 + xi[1] * p[1], 1.0 + xi[2] * p[2]);
        d[a] = [
            0.125 * p[0] * t * u,
            0.125 * s * p[1] * u,
            0.125 * s * t * p[2],
        ];
        a += 1;
    }
    d
}

/// Linear tet4 shape functions N = (1 − ξ − η − ζ, ξ, η, ζ).
pub const fn tet4_n(xi: [f64; 3]) -> [f64; 4] {
    [1.0 - xi[0] - xi[1] - xi[2], xi[0], xi[1], xi[2]]
}

/// ∂N_a/∂ξ of the tet4 (constant).
pub const fn tet4_dn(_xi: [f64; 3]) -> [[f64; 3]; 4] {
    [
        [-1.0, -1.0, -1.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ]
}

/// Edges of the tet10 holding its midside nodes 4..9 (the mesh's node convention).
pub use crate::mesh::TET10_EDGES;

/// Barycentric coordinates L = (1 − ξ − η − ζ, ξ, η, ζ) and their constant gradients.
const fn tet_bary(xi: [f64; 3]) -> [f64; 4] {
    tet4_n(xi)
}

/// Quadratic tet10 shape functions: corners N_i = L_i (2 L_i − 1), midside nodes
/// N_ij = 4 L_i L_j (Hughes §3.I, Zienkiewicz & Taylor vol. 1 §6.6).
pub const fn tet10_n(xi: [f64; 3]) -> [f64; 10] {
    let l = tet_bary(xi);
    let mut n = [0.0; 10];
    let mut a = 0;
    while a < 4 {
        n[a] = l[a] * (2.0 * l[a] - 1.0);
        a += 1;
    }
    let mut e = 0;
    while e < 6 {
        let [i, j] = TET10_EDGES[e];
        n[4 + e] = 4.0 * l[i] * l[j];
        e += 1;
    }
    n
}

/// ∂N_a/∂ξ of the tet10, `[a][j]`.
pub const fn tet10_dn(xi: [f64; 3]) -> [[f64; 3]; 10] {
    let l = tet_bary(xi);
    let dl = tet4_dn(xi);
    let mut d = [[0.0; 3]; 10];
    let mut a = 0;
    while a < 4 {
        let mut j = 0;
        while j < 3 {
            d[a][j] = (4.0 * l[a] - 1.0) * dl[a][j];
            j += 1;
        }
        a += 1;
    }
    let mut e = 0;
    while e < 6 {
        let [p, q] = TET10_EDGES[e];
        let mut j = 0;
        while j < 3 {
            d[4 + e][j] = 4.0 * (l[p] * dl[q][j] + l[q] * dl[p][j]);
            j += 1;
        }
        e += 1;
    }
    d
}

/// Bilinear quad4 shape functions N_a = ¼ (1 + ξ ξ_a)(1 + η η_a).
pub const fn quad4_n(xi: [f64; 2]) -> [f64; 4] {
    let mut n = [0.0; 4];
    let mut a = 0;
    while a < 4 {
        let p = QUAD4_NODES[a];
        n[a] = 0.25 * (1.0 + xi[0] * p[0]) * (1.0 + xi[1] * p[1]);
        a += 1;
    }
    n
}

/// ∂N_a/∂ξ of the quad4, `[a][j]`.
pub const fn quad4_dn(xi: [f64; 2]) -> [[f64; 2]; 4] {
    let mut d = [[0.0; 2]; 4];
    let mut a = 0;
    while a < 4 {
        let p = QUAD4_NODES[a];
        d[a] = [
            0.25 * p[0] * (1.0 + xi[1] * p[1]),
            0.25 * (1.0 + xi[0] * p[0]) * p[1],
        ];
        a += 1;
    }
    d
}

/// Linear tri3 shape functions N = (1 − ξ − η, ξ, η).
pub const fn tri3_n(xi: [f64; 2]) -> [f64; 3] {
    [1.0 - xi[0] - xi[1], xi[0], xi[1]]
}

/// ∂N_a/∂ξ of the tri3 (constant).
pub const fn tri3_dn(_xi: [f64; 2]) -> [[f64; 2]; 3] {
    [[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]]
}

/// Wedge6 (prism) shape functions: triangle (ξ, η) × ζ ∈ [−1, 1]; nodes 0-1-2 the
/// bottom triangle (ζ = −1, counter-clockwise seen from the top), 3-4-5 above them
/// (Gmsh's order): N = L_i (1 ∓ ζ)/2 with L = (1 − ξ − η, ξ, η).
pub const fn wedge6_n(xi: [f64; 3]) -> [f64; 6] {
    let l = [1.0 - xi[0] - xi[1], xi[0], xi[1]];
    let (b, t) = (0.5 * (1.0 - xi[2]), 0.5 * (1.0 + xi[2]));
    [l[0] * b, l[1] * b, l[2] * b, l[0] * t, l[1] * t, l[2] * t]
}

/// ∂N_a/∂ξ of the wedge6.
pub const fn wedge6_dn(xi: [f64; 3]) -> [[f64; 3]; 6] {
    let l = [1.0 - xi[0] - xi[1], xi[0], xi[1]];
    let (b, t) = (0.5 * (1.0 - xi[2]), 0.5 * (1.0 + xi[2]));
    [
        [-b, -b, -0.5 * l[0]],
        [b, 0.0, -0.5 * l[1]],
        [0.0, b, -0.5 * l[2]],
        [-t, -t, 0.5 * l[0]],
        [t, 0.0, 0.5 * l[1]],
        [0.0, t, 0.5 * l[2]],
    ]
}

/// Quadratic tri6 shape functions: corners (0,0), (1,0), (0,1), then the midside nodes
/// of edges 0-1, 1-2, 2-0 (Gmsh's order, the tet10's face order): N = L(2L − 1) at a
/// corner, 4 L_i L_j at a midside node, with L = (1 − ξ − η, ξ, η).
pub const fn tri6_n(xi: [f64; 2]) -> [f64; 6] {
    let l = [1.0 - xi[0] - xi[1], xi[0], xi[1]];
    [
        l[0] * (2.0 * l[0] - 1.0),
        l[1] * (2.0 * l[1] - 1.0),
        l[2] * (2.0 * l[2] - 1.0),
        4.0 * l[0] * l[1],
        4.0 * l[1] * l[2],
        4.0 * l[2] * l[0],
    ]
}

/// ∂N_a/∂ξ of the tri6 (∂L/∂ξ = (−1, 1, 0), ∂L/∂η = (−1, 0, 1)).
pub const fn tri6_dn(xi: [f64; 2]) -> [[f64; 2]; 6] {
    let l = [1.0 - xi[0] - xi[1], xi[0], xi[1]];
    let c0 = 1.0 - 4.0 * l[0];
    [
        [c0, c0],
        [4.0 * l[1] - 1.0, 0.0],
        [0.0, 4.0 * l[2] - 1.0],
        [4.0 * (l[0] - l[1]), -4.0 * l[1]],
        [4.0 * l[2], 4.0 * l[1]],
        [-4.0 * l[2], 4.0 * (l[0] - l[2])],
    ]
}

/// A reference element's shape functions tabulated at its integration rule:
/// dimension `D`, `N` nodes, `G` points.
#[derive(Debug, Clone, Copy)]
pub struct Tabulated<const D: usize, const N: usize, const G: usize> {
    /// Integration points in natural coordinates.
    pub points: [[f64; D]; G],
    /// Weights (sum = reference volume: 8 for hex8, 1/6 for tet4, 4 quad4, 1/2 tri3).
    pub weights: [f64; G],
    /// N_a at each point, `[g][a]`.
    pub n: [[f64; N]; G],
    /// ∂N_a/∂ξ_j at each point, `[g][a][j]`.
    pub dn: [[[f64; D]; N]; G],
}

const fn hex8_table() -> Tabulated<3, 8, 8> {
    let mut t = Tabulated {
        points: [[0.0; 3]; 8],
        weights: [1.0; 8],
        n: [[0.0; 8]; 8],
        dn: [[[0.0; 3]; 8]; 8],
    };
    // Points at the nodes' corners scaled by 1/√3, so point g sits nearest node g.
    let mut g = 0;
    while g < 8 {
        let p = HEX8_NODES[g];
        let xi = [p[0] * GAUSS2, p[1] * GAUSS2, p[2] * GAUSS2];
        t.points[g] = xi;
        t.n[g] = hex8_n(xi);
        t.dn[g] = hex8_dn(xi);
        g += 1;
    }
    t
}

const fn quad4_table() -> Tabulated<2, 4, 4> {
    let mut t = Tabulated {
        points: [[0.0; 2]; 4],
        weights: [1.0; 4],
        n: [[0.0; 4]; 4],
        dn: [[[0.0; 2]; 4]; 4],
    };
    let mut g = 0;
    while g < 4 {
        let p = QUAD4_NODES[g];
        let xi = [p[0] * GAUSS2, p[1] * GAUSS2];
        t.points[g] = xi;
        t.n[g] = quad4_n(xi);
        t.dn[g] = quad4_dn(xi);
        g += 1;
    }
    t
}

const fn tri3_table() -> Tabulated<2, 3, 3> {
    // Strang–Fix 3-point interior rule, exact for quadratics (Hughes Table 3.I.1).
    let points = [
        [1.0 / 6.0, 1.0 / 6.0],
        [2.0 / 3.0, 1.0 / 6.0],
        [1.0 / 6.0, 2.0 / 3.0],
    ];
    let mut t = Tabulated {
        points,
        weights: [1.0 / 6.0; 3],
        n: [[0.0; 3]; 3],
        dn: [[[0.0; 2]; 3]; 3],
    };
    let mut g = 0;
    while g < 3 {
        t.n[g] = tri3_n(points[g]);
        t.dn[g] = tri3_dn(points[g]);
        g += 1;
    }
    t
}

const fn wedge6_table() -> Tabulated<3, 6, 6> {
    // The tri3's 3-point rule (degree 2) times 2-point Gauss in ζ (degree 3): exact for
    // the volume and the stiffness of a prism with parallel triangles.
    let tri = [
        [1.0 / 6.0, 1.0 / 6.0],
        [2.0 / 3.0, 1.0 / 6.0],
        [1.0 / 6.0, 2.0 / 3.0],
    ];
    let mut t = Tabulated {
        points: [[0.0; 3]; 6],
        weights: [1.0 / 6.0; 6],
        n: [[0.0; 6]; 6],
        dn: [[[0.0; 3]; 6]; 6],
    };
    let mut g = 0;
    while g < 6 {
        let z = if g < 3 { -GAUSS2 } else { GAUSS2 };
        let p = [tri[g % 3][0], tri[g % 3][1], z];
        t.points[g] = p;
        t.n[g] = wedge6_n(p);
        t.dn[g] = wedge6_dn(p);
        g += 1;
    }
    t
}

const fn tri6_table() -> Tabulated<2, 6, 6> {
    // Dunavant's 6-point rule of degree 4 (Strang–Fix): barycentric (a, b, b) with
    // a = 0.108103018168070, b = 0.445948490915965, weight 0.223381589678011, and
    // (c, d, d) with c = 0.816847572980459, d = 0.091576213509771, weight
    // 0.109951743655322 (weights for area 1, halved here).
    const A: f64 = 0.108_103_018_168_070;
    const B: f64 = 0.445_948_490_915_965;
    const C: f64 = 0.816_847_572_980_459;
    const D: f64 = 0.091_576_213_509_771;
    const WA: f64 = 0.5 * 0.223_381_589_678_011;
    const WC: f64 = 0.5 * 0.109_951_743_655_322;
    let points = [[B, B], [A, B], [B, A], [D, D], [C, D], [D, C]];
    let mut t = Tabulated {
        points,
        weights: [WA, WA, WA, WC, WC, WC],
        n: [[0.0; 6]; 6],
        dn: [[[0.0; 2]; 6]; 6],
    };
    let mut g = 0;
    while g < 6 {
        t.n[g] = tri6_n(points[g]);
        t.dn[g] = tri6_dn(points[g]);
        g += 1;
    }
    t
}

const fn tet10_table() -> Tabulated<3, 10, 4> {
    // The 4-point rule of degree 2 (Hughes Table 3.I.2; Abaqus C3D10): barycentric
    // (a, b, b, b) and permutations, a = (5 + 3√5)/20, b = (5 − √5)/20. The stiffness
    // integrand Bᵀ C B of an undistorted (straight-sided) tet10 is quadratic, so the
    // rule is exact for it, and for the volume (constant det J₀); it has no spurious
    // zero-energy modes on the element.
    const A: f64 = 0.585_410_196_624_968_5;
    const B: f64 = 0.138_196_601_125_010_5;
    let points = [[B, B, B], [A, B, B], [B, A, B], [B, B, A]];
    let mut t = Tabulated {
        points,
        weights: [1.0 / 24.0; 4],
        n: [[0.0; 10]; 4],
        dn: [[[0.0; 3]; 10]; 4],
    };
    let mut g = 0;
    while g < 4 {
        t.n[g] = tet10_n(points[g]);
        t.dn[g] = tet10_dn(points[g]);
        g += 1;
    }
    t
}

/// Tet10 with the 4-point degree-2 rule (exact for the stiffness of a straight-sided
/// element).
pub const TET10: Tabulated<3, 10, 4> = tet10_table();

/// Hex8 with the 2×2×2 Gauss rule (exact for the trilinear element's mass and volume).
pub const HEX8: Tabulated<3, 8, 8> = hex8_table();
/// Tet4 with the 1-point centroid rule (exact: ∇N is constant).
pub const TET4: Tabulated<3, 4, 1> = Tabulated {
    points: [[0.25; 3]],
    weights: [1.0 / 6.0],
    n: [tet4_n([0.25; 3])],
    dn: [tet4_dn([0.25; 3])],
};
/// Quad4 face with the 2×2 Gauss rule (exact for the area vector x,ξ × x,η).
pub const QUAD4: Tabulated<2, 4, 4> = quad4_table();
/// Wedge6 with the 3 × 2 rule (reference volume 1).
pub const WEDGE6: Tabulated<3, 6, 6> = wedge6_table();
/// Tri6 face with the 6-point degree-4 rule: N_a (degree 2) times the area vector of a
/// curved face (degree 2) is exact; a flat face needs degree 2 only.
pub const TRI6: Tabulated<2, 6, 6> = tri6_table();
/// Tri3 face with the 3-point rule (N_a times constant area vector needs degree 1; the
/// extra points keep consistent face masses exact later).
pub const TRI3: Tabulated<2, 3, 3> = tri3_table();

#[cfg(test)]
mod tests {
    use super::*;

    /// A few interior points, including off-axis ones.
    const PTS3: [[f64; 3]; 4] = [
        [0.1, -0.3, 0.7],
        [-0.8, 0.2, 0.05],
        [0.0, 0.0, 0.0],
        [0.15, 0.2, 0.3],
    ];

    fn fd3<const N: usize>(
        n: fn([f64; 3]) -> [f64; N],
        dn: fn([f64; 3]) -> [[f64; 3]; N],
        x: [f64; 3],
    ) {
        let h = 1e-6;
        let d = dn(x);
        for j in 0..3 {
            let (mut xp, mut xm) = (x, x);
            xp[j] += h;
            xm[j] -= h;
            let (np, nm) = (n(xp), n(xm));
            for a in 0..N {
                let fd = (np[a] - nm[a]) / (2.0 * h);
                assert!(
                    (fd - d[a][j]).abs() < 1e-8,
                    "node {a} dir {j}: {fd} vs {}",
                    d[a][j]
                );
            }
        }
    }

    fn fd2<const N: usize>(
        n: fn([f64; 2]) -> [f64; N],
        dn: fn([f64; 2]) -> [[f64; 2]; N],
        x: [f64; 2],
    ) {
        let h = 1e-6;
        let d = dn(x);
        for j in 0..2 {
            let (mut xp, mut xm) = (x, x);
            xp[j] += h;
            xm[j] -= h;
            let (np, nm) = (n(xp), n(xm));
            for a in 0..N {
                let fd = (np[a] - nm[a]) / (2.0 * h);
                assert!(
                    (fd - d[a][j]).abs() < 1e-8,
                    "node {a} dir {j}: {fd} vs {}",
                    d[a][j]
                );
            }
        }
    }

    #[test]
    fn partition_of_unity() {
        for x in PTS3 {
            assert!((hex8_n(x).iter().sum::<f64>() - 1.0).abs() < 1e-14);
            assert!((tet4_n(x).iter().sum::<f64>() - 1.0).abs() < 1e-14);
            assert!((tet10_n(x).iter().sum::<f64>() - 1.0).abs() < 1e-14);
            for j in 0..3 {
                assert!(tet10_dn(x).iter().map(|d| d[j]).sum::<f64>().abs() < 1e-13);
            }
            for j in 0..3 {
                assert!(hex8_dn(x).iter().map(|d| d[j]).sum::<f64>().abs() < 1e-14);
            }
            let y = [x[0], x[1]];
            assert!((quad4_n(y).iter().sum::<f64>() - 1.0).abs() < 1e-14);
            assert!((tri3_n(y).iter().sum::<f64>() - 1.0).abs() < 1e-14);
        }
    }

    #[test]
    fn kronecker_at_nodes() {
        for (a, p) in HEX8_NODES.iter().enumerate() {
            let n = hex8_n(*p);
            for (b, v) in n.iter().enumerate() {
                assert_eq!(*v, if a == b { 1.0 } else { 0.0 });
            }
        }
        for (a, p) in QUAD4_NODES.iter().enumerate() {
            let n = quad4_n(*p);
            for (b, v) in n.iter().enumerate() {
                assert_eq!(*v, if a == b { 1.0 } else { 0.0 });
            }
        }
        let tet = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        for (a, p) in tet.iter().enumerate() {
            assert_eq!(tet4_n(*p)[a], 1.0);
        }
        // Tet10: corners, then the midpoints of its edges.
        let mut t10: Vec<[f64; 3]> = tet.to_vec();
        for [i, j] in TET10_EDGES {
            t10.push(std::array::from_fn(|c| 0.5 * (tet[i][c] + tet[j][c])));
        }
        for (a, p) in t10.iter().enumerate() {
            let n = tet10_n(*p);
            for (b, v) in n.iter().enumerate() {
                assert!(
                    (v - if a == b { 1.0 } else { 0.0 }).abs() < 1e-15,
                    "{a} {b} {v}"
                );
            }
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        for x in PTS3 {
            fd3(hex8_n, hex8_dn, x);
            fd3(tet4_n, tet4_dn, x);
            fd3(tet10_n, tet10_dn, x);
            fd2(quad4_n, quad4_dn, [x[0], x[1]]);
            fd2(tri3_n, tri3_dn, [x[0], x[1]]);
        }
    }

    #[test]
    fn tables_are_consistent() {
        assert!((HEX8.weights.iter().sum::<f64>() - 8.0).abs() < 1e-14);
        assert!((TET4.weights.iter().sum::<f64>() - 1.0 / 6.0).abs() < 1e-14);
        assert!((QUAD4.weights.iter().sum::<f64>() - 4.0).abs() < 1e-14);
        assert!((TRI3.weights.iter().sum::<f64>() - 0.5).abs() < 1e-14);
        for g in 0..8 {
            assert_eq!(HEX8.dn[g], hex8_dn(HEX8.points[g]));
            assert_eq!(HEX8.n[g], hex8_n(HEX8.points[g]));
        }
        // 2×2×2 Gauss integrates ξ²η²ζ² exactly: (2/3)³.
        let q: f64 = (0..8)
            .map(|g| HEX8.weights[g] * HEX8.points[g].iter().map(|x| x * x).product::<f64>())
            .sum();
        assert!((q - 8.0 / 27.0).abs() < 1e-14);
        // The tri3 rule integrates ξ² exactly: 1/12.
        let q: f64 = (0..3)
            .map(|g| TRI3.weights[g] * TRI3.points[g][0].powi(2))
            .sum();
        assert!((q - 1.0 / 12.0).abs() < 1e-14);
        // The tet10 rule: weights sum to 1/6, exact for every monomial of degree ≤ 2
        // (∫ ξ² = 1/60, ∫ ξη = 1/120 on the unit tet), and its tables match.
        assert!((TET10.weights.iter().sum::<f64>() - 1.0 / 6.0).abs() < 1e-15);
        let int = |f: &dyn Fn([f64; 3]) -> f64| -> f64 {
            (0..4).map(|g| TET10.weights[g] * f(TET10.points[g])).sum()
        };
        assert!((int(&|p| p[0]) - 1.0 / 24.0).abs() < 1e-15);
        assert!((int(&|p| p[1] * p[1]) - 1.0 / 60.0).abs() < 1e-15);
        assert!((int(&|p| p[0] * p[2]) - 1.0 / 120.0).abs() < 1e-15);
        for g in 0..4 {
            assert_eq!(TET10.n[g], tet10_n(TET10.points[g]));
            assert_eq!(TET10.dn[g], tet10_dn(TET10.points[g]));
        }
    }
}
