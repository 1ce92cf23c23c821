//! The `alfe` command line: parse arguments (clap), call the library, map errors to exit
//! codes (0 ok, 1 runtime failure, 2 bad input, 3 not converged; README "Exit codes").

use alfe::app::{self, RunOptions};
use alfe::contact::wall::ContactMethod;
use alfe::parallel::{Comm, MpiComm};
use alfe::solve::nonlinear::SolverKind;
use alfe::{Error, Result};
use clap::{Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

/// alfe — distributed implicit finite elements for solids in contact.
///
/// Run on several ranks with `mpirun -n N alfe run ...`. `alfe DECK` is `alfe run DECK`;
/// `alfe` alone runs the default scene (cantilever).
/// Exit codes: 0 ok, 1 runtime failure, 2 bad input, 3 not converged.
#[derive(Parser, Debug)]
#[command(name = "alfe", version = alfe::VERSION, about, long_about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run a built-in scene or a deck file (the default command).
    Run(RunArgs),
    /// List the built-in scenes, one line each.
    Scenes,
    /// Print a built-in scene's deck (`alfe scene show NAME > my.toml`).
    Scene {
        #[command(subcommand)]
        what: SceneCommand,
    },
    /// Validate a deck; print the model size, its contributions and partition quality.
    Check {
        /// Built-in scene name or deck path (default: cantilever).
        target: Option<String>,
        /// Partition for this many ranks and report its quality.
        #[arg(short = 'n', long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
        ranks: u32,
        #[command(flatten)]
        study: StudyArgs,
    },
    /// Translate an Abaqus/CalculiX input file (.inp) or an LS-DYNA keyword file (.k) into
    /// an alfe deck: the mesh stays in the file; every keyword not translated is listed
    /// with its line, in the deck and on stderr.
    Import {
        /// The input file.
        file: PathBuf,
        /// The deck to write (default: the input's name with .toml, here).
        #[arg(short, long, value_name = "DECK")]
        out: Option<PathBuf>,
    },
    /// Print the deck's JSON Schema (for an editor's completion and checks of TOML decks).
    Schema,
    /// Write a built-in scene or a deck as an Abaqus/CalculiX input file (.inp) or an
    /// LS-DYNA keyword file (.k), by the extension; what has no equivalent is listed.
    Export {
        /// Built-in scene name or deck path.
        target: String,
        /// The .inp or .k file to write.
        #[arg(short, long, value_name = "FILE")]
        out: PathBuf,
    },
    /// Write the METIS partition for a rank count to the partition cache.
    Partition {
        /// Built-in scene name or deck path.
        target: Option<String>,
        /// The rank count to partition for.
        #[arg(short = 'n', long, value_parser = clap::value_parser!(u32).range(1..))]
        ranks: u32,
        /// Partition cache directory (default $XDG_CACHE_HOME/alfe/partitions, else
        /// ~/.cache/alfe/partitions).
        #[arg(long, value_name = "DIR")]
        partitions: Option<PathBuf>,
    },
}

#[derive(Subcommand, Debug)]
enum SceneCommand {
    /// Print the deck of a built-in scene.
    Show {
        /// The scene's name (see `alfe scenes`).
        name: String,
    },
}

#[derive(clap::Args, Debug)]
struct RunArgs {
    /// Built-in scene name or deck path (default: cantilever). A name is looked up among
    /// the built-in scenes first, then as a file.
    target: Option<String>,
    /// Results directory (default out/<scene>).
    #[arg(short, long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Partition cache directory (default $XDG_CACHE_HOME/alfe/partitions, else
    /// ~/.cache/alfe/partitions).
    #[arg(long, value_name = "DIR")]
    partitions: Option<PathBuf>,
    /// Recompute a cached partition instead of using it.
    #[arg(long)]
    repartition: bool,
    /// No progress lines.
    #[arg(short, long)]
    quiet: bool,
    /// Nonlinear solver (overrides the deck's `[solver] nonlinear`).
    #[arg(short, long, value_enum)]
    solver: Option<SolverArg>,
    /// Contact enforcement of every [[walls]], [[entities]] and [[pairs]] entry
    /// ([[bolts]] sections stay tied by ALM).
    #[arg(short, long, value_enum)]
    contact: Option<ContactArg>,
    /// Write every nonlinear iteration's residual, failed attempts included, to
    /// iterations.csv.
    #[arg(long)]
    iterations: bool,
    /// Go on from an earlier run's output directory (its restart files, written at every
    /// step that writes fields), with its deck.toml unless a deck is given; results go to
    /// DIR-restart unless --out says otherwise.
    #[arg(long, value_name = "DIR")]
    restart: Option<PathBuf>,
    /// End the run after this step, as if interrupted (it can go on with --restart).
    #[arg(long, value_name = "STEP", value_parser = clap::value_parser!(u64).range(1..))]
    stop_after: Option<u64>,
    /// Write the first Newton linear system (matrix with its constraints, right-hand
    /// side, node coordinates, row ownership) in PETSc's binary format to DIR, for the
    /// PETSc peers in scripts/ (newton only)
    #[arg(long, value_name = "DIR")]
    export_system: Option<PathBuf>,
    #[command(flatten)]
    study: StudyArgs,
}

/// A study's changes to the deck, without editing it (scripts/study uses them).
#[derive(clap::Args, Debug)]
struct StudyArgs {
    /// Multiply the cells of every generated mesh by K (a direction with one cell keeps
    /// it; blocks divide their cell size; Gmsh meshes cannot be refined).
    #[arg(long, value_name = "K", default_value_t = 1)]
    refine: usize,
    /// Multiply every increment (step, min_step, max_step) by F.
    #[arg(long, value_name = "F", default_value_t = 1.0)]
    step_scale: f64,
    /// Set every wall's, entity's and pair's penalty_scale (with --contact penalty).
    #[arg(long, value_name = "S")]
    penalty_scale: Option<f64>,
    /// The Krylov solves' preconditioner (overrides the deck's `[solver.linear]
    /// preconditioner`): auto, block-jacobi, asm, two-level, two-level-bj, amg or none.
    #[arg(long, value_name = "NAME", value_parser = parse_pc)]
    preconditioner: Option<alfe::linalg::PcKind>,
    /// Layers of overlap of the Schwarz subdomains (overrides `[solver.linear] overlap`).
    #[arg(long, value_name = "K")]
    overlap: Option<usize>,
}

fn parse_pc(s: &str) -> std::result::Result<alfe::linalg::PcKind, String> {
    alfe::linalg::PcKind::parse(s).ok_or_else(|| {
        format!(
            "expected one of {}",
            alfe::linalg::PcKind::ALL
                .iter()
                .map(|k| k.name())
                .collect::<Vec<_>>()
                .join(", ")
        )
    })
}

impl StudyArgs {
    fn overrides(&self) -> alfe::scene::Overrides {
        alfe::scene::Overrides {
            refine: self.refine,
            step_scale: self.step_scale,
            penalty_scale: self.penalty_scale,
            contact: None,
            preconditioner: self.preconditioner,
            overlap: self.overlap,
        }
    }
}

#[derive(ValueEnum, Clone, Copy, Debug)]
enum SolverArg {
    Newton,
    Bfgs,
    Jfnk,
    Auto,
}

#[derive(ValueEnum, Clone, Copy, Debug)]
enum ContactArg {
    Alm,
    Penalty,
}

impl SolverArg {
    fn kind(self) -> SolverKind {
        match self {
            SolverArg::Newton => SolverKind::Newton,
            SolverArg::Bfgs => SolverKind::Bfgs,
            SolverArg::Jfnk => SolverKind::Jfnk,
            SolverArg::Auto => SolverKind::Auto,
        }
    }
}

impl ContactArg {
    fn method(self) -> ContactMethod {
        match self {
            ContactArg::Alm => ContactMethod::Alm,
            ContactArg::Penalty => ContactMethod::Penalty,
        }
    }
}

/// The subcommand names (an argument that is none of them, nor an option, is a target
/// to run: `alfe my.toml`).
const COMMANDS: [&str; 9] = [
    "run",
    "scenes",
    "scene",
    "check",
    "import",
    "export",
    "schema",
    "partition",
    "help",
];

/// `alfe`, `alfe DECK` and `alfe --out DIR` mean `alfe run ...`.
fn with_default_command(raw: Vec<String>) -> Vec<String> {
    let mut args = vec!["alfe".to_string()];
    let explicit = match raw.first().map(String::as_str) {
        Some(a) => COMMANDS.contains(&a) || matches!(a, "-h" | "--help" | "-V" | "--version"),
        None => false,
    };
    if !explicit {
        args.push("run".into());
    }
    args.extend(raw);
    args
}

fn target(t: Option<String>) -> String {
    t.unwrap_or_else(|| alfe::scene::DEFAULT_SCENE.to_string())
}

/// A command-line mistake as one line (clap's first line, without its `error: `).
fn usage_error(e: &clap::Error) -> Error {
    let text = e.render().to_string();
    let mut lines = text.lines().map(str::trim).filter(|l| !l.is_empty());
    let mut first = lines
        .next()
        .unwrap_or("bad command line")
        .trim_start_matches("error: ")
        .to_string();
    // "the following required arguments were not provided:" names them below.
    if first.ends_with(':') {
        if let Some(next) = lines.next() {
            first = format!("{first} {next}");
        }
    }
    Error::input(format!("{first} (see `alfe --help`)"))
}

fn main_inner(comm: &dyn Comm, raw: Vec<String>) -> Result<()> {
    let root = comm.rank() == 0;
    let say = |s: &str| {
        if root {
            println!("{s}");
        }
    };
    let cli = match Cli::try_parse_from(with_default_command(raw)) {
        Ok(c) => c,
        Err(e) => {
            use clap::error::ErrorKind;
            return match e.kind() {
                ErrorKind::DisplayHelp
                | ErrorKind::DisplayVersion
                | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
                    if root {
                        print!("{}", e.render());
                    }
                    Ok(())
                }
                _ => Err(usage_error(&e)),
            };
        }
    };
    match cli.command {
        Command::Run(a) => {
            let deck = match (a.target, &a.restart) {
                (Some(t), _) => t,
                (None, Some(dir)) => dir.join("deck.toml").display().to_string(),
                (None, None) => alfe::scene::DEFAULT_SCENE.to_string(),
            };
            let opts = RunOptions {
                target: deck,
                out: a.out,
                partitions: a
                    .partitions
                    .unwrap_or_else(alfe::partition::cache::default_dir),
                repartition: a.repartition,
                quiet: a.quiet,
                solver: a.solver.map(SolverArg::kind),
                iterations: a.iterations,
                restart: a.restart,
                stop_after: a.stop_after.map(|n| n as usize),
                overrides: alfe::scene::Overrides {
                    contact: a.contact.map(ContactArg::method),
                    ..a.study.overrides()
                },
                export_system: a.export_system,
            };
            let s = app::run(comm, &opts)?.summary;
            say(&s.headline());
            Ok(())
        }
        Command::Scenes => {
            say(&scene_list());
            Ok(())
        }
        Command::Scene {
            what: SceneCommand::Show { name },
        } => {
            let (_, _, text) = alfe::scene::BUILTIN
                .iter()
                .find(|(n, _, _)| *n == name)
                .ok_or_else(|| {
                    Error::input(format!(
                        "unknown scene `{name}` (built-in scenes: {})",
                        alfe::scene::BUILTIN
                            .iter()
                            .map(|s| s.0)
                            .collect::<Vec<_>>()
                            .join(", ")
                    ))
                })?;
            if root {
                print!("{text}");
            }
            Ok(())
        }
        Command::Check {
            target: t,
            ranks,
            study,
        } => {
            let t = target(t);
            let o = study.overrides();
            let r = alfe::parallel::on_rank0(comm, || app::check(&t, ranks as usize, &o))?;
            if let Some(s) = r {
                print!("{s}");
            }
            Ok(())
        }
        Command::Schema => {
            if comm.rank() == 0 {
                use std::io::Write;
                // A closed pipe (`alfe schema | head`) is not an error.
                let _ = writeln!(std::io::stdout(), "{}", app::schema::deck_schema());
            }
            Ok(())
        }
        Command::Export { target, out } => {
            let r = alfe::parallel::on_rank0(comm, || app::export::export(&target, &out))?;
            if let Some(left) = r {
                for l in &left {
                    eprintln!("alfe: not exported: {l}");
                }
                say(&format!(
                    "alfe: wrote {} ({} things not exported, listed in its header)",
                    out.display(),
                    left.len()
                ));
            }
            Ok(())
        }
        Command::Import { file, out } => {
            let out = out.unwrap_or_else(|| {
                PathBuf::from(file.file_stem().unwrap_or(file.as_os_str())).with_extension("toml")
            });
            let r = alfe::parallel::on_rank0(comm, || app::import::import(&file, &out))?;
            if let Some(r) = r {
                for u in &r.untranslated {
                    eprintln!("alfe: not translated: {u}");
                }
                say(&format!(
                    "alfe: wrote {} ({} keywords or lines not translated, listed in the deck)",
                    r.written.join(", "),
                    r.untranslated.len()
                ));
            }
            Ok(())
        }
        Command::Partition {
            target: t,
            ranks,
            partitions,
        } => {
            let t = target(t);
            let partitions = partitions.unwrap_or_else(alfe::partition::cache::default_dir);
            let r =
                alfe::parallel::on_rank0(comm, || app::partition(&t, ranks as usize, &partitions))?;
            if let Some(s) = r {
                print!("{s}");
            }
            Ok(())
        }
    }
}

extern "C" {
    fn signal(signum: i32, handler: usize) -> usize;
}

fn main() {
    faer::set_global_parallelism(faer::Par::Seq);
    // A file-size limit (`ulimit -f`) is a full disk to the writer: a write error, not
    // SIGXFSZ (25 on Linux) killing one rank. SIG_IGN is 1.
    unsafe {
        signal(25, 1);
    }
    let Some(universe) = mpi::initialize() else {
        eprintln!("alfe: error: MPI could not be initialised");
        std::process::exit(1);
    };
    // A panic on one rank must not leave the others waiting in a collective.
    std::panic::set_hook(Box::new(|info| {
        eprintln!("alfe: internal error: {info}");
        unsafe {
            mpi::ffi::MPI_Abort(mpi::ffi::RSMPI_COMM_WORLD, 101);
        }
    }));
    // After MPI's own set-up, so these handlers are the ones that run.
    if let Err(e) = app::interrupt::install() {
        eprintln!("alfe: warning: SIGINT/SIGTERM will not stop a run cleanly: {e}");
    }
    let comm = MpiComm::new(universe.world());
    let raw: Vec<String> = std::env::args().skip(1).collect();
    let res = main_inner(&comm, raw);
    let code = match &res {
        Ok(()) => 0,
        Err(e) => {
            match e.kind {
                // The summary's headline: not an error of the run's input or solver.
                alfe::ErrorKind::Interrupted(_) if comm.rank() == 0 => eprintln!("{e}"),
                _ if comm.rank() == 0 => eprintln!("alfe: error: {e}"),
                _ => {}
            }
            e.exit_code()
        }
    };
    // An output file left open after a failed collective write (a full disk) cannot be
    // closed safely: end every rank now, with the run's exit code, instead of letting
    // MPI_Finalize make HDF5 close it and wait. The steps flushed before stay readable.
    if alfe::output::h5::LEFT_OPEN.load(std::sync::atomic::Ordering::SeqCst) {
        unsafe {
            mpi::ffi::MPI_Abort(mpi::ffi::RSMPI_COMM_WORLD, code);
        }
    }
    drop(comm);
    drop(universe);
    std::process::exit(code);
}

/// `alfe scenes`: one line per built-in scene, names aligned to the longest.
fn scene_list() -> String {
    let w = alfe::scene::BUILTIN
        .iter()
        .map(|b| b.0.len())
        .max()
        .unwrap_or(0);
    let lines: Vec<String> = alfe::scene::BUILTIN
        .iter()
        .map(|(name, desc, _)| format!("{name:<w$} {desc}"))
        .collect();
    lines.join("\n")
}
