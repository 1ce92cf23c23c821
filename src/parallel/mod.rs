//! The parallel layer: a thin seam over MPI. It moves numbers and knows no physics.
//!
//! Everything above it talks to [`Comm`]; [`SerialComm`] runs the same code in one
//! process (unit tests, `cargo test` in-process), [`MpiComm`] runs it under `mpirun`.

pub mod collective;
pub mod comm;
pub mod halo;
pub mod layout;
pub mod mpi_comm;
pub mod thread_comm;

pub use collective::{broadcast, on_rank0, peak_rss_mb, rank0_outcome};
pub use comm::{Comm, SerialComm, Traffic};
pub use halo::HaloPlan;
pub use layout::Layout;
pub use mpi_comm::MpiComm;
pub use thread_comm::{run_ranks, ThreadComm};
