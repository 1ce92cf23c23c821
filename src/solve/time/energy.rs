//! Energy bookkeeping of dynamic runs: kinetic energy ½ vᵀM v, the work of the internal
//! forces and of the external forces (loads and the reactions at prescribed dofs), each
//! accumulated by the trapezoidal rule Σ ½ (f_n + f_{n+1})·Δu, which needs no strain
//! energy function and so holds for any material (plasticity included).
//!
//! Balance: KE + W_int − W_ext − KE₀ = 0 for an exact solution; the reported error is
//! |KE + W_int − W_ext − KE₀| / max(KE, |W_int|, |W_ext|, KE₀).

// Index loops over several dof vectors at once read like the formulas.
#![allow(clippy::needless_range_loop)]

use crate::parallel::Comm;

/// The energies after a step (history columns).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Energies {
    pub kinetic: f64,
    pub internal: f64,
    pub external: f64,
    pub balance: f64,
}

/// Running sums and the forces of the last state (kept in a restart file as is).
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct EnergyAccount {
    ke0: f64,
    w_int: f64,
    w_ext: f64,
    f_int: Vec<f64>,
    f_ext: Vec<f64>,
    pub current: Energies,
}

impl EnergyAccount {
    /// Start from the initial state: its internal force, its external force including
    /// reactions, and its kinetic energy.
    pub fn new(f_int: Vec<f64>, f_ext: Vec<f64>, ke0: f64) -> Self {
        Self {
            ke0,
            w_int: 0.0,
            w_ext: 0.0,
            f_int,
            f_ext,
            current: Energies {
                kinetic: ke0,
                ..Energies::default()
            },
        }
    }

    /// Advance by a step with displacement increment `du` to the state with forces
    /// `f_int`, `f_ext` (reactions included) and velocity `v` with `mv` = M v.
    /// One reduction.
    pub fn step(
        &mut self,
        comm: &dyn Comm,
        du: &[f64],
        f_int: &[f64],
        f_ext: &[f64],
        v: &[f64],
        mv: &[f64],
    ) -> Energies {
        let mut s = [0.0; 3];
        for i in 0..du.len() {
            s[0] += 0.5 * (self.f_int[i] + f_int[i]) * du[i];
            s[1] += 0.5 * (self.f_ext[i] + f_ext[i]) * du[i];
            s[2] += 0.5 * v[i] * mv[i];
        }
        comm.allreduce_sum(&mut s);
        self.w_int += s[0];
        self.w_ext += s[1];
        self.f_int.copy_from_slice(f_int);
        self.f_ext.copy_from_slice(f_ext);
        let ke = s[2];
        let scale = ke.max(self.w_int.abs()).max(self.w_ext.abs()).max(self.ke0);
        let err = (ke + self.w_int - self.w_ext - self.ke0).abs();
        self.current = Energies {
            kinetic: ke,
            internal: self.w_int,
            external: self.w_ext,
            balance: if scale > 0.0 { err / scale } else { 0.0 },
        };
        self.current
    }
}
