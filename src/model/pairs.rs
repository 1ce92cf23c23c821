//! Small-sliding contact between deformable parts (paper §3.7): a `[[pairs]]` entry is a
//! list of pairs, each a tracked node paired once with a point on a reference face of
//! another part ([`crate::contact::pair`] evaluates one). Each pair is a stencil (the
//! node and the face's nodes), evaluated on the rank that owns the node, which also
//! owns its multipliers; the face's nodes are ghosts there where another rank owns
//! them, and their rows are sent to their owners by the matrix and the residual sum.

// Index loops over small blocks read like the formulas.
#![allow(clippy::needless_range_loop)]

use super::contribution::{
    Center, Column, Combine, Contribution, Evaluation, Explicit, FieldSpec, Outputs, Recovery,
    Reduce, Reference, Scaled, State, SummaryEntry,
};
use super::dofs::{DofMap, Unknowns};
use super::kind::{ContributionKind, Localizer};
use super::local::{LocalElements, LocalMesh};
use super::walls::{soften_cycling, CYCLING_FLIPS};
use crate::contact::law::{AlmLaw, Branch, Decision, Threshold};
use crate::contact::pair::{evaluate, Offsets, PairLaw};
use crate::contact::penalty::{PenaltyLaw, SLIP_TOLERANCE};
use crate::contact::wall::ContactMethod;
use crate::curve::Curve;
use serde::{Deserialize, Serialize};

/// One pair: the tracked node, its reference nodes with their weights in x_m and the
/// shape-function derivatives that give the frame (see [`crate::contact::pair`]), and
/// the node's area (tributary or mortar; 0 where unknown).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Pair {
    pub node: usize,
    pub nodes: Vec<usize>,
    pub w: Vec<f64>,
    pub dn: Vec<[f64; 2]>,
    pub area: f64,
}

/// What the deck says about a list of pairs, with the pairs found at the start.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PairsDef {
    pub name: String,
    pub method: ContactMethod,
    /// Bonded in all directions (no separation, no slip).
    pub tied: bool,
    pub friction: f64,
    pub kappa: Option<f64>,
    pub penalty_scale: f64,
    pub tangential_augmentation: f64,
    pub friction_threshold: Threshold,
    /// The deck's tracked and reference surface names (for messages).
    pub tracked: String,
    pub reference: String,
    pub pairs: Vec<Pair>,
    /// Tracked nodes left without a pair (no reference face within reach).
    pub unpaired: usize,
    /// The deck's pairing choices, kept so that `alfe export` can write the deck back:
    /// its search distance (None: the default) and whether the weights are mortar
    /// integrals (else node-to-face).
    #[serde(default)]
    pub search_distance: Option<f64>,
    #[serde(default)]
    pub mortar: bool,
    /// A bolt's pretension section: tied pairs whose normal gap is shifted by one global
    /// unknown s, the section's shortening.
    #[serde(default)]
    pub pretension: Option<Pretension>,
    /// The mean size of the contact faces (the tracked surface's, else the reference
    /// ones'): penalty friction's allowable elastic slip is
    /// [`crate::contact::penalty::SLIP_TOLERANCE`] of it.
    #[serde(default)]
    pub face_size: f64,
}

/// A pretension section (Abaqus `*PRE-TENSION SECTION`, LS-DYNA
/// `*INITIAL_STRESS_SECTION`): until `lock_at` the shortening s is free and the
/// section carries the tension `force × curve(t)` (the sum of its pairs' normal forces
/// pulls the two sides together by that much); from `lock_at` on s keeps the value it
/// reached, and the bolt's force follows the service loads.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Pretension {
    pub force: f64,
    pub curve: Curve,
    pub lock_at: f64,
    /// The rank that owns s (the one with most of the section's pairs).
    pub owner: usize,
}

impl ContributionKind for PairsDef {
    fn kind_name(&self) -> &'static str {
        "pairs"
    }
    fn name(&self) -> &str {
        &self.name
    }
    fn describe(&self) -> String {
        if let Some(p) = &self.pretension {
            return format!(
                "bolt {}: pretension {} locked at t = {}, section {} tied to {} ({} pairs{})",
                self.name,
                p.force,
                p.lock_at,
                self.tracked,
                self.reference,
                self.pairs.len(),
                if self.unpaired > 0 {
                    format!(", {} nodes left without a face in reach", self.unpaired)
                } else {
                    String::new()
                }
            );
        }
        format!(
            "pairs {}: {}{}, μ = {}, {} tracked nodes of {} paired with faces of {}{}",
            self.name,
            self.method.name(),
            if self.tied { " tied" } else { "" },
            self.friction,
            self.pairs.len(),
            self.tracked,
            self.reference,
            if self.unpaired > 0 {
                format!(" ({} left without a face in reach)", self.unpaired)
            } else {
                String::new()
            }
        )
    }
    fn nodes(&self) -> Vec<usize> {
        self.pairs.iter().map(|p| p.node).collect()
    }
    fn extra_unknowns(&self) -> usize {
        let s = if self.pretension.is_some() { 3 } else { 0 };
        s + if self.method == ContactMethod::Alm {
            3 * self.pairs.len()
        } else {
            0
        }
    }
    fn stencils(&self) -> Vec<Vec<usize>> {
        self.pairs
            .iter()
            .map(|p| {
                std::iter::once(p.node)
                    .chain(p.nodes.iter().copied())
                    .collect()
            })
            .collect()
    }
    /// The pairs whose tracked node this rank owns, in local node numbers (the face's
    /// nodes are local here: the stencil made them ghosts where owned elsewhere).
    fn localize(&self, l: &Localizer) -> Self {
        let mut mine: Vec<Pair> = self
            .pairs
            .iter()
            .filter_map(|p| {
                l.owned(p.node).map(|node| Pair {
                    node,
                    nodes: p.nodes.iter().map(|&n| l.local_of[n]).collect(),
                    ..p.clone()
                })
            })
            .collect();
        mine.sort_by_key(|p| p.node);
        // s belongs to the rank owning most of the section's tracked nodes (the lowest
        // on a tie): the same on every rank.
        let pretension = self.pretension.as_ref().map(|p| {
            let mut per_rank = vec![0usize; l.ranks];
            for q in &self.pairs {
                per_rank[l.owner[q.node] as usize] += 1;
            }
            let owner = (0..l.ranks).fold(0, |b, r| if per_rank[r] > per_rank[b] { r } else { b });
            Pretension { owner, ..p.clone() }
        });
        Self {
            pairs: mine,
            pretension,
            ..self.clone()
        }
    }
    fn build(&self, _mesh: &LocalMesh, _elements: &LocalElements) -> Box<dyn Contribution> {
        Box::new(Pairs::new(self.clone()))
    }
}

impl PairsDef {
    /// Whether it can take part in an explicit analysis (else why not): the check of
    /// its runtime's [`Explicit::start_explicit`].
    fn explicit_ok(&self) -> Result<(), String> {
        Err(format!(
            "pairs `{}`: small-sliding pairs take part in static analyses and implicit dynamics",
            self.name
        ))
    }
}

/// What one pair did at the last evaluation.
#[derive(Debug, Clone, Copy, Default)]
struct PairState {
    gap: f64,
    force: [f64; 3],
    normal_force: f64,
    /// |tangential part of d − d₀|: how far the node slid on its face since the start.
    slip: f64,
    active: bool,
    sticking: bool,
    branch: Branch,
    /// Where the tracked node is (for messages).
    x: [f64; 3],
}

/// One `[[pairs]]` entry on this rank (the pairs of its owned tracked nodes).
#[derive(Debug)]
pub struct Pairs {
    def: PairsDef,
    /// Local block of the first multiplier (ALM).
    mult: Option<usize>,
    kappa: Vec<f64>,
    k_node: Vec<f64>,
    /// d = x_s − x_m of each pair at the start (the tie's offset), at the start of the
    /// step and at the last evaluation.
    d0: Vec<[f64; 3]>,
    d_old: Vec<[f64; 3]>,
    d_new: Vec<[f64; 3]>,
    /// Penalty's elastic slip carried over steps (global, see
    /// [`crate::contact::penalty`]).
    slip_old: Vec<[f64; 3]>,
    slip_new: Vec<[f64; 3]>,
    last: Vec<PairState>,
    /// Stick/slip flips of each pair since the last commit.
    flips: Vec<u32>,
    /// Penalty: each pair's factor on its stick stiffness μ f_N / δ, lowered for a pair
    /// that cycled in a failed attempt (as the walls' nodes, see
    /// [`super::walls`]), kept for the rest of the run.
    stick_scale: Vec<f64>,
    started: bool,
    /// A pretension section: the local block of s (its first component), whether this
    /// rank owns it, the time of the last evaluation, and s where it was locked.
    s_block: Option<usize>,
    s_owner: bool,
    t_new: f64,
    s_new: f64,
    s_lock: Option<f64>,
}

impl Pairs {
    pub fn new(def: PairsDef) -> Self {
        let n = def.pairs.len();
        Self {
            mult: None,
            kappa: vec![def.kappa.unwrap_or(1.0); n],
            k_node: vec![1.0; n],
            d0: vec![[0.0; 3]; n],
            d_old: vec![[0.0; 3]; n],
            d_new: vec![[0.0; 3]; n],
            slip_old: vec![[0.0; 3]; n],
            slip_new: vec![[0.0; 3]; n],
            last: vec![PairState::default(); n],
            flips: vec![0; n],
            stick_scale: vec![1.0; n],
            started: false,
            s_block: None,
            s_owner: false,
            t_new: 0.0,
            s_new: 0.0,
            s_lock: None,
            def,
        }
    }

    fn is_alm(&self) -> bool {
        self.def.method == ContactMethod::Alm
    }

    /// Frictional penalty pairs: their stick is softened where it cycles.
    fn softens(&self) -> bool {
        self.def.method == ContactMethod::Penalty && !self.def.tied && self.def.friction > 0.0
    }

    fn law(&self, j: usize) -> PairLaw {
        let kp = self.def.penalty_scale * self.k_node[j];
        match (self.def.method, self.def.tied) {
            (ContactMethod::Alm, false) => PairLaw::Alm {
                law: AlmLaw {
                    mu: self.def.friction,
                    alpha: self.def.tangential_augmentation,
                    threshold: self.def.friction_threshold,
                },
                kappa: self.kappa[j],
            },
            (ContactMethod::Alm, true) => PairLaw::TiedAlm {
                kappa: self.kappa[j],
            },
            (ContactMethod::Penalty, false) => PairLaw::Penalty {
                law: PenaltyLaw {
                    kn: kp,
                    mu: self.def.friction,
                    slip: SLIP_TOLERANCE * self.def.face_size,
                    stick_scale: self.stick_scale[j],
                },
                e_old: self.slip_old[j],
            },
            (ContactMethod::Penalty, true) => PairLaw::TiedPenalty { kp },
        }
    }

    /// The pair's node then face positions.
    fn positions(&self, j: usize, coords: &[[f64; 3]], u: &[f64]) -> Vec<[f64; 3]> {
        let p = &self.def.pairs[j];
        std::iter::once(p.node)
            .chain(p.nodes.iter().copied())
            .map(|n| std::array::from_fn(|c| coords[n][c] + u[3 * n + c]))
            .collect()
    }

    /// d at the reference configuration (u = 0) of every pair.
    fn start(&mut self, coords: &[[f64; 3]]) {
        let zero = vec![0.0; 3 * coords.len()];
        for j in 0..self.def.pairs.len() {
            let x = self.positions(j, coords, &zero);
            let p = &self.def.pairs[j];
            let e = evaluate(
                &x,
                &p.w,
                &p.dn,
                [0.0; 3],
                &Offsets {
                    c_n: [0.0; 3],
                    c_t: [0.0; 3],
                    shift: 0.0,
                },
                &PairLaw::TiedPenalty { kp: 0.0 },
                Decision::Natural,
            );
            self.d0[j] = e.d;
            self.d_old[j] = e.d;
            self.d_new[j] = e.d;
        }
        self.started = true;
    }
}

/// Column layout: force on the tracked side (3), active pairs, largest slip, for a
/// pretension section its tension and shortening, then the shared ones.
impl Pairs {
    fn n_own_columns(&self) -> usize {
        5 + 2 * self.def.pretension.is_some() as usize
    }
}

impl Contribution for Pairs {
    fn name(&self) -> &str {
        &self.def.name
    }

    /// ALM (tied or not): three multipliers per pair, owned with its tracked node.
    fn unknowns(&self) -> Unknowns {
        let owned = if self.is_alm() {
            self.def.pairs.len()
        } else {
            0
        };
        match &self.def.pretension {
            Some(p) => Unknowns {
                owned,
                global: 1,
                owner: p.owner,
                reads_global: true,
            },
            None => Unknowns {
                owned,
                ..Unknowns::default()
            },
        }
    }

    fn bind(&mut self, dofs: &DofMap, index: usize) {
        let placed = dofs.placed(index);
        if self.is_alm() {
            self.mult = Some(placed.owned_local);
        }
        if self.def.pretension.is_some() {
            self.s_block = Some(
                dofs.local_block(placed.global_first)
                    .expect("every rank reads a section's shortening"),
            );
            self.s_owner = dofs.owned_index(3 * self.s_block.unwrap_or(0)).is_some();
        }
    }

    fn pattern(&self, dofs: &DofMap, out: &mut Vec<(usize, usize)>) {
        for (j, p) in self.def.pairs.iter().enumerate() {
            let mut blocks: Vec<usize> = std::iter::once(p.node)
                .chain(p.nodes.iter().copied())
                .map(|n| dofs.global_block(n))
                .collect();
            if let Some(m0) = self.mult {
                blocks.push(dofs.global_block(m0 + j));
            }
            for &a in &blocks {
                for &b in &blocks {
                    out.push((a, b));
                }
            }
            if let Some(sb) = self.s_block {
                let s = dofs.global_block(sb);
                for &a in &blocks {
                    out.extend_from_slice(&[(a, s), (s, a)]);
                }
            }
        }
        if let Some(sb) = self.s_block {
            if self.s_owner || !self.def.pairs.is_empty() {
                let s = dofs.global_block(sb);
                out.push((s, s));
            }
        }
    }

    /// A section's shortening: its two unused components always, and s itself from the
    /// lock on (the value it had then).
    fn prescribed(&self, _t: f64, dofs: &DofMap, out: &mut Vec<(usize, f64)>) {
        let Some(sb) = self.s_block.filter(|_| self.s_owner) else {
            return;
        };
        let i = dofs.owned_index(3 * sb).expect("the owner owns s");
        out.extend_from_slice(&[(i + 1, 0.0), (i + 2, 0.0)]);
        if let Some(s) = self.s_lock {
            out.push((i, s));
        }
    }

    /// The tracked nodes' forces count as external, the face nodes' reactions too (the
    /// pair exerts no net force); multiplier rows (−κ h) go with the internal forces.
    fn evaluate(&mut self, ev: &mut Evaluation) -> Result<(), String> {
        if !self.started {
            self.start(ev.coords);
        }
        self.t_new = ev.t;
        let s = self.s_block.map_or(0.0, |sb| ev.u[3 * sb]);
        if let (Some(sb), Some(p)) = (self.s_block, &self.def.pretension) {
            if self.s_owner {
                // r_s = Σ f_N + T(t): the section's pairs pull its sides together by T.
                if let Some((_, f_ext)) = ev.forces.as_mut() {
                    f_ext[3 * sb] -= p.force * p.curve.eval(ev.t);
                }
                if let Some(k) = ev.jacobian.as_deref_mut() {
                    let g = ev.dofs.global_block(sb);
                    // Jacobian-only diagonal on the two unused (prescribed) components.
                    let mean = self.kappa.iter().sum::<f64>() / self.kappa.len().max(1) as f64;
                    let d = (1e-8 * mean).max(f64::MIN_POSITIVE);
                    k.add_block(g, g, &[0.0, 0.0, 0.0, 0.0, d, 0.0, 0.0, 0.0, d]);
                }
            }
            if !ev.frozen {
                self.s_new = s;
            }
        }
        for j in 0..self.def.pairs.len() {
            let x = self.positions(j, ev.coords, ev.u);
            let lam = match self.mult {
                Some(m0) => {
                    let b = 3 * (m0 + j);
                    [ev.u[b], ev.u[b + 1], ev.u[b + 2]]
                }
                None => [0.0; 3],
            };
            let (c_n, c_t) = if self.def.tied {
                (self.d0[j], self.d0[j])
            } else {
                ([0.0; 3], self.d_old[j])
            };
            let decision = if ev.frozen {
                Decision::Forced(self.last[j].branch)
            } else {
                Decision::Natural
            };
            let law = self.law(j);
            let p = &self.def.pairs[j];
            let e = evaluate(
                &x,
                &p.w,
                &p.dn,
                lam,
                &Offsets { c_n, c_t, shift: s },
                &law,
                decision,
            );
            let nodes: Vec<usize> = std::iter::once(p.node)
                .chain(p.nodes.iter().copied())
                .collect();
            let np = nodes.len();
            if let Some((f_int, f_ext)) = ev.forces.as_mut() {
                for (q, &n) in nodes.iter().enumerate() {
                    for c in 0..3 {
                        f_ext[3 * n + c] -= e.r[3 * q + c];
                    }
                }
                if let Some(m0) = self.mult {
                    for c in 0..3 {
                        f_int[3 * (m0 + j) + c] += e.r[3 * np + c];
                    }
                }
                if let Some(sb) = self.s_block {
                    f_int[3 * sb] += e.normal_force;
                }
            }
            if let Some(k) = ev.jacobian.as_deref_mut() {
                let mut blocks: Vec<usize> =
                    nodes.iter().map(|&n| ev.dofs.global_block(n)).collect();
                if let Some(m0) = self.mult {
                    blocks.push(ev.dofs.global_block(m0 + j));
                }
                let nr = 3 * blocks.len();
                for (bi, &a) in blocks.iter().enumerate() {
                    for (bj, &b) in blocks.iter().enumerate() {
                        let blk: [f64; 9] =
                            std::array::from_fn(|t| e.k[(3 * bi + t / 3) * nr + 3 * bj + t % 3]);
                        k.add_block(a, b, &blk);
                    }
                }
                if let Some(sb) = self.s_block {
                    let sg = ev.dofs.global_block(sb);
                    for (bi, &a) in blocks.iter().enumerate() {
                        let col: [f64; 9] = std::array::from_fn(|t| {
                            if t % 3 == 0 {
                                e.dr_ds[3 * bi + t / 3]
                            } else {
                                0.0
                            }
                        });
                        k.add_block(a, sg, &col);
                        let row: [f64; 9] =
                            std::array::from_fn(|t| if t < 3 { e.dfn[3 * bi + t] } else { 0.0 });
                        k.add_block(sg, a, &row);
                    }
                    let mut ss = [0.0; 9];
                    ss[0] = e.dfn_ds;
                    k.add_block(sg, sg, &ss);
                }
            }
            if ev.frozen {
                continue;
            }
            self.d_new[j] = e.d;
            self.slip_new[j] = e.elastic_slip;
            let was = self.last[j];
            if was.active && e.active && was.sticking != e.sticking {
                self.flips[j] += 1;
            }
            self.last[j] = PairState {
                gap: e.gap,
                force: e.force,
                normal_force: e.normal_force,
                slip: {
                    let s: [f64; 3] = std::array::from_fn(|c| e.d[c] - self.d0[j][c]);
                    let [_, t1, t2] = e.frame;
                    let dot = |a: [f64; 3]| a[0] * s[0] + a[1] * s[1] + a[2] * s[2];
                    dot(t1).hypot(dot(t2))
                },
                active: e.active,
                sticking: e.sticking,
                branch: e.branch,
                x: x[0],
            };
        }
        Ok(())
    }

    /// `[started, t, s, locked, s_lock, d0 (3 n), d_old (3 n), slip_old (3 n: penalty's
    /// elastic slip), (active, sticking, stick_scale) (3 n)]`: contact and stick at the
    /// last evaluation, against which the next step counts stick/slip flips.
    fn saved_state(&self) -> Vec<f64> {
        let mut s = vec![
            f64::from(u8::from(self.started)),
            self.t_new,
            self.s_new,
            f64::from(u8::from(self.s_lock.is_some())),
            self.s_lock.unwrap_or(0.0),
        ];
        for v in [&self.d0, &self.d_old, &self.slip_old] {
            s.extend(v.iter().flatten());
        }
        for (c, k) in self.last.iter().zip(&self.stick_scale) {
            s.extend([
                f64::from(u8::from(c.active)),
                f64::from(u8::from(c.sticking)),
                *k,
            ]);
        }
        s
    }

    fn restore_state(&mut self, s: &[f64]) -> Result<(), String> {
        let n = self.d0.len();
        if s.len() != 5 + 12 * n {
            return Err(format!("{} values for {} expected", s.len(), 5 + 12 * n));
        }
        self.started = s[0] != 0.0;
        self.t_new = s[1];
        self.s_new = s[2];
        self.s_lock = (s[3] != 0.0).then_some(s[4]);
        for j in 0..n {
            let at = |o: usize| [s[o + 3 * j], s[o + 3 * j + 1], s[o + 3 * j + 2]];
            self.d0[j] = at(5);
            self.d_old[j] = at(5 + 3 * n);
            self.slip_old[j] = at(5 + 6 * n);
            let [active, sticking, k] = at(5 + 9 * n);
            self.last[j].active = active != 0.0;
            self.last[j].sticking = sticking != 0.0;
            self.stick_scale[j] = k;
        }
        self.d_new.copy_from_slice(&self.d_old);
        self.slip_new.copy_from_slice(&self.slip_old);
        self.flips.iter_mut().for_each(|f| *f = 0);
        Ok(())
    }

    fn commit(&mut self) {
        self.d_old.copy_from_slice(&self.d_new);
        self.slip_old.copy_from_slice(&self.slip_new);
        self.flips.iter_mut().for_each(|f| *f = 0);
        if let Some(p) = &self.def.pretension {
            if self.s_lock.is_none() && self.t_new >= p.lock_at - 1e-12 * p.lock_at.abs().max(1.0) {
                self.s_lock = Some(self.s_new);
            }
        }
    }

    fn scaled(&mut self) -> Option<&mut dyn Scaled> {
        Some(self)
    }
    fn outputs(&self) -> Option<&dyn Outputs> {
        Some(self)
    }
    fn explicit(&mut self) -> Option<&mut dyn Explicit> {
        Some(self)
    }
    fn recovery(&self) -> Option<&dyn Recovery> {
        Some(self)
    }
    fn recovery_mut(&mut self) -> Option<&mut dyn Recovery> {
        Some(self)
    }
}

impl Recovery for Pairs {
    /// Penalty pairs with friction: stick/slip cycling as for walls, pairs that switched
    /// between stick and slip at least [`CYCLING_FLIPS`] times since the step began.
    /// (ALM pairs report nothing and keep their stick stiffness, as before.)
    fn diagnose(&self) -> Option<String> {
        if !self.softens() {
            return None;
        }
        let cycling: Vec<usize> = (0..self.flips.len())
            .filter(|&j| self.flips[j] >= CYCLING_FLIPS)
            .collect();
        let worst = *cycling.iter().max_by_key(|&&j| self.flips[j])?;
        let x = self.last[worst].x;
        Some(format!(
            "stick/slip cycling at pairs `{}`: {} pair(s) switched between stick and slip {CYCLING_FLIPS} or more times in this step, one {} times at ({:.4e}, {:.4e}, {:.4e})",
            self.def.name,
            cycling.len(),
            self.flips[worst],
            x[0],
            x[1],
            x[2]
        ))
    }

    /// A penalty pair that cycled gets its stick stiffness × 0.3, twice at most, as a
    /// wall's node does.
    fn after_failed_attempt(&mut self) -> bool {
        self.softens() && soften_cycling(&self.flips, &mut self.stick_scale, &mut self.slip_old)
    }
}

impl Explicit for Pairs {
    /// Small-sliding pairs take no part in explicit runs (their multipliers carry no
    /// mass); the deck does not refuse the combination, so this does.
    fn start_explicit(&mut self) -> Result<(), String> {
        self.def.explicit_ok()
    }
}

impl Scaled for Pairs {
    fn wants_reference(&self) -> bool {
        !self.def.pairs.is_empty()
    }

    /// κ and the penalty stiffness from the tracked node's stiffness, as for walls (see
    /// [`super::walls`]): κ scaled from the P-wave modulus down to Young's modulus.
    fn setup(&mut self, r: &Reference) {
        for (j, p) in self.def.pairs.iter().enumerate() {
            let (k, kappa) = r.contact_scales(p.node);
            self.k_node[j] = k;
            if self.def.kappa.is_none() {
                self.kappa[j] = kappa;
            }
        }
    }
}

impl Outputs for Pairs {
    /// `<pairs>.fx/.fy/.fz`: the force on the tracked side (its reaction on the
    /// reference side is opposite), `<pairs>.active`, `<pairs>.max_slip` (the largest
    /// tangential relative displacement since the start), and the shared `max_penetration`,
    /// `contact_active` and `contact_sticking` (tied pairs count as active and
    /// sticking).
    fn columns(&self) -> Vec<Column> {
        let w = &self.def.name;
        let mut c: Vec<Column> = ["fx", "fy", "fz"]
            .iter()
            .map(|s| Column::sum(format!("{w}.{s}")))
            .collect();
        c.push(Column {
            count: true,
            ..Column::sum(format!("{w}.active"))
        });
        c.push(Column {
            reduce: Reduce::Max,
            run_max: true,
            ..Column::sum(format!("{w}.max_slip"))
        });
        if self.def.pretension.is_some() {
            c.push(Column::sum(format!("{w}.force")));
            c.push(Column::sum(format!("{w}.shortening")));
        }
        c.push(Column {
            reduce: Reduce::Max,
            shared: true,
            run_max: true,
            ..Column::sum("max_penetration")
        });
        for name in ["contact_active", "contact_sticking"] {
            c.push(Column {
                shared: true,
                count: true,
                ..Column::sum(name)
            });
        }
        c
    }

    fn column_values(&self, _s: &State, out: &mut [f64]) {
        let own = self.n_own_columns();
        let bolt = self.def.pretension.is_some();
        if bolt && self.s_owner {
            out[6] = self.s_new;
        }
        for p in &self.last {
            for i in 0..3 {
                out[i] += p.force[i];
            }
            out[4] = out[4].max(p.slip);
            if bolt {
                out[5] -= p.normal_force;
            }
            if p.active {
                out[3] += 1.0;
                out[own + 1] += 1.0;
            }
            if !self.def.tied && p.gap < 0.0 {
                out[own] = out[own].max(-p.gap);
            }
            if p.sticking {
                out[own + 2] += 1.0;
            }
        }
    }

    fn summary(&self, values: &[f64]) -> Option<SummaryEntry> {
        let mut v = serde_json::json!({
            "force": [values[0], values[1], values[2]],
            "active": values[3],
            "max_slip": values[4],
            "pairs": self.def.pairs.len(),
        });
        if self.def.pretension.is_some() {
            v["bolt_force"] = values[5].into();
            v["shortening"] = values[6].into();
        }
        Some(("pairs", self.def.name.clone(), v))
    }

    /// On the tracked nodes: the normal gap, the pressure (normal force / tributary
    /// area) and the force, combined with the walls' fields of the same names.
    fn fields(&self) -> Vec<FieldSpec> {
        let node = |name: &str, width, combine, empty| FieldSpec {
            name: name.into(),
            center: Center::Node,
            width,
            combine,
            empty,
        };
        vec![
            node("contact_gap", 1, Combine::Min, f64::NAN),
            node("contact_pressure", 1, Combine::Sum, 0.0),
            node("contact_force", 3, Combine::Sum, 0.0),
        ]
    }

    fn field_values(&self, _s: &State, out: &mut [Vec<f64>]) {
        for (p, c) in self.def.pairs.iter().zip(&self.last) {
            let n = p.node;
            out[0][n] = c.gap;
            out[1][n] = if p.area > 0.0 {
                c.normal_force / p.area
            } else {
                0.0
            };
            out[2][3 * n..3 * n + 3].copy_from_slice(&c.force);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::pair::face_shape;
    use crate::parallel::run_ranks;

    /// A frictional penalty pair (k_N = 1, μ = 0.5, faces of size 1: δ = 0.005): its
    /// node pressed 0.1 through a unit face and slid along it step by step sticks while
    /// the elastic slip carried across commits stays below δ, then slips at μ f_N; the
    /// state survives a restart round trip, and a cycling pair is reported and softened.
    #[test]
    fn a_penalty_pair_carries_its_elastic_slip_and_softens_where_it_cycles() {
        run_ranks(1, |c| {
            let (w, dn) = face_shape(4, [0.0, 0.0]);
            let def = PairsDef {
                name: "p".into(),
                method: ContactMethod::Penalty,
                tied: false,
                friction: 0.5,
                kappa: None,
                penalty_scale: 1.0,
                tangential_augmentation: 1.0,
                friction_threshold: Threshold::Multiplier,
                tracked: "t".into(),
                reference: "r".into(),
                pairs: vec![Pair {
                    node: 0,
                    nodes: vec![1, 2, 3, 4],
                    w,
                    dn,
                    area: 1.0,
                }],
                unpaired: 0,
                search_distance: None,
                mortar: false,
                pretension: None,
                face_size: 1.0,
            };
            let coords = [
                [0.5, 0.5, 0.0],
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ];
            let dofs = DofMap::new(c, &[5], &[], &[Unknowns::default()]);
            let fresh = || {
                let mut p = Pairs::new(def.clone());
                p.bind(&dofs, 0);
                p
            };
            let eval = |p: &mut Pairs, ux: f64| {
                let mut u = [0.0; 15];
                (u[0], u[2]) = (ux, -0.1);
                let (mut fi, mut fe) = ([0.0; 15], [0.0; 15]);
                let mut ev = Evaluation {
                    t: 0.0,
                    coords: &coords,
                    dofs: &dofs,
                    u: &u,
                    forces: Some((&mut fi, &mut fe)),
                    jacobian: None,
                    frozen: false,
                };
                p.evaluate(&mut ev).unwrap();
                p.last[0]
            };
            let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
            let mut p = fresh();
            let s = eval(&mut p, 0.002);
            assert!(
                s.active && s.sticking && close(s.normal_force, 0.1),
                "{s:?}"
            );
            assert!(close(s.force[0], -10.0 * 0.002), "{s:?}");
            p.commit();
            let s = eval(&mut p, 0.004);
            assert!(s.sticking && close(s.force[0], -10.0 * 0.004), "{s:?}");
            p.commit();
            let saved = p.saved_state();
            let slip = eval(&mut p, 0.006);
            assert!(!slip.sticking && close(slip.force[0], -0.05), "{slip:?}");
            let mut r = fresh();
            r.restore_state(&saved).unwrap();
            assert_eq!(eval(&mut r, 0.006).force, slip.force);
            // Back and forth across the cone within one step: reported, then softened.
            for k in 0..8 {
                eval(&mut p, if k % 2 == 0 { 0.004 } else { 0.006 });
            }
            let why = p.diagnose().expect("cycling is reported");
            assert!(
                why.contains("pairs `p`") && why.contains("1 pair(s)"),
                "{why}"
            );
            assert!(p.after_failed_attempt());
            assert!(p.after_failed_attempt());
            assert!(!p.after_failed_attempt());
            assert!(close(p.stick_scale[0], 0.09));
            // The committed state keeps its force (its carried slip grew by 1 / 0.09).
            let s = eval(&mut p, 0.004);
            assert!(s.sticking && close(s.force[0], -10.0 * 0.004), "{s:?}");
            let soft = p.saved_state();
            let mut r = fresh();
            r.restore_state(&soft).unwrap();
            assert!(close(r.stick_scale[0], 0.09));
            p.commit();
            assert!(p.diagnose().is_none());
        });
    }
}
