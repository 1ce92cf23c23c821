//! Rigid-wall geometry: closest-point projection onto analytic surfaces.
//!
//! Each shape lives in its own local frame; the wall that owns it places it in the world.
//! Contact laws need, at a slave point x, the signed distance function g(x) (the gap),
//! its gradient n = ∇g (the outward normal), a tangent frame for friction, and ∇∇g
//! (= ∂n/∂x) for the consistent linearisation of the normal direction. Everything here is
//! closed-form but the ellipsoid's (a scalar root, found to machine precision), so a
//! Newton iteration on the contact residual never solves an inner projection problem.
//!
//! Conventions: gap > 0 outside, < 0 inside (penetration); [n, t1, t2] right-handed
//! (n × t1 = t2). Shapes are solid: "inside" is the rigid body's material.

/// Closest-point projection of a point onto a shape's surface, in the shape's local frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projection {
    /// Signed distance: > 0 outside, < 0 inside (penetration).
    pub gap: f64,
    /// Unit outward normal at the closest point (= gradient of the signed distance at x).
    pub normal: [f64; 3],
    /// Closest point on the surface.
    pub point: [f64; 3],
    /// Two unit tangents t1, t2 such that [normal, t1, t2] is a right-handed orthonormal frame (normal × t1 = t2).
    pub tangents: [[f64; 3]; 2],
    /// Hessian of the signed distance at x (= ∂normal/∂x), symmetric; zero on flat parts.
    pub hessian: [[f64; 3]; 3],
}

/// A rigid surface in its own frame (docs/src/design.md "Contact: the formulation": rigid walls are
/// plane, finite plane, cylinder, sphere, prism, ellipsoid, torus).
pub trait Shape: std::fmt::Debug + Send + Sync {
    /// Projection of local point x; None where the shape cannot be touched from x (beyond a finite plane's edges, beyond a cylinder's ends).
    fn project(&self, x: [f64; 3]) -> Option<Projection>;
    /// The projection of a point last seen (at the start of the step) with outward normal
    /// `hint` (local frame). Only a prism's inside is ambiguous: near an edge the nearest
    /// face flips between iterates and the contact normal turns by 90°, which made
    /// Newton cycle; a penetrating node keeps the face it came through.
    fn project_hinted(&self, x: [f64; 3], hint: Option<[f64; 3]>) -> Option<Projection> {
        let _ = hint;
        self.project(x)
    }
    /// A triangulated surface for output (local frame): vertices and triangles (outward-facing counter-clockwise).
    fn surface(&self) -> (Vec<[f64; 3]>, Vec<[usize; 3]>);
    /// Short kind name: "plane", "finite-plane", "cylinder", "sphere", "prism",
    /// "ellipsoid", "torus".
    fn kind(&self) -> &'static str;
}

/// Infinite plane z = 0 with outward normal +z; z < 0 is inside.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    /// Edge length of the square drawn by [`Shape::surface`] (the plane itself is infinite).
    pub display_size: f64,
    /// Its centre in the plane's (x, y): where the model is, so it is drawn under it.
    pub display_center: [f64; 2],
}

/// Rectangle |x| ≤ lx/2, |y| ≤ ly/2 at z = 0, normal +z. Points whose (x, y) fall outside
/// the rectangle cannot touch it (no edge contact: the rectangle is a one-sided wall).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FinitePlane {
    /// Extent along x.
    pub lx: f64,
    /// Extent along y.
    pub ly: f64,
}

/// Solid cylinder about the z axis, centred at the origin, |z| ≤ length/2. Only the
/// lateral surface is a contact surface: the end caps are not (points beyond the ends get
/// None), which is what a roller or a punch side needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cylinder {
    /// Radius R.
    pub radius: f64,
    /// Axial length.
    pub length: f64,
}

/// Solid sphere centred at the origin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sphere {
    /// Radius R.
    pub radius: f64,
}

/// Solid box centred at the origin, faces normal to the axes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Prism {
    /// Edge lengths along x, y, z.
    pub size: [f64; 3],
}

/// Solid ellipsoid x²/a² + y²/b² + z²/c² ≤ 1 centred at the origin, semi-axes along the
/// local axes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ellipsoid {
    /// Semi-axes a, b, c.
    pub radii: [f64; 3],
}

/// Solid torus about the z axis centred at the origin: the points within `tube` of the
/// circle of radius `radius` in the plane z = 0 (ring torus: tube < radius).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Torus {
    /// Radius of the centre circle R.
    pub radius: f64,
    /// Radius of the tube r < R.
    pub tube: f64,
}

/// Below this fraction of the radius the radial direction is undefined (x on the axis or
/// at the centre): no normal, so no projection.
const AXIS_TOL: f64 = 1e-14;

/// Segments around the cylinder's and sphere's circumference in [`Shape::surface`].
const AROUND: usize = 48;
/// Latitude bands of the sphere's surface.
const BANDS: usize = 24;

use super::vec3::{cross, dot, norm, scale, sub};

/// Unit vector along axis `i`.
fn e(i: usize) -> [f64; 3] {
    let mut v = [0.0; 3];
    v[i] = 1.0;
    v
}

const ZERO3: [[f64; 3]; 3] = [[0.0; 3]; 3];

/// (I − Σ aₖ aₖᵀ)/ρ: the Hessian of a distance to a curved surface whose principal
/// directions are removed by the projectors aₖ (normal, and axis for the cylinder).
fn curvature_hessian(rho: f64, dirs: &[[f64; 3]]) -> [[f64; 3]; 3] {
    let mut h = [[0.0; 3]; 3];
    for (i, row) in h.iter_mut().enumerate() {
        for (j, hij) in row.iter_mut().enumerate() {
            let mut v = if i == j { 1.0 } else { 0.0 };
            for a in dirs {
                v -= a[i] * a[j];
            }
            *hij = v / rho;
        }
    }
    h
}

/// Tangents from a normal alone, used where no fixed direction is natural (sphere, box
/// corner). Reference axis e_z, switched to e_x near the poles so a × n never degenerates;
/// the frame jumps at the switch, so quantities carried between steps (slip, stick
/// anchors) are best stored as vectors, not as (t1, t2) components.
fn tangents_from_normal(n: [f64; 3]) -> [[f64; 3]; 2] {
    let a = if n[2].abs() > 0.9 { e(0) } else { e(2) };
    let c = cross(a, n);
    let t1 = scale(1.0 / norm(c), c);
    [t1, cross(n, t1)]
}

/// Normal and tangents of the box face normal to axis `a` on side `s` (±1): t1 = e_{a+1},
/// t2 = s·e_{a+2}, the cyclic choice that is right-handed on all six faces.
fn face_frame(a: usize, s: f64) -> ([f64; 3], [[f64; 3]; 2]) {
    (scale(s, e(a)), [e((a + 1) % 3), scale(s, e((a + 2) % 3))])
}

/// Error message unless `v` is finite and positive.
fn check_positive(name: &str, v: f64) -> Result<(), String> {
    if !v.is_finite() {
        Err(format!("{name} must be finite, got {v}"))
    } else if v <= 0.0 {
        Err(format!("{name} must be positive, got {v}"))
    } else {
        Ok(())
    }
}

/// A flat square or rectangle at z = 0 facing +z, as two counter-clockwise triangles.
fn rectangle_surface(lx: f64, ly: f64) -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
    let (a, b) = (0.5 * lx, 0.5 * ly);
    (
        vec![[-a, -b, 0.0], [a, -b, 0.0], [a, b, 0.0], [-a, b, 0.0]],
        vec![[0, 1, 2], [0, 2, 3]],
    )
}

/// Projection onto the plane z = 0 (shared by [`Plane`] and [`FinitePlane`]): g = z.
fn project_xy_plane(x: [f64; 3]) -> Projection {
    let (normal, tangents) = face_frame(2, 1.0);
    Projection {
        gap: x[2],
        normal,
        point: [x[0], x[1], 0.0],
        tangents,
        hessian: ZERO3,
    }
}

impl Plane {
    /// Checks the dimensions; the message names the offending field.
    pub fn validate(&self) -> Result<(), String> {
        check_positive("display_size", self.display_size)
    }
}

impl Shape for Plane {
    fn project(&self, x: [f64; 3]) -> Option<Projection> {
        Some(project_xy_plane(x))
    }

    fn surface(&self) -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
        let (mut v, t) = rectangle_surface(self.display_size, self.display_size);
        for p in &mut v {
            p[0] += self.display_center[0];
            p[1] += self.display_center[1];
        }
        (v, t)
    }

    fn kind(&self) -> &'static str {
        "plane"
    }
}

impl FinitePlane {
    /// Checks the dimensions; the message names the offending field.
    pub fn validate(&self) -> Result<(), String> {
        check_positive("lx", self.lx)?;
        check_positive("ly", self.ly)
    }
}

impl Shape for FinitePlane {
    fn project(&self, x: [f64; 3]) -> Option<Projection> {
        if x[0].abs() > 0.5 * self.lx || x[1].abs() > 0.5 * self.ly {
            return None;
        }
        Some(project_xy_plane(x))
    }

    fn surface(&self) -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
        rectangle_surface(self.lx, self.ly)
    }

    fn kind(&self) -> &'static str {
        "finite-plane"
    }
}

impl Cylinder {
    /// Checks the dimensions; the message names the offending field.
    pub fn validate(&self) -> Result<(), String> {
        check_positive("radius", self.radius)?;
        check_positive("length", self.length)
    }
}

impl Shape for Cylinder {
    /// Signed distance to the lateral surface, g = ρ − R with ρ the distance to the axis;
    /// ∇g = n radial, ∇∇g = (I − n nᵀ − e_z e_zᵀ)/ρ (curvature 1/ρ in the circumferential
    /// direction only).
    fn project(&self, x: [f64; 3]) -> Option<Projection> {
        let r = self.radius;
        let rho = x[0].hypot(x[1]);
        if x[2].abs() > 0.5 * self.length || rho < AXIS_TOL * r {
            return None;
        }
        let n = [x[0] / rho, x[1] / rho, 0.0];
        let ez = e(2);
        Some(Projection {
            gap: rho - r,
            normal: n,
            point: [r * n[0], r * n[1], x[2]],
            tangents: [cross(ez, n), ez],
            hessian: curvature_hessian(rho, &[n, ez]),
        })
    }

    /// The lateral surface (AROUND quads, 1 along) closed by two capping fans, so that
    /// a viewer draws a solid roller, not a tube to look into. The caps are drawn only:
    /// contact is with the lateral surface ([`Shape::project`] is `None` past the ends).
    fn surface(&self) -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
        let (r, hz) = (self.radius, 0.5 * self.length);
        let mut v = Vec::with_capacity(2 * AROUND + 2);
        for z in [-hz, hz] {
            for k in 0..AROUND {
                let th = std::f64::consts::TAU * k as f64 / AROUND as f64;
                v.push([r * th.cos(), r * th.sin(), z]);
            }
        }
        let (bottom, top) = (2 * AROUND, 2 * AROUND + 1);
        v.push([0.0, 0.0, -hz]);
        v.push([0.0, 0.0, hz]);
        let mut t = Vec::with_capacity(4 * AROUND);
        for i in 0..AROUND {
            let j = (i + 1) % AROUND;
            let (b0, b1, t0, t1) = (i, j, AROUND + i, AROUND + j);
            t.push([b0, b1, t1]);
            t.push([b0, t1, t0]);
            t.push([bottom, b1, b0]);
            t.push([top, t0, t1]);
        }
        (v, t)
    }

    fn kind(&self) -> &'static str {
        "cylinder"
    }
}

impl Sphere {
    /// Checks the dimensions; the message names the offending field.
    pub fn validate(&self) -> Result<(), String> {
        check_positive("radius", self.radius)
    }
}

impl Shape for Sphere {
    /// Signed distance g = ρ − R with ρ = |x|; ∇g = x/ρ, ∇∇g = (I − n nᵀ)/ρ.
    fn project(&self, x: [f64; 3]) -> Option<Projection> {
        let r = self.radius;
        let rho = norm(x);
        if rho < AXIS_TOL * r {
            return None;
        }
        let n = scale(1.0 / rho, x);
        Some(Projection {
            gap: rho - r,
            normal: n,
            point: scale(r, n),
            tangents: tangents_from_normal(n),
            hessian: curvature_hessian(rho, &[n]),
        })
    }

    /// UV sphere: poles plus BANDS − 1 rings of AROUND vertices.
    fn surface(&self) -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
        use std::f64::consts::{PI, TAU};
        let r = self.radius;
        let mut v = vec![[0.0, 0.0, r]];
        for b in 1..BANDS {
            let phi = PI * b as f64 / BANDS as f64;
            for k in 0..AROUND {
                let th = TAU * k as f64 / AROUND as f64;
                v.push([
                    r * phi.sin() * th.cos(),
                    r * phi.sin() * th.sin(),
                    r * phi.cos(),
                ]);
            }
        }
        let south = v.len();
        v.push([0.0, 0.0, -r]);
        let ring = |b: usize, k: usize| 1 + (b - 1) * AROUND + k % AROUND;
        let mut t = Vec::with_capacity(2 * AROUND * (BANDS - 1));
        for k in 0..AROUND {
            t.push([0, ring(1, k), ring(1, k + 1)]);
        }
        for b in 1..BANDS - 1 {
            for k in 0..AROUND {
                let (a0, a1) = (ring(b, k), ring(b, k + 1));
                let (l0, l1) = (ring(b + 1, k), ring(b + 1, k + 1));
                t.push([l0, l1, a1]);
                t.push([l0, a1, a0]);
            }
        }
        for k in 0..AROUND {
            t.push([south, ring(BANDS - 1, k + 1), ring(BANDS - 1, k)]);
        }
        (v, t)
    }

    fn kind(&self) -> &'static str {
        "sphere"
    }
}

impl Prism {
    /// Checks the dimensions; the message names the offending field.
    pub fn validate(&self) -> Result<(), String> {
        for (i, &s) in self.size.iter().enumerate() {
            check_positive(&format!("size[{i}]"), s)?;
        }
        Ok(())
    }

    fn half(&self) -> [f64; 3] {
        scale(0.5, self.size)
    }
}

impl Shape for Prism {
    /// Closest-point projection onto the box surface.
    ///
    /// Outside: point = clamp(x, −h, h), g = |x − point|, n = (x − point)/g, which is the
    /// exact Euclidean signed distance function and its gradient in the face, edge and
    /// corner regions alike. The Hessian is set to zero everywhere: exact on faces; near
    /// edges and corners the true one is the curvature of the rounded offset surface,
    /// ~1/g, deliberately not linearised because it would blow up as g → 0 at contact.
    ///
    /// Inside: g = −minᵢ(hᵢ − |xᵢ|) against the nearest face, whose normal is n (ties: the
    /// lowest axis, then the + side at xᵢ = 0, so the answer is deterministic). A point
    /// exactly on the surface takes this branch and gets g = 0 with a face normal.
    fn project_hinted(&self, x: [f64; 3], hint: Option<[f64; 3]>) -> Option<Projection> {
        let h = self.half();
        let inside = (0..3).all(|i| x[i].abs() <= h[i]);
        match hint {
            Some(nh) if inside => {
                // The face whose outward normal is closest to the hint.
                let a = (0..3)
                    .max_by(|&i, &j| nh[i].abs().total_cmp(&nh[j].abs()))
                    .unwrap_or(0);
                let s = if nh[a] >= 0.0 { 1.0 } else { -1.0 };
                let depth = h[a] - s * x[a];
                let mut p = x;
                p[a] = s * h[a];
                let (n, t) = face_frame(a, s);
                Some(Projection {
                    gap: if depth > 0.0 { -depth } else { 0.0 },
                    normal: n,
                    point: p,
                    tangents: t,
                    hessian: ZERO3,
                })
            }
            _ => self.project(x),
        }
    }

    fn project(&self, x: [f64; 3]) -> Option<Projection> {
        let h = self.half();
        let point: [f64; 3] = std::array::from_fn(|i| x[i].clamp(-h[i], h[i]));
        // Axes on which x lies beyond the box, in increasing order (no heap in the hot path).
        let mut clamped = [0usize; 3];
        let mut n_clamped = 0;
        for i in (0..3).filter(|&i| point[i] != x[i]) {
            clamped[n_clamped] = i;
            n_clamped += 1;
        }
        let d = sub(x, point);
        let (gap, normal, point, tangents) = match clamped[..n_clamped] {
            [] => {
                // Nearest face: smallest hᵢ − |xᵢ|; strict < keeps the lowest axis on ties.
                let mut a = 0;
                for i in 1..3 {
                    if h[i] - x[i].abs() < h[a] - x[a].abs() {
                        a = i;
                    }
                }
                let s = if x[a] >= 0.0 { 1.0 } else { -1.0 };
                let depth = h[a] - x[a].abs();
                let mut p = x;
                p[a] = s * h[a];
                let (n, t) = face_frame(a, s);
                // depth == 0 on the surface: report +0, not −0.
                let gap = if depth > 0.0 { -depth } else { 0.0 };
                (gap, n, p, t)
            }
            [a] => {
                let s = d[a].signum();
                let (n, t) = face_frame(a, s);
                (d[a].abs(), n, point, t)
            }
            [a, b] => {
                let g = norm(d);
                let n = scale(1.0 / g, d);
                // Edge direction: the axis that was not clamped, taken as t1.
                let t1 = e(3 - a - b);
                (g, n, point, [t1, cross(n, t1)])
            }
            _ => {
                let g = norm(d);
                let n = scale(1.0 / g, d);
                (g, n, point, tangents_from_normal(n))
            }
        };
        Some(Projection {
            gap,
            normal,
            point,
            tangents,
            hessian: ZERO3,
        })
    }

    /// The eight corners and two triangles per face: a closed surface (a viewer's
    /// feature edges find no boundary; without normals it shades each face flat).
    fn surface(&self) -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
        let h = self.half();
        // Corner k has the sign of h[a] from bit a of k.
        let v: Vec<[f64; 3]> = (0..8)
            .map(|k| std::array::from_fn(|a| if k >> a & 1 == 1 { h[a] } else { -h[a] }))
            .collect();
        let mut t = Vec::with_capacity(12);
        for a in 0..3 {
            let (b, c) = ((a + 1) % 3, (a + 2) % 3);
            for s in [0, 1] {
                // The face x_a = ±h_a, its corners counter-clockwise in (e_b, e_c): that
                // turns outward on the + side; the − side takes them the other way.
                let corner = |ib: usize, ic: usize| (s << a) | (ib << b) | (ic << c);
                let mut q = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)];
                if s == 0 {
                    q.reverse();
                }
                t.push([q[0], q[1], q[2]]);
                t.push([q[0], q[2], q[3]]);
            }
        }
        (v, t)
    }

    fn kind(&self) -> &'static str {
        "prism"
    }
}

/// ∇∇g at a distance g from a surface point with outward normal n whose shape operator
/// in the tangent basis (t1, t2) is W: Σ κ/(1 + g κ) over the principal curvatures,
/// i.e. W (I + g W)⁻¹ in that basis (2 × 2, symmetric), made exactly symmetric.
fn offset_hessian(g: f64, w: [[f64; 2]; 2], t: [[f64; 3]; 2]) -> [[f64; 3]; 3] {
    let m = [
        [1.0 + g * w[0][0], g * w[0][1]],
        [g * w[1][0], 1.0 + g * w[1][1]],
    ];
    let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    let inv = [
        [m[1][1] / det, -m[0][1] / det],
        [-m[1][0] / det, m[0][0] / det],
    ];
    let h2: [[f64; 2]; 2] =
        std::array::from_fn(|a| std::array::from_fn(|b| w[a][0] * inv[0][b] + w[a][1] * inv[1][b]));
    let mut h = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in i..3 {
            let mut v = 0.0;
            for a in 0..2 {
                for b in 0..2 {
                    v += 0.5 * (h2[a][b] + h2[b][a]) * t[a][i] * t[b][j];
                }
            }
            h[i][j] = v;
            h[j][i] = v;
        }
    }
    h
}

impl Ellipsoid {
    /// Checks the dimensions; the message names the offending field.
    pub fn validate(&self) -> Result<(), String> {
        for (i, &r) in self.radii.iter().enumerate() {
            check_positive(&format!("radii[{i}]"), r)?;
        }
        Ok(())
    }
}

impl Shape for Ellipsoid {
    /// The closest point p is x's foot along the normal: pᵢ = eᵢ² xᵢ / (t + eᵢ²) with t
    /// the root of F(t) = Σ (eᵢ xᵢ / (t + eᵢ²))² = 1 above −min eᵢ² over the axes where
    /// xᵢ ≠ 0; F decreases there, so a bracketed Newton iteration finds it (Eberly,
    /// "Distance from a point to an ellipse, an ellipsoid, or a hyperellipsoid", 2013).
    /// For a point that deep inside, off its plane of symmetry, no closest point lies in
    /// that plane and the shape says none (g is not smooth there anyway). The Hessian is
    /// the offset surface's: W (I + g W)⁻¹ with W the shape operator at p.
    fn project(&self, x: [f64; 3]) -> Option<Projection> {
        let e = self.radii;
        let emax = e[0].max(e[1]).max(e[2]);
        let tiny = AXIS_TOL * emax;
        let y: [f64; 3] = std::array::from_fn(|i| x[i].abs());
        let nonzero: Vec<usize> = (0..3).filter(|&i| y[i] > tiny).collect();
        if nonzero.is_empty() {
            return None;
        }
        let lo0 = nonzero
            .iter()
            .map(|&i| -e[i] * e[i])
            .fold(f64::MIN, f64::max);
        let f = |t: f64| -> (f64, f64) {
            let (mut v, mut d) = (-1.0, 0.0);
            for &i in &nonzero {
                let q = e[i] * y[i] / (t + e[i] * e[i]);
                v += q * q;
                d -= 2.0 * q * q / (t + e[i] * e[i]);
            }
            (v, d)
        };
        let hi0 = nonzero
            .iter()
            .map(|&i| (e[i] * y[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        // Newton from t = 0 (G(0) = Σ xᵢ²/eᵢ² − 1: the root is > 0 outside, < 0
        // inside), bisecting whenever a step leaves the bracket [lo, hi].
        let (mut lo, mut hi) = (lo0, hi0.max(0.0));
        let mut t = 0.0;
        for _ in 0..200 {
            let (v, d) = f(t);
            if v == 0.0 {
                break;
            }
            if v > 0.0 {
                lo = t;
            } else {
                hi = t;
            }
            let step = -v / d;
            let next = t + step;
            if next >= lo && next <= hi {
                t = next;
                if step.abs() <= 1e-15 * (t.abs() + emax * emax) {
                    break;
                }
            } else {
                t = 0.5 * (lo + hi);
            }
            if hi - lo <= 1e-15 * emax * emax {
                break;
            }
        }
        // A zero component stays in its plane only where t + eᵢ² > 0 for it too.
        if (0..3).any(|i| y[i] <= tiny && t + e[i] * e[i] <= 0.0) {
            return None;
        }
        let point: [f64; 3] = std::array::from_fn(|i| {
            if y[i] <= tiny {
                0.0
            } else {
                e[i] * e[i] * x[i] / (t + e[i] * e[i])
            }
        });
        // Outward normal ∝ ∇(Σ pᵢ²/eᵢ²) at p.
        let q: [f64; 3] = std::array::from_fn(|i| point[i] / (e[i] * e[i]));
        let qn = norm(q);
        let n = scale(1.0 / qn, q);
        let inside = (0..3).map(|i| (x[i] / e[i]).powi(2)).sum::<f64>() < 1.0;
        let dist = norm(sub(x, point));
        let gap = if inside { -dist } else { dist };
        let tangents = tangents_from_normal(n);
        // Shape operator at p: P diag(1/eᵢ²) P / |q| in the tangent basis.
        let w: [[f64; 2]; 2] = std::array::from_fn(|a| {
            std::array::from_fn(|b| {
                (0..3)
                    .map(|i| tangents[a][i] * tangents[b][i] / (e[i] * e[i]))
                    .sum::<f64>()
                    / qn
            })
        });
        Some(Projection {
            gap,
            normal: n,
            point,
            tangents,
            hessian: offset_hessian(gap, w, tangents),
        })
    }

    /// The sphere's triangulation scaled by the semi-axes (still outward).
    fn surface(&self) -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
        let (v, t) = Sphere { radius: 1.0 }.surface();
        let e = self.radii;
        (
            v.into_iter()
                .map(|p| [e[0] * p[0], e[1] * p[1], e[2] * p[2]])
                .collect(),
            t,
        )
    }

    fn kind(&self) -> &'static str {
        "ellipsoid"
    }
}

impl Torus {
    /// Checks the dimensions; the message names the offending field.
    pub fn validate(&self) -> Result<(), String> {
        check_positive("radii[0]", self.radius)?;
        check_positive("radii[1]", self.tube)?;
        if self.tube >= self.radius {
            return Err(format!(
                "radii: the tube radius {} must be below the centre circle's {} (a ring torus)",
                self.tube, self.radius
            ));
        }
        Ok(())
    }
}

impl Shape for Torus {
    /// g = |x − c| − r with c = R e_ρ the nearest point of the centre circle (e_ρ the
    /// radial direction of x); n = (x − c)/|x − c|. The level sets are tori: ∇∇g has
    /// curvature 1/|x − c| along the meridian n × e_φ and (n · e_ρ)/ρ along the parallel
    /// e_φ (ρ the distance from the axis). None on the axis and on the centre circle.
    fn project(&self, x: [f64; 3]) -> Option<Projection> {
        let (big, r) = (self.radius, self.tube);
        let rho = (x[0] * x[0] + x[1] * x[1]).sqrt();
        if rho < AXIS_TOL * big {
            return None;
        }
        let er = [x[0] / rho, x[1] / rho, 0.0];
        let d = sub(x, scale(big, er));
        let dist = norm(d);
        if dist < AXIS_TOL * big {
            return None;
        }
        let n = scale(1.0 / dist, d);
        let ephi = [-er[1], er[0], 0.0];
        let t2 = cross(n, ephi);
        let (k_m, k_p) = (1.0 / dist, dot(n, er) / rho);
        let mut h = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in i..3 {
                let v = k_m * t2[i] * t2[j] + k_p * ephi[i] * ephi[j];
                h[i][j] = v;
                h[j][i] = v;
            }
        }
        Some(Projection {
            gap: dist - r,
            normal: n,
            point: add3(scale(big, er), scale(r, n)),
            tangents: [ephi, t2],
            hessian: h,
        })
    }

    /// AROUND × AROUND / 2 quads along the parallels and meridians, two triangles each.
    fn surface(&self) -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
        use std::f64::consts::TAU;
        let (big, r) = (self.radius, self.tube);
        let (nu, nv) = (AROUND, AROUND / 2);
        let mut v = Vec::with_capacity(nu * nv);
        for i in 0..nu {
            let u = TAU * i as f64 / nu as f64;
            for j in 0..nv {
                let w = TAU * j as f64 / nv as f64;
                let rr = big + r * w.cos();
                v.push([rr * u.cos(), rr * u.sin(), r * w.sin()]);
            }
        }
        let at = |i: usize, j: usize| (i % nu) * nv + j % nv;
        let mut t = Vec::with_capacity(2 * nu * nv);
        for i in 0..nu {
            for j in 0..nv {
                // (u, w) counter-clockwise seen from outside: ∂/∂u × ∂/∂w points outward.
                t.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                t.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        (v, t)
    }

    fn kind(&self) -> &'static str {
        "torus"
    }
}

fn add3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deterministic pseudo-random numbers (Knuth's MMIX LCG), so failures reproduce.
    struct Lcg(u64);

    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
            lo + (hi - lo) * self.next()
        }
        fn unit(&mut self) -> [f64; 3] {
            loop {
                let v = [
                    self.uniform(-1.0, 1.0),
                    self.uniform(-1.0, 1.0),
                    self.uniform(-1.0, 1.0),
                ];
                let r = norm(v);
                if r > 0.1 && r <= 1.0 {
                    return scale(1.0 / r, v);
                }
            }
        }
    }

    fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
        [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
    }

    fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
        norm(sub(a, b))
    }

    fn close(a: [f64; 3], b: [f64; 3], tol: f64) -> bool {
        dist(a, b) <= tol
    }

    /// Every projection invariant at x: normal = central-difference ∇g, (optionally)
    /// Hessian = central-difference ∂n/∂x, point = x − g n, g(point) = 0, orthonormal
    /// right-handed frame, symmetric Hessian.
    fn check_projection(shape: &dyn Shape, x: [f64; 3], check_hessian: bool) {
        let p = shape
            .project(x)
            .unwrap_or_else(|| panic!("{}: no projection at {x:?}", shape.kind()));
        let ctx = format!("{} at {x:?}: {p:?}", shape.kind());
        let scale_x = norm(x).max(1.0);
        let step = 1e-6 * scale_x;
        let at = |i: usize, s: f64| {
            let mut y = x;
            y[i] += s * step;
            shape
                .project(y)
                .unwrap_or_else(|| panic!("{ctx}: stencil left the shape"))
        };
        for i in 0..3 {
            let (pp, pm) = (at(i, 1.0), at(i, -1.0));
            let dg = (pp.gap - pm.gap) / (2.0 * step);
            assert!((dg - p.normal[i]).abs() <= 1e-6, "{ctx}: ∂g/∂x{i} = {dg}");
            if check_hessian {
                for k in 0..3 {
                    let dn = (pp.normal[k] - pm.normal[k]) / (2.0 * step);
                    let hk = p.hessian[k][i];
                    assert!(
                        (dn - hk).abs() <= 1e-5 * hk.abs().max(1.0),
                        "{ctx}: ∂n{k}/∂x{i} = {dn}, hessian {hk}"
                    );
                }
            }
        }
        for i in 0..3 {
            for j in 0..3 {
                assert_eq!(p.hessian[i][j], p.hessian[j][i], "{ctx}: asymmetric");
            }
        }
        let tol = 1e-12 * scale_x;
        assert!(
            close(p.point, sub(x, scale(p.gap, p.normal)), tol),
            "{ctx}: point ≠ x − g n"
        );
        let back = shape.project(p.point).expect("closest point is touchable");
        assert!(back.gap.abs() <= tol, "{ctx}: g(point) = {}", back.gap);
        let [t1, t2] = p.tangents;
        let n = p.normal;
        for (v, name) in [(n, "n"), (t1, "t1"), (t2, "t2")] {
            assert!((norm(v) - 1.0).abs() < 1e-12, "{ctx}: |{name}| ≠ 1");
        }
        assert!(
            dot(n, t1).abs() < 1e-12 && dot(n, t2).abs() < 1e-12,
            "{ctx}"
        );
        assert!(dot(t1, t2).abs() < 1e-12, "{ctx}: t1·t2 ≠ 0");
        assert!(close(cross(n, t1), t2, 1e-12), "{ctx}: n × t1 ≠ t2");
    }

    #[test]
    fn plane_random_points() {
        let shape = Plane {
            display_size: 3.0,
            display_center: [0.0; 2],
        };
        let mut rng = Lcg(1);
        for _ in 0..200 {
            let x = [
                rng.uniform(-5.0, 5.0),
                rng.uniform(-5.0, 5.0),
                rng.uniform(-2.0, 2.0),
            ];
            check_projection(&shape, x, true);
            let p = shape.project(x).unwrap();
            assert_eq!(p.gap, x[2]);
            assert_eq!(p.normal, [0.0, 0.0, 1.0]);
        }
    }

    #[test]
    fn finite_plane_random_points_and_extent() {
        let shape = FinitePlane { lx: 2.0, ly: 3.0 };
        let mut rng = Lcg(2);
        for _ in 0..200 {
            let x = [
                rng.uniform(-0.99, 0.99),
                rng.uniform(-1.49, 1.49),
                rng.uniform(-1.0, 1.0),
            ];
            check_projection(&shape, x, true);
            assert_eq!(shape.project(x).unwrap().gap, x[2]);
        }
        // Edges are part of the rectangle; just beyond them nothing can touch it.
        assert!(shape.project([1.0, 1.5, -0.1]).is_some());
        for x in [
            [1.0 + 1e-9, 0.0, -0.1],
            [-1.2, 0.0, 0.1],
            [0.0, 1.5 + 1e-9, 0.0],
            [0.0, -2.0, -0.5],
            [5.0, 5.0, 0.0],
        ] {
            assert!(shape.project(x).is_none(), "{x:?}");
        }
    }

    #[test]
    fn cylinder_random_points_and_extent() {
        let shape = Cylinder {
            radius: 1.0,
            length: 4.0,
        };
        let mut rng = Lcg(3);
        let (mut inside, mut outside) = (0, 0);
        for _ in 0..300 {
            let rho = rng.uniform(0.2, 2.5);
            let th = rng.uniform(0.0, std::f64::consts::TAU);
            let x = [rho * th.cos(), rho * th.sin(), rng.uniform(-1.9, 1.9)];
            check_projection(&shape, x, true);
            let p = shape.project(x).unwrap();
            assert!((p.gap - (rho - 1.0)).abs() < 1e-12);
            // Prescribed tangents: circumferential, then axial.
            assert_eq!(p.tangents[1], [0.0, 0.0, 1.0]);
            assert!(close(p.tangents[0], [-th.sin(), th.cos(), 0.0], 1e-12));
            if p.gap < 0.0 {
                inside += 1;
            } else {
                outside += 1;
            }
        }
        assert!(
            inside > 30 && outside > 30,
            "{inside} inside, {outside} outside"
        );
        assert!(shape.project([1.5, 0.0, 2.0]).is_some());
        for x in [
            [1.5, 0.0, 2.0 + 1e-9],
            [0.5, 0.5, -2.5],
            [0.0, 0.0, 0.0],
            [1e-15, 0.0, 1.0],
        ] {
            assert!(shape.project(x).is_none(), "{x:?}");
        }
    }

    #[test]
    fn sphere_random_points() {
        let shape = Sphere { radius: 1.5 };
        let mut rng = Lcg(4);
        let (mut inside, mut outside) = (0, 0);
        for _ in 0..300 {
            let rho = rng.uniform(0.3, 3.75);
            let x = scale(rho, rng.unit());
            check_projection(&shape, x, true);
            let p = shape.project(x).unwrap();
            assert!((p.gap - (rho - 1.5)).abs() < 1e-12);
            if p.gap < 0.0 {
                inside += 1;
            } else {
                outside += 1;
            }
        }
        assert!(
            inside > 30 && outside > 30,
            "{inside} inside, {outside} outside"
        );
        // Both branches of the tangent construction (near the poles and elsewhere).
        check_projection(&shape, [0.1, 0.2, 2.0], true);
        check_projection(&shape, [0.1, 0.2, -2.0], true);
        assert!(shape.project([0.0; 3]).is_none());
        assert!(shape.project([1e-15, 0.0, 0.0]).is_none());
    }

    /// Which Voronoi region of the box x is in, or None within `margin` of a region
    /// boundary (where finite differences would straddle two formulas).
    fn prism_region(h: [f64; 3], x: [f64; 3], margin: f64) -> Option<usize> {
        let out: Vec<f64> = (0..3).map(|i| x[i].abs() - h[i]).collect();
        if out.iter().any(|o| o.abs() < margin) {
            return None;
        }
        let n_out = out.iter().filter(|&&o| o > 0.0).count();
        if n_out == 0 {
            let mut depth: Vec<(f64, usize)> = (0..3).map(|i| (-out[i], i)).collect();
            depth.sort_by(|a, b| a.0.total_cmp(&b.0));
            if depth[1].0 - depth[0].0 < margin || x[depth[0].1].abs() < margin {
                return None;
            }
        }
        Some(n_out)
    }

    #[test]
    fn prism_random_points() {
        let shape = Prism {
            size: [2.0, 3.0, 4.0],
        };
        let h = [1.0, 1.5, 2.0];
        let mut rng = Lcg(5);
        let mut count = [0; 4];
        for _ in 0..2000 {
            let x: [f64; 3] = std::array::from_fn(|i| rng.uniform(-2.0 * h[i], 2.0 * h[i]));
            let Some(region) = prism_region(h, x, 1e-3) else {
                continue;
            };
            count[region] += 1;
            // The zero Hessian is exact inside and on faces; at edges and corners it is a
            // deliberate omission, so only the gradient is checked there.
            check_projection(&shape, x, region <= 1);
        }
        assert!(count.iter().all(|&c| c > 50), "points per region {count:?}");
    }

    /// Distance from x to the box surface by brute force over a grid on each face.
    fn brute_distance(h: [f64; 3], x: [f64; 3], m: usize) -> f64 {
        let mut best = f64::INFINITY;
        for a in 0..3 {
            let (b, c) = ((a + 1) % 3, (a + 2) % 3);
            for s in [-1.0, 1.0] {
                for i in 0..=m {
                    for j in 0..=m {
                        let mut y = [0.0; 3];
                        y[a] = s * h[a];
                        y[b] = h[b] * (2.0 * i as f64 / m as f64 - 1.0);
                        y[c] = h[c] * (2.0 * j as f64 / m as f64 - 1.0);
                        best = best.min(dist(x, y));
                    }
                }
            }
        }
        best
    }

    #[test]
    fn prism_gap_is_distance_to_box() {
        let h = [1.0, 2.0, 3.0];
        let shape = Prism {
            size: [2.0, 4.0, 6.0],
        };
        // Face, edge and corner regions, by hand.
        let p = shape.project([1.5, 0.3, -1.0]).unwrap();
        assert_eq!(p.gap, 0.5);
        assert_eq!(p.normal, [1.0, 0.0, 0.0]);
        assert_eq!(p.point, [1.0, 0.3, -1.0]);
        let p = shape.project([2.0, 3.0, 0.5]).unwrap();
        assert!((p.gap - 2f64.sqrt()).abs() < 1e-15);
        let r = 0.5f64.sqrt();
        assert!(close(p.normal, [r, r, 0.0], 1e-15));
        assert_eq!(p.point, [1.0, 2.0, 0.5]);
        assert_eq!(
            p.tangents[0],
            [0.0, 0.0, 1.0],
            "edge tangent t1 = edge direction"
        );
        let p = shape.project([-2.0, -4.0, 5.0]).unwrap();
        assert!((p.gap - 3.0).abs() < 1e-15);
        assert!(close(p.normal, [-1.0 / 3.0, -2.0 / 3.0, 2.0 / 3.0], 1e-15));
        assert_eq!(p.point, [-1.0, -2.0, 3.0]);
        // Inside: minus the distance to the nearest face.
        let p = shape.project([0.2, -1.5, 0.5]).unwrap();
        assert!((p.gap + 0.5).abs() < 1e-15);
        assert_eq!(p.normal, [0.0, -1.0, 0.0]);
        assert_eq!(p.point, [0.2, -2.0, 0.5]);
        // Against brute force, inside and out: |g| = distance, sign = outside.
        let mut rng = Lcg(6);
        let m = 200;
        let cell = 2.0 * 3.0 / m as f64;
        for _ in 0..40 {
            let x: [f64; 3] = std::array::from_fn(|i| rng.uniform(-2.0 * h[i], 2.0 * h[i]));
            let p = shape.project(x).unwrap();
            let brute = brute_distance(h, x, m);
            let outside = (0..3).any(|i| x[i].abs() > h[i]);
            assert_eq!(p.gap > 0.0, outside, "{x:?}: {p:?}");
            assert!(
                p.gap.abs() <= brute + 1e-14,
                "{x:?}: {} > {brute}",
                p.gap.abs()
            );
            assert!(
                p.gap.abs() >= brute - cell,
                "{x:?}: {} ≪ {brute}",
                p.gap.abs()
            );
        }
    }

    #[test]
    fn prism_on_surface_and_diagonal() {
        let shape = Prism {
            size: [2.0, 4.0, 6.0],
        };
        // Exactly on a face, an edge, a corner: g = +0, a face normal (lowest axis on ties).
        for (x, n) in [
            ([1.0, 0.5, 0.2], [1.0, 0.0, 0.0]),
            ([0.5, -2.0, 0.2], [0.0, -1.0, 0.0]),
            ([0.5, 1.0, 3.0], [0.0, 0.0, 1.0]),
            ([1.0, 2.0, 0.0], [1.0, 0.0, 0.0]),
            ([-1.0, -2.0, -3.0], [-1.0, 0.0, 0.0]),
        ] {
            let p = shape.project(x).unwrap();
            assert!(p.gap == 0.0 && p.gap.is_sign_positive(), "{x:?}: {p:?}");
            assert_eq!(p.normal, n, "{x:?}");
            assert_eq!(p.point, x);
        }

        // Cube, along the diagonal from the centre: inside all faces tie (x wins).
        let cube = Prism { size: [2.0; 3] };
        for t in [0.0, 0.25, 0.5, 0.9, 1.0] {
            let p = cube.project([t; 3]).unwrap();
            assert!((p.gap + (1.0 - t)).abs() < 1e-15, "t = {t}: {p:?}");
            assert_eq!(p.normal, [1.0, 0.0, 0.0]);
            assert_eq!(p.point, [1.0, t, t]);
        }
        for t in [1.1, 2.0, 5.0] {
            let p = cube.project([t; 3]).unwrap();
            assert!((p.gap - 3f64.sqrt() * (t - 1.0)).abs() < 1e-14, "t = {t}");
            assert!(close(p.normal, [1.0 / 3f64.sqrt(); 3], 1e-15));
            assert_eq!(p.point, [1.0; 3]);
            check_projection(&cube, [t; 3], false);
        }
        // Non-cube diagonal x = t h: depths (1 − t) hᵢ, nearest face is the smallest hᵢ.
        for t in [0.3, 0.8] {
            let p = shape.project([t, 2.0 * t, 3.0 * t]).unwrap();
            assert!((p.gap + (1.0 - t)).abs() < 1e-15);
            assert_eq!(p.normal, [1.0, 0.0, 0.0]);
        }
        let p = shape.project([-1.5, 3.0, -4.5]).unwrap();
        assert!((p.gap - 0.5 * 14f64.sqrt()).abs() < 1e-14);
        assert!(close(
            p.normal,
            scale(1.0 / 14f64.sqrt(), [-1.0, 2.0, -3.0]),
            1e-15
        ));
    }

    #[test]
    fn prism_inside_keeps_the_hinted_face() {
        let p = Prism {
            size: [2.0, 2.0, 2.0],
        };
        // Nearer the +x face (depth 0.1) than the +z face (depth 0.2).
        let x = [0.9, 0.0, 0.8];
        assert_eq!(p.project(x).unwrap().normal, [1.0, 0.0, 0.0]);
        let q = p.project_hinted(x, Some([0.1, 0.0, 0.99])).unwrap();
        assert_eq!(q.normal, [0.0, 0.0, 1.0]);
        assert!((q.gap + 0.2).abs() < 1e-15);
        assert_eq!(q.point, [0.9, 0.0, 1.0]);
        // Outside, the hint changes nothing.
        let y = [1.5, 0.0, 0.3];
        assert_eq!(p.project_hinted(y, Some([0.0, 0.0, 1.0])), p.project(y));
    }

    #[test]
    fn prism_mirror_symmetry() {
        let h = [1.0, 1.5, 2.0];
        let shape = Prism {
            size: [2.0, 3.0, 4.0],
        };
        let mut rng = Lcg(7);
        for _ in 0..200 {
            let x: [f64; 3] = std::array::from_fn(|i| rng.uniform(0.01, 2.0 * h[i]));
            if prism_region(h, x, 1e-9).is_none() {
                continue;
            }
            let p = shape.project(x).unwrap();
            for code in 1..8 {
                let s: [f64; 3] =
                    std::array::from_fn(|i| if code >> i & 1 == 1 { -1.0 } else { 1.0 });
                let mirror = |v: [f64; 3]| -> [f64; 3] { std::array::from_fn(|i| s[i] * v[i]) };
                let q = shape.project(mirror(x)).unwrap();
                assert_eq!(q.gap, p.gap, "{x:?} mirrored by {s:?}");
                assert_eq!(q.normal, mirror(p.normal), "{x:?} mirrored by {s:?}");
                assert_eq!(q.point, mirror(p.point), "{x:?} mirrored by {s:?}");
            }
        }
    }

    /// Vertices on the surface (g ≈ 0), triangles valid and facing the shape normal at
    /// their centroid, and the total area, which catches missing or doubled triangles.
    /// The drawn surface lies on the shape and faces outward; its contact part (the
    /// triangles whose centroid projects) has area `area`; a `volume` given, the surface
    /// is closed as a viewer sees it (every edge, by its vertex indices, in two
    /// triangles) and
    /// encloses that volume (the divergence theorem: positive when it faces outward).
    fn check_surface(shape: &dyn Shape, area: f64, area_tol: f64, volume: Option<f64>) {
        let (v, t) = shape.surface();
        let kind = shape.kind();
        assert!(!t.is_empty(), "{kind}: empty surface");
        for x in &v {
            match shape.project(*x) {
                Some(p) => assert!(
                    p.gap.abs() < 1e-12,
                    "{kind}: vertex {x:?} has gap {}",
                    p.gap
                ),
                // A cylinder's cap centres are on its axis, where it has no normal.
                None => assert!(
                    kind == "cylinder" && x[0] == 0.0 && x[1] == 0.0,
                    "{kind}: {x:?}"
                ),
            }
        }
        let (mut total, mut enclosed) = (0.0, 0.0);
        let mut edges = std::collections::BTreeMap::<[usize; 2], usize>::new();
        for tri in &t {
            assert!(
                tri.iter().all(|&i| i < v.len()),
                "{kind}: {tri:?} out of range"
            );
            let [a, b, c] = tri.map(|i| v[i]);
            let an = cross(sub(b, a), sub(c, a));
            enclosed += dot(a, an) / 6.0;
            for (p, q) in [(tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])] {
                *edges.entry([p.min(q), p.max(q)]).or_default() += 1;
            }
            let centroid = scale(1.0 / 3.0, add(add(a, b), c));
            // A drawn-only cap's centroid is off the contact surface (or has no projection).
            let on = |p: &Projection| p.gap.abs() < 0.1 * norm(sub(b, a)).max(norm(sub(c, a)));
            let Some(n) = shape.project(centroid).filter(on).map(|p| p.normal) else {
                continue;
            };
            assert!(
                dot(an, n) > 0.99 * norm(an),
                "{kind}: triangle {tri:?} faces {an:?}, shape normal {n:?}"
            );
            total += 0.5 * norm(an);
        }
        assert!(
            (total - area).abs() <= area_tol * area,
            "{kind}: area {total} vs {area}"
        );
        if let Some(vol) = volume {
            let open = edges.values().filter(|&&k| k != 2).count();
            assert_eq!(open, 0, "{kind}: {open} edges not in exactly two triangles");
            assert!(
                (enclosed - vol).abs() <= 2.0 * area_tol * vol,
                "{kind}: encloses {enclosed}, the solid is {vol}"
            );
        }
    }

    #[test]
    fn surfaces_lie_on_shapes_and_face_outward() {
        use std::f64::consts::PI;
        check_surface(
            &Plane {
                display_size: 3.0,
                display_center: [0.0; 2],
            },
            9.0,
            1e-14,
            None,
        );
        check_surface(&FinitePlane { lx: 2.0, ly: 3.0 }, 6.0, 1e-14, None);
        let (r, l) = (0.7, 2.5);
        check_surface(
            &Cylinder {
                radius: r,
                length: l,
            },
            2.0 * PI * r * l,
            5e-3,
            Some(PI * r * r * l),
        );
        let r = 1.3;
        check_surface(
            &Sphere { radius: r },
            4.0 * PI * r * r,
            1e-2,
            Some(4.0 / 3.0 * PI * r * r * r),
        );
        check_surface(
            &Prism {
                size: [1.0, 2.0, 3.0],
            },
            2.0 * (2.0 + 6.0 + 3.0),
            1e-14,
            Some(6.0),
        );
        // Knud Thomsen's approximation of the ellipsoid's area (within about 1 %).
        let (a, b, c) = (2.0f64, 1.5f64, 1.0f64);
        let p = 1.6075;
        let thomsen =
            4.0 * PI * (((a * b).powf(p) + (a * c).powf(p) + (b * c).powf(p)) / 3.0).powf(1.0 / p);
        check_surface(
            &Ellipsoid { radii: [a, b, c] },
            thomsen,
            2e-2,
            Some(4.0 / 3.0 * PI * a * b * c),
        );
        check_surface(
            &Torus {
                radius: 2.0,
                tube: 0.5,
            },
            4.0 * PI * PI * 2.0 * 0.5,
            1e-2,
            Some(2.0 * PI * PI * 2.0 * 0.5 * 0.5),
        );
    }

    /// The ellipsoid's gap against a brute-force distance to its surface sampled on a
    /// fine grid of (θ, φ), every projection invariant (Newton's root to machine
    /// precision: the finite-difference checks see it), points inside and outside, a
    /// sphere as the special case, and none deep inside off a plane of symmetry.
    #[test]
    fn ellipsoid_random_points() {
        let e = [2.0, 1.5, 1.0];
        let shape = Ellipsoid { radii: e };
        let mut rng = Lcg(11);
        let (mut inside, mut outside) = (0, 0);
        let m = 400;
        let samples: Vec<[f64; 3]> = (0..m)
            .flat_map(|i| {
                (0..2 * m).map(move |j| {
                    let th = std::f64::consts::PI * (i as f64 + 0.5) / m as f64;
                    let ph = std::f64::consts::PI * j as f64 / m as f64;
                    [
                        e[0] * th.sin() * ph.cos(),
                        e[1] * th.sin() * ph.sin(),
                        e[2] * th.cos(),
                    ]
                })
            })
            .collect();
        for k in 0..300 {
            let u = rng.unit();
            let on: [f64; 3] = std::array::from_fn(|i| e[i] * u[i] / norm([u[0], u[1], u[2]]));
            let s = rng.uniform(0.85, 1.6);
            let x = scale(s, on);
            let p = match shape.project(x) {
                Some(p) => p,
                None => panic!("no projection at {x:?}"),
            };
            check_projection(&shape, x, true);
            if k < 40 {
                let brute = samples
                    .iter()
                    .map(|q| dist(*q, x))
                    .fold(f64::INFINITY, f64::min);
                // A sample lies within h = 0.012 (the grid's spacing) of the closest
                // point, so the sampled minimum is at most √(g² + h²).
                let h = 0.012;
                assert!(
                    p.gap.abs() <= brute + 1e-12 && brute <= (p.gap * p.gap + h * h).sqrt(),
                    "{x:?}: gap {} vs sampled {brute}",
                    p.gap
                );
            }
            if p.gap < 0.0 {
                inside += 1;
            } else {
                outside += 1;
            }
        }
        assert!(inside > 30 && outside > 30, "{inside} in, {outside} out");
        let ball = Ellipsoid { radii: [1.5; 3] };
        let sphere = Sphere { radius: 1.5 };
        for x in [[0.3, -2.0, 0.7], [0.2, 0.1, -0.9], [1.0, 1.0, 1.0]] {
            let (a, b) = (ball.project(x).unwrap(), sphere.project(x).unwrap());
            assert!((a.gap - b.gap).abs() < 1e-14, "{x:?}");
            assert!(close(a.normal, b.normal, 1e-14), "{x:?}");
        }
        // On the axes and planes of symmetry.
        check_projection(&shape, [2.5, 0.0, 0.0], true);
        check_projection(&shape, [0.0, 0.0, -1.2], true);
        check_projection(&shape, [1.9, 0.0, 0.0], true);
        // The centre, and a point deep inside on the plane z = 0 whose nearest surface
        // points lie off it (above and below): no projection.
        assert!(shape.project([0.0; 3]).is_none());
        assert!(shape.project([0.3, 0.0, 0.0]).is_none());
    }

    /// The torus: the gap is the distance to the tube's circle less r, every invariant
    /// (inside the tube and out, on the outer and the inner side of the hole), and no
    /// projection on the axis or on the centre circle.
    #[test]
    fn torus_random_points() {
        let shape = Torus {
            radius: 2.0,
            tube: 0.5,
        };
        let mut rng = Lcg(12);
        let (mut inside, mut outside, mut hole_side) = (0, 0, 0);
        for _ in 0..300 {
            let u = rng.uniform(0.0, std::f64::consts::TAU);
            let w = rng.uniform(0.0, std::f64::consts::TAU);
            let d = rng.uniform(0.1, 1.2);
            let rr = 2.0 + d * w.cos();
            let x = [rr * u.cos(), rr * u.sin(), d * w.sin()];
            check_projection(&shape, x, true);
            let p = shape.project(x).unwrap();
            assert!((p.gap - (d - 0.5)).abs() < 1e-12, "{x:?}");
            if p.gap < 0.0 {
                inside += 1;
            } else {
                outside += 1;
            }
            hole_side += (w.cos() < 0.0) as usize;
        }
        assert!(inside > 30 && outside > 30 && hole_side > 30);
        assert!(shape.project([0.0, 0.0, 1.0]).is_none());
        assert!(shape.project([2.0, 0.0, 0.0]).is_none());
    }

    #[test]
    fn validate_names_the_field() {
        assert!(Plane {
            display_size: 1.0,
            display_center: [0.0; 2]
        }
        .validate()
        .is_ok());
        assert!(FinitePlane { lx: 1.0, ly: 2.0 }.validate().is_ok());
        assert!(Cylinder {
            radius: 1.0,
            length: 2.0
        }
        .validate()
        .is_ok());
        assert!(Sphere { radius: 1.0 }.validate().is_ok());
        assert!(Prism { size: [1.0; 3] }.validate().is_ok());
        let err = |r: Result<(), String>| r.unwrap_err();
        assert_eq!(
            err(Sphere { radius: -1.0 }.validate()),
            "radius must be positive, got -1"
        );
        assert_eq!(
            err(Plane {
                display_size: 0.0,
                display_center: [0.0; 2]
            }
            .validate()),
            "display_size must be positive, got 0"
        );
        assert!(err(FinitePlane {
            lx: 1.0,
            ly: f64::NAN
        }
        .validate())
        .starts_with("ly "));
        assert!(err(Cylinder {
            radius: 1.0,
            length: f64::INFINITY
        }
        .validate())
        .starts_with("length must be finite"));
        assert!(err(Cylinder {
            radius: -2.0,
            length: 1.0
        }
        .validate())
        .starts_with("radius "));
        assert_eq!(
            err(Prism {
                size: [1.0, 1.0, -0.5]
            }
            .validate()),
            "size[2] must be positive, got -0.5"
        );
    }

    #[test]
    fn kinds() {
        let shapes: [&dyn Shape; 5] = [
            &Plane {
                display_size: 1.0,
                display_center: [0.0; 2],
            },
            &FinitePlane { lx: 1.0, ly: 1.0 },
            &Cylinder {
                radius: 1.0,
                length: 1.0,
            },
            &Sphere { radius: 1.0 },
            &Prism { size: [1.0; 3] },
        ];
        let kinds = shapes.map(|s| s.kind());
        assert_eq!(
            kinds,
            ["plane", "finite-plane", "cylinder", "sphere", "prism"]
        );
    }
}
