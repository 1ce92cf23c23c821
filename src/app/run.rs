//! `alfe run`: set up on every rank (deck, mesh, partition, model), run the analysis with
//! one observer that writes the output and the progress, and write the summary.

use super::check::nominal_steps;
use super::observe::Observer;
use super::progress::Progress;
use super::restart::{load_restart, Restart};
use super::summary::{
    contributions_summary, CoarseSummary, Phases, RestartedFrom, Summary, TrafficSummary,
};
use crate::model::distribute;
use crate::model::Model;
use crate::output::iterations::IterationLog;
use crate::output::log::Log;
use crate::output::record::RunRecord;
use crate::output::results::ResultsWriter;
use crate::output::schedule::{OutputClock, Schedule};
use crate::parallel::{broadcast, on_rank0, peak_rss_mb, rank0_outcome, Comm};
use crate::partition::cache;
use crate::scene::{RunSettings, Scene};
use crate::solve::nonlinear::SolverKind;
use crate::solve::stepping::{run_static, RunTotals};
use crate::solve::stepping::{Attempt, Resume, StepRecord};
use crate::solve::time::explicit::run_explicit;
use crate::solve::time::implicit::run_implicit;
use crate::solve::time::DynState;
use crate::solve::AnalysisKind;
use crate::{Error, Result};
use std::path::PathBuf;
use std::time::Instant;

#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Built-in scene name or deck path.
    pub target: String,
    /// Output directory; default `out/<scene>`.
    pub out: Option<PathBuf>,
    /// Partition cache directory.
    pub partitions: PathBuf,
    /// Recompute and overwrite a cached partition.
    pub repartition: bool,
    /// No progress lines.
    pub quiet: bool,
    /// Override the deck's nonlinear solver (`--solver`).
    pub solver: Option<SolverKind>,
    /// Write `iterations.csv` (`--iterations`; also the deck's `[output] iterations`).
    pub iterations: bool,
    /// Go on from the restart files of an earlier run's output directory.
    pub restart: Option<PathBuf>,
    /// End the run after this step (as if interrupted; resumable with `restart`).
    pub stop_after: Option<usize>,
    /// A study's changes to the deck (`--refine`, `--step-scale`, `--penalty-scale`).
    pub overrides: crate::scene::Overrides,
    /// Write the first Newton linear system in PETSc's format here (`--export-system`).
    pub export_system: Option<PathBuf>,
}

impl RunOptions {
    /// Run `target` with the defaults of `alfe run TARGET`.
    pub fn new(target: impl Into<String>) -> Self {
        Self {
            target: target.into(),
            out: None,
            partitions: crate::partition::cache::default_dir(),
            repartition: false,
            quiet: false,
            solver: None,
            iterations: false,
            restart: None,
            stop_after: None,
            overrides: crate::scene::Overrides::default(),
            export_system: None,
        }
    }
}

/// Everything a run needs on every rank: its piece of the model, how to run it, and
/// where the partition came from.
pub struct Setup {
    pub model: Model,
    pub run: RunSettings,
    /// "cache", "computed" or "trivial".
    pub partition: String,
    /// What the deck left to alfe and alfe chose (rank 0; for `deck.toml`).
    pub resolved: Vec<String>,
}

/// Collective: read and partition on rank 0, give each rank its piece and the run
/// settings (with `--solver` applied, and the FD length of the mesh).
pub fn setup(comm: &dyn Comm, opts: &RunOptions, phases: &mut Phases) -> Result<Setup> {
    let t0 = Instant::now();
    let mut t_part = 0.0;
    let pieces = on_rank0(comm, || {
        let src = crate::scene::load(&opts.target)?;
        let Scene {
            model: def,
            mut run,
        } = crate::scene::read_with(&src, &opts.overrides)?;
        if let Some(k) = opts.solver {
            run.solver.kind = k;
        }
        let tp = Instant::now();
        let edges = def.coupling_edges();
        let req = def.partition_request(&edges);
        let (part, origin, _) = cache::get(
            &opts.partitions,
            &run.name,
            &req,
            comm.size(),
            opts.repartition,
        )?;
        let pieces = distribute::split(&def, &part, comm.size());
        t_part = tp.elapsed().as_secs_f64();
        let origin = match origin {
            cache::Origin::Cache => "cache",
            cache::Origin::Computed => "computed",
            cache::Origin::Trivial => "trivial",
        };
        let resolved = run.parts.iter().map(|p| format!("part {p}")).collect();
        Ok((pieces, run, origin.to_string(), resolved))
    })?;
    let (pieces, run, origin, resolved) = match pieces {
        Some((p, r, o, v)) => (Some(p), Some(r), o, v),
        None => (None, None, String::new(), Vec::new()),
    };
    let tp = Instant::now();
    let local = distribute::scatter(comm, pieces)?;
    let mut run: RunSettings = broadcast(comm, run)?;
    let model = Model::new(comm, local)?;
    run.solver.char_length = model.char_length(comm);
    t_part += tp.elapsed().as_secs_f64();
    phases.partition = t_part;
    phases.setup = t0.elapsed().as_secs_f64() - t_part;
    Ok(Setup {
        model,
        run,
        partition: origin,
        resolved,
    })
}

/// What `run` hands back to a caller in the same process (tests, scripts in Rust).
pub struct RunOutcome {
    pub summary: Summary,
    /// The converged displacement of the owned nodes (3 per node, rank-contiguous order).
    pub u: Vec<f64>,
    pub model: Model,
    /// Every converged step's record.
    pub steps: Vec<crate::solve::stepping::StepRecord>,
}

impl RunOutcome {
    /// Displacement of every owned node indexed by the user's node number.
    pub fn displacement_by_node(&self) -> Vec<(usize, [f64; 3], [f64; 3])> {
        let l = &self.model.mesh;
        (0..l.n_owned())
            .map(|i| {
                (
                    l.orig_node[i] as usize,
                    l.coords[i],
                    [self.u[3 * i], self.u[3 * i + 1], self.u[3 * i + 2]],
                )
            })
            .collect()
    }
}

/// Collective: the whole `alfe run`. A run that did not converge returns
/// `Err(Convergence)` after writing everything converged so far and the summary. Once
/// the output directory is there, the run's record (`deck.toml`) and log (`log.txt`)
/// are written, and the log ends with the run's last line or its error.
pub fn run(comm: &dyn Comm, opts: &RunOptions) -> Result<RunOutcome> {
    let t_start = Instant::now();
    let record = RunRecord::now(&opts.target, comm.size());
    let mut phases = Phases::default();
    let Setup {
        mut model,
        run: mut settings,
        partition: origin,
        mut resolved,
    } = setup(comm, opts, &mut phases)?;
    settings.solver.preconditioner = settings
        .solver
        .preconditioner
        .resolve(comm.size(), model.dofs.dofs.global_len());
    settings.solver.export_system = opts.export_system.clone();
    let restart = match &opts.restart {
        Some(dir) => Some(load_restart(comm, dir, &mut model, &settings)?),
        None => None,
    };
    let out = match (&opts.out, &opts.restart) {
        (Some(o), _) => o.clone(),
        (None, Some(dir)) => {
            // `results/` restarts into `results-restart`, beside it.
            let name = dir.file_name().map_or_else(
                || "restart".to_string(),
                |n| format!("{}-restart", n.to_string_lossy()),
            );
            dir.parent().unwrap_or(std::path::Path::new("")).join(name)
        }
        (None, None) => PathBuf::from("out").join(&settings.name),
    };
    if let Some(dir) = &opts.restart {
        let same = |a: &std::path::Path, b: &std::path::Path| {
            std::fs::canonicalize(a)
                .ok()
                .is_some_and(|x| std::fs::canonicalize(b).ok() == Some(x))
        };
        if same(dir, &out) {
            return Err(Error::input(format!(
                "--out {}: a restart writes to another directory than the one it restarts from",
                out.display()
            )));
        }
    }
    // One run per output directory (rank 0 holds the lock until the run ends).
    let _lock = on_rank0(comm, || crate::output::lock::OutLock::acquire(&out))?;
    let mut log = Log::open(&out, comm.rank() == 0, opts.quiet);
    // Choices known to lock (scene/parts.rs), once, on rank 0: stderr, even when quiet,
    // and the log.
    if comm.rank() == 0 {
        for w in &settings.warnings {
            let line = format!("alfe: warning: {w}");
            eprintln!("{line}");
            log.file_only(&line);
        }
    }
    if settings.analysis.kind != AnalysisKind::Explicit {
        resolved.push(format!(
            "nonlinear = \"{}\", preconditioner = \"{}\", finite-difference length h = {:.4e}",
            settings.solver.kind.name(),
            settings.solver.preconditioner.name(),
            settings.solver.char_length
        ));
    }
    let written = on_rank0(comm, || {
        record
            .write_deck(&out, &settings.echo, &resolved)
            .map_err(|e| {
                Error::runtime(format!(
                    "cannot write {}: {e}",
                    out.join("deck.toml").display()
                ))
            })
    });
    let res = written.and_then(|_| {
        let run = Prepared {
            model,
            settings,
            restart,
            origin,
            record,
            t_start,
            phases,
        };
        execute(comm, opts, &out, &mut log, run)
    });
    match &res {
        Ok(o) => log.file_only(&o.summary.headline()),
        Err(e) => log.file_only(&format!("alfe: error: {e}")),
    }
    res
}

/// What [`announce`] found: the method's name, the explicit time step, the history's
/// columns.
struct Intro {
    method: String,
    explicit_dt: Option<(f64, crate::model::dynamics::StableStep)>,
    header: Vec<String>,
}

/// The run's first lines (scene, ranks, method, sizes; the explicit time step; where a
/// restart goes on from), and the checks that need the model: an explicit run cannot
/// restart, a quantity must name one of the history's columns.
fn announce(
    comm: &dyn Comm,
    model: &Model,
    settings: &RunSettings,
    restart: &Option<Restart>,
    log: &mut Log,
) -> Result<Intro> {
    let analysis = &settings.analysis;
    let nopts = &settings.solver;
    let kind = analysis.kind;
    // Explicit runs: the time step from the mesh (an input error if the deck's is unstable).
    let explicit_dt = if kind == AnalysisKind::Explicit {
        Some(crate::solve::time::explicit::explicit_time_step(
            comm, model, analysis,
        )?)
    } else {
        None
    };
    let method = match kind {
        AnalysisKind::Explicit => "central-difference".to_string(),
        _ => nopts.kind.name().to_string(),
    };
    log.line(&format!(
        "alfe: scene {} on {} rank(s) with {method}{}: {} nodes, {} elements, {} unknowns, {} nominal steps",
        settings.name,
        comm.size(),
        match kind {
            AnalysisKind::Explicit => String::new(),
            _ => format!(" ({})", nopts.preconditioner.name()),
        },
        model.mesh.n_nodes_global,
        model.mesh.n_elems_global,
        model.dofs.dofs.global_len(),
        nominal_steps(analysis)
    ));
    if let Some((dt, st)) = &explicit_dt {
        log.line(&format!(
            "explicit: stable step {:.4e} (L_e = {:.4e}, c_d = {:.4e}), using {dt:.4e}, {} steps",
            st.dt,
            st.length,
            st.wave_speed,
            (analysis.end_time / dt).ceil()
        ));
    }
    if restart.is_some() && kind == AnalysisKind::Explicit {
        return Err(Error::input(
            "--restart: explicit runs cannot be restarted (static and implicit ones can)",
        ));
    }
    let header = crate::output::results::history_columns(
        model,
        analysis.is_dynamic(),
        !analysis.stages.is_empty(),
    );
    if let Some((i, c)) = crate::output::quantities::missing_columns(&settings.quantities, &header)
        .into_iter()
        .next()
    {
        return Err(Error::input(format!(
            "quantities[{i}].expression: this run has no history column `{c}` (its columns: {})",
            header.join(", ")
        )));
    }
    if let Some(r) = restart {
        log.line(&format!(
            "restart from {} after step {} (t = {})",
            r.dir.display(),
            r.step,
            r.time
        ));
    }
    Ok(Intro {
        method,
        explicit_dt,
        header,
    })
}

/// The output schedule of this run; after a restart, counted on from the earlier run's
/// rows (rank 0 read them; every rank must agree on which steps write fields).
fn schedule(
    comm: &dyn Comm,
    settings: &RunSettings,
    restart: &Option<Restart>,
    header: &[String],
    earlier: &[Vec<f64>],
) -> Schedule {
    let analysis = &settings.analysis;
    let mut s = if analysis.kind != AnalysisKind::Static {
        Schedule::Interval(OutputClock::new(
            settings.output.interval,
            analysis.end_time,
        ))
    } else {
        Schedule::Increments {
            every: settings.output.every,
            stage_every: settings.output.stage_every.clone(),
            stages: analysis.stages.clone(),
            end_time: analysis.end_time,
            seen: (0, 0),
        }
    };
    if let Some(r) = restart {
        let mut seen = [0.0, 0.0];
        if analysis.kind == AnalysisKind::Static {
            if let Some(k) = header.iter().position(|h| h == "analysis_step") {
                if let Some(&stage) = earlier.last().and_then(|r| r.get(k)) {
                    let n = earlier.iter().filter(|r| r.get(k) == Some(&stage)).count();
                    seen = [(stage - 1.0).max(0.0), n as f64];
                }
            }
            comm.allreduce_max(&mut seen);
        }
        s.resume(r.time, seen[0] as usize, seen[1] as usize);
    }
    s
}

/// Run the analysis the settings say, every step through `obs`; the totals and the
/// final solution.
fn analyze(
    comm: &dyn Comm,
    model: &mut Model,
    settings: &RunSettings,
    restart: &Option<Restart>,
    explicit_dt: &Option<(f64, crate::model::dynamics::StableStep)>,
    obs: &mut Observer,
) -> (Result<RunTotals>, Vec<f64>) {
    let analysis = &settings.analysis;
    let nopts = &settings.solver;
    let resume = restart.as_ref().map(|r| &r.resume);
    if analysis.kind == AnalysisKind::Static {
        let mut u = restart.as_ref().map(|r| r.u.clone()).unwrap_or_default();
        if restart.is_none() {
            u.resize(model.n_owned_dofs(), 0.0);
            if let Err(e) = obs.initial(&u, model) {
                return (Err(e), u);
            }
        }
        let t = run_static(
            comm,
            model,
            &mut u,
            analysis,
            nopts,
            resume,
            &mut |rec, u, m, resume| obs.step(rec, u, m, &[], Some(resume)),
        );
        return (t, u);
    }
    let mut state = DynState::default();
    if let Some(r) = restart {
        state.u = r.u.clone();
    }
    let mut observe =
        |rec: &StepRecord, s: &DynState, m: &Model, resume: Option<&dyn Fn() -> Resume>| {
            let nodal: [(&str, &[f64]); 2] = [("velocity", &s.v), ("acceleration", &s.a)];
            obs.step(rec, &s.u, m, &nodal, resume)
        };
    let t = match explicit_dt {
        Some((dt, stable)) => {
            run_explicit(comm, model, &mut state, analysis, *dt, stable, &mut observe)
        }
        None => run_implicit(
            comm,
            model,
            &mut state,
            analysis,
            nopts,
            resume,
            &mut observe,
        ),
    };
    (t, state.u)
}

/// The quantities of interest, from the history as written (rank 0), reported in the log.
fn quantities(
    comm: &dyn Comm,
    settings: &RunSettings,
    out: &std::path::Path,
    log: &mut Log,
) -> Vec<crate::output::quantities::QuantityValue> {
    let quantities = if comm.rank() == 0 && !settings.quantities.is_empty() {
        match crate::output::results::read_history(out) {
            Ok((head, rows)) => {
                crate::output::quantities::evaluate(&settings.quantities, &head, &rows)
            }
            Err(e) => {
                log.line(&format!(
                    "warning: cannot read {} for the quantities: {e}",
                    out.join("history.csv").display()
                ));
                Vec::new()
            }
        }
    } else {
        Vec::new()
    };
    for line in crate::output::quantities::report(&quantities) {
        log.line(&line);
    }
    quantities
}

/// Each analysis step's counts and wall time (`summary.json` `analysis_steps`).
fn analysis_steps(
    settings: &RunSettings,
    totals: &RunTotals,
    records: &[StepRecord],
) -> Vec<serde_json::Value> {
    settings
        .analysis
        .stages
        .iter()
        .enumerate()
        .map(|(k, st)| {
            let b = totals.by_stage.get(k).cloned().unwrap_or_default();
            let mine = records.iter().filter(|r| r.stage == k && r.step > 0);
            serde_json::json!({
                "name": st.name,
                "start_time": st.start,
                "end_time": st.end,
                "completed": records.last().is_some_and(|r| r.time >= st.end * (1.0 - 1e-9)),
                "increments": b.increments,
                "nonlinear_iterations": b.nonlinear_iterations,
                "linear_iterations": b.linear_iterations,
                "retries": b.retries,
                "wall_time_s": mine.map(|r| r.wall_seconds).sum::<f64>(),
            })
        })
        .collect()
}

/// Collective: rank 0 writes `summary.json`; every rank learns whether it could.
fn write_summary(comm: &dyn Comm, out: &std::path::Path, summary: &Summary) -> Result<()> {
    let r = if comm.rank() == 0 {
        serde_json::to_string_pretty(summary)
            .map_err(|e| Error::runtime(e.to_string()))
            .and_then(|s| {
                std::fs::write(out.join("summary.json"), s + "\n")
                    .map_err(|e| Error::runtime(format!("cannot write summary.json: {e}")))
            })
    } else {
        Ok(())
    };
    rank0_outcome(comm, r)
}

/// The earlier run's history up to the restart (copied into this run's), so quantities
/// cover the whole run; none without a restart or when it cannot be read (a warning).
fn earlier_history(
    comm: &dyn Comm,
    writer: &mut ResultsWriter,
    restart: &Option<Restart>,
    log: &mut Log,
) -> Result<Vec<Vec<f64>>> {
    if let Some(why) = restart
        .as_ref()
        .and_then(|r| writer.carry_steps(comm, &r.dir, r.time))
    {
        log.line(&format!(
            "warning: {why}; the .xmf begins at the restart (the earlier run's .xmf has the steps before it)"
        ));
    }
    Ok(match restart {
        Some(r) => match writer.carry_history(comm, &r.dir, r.step)? {
            Ok(rows) => rows,
            Err(why) => {
                log.line(&format!(
                    "warning: {why}; history.csv and the quantities begin at the restart"
                ));
                Vec::new()
            }
        },
        None => Vec::new(),
    })
}

/// The failed attempts at the step that stopped the run (`iterations.csv`), numbered
/// after the last converged step.
fn log_failed_attempts(
    iters: &mut IterationLog,
    totals: &RunTotals,
    records: &[StepRecord],
    restart: &Option<Restart>,
) {
    let failed: Vec<&Attempt> = totals.failed_last.iter().collect();
    let last_step = records
        .last()
        .map(|r| r.step)
        .or(restart.as_ref().map(|r| r.step))
        .unwrap_or(0);
    iters.step(last_step + 1, &failed, false);
}

/// Where a restarted run went on from, for its summary.
fn restarted_from(restart: &Option<Restart>) -> Option<RestartedFrom> {
    restart.as_ref().map(|r| RestartedFrom {
        dir: r.dir.display().to_string(),
        step: r.step,
        time: r.time,
    })
}

/// What [`run`] has set up for [`execute`]: the model and its settings, the restart
/// state, and what the summary reports of the set-up (partition origin, the run's
/// record, its start and phase times so far).
struct Prepared {
    model: Model,
    settings: RunSettings,
    restart: Option<Restart>,
    origin: String,
    record: RunRecord,
    t_start: Instant,
    phases: Phases,
}

/// A run that failed (exit 3) or was stopped by a signal (128 + signal) is an error
/// once its summary is written.
fn ending(failure: Option<String>, interrupted: Option<i32>, summary: &Summary) -> Result<()> {
    if let Some(f) = failure {
        return Err(Error::convergence(format!(
            "{f}; {} converged step(s) written to {}",
            summary.steps, summary.output_dir
        )));
    }
    match interrupted {
        Some(sig) => Err(Error::interrupted(sig, summary.headline())),
        None => Ok(()),
    }
}

/// The analysis, the outputs and the summary of [`run`].
fn execute(
    comm: &dyn Comm,
    opts: &RunOptions,
    out: &std::path::Path,
    log: &mut Log,
    run: Prepared,
) -> Result<RunOutcome> {
    let Prepared {
        mut model,
        settings,
        restart,
        origin,
        record,
        t_start,
        mut phases,
    } = run;
    let scene = settings.name.clone();
    let analysis = &settings.analysis;
    let mut writer = ResultsWriter::create(
        comm,
        out,
        &model,
        &scene,
        settings.units.describe(),
        analysis.is_dynamic(),
        !analysis.stages.is_empty(),
    )?;
    let nopts = &settings.solver;
    let kind = analysis.kind;
    let Intro {
        method,
        explicit_dt,
        header,
    } = announce(comm, &model, &settings, &restart, log)?;
    let t0 = restart.as_ref().map_or(0.0, |r| r.time);
    let earlier = earlier_history(comm, &mut writer, &restart, log)?;
    let mut obs = Observer {
        comm,
        out,
        progress: Progress::new(
            std::mem::replace(log, Log::silent()),
            &model,
            t0,
            analysis.end_time,
        ),
        iters: IterationLog::open(
            out,
            opts.iterations || settings.output.iterations,
            comm.rank() == 0,
        ),
        schedule: schedule(comm, &settings, &restart, &header, &earlier),
        writer,
        records: Vec::new(),
        t_prev: t0,
        scene: scene.clone(),
        deck_print: crate::output::checkpoint::fingerprint(&settings.echo),
        stop_after: opts.stop_after,
        interrupted: None,
        solver: (kind == AnalysisKind::Static).then(|| nopts.kind.name().to_string()),
        set_names: model.reaction_sets.clone(),
    };
    let (totals, u) = analyze(
        comm,
        &mut model,
        &settings,
        &restart,
        &explicit_dt,
        &mut obs,
    );
    let Observer {
        writer,
        progress,
        mut iters,
        records,
        interrupted,
        ..
    } = obs;
    *log = progress.log;
    let totals = totals?;
    log_failed_attempts(&mut iters, &totals, &records, &restart);
    phases.assembly = totals.seconds_assembly;
    phases.linear_solve = totals.seconds_linear;
    phases.preconditioner_setup = totals.seconds_pc_setup;
    phases.output = writer.seconds;
    let traffic = TrafficSummary::gather(comm);
    let coarse_space = CoarseSummary::gather(comm, totals.coarse);
    let phases = phases.max_over_ranks(comm);
    let rss = comm.allgather_f64(peak_rss_mb());
    let message = totals.failure.clone().unwrap_or_else(|| "converged".into());
    let contributions = contributions_summary(&model, &records, &header, &earlier);
    let quantities = quantities(comm, &settings, out, log);
    let summary = Summary {
        scene: scene.clone(),
        units: settings.units.describe().into(),
        ranks: comm.size(),
        nodes: model.mesh.n_nodes_global,
        elements: model.mesh.n_elems_global,
        unknowns: model.dofs.dofs.global_len(),
        solver: method,
        preconditioner: match kind {
            AnalysisKind::Explicit => "none".into(),
            _ => nopts.preconditioner.name().into(),
        },
        coarse_space,
        analysis: kind.name().into(),
        time_step: explicit_dt
            .as_ref()
            .map(|(dt, _)| *dt)
            .unwrap_or(analysis.step),
        stable_time_step: explicit_dt.as_ref().map(|(_, s)| s.dt),
        steps: totals.steps,
        converged: totals.converged,
        nonlinear_iterations: totals.nonlinear_iterations,
        linear_iterations: totals.linear_iterations,
        residual_evaluations: totals.residual_evaluations,
        factorizations: totals.factorizations,
        retries: totals.retries,
        solver_counts: totals.counts.clone(),
        contributions,
        analysis_steps: analysis_steps(&settings, &totals, &records),
        wall_time_s: t_start.elapsed().as_secs_f64(),
        phases,
        traffic,
        peak_rss_mb: rss.iter().cloned().fold(0.0, f64::max),
        peak_rss_mb_per_rank: rss,
        partition: origin,
        message: message.clone(),
        failure_reason: totals.failure_reason,
        output_dir: out.display().to_string(),
        run: record,
        restarted_from: restarted_from(&restart),
        stopped: totals.stopped,
        interrupted: interrupted.map(super::interrupt::name),
        quantities,
    };
    drop(writer);
    write_summary(comm, out, &summary)?;
    ending(totals.failure, interrupted, &summary)?;
    Ok(RunOutcome {
        summary,
        u,
        model,
        steps: records,
    })
}
