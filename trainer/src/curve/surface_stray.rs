//! Stray surface: how far a fitted surface gets from the points it was fitted to. Residuals
//! measure only the other way, points to surface, and stay small when a surface bridges an
//! opening of the points or swings out between them.

use std::num::NonZeroUsize;

use kiddo::ImmutableKdTree;

use super::groups::nearest;
use super::spline::BSplineSurface;

/// Which nearest other point sets a point's spacing in [`stray_distance`]: the third, so
/// that a close pair does not make a hole next to it look wide.
pub const SPACING_RANK: usize = 3;

/// Samples of the surface per control point and direction that [`stray_distance`] measures.
pub const STRAY_SAMPLES: usize = 4;

/// The largest distance from a sample of `surface` over the parameters `window` (`[[u₀, u₁],
/// [v₀, v₁]]`; a grid of [`STRAY_SAMPLES`] per control point in each direction, at least 64 ×
/// 64) to the nearest of `points`, in that point's spacing (its distance to its
/// [`SPACING_RANK`]-th nearest other point), so that sparse parts of the points count like
/// dense ones. `None` when the points can't be put in a tree, or fewer than
/// [`SPACING_RANK`] + 1 points lie together.
pub fn stray_distance(
    surface: &BSplineSurface,
    points: &[[f64; 3]],
    window: [[f64; 2]; 2],
) -> Option<f64> {
    let tree = ImmutableKdTree::<f64, 3>::new_from_slice(points).ok()?;
    // Each point's spacing: the distance to its `SPACING_RANK`-th nearest other point.
    let spacing: Vec<f64> = nearest(&tree, points, NonZeroUsize::new(SPACING_RANK + 1)?)
        .iter()
        .map(|list| list.last().map_or(0.0, |f| f.1))
        .collect();
    let count = |c: usize| (STRAY_SAMPLES * c).max(64);
    let (along_u, along_v) = (count(surface.count_u), count(surface.count_v));
    let at = |range: [f64; 2], k: usize, count: usize| {
        range[0] + (range[1] - range[0]) * k as f64 / count as f64
    };
    let [u, v] = window;
    let samples: Vec<[f64; 3]> = (0..=along_v)
        .flat_map(|j| {
            (0..=along_u).map(move |i| surface.point(at(u, i, along_u), at(v, j, along_v)))
        })
        .collect();
    let farthest = nearest(&tree, &samples, NonZeroUsize::MIN)
        .iter()
        .filter_map(|list| list.first())
        .map(|&(i, d)| {
            let s = spacing[i];
            if s > 0.0 { d / s } else { f64::INFINITY }
        })
        .fold(0.0, f64::max);
    farthest.is_finite().then_some(farthest)
}
