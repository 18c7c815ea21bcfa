//! Automatic decomposition of a point set into K features (Carcenac §8's future work): compact,
//! roughly equal groups of neighbouring points.
//!
//! Recursive principal-axis bisection gives exactly balanced, spatially coherent groups; a few
//! rounds of capacity-constrained k-means then make them compact (each point goes to its
//! nearest centroid unless that group is full; capacity is 110 % of the mean size).

use nalgebra::Vector3;

use super::tree::principal_axis;
use crate::error::{Error, Result};

/// Refinement rounds of capacity-constrained k-means.
const REFINE_ROUNDS: usize = 8;
/// Largest group size as a multiple of the mean.
const CAPACITY: f64 = 1.1;

/// Splits `positions` into `k` features and returns each point's feature index.
///
/// # Errors
/// [`Error::InvalidInput`] when `k` is 0 or there are fewer than `min_points · k` points.
pub fn decompose(positions: &[[f64; 3]], k: usize, min_points: usize) -> Result<Vec<u32>> {
    if k == 0 {
        return Err(Error::invalid("the number of features must be at least 1"));
    }
    if positions.len() < k * min_points {
        return Err(Error::invalid(format!(
            "{} points cannot make {k} features of at least {min_points} points each",
            positions.len()
        )));
    }
    let mut labels = vec![0_u32; positions.len()];
    let indices: Vec<usize> = (0..positions.len()).collect();
    bisect(positions, indices, k, 0, &mut labels);
    refine(positions, k, &mut labels);
    Ok(labels)
}

fn bisect(
    positions: &[[f64; 3]],
    mut indices: Vec<usize>,
    k: usize,
    first_label: u32,
    labels: &mut [u32],
) {
    if k == 1 {
        for i in indices {
            labels[i] = first_label;
        }
        return;
    }
    let axis = principal_axis(indices.iter().map(|&i| positions[i]));
    let key = |i: usize| axis.dot(&Vector3::from(positions[i]));
    indices.sort_by(|&a, &b| key(a).total_cmp(&key(b)).then(a.cmp(&b)));
    let k_left = k / 2;
    let cut = indices.len() * k_left / k;
    let right = indices.split_off(cut);
    bisect(positions, indices, k_left, first_label, labels);
    bisect(
        positions,
        right,
        k - k_left,
        first_label + k_left as u32,
        labels,
    );
}

fn refine(positions: &[[f64; 3]], k: usize, labels: &mut [u32]) {
    let n = positions.len();
    let capacity = ((n as f64 / k as f64) * CAPACITY).ceil() as usize;
    for _ in 0..REFINE_ROUNDS {
        let mut sums = vec![Vector3::zeros(); k];
        let mut counts = vec![0_usize; k];
        for (p, &l) in positions.iter().zip(labels.iter()) {
            sums[l as usize] += Vector3::from(*p);
            counts[l as usize] += 1;
        }
        let centroids: Vec<Vector3<f64>> = sums
            .iter()
            .zip(&counts)
            .map(|(s, &c)| s / c.max(1) as f64)
            .collect();
        // Every (point, group) pair by distance; greedy assignment within capacity.
        let mut pairs: Vec<(f64, usize, usize)> = Vec::with_capacity(n * k);
        for (i, p) in positions.iter().enumerate() {
            let p = Vector3::from(*p);
            for (g, c) in centroids.iter().enumerate() {
                pairs.push(((p - c).norm_squared(), i, g));
            }
        }
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
        let mut assigned = vec![false; n];
        let mut sizes = vec![0_usize; k];
        let mut next = labels.to_vec();
        for (_, i, g) in pairs {
            if !assigned[i] && sizes[g] < capacity {
                assigned[i] = true;
                sizes[g] += 1;
                next[i] = g as u32;
            }
        }
        if next == labels {
            break;
        }
        labels.copy_from_slice(&next);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn groups_are_balanced_and_cover_every_label() {
        let points: Vec<[f64; 3]> = (0..1000)
            .map(|i| {
                let t = f64::from(i) * 0.0137;
                [
                    t.cos() * (1.0 + 0.3 * (3.0 * t).sin()),
                    t.sin(),
                    0.2 * (5.0 * t).cos(),
                ]
            })
            .collect();
        for k in [1, 2, 3, 5, 7, 17] {
            let labels = decompose(&points, k, 4).unwrap();
            let mut sizes = vec![0; k];
            for &l in &labels {
                sizes[l as usize] += 1;
            }
            let (min, max) = (*sizes.iter().min().unwrap(), *sizes.iter().max().unwrap());
            assert!(min > 0, "k = {k}: {sizes:?}");
            assert!(
                max as f64 <= 1.1 * 1000.0 / k as f64 + 1.0,
                "k = {k}: {sizes:?}"
            );
        }
    }

    #[test]
    fn separated_clusters_are_recovered() {
        let centers = [
            [0.0, 0.0, 0.0],
            [10.0, 0.0, 0.0],
            [0.0, 10.0, 0.0],
            [0.0, 0.0, 10.0],
        ];
        let mut points = Vec::new();
        for c in centers {
            for i in 0..50 {
                let a = f64::from(i) * 0.7;
                points.push([c[0] + a.cos(), c[1] + a.sin(), c[2] + (a * 0.3).sin()]);
            }
        }
        let labels = decompose(&points, 4, 4).unwrap();
        for cluster in labels.chunks(50) {
            assert!(cluster.iter().all(|&l| l == cluster[0]), "{cluster:?}");
        }
    }

    #[test]
    fn too_few_points_is_an_error() {
        let err = decompose(&[[0.0; 3]; 10], 3, 4).unwrap_err().to_string();
        assert!(
            err.contains("10 points") && err.contains("3 features"),
            "{err}"
        );
        assert!(decompose(&[[0.0; 3]; 10], 0, 4).is_err());
    }
}
