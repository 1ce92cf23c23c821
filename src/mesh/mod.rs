//! Meshes: nodes, elements (hex8, tet4, tet10, wedge6), named node sets and faces, generators and readers.
//!
//! A [`Mesh`] is the serial, whole-model mesh that rank 0 builds or reads before it
//! partitions; ranks receive their pieces through `partition::distribute`.

pub mod abaqus;
pub mod blocks;
pub mod cylinder;
pub mod generate;
pub mod gmsh;
pub mod lsdyna;
pub mod patches;
pub mod quadratic;
pub mod select;
pub mod sheet;
pub mod subset;

use nalgebra::Vector3;
use std::collections::BTreeMap;

/// Element types. Node orderings follow Gmsh/VTK: hex8 bottom face 0-1-2-3
/// counter-clockwise seen from above, top face 4-5-6-7; tet4 0-1-2 then apex 3.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum ElemKind {
    Hex8,
    Tet4,
    Tet10,
    /// Prism: triangle 0-1-2 (counter-clockwise seen from 3-4-5), 3-4-5 above it.
    Wedge6,
}

/// Edges of the tet10 holding its midside nodes 4..9, in Gmsh's order (VTK swaps the
/// last two: its node 8 is on edge 1-3 and 9 on 2-3).
pub const TET10_EDGES: [[usize; 2]; 6] = [[0, 1], [1, 2], [2, 0], [0, 3], [2, 3], [1, 3]];

/// Most nodes of any element kind (the tet10): fixed-size gather buffers.
pub const MAX_NODES: usize = 10;

impl ElemKind {
    pub fn n_nodes(self) -> usize {
        match self {
            ElemKind::Hex8 => 8,
            ElemKind::Tet4 => 4,
            ElemKind::Tet10 => 10,
            ElemKind::Wedge6 => 6,
        }
    }
    /// Local node indices of each face, ordered so the normal (right-hand rule) points
    /// out of the element.
    pub fn faces(self) -> &'static [&'static [usize]] {
        match self {
            ElemKind::Hex8 => &[
                &[0, 3, 2, 1],
                &[4, 5, 6, 7],
                &[0, 1, 5, 4],
                &[1, 2, 6, 5],
                &[2, 3, 7, 6],
                &[3, 0, 4, 7],
            ],
            ElemKind::Tet4 => &[&[0, 2, 1], &[0, 1, 3], &[1, 2, 3], &[0, 3, 2]],
            // Tri6 faces: the tet4's corners, then the midside nodes of edges c0-c1,
            // c1-c2, c2-c0 (Gmsh's tri6 order).
            ElemKind::Tet10 => &[
                &[0, 2, 1, 6, 5, 4],
                &[0, 1, 3, 4, 9, 7],
                &[1, 2, 3, 5, 8, 9],
                &[0, 3, 2, 7, 8, 6],
            ],
            // Two triangles, then the three quads (Gmsh's prism face order).
            ElemKind::Wedge6 => &[
                &[0, 2, 1],
                &[3, 4, 5],
                &[0, 1, 4, 3],
                &[1, 2, 5, 4],
                &[2, 0, 3, 5],
            ],
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            ElemKind::Hex8 => "hex8",
            ElemKind::Tet4 => "tet4",
            ElemKind::Tet10 => "tet10",
            ElemKind::Wedge6 => "wedge6",
        }
    }
    /// The corner nodes of a face (its first 3 or 4 local nodes): what a flat face is.
    pub fn face_corners(self, face: usize) -> &'static [usize] {
        let f = self.faces()[face];
        match self {
            ElemKind::Tet10 => &f[..3],
            _ => f,
        }
    }
}

/// A face of an element: element index and local face number in [`ElemKind::faces`].
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize, serde::Deserialize,
)]
pub struct FaceRef {
    pub elem: usize,
    pub face: u8,
}

#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct Mesh {
    pub coords: Vec<[f64; 3]>,
    pub kinds: Vec<ElemKind>,
    /// Element e's nodes are `conn[offsets[e]..offsets[e + 1]]`.
    pub offsets: Vec<usize>,
    pub conn: Vec<usize>,
    /// Index of the part (deck order) each element belongs to.
    pub elem_part: Vec<u32>,
    /// Named node sets from the mesh source (Gmsh physical groups of any dimension).
    pub node_groups: BTreeMap<String, Vec<usize>>,
    /// Named boundary faces from the mesh source (Gmsh physical surfaces).
    pub face_groups: BTreeMap<String, Vec<FaceRef>>,
    /// Named element groups from the mesh source (Gmsh physical volumes).
    pub elem_groups: BTreeMap<String, Vec<usize>>,
}

impl Mesh {
    pub fn n_nodes(&self) -> usize {
        self.coords.len()
    }
    pub fn n_elems(&self) -> usize {
        self.kinds.len()
    }
    pub fn elem_nodes(&self, e: usize) -> &[usize] {
        &self.conn[self.offsets[e]..self.offsets[e + 1]]
    }
    /// Global node numbers of one face, in the face's outward order.
    pub fn face_nodes(&self, f: FaceRef) -> Vec<usize> {
        let en = self.elem_nodes(f.elem);
        self.kinds[f.elem].faces()[f.face as usize]
            .iter()
            .map(|&i| en[i])
            .collect()
    }
    pub fn push_elem(&mut self, kind: ElemKind, nodes: &[usize], part: u32) {
        if self.offsets.is_empty() {
            self.offsets.push(0);
        }
        self.kinds.push(kind);
        self.conn.extend_from_slice(nodes);
        self.offsets.push(self.conn.len());
        self.elem_part.push(part);
    }
    /// Append another mesh (a further part), renumbering its nodes and elements after ours.
    pub fn append(&mut self, other: &Mesh) {
        let n0 = self.n_nodes();
        let e0 = self.n_elems();
        self.coords.extend_from_slice(&other.coords);
        for e in 0..other.n_elems() {
            let nodes: Vec<usize> = other.elem_nodes(e).iter().map(|&n| n + n0).collect();
            self.push_elem(other.kinds[e], &nodes, other.elem_part[e]);
        }
        for (k, v) in &other.node_groups {
            self.node_groups
                .entry(k.clone())
                .or_default()
                .extend(v.iter().map(|&n| n + n0));
        }
        for (k, v) in &other.face_groups {
            self.face_groups
                .entry(k.clone())
                .or_default()
                .extend(v.iter().map(|f| FaceRef {
                    elem: f.elem + e0,
                    face: f.face,
                }));
        }
        for (k, v) in &other.elem_groups {
            self.elem_groups
                .entry(k.clone())
                .or_default()
                .extend(v.iter().map(|&e| e + e0));
        }
    }
    /// Faces that belong to exactly one element (the boundary), sorted.
    pub fn boundary_faces(&self) -> Vec<FaceRef> {
        let mut seen: std::collections::HashMap<Vec<usize>, (FaceRef, u32)> = Default::default();
        for e in 0..self.n_elems() {
            for (fi, _) in self.kinds[e].faces().iter().enumerate() {
                let f = FaceRef {
                    elem: e,
                    face: fi as u8,
                };
                let mut key = self.face_nodes(f);
                key.sort_unstable();
                seen.entry(key).and_modify(|v| v.1 += 1).or_insert((f, 1));
            }
        }
        let mut out: Vec<FaceRef> = seen
            .into_values()
            .filter(|v| v.1 == 1)
            .map(|v| v.0)
            .collect();
        out.sort();
        out
    }
    /// Signed volume of element e: positive when its node order follows the Gmsh/VTK
    /// convention. Hex8 uses 2x2x2 Gauss points, exact for trilinear geometry; a tet10
    /// is measured by its corners (exact when its edges are straight).
    pub fn elem_volume(&self, e: usize) -> f64 {
        let x: Vec<[f64; 3]> = self.elem_nodes(e).iter().map(|&n| self.coords[n]).collect();
        match self.kinds[e] {
            ElemKind::Tet4 | ElemKind::Tet10 => {
                let p = |i: usize| Vector3::from(x[i]);
                (p(1) - p(0)).cross(&(p(2) - p(0))).dot(&(p(3) - p(0))) / 6.0
            }
            // Three tets (exact for planar quad faces).
            ElemKind::Wedge6 => {
                let p = |i: usize| Vector3::from(x[i]);
                let tet = |a: usize, b: usize, c: usize, d: usize| {
                    (p(b) - p(a)).cross(&(p(c) - p(a))).dot(&(p(d) - p(a))) / 6.0
                };
                tet(0, 1, 2, 3) + tet(1, 2, 3, 4) + tet(2, 3, 4, 5)
            }
            ElemKind::Hex8 => {
                const S: [f64; 8] = [-1.0, 1.0, 1.0, -1.0, -1.0, 1.0, 1.0, -1.0];
                const T: [f64; 8] = [-1.0, -1.0, 1.0, 1.0, -1.0, -1.0, 1.0, 1.0];
                const U: [f64; 8] = [-1.0, -1.0, -1.0, -1.0, 1.0, 1.0, 1.0, 1.0];
                let g = 1.0 / 3f64.sqrt();
                let mut vol = 0.0;
                for q in 0..8 {
                    let (a, b, c) = (g * S[q], g * T[q], g * U[q]);
                    let mut j = [[0.0; 3]; 3];
                    for i in 0..8 {
                        let d = [
                            S[i] * (1.0 + T[i] * b) * (1.0 + U[i] * c),
                            T[i] * (1.0 + S[i] * a) * (1.0 + U[i] * c),
                            U[i] * (1.0 + S[i] * a) * (1.0 + T[i] * b),
                        ];
                        for (col, dv) in j.iter_mut().zip(d) {
                            for k in 0..3 {
                                col[k] += 0.125 * dv * x[i][k];
                            }
                        }
                    }
                    let [j0, j1, j2] = j.map(Vector3::from);
                    vol += j0.cross(&j1).dot(&j2);
                }
                vol
            }
        }
    }
    /// A 64-bit FNV-1a hash of the coordinates and connectivity: keys partition caches.
    pub fn hash(&self) -> u64 {
        let mut h: u64 = 0xcbf29ce484222325;
        let mut eat = |bytes: &[u8]| {
            for &b in bytes {
                h ^= b as u64;
                h = h.wrapping_mul(0x100000001b3);
            }
        };
        for c in &self.coords {
            for x in c {
                eat(&x.to_le_bytes());
            }
        }
        for k in &self.kinds {
            eat(&[*k as u8]);
        }
        for n in &self.conn {
            eat(&(*n as u64).to_le_bytes());
        }
        h
    }
}
