//! `alfe-bench linear`: the core's speed on a generated linear-elastic block, measured on
//! however many ranks it is started with (scripts/bench-core runs it on 1 and 2 and runs
//! PETSc on the exported system beside it), with any preconditioner by name. Also checks
//! the GMRES answer against the true residual, which the MPI test of the linear solver
//! relies on.

use crate::common::{elastic_block_deck, generated_model, report, time_median, Cells};
use alfe::linalg::gmres::{gmres, GmresOptions, GmresStats};
use alfe::linalg::Preconditioner;
use alfe::linalg::{preconditioner, BlockJacobi, DistMatrix, FactorOptions, PcKind};
use alfe::model::Model;
use alfe::output::h5::H5File;
use alfe::parallel::{peak_rss_mb, Comm};
use alfe::{Error, Result};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// `alfe-bench linear`'s options.
#[derive(clap::Args, Debug)]
pub struct LinearArgs {
    /// Cells NX,NY,NZ of the unit block.
    #[arg(long, value_name = "NX,NY,NZ", default_value = "44,44,44")]
    pub cells: Cells,
    /// GMRES relative tolerance, in (0, 1).
    #[arg(long, default_value = "1e-8", value_parser = parse_rtol)]
    pub rtol: f64,
    /// Write the measurements to this JSON file.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Export the matrix and right-hand side to this directory (PETSc binary format, for
    /// the PETSc peers in scripts/).
    #[arg(long, value_name = "DIR")]
    pub export: Option<PathBuf>,
    /// Preconditioner: block-jacobi, asm, two-level, two-level-bj or amg.
    #[arg(long, value_name = "NAME", default_value = "block-jacobi", value_parser = parse_pc)]
    pub pc: PcKind,
    /// AMG's near-null space from the rigid-body rotations.
    #[arg(long)]
    pub rigid_body_modes: bool,
}

fn parse_rtol(s: &str) -> std::result::Result<f64, String> {
    s.parse()
        .ok()
        .filter(|v: &f64| *v > 0.0 && *v < 1.0)
        .ok_or_else(|| format!("expected a number in (0, 1), got `{s}`"))
}

/// The preconditioners that can be named (not `auto`, `auto-factored` or `none`).
fn parse_pc(s: &str) -> std::result::Result<PcKind, String> {
    let named = |k: &PcKind| !matches!(k, PcKind::None | PcKind::Auto | PcKind::AutoFactored);
    PcKind::parse(s).filter(named).ok_or_else(|| {
        let names: Vec<&str> = PcKind::ALL
            .iter()
            .filter(|k| named(k))
            .map(|k| k.name())
            .collect();
        format!("expected one of {}, got `{s}`", names.join(", "))
    })
}

/// Residual and tangent assembly rates, and the model's set-up time.
struct Rates {
    setup_s: f64,
    residual_s: f64,
    jacobian_s: f64,
}

/// The timed preconditioner: its first set-up and re-set-up times, and for block Jacobi
/// the factorization kind and symbolic time (scripts/bench_core_report.py).
struct TimedPc {
    pc: Box<dyn Preconditioner>,
    factor_info: Option<(String, f64)>,
    first_s: f64,
    refactor_s: f64,
}

/// Everything measured, for the report.
struct Measured {
    rates: Rates,
    pc: TimedPc,
    solve: Solve,
    /// HDF5 write: seconds and bytes.
    h5: (f64, u64),
}

/// The timed GMRES solve and the true relative residual ‖b − Ax‖/‖b‖ after it.
struct Solve {
    x: Vec<f64>,
    stats: GmresStats,
    seconds: f64,
    true_rel: f64,
}

/// Run the benchmark on the ranks of `comm`; the report goes to stdout (rank 0) and
/// `--json`. An unconverged GMRES is an error (exit 3) after the report.
pub fn run(comm: &dyn Comm, a: &LinearArgs) -> Result<()> {
    let t_setup = Instant::now();
    let mut model = generated_model(comm, elastic_block_deck(a.cells.0), "bench-linear")?;
    let setup_s = t_setup.elapsed().as_secs_f64();
    let rates = assembly_rates(comm, &mut model, setup_s)?;
    let (mut k, b) = linear_system(comm, &mut model)?;
    let pc = timed_preconditioner(comm, &model, &k, a.pc, a.rigid_body_modes)?;
    let solve = timed_gmres(comm, &mut k, pc.pc.as_ref(), &b, a.rtol)?;
    let h5 = h5_write(comm, &model, &solve.x, a.json.as_deref())?;
    let m = Measured {
        rates,
        pc,
        solve,
        h5,
    };
    report(
        comm,
        &json_report(comm, a, &model, &k, &m),
        a.json.as_deref(),
    )?;
    if let Some(dir) = &a.export {
        alfe::linalg::export::write_petsc(comm, dir, &k, &b, None)?;
    }
    if !m.solve.stats.converged {
        return Err(Error::convergence(format!(
            "GMRES did not converge in {} iterations",
            m.solve.stats.iterations
        )));
    }
    Ok(())
}

/// Median residual and tangent times at a small displacement (5 repetitions).
fn assembly_rates(comm: &dyn Comm, model: &mut Model, setup_s: f64) -> Result<Rates> {
    let n = model.n_owned_dofs();
    let u: Vec<f64> = (0..n)
        .map(|i| 1e-6 * ((i * 7919 % 1000) as f64 / 1000.0 - 0.5))
        .collect();
    let mut r = vec![0.0; n];
    let reps = 5;
    let residual_s = time_median(comm, reps, || {
        model.residual(comm, &u, 1.0, &mut r).map(|_| ())
    })?;
    let mut k = model.new_matrix(comm);
    let jacobian_s = time_median(comm, reps, || model.jacobian(comm, &u, 1.0, &mut k))?;
    Ok(Rates {
        setup_s,
        residual_s,
        jacobian_s,
    })
}

/// The system K du = −r(0) with the clamp imposed: the linear-elastic solution.
fn linear_system(comm: &dyn Comm, model: &mut Model) -> Result<(DistMatrix, Vec<f64>)> {
    let n = model.n_owned_dofs();
    let zero = vec![0.0; n];
    let mut r = vec![0.0; n];
    let mut k = model.new_matrix(comm);
    model.residual(comm, &zero, 1.0, &mut r)?;
    model.jacobian(comm, &zero, 1.0, &mut k)?;
    let cdofs = model.constrained_dofs();
    let mut b: Vec<f64> = r.iter().map(|v| -v).collect();
    for &d in &cdofs {
        b[d] = 0.0;
    }
    k.constrain(comm, &cdofs);
    Ok((k, b))
}

/// The preconditioner's first set-up, timed, then the median of 3 re-set-ups. Block
/// Jacobi is built directly so that its factorization kind and symbolic time reach the
/// report; the others by name.
fn timed_preconditioner(
    comm: &dyn Comm,
    model: &Model,
    k: &DistMatrix,
    kind: PcKind,
    rigid_body_modes: bool,
) -> Result<TimedPc> {
    comm.barrier();
    let t = Instant::now();
    let first = if kind == PcKind::BlockJacobi {
        BlockJacobi::new(k).map(|bj| {
            let info = (format!("{:?}", bj.kind()), bj.symbolic_seconds());
            (Box::new(bj) as Box<dyn Preconditioner>, Some(info))
        })
    } else {
        let points = rigid_body_modes.then(|| model.node_points());
        let mut pc = preconditioner(kind, FactorOptions::default(), points);
        pc.setup(comm, k).map(|()| (pc, None))
    };
    if !comm.all_ok(first.is_ok()) {
        first?;
        return Err(Error::runtime(
            "preconditioner setup failed on another rank",
        ));
    }
    let (mut pc, factor_info) = first?;
    let first_s = t.elapsed().as_secs_f64();
    let refactor_s = time_median(comm, 3, || pc.setup(comm, k))?;
    Ok(TimedPc {
        pc,
        factor_info,
        first_s,
        refactor_s,
    })
}

/// GMRES(60) from x = 0 to `rtol`, timed, and the true residual after it.
fn timed_gmres(
    comm: &dyn Comm,
    k: &mut DistMatrix,
    pc: &dyn Preconditioner,
    b: &[f64],
    rtol: f64,
) -> Result<Solve> {
    let opts = GmresOptions {
        rtol,
        atol: 0.0,
        restart: 60,
        max_iterations: 5000,
    };
    let n = b.len();
    let mut x = vec![0.0; n];
    comm.barrier();
    let t = Instant::now();
    let stats = gmres(comm, k, pc, b, &mut x, &opts)?;
    comm.barrier();
    let seconds = t.elapsed().as_secs_f64();
    let mut ax = vec![0.0; n];
    k.spmv(comm, &x, &mut ax);
    let res: Vec<f64> = b.iter().zip(&ax).map(|(b, a)| b - a).collect();
    let true_rel = comm.norm2(&res) / comm.norm2(b);
    Ok(Solve {
        x,
        stats,
        seconds,
        true_rel,
    })
}

/// HDF5 write bandwidth: the displacement and a stress-sized array, written collectively
/// beside the JSON report (or to the temporary directory) and removed. Seconds and bytes.
fn h5_write(comm: &dyn Comm, model: &Model, x: &[f64], json: Option<&Path>) -> Result<(f64, u64)> {
    let dir = json
        .map(|j| j.parent().unwrap_or(Path::new(".")).to_path_buf())
        .unwrap_or_else(std::env::temp_dir);
    // Every rank must open the same file: rank 0 names it.
    let mut name = format!("bench-linear-{}.h5", std::process::id()).into_bytes();
    comm.broadcast_bytes(0, &mut name);
    let h5path = dir.join(String::from_utf8_lossy(&name).to_string());
    let stress = vec![1.0f64; 6 * model.solids.len()];
    comm.barrier();
    let t = Instant::now();
    let bytes = {
        let h5 = H5File::create(comm, &h5path)?;
        let nn = model.mesh.n_nodes_global as u64;
        let nel = model.mesh.n_elems_global as u64;
        h5.write_rows_f64("/displacement", nn, 3, model.mesh.node_start() as u64, x)?;
        h5.write_rows_f64("/stress", nel, 6, model.mesh.elem_start() as u64, &stress)?;
        h5.flush()?;
        8 * (3 * nn + 6 * nel)
    };
    comm.barrier();
    let seconds = t.elapsed().as_secs_f64();
    if comm.rank() == 0 {
        let _ = std::fs::remove_file(&h5path);
    }
    Ok((seconds, bytes))
}

/// The report (collective: it gathers per-rank numbers).
fn json_report(
    comm: &dyn Comm,
    a: &LinearArgs,
    model: &Model,
    k: &DistMatrix,
    m: &Measured,
) -> serde_json::Value {
    let (rates, pc, solve) = (&m.rates, &m.pc, &m.solve);
    let (h5_s, h5_bytes) = m.h5;
    let nnz = {
        let mut v = [k.nnz_local() as u64];
        comm.allreduce_sum_u64(&mut v);
        v[0]
    };
    let n = model.n_owned_dofs();
    let rss = comm.allgather_f64(peak_rss_mb());
    let elems = comm.allgather_f64(model.solids.len() as f64);
    let min_elems = elems.iter().cloned().fold(f64::INFINITY, f64::min);
    let max_elems = elems.iter().cloned().fold(0.0, f64::max);
    let gs = &solve.stats;
    let factor_info = pc.factor_info.clone();
    serde_json::json!({
        "ranks": comm.size(),
        "cells": a.cells.0,
        "unknowns": 3 * model.mesh.n_nodes_global,
        "elements": model.mesh.n_elems_global,
        "nnz": nnz,
        "setup_s": rates.setup_s,
        "residual_s": rates.residual_s,
        "residual_elems_per_s_per_rank": max_elems / rates.residual_s,
        "residual_elems_per_s_per_rank_min": min_elems / rates.residual_s,
        "jacobian_s": rates.jacobian_s,
        "jacobian_elems_per_s_per_rank": max_elems / rates.jacobian_s,
        "owned_dofs_per_rank": comm.allgather_f64(n as f64),
        "preconditioner": a.pc.name(),
        "factorization": factor_info.as_ref().map(|f| f.0.clone()),
        "symbolic_s_per_rank": comm.allgather_f64(factor_info.map_or(0.0, |f| f.1)),
        "rigid_body_modes": a.rigid_body_modes,
        "factor_first_s": pc.first_s,
        "refactor_s": pc.refactor_s,
        "gmres_s": solve.seconds,
        "gmres_iterations": gs.iterations,
        "gmres_s_per_iteration": solve.seconds / gs.iterations.max(1) as f64,
        "gmres_converged": gs.converged,
        "gmres_reductions": gs.reductions,
        "rtol": a.rtol,
        "true_relative_residual": solve.true_rel,
        "solve_s": pc.refactor_s + solve.seconds,
        "solution_norm": comm.norm2(&solve.x),
        "h5_write_s": h5_s,
        "h5_mb_per_s": h5_bytes as f64 / 1e6 / h5_s,
        "peak_rss_mb_per_rank": rss,
    })
}
