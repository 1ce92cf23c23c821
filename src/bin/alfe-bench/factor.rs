//! `alfe-bench factor-timing`: the block-Jacobi factorizations on one large elastic
//! block — Cholesky and LU, each with AMD/COLAMD and with nested dissection: ordering,
//! symbolic and numeric times, refactor and solve times, the Cholesky factor's size and
//! the peak memory — then block-Jacobi GMRES on 2 and 4 thread ranks (one process, no
//! MPI). The README's factorization figures come from it (it was the ignored unit test
//! `timing_elasticity_100k` of `linalg/block_jacobi.rs`).
//!
//! The matrix is the clamped tangent of `alfe-bench linear`'s block (31³ cells by
//! default: 32³ nodes, 98,304 unknowns), through the public model API; on thread ranks
//! it is partitioned by METIS as a run's is.

use crate::common::{elastic_block_deck, generated_model, Cells};
use alfe::linalg::Preconditioner;
use alfe::linalg::{gmres, BlockJacobi, DistMatrix, Factorization, FillOrdering, GmresOptions};
use alfe::parallel::{peak_rss_mb, run_ranks, Comm, SerialComm};
use alfe::{Error, Result};
use std::time::Instant;

/// A timing of `factor-timing`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Case {
    /// Cholesky, AMD ordering.
    LltAmd,
    /// Cholesky, nested dissection.
    LltNd,
    /// LU, COLAMD ordering.
    LuAmd,
    /// LU, nested dissection of the squared graph.
    LuNd,
    /// Block-Jacobi GMRES on thread ranks.
    Ranks,
}

/// `alfe-bench factor-timing`'s options.
#[derive(clap::Args, Debug)]
pub struct FactorArgs {
    /// Cells NX,NY,NZ of the unit block (31,31,31: 98,304 unknowns; 43,43,43: 254k).
    #[arg(long, value_name = "NX,NY,NZ", default_value = "31,31,31")]
    pub cells: Cells,
    /// The timings to run, comma-separated.
    #[arg(long, value_enum, value_delimiter = ',',
          default_values = ["llt-amd", "llt-nd", "lu-amd", "lu-nd", "ranks"])]
    pub cases: Vec<Case>,
    /// The thread-rank counts of the `ranks` case, comma-separated.
    #[arg(long, value_name = "P,...", value_delimiter = ',', default_values = ["2", "4"],
          value_parser = clap::value_parser!(u32).range(1..))]
    pub thread_ranks: Vec<u32>,
}

/// The factorization cases: name, kind, ordering.
const FACTORIZATIONS: [(Case, &str, Factorization, FillOrdering); 4] = [
    (
        Case::LltAmd,
        "llt-amd",
        Factorization::Cholesky,
        FillOrdering::Amd,
    ),
    (
        Case::LltNd,
        "llt-nd",
        Factorization::Cholesky,
        FillOrdering::NestedDissection,
    ),
    (Case::LuAmd, "lu-amd", Factorization::Lu, FillOrdering::Amd),
    (
        Case::LuNd,
        "lu-nd",
        Factorization::Lu,
        FillOrdering::NestedDissection,
    ),
];

/// Run the asked timings in this process (started without mpirun); one line each on
/// stdout.
pub fn run(a: &FactorArgs) -> Result<()> {
    let t = Instant::now();
    let (mut m, b) = system(&SerialComm, a.cells)?;
    let t_asm = t.elapsed().as_secs_f64();
    let x: Vec<f64> = (0..m.n_owned_dofs()).map(|i| (i as f64).sin()).collect();
    let mut y = vec![0.0; x.len()];
    let t = Instant::now();
    for _ in 0..20 {
        m.spmv(&SerialComm, &x, &mut y);
    }
    println!(
        "1 rank: n = {}, {} scalar nonzeros; model and assembly {t_asm:.2} s; spmv {:.2} ms; \
         peak RSS {:.0} MiB",
        m.n_owned_dofs(),
        m.nnz_local(),
        t.elapsed().as_secs_f64() / 20.0 * 1e3,
        peak_rss_mb()
    );
    let mut z_first: Option<Vec<f64>> = None;
    for (case, name, kind, ordering) in FACTORIZATIONS {
        if a.cases.contains(&case) {
            let z = factorization(&m, &b, name, kind, ordering, z_first.as_deref())?;
            z_first.get_or_insert(z);
        }
    }
    if a.cases.contains(&Case::Ranks) {
        // One block is a direct solve: GMRES converges in one iteration.
        let bj = BlockJacobi::new(&m)?;
        let mut x = vec![0.0; b.len()];
        let st = gmres(
            &SerialComm,
            &mut m,
            &bj,
            &b,
            &mut x,
            &GmresOptions::default(),
        )?;
        if !(st.converged && st.iterations == 1) {
            return Err(Error::runtime(format!(
                "1 rank: block Jacobi is not a direct solve ({} iterations)",
                st.iterations
            )));
        }
        for &p in &a.thread_ranks {
            thread_ranks(p as usize, a.cells)?;
        }
    }
    Ok(())
}

/// The clamped tangent of the elastic block on the ranks of `comm`, and a right-hand
/// side (−1 in z, 0.1 in x and y on every owned unknown).
fn system(comm: &dyn Comm, cells: Cells) -> Result<(DistMatrix, Vec<f64>)> {
    let mut model = generated_model(comm, elastic_block_deck(cells.0), "factor-timing")?;
    let n = model.n_owned_dofs();
    let mut k = model.new_matrix(comm);
    model.jacobian(comm, &vec![0.0; n], 1.0, &mut k)?;
    k.constrain(comm, &model.constrained_dofs());
    let b = (0..n)
        .map(|i| if i % 3 == 2 { -1.0 } else { 0.1 })
        .collect();
    Ok((k, b))
}

/// ‖Az − r‖ / ‖r‖ on one rank.
fn relative_residual(m: &DistMatrix, z: &[f64], r: &[f64]) -> f64 {
    let mut az = vec![0.0; r.len()];
    m.spmv(&SerialComm, z, &mut az);
    let e: f64 = az
        .iter()
        .zip(r)
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<f64>()
        .sqrt();
    e / SerialComm.norm2(r)
}

/// Reset the peak RSS to the current RSS (Linux: write 5 to /proc/self/clear_refs).
fn reset_peak_rss() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// One factorization of the whole matrix, timed, its solve checked (residual < 1e-8) and
/// compared with the first case's (`z_first`). Returns the solution.
fn factorization(
    m: &DistMatrix,
    b: &[f64],
    name: &str,
    kind: Factorization,
    ordering: FillOrdering,
    z_first: Option<&[f64]>,
) -> Result<Vec<f64>> {
    reset_peak_rss();
    let rss0 = peak_rss_mb();
    let t = Instant::now();
    let mut bj = BlockJacobi::with_options(m, kind, ordering)?;
    let t_first = t.elapsed().as_secs_f64();
    if bj.kind() != kind {
        return Err(Error::runtime(format!(
            "{name}: factored as {:?}",
            bj.kind()
        )));
    }
    let rss1 = peak_rss_mb();
    let t = Instant::now();
    bj.refactor(m)?;
    let t_refactor = t.elapsed().as_secs_f64();
    let mut z = vec![0.0; b.len()];
    let t = Instant::now();
    bj.apply(&SerialComm, b, &mut z);
    let t_solve = t.elapsed().as_secs_f64();
    let res = relative_residual(m, &z, b);
    let diff = z_first.map_or(0.0, |r| {
        r.iter()
            .zip(&z)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
    });
    let zmax = z.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    println!(
        "1 rank {name}: ordering {:.2} s; symbolic (incl. ordering) {:.2} s; new() total \
         {t_first:.2} s; refactor {t_refactor:.2} s; one solve {t_solve:.3} s; L values {}; \
         peak RSS during new() {:.0} MiB (+{:.0}); residual {res:.1e}; \
         max|z - z_first| / max|z| = {:.1e}",
        bj.ordering_seconds(),
        bj.symbolic_seconds(),
        bj.cholesky_factor_nnz(),
        rss1,
        rss1 - rss0,
        diff / zmax
    );
    if res >= 1e-8 {
        return Err(Error::runtime(format!("{name}: residual {res:e}")));
    }
    Ok(z)
}

/// Block-Jacobi GMRES on `p` thread ranks: factor time per rank, iterations and times.
fn thread_ranks(p: usize, cells: Cells) -> Result<()> {
    let out = run_ranks(p, |c| -> Result<_> {
        let (mut m, b) = system(c, cells)?;
        let t = Instant::now();
        let bj = BlockJacobi::new(&m);
        if !c.all_ok(bj.is_ok()) {
            bj?;
            return Err(Error::runtime("block Jacobi failed on another rank"));
        }
        let bj = bj?;
        let t_fac = t.elapsed().as_secs_f64();
        let mut x = vec![0.0; b.len()];
        let t = Instant::now();
        let st = gmres(c, &mut m, &bj, &b, &mut x, &GmresOptions::default())?;
        Ok((t_fac, t.elapsed().as_secs_f64(), st))
    });
    let out = out.into_iter().collect::<Result<Vec<_>>>()?;
    let (_, t_gm, st) = &out[0];
    let facs: Vec<String> = out.iter().map(|o| format!("{:.2}", o.0)).collect();
    println!(
        "{p} thread ranks (on {} cores): factor per rank [{}] s; GMRES {} it, {:.2} s \
         (rank 0: operator {:.2} s, preconditioner {:.2} s), converged {}, {} reductions",
        std::thread::available_parallelism().map_or(0, |n| n.get()),
        facs.join(", "),
        st.iterations,
        t_gm,
        st.seconds_in_operator,
        st.seconds_in_preconditioner,
        st.converged,
        st.reductions
    );
    Ok(())
}
