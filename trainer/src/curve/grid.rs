//! A uniform grid over a fixed box for exact nearest-neuron queries while neurons move.
//!
//! Kohonen updates move every neuron by a convex combination towards an input point, so a
//! neuron that starts inside the points' bounding box never leaves it: a dense grid over the
//! box never needs resizing. Each cell keeps a doubly linked list of its neurons, so moving
//! a neuron between cells is O(1), and a query visits rings of cells around the query until
//! no unvisited cell can hold a closer neuron — the answer is exact, not approximate.

use crate::geometry::vector::distance_squared;

/// No neuron (end of a cell list).
const NONE: u32 = u32::MAX;

/// Cells per neuron: a few, so a query near the chain visits a few neurons per cell.
const CELLS_PER_NEURON: f64 = 2.0;

/// The grid: cell lists over the box `[origin, origin + dims · cell]`.
#[derive(Clone, Debug)]
pub(crate) struct NeuronGrid {
    origin: [f64; 3],
    inverse_cell: f64,
    cell: f64,
    dims: [usize; 3],
    head: Vec<u32>,
    next: Vec<u32>,
    prev: Vec<u32>,
    cell_of: Vec<u32>,
}

impl NeuronGrid {
    /// A grid over `[lower, upper]` holding `neurons` (which must lie in the box; points
    /// outside are clamped into the border cells, which keeps queries exact but slower).
    pub(crate) fn new(lower: [f64; 3], upper: [f64; 3], neurons: &[[f64; 3]]) -> Self {
        let extent = [0, 1, 2].map(|k| (upper[k] - lower[k]).max(0.0));
        let diagonal = extent
            .iter()
            .map(|e| e * e)
            .sum::<f64>()
            .sqrt()
            .max(f64::MIN_POSITIVE);
        // Only axes with a real extent count towards the cell volume.
        let axes: Vec<f64> = extent
            .iter()
            .copied()
            .filter(|&e| e > 1e-9 * diagonal)
            .collect();
        let cells_wanted = (CELLS_PER_NEURON * neurons.len() as f64).max(1.0);
        let volume: f64 = axes.iter().product();
        let mut cell = if axes.is_empty() {
            diagonal
        } else {
            (volume / cells_wanted).powf(1.0 / axes.len() as f64)
        };
        // Thin boxes: never more cells along one axis than wanted in total.
        cell = cell.max(diagonal / cells_wanted);
        let dims = extent.map(|e| ((e / cell).ceil() as usize).clamp(1, 1 << 20));
        let count = dims[0] * dims[1] * dims[2];
        let mut grid = NeuronGrid {
            origin: lower,
            inverse_cell: 1.0 / cell,
            cell,
            dims,
            head: vec![NONE; count],
            next: vec![NONE; neurons.len()],
            prev: vec![NONE; neurons.len()],
            cell_of: vec![0; neurons.len()],
        };
        for (i, &p) in neurons.iter().enumerate() {
            let c = grid.cell_index(grid.cell_coordinates(p));
            grid.link(i as u32, c);
        }
        grid
    }

    #[inline]
    fn cell_coordinates(&self, p: [f64; 3]) -> [usize; 3] {
        let axis = |k: usize| {
            // Truncation is the floor for the non-negative values kept here; NaN and
            // negatives go to 0 (the cast saturates), large values to the last cell.
            let c = ((p[k] - self.origin[k]) * self.inverse_cell).max(0.0);
            (c as usize).min(self.dims[k] - 1)
        };
        [axis(0), axis(1), axis(2)]
    }

    #[inline]
    fn cell_index(&self, c: [usize; 3]) -> u32 {
        ((c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0]) as u32
    }

    fn link(&mut self, i: u32, cell: u32) {
        let head = self.head[cell as usize];
        self.next[i as usize] = head;
        self.prev[i as usize] = NONE;
        if head != NONE {
            self.prev[head as usize] = i;
        }
        self.head[cell as usize] = i;
        self.cell_of[i as usize] = cell;
    }

    fn unlink(&mut self, i: u32) {
        let (p, n) = (self.prev[i as usize], self.next[i as usize]);
        if p == NONE {
            self.head[self.cell_of[i as usize] as usize] = n;
        } else {
            self.next[p as usize] = n;
        }
        if n != NONE {
            self.prev[n as usize] = p;
        }
    }

    /// Records that neuron `i` now sits at `position`.
    #[inline]
    pub(crate) fn moved(&mut self, i: usize, position: [f64; 3]) {
        let cell = self.cell_index(self.cell_coordinates(position));
        if cell != self.cell_of[i] {
            self.unlink(i as u32);
            self.link(i as u32, cell);
        }
    }

    /// The neuron nearest to `query` and its squared distance; ties go to the lowest index.
    /// `neurons` are the positions the grid was kept up to date with; `skip` is excluded.
    ///
    /// Cost: the cells within the distance of the answer (plus one ring), and their neurons.
    pub(crate) fn nearest(
        &self,
        query: [f64; 3],
        neurons: &[[f64; 3]],
        skip: Option<usize>,
    ) -> Option<(usize, f64)> {
        let centre = self.cell_coordinates(query);
        let mut best: Option<(usize, f64)> = None;
        let max_ring = self.dims.iter().copied().max().unwrap_or(1);
        for ring in 0..=max_ring {
            self.visit_ring(centre, ring, |i| {
                if Some(i) == skip {
                    return;
                }
                let d = distance_squared(query, neurons[i]);
                if best.is_none_or(|(b, bd)| d < bd || (d == bd && i < b)) {
                    best = Some((i, d));
                }
            });
            // Cells in rings beyond `ring` are at least ring · cell away from the query.
            if let Some((_, d)) = best {
                let reach = ring as f64 * self.cell;
                if d < reach * reach {
                    break;
                }
            }
        }
        best
    }

    /// The `k` neurons nearest to `query` (excluding `skip`), nearest first, as
    /// (squared distance, index) in `found`; ties by index. Fewer if there are fewer.
    pub(crate) fn nearest_k(
        &self,
        query: [f64; 3],
        neurons: &[[f64; 3]],
        skip: Option<usize>,
        k: usize,
        found: &mut Vec<(f64, usize)>,
    ) {
        found.clear();
        if k == 0 {
            return;
        }
        let centre = self.cell_coordinates(query);
        let max_ring = self.dims.iter().copied().max().unwrap_or(1);
        for ring in 0..=max_ring {
            self.visit_ring(centre, ring, |i| {
                if Some(i) == skip {
                    return;
                }
                let entry = (distance_squared(query, neurons[i]), i);
                let full = found.len() == k;
                if full && found.last().is_some_and(|&last| entry >= last) {
                    return;
                }
                let at = found.partition_point(|&e| e < entry);
                found.insert(at, entry);
                if found.len() > k {
                    found.pop();
                }
            });
            if found.len() == k
                && let Some(&(d, _)) = found.last()
            {
                let reach = ring as f64 * self.cell;
                if d < reach * reach {
                    break;
                }
            }
        }
    }

    /// Calls `f` for every neuron in the cells at Chebyshev distance exactly `ring` from
    /// `centre`.
    fn visit_ring(&self, centre: [usize; 3], ring: usize, mut f: impl FnMut(usize)) {
        let r = ring as i64;
        let range = |k: usize| {
            let c = centre[k] as i64;
            (c - r).max(0)..=(c + r).min(self.dims[k] as i64 - 1)
        };
        for z in range(2) {
            let on_z = (z - centre[2] as i64).abs() == r;
            for y in range(1) {
                let on_y = on_z || (y - centre[1] as i64).abs() == r;
                let c = centre[0] as i64;
                let mut visit_cell = |x: i64| {
                    let cell = self.cell_index([x as usize, y as usize, z as usize]);
                    let mut i = self.head[cell as usize];
                    while i != NONE {
                        f(i as usize);
                        i = self.next[i as usize];
                    }
                };
                if on_y {
                    range(0).for_each(&mut visit_cell);
                } else {
                    for x in [c - r, c + r] {
                        if x >= 0 && x < self.dims[0] as i64 {
                            visit_cell(x);
                        }
                    }
                }
            }
        }
    }
}
