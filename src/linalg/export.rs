//! A distributed linear system written for PETSc (`MatLoad` / `VecLoad` binary format,
//! big-endian): what the peers in `scripts/` (petsc_bjacobi.py, petsc_dd.py) solve side
//! by side with alfe on the same matrix.
//!
//! `DIR/A.petsc` and `DIR/b.petsc`, gathered on rank 0; `DIR/coords.petsc`, three values
//! per block (a node block's reference coordinates, zeros for the other unknowns), for
//! rigid-body near-null spaces; `DIR/system.json`, alfe's row ownership
//! (`owned_dofs_per_rank`), which blocks are nodes (`node_blocks_per_rank`: the first
//! blocks of each rank's range) and the global unknowns' blocks (`global_blocks`).

use super::DistMatrix;
use crate::parallel::{rank0_outcome, Comm};
use crate::{Error, Result};
use std::io::Write;
use std::path::Path;

/// Collective: add alfe's own solve of the written system to `DIR/system.json` (`alfe`:
/// the preconditioner, its setup and GMRES seconds, the largest over the ranks, GMRES
/// iterations and the relative residual reached), for the side-by-side tables.
pub fn write_alfe_solve(
    comm: &dyn Comm,
    dir: &Path,
    preconditioner: &str,
    setup_s: f64,
    gmres_s: f64,
    iterations: usize,
    relative_residual: f64,
) -> Result<()> {
    let r = if comm.rank() == 0 {
        (|| -> std::result::Result<(), String> {
            let path = dir.join("system.json");
            let text = std::fs::read_to_string(&path).map_err(|e| e.to_string())?;
            let mut meta: serde_json::Value =
                serde_json::from_str(&text).map_err(|e| e.to_string())?;
            meta["alfe"] = serde_json::json!({
                "ranks": comm.size(),
                "preconditioner": preconditioner,
                "setup_s": setup_s,
                "gmres_s": gmres_s,
                "time_to_tol_s": setup_s + gmres_s,
                "iterations": iterations,
                "true_relative_residual": relative_residual,
            });
            let text = serde_json::to_string_pretty(&meta).map_err(|e| e.to_string())?;
            std::fs::write(&path, text).map_err(|e| e.to_string())
        })()
        .map_err(|e| Error::runtime(format!("{}: {e}", dir.display())))
    } else {
        Ok(())
    };
    rank0_outcome(comm, r)
}

/// Collective: write `k`, `b` (owned parts) and, if given, the owned nodes' coordinates
/// (the first [`DistMatrix::node_blocks`] owned blocks) to `dir` (see the module
/// documentation). A failure on rank 0 is returned on every rank.
pub fn write_petsc(
    comm: &dyn Comm,
    dir: &Path,
    k: &DistMatrix,
    b: &[f64],
    points: Option<&[[f64; 3]]>,
) -> Result<()> {
    let (ptr, cols, vals) = k.local_csr();
    let p = comm.size();
    let to0 = |n: usize| -> Vec<usize> { (0..p).map(|r| if r == 0 { n } else { 0 }).collect() };
    let lens: Vec<u64> = ptr.windows(2).map(|w| (w[1] - w[0]) as u64).collect();
    let gather_u = |v: &[u64]| {
        let s = to0(v.len());
        let rc = comm.alltoall_counts(&s);
        comm.alltoallv_u64(v, &s, &rc)
    };
    let gather_f = |v: &[f64]| {
        let s = to0(v.len());
        let rc = comm.alltoall_counts(&s);
        comm.alltoallv_f64(v, &s, &rc)
    };
    let all_lens = gather_u(&lens);
    let all_cols = gather_u(&cols.iter().map(|&c| c as u64).collect::<Vec<_>>());
    let all_vals = gather_f(&vals);
    let all_b = gather_f(b);
    let mut xyz = vec![0.0; b.len()];
    if let Some(pts) = points {
        for (i, x) in pts.iter().enumerate() {
            xyz[3 * i..3 * i + 3].copy_from_slice(x);
        }
    }
    let all_xyz = gather_f(&xyz);
    let dofs: Vec<f64> = comm.allgather_f64(b.len() as f64);
    let nodes: Vec<f64> = comm.allgather_f64(k.node_blocks() as f64);
    let r = if comm.rank() == 0 {
        (|| -> std::io::Result<()> {
            std::fs::create_dir_all(dir)?;
            let m = all_lens.len() as i32;
            let mut w = std::io::BufWriter::new(std::fs::File::create(dir.join("A.petsc"))?);
            for v in [1211216i32, m, m, all_cols.len() as i32] {
                w.write_all(&v.to_be_bytes())?;
            }
            for &l in &all_lens {
                w.write_all(&(l as i32).to_be_bytes())?;
            }
            for &c in &all_cols {
                w.write_all(&(c as i32).to_be_bytes())?;
            }
            for &v in &all_vals {
                w.write_all(&v.to_be_bytes())?;
            }
            w.flush()?;
            for (name, v) in [("b.petsc", &all_b), ("coords.petsc", &all_xyz)] {
                let mut w = std::io::BufWriter::new(std::fs::File::create(dir.join(name))?);
                for h in [1211214i32, m] {
                    w.write_all(&h.to_be_bytes())?;
                }
                for x in v.iter() {
                    w.write_all(&x.to_be_bytes())?;
                }
                w.flush()?;
            }
            let meta = serde_json::json!({
                "unknowns": m,
                "owned_dofs_per_rank": dofs.iter().map(|&v| v as u64).collect::<Vec<_>>(),
                "node_blocks_per_rank": nodes.iter().map(|&v| v as u64).collect::<Vec<_>>(),
                "global_blocks": k.global_blocks(),
            });
            std::fs::write(
                dir.join("system.json"),
                serde_json::to_string_pretty(&meta)?,
            )?;
            Ok(())
        })()
        .map_err(|e| Error::runtime(format!("{}: cannot write the system: {e}", dir.display())))
    } else {
        Ok(())
    };
    rank0_outcome(comm, r)
}
