//! Where each rank's elements go in the results file: every part's cells contiguous
//! (parts in deck order, ranks in order within a part), so that ParaView's block of a
//! part is one row range (an XDMF hyperslab) of every cell dataset, written once.
//! With one part this is the plain rank-by-rank order.

use super::h5::{H5Elem, H5File};
use super::xdmf::XdmfPart;
use crate::model::Model;
use crate::parallel::Comm;
use crate::Result;

/// See the module documentation.
pub struct CellRows {
    /// This rank's elements in file order (by part, then local order).
    order: Vec<usize>,
    /// This rank's rows of each part's cells: (first row, rows).
    blocks: Vec<(u64, u64)>,
    /// This rank's entries of each part in a mixed connectivity array.
    entry_blocks: Vec<(u64, u64)>,
    /// Every part's rows and entries in the whole file.
    pub parts: Vec<XdmfPart>,
}

impl CellRows {
    /// Collective: the layout of `model`'s elements (one allreduce of the per-part
    /// counts of every rank).
    pub fn new(comm: &dyn Comm, model: &Model) -> Self {
        let el = &model.solids.elements;
        let part_of = |e: usize| el.part.get(e).map_or(0, |&p| p as usize);
        let mut names = model.solids.part_names.clone();
        let n_parts = (0..el.len()).map(|e| part_of(e) + 1).max().unwrap_or(0);
        let mut n = [n_parts as u64];
        comm.allreduce_max_u64(&mut n);
        let n_parts = (n[0] as usize).max(names.len()).max(1);
        for p in names.len()..n_parts {
            names.push(if p == 0 {
                "mesh".into()
            } else {
                format!("part_{p}")
            });
        }
        let mut order: Vec<usize> = (0..el.len()).collect();
        order.sort_by_key(|&e| part_of(e));
        // Per part, this rank's cells and mixed-array entries (type id + nodes), in a
        // rank-major table every rank fills its row of.
        let (ranks, me) = (comm.size(), comm.rank());
        let mut table = vec![0u64; 2 * n_parts * ranks];
        for e in 0..el.len() {
            let row = &mut table[2 * (me * n_parts + part_of(e))..];
            row[0] += 1;
            row[1] += 1 + el.nodes(e).len() as u64;
        }
        comm.allreduce_sum_u64(&mut table);
        let at = |r: usize, p: usize, k: usize| table[2 * (r * n_parts + p) + k];
        let (mut blocks, mut entry_blocks, mut parts) = (Vec::new(), Vec::new(), Vec::new());
        let (mut cell0, mut entry0) = (0u64, 0u64);
        for (p, name) in names.into_iter().enumerate() {
            let before = |k: usize| (0..me).map(|r| at(r, p, k)).sum::<u64>();
            let total = |k: usize| (0..ranks).map(|r| at(r, p, k)).sum::<u64>();
            blocks.push((cell0 + before(0), at(me, p, 0)));
            entry_blocks.push((entry0 + before(1), at(me, p, 1)));
            parts.push(XdmfPart {
                name,
                cells: (cell0, total(0)),
                entries: (entry0, total(1)),
            });
            cell0 += total(0);
            entry0 += total(1);
        }
        CellRows {
            order,
            blocks,
            entry_blocks,
            parts,
        }
    }

    /// This rank's elements in file order.
    pub fn order(&self) -> &[usize] {
        &self.order
    }

    /// Collective: write this rank's rows of a cell dataset of `n_rows` rows of
    /// `n_cols`, given in local element order.
    pub fn write<T: H5Elem>(
        &self,
        h5: &H5File,
        path: &str,
        n_rows: u64,
        n_cols: u64,
        local: &[T],
    ) -> Result<()> {
        let c = n_cols as usize;
        if local.len() != c * self.order.len() {
            return Err(crate::Error::runtime(format!(
                "HDF5 dataset '{path}': {} values for {} elements of {c}",
                local.len(),
                self.order.len()
            )));
        }
        let rows: Vec<T> = self
            .order
            .iter()
            .flat_map(|&e| local[c * e..c * e + c].iter().copied())
            .collect();
        h5.write_row_blocks(path, n_rows, n_cols, &self.blocks, &rows)
    }

    /// Collective: write a mixed connectivity array of `n_entries`, this rank's entries
    /// already in file order.
    pub fn write_entries(&self, h5: &H5File, path: &str, n_entries: u64, v: &[i64]) -> Result<()> {
        h5.write_row_blocks(path, n_entries, 1, &self.entry_blocks, v)
    }
}
