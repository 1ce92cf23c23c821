//! What the commands do: `run`, `check`, `partition`. The CLI (`main.rs`) only parses
//! arguments and maps errors to exit codes; tests call these functions directly.

mod progress;

use crate::model::def::ModelDef;
use crate::model::distribute;
use crate::model::Model;
use crate::output::iterations::IterationLog;
use crate::output::log::Log;
use crate::output::record::RunRecord;
use crate::output::results::ResultsWriter;
use crate::parallel::{Comm, Traffic};
use crate::partition::{cache, quality};
use crate::scene::{RunSettings, Scene};
use crate::solve::nonlinear::SolverKind;
use crate::solve::stepping::{run_static, RunTotals};
use crate::solve::stepping::{Attempt, Flow, Resume, StepRecord};
use crate::solve::time::explicit::run_explicit;
use crate::solve::time::implicit::run_implicit;
use crate::solve::time::{DynState, OutputClock};
use crate::solve::{Analysis, AnalysisKind};
use crate::{Error, ErrorKind, Result};
use std::collections::BTreeMap;
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
    /// Switch every wall's enforcement (`--contact alm|penalty`).
    pub contact: Option<crate::contact::wall::ContactMethod>,
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
            partitions: PathBuf::from("partitions"),
            repartition: false,
            quiet: false,
            solver: None,
            contact: None,
            iterations: false,
            restart: None,
            stop_after: None,
            overrides: crate::scene::Overrides::default(),
            export_system: None,
        }
    }
}

/// What a run leaves behind besides its files (also written to `summary.json`).
#[derive(Debug, Clone, serde::Serialize)]
pub struct Summary {
    pub scene: String,
    pub units: String,
    pub ranks: usize,
    pub nodes: usize,
    pub elements: usize,
    pub unknowns: usize,
    /// The nonlinear solver used (`central-difference` for explicit runs).
    pub solver: String,
    /// The preconditioner of the linear solves ("auto" resolved; explicit runs have none).
    pub preconditioner: String,
    /// A two-level preconditioner's coarse space: its size, and what its setups cost
    /// (the largest over the ranks).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub coarse_space: Option<CoarseSummary>,
    /// `static`, `implicit` or `explicit`.
    pub analysis: String,
    /// The (first) time step: the deck's step, or the explicit step used.
    pub time_step: f64,
    /// Explicit runs: the stable step min_e L_e / c_d before the factor.
    pub stable_time_step: Option<f64>,
    pub steps: usize,
    pub converged: bool,
    pub nonlinear_iterations: usize,
    pub linear_iterations: usize,
    pub residual_evaluations: usize,
    pub factorizations: usize,
    pub retries: usize,
    /// What the model's contributions report: the largest value over the run of the
    /// history columns that ask for it (`max_penetration` with contact), and each
    /// contribution's entry at the last converged step by group (`walls`: force, moment
    /// and displacement of each wall).
    #[serde(flatten)]
    pub contributions: BTreeMap<String, serde_json::Value>,
    /// Analysis steps (the deck's `[[steps]]`), in order: name, end time and counts
    /// (failed attempts included), wall time of their converged increments. Absent
    /// without steps.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub analysis_steps: Vec<serde_json::Value>,
    pub wall_time_s: f64,
    /// Wall time by phase (max over ranks): setup, partition, assembly, linear_solve, output.
    pub phases: Phases,
    /// Messages alfe sent (hypre's own are not counted): the largest count of each kind
    /// over the ranks, and the sum over ranks.
    pub traffic: TrafficSummary,
    /// Largest peak resident set over the ranks, and every rank's.
    pub peak_rss_mb: f64,
    pub peak_rss_mb_per_rank: Vec<f64>,
    /// Where the partition came from: "cache", "computed" or "trivial".
    pub partition: String,
    pub message: String,
    pub output_dir: String,
    /// Which alfe ran what, how and when (also the header of `deck.toml`).
    pub run: RunRecord,
    /// A restart: the directory, step and time it went on from.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub restarted_from: Option<RestartedFrom>,
    /// The run was stopped after a step on request (`--stop-after`).
    pub stopped: bool,
    /// The scene's quantities of interest over this run (rank 0's summary).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub quantities: Vec<crate::output::quantities::QuantityValue>,
}

/// Where a restarted run went on from (summary.json's `restarted_from`).
#[derive(Debug, Clone, serde::Serialize)]
pub struct RestartedFrom {
    pub dir: String,
    pub step: usize,
    pub time: f64,
}

impl Summary {
    /// The number of the last step done (a restarted run counts from its start).
    fn run_steps_end(&self) -> usize {
        self.restarted_from.as_ref().map_or(0, |r| r.step) + self.steps
    }

    /// The one line a finished run ends with.
    pub fn headline(&self) -> String {
        if self.stopped {
            return format!(
                "alfe: stopped after step {} as asked ({:.2} s); go on with `alfe run --restart {}`",
                self.run_steps_end(),
                self.wall_time_s,
                self.output_dir
            );
        }
        format!(
            "alfe: {} steps converged in {:.2} s ({} nonlinear, {} GMRES iterations); results in {}/ ({}.h5, {}.xmf, history.csv, summary.json, deck.toml, log.txt)",
            self.steps,
            self.wall_time_s,
            self.nonlinear_iterations,
            self.linear_iterations,
            self.output_dir,
            self.scene,
            self.scene
        )
    }
}

#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct Phases {
    pub setup: f64,
    pub partition: f64,
    pub assembly: f64,
    pub linear_solve: f64,
    /// Of `linear_solve`, the preconditioner's setups (factorizations, coarse spaces);
    /// the rest is GMRES.
    pub preconditioner_setup: f64,
    pub output: f64,
}

/// summary.json's `coarse_space`: sizes, and seconds of the last setup by phase and of
/// all setups, each the largest over the ranks.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct CoarseSummary {
    pub dimension: usize,
    pub kept: usize,
    pub components: usize,
    pub setups: usize,
    pub max_local_functions: usize,
    pub max_columns: usize,
    pub extension_s: f64,
    pub galerkin_s: f64,
    pub factor_s: f64,
    pub symbolic_s: f64,
    pub total_s: f64,
}

impl CoarseSummary {
    /// Collective.
    fn gather(comm: &dyn Comm, c: Option<crate::linalg::CoarseStats>) -> Option<Self> {
        let c = c.unwrap_or_default();
        let mut v = [
            c.local_functions as f64,
            c.columns as f64,
            c.extension_seconds,
            c.galerkin_seconds,
            c.factor_seconds,
            c.symbolic_seconds,
            c.total_seconds,
            c.dimension as f64,
        ];
        comm.allreduce_max(&mut v);
        (v[7] > 0.0).then(|| Self {
            dimension: c.dimension,
            kept: c.kept,
            components: c.components,
            setups: c.setups,
            max_local_functions: v[0] as usize,
            max_columns: v[1] as usize,
            extension_s: v[2],
            galerkin_s: v[3],
            factor_s: v[4],
            symbolic_s: v[5],
            total_s: v[6],
        })
    }
}

#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct TrafficSummary {
    pub max_per_rank: Traffic,
    pub total: Traffic,
}

impl TrafficSummary {
    /// Gather every rank's traffic (taken before the gathering reductions).
    fn gather(comm: &dyn Comm) -> Self {
        let t = comm.traffic();
        let mine = [t.reductions, t.exchanges, t.messages, t.bytes];
        let mut max = mine;
        let mut sum = mine;
        comm.allreduce_max_u64(&mut max);
        comm.allreduce_sum_u64(&mut sum);
        let of = |v: [u64; 4]| Traffic {
            reductions: v[0],
            exchanges: v[1],
            messages: v[2],
            bytes: v[3],
        };
        Self {
            max_per_rank: of(max),
            total: of(sum),
        }
    }
}

/// Peak resident set size of this process in MB (Linux VmHWM).
pub fn peak_rss_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map(|kb| kb / 1024.0)
        .unwrap_or(0.0)
}

/// Run `f` on rank 0 only and let every rank know whether it failed (with the same
/// error), so that a bad deck stops all ranks together instead of leaving them waiting.
pub fn on_rank0<T>(comm: &dyn Comm, f: impl FnOnce() -> Result<T>) -> Result<Option<T>> {
    let (res, mut msg) = if comm.rank() == 0 {
        match f() {
            Ok(v) => (Some(v), vec![0u8]),
            Err(e) => {
                let code = match e.kind {
                    ErrorKind::Input => 1u8,
                    ErrorKind::Convergence => 2,
                    ErrorKind::Runtime => 3,
                };
                let mut m = vec![code];
                m.extend_from_slice(e.message.as_bytes());
                (None, m)
            }
        }
    } else {
        (None, Vec::new())
    };
    comm.broadcast_bytes(0, &mut msg);
    if msg[0] == 0 {
        return Ok(res);
    }
    let text = String::from_utf8_lossy(&msg[1..]).to_string();
    Err(match msg[0] {
        1 => Error::input(text),
        2 => Error::convergence(text),
        _ => Error::runtime(text),
    })
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
/// settings (with `--solver` and `--contact` applied, and the FD length of the mesh).
pub fn setup(comm: &dyn Comm, opts: &RunOptions, phases: &mut Phases) -> Result<Setup> {
    let t0 = Instant::now();
    let mut t_part = 0.0;
    let pieces = on_rank0(comm, || {
        let src = crate::scene::load(&opts.target)?;
        let Scene {
            model: mut def,
            mut run,
        } = crate::scene::read_with(&src, &opts.overrides)?;
        if let Some(m) = opts.contact {
            for c in &mut def.contributions {
                c.kind_mut().set_contact_method(m);
            }
        }
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
        let resolved = def
            .part_names
            .iter()
            .zip(&def.part_formulation)
            .map(|(n, f)| format!("part {n}: {}", f.describe()))
            .collect();
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

/// Collective: rank 0's value on every rank (serialised).
fn broadcast<T: serde::Serialize + serde::de::DeserializeOwned>(
    comm: &dyn Comm,
    value: Option<T>,
) -> Result<T> {
    let mut bytes = match &value {
        Some(v) if comm.rank() == 0 => bincode::serialize(v)
            .map_err(|e| Error::runtime(format!("serialising run settings: {e}")))?,
        _ => Vec::new(),
    };
    comm.broadcast_bytes(0, &mut bytes);
    bincode::deserialize(&bytes).map_err(|e| Error::runtime(format!("receiving run settings: {e}")))
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
        execute(
            comm, opts, model, settings, origin, record, &out, t_start, phases, &mut log, restart,
        )
    });
    match &res {
        Ok(o) => log.file_only(&o.summary.headline()),
        Err(e) => log.file_only(&format!("alfe: error: {e}")),
    }
    res
}

/// The analysis, the outputs and the summary of [`run`].
#[allow(clippy::too_many_arguments)]
fn execute(
    comm: &dyn Comm,
    opts: &RunOptions,
    mut model: Model,
    settings: RunSettings,
    origin: String,
    record: RunRecord,
    out: &std::path::Path,
    t_start: Instant,
    mut phases: Phases,
    log: &mut Log,
    restart: Option<Restart>,
) -> Result<RunOutcome> {
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
    let every = settings.output.every;
    let end_time = analysis.end_time;
    let kind = analysis.kind;
    let n_steps = nominal_steps(analysis);
    // Explicit runs: the time step from the mesh (an input error if the deck's is unstable).
    let explicit_dt = if kind == AnalysisKind::Explicit {
        Some(crate::solve::time::explicit::explicit_time_step(
            comm, &model, analysis,
        )?)
    } else {
        None
    };
    let method = match kind {
        AnalysisKind::Explicit => "central-difference".to_string(),
        _ => nopts.kind.name().to_string(),
    };
    log.line(&format!(
        "alfe: scene {scene} on {} rank(s) with {method}{}: {} nodes, {} elements, {} unknowns, {} nominal steps",
        comm.size(),
        match kind {
            AnalysisKind::Explicit => String::new(),
            _ => format!(" ({})", nopts.preconditioner.name()),
        },
        model.mesh.n_nodes_global,
        model.mesh.n_elems_global,
        model.dofs.dofs.global_len(),
        n_steps
    ));
    if let Some((dt, st)) = &explicit_dt {
        log.line(&format!(
            "explicit: stable step {:.4e} (L_e = {:.4e}, c_d = {:.4e}), using {dt:.4e}, {} steps",
            st.dt,
            st.length,
            st.wave_speed,
            (end_time / dt).ceil()
        ));
    }
    if restart.is_some() && kind == AnalysisKind::Explicit {
        return Err(Error::input(
            "--restart: explicit runs cannot be restarted (static and implicit ones can)",
        ));
    }
    let header = crate::output::results::history_columns(
        &model,
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
    let t0 = restart.as_ref().map_or(0.0, |r| r.time);
    if let Some(r) = &restart {
        log.line(&format!(
            "restart from {} after step {} (t = {})",
            r.dir.display(),
            r.step,
            r.time
        ));
    }
    // The earlier run's history up to the restart, so quantities cover the whole run.
    let earlier = match &restart {
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
    };
    let mut progress =
        progress::Progress::new(std::mem::replace(log, Log::silent()), &model, t0, end_time);
    let deck_print = crate::output::checkpoint::fingerprint(&settings.echo);
    // A restart file after every step that writes fields (each rank its own).
    let save = |rec: &StepRecord, u: &[f64], m: &Model, resume: &dyn Fn() -> Resume| {
        crate::output::checkpoint::write(
            comm,
            out,
            &crate::output::checkpoint::Checkpoint {
                format: crate::output::checkpoint::FORMAT,
                alfe: crate::VERSION.into(),
                scene: scene.clone(),
                deck: deck_print,
                ranks: comm.size(),
                rank: comm.rank(),
                first_dof: m.dofs.dofs.start(),
                n_dofs: u.len(),
                step: rec.step,
                time: rec.time,
                u: u.to_vec(),
                model: m.saved_state(),
                resume: resume(),
            },
        )
    };
    let flow = |rec: &StepRecord| match opts.stop_after {
        Some(n) if rec.step >= n => Flow::Stop,
        _ => Flow::Continue,
    };
    let mut iters = IterationLog::open(
        out,
        opts.iterations || settings.output.iterations,
        comm.rank() == 0,
    );
    // The attempts at a converged step, its failed ones first (`iterations.csv`).
    let mut t_prev = t0;
    let mut log_attempts = |rec: &StepRecord| {
        let ok = Attempt {
            t_start: t_prev,
            t_end: rec.time,
            stats: rec.stats.clone(),
        };
        let all: Vec<&Attempt> = rec.failed.iter().chain(std::iter::once(&ok)).collect();
        iters.step(rec.step, &all, true);
        t_prev = rec.time;
    };
    let mut u = Vec::new();
    let mut records = Vec::new();
    let set_names = model.reaction_sets.clone();
    let totals: Result<RunTotals> = if kind != AnalysisKind::Static {
        let interval = settings.output.interval;
        let mut clock = OutputClock::new(interval, end_time);
        let mut state = DynState::default();
        if let Some(r) = &restart {
            state.u = r.u.clone();
            clock.skip_to(r.time);
        }
        let mut observe = |rec: &StepRecord,
                           s: &DynState,
                           m: &Model,
                           resume: Option<&dyn Fn() -> Resume>|
         -> Result<Flow> {
            let fields = clock.due(rec.time);
            let nodal: [(&str, &[f64]); 2] = [("velocity", &s.v), ("acceleration", &s.a)];
            writer.step_with(comm, rec, &s.u, m, fields, &nodal)?;
            log_attempts(rec);
            records.push(rec.clone());
            if fields {
                progress.dynamic_step(rec, &set_names);
            }
            if let (true, Some(resume)) = (fields || flow(rec) == Flow::Stop, resume) {
                save(rec, &s.u, m, resume)?;
            }
            Ok(flow(rec))
        };
        let t = match &explicit_dt {
            Some((dt, stable)) => run_explicit(
                comm,
                &mut model,
                &mut state,
                analysis,
                *dt,
                stable,
                &mut observe,
            ),
            None => run_implicit(
                comm,
                &mut model,
                &mut state,
                analysis,
                nopts,
                restart.as_ref().map(|r| &r.resume),
                &mut observe,
            ),
        };
        u = state.u;
        t
    } else {
        // (analysis step, increments of it so far)
        let mut stage_seen = (0usize, 0usize);
        // After a restart, counted on from the earlier run's rows (rank 0 read them;
        // every rank must agree on which steps write fields).
        if restart.is_some() {
            let mut seen = [0.0, 0.0];
            if let Some(k) = header.iter().position(|h| h == "analysis_step") {
                if let Some(&stage) = earlier.last().and_then(|r| r.get(k)) {
                    let n = earlier.iter().filter(|r| r.get(k) == Some(&stage)).count();
                    seen = [(stage - 1.0).max(0.0), n as f64];
                }
            }
            comm.allreduce_max(&mut seen);
            stage_seen = (seen[0] as usize, seen[1] as usize);
        }
        if let Some(r) = &restart {
            u = r.u.clone();
        }
        run_static(
            comm,
            &mut model,
            &mut u,
            analysis,
            nopts,
            restart.as_ref().map(|r| &r.resume),
            &mut |rec, u, m, resume| {
                // With analysis steps: every n-th increment of the step, and its last.
                let fields = match analysis.stages.get(rec.stage) {
                    Some(st) => {
                        if rec.stage != stage_seen.0 {
                            stage_seen = (rec.stage, 0);
                        }
                        stage_seen.1 += 1;
                        let n = settings
                            .output
                            .stage_every
                            .get(rec.stage)
                            .copied()
                            .unwrap_or(every);
                        stage_seen.1.is_multiple_of(n)
                            || rec.time >= st.end - 1e-9 * end_time.max(1.0)
                    }
                    None => rec.step % every == 0 || rec.time >= end_time,
                };
                writer.step(comm, rec, u, m, fields)?;
                log_attempts(rec);
                records.push(rec.clone());
                progress.static_step(rec, nopts.kind.name(), &set_names);
                if fields || flow(rec) == Flow::Stop {
                    save(rec, u, m, resume)?;
                }
                Ok(flow(rec))
            },
        )
    };
    *log = progress.log;
    let totals = totals?;
    let failed: Vec<&Attempt> = totals.failed_last.iter().collect();
    let last_step = records
        .last()
        .map(|r| r.step)
        .or(restart.as_ref().map(|r| r.step))
        .unwrap_or(0);
    iters.step(last_step + 1, &failed, false);
    phases.assembly = totals.seconds_assembly;
    phases.linear_solve = totals.seconds_linear;
    phases.preconditioner_setup = totals.seconds_pc_setup;
    phases.output = writer.seconds;
    let mut ph = [
        phases.setup,
        phases.partition,
        phases.assembly,
        phases.linear_solve,
        phases.output,
        phases.preconditioner_setup,
    ];
    let traffic = TrafficSummary::gather(comm);
    let coarse_space = CoarseSummary::gather(comm, totals.coarse);
    comm.allreduce_max(&mut ph);
    let rss = comm.allgather_f64(peak_rss_mb());
    let message = totals.failure.clone().unwrap_or_else(|| "converged".into());
    let contributions = contributions_summary(&model, &records, &header, &earlier);
    // The quantities of interest, from the history as written (rank 0).
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
        contributions,
        analysis_steps: analysis
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
            .collect(),
        wall_time_s: t_start.elapsed().as_secs_f64(),
        phases: Phases {
            setup: ph[0],
            partition: ph[1],
            assembly: ph[2],
            linear_solve: ph[3],
            output: ph[4],
            preconditioner_setup: ph[5],
        },
        traffic,
        peak_rss_mb: rss.iter().cloned().fold(0.0, f64::max),
        peak_rss_mb_per_rank: rss,
        partition: origin,
        message: message.clone(),
        output_dir: out.display().to_string(),
        run: record,
        restarted_from: restart.as_ref().map(|r| RestartedFrom {
            dir: r.dir.display().to_string(),
            step: r.step,
            time: r.time,
        }),
        stopped: totals.stopped,
        quantities,
    };
    drop(writer);
    let r = if comm.rank() == 0 {
        serde_json::to_string_pretty(&summary)
            .map_err(|e| Error::runtime(e.to_string()))
            .and_then(|s| {
                std::fs::write(out.join("summary.json"), s + "\n")
                    .map_err(|e| Error::runtime(format!("cannot write summary.json: {e}")))
            })
    } else {
        Ok(())
    };
    if !comm.all_ok(r.is_ok()) {
        return Err(r
            .err()
            .unwrap_or_else(|| Error::runtime("writing summary.json failed on rank 0")));
    }
    if let Some(f) = totals.failure {
        return Err(Error::convergence(format!(
            "{f}; {} converged step(s) written to {}",
            totals.steps,
            out.display()
        )));
    }
    Ok(RunOutcome {
        summary,
        u,
        model,
        steps: records,
    })
}

/// Where a restarted run goes on from: the earlier run's directory, its last step and
/// time, and this rank's solution and stepping state (the model's state is restored).
struct Restart {
    dir: PathBuf,
    step: usize,
    time: f64,
    u: Vec<f64>,
    resume: Resume,
}

/// Collective: read this rank's restart file from `dir`, check it was written by this
/// deck on this partition, and restore the model's state from it.
fn load_restart(
    comm: &dyn Comm,
    dir: &std::path::Path,
    model: &mut Model,
    settings: &RunSettings,
) -> Result<Restart> {
    let c = crate::output::checkpoint::read(comm, dir)?;
    let mine = if c.scene != settings.name
        || c.deck != crate::output::checkpoint::fingerprint(&settings.echo)
    {
        Some(format!(
            "the restart files were written by another deck (scene `{}`); a restart needs the \
             deck of the run, e.g. {}",
            c.scene,
            dir.join("deck.toml").display()
        ))
    } else if c.first_dof != model.dofs.dofs.start()
        || c.n_dofs != model.n_owned_dofs()
        || c.u.len() != c.n_dofs
    {
        Some("the restart files were written on another partition of the model".into())
    } else {
        model.restore_state(&c.model).err().map(|e| e.message)
    };
    if let Some(why) = comm.first_message(mine) {
        return Err(Error::input(format!("--restart {}: {why}", dir.display())));
    }
    Ok(Restart {
        dir: dir.to_path_buf(),
        step: c.step,
        time: c.time,
        u: c.u,
        resume: c.resume,
    })
}

/// The summary's entries from the contributions: for every history column that asks
/// for it, its largest value over the steps (from 0); and each contribution's entry from
/// its columns at the last step.
fn contributions_summary(
    model: &Model,
    records: &[StepRecord],
    header: &[String],
    earlier: &[Vec<f64>],
) -> BTreeMap<String, serde_json::Value> {
    let cols = model.columns();
    let mut out = BTreeMap::new();
    for (i, c) in cols.iter().enumerate() {
        if c.run_max {
            // `earlier`: history rows of the run this one restarted from.
            let before = header.iter().position(|h| *h == c.name).map_or(0.0, |k| {
                earlier
                    .iter()
                    .filter_map(|r| r.get(k))
                    .filter(|v| v.is_finite())
                    .fold(0.0, |a: f64, &b| a.max(b))
            });
            let m = records
                .iter()
                .filter_map(|r| r.columns.get(i))
                .fold(before, |a: f64, &b| a.max(b));
            out.insert(c.name.clone(), serde_json::json!(m));
        }
    }
    let zeros = vec![0.0; cols.len()];
    let last = records.last().map_or(&zeros, |r| &r.columns);
    out.extend(model.summary(last));
    out
}

/// `alfe check`: validate and report the model size and partition quality (serial).
pub fn check(target: &str, ranks: usize, o: &crate::scene::Overrides) -> Result<String> {
    check_source(&crate::scene::load(target)?, ranks, o)
}

/// [`check`] of a deck's text (the deck fuzzer calls it for thousands of decks).
pub fn check_source(
    src: &crate::scene::Source,
    ranks: usize,
    o: &crate::scene::Overrides,
) -> Result<String> {
    let scene = crate::scene::read_with(src, o)?;
    let def = &scene.model;
    let mut s = describe(def, &scene.run);
    if ranks > 1 {
        let edges = def.coupling_edges();
        let part = def.partition_request(&edges).compute(ranks)?;
        s.push_str(&describe_partition(def, &part, ranks)?);
    }
    Ok(s)
}

fn describe(def: &ModelDef, run: &RunSettings) -> String {
    let m = &def.mesh;
    let mut kinds = std::collections::BTreeMap::new();
    for k in &m.kinds {
        *kinds.entry(k.name()).or_insert(0usize) += 1;
    }
    let kinds: Vec<String> = kinds.iter().map(|(k, n)| format!("{n} {k}")).collect();
    let extra: usize = def
        .contributions
        .iter()
        .map(|c| c.kind().extra_unknowns())
        .sum();
    // A hybrid hex8's pressure takes a block of three unknowns (one used).
    let hybrid = (0..m.n_elems())
        .filter(|&e| {
            m.kinds[e] == crate::mesh::ElemKind::Hex8
                && def.part_formulation[m.elem_part[e] as usize].is_hybrid()
        })
        .count();
    let mut parts_of = Vec::new();
    if extra > 0 {
        parts_of.push(format!("{extra} multipliers and reference-point DOFs"));
    }
    if hybrid > 0 {
        parts_of.push(format!(
            "{} element pressure blocks ({hybrid} pressures)",
            3 * hybrid
        ));
    }
    let unknowns = if parts_of.is_empty() {
        format!("{} (3 per node)", 3 * m.n_nodes())
    } else {
        format!(
            "{} ({} node displacements, {})",
            3 * m.n_nodes() + extra + 3 * hybrid,
            3 * m.n_nodes(),
            parts_of.join(", ")
        )
    };
    let parts: Vec<String> = def
        .part_names
        .iter()
        .zip(&def.part_formulation)
        .map(|(n, f)| format!("{n} ({})", f.describe()))
        .collect();
    let mut s = format!(
        "scene {}: valid\n  units: {}\n  parts: {}\n  nodes: {}\n  elements: {} ({})\n  unknowns: {unknowns}\n  supports: {}\n  node sets: {}\n  surfaces: {}\n  steps: {}\n",
        run.name,
        run.units.describe(),
        parts.join(", "),
        m.n_nodes(),
        m.n_elems(),
        kinds.join(", "),
        def.constraints.len(),
        def.node_sets.iter().map(|(k, v)| format!("{k} ({} nodes)", v.len())).collect::<Vec<_>>().join(", "),
        def.surfaces.iter().map(|(k, v)| format!("{k} ({} faces)", v.len())).collect::<Vec<_>>().join(", "),
        nominal_steps(&run.analysis),
    );
    s.push_str(&format!("  contributions: {}\n", def.contributions.len()));
    for c in &def.contributions {
        s.push_str(&format!("    {}\n", c.kind().describe()));
        if let Some(more) = c.kind().initial_state(&m.coords) {
            s.push_str(&format!("      {more}\n"));
        }
    }
    s
}

/// Steps at the deck's step size ("from the mesh" for explicit runs without one).
fn nominal_steps(a: &Analysis) -> String {
    if !a.stages.is_empty() {
        let each: Vec<usize> = a
            .stages
            .iter()
            .map(|s| crate::solve::control::step_times(s.end - s.start, s.step).len())
            .collect();
        let names: Vec<String> = a
            .stages
            .iter()
            .zip(&each)
            .map(|(s, n)| format!("{} {n}", s.name))
            .collect();
        return format!("{} ({})", each.iter().sum::<usize>(), names.join(", "));
    }
    if a.step > 0.0 {
        crate::solve::control::step_times(a.end_time, a.step)
            .len()
            .to_string()
    } else {
        "(time step from the mesh)".into()
    }
}

fn describe_partition(def: &ModelDef, part: &[u32], ranks: usize) -> Result<String> {
    let q = quality(&def.mesh, part, ranks)?;
    let owner = crate::partition::node_owner(&def.mesh, part);
    let mut s = format!("partition over {ranks} ranks ({}):\n  edge cut: {} faces\n  imbalance: {:.3} (max/mean elements)\n", def.partition.describe(), q.edge_cut, q.imbalance);
    for r in 0..ranks {
        s.push_str(&format!(
            "  rank {r}: {} elements, {} owned nodes ({} unknowns), {} ghost nodes\n",
            q.elements_per_rank[r],
            q.owned_nodes_per_rank[r],
            3 * q.owned_nodes_per_rank[r],
            q.ghost_nodes_per_rank[r]
        ));
    }
    for (name, faces) in &def.surfaces {
        let mut rs: Vec<u32> = faces.iter().map(|f| part[f.elem]).collect();
        rs.sort_unstable();
        rs.dedup();
        s.push_str(&format!(
            "  surface {name} on rank(s) {}\n",
            rs.iter()
                .map(|r| r.to_string())
                .collect::<Vec<_>>()
                .join(",")
        ));
    }
    for c in &def.contributions {
        let nodes = c.kind().nodes();
        if nodes.is_empty() {
            continue;
        }
        let mut rs: Vec<u32> = nodes.iter().map(|&n| owner[n]).collect();
        rs.sort_unstable();
        rs.dedup();
        s.push_str(&format!(
            "  {} {}: nodes owned by rank(s) {}\n",
            c.kind().kind_name(),
            c.kind().name(),
            rs.iter()
                .map(|r| r.to_string())
                .collect::<Vec<_>>()
                .join(",")
        ));
    }
    for (name, nodes) in &def.node_sets {
        let mut rs: Vec<u32> = nodes.iter().map(|&n| owner[n]).collect();
        rs.sort_unstable();
        rs.dedup();
        s.push_str(&format!(
            "  set {name} owned by rank(s) {}\n",
            rs.iter()
                .map(|r| r.to_string())
                .collect::<Vec<_>>()
                .join(",")
        ));
    }
    Ok(s)
}

/// `alfe partition`: compute the METIS partition and write it to the cache directory.
pub fn partition(target: &str, ranks: usize, dir: &std::path::Path) -> Result<String> {
    if ranks < 2 {
        return Err(Error::input(
            "--ranks: expected 2 or more (one rank needs no partition)",
        ));
    }
    let src = crate::scene::load(target)?;
    let Scene { model: def, run } = crate::scene::read(&src)?;
    let edges = def.coupling_edges();
    let req = def.partition_request(&edges);
    let part = req.compute(ranks)?;
    let file = cache::path(dir, &run.name, ranks, &req);
    cache::write(&file, &req, ranks, &part)?;
    Ok(format!(
        "wrote {}\n{}",
        file.display(),
        describe_partition(&def, &part, ranks)?
    ))
}
