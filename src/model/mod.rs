//! The distributed finite-element problem on one rank: element loops over local
//! elements, ghost contributions summed on owners, constraints, loads and reactions.
//! It knows physics and calls the parallel layer only through [`Comm`] and plans.

pub mod contact;
pub mod def;
pub mod dynamics;

use crate::fem::element::{element_force, element_stress, n_gauss};
use crate::fem::surface::{pressure_face, traction_face};
use crate::material::Material;
use crate::model::def::Load;
use crate::parallel::{Comm, HaloPlan, Layout};
use crate::partition::distribute::LocalModel;
use crate::solve::linear::matrix::DistMatrix;
use crate::{Error, Result};

/// Unknowns are numbered in triples ("blocks"): each rank's range holds one block per
/// owned node (its displacement), then one block per owned node tracked by an ALM wall
/// (its multipliers λ_N, λ_T1, λ_T2); rigid-body DOFs will follow (DESIGN.md). Local
/// vectors over owned + ghost nodes (`u_local`) hold node dofs only: owned nodes, then
/// ghosts; multipliers are never ghosted (their rows couple only to their own node).
pub struct Model {
    pub local: LocalModel,
    pub materials: Vec<Box<dyn Material>>,
    /// Block (node) ownership: rank r owns blocks [start, end).
    pub blocks: Layout,
    /// Scalar unknown ownership (3 per block).
    pub dofs: Layout,
    /// Ghost exchange of scalar dofs of ghost nodes.
    pub halo: HaloPlan,
    /// Global block of each local node.
    pub node_block: Vec<usize>,
    /// Constrained local dofs (owned and ghost) with the constraint that sets them.
    constrained_local: Vec<(usize, usize)>,
    /// Owned constrained dofs (local scalar index) with their constraint.
    pub constrained_owned: Vec<(usize, usize)>,
    /// Per element offset into the history arrays.
    state_offset: Vec<usize>,
    state_old: Vec<f64>,
    state_new: Vec<f64>,
    /// Owned nodes of each reaction set.
    reaction_nodes: Vec<Vec<usize>>,
    /// Work vector over local dofs (owned + ghost).
    work: Vec<f64>,
    /// Total element evaluations (for rates).
    pub element_evaluations: u64,
    /// Rigid walls and their tracked nodes on this rank.
    pub contact: contact::Contact,
}

/// What a residual evaluation reports besides the residual.
#[derive(Debug, Clone, Copy)]
pub struct ResidualInfo {
    /// Force scale for relative convergence: max(‖f_int‖, ‖f_ext‖) over all owned dofs.
    pub f_ref: f64,
}

impl Model {
    /// Collective: build plans, material objects and history storage.
    pub fn new(comm: &dyn Comm, local: LocalModel) -> Result<Self> {
        let n_mult = contact::Contact::n_mult_blocks(&local.walls);
        let mults = Layout::gather(comm, n_mult);
        let nodes = Layout::from_counts(&local.owned_nodes_per_rank, local.rank);
        let block_counts: Vec<usize> = (0..nodes.size())
            .map(|r| nodes.starts[r + 1] - nodes.starts[r] + mults.starts[r + 1] - mults.starts[r])
            .collect();
        let blocks = Layout::from_counts(&block_counts, local.rank);
        let dof_counts: Vec<usize> = block_counts.iter().map(|c| 3 * c).collect();
        let dofs = Layout::from_counts(&dof_counts, local.rank);
        // A node's block: its owner's first block plus its place among the owner's nodes.
        let node_block: Vec<usize> = (0..local.n_local_nodes())
            .map(|n| {
                let g = local.global_node(n);
                let q = nodes.owner(g);
                blocks.starts[q] + g - nodes.starts[q]
            })
            .collect();
        let ghost_dofs: Vec<usize> = node_block[local.n_owned()..]
            .iter()
            .flat_map(|&b| (0..3).map(move |c| 3 * b + c))
            .collect();
        let halo = HaloPlan::new(comm, &dofs, ghost_dofs);
        let contact = contact::Contact::new(
            &local.walls,
            &local.coords,
            3 * local.n_owned(),
            blocks.start() + local.n_owned(),
        );
        let materials: Vec<Box<dyn Material>> =
            local.materials.iter().map(|(_, m)| m.build()).collect();
        let mut state_offset = Vec::with_capacity(local.n_elems() + 1);
        let mut s = 0;
        for e in 0..local.n_elems() {
            state_offset.push(s);
            s += n_gauss(local.kinds[e]) * materials[local.elem_material[e] as usize].n_state();
        }
        state_offset.push(s);
        // Constraints: later entries win where two constrain the same dof.
        let mut which = vec![usize::MAX; 3 * local.n_local_nodes()];
        for (ci, c) in local.constraints.iter().enumerate() {
            let nodes = local
                .node_sets
                .get(&c.set)
                .map(|v| v.as_slice())
                .unwrap_or(&[]);
            for &n in nodes {
                for k in 0..3 {
                    if c.comps[k] {
                        which[3 * n + k] = ci;
                    }
                }
            }
        }
        let constrained_local: Vec<(usize, usize)> = which
            .iter()
            .enumerate()
            .filter(|(_, &c)| c != usize::MAX)
            .map(|(d, &c)| (d, c))
            .collect();
        let n_owned_dofs = 3 * local.n_owned();
        let constrained_owned = constrained_local
            .iter()
            .copied()
            .filter(|&(d, _)| d < n_owned_dofs)
            .collect();
        let reaction_nodes = local
            .reaction_sets
            .iter()
            .map(|s| {
                local
                    .node_sets
                    .get(s)
                    .map(|v| v.iter().copied().filter(|&n| n < local.n_owned()).collect())
                    .unwrap_or_default()
            })
            .collect();
        let n_local_dofs = 3 * local.n_local_nodes();
        let mut model = Self {
            materials,
            blocks,
            dofs,
            halo,
            node_block,
            constrained_local,
            constrained_owned,
            state_old: vec![0.0; s],
            state_new: vec![0.0; s],
            state_offset,
            reaction_nodes,
            work: vec![0.0; n_local_dofs],
            element_evaluations: 0,
            local,
            contact,
        };
        if comm.all_ok(model.contact.is_empty()) {
            return Ok(model);
        }
        model.set_contact_scales(comm);
        Ok(model)
    }

    /// κ of every tracked node without a deck value: the mean diagonal entry of its
    /// block of the stiffness at the reference state, scaled from the P-wave modulus
    /// λ + 2μ that dominates it down to Young's modulus E, by (1 + ν)(1 − 2ν)/(1 − ν)
    /// (smallest over the node's materials). κ is the augmentation parameter of the
    /// friction law (γ compares λ_T with the slip g_T); Alart–Curnier-type semi-smooth
    /// Newton wants it of the order of E·h, and a bulk-dominated κ (rubber: K/G ~ 1000)
    /// made the stick/slip decisions cycle (collective: one assembly).
    fn set_contact_scales(&mut self, comm: &dyn Comm) {
        let mut factor = vec![1.0f64; self.local.n_local_nodes()];
        for e in 0..self.local.n_elems() {
            let nu = self.local.materials[self.local.elem_material[e] as usize]
                .1
                .nu();
            let f = (1.0 + nu) * (1.0 - 2.0 * nu) / (1.0 - nu);
            for &n in self.local.elem_nodes(e) {
                factor[n] = factor[n].min(f);
            }
        }
        let mut k = self.new_matrix(comm);
        k.zero();
        let u0 = vec![0.0; 3 * self.local.n_local_nodes()];
        let old = self.state_new.clone();
        self.element_pass(&u0, None, Some(&mut k));
        self.state_new = old;
        k.finish_assembly(comm);
        let start = self.blocks.start();
        let nb = &self.node_block;
        self.contact.set_kappa(|n| {
            let d = k
                .block(nb[n] - start, nb[n])
                .map(|b| (b[0] + b[4] + b[8]) / 3.0)
                .unwrap_or(0.0);
            (d, factor[n])
        });
    }

    /// All unknowns owned here: node dofs, then multipliers.
    pub fn n_owned_dofs(&self) -> usize {
        3 * self.blocks.owned_len()
    }

    /// The owned node dofs (the first `3 · n_owned` unknowns of the owned range).
    pub fn n_node_dofs(&self) -> usize {
        3 * self.local.n_owned()
    }

    /// Local indices of the owned multiplier unknowns.
    pub fn multiplier_range(&self) -> std::ops::Range<usize> {
        self.n_node_dofs()..self.n_owned_dofs()
    }

    /// Owned node dofs plus ghost copies, refreshed from their owners (multipliers are
    /// left out: `u_local` is indexed by local node).
    pub fn gather(&self, comm: &dyn Comm, u_owned: &[f64], u_local: &mut Vec<f64>) {
        let n = self.n_node_dofs();
        u_local.resize(n + self.halo.n_ghosts(), 0.0);
        u_local[..n].copy_from_slice(&u_owned[..n]);
        let (_, ghosts) = u_local.split_at_mut(n);
        self.halo.forward(comm, u_owned, ghosts);
    }

    /// The prescribed values at time t of the owned constrained dofs: (local dof, value).
    pub fn prescribed(&self, t: f64) -> Vec<(usize, f64)> {
        self.constrained_owned
            .iter()
            .map(|&(d, c)| {
                let con = &self.local.constraints[c];
                (d, con.value(self.local.coords[d / 3], d % 3, t))
            })
            .collect()
    }

    fn elem_coords(
        &self,
        e: usize,
        u_local: &[f64],
        x0: &mut [[f64; 3]; 8],
        u: &mut [[f64; 3]; 8],
    ) -> usize {
        let nodes = self.local.elem_nodes(e);
        for (a, &n) in nodes.iter().enumerate() {
            x0[a] = self.local.coords[n];
            u[a] = [u_local[3 * n], u_local[3 * n + 1], u_local[3 * n + 2]];
        }
        nodes.len()
    }

    /// Residual r = f_int(u) − f_ext(u, t) on owned dofs, constrained rows included
    /// (there r is the reaction). Collective; a failure on any rank (an inverted element)
    /// is a failure on all.
    pub fn residual(
        &mut self,
        comm: &dyn Comm,
        u_owned: &[f64],
        t: f64,
        r: &mut [f64],
    ) -> Result<ResidualInfo> {
        let n = u_owned.len();
        let mut fi = vec![0.0; n];
        let info = self.forces(comm, u_owned, t, &mut fi, r)?;
        for i in 0..n {
            r[i] = fi[i] - r[i];
        }
        Ok(info)
    }

    /// Internal and external forces on owned dofs (ghost contributions summed), as
    /// [`Model::residual`] combines them. Collective.
    pub fn forces(
        &mut self,
        comm: &dyn Comm,
        u_owned: &[f64],
        t: f64,
        f_int_owned: &mut [f64],
        f_ext_owned: &mut [f64],
    ) -> Result<ResidualInfo> {
        let mut u_local = std::mem::take(&mut self.work);
        self.gather(comm, u_owned, &mut u_local);
        let nl = u_local.len();
        let mut f_int = vec![0.0; nl];
        let mut f_ext = vec![0.0; nl];
        let failure = self.element_pass(&u_local, Some(&mut f_int), None);
        self.external_forces(&u_local, t, &mut f_ext, None);
        // Sum ghost contributions on the owners.
        let no = self.n_node_dofs();
        let (own_i, ghost_i) = f_int.split_at_mut(no);
        self.halo.reverse_add(comm, ghost_i, own_i);
        let (own_e, ghost_e) = f_ext.split_at_mut(no);
        self.halo.reverse_add(comm, ghost_e, own_e);
        f_int_owned.iter_mut().for_each(|x| *x = 0.0);
        f_ext_owned.iter_mut().for_each(|x| *x = 0.0);
        f_int_owned[..no].copy_from_slice(own_i);
        f_ext_owned[..no].copy_from_slice(own_e);
        // Rigid walls: forces on owned tracked nodes count as external; multiplier rows
        // (−κ h, zero at a solution) go with the internal forces.
        self.contact.residual(
            &self.local.coords,
            &u_local,
            u_owned,
            t,
            f_ext_owned,
            f_int_owned,
            None,
            &self.node_block,
        );
        let mut sums = [0.0, 0.0, if failure.is_some() { 1.0 } else { 0.0 }];
        for i in 0..f_int_owned.len() {
            sums[0] += f_int_owned[i] * f_int_owned[i];
            sums[1] += f_ext_owned[i] * f_ext_owned[i];
        }
        comm.allreduce_sum(&mut sums);
        self.work = u_local;
        if sums[2] > 0.0 {
            let msg = failure.unwrap_or_else(|| "an element on another rank failed".into());
            return Err(Error::convergence(format!(
                "residual could not be evaluated: {msg}"
            )));
        }
        Ok(ResidualInfo {
            f_ref: sums[0].sqrt().max(sums[1].sqrt()),
        })
    }

    /// One loop over the local elements at `u_local`: internal forces into `f_int`
    /// and/or element tangents into `k`. Returns the first element failure (an
    /// inverted element), which the caller agrees on across ranks.
    fn element_pass(
        &mut self,
        u_local: &[f64],
        mut f_int: Option<&mut [f64]>,
        mut k: Option<&mut DistMatrix>,
    ) -> Option<String> {
        let mut failure: Option<String> = None;
        let mut x0 = [[0.0; 3]; 8];
        let mut ue = [[0.0; 3]; 8];
        let mut fe = [0.0; 24];
        let mut ke = vec![0.0; if k.is_some() { 576 } else { 0 }];
        let mut blocks = [0usize; 8];
        for e in 0..self.local.n_elems() {
            let n = self.elem_coords(e, u_local, &mut x0, &mut ue);
            let mat = self.materials[self.local.elem_material[e] as usize].as_ref();
            let (s0, s1) = (self.state_offset[e], self.state_offset[e + 1]);
            let res = element_force(
                self.local.kinds[e],
                self.local.elem_formulation[e],
                &x0[..n],
                &ue[..n],
                mat,
                &self.state_old[s0..s1],
                &mut self.state_new[s0..s1],
                &mut fe[..3 * n],
                k.as_ref().map(|_| &mut ke[..9 * n * n]),
            );
            if let Err(err) = res {
                failure.get_or_insert_with(|| {
                    format!("element {}: {}", self.local.orig_elem[e], err.0)
                });
                continue;
            }
            let nodes = self.local.elem_nodes(e);
            if let Some(f) = f_int.as_deref_mut() {
                for (a, &node) in nodes.iter().enumerate() {
                    for c in 0..3 {
                        f[3 * node + c] += fe[3 * a + c];
                    }
                }
            }
            if let Some(kmat) = k.as_deref_mut() {
                for (a, &node) in nodes.iter().enumerate() {
                    blocks[a] = self.node_block[node];
                }
                kmat.add_element(&blocks[..n], &ke[..9 * n * n]);
            }
        }
        self.element_evaluations += self.local.n_elems() as u64;
        failure
    }

    /// External forces at time t into `f` (local dofs); if `k` is given, the load
    /// stiffness −∂f_ext/∂u of follower loads is added to it.
    fn external_forces(
        &self,
        u_local: &[f64],
        t: f64,
        f: &mut [f64],
        mut k: Option<&mut DistMatrix>,
    ) {
        let no = self.local.n_owned();
        let mut fe = [0.0; 12];
        let mut ke = [0.0; 144];
        for load in &self.local.loads {
            match load {
                Load::Nodal { set, force, curve } => {
                    let s = curve.eval(t);
                    for &n in self
                        .local
                        .node_sets
                        .get(set)
                        .map(|v| v.as_slice())
                        .unwrap_or(&[])
                    {
                        if n < no {
                            for c in 0..3 {
                                f[3 * n + c] += force[c] * s;
                            }
                        }
                    }
                }
                Load::Traction {
                    surface,
                    traction,
                    curve,
                } => {
                    let s = curve.eval(t);
                    let tr = [traction[0] * s, traction[1] * s, traction[2] * s];
                    for &(e, face) in self
                        .local
                        .surfaces
                        .get(surface)
                        .map(|v| v.as_slice())
                        .unwrap_or(&[])
                    {
                        let nodes = self.face_nodes(e, face);
                        let x0: Vec<[f64; 3]> =
                            nodes.iter().map(|&n| self.local.coords[n]).collect();
                        let m = nodes.len();
                        traction_face(&x0, tr, &mut fe[..3 * m]);
                        for (a, &n) in nodes.iter().enumerate() {
                            for c in 0..3 {
                                f[3 * n + c] += fe[3 * a + c];
                            }
                        }
                    }
                }
                Load::Pressure {
                    surface,
                    pressure,
                    curve,
                } => {
                    let p = pressure * curve.eval(t);
                    for &(e, face) in self
                        .local
                        .surfaces
                        .get(surface)
                        .map(|v| v.as_slice())
                        .unwrap_or(&[])
                    {
                        let nodes = self.face_nodes(e, face);
                        let m = nodes.len();
                        let x0: Vec<[f64; 3]> =
                            nodes.iter().map(|&n| self.local.coords[n]).collect();
                        let u: Vec<[f64; 3]> = nodes
                            .iter()
                            .map(|&n| [u_local[3 * n], u_local[3 * n + 1], u_local[3 * n + 2]])
                            .collect();
                        let want_k = k.is_some();
                        pressure_face(
                            &x0,
                            &u,
                            p,
                            &mut fe[..3 * m],
                            if want_k {
                                Some(&mut ke[..9 * m * m])
                            } else {
                                None
                            },
                        );
                        for (a, &n) in nodes.iter().enumerate() {
                            for c in 0..3 {
                                f[3 * n + c] += fe[3 * a + c];
                            }
                        }
                        if let Some(kmat) = k.as_deref_mut() {
                            // Jacobian of r = f_int − f_ext gets −∂f_ext/∂u.
                            let neg: Vec<f64> = ke[..9 * m * m].iter().map(|v| -v).collect();
                            let blocks: Vec<usize> =
                                nodes.iter().map(|&n| self.node_block[n]).collect();
                            kmat.add_element(&blocks, &neg);
                        }
                    }
                }
            }
        }
    }

    fn face_nodes(&self, e: usize, face: u8) -> Vec<usize> {
        let en = self.local.elem_nodes(e);
        self.local.kinds[e].faces()[face as usize]
            .iter()
            .map(|&i| en[i])
            .collect()
    }

    /// The sparsity pattern of the Jacobian (collective).
    pub fn new_matrix(&self, comm: &dyn Comm) -> DistMatrix {
        let mut pairs = Vec::new();
        for e in 0..self.local.n_elems() {
            let nodes = self.local.elem_nodes(e);
            for &a in nodes {
                for &b in nodes {
                    pairs.push((self.node_block[a], self.node_block[b]));
                }
            }
        }
        pairs.extend(self.contact.pattern(&self.node_block));
        pairs.sort_unstable();
        pairs.dedup();
        DistMatrix::new(comm, self.blocks.clone(), &pairs)
    }

    /// Assemble the (unconstrained) Jacobian ∂r/∂u at u (collective).
    pub fn jacobian(
        &mut self,
        comm: &dyn Comm,
        u_owned: &[f64],
        t: f64,
        k: &mut DistMatrix,
    ) -> Result<()> {
        let mut u_local = std::mem::take(&mut self.work);
        self.gather(comm, u_owned, &mut u_local);
        k.zero();
        let failure = self.element_pass(&u_local, None, Some(k));
        let mut scratch = vec![0.0; u_local.len()];
        self.external_forces(&u_local, t, &mut scratch, Some(k));
        let mut scratch_f = vec![0.0; u_owned.len()];
        let mut scratch_r = vec![0.0; u_owned.len()];
        self.contact.residual(
            &self.local.coords,
            &u_local,
            u_owned,
            t,
            &mut scratch_f,
            &mut scratch_r,
            Some(k),
            &self.node_block,
        );
        k.finish_assembly(comm);
        self.work = u_local;
        if !comm.all_ok(failure.is_none()) {
            let msg = failure.unwrap_or_else(|| "an element on another rank failed".into());
            return Err(Error::convergence(format!(
                "Jacobian could not be assembled: {msg}"
            )));
        }
        Ok(())
    }

    /// Accept the history computed at the last converged evaluation.
    pub fn commit(&mut self) {
        self.state_old.copy_from_slice(&self.state_new);
        self.contact.commit();
    }

    /// Explicit runs: put tracked nodes of ALM walls that penetrate back on the wall and
    /// remove their approach velocity (`v` is the mid-step velocity).
    pub fn contact_kinematic(&mut self, u: &mut [f64], v: &mut [f64], m: &[f64], t: f64, h: f64) {
        self.contact.kinematic(&self.local.coords, u, v, m, t, h);
    }

    /// Implicit dynamics after a converged step: tracked nodes pressed against a wall get
    /// the wall's normal velocity and acceleration (owned dofs; no communication).
    pub fn contact_persistency(&self, v: &mut [f64], a: &mut [f64], t: f64, h: f64) {
        self.contact.persistency(v, a, t, h);
    }

    /// Wall forces, penetration and contact counts at the last evaluation (collective).
    pub fn contact_report(&self, comm: &dyn Comm) -> Option<contact::ContactReport> {
        if self.local.walls.is_empty() {
            return None;
        }
        Some(self.contact.report(comm, self.local.walls.len()))
    }

    /// Reaction force on each reaction set: Σ over its owned nodes of r = f_int − f_ext
    /// (the force the supports exert on the body), summed over ranks.
    pub fn reactions(&self, comm: &dyn Comm, r: &[f64]) -> Vec<[f64; 3]> {
        let mut sums = vec![0.0; 3 * self.reaction_nodes.len()];
        for (s, nodes) in self.reaction_nodes.iter().enumerate() {
            for &n in nodes {
                for c in 0..3 {
                    sums[3 * s + c] += r[3 * n + c];
                }
            }
        }
        comm.allreduce_sum(&mut sums);
        sums.chunks(3).map(|c| [c[0], c[1], c[2]]).collect()
    }

    /// Whether any material carries an equivalent plastic strain (same on all ranks:
    /// every rank holds the whole material list).
    pub fn has_plastic_strain(&self) -> bool {
        self.materials.iter().any(|m| {
            m.equivalent_plastic_strain(&vec![0.0; m.n_state()])
                .is_some()
        })
    }

    /// Equivalent plastic strain of every local element at the last committed state:
    /// the mean over its integration points (0 for elastic materials).
    pub fn plastic_strains(&self) -> Vec<f64> {
        (0..self.local.n_elems())
            .map(|e| {
                let mat = self.materials[self.local.elem_material[e] as usize].as_ref();
                let ns = mat.n_state();
                let (s0, s1) = (self.state_offset[e], self.state_offset[e + 1]);
                if ns == 0 || s1 == s0 {
                    return 0.0;
                }
                let pts = self.state_old[s0..s1].chunks(ns);
                let n = pts.len() as f64;
                pts.map(|s| mat.equivalent_plastic_strain(s).unwrap_or(0.0))
                    .sum::<f64>()
                    / n
            })
            .collect()
    }

    /// Volume-averaged Cauchy stress of every local element.
    pub fn stresses(&self, comm: &dyn Comm, u_owned: &[f64]) -> Result<Vec<[f64; 6]>> {
        let mut u_local = Vec::new();
        self.gather(comm, u_owned, &mut u_local);
        let mut x0 = [[0.0; 3]; 8];
        let mut ue = [[0.0; 3]; 8];
        let mut out = Vec::with_capacity(self.local.n_elems());
        for e in 0..self.local.n_elems() {
            let n = self.elem_coords(e, &u_local, &mut x0, &mut ue);
            let mat = self.materials[self.local.elem_material[e] as usize].as_ref();
            let (s0, s1) = (self.state_offset[e], self.state_offset[e + 1]);
            let s = element_stress(
                self.local.kinds[e],
                self.local.elem_formulation[e],
                &x0[..n],
                &ue[..n],
                mat,
                &self.state_old[s0..s1],
            )
            .unwrap_or([f64::NAN; 6]);
            out.push(s);
        }
        Ok(out)
    }

    /// Mean characteristic element length over the whole model (collective).
    pub fn char_length(&self, comm: &dyn Comm) -> f64 {
        let mut s = [0.0, self.local.n_elems() as f64];
        for e in 0..self.local.n_elems() {
            let x0: Vec<[f64; 3]> = self
                .local
                .elem_nodes(e)
                .iter()
                .map(|&n| self.local.coords[n])
                .collect();
            s[0] += crate::fem::element::char_length(self.local.kinds[e], &x0);
        }
        comm.allreduce_sum(&mut s);
        s[0] / s[1].max(1.0)
    }

    /// Owned constrained dofs, local scalar indices (for `DistMatrix::constrain`).
    pub fn constrained_dofs(&self) -> Vec<usize> {
        self.constrained_owned.iter().map(|&(d, _)| d).collect()
    }

    /// How many local (owned + ghost) dofs are constrained.
    pub fn n_constrained_local(&self) -> usize {
        self.constrained_local.len()
    }
}
