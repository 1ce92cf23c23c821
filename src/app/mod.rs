//! What the commands do: `run` (and restart), `check`, `partition`. The CLI (`main.rs`)
//! only parses arguments and maps errors to exit codes; tests call these functions
//! directly. One file per job: `run.rs` (set up, run, observe), `restart.rs`,
//! `summary.rs` (`summary.json`), `check.rs`, `progress.rs` (the progress line).

mod check;
pub mod export;
pub mod import;
pub mod interrupt;
mod observe;
mod progress;
mod restart;
mod run;
pub mod schema;
mod summary;

pub use check::{check, check_source, partition};
pub use run::{run, setup, RunOptions, RunOutcome, Setup};
pub use summary::{CoarseSummary, Phases, RestartedFrom, Summary, TrafficSummary};
