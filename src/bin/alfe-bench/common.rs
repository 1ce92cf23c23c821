//! What the benchmarks share: the cell-count argument, a generated model distributed over
//! the ranks, median timings and the JSON report. Only the library's public API.

use alfe::model::{distribute, Model};
use alfe::parallel::{on_rank0, Comm};
use alfe::partition::partition_elements;
use alfe::{Error, Result};
use std::path::Path;
use std::time::Instant;

/// Cells of the generated box, `NX,NY,NZ` on the command line.
#[derive(Clone, Copy, Debug)]
pub struct Cells(pub [usize; 3]);

impl std::str::FromStr for Cells {
    type Err = String;

    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let v: Vec<usize> = s
            .split(',')
            .map(|x| x.trim().parse::<usize>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| format!("expected NX,NY,NZ, got `{s}`"))?;
        match v.as_slice() {
            [a, b, c] if *a > 0 && *b > 0 && *c > 0 => Ok(Cells([*a, *b, *c])),
            _ => Err(format!(
                "expected three positive counts NX,NY,NZ, got `{s}`"
            )),
        }
    }
}

/// The linear-elastic steel block of `alfe-bench linear` (and of `factor-timing`):
/// clamped on x = 0, a traction on x = 1.
pub fn elastic_block_deck(cells: [usize; 3]) -> String {
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

/// A deck text partitioned (METIS) over the ranks of `comm` and distributed: the model
/// the benchmarks time. Collective.
pub fn generated_model(comm: &dyn Comm, text: String, label: &str) -> Result<Model> {
    let p = comm.size();
    let pieces = on_rank0(comm, || {
        let src = alfe::scene::Source {
            text: text.clone(),
            dir: ".".into(),
            label: label.into(),
        };
        let def = alfe::scene::read(&src)?.model;
        let part = partition_elements(&def.mesh, p, def.partition, &def.coupling_edges())?;
        Ok(distribute::split(&def, &part, p))
    })?;
    let local = distribute::scatter(comm, pieces)?;
    Model::new(comm, local)
}

/// Median of repeated timings of a collective action (barrier before each).
pub fn time_median(comm: &dyn Comm, reps: usize, mut f: impl FnMut() -> Result<()>) -> Result<f64> {
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

/// Print the report on rank 0 and write it to `json` if asked.
pub fn report(comm: &dyn Comm, out: &serde_json::Value, json: Option<&Path>) -> Result<()> {
    if comm.rank() == 0 {
        let text = serde_json::to_string_pretty(out).unwrap();
        println!("{text}");
        if let Some(j) = json {
            std::fs::write(j, text + "\n")
                .map_err(|e| Error::runtime(format!("cannot write `{}`: {e}", j.display())))?;
        }
    }
    Ok(())
}
