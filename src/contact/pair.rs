//! One small-sliding contact pair (paper §3.7, LS-DYNA's
//! `*CONTACT_CONSTRAINT_SURFACE_TO_SURFACE`, Abaqus' small sliding): a tracked node s
//! paired once, at the start, with reference nodes a and weights w_a (Σ w_a = 1) that
//! never change. What is measured in the current configuration is d = x_s − x_m,
//! x_m = Σ w_a x_a, in the frame [n, t1, t2] of the reference face the node projects
//! on (n = a1 × a2 / |a1 × a2| at its point ξ, outward from the reference part; t1 along
//! a1 = ∂x/∂ξ; t2 = n × t1). Node-to-face weights are the face's shape functions at ξ;
//! mortar weights ([`super::mortar`]) spread the node over every reference face its
//! dual shape function overlaps.
//!
//! The gaps handed to the contact law (the walls' [`super::law`] or
//! [`super::penalty`], unchanged) are
//! g = (n · (d − c_N), t1 · (d − c_T), t2 · (d − c_T)): for contact c_N = 0 and c_T = d at
//! the start of the step (the slip over the step); for a tied pair c_N = c_T = d₀ (the
//! initial offset, so a tie holds the parts where they are). The force on the node is
//! f = P f_loc, P = [n t1 t2]; the face nodes get −N_a f. The Jacobian is exact: the
//! law's generalized derivative with the frame's and the gaps' derivatives by the face
//! nodes (δn = (I − n nᵀ) δ(a1 × a2) / |a1 × a2|, δt1 = (I − t1 t1ᵀ) δa1 / |a1|,
//! δt2 = δn × t1 + n × δt1).

// Index loops over 3×3 frames read like the formulas.
#![allow(clippy::needless_range_loop)]

use super::law::{alm_law, AlmLaw, Branch, Decision, Tangential};
use super::penalty::{penalty, PenaltyLaw};
use super::vec3::{cross, dot, norm};

type M3 = [[f64; 3]; 3];

/// Shape functions of a reference face at ξ and their derivatives (3, 4 or 6 nodes, in
/// [`crate::mesh::ElemKind::faces`] order: quad4 counter-clockwise from (−1, −1); tri3
/// with N = (1 − ξ − η, ξ, η); tri6, a tet10's face, its corners then midside nodes).
pub fn face_shape(n_nodes: usize, xi: [f64; 2]) -> (Vec<f64>, Vec<[f64; 2]>) {
    let (s, t) = (xi[0], xi[1]);
    if n_nodes == 6 {
        use crate::fem::shape::{tri6_dn, tri6_n};
        return (tri6_n(xi).to_vec(), tri6_dn(xi).to_vec());
    }
    if n_nodes == 3 {
        (
            vec![1.0 - s - t, s, t],
            vec![[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]],
        )
    } else {
        let c = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
        (
            c.iter()
                .map(|p| 0.25 * (1.0 + p[0] * s) * (1.0 + p[1] * t))
                .collect(),
            c.iter()
                .map(|p| {
                    [
                        0.25 * p[0] * (1.0 + p[1] * t),
                        0.25 * p[1] * (1.0 + p[0] * s),
                    ]
                })
                .collect(),
        )
    }
}

/// Whether ξ lies on the face (within `tol` in its parameters).
pub fn on_face(n_nodes: usize, xi: [f64; 2], tol: f64) -> bool {
    if n_nodes != 4 {
        xi[0] >= -tol && xi[1] >= -tol && xi[0] + xi[1] <= 1.0 + tol
    } else {
        xi[0].abs() <= 1.0 + tol && xi[1].abs() <= 1.0 + tol
    }
}

fn skew(a: [f64; 3]) -> M3 {
    [[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]]
}
fn mm(a: &M3, b: &M3) -> M3 {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}
fn projector(v: [f64; 3], scale: f64) -> M3 {
    std::array::from_fn(|i| {
        std::array::from_fn(|j| ((if i == j { 1.0 } else { 0.0 }) - v[i] * v[j]) * scale)
    })
}

/// The tri6's second derivatives (∂ξ², ∂ξ∂η, ∂η²) per node, constant.
const TRI6_DD: [[f64; 3]; 6] = [
    [4.0, 4.0, 4.0],
    [4.0, 0.0, 0.0],
    [0.0, 0.0, 4.0],
    [-8.0, -4.0, 0.0],
    [0.0, 4.0, 0.0],
    [0.0, -4.0, -8.0],
];

/// The closest point of x on a face (its nodes' positions `xa`): ξ by Newton on
/// min |x − x(ξ)|² from the centre (Gauss–Newton with the exact second term for the
/// bilinear quad and the tri6), and the distance. Coordinates are taken relative to the face's
/// centroid, so a model far from the origin converges as one at it. None if Newton does
/// not settle (a degenerate face).
pub fn project_on_face(x: [f64; 3], xa: &[[f64; 3]]) -> Option<([f64; 2], f64)> {
    let nf = xa.len();
    let c: [f64; 3] = std::array::from_fn(|k| xa.iter().map(|p| p[k]).sum::<f64>() / nf as f64);
    let x = [x[0] - c[0], x[1] - c[1], x[2] - c[2]];
    let xa: Vec<[f64; 3]> = xa
        .iter()
        .map(|p| [p[0] - c[0], p[1] - c[1], p[2] - c[2]])
        .collect();
    let mut xi = if nf != 4 { [1.0 / 3.0; 2] } else { [0.0; 2] };
    let point = |xi: [f64; 2]| -> [f64; 3] {
        let (n, _) = face_shape(nf, xi);
        std::array::from_fn(|k| (0..nf).map(|a| n[a] * xa[a][k]).sum())
    };
    let mut last = f64::INFINITY;
    for _ in 0..50 {
        let (n, dn) = face_shape(nf, xi);
        let mut p = [0.0; 3];
        let mut a = [[0.0; 3]; 2];
        for k in 0..nf {
            for c in 0..3 {
                p[c] += n[k] * xa[k][c];
                a[0][c] += dn[k][0] * xa[k][c];
                a[1][c] += dn[k][1] * xa[k][c];
            }
        }
        let r = [x[0] - p[0], x[1] - p[1], x[2] - p[2]];
        // ∂²x/∂ξ², ∂ξ∂η, ∂η²: the bilinear quad's cross term, the tri6's constant
        // second derivatives (zero on a tri3).
        let mut a2nd = [[0.0; 3]; 3];
        if nf == 4 {
            let c = [1.0, -1.0, 1.0, -1.0];
            for k in 0..4 {
                for d in 0..3 {
                    a2nd[1][d] += 0.25 * c[k] * xa[k][d];
                }
            }
        } else if nf == 6 {
            for (k, dd) in TRI6_DD.iter().enumerate() {
                for (row, v) in a2nd.iter_mut().zip(dd) {
                    for d in 0..3 {
                        row[d] += v * xa[k][d];
                    }
                }
            }
        }
        let g = [dot(a[0], r), dot(a[1], r)];
        let h = [
            [
                dot(a[0], a[0]) - dot(a2nd[0], r),
                dot(a[0], a[1]) - dot(a2nd[1], r),
            ],
            [
                dot(a[1], a[0]) - dot(a2nd[1], r),
                dot(a[1], a[1]) - dot(a2nd[2], r),
            ],
        ];
        let det = h[0][0] * h[1][1] - h[0][1] * h[1][0];
        if det.abs() <= 1e-300 || !det.is_finite() {
            return None;
        }
        let dxi = [
            (h[1][1] * g[0] - h[0][1] * g[1]) / det,
            (h[0][0] * g[1] - h[1][0] * g[0]) / det,
        ];
        xi = [xi[0] + dxi[0], xi[1] + dxi[1]];
        let step = dxi[0].abs() + dxi[1].abs();
        // ξ is dimensionless: round-off leaves it at ~1e-15; stop there, or where the
        // steps stop shrinking at that level.
        if step < 1e-13 || (step < 1e-10 && step >= last) {
            let p = point(xi);
            return Some((xi, norm([x[0] - p[0], x[1] - p[1], x[2] - p[2]])));
        }
        last = step;
    }
    None
}

/// How a pair is enforced.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PairLaw {
    /// The paper's augmented Lagrangian (multipliers λ, scale κ).
    Alm { law: AlmLaw, kappa: f64 },
    /// Penalty normal stiffness and the elastic-slip Coulomb law ([`super::penalty`];
    /// `e_old`: the elastic slip carried from the last step, global).
    Penalty { law: PenaltyLaw, e_old: [f64; 3] },
    /// Bonded in all directions: h = g with multipliers.
    TiedAlm { kappa: f64 },
    /// Bonded by a penalty spring f = −k_p g.
    TiedPenalty { kp: f64 },
}

impl PairLaw {
    pub fn has_multipliers(&self) -> bool {
        matches!(self, PairLaw::Alm { .. } | PairLaw::TiedAlm { .. })
    }
}

/// A pair's evaluation: the residual rows of its node, the face nodes and (with
/// multipliers) its multiplier block, and their dense Jacobian (row-major, the same
/// order), with what it reports.
#[derive(Debug, Clone)]
pub struct PairEval {
    pub r: Vec<f64>,
    pub k: Vec<f64>,
    /// Normal gap n · (d − c_N).
    pub gap: f64,
    /// Force on the tracked node (global) and its normal component.
    pub force: [f64; 3],
    pub normal_force: f64,
    pub active: bool,
    pub sticking: bool,
    pub branch: Branch,
    pub cone_excess: f64,
    /// Penalty: the elastic slip to carry to the next step (global).
    pub elastic_slip: [f64; 3],
    /// d = x_s − x_m now.
    pub d: [f64; 3],
    /// The frame [n, t1, t2] now (rows).
    pub frame: [[f64; 3]; 3],
    /// ∂r/∂s of a pretension shift s (see [`evaluate`]), the same rows as `r`.
    pub dr_ds: Vec<f64>,
    /// The normal force f_loc,N and its derivatives by the pair's unknowns (the same
    /// order as `r`'s rows) and by s: a bolt section's force sums them.
    pub dfn: Vec<f64>,
    pub dfn_ds: f64,
}

/// Jacobian-only diagonal on multiplier rows (relative to κ), as for walls: keeps a
/// stick row whose node is held by a support regular.
const JACOBIAN_REG: f64 = 1e-8;

/// What a pair's gaps are measured from: `c_n`, `c_t` the gap offsets (see the module
/// docs) and `shift` s added to the normal gap (a bolt's pretension section:
/// g_N = n · (d − c_N) + s, so s > 0 pulls the two sides s into each other).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Offsets {
    pub c_n: [f64; 3],
    pub c_t: [f64; 3],
    pub shift: f64,
}

/// The reference face's frame at the node's point and the node's offset from it.
struct Frame {
    /// Reference nodes.
    nf: usize,
    /// d = x_s − x_m.
    d: [f64; 3],
    /// ∂x/∂ξ, ∂x/∂η at the point, and |a1 × a2|, |a1|.
    a1: [f64; 3],
    a2: [f64; 3],
    la: f64,
    l1: f64,
    /// [n, t1, t2].
    cols: [[f64; 3]; 3],
}

fn frame(x: &[[f64; 3]], nn: &[f64], dn: &[[f64; 2]]) -> Frame {
    let nf = x.len() - 1;
    let mut xm = [0.0; 3];
    let mut a1 = [0.0; 3];
    let mut a2 = [0.0; 3];
    for k in 0..nf {
        for c in 0..3 {
            xm[c] += nn[k] * x[1 + k][c];
            a1[c] += dn[k][0] * x[1 + k][c];
            a2[c] += dn[k][1] * x[1 + k][c];
        }
    }
    let d = [x[0][0] - xm[0], x[0][1] - xm[1], x[0][2] - xm[2]];
    let a = cross(a1, a2);
    let (la, l1) = (norm(a), norm(a1));
    let n = [a[0] / la, a[1] / la, a[2] / la];
    let t1 = [a1[0] / l1, a1[1] / l1, a1[2] / l1];
    let t2 = cross(n, t1);
    Frame {
        nf,
        d,
        a1,
        a2,
        la,
        l1,
        cols: [n, t1, t2],
    }
}

/// The law at the gaps: the local force fl on the node, ∂fl/∂g, ∂fl/∂λ, the multiplier
/// rows and their derivatives, and what it reports.
struct Local {
    fl: [f64; 3],
    dfdg: M3,
    dfdl: M3,
    r_l: [f64; 3],
    k_lg: M3,
    k_ll: M3,
    active: bool,
    sticking: bool,
    branch: Branch,
    cone_excess: f64,
    elastic_slip: [f64; 3],
}

fn local_law(
    g: [f64; 3],
    lam: [f64; 3],
    t1: [f64; 3],
    t2: [f64; 3],
    law: &PairLaw,
    decision: Decision,
) -> Local {
    let mut fl = [0.0; 3];
    let mut dfdg = [[0.0; 3]; 3];
    let mut dfdl = [[0.0; 3]; 3];
    let mut r_l = [0.0; 3];
    let mut k_lg = [[0.0; 3]; 3];
    let mut k_ll = [[0.0; 3]; 3];
    let (mut active, mut sticking, mut branch, mut cone_excess) =
        (true, true, Branch::default(), f64::NEG_INFINITY);
    let mut elastic_slip = [0.0; 3];
    match *law {
        PairLaw::Alm { law, kappa } => {
            // A closed pair that has carried no force yet (the first iteration of its
            // first step: λ = 0, no slip) starts in stick, not "free": a part held only
            // by friction (a clamped plate) has no tangential stiffness otherwise, and
            // the first linear solve is singular. Its next iterations decide as usual.
            let untouched = lam == [0.0; 3] && g[1] == 0.0 && g[2] == 0.0 && g[0] <= 0.0;
            let decision = match decision {
                Decision::Natural if untouched && law.mu > 0.0 => Decision::Forced(Branch {
                    active: true,
                    tangential: Tangential::Stick,
                }),
                d => d,
            };
            let p = alm_law(g, lam, &law, decision);
            (active, sticking, branch, cone_excess) =
                (p.active, p.sticking, p.branch, p.cone_excess);
            for i in 0..3 {
                fl[i] = kappa * (lam[i] - p.h[i]);
                r_l[i] = -kappa * p.h[i];
                for k in 0..3 {
                    let id = if i == k { 1.0 } else { 0.0 };
                    dfdg[i][k] = -kappa * p.dh_dg[i][k];
                    dfdl[i][k] = kappa * (id - p.dh_dl[i][k]);
                    k_lg[i][k] = -kappa * p.dh_dg[i][k];
                    k_ll[i][k] = -kappa * (p.dh_dl[i][k] + id * JACOBIAN_REG);
                }
            }
        }
        PairLaw::TiedAlm { kappa } => {
            for i in 0..3 {
                fl[i] = kappa * (lam[i] - g[i]);
                r_l[i] = -kappa * g[i];
                dfdg[i][i] = -kappa;
                dfdl[i][i] = kappa;
                k_lg[i][i] = -kappa;
                k_ll[i][i] = -kappa * JACOBIAN_REG;
            }
        }
        PairLaw::Penalty { law, e_old } => {
            let eo = [dot(t1, e_old), dot(t2, e_old)];
            let p = penalty(g, eo, &law, decision);
            (active, sticking, branch) = (p.active, p.sticking, p.branch);
            fl = p.f;
            dfdg = p.df_dg;
            let e = p.elastic_slip;
            for c in 0..3 {
                elastic_slip[c] = t1[c] * e[0] + t2[c] * e[1];
            }
        }
        PairLaw::TiedPenalty { kp } => {
            for i in 0..3 {
                fl[i] = -kp * g[i];
                dfdg[i][i] = -kp;
            }
        }
    }
    Local {
        fl,
        dfdg,
        dfdl,
        r_l,
        k_lg,
        k_ll,
        active,
        sticking,
        branch,
        cone_excess,
        elastic_slip,
    }
}

/// The dense Jacobian (`nr` × `nr`, rows and columns as [`PairEval::r`]) and the normal
/// force's derivatives `dfn` by the pair's unknowns: the gaps `e` (rows: the vectors
/// projected on n, t1, t2) and the frame differentiated by every position node.
fn jacobian(
    fr: &Frame,
    e: &M3,
    nn: &[f64],
    dn: &[[f64; 2]],
    lo: &Local,
    law: &PairLaw,
) -> (Vec<f64>, Vec<f64>) {
    let nf = fr.nf;
    let mult = law.has_multipliers();
    let (cols, fl, dfdg) = (fr.cols, lo.fl, lo.dfdg);
    let [n, t1, _] = cols;
    // Derivatives of d and the frame columns by each position node: node 0 is the
    // tracked node (∂d = I, frame unchanged), node 1 + a a face node (∂d = −N_a I).
    let np = 1 + nf;
    let nr = 3 * np + if mult { 3 } else { 0 };
    let mut k = vec![0.0; nr * nr];
    let mut dfn = vec![0.0; nr];
    let pn = projector(n, 1.0 / fr.la);
    let p1 = projector(t1, 1.0 / fr.l1);
    let (s1, s2, st1, sn) = (skew(fr.a1), skew(fr.a2), skew(t1), skew(n));
    let (k_lg, dfdl, k_ll) = (lo.k_lg, lo.dfdl, lo.k_ll);
    for q in 0..np {
        let (dd, dcols): (f64, [M3; 3]) = if q == 0 {
            (1.0, [[[0.0; 3]; 3]; 3])
        } else {
            let (na_xi, na_eta) = (dn[q - 1][0], dn[q - 1][1]);
            // δa = δa1 × a2 + a1 × δa2 = (−N_a,ξ [a2]ₓ + N_a,η [a1]ₓ) v.
            let da: M3 = std::array::from_fn(|i| {
                std::array::from_fn(|j| -na_xi * s2[i][j] + na_eta * s1[i][j])
            });
            let d_n = mm(&pn, &da);
            let d_t1: M3 = std::array::from_fn(|i| std::array::from_fn(|j| p1[i][j] * na_xi));
            let a = mm(&st1, &d_n);
            let b = mm(&sn, &d_t1);
            let d_t2: M3 = std::array::from_fn(|i| std::array::from_fn(|j| b[i][j] - a[i][j]));
            (-nn[q - 1], [d_n, d_t1, d_t2])
        };
        // ∂g_k/∂x_q = e_kᵀ ∂P_k + dd P_kᵀ.
        let dg: M3 = std::array::from_fn(|kk| {
            std::array::from_fn(|j| {
                (0..3).map(|i| e[kk][i] * dcols[kk][i][j]).sum::<f64>() + dd * cols[kk][j]
            })
        });
        // ∂f/∂x_q = Σ_k ∂P_k fl_k + P ∂fl/∂x_q, ∂fl/∂x_q = ∂fl/∂g ∂g/∂x_q (and for
        // penalty, the carried elastic slip's projection on the turning tangents: the
        // trial slip is e_o + g_T, so ∂f_T/∂e_o = ∂f_T/∂g_T in stick and in slip).
        let mut dfl: M3 = mm(&dfdg, &dg);
        if let PairLaw::Penalty { e_old, .. } = *law {
            for i in 0..2 {
                for kk in 0..2 {
                    let w = dfdg[1 + i][1 + kk];
                    for j in 0..3 {
                        dfl[1 + i][j] +=
                            w * (0..3).map(|c| e_old[c] * dcols[1 + kk][c][j]).sum::<f64>();
                    }
                }
            }
        }
        let df: M3 = std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                (0..3)
                    .map(|kk| dcols[kk][i][j] * fl[kk] + cols[kk][i] * dfl[kk][j])
                    .sum()
            })
        });
        for j in 0..3 {
            dfn[3 * q + j] = dfl[0][j];
        }
        // Rows: r_s = −f, r_a = N_a f, r_λ = ∂(−κ h) = k_lg ∂g.
        for row in 0..np {
            let w = if row == 0 { -1.0 } else { nn[row - 1] };
            for i in 0..3 {
                for j in 0..3 {
                    k[(3 * row + i) * nr + 3 * q + j] += w * df[i][j];
                }
            }
        }
        if mult {
            let dl = mm(&k_lg, &dg);
            for i in 0..3 {
                for j in 0..3 {
                    k[(3 * np + i) * nr + 3 * q + j] += dl[i][j];
                }
            }
        }
    }
    if mult {
        // ∂f/∂λ = P ∂fl/∂λ.
        let dfl: M3 = std::array::from_fn(|i| {
            std::array::from_fn(|j| (0..3).map(|kk| cols[kk][i] * dfdl[kk][j]).sum())
        });
        for row in 0..np {
            let w = if row == 0 { -1.0 } else { nn[row - 1] };
            for i in 0..3 {
                for j in 0..3 {
                    k[(3 * row + i) * nr + 3 * np + j] += w * dfl[i][j];
                }
            }
        }
        for i in 0..3 {
            for j in 0..3 {
                k[(3 * np + i) * nr + 3 * np + j] += k_ll[i][j];
            }
        }
        for j in 0..3 {
            dfn[3 * np + j] = dfdl[0][j];
        }
    }
    (k, dfn)
}

/// Evaluate one pair: `x[0]` the tracked node, `x[1..]` the reference nodes (current
/// positions) with their weights `w` in x_m and their shape-function derivatives `dn`
/// (∂N/∂ξ, ∂N/∂η at the node's point on its face; zero for nodes off that face) that
/// give the frame; `lam` its multipliers (ignored without); `off` what the gaps are
/// measured from ([`Offsets`]); `decision` the law's branch choice.
pub fn evaluate(
    x: &[[f64; 3]],
    w: &[f64],
    dn: &[[f64; 2]],
    lam: [f64; 3],
    off: &Offsets,
    law: &PairLaw,
    decision: Decision,
) -> PairEval {
    let Offsets { c_n, c_t, shift } = *off;
    let nn = w;
    let fr = frame(x, nn, dn);
    let (nf, d, cols) = (fr.nf, fr.d, fr.cols);
    let [n, t1, t2] = cols;
    let e = [
        [d[0] - c_n[0], d[1] - c_n[1], d[2] - c_n[2]],
        [d[0] - c_t[0], d[1] - c_t[1], d[2] - c_t[2]],
        [d[0] - c_t[0], d[1] - c_t[1], d[2] - c_t[2]],
    ];
    let g = [dot(n, e[0]) + shift, dot(t1, e[1]), dot(t2, e[2])];

    // The law: local force fl on the node, ∂fl/∂g, ∂fl/∂λ, and the multiplier rows.
    let mult = law.has_multipliers();
    let lo = local_law(g, lam, t1, t2, law, decision);
    let (fl, dfdg, k_lg) = (lo.fl, lo.dfdg, lo.k_lg);
    let f: [f64; 3] = std::array::from_fn(|i| (0..3).map(|k| cols[k][i] * fl[k]).sum());
    let (k, dfn) = jacobian(&fr, &e, nn, dn, &lo, law);
    let np = 1 + nf;
    let nr = 3 * np + if mult { 3 } else { 0 };
    // The shift enters g_N alone: ∂fl/∂s = ∂fl/∂g_N, ∂f/∂s = P ∂fl/∂g_N.
    let df_ds: [f64; 3] = std::array::from_fn(|i| (0..3).map(|kk| cols[kk][i] * dfdg[kk][0]).sum());
    let mut dr_ds = vec![0.0; nr];
    for i in 0..3 {
        dr_ds[i] = -df_ds[i];
        for a in 0..nf {
            dr_ds[3 * (1 + a) + i] = nn[a] * df_ds[i];
        }
        if mult {
            dr_ds[3 * np + i] = k_lg[i][0];
        }
    }
    let mut r = vec![0.0; nr];
    for i in 0..3 {
        r[i] = -f[i];
        for a in 0..nf {
            r[3 * (1 + a) + i] = nn[a] * f[i];
        }
        if mult {
            r[3 * np + i] = lo.r_l[i];
        }
    }
    PairEval {
        r,
        k,
        gap: g[0],
        force: f,
        normal_force: fl[0],
        active: lo.active,
        sticking: lo.sticking,
        branch: lo.branch,
        cone_excess: lo.cone_excess,
        elastic_slip: lo.elastic_slip,
        d,
        frame: cols,
        dr_ds,
        dfn,
        dfn_ds: dfdg[0][0],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::law::Threshold;

    /// A slanted, warped quad and a tracked node near it, every law: the Jacobian
    /// against central differences of the residual on the branch of the base point.
    #[test]
    fn jacobian_matches_central_differences() {
        let face = [
            [0.0, 0.0, 0.0],
            [1.1, 0.1, 0.05],
            [1.0, 0.9, -0.1],
            [-0.1, 1.0, 0.02],
        ];
        let tri = [[0.0, 0.0, 0.0], [1.1, 0.1, 0.05], [0.1, 1.0, -0.1]];
        let alm = AlmLaw {
            mu: 0.3,
            alpha: 1.0,
            threshold: Threshold::Multiplier,
        };
        let laws = [
            PairLaw::Alm {
                law: alm,
                kappa: 7.0,
            },
            PairLaw::Penalty {
                law: PenaltyLaw {
                    kn: 50.0,
                    mu: 0.3,
                    slip: 0.02,
                    stick_scale: 1.0,
                },
                e_old: [0.004, -0.002, 0.001],
            },
            PairLaw::Penalty {
                law: PenaltyLaw {
                    kn: 50.0,
                    mu: 0.3,
                    slip: 1.0,
                    stick_scale: 0.3,
                },
                e_old: [-0.01, 0.02, 0.005],
            },
            PairLaw::TiedAlm { kappa: 3.0 },
            PairLaw::TiedPenalty { kp: 20.0 },
        ];
        // (node, λ): stick, slip, separated.
        let cases = [
            ([0.45, 0.4, -0.02], [0.5, 0.01, -0.02]),
            ([0.45, 0.4, -0.02], [0.5, 0.4, -0.3]),
            ([0.45, 0.4, 0.03], [-0.1, 0.0, 0.0]),
        ];
        let c_t = [0.01, -0.02, 0.0];
        let off = |shift: f64| Offsets {
            c_n: [0.0; 3],
            c_t,
            shift,
        };
        let mut branches = std::collections::BTreeSet::new();
        let mut penalty_states = std::collections::BTreeSet::new();
        for nodes in [&face[..], &tri[..]] {
            let xi = if nodes.len() == 3 {
                [0.3, 0.35]
            } else {
                [-0.1, 0.2]
            };
            for law in &laws {
                for (xs, lam) in cases {
                    let mut x = vec![xs];
                    x.extend_from_slice(nodes);
                    let (w, dn) = face_shape(nodes.len(), xi);
                    let base = evaluate(&x, &w, &dn, lam, &off(0.01), law, Decision::Natural);
                    branches.insert(format!("{:?}", base.branch));
                    if let PairLaw::Penalty { .. } = law {
                        penalty_states.insert((base.active, base.sticking));
                    }
                    let forced = Decision::Forced(base.branch);
                    let nr = base.r.len();
                    let np = x.len();
                    let h = 1e-6;
                    let mut worst = 0.0f64;
                    let scale = base.k.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                    for j in 0..nr {
                        let at = |s: f64| {
                            let (mut y, mut l) = (x.clone(), lam);
                            if j < 3 * np {
                                y[j / 3][j % 3] += s * h;
                            } else {
                                l[j - 3 * np] += s * h;
                            }
                            evaluate(&y, &w, &dn, l, &off(0.01), law, forced).r
                        };
                        let (rp, rm) = (at(1.0), at(-1.0));
                        for i in 0..nr {
                            let fd = (rp[i] - rm[i]) / (2.0 * h);
                            worst = worst.max((fd - base.k[i * nr + j]).abs());
                        }
                    }
                    assert!(
                        worst <= 1e-7 * scale.max(1.0),
                        "{law:?} at {xs:?}, {} nodes: off by {worst:e} (scale {scale:e})",
                        nodes.len()
                    );
                    // The shift's column and the normal force's row.
                    let at_s = |s: f64| evaluate(&x, &w, &dn, lam, &off(0.01 + s), law, forced);
                    let (ep, em) = (at_s(h), at_s(-h));
                    for i in 0..nr {
                        let fd = (ep.r[i] - em.r[i]) / (2.0 * h);
                        assert!(
                            (fd - base.dr_ds[i]).abs() <= 1e-7 * scale.max(1.0),
                            "{law:?}: ∂r{i}/∂s"
                        );
                    }
                    let fd = (ep.normal_force - em.normal_force) / (2.0 * h);
                    assert!(
                        (fd - base.dfn_ds).abs() <= 1e-7 * scale.max(1.0),
                        "{law:?}: ∂f_N/∂s"
                    );
                    for j in 0..nr {
                        let (mut y, mut l) = (x.clone(), lam);
                        let (mut y2, mut l2) = (x.clone(), lam);
                        if j < 3 * np {
                            y[j / 3][j % 3] += h;
                            y2[j / 3][j % 3] -= h;
                        } else {
                            l[j - 3 * np] += h;
                            l2[j - 3 * np] -= h;
                        }
                        let fp = evaluate(&y, &w, &dn, l, &off(0.01), law, forced).normal_force;
                        let fm = evaluate(&y2, &w, &dn, l2, &off(0.01), law, forced).normal_force;
                        let fd = (fp - fm) / (2.0 * h);
                        assert!(
                            (fd - base.dfn[j]).abs() <= 1e-7 * scale.max(1.0),
                            "{law:?}: ∂f_N/∂q{j}: {fd} vs {}",
                            base.dfn[j]
                        );
                    }
                }
            }
        }
        // The cases reach stick, slip and separation of the ALM law.
        for t in ["Stick", "Slip", "active: false"] {
            assert!(branches.iter().any(|b| b.contains(t)), "{t}: {branches:?}");
        }
        // ... and stick, slip and separation of the penalty law (with a carried slip).
        let want = [(true, true), (true, false), (false, false)];
        assert!(
            want.iter().all(|s| penalty_states.contains(s)),
            "{penalty_states:?}"
        );
    }

    /// On a curved tri6 face (midside nodes lifted) the closest point search converges
    /// (Newton with the tri6's second derivatives) to a point whose distance vector is
    /// normal to the face, and the tri6 shape functions sum to one with derivatives
    /// summing to zero.
    #[test]
    fn projection_on_a_curved_tri6_face() {
        let face = [
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [0.0, 2.0, 0.0],
            [1.0, 0.0, 0.2],
            [1.0, 1.0, 0.3],
            [0.0, 1.0, 0.2],
        ];
        let x = [0.7, 0.6, 1.1];
        let (xi, dist) = project_on_face(x, &face).unwrap();
        assert!(on_face(6, xi, 0.0), "{xi:?}");
        let (n, dn) = face_shape(6, xi);
        assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-14);
        assert!(dn.iter().map(|d| d[0].abs() + d[1].abs()).sum::<f64>() > 0.0);
        assert!((0..2).all(|j| dn.iter().map(|d| d[j]).sum::<f64>().abs() < 1e-14));
        let p: [f64; 3] = std::array::from_fn(|c| (0..6).map(|k| n[k] * face[k][c]).sum());
        let r = [x[0] - p[0], x[1] - p[1], x[2] - p[2]];
        for j in 0..2 {
            let a: [f64; 3] = std::array::from_fn(|c| (0..6).map(|k| dn[k][j] * face[k][c]).sum());
            assert!(dot(a, r).abs() < 1e-12, "tangent {j}: {}", dot(a, r));
        }
        assert!((norm(r) - dist).abs() < 1e-14);
        // Not the flat corner triangle's answer: the lifted face is closer.
        assert!(dist < 1.1 - 0.1, "{dist}");
    }

    /// A node's residual and its face nodes' are equal and opposite in sum (the pair
    /// exerts no net force), the gap is the distance along the normal, and the closest
    /// point search finds ξ back.
    #[test]
    fn forces_balance_and_projection_finds_xi() {
        let face = [
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [2.0, 1.0, 0.3],
            [0.0, 1.0, 0.0],
        ];
        let xi = [0.25, -0.4];
        let (n, dn) = face_shape(4, xi);
        let xm: [f64; 3] = std::array::from_fn(|c| (0..4).map(|k| n[k] * face[k][c]).sum());
        let e = evaluate(
            &[[xm[0], xm[1], xm[2]], face[0], face[1], face[2], face[3]],
            &n,
            &dn,
            [0.0; 3],
            &Offsets {
                c_n: [0.0; 3],
                c_t: [0.0; 3],
                shift: 0.0,
            },
            &PairLaw::TiedPenalty { kp: 1.0 },
            Decision::Natural,
        );
        assert!(e.gap.abs() < 1e-15);
        let x = [xm[0] + 0.01, xm[1] - 0.02, xm[2] + 0.05];
        let (found, dist) = project_on_face(x, &face).unwrap();
        let (n, dn) = face_shape(4, found);
        let ev = evaluate(
            &[x, face[0], face[1], face[2], face[3]],
            &n,
            &dn,
            [0.0; 3],
            &Offsets {
                c_n: [0.0; 3],
                c_t: [0.0; 3],
                shift: 0.0,
            },
            &PairLaw::Penalty {
                law: PenaltyLaw {
                    kn: 10.0,
                    mu: 0.0,
                    slip: 1.0,
                    stick_scale: 1.0,
                },
                e_old: [0.0; 3],
            },
            Decision::Natural,
        );
        // The closest point: x − x_m is along n, and the gap is the distance.
        assert!((ev.gap.abs() - dist).abs() < 1e-12, "{} vs {dist}", ev.gap);
        for c in 0..3 {
            let s: f64 = (0..5).map(|a| ev.r[3 * a + c]).sum();
            assert!(s.abs() < 1e-14, "net force {s}");
        }
        assert!(on_face(4, found, 0.0));
        assert!(!on_face(3, [0.6, 0.5], 1e-9));
    }
}
