//! The grid the guards are placed and checked on.

use super::*;

/// The checked grid: `counts` points per axis from `lo`, `spacing` apart along each axis.
pub(super) struct Grid {
    pub(super) lo: [f64; 3],
    /// The longest side over [`GUARD_RESOLUTION`]: the largest spacing.
    pub(super) step: f64,
    pub(super) spacing: [f64; 3],
    pub(super) counts: [usize; 3],
}

impl Grid {
    /// [`GUARD_RESOLUTION`] cells along the longest side, and at least
    /// [`GUARD_MIN_CELLS`] along the others: a stray piece thin along the short side of a flat
    /// shape is caught as surely as the 48³ stray-surface test finds it.
    pub(super) fn over(domain: &Aabb) -> Option<Grid> {
        let extent = [0, 1, 2].map(|k| domain.hi[k] - domain.lo[k]);
        let step = extent.iter().copied().fold(0.0, f64::max) / GUARD_RESOLUTION as f64;
        if !(step > 0.0 && step.is_finite()) {
            return None;
        }
        let spacing = extent.map(|e| step.min(e / GUARD_MIN_CELLS as f64).max(step * 1e-3));
        Some(Grid {
            lo: domain.lo,
            step,
            spacing,
            counts: [0, 1, 2].map(|k| (extent[k] / spacing[k]).ceil() as usize + 1),
        })
    }

    pub(super) fn len(&self) -> usize {
        self.counts.iter().product()
    }

    /// The index of point `i` along each axis.
    pub(super) fn index(&self, i: usize) -> [usize; 3] {
        let [nx, ny, _] = self.counts;
        [i % nx, (i / nx) % ny, i / (nx * ny)]
    }

    /// Whether point `i` is on the coarse grid: every second point along each axis, and the
    /// last.
    pub(super) fn is_coarse(&self, i: usize) -> bool {
        let index = self.index(i);
        (0..3).all(|k| index[k].is_multiple_of(2) || index[k] + 1 == self.counts[k])
    }

    /// The corners of the coarse cell that holds point `i` (itself when it is coarse).
    pub(super) fn coarse_corners(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        let index = self.index(i);
        let [nx, ny, _] = self.counts;
        let span = [0, 1, 2].map(|k| {
            if index[k].is_multiple_of(2) || index[k] + 1 == self.counts[k] {
                (index[k], index[k])
            } else {
                (index[k] - 1, index[k] + 1)
            }
        });
        (0..8_usize).filter_map(move |corner| {
            let bit = |k: usize| corner >> k & 1 == 1;
            // Each distinct corner once.
            if (0..3).any(|k| bit(k) && span[k].0 == span[k].1) {
                return None;
            }
            let c = [0, 1, 2].map(|k| if bit(k) { span[k].1 } else { span[k].0 });
            Some(c[0] + nx * (c[1] + ny * c[2]))
        })
    }

    /// The grid points next to point `i` along each axis.
    pub(super) fn neighbours(&self, i: usize) -> impl Iterator<Item = usize> {
        let index = self.index(i);
        let counts = self.counts;
        let stride = [1, counts[0], counts[0] * counts[1]];
        (0..3).flat_map(move |k| {
            let below = (index[k] > 0).then(|| i - stride[k]);
            let above = (index[k] + 1 < counts[k]).then(|| i + stride[k]);
            below.into_iter().chain(above)
        })
    }

    /// The corners of the grid cell that holds `q` (the nearest cell for a point outside the
    /// grid).
    pub(super) fn cell_corners(&self, q: [f64; 3]) -> impl Iterator<Item = usize> + use<> {
        let low = [0, 1, 2].map(|k| {
            let cells = self.counts[k].saturating_sub(1);
            let t = ((q[k] - self.lo[k]) / self.spacing[k]).floor();
            // NaN and negative go to 0; `as` saturates.
            (t.max(0.0) as usize).min(cells.saturating_sub(1))
        });
        let [nx, ny, _] = self.counts;
        let counts = self.counts;
        (0..8_usize).filter_map(move |corner| {
            let c = [0, 1, 2].map(|k| low[k] + (corner >> k & 1));
            (0..3)
                .all(|k| c[k] < counts[k])
                .then(|| c[0] + nx * (c[1] + ny * c[2]))
        })
    }

    pub(super) fn point(&self, i: usize) -> [f64; 3] {
        let index = self.index(i);
        [0, 1, 2].map(|k| self.lo[k] + self.spacing[k] * index[k] as f64)
    }
}

/// Grid points per side of the blocks [`Grid::disk_distances_below`] rules out at once.
const BLOCK: usize = 4;

impl Grid {
    /// [`Oracle::disk_distance_below`]`(point, bound)` at every grid point, NaN where it is
    /// `None`: the same values, but a block of [`BLOCK`]³ points that one nearest-point query
    /// at its centre clears ([`Oracle::ball_clears`] over the block's half diagonal) is NaN
    /// without a query per point. Most of the grid is far from the data, so most blocks go
    /// in one query.
    pub(super) fn disk_distances_below(&self, oracle: &Oracle, bound: f64) -> Vec<f64> {
        let [nx, ny, nz] = self.counts;
        let mut distances = vec![f64::NAN; self.len()];
        // Slabs of BLOCK layers along z are contiguous in the grid's order.
        distances
            .par_chunks_mut(nx * ny * BLOCK)
            .enumerate()
            .for_each(|(slab, out)| {
                let z0 = slab * BLOCK;
                let z1 = (z0 + BLOCK).min(nz);
                for y0 in (0..ny).step_by(BLOCK) {
                    let y1 = (y0 + BLOCK).min(ny);
                    for x0 in (0..nx).step_by(BLOCK) {
                        let x1 = (x0 + BLOCK).min(nx);
                        let (lo, hi) = ([x0, y0, z0], [x1 - 1, y1 - 1, z1 - 1]);
                        let corner = |index: [usize; 3]| {
                            [0, 1, 2].map(|k| self.lo[k] + self.spacing[k] * index[k] as f64)
                        };
                        let (a, b) = (corner(lo), corner(hi));
                        let centre = [0, 1, 2].map(|k| 0.5 * (a[k] + b[k]));
                        if oracle.ball_clears(centre, 0.5 * distance(a, b), bound) {
                            continue;
                        }
                        for z in z0..z1 {
                            for y in y0..y1 {
                                for x in x0..x1 {
                                    let i = x + nx * (y + ny * z);
                                    out[i - z0 * nx * ny] = oracle
                                        .disk_distance_below(self.point(i), bound)
                                        .unwrap_or(f64::NAN);
                                }
                            }
                        }
                    }
                }
            });
        distances
    }
}
