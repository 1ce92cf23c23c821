//! Solid element kernels: internal force, consistent tangent and stress of one hex8 or
//! tet4, total Lagrangian written in the spatial form of Simo & Hughes, *Computational
//! Inelasticity*, §7.2 / Bonet & Wood, *Nonlinear Continuum Mechanics for FEA*, §8–9:
//!
//! * F = I + Σ_a u_a ⊗ ∇_X N_a,   ∇_x N_a = F⁻ᵀ ∇_X N_a;
//! * f_a = Σ_gp τ ∇_x N_a w det J₀  (= ∫ P ∇_X N_a dV with P = τ F⁻ᵀ);
//! * K_ab = Σ_gp [B_aᵀ c B_b + (∇_x N_a · τ ∇_x N_b) I] w det J₀ (material + geometric),
//!   with c the spatial tangent of the Kirchhoff stress and B the spatial
//!   strain-displacement matrix with engineering shear (B&W eq. 9.35–9.44).
//!
//! For [`Kinematics::Small`] the same loop runs with ∇_X in place of ∇_x, the Cauchy
//! stress, and no geometric term (Hughes, *The Finite Element Method*, §3.9).
//!
//! Everything is on the stack with const-generic node and point counts. The per-point
//! pieces ([`reference_gradients`], [`deformation_gradient`], the force and tangent
//! accumulators) are separate so an F-bar hex8 (F̄ = (J̄/J)^{1/3} F, de Souza Neto et al.
//! 1996) can reuse them with only a modified F and an extra tangent term.

use super::kinematics::{
    add_fbar_tangent, add_force, add_tangent, element_kinematics, LocalTangent,
};
pub use super::kinematics::{deformation_gradient, reference_gradients, ElementError};
use super::shape::{Tabulated, HEX8, HEX8_NODES, TET4};
use crate::material::{Kinematics, Material};
use crate::mesh::ElemKind;

/// How the element treats volume change.
///
/// * `Standard`: full 2×2×2 integration of F; hex8 locks when the material is nearly
///   incompressible or the flow is isochoric (the constraint J = 1 at 8 points).
/// * `FBar`: F̄ = (J̄/J)^{1/3} F at every point with J̄ = v/V, the element's volume ratio
///   (de Souza Neto, Perić & Owen, *Computational Methods for Plasticity*, §15.2, with
///   the mean-dilatation choice of J̄, which makes the volumetric part one constant per
///   element as in Q1/P0, Simo–Taylor–Pister 1985). Small kinematics uses the same idea
///   as B-bar: ε̄ = ε + (θ̄ − tr ε)/3 I with θ̄ the volume average of tr ε (Hughes §4.5).
///   The consistent tangent gains the non-symmetric term of de Souza Neto eq. 15.20.
///   Only hex8 changes; a one-point tet4 is the same either way.
/// * `Reduced`: one point with the mean gradients and a hourglass stiffness
///   ([`super::reduced`]; LS-DYNA's default solid). Does not lock, and its hourglass
///   modes stay at their reference stiffness under any compression.
///
/// `hourglass` scales the hourglass spring of [`super::reduced`] (1 = the element's own
/// deviatoric stiffness in those modes). On F-bar it is added to the full element
/// (default 0): under compressions beyond about 40 % the pressure's geometric stiffness
/// turns an F-bar hourglass mode negative and elements fold one by one; the spring
/// holds them, at the price of some extra stiffness (measured in README "Why
/// rubber-indent stops").
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub enum Formulation {
    #[default]
    Standard,
    FBar {
        hourglass: f64,
    },
    Reduced {
        hourglass: f64,
    },
    /// Enhanced assumed strains, Q1/E9 ([`super::eas`]): bends with one element through
    /// a thin wall.
    Eas,
    /// F-bar with its pressure as an unknown, one per element ([`super::hybrid`], as
    /// Abaqus' C3D8H): the same answers, and Newton converges on nearly incompressible
    /// solids as on compressible ones. Without its pressure unknown (here) it is F-bar.
    Hybrid {
        hourglass: f64,
    },
}

impl Formulation {
    /// F-bar without hourglass spring.
    pub const FBAR: Formulation = Formulation::FBar { hourglass: 0.0 };
    /// The reduced element with its reference hourglass stiffness.
    pub const REDUCED: Formulation = Formulation::Reduced { hourglass: 1.0 };

    /// F-bar kinematics: F-bar itself, and the hybrid element (F-bar with its pressure
    /// as an unknown; without the unknown, as here, it is F-bar).
    fn is_fbar(self) -> bool {
        matches!(self, Formulation::FBar { .. } | Formulation::Hybrid { .. })
    }

    /// A short description for `alfe check`: how hex8 elements of the part behave.
    pub fn describe(self) -> String {
        let hg = |h: f64| {
            if h > 0.0 {
                format!(", hourglass {h}")
            } else {
                String::new()
            }
        };
        match self {
            Formulation::Standard => "standard hex8".into(),
            Formulation::FBar { hourglass } => format!("F-bar hex8{}", hg(hourglass)),
            Formulation::Reduced { hourglass } => format!("reduced hex8, hourglass {hourglass}"),
            Formulation::Eas => "EAS hex8".into(),
            Formulation::Hybrid { hourglass } => format!("hybrid hex8{}", hg(hourglass)),
        }
    }

    /// Whether the element carries a pressure unknown (a block of its own).
    pub fn is_hybrid(self) -> bool {
        matches!(self, Formulation::Hybrid { .. })
    }
}

/// Number of integration points of the kind's rule under `form` (history is stored per
/// point).
/// History values of one element: its points' material history (and, for EAS, its
/// enhanced parameters after them).
pub fn state_len(kind: ElemKind, form: Formulation, n_state: usize) -> usize {
    match (kind, form) {
        (ElemKind::Hex8, Formulation::Eas) => super::eas::state_len(n_state),
        _ => n_gauss(kind, form) * n_state,
    }
}

pub fn n_gauss(kind: ElemKind, form: Formulation) -> usize {
    match (kind, form) {
        (ElemKind::Hex8, Formulation::Reduced { .. }) => 1,
        (ElemKind::Hex8, _) => 8,
        (ElemKind::Tet4, _) => 1,
    }
}

/// Internal force f (len 3n, node-major: `f[3a+i]`) and, if `k` is `Some`, the
/// consistent tangent (3n×3n row-major, `k[(3a+i)*3n + 3b+j]`) of one element.
///
/// `x0`: reference coordinates of the element nodes, `u`: nodal displacements.
/// `state_old`/`state_new`: `n_gauss(kind, form) * mat.n_state()` history values (empty for
/// elastic models). `f` and `k` are overwritten, not accumulated.
///
/// `form` selects F-bar or the reduced element for hex8, with its hourglass spring (see
/// [`Formulation`]).
///
/// Finite kinematics: det F ≤ 0 at a point is an error. Small kinematics never checks
/// det F: a linear model is defined for any displacement, and Newton's first trial on a
/// linear problem may overshoot without meaning anything.
///
/// # Panics
/// If slice lengths do not match the kind (a caller bug, not a model condition).
#[allow(clippy::too_many_arguments)]
pub fn element_force(
    kind: ElemKind,
    form: Formulation,
    x0: &[[f64; 3]],
    u: &[[f64; 3]],
    mat: &dyn Material,
    state_old: &[f64],
    state_new: &mut [f64],
    f: &mut [f64],
    k: Option<&mut [f64]>,
) -> Result<(), ElementError> {
    match kind {
        ElemKind::Hex8 => match form {
            Formulation::Eas => {
                super::eas::force(nodes(x0), nodes(u), mat, state_old, state_new, f, k)
            }
            Formulation::Reduced { hourglass } => super::reduced::force(
                nodes(x0),
                nodes(u),
                mat,
                hourglass,
                state_old,
                state_new,
                f,
                k,
            ),
            _ => {
                let mut k = k;
                force_kernel(
                    &HEX8,
                    form.is_fbar(),
                    nodes(x0),
                    nodes(u),
                    mat,
                    state_old,
                    state_new,
                    f,
                    k.as_deref_mut(),
                )?;
                match form {
                    Formulation::FBar { hourglass } | Formulation::Hybrid { hourglass }
                        if hourglass > 0.0 =>
                    {
                        super::reduced::add_hourglass(
                            nodes(x0),
                            nodes(u),
                            mat.shear_modulus(),
                            hourglass,
                            f,
                            k,
                        )
                    }
                    _ => Ok(()),
                }
            }
        },
        ElemKind::Tet4 => force_kernel(
            &TET4,
            false,
            nodes(x0),
            nodes(u),
            mat,
            state_old,
            state_new,
            f,
            k,
        ),
    }
}

/// Volume-averaged Cauchy stress σ (Voigt) of the element at displacement `u`:
/// (1/v) ∫ σ dv = Σ τ w det J₀ / Σ J w det J₀ (finite), or the plain average of σ (small).
pub fn element_stress(
    kind: ElemKind,
    form: Formulation,
    x0: &[[f64; 3]],
    u: &[[f64; 3]],
    mat: &dyn Material,
    state_old: &[f64],
) -> Result<[f64; 6], ElementError> {
    match kind {
        ElemKind::Hex8 if matches!(form, Formulation::Reduced { .. }) => {
            super::reduced::stress(nodes(x0), nodes(u), mat, state_old)
        }
        ElemKind::Hex8 if form == Formulation::Eas => {
            super::eas::stress(nodes(x0), nodes(u), mat, state_old)
        }
        ElemKind::Hex8 => stress_kernel(&HEX8, form.is_fbar(), nodes(x0), nodes(u), mat, state_old),
        ElemKind::Tet4 => stress_kernel(&TET4, false, nodes(x0), nodes(u), mat, state_old),
    }
}

/// Reference-configuration check: `Err` with a short reason if det J ≤ 0, or tiny
/// relative to the element's size, at any Gauss point or corner (an inverted or
/// degenerate element). Corners catch warped hexes that the Gauss points miss.
pub fn check_reference(kind: ElemKind, x0: &[[f64; 3]]) -> Result<(), String> {
    // Scaled Jacobian det J · (reference volume) / diameter³: ≈ 0.19 for a cube and
    // ≈ 0.12 for a regular tet, so 1e-6 only flags elements that are flat in practice.
    const TINY: f64 = 1e-6;
    let d = diameter(x0);
    let check = |det: f64, where_: &str, ref_vol: f64| -> Result<(), String> {
        if det.is_nan() || det <= 0.0 {
            return Err(format!(
                "inverted {}: det J = {det:.3e} ≤ 0 at {where_}",
                kind.name()
            ));
        }
        if det * ref_vol < TINY * d * d * d {
            return Err(format!(
                "degenerate {}: det J = {det:.3e} at {where_} is tiny for its size {d:.3e}",
                kind.name()
            ));
        }
        Ok(())
    };
    match kind {
        ElemKind::Hex8 => {
            let x0: &[[f64; 3]; 8] = nodes(x0);
            for g in 0..8 {
                check(
                    reference_gradients(x0, &HEX8.dn[g]).1,
                    &format!("Gauss point {g}"),
                    8.0,
                )?;
            }
            for (c, xi) in HEX8_NODES.iter().enumerate() {
                let dn = super::shape::hex8_dn(*xi);
                check(reference_gradients(x0, &dn).1, &format!("corner {c}"), 8.0)?;
            }
            Ok(())
        }
        ElemKind::Tet4 => check(
            reference_gradients(nodes::<4>(x0), &TET4.dn[0]).1,
            "its centroid",
            1.0 / 6.0,
        ),
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
    let amax = kind
        .faces()
        .iter()
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

/// View a node slice as a fixed-size array; a length mismatch is a caller bug.
#[inline]
fn nodes<const N: usize>(x: &[[f64; 3]]) -> &[[f64; 3]; N] {
    x.try_into()
        .unwrap_or_else(|_| panic!("element has {} nodes, kind needs {N}", x.len()))
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

#[allow(clippy::too_many_arguments)]
fn force_kernel<const N: usize, const G: usize>(
    tab: &Tabulated<3, N, G>,
    fbar: bool,
    x0: &[[f64; 3]; N],
    u: &[[f64; 3]; N],
    mat: &dyn Material,
    state_old: &[f64],
    state_new: &mut [f64],
    f: &mut [f64],
    k: Option<&mut [f64]>,
) -> Result<(), ElementError> {
    let ns = mat.n_state();
    assert_eq!(f.len(), 3 * N, "force slice length");
    assert!(
        state_old.len() == G * ns && state_new.len() == G * ns,
        "history length must be n_gauss × n_state"
    );
    match k {
        Some(k) => {
            assert_eq!(k.len(), 9 * N * N, "tangent slice length");
            let mut kloc = [[[[0.0; 3]; N]; 3]; N];
            gauss_loop(
                tab,
                fbar,
                x0,
                u,
                mat,
                state_old,
                state_new,
                f,
                Some(&mut kloc),
            )?;
            k.copy_from_slice(kloc.as_flattened().as_flattened().as_flattened());
            Ok(())
        }
        None => gauss_loop(tab, fbar, x0, u, mat, state_old, state_new, f, None),
    }
}

/// The integration-point loop shared by force and force + tangent.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn gauss_loop<const N: usize, const G: usize>(
    tab: &Tabulated<3, N, G>,
    fbar: bool,
    x0: &[[f64; 3]; N],
    u: &[[f64; 3]; N],
    mat: &dyn Material,
    state_old: &[f64],
    state_new: &mut [f64],
    f: &mut [f64],
    mut k: Option<&mut LocalTangent<N>>,
) -> Result<(), ElementError> {
    let ns = mat.n_state();
    let kin = mat.kinematics();
    let finite = kin == Kinematics::Finite;
    let (pts, gbar) = element_kinematics(tab, fbar, kin, x0, u)?;
    f.fill(0.0);
    let merr = |g: usize, e: crate::material::MaterialError| {
        ElementError(format!("material at Gauss point {g}: {}", e.0))
    };
    for (g, p) in pts.iter().enumerate() {
        let (old, new) = (
            &state_old[g * ns..(g + 1) * ns],
            &mut state_new[g * ns..(g + 1) * ns],
        );
        match k.as_deref_mut() {
            Some(k) => {
                let sp = mat.evaluate(&p.f, old, new).map_err(|e| merr(g, e))?;
                add_force(&p.grad, &sp.stress, p.w, f);
                add_tangent(&p.grad, &sp, finite, p.w, k);
                if let Some(gb) = &gbar {
                    add_fbar_tangent(&p.grad, gb, &sp, finite, p.w, k);
                }
            }
            // A residual needs no tangent: the cheaper stress-only path.
            None => {
                let s = mat
                    .evaluate_stress(&p.f, old, new)
                    .map_err(|e| merr(g, e))?;
                add_force(&p.grad, &s, p.w, f);
            }
        }
    }
    Ok(())
}

fn stress_kernel<const N: usize, const G: usize>(
    tab: &Tabulated<3, N, G>,
    fbar: bool,
    x0: &[[f64; 3]; N],
    u: &[[f64; 3]; N],
    mat: &dyn Material,
    state_old: &[f64],
) -> Result<[f64; 6], ElementError> {
    const STACK: usize = 64;
    let ns = mat.n_state();
    assert_eq!(
        state_old.len(),
        G * ns,
        "history length must be n_gauss × n_state"
    );
    // The material writes trial history somewhere; it is discarded here.
    let mut stack = [0.0; STACK];
    let mut heap = Vec::new();
    let scratch: &mut [f64] = if ns <= STACK {
        &mut stack[..ns]
    } else {
        heap.resize(ns, 0.0);
        &mut heap
    };
    let kin = mat.kinematics();
    let (pts, _) = element_kinematics(tab, fbar, kin, x0, u)?;
    let (mut sum, mut vol) = ([0.0; 6], 0.0);
    for (g, p) in pts.iter().enumerate() {
        let stress = mat
            .evaluate_stress(&p.f, &state_old[g * ns..(g + 1) * ns], scratch)
            .map_err(|e| ElementError(format!("material at Gauss point {g}: {}", e.0)))?;
        for (s, t) in sum.iter_mut().zip(&stress) {
            *s += p.w * t;
        }
        // Kirchhoff τ integrated over dV, divided by v = ∫ J dV, is the mean of σ over dv
        // (under F-bar J̄ is constant and ∫ J̄ dV = v as well).
        vol += p.w
            * if kin == Kinematics::Finite {
                p.f.determinant()
            } else {
                1.0
            };
    }
    Ok(sum.map(|s| s / vol))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{LinearElastic, NeoHookean, StressPoint};
    use nalgebra::{Matrix3, Rotation3, Vector3};

    /// A unit-ish hex with every node moved off the cube by up to ~0.2 (non-parallel
    /// faces, warped sides), positively oriented.
    fn hex() -> Vec<[f64; 3]> {
        let d = [
            [0.05, -0.1, 0.02],
            [0.2, 0.07, -0.05],
            [-0.1, 0.15, 0.1],
            [0.08, -0.05, -0.12],
            [-0.07, 0.1, 0.15],
            [0.12, -0.15, 0.04],
            [0.18, 0.2, -0.08],
            [-0.15, 0.05, 0.1],
        ];
        HEX8_NODES
            .iter()
            .zip(&d)
            .map(|(p, d)| {
                [
                    0.5 * (p[0] + 1.0) * 1.4 + d[0],
                    0.5 * (p[1] + 1.0) + d[1],
                    0.5 * (p[2] + 1.0) * 0.8 + d[2],
                ]
            })
            .collect()
    }

    fn tet() -> Vec<[f64; 3]> {
        vec![
            [0.1, -0.05, 0.02],
            [1.2, 0.1, -0.1],
            [0.2, 0.9, 0.15],
            [0.1, 0.3, 1.1],
        ]
    }

    fn mats() -> [Box<dyn Material>; 2] {
        [
            Box::new(NeoHookean::new(10.0, 0.35, 1.0)),
            Box::new(LinearElastic::new(10.0, 0.35, 1.0)),
        ]
    }

    /// u_a = (F − I) X_a + a deterministic wiggle of amplitude `wiggle`.
    fn deform(x0: &[[f64; 3]], f: &Matrix3<f64>, wiggle: f64) -> Vec<[f64; 3]> {
        x0.iter()
            .enumerate()
            .map(|(a, x)| {
                let v = (f - Matrix3::identity()) * Vector3::from(*x);
                let s = |i: usize| wiggle * (((7 * a + 3 * i) as f64) * 1.3).sin();
                [v[0] + s(0), v[1] + s(1), v[2] + s(2)]
            })
            .collect()
    }

    fn force(
        kind: ElemKind,
        x0: &[[f64; 3]],
        u: &[[f64; 3]],
        mat: &dyn Material,
        with_k: bool,
    ) -> (Vec<f64>, Vec<f64>) {
        force_with(kind, Formulation::Standard, x0, u, mat, with_k)
    }

    fn force_with(
        kind: ElemKind,
        form: Formulation,
        x0: &[[f64; 3]],
        u: &[[f64; 3]],
        mat: &dyn Material,
        with_k: bool,
    ) -> (Vec<f64>, Vec<f64>) {
        let n = 3 * kind.n_nodes();
        let mut f = vec![0.0; n];
        let mut k = vec![0.0; n * n];
        let kk = if with_k { Some(&mut k[..]) } else { None };
        element_force(kind, form, x0, u, mat, &[], &mut [], &mut f, kk).unwrap();
        (f, k)
    }

    fn some_f() -> Matrix3<f64> {
        Matrix3::new(1.25, 0.2, -0.1, 0.05, 0.9, 0.15, -0.08, 0.1, 1.1)
    }

    fn cases() -> [(ElemKind, Vec<[f64; 3]>); 2] {
        [(ElemKind::Hex8, hex()), (ElemKind::Tet4, tet())]
    }

    #[test]
    fn rigid_translation_gives_zero_force() {
        for (kind, x0) in cases() {
            for mat in mats() {
                let u = vec![[0.3, -1.7, 2.2]; kind.n_nodes()];
                let (f, _) = force(kind, &x0, &u, mat.as_ref(), false);
                assert!(f.iter().all(|v| v.abs() < 1e-13), "{kind:?} {mat:?}: {f:?}");
            }
        }
    }

    #[test]
    fn finite_rigid_rotation_gives_zero_force() {
        let r = Rotation3::from_axis_angle(
            &nalgebra::Unit::new_normalize(Vector3::new(1.0, 2.0, -0.5)),
            60f64.to_radians(),
        );
        let rot = r.into_inner();
        for (kind, x0) in cases() {
            let mat = NeoHookean::new(10.0, 0.35, 1.0);
            let mut u = deform(&x0, &rot, 0.0);
            for ua in &mut u {
                ua[0] += 0.4; // and a translation
            }
            let (f, _) = force(kind, &x0, &u, &mat, false);
            assert!(f.iter().all(|v| v.abs() < 1e-13), "{kind:?}: {f:?}");
            // Linear elasticity is not rotation invariant: the test can tell.
            let (fl, _) = force(kind, &x0, &u, &LinearElastic::new(10.0, 0.35, 1.0), false);
            assert!(fl.iter().any(|v| v.abs() > 1e-2));
        }
    }

    /// Where Newton struggles (nearly incompressible F-bar under contact, issue 11) the
    /// tangent is still exact: Mooney–Rivlin at ν = 0.4995, 20 % compression.
    #[test]
    fn nearly_incompressible_mooney_rivlin_tangent_matches_central_difference() {
        let mat = crate::material::MooneyRivlin::new(0.5508, 0.1377, 0.4995, 1.0);
        let x0 = hex();
        let comp = Matrix3::new(1.05, 0.1, -0.05, 0.02, 0.97, 0.05, -0.03, 0.04, 0.8);
        for form in [Formulation::Standard, Formulation::FBAR] {
            check_tangent(ElemKind::Hex8, form, &x0, &deform(&x0, &comp, 0.03), &mat);
        }
    }

    #[test]
    fn tangent_matches_central_difference() {
        for (kind, x0) in cases() {
            for mat in mats() {
                for form in [
                    Formulation::Standard,
                    Formulation::FBAR,
                    Formulation::REDUCED,
                    Formulation::FBar { hourglass: 2.0 },
                    Formulation::Reduced { hourglass: 3.0 },
                ] {
                    check_tangent(kind, form, &x0, &deform(&x0, &some_f(), 0.04), mat.as_ref());
                }
            }
        }
    }

    /// The element tangent equals a central difference of the element force.
    fn check_tangent(
        kind: ElemKind,
        form: Formulation,
        x0: &[[f64; 3]],
        u: &[[f64; 3]],
        mat: &dyn Material,
    ) {
        let (_, k) = force_with(kind, form, x0, u, mat, true);
        let n = 3 * kind.n_nodes();
        let kmax = k.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let h = 1e-6 * char_length(kind, x0);
        for col in 0..n {
            let (mut up, mut um) = (u.to_vec(), u.to_vec());
            up[col / 3][col % 3] += h;
            um[col / 3][col % 3] -= h;
            let (fp, _) = force_with(kind, form, x0, &up, mat, false);
            let (fm, _) = force_with(kind, form, x0, &um, mat, false);
            for row in 0..n {
                let fd = (fp[row] - fm[row]) / (2.0 * h);
                let an = k[row * n + col];
                assert!(
                    (fd - an).abs() < 1e-6 * kmax,
                    "{kind:?} {form:?} {mat:?} K[{row},{col}] = {an}, fd {fd}"
                );
            }
        }
    }

    /// F-bar changes nothing where J is uniform (homogeneous F, rigid motion) and
    /// something where it is not.
    #[test]
    fn fbar_agrees_with_standard_for_homogeneous_deformation() {
        let x0 = hex();
        let r = Rotation3::from_axis_angle(&Vector3::z_axis(), 0.7).into_inner();
        for mat in mats() {
            for fdef in [some_f(), r] {
                let u = deform(&x0, &fdef, 0.0);
                let (fs, _) = force(ElemKind::Hex8, &x0, &u, mat.as_ref(), false);
                let (fb, _) = force_with(
                    ElemKind::Hex8,
                    Formulation::FBAR,
                    &x0,
                    &u,
                    mat.as_ref(),
                    false,
                );
                let scale = fs.iter().fold(1.0f64, |m, v| m.max(v.abs()));
                for (a, b) in fs.iter().zip(&fb) {
                    assert!((a - b).abs() < 1e-12 * scale, "{mat:?}: {a} vs {b}");
                }
                let ss = element_stress(
                    ElemKind::Hex8,
                    Formulation::Standard,
                    &x0,
                    &u,
                    mat.as_ref(),
                    &[],
                )
                .unwrap();
                let sb = element_stress(
                    ElemKind::Hex8,
                    Formulation::FBAR,
                    &x0,
                    &u,
                    mat.as_ref(),
                    &[],
                )
                .unwrap();
                for (a, b) in ss.iter().zip(&sb) {
                    assert!((a - b).abs() < 1e-12 * scale.max(1.0), "{ss:?} vs {sb:?}");
                }
            }
            let u = deform(&x0, &some_f(), 0.04);
            let (fs, _) = force(ElemKind::Hex8, &x0, &u, mat.as_ref(), false);
            let (fb, _) = force_with(
                ElemKind::Hex8,
                Formulation::FBAR,
                &x0,
                &u,
                mat.as_ref(),
                false,
            );
            let diff = fs
                .iter()
                .zip(&fb)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            assert!(
                diff > 1e-4,
                "{mat:?}: F-bar should differ for a non-uniform J"
            );
        }
    }

    /// A nearly incompressible block under a bending-like field: the standard hex8's
    /// volumetric stiffness dominates, F-bar's does not (it only sees the mean J).
    #[test]
    fn fbar_relieves_volumetric_locking_in_bending() {
        let x0: Vec<[f64; 3]> = HEX8_NODES
            .iter()
            .map(|p| [0.5 * (p[0] + 1.0), 0.5 * (p[1] + 1.0), 0.5 * (p[2] + 1.0)])
            .collect();
        // Pure bending mode u_x = κ x z (trapezoid in x–z): isochoric on average but not
        // pointwise. Its energy with a large bulk modulus shows locking.
        let u: Vec<[f64; 3]> = x0
            .iter()
            .map(|x| [1e-3 * (x[2] - 0.5) * (2.0 * x[0] - 1.0), 0.0, 0.0])
            .collect();
        let energy = |form, nu| {
            let mat = LinearElastic::new(1.0, nu, 1.0);
            let (f, _) = force_with(ElemKind::Hex8, form, &x0, &u, &mat, false);
            f.iter()
                .zip(u.iter().flatten())
                .map(|(a, b)| a * b)
                .sum::<f64>()
        };
        let (s0, s1) = (
            energy(Formulation::Standard, 0.3),
            energy(Formulation::Standard, 0.4999),
        );
        let (b0, b1) = (
            energy(Formulation::FBAR, 0.3),
            energy(Formulation::FBAR, 0.4999),
        );
        assert!(s1 / s0 > 100.0, "standard hex8 should lock: {s0} → {s1}");
        assert!(b1 / b0 < 2.0, "F-bar should not lock: {b0} → {b1}");
    }

    #[test]
    fn neo_hookean_tangent_is_symmetric() {
        for (kind, x0) in cases() {
            let u = deform(&x0, &some_f(), 0.04);
            let (_, k) = force(kind, &x0, &u, &NeoHookean::new(10.0, 0.35, 1.0), true);
            let n = 3 * kind.n_nodes();
            let kmax = k.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for i in 0..n {
                for j in 0..i {
                    assert!((k[i * n + j] - k[j * n + i]).abs() < 1e-12 * kmax);
                }
            }
        }
    }

    /// For homogeneous F, f_a = V P ∇_X N_a integrated exactly, so Σ_a f_a ⊗ X_a = V P
    /// (because Σ_a ∇_X N_a ⊗ X_a = I) and Σ_a f_a = 0; the element stress is σ = τ / J.
    #[test]
    fn homogeneous_deformation_gives_exact_forces_and_stress() {
        let fdef = some_f();
        for (kind, x0) in cases() {
            for mat in mats() {
                let u = deform(&x0, &fdef, 0.0);
                let (f, _) = force(kind, &x0, &u, mat.as_ref(), false);
                let sp = mat.evaluate(&fdef, &[], &mut []).unwrap();
                let s = sp.stress;
                let tau = Matrix3::new(s[0], s[3], s[5], s[3], s[1], s[4], s[5], s[4], s[2]);
                let (p, sigma) = match mat.kinematics() {
                    Kinematics::Finite => {
                        let j = fdef.determinant();
                        (tau * fdef.try_inverse().unwrap().transpose(), tau / j)
                    }
                    Kinematics::Small => (tau, tau),
                };
                let vol = element_volume(kind, &x0);
                let mut m = Matrix3::zeros();
                let mut sum = [0.0; 3];
                for (a, x) in x0.iter().enumerate() {
                    for i in 0..3 {
                        sum[i] += f[3 * a + i];
                        for c in 0..3 {
                            m[(i, c)] += f[3 * a + i] * x[c];
                        }
                    }
                }
                assert!(
                    (m - p * vol).norm() < 1e-12 * p.norm(),
                    "{kind:?} {mat:?}: {m} vs {}",
                    p * vol
                );
                assert!(sum.iter().all(|v| v.abs() < 1e-12 * p.norm()));
                let st = element_stress(kind, Formulation::Standard, &x0, &u, mat.as_ref(), &[])
                    .unwrap();
                let want = [
                    sigma[(0, 0)],
                    sigma[(1, 1)],
                    sigma[(2, 2)],
                    sigma[(0, 1)],
                    sigma[(1, 2)],
                    sigma[(0, 2)],
                ];
                for (a, b) in st.iter().zip(&want) {
                    assert!((a - b).abs() < 1e-12 * sigma.norm(), "{st:?} vs {want:?}");
                }
            }
        }
    }

    #[test]
    fn inverted_deformation_is_an_error() {
        let x0 = hex();
        let flip = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -0.5));
        let u = deform(&x0, &flip, 0.0);
        let mut f = vec![0.0; 24];
        let mat = NeoHookean::new(10.0, 0.3, 1.0);
        let e = element_force(
            ElemKind::Hex8,
            Formulation::Standard,
            &x0,
            &u,
            &mat,
            &[],
            &mut [],
            &mut f,
            None,
        )
        .unwrap_err();
        assert!(e.0.contains("det F"), "{e:?}");
        assert!(element_stress(ElemKind::Hex8, Formulation::Standard, &x0, &u, &mat, &[]).is_err());
    }

    #[test]
    fn reference_check() {
        assert!(check_reference(ElemKind::Hex8, &hex()).is_ok());
        assert!(check_reference(ElemKind::Tet4, &tet()).is_ok());
        // Two nodes swapped: a bow-tie.
        let mut h = hex();
        h.swap(0, 1);
        assert!(check_reference(ElemKind::Hex8, &h)
            .unwrap_err()
            .contains("inverted"));
        // Mirrored: negative everywhere.
        let m: Vec<[f64; 3]> = hex().iter().map(|x| [-x[0], x[1], x[2]]).collect();
        assert!(check_reference(ElemKind::Hex8, &m)
            .unwrap_err()
            .contains("inverted"));
        assert!(check_reference(
            ElemKind::Tet4,
            &[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
        )
        .is_ok());
        let mut t = tet();
        t.swap(1, 2);
        assert!(check_reference(ElemKind::Tet4, &t)
            .unwrap_err()
            .contains("inverted"));
        // Flat tet: apex in the base plane (up to round-off).
        let flat = [
            [0.0; 3],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.3, 0.3, 1e-12],
        ];
        assert!(check_reference(ElemKind::Tet4, &flat)
            .unwrap_err()
            .contains("degenerate"));
        // A hex whose top face is folded down through the bottom at one corner: fine at
        // some Gauss points, negative at the corner.
        let mut h = HEX8_NODES
            .iter()
            .map(|p| [p[0], p[1], p[2]])
            .collect::<Vec<_>>();
        h[6] = [0.6, 0.6, -0.8];
        let e = check_reference(ElemKind::Hex8, &h).unwrap_err();
        assert!(e.contains("corner"), "{e}");
    }

    #[test]
    fn volume_and_length() {
        // Affine image of the unit cube / reference tet: volume det A (times 1/6).
        let a = Matrix3::new(2.0, 0.3, 0.1, 0.0, 1.5, -0.2, 0.1, 0.0, 0.7);
        let map = |p: [f64; 3]| {
            let v = a * Vector3::from(p);
            [v[0] + 1.0, v[1] - 2.0, v[2]]
        };
        let h: Vec<_> = HEX8_NODES
            .iter()
            .map(|p| map([0.5 * (p[0] + 1.0), 0.5 * (p[1] + 1.0), 0.5 * (p[2] + 1.0)]))
            .collect();
        assert!((element_volume(ElemKind::Hex8, &h) - a.determinant()).abs() < 1e-13);
        assert!((char_length(ElemKind::Hex8, &h) - a.determinant().cbrt()).abs() < 1e-13);
        let t: Vec<_> = [[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
            .into_iter()
            .map(map)
            .collect();
        assert!((element_volume(ElemKind::Tet4, &t) - a.determinant() / 6.0).abs() < 1e-13);
    }

    #[test]
    fn von_mises_values() {
        assert!((von_mises(&[3.0, 0.0, 0.0, 0.0, 0.0, 0.0]) - 3.0).abs() < 1e-14);
        assert!((von_mises(&[0.0, 0.0, 0.0, 0.0, 2.0, 0.0]) - 2.0 * 3f64.sqrt()).abs() < 1e-14);
        assert!(von_mises(&[5.0, 5.0, 5.0, 0.0, 0.0, 0.0]).abs() < 1e-14);
    }

    #[test]
    fn history_is_passed_per_point() {
        /// Records the history slice it was given into the new one, times two.
        #[derive(Debug)]
        struct Probe;
        impl Material for Probe {
            fn kinematics(&self) -> Kinematics {
                Kinematics::Small
            }
            fn n_state(&self) -> usize {
                2
            }
            fn evaluate(
                &self,
                _: &Matrix3<f64>,
                old: &[f64],
                new: &mut [f64],
            ) -> Result<StressPoint, crate::material::MaterialError> {
                new[0] = 2.0 * old[0];
                new[1] = 2.0 * old[1];
                Ok(StressPoint {
                    stress: [0.0; 6],
                    tangent: [[0.0; 6]; 6],
                })
            }
            fn shear_modulus(&self) -> f64 {
                1.0
            }
            fn bulk_modulus(&self) -> f64 {
                1.0
            }
            fn density(&self) -> f64 {
                1.0
            }
        }
        let old: Vec<f64> = (0..16).map(|i| i as f64).collect();
        let mut new = vec![0.0; 16];
        let mut f = vec![0.0; 24];
        element_force(
            ElemKind::Hex8,
            Formulation::FBAR,
            &hex(),
            &[[0.0; 3]; 8],
            &Probe,
            &old,
            &mut new,
            &mut f,
            None,
        )
        .unwrap();
        assert!(new.iter().zip(&old).all(|(n, o)| *n == 2.0 * o));
    }
}
