//! The solid elements of one rank as a contribution: the element loop (internal forces
//! and tangents from `fem` kernels and `material` models), the material history, and the
//! element fields (stress, von Mises, plastic strain). The model also reaches it by type
//! for what only elements have: mass, the explicit stable step, the mesh for output.

use super::contribution::{
    Center, Column, Combine, Contribution, Evaluation, Explicit, FieldSpec, Outputs, Reduce, State,
};
use super::def::MaterialDef;
use super::distribute::LocalElements;
use super::dofs::{DofMap, Unknowns};
use super::solid_patches::{Patches, Scratch};
use crate::fem::element::kernel;
use crate::fem::kernel::{ElementData, ElementKernel, ElementOutput};
use crate::fem::measure::{char_length, von_mises};
use crate::material::Material;
use crate::mesh::MAX_NODES;

/// Rows of the largest element: its nodes' (a tet10's 10) and a pressure block.
const MAX_DOFS: usize = 3 * MAX_NODES + 3;

pub struct Solids {
    pub elements: LocalElements,
    pub materials: Vec<Box<dyn Material>>,
    /// The definitions the materials were built from (ν for contact scales).
    pub material_defs: Vec<MaterialDef>,
    /// Per element offset into the history arrays.
    state_offset: Vec<usize>,
    /// History at the start of the step (committed) and at the last evaluation.
    pub(crate) state_old: Vec<f64>,
    pub(crate) state_new: Vec<f64>,
    /// A frozen product's trial history (discarded): `state_new` keeps the natural
    /// evaluation's, whose branches the product takes. Sized on first use.
    state_frozen: Vec<f64>,
    /// Element evaluations so far (for rates).
    pub evaluations: u64,
    /// Parts whose largest element von Mises stress is a column `<part>.max_von_mises`.
    pub peak_stress_parts: Vec<(String, u32)>,
    /// The parts' names (deck order; `elements.part` indexes them): the output's blocks.
    pub part_names: Vec<String>,
    /// The distinct element kernels of this rank ([`crate::fem::element::kernel`] of
    /// each kind and formulation), and each element's index into them.
    kernels: Vec<Box<dyn ElementKernel>>,
    kernel_of: Vec<u32>,
    /// Per element, its first own block (a hybrid element's pressure) among the
    /// elements' own blocks (`u32::MAX`: none).
    own_index: Vec<u32>,
    /// How many own blocks the local elements have.
    n_own: usize,
    /// Local block of the first element's first own block (set by `bind`).
    own_first: usize,
    /// The F-bar patches of tet4 (evaluated patch by patch, not element by element);
    /// hybrid patches' pressure blocks follow the elements' own blocks.
    patches: Patches,
    /// How many own blocks the elements carry (the patches' come after).
    n_own_elements: usize,
}

impl Solids {
    pub fn new(elements: LocalElements, materials: &[(String, MaterialDef)]) -> Self {
        let built: Vec<Box<dyn Material>> = materials.iter().map(|(_, m)| m.build()).collect();
        let mut kernels: Vec<Box<dyn ElementKernel>> = Vec::new();
        let mut distinct = Vec::new();
        let kernel_of: Vec<u32> = (0..elements.len())
            .map(|e| {
                let key = (elements.kinds[e], elements.formulation[e]);
                let i = distinct.iter().position(|k| *k == key).unwrap_or_else(|| {
                    distinct.push(key);
                    kernels.push(kernel(key.0, key.1));
                    kernels.len() - 1
                });
                i as u32
            })
            .collect();
        let mut state_offset = Vec::with_capacity(elements.len() + 1);
        let mut s = 0;
        let mut n_own = 0;
        let mut own_index = Vec::with_capacity(elements.len());
        for e in 0..elements.len() {
            let k = &kernels[kernel_of[e] as usize];
            state_offset.push(s);
            s += k.state_len(built[elements.material[e] as usize].n_state());
            own_index.push(if k.own_blocks() > 0 {
                n_own as u32
            } else {
                u32::MAX
            });
            n_own += k.own_blocks();
        }
        state_offset.push(s);
        let patches = Patches::new(&elements);
        let n_own_elements = n_own;
        let n_own = n_own + patches.n_own();
        Self {
            elements,
            materials: built,
            material_defs: materials.iter().map(|(_, m)| m.clone()).collect(),
            state_offset,
            state_old: vec![0.0; s],
            state_new: vec![0.0; s],
            state_frozen: Vec::new(),
            evaluations: 0,
            peak_stress_parts: Vec::new(),
            part_names: Vec::new(),
            kernels,
            kernel_of,
            own_index,
            n_own,
            own_first: 0,
            patches,
            n_own_elements,
        }
    }

    /// Patch i's pressure block (local block index), if it is hybrid.
    fn patch_block(&self, i: usize) -> Option<usize> {
        self.patches.list[i]
            .own
            .map(|o| self.own_first + self.n_own_elements + o)
    }

    /// Patch i's pressure block values from `u`, if it is hybrid.
    fn patch_pi<'u>(&self, i: usize, u: &'u [f64]) -> Option<&'u [f64; 3]> {
        self.patch_block(i)
            .map(|b| u[3 * b..3 * b + 3].try_into().expect("a block of three"))
    }

    /// Element e's kernel.
    pub fn kernel(&self, e: usize) -> &dyn ElementKernel {
        self.kernels[self.kernel_of[e] as usize].as_ref()
    }

    /// Element e's own blocks (local): the first and how many (0: none).
    fn own_blocks(&self, e: usize) -> (usize, usize) {
        let i = self.own_index[e];
        if i == u32::MAX {
            (0, 0)
        } else {
            (self.own_first + i as usize, self.kernel(e).own_blocks())
        }
    }

    /// How many own blocks the local elements carry (one per hybrid element).
    pub fn n_hybrid(&self) -> usize {
        self.n_own
    }

    /// The displacement-only tangent at `u_local`, hybrid elements as F-bar (their
    /// pressure condensed, p = U'(J̄)): the reference stiffness whose diagonal scales
    /// contact, with the bulk stiffness on the nodes where contact needs it.
    pub fn assemble_condensed_tangent(
        &self,
        coords: &[[f64; 3]],
        dofs: &DofMap,
        u_local: &[f64],
        k: &mut crate::linalg::DistMatrix,
    ) {
        let mut x0 = [[0.0; 3]; MAX_NODES];
        let mut ue = [[0.0; 3]; MAX_NODES];
        let mut fe = [0.0; 3 * MAX_NODES];
        let mut ke = vec![0.0; 9 * MAX_NODES * MAX_NODES];
        let mut blocks = [0usize; MAX_NODES];
        let mut scratch = Vec::new();
        for e in (0..self.len()).filter(|&e| !self.patches.member[e]) {
            let n = self.gather(e, coords, u_local, &mut x0, &mut ue);
            let mat = self.materials[self.elements.material[e] as usize].as_ref();
            let (s0, s1) = (self.state_offset[e], self.state_offset[e + 1]);
            scratch.resize(s1 - s0, 0.0);
            let kernel = self.kernel(e);
            let ok = kernel.condensed().unwrap_or(kernel).force(
                &ElementData::new(&x0[..n], &ue[..n], mat, &self.state_old[s0..s1]),
                ElementOutput::new(&mut scratch, &mut fe[..3 * n], Some(&mut ke[..9 * n * n])),
            );
            if ok.is_ok() {
                for (a, &node) in self.elements.nodes(e).iter().enumerate() {
                    blocks[a] = dofs.global_block(node);
                }
                k.add_element(&blocks[..n], &ke[..9 * n * n]);
            }
        }
        let mut s = Scratch::default();
        let mut trial = self.state_old.clone();
        for i in 0..self.patches.len() {
            let p = &self.patches.list[i];
            let history = (
                &self.state_old[..],
                &self.state_offset[..],
                None,
                &mut trial[..],
            );
            let mat = self.material(p.elems[0]);
            let orig = &self.elements.orig;
            if self
                .patches
                .force(i, &mut s, coords, u_local, mat, None, history, orig, true)
                .is_ok()
            {
                let blocks: Vec<usize> = p.nodes.iter().map(|&n| dofs.global_block(n)).collect();
                k.add_element(&blocks, &s.k);
            }
        }
    }

    pub fn len(&self) -> usize {
        self.elements.len()
    }
    pub fn is_empty(&self) -> bool {
        self.elements.is_empty()
    }

    pub fn material(&self, e: usize) -> &dyn Material {
        self.materials[self.elements.material[e] as usize].as_ref()
    }

    /// The committed history of element e.
    pub fn history(&self, e: usize) -> &[f64] {
        &self.state_old[self.state_offset[e]..self.state_offset[e + 1]]
    }

    /// Reference coordinates and displacements of element e's nodes; returns its node
    /// count.
    pub fn gather(
        &self,
        e: usize,
        coords: &[[f64; 3]],
        u_local: &[f64],
        x0: &mut [[f64; 3]; MAX_NODES],
        u: &mut [[f64; 3]; MAX_NODES],
    ) -> usize {
        let nodes = self.elements.nodes(e);
        for (a, &n) in nodes.iter().enumerate() {
            x0[a] = coords[n];
            u[a] = [u_local[3 * n], u_local[3 * n + 1], u_local[3 * n + 2]];
        }
        nodes.len()
    }

    /// Whether any material carries an equivalent plastic strain (the same on every
    /// rank: every rank holds the whole material list).
    pub fn has_plastic_strain(&self) -> bool {
        self.materials.iter().any(|m| {
            m.equivalent_plastic_strain(&vec![0.0; m.n_state()])
                .is_some()
        })
    }

    /// Equivalent plastic strain of every local element at the last committed state:
    /// the mean over its integration points (0 for elastic materials).
    pub fn plastic_strains(&self) -> Vec<f64> {
        (0..self.len())
            .map(|e| {
                let mat = self.material(e);
                let ns = mat.n_state();
                let h = self.history(e);
                if ns == 0 || h.is_empty() {
                    return 0.0;
                }
                // EAS keeps its enhanced parameters after the points' history.
                let ng = self.kernel(e).n_points();
                let pts = h[..ng * ns].chunks(ns);
                let n = pts.len() as f64;
                pts.map(|s| mat.equivalent_plastic_strain(s).unwrap_or(0.0))
                    .sum::<f64>()
                    / n
            })
            .collect()
    }

    /// Volume-averaged Cauchy stress of every local element at `u_local` (NaN where an
    /// element cannot be evaluated).
    pub fn stresses(&self, coords: &[[f64; 3]], u_local: &[f64]) -> Vec<[f64; 6]> {
        let mut x0 = [[0.0; 3]; MAX_NODES];
        let mut ue = [[0.0; 3]; MAX_NODES];
        let mut out: Vec<[f64; 6]> = (0..self.len())
            .map(|e| {
                if self.patches.member[e] {
                    return [f64::NAN; 6];
                }
                let n = self.gather(e, coords, u_local, &mut x0, &mut ue);
                let (ob, no) = self.own_blocks(e);
                let data = ElementData::new(&x0[..n], &ue[..n], self.material(e), self.history(e))
                    .with_own(&u_local[3 * ob..3 * (ob + no)]);
                self.kernel(e).stress(&data).unwrap_or([f64::NAN; 6])
            })
            .collect();
        let mut s = Scratch::default();
        for i in 0..self.patches.len() {
            let mat = self.material(self.patches.list[i].elems[0]);
            let history = (&self.state_old[..], &self.state_offset[..]);
            let pi = self.patch_pi(i, u_local).map(|b| b[0]);
            self.patches
                .stresses(i, &mut s, coords, u_local, mat, pi, history, &mut out);
        }
        out
    }

    /// Sum of the characteristic lengths of the local elements.
    pub fn char_length_sum(&self, coords: &[[f64; 3]]) -> f64 {
        (0..self.len())
            .map(|e| {
                let x0: Vec<[f64; 3]> = self.elements.nodes(e).iter().map(|&n| coords[n]).collect();
                char_length(self.elements.kinds[e], &x0)
            })
            .sum()
    }
}

impl Contribution for Solids {
    fn name(&self) -> &str {
        "solids"
    }

    /// One pressure block per hybrid element, owned with the element.
    fn unknowns(&self) -> Unknowns {
        Unknowns {
            owned: self.n_hybrid(),
            ..Unknowns::default()
        }
    }

    fn bind(&mut self, dofs: &DofMap, index: usize) {
        self.own_first = dofs.placed(index).owned_local;
    }

    fn pattern(&self, dofs: &DofMap, out: &mut Vec<(usize, usize)>) {
        for (i, p) in self.patches.list.iter().enumerate() {
            let blocks: Vec<usize> = p.nodes.iter().copied().chain(self.patch_block(i)).collect();
            for &a in &blocks {
                for &b in &blocks {
                    out.push((dofs.global_block(a), dofs.global_block(b)));
                }
            }
        }
        for e in 0..self.len() {
            let nodes = self.elements.nodes(e);
            for &a in nodes {
                for &b in nodes {
                    out.push((dofs.global_block(a), dofs.global_block(b)));
                }
            }
            let (ob, no) = self.own_blocks(e);
            for p in ob..ob + no {
                let gp = dofs.global_block(p);
                out.push((gp, gp));
                for &a in nodes {
                    out.push((gp, dofs.global_block(a)));
                    out.push((dofs.global_block(a), gp));
                }
            }
        }
    }

    /// One loop over the local elements (internal forces and/or element tangents), then
    /// one over the F-bar patches. The first element that cannot be evaluated (an
    /// inverted element) is reported after the loops.
    fn evaluate(&mut self, ev: &mut Evaluation) -> Result<(), String> {
        let mut failure: Option<String> = None;
        let mut x0 = [[0.0; 3]; MAX_NODES];
        let mut ue = [[0.0; 3]; MAX_NODES];
        let mut fe = [0.0; MAX_DOFS];
        let want_k = ev.jacobian.is_some();
        let mut ke = vec![0.0; if want_k { MAX_DOFS * MAX_DOFS } else { 0 }];
        let mut blocks = [0usize; MAX_DOFS / 3];
        // A frozen product (JFNK) keeps each point's return-map branch of the last
        // natural evaluation (`state_new`) and writes its own trial history aside.
        let frozen = ev.frozen && !self.state_new.is_empty();
        if frozen {
            self.state_frozen.resize(self.state_new.len(), 0.0);
        }
        for e in 0..self.len() {
            if self.patches.member[e] {
                continue;
            }
            let n = self.gather(e, ev.coords, ev.u, &mut x0, &mut ue);
            let mat = self.materials[self.elements.material[e] as usize].as_ref();
            let (s0, s1) = (self.state_offset[e], self.state_offset[e + 1]);
            let (ob, no) = self.own_blocks(e);
            let kernel = self.kernels[self.kernel_of[e] as usize].as_ref();
            let nd = kernel.n_dofs();
            let (branch, trial) = if frozen {
                let b = Some(&self.state_new[s0..s1]);
                (b, &mut self.state_frozen[s0..s1])
            } else {
                (None, &mut self.state_new[s0..s1])
            };
            let res = kernel.force(
                &ElementData::new(&x0[..n], &ue[..n], mat, &self.state_old[s0..s1])
                    .with_own(&ev.u[3 * ob..3 * (ob + no)])
                    .on_branch(branch),
                ElementOutput::new(
                    trial,
                    &mut fe[..nd],
                    if want_k {
                        Some(&mut ke[..nd * nd])
                    } else {
                        None
                    },
                ),
            );
            if let Err(err) = res {
                failure.get_or_insert_with(|| format!("element {}: {err}", self.elements.orig[e]));
                continue;
            }
            // The nodes' blocks, then the element's own.
            for (a, &node) in self.elements.nodes(e).iter().enumerate() {
                blocks[a] = node;
            }
            for (b, p) in (ob..ob + no).enumerate() {
                blocks[n + b] = p;
            }
            let k = want_k.then(|| &ke[..nd * nd]);
            scatter(ev, &mut blocks[..n + no], &fe[..nd], k);
        }
        let mut s = Scratch::default();
        let mut pblocks = Vec::new();
        for i in 0..self.patches.len() {
            let p = &self.patches.list[i];
            let mat = self.materials[self.elements.material[p.elems[0]] as usize].as_ref();
            let history = if frozen {
                let b = Some(&self.state_new[..]);
                let offset = &self.state_offset[..];
                (&self.state_old[..], offset, b, &mut self.state_frozen[..])
            } else {
                let offset = &self.state_offset[..];
                (&self.state_old[..], offset, None, &mut self.state_new[..])
            };
            let orig = &self.elements.orig;
            let own = p.own.map(|o| self.own_first + self.n_own_elements + o);
            let pi: Option<&[f64; 3]> =
                own.map(|b| ev.u[3 * b..3 * b + 3].try_into().expect("a block of three"));
            let res = self
                .patches
                .force(i, &mut s, ev.coords, ev.u, mat, pi, history, orig, want_k);
            if let Err(err) = res {
                failure.get_or_insert(err);
                continue;
            }
            pblocks.clear();
            pblocks.extend_from_slice(&p.nodes);
            pblocks.extend(own);
            scatter(ev, &mut pblocks, &s.f, want_k.then_some(&s.k[..]));
        }
        self.evaluations += self.len() as u64;
        match failure {
            Some(f) => Err(f),
            None => Ok(()),
        }
    }

    fn commit(&mut self) {
        self.state_old.copy_from_slice(&self.state_new);
    }

    fn saved_state(&self) -> Vec<f64> {
        self.state_old.clone()
    }

    fn restore_state(&mut self, s: &[f64]) -> Result<(), String> {
        if s.len() != self.state_old.len() {
            return Err(format!(
                "{} history values for {} expected",
                s.len(),
                self.state_old.len()
            ));
        }
        self.state_old.copy_from_slice(s);
        self.state_new.copy_from_slice(s);
        Ok(())
    }

    fn outputs(&self) -> Option<&dyn Outputs> {
        Some(self)
    }
    fn explicit(&mut self) -> Option<&mut dyn Explicit> {
        Some(self)
    }
}

/// Add one element's (or patch's) rows to the residual and its matrix to the Jacobian;
/// `blocks` are local blocks, turned into global ones for the matrix.
fn scatter(ev: &mut Evaluation, blocks: &mut [usize], fe: &[f64], ke: Option<&[f64]>) {
    if let Some((f, _)) = ev.forces.as_mut() {
        for (&block, fa) in blocks.iter().zip(fe.chunks_exact(3)) {
            for c in 0..3 {
                f[3 * block + c] += fa[c];
            }
        }
    }
    if let (Some(k), Some(ke)) = (ev.jacobian.as_deref_mut(), ke) {
        for b in blocks.iter_mut() {
            *b = ev.dofs.global_block(*b);
        }
        k.add_element(blocks, ke);
    }
}

impl Outputs for Solids {
    fn columns(&self) -> Vec<Column> {
        self.peak_stress_parts
            .iter()
            .map(|(name, _)| Column {
                reduce: Reduce::Max,
                run_max: true,
                ..Column::sum(format!("{name}.max_von_mises"))
            })
            .collect()
    }

    /// The largest element von Mises stress (the element's mean over its Gauss points,
    /// as in the `von_mises` field) of each listed part.
    fn column_values(&self, s: &State, out: &mut [f64]) {
        if self.peak_stress_parts.is_empty() {
            return;
        }
        let sig = self.stresses(s.coords, s.u);
        for (o, (_, p)) in out.iter_mut().zip(&self.peak_stress_parts) {
            *o = sig
                .iter()
                .zip(&self.elements.part)
                .filter(|(_, q)| *q == p)
                .map(|(v, _)| von_mises(v))
                .fold(0.0, f64::max);
        }
    }

    fn fields(&self) -> Vec<FieldSpec> {
        let cell = |name: &str, width| FieldSpec {
            name: name.into(),
            center: Center::Cell,
            width,
            combine: Combine::First,
            empty: f64::NAN,
        };
        let mut f = vec![cell("stress", 6), cell("von_mises", 1)];
        if self.has_plastic_strain() {
            f.push(cell("plastic_strain", 1));
        }
        f
    }

    fn field_values(&self, s: &State, out: &mut [Vec<f64>]) {
        let sig = self.stresses(s.coords, s.u);
        out[0].copy_from_slice(&sig.concat());
        for (o, v) in out[1].iter_mut().zip(&sig) {
            *o = von_mises(v);
        }
        if out.len() > 2 {
            out[2].copy_from_slice(&self.plastic_strains());
        }
    }
}

impl Explicit for Solids {
    /// Pressure unknowns are algebraic: an explicit step cannot solve for them (the deck
    /// refuses the combination; this is the backstop).
    fn start_explicit(&mut self) -> Result<(), String> {
        if self.n_hybrid() > 0 {
            return Err("hybrid elements need a static or implicit analysis".into());
        }
        Ok(())
    }
}
