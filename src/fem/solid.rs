//! The standard and F-bar solid kernels: internal force, consistent tangent and stress
//! of one element with a tabulated rule (hex8 2×2×2, tet4 one point), total Lagrangian
//! written in the spatial form of Simo & Hughes, *Computational Inelasticity*, §7.2 /
//! Bonet & Wood, *Nonlinear Continuum Mechanics for FEA*, §8–9:
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
//! pieces live in [`super::kinematics`], so F-bar (F̄ = (J̄/J)^{1/3} F, de Souza Neto et
//! al. 1996) reuses them with only a modified F and an extra tangent term.

use super::error::{material_at, At, ElementError};
use super::kernel::{nodes, ElementData, ElementKernel, ElementOutput};
use super::kinematics::{
    add_fbar_tangent, add_force, add_tangent, element_kinematics, LocalTangent,
};
use super::shape::{Tabulated, HEX8};
use crate::material::Kinematics;

/// The standard element of any kind with a tabulated rule: full integration of F.
/// A hex8 locks when the material is nearly incompressible; a one-point tet4 is what it
/// is under any formulation.
#[derive(Debug, Clone, Copy)]
pub struct Standard<const N: usize, const G: usize> {
    pub tab: &'static Tabulated<3, N, G>,
}

impl<const N: usize, const G: usize> ElementKernel for Standard<N, G> {
    fn n_nodes(&self) -> usize {
        N
    }
    fn n_points(&self) -> usize {
        G
    }
    fn force(&self, e: &ElementData, out: ElementOutput) -> Result<(), ElementError> {
        force_kernel(self.tab, false, e, out)
    }
    fn stress(&self, e: &ElementData) -> Result<[f64; 6], ElementError> {
        stress_kernel(self.tab, false, e)
    }
}

/// The mean-dilatation element of any tabulated kind: F-bar with J̄ = v/V, the element's
/// volume ratio (Simo, Taylor & Pister 1985). On a tet10 it is P2/P0 with the constant
/// pressure condensed, which does not lock for nearly incompressible materials.
#[derive(Debug, Clone, Copy)]
pub struct MeanDilatation<const N: usize, const G: usize> {
    pub tab: &'static Tabulated<3, N, G>,
}

impl<const N: usize, const G: usize> ElementKernel for MeanDilatation<N, G> {
    fn n_nodes(&self) -> usize {
        N
    }
    fn n_points(&self) -> usize {
        G
    }
    fn force(&self, e: &ElementData, out: ElementOutput) -> Result<(), ElementError> {
        force_kernel(self.tab, true, e, out)
    }
    fn stress(&self, e: &ElementData) -> Result<[f64; 6], ElementError> {
        stress_kernel(self.tab, true, e)
    }
}

/// The F-bar hex8 (see [`super::element::Formulation::FBar`]), with the hourglass spring
/// of [`super::reduced`] scaled by `hourglass` when it is positive.
#[derive(Debug, Clone, Copy)]
pub struct FBar {
    pub hourglass: f64,
}

impl ElementKernel for FBar {
    fn n_nodes(&self) -> usize {
        8
    }
    fn n_points(&self) -> usize {
        8
    }
    fn force(&self, e: &ElementData, out: ElementOutput) -> Result<(), ElementError> {
        let ElementOutput {
            state_new,
            f,
            mut k,
        } = out;
        force_kernel(
            &HEX8,
            true,
            e,
            ElementOutput::new(state_new, f, k.as_deref_mut()),
        )?;
        if self.hourglass > 0.0 {
            super::reduced::add_hourglass(
                nodes(e.x0),
                nodes(e.u),
                e.mat.shear_modulus(),
                self.hourglass,
                f,
                k,
            )
        } else {
            Ok(())
        }
    }
    fn stress(&self, e: &ElementData) -> Result<[f64; 6], ElementError> {
        stress_kernel(&HEX8, true, e)
    }
}

fn force_kernel<const N: usize, const G: usize>(
    tab: &Tabulated<3, N, G>,
    fbar: bool,
    e: &ElementData,
    out: ElementOutput,
) -> Result<(), ElementError> {
    let ns = e.mat.n_state();
    let ElementOutput { state_new, f, k } = out;
    assert_eq!(f.len(), 3 * N, "force slice length");
    assert!(
        e.state_old.len() == G * ns && state_new.len() == G * ns,
        "history length must be n_gauss × n_state"
    );
    match k {
        Some(k) => {
            assert_eq!(k.len(), 9 * N * N, "tangent slice length");
            let mut kloc = [[[[0.0; 3]; N]; 3]; N];
            gauss_loop(tab, fbar, e, state_new, f, Some(&mut kloc))?;
            k.copy_from_slice(kloc.as_flattened().as_flattened().as_flattened());
            Ok(())
        }
        None => gauss_loop(tab, fbar, e, state_new, f, None),
    }
}

/// The integration-point loop shared by force and force + tangent.
#[inline(always)]
fn gauss_loop<const N: usize, const G: usize>(
    tab: &Tabulated<3, N, G>,
    fbar: bool,
    e: &ElementData,
    state_new: &mut [f64],
    f: &mut [f64],
    mut k: Option<&mut LocalTangent<N>>,
) -> Result<(), ElementError> {
    let mat = e.mat;
    let ns = mat.n_state();
    let kin = mat.kinematics();
    let finite = kin == Kinematics::Finite;
    let (pts, gbar) = element_kinematics(tab, fbar, kin, nodes::<N>(e.x0), nodes::<N>(e.u))?;
    f.fill(0.0);
    for (g, p) in pts.iter().enumerate() {
        let (at, new) = (g * ns..(g + 1) * ns, &mut state_new[g * ns..(g + 1) * ns]);
        match k.as_deref_mut() {
            Some(k) => {
                let sp = e
                    .evaluate(&p.f, at, new)
                    .map_err(material_at(At::Gauss(g)))?;
                add_force(&p.grad, &sp.stress, p.w, f);
                add_tangent(&p.grad, &sp, finite, p.w, k);
                if let Some(gb) = &gbar {
                    add_fbar_tangent(&p.grad, gb, &sp, finite, p.w, k);
                }
            }
            // A residual needs no tangent: the cheaper stress-only path.
            None => {
                let s = e
                    .evaluate_stress(&p.f, at, new)
                    .map_err(material_at(At::Gauss(g)))?;
                add_force(&p.grad, &s, p.w, f);
            }
        }
    }
    Ok(())
}

fn stress_kernel<const N: usize, const G: usize>(
    tab: &Tabulated<3, N, G>,
    fbar: bool,
    e: &ElementData,
) -> Result<[f64; 6], ElementError> {
    const STACK: usize = 64;
    let (mat, state_old) = (e.mat, e.state_old);
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
    let (pts, _) = element_kinematics(tab, fbar, kin, nodes::<N>(e.x0), nodes::<N>(e.u))?;
    let (mut sum, mut vol) = ([0.0; 6], 0.0);
    for (g, p) in pts.iter().enumerate() {
        let stress = mat
            .evaluate_stress(&p.f, &state_old[g * ns..(g + 1) * ns], scratch)
            .map_err(material_at(At::Gauss(g)))?;
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
