//! The hybrid hex8: the F-bar element with its pressure as an unknown, one per element
//! (a mixed u–p form of F-bar; what Abaqus' C3D8H does for the Q1/P0 element of Simo,
//! Taylor & Pister 1985), for nearly incompressible solids.
//!
//! **Why.** With the pressure a function of the displacements (F-bar: p = U'(J̄)), the
//! volumetric residual is K (J̄ − 1) times a volume gradient: a Newton correction that is
//! right to first order leaves J̄ wrong to second order (a rotation increment θ changes J
//! by O(θ²)), and K ≫ G turns that into a pressure error of order K θ². Rubber that flows
//! round an indenter then takes 10–20 damped Newton iterations per step
//! (`cylinder-press`: 4 per step at ν = 0.45, 12 at ν = 0.4995, issue 11). With p an
//! unknown, the momentum rows are linear in p and the constraint row is weighted by 1/K:
//! Newton's basin no longer shrinks as K/G grows.
//!
//! **Equations.** The energy splits as W = W₁(F) + U(J) ([`Material::volumetric`]). F-bar
//! evaluates the material at F̄ = (J̄/J)^{1/3} F, J̄ = v/V, so its volumetric stress is
//! J̄ U'(J̄) I at every point; here U'(J̄) is replaced by the element's pressure p, and p
//! gets its own equation:
//!
//! ```text
//!   r_a = ∫ (τ(F̄) + J̄ (p − U'(J̄)) I) ∇ₓN_a dV       (F-bar's force with p for U')
//!   r_p = V (U'(J̄) − p) / K₀,   K₀ = U''(1)
//! ```
//!
//! At a solution p = U'(J̄) and r_a is F-bar's force: the answers are F-bar's (its
//! accuracy, its hourglass spring and its stability under compression: a variational
//! Q1/P0 with the pressure tested by ∫ J ∇ₓN dV was tried first and folded earlier, at
//! 22 mm on `rubber-indent` without the spring where F-bar folds at 47.5, and on
//! `sphere-roll` with it). The stress τ(F̄) + J̄ (p − U'(J̄)) I is a function of F̄ for
//! fixed p, so F-bar's tangent applies to it with c + J̄ (δp − J̄ U''(J̄)) I⊗I − 2 J̄ δp 𝕀,
//! δp = p − U'(J̄); the pressure column is b̂_a = J̄ ∫ ∇ₓN_a dV, the pressure row
//! U''(J̄)/K₀ b_a with b_a = ∂v/∂u_a = ∫ J ∇ₓN_a dV, its diagonal −V/K₀ (non-symmetric,
//! as F-bar's tangent is).
//!
//! **Scaling.** The unknown is π = p / s with s = G / V^{1/3}, a length like the
//! displacements and the contact multipliers (JFNK's finite-difference step and GMRES's
//! norms treat all unknowns alike), and the pressure rows are scaled by s to forces. The
//! pressure takes the first entry of a block of three; the other two are inert unknowns
//! with the pressure row's diagonal (`−s² V/K₀`), so the block's diagonal stays negative
//! definite for the condensation (`linalg/condense.rs`), which eliminates it
//! exactly: the factored matrix has only the displacements.

use super::error::{material_at, At, ElementError};
use super::kernel::{nodes, ElementData, ElementKernel, ElementOutput};
use super::kinematics::{
    add_fbar_tangent, add_force, add_tangent, element_kinematics, LocalTangent,
};
use super::shape::{Tabulated, HEX8, TET10, WEDGE6};
use super::solid::{FBar, MeanDilatation};
use crate::material::{Kinematics, Material, StressPoint};

/// Rows of a hybrid hex8: 8 nodes and the pressure block.
pub const DOFS: usize = 27;

/// What the pressure rows need from the element loop.
struct Volumes<const N: usize> {
    /// Reference volume and J̄.
    big_v: f64,
    jbar: f64,
    /// b_a = ∂v/∂u_a, and the pressure column b̂_a = J̄ ∫ ∇ₓN_a dV.
    b: [[f64; 3]; N],
    bhat: [[f64; 3]; N],
    /// U'(J̄), U''(J̄), K₀ = U''(1).
    u1: f64,
    u2: f64,
    k0: f64,
    /// The pressure's scale s = G / V^{1/3} and the pressure p = s π.
    s: f64,
    p: f64,
}

fn no_split(mat: &dyn Material) -> ElementError {
    ElementError::NoVolumetricSplit {
        material: format!("{mat:?}"),
    }
}

/// The hybrid hex8 with the hourglass spring of [`super::reduced`] scaled by `hourglass`
/// (as on F-bar); its pressure block is its one own block, and without it (condensed,
/// p = U'(J̄)) it is F-bar.
#[derive(Debug, Clone, Copy)]
pub struct Hybrid {
    fbar: FBar,
}

impl Hybrid {
    pub fn new(hourglass: f64) -> Self {
        Self {
            fbar: FBar { hourglass },
        }
    }
}

impl ElementKernel for Hybrid {
    fn n_nodes(&self) -> usize {
        8
    }
    fn n_points(&self) -> usize {
        8
    }
    fn own_blocks(&self) -> usize {
        1
    }
    fn force(&self, e: &ElementData, out: ElementOutput) -> Result<(), ElementError> {
        let pi: &[f64; 3] = e.own.try_into().expect("one pressure block");
        force(&HEX8, e, pi, self.fbar.hourglass, out)
    }
    fn stress(&self, e: &ElementData) -> Result<[f64; 6], ElementError> {
        stress(&HEX8, e, e.own[0])
    }
    fn condensed(&self) -> Option<&dyn ElementKernel> {
        Some(&self.fbar)
    }
}

/// The hybrid mean-dilatation element of any tabulated kind (tet10, wedge6): the
/// mean-dilatation element (J̄ = v/V over the element, P2/P0 on a tet10) with its
/// constant pressure as an unknown, as the hybrid hex8 is F-bar's; condensed, it is
/// [`MeanDilatation`]. The same answers, in the hybrid hex8's Newton iterations instead
/// of F-bar's (the module documentation; Abaqus' C3D10H is the tet10 analogue with a
/// linear pressure).
#[derive(Debug, Clone, Copy)]
pub struct HybridMd<const N: usize, const G: usize> {
    md: MeanDilatation<N, G>,
}

impl<const N: usize, const G: usize> HybridMd<N, G> {
    pub const fn new(tab: &'static Tabulated<3, N, G>) -> Self {
        Self {
            md: MeanDilatation { tab },
        }
    }
}

/// The hybrid tet10.
pub const HYBRID_TET10: HybridMd<10, 4> = HybridMd::new(&TET10);
/// The hybrid wedge6.
pub const HYBRID_WEDGE6: HybridMd<6, 6> = HybridMd::new(&WEDGE6);

impl<const N: usize, const G: usize> ElementKernel for HybridMd<N, G> {
    fn n_nodes(&self) -> usize {
        N
    }
    fn n_points(&self) -> usize {
        G
    }
    fn own_blocks(&self) -> usize {
        1
    }
    fn force(&self, e: &ElementData, out: ElementOutput) -> Result<(), ElementError> {
        let pi: &[f64; 3] = e.own.try_into().expect("one pressure block");
        force(self.md.tab, e, pi, 0.0, out)
    }
    fn stress(&self, e: &ElementData) -> Result<[f64; 6], ElementError> {
        stress(self.md.tab, e, e.own[0])
    }
    fn condensed(&self) -> Option<&dyn ElementKernel> {
        Some(&self.md)
    }
}

/// The pressure unknown's scale s = G / V^{1/3} (p = s π).
pub fn pressure_scale(mat: &dyn Material, reference_volume: f64) -> f64 {
    mat.shear_modulus() / reference_volume.cbrt()
}

/// The displacement rows `f` (3N) and, with `k`, their tangent for the pressure
/// p = s `pi` held fixed (s from the reference volume the kinematics integrate).
fn core<const N: usize, const G: usize>(
    tab: &Tabulated<3, N, G>,
    e: &ElementData,
    pi: f64,
    state_new: &mut [f64],
    f: &mut [f64],
    mut k: Option<&mut LocalTangent<N>>,
) -> Result<Volumes<N>, ElementError> {
    let (mat, state_old) = (e.mat, e.state_old);
    let (x0, u) = (nodes::<N>(e.x0), nodes::<N>(e.u));
    let ns = mat.n_state();
    assert!(
        state_old.len() == G * ns && state_new.len() == G * ns,
        "history length must be n_gauss × n_state"
    );
    if mat.kinematics() != Kinematics::Finite {
        return Err(no_split(mat));
    }
    let (pts, gbar) = element_kinematics(tab, true, Kinematics::Finite, x0, u)?;
    let gbar = gbar.expect("F-bar kinematics return the mean gradients");
    let big_v: f64 = pts.iter().map(|q| q.w).sum();
    let s = pressure_scale(mat, big_v.abs());
    let p = s * pi;
    let jbar = pts[0].f.determinant();
    let v = jbar * big_v;
    let b: [[f64; 3]; N] = std::array::from_fn(|a| gbar[a].map(|c| c * v));
    let mut bhat = [[0.0; 3]; N];
    for q in &pts {
        for (bh, g) in bhat.iter_mut().zip(&q.grad) {
            for c in 0..3 {
                bh[c] += jbar * q.w * g[c];
            }
        }
    }
    let (u1, u2) = mat.volumetric(jbar).ok_or_else(|| no_split(mat))?;
    let k0 = mat.volumetric(1.0).ok_or_else(|| no_split(mat))?.1;
    // τ(F̄) + J̄ δp I with its tangent for δp fixed (the module documentation).
    let dp = p - u1;
    let a = jbar * (dp - jbar * u2);
    f.fill(0.0);
    for (g, q) in pts.iter().enumerate() {
        let (at, new) = (g * ns..(g + 1) * ns, &mut state_new[g * ns..(g + 1) * ns]);
        match k.as_deref_mut() {
            Some(k) => {
                let mut sp: StressPoint = e
                    .evaluate(&q.f, at, new)
                    .map_err(material_at(At::Gauss(g)))?;
                for r in 0..3 {
                    sp.stress[r] += jbar * dp;
                    for c in 0..3 {
                        sp.tangent[r][c] += a;
                    }
                    sp.tangent[r][r] -= 2.0 * jbar * dp;
                    sp.tangent[r + 3][r + 3] -= jbar * dp;
                }
                add_force(&q.grad, &sp.stress, q.w, f);
                add_tangent(&q.grad, &sp, true, q.w, k);
                add_fbar_tangent(&q.grad, &gbar, &sp, true, q.w, k);
            }
            None => {
                let mut s = e
                    .evaluate_stress(&q.f, at, new)
                    .map_err(material_at(At::Gauss(g)))?;
                for si in s.iter_mut().take(3) {
                    *si += jbar * dp;
                }
                add_force(&q.grad, &s, q.w, f);
            }
        }
    }
    Ok(Volumes {
        big_v,
        jbar,
        b,
        bhat,
        u1,
        u2,
        k0,
        s,
        p,
    })
}

/// Residual rows of one hybrid element of N nodes with its pressure block `pi` (the
/// element's block of three unknowns: π and two inert ones): `f` (3N + 3: the nodes'
/// rows, then the block's) and, with `k`, the (3N + 3)² Jacobian (row-major).
/// `hourglass` > 0 (hex8 only) adds the hourglass spring of [`super::reduced`] (as on
/// F-bar).
fn force<const N: usize, const G: usize>(
    tab: &Tabulated<3, N, G>,
    e: &ElementData,
    pi: &[f64; 3],
    hourglass: f64,
    out: ElementOutput,
) -> Result<(), ElementError> {
    let ElementOutput { state_new, f, k } = out;
    let mat = e.mat;
    let (nu, dofs) = (3 * N, 3 * N + 3);
    assert_eq!(f.len(), dofs, "force slice length");
    match k {
        Some(k) => {
            assert_eq!(k.len(), dofs * dofs, "tangent slice length");
            let mut kloc = [[[[0.0; 3]; N]; 3]; N];
            let vols = core(tab, e, pi[0], state_new, &mut f[..nu], Some(&mut kloc))?;
            k.fill(0.0);
            let kuu = kloc.as_flattened().as_flattened().as_flattened();
            for r in 0..nu {
                k[r * dofs..r * dofs + nu].copy_from_slice(&kuu[r * nu..r * nu + nu]);
            }
            let s = vols.s;
            let d = -s * s * vols.big_v / vols.k0;
            let up = s * vols.u2 / vols.k0;
            for a in 0..N {
                for i in 0..3 {
                    k[(3 * a + i) * dofs + nu] = s * vols.bhat[a][i];
                    k[nu * dofs + 3 * a + i] = up * vols.b[a][i];
                }
            }
            for q in nu..dofs {
                k[q * dofs + q] = d;
            }
            if hourglass > 0.0 {
                let (x0, u) = (nodes::<8>(e.x0), nodes::<8>(e.u));
                let mut k24 = [0.0; 576];
                let mut f24 = [0.0; 24];
                super::reduced::add_hourglass(
                    x0,
                    u,
                    mat.shear_modulus(),
                    hourglass,
                    &mut f24,
                    Some(&mut k24),
                )?;
                for r in 0..24 {
                    f[r] += f24[r];
                    for c in 0..24 {
                        k[r * dofs + c] += k24[r * 24 + c];
                    }
                }
            }
            pressure_rows(&vols, pi, f);
        }
        None => {
            let vols = core(tab, e, pi[0], state_new, &mut f[..nu], None)?;
            if hourglass > 0.0 {
                let (x0, u) = (nodes::<8>(e.x0), nodes::<8>(e.u));
                super::reduced::add_hourglass(
                    x0,
                    u,
                    mat.shear_modulus(),
                    hourglass,
                    &mut f[..24],
                    None,
                )?;
            }
            pressure_rows(&vols, pi, f);
        }
    }
    Ok(())
}

/// r_π = s V (U'(J̄) − p)/K₀ and the inert entries' rows (the last three of `f`).
fn pressure_rows<const N: usize>(vols: &Volumes<N>, pi: &[f64; 3], f: &mut [f64]) {
    let s = vols.s;
    let d = -s * s * vols.big_v / vols.k0;
    let nu = 3 * N;
    f[nu] = s * vols.big_v * (vols.u1 - vols.p) / vols.k0;
    f[nu + 1] = d * pi[1];
    f[nu + 2] = d * pi[2];
}

/// Volume-averaged Cauchy stress of the element with its pressure unknown `pi`: F-bar's,
/// with J̄ p in place of J̄ U'(J̄) (equal at a solution).
fn stress<const N: usize, const G: usize>(
    tab: &Tabulated<3, N, G>,
    e: &ElementData,
    pi: f64,
) -> Result<[f64; 6], ElementError> {
    let (x0, u) = (nodes::<N>(e.x0), nodes::<N>(e.u));
    let ns = e.mat.n_state();
    let mut scratch = vec![0.0; G * ns];
    // Σ_a x_a ⊗ f_a = ∫ τ dV for any element force f_a = ∫ τ ∇ₓN_a dV (Σ_a x_a ⊗ ∇ₓN_a
    // = I): the mean stress from the force without a second stress loop.
    let mut f = [[0.0; 3]; N];
    let vols = core(tab, e, pi, &mut scratch, f.as_flattened_mut(), None)?;
    let mut tau = [0.0; 6];
    let f = f.as_flattened();
    for a in 0..N {
        let x = [x0[a][0] + u[a][0], x0[a][1] + u[a][1], x0[a][2] + u[a][2]];
        let fa = &f[3 * a..3 * a + 3];
        tau[0] += x[0] * fa[0];
        tau[1] += x[1] * fa[1];
        tau[2] += x[2] * fa[2];
        tau[3] += 0.5 * (x[0] * fa[1] + x[1] * fa[0]);
        tau[4] += 0.5 * (x[1] * fa[2] + x[2] * fa[1]);
        tau[5] += 0.5 * (x[0] * fa[2] + x[2] * fa[0]);
    }
    Ok(tau.map(|t| t / (vols.jbar * vols.big_v)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::element::{element_force, element_stress, Formulation};
    use crate::fem::shape::HEX8_NODES;
    use crate::material::{Hardening, J2Plasticity, MooneyRivlin, NeoHookean};
    use crate::mesh::ElemKind;
    use nalgebra::{Matrix3, Vector3};

    fn hex() -> [[f64; 3]; 8] {
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
        std::array::from_fn(|a| {
            let p = HEX8_NODES[a];
            [
                0.5 * (p[0] + 1.0) * 1.4 + d[a][0],
                0.5 * (p[1] + 1.0) + d[a][1],
                0.5 * (p[2] + 1.0) * 0.8 + d[a][2],
            ]
        })
    }

    fn deform(x0: &[[f64; 3]; 8], f: &Matrix3<f64>, wiggle: f64) -> [[f64; 3]; 8] {
        std::array::from_fn(|a| {
            let v = (f - Matrix3::identity()) * Vector3::from(x0[a]);
            let s = |i: usize| wiggle * (((7 * a + 3 * i) as f64) * 1.3).sin();
            [v[0] + s(0), v[1] + s(1), v[2] + s(2)]
        })
    }

    fn mats() -> Vec<Box<dyn Material>> {
        vec![
            Box::new(MooneyRivlin::new(0.5508, 0.1377, 0.4995, 1.0)),
            Box::new(NeoHookean::new(10.0, 0.45, 1.0)),
            Box::new(J2Plasticity::new(
                200.0,
                0.3,
                Hardening::Linear {
                    sigma_y0: 0.5,
                    h: 20.0,
                },
                1.0,
            )),
        ]
    }

    fn comp() -> Matrix3<f64> {
        Matrix3::new(1.05, 0.1, -0.05, 0.02, 0.97, 0.05, -0.03, 0.04, 0.8)
    }

    fn mixed(
        x0: &[[f64; 3]; 8],
        u: &[[f64; 3]; 8],
        pi: &[f64; 3],
        mat: &dyn Material,
        hg: f64,
        with_k: bool,
    ) -> (Vec<f64>, Vec<f64>) {
        let ns = 8 * mat.n_state();
        let (old, mut new) = (vec![0.0; ns], vec![0.0; ns]);
        let mut f = vec![0.0; DOFS];
        let mut k = vec![0.0; DOFS * DOFS];
        Hybrid::new(hg)
            .force(
                &ElementData::new(x0, u, mat, &old).with_own(pi),
                ElementOutput::new(&mut new, &mut f, with_k.then_some(&mut k[..])),
            )
            .unwrap();
        (f, k)
    }

    /// The hybrid tet10's 33×33 Jacobian against central differences on a curved,
    /// deformed tet10, with the pressure off equilibrium; condensed, it is the
    /// mean-dilatation element, and at the equilibrium pressure their forces agree.
    #[test]
    fn hybrid_tet10_jacobian_and_condensed_force() {
        let c = [
            [0.0, 0.1, 0.0],
            [1.2, 0.0, 0.1],
            [0.1, 0.9, -0.1],
            [0.2, 0.3, 1.0],
        ];
        let mut x0 = c.to_vec();
        for (e, [i, j]) in crate::fem::shape::TET10_EDGES.into_iter().enumerate() {
            x0.push(std::array::from_fn(|k| {
                0.5 * (c[i][k] + c[j][k]) + 0.03 * ((5 * e + 2 * k) as f64).sin()
            }));
        }
        let f = comp();
        let u0: Vec<[f64; 3]> = x0
            .iter()
            .enumerate()
            .map(|(a, x)| {
                let y = f * Vector3::from(*x);
                std::array::from_fn(|k| y[k] - x[k] + 0.02 * ((3 * a + k) as f64).cos())
            })
            .collect();
        let kern = HYBRID_TET10;
        let n = 33;
        let run = |u: &[[f64; 3]], pi: &[f64; 3], mat: &dyn Material, with_k: bool| {
            let ns = 4 * mat.n_state();
            let (old, mut new) = (vec![0.0; ns], vec![0.0; ns]);
            let (mut fv, mut k) = (vec![0.0; n], vec![0.0; n * n]);
            kern.force(
                &ElementData::new(&x0, u, mat, &old).with_own(pi),
                ElementOutput::new(&mut new, &mut fv, with_k.then_some(&mut k[..])),
            )
            .unwrap();
            (fv, k)
        };
        for mat in mats() {
            let s = pressure_scale(mat.as_ref(), 1.0);
            let pi = [0.3 * mat.shear_modulus() / s, 0.1, -0.2];
            let (_, k) = run(&u0, &pi, mat.as_ref(), true);
            let kmax = k.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let h = 1e-6;
            for col in 0..n {
                let (mut up, mut um, mut pp, mut pm) = (u0.clone(), u0.clone(), pi, pi);
                if col < 30 {
                    up[col / 3][col % 3] += h;
                    um[col / 3][col % 3] -= h;
                } else {
                    pp[col - 30] += h;
                    pm[col - 30] -= h;
                }
                let (fp, _) = run(&up, &pp, mat.as_ref(), false);
                let (fm, _) = run(&um, &pm, mat.as_ref(), false);
                for row in 0..n {
                    let fd = (fp[row] - fm[row]) / (2.0 * h);
                    let an = k[row * n + col];
                    assert!(
                        (fd - an).abs() < 1e-6 * kmax,
                        "{mat:?}: K[{row},{col}] = {an}, fd {fd}"
                    );
                }
            }
            // At the pressure its own row makes zero, the force is the condensed one's.
            let (f0, _) = run(&u0, &[0.0; 3], mat.as_ref(), false);
            let (f1, _) = run(&u0, &[1.0, 0.0, 0.0], mat.as_ref(), false);
            let pi_eq = -f0[30] / (f1[30] - f0[30]);
            let (fh, _) = run(&u0, &[pi_eq, 0.0, 0.0], mat.as_ref(), false);
            let ns = 4 * mat.n_state();
            let (old, mut new) = (vec![0.0; ns], vec![0.0; ns]);
            let mut fc = vec![0.0; 30];
            kern.condensed()
                .unwrap()
                .force(
                    &ElementData::new(&x0, &u0, mat.as_ref(), &old),
                    ElementOutput::new(&mut new, &mut fc, None),
                )
                .unwrap();
            let scale = fc.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (a, b) in fc.iter().zip(&fh[..30]) {
                assert!((a - b).abs() < 1e-9 * scale, "{mat:?}: {a} vs {b}");
            }
        }
    }

    /// The 27×27 Jacobian (pressure block included) equals central differences of the
    /// residual, elastic and plastic, with and without the hourglass spring.
    #[test]
    fn jacobian_matches_central_difference() {
        let x0 = hex();
        let u0 = deform(&x0, &comp(), 0.03);
        for mat in mats() {
            for hg in [0.0, 4.0] {
                // A pressure off its equilibrium value, as inside a Newton iteration.
                let s = pressure_scale(mat.as_ref(), 1.0);
                let pi = [0.3 * mat.shear_modulus() / s, 0.1, -0.2];
                let (_, k) = mixed(&x0, &u0, &pi, mat.as_ref(), hg, true);
                let kmax = k.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                let h = 1e-6;
                for col in 0..DOFS {
                    let (mut up, mut um, mut pp, mut pm) = (u0, u0, pi, pi);
                    if col < 24 {
                        up[col / 3][col % 3] += h;
                        um[col / 3][col % 3] -= h;
                    } else {
                        pp[col - 24] += h;
                        pm[col - 24] -= h;
                    }
                    let (fp, _) = mixed(&x0, &up, &pp, mat.as_ref(), hg, false);
                    let (fm, _) = mixed(&x0, &um, &pm, mat.as_ref(), hg, false);
                    for row in 0..DOFS {
                        let fd = (fp[row] - fm[row]) / (2.0 * h);
                        let an = k[row * DOFS + col];
                        assert!(
                            (fd - an).abs() < 1e-6 * kmax,
                            "{mat:?} hg {hg}: K[{row},{col}] = {an}, fd {fd}"
                        );
                    }
                }
            }
        }
    }

    /// At its equilibrium pressure p = U'(J̄) the hybrid element is F-bar: the same force
    /// and stress (a non-uniform J, with and without the hourglass spring), and r_π = 0.
    #[test]
    fn at_equilibrium_pressure_it_is_fbar() {
        let x0 = hex();
        let u = deform(&x0, &comp(), 0.03);
        for mat in mats() {
            for hg in [0.0, 3.0] {
                let ns = 8 * mat.n_state();
                let (old, mut new) = (vec![0.0; ns], vec![0.0; ns]);
                let mut fb = vec![0.0; 24];
                element_force(
                    ElemKind::Hex8,
                    Formulation::FBar { hourglass: hg },
                    &ElementData::new(&x0, &u, mat.as_ref(), &old),
                    ElementOutput::new(&mut new, &mut fb, None),
                )
                .unwrap();
                let v0 = crate::fem::measure::element_volume(ElemKind::Hex8, &x0);
                let jbar = crate::fem::measure::element_volume(
                    ElemKind::Hex8,
                    &std::array::from_fn::<_, 8, _>(|a| {
                        [x0[a][0] + u[a][0], x0[a][1] + u[a][1], x0[a][2] + u[a][2]]
                    }),
                ) / v0;
                let p = mat.volumetric(jbar).unwrap().0;
                let pi = [p / pressure_scale(mat.as_ref(), v0), 0.0, 0.0];
                let (fh, _) = mixed(&x0, &u, &pi, mat.as_ref(), hg, false);
                let scale = fb.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                for (a, b) in fb.iter().zip(&fh[..24]) {
                    assert!((a - b).abs() < 1e-10 * scale, "{mat:?}: {a} vs {b}");
                }
                assert!(fh[24].abs() < 1e-10 * scale, "{mat:?}: r_p = {}", fh[24]);
                let sb = element_stress(
                    ElemKind::Hex8,
                    Formulation::FBAR,
                    &ElementData::new(&x0, &u, mat.as_ref(), &old),
                )
                .unwrap();
                let sh = Hybrid::new(0.0)
                    .stress(&ElementData::new(&x0, &u, mat.as_ref(), &old).with_own(&pi))
                    .unwrap();
                let smax = sb.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                for i in 0..6 {
                    assert!((sb[i] - sh[i]).abs() < 1e-10 * smax, "{sb:?} vs {sh:?}");
                }
            }
        }
    }

    /// Where J is uniform (a homogeneous F) the hybrid element at its equilibrium
    /// pressure is the standard element: the same force and stress, and r_π = 0.
    #[test]
    fn homogeneous_deformation_at_equilibrium_pressure_is_the_standard_element() {
        let x0 = hex();
        for mat in mats() {
            let u = deform(&x0, &comp(), 0.0);
            let j = comp().determinant();
            let p = mat.volumetric(j).unwrap().0;
            let v0 = crate::fem::measure::element_volume(ElemKind::Hex8, &x0);
            let pi = [p / pressure_scale(mat.as_ref(), v0), 0.0, 0.0];
            let (fh, _) = mixed(&x0, &u, &pi, mat.as_ref(), 0.0, false);
            let ns = 8 * mat.n_state();
            let (old, mut new) = (vec![0.0; ns], vec![0.0; ns]);
            let mut fs = vec![0.0; 24];
            element_force(
                ElemKind::Hex8,
                Formulation::Standard,
                &ElementData::new(&x0, &u, mat.as_ref(), &old),
                ElementOutput::new(&mut new, &mut fs, None),
            )
            .unwrap();
            let scale = fs.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (a, b) in fs.iter().zip(&fh[..24]) {
                assert!((a - b).abs() < 1e-10 * scale, "{mat:?}: {a} vs {b}");
            }
            assert!(fh[24].abs() < 1e-10 * scale, "{mat:?}: r_p = {}", fh[24]);
            let ss = element_stress(
                ElemKind::Hex8,
                Formulation::Standard,
                &ElementData::new(&x0, &u, mat.as_ref(), &old),
            )
            .unwrap();
            let sh = Hybrid::new(0.0)
                .stress(&ElementData::new(&x0, &u, mat.as_ref(), &old).with_own(&pi))
                .unwrap();
            let smax = ss.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for i in 0..6 {
                assert!((ss[i] - sh[i]).abs() < 1e-10 * smax, "{ss:?} vs {sh:?}");
            }
        }
    }

    /// A rigid motion with zero pressure gives no force.
    #[test]
    fn rigid_motion_gives_zero_force() {
        let x0 = hex();
        let r = nalgebra::Rotation3::from_axis_angle(
            &nalgebra::Unit::new_normalize(Vector3::new(1.0, 2.0, -0.5)),
            1.0,
        )
        .into_inner();
        let mut u = deform(&x0, &r, 0.0);
        for ua in &mut u {
            ua[2] += 0.7;
        }
        for mat in mats() {
            let (f, _) = mixed(&x0, &u, &[0.0; 3], mat.as_ref(), 3.0, false);
            assert!(f.iter().all(|v| v.abs() < 1e-12), "{mat:?}: {f:?}");
        }
    }
}
