//! This rank's F-bar patches of tet4 (`fem::patch`) for the solids contribution: which
//! local elements form each patch, the union of their nodes, and the gather/scatter of
//! nodes and history around `fem::patch`. Every patch is whole on one rank (the
//! partition keeps it so), so no patch needs another rank's elements.

use super::local::LocalElements;
use crate::fem::patch::{self, PatchData};
use crate::material::Material;
use std::collections::BTreeMap;

/// One patch: its elements (local), its nodes (local, the union of theirs) and each
/// tet's nodes as indices into `nodes`.
#[derive(Debug, Clone)]
pub(super) struct Patch {
    pub(super) elems: Vec<usize>,
    pub(super) nodes: Vec<usize>,
    tets: Vec<[usize; 4]>,
    /// Its pressure block among the patches' own blocks (hybrid patches), or none.
    pub(super) own: Option<usize>,
}

/// The patches of this rank and whether each local element is in one.
#[derive(Debug, Clone, Default)]
pub(super) struct Patches {
    pub(super) list: Vec<Patch>,
    pub(super) member: Vec<bool>,
}

/// Per-patch work arrays, reused across patches.
/// A patch force's history: committed values, per-element offsets, a frozen product's
/// branches, and where the trial history goes.
pub(super) type History<'a> = (&'a [f64], &'a [usize], Option<&'a [f64]>, &'a mut [f64]);

#[derive(Default)]
pub(super) struct Scratch {
    x0: Vec<[f64; 3]>,
    u: Vec<[f64; 3]>,
    old: Vec<f64>,
    new: Vec<f64>,
    /// A frozen product's branches (the natural evaluation's trial history).
    branch: Vec<f64>,
    /// The last patch's residual rows and tangent.
    pub(super) f: Vec<f64>,
    pub(super) k: Vec<f64>,
}

impl Patches {
    pub(super) fn new(elements: &LocalElements) -> Self {
        let mut member = vec![false; elements.len()];
        let mut by_patch: BTreeMap<u32, Vec<usize>> = BTreeMap::new();
        for (e, &p) in elements.patch.iter().enumerate() {
            if p != u32::MAX {
                by_patch.entry(p).or_default().push(e);
                member[e] = true;
            }
        }
        let mut n_own = 0;
        let list = by_patch
            .into_values()
            .map(|elems| {
                let own = elements.formulation[elems[0]].is_hybrid().then(|| {
                    n_own += 1;
                    n_own - 1
                });
                let mut nodes: Vec<usize> = Vec::new();
                let tets = elems
                    .iter()
                    .map(|&e| {
                        let en = elements.nodes(e);
                        std::array::from_fn(|a| {
                            nodes.iter().position(|&n| n == en[a]).unwrap_or_else(|| {
                                nodes.push(en[a]);
                                nodes.len() - 1
                            })
                        })
                    })
                    .collect();
                Patch {
                    elems,
                    nodes,
                    tets,
                    own,
                }
            })
            .collect();
        Self { list, member }
    }

    pub(super) fn len(&self) -> usize {
        self.list.len()
    }

    /// Pressure blocks of the hybrid patches.
    pub(super) fn n_own(&self) -> usize {
        self.list.iter().filter(|p| p.own.is_some()).count()
    }

    /// Gather patch `i`'s nodes and committed history into `s`.
    fn gather(
        &self,
        i: usize,
        s: &mut Scratch,
        coords: &[[f64; 3]],
        u: &[f64],
        history: &[f64],
        offset: &[usize],
    ) {
        let p = &self.list[i];
        s.x0.clear();
        s.u.clear();
        for &n in &p.nodes {
            s.x0.push(coords[n]);
            s.u.push([u[3 * n], u[3 * n + 1], u[3 * n + 2]]);
        }
        s.old.clear();
        for &e in &p.elems {
            s.old.extend_from_slice(&history[offset[e]..offset[e + 1]]);
        }
        s.new.resize(s.old.len(), 0.0);
    }

    /// Residual rows (into `s.f`) and, if `want_k`, tangent (into `s.k`) of patch `i`,
    /// with its pressure block `pi` if it is hybrid (`None`: condensed, the F-bar patch);
    /// its elements' trial history goes to `state_new`. An error names the mesh element
    /// (`orig`) that failed. With `branch` (a frozen product) every tet keeps the branch
    /// of that trial history ([`crate::fem::kernel::ElementData::branch`]).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn force(
        &self,
        i: usize,
        s: &mut Scratch,
        coords: &[[f64; 3]],
        u: &[f64],
        mat: &dyn Material,
        pi: Option<&[f64; 3]>,
        (state_old, offset, branch, state_new): History,
        orig: &[u64],
        want_k: bool,
    ) -> Result<(), String> {
        self.gather(i, s, coords, u, state_old, offset);
        let p = &self.list[i];
        s.branch.clear();
        if let Some(b) = branch {
            for &e in &p.elems {
                s.branch.extend_from_slice(&b[offset[e]..offset[e + 1]]);
            }
        }
        let dofs = 3 * p.nodes.len() + if pi.is_some() { 3 } else { 0 };
        s.f.resize(dofs, 0.0);
        s.k.resize(if want_k { dofs * dofs } else { 0 }, 0.0);
        let data = PatchData {
            x0: &s.x0,
            u: &s.u,
            tets: &p.tets,
            mat,
            state_old: &s.old,
            branch: branch.map(|_| &s.branch[..]),
        };
        let k = if want_k { Some(&mut s.k[..]) } else { None };
        patch::force(&data, pi, &mut s.new, &mut s.f, k).map_err(|e| {
            format!(
                "element {} (in an F-bar patch): {}",
                orig[p.elems[e.tet]], e.error
            )
        })?;
        let mut at = 0;
        for &e in &p.elems {
            let len = offset[e + 1] - offset[e];
            state_new[offset[e]..offset[e + 1]].copy_from_slice(&s.new[at..at + len]);
            at += len;
        }
        Ok(())
    }

    /// Cauchy stress of every element of patch `i` at the committed history, written
    /// into `out` by local element (NaN if the patch cannot be evaluated).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn stresses(
        &self,
        i: usize,
        s: &mut Scratch,
        coords: &[[f64; 3]],
        u: &[f64],
        mat: &dyn Material,
        pi: Option<f64>,
        (history, offset): (&[f64], &[usize]),
        out: &mut [[f64; 6]],
    ) {
        self.gather(i, s, coords, u, history, offset);
        let p = &self.list[i];
        let data = PatchData {
            x0: &s.x0,
            u: &s.u,
            tets: &p.tets,
            mat,
            state_old: &s.old,
            branch: None,
        };
        match patch::stresses(&data, pi) {
            Ok(sig) => {
                for (&e, v) in p.elems.iter().zip(sig) {
                    out[e] = v;
                }
            }
            Err(_) => {
                for &e in &p.elems {
                    out[e] = [f64::NAN; 6];
                }
            }
        }
    }
}
