//! Input checks and k nearest neighbours (§4.1 step 1) through `kiddo`'s immutable k-d tree.
//!
//! Every point set that reaches the embedding passes [`check_points`]: finite coordinates,
//! enough points, no two points closer than [`DUPLICATE_TOLERANCE`] times the bounding-box
//! diagonal (a duplicate makes the local Gram matrix singular and its weights arbitrary), and
//! not all on one line (the PCA spread across the main axis must be at least
//! [`LINE_TOLERANCE`] of the spread along it).

use std::num::NonZeroUsize;

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::{Matrix3, SymmetricEigen, Vector3};

use crate::error::{Error, Result};

/// Two points closer than this fraction of the bounding-box diagonal are duplicates.
pub const DUPLICATE_TOLERANCE: f64 = 1e-9;
/// Points whose second principal standard deviation is below this fraction of the first lie
/// on a line.
pub const LINE_TOLERANCE: f64 = 1e-6;

/// The bounding-box diagonal of finite `points`, after checking they are finite, at least
/// `min_count`, and not on one line.
///
/// # Errors
/// [`Error::InvalidInput`] naming the problem.
pub fn check_points(points: &[[f64; 3]], min_count: usize) -> Result<f64> {
    if points.len() < min_count {
        return Err(Error::invalid(format!(
            "{} points are too few: at least {min_count} are needed",
            points.len()
        )));
    }
    if let Some((i, p)) = points
        .iter()
        .enumerate()
        .find(|(_, p)| p.iter().any(|c| !c.is_finite()))
    {
        return Err(Error::invalid(format!(
            "point {i} has a non-finite coordinate {p:?}"
        )));
    }
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    let mut mean = Vector3::zeros();
    for p in points {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
        mean += Vector3::from(*p);
    }
    let diagonal = (0..3).map(|a| (hi[a] - lo[a]).powi(2)).sum::<f64>().sqrt();
    if diagonal <= 0.0 {
        return Err(Error::invalid("all points coincide"));
    }
    mean /= points.len() as f64;
    let mut covariance = Matrix3::zeros();
    for p in points {
        let d = Vector3::from(*p) - mean;
        covariance += d * d.transpose();
    }
    let mut spread: Vec<f64> = SymmetricEigen::new(covariance)
        .eigenvalues
        .iter()
        .map(|v| v.max(0.0).sqrt())
        .collect();
    spread.sort_by(|a, b| b.total_cmp(a));
    if spread[1] < LINE_TOLERANCE * spread[0] {
        return Err(Error::invalid(format!(
            "the points lie on a line (spread across it {:.3e} of the spread along it): a \
             surface needs two directions",
            spread[1] / spread[0]
        )));
    }
    Ok(diagonal)
}

/// The `k` nearest other points of every point, nearest first.
///
/// # Errors
/// [`Error::InvalidInput`] when there are at most `k` points, `k` is below 3, or two points
/// coincide (within [`DUPLICATE_TOLERANCE`] of the bounding-box diagonal `diagonal`).
pub fn nearest_neighbors(points: &[[f64; 3]], k: usize, diagonal: f64) -> Result<Vec<Vec<usize>>> {
    if k < 3 {
        return Err(Error::invalid(format!(
            "k = {k} neighbours cannot reconstruct a surface point: use at least 3"
        )));
    }
    if points.len() <= k {
        return Err(Error::invalid(format!(
            "{} points are too few for k = {k} neighbours: need at least {}",
            points.len(),
            k + 1
        )));
    }
    let tree: ImmutableKdTree<f64, 3> = ImmutableKdTree::new_from_slice(points)
        .map_err(|e| Error::invalid(format!("k-d tree construction failed: {e}")))?;
    let count = NonZeroUsize::new(k + 1).ok_or_else(|| Error::invalid("k overflows"))?;
    let tolerance = (DUPLICATE_TOLERANCE * diagonal).powi(2);
    let mut all = Vec::with_capacity(points.len());
    for (i, p) in points.iter().enumerate() {
        let found = tree
            .query(p)
            .nearest_n::<SquaredEuclidean<f64>>(count)
            .execute();
        let mut list = Vec::with_capacity(k);
        for item in found {
            let j = item.item as usize;
            if j == i {
                continue;
            }
            if item.distance <= tolerance {
                return Err(Error::invalid(format!(
                    "points {} and {} coincide ({:?}): remove duplicate points",
                    i.min(j),
                    i.max(j),
                    p
                )));
            }
            if list.len() < k {
                list.push(j);
            }
        }
        all.push(list);
    }
    Ok(all)
}
