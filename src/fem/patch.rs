//! The F-bar-patch tetrahedron: linear tets grouped into patches of a few elements, each
//! tet's F replaced by F̄ = (J̄/J)^{1/3} F with J̄ = v_P / V_P the volume ratio of its
//! patch (de Souza Neto, Andrade Pires & Owen, IJNME 62 (2005) 353, and Andrade Pires,
//! de Souza Neto & Owen, CMAME 193 (2004) 5223 for tetrahedra). A one-point tet4 mesh
//! has about as many volume constraints as nodes and locks for nearly incompressible
//! materials; with patches of n tets there are n times fewer, and for n ≈ 6 the
//! constraint count is a third of the unknowns' (Hughes' constraint ratio 3).
//!
//! A patch is evaluated as one unit over the union of its tets' nodes: every tet's
//! stress depends on every node of the patch through J̄. Residual (the standard F-bar
//! form, spatial, total Lagrangian): f_a = Σ_t τ(F̄_t) ∇_x N_a^t V_t. Tangent: the
//! standard one of each tet at F̄ plus the F-bar term of de Souza Neto eq. 15.20 with
//! the patch's ḡ_b = Σ_t v_t ∇_x N_b^t / v_P ([`super::kinematics::add_fbar_tangent`]
//! with ḡ spread over the patch). Small strain: ε̄ = ε + (θ̄ − tr ε)/3 I, θ̄ the patch's
//! mean volumetric strain. A patch of one tet is the standard tet4.

use super::error::{material_at, At, ElementError};
use super::hybrid::pressure_scale;
use super::kinematics::{
    add_force, add_tangent, cofactor, deformation_gradient, reference_point, transform_gradients,
    LocalTangent,
};
use super::shape::TET4;
use crate::material::{Kinematics, Material};
use nalgebra::Matrix3;

/// One patch: the union of its tets' nodes and the tets in patch-local node numbers.
#[derive(Clone, Copy)]
pub struct PatchData<'a> {
    /// Reference coordinates of the patch's nodes.
    pub x0: &'a [[f64; 3]],
    /// Their displacements.
    pub u: &'a [[f64; 3]],
    /// Each tet's four nodes, indices into `x0`.
    pub tets: &'a [[usize; 4]],
    pub mat: &'a dyn Material,
    /// Committed history, `n_state` values per tet, tet by tet.
    pub state_old: &'a [f64],
    /// JFNK's frozen products: the last natural evaluation's trial history, whose
    /// branches each tet keeps (see [`super::kernel::ElementData::branch`]).
    pub branch: Option<&'a [f64]>,
}

/// An element failure in a patch: which tet (index into [`PatchData::tets`]) and why.
#[derive(Debug, Clone, PartialEq)]
pub struct PatchError {
    pub tet: usize,
    pub error: ElementError,
}

/// One tet's kinematics at its single point.
struct TetPoint {
    /// F̄ (handed to the material).
    f: Matrix3<f64>,
    /// ∇_x N (finite) or ∇_X N (small) of its four nodes.
    grad: [[f64; 3]; 4],
    /// Reference volume.
    w: f64,
}

fn tet_nodes<T: Copy>(all: &[T], t: &[usize; 4]) -> [T; 4] {
    t.map(|a| all[a])
}

/// The patch's kinematics: every tet's point with F̄, ḡ (one per patch node), and the
/// patch's current (finite) and reference volumes.
struct Kin {
    pts: Vec<TetPoint>,
    gbar: Vec<[f64; 3]>,
    v: f64,
    big_v: f64,
}

fn kinematics(p: &PatchData, kin: Kinematics) -> Result<Kin, PatchError> {
    let mut pts = Vec::with_capacity(p.tets.len());
    let mut vol = Vec::with_capacity(p.tets.len());
    for (t, tet) in p.tets.iter().enumerate() {
        let fail = |error| PatchError { tet: t, error };
        let (grad0, det0) = reference_point(&tet_nodes(p.x0, tet), &TET4.dn[0], 0).map_err(fail)?;
        let f = deformation_gradient(&tet_nodes(p.u, tet), &grad0);
        let w = TET4.weights[0] * det0;
        match kin {
            Kinematics::Small => {
                vol.push(f.trace() - 3.0);
                pts.push(TetPoint { f, grad: grad0, w });
            }
            Kinematics::Finite => {
                let j = f.determinant();
                if j.is_nan() || j <= 0.0 {
                    return Err(fail(ElementError::Inverted {
                        at: At::Centroid,
                        det: j,
                    }));
                }
                let grad = transform_gradients(&(cofactor(&f) / j), &grad0);
                vol.push(j);
                pts.push(TetPoint { f, grad, w });
            }
        }
    }
    // ḡ weights: current volume (finite), reference volume (small).
    let mut gbar = vec![[0.0; 3]; p.x0.len()];
    let (mut v, mut big_v, mut theta) = (0.0, 0.0, 0.0);
    for ((pt, &m), tet) in pts.iter().zip(&vol).zip(p.tets) {
        let wt = match kin {
            Kinematics::Finite => m * pt.w,
            Kinematics::Small => pt.w,
        };
        v += wt;
        big_v += pt.w;
        theta += m * pt.w;
        for (&a, ga) in tet.iter().zip(&pt.grad) {
            for c in 0..3 {
                gbar[a][c] += wt * ga[c];
            }
        }
    }
    for gb in &mut gbar {
        for c in gb.iter_mut() {
            *c /= v;
        }
    }
    for (pt, &m) in pts.iter_mut().zip(&vol) {
        match kin {
            Kinematics::Finite => pt.f *= (v / big_v / m).cbrt(),
            Kinematics::Small => {
                let d = (theta / big_v - m) / 3.0;
                for c in 0..3 {
                    pt.f[(c, c)] += d;
                }
            }
        }
    }
    Ok(Kin {
        pts,
        gbar,
        v,
        big_v,
    })
}

/// The hybrid patch's pressure p = s π against U'(J̄) (see [`super::hybrid`]).
struct Pressure {
    s: f64,
    p: f64,
    jbar: f64,
    u1: f64,
    u2: f64,
    k0: f64,
}

impl Pressure {
    fn new(mat: &dyn Material, k: &Kin, pi: f64) -> Result<Self, ElementError> {
        let no_split = || ElementError::NoVolumetricSplit {
            material: format!("{mat:?}"),
        };
        if mat.kinematics() != Kinematics::Finite {
            return Err(no_split());
        }
        let s = pressure_scale(mat, k.big_v);
        let jbar = k.v / k.big_v;
        let (u1, u2) = mat.volumetric(jbar).ok_or_else(no_split)?;
        let k0 = mat.volumetric(1.0).ok_or_else(no_split)?.1;
        Ok(Self {
            s,
            p: s * pi,
            jbar,
            u1,
            u2,
            k0,
        })
    }
    /// J̄ (p − U'(J̄)): added to the normal stresses.
    fn extra(&self) -> f64 {
        self.jbar * (self.p - self.u1)
    }
    /// τ(F̄) + J̄ δp I and its tangent for δp fixed (super::hybrid's module doc).
    fn modify(&self, sp: &mut crate::material::StressPoint) {
        let (jbar, dp) = (self.jbar, self.p - self.u1);
        let a = jbar * (dp - jbar * self.u2);
        for r in 0..3 {
            sp.stress[r] += jbar * dp;
            for c in 0..3 {
                sp.tangent[r][c] += a;
            }
            sp.tangent[r][r] -= 2.0 * jbar * dp;
            sp.tangent[r + 3][r + 3] -= jbar * dp;
        }
    }
}

/// Residual rows `f` (3 per patch node, overwritten) and, with `k`, the consistent
/// tangent (row-major, square, overwritten); the trial history goes to `state_new`.
/// With `pi` (the hybrid patch: its pressure block π, p = s π) `f` and `k` have the
/// block's three rows after the nodes' ([`super::hybrid`]'s equations with the patch's
/// J̄ = v_P / V_P, b_a = ∂v_P/∂u_a and b̂_a = J̄ Σ_t V_t ∇ₓN_a).
pub fn force(
    p: &PatchData,
    pi: Option<&[f64; 3]>,
    state_new: &mut [f64],
    f: &mut [f64],
    mut k: Option<&mut [f64]>,
) -> Result<(), PatchError> {
    let (mat, ns, m) = (p.mat, p.mat.n_state(), p.x0.len());
    let nu = 3 * m;
    let dofs = nu + if pi.is_some() { 3 } else { 0 };
    assert_eq!(f.len(), dofs, "force slice length");
    assert!(p.state_old.len() == p.tets.len() * ns && state_new.len() == p.state_old.len());
    let kin = mat.kinematics();
    let finite = kin == Kinematics::Finite;
    let geo = kinematics(p, kin)?;
    let pressure = match pi {
        Some(pi) => {
            Some(Pressure::new(mat, &geo, pi[0]).map_err(|error| PatchError { tet: 0, error })?)
        }
        None => None,
    };
    f.fill(0.0);
    if let Some(k) = k.as_deref_mut() {
        assert_eq!(k.len(), dofs * dofs, "tangent slice length");
        k.fill(0.0);
    }
    for (t, (pt, tet)) in geo.pts.iter().zip(p.tets).enumerate() {
        let fail = |error| PatchError { tet: t, error };
        let (old, new) = (
            &p.state_old[t * ns..(t + 1) * ns],
            &mut state_new[t * ns..(t + 1) * ns],
        );
        let branch = p.branch.map(|b| &b[t * ns..(t + 1) * ns]);
        let mut ft = [0.0; 12];
        match k.as_deref_mut() {
            Some(k) => {
                let mut sp = match branch {
                    Some(b) => mat.evaluate_on(&pt.f, old, b, new),
                    None => mat.evaluate(&pt.f, old, new),
                }
                .map_err(material_at(At::Centroid))
                .map_err(fail)?;
                if let Some(pr) = &pressure {
                    pr.modify(&mut sp);
                }
                add_force(&pt.grad, &sp.stress, pt.w, &mut ft);
                let mut kt: LocalTangent<4> = [[[[0.0; 3]; 4]; 3]; 4];
                add_tangent(&pt.grad, &sp, finite, pt.w, &mut kt);
                for (a, &pa) in tet.iter().enumerate() {
                    for i in 0..3 {
                        let row = &mut k[(3 * pa + i) * dofs..(3 * pa + i + 1) * dofs];
                        for (b, &pb) in tet.iter().enumerate() {
                            for j in 0..3 {
                                row[3 * pb + j] += kt[a][i][b][j];
                            }
                        }
                    }
                }
                add_patch_fbar_tangent(pt, tet, &geo.gbar, &sp, finite, dofs, k);
            }
            None => {
                let mut s = match branch {
                    Some(b) => mat.evaluate_stress_on(&pt.f, old, b, new),
                    None => mat.evaluate_stress(&pt.f, old, new),
                }
                .map_err(material_at(At::Centroid))
                .map_err(fail)?;
                if let Some(pr) = &pressure {
                    for si in s.iter_mut().take(3) {
                        *si += pr.extra();
                    }
                }
                add_force(&pt.grad, &s, pt.w, &mut ft);
            }
        }
        for (&a, fa) in tet.iter().zip(ft.chunks_exact(3)) {
            for c in 0..3 {
                f[3 * a + c] += fa[c];
            }
        }
    }
    if let (Some(pr), Some(pi)) = (&pressure, pi) {
        pressure_block(p, &geo, pr, pi, f, k);
    }
    Ok(())
}

/// The hybrid patch's pressure rows r_π = s V (U'(J̄) − p)/K₀ (and two inert rows) and,
/// with `k`, its column s b̂_a, row s U''/K₀ b_a and diagonal −s² V/K₀.
fn pressure_block(
    p: &PatchData,
    geo: &Kin,
    pr: &Pressure,
    pi: &[f64; 3],
    f: &mut [f64],
    k: Option<&mut [f64]>,
) {
    let nu = 3 * p.x0.len();
    let dofs = nu + 3;
    let s = pr.s;
    let d = -s * s * geo.big_v / pr.k0;
    f[nu] = s * geo.big_v * (pr.u1 - pr.p) / pr.k0;
    f[nu + 1] = d * pi[1];
    f[nu + 2] = d * pi[2];
    let Some(k) = k else { return };
    let up = s * pr.u2 / pr.k0;
    let mut bhat = vec![[0.0; 3]; p.x0.len()];
    for (pt, tet) in geo.pts.iter().zip(p.tets) {
        for (&a, g) in tet.iter().zip(&pt.grad) {
            for c in 0..3 {
                bhat[a][c] += pr.jbar * pt.w * g[c];
            }
        }
    }
    for (a, (bh, gb)) in bhat.iter().zip(&geo.gbar).enumerate() {
        for i in 0..3 {
            k[(3 * a + i) * dofs + nu] = s * bh[i];
            k[nu * dofs + 3 * a + i] = up * gb[i] * geo.v;
        }
    }
    for q in nu..dofs {
        k[q * dofs + q] = d;
    }
}

/// K_ab += w/3 (M g_a) ⊗ (ḡ_b − g_b) for a in the tet and b over the patch (g_b = 0
/// off the tet), M = c:I + 2τ̄ (finite) or C:I (small): the term of
/// [`super::kinematics::add_fbar_tangent`] with the patch's ḡ.
fn add_patch_fbar_tangent(
    pt: &TetPoint,
    tet: &[usize; 4],
    gbar: &[[f64; 3]],
    sp: &crate::material::StressPoint,
    finite: bool,
    dofs: usize,
    k: &mut [f64],
) {
    let c = &sp.tangent;
    let s2 = if finite { 2.0 } else { 0.0 };
    let mm: [f64; 6] = std::array::from_fn(|r| c[r][0] + c[r][1] + c[r][2] + s2 * sp.stress[r]);
    let mut d: Vec<[f64; 3]> = gbar.iter().map(|g| g.map(|x| x * pt.w / 3.0)).collect();
    for (&b, gb) in tet.iter().zip(&pt.grad) {
        for j in 0..3 {
            d[b][j] -= gb[j] * pt.w / 3.0;
        }
    }
    for (&a, ga) in tet.iter().zip(&pt.grad) {
        let [g0, g1, g2] = *ga;
        let mg = [
            mm[0] * g0 + mm[3] * g1 + mm[5] * g2,
            mm[3] * g0 + mm[1] * g1 + mm[4] * g2,
            mm[5] * g0 + mm[4] * g1 + mm[2] * g2,
        ];
        for (i, &mgi) in mg.iter().enumerate() {
            let row = &mut k[(3 * a + i) * dofs..(3 * a + i + 1) * dofs];
            for (b, db) in d.iter().enumerate() {
                for j in 0..3 {
                    row[3 * b + j] += mgi * db[j];
                }
            }
        }
    }
}

/// Cauchy stress σ of every tet at the committed history (τ/J̄ under finite strain),
/// with J̄ p in place of J̄ U'(J̄) for a hybrid patch (`pi`; equal at a solution).
pub fn stresses(p: &PatchData, pi: Option<f64>) -> Result<Vec<[f64; 6]>, PatchError> {
    let (mat, ns) = (p.mat, p.mat.n_state());
    let kin = mat.kinematics();
    let geo = kinematics(p, kin)?;
    let extra = match pi {
        Some(pi) => Pressure::new(mat, &geo, pi)
            .map_err(|error| PatchError { tet: 0, error })?
            .extra(),
        None => 0.0,
    };
    let mut scratch = vec![0.0; ns];
    geo.pts
        .iter()
        .enumerate()
        .map(|(t, pt)| {
            let s = mat
                .evaluate_stress(&pt.f, &p.state_old[t * ns..(t + 1) * ns], &mut scratch)
                .map_err(material_at(At::Centroid))
                .map_err(|error| PatchError { tet: t, error })?;
            let mut s = s;
            for si in s.iter_mut().take(3) {
                *si += extra;
            }
            let j = match kin {
                Kinematics::Finite => pt.f.determinant(),
                Kinematics::Small => 1.0,
            };
            Ok(s.map(|x| x / j))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::kernel::ElementKernel;
    use crate::fem::kernel::{ElementData, ElementOutput};
    use crate::fem::solid::Standard;
    use crate::material::{linear_elastic::LinearElastic, neo_hookean::NeoHookean};

    /// A unit cube split into six tets around its diagonal 0–6 (Kuhn).
    fn cube() -> (Vec<[f64; 3]>, Vec<[usize; 4]>) {
        let x: Vec<[f64; 3]> = (0..8)
            .map(|i| {
                let (a, b, c) = ((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64);
                [a, b, c]
            })
            .collect();
        // Node i = a + 2b + 4c; paths 0 → 7 along the axes in every order.
        let paths = [
            [1, 2, 4],
            [1, 4, 2],
            [2, 1, 4],
            [2, 4, 1],
            [4, 1, 2],
            [4, 2, 1],
        ];
        let tets = paths
            .iter()
            .map(|p| {
                let n1 = p[0];
                let n2 = n1 + p[1];
                let mut t = [0, n1, n2, 7];
                // Positive orientation.
                let v = |a: usize| x[a];
                let (a, b, c, d) = (v(t[0]), v(t[1]), v(t[2]), v(t[3]));
                let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
                let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
                let e3 = [d[0] - a[0], d[1] - a[1], d[2] - a[2]];
                let det = e1[0] * (e2[1] * e3[2] - e2[2] * e3[1])
                    - e1[1] * (e2[0] * e3[2] - e2[2] * e3[0])
                    + e1[2] * (e2[0] * e3[1] - e2[1] * e3[0]);
                if det < 0.0 {
                    t.swap(1, 2);
                }
                t
            })
            .collect();
        (x, tets)
    }

    fn displaced(x: &[[f64; 3]]) -> Vec<[f64; 3]> {
        x.iter()
            .enumerate()
            .map(|(i, p)| {
                let s = 0.01 * (i as f64 + 1.0);
                [0.05 * p[1] + s, -0.03 * p[2] + 0.5 * s, 0.04 * p[0] - s]
            })
            .collect()
    }

    #[test]
    fn a_patch_of_one_tet_is_the_standard_tet4() {
        let (x, tets) = cube();
        let u = displaced(&x);
        let mat = NeoHookean::new(1.0, 0.45, 1.0);
        let t = tets[2];
        let (x4, u4) = (tet_nodes(&x, &t), tet_nodes(&u, &t));
        let local = [[0, 1, 2, 3]];
        let p = PatchData {
            x0: &x4,
            u: &u4,
            tets: &local,
            mat: &mat,
            state_old: &[],
            branch: None,
        };
        let (mut f, mut k) = (vec![0.0; 12], vec![0.0; 144]);
        force(&p, None, &mut [], &mut f, Some(&mut k)).unwrap();
        let (mut fs, mut ks) = (vec![0.0; 12], vec![0.0; 144]);
        Standard { tab: &TET4 }
            .force(
                &ElementData::new(&x4, &u4, &mat, &[]),
                ElementOutput::new(&mut [], &mut fs, Some(&mut ks)),
            )
            .unwrap();
        for (a, b) in f.iter().zip(&fs).chain(k.iter().zip(&ks)) {
            assert!((a - b).abs() < 1e-13 * (1.0 + b.abs()), "{a} vs {b}");
        }
    }

    /// The tangent against central differences of the residual, finite and small strain.
    #[test]
    fn tangent_is_the_derivative_of_the_residual() {
        let (x, tets) = cube();
        let u = displaced(&x);
        let nh = NeoHookean::new(1.0, 0.49, 1.0);
        let le = LinearElastic::new(1.0, 0.49, 1.0);
        for mat in [&nh as &dyn Material, &le] {
            let m = x.len();
            let eval = |u: &[[f64; 3]], k: Option<&mut [f64]>| {
                let p = PatchData {
                    x0: &x,
                    u,
                    tets: &tets,
                    mat,
                    state_old: &[],
                    branch: None,
                };
                let mut f = vec![0.0; 3 * m];
                force(&p, None, &mut [], &mut f, k).unwrap();
                f
            };
            let mut k = vec![0.0; 9 * m * m];
            eval(&u, Some(&mut k));
            let h = 1e-6;
            let mut worst: f64 = 0.0;
            let scale = k.iter().fold(0.0f64, |s, v| s.max(v.abs()));
            for col in 0..3 * m {
                let (mut up, mut um) = (u.clone(), u.clone());
                up[col / 3][col % 3] += h;
                um[col / 3][col % 3] -= h;
                let (fp, fm) = (eval(&up, None), eval(&um, None));
                for row in 0..3 * m {
                    let fd = (fp[row] - fm[row]) / (2.0 * h);
                    worst = worst.max((fd - k[row * 3 * m + col]).abs());
                }
            }
            assert!(
                worst < 1e-6 * scale,
                "tangent error {worst} (scale {scale})"
            );
        }
    }

    /// The hybrid patch's Jacobian (nodes and pressure block) against central
    /// differences, away from the solution (p ≠ U'(J̄)).
    #[test]
    fn hybrid_tangent_is_the_derivative_of_the_residual() {
        let (x, tets) = cube();
        let u = displaced(&x);
        let mat = NeoHookean::new(1.0, 0.49, 1.0);
        let m = x.len();
        let dofs = 3 * m + 3;
        let eval = |u: &[[f64; 3]], pi: &[f64; 3], k: Option<&mut [f64]>| {
            let p = PatchData {
                x0: &x,
                u,
                tets: &tets,
                mat: &mat,
                state_old: &[],
                branch: None,
            };
            let mut f = vec![0.0; dofs];
            force(&p, Some(pi), &mut [], &mut f, k).unwrap();
            f
        };
        let pi = [0.3, 0.1, -0.2];
        let mut k = vec![0.0; dofs * dofs];
        eval(&u, &pi, Some(&mut k));
        let scale = k.iter().fold(0.0f64, |s, v| s.max(v.abs()));
        let h = 1e-6;
        let mut worst: f64 = 0.0;
        for col in 0..dofs {
            let (mut up, mut um, mut pp, mut pm) = (u.clone(), u.clone(), pi, pi);
            if col < 3 * m {
                up[col / 3][col % 3] += h;
                um[col / 3][col % 3] -= h;
            } else {
                pp[col - 3 * m] += h;
                pm[col - 3 * m] -= h;
            }
            let (fp, fm) = (eval(&up, &pp, None), eval(&um, &pm, None));
            for row in 0..dofs {
                let fd = (fp[row] - fm[row]) / (2.0 * h);
                worst = worst.max((fd - k[row * dofs + col]).abs());
            }
        }
        assert!(
            worst < 1e-6 * scale,
            "tangent error {worst} (scale {scale})"
        );
        // At p = U'(J̄) the nodes' rows are the F-bar patch's.
        let p = PatchData {
            x0: &x,
            u: &u,
            tets: &tets,
            mat: &mat,
            state_old: &[],
            branch: None,
        };
        let geo = kinematics(&p, Kinematics::Finite).unwrap();
        let pr = Pressure::new(&mat, &geo, 0.0).unwrap();
        let at = [pr.u1 / pr.s, 0.0, 0.0];
        let fh = eval(&u, &at, None);
        let mut ff = vec![0.0; 3 * m];
        force(&p, None, &mut [], &mut ff, None).unwrap();
        for (a, b) in fh.iter().zip(&ff) {
            assert!((a - b).abs() < 1e-12 * (1.0 + b.abs()), "{a} vs {b}");
        }
        assert!(fh[3 * m].abs() < 1e-12, "pressure row {}", fh[3 * m]);
    }

    /// Under a uniform F every tet's F̄ is F: the patch reproduces the homogeneous state
    /// (the patch test), and its stresses are the material's.
    #[test]
    fn homogeneous_deformation_is_reproduced() {
        let (x, tets) = cube();
        let g = Matrix3::new(0.1, 0.02, 0.0, -0.01, -0.05, 0.03, 0.0, 0.02, 0.07);
        let u: Vec<[f64; 3]> = x
            .iter()
            .map(|p| {
                let v = g * nalgebra::Vector3::from(*p);
                [v[0], v[1], v[2]]
            })
            .collect();
        let mat = NeoHookean::new(1.0, 0.499, 1.0);
        let p = PatchData {
            x0: &x,
            u: &u,
            tets: &tets,
            mat: &mat,
            state_old: &[],
            branch: None,
        };
        let sig = stresses(&p, None).unwrap();
        for s in &sig[1..] {
            for (a, b) in s.iter().zip(&sig[0]) {
                assert!(
                    (a - b).abs() < 1e-10 * (1.0 + b.abs()),
                    "{s:?} vs {:?}",
                    sig[0]
                );
            }
        }
        // Interior node 0 and 7 are corners here; the resultant of all nodal forces is 0.
        let mut f = vec![0.0; 24];
        force(&p, None, &mut [], &mut f, None).unwrap();
        for c in 0..3 {
            let sum: f64 = f.chunks_exact(3).map(|fa| fa[c]).sum();
            assert!(sum.abs() < 1e-12, "resultant {sum}");
        }
    }
}
