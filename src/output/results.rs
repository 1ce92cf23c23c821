//! The run's results, a stable interface for scripts (README "Outputs"):
//! `DIR/<scene>.h5` (mesh once, then `/steps/NNNNNN/{displacement,stress,von_mises}`,
//! written collectively, each rank its own rows), `DIR/<scene>.xmf` (XDMF3 for
//! ParaView, rewritten after each step so an interrupted run stays readable),
//! `DIR/history.csv` (one row per converged step) and `DIR/summary.json`.

use super::cells::CellRows;
use super::h5::H5File;
use super::xdmf::{
    write_xdmf_with_grids, AttrKind, Center, GridAt, XdmfAttr, XdmfGrid, XdmfMesh, XdmfStep,
    XdmfTopology,
};
use crate::mesh::ElemKind;
use crate::model::contribution::Center as FieldCenter;
use crate::model::Model;
use crate::parallel::{rank0_outcome, Comm};
use crate::solve::stepping::StepRecord;
use crate::{Error, Result};
use std::io::Write;
use std::path::{Path, PathBuf};

/// A contribution's moving geometry in the file: its HDF5 group, point count and
/// cells, and (for a grid whose paths are drawn) the points of every output step so
/// far, step-major (rank 0's copy) with the index of its path grid in `xgrids`.
struct GridOut {
    group: String,
    n_points: usize,
    cells: (String, u64),
    path: Option<(usize, Vec<[f64; 3]>)>,
}

pub struct ResultsWriter {
    h5: H5File,
    xmf_path: PathBuf,
    xmesh: XdmfMesh,
    steps: Vec<XdmfStep>,
    /// The contributions' moving geometry (model order) and its XDMF grids.
    grids: Vec<GridOut>,
    xgrids: Vec<XdmfGrid>,
    history: Option<std::fs::File>,
    /// The header written to `history.csv` (rank 0).
    history_head: String,
    /// The run has analysis steps: history.csv has an `analysis_step` column.
    staged: bool,
    /// Which of the contributions' history columns are integer counts.
    counts: Vec<bool>,
    n_nodes: u64,
    n_elems: u64,
    node_start: u64,
    /// Where this rank's elements go in the cell datasets.
    cells: CellRows,
    /// Owned node dofs: the displacement part of an owned unknown vector.
    n_node_dofs: usize,
    /// Output steps carried from the run this one restarts (at the front of `steps`).
    carried: usize,
    pub seconds: f64,
    pub bytes_written: u64,
}

/// What the `.xmf` is written from, kept beside the restart files (`restart/xdmf.json`)
/// so that a restarted run's `.xmf` covers the earlier run's steps too.
#[derive(serde::Serialize, serde::Deserialize)]
struct XdmfIndex {
    h5_file: String,
    steps: Vec<XdmfStep>,
    grids: Vec<(String, Vec<GridAt>)>,
}

/// `to` relative to directory `from` (both made absolute), e.g. `../run/scene.h5`.
fn relative(from: &Path, to: &Path) -> Option<PathBuf> {
    let (from, to) = (from.canonicalize().ok()?, to.canonicalize().ok()?);
    let common = from
        .components()
        .zip(to.components())
        .take_while(|(a, b)| a == b)
        .count();
    let mut out = PathBuf::new();
    for _ in from.components().skip(common) {
        out.push("..");
    }
    out.extend(to.components().skip(common));
    Some(out)
}

/// HDF5 group paths of the grids: each `/`-separated component of the names the
/// contributions give kept (a deck name's own `/` replaced), made unique by the grid's
/// index where that makes two equal.
fn grid_groups(names: &[String]) -> Vec<String> {
    let mut out: Vec<String> = Vec::with_capacity(names.len());
    for (i, n) in names.iter().enumerate() {
        let (dir, leaf) = match n.split_once('/') {
            Some((d, l)) => (format!("{d}/"), l),
            None => (String::new(), n.as_str()),
        };
        let mut g = leaf.replace('/', "_");
        if g.is_empty() || g == "." || g == ".." || out.contains(&format!("{dir}{g}")) {
            g = format!("{g}_{i}");
        }
        out.push(format!("{dir}{g}"));
    }
    out
}

/// Collective: the paths of `n` points through the output steps so far, after adding
/// this step's `now` (rank 0's; `so_far` grows on rank 0 only), `n_steps` output steps
/// in all with this one, as points (step-major:
/// step s, point p is row s n + p) and segments joining each point's consecutive rows
/// (at the first step, one degenerate segment per point). Its size grows with the
/// step count, but a step's fields (several values per node) stay larger for as many
/// output steps as a run has nodes, so the file does not grow faster than its fields.
fn write_paths(
    h5: &H5File,
    group: &str,
    n: usize,
    n_steps: usize,
    so_far: &mut Vec<[f64; 3]>,
    now: &[[f64; 3]],
    rank0: bool,
) -> Result<GridAt> {
    so_far.extend_from_slice(now);
    let n_points = (n_steps * n) as u64;
    let n_cells = ((n_steps - 1).max(1) * n) as u64;
    let (points, segments): (Vec<f64>, Vec<i64>) = if rank0 {
        let seg = (0..n_cells as usize).flat_map(|r| {
            let a = r as i64;
            [a, if n_steps > 1 { a + n as i64 } else { a }]
        });
        (so_far.iter().flatten().copied().collect(), seg.collect())
    } else {
        (Vec::new(), Vec::new())
    };
    let at = GridAt {
        points: format!("{group}/points"),
        n_points,
        cells: format!("{group}/segments"),
        n_cells,
    };
    h5.write_rows_f64(&at.points, n_points, 3, 0, &points)?;
    h5.write_rows_i64(&at.cells, n_cells, 2, 0, &segments)?;
    Ok(at)
}

/// The columns of `history.csv` a run of `model` writes (what quantities of interest may
/// read).
pub fn history_columns(model: &Model, dynamic: bool, staged: bool) -> Vec<String> {
    let columns: Vec<String> = model.columns().iter().map(|c| c.name.clone()).collect();
    history_header(
        &model.reaction_sets,
        &model.displacement_sets,
        dynamic,
        staged,
        &columns,
    )
    .split(',')
    .map(String::from)
    .collect()
}

/// `history.csv` of `dir` as its header and rows of numbers.
pub fn read_history(dir: &Path) -> std::io::Result<(Vec<String>, Vec<Vec<f64>>)> {
    let text = std::fs::read_to_string(dir.join("history.csv"))?;
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap_or_default()
        .split(',')
        .map(String::from)
        .collect();
    let rows = lines
        .map(|l| {
            l.split(',')
                .map(|v| v.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    Ok((header, rows))
}

/// The header of `history.csv` (README "Outputs"); [`history_row`] writes the rows.
/// `columns` are the contributions' columns (wall forces, contact counts, ...).
pub(crate) fn history_header(
    reaction_sets: &[String],
    displacement_sets: &[String],
    dynamic: bool,
    staged: bool,
    columns: &[String],
) -> String {
    let mut head =
        String::from("step,time,nonlinear_iterations,linear_iterations,retries,wall_time_s");
    if staged {
        head.push_str(",analysis_step");
    }
    for s in reaction_sets {
        head.push_str(&format!(",{s}.fx,{s}.fy,{s}.fz"));
    }
    head.push_str(
        ",residual_evaluations,factorizations,final_relative_residual,assembly_s,linear_s",
    );
    for s in displacement_sets {
        head.push_str(&format!(",{s}.ux,{s}.uy,{s}.uz"));
    }
    if dynamic {
        head.push_str(",kinetic_energy,internal_energy,external_work,energy_balance");
    }
    for c in columns {
        head.push(',');
        head.push_str(c);
    }
    head
}

/// One row of `history.csv` (the columns of [`history_header`]); `counts` says which of
/// the contributions' columns are integer counts; `nan` where a record lacks them.
pub(crate) fn history_row(rec: &StepRecord, staged: bool, counts: &[bool]) -> String {
    let s = &rec.stats;
    let mut row = format!(
        "{},{},{},{},{},{:.6}",
        rec.step, rec.time, s.iterations, s.linear_iterations, rec.retries, rec.wall_seconds
    );
    if staged {
        row.push_str(&format!(",{}", rec.stage + 1));
    }
    for f3 in &rec.reactions {
        row.push_str(&format!(",{:.12e},{:.12e},{:.12e}", f3[0], f3[1], f3[2]));
    }
    row.push_str(&format!(
        ",{},{},{:.3e},{:.6},{:.6}",
        s.residual_evaluations,
        s.factorizations,
        s.residual_history.last().copied().unwrap_or(0.0),
        s.seconds_assembly,
        s.seconds_linear
    ));
    for d in &rec.displacements {
        row.push_str(&format!(",{:.12e},{:.12e},{:.12e}", d[0], d[1], d[2]));
    }
    if let Some(e) = &rec.energies {
        row.push_str(&format!(
            ",{:.12e},{:.12e},{:.12e},{:.6e}",
            e.kinetic, e.internal, e.external, e.balance
        ));
    }
    for (i, &count) in counts.iter().enumerate() {
        match rec.columns.get(i) {
            Some(v) if count => row.push_str(&format!(",{}", *v as u64)),
            Some(v) => row.push_str(&format!(",{v:.12e}")),
            None => row.push_str(",nan"),
        }
    }
    row
}

/// Collective: `/mesh`: coordinates, original ids, connectivity, partition, material
/// and part (cell rows in `cells`' order); returns the XDMF topology and the bytes of
/// coordinates written.
fn write_mesh(
    comm: &dyn Comm,
    h5: &H5File,
    model: &Model,
    cells: &CellRows,
) -> Result<(XdmfTopology, u64)> {
    let l = &model.mesh;
    let el = &model.solids.elements;
    let n_nodes = l.n_nodes_global as u64;
    let n_elems = l.n_elems_global as u64;
    let node_start = l.node_start() as u64;
    let coords: Vec<f64> = l.coords[..l.n_owned()].iter().flatten().copied().collect();
    h5.write_rows_f64("/mesh/coordinates", n_nodes, 3, node_start, &coords)?;
    let orig_n: Vec<i64> = l.orig_node.iter().map(|&n| n as i64).collect();
    h5.write_rows_i64("/mesh/original_node_id", n_nodes, 1, node_start, &orig_n)?;
    let topology = write_connectivity(comm, h5, model, cells)?;
    let part: Vec<i32> = vec![comm.rank() as i32; el.len()];
    cells.write(h5, "/mesh/partition", n_elems, 1, &part)?;
    let mat: Vec<i32> = el.material.iter().map(|&m| m as i32).collect();
    cells.write(h5, "/mesh/material", n_elems, 1, &mat)?;
    let parts: Vec<i32> = (0..el.len())
        .map(|e| el.part.get(e).map_or(0, |&p| p as i32))
        .collect();
    cells.write(h5, "/mesh/part", n_elems, 1, &parts)?;
    let orig_e: Vec<i64> = el.orig.iter().map(|&e| e as i64).collect();
    cells.write(h5, "/mesh/original_element_id", n_elems, 1, &orig_e)?;
    Ok((topology, 8 * coords.len() as u64))
}

/// Collective: `/mesh/connectivity` in global (rank-contiguous) node numbers, cells in
/// `cells`' order: one row per element where all elements are of one kind, else XDMF
/// mixed (`[type, nodes...]` per element).
fn write_connectivity(
    comm: &dyn Comm,
    h5: &H5File,
    model: &Model,
    cells: &CellRows,
) -> Result<XdmfTopology> {
    let l = &model.mesh;
    let el = &model.solids.elements;
    // Which kinds are present anywhere: hex8, tet4, tet10, wedge6.
    let mut kinds = [0.0; 4];
    for k in &el.kinds {
        kinds[match k {
            ElemKind::Hex8 => 0,
            ElemKind::Tet4 => 1,
            ElemKind::Tet10 => 2,
            ElemKind::Wedge6 => 3,
        }] = 1.0;
    }
    comm.allreduce_max(&mut kinds);
    // A tet10's nodes in VTK/XDMF order (its midside nodes of edges 2-3 and 1-3 swap).
    let out_nodes = |e: usize| -> Vec<i64> {
        let en = el.nodes(e);
        let g = |a: usize| l.global_node(en[a]) as i64;
        match el.kinds[e] {
            ElemKind::Tet10 => [0, 1, 2, 3, 4, 5, 6, 7, 9, 8].map(g).to_vec(),
            // VTK's wedge: the first triangle's normal points away from the second.
            ElemKind::Wedge6 => [0, 2, 1, 3, 5, 4].map(g).to_vec(),
            _ => (0..en.len()).map(g).collect(),
        }
    };
    // Wedges go out as a mixed array (no uniform wedge topology here).
    if kinds.iter().filter(|&&k| k > 0.0).count() > 1 || kinds[3] > 0.0 {
        let mut mixed = Vec::new();
        for &e in cells.order() {
            mixed.push(match el.kinds[e] {
                ElemKind::Hex8 => 9,
                ElemKind::Tet4 => 6,
                ElemKind::Tet10 => super::xdmf::XDMF_TETRAHEDRON_10,
                ElemKind::Wedge6 => 8,
            });
            mixed.extend(out_nodes(e));
        }
        let (_, total) = comm.exclusive_scan(mixed.len() as u64);
        cells.write_entries(h5, "/mesh/connectivity", total, &mixed)?;
        return Ok(XdmfTopology::Mixed { n_entries: total });
    }
    let npe = if kinds[2] > 0.0 {
        10
    } else if kinds[1] > 0.0 {
        4
    } else {
        8
    };
    let conn: Vec<i64> = (0..el.len()).flat_map(out_nodes).collect();
    cells.write(
        h5,
        "/mesh/connectivity",
        l.n_elems_global as u64,
        npe,
        &conn,
    )?;
    Ok(if npe == 10 {
        XdmfTopology::Tetrahedron10
    } else if npe == 4 {
        XdmfTopology::Tetrahedron
    } else {
        XdmfTopology::Hexahedron
    })
}

/// Collective: the moving geometry's cells, once (rank 0 writes the rows, every rank
/// takes part); returns the grids' output state, their XDMF grids and the bytes written.
fn write_grids(
    comm: &dyn Comm,
    h5: &H5File,
    model: &Model,
) -> Result<(Vec<GridOut>, Vec<XdmfGrid>, u64)> {
    let mut bytes = 0;
    let specs = model.grids();
    let names: Vec<String> = specs.iter().map(|g| g.name.clone()).collect();
    let mut grids = Vec::new();
    let mut xgrids = Vec::new();
    for (g, group) in specs.iter().zip(grid_groups(&names)) {
        let width = g.cells.first().map_or(3, |c| c.len()).clamp(1, 3);
        let what = ["vertices", "segments", "triangles"][width - 1];
        let path = format!("/{group}/{what}");
        let flat: Vec<i64> = if comm.rank() == 0 {
            g.cells.iter().flatten().map(|&i| i as i64).collect()
        } else {
            Vec::new()
        };
        h5.write_rows_i64(&path, g.cells.len() as u64, width as u64, 0, &flat)?;
        for (k, v) in &g.attrs {
            h5.write_attr_str(&format!("/{group}"), k, v)?;
        }
        // Its ParaView block names (the grid's, and its path's where it draws one).
        h5.write_attr_str(&format!("/{group}"), "block", &g.label)?;
        if g.paths {
            h5.write_attr_str(
                &format!("/{group}"),
                "path_block",
                &format!("{}_path", g.label),
            )?;
        }
        bytes += 8 * flat.len() as u64;
        xgrids.push(XdmfGrid {
            name: g.label.clone(),
            nodes_per_cell: width as u64,
            steps: Vec::new(),
        });
        let path_grid = g.paths.then(|| {
            xgrids.push(XdmfGrid {
                name: format!("{}_path", g.label),
                nodes_per_cell: 2,
                steps: Vec::new(),
            });
            (xgrids.len() - 1, Vec::new())
        });
        grids.push(GridOut {
            group,
            n_points: g.n_points,
            cells: (path, g.cells.len() as u64),
            path: path_grid,
        });
    }
    Ok((grids, xgrids, bytes))
}

impl ResultsWriter {
    /// Collective: create the files (named after `scene`) and write the mesh; `units`
    /// describes the unit system, `dynamic` adds the energy columns.
    pub fn create(
        comm: &dyn Comm,
        dir: &Path,
        model: &Model,
        scene: &str,
        units: &str,
        dynamic: bool,
        staged: bool,
    ) -> Result<Self> {
        let t0 = std::time::Instant::now();
        let l = &model.mesh;
        let r = if comm.rank() == 0 {
            std::fs::create_dir_all(dir).map_err(|e| {
                Error::runtime(format!(
                    "cannot create output directory `{}`: {e}",
                    dir.display()
                ))
            })
        } else {
            Ok(())
        };
        rank0_outcome(comm, r)?;
        let h5_name = format!("{scene}.h5");
        let h5 = H5File::create(comm, &dir.join(&h5_name))?;
        let n_nodes = l.n_nodes_global as u64;
        let n_elems = l.n_elems_global as u64;
        let node_start = l.node_start() as u64;
        let cells = CellRows::new(comm, model);
        let mut bytes = 0u64;
        h5.write_attr_str("/", "scene", scene)?;
        h5.write_attr_str("/", "units", units)?;
        h5.write_attr_str("/", "alfe_version", env!("CARGO_PKG_VERSION"))?;
        h5.create_group("/mesh")?;
        let (topology, mesh_bytes) = write_mesh(comm, &h5, model, &cells)?;
        // The part names (`/mesh/part` indexes them; ParaView's blocks are named so).
        let names: Vec<&str> = cells.parts.iter().map(|p| p.name.as_str()).collect();
        let names = serde_json::to_string(&names).map_err(|e| Error::runtime(e.to_string()))?;
        h5.write_attr_str("/mesh", "part_names", &names)?;
        let (grids, xgrids, grid_bytes) = write_grids(comm, &h5, model)?;
        bytes += mesh_bytes + grid_bytes;
        h5.create_group("/steps")?;
        h5.flush()?;
        let cell_i32 = |name: &str, path: &str| XdmfAttr {
            name: name.into(),
            center: Center::Cell,
            kind: AttrKind::Scalar,
            h5_path: path.into(),
            n_rows: n_elems,
            n_cols: 1,
            number_type: "Int".into(),
            precision: 4,
        };
        let xmesh = XdmfMesh {
            h5_file_name: h5_name,
            n_nodes,
            n_elems,
            topology,
            static_cell_attrs: vec![
                cell_i32("partition", "/mesh/partition"),
                cell_i32("material", "/mesh/material"),
                cell_i32("part", "/mesh/part"),
            ],
            parts: cells.parts.clone(),
        };
        let xmf_path = dir.join(format!("{scene}.xmf"));
        let columns: Vec<String> = model.columns().iter().map(|c| c.name.clone()).collect();
        let mut history = None;
        let mut history_head = String::new();
        let r = if comm.rank() == 0 {
            (|| -> Result<()> {
                write_xdmf_with_grids(&xmf_path, &xmesh, &[], &xgrids)?;
                let mut f = std::fs::File::create(dir.join("history.csv"))?;
                let head = history_header(
                    &model.reaction_sets,
                    &model.displacement_sets,
                    dynamic,
                    staged,
                    &columns,
                );
                writeln!(f, "{head}")?;
                history = Some(f);
                history_head = head;
                Ok(())
            })()
        } else {
            Ok(())
        };
        rank0_outcome(comm, r)?;
        let mut w = Self {
            h5,
            xmf_path,
            xmesh,
            steps: Vec::new(),
            grids,
            xgrids,
            history,
            history_head,
            counts: model.columns().iter().map(|c| c.count).collect(),
            staged,
            n_nodes,
            n_elems,
            node_start,
            cells,
            carried: 0,
            n_node_dofs: model.n_node_dofs(),
            seconds: 0.0,
            bytes_written: 0,
        };
        w.bytes_written = bytes;
        w.seconds = t0.elapsed().as_secs_f64();
        Ok(w)
    }

    /// Collective: a restarted run's history begins with the earlier run's rows up to
    /// the step it goes on from (`dir`'s `history.csv`, same columns), so the history
    /// and the quantities of interest cover the whole run. Returns, on rank 0, the rows
    /// carried or why none were (the run goes on either way).
    pub fn carry_history(
        &mut self,
        comm: &dyn Comm,
        dir: &Path,
        up_to_step: usize,
    ) -> Result<std::result::Result<Vec<Vec<f64>>, String>> {
        let mut carried = Ok(Vec::new());
        let r = match self.history.as_mut() {
            Some(f) => {
                let path = dir.join("history.csv");
                let head = &self.history_head;
                let lines = std::fs::read_to_string(&path)
                    .map_err(|e| format!("cannot read {}: {e}", path.display()))
                    .and_then(|text| {
                        let mut lines = text.lines();
                        if lines.next() != Some(head.as_str()) {
                            return Err(format!(
                                "{} has other columns than this run",
                                path.display()
                            ));
                        }
                        Ok(lines
                            .take_while(|l| {
                                l.split(',')
                                    .next()
                                    .and_then(|x| x.parse::<usize>().ok())
                                    .is_some_and(|k| k <= up_to_step)
                            })
                            .map(String::from)
                            .collect::<Vec<_>>())
                    });
                let written = lines
                    .iter()
                    .flatten()
                    .try_for_each(|l| writeln!(f, "{l}"))
                    .and_then(|_| f.flush())
                    .map_err(Error::from);
                carried = lines.map(|ls| {
                    ls.iter()
                        .map(|l| {
                            l.split(',')
                                .map(|v| v.parse().unwrap_or(f64::NAN))
                                .collect()
                        })
                        .collect()
                });
                written
            }
            None => Ok(()),
        };
        rank0_outcome(comm, r)?;
        Ok(carried)
    }

    /// Collective: the history row of a converged step (always) and, if `fields`, its
    /// displacement and the model's fields and geometry.
    pub fn step(
        &mut self,
        comm: &dyn Comm,
        rec: &StepRecord,
        u: &[f64],
        model: &Model,
        fields: bool,
    ) -> Result<()> {
        self.step_with(comm, rec, u, model, fields, &[])
    }

    /// [`ResultsWriter::step`] with more nodal vector fields (n_nodes × 3, owned rows)
    /// written beside the displacement: velocity and acceleration of dynamic runs.
    pub fn step_with(
        &mut self,
        comm: &dyn Comm,
        rec: &StepRecord,
        u: &[f64],
        model: &Model,
        fields: bool,
        nodal: &[(&str, &[f64])],
    ) -> Result<()> {
        let t0 = std::time::Instant::now();
        let r = if let Some(f) = self.history.as_mut() {
            let row = history_row(rec, self.staged, &self.counts);
            writeln!(f, "{row}")
                .and_then(|_| f.flush())
                .map_err(Error::from)
        } else {
            Ok(())
        };
        rank0_outcome(comm, r)?;
        if fields {
            self.fields(comm, rec, u, model, nodal)?;
        }
        self.seconds += t0.elapsed().as_secs_f64();
        Ok(())
    }

    /// Collective: the state before the first increment (`u` zero, time `rec.time`) as
    /// output step `/steps/000000`: fields and geometry, no history row (the history
    /// holds converged steps). ParaView then shows the undeformed model and the walls
    /// where they start.
    pub fn initial_state(
        &mut self,
        comm: &dyn Comm,
        rec: &StepRecord,
        u: &[f64],
        model: &Model,
    ) -> Result<()> {
        let t0 = std::time::Instant::now();
        self.fields(comm, rec, u, model, &[])?;
        self.seconds += t0.elapsed().as_secs_f64();
        Ok(())
    }

    /// Collective: step `rec`'s displacement, the model's fields and its moving geometry
    /// under `/steps/NNNNNN`, then the `.xmf` again with this step.
    fn fields(
        &mut self,
        comm: &dyn Comm,
        rec: &StepRecord,
        u: &[f64],
        model: &Model,
        nodal: &[(&str, &[f64])],
    ) -> Result<()> {
        let g = format!("/steps/{:06}", rec.step);
        self.h5.create_group(&g)?;
        self.h5.write_attr_f64(&g, "time", rec.time)?;
        let attr =
            |name: &str, center: Center, kind: AttrKind, n_rows: u64, n_cols: u64| XdmfAttr {
                name: name.into(),
                center,
                kind,
                h5_path: format!("{g}/{name}"),
                n_rows,
                n_cols,
                number_type: "Float".into(),
                precision: 8,
            };
        let mut attrs = Vec::new();
        let mut node_vectors: Vec<(&str, &[f64])> = vec![("displacement", u)];
        node_vectors.extend_from_slice(nodal);
        for (name, v) in node_vectors {
            let v = &v[..self.n_node_dofs];
            self.h5
                .write_rows_f64(&format!("{g}/{name}"), self.n_nodes, 3, self.node_start, v)?;
            self.bytes_written += 8 * v.len() as u64;
            attrs.push(attr(name, Center::Node, AttrKind::Vector, self.n_nodes, 3));
        }
        for f in model.fields(comm, u, rec.time) {
            let kind = match f.spec.width {
                1 => AttrKind::Scalar,
                3 => AttrKind::Vector,
                _ => AttrKind::Tensor6,
            };
            let (cols, path) = (kind.n_cols(), format!("{g}/{}", f.spec.name));
            let (center, n_rows) = match f.spec.center {
                FieldCenter::Node => {
                    let (n, start) = (self.n_nodes, self.node_start);
                    self.h5.write_rows_f64(&path, n, cols, start, &f.values)?;
                    (Center::Node, n)
                }
                FieldCenter::Cell => {
                    let n = self.n_elems;
                    self.cells.write(&self.h5, &path, n, cols, &f.values)?;
                    (Center::Cell, n)
                }
            };
            self.bytes_written += 8 * f.values.len() as u64;
            attrs.push(attr(&f.spec.name, center, kind, n_rows, cols));
        }
        // Moving geometry at this step (rank 0 writes the rows, every rank takes part).
        if !self.grids.is_empty() {
            let points = model.grid_points(rec.time, &rec.columns);
            let mut grid = 0;
            for (gr, pts) in self.grids.iter_mut().zip(points) {
                let rank0 = comm.rank() == 0;
                let flat: Vec<f64> = if rank0 {
                    pts.iter().flatten().copied().collect()
                } else {
                    Vec::new()
                };
                let path = format!("{g}/{}/points", gr.group);
                self.h5
                    .write_rows_f64(&path, gr.n_points as u64, 3, 0, &flat)?;
                self.bytes_written += 8 * flat.len() as u64;
                self.xgrids[grid].steps.push(GridAt {
                    points: path,
                    n_points: gr.n_points as u64,
                    cells: gr.cells.0.clone(),
                    n_cells: gr.cells.1,
                });
                grid += 1;
                if let Some((i, so_far)) = gr.path.as_mut() {
                    let at = write_paths(
                        &self.h5,
                        &format!("{g}/{}/path", gr.group),
                        gr.n_points,
                        self.xgrids[*i].steps.len() - self.carried + 1,
                        so_far,
                        if rank0 { &pts } else { &[] },
                        rank0,
                    )?;
                    self.bytes_written += at.n_points * 24 + at.n_cells * 16;
                    self.xgrids[*i].steps.push(at);
                    grid += 1;
                }
            }
        }
        self.h5.flush()?;
        self.steps.push(XdmfStep {
            time: rec.time,
            attrs,
            h5_file: None,
        });
        let r = if comm.rank() == 0 {
            write_xdmf_with_grids(&self.xmf_path, &self.xmesh, &self.steps, &self.xgrids)
                .and_then(|_| self.write_index())
        } else {
            Ok(())
        };
        rank0_outcome(comm, r)?;
        Ok(())
    }

    /// `restart/xdmf.json` beside the `.xmf` (rank 0).
    fn write_index(&self) -> Result<()> {
        let index = XdmfIndex {
            h5_file: self.xmesh.h5_file_name.clone(),
            steps: self.steps.clone(),
            grids: self
                .xgrids
                .iter()
                .map(|g| (g.name.clone(), g.steps.clone()))
                .collect(),
        };
        let dir = self.xmf_path.with_file_name("restart");
        let text = serde_json::to_string(&index).map_err(|e| Error::runtime(e.to_string()))?;
        std::fs::create_dir_all(&dir)
            .and_then(|_| std::fs::write(dir.join("xdmf.json"), text))
            .map_err(|e| Error::runtime(format!("cannot write {}/xdmf.json: {e}", dir.display())))
    }

    /// Collective: a restarted run's `.xmf` begins with the output steps of the run in
    /// `dir` up to time `t` (read from its `restart/xdmf.json`, its HDF5 file referred
    /// to by a relative path), so that ParaView shows the whole run from one file. Every
    /// rank reads the index (as it reads its restart file) and all carry it or none.
    /// Returns why none were carried, if so (the run goes on either way).
    pub fn carry_steps(&mut self, comm: &dyn Comm, dir: &Path, t: f64) -> Option<String> {
        let loaded = self.earlier_steps(dir, t);
        let mut failed = [loaded.is_err() as u64];
        comm.allreduce_max_u64(&mut failed);
        let (mut steps, grids) = match loaded {
            Ok(l) if failed[0] == 0 => l,
            Ok(_) => return Some("another rank cannot read the earlier run's steps".into()),
            Err(why) => return Some(why),
        };
        for (g, at) in self.xgrids.iter_mut().zip(grids) {
            g.steps.splice(0..0, at);
        }
        self.carried = steps.len();
        steps.append(&mut self.steps);
        self.steps = steps;
        let r = if comm.rank() == 0 {
            write_xdmf_with_grids(&self.xmf_path, &self.xmesh, &self.steps, &self.xgrids)
        } else {
            Ok(())
        };
        rank0_outcome(comm, r).err().map(|e| e.to_string())
    }

    /// The output steps of the run in `dir` up to time `t` and its grids at them, the
    /// steps' HDF5 files relative to this run's directory.
    #[allow(clippy::type_complexity)]
    fn earlier_steps(
        &self,
        dir: &Path,
        t: f64,
    ) -> std::result::Result<(Vec<XdmfStep>, Vec<Vec<GridAt>>), String> {
        let here = self.xmf_path.parent().unwrap_or(Path::new("."));
        let path = dir.join("restart").join("xdmf.json");
        let index: XdmfIndex = std::fs::read_to_string(&path)
            .map_err(|e| e.to_string())
            .and_then(|t| serde_json::from_str(&t).map_err(|e| e.to_string()))
            .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        let keep = index
            .steps
            .iter()
            .take_while(|s| s.time <= t * (1.0 + 1e-12))
            .count();
        let names: Vec<&String> = index.grids.iter().map(|g| &g.0).collect();
        if names != self.xgrids.iter().map(|g| &g.name).collect::<Vec<_>>()
            || index.grids.iter().any(|g| g.1.len() < keep)
        {
            return Err(format!("{} has other walls or entities", path.display()));
        }
        let mut steps = Vec::with_capacity(keep);
        for s in &index.steps[..keep] {
            let file = dir.join(s.h5_file.as_deref().unwrap_or(&index.h5_file));
            let rel = relative(here, &file).ok_or(format!("cannot find {}", file.display()))?;
            steps.push(XdmfStep {
                h5_file: Some(rel.to_string_lossy().into_owned()),
                ..s.clone()
            });
        }
        let grids = index
            .grids
            .into_iter()
            .map(|g| g.1[..keep].to_vec())
            .collect();
        Ok((steps, grids))
    }

    pub fn n_field_steps(&self) -> usize {
        self.steps.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solve::nonlinear::SolveStats;
    use crate::solve::time::energy::Energies;

    fn record(energies: bool, columns: Vec<f64>) -> StepRecord {
        StepRecord {
            failed: Vec::new(),
            step: 3,
            time: 0.75,
            stage: 1,
            stats: SolveStats::default(),
            retries: 0,
            reactions: vec![[1.0, 2.0, 3.0]],
            wall_seconds: 0.1,
            displacements: vec![[0.0; 3], [0.5; 3]],
            energies: energies.then(Energies::default),
            columns,
        }
    }

    fn cols(s: &str) -> Vec<&str> {
        s.split(',').collect()
    }

    #[test]
    fn history_header_and_rows_have_the_same_columns() {
        let sets = vec!["top".to_string()];
        let disp = vec!["a".to_string(), "b".to_string()];
        // Without contribution columns: none at all.
        for dynamic in [false, true] {
            let h = history_header(&sets, &disp, dynamic, dynamic, &[]);
            assert!(!h.contains("max_penetration"), "{h}");
            let r = history_row(&record(dynamic, vec![]), dynamic, &[]);
            assert_eq!(cols(&h).len(), cols(&r).len(), "{h}\n{r}");
        }
        // A wall's columns and the shared contact columns, last; counts as integers.
        let names: Vec<String> = [
            "floor.fx",
            "floor.fy",
            "floor.fz",
            "floor.mx",
            "max_penetration",
            "contact_active",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        let counts = [false, false, false, false, false, true];
        let values = vec![0.0, 0.0, -15.0, -7.5, 1e-3, 9.0];
        for dynamic in [false, true] {
            let h = history_header(&sets, &disp, dynamic, false, &names);
            let hc = cols(&h);
            let n = hc.len();
            assert_eq!(
                hc[n - 6..],
                names.iter().map(|s| s.as_str()).collect::<Vec<_>>()[..]
            );
            let r = history_row(&record(dynamic, values.clone()), false, &counts);
            let rc = cols(&r);
            assert_eq!(rc.len(), n, "{h}\n{r}");
            let at = |name: &str| rc[hc.iter().position(|c| *c == name).unwrap()];
            assert_eq!(at("floor.fz").parse::<f64>().unwrap(), -15.0);
            assert_eq!(at("max_penetration").parse::<f64>().unwrap(), 1e-3);
            assert_eq!(at("contact_active"), "9");
            assert_eq!(at("top.fy").parse::<f64>().unwrap(), 2.0);
            // A record without its columns still fills every column.
            let r = history_row(&record(dynamic, vec![]), false, &counts);
            assert_eq!(cols(&r).len(), n, "{r}");
            assert!(r.ends_with(",nan,nan"), "{r}");
        }
    }

    #[test]
    fn grid_groups_are_valid_and_unique() {
        let names: Vec<String> = [
            "walls/floor",
            "walls/a/b",
            "walls/a_b",
            "walls/.",
            "points/p",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        assert_eq!(
            grid_groups(&names),
            [
                "walls/floor",
                "walls/a_b",
                "walls/a_b_2",
                "walls/._3",
                "points/p"
            ]
        );
    }
}
