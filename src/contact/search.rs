//! The initial contact search's spatial index: axis-aligned boxes (reference faces
//! grown by the search distance) binned on a uniform hash grid, so pairing N tracked
//! nodes or faces with M reference faces costs about N + M box tests instead of N·M.

use std::collections::HashMap;

/// An axis-aligned box `(min, max)`.
pub type Bounds = ([f64; 3], [f64; 3]);

/// The smallest box holding the points.
pub fn bounds(x: &[[f64; 3]]) -> Bounds {
    let lo = std::array::from_fn(|c| x.iter().map(|p| p[c]).fold(f64::INFINITY, f64::min));
    let hi = std::array::from_fn(|c| x.iter().map(|p| p[c]).fold(f64::NEG_INFINITY, f64::max));
    (lo, hi)
}

pub struct BoxGrid {
    boxes: Vec<Bounds>,
    h: f64,
    cells: HashMap<[i64; 3], Vec<u32>>,
}

impl BoxGrid {
    /// Bin `boxes`, each grown by `grow` on every side; the cell size is their mean
    /// largest extent, so a box touches a few cells.
    pub fn new(boxes: &[Bounds], grow: f64) -> Self {
        let boxes: Vec<Bounds> = boxes
            .iter()
            .map(|(lo, hi)| (lo.map(|v| v - grow), hi.map(|v| v + grow)))
            .collect();
        let ext: f64 = boxes
            .iter()
            .map(|(lo, hi)| (0..3).map(|c| hi[c] - lo[c]).fold(0.0, f64::max))
            .sum::<f64>()
            / boxes.len().max(1) as f64;
        let h = if ext > 0.0 && ext.is_finite() {
            ext
        } else {
            1.0
        };
        let mut g = Self {
            boxes,
            h,
            cells: HashMap::new(),
        };
        for k in 0..g.boxes.len() {
            let (lo, hi) = g.boxes[k];
            for key in g.keys(lo, hi) {
                g.cells.entry(key).or_default().push(k as u32);
            }
        }
        g
    }

    fn keys(&self, lo: [f64; 3], hi: [f64; 3]) -> Vec<[i64; 3]> {
        let a: [i64; 3] = std::array::from_fn(|c| (lo[c] / self.h).floor() as i64);
        let b: [i64; 3] = std::array::from_fn(|c| (hi[c] / self.h).floor() as i64);
        let mut out = Vec::new();
        for i in a[0]..=b[0] {
            for j in a[1]..=b[1] {
                for k in a[2]..=b[2] {
                    out.push([i, j, k]);
                }
            }
        }
        out
    }

    /// The boxes that overlap `[lo, hi]`, ascending (the order a full scan would see).
    pub fn overlapping(&self, lo: [f64; 3], hi: [f64; 3]) -> Vec<usize> {
        let mut out: Vec<usize> = self
            .keys(lo, hi)
            .iter()
            .filter_map(|key| self.cells.get(key))
            .flatten()
            .map(|&k| k as usize)
            .filter(|&k| {
                let (blo, bhi) = self.boxes[k];
                (0..3).all(|c| blo[c] <= hi[c] && bhi[c] >= lo[c])
            })
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The grid returns exactly the boxes a full scan finds, in ascending order.
    #[test]
    fn finds_what_a_scan_finds() {
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let boxes: Vec<Bounds> = (0..400)
            .map(|_| {
                let lo = [rnd() * 10.0 - 5.0, rnd() * 10.0, rnd() * 2.0];
                let s = 0.1 + rnd();
                (lo, [lo[0] + s, lo[1] + s * rnd(), lo[2] + 0.01])
            })
            .collect();
        let grow = 0.05;
        let g = BoxGrid::new(&boxes, grow);
        for _ in 0..300 {
            let p = [rnd() * 12.0 - 6.0, rnd() * 11.0 - 0.5, rnd() * 2.2 - 0.1];
            let q = [p[0] + rnd() * 0.5, p[1], p[2] + rnd() * 0.1];
            let scan: Vec<usize> = (0..boxes.len())
                .filter(|&k| {
                    let (lo, hi) = boxes[k];
                    (0..3).all(|c| lo[c] - grow <= q[c] && hi[c] + grow >= p[c])
                })
                .collect();
            assert_eq!(g.overlapping(p, q), scan);
        }
    }
}
