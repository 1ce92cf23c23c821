//! What dynamics needs from the distributed model: mass (lumped vector or consistent
//! element matrices applied on the fly), mass into the Jacobian, the explicit stable
//! time step, initial velocities and set-mean displacements for the history.

// Index loops over several dof vectors at once read like the formulas.
#![allow(clippy::needless_range_loop)]

use super::Model;
use crate::fem::mass::{consistent_mass, lumped_mass, max_frequency};
use crate::linalg::matrix::DistMatrix;
use crate::mesh::MAX_NODES;
use crate::parallel::Comm;
use crate::{Error, Result};

/// The mass operator of a dynamic run.
#[derive(Debug, Clone)]
pub enum MassMatrix {
    /// Row-sum lumped masses on owned dofs (3 equal entries per node).
    Lumped(Vec<f64>),
    /// ρ ∫ N_a N_b dV, applied element by element.
    Consistent,
}

/// The explicit stable step and where it comes from.
#[derive(Debug, Clone)]
pub struct StableStep {
    /// min_e L_e / c_d over the whole model (before the safety factor).
    pub dt: f64,
    /// The smallest characteristic length L_e = 2 c_d / ω_e.
    pub length: f64,
    /// Dilatational wave speed √((K + 4G/3)/ρ) of that element's material.
    pub wave_speed: f64,
    /// Per local element: its own stable step 2/ω_e and its reference thickness
    /// ([`crate::fem::measure::thickness`]), for [`Model::current_stable_time_step`].
    pub elements: Vec<(f64, f64)>,
}

impl Model {
    fn elem_x0(&self, e: usize, x0: &mut [[f64; 3]; MAX_NODES]) -> usize {
        let nodes = self.solids.elements.nodes(e);
        for (a, &n) in nodes.iter().enumerate() {
            x0[a] = self.mesh.coords[n];
        }
        nodes.len()
    }

    fn density(&self, e: usize) -> f64 {
        self.solids.material(e).density()
    }

    /// Lumped (row-sum) mass on owned dofs, ghost contributions summed (collective).
    /// Unknowns other than node displacements (multipliers, reference points) carry no
    /// mass.
    pub fn lumped_mass(&self, comm: &dyn Comm) -> Vec<f64> {
        let mut m = vec![0.0; self.dofs.n_local_dofs()];
        let mut x0 = [[0.0; 3]; MAX_NODES];
        let mut me = [0.0; MAX_NODES];
        for e in 0..self.solids.len() {
            let n = self.elem_x0(e, &mut x0);
            lumped_mass(
                self.solids.elements.kinds[e],
                &x0[..n],
                self.density(e),
                &mut me[..n],
            );
            for (a, &node) in self.solids.elements.nodes(e).iter().enumerate() {
                for c in 0..3 {
                    m[3 * node + c] += me[a];
                }
            }
        }
        let mut owned = vec![0.0; self.n_owned_dofs()];
        self.dofs.sum_to_owned(comm, &m, &mut owned);
        for (i, mi) in self.extra_masses() {
            owned[i] += mi;
        }
        owned
    }

    /// The contributions' own masses (a rigid body's): (owned index, mass).
    pub fn extra_masses(&self) -> Vec<(usize, f64)> {
        self.each_ref()
            .filter_map(|c| c.dynamics())
            .flat_map(|d| d.masses(&self.dofs))
            .collect()
    }

    /// The owned unknowns without mass that are not node displacements (multipliers,
    /// reference points, massless body DOFs): algebraic in time integration.
    pub fn algebraic_dofs(&self) -> Vec<usize> {
        let massive: std::collections::BTreeSet<usize> = self
            .extra_masses()
            .into_iter()
            .filter(|m| m.1 > 0.0)
            .map(|m| m.0)
            .collect();
        self.extra_range()
            .filter(|i| !massive.contains(i))
            .collect()
    }

    /// out = M v on owned dofs (collective for the consistent mass).
    pub fn apply_mass(&self, comm: &dyn Comm, mass: &MassMatrix, v: &[f64], out: &mut [f64]) {
        match mass {
            MassMatrix::Lumped(m) => {
                for i in 0..v.len() {
                    out[i] = m[i] * v[i];
                }
            }
            MassMatrix::Consistent => {
                let mut vl = Vec::new();
                self.gather(comm, v, &mut vl);
                let mut f = vec![0.0; vl.len()];
                let mut x0 = [[0.0; 3]; MAX_NODES];
                let mut me = [0.0; MAX_NODES * MAX_NODES];
                for e in 0..self.solids.len() {
                    let n = self.elem_x0(e, &mut x0);
                    consistent_mass(
                        self.solids.elements.kinds[e],
                        &x0[..n],
                        self.density(e),
                        &mut me[..n * n],
                    );
                    let nodes = self.solids.elements.nodes(e);
                    for (a, &na) in nodes.iter().enumerate() {
                        for (b, &nb) in nodes.iter().enumerate() {
                            let m = me[a * n + b];
                            for c in 0..3 {
                                f[3 * na + c] += m * vl[3 * nb + c];
                            }
                        }
                    }
                }
                self.dofs.sum_to_owned(comm, &f, out);
                for (i, mi) in self.extra_masses() {
                    out[i] += mi * v[i];
                }
            }
        }
    }

    /// k += scale · M (after [`Model::jacobian`]; collective: finishes the assembly again).
    pub fn add_mass(&self, comm: &dyn Comm, mass: &MassMatrix, scale: f64, k: &mut DistMatrix) {
        match mass {
            MassMatrix::Lumped(m) => {
                for i in 0..self.mesh.n_owned() {
                    let b = self.dofs.global_block(i);
                    let d = scale * m[3 * i];
                    k.add_block(b, b, &[d, 0.0, 0.0, 0.0, d, 0.0, 0.0, 0.0, d]);
                }
                for (i, _) in self.extra_masses() {
                    let mut d = [0.0; 9];
                    d[4 * (i % 3)] = scale * m[i];
                    let b = self.dofs.owned_global_block(i);
                    k.add_block(b, b, &d);
                }
            }
            MassMatrix::Consistent => {
                let mut x0 = [[0.0; 3]; MAX_NODES];
                let mut me = [0.0; MAX_NODES * MAX_NODES];
                let mut ke = [0.0; 9 * MAX_NODES * MAX_NODES];
                let mut blocks = [0usize; MAX_NODES];
                for e in 0..self.solids.len() {
                    let n = self.elem_x0(e, &mut x0);
                    consistent_mass(
                        self.solids.elements.kinds[e],
                        &x0[..n],
                        self.density(e),
                        &mut me[..n * n],
                    );
                    let w = 3 * n;
                    ke[..w * w].fill(0.0);
                    for a in 0..n {
                        for b in 0..n {
                            for c in 0..3 {
                                ke[(3 * a + c) * w + 3 * b + c] = scale * me[a * n + b];
                            }
                        }
                    }
                    for (a, &node) in self.solids.elements.nodes(e).iter().enumerate() {
                        blocks[a] = self.dofs.global_block(node);
                    }
                    k.add_element(&blocks[..n], &ke[..w * w]);
                }
                for (i, mi) in self.extra_masses() {
                    let mut d = [0.0; 9];
                    d[4 * (i % 3)] = scale * mi;
                    let b = self.dofs.owned_global_block(i);
                    k.add_block(b, b, &d);
                }
            }
        }
        k.finish_assembly(comm);
    }

    /// The explicit stable step min_e L_e / c_d with L_e = 2 c_d / ω_e, ω_e the element's
    /// highest frequency with lumped mass at the reference state ([`max_frequency`]),
    /// and c_d = √((K + 4G/3)/ρ). One reduction.
    pub fn stable_time_step(&self, comm: &dyn Comm) -> Result<StableStep> {
        // Reduce [−dt, −L, c_d of that element] by max on −dt: one allreduce of the
        // minimum dt, then the owner of the minimum reports L and c_d (second reduction
        // of two numbers; cheap and only at start-up).
        let mut best = (f64::INFINITY, 0.0, 0.0);
        let mut elements = Vec::with_capacity(self.solids.len());
        let mut failure = None;
        let mut x0 = [[0.0; 3]; MAX_NODES];
        let el = &self.solids.elements;
        for e in 0..self.solids.len() {
            let n = self.elem_x0(e, &mut x0);
            let mat = self.solids.material(e);
            match max_frequency(
                el.kinds[e],
                el.formulation[e],
                &x0[..n],
                mat,
                self.solids.history(e),
            ) {
                Ok(w) => {
                    let cd = ((mat.bulk_modulus() + 4.0 / 3.0 * mat.shear_modulus())
                        / mat.density())
                    .sqrt();
                    let dt = 2.0 / w;
                    let t =
                        crate::fem::measure::thickness(el.kinds[e], &x0[..n]).unwrap_or(f64::NAN);
                    elements.push((dt, t));
                    if dt < best.0 {
                        best = (dt, cd * dt, cd);
                    }
                }
                Err(why) => {
                    failure.get_or_insert(format!("element {}: {why}", el.orig[e]));
                }
            }
        }
        if let Some(why) = comm.first_message(failure) {
            return Err(Error::runtime(format!("stable time step: {why}")));
        }
        let mut m = [-best.0];
        comm.allreduce_max(&mut m);
        let dt = -m[0];
        let mine = if best.0 == dt { 1.0 } else { 0.0 };
        let mut lc = [mine, mine * best.1, mine * best.2];
        comm.allreduce_sum(&mut lc);
        let k = lc[0].max(1.0);
        Ok(StableStep {
            dt,
            length: lc[1] / k,
            wave_speed: lc[2] / k,
            elements,
        })
    }

    /// The stable step at displacement `u_owned` (collective): each element's reference
    /// step 2/ω_e scaled by how much thinner it has become (current / reference
    /// thickness, never more than 1), minimised over the model. An impact squashes the
    /// elements at the contact face, and a step computed once at the start becomes
    /// unstable (a Taylor bar blew up at 12 % of its run that way). The wave speed is
    /// kept at its reference value: right for metals (hardening only softens), a
    /// lower bound for hyperelastic stiffening in compression (hence `dt_factor`).
    pub fn current_stable_time_step(
        &self,
        comm: &dyn Comm,
        u_owned: &[f64],
        reference: &StableStep,
    ) -> f64 {
        let mut u_local = Vec::new();
        self.gather(comm, u_owned, &mut u_local);
        let mut x = [[0.0; 3]; MAX_NODES];
        let mut dt = f64::INFINITY;
        for (e, &(dt_e, t_ref)) in reference.elements.iter().enumerate() {
            let nodes = self.solids.elements.nodes(e);
            for (a, &nd) in nodes.iter().enumerate() {
                let c = self.mesh.coords[nd];
                x[a] = [
                    c[0] + u_local[3 * nd],
                    c[1] + u_local[3 * nd + 1],
                    c[2] + u_local[3 * nd + 2],
                ];
            }
            let ratio =
                crate::fem::measure::thickness(self.solids.elements.kinds[e], &x[..nodes.len()])
                    .map_or(0.0, |t| (t / t_ref).min(1.0));
            dt = dt.min(dt_e * ratio);
        }
        let mut m = [-dt];
        comm.allreduce_max(&mut m);
        -m[0]
    }

    /// Initial velocity on owned dofs from the deck's `[[initial_velocity]]`.
    pub fn initial_velocity(&self) -> Vec<f64> {
        let no = self.mesh.n_owned();
        let mut v = vec![0.0; self.n_owned_dofs()];
        for (set, vel) in &self.initial_velocity {
            for &n in self.mesh.set(set) {
                if n < no {
                    v[3 * n..3 * n + 3].copy_from_slice(vel);
                }
            }
        }
        for d in self.each_ref().filter_map(|c| c.dynamics()) {
            for (i, vi) in d.initial_velocities(&self.dofs) {
                v[i] = vi;
            }
        }
        v
    }

    /// Mean displacement of each of the model's displacement sets over all ranks (one
    /// reduction).
    pub fn mean_displacements(&self, comm: &dyn Comm, u: &[f64]) -> Vec<[f64; 3]> {
        let sets = &self.displacement_sets;
        if sets.is_empty() {
            return Vec::new();
        }
        let no = self.mesh.n_owned();
        let mut s = vec![0.0; 4 * sets.len()];
        for (i, name) in sets.iter().enumerate() {
            for &n in self.mesh.set(name) {
                if n < no {
                    for c in 0..3 {
                        s[4 * i + c] += u[3 * n + c];
                    }
                    s[4 * i + 3] += 1.0;
                }
            }
        }
        comm.allreduce_sum(&mut s);
        s.chunks(4)
            .map(|c| {
                let k = c[3].max(1.0);
                [c[0] / k, c[1] / k, c[2] / k]
            })
            .collect()
    }
}
