//! The pattern of a local block matrix: what a factorization of a rank's block (block
//! Jacobi's diagonal block, RAS's subdomain) and the transformations before it (the
//! condensation of attached multipliers, a dense border) read and write.

/// A square local block matrix (3×3 blocks, scalar size 3·`n_nodes`) as block rows of
/// (local block column, entry) pairs: entry e's values are `vals[9e..9e + 9]` (row-major)
/// of the value array given to [`super::LocalFactor::new`] / [`super::LocalFactor::refactor`]. Rows may
/// list their columns in any order; a (row, column) pair appears at most once.
#[derive(Debug, Clone, Default)]
pub struct LocalBlockPattern {
    pub n_nodes: usize,
    /// Row `i`'s pairs are `row_ptr[i]..row_ptr[i + 1]`.
    pub row_ptr: Vec<usize>,
    pub cols: Vec<usize>,
    pub entries: Vec<usize>,
    /// Rows that belong to one element alone (a hybrid hex8's pressure block); empty if
    /// none. See [`super::DistMatrix::set_element_rows`].
    pub element_rows: Vec<bool>,
}

impl LocalBlockPattern {
    /// Whether row `i` belongs to one element alone.
    pub fn is_element_row(&self, i: usize) -> bool {
        self.element_rows.get(i).copied().unwrap_or(false)
    }
}
