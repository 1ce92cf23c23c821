//! Ownership of a globally numbered index space split into one contiguous range per
//! rank (the PETSc convention): rank r owns `[start(r), start(r+1))`.

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Layout {
    /// `starts[r]` is the first global index of rank r; `starts[size]` is the total.
    pub starts: Vec<usize>,
    pub rank: usize,
}

impl Layout {
    /// From every rank's owned count (the same vector on every rank).
    pub fn from_counts(counts: &[usize], rank: usize) -> Self {
        let mut starts = Vec::with_capacity(counts.len() + 1);
        let mut s = 0;
        starts.push(0);
        for &c in counts {
            s += c;
            starts.push(s);
        }
        Self { starts, rank }
    }
    /// Build collectively from each rank's owned count.
    pub fn gather(comm: &dyn super::Comm, owned: usize) -> Self {
        let mut all = vec![0u64; comm.size()];
        all[comm.rank()] = owned as u64;
        comm.allreduce_sum_u64(&mut all);
        let counts: Vec<usize> = all.iter().map(|&c| c as usize).collect();
        Self::from_counts(&counts, comm.rank())
    }
    pub fn size(&self) -> usize {
        self.starts.len() - 1
    }
    pub fn global_len(&self) -> usize {
        *self.starts.last().unwrap()
    }
    pub fn start(&self) -> usize {
        self.starts[self.rank]
    }
    pub fn end(&self) -> usize {
        self.starts[self.rank + 1]
    }
    pub fn owned_len(&self) -> usize {
        self.end() - self.start()
    }
    pub fn owns(&self, g: usize) -> bool {
        g >= self.start() && g < self.end()
    }
    /// The rank owning global index `g` (binary search over the starts).
    pub fn owner(&self, g: usize) -> usize {
        debug_assert!(g < self.global_len());
        self.starts.partition_point(|&s| s <= g) - 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn owner_of_each_index() {
        let l = Layout::from_counts(&[3, 0, 2], 0);
        let owners: Vec<usize> = (0..5).map(|g| l.owner(g)).collect();
        assert_eq!(owners, vec![0, 0, 0, 2, 2]);
        assert_eq!(l.global_len(), 5);
    }
}
