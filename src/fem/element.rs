//! The element dispatcher: which [`ElementKernel`] an element kind and [`Formulation`]
//! get. The kernels live beside it: [`super::solid`] (standard and F-bar),
//! [`super::reduced`], [`super::eas`], [`super::hybrid`]; the seam is
//! [`super::kernel`], the formulation-free measures (volume, reference check) are in
//! [`super::measure`].

use super::eas::{Eas, EasWedge};
pub use super::error::ElementError;
use super::hybrid::{Hybrid, HYBRID_TET10, HYBRID_WEDGE6};
use super::kernel::{ElementData, ElementKernel, ElementOutput};
use super::reduced::Reduced;
use super::shape::{HEX8, TET10, TET4, WEDGE6};
use super::solid::{FBar, MeanDilatation, Standard};
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

    /// A short description for `alfe check` and the run's record: the formulation and
    /// its hourglass coefficient, without the element type (the caller names it, since
    /// a formulation means something only for the types it [`applies`] to).
    pub fn describe(self) -> String {
        let hg = |h: f64| {
            if h > 0.0 {
                format!(", hourglass {h}")
            } else {
                String::new()
            }
        };
        match self {
            Formulation::Standard => "standard".into(),
            Formulation::FBar { hourglass } => format!("F-bar{}", hg(hourglass)),
            Formulation::Reduced { hourglass } => format!("reduced, hourglass {hourglass}"),
            Formulation::Eas => "EAS".into(),
            Formulation::Hybrid { hourglass } => format!("hybrid{}", hg(hourglass)),
        }
    }

    /// The deck's name of the formulation (`formulation = "..."`).
    pub fn deck_name(self) -> &'static str {
        match self {
            Formulation::Standard => "standard",
            Formulation::FBar { .. } => "fbar",
            Formulation::Reduced { .. } => "reduced",
            Formulation::Eas => "eas",
            Formulation::Hybrid { .. } => "hybrid",
        }
    }

    /// Whether the element carries a pressure unknown (a block of its own).
    pub fn is_hybrid(self) -> bool {
        matches!(self, Formulation::Hybrid { .. })
    }
}

/// Whether `form` is a formulation of `kind`: hex8 has them all; tet4 the standard
/// one-point element, F-bar, which on a tet4 is the F-bar patch ([`super::patch`]: a
/// tet's own J̄ would be its J), and hybrid, the F-bar patch with a pressure unknown per
/// patch; tet10 and wedge6 standard, F-bar and hybrid (the mean-dilatation element), and
/// the wedge6 EAS (the solid-shell wedge of a sheet's triangles). The deck refuses a
/// formulation that does not apply (`scene/formulation.rs`); a new element type adds its
/// arm here and in [`kernel`].
pub fn applies(kind: ElemKind, form: Formulation) -> bool {
    match kind {
        ElemKind::Hex8 => true,
        // F-bar and hybrid are the mean-dilatation element on tet10 and wedge6 ([`kernel`]),
        // the F-bar patch on tet4.
        ElemKind::Tet4 | ElemKind::Tet10 => matches!(
            form,
            Formulation::Standard | Formulation::FBar { .. } | Formulation::Hybrid { .. }
        ),
        ElemKind::Wedge6 => !matches!(form, Formulation::Reduced { .. }),
    }
}

/// The formulation an element of `kind` takes in a part whose formulation is `form`:
/// `form` where it applies; else hybrid's nearest, F-bar, where that applies (a tet4 in
/// a hybrid part is an F-bar-patch tet); else the standard element. A part that names a
/// formulation has been checked to apply to all its types; this serves `auto`.
pub fn for_kind(kind: ElemKind, form: Formulation) -> Formulation {
    if applies(kind, form) {
        form
    } else if form.is_hybrid() && applies(kind, Formulation::FBAR) {
        Formulation::FBAR
    } else {
        Formulation::Standard
    }
}

/// Whether an element of `kind` under `form` is evaluated in an F-bar patch with its
/// neighbours ([`super::patch`]) rather than alone.
pub fn in_patch(kind: ElemKind, form: Formulation) -> bool {
    kind == ElemKind::Tet4
        && matches!(
            for_kind(kind, form),
            Formulation::FBar { .. } | Formulation::Hybrid { .. }
        )
}

/// [`Formulation::describe`] as an element of `kind` gets it: F-bar and hybrid tet10 are
/// the mean-dilatation element, its pressure condensed or an unknown.
pub fn describe_for(kind: ElemKind, form: Formulation) -> String {
    match (kind, form) {
        (ElemKind::Tet4, Formulation::FBar { .. }) => format!(
            "F-bar patch ({} tets share one volume ratio)",
            crate::mesh::patches::PATCH_ELEMENTS
        ),
        (ElemKind::Tet4, Formulation::Hybrid { .. }) => format!(
            "hybrid F-bar patch ({} tets share one volume ratio and a pressure unknown)",
            crate::mesh::patches::PATCH_ELEMENTS
        ),
        (ElemKind::Tet10, Formulation::FBar { .. }) => {
            "mean dilatation (P2/P0, pressure condensed)".into()
        }
        (ElemKind::Tet10, Formulation::Hybrid { .. }) => {
            "hybrid (P2/P0: mean dilatation with its pressure an unknown)".into()
        }
        (ElemKind::Wedge6, Formulation::Eas) => "EAS (solid-shell wedge, 12 modes)".into(),
        (ElemKind::Wedge6, Formulation::FBar { .. }) => {
            "mean dilatation (pressure condensed)".into()
        }
        (ElemKind::Wedge6, Formulation::Hybrid { .. }) => {
            "hybrid (mean dilatation with its pressure an unknown)".into()
        }
        _ => form.describe(),
    }
}

/// The kernel of an element of `kind` under `form`.
///
/// A tet4 is the standard one-point element here under any formulation: under F-bar the
/// model evaluates it with its patch ([`in_patch`], [`super::patch`]), and this kernel
/// only says its point count. A part that mixes hex8 and tet4 under `auto` gives each
/// type [`for_kind`]'s choice (`alfe check` prints both, and warns when one locks).
pub fn kernel(kind: ElemKind, form: Formulation) -> Box<dyn ElementKernel> {
    match (kind, form) {
        (ElemKind::Hex8, Formulation::Standard) => Box::new(Standard { tab: &HEX8 }),
        (ElemKind::Hex8, Formulation::FBar { hourglass }) => Box::new(FBar { hourglass }),
        (ElemKind::Hex8, Formulation::Reduced { hourglass }) => Box::new(Reduced { hourglass }),
        (ElemKind::Hex8, Formulation::Eas) => Box::new(Eas),
        (ElemKind::Hex8, Formulation::Hybrid { hourglass }) => Box::new(Hybrid::new(hourglass)),
        (ElemKind::Tet4, _) => Box::new(Standard { tab: &TET4 }),
        (ElemKind::Tet10, Formulation::Standard) => Box::new(Standard { tab: &TET10 }),
        // Issue 35, tet10: F-bar parts get the mean-dilatation tet10 (J̄ = v/V, P2/P0
        // with the constant pressure condensed), hybrid parts the same element with its
        // pressure an unknown (the hybrid hex8's Newton). Reduced and EAS do not apply to
        // a tet10: `scene/` refuses them by part ([`applies`]); were one to arrive here it
        // would get the standard tet10, which does not lock in bending.
        (ElemKind::Tet10, Formulation::FBar { .. }) => Box::new(MeanDilatation { tab: &TET10 }),
        (ElemKind::Tet10, Formulation::Hybrid { .. }) => Box::new(HYBRID_TET10),
        (ElemKind::Tet10, Formulation::Reduced { .. } | Formulation::Eas) => {
            Box::new(Standard { tab: &TET10 })
        }
        // The wedge6 as the tet10 (P1 × P1 prism, 3 × 2 points).
        (ElemKind::Wedge6, Formulation::FBar { .. }) => Box::new(MeanDilatation { tab: &WEDGE6 }),
        (ElemKind::Wedge6, Formulation::Hybrid { .. }) => Box::new(HYBRID_WEDGE6),
        (ElemKind::Wedge6, Formulation::Eas) => Box::new(EasWedge),
        (ElemKind::Wedge6, _) => Box::new(Standard { tab: &WEDGE6 }),
    }
}

/// Internal force and, with `out.k`, tangent of one element through its
/// displacement-only kernel ([`ElementKernel::condensed`]: a hybrid element as F-bar).
pub fn element_force(
    kind: ElemKind,
    form: Formulation,
    e: &ElementData,
    out: ElementOutput,
) -> Result<(), ElementError> {
    let k = kernel(kind, form);
    k.condensed().unwrap_or(k.as_ref()).force(e, out)
}

/// Volume-averaged Cauchy stress of one element through its displacement-only kernel.
pub fn element_stress(
    kind: ElemKind,
    form: Formulation,
    e: &ElementData,
) -> Result<[f64; 6], ElementError> {
    let k = kernel(kind, form);
    k.condensed().unwrap_or(k.as_ref()).stress(e)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// hex8 has every formulation; tet4, tet10 and wedge6 standard, F-bar and hybrid (the
    /// deck refuses the rest); describe() names the formulation alone; `auto`'s choice
    /// falls back per type and puts F-bar and hybrid tet4 in patches.
    #[test]
    fn formulations_apply_to_the_element_types_that_have_them() {
        for f in [
            Formulation::Standard,
            Formulation::FBAR,
            Formulation::REDUCED,
            Formulation::Eas,
            Formulation::Hybrid { hourglass: 0.0 },
        ] {
            assert!(applies(ElemKind::Hex8, f));
            assert_eq!(for_kind(ElemKind::Hex8, f), f);
            assert_eq!(
                in_patch(ElemKind::Tet4, f),
                matches!(f, Formulation::FBar { .. } | Formulation::Hybrid { .. })
            );
            assert!(!in_patch(ElemKind::Hex8, f) && !in_patch(ElemKind::Tet10, f));
            for k in [ElemKind::Tet4, ElemKind::Tet10, ElemKind::Wedge6] {
                if !applies(k, f) {
                    assert_eq!(for_kind(k, f), Formulation::Standard);
                }
                assert_eq!(
                    applies(k, f),
                    !matches!(f, Formulation::Reduced { .. })
                        && (k == ElemKind::Wedge6 || f != Formulation::Eas)
                );
            }
            assert!(!f.describe().contains("hex8"), "{}", f.describe());
        }
        assert_eq!(
            Formulation::FBar { hourglass: 2.0 }.describe(),
            "F-bar, hourglass 2"
        );
    }
    use crate::fem::measure::{char_length, check_reference, element_volume, von_mises};
    use crate::fem::shape::HEX8_NODES;
    use crate::material::{Kinematics, LinearElastic, Material, NeoHookean, StressPoint};
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

    /// The tet above with its midside nodes moved off their edges by up to ~0.04:
    /// curved edges, a distorted quadratic element.
    fn tet10() -> Vec<[f64; 3]> {
        let c = tet();
        let mut x = c.clone();
        for (e, [i, j]) in crate::fem::shape::TET10_EDGES.iter().enumerate() {
            let s = |k: usize| 0.04 * (((5 * e + 2 * k) as f64) * 1.7).sin();
            x.push(std::array::from_fn(|k| 0.5 * (c[*i][k] + c[*j][k]) + s(k)));
        }
        x
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
        element_force(
            kind,
            form,
            &ElementData::new(x0, u, mat, &[]),
            ElementOutput::new(&mut [], &mut f, kk),
        )
        .unwrap();
        (f, k)
    }

    fn some_f() -> Matrix3<f64> {
        Matrix3::new(1.25, 0.2, -0.1, 0.05, 0.9, 0.15, -0.08, 0.1, 1.1)
    }

    /// A prism with its top triangle shifted, twisted and tilted.
    fn wedge() -> Vec<[f64; 3]> {
        vec![
            [0.0, 0.05, -0.02],
            [1.1, -0.05, 0.1],
            [0.05, 0.95, 0.0],
            [0.1, 0.1, 0.9],
            [1.0, 0.15, 1.1],
            [0.2, 1.05, 1.0],
        ]
    }

    fn cases() -> [(ElemKind, Vec<[f64; 3]>); 4] {
        [
            (ElemKind::Hex8, hex()),
            (ElemKind::Tet4, tet()),
            (ElemKind::Tet10, tet10()),
            (ElemKind::Wedge6, wedge()),
        ]
    }

    /// Tet10: a straight-sided one has the tet4's volume; the distorted one passes the
    /// reference check; a midside node pulled across the opposite face fails it.
    #[test]
    fn tet10_volume_and_reference_check() {
        let c = tet();
        let mut straight = c.clone();
        for [i, j] in crate::fem::shape::TET10_EDGES {
            straight.push(std::array::from_fn(|k| 0.5 * (c[i][k] + c[j][k])));
        }
        let v4 = element_volume(ElemKind::Tet4, &c);
        assert!((element_volume(ElemKind::Tet10, &straight) - v4).abs() < 1e-14);
        assert!(check_reference(ElemKind::Tet10, &tet10()).is_ok());
        let mut bad = tet10();
        // The midside node of edge 0-1 beyond corner 1: the edge folds back at corner 1.
        bad[4] = std::array::from_fn(|k| 2.0 * c[1][k] - c[0][k]);
        assert!(check_reference(ElemKind::Tet10, &bad).is_err());
    }

    /// The mean-dilatation tet10 (F-bar and hybrid parts) does not lock where the
    /// standard one stiffens: a quadratic bending field on a nearly incompressible
    /// material, on a straight-sided element (its centroid is the corners' mean, so the
    /// field's mean dilatation is zero).
    #[test]
    fn mean_dilatation_tet10_relieves_locking() {
        let c = tet();
        let mut x0 = c.clone();
        for [i, j] in crate::fem::shape::TET10_EDGES {
            x0.push(std::array::from_fn(|k| 0.5 * (c[i][k] + c[j][k])));
        }
        let zc = (0..4).map(|a| x0[a][2]).sum::<f64>() / 4.0;
        let u: Vec<[f64; 3]> = x0
            .iter()
            .map(|x| [1e-3 * (x[2] - zc) * x[0], 0.0, -0.5e-3 * x[0] * x[0]])
            .collect();
        let energy = |form, nu| {
            let mat = LinearElastic::new(1.0, nu, 1.0);
            let (f, _) = force_with(ElemKind::Tet10, form, &x0, &u, &mat, false);
            f.iter()
                .zip(u.iter().flatten())
                .map(|(a, b)| a * b)
                .sum::<f64>()
        };
        let s = energy(Formulation::Standard, 0.4999) / energy(Formulation::Standard, 0.3);
        let b = energy(Formulation::FBAR, 0.4999) / energy(Formulation::FBAR, 0.3);
        eprintln!("tet10 energy ratio ν 0.4999 / 0.3: standard {s:.3}, mean dilatation {b:.3}");
        assert!(b < 2.0 && s > 10.0 * b, "standard {s}, mean dilatation {b}");
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
                    &ElementData::new(&x0, &u, mat.as_ref(), &[]),
                )
                .unwrap();
                let sb = element_stress(
                    ElemKind::Hex8,
                    Formulation::FBAR,
                    &ElementData::new(&x0, &u, mat.as_ref(), &[]),
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
                let st = element_stress(
                    kind,
                    Formulation::Standard,
                    &ElementData::new(&x0, &u, mat.as_ref(), &[]),
                )
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
            &ElementData::new(&x0, &u, &mat, &[]),
            ElementOutput::new(&mut [], &mut f, None),
        )
        .unwrap_err();
        assert!(e.to_string().contains("det F"), "{e:?}");
        assert!(element_stress(
            ElemKind::Hex8,
            Formulation::Standard,
            &ElementData::new(&x0, &u, &mat, &[])
        )
        .is_err());
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
            .to_string()
            .contains("inverted"));
        // Mirrored: negative everywhere.
        let m: Vec<[f64; 3]> = hex().iter().map(|x| [-x[0], x[1], x[2]]).collect();
        assert!(check_reference(ElemKind::Hex8, &m)
            .unwrap_err()
            .to_string()
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
            .to_string()
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
            .to_string()
            .contains("degenerate"));
        // A hex whose top face is folded down through the bottom at one corner: fine at
        // some Gauss points, negative at the corner.
        let mut h = HEX8_NODES
            .iter()
            .map(|p| [p[0], p[1], p[2]])
            .collect::<Vec<_>>();
        h[6] = [0.6, 0.6, -0.8];
        let e = check_reference(ElemKind::Hex8, &h).unwrap_err().to_string();
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
            &ElementData::new(&hex(), &[[0.0; 3]; 8], &Probe, &old),
            ElementOutput::new(&mut new, &mut f, None),
        )
        .unwrap();
        assert!(new.iter().zip(&old).all(|(n, o)| *n == 2.0 * o));
    }
}
