//! Stray surface: sign changes of Φ between neighbouring grid points that are both far from
//! the true surface. A model that is right near its data but wrong away from it shows here,
//! where every measure taken on the true surface alone looks excellent.

use rayon::prelude::*;
use serde::Serialize;

use super::truth::Truth;
use crate::render::Aabb;

/// Grid points per axis of the stray-surface test.
pub const STRAY_RESOLUTION: usize = 48;
/// The grid covers the reference's bounding box grown by this fraction of its size per side.
pub const STRAY_GROWTH: f64 = 0.1;
/// A grid point is far from the surface beyond this fraction of the bounding diagonal.
pub const FAR_FRACTION: f64 = 0.05;

/// What the stray-surface test found.
#[derive(Copy, Clone, Debug, PartialEq, Serialize)]
pub struct StrayReport {
    /// Grid points per axis.
    pub resolution: usize,
    /// Grid points farther than [`FAR_FRACTION`] of the diagonal from the surface.
    pub far_points: usize,
    /// Pairs of neighbouring far grid points where Φ changes sign: each is a piece of
    /// surface where there is none. 0 for a clean model.
    pub sign_changes: usize,
}

impl StrayReport {
    /// Whether no stray surface was found.
    pub fn is_clean(&self) -> bool {
        self.sign_changes == 0
    }
}

/// Φ at a batch of points, written into the second slice (same length).
pub type BatchField<'a> = dyn Fn(&[[f64; 3]], &mut [f64]) + Sync + 'a;

/// The grown bounding box the test (and the two-sided mesh) covers.
pub fn grown_bounds(truth: &Truth, growth: f64) -> Aabb {
    let b = truth.bounds();
    let pad = [0, 1, 2].map(|k| growth * (b.hi[k] - b.lo[k]));
    Aabb {
        lo: [0, 1, 2].map(|k| b.lo[k] - pad[k]),
        hi: [0, 1, 2].map(|k| b.hi[k] + pad[k]),
    }
}

/// Runs the test on a `resolution`³ grid over the truth's bounding box grown by
/// [`STRAY_GROWTH`] per side. `values` evaluates Φ at a batch of points.
pub fn stray_surface(truth: &Truth, resolution: usize, values: &BatchField<'_>) -> StrayReport {
    let n = resolution.max(2);
    let bounds = grown_bounds(truth, STRAY_GROWTH);
    let step = [0, 1, 2].map(|k| (bounds.hi[k] - bounds.lo[k]) / (n - 1) as f64);
    let far = FAR_FRACTION * truth.diagonal();
    // One z slice per task: the points, whether each is far, and Φ's sign.
    let slices: Vec<(Vec<bool>, Vec<bool>)> = (0..n)
        .into_par_iter()
        .map(|z| {
            let points: Vec<[f64; 3]> = (0..n * n)
                .map(|i| {
                    let (x, y) = (i % n, i / n);
                    [
                        bounds.lo[0] + step[0] * x as f64,
                        bounds.lo[1] + step[1] * y as f64,
                        bounds.lo[2] + step[2] * z as f64,
                    ]
                })
                .collect();
            let mut phi = vec![0.0; points.len()];
            values(&points, &mut phi);
            let is_far = points.iter().map(|&p| truth.distance(p) > far).collect();
            (is_far, phi.iter().map(|&v| v > 0.0).collect())
        })
        .collect();
    let mut far_points = 0;
    let mut sign_changes = 0;
    let index = |x: usize, y: usize| x + n * y;
    for z in 0..n {
        let (far_z, inside_z) = &slices[z];
        far_points += far_z.iter().filter(|&&f| f).count();
        for y in 0..n {
            for x in 0..n {
                let i = index(x, y);
                if !far_z[i] {
                    continue;
                }
                let mut neighbours = Vec::with_capacity(3);
                if x + 1 < n {
                    neighbours.push((far_z[i + 1], inside_z[i + 1]));
                }
                if y + 1 < n {
                    neighbours.push((far_z[index(x, y + 1)], inside_z[index(x, y + 1)]));
                }
                if z + 1 < n {
                    let (far_up, inside_up) = &slices[z + 1];
                    neighbours.push((far_up[i], inside_up[i]));
                }
                sign_changes += neighbours
                    .iter()
                    .filter(|(f, inside)| *f && *inside != inside_z[i])
                    .count();
            }
        }
    }
    StrayReport {
        resolution: n,
        far_points,
        sign_changes,
    }
}
