//! The `alfe` command line: parse arguments, call the library, map errors to exit codes
//! (0 ok, 1 runtime failure, 2 bad input, 3 not converged; README "Exit codes").

use alfe::app::{self, RunOptions};
use alfe::parallel::{Comm, MpiComm};
use alfe::{Error, Result};
use std::path::PathBuf;

const USAGE: &str = "\
alfe — distributed implicit finite elements for solids in contact

usage:
  alfe                                   run the default scene (cantilever)
  alfe run [SCENE|DECK] [options]        run a built-in scene or a deck file
      --out DIR          results directory (default out/<scene>)
      --partitions DIR   partition cache directory (default partitions)
      --repartition      recompute a cached partition instead of using it
      --quiet            no progress lines
      --solver S         newton | bfgs | jfnk (overrides the deck's [solver] nonlinear)
      --contact M        alm | penalty (switches every [[walls]], [[entities]] and [[pairs]]
                         entry of the scene; [[bolts]] sections stay tied by ALM)
  alfe scenes                            list the built-in scenes
  alfe scene show NAME                   print a built-in scene's deck
  alfe check SCENE|DECK [--ranks N]      validate; print model size and partition quality
  alfe partition SCENE|DECK --ranks N [--partitions DIR]
                                         write the METIS partition to the cache
  alfe bench-linear [--cells NX,NY,NZ] [--rtol R] [--json FILE] [--export DIR]
                    [--pc block-jacobi|asm|amg [--rigid-body-modes]]
                                         linear-elastic block: assembly, preconditioner set-up,
                                         GMRES, HDF5 rates (scripts/bench-core uses it)
  alfe bench-residual [--cells NX,NY,NZ] [--reps N] [--json FILE]
                                         residual/tangent rates per material and formulation

Run on several ranks with `mpirun -n N alfe run ...`.
exit codes: 0 ok, 1 runtime failure, 2 bad input, 3 not converged";

struct Args {
    words: Vec<String>,
    flags: Vec<(String, Option<String>)>,
}

/// Split arguments into positional words and `--flag [value]` pairs.
fn parse_args(raw: &[String], valued: &[&str], bare: &[&str]) -> Result<Args> {
    let mut words = Vec::new();
    let mut flags = Vec::new();
    let mut i = 0;
    while i < raw.len() {
        let a = &raw[i];
        if let Some(name) = a.strip_prefix("--") {
            if valued.contains(&name) {
                let v = raw
                    .get(i + 1)
                    .ok_or_else(|| Error::input(format!("--{name}: expected a value")))?;
                flags.push((name.to_string(), Some(v.clone())));
                i += 2;
                continue;
            } else if bare.contains(&name) {
                flags.push((name.to_string(), None));
            } else {
                return Err(Error::input(format!(
                    "unknown option `{a}` (see `alfe --help`)"
                )));
            }
        } else {
            words.push(a.clone());
        }
        i += 1;
    }
    Ok(Args { words, flags })
}

impl Args {
    fn get(&self, name: &str) -> Option<&str> {
        self.flags
            .iter()
            .rev()
            .find(|(n, _)| n == name)
            .and_then(|(_, v)| v.as_deref())
    }
    fn has(&self, name: &str) -> bool {
        self.flags.iter().any(|(n, _)| n == name)
    }
    fn ranks(&self) -> Result<Option<usize>> {
        self.get("ranks")
            .map(|v| {
                v.parse::<usize>().ok().filter(|&n| n >= 1).ok_or_else(|| {
                    Error::input(format!("--ranks: expected a positive integer, got `{v}`"))
                })
            })
            .transpose()
    }
}

fn one_target(words: &[String], cmd: &str) -> Result<String> {
    match words {
        [] => Ok(alfe::scene::DEFAULT_SCENE.to_string()),
        [t] => Ok(t.clone()),
        _ => Err(Error::input(format!(
            "`alfe {cmd}` takes one scene name or deck path, got {}",
            words.len()
        ))),
    }
}

fn main_inner(comm: &dyn Comm, raw: &[String]) -> Result<()> {
    let root = comm.rank() == 0;
    let say = |s: &str| {
        if root {
            println!("{s}");
        }
    };
    let (cmd, rest) = match raw.first().map(|s| s.as_str()) {
        None => ("run", &raw[..0]),
        Some("-h") | Some("--help") | Some("help") => {
            say(USAGE);
            return Ok(());
        }
        Some("--version") => {
            say(concat!("alfe ", env!("CARGO_PKG_VERSION")));
            return Ok(());
        }
        Some(c) if c.starts_with("--") => ("run", raw),
        Some(c) => (c, &raw[1..]),
    };
    match cmd {
        "run" => {
            let a = parse_args(
                rest,
                &["out", "partitions", "solver", "contact"],
                &["repartition", "quiet"],
            )?;
            let solver = a
                .get("solver")
                .map(|s| {
                    alfe::solve::nonlinear::SolverKind::parse(s).ok_or_else(|| {
                        Error::input(format!(
                            "--solver: expected newton, bfgs or jfnk, got `{s}`"
                        ))
                    })
                })
                .transpose()?;
            let contact = a
                .get("contact")
                .map(|s| {
                    alfe::contact::wall::ContactMethod::parse(s).ok_or_else(|| {
                        Error::input(format!("--contact: expected alm or penalty, got `{s}`"))
                    })
                })
                .transpose()?;
            let opts = RunOptions {
                contact,
                target: one_target(&a.words, "run")?,
                out: a.get("out").map(PathBuf::from),
                partitions: PathBuf::from(a.get("partitions").unwrap_or("partitions")),
                repartition: a.has("repartition"),
                quiet: a.has("quiet"),
                solver,
            };
            let s = app::run(comm, &opts)?.summary;
            say(&format!(
                "alfe: {} steps converged in {:.2} s ({} nonlinear, {} GMRES iterations); results in {}/ ({}.h5, {}.xmf, history.csv, summary.json)",
                s.steps, s.wall_time_s, s.nonlinear_iterations, s.linear_iterations, s.output_dir, s.scene, s.scene
            ));
            Ok(())
        }
        "scenes" => {
            parse_args(rest, &[], &[])?;
            for (name, desc, _) in alfe::scene::BUILTIN {
                say(&format!("{name:<14} {desc}"));
            }
            Ok(())
        }
        "scene" => match rest {
            [show, name] if show == "show" => {
                let (_, _, text) = alfe::scene::BUILTIN
                    .iter()
                    .find(|(n, _, _)| n == name)
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
            _ => Err(Error::input("usage: alfe scene show NAME")),
        },
        "check" => {
            let a = parse_args(rest, &["ranks"], &[])?;
            let target = one_target(&a.words, "check")?;
            let ranks = a.ranks()?.unwrap_or(1);
            let r = app::on_rank0(comm, || app::check(&target, ranks))?;
            if let Some(s) = r {
                print!("{s}");
            }
            Ok(())
        }
        "partition" => {
            let a = parse_args(rest, &["ranks", "partitions"], &[])?;
            let target = one_target(&a.words, "partition")?;
            let ranks = a.ranks()?.ok_or_else(|| {
                Error::input("--ranks: required (the rank count to partition for)")
            })?;
            let dir = PathBuf::from(a.get("partitions").unwrap_or("partitions"));
            let r = app::on_rank0(comm, || app::partition(&target, ranks, &dir))?;
            if let Some(s) = r {
                print!("{s}");
            }
            Ok(())
        }
        "bench-linear" => {
            let a = parse_args(
                rest,
                &["cells", "rtol", "json", "export", "pc"],
                &["rigid-body-modes"],
            )?;
            alfe::bench::bench_linear(
                comm,
                a.get("cells"),
                a.get("rtol"),
                a.get("json"),
                a.get("export"),
                a.get("pc"),
                a.has("rigid-body-modes"),
            )
        }
        "bench-residual" => {
            let a = parse_args(rest, &["cells", "reps", "json"], &[])?;
            alfe::bench_residual::bench_residual(comm, a.get("cells"), a.get("reps"), a.get("json"))
        }
        other => Err(Error::input(format!(
            "unknown command `{other}` (see `alfe --help`)"
        ))),
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
    let comm = MpiComm::new(universe.world());
    let raw: Vec<String> = std::env::args().skip(1).collect();
    let res = main_inner(&comm, &raw);
    let code = match &res {
        Ok(()) => 0,
        Err(e) => {
            if comm.rank() == 0 {
                eprintln!("alfe: error: {e}");
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
