//! [`Comm`] over an MPI communicator (rsmpi).

use super::comm::Comm;
use mpi::collective::SystemOperation;
use mpi::datatype::{Partition, PartitionMut};
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use mpi::Count;

pub struct MpiComm {
    world: SimpleCommunicator,
}

impl MpiComm {
    pub fn new(world: SimpleCommunicator) -> Self {
        Self { world }
    }

    /// End every rank of the job at once (used by the panic hook: no rank may hang).
    pub fn abort(&self, code: i32) -> ! {
        self.world.abort(code)
    }
}

fn displs(counts: &[Count]) -> Vec<Count> {
    counts
        .iter()
        .scan(0 as Count, |acc, &c| {
            let d = *acc;
            *acc += c;
            Some(d)
        })
        .collect()
}

fn to_counts(c: &[usize]) -> Vec<Count> {
    c.iter()
        .map(|&x| Count::try_from(x).expect("message larger than 2^31 items"))
        .collect()
}

impl MpiComm {
    fn alltoallv<T: Equivalence + Default + Clone>(
        &self,
        send: &[T],
        send_counts: &[usize],
        recv_counts: &[usize],
    ) -> Vec<T> {
        let sc = to_counts(send_counts);
        let rc = to_counts(recv_counts);
        let sd = displs(&sc);
        let rd = displs(&rc);
        let total: usize = recv_counts.iter().sum();
        let mut recv = vec![T::default(); total];
        {
            let sp = Partition::new(send, &sc[..], &sd[..]);
            let mut rp = PartitionMut::new(&mut recv[..], &rc[..], &rd[..]);
            self.world.all_to_all_varcount_into(&sp, &mut rp);
        }
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
        self.world.barrier();
    }
    fn allreduce_sum(&self, v: &mut [f64]) {
        let send = v.to_vec();
        self.world
            .all_reduce_into(&send[..], v, SystemOperation::sum());
    }
    fn allreduce_max(&self, v: &mut [f64]) {
        let send = v.to_vec();
        self.world
            .all_reduce_into(&send[..], v, SystemOperation::max());
    }
    fn allreduce_sum_u64(&self, v: &mut [u64]) {
        let send = v.to_vec();
        self.world
            .all_reduce_into(&send[..], v, SystemOperation::sum());
    }
    fn allreduce_max_u64(&self, v: &mut [u64]) {
        let send = v.to_vec();
        self.world
            .all_reduce_into(&send[..], v, SystemOperation::max());
    }
    fn alltoall_counts(&self, send_counts: &[usize]) -> Vec<usize> {
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
}
