//! alfe: an MPI-distributed implicit nonlinear finite-element solver for solids in
//! contact. See `README.md` for use, `docs/src/design.md` for the map, and each module's
//! documentation for the why.
//!
//! Layers, bottom up (`docs/src/design.md`, enforced by `tests/layers.rs`): [`error`], [`curve`] and
//! [`parallel`] (moves numbers, knows no physics); [`mesh`] and [`material`]; [`fem`]
//! (element kernels; with the layers above, no MPI); [`contact`] (pointwise laws and
//! shapes), [`linalg`] (distributed matrices, GMRES, preconditioners) and [`partition`]
//! (METIS, ownership, distribution); [`model`] (the distributed problem as a list of
//! contributions); [`solve`] (nonlinear solvers, stepping, time integration); [`output`]
//! (HDF5/XDMF, CSV, JSON, restart files); [`scene`] (decks); [`app`] (what the commands
//! do). The binaries sit on top: `alfe` (`src/main.rs`) and the benchmarks `alfe-bench`
//! (`src/bin/alfe-bench/`), both through the public API only.

pub mod app;
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
