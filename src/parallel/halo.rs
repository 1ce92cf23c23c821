//! Halo (ghost) exchange plans over a [`Layout`].
//!
//! A rank holds its owned entries plus copies of some entries owned elsewhere (ghosts).
//! `forward` refreshes the ghost copies from their owners (before a matrix-vector
//! product or an element loop); `reverse_add` sends ghost contributions to the owners
//! and adds them there (after an element loop). Plans are built once from the sorted
//! list of ghost global indices; the exchange is one `alltoallv`.

use super::{Comm, Layout};

#[derive(Debug, Clone)]
pub struct HaloPlan {
    /// Global indices of the ghosts, sorted ascending (hence grouped by owner).
    pub ghosts: Vec<usize>,
    /// How many ghosts come from each rank.
    recv_counts: Vec<usize>,
    /// Owned local offsets (index - layout.start()) to send, grouped by destination.
    send_idx: Vec<usize>,
    send_counts: Vec<usize>,
}

impl HaloPlan {
    /// Collective. `ghosts` must be sorted, unique and not owned by this rank.
    pub fn new(comm: &dyn Comm, layout: &Layout, ghosts: Vec<usize>) -> Self {
        debug_assert!(ghosts.windows(2).all(|w| w[0] < w[1]));
        debug_assert!(ghosts.iter().all(|&g| !layout.owns(g)));
        let p = comm.size();
        let mut recv_counts = vec![0usize; p];
        for &g in &ghosts {
            recv_counts[layout.owner(g)] += 1;
        }
        // Ask each owner for the entries we need: the request lists become its send lists.
        let send_counts = comm.alltoall_counts(&recv_counts);
        let req: Vec<u64> = ghosts.iter().map(|&g| g as u64).collect();
        let wanted = comm.alltoallv_u64(&req, &recv_counts, &send_counts);
        let start = layout.start();
        let send_idx = wanted.iter().map(|&g| g as usize - start).collect();
        Self {
            ghosts,
            recv_counts,
            send_idx,
            send_counts,
        }
    }

    pub fn n_ghosts(&self) -> usize {
        self.ghosts.len()
    }

    /// Owned local offsets sent by [`Self::forward`], grouped by destination rank.
    pub fn send_indices(&self) -> &[usize] {
        &self.send_idx
    }

    /// How many entries [`Self::forward`] sends to each rank.
    pub fn send_counts(&self) -> &[usize] {
        &self.send_counts
    }

    /// How many ghosts come from each rank.
    pub fn recv_counts(&self) -> &[usize] {
        &self.recv_counts
    }

    /// Ranks this rank exchanges with (for diagnostics).
    pub fn neighbours(&self) -> usize {
        (0..self.recv_counts.len())
            .filter(|&r| self.recv_counts[r] > 0 || self.send_counts[r] > 0)
            .count()
    }

    /// Copy owners' values into `ghost_out` (same order as `ghosts`).
    pub fn forward(&self, comm: &dyn Comm, owned: &[f64], ghost_out: &mut [f64]) {
        let send: Vec<f64> = self.send_idx.iter().map(|&i| owned[i]).collect();
        let recv = comm.alltoallv_f64(&send, &self.send_counts, &self.recv_counts);
        ghost_out.copy_from_slice(&recv);
    }

    /// Add ghost contributions into their owners' entries of `owned`.
    pub fn reverse_add(&self, comm: &dyn Comm, ghost_vals: &[f64], owned: &mut [f64]) {
        let recv = comm.alltoallv_f64(ghost_vals, &self.recv_counts, &self.send_counts);
        for (&i, v) in self.send_idx.iter().zip(recv) {
            owned[i] += v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parallel::SerialComm;
    #[test]
    fn serial_plan_is_empty() {
        let l = Layout::from_counts(&[4], 0);
        let plan = HaloPlan::new(&SerialComm, &l, vec![]);
        let mut owned = vec![1.0; 4];
        plan.reverse_add(&SerialComm, &[], &mut owned);
        assert_eq!(owned, vec![1.0; 4]);
        assert_eq!(plan.neighbours(), 0);
    }
}
