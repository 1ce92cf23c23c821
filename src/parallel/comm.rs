//! The communicator seam: the few collectives alfe uses, typed on what it sends.

/// What one rank has sent through a communicator since it was made: counts that do not
/// depend on the machine, from which a network model predicts communication time
/// (issue 12's scaling study). Traffic of libraries that talk MPI themselves (hypre) is
/// not seen here; `scripts/scaling-study` reads it from Open MPI's monitoring.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct Traffic {
    /// Latency-bound collectives: all-reduces, broadcasts, barriers.
    pub reductions: u64,
    /// Personalised exchanges (halo updates, redistribution): `alltoall(v)` calls.
    pub exchanges: u64,
    /// Non-empty messages to other ranks within the exchanges.
    pub messages: u64,
    /// Bytes to other ranks within the exchanges.
    pub bytes: u64,
}

/// Collective operations over a fixed group of ranks.
///
/// Every method is collective: all ranks call it, in the same order. Counts passed to
/// the `alltoallv_*` calls must agree pairwise (what rank a sends to b is what b
/// expects from a); [`Comm::alltoall_counts`] exchanges them when they are not known.
pub trait Comm {
    fn rank(&self) -> usize;
    fn size(&self) -> usize;
    fn barrier(&self);
    /// Element-wise sum over ranks, in place.
    fn allreduce_sum(&self, v: &mut [f64]);
    /// Element-wise max over ranks, in place.
    fn allreduce_max(&self, v: &mut [f64]);
    /// Element-wise sum over ranks of integers, in place.
    fn allreduce_sum_u64(&self, v: &mut [u64]);
    /// Element-wise max over ranks of integers, in place.
    fn allreduce_max_u64(&self, v: &mut [u64]);
    /// Tell every rank how many items every other rank will send to it:
    /// `send_counts[r]` goes to rank r; the result's `[r]` comes from rank r.
    fn alltoall_counts(&self, send_counts: &[usize]) -> Vec<usize>;
    /// Personalised exchange of f64: `send` holds the blocks for rank 0, 1, ... in order.
    fn alltoallv_f64(&self, send: &[f64], send_counts: &[usize], recv_counts: &[usize])
        -> Vec<f64>;
    /// Personalised exchange of u64 (indices).
    fn alltoallv_u64(&self, send: &[u64], send_counts: &[usize], recv_counts: &[usize])
        -> Vec<u64>;
    /// Personalised exchange of raw bytes (serialised records).
    fn alltoallv_bytes(&self, send: &[u8], send_counts: &[usize], recv_counts: &[usize])
        -> Vec<u8>;
    /// Broadcast a byte buffer from `root`; on other ranks the buffer is replaced.
    fn broadcast_bytes(&self, root: usize, bytes: &mut Vec<u8>);
    /// The raw MPI communicator, for MPI-IO; `None` for a serial run.
    fn raw_mpi(&self) -> Option<mpi::ffi::MPI_Comm>;
    /// This rank's traffic so far; zero where nothing is sent (one rank, threads).
    fn traffic(&self) -> Traffic {
        Traffic::default()
    }

    /// True on every rank iff `ok` is true on every rank (one reduction).
    /// This is how a local failure (a bad element, a failed factorization) is agreed on
    /// by all ranks, so that no rank goes on waiting in a collective the others left.
    fn all_ok(&self, ok: bool) -> bool {
        let mut v = [if ok { 0u64 } else { 1 }];
        self.allreduce_max_u64(&mut v);
        v[0] == 0
    }
    /// The message of the lowest rank that has one, on every rank (`None` if no rank
    /// has one): a failure found on one rank (an inverted element) is reported by every
    /// rank in its own words. Two collectives; meant for failure paths.
    fn first_message(&self, mine: Option<String>) -> Option<String> {
        let n = self.size() as u64;
        let mut v = [if mine.is_some() {
            n - self.rank() as u64
        } else {
            0
        }];
        self.allreduce_max_u64(&mut v);
        if v[0] == 0 {
            return None;
        }
        let root = (n - v[0]) as usize;
        let mut bytes = if self.rank() == root {
            mine.unwrap_or_default().into_bytes()
        } else {
            Vec::new()
        };
        self.broadcast_bytes(root, &mut bytes);
        Some(String::from_utf8_lossy(&bytes).into_owned())
    }
    /// Dot product of two distributed vectors given by their owned parts.
    fn dot(&self, a: &[f64], b: &[f64]) -> f64 {
        let mut s = [a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>()];
        self.allreduce_sum(&mut s);
        s[0]
    }
    /// Euclidean norm of a distributed vector given by its owned part.
    fn norm2(&self, a: &[f64]) -> f64 {
        self.dot(a, a).sqrt()
    }
    /// Exclusive prefix sum of one count per rank, and the total.
    fn exclusive_scan(&self, count: u64) -> (u64, u64) {
        let mut all = vec![0u64; self.size()];
        all[self.rank()] = count;
        self.allreduce_sum_u64(&mut all);
        let before = all[..self.rank()].iter().sum();
        (before, all.iter().sum())
    }
    /// Every rank's value of one number, gathered on all ranks.
    fn allgather_f64(&self, x: f64) -> Vec<f64> {
        let mut all = vec![0.0; self.size()];
        all[self.rank()] = x;
        self.allreduce_sum(&mut all);
        all
    }
}

/// A group of one: every collective is the identity.
#[derive(Debug, Default, Clone, Copy)]
pub struct SerialComm;

impl Comm for SerialComm {
    fn rank(&self) -> usize {
        0
    }
    fn size(&self) -> usize {
        1
    }
    fn barrier(&self) {}
    fn allreduce_sum(&self, _v: &mut [f64]) {}
    fn allreduce_max(&self, _v: &mut [f64]) {}
    fn allreduce_sum_u64(&self, _v: &mut [u64]) {}
    fn allreduce_max_u64(&self, _v: &mut [u64]) {}
    fn alltoall_counts(&self, send_counts: &[usize]) -> Vec<usize> {
        send_counts.to_vec()
    }
    fn alltoallv_f64(&self, send: &[f64], _s: &[usize], _r: &[usize]) -> Vec<f64> {
        send.to_vec()
    }
    fn alltoallv_u64(&self, send: &[u64], _s: &[usize], _r: &[usize]) -> Vec<u64> {
        send.to_vec()
    }
    fn alltoallv_bytes(&self, send: &[u8], _s: &[usize], _r: &[usize]) -> Vec<u8> {
        send.to_vec()
    }
    fn broadcast_bytes(&self, _root: usize, _bytes: &mut Vec<u8>) {}
    fn raw_mpi(&self) -> Option<mpi::ffi::MPI_Comm> {
        None
    }
}
