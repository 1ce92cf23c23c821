//! Exercise MpiComm's personalised exchanges with uneven, large and empty messages.
use alfe::parallel::{Comm, MpiComm};
fn main() {
    let universe = mpi::initialize().unwrap();
    let comm = MpiComm::new(universe.world());
    let p = comm.size();
    let r = comm.rank();
    for &(a, b) in &[(3usize, 2usize), (5000, 4000), (45743, 40000)] {
        let send_counts: Vec<usize> = if r == 0 { vec![a, b] } else { vec![0; p] };
        let recv_counts = comm.alltoall_counts(&send_counts);
        let n: usize = send_counts.iter().sum();
        let recv = comm.alltoallv_u64(&vec![7u64; n], &send_counts, &recv_counts);
        eprintln!("rank {r}: u64 {a},{b} got {}", recv.len());
        let recv = comm.alltoallv_f64(&vec![7.0; n], &send_counts, &recv_counts);
        eprintln!("rank {r}: f64 {a},{b} got {}", recv.len());
        let bytes: Vec<u8> = (0..n).map(|i| (i % 251) as u8).collect();
        let recv = comm.alltoallv_bytes(&bytes, &send_counts, &recv_counts);
        let want: Vec<u8> = if r == 0 {
            bytes[..a].to_vec()
        } else {
            bytes_from0(a, b)
        };
        assert_eq!(recv, want, "rank {r}: bytes {a},{b}");
        let mut bc = if r == 0 { bytes.clone() } else { Vec::new() };
        comm.broadcast_bytes(0, &mut bc);
        assert_eq!(bc.len(), a + b);
        eprintln!("rank {r}: bytes {a},{b} ok");
    }
}

/// What rank 1 receives from rank 0: the bytes after rank 0's own block.
fn bytes_from0(a: usize, b: usize) -> Vec<u8> {
    (a..a + b).map(|i| (i % 251) as u8).collect()
}
