//! How well an embedding recovers a known parameterization: neighbourhood preservation and
//! distance correlation.

use std::num::NonZeroUsize;

use kiddo::{ImmutableKdTree, SquaredEuclidean};

use crate::error::{Error, Result};

/// Mean fraction of each point's `k` nearest neighbours in `truth` that are also among its `k`
/// nearest neighbours in `embedded` (1 = every neighbourhood kept).
///
/// # Errors
/// [`Error::InvalidInput`] when the lengths differ or there are at most `k` points.
pub fn neighborhood_preservation(
    truth: &[[f64; 2]],
    embedded: &[[f64; 2]],
    k: usize,
) -> Result<f64> {
    if truth.len() != embedded.len() || truth.len() <= k || k == 0 {
        return Err(Error::invalid(
            "neighbourhood preservation needs two equally long sets of more than k points",
        ));
    }
    let a = knn_2d(truth, k)?;
    let b = knn_2d(embedded, k)?;
    let kept: usize = a
        .iter()
        .zip(&b)
        .map(|(x, y)| x.iter().filter(|i| y.contains(i)).count())
        .sum();
    Ok(kept as f64 / (k * truth.len()) as f64)
}

fn knn_2d(points: &[[f64; 2]], k: usize) -> Result<Vec<Vec<u32>>> {
    let tree: ImmutableKdTree<f64, 2> = ImmutableKdTree::new_from_slice(points)
        .map_err(|e| Error::invalid(format!("k-d tree construction failed: {e}")))?;
    let count = NonZeroUsize::new(k + 1).ok_or_else(|| Error::invalid("k overflows"))?;
    Ok(points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            tree.query(p)
                .nearest_n::<SquaredEuclidean<f64>>(count)
                .execute()
                .into_iter()
                .map(|r| r.item)
                .filter(|&j| j as usize != i)
                .take(k)
                .collect()
        })
        .collect())
}

/// Pearson correlation between pairwise distances in `truth` and in `embedded`, over the
/// pairs (i, i + step) for a few strides (all pairs for small sets).
///
/// # Errors
/// [`Error::InvalidInput`] when the lengths differ or there are fewer than 3 points.
pub fn distance_correlation(truth: &[[f64; 2]], embedded: &[[f64; 2]]) -> Result<f64> {
    let n = truth.len();
    if n != embedded.len() || n < 3 {
        return Err(Error::invalid(
            "distance correlation needs two equally long sets of at least 3 points",
        ));
    }
    let dist = |p: &[f64; 2], q: &[f64; 2]| ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt();
    let mut xs = Vec::new();
    let mut ys = Vec::new();
    let strides: Vec<usize> = if n <= 400 {
        (1..n).collect()
    } else {
        (0..64).map(|s| 1 + s * (n - 1) / 64).collect()
    };
    for &s in &strides {
        for i in 0..n {
            let j = (i + s) % n;
            if j > i || n > 400 {
                xs.push(dist(&truth[i], &truth[j]));
                ys.push(dist(&embedded[i], &embedded[j]));
            }
        }
    }
    Ok(pearson(&xs, &ys))
}

/// Pearson correlation of two equally long samples (0 when either is constant).
pub fn pearson(xs: &[f64], ys: &[f64]) -> f64 {
    let n = xs.len().min(ys.len()) as f64;
    if n < 2.0 {
        return 0.0;
    }
    let mx = xs.iter().sum::<f64>() / n;
    let my = ys.iter().sum::<f64>() / n;
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (x, y) in xs.iter().zip(ys) {
        sxy += (x - mx) * (y - my);
        sxx += (x - mx).powi(2);
        syy += (y - my).powi(2);
    }
    if sxx <= 0.0 || syy <= 0.0 {
        return 0.0;
    }
    sxy / (sxx * syy).sqrt()
}

/// The affine image of `embedded` closest to `truth` in least squares, and the fraction of
/// `truth`'s variance it explains (R², 1 = the embedding is an affine copy of the truth).
///
/// LLE fixes u and v only up to rotation, reflection and per-axis scale (unit covariance,
/// Eq. 4), so a recovered parameterization is compared after this alignment.
///
/// # Errors
/// [`Error::InvalidInput`] when the lengths differ, there are fewer than 3 points, or the
/// embedding is degenerate.
pub fn align_affine(truth: &[[f64; 2]], embedded: &[[f64; 2]]) -> Result<(Vec<[f64; 2]>, f64)> {
    use nalgebra::{Matrix3, Vector3};
    if truth.len() != embedded.len() || truth.len() < 3 {
        return Err(Error::invalid(
            "alignment needs two equally long sets of at least 3 points",
        ));
    }
    let mut ata = Matrix3::zeros();
    let mut atb = [Vector3::zeros(); 2];
    for (t, e) in truth.iter().zip(embedded) {
        let a = Vector3::new(e[0], e[1], 1.0);
        ata += a * a.transpose();
        for c in 0..2 {
            atb[c] += a * t[c];
        }
    }
    let inverse = ata
        .try_inverse()
        .ok_or_else(|| Error::invalid("the embedding is degenerate (all on a line)"))?;
    let coef = [inverse * atb[0], inverse * atb[1]];
    let aligned: Vec<[f64; 2]> = embedded
        .iter()
        .map(|e| std::array::from_fn(|c| coef[c][0] * e[0] + coef[c][1] * e[1] + coef[c][2]))
        .collect();
    let n = truth.len() as f64;
    let mean = [0, 1].map(|c| truth.iter().map(|t| t[c]).sum::<f64>() / n);
    let total: f64 = truth
        .iter()
        .map(|t| (t[0] - mean[0]).powi(2) + (t[1] - mean[1]).powi(2))
        .sum();
    let residual: f64 = truth
        .iter()
        .zip(&aligned)
        .map(|(t, a)| (t[0] - a[0]).powi(2) + (t[1] - a[1]).powi(2))
        .sum();
    Ok((aligned, 1.0 - residual / total.max(f64::MIN_POSITIVE)))
}
