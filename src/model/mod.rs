//! The distributed finite-element problem on one rank: a list of contributions
//! ([`contribution`]) over one unknown map ([`dofs`]). Every evaluation runs all
//! contributions on local data, then sums ghost entries on their owners once; supports
//! (prescribed node displacements), reactions, set probes, history columns, output fields
//! and the summary are read off the same list. It knows physics and calls the parallel
//! layer only through [`Comm`], the unknown map and the distributed matrix.

pub mod body;
pub mod contribution;
pub mod coupling;
pub mod def;
pub mod distribute;
pub mod dofs;
pub mod dynamics;
pub mod kind;
pub mod loads;
pub mod local;
pub mod mat3;
pub mod pairing;
pub mod pairs;
pub mod solid_patches;
pub mod solids;
pub mod walls;

pub use contribution::Contribution;

use contribution::{
    Column, Evaluation, FieldSpec, GridSpec, Kinematic, Outputs, Reduce, Reference, State,
};
use def::Constraint;
use distribute::{LocalMesh, LocalModel};
use dofs::DofMap;
use solids::Solids;

use crate::linalg::DistMatrix;
use crate::parallel::Comm;
use crate::{Error, Result};
use std::collections::BTreeMap;

pub struct Model {
    /// This rank's nodes and sets.
    pub mesh: LocalMesh,
    /// The unknown map.
    pub dofs: DofMap,
    /// The solid elements: the first contribution, also reached by type (mass, stable
    /// step, output mesh).
    pub solids: Solids,
    /// Everything else, in the definitions' order: loads, walls, couplings.
    pub contributions: Vec<Box<dyn Contribution>>,
    constraints: Vec<Constraint>,
    /// Owned constrained node dofs (owned index) with the constraint that sets them.
    constrained_owned: Vec<(usize, usize)>,
    /// Every owned prescribed unknown (supports' and contributions'), as
    /// [`Model::prescribed`] lists them.
    prescribed_dofs: Vec<usize>,
    /// Reaction sets (names) and their owned nodes.
    pub reaction_sets: Vec<String>,
    reaction_nodes: Vec<Vec<usize>>,
    pub displacement_sets: Vec<String>,
    pub initial_velocity: Vec<(String, [f64; 3])>,
    /// The history columns of the contributions (merged: shared ones last) and where
    /// each contribution's columns go.
    columns: Vec<Column>,
    column_map: Vec<Vec<usize>>,
    /// Work vector over local dofs.
    work: Vec<f64>,
}

/// What a residual evaluation reports besides the residual.
#[derive(Debug, Clone, Copy)]
pub struct ResidualInfo {
    /// Force scale for relative convergence: max(‖f_int‖, ‖f_ext‖) over all owned dofs.
    pub f_ref: f64,
}

/// An output field with this rank's rows.
#[derive(Debug, Clone)]
pub struct Field {
    pub spec: FieldSpec,
    pub values: Vec<f64>,
}

impl Model {
    /// Collective: build the contributions, the unknown map, the material history and,
    /// if any contribution wants it, the reference stiffness scales.
    pub fn new(comm: &dyn Comm, local: LocalModel) -> Result<Self> {
        let contributions: Vec<Box<dyn Contribution>> = local
            .contributions
            .iter()
            .map(|d| d.kind().build(&local.mesh, &local.elements))
            .collect();
        let LocalModel {
            mesh,
            elements,
            materials,
            constraints,
            reaction_sets,
            displacement_sets,
            initial_velocity,
            peak_stress_parts,
            part_names,
            ..
        } = local;
        let mut solids = Solids::new(elements, &materials);
        solids.peak_stress_parts = peak_stress_parts;
        solids.part_names = part_names;
        let mut unknowns = vec![solids.unknowns()];
        unknowns.extend(contributions.iter().map(|c| c.unknowns()));
        let dofs = DofMap::new(comm, &mesh.owned_nodes_per_rank, &mesh.ghosts, &unknowns);
        // Supports of owned nodes: later entries win where two constrain the same dof.
        let n_owned = mesh.n_owned();
        let mut which = vec![usize::MAX; 3 * n_owned];
        for (ci, c) in constraints.iter().enumerate() {
            for &n in mesh.set(&c.set).iter().filter(|&&n| n < n_owned) {
                for k in 0..3 {
                    if c.comps[k] {
                        which[3 * n + k] = ci;
                    }
                }
            }
        }
        let constrained_owned = which
            .iter()
            .enumerate()
            .filter(|(_, &c)| c != usize::MAX)
            .map(|(d, &c)| (d, c))
            .collect();
        let reaction_nodes = reaction_sets
            .iter()
            .map(|s| {
                mesh.set(s)
                    .iter()
                    .copied()
                    .filter(|&n| n < mesh.n_owned())
                    .collect()
            })
            .collect();
        let mut model = Self {
            work: vec![0.0; dofs.n_local_dofs()],
            mesh,
            dofs,
            solids,
            contributions,
            constraints,
            constrained_owned,
            prescribed_dofs: Vec::new(),
            reaction_sets,
            reaction_nodes,
            displacement_sets,
            initial_velocity,
            columns: Vec::new(),
            column_map: Vec::new(),
        };
        model.solids.bind(&model.dofs, 0);
        for (i, c) in model.contributions.iter_mut().enumerate() {
            c.bind(&model.dofs, i + 1);
        }
        model.merge_columns();
        model.prescribed_dofs = model.prescribed(0.0).into_iter().map(|p| p.0).collect();
        let wants = model
            .contributions
            .iter_mut()
            .any(|c| c.scaled().is_some_and(|s| s.wants_reference()));
        if !comm.all_ok(!wants) {
            model.set_reference(comm);
        }
        Ok(model)
    }

    /// The contributions' history columns in output order: each contribution's own
    /// columns in list order, then the shared ones (merged by name).
    fn merge_columns(&mut self) {
        let declared: Vec<Vec<Column>> = self
            .each_ref()
            .map(|c| c.outputs().map_or_else(Vec::new, |o| o.columns()))
            .collect();
        let mut columns: Vec<Column> = declared
            .iter()
            .flatten()
            .filter(|c| !c.shared)
            .cloned()
            .collect();
        let n_own = columns.len();
        for col in declared.iter().flatten().filter(|c| c.shared) {
            if !columns[n_own..].iter().any(|s| s.name == col.name) {
                columns.push(col.clone());
            }
        }
        let mut next_own = 0;
        self.column_map = declared
            .iter()
            .map(|cols| {
                cols.iter()
                    .map(|col| {
                        if col.shared {
                            n_own
                                + columns[n_own..]
                                    .iter()
                                    .position(|s| s.name == col.name)
                                    .unwrap()
                        } else {
                            next_own += 1;
                            next_own - 1
                        }
                    })
                    .collect()
            })
            .collect();
        self.columns = columns;
    }

    /// Every contribution, the solid elements first.
    fn each(&mut self) -> impl Iterator<Item = &mut (dyn Contribution + 'static)> + '_ {
        std::iter::once(&mut self.solids as &mut dyn Contribution)
            .chain(self.contributions.iter_mut().map(|c| c.as_mut()))
    }

    fn each_ref(&self) -> impl Iterator<Item = &(dyn Contribution + 'static)> + '_ {
        std::iter::once(&self.solids as &dyn Contribution)
            .chain(self.contributions.iter().map(|c| c.as_ref()))
    }

    /// Every contribution's outputs, in the order of [`Model::each_ref`] (`None` for one
    /// that publishes nothing).
    fn outputs(&self) -> impl Iterator<Item = Option<&dyn Outputs>> + '_ {
        self.each_ref().map(|c| c.outputs())
    }

    /// Collective: the reference stiffness (the solid elements' tangent at u = 0, one
    /// assembly) and what it says about each node, for the contributions that scale
    /// with the mesh.
    fn set_reference(&mut self, comm: &dyn Comm) {
        let n_local = self.mesh.n_local_nodes();
        let mut factor = vec![1.0f64; n_local];
        for e in 0..self.solids.len() {
            let nu = self.solids.material_defs[self.solids.elements.material[e] as usize].nu();
            let f = (1.0 + nu) * (1.0 - 2.0 * nu) / (1.0 - nu);
            for &n in self.solids.elements.nodes(e) {
                factor[n] = factor[n].min(f);
            }
        }
        let mut k = self.new_matrix(comm);
        k.zero();
        let u0 = vec![0.0; self.dofs.n_local_dofs()];
        // Hybrid elements condensed: their bulk stiffness is in the pressure block, and
        // the contact scales need it on the nodes as F-bar has it.
        self.solids
            .assemble_condensed_tangent(&self.mesh.coords, &self.dofs, &u0, &mut k);
        k.finish_assembly(comm);
        let start = self.dofs.blocks.start();
        let mut k_diag = vec![0.0; n_local];
        let mut sum = [0.0, 0.0];
        for (n, d) in k_diag.iter_mut().enumerate().take(self.mesh.n_owned()) {
            let b = self.dofs.global_block(n);
            *d = k
                .block(b - start, b)
                .map(|b| (b[0] + b[4] + b[8]) / 3.0)
                .unwrap_or(0.0);
            sum[0] += *d;
            sum[1] += 1.0;
        }
        comm.allreduce_sum(&mut sum);
        let r = Reference {
            k_diag: &k_diag,
            e_factor: &factor,
            k_mean: sum[0] / sum[1].max(1.0),
        };
        for s in self.contributions.iter_mut().filter_map(|c| c.scaled()) {
            s.setup(&r);
        }
    }

    /// All unknowns owned here: node dofs, then the contributions' extras.
    pub fn n_owned_dofs(&self) -> usize {
        self.dofs.n_owned_dofs()
    }

    /// Reference coordinates of the owned nodes, whose displacements are the first owned
    /// blocks (AMG's rigid-body modes).
    pub fn node_points(&self) -> crate::linalg::NodePoints {
        std::sync::Arc::new(self.mesh.coords[..self.mesh.n_owned()].to_vec())
    }

    /// The owned node dofs (the first `3 · n_owned` unknowns of the owned range).
    pub fn n_node_dofs(&self) -> usize {
        self.dofs.n_node_dofs()
    }

    /// The owned unknowns that are not node displacements (multipliers, hybrid
    /// pressures, reference point DOFs): algebraic, without mass.
    pub fn extra_range(&self) -> std::ops::Range<usize> {
        self.dofs.extra_range()
    }

    /// Collective: the local vector (owned and ghost blocks) of an owned one.
    pub fn gather(&self, comm: &dyn Comm, u_owned: &[f64], u_local: &mut Vec<f64>) {
        self.dofs.gather(comm, u_owned, u_local);
    }

    /// The prescribed values at time t of the owned constrained dofs: (owned index,
    /// value): supports on node sets, then the contributions' own.
    pub fn prescribed(&self, t: f64) -> Vec<(usize, f64)> {
        let mut out: Vec<(usize, f64)> = self
            .constrained_owned
            .iter()
            .map(|&(d, c)| {
                let con = &self.constraints[c];
                (d, con.value(self.mesh.coords[d / 3], d % 3, t))
            })
            .collect();
        for c in self.each_ref() {
            c.prescribed(t, &self.dofs, &mut out);
        }
        out
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
        self.residual_at(comm, u_owned, t, r, false)
    }

    /// The residual at a perturbed state of a finite-difference product: contributions
    /// keep the branches and state of the last [`Model::residual`] (see
    /// [`Evaluation::frozen`]).
    pub fn residual_frozen(
        &mut self,
        comm: &dyn Comm,
        u_owned: &[f64],
        t: f64,
        r: &mut [f64],
    ) -> Result<ResidualInfo> {
        self.residual_at(comm, u_owned, t, r, true)
    }

    fn residual_at(
        &mut self,
        comm: &dyn Comm,
        u_owned: &[f64],
        t: f64,
        r: &mut [f64],
        frozen: bool,
    ) -> Result<ResidualInfo> {
        let n = u_owned.len();
        let mut fi = vec![0.0; n];
        let info = self.forces_at(comm, u_owned, t, &mut fi, r, frozen)?;
        for i in 0..n {
            r[i] = fi[i] - r[i];
        }
        Ok(info)
    }

    /// Internal and external forces on owned dofs: every contribution evaluated on local
    /// data, then ghost entries summed on their owners. Collective.
    pub fn forces(
        &mut self,
        comm: &dyn Comm,
        u_owned: &[f64],
        t: f64,
        f_int_owned: &mut [f64],
        f_ext_owned: &mut [f64],
    ) -> Result<ResidualInfo> {
        self.forces_at(comm, u_owned, t, f_int_owned, f_ext_owned, false)
    }

    /// [`Model::forces`], frozen as [`Model::residual_frozen`] when asked.
    pub fn forces_at(
        &mut self,
        comm: &dyn Comm,
        u_owned: &[f64],
        t: f64,
        f_int_owned: &mut [f64],
        f_ext_owned: &mut [f64],
        frozen: bool,
    ) -> Result<ResidualInfo> {
        let mut u_local = std::mem::take(&mut self.work);
        self.dofs.gather(comm, u_owned, &mut u_local);
        let nl = u_local.len();
        let mut f_int = vec![0.0; nl];
        let mut f_ext = vec![0.0; nl];
        let failure = self.evaluate_all(&u_local, t, Some((&mut f_int, &mut f_ext)), None, frozen);
        self.dofs.sum_to_owned(comm, &f_int, f_int_owned);
        self.dofs.sum_to_owned(comm, &f_ext, f_ext_owned);
        let mut sums = [0.0, 0.0, if failure.is_some() { 1.0 } else { 0.0 }];
        for i in 0..f_int_owned.len() {
            sums[0] += f_int_owned[i] * f_int_owned[i];
            sums[1] += f_ext_owned[i] * f_ext_owned[i];
        }
        comm.allreduce_sum(&mut sums);
        self.work = u_local;
        if sums[2] > 0.0 {
            let msg = comm.first_message(failure).unwrap_or_default();
            return Err(Error::convergence(format!(
                "residual could not be evaluated: {msg}"
            )));
        }
        Ok(ResidualInfo {
            f_ref: sums[0].sqrt().max(sums[1].sqrt()),
        })
    }

    /// Evaluate every contribution at the local state; the first failure's message.
    fn evaluate_all(
        &mut self,
        u_local: &[f64],
        t: f64,
        mut forces: Option<(&mut [f64], &mut [f64])>,
        mut jacobian: Option<&mut DistMatrix>,
        frozen: bool,
    ) -> Option<String> {
        let (coords, dofs) = (&self.mesh.coords, &self.dofs);
        let mut failure = None;
        let parts = std::iter::once(&mut self.solids as &mut dyn Contribution)
            .chain(self.contributions.iter_mut().map(|c| c.as_mut()));
        for c in parts {
            let mut ev = Evaluation {
                t,
                coords,
                dofs,
                u: u_local,
                forces: forces.as_mut().map(|(a, b)| (&mut **a, &mut **b)),
                jacobian: jacobian.as_deref_mut(),
                frozen,
            };
            if let Err(e) = c.evaluate(&mut ev) {
                failure.get_or_insert(e);
            }
        }
        failure
    }

    /// The sparsity pattern of the Jacobian: the couplings every contribution
    /// declares (collective).
    pub fn new_matrix(&self, comm: &dyn Comm) -> DistMatrix {
        let mut pairs = Vec::new();
        for c in self.each_ref() {
            c.pattern(&self.dofs, &mut pairs);
        }
        pairs.sort_unstable();
        pairs.dedup();
        let mut k = DistMatrix::new(comm, self.dofs.blocks.clone(), &pairs);
        // The hybrid elements' pressure blocks: the solids' owned extras.
        let p = self.dofs.placed(0);
        let first = p.owned_local - self.dofs.n_local_nodes() + self.dofs.n_owned_nodes();
        k.set_element_rows(first..first + p.owned);
        k.set_block_kinds(
            self.dofs.n_owned_nodes(),
            self.dofs.global_blocks(),
            self.node_bodies(),
        );
        k
    }

    /// The part of each owned node (the lowest of the parts of the local elements that
    /// touch it; every owned node is touched by one here): which body a node belongs to,
    /// for the coarse space's components ([`crate::linalg::coarse`]): parts that touch
    /// only through contact move apart rigidly, and their rigid modes are separate.
    pub fn node_bodies(&self) -> Vec<u32> {
        let n = self.mesh.n_owned();
        let mut body = vec![u32::MAX; n];
        let els = &self.solids.elements;
        for e in 0..els.len() {
            let part = els.part.get(e).copied().unwrap_or(0);
            for &a in els.nodes(e) {
                if a < n {
                    body[a] = body[a].min(part);
                }
            }
        }
        body
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
        self.dofs.gather(comm, u_owned, &mut u_local);
        k.zero();
        let failure = self.evaluate_all(&u_local, t, None, Some(k), false);
        k.finish_assembly(comm);
        self.work = u_local;
        if let Some(msg) = comm.first_message(failure) {
            return Err(Error::convergence(format!(
                "Jacobian could not be assembled: {msg}"
            )));
        }
        Ok(())
    }

    /// Collective, after a failed step: the first contribution diagnosis on the lowest
    /// rank that has one (the same text on every rank).
    pub fn diagnose(&self, comm: &dyn Comm) -> Option<String> {
        let mine: Vec<String> = self
            .each_ref()
            .filter_map(|c| c.recovery()?.diagnose())
            .collect();
        comm.first_message((!mine.is_empty()).then(|| mine.join("; ")))
    }

    /// After a failed attempt: each contribution adapts (see
    /// [`contribution::Recovery::after_failed_attempt`]); local, no communication.
    pub fn after_failed_attempt(&mut self) {
        for r in self.each().filter_map(|c| c.recovery_mut()) {
            r.after_failed_attempt();
        }
    }

    /// Every contribution's committed state (the solid elements first): what a restart
    /// file keeps besides the solution.
    pub fn saved_state(&self) -> Vec<Vec<f64>> {
        self.each_ref().map(|c| c.saved_state()).collect()
    }

    /// Take back [`Model::saved_state`] (this rank's); `Err` names the contribution that does
    /// not fit.
    pub fn restore_state(&mut self, s: &[Vec<f64>]) -> Result<()> {
        let n = 1 + self.contributions.len();
        if s.len() != n {
            return Err(Error::input(format!(
                "the restart file has the state of {} contributions, the model {n}",
                s.len()
            )));
        }
        for (c, v) in self.each().zip(s) {
            let name = c.name().to_string();
            c.restore_state(v)
                .map_err(|why| Error::input(format!("restart state of {name}: {why}")))?;
        }
        Ok(())
    }

    /// Accept the state of the last converged evaluation.
    pub fn commit(&mut self) {
        for c in self.each() {
            c.commit();
        }
    }

    /// An explicit run starts: every contribution must be able to take part.
    pub fn start_explicit(&mut self) -> Result<()> {
        for c in self.each() {
            let name = c.name().to_string();
            if let Some(x) = c.explicit() {
                x.start_explicit()
                    .map_err(|why| Error::input(format!("{name}: {why}")))?;
            }
        }
        Ok(())
    }

    /// Explicit runs: kinematic corrections after a step's displacement update (owned
    /// vectors; `v` the mid-step velocity, `m` the lumped mass).
    pub fn kinematic(&mut self, u: &mut [f64], v: &mut [f64], m: &[f64], t: f64, h: f64) {
        let coords = &self.mesh.coords;
        for x in self.contributions.iter_mut().filter_map(|c| c.explicit()) {
            x.kinematic(Kinematic {
                coords,
                u: &mut *u,
                v: &mut *v,
                m,
                t,
                h,
            });
        }
    }

    /// Implicit dynamics after a converged step: velocity and acceleration corrections
    /// (contact persistency; owned dofs, no communication).
    pub fn persistency(&self, v: &mut [f64], a: &mut [f64], t: f64, h: f64) {
        for d in self.each_ref().filter_map(|c| c.dynamics()) {
            d.persistency(v, a, t, h);
        }
    }

    /// Collective: the converged state the contributions publish from (`u_local` holds
    /// the gathered unknowns).
    fn state<'a>(
        &'a self,
        comm: &dyn Comm,
        u_owned: &[f64],
        t: f64,
        u_local: &'a mut Vec<f64>,
    ) -> State<'a> {
        self.dofs.gather(comm, u_owned, u_local);
        State {
            t,
            coords: &self.mesh.coords,
            dofs: &self.dofs,
            u: u_local,
        }
    }

    /// The contributions' history columns (the same on every rank).
    pub fn columns(&self) -> &[Column] {
        &self.columns
    }

    /// Collective: the history values of the contributions' columns at the last
    /// evaluation (u the converged owned unknowns at time t). Two reductions at most.
    pub fn column_values(&self, comm: &dyn Comm, u_owned: &[f64], t: f64) -> Vec<f64> {
        if self.columns.is_empty() {
            return Vec::new();
        }
        let mut u_local = Vec::new();
        let s = self.state(comm, u_owned, t, &mut u_local);
        let mut values = vec![0.0; self.columns.len()];
        let mut seen = vec![false; self.columns.len()];
        for (c, map) in self.outputs().zip(&self.column_map) {
            let Some(c) = c.filter(|_| !map.is_empty()) else {
                continue;
            };
            let mut mine = vec![0.0; map.len()];
            c.column_values(&s, &mut mine);
            for (&i, v) in map.iter().zip(mine) {
                values[i] = match (seen[i], self.columns[i].reduce) {
                    (false, _) => v,
                    (true, Reduce::Max) => values[i].max(v),
                    (true, _) => values[i] + v,
                };
                seen[i] = true;
            }
        }
        let (sum, max): (Vec<usize>, Vec<usize>) = {
            let by = |r: Reduce| -> Vec<usize> {
                (0..values.len())
                    .filter(|&i| self.columns[i].reduce == r)
                    .collect()
            };
            (by(Reduce::Sum), by(Reduce::Max))
        };
        for (idx, reduce) in [(sum, Reduce::Sum), (max, Reduce::Max)] {
            if idx.is_empty() {
                continue;
            }
            let mut buf: Vec<f64> = idx.iter().map(|&i| values[i]).collect();
            match reduce {
                Reduce::Max => comm.allreduce_max(&mut buf),
                _ => comm.allreduce_sum(&mut buf),
            }
            for (&i, v) in idx.iter().zip(buf) {
                values[i] = v;
            }
        }
        values
    }

    /// The summary entries of the contributions from the reduced column values of the
    /// last step: `{group: {name: value}}`.
    pub fn summary(&self, values: &[f64]) -> BTreeMap<String, serde_json::Value> {
        let mut out: BTreeMap<String, serde_json::Map<String, serde_json::Value>> = BTreeMap::new();
        for (c, map) in self.outputs().zip(&self.column_map) {
            let Some(c) = c else { continue };
            let mine: Vec<f64> = map
                .iter()
                .map(|&i| values.get(i).copied().unwrap_or(f64::NAN))
                .collect();
            if let Some((group, name, v)) = c.summary(&mine) {
                out.entry(group.to_string()).or_default().insert(name, v);
            }
        }
        out.into_iter()
            .map(|(k, v)| (k, serde_json::Value::Object(v)))
            .collect()
    }

    /// Collective: the contributions' output fields at the converged owned unknowns
    /// (rows of this rank), merged by name: a field several contributions publish
    /// combines entry by entry.
    pub fn fields(&self, comm: &dyn Comm, u_owned: &[f64], t: f64) -> Vec<Field> {
        let mut u_local = Vec::new();
        let s = self.state(comm, u_owned, t, &mut u_local);
        let rows = |spec: &FieldSpec| match spec.center {
            contribution::Center::Node => self.mesh.n_owned(),
            contribution::Center::Cell => self.solids.len(),
        };
        let mut out: Vec<Field> = Vec::new();
        for c in self.outputs().flatten() {
            let specs = c.fields();
            if specs.is_empty() {
                continue;
            }
            let mut mine: Vec<Vec<f64>> = specs
                .iter()
                .map(|f| vec![f64::NAN; rows(f) * f.width])
                .collect();
            c.field_values(&s, &mut mine);
            for (spec, vals) in specs.into_iter().zip(mine) {
                match out.iter_mut().find(|f| f.spec.name == spec.name) {
                    None => out.push(Field { spec, values: vals }),
                    Some(f) => {
                        for (o, v) in f.values.iter_mut().zip(vals) {
                            if o.is_nan() {
                                *o = v;
                            } else if !v.is_nan() {
                                *o = match f.spec.combine {
                                    contribution::Combine::Sum => *o + v,
                                    contribution::Combine::Min => o.min(v),
                                    contribution::Combine::First => *o,
                                };
                            }
                        }
                    }
                }
            }
        }
        for f in &mut out {
            let empty = f.spec.empty;
            f.values
                .iter_mut()
                .filter(|v| v.is_nan())
                .for_each(|v| *v = empty);
        }
        out
    }

    /// One field by name (this rank's rows), as [`Model::fields`] writes it.
    pub fn field(&self, comm: &dyn Comm, u_owned: &[f64], t: f64, name: &str) -> Option<Vec<f64>> {
        self.fields(comm, u_owned, t)
            .into_iter()
            .find(|f| f.spec.name == name)
            .map(|f| f.values)
    }

    /// The contributions' moving geometry.
    pub fn grids(&self) -> Vec<GridSpec> {
        self.outputs().flatten().flat_map(|c| c.grids()).collect()
    }

    /// The points of every grid at time t, from the reduced column values of that step.
    pub fn grid_points(&self, t: f64, values: &[f64]) -> Vec<Vec<[f64; 3]>> {
        let mut out = Vec::new();
        for (c, map) in self.outputs().zip(&self.column_map) {
            let Some(c) = c else { continue };
            let mine: Vec<f64> = map
                .iter()
                .map(|&i| values.get(i).copied().unwrap_or(f64::NAN))
                .collect();
            for i in 0..c.grids().len() {
                out.push(c.grid_points(i, t, &mine));
            }
        }
        out
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

    /// Mean characteristic element length over the whole model (collective).
    pub fn char_length(&self, comm: &dyn Comm) -> f64 {
        let mut s = [
            self.solids.char_length_sum(&self.mesh.coords),
            self.solids.len() as f64,
        ];
        comm.allreduce_sum(&mut s);
        s[0] / s[1].max(1.0)
    }

    /// Every owned prescribed unknown (the dofs of [`Model::prescribed`]).
    pub fn prescribed_dofs(&self) -> &[usize] {
        &self.prescribed_dofs
    }

    /// Owned constrained node dofs (for `DistMatrix::constrain`).
    pub fn constrained_dofs(&self) -> Vec<usize> {
        self.constrained_owned.iter().map(|&(d, _)| d).collect()
    }
}
