//! Measures of one element that do not depend on its formulation: the reference-shape
//! check, volume, characteristic length, thickness, and the von Mises value of its
//! stress.

use super::error::{At, ElementError};
use super::kernel::nodes;
use super::kinematics::reference_gradients;
use super::shape::{
    hex8_dn, tet10_dn, wedge6_dn, Tabulated, HEX8, HEX8_NODES, TET10, TET4, WEDGE6,
};
use crate::mesh::ElemKind;

/// Reference-configuration check: `Err` with a short reason if det J ≤ 0, or tiny
/// relative to the element's size, at any Gauss point or corner (an inverted or
/// degenerate element). Corners catch warped hexes that the Gauss points miss.
pub fn check_reference(kind: ElemKind, x0: &[[f64; 3]]) -> Result<(), ElementError> {
    // Scaled Jacobian det J · (reference volume) / diameter³: ≈ 0.19 for a cube and
    // ≈ 0.12 for a regular tet, so 1e-6 only flags elements that are flat in practice.
    const TINY: f64 = 1e-6;
    let d = diameter(x0);
    let check = |det: f64, at: At, ref_vol: f64| -> Result<(), ElementError> {
        if det.is_nan() || det <= 0.0 {
            return Err(ElementError::InvertedShape {
                kind: kind.name(),
                at,
                det,
            });
        }
        if det * ref_vol < TINY * d * d * d {
            return Err(ElementError::DegenerateShape {
                kind: kind.name(),
                at,
                det,
                size: d,
            });
        }
        Ok(())
    };
    match kind {
        ElemKind::Hex8 => {
            let x0: &[[f64; 3]; 8] = nodes(x0);
            for g in 0..8 {
                check(reference_gradients(x0, &HEX8.dn[g]).1, At::Gauss(g), 8.0)?;
            }
            for (c, xi) in HEX8_NODES.iter().enumerate() {
                let dn = hex8_dn(*xi);
                check(reference_gradients(x0, &dn).1, At::Corner(c), 8.0)?;
            }
            Ok(())
        }
        ElemKind::Tet4 => check(
            reference_gradients(nodes::<4>(x0), &TET4.dn[0]).1,
            At::Centroid,
            1.0 / 6.0,
        ),
        // Gauss points, then corners: a midside node pulled far off its edge folds the
        // element near a corner before its points see it.
        ElemKind::Tet10 => {
            let x0: &[[f64; 3]; 10] = nodes(x0);
            for g in 0..4 {
                check(
                    reference_gradients(x0, &TET10.dn[g]).1,
                    At::Gauss(g),
                    1.0 / 6.0,
                )?;
            }
            for c in 0..4 {
                let xi = std::array::from_fn(|j| if c == j + 1 { 1.0 } else { 0.0 });
                let dn = tet10_dn(xi);
                check(reference_gradients(x0, &dn).1, At::Corner(c), 1.0 / 6.0)?;
            }
            Ok(())
        }
        // Gauss points, then corners (reference volume 1).
        ElemKind::Wedge6 => {
            let x0: &[[f64; 3]; 6] = nodes(x0);
            for g in 0..6 {
                check(reference_gradients(x0, &WEDGE6.dn[g]).1, At::Gauss(g), 1.0)?;
            }
            const CORNERS: [[f64; 3]; 6] = [
                [0.0, 0.0, -1.0],
                [1.0, 0.0, -1.0],
                [0.0, 1.0, -1.0],
                [0.0, 0.0, 1.0],
                [1.0, 0.0, 1.0],
                [0.0, 1.0, 1.0],
            ];
            for (c, xi) in CORNERS.iter().enumerate() {
                let dn = wedge6_dn(*xi);
                check(reference_gradients(x0, &dn).1, At::Corner(c), 1.0)?;
            }
            Ok(())
        }
    }
}

/// Reference volume (exact for both kinds: det J of a trilinear map is integrated exactly
/// by the 2×2×2 rule). Negative for an inverted element.
pub fn element_volume(kind: ElemKind, x0: &[[f64; 3]]) -> f64 {
    fn vol<const N: usize, const G: usize>(t: &Tabulated<3, N, G>, x0: &[[f64; 3]; N]) -> f64 {
        (0..G)
            .map(|g| t.weights[g] * reference_gradients(x0, &t.dn[g]).1)
            .sum()
    }
    match kind {
        ElemKind::Hex8 => vol(&HEX8, nodes(x0)),
        ElemKind::Tet4 => vol(&TET4, nodes(x0)),
        ElemKind::Tet10 => vol(&TET10, nodes(x0)),
        ElemKind::Wedge6 => vol(&WEDGE6, nodes(x0)),
    }
}

/// A characteristic length |volume|^(1/3); used for finite-difference step sizes and
/// penalty scales.
pub fn char_length(kind: ElemKind, x0: &[[f64; 3]]) -> f64 {
    element_volume(kind, x0).abs().cbrt()
}

/// The element's thickness in its thinnest direction: volume / largest face area (faces
/// of a hex8 by half the cross product of their diagonals). Its ratio between the
/// current and the reference configuration scales the explicit stable step as the
/// element is squashed. `None` for an inverted or degenerate configuration.
pub fn thickness(kind: ElemKind, x: &[[f64; 3]]) -> Option<f64> {
    let v = element_volume(kind, x);
    let mut corners = [[0.0; 3]; 4];
    let amax = (0..kind.faces().len())
        .map(|fi| kind.face_corners(fi))
        .map(|f| {
            for (c, &i) in corners.iter_mut().zip(f.iter()) {
                *c = x[i];
            }
            crate::mesh::select::face_area(&corners[..f.len()])
        })
        .fold(0.0, f64::max);
    let t = v / amax;
    (t.is_finite() && t > 0.0).then_some(t)
}

/// von Mises equivalent stress √(3/2 s:s) of a Voigt stress (s the deviator).
pub fn von_mises(s: &[f64; 6]) -> f64 {
    let (a, b, c) = (s[0] - s[1], s[1] - s[2], s[2] - s[0]);
    (0.5 * (a * a + b * b + c * c) + 3.0 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5])).sqrt()
}

/// Largest distance between two nodes.
fn diameter(x: &[[f64; 3]]) -> f64 {
    let mut d2: f64 = 0.0;
    for (i, a) in x.iter().enumerate() {
        for b in &x[i + 1..] {
            d2 = d2.max((0..3).map(|k| (a[k] - b[k]).powi(2)).sum());
        }
    }
    d2.sqrt()
}
