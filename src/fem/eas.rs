//! Elements with enhanced assumed strains for thin parts: they bend with one element
//! through the thickness, where the standard elements shear-lock.
//!
//! * The hex8 Q1/E9 (Simo & Armero, IJNME 33 (1992) 1413; Simo, Armero & Taylor, CMAME
//!   110 (1993) 359): F = I + Σ_a u_a ⊗ ∇_X N_a + H̃(α), H̃ = Σ_k α_k H_k, with nine modes
//!   H_(i,m) = (j₀ / j(ξ)) ξ_m e_i ⊗ (J₀⁻ᵀ e_m): the gradients of Wilson's incompatible
//!   displacements (ξ_m² − 1)/2 e_i, mapped with the Jacobian J₀ at the centre and scaled
//!   by j₀/j so that ∫ H̃ dV = 0 and the patch test passes on any hex.
//! * The solid-shell wedge6 (issue 35: triangles in sheets), built the same way with
//!   twelve modes, the gradients of the incompatible displacements e_i (ζ² − 1)/2 through
//!   the thickness (Poisson thickness locking: ε_zz linear in ζ) and e_i φ_k(ξ, η) with
//!   φ = ξ²/2, ξη, η²/2 in the triangle (their gradients less their means over it): the
//!   bending modes' parasitic transverse shear is the gradient of a quadratic, which these
//!   cancel. Only gradients of incompatible displacements are added, so the twist of the
//!   top triangle against the bottom one (curl-shaped shear) keeps its stiffness and no
//!   zero-energy mode appears. The constant part of the shear stays a constraint per
//!   element, as in any three-node plate triangle: stiffer than the EAS hex8 where
//!   triangles dominate (measured in README "Sheets of triangles").
//! * The nine α are the element's own unknowns. At every evaluation they are solved
//!   from R_α = ∫ P : H_k dV = 0 by a local Newton iteration (starting from the last
//!   converged α), so the element's force is a function of u alone. JFNK's difference
//!   products and the exact Jacobian then see the same residual. The tangent is the
//!   condensed K_uu − K_uα K_αα⁻¹ K_αu. Nothing of α leaves the element: it is stored
//!   after the integration points' history.
//! * Any material: one bilinear form serves u and α variations alike. For variations
//!   δF₁, δF₂ fixed in the reference (Grad δu and H_k both are), with l = δF F⁻¹,
//!   D(τ : l₁)[δF₂] = sym l₁ : c : sym l₂ + τ : (l₁ᵀ l₂), the spatial form of
//!   [`super::solid`]. Small kinematics uses l = δF, the Cauchy stress, no τ term.
//!
//! Known limit (Wriggers & Reese 1996): under large compression an EAS element can show
//! hourglass instabilities; `reduced` is the element for that.

use super::error::{material_at, At, ElementError};
use super::kernel::{nodes, ElementData, ElementKernel, ElementOutput};
use super::kinematics::{
    add_force, add_tangent, cofactor, deformation_gradient, reference_point, LocalTangent,
};
use super::shape::{Tabulated, HEX8, WEDGE6};
use crate::material::{Kinematics, Material, StressPoint};
use nalgebra::{Matrix3, SMatrix, SVector};

/// Enhanced parameters of the EAS hex8.
pub const N_ALPHA: usize = 9;
/// Enhanced parameters of the solid-shell wedge6.
pub const N_ALPHA_WEDGE: usize = 12;

type M3 = Matrix3<f64>;

/// An element kind with enhanced modes: N nodes, G points, A = 3 K modes from K parent
/// gradients of incompatible displacement shapes.
trait EasShape<const N: usize, const G: usize, const A: usize> {
    const TAB: &'static Tabulated<3, N, G>;
    /// Where J₀ is taken (the parent centre).
    const CENTRE: [f64; 3];
    /// Parent gradients per mode shape (K = A / 3 of them).
    const K: usize;
    fn dn(xi: [f64; 3]) -> [[f64; 3]; N];
    /// The K parent gradients at ξ, each with zero integral over the parent.
    fn gradients(xi: [f64; 3]) -> [[f64; 3]; 4];
}

/// Q1/E9: gradients of (ξ_m² − 1)/2.
struct HexShape;
impl EasShape<8, 8, N_ALPHA> for HexShape {
    const TAB: &'static Tabulated<3, 8, 8> = &HEX8;
    const CENTRE: [f64; 3] = [0.0; 3];
    const K: usize = 3;
    fn dn(xi: [f64; 3]) -> [[f64; 3]; 8] {
        super::shape::hex8_dn(xi)
    }
    fn gradients(xi: [f64; 3]) -> [[f64; 3]; 4] {
        [
            [xi[0], 0.0, 0.0],
            [0.0, xi[1], 0.0],
            [0.0, 0.0, xi[2]],
            [0.0; 3],
        ]
    }
}

/// The solid-shell wedge: gradients of (ζ² − 1)/2, ξ²/2, ξη, η²/2 less their means
/// (1/3 for ξ and η over the triangle; the 3-point rule integrates them exactly).
struct WedgeShape;
impl EasShape<6, 6, N_ALPHA_WEDGE> for WedgeShape {
    const TAB: &'static Tabulated<3, 6, 6> = &WEDGE6;
    const CENTRE: [f64; 3] = [1.0 / 3.0, 1.0 / 3.0, 0.0];
    const K: usize = 4;
    fn dn(xi: [f64; 3]) -> [[f64; 3]; 6] {
        super::shape::wedge6_dn(xi)
    }
    fn gradients(xi: [f64; 3]) -> [[f64; 3]; 4] {
        let (a, b) = (xi[0] - 1.0 / 3.0, xi[1] - 1.0 / 3.0);
        [[0.0, 0.0, xi[2]], [a, 0.0, 0.0], [b, a, 0.0], [0.0, b, 0.0]]
    }
}

/// Reference data of one element.
struct Reference<const N: usize, const G: usize, const A: usize> {
    grad0: [[[f64; 3]; N]; G],
    w: [f64; G],
    /// The modes H_k at each point.
    modes: [[M3; A]; G],
}

fn reference<S: EasShape<N, G, A>, const N: usize, const G: usize, const A: usize>(
    x0: &[[f64; 3]; N],
) -> Result<Reference<N, G, A>, ElementError> {
    // J₀ = ∂X/∂ξ at the centre.
    let dn0 = S::dn(S::CENTRE);
    let mut j0 = M3::zeros();
    for (x, d) in x0.iter().zip(&dn0) {
        for r in 0..3 {
            for c in 0..3 {
                j0[(r, c)] += x[r] * d[c];
            }
        }
    }
    let det_j0 = j0.determinant();
    if det_j0.is_nan() || det_j0 <= 0.0 {
        return Err(ElementError::ReferenceInverted {
            at: At::Centre,
            det: det_j0,
        });
    }
    // Rows of J₀⁻¹: ∂ξ_m/∂X.
    let j0_inv = cofactor(&j0).transpose() / det_j0;
    let mut r = Reference {
        grad0: [[[0.0; 3]; N]; G],
        w: [0.0; G],
        modes: [[M3::zeros(); A]; G],
    };
    for g in 0..G {
        let (grad0, det) = reference_point(x0, &S::TAB.dn[g], g)?;
        r.grad0[g] = grad0;
        r.w[g] = S::TAB.weights[g] * det;
        let grads = S::gradients(S::TAB.points[g]);
        for i in 0..3 {
            for (k, d) in grads[..S::K].iter().enumerate() {
                // e_i ⊗ (j₀/j) J₀⁻ᵀ d.
                let mut h = M3::zeros();
                for c in 0..3 {
                    h[(i, c)] = det_j0 / det * (0..3).map(|m| d[m] * j0_inv[(m, c)]).sum::<f64>();
                }
                r.modes[g][S::K * i + k] = h;
            }
        }
    }
    Ok(r)
}

/// sym(l) in Voigt order (xx, yy, zz, xy, yz, xz) with engineering shears.
fn voigt_strain(l: &M3) -> [f64; 6] {
    [
        l[(0, 0)],
        l[(1, 1)],
        l[(2, 2)],
        l[(0, 1)] + l[(1, 0)],
        l[(1, 2)] + l[(2, 1)],
        l[(0, 2)] + l[(2, 0)],
    ]
}

fn tensor(s: &[f64; 6]) -> M3 {
    M3::new(s[0], s[3], s[5], s[3], s[1], s[4], s[5], s[4], s[2])
}

/// τ : l (τ symmetric), from sym l in Voigt order (engineering shears).
fn work(s: &[f64; 6], e: &[f64; 6]) -> f64 {
    s[0] * e[0] + s[1] * e[1] + s[2] * e[2] + s[3] * e[3] + s[4] * e[4] + s[5] * e[5]
}

/// One factor of the bilinear form below, prepared once per point: `l`, its strain
/// sym l, c : sym l and l τ. The form is evaluated 81 times per point for K_αα and 432
/// for K_uα and K_αu; preparing each factor once does the 6×6 and 3×3 products 9 + 24
/// times instead (the same operations in the same order, so the same bits).
struct Factor {
    l: M3,
    e: [f64; 6],
    ce: [f64; 6],
    lt: M3,
}

impl Factor {
    fn new(sp: &StressPoint, l: M3, finite: bool) -> Self {
        let e = voigt_strain(&l);
        let ce = std::array::from_fn(|r| {
            sp.tangent[r]
                .iter()
                .zip(&e)
                .map(|(c, b)| c * b)
                .sum::<f64>()
        });
        let lt = if finite {
            l * tensor(&sp.stress)
        } else {
            M3::zeros()
        };
        Self { l, e, ce, lt }
    }
}

/// D(τ : l₁)[δF₂] = sym l₁ : c : sym l₂ + τ : (l₁ᵀ l₂) (the second term only if finite).
fn bilinear(f1: &Factor, f2: &Factor, finite: bool) -> f64 {
    let mut s = 0.0;
    for (a, c) in f1.e.iter().zip(&f2.ce) {
        s += a * c;
    }
    if finite {
        // τ : (l₁ᵀ l₂) = tr(l₁ τ l₂ᵀ) = (l₁ τ) : l₂.
        s += f1.lt.component_mul(&f2.l).sum();
    }
    s
}

/// The enhanced F = I + Grad u + Σ α_k H_k at one point.
fn point_f<const N: usize>(
    u: &[[f64; 3]; N],
    grad0: &[[f64; 3]; N],
    modes: &[M3],
    alpha: &[f64],
) -> M3 {
    let mut f = deformation_gradient(u, grad0);
    for (h, a) in modes.iter().zip(alpha) {
        f += h * *a;
    }
    f
}

/// Largest local Newton iterations on α.
const MAX_LOCAL: usize = 30;

/// The EAS hex8 (Q1/E9); its history is the 8 points' material history, then α.
#[derive(Debug, Clone, Copy)]
pub struct Eas;

impl ElementKernel for Eas {
    fn n_nodes(&self) -> usize {
        8
    }
    fn n_points(&self) -> usize {
        8
    }
    fn state_len(&self, n_state: usize) -> usize {
        state_len(n_state)
    }
    fn force(&self, e: &ElementData, out: ElementOutput) -> Result<(), ElementError> {
        force::<HexShape, 8, 8, N_ALPHA>(e, out)
    }
    fn stress(&self, e: &ElementData) -> Result<[f64; 6], ElementError> {
        stress::<HexShape, 8, 8, N_ALPHA>(nodes(e.x0), nodes(e.u), e.mat, e.state_old)
    }
}

/// The solid-shell wedge6; its history is the 6 points' material history, then α.
#[derive(Debug, Clone, Copy)]
pub struct EasWedge;

impl ElementKernel for EasWedge {
    fn n_nodes(&self) -> usize {
        6
    }
    fn n_points(&self) -> usize {
        6
    }
    fn state_len(&self, n_state: usize) -> usize {
        6 * n_state + N_ALPHA_WEDGE
    }
    fn force(&self, e: &ElementData, out: ElementOutput) -> Result<(), ElementError> {
        force::<WedgeShape, 6, 6, N_ALPHA_WEDGE>(e, out)
    }
    fn stress(&self, e: &ElementData) -> Result<[f64; 6], ElementError> {
        stress::<WedgeShape, 6, 6, N_ALPHA_WEDGE>(nodes(e.x0), nodes(e.u), e.mat, e.state_old)
    }
}

/// One pass over the points at the current α: the enhanced residual R_α and block K_αα,
/// the scale the convergence test uses, and each point's stress and F⁻¹.
struct Pass<const G: usize, const A: usize> {
    ra: SVector<f64, A>,
    kaa: SMatrix<f64, A, A>,
    /// max over points of |τ| w |H|: the element's stress work per unit α.
    scale: f64,
    /// max over points of |F − I|: the strains' round-off floor.
    grad_max: f64,
    sps: [Option<StressPoint>; G],
    finv: [M3; G],
}

/// The element without its enhanced parameters' Newton loop: reference data, material,
/// displacements, history.
struct Local<'a, const N: usize, const G: usize, const A: usize> {
    r: &'a Reference<N, G, A>,
    u: &'a [[f64; 3]; N],
    e: &'a ElementData<'a>,
    finite: bool,
}

impl<const N: usize, const G: usize, const A: usize> Local<'_, N, G, A> {
    /// Evaluates every point at `alpha` into `p` (trial history into `state_new`);
    /// `Some((g, det F))` if point g is inverted.
    fn pass(
        &self,
        alpha: &[f64; A],
        state_new: &mut [f64],
        p: &mut Pass<G, A>,
    ) -> Result<Option<(usize, f64)>, ElementError> {
        let (r, mat, finite) = (self.r, self.e.mat, self.finite);
        let ns = mat.n_state();
        p.ra = SVector::<f64, A>::zeros();
        p.kaa.fill(0.0);
        p.scale = 0.0;
        p.grad_max = 0.0;
        for g in 0..G {
            let fm = point_f(self.u, &r.grad0[g], &r.modes[g], alpha);
            p.grad_max = p.grad_max.max((fm - M3::identity()).amax());
            if finite {
                let j = fm.determinant();
                if j.is_nan() || j <= 0.0 {
                    return Ok(Some((g, j)));
                }
                p.finv[g] = cofactor(&fm).transpose() / j;
            }
            let sp = self
                .e
                .evaluate(
                    &fm,
                    g * ns..(g + 1) * ns,
                    &mut state_new[g * ns..(g + 1) * ns],
                )
                .map_err(material_at(At::Gauss(g)))?;
            let ls: [Factor; A] =
                std::array::from_fn(|q| Factor::new(&sp, r.modes[g][q] * p.finv[g], finite));
            for a in 0..A {
                p.ra[a] += r.w[g] * work(&sp.stress, &ls[a].e);
                for q in 0..A {
                    p.kaa[(a, q)] += r.w[g] * bilinear(&ls[a], &ls[q], finite);
                }
            }
            let hmax = r.modes[g].iter().map(|h| h.amax()).fold(0.0f64, f64::max);
            let smax = sp.stress.iter().fold(0.0f64, |m, s| m.max(s.abs()));
            p.scale = p.scale.max(smax * r.w[g] * hmax);
            p.sps[g] = Some(sp);
        }
        Ok(None)
    }

    /// The local Newton iteration on R_α(u, α) = 0 from `alpha`; returns the converged
    /// α and its pass with `kaa` holding K_αα⁻¹.
    fn solve(
        &self,
        mut alpha: [f64; A],
        state_new: &mut [f64],
    ) -> Result<([f64; A], Pass<G, A>), ElementError> {
        let mut it = 0;
        let mut last_da = f64::INFINITY;
        let du = displacement_range(self.u);
        // A local step that inverts a point is halved (up to 8 times); α from the last
        // converged state that inverts one is dropped for α = 0 (the compatible element).
        #[allow(clippy::type_complexity)]
        let mut prev: Option<([f64; A], SVector<f64, A>, f64)> = None;
        let mut halvings = 0;
        let mut restarted = false;
        let mut p = Pass {
            ra: SVector::<f64, A>::zeros(),
            kaa: SMatrix::<f64, A, A>::zeros(),
            scale: 0.0,
            grad_max: 0.0,
            sps: std::array::from_fn(|_| None),
            finv: [M3::identity(); G],
        };
        loop {
            if let Some((g, j)) = self.pass(&alpha, state_new, &mut p)? {
                if let (Some((a0, da, _)), true) = (&prev, halvings < 8) {
                    halvings += 1;
                    let s = 0.5f64.powi(halvings);
                    alpha = std::array::from_fn(|i| a0[i] - s * da[i]);
                    continue;
                }
                if prev.is_none() && !restarted && alpha.iter().any(|&a| a != 0.0) {
                    restarted = true;
                    alpha = [0.0; A];
                    continue;
                }
                return Err(ElementError::Inverted {
                    at: At::Gauss(g),
                    det: j,
                });
            }
            let Some(inv) = p.kaa.try_inverse() else {
                return Err(ElementError::SingularEnhanced);
            };
            // Converged when the enhanced residual is 1e-10 of the element's stress work
            // (or there is no stress), or when the last Newton correction was 1e-8 of α
            // and of the element's displacements, or at the round-off floor: strains come
            // from F − I, which carries ε_machine / |F − I| relative noise (1e-7 at the
            // pinched cylinder's strains of 1e-9), and no iteration can pass a test finer
            // than that.
            let res = p.ra.amax();
            let a_norm = alpha.iter().fold(0.0f64, |m, a| m.max(a.abs()));
            let floor = 1e-8 + 1e3 * f64::EPSILON / p.grad_max.max(f64::MIN_POSITIVE);
            if res <= 1e-10 * p.scale || p.scale == 0.0 || last_da <= floor * (a_norm + du) {
                p.kaa = inv;
                return Ok((alpha, p));
            }
            // A local step that raises the enhanced residual (a point switching between
            // elastic and plastic across it) is halved too.
            if let (Some((a0, da, r0)), true) = (&prev, halvings < 8) {
                if res > *r0 {
                    halvings += 1;
                    let s = 0.5f64.powi(halvings);
                    alpha = std::array::from_fn(|i| a0[i] - s * da[i]);
                    continue;
                }
            }
            it += 1;
            if it > MAX_LOCAL {
                return Err(ElementError::EnhancedNotConverged {
                    iterations: MAX_LOCAL,
                    residual: p.ra.amax(),
                });
            }
            let da = inv * p.ra;
            prev = Some((alpha, da, res));
            halvings = 0;
            for (a, d) in alpha.iter_mut().zip(da.iter()) {
                *a -= d;
            }
            last_da = da.amax();
        }
    }
}

/// The element's displacement range, the size of α's corrections that matter.
fn displacement_range(u: &[[f64; 3]]) -> f64 {
    (0..3)
        .map(|c| {
            let (lo, hi) = u
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| {
                    (l.min(x[c]), h.max(x[c]))
                });
            hi - lo
        })
        .fold(0.0f64, f64::max)
}

/// Internal force and (if `out.k`) the condensed tangent of one EAS element; the history
/// holds the G points' material history and then α.
fn force<S: EasShape<N, G, A>, const N: usize, const G: usize, const A: usize>(
    e: &ElementData,
    out: ElementOutput,
) -> Result<(), ElementError> {
    let ElementOutput { state_new, f, k } = out;
    let ns = e.mat.n_state();
    assert_eq!(e.state_old.len(), G * ns + A, "EAS history length");
    assert_eq!(state_new.len(), G * ns + A, "EAS history length");
    let finite = e.mat.kinematics() == Kinematics::Finite;
    let r = reference::<S, N, G, A>(nodes(e.x0))?;
    // A frozen product starts from the iterate's α: one or two local iterations.
    let start = e.branch.unwrap_or(e.state_old);
    let alpha0: [f64; A] = std::array::from_fn(|i| start[G * ns + i]);
    let local = Local {
        r: &r,
        u: nodes(e.u),
        e,
        finite,
    };
    let (alpha, p) = local.solve(alpha0, state_new)?;
    state_new[G * ns..].copy_from_slice(&alpha);
    assemble(&r, &p, finite, f, k);
    Ok(())
}

/// Force and tangent at the converged α; `p.kaa` holds K_αα⁻¹.
fn assemble<const N: usize, const G: usize, const A: usize>(
    r: &Reference<N, G, A>,
    p: &Pass<G, A>,
    finite: bool,
    f: &mut [f64],
    k: Option<&mut [f64]>,
) {
    f.fill(0.0);
    let nd = 3 * N;
    let mut kuu: LocalTangent<N> = [[[[0.0; 3]; N]; 3]; N];
    // K_uα by rows (node, component), K_αu by columns; fixed-size, as kuu: this runs
    // for every EAS element at every tangent.
    let mut kua = [[[0.0; A]; 3]; N];
    let mut kau = [[[0.0; 3]; N]; A];
    for g in 0..G {
        let sp = p.sps[g].as_ref().expect("evaluated");
        let grad: [[f64; 3]; N] = if finite {
            super::kinematics::transform_gradients(&p.finv[g].transpose(), &r.grad0[g])
        } else {
            r.grad0[g]
        };
        add_force(&grad, &sp.stress, r.w[g], f);
        if k.is_none() {
            continue;
        }
        add_tangent(&grad, sp, finite, r.w[g], &mut kuu);
        let ls: [Factor; A] =
            std::array::from_fn(|q| Factor::new(sp, r.modes[g][q] * p.finv[g], finite));
        for a in 0..N {
            for i in 0..3 {
                let mut lu = M3::zeros();
                for c in 0..3 {
                    lu[(i, c)] = grad[a][c];
                }
                let lu = Factor::new(sp, lu, finite);
                for q in 0..A {
                    kua[a][i][q] += r.w[g] * bilinear(&lu, &ls[q], finite);
                    kau[q][a][i] += r.w[g] * bilinear(&ls[q], &lu, finite);
                }
            }
        }
    }
    if let Some(k) = k {
        let flat = kuu.as_flattened().as_flattened().as_flattened();
        // K_uα K_αα⁻¹, then the product with K_αu.
        let kua = kua.as_flattened();
        let mut kuaa = [[[0.0; A]; 3]; N];
        for (row, src) in kuaa.as_flattened_mut().iter_mut().zip(kua) {
            for (q, r) in row.iter_mut().enumerate() {
                *r = (0..A).map(|a| src[a] * p.kaa[(a, q)]).sum();
            }
        }
        let kuaa_flat = kuaa.as_flattened();
        for i in 0..nd {
            for j in 0..nd {
                k[nd * i + j] = flat[nd * i + j]
                    - (0..A)
                        .map(|q| kuaa_flat[i][q] * kau[q].as_flattened()[j])
                        .sum::<f64>();
            }
        }
    }
}

/// History length of an EAS hex8: the points' material history, then α.
pub fn state_len(n_state: usize) -> usize {
    8 * n_state + N_ALPHA
}

/// Volume-averaged stress at the committed state (α from `state_old`), as the other
/// kernels give it.
fn stress<S: EasShape<N, G, A>, const N: usize, const G: usize, const A: usize>(
    x0: &[[f64; 3]; N],
    u: &[[f64; 3]; N],
    mat: &dyn Material,
    state_old: &[f64],
) -> Result<[f64; 6], ElementError> {
    let ns = mat.n_state();
    let r = reference::<S, N, G, A>(x0)?;
    let alpha = &state_old[G * ns..G * ns + A];
    let mut scratch = vec![0.0; ns];
    let finite = mat.kinematics() == Kinematics::Finite;
    let (mut sum, mut vol) = ([0.0; 6], 0.0);
    for g in 0..G {
        let fm = point_f(u, &r.grad0[g], &r.modes[g], alpha);
        let s = mat
            .evaluate_stress(&fm, &state_old[g * ns..(g + 1) * ns], &mut scratch)
            .map_err(material_at(At::Gauss(g)))?;
        for (a, b) in sum.iter_mut().zip(&s) {
            *a += r.w[g] * b;
        }
        vol += r.w[g] * if finite { fm.determinant() } else { 1.0 };
    }
    Ok(sum.map(|s| s / vol))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::element::{element_force, kernel, Formulation};
    use crate::fem::shape::HEX8_NODES;
    use crate::material::{Hardening, J2Plasticity, LinearElastic, NeoHookean};
    use crate::mesh::ElemKind;

    /// A distorted hex about the box [0, 2] × [0, 1] × [0, 0.5].
    fn distorted() -> Vec<[f64; 3]> {
        let d = [
            [0.05, -0.03, 0.02],
            [-0.04, 0.02, -0.01],
            [0.03, 0.04, 0.03],
            [-0.02, -0.05, 0.01],
            [0.01, 0.03, -0.02],
            [0.06, -0.02, 0.02],
            [-0.03, 0.01, -0.03],
            [0.02, 0.02, 0.01],
        ];
        HEX8_NODES
            .iter()
            .zip(d)
            .map(|(p, e)| {
                [
                    (p[0] + 1.0) + e[0],
                    0.5 * (p[1] + 1.0) + e[1],
                    0.25 * (p[2] + 1.0) + e[2],
                ]
            })
            .collect()
    }

    fn run(
        form: Formulation,
        x0: &[[f64; 3]],
        u: &[[f64; 3]],
        mat: &dyn Material,
        k: bool,
    ) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        run_kind(ElemKind::Hex8, form, x0, u, mat, k)
    }

    fn run_kind(
        kind: ElemKind,
        form: Formulation,
        x0: &[[f64; 3]],
        u: &[[f64; 3]],
        mat: &dyn Material,
        k: bool,
    ) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let n = kernel(kind, form).state_len(mat.n_state());
        let (old, mut new) = (vec![0.0; n], vec![0.0; n]);
        let nd = 3 * kind.n_nodes();
        let mut f = vec![0.0; nd];
        let mut kk = vec![0.0; nd * nd];
        element_force(
            kind,
            form,
            &ElementData::new(x0, u, mat, &old),
            ElementOutput::new(&mut new, &mut f, if k { Some(&mut kk) } else { None }),
        )
        .unwrap();
        (f, kk, new)
    }

    /// The patch test: under any homogeneous deformation of a distorted element the
    /// enhanced strains stay at zero and the force is the standard element's.
    #[test]
    fn homogeneous_fields_leave_the_enhanced_strains_at_zero() {
        let x0 = distorted();
        let fdef = Matrix3::new(1.1, 0.05, -0.02, 0.03, 0.95, 0.04, -0.01, 0.02, 1.05);
        let u: Vec<[f64; 3]> = x0
            .iter()
            .map(|x| {
                let v = (fdef - Matrix3::identity()) * nalgebra::Vector3::from(*x);
                [v[0], v[1], v[2]]
            })
            .collect();
        let mat = NeoHookean::new(100.0, 0.3, 1.0);
        let (fe, _, state) = run(Formulation::Eas, &x0, &u, &mat, false);
        let (fs, _, _) = run(Formulation::Standard, &x0, &u, &mat, false);
        let scale = fs.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(fe
            .iter()
            .zip(&fs)
            .all(|(a, b)| (a - b).abs() < 1e-11 * scale));
        assert!(state.iter().all(|a| a.abs() < 1e-12), "{state:?}");
    }

    /// The condensed tangent is the derivative of the force (α re-solved at every
    /// perturbed state) for an elastic, a hyperelastic and a yielding material.
    #[test]
    fn condensed_tangent_matches_finite_differences() {
        let x0 = distorted();
        let u: Vec<[f64; 3]> = (0..8)
            .map(|a| {
                let s = a as f64;
                [
                    0.02 * (s * 1.3).sin(),
                    -0.015 * (s * 0.7).cos(),
                    0.03 * (s * 2.1).sin() * x0[a][0],
                ]
            })
            .collect();
        let mats: Vec<Box<dyn Material>> = vec![
            Box::new(LinearElastic::new(200.0, 0.3, 1.0)),
            Box::new(NeoHookean::new(100.0, 0.45, 1.0)),
            Box::new(J2Plasticity::new(
                200.0,
                0.3,
                Hardening::Linear {
                    sigma_y0: 0.5,
                    h: 20.0,
                },
                1.0,
            )),
        ];
        for mat in &mats {
            let (_, k, _) = run(Formulation::Eas, &x0, &u, mat.as_ref(), true);
            let kmax = k.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let h = 1e-6;
            let mut worst = 0.0f64;
            for j in 0..24 {
                let mut up = u.clone();
                let mut um = u.clone();
                up[j / 3][j % 3] += h;
                um[j / 3][j % 3] -= h;
                let (fp, _, _) = run(Formulation::Eas, &x0, &up, mat.as_ref(), false);
                let (fm, _, _) = run(Formulation::Eas, &x0, &um, mat.as_ref(), false);
                for i in 0..24 {
                    let fd = (fp[i] - fm[i]) / (2.0 * h);
                    worst = worst.max((fd - k[24 * i + j]).abs() / kmax);
                }
            }
            assert!(worst < 1e-6, "{mat:?}: {worst:.2e}");
        }
    }

    /// Why the element exists: one element of a beam (L = 2, b = 1, t = 0.5, ν = 0) bent
    /// to curvature κ stores E I κ² L / 2 exactly, where the standard hex8 locks.
    #[test]
    fn pure_bending_is_exact() {
        let (l, b, t) = (2.0, 1.0, 0.5);
        let x0: Vec<[f64; 3]> = HEX8_NODES
            .iter()
            .map(|p| {
                [
                    0.5 * l * (p[0] + 1.0),
                    0.5 * b * (p[1] + 1.0),
                    0.5 * t * p[2],
                ]
            })
            .collect();
        let kappa = 1e-3;
        let u: Vec<[f64; 3]> = x0
            .iter()
            .map(|x| [-kappa * x[2] * x[0], 0.0, 0.5 * kappa * x[0] * x[0]])
            .collect();
        let e = 1000.0;
        let mat = LinearElastic::new(e, 0.0, 1.0);
        let energy = |form| {
            let (f, _, _) = run(form, &x0, &u, &mat, false);
            0.5 * f
                .chunks(3)
                .zip(&u)
                .map(|(fa, ua)| fa[0] * ua[0] + fa[1] * ua[1] + fa[2] * ua[2])
                .sum::<f64>()
        };
        let exact = 0.5 * e * b * t.powi(3) / 12.0 * kappa * kappa * l;
        let eas = energy(Formulation::Eas);
        assert!((eas - exact).abs() < 1e-9 * exact, "{eas} vs {exact}");
        assert!(energy(Formulation::Standard) > 3.0 * exact);
    }

    /// A prism about the triangle (0,0)-(2,0)-(0,1.5), 0.4 thick, its nodes moved.
    fn distorted_wedge() -> Vec<[f64; 3]> {
        let base = [[0.0, 0.0], [2.0, 0.0], [0.0, 1.5]];
        let d = [
            [0.05, -0.03, 0.02],
            [-0.04, 0.02, -0.01],
            [0.03, 0.04, 0.03],
            [-0.02, -0.05, 0.01],
            [0.01, 0.03, -0.02],
            [0.06, -0.02, 0.02],
        ];
        (0..6)
            .map(|a| {
                let z = if a < 3 { 0.0 } else { 0.4 };
                let b = base[a % 3];
                [b[0] + d[a][0], b[1] + d[a][1], z + d[a][2]]
            })
            .collect()
    }

    /// The solid-shell wedge passes the patch test: homogeneous F leaves α at zero and
    /// the force is the standard wedge's.
    #[test]
    fn wedge_homogeneous_fields_leave_the_enhanced_strains_at_zero() {
        let x0 = distorted_wedge();
        let fdef = Matrix3::new(1.1, 0.05, -0.02, 0.03, 0.95, 0.04, -0.01, 0.02, 1.05);
        let u: Vec<[f64; 3]> = x0
            .iter()
            .map(|x| {
                let v = (fdef - Matrix3::identity()) * nalgebra::Vector3::from(*x);
                [v[0], v[1], v[2]]
            })
            .collect();
        let mat = NeoHookean::new(100.0, 0.3, 1.0);
        let (fe, _, state) = run_kind(ElemKind::Wedge6, Formulation::Eas, &x0, &u, &mat, false);
        let (fs, _, _) = run_kind(
            ElemKind::Wedge6,
            Formulation::Standard,
            &x0,
            &u,
            &mat,
            false,
        );
        let scale = fs.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(fe
            .iter()
            .zip(&fs)
            .all(|(a, b)| (a - b).abs() < 1e-11 * scale));
        assert!(state.iter().all(|a| a.abs() < 1e-12), "{state:?}");
    }

    /// The wedge's condensed tangent is the derivative of its force, for the three kinds
    /// of material.
    #[test]
    fn wedge_condensed_tangent_matches_finite_differences() {
        let x0 = distorted_wedge();
        let u: Vec<[f64; 3]> = (0..6)
            .map(|a| {
                let s = a as f64;
                [
                    0.02 * (s * 1.3).sin(),
                    -0.015 * (s * 0.7).cos(),
                    0.03 * (s * 2.1).sin() * x0[a][0],
                ]
            })
            .collect();
        let mats: Vec<Box<dyn Material>> = vec![
            Box::new(LinearElastic::new(200.0, 0.3, 1.0)),
            Box::new(NeoHookean::new(100.0, 0.45, 1.0)),
            Box::new(J2Plasticity::new(
                200.0,
                0.3,
                Hardening::Linear {
                    sigma_y0: 0.5,
                    h: 20.0,
                },
                1.0,
            )),
        ];
        let w = ElemKind::Wedge6;
        for mat in &mats {
            let (_, k, _) = run_kind(w, Formulation::Eas, &x0, &u, mat.as_ref(), true);
            let kmax = k.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let h = 1e-6;
            let mut worst = 0.0f64;
            for j in 0..18 {
                let (mut up, mut um) = (u.clone(), u.clone());
                up[j / 3][j % 3] += h;
                um[j / 3][j % 3] -= h;
                let (fp, _, _) = run_kind(w, Formulation::Eas, &x0, &up, mat.as_ref(), false);
                let (fm, _, _) = run_kind(w, Formulation::Eas, &x0, &um, mat.as_ref(), false);
                for i in 0..18 {
                    let fd = (fp[i] - fm[i]) / (2.0 * h);
                    worst = worst.max((fd - k[18 * i + j]).abs() / kmax);
                }
            }
            assert!(worst < 1e-6, "{mat:?}: {worst:.2e}");
        }
    }

    /// No mode but the six rigid ones costs no energy: the enhanced modes are gradients
    /// of incompatible displacements, so the top triangle's twist against the bottom one
    /// (curl-shaped transverse shear) keeps its stiffness.
    #[test]
    fn wedge_has_only_the_rigid_zero_energy_modes() {
        let x0 = distorted_wedge();
        let mat = LinearElastic::new(200.0, 0.3, 1.0);
        let u = vec![[0.0; 3]; 6];
        let (_, k, _) = run_kind(ElemKind::Wedge6, Formulation::Eas, &x0, &u, &mat, true);
        let k = nalgebra::DMatrix::from_row_slice(18, 18, &k);
        let sym = (&k - k.transpose()).amax();
        let mut ev: Vec<f64> = k.symmetric_eigen().eigenvalues.iter().copied().collect();
        ev.sort_by(f64::total_cmp);
        assert!(sym < 1e-10 * ev[17], "asymmetric by {sym}");
        assert!(ev[5].abs() < 1e-10 * ev[17], "{ev:?}");
        assert!(ev[6] > 1e-3 * ev[17], "a spurious mode: {ev:?}");
    }

    /// What the wedge's modes do and do not do: a strip of two prisms (a 2 × 1 rectangle
    /// cut on its diagonal, 0.1 thick: h/t = 20, ν = 0) bent to curvature κ. The
    /// standard wedge stores 201 × E I κ² L / 2, the solid-shell wedge 68 ×: the linear
    /// part of the parasitic shear is gone, its constant part (−κ/3 here: the slope of
    /// the interpolated w against the mean rotation) is the three-node triangle's
    /// locking, which no mode with zero mean can remove.
    #[test]
    fn wedge_bends_without_locking() {
        let (l, b, t) = (2.0, 1.0, 0.1);
        let tris = [
            [[0.0, 0.0], [l, 0.0], [l, b]],
            [[0.0, 0.0], [l, b], [0.0, b]],
        ];
        let kappa = 1e-3;
        let e = 1000.0;
        let mat = LinearElastic::new(e, 0.0, 1.0);
        let energy = |form| {
            let mut total = 0.0;
            for tri in &tris {
                let x0: Vec<[f64; 3]> = (0..6)
                    .map(|a| {
                        let p = tri[a % 3];
                        [p[0], p[1], if a < 3 { -0.5 * t } else { 0.5 * t }]
                    })
                    .collect();
                let u: Vec<[f64; 3]> = x0
                    .iter()
                    .map(|x| [-kappa * x[2] * x[0], 0.0, 0.5 * kappa * x[0] * x[0]])
                    .collect();
                let (f, _, _) = run_kind(ElemKind::Wedge6, form, &x0, &u, &mat, false);
                total += 0.5
                    * f.chunks(3)
                        .zip(&u)
                        .map(|(fa, ua)| fa[0] * ua[0] + fa[1] * ua[1] + fa[2] * ua[2])
                        .sum::<f64>();
            }
            total
        };
        let exact = 0.5 * e * b * t.powi(3) / 12.0 * kappa * kappa * l;
        let (eas, std) = (energy(Formulation::Eas), energy(Formulation::Standard));
        eprintln!(
            "wedge bending energy / exact: EAS {:.3}, standard {:.3}",
            eas / exact,
            std / exact
        );
        assert!(
            eas > exact && eas < 0.4 * std,
            "EAS {eas}, standard {std}, exact {exact}"
        );
        assert!(std > 100.0 * exact);
    }
}
