//! A rigid wall as elements another code can contact: the wall's surface, near the
//! nodes it tracks, faceted into quads and extruded inward by one layer of hex8. Codes
//! without analytical rigid surfaces (CalculiX) contact element faces; every node of the
//! layer follows the wall's prescribed motion, so the layer is rigid and its material
//! does not matter. Facets are about as wide as the slave faces' median edge h, and
//! across a curved direction of radius R no wider than R/80: a sphere's chord then sags
//! R/80²/8 ≈ 2e-5 R below the surface (2e-3 of Hertz's 1 mm indentation at R = 50).
//! Along a straight direction (a cylinder's axis) they stay h wide, and a layer over
//! [`MAX_FACETS`] is coarsened to that many, so files stay a few MB.

// Index loops over xyz components read like the formulas.
#![allow(clippy::needless_range_loop)]

use crate::contact::vec3::{cross, dot, norm, scale, sub};
use crate::contact::wall::ShapeDef;
use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// A hex8 layer in the wall's own frame: nodes, elements in Abaqus C3D8 order (nodes
/// 1–4 the inner quad, 5–8 the outer one, so face S2 is the contact face).
pub struct RigidLayer {
    pub nodes: Vec<[f64; 3]>,
    pub elems: Vec<[usize; 8]>,
}

/// A patch of the surface: (u, v) ∈ [0, 1]² → local point, with its cell counts.
struct Patch {
    map: Box<dyn Fn(f64, f64) -> [f64; 3]>,
    nu: usize,
    nv: usize,
}

/// At most this many facets per wall (so that exported files stay a few MB).
pub const MAX_FACETS: usize = 20_000;

fn cells(length: f64, h: f64) -> usize {
    ((length / h).ceil() as usize).clamp(1, 4000)
}

fn rect(origin: [f64; 3], a: [f64; 3], b: [f64; 3], h: f64) -> Patch {
    let (la, lb) = (norm(a), norm(b));
    Patch {
        map: Box::new(move |u, v| {
            let mut p = origin;
            for k in 0..3 {
                p[k] += u * a[k] + v * b[k];
            }
            p
        }),
        nu: cells(la, h),
        nv: cells(lb, h),
    }
}

/// The six faces of the cube [−1, 1]³ mapped onto the ellipsoid with semi-axes `r`
/// (the cube-sphere: cells of nearly equal size, no poles).
fn cube_sphere(r: [f64; 3], h: f64) -> Vec<Patch> {
    let n = cells(FRAC_PI_2 * r[0].max(r[1]).max(r[2]), h);
    let mut out = Vec::new();
    for axis in 0..3 {
        for sign in [-1.0, 1.0] {
            let (i, j) = ((axis + 1) % 3, (axis + 2) % 3);
            out.push(Patch {
                map: Box::new(move |u, v| {
                    // Equal angles, not equal cube lengths: tan spreads cells evenly.
                    let mut c = [0.0; 3];
                    c[axis] = sign;
                    c[i] = ((u - 0.5) * FRAC_PI_2).tan();
                    c[j] = ((v - 0.5) * FRAC_PI_2).tan();
                    let l = norm(c);
                    [r[0] * c[0] / l, r[1] * c[1] / l, r[2] * c[2] / l]
                }),
                nu: n,
                nv: n,
            });
        }
    }
    out
}

/// The surface patches of a shape, facets about `h` wide (r/80 at most across curved
/// directions of radius r); an infinite plane is meshed over the box's footprint `lo..hi` only.
fn patches(shape: &ShapeDef, h: f64, f: f64, lo: [f64; 3], hi: [f64; 3]) -> Vec<Patch> {
    // Coarsened by `f` (over the cap): straight directions h f, curved min(h, r/80) f.
    let curved = |r: f64| h.min(r / 80.0) * f;
    let h = h * f;
    match *shape {
        ShapeDef::Plane { .. } => vec![rect(
            [lo[0], lo[1], 0.0],
            [hi[0] - lo[0], 0.0, 0.0],
            [0.0, hi[1] - lo[1], 0.0],
            h,
        )],
        ShapeDef::FinitePlane { lx, ly } => vec![rect(
            [-0.5 * lx, -0.5 * ly, 0.0],
            [lx, 0.0, 0.0],
            [0.0, ly, 0.0],
            h,
        )],
        ShapeDef::Prism { size } => {
            let hs = size.map(|s| 0.5 * s);
            let mut out = Vec::new();
            for axis in 0..3 {
                let (i, j) = ((axis + 1) % 3, (axis + 2) % 3);
                for sign in [-1.0, 1.0] {
                    let mut o = [0.0; 3];
                    o[axis] = sign * hs[axis];
                    o[i] = -hs[i];
                    o[j] = -hs[j];
                    let mut a = [0.0; 3];
                    a[i] = size[i];
                    let mut b = [0.0; 3];
                    b[j] = size[j];
                    out.push(rect(o, a, b, h));
                }
            }
            out
        }
        ShapeDef::Sphere { radius } => cube_sphere([radius; 3], curved(radius)),
        ShapeDef::Ellipsoid { radii } => {
            let rmin = radii[0].min(radii[1]).min(radii[2]);
            cube_sphere(radii, curved(rmin))
        }
        ShapeDef::Cylinder { radius, length } => {
            let hc = curved(radius);
            vec![Patch {
                map: Box::new(move |u, v| {
                    let th = TAU * u;
                    [radius * th.cos(), radius * th.sin(), (v - 0.5) * length]
                }),
                nu: cells(TAU * radius, hc),
                nv: cells(length, h),
            }]
        }
        ShapeDef::Torus { radius, tube } => {
            vec![Patch {
                map: Box::new(move |u, v| {
                    let (th, ph) = (TAU * u, TAU * v - PI);
                    let rho = radius + tube * ph.cos();
                    [rho * th.cos(), rho * th.sin(), tube * ph.sin()]
                }),
                nu: cells(TAU * (radius + tube), curved(radius + tube)),
                nv: cells(TAU * tube, curved(tube)),
            }]
        }
    }
}

/// The layer of `shape` over the local box `lo..hi` (where tracked nodes can meet it),
/// facets about `h` wide, h/2 deep; coarser where that would be over [`MAX_FACETS`].
pub fn rigid_layer(shape: &ShapeDef, lo: [f64; 3], hi: [f64; 3], h: f64) -> RigidLayer {
    let projector = shape.build();
    let mut f = 1.0;
    loop {
        let mut layer = RigidLayer {
            nodes: Vec::new(),
            elems: Vec::new(),
        };
        for p in &patches(shape, h, f, lo, hi) {
            add_patch(&mut layer, p, projector.as_ref(), lo, hi, 0.5 * h);
        }
        // A layer already one facet a patch cannot be coarsened further.
        if layer.elems.len() <= MAX_FACETS || f > 1e6 {
            return layer;
        }
        // Facets scale as 1/f² on a surface; a little more so that it lands under.
        f *= 1.05 * (layer.elems.len() as f64 / MAX_FACETS as f64).sqrt();
    }
}

fn inside(p: [f64; 3], lo: [f64; 3], hi: [f64; 3]) -> bool {
    (0..3).all(|k| p[k] >= lo[k] && p[k] <= hi[k])
}

/// Grid the patch, keep the quads whose centre lies in the box, orient each outward
/// (the shape's normal at the centre) and extrude it inward by `t`.
fn add_patch(
    layer: &mut RigidLayer,
    p: &Patch,
    shape: &dyn crate::contact::shape::Shape,
    lo: [f64; 3],
    hi: [f64; 3],
    t: f64,
) {
    let (nu, nv) = (p.nu, p.nv);
    let grid = |i: usize, j: usize| (p.map)(i as f64 / nu as f64, j as f64 / nv as f64);
    let mut index = std::collections::HashMap::new();
    for i in 0..nu {
        for j in 0..nv {
            let q = [
                grid(i, j),
                grid(i + 1, j),
                grid(i + 1, j + 1),
                grid(i, j + 1),
            ];
            let c = centroid(&q);
            if !inside(c, lo, hi) {
                continue;
            }
            let Some(proj) = shape.project(c) else {
                continue;
            };
            let n = proj.normal;
            let mut ids = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
            let mut pts = q;
            if dot(cross(sub(q[1], q[0]), sub(q[3], q[0])), n) < 0.0 {
                ids.swap(1, 3);
                pts.swap(1, 3);
            }
            let mut e = [0; 8];
            for a in 0..4 {
                let outer = *index.entry(ids[a]).or_insert_with(|| {
                    layer.nodes.push(pts[a]);
                    layer.nodes.len() - 1
                });
                layer.nodes.push(sub(pts[a], scale(t, n)));
                e[a] = layer.nodes.len() - 1;
                e[4 + a] = outer;
            }
            layer.elems.push(e);
        }
    }
}

fn centroid(q: &[[f64; 3]; 4]) -> [f64; 3] {
    let mut c = [0.0; 3];
    for p in q {
        for k in 0..3 {
            c[k] += 0.25 * p[k];
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Signed volume of a hex8 in Abaqus order, from its 6 faces' tetrahedra about the
    /// centroid (exact for planar faces, close for the layer's slightly warped ones).
    fn volume(x: &[[f64; 3]; 8]) -> f64 {
        let faces = [
            [0, 3, 2, 1],
            [4, 5, 6, 7],
            [0, 1, 5, 4],
            [1, 2, 6, 5],
            [2, 3, 7, 6],
            [3, 0, 4, 7],
        ];
        let mut c = [0.0; 3];
        for p in x {
            for k in 0..3 {
                c[k] += p[k] / 8.0;
            }
        }
        let mut v = 0.0;
        for f in faces {
            for (a, b) in [(0, 1), (1, 2), (2, 3), (3, 0)] {
                let m = centroid(&[x[f[0]], x[f[1]], x[f[2]], x[f[3]]]);
                let (p, q, r) = (sub(x[f[a]], c), sub(x[f[b]], c), sub(m, c));
                v += dot(p, cross(q, r)) / 6.0;
            }
        }
        v
    }

    fn check_layer(shape: &ShapeDef, lo: [f64; 3], hi: [f64; 3], h: f64) -> RigidLayer {
        let layer = rigid_layer(shape, lo, hi, h);
        assert!(!layer.elems.is_empty());
        let s = shape.build();
        for e in &layer.elems {
            let x: [[f64; 3]; 8] = e.map(|a| layer.nodes[a]);
            assert!(volume(&x) > 0.0, "inverted element {x:?}");
            // The outer quad (S2) faces away from the shape: its normal agrees with the
            // shape's outward normal at its centre, and its nodes are on the surface.
            let outer = [x[4], x[5], x[6], x[7]];
            let c = centroid(&outer);
            let n = cross(sub(outer[1], outer[0]), sub(outer[3], outer[0]));
            assert!(dot(n, s.project(c).unwrap().normal) > 0.0);
            for p in outer {
                assert!(s.project(p).unwrap().gap.abs() < 1e-9 * (1.0 + norm(p)));
            }
        }
        layer
    }

    #[test]
    fn a_sphere_cap_is_faceted_finely_and_faces_outward() {
        let r = 50.0;
        let layer = check_layer(
            &ShapeDef::Sphere { radius: r },
            [-10.0, -10.0, -60.0],
            [30.0, 30.0, -40.0],
            2.5,
        );
        // Facets no wider than h (diagonals ≤ √2 h, a little more off the cube-face centres).
        for e in &layer.elems {
            let d = norm(sub(layer.nodes[e[6]], layer.nodes[e[4]]));
            assert!(d < 1.6 * 2.5 * 2f64.sqrt(), "facet diagonal {d}");
        }
        // Only the cap inside the box: every outer node lies below z = −40 + a facet.
        assert!(layer
            .elems
            .iter()
            .all(|e| e[4..].iter().all(|&a| layer.nodes[a][2] < -39.0)));
    }

    #[test]
    fn prisms_cylinders_planes_and_tori_give_valid_layers() {
        let big = ([-100.0; 3], [100.0; 3]);
        let prism = check_layer(
            &ShapeDef::Prism {
                size: [20.0, 120.0, 20.0],
            },
            big.0,
            big.1,
            4.0,
        );
        // 5 × 30 facets on each long face, 5 × 5 on the ends.
        assert_eq!(prism.elems.len(), 4 * 5 * 30 + 2 * 5 * 5);
        check_layer(
            &ShapeDef::Cylinder {
                radius: 10.0,
                length: 30.0,
            },
            big.0,
            big.1,
            1.0,
        );
        check_layer(
            &ShapeDef::Plane {
                display_size: 1.0,
                display_center: [0.0; 2],
            },
            [0.0, 0.0, -1.0],
            [10.0, 5.0, 1.0],
            1.0,
        );
        check_layer(
            &ShapeDef::Torus {
                radius: 20.0,
                tube: 5.0,
            },
            [15.0, -3.0, -6.0],
            [26.0, 3.0, 6.0],
            2.0,
        );
        check_layer(
            &ShapeDef::Ellipsoid {
                radii: [10.0, 20.0, 5.0],
            },
            big.0,
            big.1,
            2.0,
        );
    }

    #[test]
    fn a_fine_slave_mesh_gives_at_most_the_facet_cap() {
        let layer = rigid_layer(
            &ShapeDef::Cylinder {
                radius: 4.0,
                length: 10.0,
            },
            [-10.0; 3],
            [10.0; 3],
            0.01,
        );
        assert!(layer.elems.len() <= MAX_FACETS && layer.elems.len() > MAX_FACETS / 3);
    }
}
