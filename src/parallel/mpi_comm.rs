//! [`Comm`] over an MPI communicator (rsmpi).

use super::comm::{Comm, Traffic};
use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

pub struct MpiComm {
    world: SimpleCommunicator,
    /// Private duplicate for the point-to-point exchanges.
    exchange: SimpleCommunicator,
    reductions: AtomicU64,
    exchanges: AtomicU64,
    messages: AtomicU64,
    bytes: AtomicU64,
}

impl MpiComm {
    pub fn new(world: SimpleCommunicator) -> Self {
        Self {
            exchange: world.duplicate(),
            world,
            reductions: AtomicU64::new(0),
            exchanges: AtomicU64::new(0),
            messages: AtomicU64::new(0),
            bytes: AtomicU64::new(0),
        }
    }

    fn count_reduction(&self) {
        self.reductions.fetch_add(1, Relaxed);
    }

    /// One exchange sending `counts[r]` items of `item` bytes to each rank r.
    fn count_exchange(&self, counts: &[usize], item: usize) {
        let me = self.world.rank() as usize;
        let others = counts
            .iter()
            .enumerate()
            .filter(|&(r, &c)| r != me && c > 0);
        let (m, b) = others.fold((0u64, 0u64), |(m, b), (_, &c)| {
            (m + 1, b + (c * item) as u64)
        });
        self.exchanges.fetch_add(1, Relaxed);
        self.messages.fetch_add(m, Relaxed);
        self.bytes.fetch_add(b, Relaxed);
    }

    /// End every rank of the job at once (used by the panic hook: no rank may hang).
    pub fn abort(&self, code: i32) -> ! {
        self.world.abort(code)
    }
}

/// Tag of the sparse exchanges on the private duplicate communicator.
const EXCHANGE_TAG: i32 = 17;

impl MpiComm {
    /// A personalised exchange with the ranks that have something to send or receive:
    /// point-to-point on a private duplicate of the communicator, not `MPI_Alltoallv`,
    /// because Open MPI's alltoallv posts a message to every rank, empty ones included
    /// (measured with its monitoring component: at P ranks a halo update cost P − 1
    /// messages however few neighbours a subdomain has). Both sides know the counts, so
    /// receives are posted for exactly the nonzero ones; MPI's non-overtaking order keeps
    /// successive exchanges apart.
    fn alltoallv<T: Equivalence + Default + Clone>(
        &self,
        send: &[T],
        send_counts: &[usize],
        recv_counts: &[usize],
    ) -> Vec<T> {
        self.count_exchange(send_counts, std::mem::size_of::<T>());
        let me = self.world.rank() as usize;
        let total: usize = recv_counts.iter().sum();
        let mut recv = vec![T::default(); total];
        let sd: Vec<usize> = send_counts
            .iter()
            .scan(0, |a, &c| {
                *a += c;
                Some(*a - c)
            })
            .collect();
        mpi::request::scope(|sc| {
            let mut receives = Vec::new();
            let mut rest: &mut [T] = &mut recv;
            for (r, &c) in recv_counts.iter().enumerate() {
                let (mine, tail) = rest.split_at_mut(c);
                rest = tail;
                if r == me {
                    mine.clone_from_slice(&send[sd[r]..sd[r] + send_counts[r]]);
                } else if c > 0 {
                    let p = self.exchange.process_at_rank(r as i32);
                    receives.push(p.immediate_receive_into_with_tag(sc, mine, EXCHANGE_TAG));
                }
            }
            let sends: Vec<_> = (0..send_counts.len())
                .filter(|&r| r != me && send_counts[r] > 0)
                .map(|r| {
                    let p = self.exchange.process_at_rank(r as i32);
                    let buf = &send[sd[r]..sd[r] + send_counts[r]];
                    p.immediate_send_with_tag(sc, buf, EXCHANGE_TAG)
                })
                .collect();
            for q in receives {
                q.wait();
            }
            for q in sends {
                q.wait();
            }
        });
        recv
    }
}

/// Bytes as little-endian u64 words, zero-padded.
fn pack(b: &[u8]) -> Vec<u64> {
    b.chunks(8)
        .map(|c| {
            let mut w = [0u8; 8];
            w[..c.len()].copy_from_slice(c);
            u64::from_le_bytes(w)
        })
        .collect()
}

fn unpack(w: &[u64]) -> Vec<u8> {
    w.iter().flat_map(|x| x.to_le_bytes()).collect()
}

impl Comm for MpiComm {
    fn rank(&self) -> usize {
        self.world.rank() as usize
    }
    fn size(&self) -> usize {
        self.world.size() as usize
    }
    fn barrier(&self) {
        self.count_reduction();
        self.world.barrier();
    }
    fn allreduce_sum(&self, v: &mut [f64]) {
        self.count_reduction();
        let send = v.to_vec();
        self.world
            .all_reduce_into(&send[..], v, SystemOperation::sum());
    }
    fn allreduce_max(&self, v: &mut [f64]) {
        self.count_reduction();
        let send = v.to_vec();
        self.world
            .all_reduce_into(&send[..], v, SystemOperation::max());
    }
    fn allreduce_sum_u64(&self, v: &mut [u64]) {
        self.count_reduction();
        let send = v.to_vec();
        self.world
            .all_reduce_into(&send[..], v, SystemOperation::sum());
    }
    fn allreduce_max_u64(&self, v: &mut [u64]) {
        self.count_reduction();
        let send = v.to_vec();
        self.world
            .all_reduce_into(&send[..], v, SystemOperation::max());
    }
    fn alltoall_counts(&self, send_counts: &[usize]) -> Vec<usize> {
        let ones = vec![1; self.size()];
        self.count_exchange(&ones, 8);
        let send: Vec<u64> = send_counts.iter().map(|&c| c as u64).collect();
        let mut recv = vec![0u64; self.size()];
        self.world.all_to_all_into(&send[..], &mut recv[..]);
        recv.into_iter().map(|c| c as usize).collect()
    }
    fn alltoallv_f64(&self, send: &[f64], s: &[usize], r: &[usize]) -> Vec<f64> {
        self.alltoallv(send, s, r)
    }
    fn alltoallv_u64(&self, send: &[u64], s: &[usize], r: &[usize]) -> Vec<u64> {
        self.alltoallv(send, s, r)
    }
    fn alltoallv_bytes(&self, send: &[u8], s: &[usize], r: &[usize]) -> Vec<u8> {
        // Shipped as u64 words: MPI_Alltoallv with rsmpi's u8 (MPI_UINT8_T) datatype
        // truncates/corrupts messages under Debian's Open MPI 4.1.4 (examples/comm_check).
        let words = |c: usize| c.div_ceil(8);
        let ws: Vec<usize> = s.iter().map(|&c| words(c)).collect();
        let wr: Vec<usize> = r.iter().map(|&c| words(c)).collect();
        let mut packed = Vec::with_capacity(ws.iter().sum());
        let mut off = 0;
        for &c in s {
            packed.extend(pack(&send[off..off + c]));
            off += c;
        }
        let got = self.alltoallv(&packed, &ws, &wr);
        let mut out = Vec::with_capacity(r.iter().sum());
        let mut woff = 0;
        for (&c, &w) in r.iter().zip(&wr) {
            out.extend_from_slice(&unpack(&got[woff..woff + w])[..c]);
            woff += w;
        }
        out
    }
    fn broadcast_bytes(&self, root: usize, bytes: &mut Vec<u8>) {
        self.count_reduction();
        let root_proc = self.world.process_at_rank(root as i32);
        let mut len = [bytes.len() as u64];
        root_proc.broadcast_into(&mut len[..]);
        let n = len[0] as usize;
        if n == 0 {
            bytes.clear();
            return;
        }
        let mut words = if self.rank() == root {
            pack(bytes)
        } else {
            vec![0u64; n.div_ceil(8)]
        };
        root_proc.broadcast_into(&mut words[..]);
        if self.rank() != root {
            *bytes = unpack(&words)[..n].to_vec();
        }
    }
    fn raw_mpi(&self) -> Option<mpi::ffi::MPI_Comm> {
        Some(self.world.as_raw())
    }
    fn traffic(&self) -> Traffic {
        Traffic {
            reductions: self.reductions.load(Relaxed),
            exchanges: self.exchanges.load(Relaxed),
            messages: self.messages.load(Relaxed),
            bytes: self.bytes.load(Relaxed),
        }
    }
}
