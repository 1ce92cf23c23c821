//! The run's results, a stable interface for scripts (README "Outputs"):
//! `DIR/<scene>.h5` (mesh once, then `/steps/NNNNNN/{displacement,stress,von_mises}`,
//! written collectively, each rank its own rows), `DIR/<scene>.xmf` (XDMF3 for
//! ParaView, rewritten after each step so an interrupted run stays readable),
//! `DIR/history.csv` (one row per converged step) and `DIR/summary.json`.

use super::h5::H5File;
use super::xdmf::{
    write_xdmf_with_walls, AttrKind, Center, XdmfAttr, XdmfMesh, XdmfStep, XdmfTopology, XdmfWall,
};
use crate::fem::element::von_mises;
use crate::mesh::ElemKind;
use crate::model::Model;
use crate::parallel::Comm;
use crate::solve::stepping::StepRecord;
use crate::{Error, Result};
use std::io::Write;
use std::path::{Path, PathBuf};

/// A rigid wall's surface for output: local-frame vertices (placed at each step by the
/// wall's motion) and its HDF5 group name.
struct WallSurface {
    group: String,
    local_points: Vec<[f64; 3]>,
}

pub struct ResultsWriter {
    h5: H5File,
    xmf_path: PathBuf,
    xmesh: XdmfMesh,
    steps: Vec<XdmfStep>,
    /// Rigid walls (model order): their surfaces and XDMF grids (empty without walls).
    walls: Vec<WallSurface>,
    xwalls: Vec<XdmfWall>,
    history: Option<std::fs::File>,
    n_nodes: u64,
    n_elems: u64,
    node_start: u64,
    elem_start: u64,
    /// Owned node dofs: the displacement part of an owned unknown vector.
    n_node_dofs: usize,
    pub seconds: f64,
    pub bytes_written: u64,
}

/// Every rank learns whether a rank-0-only action succeeded, so none is left waiting.
fn agree(comm: &dyn Comm, r: Result<()>) -> Result<()> {
    let ok = comm.all_ok(r.is_ok());
    match (r, ok) {
        (Err(e), _) => Err(e),
        (Ok(()), false) => Err(Error::runtime("writing results failed on rank 0")),
        (Ok(()), true) => Ok(()),
    }
}

/// HDF5 group names of the walls: the deck names with `/` (a path separator in HDF5)
/// replaced, made unique by the wall's index where that makes two equal.
fn wall_groups(names: &[String]) -> Vec<String> {
    let mut out: Vec<String> = Vec::with_capacity(names.len());
    for (i, n) in names.iter().enumerate() {
        let mut g = n.replace('/', "_");
        if g.is_empty() || g == "." || g == ".." || out.contains(&g) {
            g = format!("{g}_{i}");
        }
        out.push(g);
    }
    out
}

/// The header of `history.csv` (README "Outputs"); [`history_row`] writes the rows.
pub(crate) fn history_header(
    reaction_sets: &[String],
    displacement_sets: &[String],
    dynamic: bool,
    walls: &[String],
) -> String {
    let mut head =
        String::from("step,time,nonlinear_iterations,linear_iterations,retries,wall_time_s");
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
    if !walls.is_empty() {
        for w in walls {
            for c in ["fx", "fy", "fz", "mx", "my", "mz", "ux", "uy", "uz"] {
                head.push_str(&format!(",{w}.{c}"));
            }
        }
        head.push_str(",max_penetration,contact_active,contact_sticking");
    }
    head
}

/// One row of `history.csv` for a model with `n_walls` walls (the columns of
/// [`history_header`]; contact columns are `nan` should a record lack its report).
pub(crate) fn history_row(rec: &StepRecord, n_walls: usize) -> String {
    let s = &rec.stats;
    let mut row = format!(
        "{},{},{},{},{},{:.6}",
        rec.step, rec.time, s.iterations, s.linear_iterations, rec.retries, rec.wall_seconds
    );
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
    if n_walls > 0 {
        let c = rec.contact.as_ref();
        for wi in 0..n_walls {
            match c.and_then(|c| c.walls.get(wi)) {
                Some(w) => {
                    for v in w.force.iter().chain(&w.moment).chain(&w.displacement) {
                        row.push_str(&format!(",{v:.12e}"));
                    }
                }
                None => row.push_str(&",nan".repeat(9)),
            }
        }
        match c {
            Some(c) => row.push_str(&format!(
                ",{:.12e},{},{}",
                c.max_penetration, c.active, c.sticking
            )),
            None => row.push_str(",nan,nan,nan"),
        }
    }
    row
}

impl ResultsWriter {
    /// Collective: create the files and write the mesh.
    pub fn create(comm: &dyn Comm, dir: &Path, model: &Model) -> Result<Self> {
        let t0 = std::time::Instant::now();
        let l = &model.local;
        let scene = l.settings.scene.clone();
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
        agree(comm, r)?;
        let h5_name = format!("{scene}.h5");
        let h5 = H5File::create(comm, &dir.join(&h5_name))?;
        let n_nodes = l.n_nodes_global as u64;
        let n_elems = l.n_elems_global as u64;
        let node_start = l.node_start() as u64;
        let elem_start = l.elem_start() as u64;
        let no = l.n_owned();
        let mut bytes = 0u64;
        h5.write_attr_str("/", "scene", &scene)?;
        h5.write_attr_str("/", "units", l.settings.units.describe())?;
        h5.write_attr_str("/", "alfe_version", env!("CARGO_PKG_VERSION"))?;
        h5.create_group("/mesh")?;
        let coords: Vec<f64> = l.coords[..no].iter().flatten().copied().collect();
        h5.write_rows_f64("/mesh/coordinates", n_nodes, 3, node_start, &coords)?;
        bytes += 8 * coords.len() as u64;
        let orig_n: Vec<i64> = l.orig_node.iter().map(|&n| n as i64).collect();
        h5.write_rows_i64("/mesh/original_node_id", n_nodes, 1, node_start, &orig_n)?;
        // Connectivity in global (rank-contiguous) node numbers.
        let mut kinds = [0.0, 0.0];
        for k in &l.kinds {
            kinds[(*k == ElemKind::Tet4) as usize] = 1.0;
        }
        comm.allreduce_max(&mut kinds);
        let topology = if kinds[0] > 0.0 && kinds[1] > 0.0 {
            // XDMF mixed: [type, nodes...] per element; offsets by exclusive scan.
            let mut mixed = Vec::new();
            for e in 0..l.n_elems() {
                mixed.push(match l.kinds[e] {
                    ElemKind::Hex8 => 9,
                    ElemKind::Tet4 => 6,
                });
                mixed.extend(l.elem_nodes(e).iter().map(|&n| l.global_node(n) as i64));
            }
            let (before, total) = comm.exclusive_scan(mixed.len() as u64);
            h5.write_rows_i64("/mesh/connectivity", total, 1, before, &mixed)?;
            XdmfTopology::Mixed { n_entries: total }
        } else {
            let npe = if kinds[1] > 0.0 { 4 } else { 8 };
            let conn: Vec<i64> = (0..l.n_elems())
                .flat_map(|e| {
                    l.elem_nodes(e)
                        .iter()
                        .map(|&n| l.global_node(n) as i64)
                        .collect::<Vec<_>>()
                })
                .collect();
            h5.write_rows_i64("/mesh/connectivity", n_elems, npe, elem_start, &conn)?;
            if npe == 4 {
                XdmfTopology::Tetrahedron
            } else {
                XdmfTopology::Hexahedron
            }
        };
        let part: Vec<i32> = vec![comm.rank() as i32; l.n_elems()];
        h5.write_rows_i32("/mesh/partition", n_elems, 1, elem_start, &part)?;
        let mat: Vec<i32> = l.elem_material.iter().map(|&m| m as i32).collect();
        h5.write_rows_i32("/mesh/material", n_elems, 1, elem_start, &mat)?;
        let orig_e: Vec<i64> = l.orig_elem.iter().map(|&e| e as i64).collect();
        h5.write_rows_i64("/mesh/original_element_id", n_elems, 1, elem_start, &orig_e)?;
        // Rigid walls: triangles once (rank 0 writes the rows, every rank takes part).
        let names: Vec<String> = model
            .contact
            .walls
            .iter()
            .map(|w| w.def.name.clone())
            .collect();
        let mut walls = Vec::new();
        let mut xwalls = Vec::new();
        for (w, group) in model.contact.walls.iter().zip(wall_groups(&names)) {
            let (points, tris) = w.shape.surface();
            let path = format!("/walls/{group}/triangles");
            let flat: Vec<i64> = if comm.rank() == 0 {
                tris.iter().flatten().map(|&i| i as i64).collect()
            } else {
                Vec::new()
            };
            h5.write_rows_i64(&path, tris.len() as u64, 3, 0, &flat)?;
            h5.write_attr_str(&format!("/walls/{group}"), "name", &w.def.name)?;
            h5.write_attr_str(&format!("/walls/{group}"), "shape", w.shape.kind())?;
            bytes += 8 * flat.len() as u64;
            xwalls.push(XdmfWall {
                name: w.def.name.clone(),
                triangles_path: path,
                n_triangles: tris.len() as u64,
                n_points: points.len() as u64,
                points_paths: Vec::new(),
            });
            walls.push(WallSurface {
                group,
                local_points: points,
            });
        }
        h5.create_group("/steps")?;
        h5.flush()?;
        let cell_i32 = |name: &str, path: &str| XdmfAttr {
            name: name.into(),
            center: Center::Cell,
            kind: AttrKind::Scalar,
            h5_path: path.into(),
            n_rows: n_elems,
            n_cols: 1,
            number_type: "Int",
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
            ],
        };
        let xmf_path = dir.join(format!("{scene}.xmf"));
        let mut history = None;
        let r = if comm.rank() == 0 {
            (|| -> Result<()> {
                write_xdmf_with_walls(&xmf_path, &xmesh, &[], &xwalls)?;
                let mut f = std::fs::File::create(dir.join("history.csv"))?;
                let head = history_header(
                    &l.reaction_sets,
                    &l.settings.output.displacements,
                    l.settings.analysis.kind != crate::scene::deck::AnalysisKind::Static,
                    &names,
                );
                writeln!(f, "{head}")?;
                history = Some(f);
                Ok(())
            })()
        } else {
            Ok(())
        };
        agree(comm, r)?;
        let mut w = Self {
            h5,
            xmf_path,
            xmesh,
            steps: Vec::new(),
            walls,
            xwalls,
            history,
            n_nodes,
            n_elems,
            node_start,
            elem_start,
            n_node_dofs: model.n_node_dofs(),
            seconds: 0.0,
            bytes_written: 0,
        };
        w.bytes_written = bytes;
        w.seconds = t0.elapsed().as_secs_f64();
        Ok(w)
    }

    /// Collective: the history row of a converged step (always) and, if `fields`, its
    /// displacement and stress fields.
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
        let n_walls = self.walls.len();
        let r = if let Some(f) = self.history.as_mut() {
            let row = history_row(rec, n_walls);
            writeln!(f, "{row}")
                .and_then(|_| f.flush())
                .map_err(Error::from)
        } else {
            Ok(())
        };
        agree(comm, r)?;
        if fields {
            let g = format!("/steps/{:06}", rec.step);
            self.h5.create_group(&g)?;
            self.h5.write_attr_f64(&g, "time", rec.time)?;
            self.h5.write_rows_f64(
                &format!("{g}/displacement"),
                self.n_nodes,
                3,
                self.node_start,
                &u[..self.n_node_dofs],
            )?;
            let sig = model.stresses(comm, u)?;
            let flat: Vec<f64> = sig.iter().flatten().copied().collect();
            self.h5.write_rows_f64(
                &format!("{g}/stress"),
                self.n_elems,
                6,
                self.elem_start,
                &flat,
            )?;
            let vm: Vec<f64> = sig.iter().map(von_mises).collect();
            self.h5.write_rows_f64(
                &format!("{g}/von_mises"),
                self.n_elems,
                1,
                self.elem_start,
                &vm,
            )?;
            let plastic = model.has_plastic_strain();
            if plastic {
                let ep = model.plastic_strains();
                self.h5.write_rows_f64(
                    &format!("{g}/plastic_strain"),
                    self.n_elems,
                    1,
                    self.elem_start,
                    &ep,
                )?;
                self.bytes_written += 8 * ep.len() as u64;
            }
            for (name, v) in nodal {
                self.h5.write_rows_f64(
                    &format!("{g}/{name}"),
                    self.n_nodes,
                    3,
                    self.node_start,
                    &v[..self.n_node_dofs],
                )?;
                self.bytes_written += 8 * v.len() as u64;
            }
            // Contact: nodal fields (owned rows, like the displacement) and each wall's
            // surface at this step's time (rank 0 writes the rows, every rank takes part).
            let contact_fields: [(&str, AttrKind); 4] = [
                ("contact_gap", AttrKind::Scalar),
                ("contact_pressure", AttrKind::Scalar),
                ("contact_force", AttrKind::Vector),
                ("contact_lambda", AttrKind::Vector),
            ];
            if !self.walls.is_empty() {
                let cf = model.contact.nodal_fields(model.local.n_owned());
                let values = [&cf.gap, &cf.pressure, &cf.force, &cf.lambda];
                for ((name, kind), v) in contact_fields.iter().zip(values) {
                    self.h5.write_rows_f64(
                        &format!("{g}/{name}"),
                        self.n_nodes,
                        kind.n_cols(),
                        self.node_start,
                        v,
                    )?;
                    self.bytes_written += 8 * v.len() as u64;
                }
                for (wi, w) in self.walls.iter().enumerate() {
                    let pose = model.contact.walls[wi].def.motion.pose(rec.time);
                    let points: Vec<f64> = if comm.rank() == 0 {
                        w.local_points
                            .iter()
                            .flat_map(|&p| pose.to_global(p))
                            .collect()
                    } else {
                        Vec::new()
                    };
                    let path = format!("{g}/walls/{}/points", w.group);
                    self.h5
                        .write_rows_f64(&path, w.local_points.len() as u64, 3, 0, &points)?;
                    self.bytes_written += 8 * points.len() as u64;
                    self.xwalls[wi].points_paths.push(path);
                }
            }
            self.h5.flush()?;
            self.bytes_written += 8 * (u.len() + flat.len() + vm.len()) as u64;
            let attr =
                |name: &str, center: Center, kind: AttrKind, n_rows: u64, n_cols: u64| XdmfAttr {
                    name: name.into(),
                    center,
                    kind,
                    h5_path: format!("{g}/{name}"),
                    n_rows,
                    n_cols,
                    number_type: "Float",
                    precision: 8,
                };
            let mut attrs = vec![
                attr(
                    "displacement",
                    Center::Node,
                    AttrKind::Vector,
                    self.n_nodes,
                    3,
                ),
                attr("stress", Center::Cell, AttrKind::Tensor6, self.n_elems, 6),
                attr("von_mises", Center::Cell, AttrKind::Scalar, self.n_elems, 1),
            ];
            for (name, _) in nodal {
                attrs.push(attr(name, Center::Node, AttrKind::Vector, self.n_nodes, 3));
            }
            self.steps.push(XdmfStep {
                time: rec.time,
                attrs,
            });
            if plastic {
                let last = self.steps.last_mut().expect("just pushed");
                last.attrs.push(attr(
                    "plastic_strain",
                    Center::Cell,
                    AttrKind::Scalar,
                    self.n_elems,
                    1,
                ));
            }
            if !self.walls.is_empty() {
                let last = self.steps.last_mut().expect("just pushed");
                for (name, kind) in contact_fields {
                    last.attrs
                        .push(attr(name, Center::Node, kind, self.n_nodes, kind.n_cols()));
                }
            }
            let r = if comm.rank() == 0 {
                write_xdmf_with_walls(&self.xmf_path, &self.xmesh, &self.steps, &self.xwalls)
            } else {
                Ok(())
            };
            agree(comm, r)?;
        }
        self.seconds += t0.elapsed().as_secs_f64();
        Ok(())
    }

    pub fn n_field_steps(&self) -> usize {
        self.steps.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::contact::{ContactReport, WallReport};
    use crate::solve::nonlinear::SolveStats;
    use crate::solve::time::energy::Energies;

    fn record(energies: bool, contact: Option<ContactReport>) -> StepRecord {
        StepRecord {
            step: 3,
            time: 0.75,
            stats: SolveStats::default(),
            retries: 0,
            reactions: vec![[1.0, 2.0, 3.0]],
            wall_seconds: 0.1,
            displacements: vec![[0.0; 3], [0.5; 3]],
            energies: energies.then(Energies::default),
            contact,
        }
    }

    fn cols(s: &str) -> Vec<&str> {
        s.split(',').collect()
    }

    #[test]
    fn history_header_and_rows_have_the_same_columns() {
        let sets = vec!["top".to_string()];
        let disp = vec!["a".to_string(), "b".to_string()];
        // Without walls: no contact columns at all.
        for dynamic in [false, true] {
            let h = history_header(&sets, &disp, dynamic, &[]);
            assert!(!h.contains("max_penetration"), "{h}");
            let r = history_row(&record(dynamic, None), 0);
            assert_eq!(cols(&h).len(), cols(&r).len(), "{h}\n{r}");
        }
        // Two walls: 9 columns each, then penetration and the two counts, last.
        let walls = vec!["floor".to_string(), "punch".to_string()];
        let report = ContactReport {
            walls: vec![
                WallReport {
                    force: [0.0, 0.0, -15.0],
                    moment: [-7.5, 7.5, 0.0],
                    displacement: [0.0, 0.0, 0.25],
                },
                WallReport::default(),
            ],
            max_penetration: 1e-3,
            active: 9,
            sticking: 4,
        };
        for dynamic in [false, true] {
            let h = history_header(&sets, &disp, dynamic, &walls);
            let hc = cols(&h);
            let n = hc.len();
            assert_eq!(
                hc[n - 21..n - 12],
                [
                    "floor.fx", "floor.fy", "floor.fz", "floor.mx", "floor.my", "floor.mz",
                    "floor.ux", "floor.uy", "floor.uz"
                ]
            );
            assert_eq!(hc[n - 12], "punch.fx");
            assert_eq!(
                hc[n - 3..],
                ["max_penetration", "contact_active", "contact_sticking"]
            );
            let r = history_row(&record(dynamic, Some(report.clone())), walls.len());
            let rc = cols(&r);
            assert_eq!(rc.len(), n, "{h}\n{r}");
            let at = |name: &str| -> f64 {
                rc[hc.iter().position(|c| *c == name).unwrap()]
                    .parse()
                    .unwrap()
            };
            assert_eq!(at("floor.fz"), -15.0);
            assert_eq!(at("floor.mx"), -7.5);
            assert_eq!(at("floor.uz"), 0.25);
            assert_eq!(at("max_penetration"), 1e-3);
            assert_eq!(at("contact_active"), 9.0);
            assert_eq!(at("contact_sticking"), 4.0);
            assert_eq!(at("top.fy"), 2.0);
            // A record without its report still fills every column.
            let r = history_row(&record(dynamic, None), walls.len());
            assert_eq!(cols(&r).len(), n, "{r}");
            assert!(r.ends_with(",nan,nan,nan"), "{r}");
        }
    }

    #[test]
    fn wall_groups_are_valid_and_unique() {
        let names: Vec<String> = ["floor", "a/b", "a_b", ".", "floor2"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        assert_eq!(
            wall_groups(&names),
            ["floor", "a_b", "a_b_2", "._3", "floor2"]
        );
    }
}
