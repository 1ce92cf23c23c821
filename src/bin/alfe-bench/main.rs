//! `alfe-bench`: the core's benchmarks, a binary of their own beside `alfe` that uses
//! only the library's public API (issue 34: benchmarks out of the library). Built by
//! `cargo build --release` with `alfe`; started like it, on any rank count:
//!
//! * `mpirun -n N alfe-bench linear`: assembly, preconditioner set-up, GMRES and HDF5
//!   rates on a linear-elastic block (scripts/bench-core, scripts/bench-amg);
//! * `mpirun -n N alfe-bench residual`: residual and tangent rates per material and
//!   formulation (scripts/bench-core);
//! * `alfe-bench factor-timing`: the block-Jacobi factorizations on one large block and
//!   block-Jacobi GMRES on thread ranks (one process).
//!
//! Each prints its measurements as JSON (`linear`, `residual`) or lines
//! (`factor-timing`). Exit codes as `alfe`'s: 0 ok, 1 runtime failure, 2 bad input, 3 not
//! converged.

mod common;
mod factor;
mod linear;
mod residual;

use alfe::parallel::{Comm, MpiComm};
use alfe::{Error, Result};
use clap::{Parser, Subcommand};

/// alfe's benchmarks: `mpirun -n N alfe-bench linear|residual`, `alfe-bench factor-timing`.
///
/// Exit codes: 0 ok, 1 runtime failure, 2 bad input, 3 not converged.
#[derive(Parser, Debug)]
#[command(name = "alfe-bench", version = alfe::VERSION, about, long_about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Linear-elastic block: assembly, preconditioner set-up, GMRES and HDF5 rates
    /// (scripts/bench-core, scripts/bench-amg).
    Linear(linear::LinearArgs),
    /// Residual and tangent rates per material and formulation (scripts/bench-core).
    Residual(residual::ResidualArgs),
    /// Block-Jacobi factorizations (Cholesky and LU, AMD and nested dissection) on one
    /// large elastic block, and block-Jacobi GMRES on thread ranks; one process, no mpirun.
    FactorTiming(factor::FactorArgs),
}

/// A command-line mistake as one line (clap's first line, without its `error: `).
fn usage_error(e: &clap::Error) -> Error {
    let text = e.render().to_string();
    let first = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty())
        .unwrap_or("bad command line")
        .trim_start_matches("error: ");
    Error::input(format!("{first} (see `alfe-bench --help`)"))
}

fn main_inner(comm: &dyn Comm) -> Result<()> {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            use clap::error::ErrorKind;
            return match e.kind() {
                ErrorKind::DisplayHelp
                | ErrorKind::DisplayVersion
                | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
                    if comm.rank() == 0 {
                        print!("{}", e.render());
                    }
                    Ok(())
                }
                _ => Err(usage_error(&e)),
            };
        }
    };
    match cli.command {
        Command::Linear(a) => linear::run(comm, &a),
        Command::Residual(a) => residual::run(comm, &a),
        Command::FactorTiming(a) => {
            if comm.size() > 1 {
                return Err(Error::input(
                    "factor-timing runs its thread ranks in one process: start it without mpirun",
                ));
            }
            factor::run(&a)
        }
    }
}

fn main() {
    faer::set_global_parallelism(faer::Par::Seq);
    let Some(universe) = mpi::initialize() else {
        eprintln!("alfe-bench: error: MPI could not be initialised");
        std::process::exit(1);
    };
    // A panic on one rank must not leave the others waiting in a collective.
    std::panic::set_hook(Box::new(|info| {
        eprintln!("alfe-bench: internal error: {info}");
        unsafe {
            mpi::ffi::MPI_Abort(mpi::ffi::RSMPI_COMM_WORLD, 101);
        }
    }));
    let comm = MpiComm::new(universe.world());
    let code = match main_inner(&comm) {
        Ok(()) => 0,
        Err(e) => {
            if comm.rank() == 0 {
                eprintln!("alfe-bench: error: {e}");
            }
            e.exit_code()
        }
    };
    drop(comm);
    drop(universe);
    std::process::exit(code);
}
