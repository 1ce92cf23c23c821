//! [`Comm`] over threads of one process: several ranks in one test, no MPI.
//!
//! MPI can be initialised only once per process, so in-process tests cannot run several
//! MPI ranks. [`run_ranks`] starts `n` threads that share one exchange area and a
//! barrier; each collective deposits this rank's contribution, waits for all ranks,
//! reads what it needs and waits again (so no rank overwrites a slot another is still
//! reading). Reductions add contributions in rank order, so every rank gets bit-identical
//! results, as with MPI.
//!
//! If one rank panics, the others are released from the barrier (they panic too, with a
//! note) and [`run_ranks`] re-raises the first panic: a failing test never hangs.

use super::comm::Comm;
use std::any::Any;
use std::sync::{Condvar, Mutex};

struct BarrierState {
    count: usize,
    generation: u64,
    poisoned: bool,
}

struct Shared {
    n: usize,
    slots: Mutex<Vec<Option<Box<dyn Any + Send>>>>,
    state: Mutex<BarrierState>,
    cv: Condvar,
}

const POISON_MSG: &str = "ThreadComm: another rank panicked";

impl Shared {
    fn wait(&self) {
        let mut st = self.state.lock().unwrap_or_else(|e| e.into_inner());
        if st.poisoned {
            drop(st);
            panic!("{POISON_MSG}");
        }
        st.count += 1;
        if st.count == self.n {
            st.count = 0;
            st.generation += 1;
            self.cv.notify_all();
            return;
        }
        let gen = st.generation;
        while st.generation == gen && !st.poisoned {
            st = self.cv.wait(st).unwrap_or_else(|e| e.into_inner());
        }
        if st.poisoned {
            drop(st);
            panic!("{POISON_MSG}");
        }
    }

    fn poison(&self) {
        let mut st = self.state.lock().unwrap_or_else(|e| e.into_inner());
        st.poisoned = true;
        self.cv.notify_all();
    }
}

/// One rank of an in-process group (see [`run_ranks`]).
pub struct ThreadComm<'a> {
    rank: usize,
    shared: &'a Shared,
}

struct PoisonOnPanic<'a>(&'a Shared);

impl Drop for PoisonOnPanic<'_> {
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.0.poison();
        }
    }
}

/// Run `f` on `n` ranks, one thread each, and return the results in rank order.
/// A panic on any rank is re-raised here (the first rank's own panic, not the
/// follow-up panics of the ranks it released).
///
/// Like the `alfe` binary (one MPI rank per core), the ranks' dense and sparse kernels
/// run sequentially: a rayon pool under each thread rank would make the floating-point
/// results depend on scheduling.
pub fn run_ranks<F, R>(n: usize, f: F) -> Vec<R>
where
    F: Fn(&ThreadComm) -> R + Sync,
    R: Send,
{
    assert!(n >= 1, "run_ranks needs at least one rank");
    faer::set_global_parallelism(faer::Par::Seq);
    let shared = Shared {
        n,
        slots: Mutex::new((0..n).map(|_| None).collect()),
        state: Mutex::new(BarrierState {
            count: 0,
            generation: 0,
            poisoned: false,
        }),
        cv: Condvar::new(),
    };
    let outcomes: Vec<std::thread::Result<R>> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..n)
            .map(|rank| {
                let shared = &shared;
                let f = &f;
                std::thread::Builder::new()
                    .name(format!("rank{rank}"))
                    .stack_size(16 << 20)
                    .spawn_scoped(s, move || {
                        let _guard = PoisonOnPanic(shared);
                        let comm = ThreadComm { rank, shared };
                        f(&comm)
                    })
                    .expect("spawn rank thread")
            })
            .collect();
        handles.into_iter().map(|h| h.join()).collect()
    });
    let mut results = Vec::with_capacity(n);
    let mut first_panic: Option<Box<dyn Any + Send>> = None;
    let mut follow_up: Option<Box<dyn Any + Send>> = None;
    for o in outcomes {
        match o {
            Ok(r) => results.push(r),
            Err(p) => {
                let is_follow_up = p
                    .downcast_ref::<String>()
                    .is_some_and(|s| s.as_str() == POISON_MSG);
                if is_follow_up {
                    follow_up.get_or_insert(p);
                } else {
                    first_panic.get_or_insert(p);
                }
            }
        }
    }
    if let Some(p) = first_panic.or(follow_up) {
        std::panic::resume_unwind(p);
    }
    results
}

impl ThreadComm<'_> {
    /// Every rank contributes one value; every rank gets all of them in rank order.
    fn allgather_any<T: Clone + Send + 'static>(&self, mine: T) -> Vec<T> {
        self.shared.slots.lock().unwrap_or_else(|e| e.into_inner())[self.rank] =
            Some(Box::new(mine));
        self.shared.wait();
        let all: Vec<T> = {
            let slots = self.shared.slots.lock().unwrap_or_else(|e| e.into_inner());
            slots
                .iter()
                .map(|s| {
                    s.as_ref()
                        .and_then(|b| b.downcast_ref::<T>())
                        .expect("ThreadComm: ranks called different collectives")
                        .clone()
                })
                .collect()
        };
        self.shared.wait();
        all
    }

    /// Personalised exchange: `send[r]` goes to rank r; result `[r]` came from rank r.
    fn exchange<T: Clone + Send + Sync + 'static>(&self, send: Vec<Vec<T>>) -> Vec<Vec<T>> {
        debug_assert_eq!(send.len(), self.shared.n);
        self.shared.slots.lock().unwrap_or_else(|e| e.into_inner())[self.rank] =
            Some(Box::new(send));
        self.shared.wait();
        let recv: Vec<Vec<T>> = {
            let slots = self.shared.slots.lock().unwrap_or_else(|e| e.into_inner());
            slots
                .iter()
                .map(|s| {
                    s.as_ref()
                        .and_then(|b| b.downcast_ref::<Vec<Vec<T>>>())
                        .expect("ThreadComm: ranks called different collectives")[self.rank]
                        .clone()
                })
                .collect()
        };
        self.shared.wait();
        recv
    }

    fn alltoallv<T: Clone + Send + Sync + 'static>(
        &self,
        send: &[T],
        send_counts: &[usize],
        recv_counts: &[usize],
    ) -> Vec<T> {
        assert_eq!(send_counts.len(), self.shared.n);
        assert_eq!(
            send_counts.iter().sum::<usize>(),
            send.len(),
            "alltoallv: send length"
        );
        let mut parts = Vec::with_capacity(self.shared.n);
        let mut off = 0;
        for &c in send_counts {
            parts.push(send[off..off + c].to_vec());
            off += c;
        }
        let recv = self.exchange(parts);
        for (r, part) in recv.iter().enumerate() {
            assert_eq!(
                part.len(),
                recv_counts[r],
                "alltoallv: rank {} expected {} items from rank {r}, got {}",
                self.rank,
                recv_counts[r],
                part.len()
            );
        }
        recv.concat()
    }

    fn reduce<T: Copy + Send + Sync + 'static>(&self, v: &mut [T], op: impl Fn(T, T) -> T) {
        let all = self.allgather_any(v.to_vec());
        for (i, out) in v.iter_mut().enumerate() {
            let mut acc = all[0][i];
            for other in &all[1..] {
                acc = op(acc, other[i]);
            }
            *out = acc;
        }
    }
}

impl Comm for ThreadComm<'_> {
    fn rank(&self) -> usize {
        self.rank
    }
    fn size(&self) -> usize {
        self.shared.n
    }
    fn barrier(&self) {
        self.shared.wait();
    }
    fn allreduce_sum(&self, v: &mut [f64]) {
        self.reduce(v, |a, b| a + b);
    }
    fn allreduce_max(&self, v: &mut [f64]) {
        self.reduce(v, f64::max);
    }
    fn allreduce_sum_u64(&self, v: &mut [u64]) {
        self.reduce(v, |a, b| a + b);
    }
    fn allreduce_max_u64(&self, v: &mut [u64]) {
        self.reduce(v, u64::max);
    }
    fn alltoall_counts(&self, send_counts: &[usize]) -> Vec<usize> {
        let parts = send_counts.iter().map(|&c| vec![c]).collect();
        self.exchange(parts).into_iter().map(|v| v[0]).collect()
    }
    fn alltoallv_f64(&self, send: &[f64], s: &[usize], r: &[usize]) -> Vec<f64> {
        self.alltoallv(send, s, r)
    }
    fn alltoallv_u64(&self, send: &[u64], s: &[usize], r: &[usize]) -> Vec<u64> {
        self.alltoallv(send, s, r)
    }
    fn alltoallv_bytes(&self, send: &[u8], s: &[usize], r: &[usize]) -> Vec<u8> {
        self.alltoallv(send, s, r)
    }
    fn broadcast_bytes(&self, root: usize, bytes: &mut Vec<u8>) {
        let mine = if self.rank == root {
            bytes.clone()
        } else {
            Vec::new()
        };
        let all = self.allgather_any(mine);
        if self.rank != root {
            *bytes = all[root].clone();
        }
    }
    fn raw_mpi(&self) -> Option<mpi::ffi::MPI_Comm> {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parallel::{HaloPlan, Layout};

    /// Every rank gets the lowest rank's message, or none if no rank has one.
    #[test]
    fn first_message_is_the_lowest_ranks() {
        let out = run_ranks(3, |c| {
            let mine = (c.rank() > 0).then(|| format!("element on rank {}", c.rank()));
            (c.first_message(mine), c.first_message(None))
        });
        for (some, none) in out {
            assert_eq!(some.as_deref(), Some("element on rank 1"));
            assert_eq!(none, None);
        }
    }

    #[test]
    fn allreduce_is_identical_on_all_ranks() {
        let out = run_ranks(3, |c| {
            let mut v = [c.rank() as f64 + 0.1, 1.0 / (c.rank() as f64 + 3.0)];
            c.allreduce_sum(&mut v);
            let mut m = [c.rank() as f64];
            c.allreduce_max(&mut m);
            let mut u = [c.rank() as u64 + 1, 7];
            c.allreduce_sum_u64(&mut u);
            let mut um = [10 - c.rank() as u64];
            c.allreduce_max_u64(&mut um);
            (
                v,
                m[0],
                u,
                um[0],
                c.dot(&[1.0, 2.0], &[3.0, c.rank() as f64]),
            )
        });
        for o in &out {
            assert_eq!(o.0, out[0].0);
            assert!((o.0[0] - 3.3).abs() < 1e-12);
            assert_eq!(o.1, 2.0);
            assert_eq!(o.2, [6, 21]);
            assert_eq!(o.3, 10);
            assert_eq!(o.4, 9.0 + 2.0 * 3.0);
        }
    }

    #[test]
    fn alltoallv_and_broadcast() {
        let out = run_ranks(3, |c| {
            let me = c.rank();
            // Rank r sends r+1 copies of (10 r + dest) to each dest.
            let counts = vec![me + 1; 3];
            let send: Vec<f64> = (0..3)
                .flat_map(|d| std::iter::repeat_n((10 * me + d) as f64, me + 1))
                .collect();
            let rc = c.alltoall_counts(&counts);
            assert_eq!(rc, vec![1, 2, 3]);
            let recv = c.alltoallv_f64(&send, &counts, &rc);
            let sendu: Vec<u64> = send.iter().map(|&x| x as u64).collect();
            let recvu = c.alltoallv_u64(&sendu, &counts, &rc);
            let mut b = if me == 1 { vec![1u8, 2, 3] } else { vec![9u8] };
            c.broadcast_bytes(1, &mut b);
            (recv, recvu, b)
        });
        for (me, (recv, recvu, b)) in out.into_iter().enumerate() {
            let expect: Vec<f64> = vec![
                me as f64,
                (10 + me) as f64,
                (10 + me) as f64,
                (20 + me) as f64,
                (20 + me) as f64,
                (20 + me) as f64,
            ];
            assert_eq!(recv, expect);
            assert_eq!(recvu, expect.iter().map(|&x| x as u64).collect::<Vec<_>>());
            assert_eq!(b, vec![1, 2, 3]);
        }
    }

    #[test]
    fn halo_forward_and_reverse_add_on_three_ranks() {
        // 9 entries: rank 0 owns 0..4, rank 1 owns 4..5, rank 2 owns 5..9.
        let out = run_ranks(3, |c| {
            let layout = Layout::gather(c, [4, 1, 4][c.rank()]);
            let ghosts: Vec<usize> = match c.rank() {
                0 => vec![4, 6, 8],
                1 => vec![0, 3, 5],
                _ => vec![1, 4],
            };
            let plan = HaloPlan::new(c, &layout, ghosts.clone());
            let owned: Vec<f64> = (layout.start()..layout.end())
                .map(|g| 100.0 + g as f64)
                .collect();
            let mut ghost_vals = vec![0.0; ghosts.len()];
            plan.forward(c, &owned, &mut ghost_vals);
            let expect: Vec<f64> = ghosts.iter().map(|&g| 100.0 + g as f64).collect();
            assert_eq!(ghost_vals, expect);
            let mut acc = vec![0.0; layout.owned_len()];
            let contrib = vec![1.0; ghosts.len()];
            plan.reverse_add(c, &contrib, &mut acc);
            acc
        });
        // Global tally of ghost references: 0:1, 1:1, 3:1, 4:2, 5:1, 6:1, 8:1.
        let all: Vec<f64> = out.concat();
        assert_eq!(all, vec![1.0, 1.0, 0.0, 1.0, 2.0, 1.0, 1.0, 0.0, 1.0]);
    }

    #[test]
    fn a_panicking_rank_does_not_hang_the_others() {
        let r = std::panic::catch_unwind(|| {
            run_ranks(3, |c| {
                if c.rank() == 2 {
                    panic!("rank two fails");
                }
                c.barrier();
            })
        });
        let p = r.expect_err("must panic");
        assert_eq!(p.downcast_ref::<&str>().copied(), Some("rank two fails"));
    }
}
