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
use crate::fem::element::{
    element_force, element_stress, n_gauss, state_len, von_mises, Formulation,
};
use crate::fem::hybrid;
use crate::material::Material;
use crate::mesh::ElemKind;

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
    /// Element evaluations so far (for rates).
    pub evaluations: u64,
    /// Parts whose largest element von Mises stress is a column `<part>.max_von_mises`.
    pub peak_stress_parts: Vec<(String, u32)>,
    /// Per element, its pressure block among the hybrid elements (`u32::MAX`: none).
    hybrid_index: Vec<u32>,
    /// Local block of the first hybrid element's pressure block (set by `bind`).
    hybrid_first: usize,
}

impl Solids {
    pub fn new(elements: LocalElements, materials: &[(String, MaterialDef)]) -> Self {
        let built: Vec<Box<dyn Material>> = materials.iter().map(|(_, m)| m.build()).collect();
        let mut state_offset = Vec::with_capacity(elements.len() + 1);
        let mut s = 0;
        for e in 0..elements.len() {
            state_offset.push(s);
            s += state_len(
                elements.kinds[e],
                elements.formulation[e],
                built[elements.material[e] as usize].n_state(),
            );
        }
        state_offset.push(s);
        let mut n_hybrid = 0u32;
        let hybrid_index = (0..elements.len())
            .map(|e| {
                if has_pressure(elements.kinds[e], elements.formulation[e]) {
                    n_hybrid += 1;
                    n_hybrid - 1
                } else {
                    u32::MAX
                }
            })
            .collect();
        Self {
            elements,
            materials: built,
            material_defs: materials.iter().map(|(_, m)| m.clone()).collect(),
            state_offset,
            state_old: vec![0.0; s],
            state_new: vec![0.0; s],
            evaluations: 0,
            peak_stress_parts: Vec::new(),
            hybrid_index,
            hybrid_first: 0,
        }
    }

    /// Element e's pressure block (local), if it is a hybrid element.
    fn pressure_block(&self, e: usize) -> Option<usize> {
        let i = self.hybrid_index[e];
        (i != u32::MAX).then(|| self.hybrid_first + i as usize)
    }

    /// How many local elements carry a pressure unknown.
    pub fn n_hybrid(&self) -> usize {
        self.hybrid_index.iter().filter(|&&i| i != u32::MAX).count()
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
        let mut x0 = [[0.0; 3]; 8];
        let mut ue = [[0.0; 3]; 8];
        let mut fe = [0.0; 24];
        let mut ke = vec![0.0; 576];
        let mut blocks = [0usize; 8];
        let mut scratch = Vec::new();
        for e in 0..self.len() {
            let n = self.gather(e, coords, u_local, &mut x0, &mut ue);
            let mat = self.materials[self.elements.material[e] as usize].as_ref();
            let (s0, s1) = (self.state_offset[e], self.state_offset[e + 1]);
            scratch.resize(s1 - s0, 0.0);
            let ok = element_force(
                self.elements.kinds[e],
                self.elements.formulation[e],
                &x0[..n],
                &ue[..n],
                mat,
                &self.state_old[s0..s1],
                &mut scratch,
                &mut fe[..3 * n],
                Some(&mut ke[..9 * n * n]),
            );
            if ok.is_ok() {
                for (a, &node) in self.elements.nodes(e).iter().enumerate() {
                    blocks[a] = dofs.global_block(node);
                }
                k.add_element(&blocks[..n], &ke[..9 * n * n]);
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
        x0: &mut [[f64; 3]; 8],
        u: &mut [[f64; 3]; 8],
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
                let ng = n_gauss(self.elements.kinds[e], self.elements.formulation[e]);
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
        let mut x0 = [[0.0; 3]; 8];
        let mut ue = [[0.0; 3]; 8];
        (0..self.len())
            .map(|e| {
                let n = self.gather(e, coords, u_local, &mut x0, &mut ue);
                if let Some(pb) = self.pressure_block(e) {
                    return hybrid::stress(
                        &x0,
                        &ue,
                        u_local[3 * pb],
                        self.material(e),
                        self.history(e),
                    )
                    .unwrap_or([f64::NAN; 6]);
                }
                element_stress(
                    self.elements.kinds[e],
                    self.elements.formulation[e],
                    &x0[..n],
                    &ue[..n],
                    self.material(e),
                    self.history(e),
                )
                .unwrap_or([f64::NAN; 6])
            })
            .collect()
    }

    /// Sum of the characteristic lengths of the local elements.
    pub fn char_length_sum(&self, coords: &[[f64; 3]]) -> f64 {
        (0..self.len())
            .map(|e| {
                let x0: Vec<[f64; 3]> = self.elements.nodes(e).iter().map(|&n| coords[n]).collect();
                crate::fem::element::char_length(self.elements.kinds[e], &x0)
            })
            .sum()
    }
}

/// Whether an element of this kind and formulation carries a pressure unknown (a hybrid
/// hex8; the formulation leaves tet4 alone).
fn has_pressure(kind: ElemKind, form: Formulation) -> bool {
    kind == ElemKind::Hex8 && form.is_hybrid()
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
        self.hybrid_first = dofs.placed(index).owned_local;
    }

    fn pattern(&self, dofs: &DofMap, out: &mut Vec<(usize, usize)>) {
        for e in 0..self.len() {
            let nodes = self.elements.nodes(e);
            for &a in nodes {
                for &b in nodes {
                    out.push((dofs.global_block(a), dofs.global_block(b)));
                }
            }
            if let Some(p) = self.pressure_block(e) {
                let gp = dofs.global_block(p);
                out.push((gp, gp));
                for &a in nodes {
                    out.push((gp, dofs.global_block(a)));
                    out.push((dofs.global_block(a), gp));
                }
            }
        }
    }

    /// One loop over the local elements: internal forces and/or element tangents. The
    /// first element that cannot be evaluated (an inverted element) is reported after
    /// the loop.
    fn evaluate(&mut self, ev: &mut Evaluation) -> Result<(), String> {
        let mut failure: Option<String> = None;
        let mut x0 = [[0.0; 3]; 8];
        let mut ue = [[0.0; 3]; 8];
        let mut fe = [0.0; hybrid::DOFS];
        let want_k = ev.jacobian.is_some();
        let mut ke = vec![
            0.0;
            if want_k {
                hybrid::DOFS * hybrid::DOFS
            } else {
                0
            }
        ];
        let mut blocks = [0usize; 9];
        for e in 0..self.len() {
            let n = self.gather(e, ev.coords, ev.u, &mut x0, &mut ue);
            let mat = self.materials[self.elements.material[e] as usize].as_ref();
            let (s0, s1) = (self.state_offset[e], self.state_offset[e + 1]);
            if let Some(pb) = self.pressure_block(e) {
                let Formulation::Hybrid { hourglass } = self.elements.formulation[e] else {
                    unreachable!("a pressure block belongs to a hybrid element")
                };
                let pi = [ev.u[3 * pb], ev.u[3 * pb + 1], ev.u[3 * pb + 2]];
                let res = hybrid::force(
                    &x0,
                    &ue,
                    &pi,
                    mat,
                    hourglass,
                    &self.state_old[s0..s1],
                    &mut self.state_new[s0..s1],
                    &mut fe,
                    if want_k { Some(&mut ke[..]) } else { None },
                );
                if let Err(err) = res {
                    failure.get_or_insert_with(|| {
                        format!("element {}: {}", self.elements.orig[e], err.0)
                    });
                    continue;
                }
                let nodes = self.elements.nodes(e);
                if let Some((f, _)) = ev.forces.as_mut() {
                    for (a, &node) in nodes.iter().enumerate() {
                        for c in 0..3 {
                            f[3 * node + c] += fe[3 * a + c];
                        }
                    }
                    for c in 0..3 {
                        f[3 * pb + c] += fe[24 + c];
                    }
                }
                if let Some(k) = ev.jacobian.as_deref_mut() {
                    for (a, &node) in nodes.iter().enumerate() {
                        blocks[a] = ev.dofs.global_block(node);
                    }
                    blocks[8] = ev.dofs.global_block(pb);
                    k.add_element(&blocks, &ke);
                }
                continue;
            }
            let res = element_force(
                self.elements.kinds[e],
                self.elements.formulation[e],
                &x0[..n],
                &ue[..n],
                mat,
                &self.state_old[s0..s1],
                &mut self.state_new[s0..s1],
                &mut fe[..3 * n],
                if want_k {
                    Some(&mut ke[..9 * n * n])
                } else {
                    None
                },
            );
            if let Err(err) = res {
                failure
                    .get_or_insert_with(|| format!("element {}: {}", self.elements.orig[e], err.0));
                continue;
            }
            let nodes = self.elements.nodes(e);
            if let Some((f, _)) = ev.forces.as_mut() {
                for (a, &node) in nodes.iter().enumerate() {
                    for c in 0..3 {
                        f[3 * node + c] += fe[3 * a + c];
                    }
                }
            }
            if let Some(k) = ev.jacobian.as_deref_mut() {
                for (a, &node) in nodes.iter().enumerate() {
                    blocks[a] = ev.dofs.global_block(node);
                }
                k.add_element(&blocks[..n], &ke[..9 * n * n]);
            }
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
