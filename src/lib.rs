//! alfe: an MPI-distributed implicit nonlinear finite-element solver for solids in
//! contact. See `README.md` for use and `DESIGN` notes in each module for the why.
//!
//! Layers, bottom up: [`parallel`] (moves numbers, knows no physics), [`mesh`],
//! [`fem`] and [`material`] (physics kernels, know no MPI), [`partition`] (METIS,
//! ownership, distribution), [`solve`] (distributed linear algebra, nonlinear solvers,
//! stepping), [`model`] (the distributed FE problem: assembly, constraints, loads),
//! [`scene`] (decks), [`output`] (HDF5/XDMF, CSV, JSON), [`app`] (what `alfe run` does).

pub mod app;
pub mod bench;
pub mod bench_residual;
pub mod contact;
pub mod curve;
pub mod error;
pub mod fem;
pub mod linalg;
pub mod material;
pub mod mesh;
pub mod model;
pub mod output;
pub mod parallel;
pub mod partition;
pub mod scene;
pub mod solve;

pub use error::{Error, ErrorKind, Result};

/// The version and the commit alfe was built from (`alfe --version`, `summary.json`).
pub const VERSION: &str = concat!(env!("CARGO_PKG_VERSION"), " (", env!("ALFE_COMMIT"), ")");
/// The commit alone.
pub const COMMIT: &str = env!("ALFE_COMMIT");
