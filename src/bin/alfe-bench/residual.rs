//! `alfe-bench residual`: residual-evaluation and tangent-assembly rates (elements per
//! second per rank) of the material/formulation pairs the scenes use, on one generated
//! hex8 block at a fixed inhomogeneous deformation, on however many ranks it is started
//! with. scripts/bench-core runs it on 1 and 2 ranks beside the linear benchmark.

use crate::common::{generated_model, report, time_median, Cells};
use alfe::parallel::Comm;
use alfe::Result;
use std::path::PathBuf;

/// `alfe-bench residual`'s options.
#[derive(clap::Args, Debug)]
pub struct ResidualArgs {
    /// Cells NX,NY,NZ of the unit block.
    #[arg(long, value_name = "NX,NY,NZ", default_value = "30,30,30")]
    pub cells: Cells,
    /// Repetitions (the median is reported).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..))]
    pub reps: u32,
    /// Write the measurements to this JSON file.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
}

/// (label, material table, part formulation).
const CASES: &[(&str, &str, &str)] = &[
    (
        "linear-elastic, standard",
        "model = \"linear-elastic\"\nE = 210000.0\nnu = 0.3",
        "standard",
    ),
    (
        "neo-hookean, standard",
        "model = \"neo-hookean\"\nE = 210000.0\nnu = 0.3",
        "standard",
    ),
    (
        "neo-hookean, F-bar",
        "model = \"neo-hookean\"\nE = 210000.0\nnu = 0.3",
        "fbar",
    ),
    (
        "mooney-rivlin, standard",
        "model = \"mooney-rivlin\"\nC10 = 0.5508\nC01 = 0.1377\nnu = 0.4995",
        "standard",
    ),
    (
        "mooney-rivlin, F-bar",
        "model = \"mooney-rivlin\"\nC10 = 0.5508\nC01 = 0.1377\nnu = 0.4995",
        "fbar",
    ),
    (
        "j2 (plastic at every point), F-bar",
        "model = \"j2\"\nE = 210000.0\nnu = 0.3\nyield_stress = 250.0\nhardening = { type = \"linear\", modulus = 1000.0 }",
        "fbar",
    ),
];

fn deck(cells: [usize; 3], material: &str, formulation: &str) -> String {
    format!(
        "[scene]\nname = \"bench-residual\"\nunits = \"mm-t-s\"\n\
         [[materials]]\nname = \"m\"\n{material}\n\
         [[parts]]\nname = \"block\"\nmaterial = \"m\"\nformulation = \"{formulation}\"\n\
         mesh = {{ kind = \"box\", size = [1, 1, 1], cells = [{}, {}, {}] }}\n\
         [analysis]\ntype = \"static\"\nend_time = 1.0\nstep = 1.0\n",
        cells[0], cells[1], cells[2]
    )
}

/// Run every case on the ranks of `comm`; the report goes to stdout (rank 0) and
/// `--json`.
pub fn run(comm: &dyn Comm, a: &ResidualArgs) -> Result<()> {
    let (cells, reps) = (a.cells.0, a.reps as usize);
    let p = comm.size();
    let mut rows = Vec::new();
    for (label, material, formulation) in CASES {
        let mut model =
            generated_model(comm, deck(cells, material, formulation), "bench-residual")?;
        // u = (F − I) X with F = diag(1.02, 0.99, 0.99) plus a smooth wiggle: a 2 %
        // stretch is 17 yield strains for the J2 case, so every point returns.
        let n = model.n_owned_dofs();
        let u: Vec<f64> = (0..n)
            .map(|i| {
                let x = model.mesh.coords[i / 3];
                let c = i % 3;
                let stretch = [0.02, -0.01, -0.01][c] * x[c];
                stretch + 2e-3 * (3.0 * x[0] + 2.0 * x[1] - x[2] + c as f64).sin()
            })
            .collect();
        let mut r = vec![0.0; n];
        model.residual(comm, &u, 1.0, &mut r)?;
        let t_res = time_median(comm, reps, || {
            model.residual(comm, &u, 1.0, &mut r).map(|_| ())
        })?;
        let mut k = model.new_matrix(comm);
        let t_jac = time_median(comm, reps, || model.jacobian(comm, &u, 1.0, &mut k))?;
        let elems = comm.allgather_f64(model.solids.len() as f64);
        let max_elems = elems.iter().cloned().fold(0.0, f64::max);
        rows.push(serde_json::json!({
            "case": label,
            "elements": model.mesh.n_elems_global,
            "residual_s": t_res,
            "residual_elems_per_s_per_rank": max_elems / t_res,
            "jacobian_s": t_jac,
            "jacobian_elems_per_s_per_rank": max_elems / t_jac,
        }));
    }
    let out = serde_json::json!({ "ranks": p, "cells": cells, "reps": reps, "cases": rows });
    report(comm, &out, a.json.as_deref())
}
