//! Collective HDF5 + XDMF output on a tiny hex mesh, split over the ranks.
//!
//! ```text
//! mpirun -n 2 target/release/examples/h5_collective /tmp/out   # writes /tmp/out/run.h5, run.xmf
//! ```
//! Two hexahedra side by side (12 nodes); node and element rows are split into
//! contiguous blocks over the ranks (with 3 ranks one rank owns no element and still
//! takes part in every collective write). Two output steps with `displacement` (node
//! vector), `stress` (cell Tensor6) and `von_mises` (cell scalar), each step's group
//! carrying a `time` attribute. Values are closed-form so a reader can check them:
//! node n, step s: u = (0.1 s x, 0.01 s n, -s); element e: stress_k = s (10 e + k + 1),
//! von Mises = e + s; partition id = the owning rank.

use alfe::output::xdmf::{CONNECTIVITY, COORDINATES};
use alfe::output::XdmfTopology;
use alfe::output::{write_xdmf, AttrKind, Center, H5File, XdmfAttr, XdmfMesh, XdmfStep};
use alfe::parallel::{Comm, MpiComm};
use std::path::Path;

/// Rows [begin, end) of `n` owned by `rank` of `size` (contiguous blocks).
fn block(n: u64, rank: usize, size: usize) -> (u64, u64) {
    let (r, s) = (rank as u64, size as u64);
    (n * r / s, n * (r + 1) / s)
}

fn attr(name: &str, center: Center, kind: AttrKind, h5_path: String, n_rows: u64) -> XdmfAttr {
    XdmfAttr {
        name: name.into(),
        center,
        kind,
        h5_path,
        n_rows,
        n_cols: kind.n_cols(),
        number_type: "Float".into(),
        precision: 8,
    }
}

fn run(comm: &dyn Comm, dir: &Path) -> alfe::Result<()> {
    let (rank, size) = (comm.rank(), comm.size());
    // Nodes: x in {0,1,2}, y in {0,1}, z in {0,1}; id = x + 3 (y + 2 z).
    let node = |x: u64, y: u64, z: u64| (x + 3 * (y + 2 * z)) as i64;
    let (n_nodes, n_elems) = (12u64, 2u64);
    let (n0, n1) = block(n_nodes, rank, size);
    let (e0, e1) = block(n_elems, rank, size);

    let h5_path = dir.join("run.h5");
    let f = H5File::create(comm, &h5_path)?;
    f.write_attr_str("/", "program", "alfe h5_collective example")?;

    let coords: Vec<f64> = (n0..n1)
        .flat_map(|n| [(n % 3) as f64, ((n / 3) % 2) as f64, (n / 6) as f64])
        .collect();
    f.write_rows_f64(COORDINATES, n_nodes, 3, n0, &coords)?;
    let conn: Vec<i64> = (e0..e1)
        .flat_map(|e| {
            let (a, b) = (e, e + 1);
            [
                node(a, 0, 0),
                node(b, 0, 0),
                node(b, 1, 0),
                node(a, 1, 0),
                node(a, 0, 1),
                node(b, 0, 1),
                node(b, 1, 1),
                node(a, 1, 1),
            ]
        })
        .collect();
    f.write_rows_i64(CONNECTIVITY, n_elems, 8, e0, &conn)?;
    let part: Vec<i32> = (e0..e1).map(|_| rank as i32).collect();
    f.write_rows_i32("/mesh/partition", n_elems, 1, e0, &part)?;

    let mesh = XdmfMesh {
        h5_file_name: "run.h5".into(),
        n_nodes,
        n_elems,
        topology: XdmfTopology::Hexahedron,
        static_cell_attrs: vec![XdmfAttr {
            number_type: "Int".into(),
            precision: 4,
            ..attr(
                "partition",
                Center::Cell,
                AttrKind::Scalar,
                "/mesh/partition".into(),
                n_elems,
            )
        }],
        parts: vec![],
    };
    let mut steps = Vec::new();
    for s in 1..=2u64 {
        let t = 0.5 * s as f64;
        let sf = s as f64;
        let g = format!("/steps/{s:06}");
        f.create_group(&g)?;
        f.write_attr_f64(&g, "time", t)?;
        let u: Vec<f64> = (n0..n1)
            .flat_map(|n| [0.1 * sf * (n % 3) as f64, 0.01 * sf * n as f64, -sf])
            .collect();
        f.write_rows_f64(&format!("{g}/displacement"), n_nodes, 3, n0, &u)?;
        let stress: Vec<f64> = (e0..e1)
            .flat_map(|e| (0..6).map(move |k| sf * (10 * e + k + 1) as f64))
            .collect();
        f.write_rows_f64(&format!("{g}/stress"), n_elems, 6, e0, &stress)?;
        let vm: Vec<f64> = (e0..e1).map(|e| e as f64 + sf).collect();
        f.write_rows_f64(&format!("{g}/von_mises"), n_elems, 1, e0, &vm)?;
        f.flush()?;
        steps.push(XdmfStep {
            time: t,
            attrs: vec![
                attr(
                    "displacement",
                    Center::Node,
                    AttrKind::Vector,
                    format!("{g}/displacement"),
                    n_nodes,
                ),
                attr(
                    "stress",
                    Center::Cell,
                    AttrKind::Tensor6,
                    format!("{g}/stress"),
                    n_elems,
                ),
                attr(
                    "von_mises",
                    Center::Cell,
                    AttrKind::Scalar,
                    format!("{g}/von_mises"),
                    n_elems,
                ),
            ],
            h5_file: None,
        });
        if rank == 0 {
            write_xdmf(&dir.join("run.xmf"), &mesh, &steps)?;
        }
        println!("rank {rank}/{size}: step {s}: nodes {n0}..{n1}, elements {e0}..{e1}");
    }
    if f.independent_writes() != 0 {
        return Err(alfe::Error::runtime(format!(
            "rank {rank}: {} dataset writes were not collective",
            f.independent_writes()
        )));
    }
    println!("rank {rank}/{size}: all dataset writes collective");
    Ok(()) // `f` dropped here: the file is closed collectively, before MPI finalises.
}

fn main() {
    let dir = std::env::args().nth(1).unwrap_or_else(|| ".".into());
    let universe = mpi::initialize().expect("MPI already initialised");
    let comm = MpiComm::new(universe.world());
    if comm.rank() == 0 {
        std::fs::create_dir_all(&dir).expect("cannot create the output directory");
    }
    comm.barrier();
    if let Err(e) = run(&comm, Path::new(&dir)) {
        eprintln!("rank {}: error: {e}", comm.rank());
        comm.abort(e.exit_code());
    }
    drop(comm);
    drop(universe);
}
