//! `alfe bench-linear`: the core's speed on a generated linear-elastic block, measured
//! on however many ranks it is started with (scripts/bench-core runs it on 1 and 2 and
//! runs PETSc on the exported system beside it), with any preconditioner by name. Also checks the GMRES answer against
//! the true residual, which the MPI test of the linear solver relies on.

use crate::linalg::gmres::{gmres, GmresOptions};
use crate::linalg::{preconditioner, BlockJacobi, FactorOptions, PcKind, Preconditioner};
use crate::model::distribute;
use crate::model::Model;
use crate::output::h5::H5File;
use crate::parallel::Comm;
use crate::parallel::{on_rank0, peak_rss_mb};
use crate::partition::partition_elements;
use crate::{Error, Result};
use std::path::Path;
use std::time::Instant;

fn deck(cells: [usize; 3]) -> String {
    format!(
        r#"
[scene]
name = "bench-block"
units = "mm-t-s"
[[materials]]
name = "steel"
model = "linear-elastic"
E = 210000.0
nu = 0.3
[[parts]]
name = "block"
material = "steel"
mesh = {{ kind = "box", size = [1, 1, 1], cells = [{}, {}, {}] }}
[[node_sets]]
name = "fixed"
group = "xmin"
[[surfaces]]
name = "loaded"
group = "xmax"
[[boundary]]
type = "fixed"
set = "fixed"
[[loads]]
type = "traction"
surface = "loaded"
traction = [100.0, 50.0, 25.0]
[analysis]
type = "static"
end_time = 1.0
step = 1.0
"#,
        cells[0], cells[1], cells[2]
    )
}

pub(crate) fn parse_cells(s: Option<&str>, default: [usize; 3]) -> Result<[usize; 3]> {
    let Some(s) = s else { return Ok(default) };
    let v: Vec<usize> = s
        .split(',')
        .map(|x| x.trim().parse::<usize>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| Error::input(format!("--cells: expected NX,NY,NZ, got `{s}`")))?;
    match v.as_slice() {
        [a, b, c] if *a > 0 && *b > 0 && *c > 0 => Ok([*a, *b, *c]),
        _ => Err(Error::input(format!(
            "--cells: expected three positive counts NX,NY,NZ, got `{s}`"
        ))),
    }
}

/// A deck text partitioned (METIS) over the ranks of `comm` and distributed: the model
/// the benchmarks time.
pub(crate) fn generated_model(comm: &dyn Comm, text: String, label: &str) -> Result<Model> {
    let p = comm.size();
    let pieces = on_rank0(comm, || {
        let src = crate::scene::Source {
            text: text.clone(),
            dir: ".".into(),
            label: label.into(),
        };
        let def = crate::scene::read(&src)?.model;
        let part = partition_elements(&def.mesh, p, def.partition, &def.coupling_edges())?;
        Ok(distribute::split(&def, &part, p))
    })?;
    let local = distribute::scatter(comm, pieces)?;
    Model::new(comm, local)
}

/// Median of repeated timings of a collective action (barrier before each).
pub(crate) fn time_median(
    comm: &dyn Comm,
    reps: usize,
    mut f: impl FnMut() -> Result<()>,
) -> Result<f64> {
    let mut ts = Vec::with_capacity(reps);
    for _ in 0..reps {
        comm.barrier();
        let t = Instant::now();
        f()?;
        comm.barrier();
        ts.push(t.elapsed().as_secs_f64());
    }
    ts.sort_by(|a, b| a.partial_cmp(b).unwrap());
    Ok(ts[ts.len() / 2])
}

pub fn bench_linear(
    comm: &dyn Comm,
    cells: Option<&str>,
    rtol: Option<&str>,
    json: Option<&str>,
    export: Option<&str>,
    pc_name: Option<&str>,
    rigid_body_modes: bool,
) -> Result<()> {
    let cells = parse_cells(cells, [44, 44, 44])?;
    let name = pc_name.unwrap_or("block-jacobi");
    let kind = PcKind::parse(name)
        .filter(|k| !matches!(k, PcKind::None | PcKind::Auto | PcKind::AutoFactored))
        .ok_or_else(|| {
            Error::input(format!(
                "--pc: expected block-jacobi, asm or amg, got `{name}`"
            ))
        })?;
    let rtol: f64 = match rtol {
        None => 1e-8,
        Some(s) => s
            .parse()
            .ok()
            .filter(|v: &f64| *v > 0.0 && *v < 1.0)
            .ok_or_else(|| {
                Error::input(format!("--rtol: expected a number in (0, 1), got `{s}`"))
            })?,
    };
    let p = comm.size();
    let t_setup = Instant::now();
    let mut model = generated_model(comm, deck(cells), "bench-linear")?;
    let setup_s = t_setup.elapsed().as_secs_f64();
    let n = model.n_owned_dofs();
    let ne_local = model.solids.len() as f64;
    let u: Vec<f64> = (0..n)
        .map(|i| 1e-6 * ((i * 7919 % 1000) as f64 / 1000.0 - 0.5))
        .collect();
    let mut r = vec![0.0; n];
    let reps = 5;
    let t_res = time_median(comm, reps, || {
        model.residual(comm, &u, 1.0, &mut r).map(|_| ())
    })?;
    let mut k = model.new_matrix(comm);
    let t_jac = time_median(comm, reps, || model.jacobian(comm, &u, 1.0, &mut k))?;
    // The system K du = −r(0) with the clamp imposed: the linear-elastic solution.
    let zero = vec![0.0; n];
    model.residual(comm, &zero, 1.0, &mut r)?;
    model.jacobian(comm, &zero, 1.0, &mut k)?;
    let cdofs = model.constrained_dofs();
    let mut b: Vec<f64> = r.iter().map(|v| -v).collect();
    for &d in &cdofs {
        b[d] = 0.0;
    }
    k.constrain(comm, &cdofs);
    comm.barrier();
    let t = Instant::now();
    // Block Jacobi is built directly so that its factorization kind and symbolic time
    // reach the report (scripts/bench_core_report.py); the others by name.
    let first = if kind == PcKind::BlockJacobi {
        BlockJacobi::new(&k).map(|bj| {
            let info = (format!("{:?}", bj.kind()), bj.symbolic_seconds());
            (Box::new(bj) as Box<dyn Preconditioner>, Some(info))
        })
    } else {
        let points = rigid_body_modes.then(|| model.node_points());
        let mut pc = preconditioner(kind, FactorOptions::default(), points);
        pc.setup(comm, &k).map(|()| (pc, None))
    };
    if !comm.all_ok(first.is_ok()) {
        first?;
        return Err(Error::runtime(
            "preconditioner setup failed on another rank",
        ));
    }
    let (mut pc, factor_info) = first?;
    let t_factor_first = t.elapsed().as_secs_f64();
    let t_refactor = time_median(comm, 3, || pc.setup(comm, &k))?;
    let opts = GmresOptions {
        rtol,
        atol: 0.0,
        restart: 60,
        max_iterations: 5000,
    };
    let mut x = vec![0.0; n];
    comm.barrier();
    let t = Instant::now();
    let gs = gmres(comm, &mut k, pc.as_ref(), &b, &mut x, &opts)?;
    comm.barrier();
    let t_gmres = t.elapsed().as_secs_f64();
    let mut ax = vec![0.0; n];
    k.spmv(comm, &x, &mut ax);
    let res: Vec<f64> = b.iter().zip(&ax).map(|(b, a)| b - a).collect();
    let true_rel = comm.norm2(&res) / comm.norm2(&b);
    // HDF5 write bandwidth: displacement + a stress-sized array, collectively.
    let dir = json
        .map(|j| {
            Path::new(j)
                .parent()
                .unwrap_or(Path::new("."))
                .to_path_buf()
        })
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
        h5.write_rows_f64("/displacement", nn, 3, model.mesh.node_start() as u64, &x)?;
        h5.write_rows_f64("/stress", nel, 6, model.mesh.elem_start() as u64, &stress)?;
        h5.flush()?;
        8 * (3 * nn + 6 * nel)
    };
    comm.barrier();
    let t_h5 = t.elapsed().as_secs_f64();
    if comm.rank() == 0 {
        let _ = std::fs::remove_file(&h5path);
    }
    let nnz = {
        let mut v = [k.nnz_local() as u64];
        comm.allreduce_sum_u64(&mut v);
        v[0]
    };
    let rss = comm.allgather_f64(peak_rss_mb());
    let elems = comm.allgather_f64(ne_local);
    let min_elems = elems.iter().cloned().fold(f64::INFINITY, f64::min);
    let max_elems = elems.iter().cloned().fold(0.0, f64::max);
    let out = serde_json::json!({
        "ranks": p,
        "cells": cells,
        "unknowns": 3 * model.mesh.n_nodes_global,
        "elements": model.mesh.n_elems_global,
        "nnz": nnz,
        "setup_s": setup_s,
        "residual_s": t_res,
        "residual_elems_per_s_per_rank": max_elems / t_res,
        "residual_elems_per_s_per_rank_min": min_elems / t_res,
        "jacobian_s": t_jac,
        "jacobian_elems_per_s_per_rank": max_elems / t_jac,
        "owned_dofs_per_rank": comm.allgather_f64(n as f64),
        "preconditioner": kind.name(),
        "factorization": factor_info.as_ref().map(|f| f.0.clone()),
        "symbolic_s_per_rank": comm.allgather_f64(factor_info.map_or(0.0, |f| f.1)),
        "rigid_body_modes": rigid_body_modes,
        "factor_first_s": t_factor_first,
        "refactor_s": t_refactor,
        "gmres_s": t_gmres,
        "gmres_iterations": gs.iterations,
        "gmres_s_per_iteration": t_gmres / gs.iterations.max(1) as f64,
        "gmres_converged": gs.converged,
        "gmres_reductions": gs.reductions,
        "rtol": rtol,
        "true_relative_residual": true_rel,
        "solve_s": t_refactor + t_gmres,
        "solution_norm": comm.norm2(&x),
        "h5_write_s": t_h5,
        "h5_mb_per_s": bytes as f64 / 1e6 / t_h5,
        "peak_rss_mb_per_rank": rss,
    });
    if comm.rank() == 0 {
        println!("{}", serde_json::to_string_pretty(&out).unwrap());
        if let Some(j) = json {
            std::fs::write(j, serde_json::to_string_pretty(&out).unwrap() + "\n")
                .map_err(|e| Error::runtime(format!("cannot write `{j}`: {e}")))?;
        }
    }
    if let Some(dir) = export {
        crate::linalg::export::write_petsc(comm, Path::new(dir), &k, &b, None)?;
    }
    if !gs.converged {
        return Err(Error::convergence(format!(
            "GMRES did not converge in {} iterations",
            gs.iterations
        )));
    }
    Ok(())
}
