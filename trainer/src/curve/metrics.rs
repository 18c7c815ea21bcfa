//! Scores of a reconstruction against the truth: order adjacency and Hausdorff distance.

use crate::error::{Error, Result};

use crate::geometry::vector::distance_to_segment;

/// The fraction of consecutive pairs of a recovered `order` that are neighbours on the true
/// curve.
///
/// Precisely: rank the points by `true_parameters` (ties by index); the pair (a, b) is
/// adjacent when their ranks differ by exactly 1 or, for a closed curve, are 0 and n − 1.
/// The pairs are (`order[k]`, `order[k+1]`) for k < n − 1, plus (`order[n−1]`, `order[0]`) when
/// closed: n − 1 pairs open, n closed. Direction does not matter.
///
/// # Errors
/// [`Error::InvalidInput`] when `order` is not a permutation of the parameters' indices or
/// there are fewer than 2 points.
pub fn adjacency_fraction(order: &[usize], true_parameters: &[f64], closed: bool) -> Result<f64> {
    let n = true_parameters.len();
    if n < 2 || order.len() != n {
        return Err(Error::invalid(format!(
            "adjacency needs an order of all {n} points (≥ 2), got {} indices",
            order.len()
        )));
    }
    let mut by_parameter: Vec<usize> = (0..n).collect();
    by_parameter.sort_by(|&a, &b| {
        true_parameters[a]
            .total_cmp(&true_parameters[b])
            .then(a.cmp(&b))
    });
    let mut rank = vec![usize::MAX; n];
    for (r, &i) in by_parameter.iter().enumerate() {
        rank[i] = r;
    }
    let mut seen = vec![false; n];
    for &i in order {
        if i >= n || std::mem::replace(&mut seen[i], true) {
            return Err(Error::invalid(format!(
                "the order is not a permutation of 0..{n} (index {i})"
            )));
        }
    }
    let pairs = if closed { n } else { n - 1 };
    let adjacent = (0..pairs)
        .filter(|&k| {
            let (a, b) = (rank[order[k]], rank[order[(k + 1) % n]]);
            let gap = a.abs_diff(b);
            gap == 1 || (closed && gap == n - 1)
        })
        .count();
    Ok(adjacent as f64 / pairs as f64)
}

/// max over the vertices of `a` of the distance to the polyline `b`. O(|a| · |b|).
pub fn directed_distance(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .map(|&p| distance_to_polyline(p, b))
        .fold(0.0, f64::max)
}

/// Distance from `p` to the polyline `line` (its segments; its only vertex if it has one;
/// +∞ if empty).
pub fn distance_to_polyline(p: [f64; 3], line: &[[f64; 3]]) -> f64 {
    match line {
        [] => f64::INFINITY,
        [only] => crate::geometry::vector::distance(p, *only),
        _ => line
            .windows(2)
            .map(|s| distance_to_segment(p, s[0], s[1]))
            .fold(f64::INFINITY, f64::min),
    }
}

/// The symmetric Hausdorff distance between two polylines, measured from each one's vertices
/// to the other's segments: exact for the vertex-to-polyline part, and within the chord
/// length of dense polylines of the true distance between the curves. O(|a| · |b|).
pub fn hausdorff_distance(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    directed_distance(a, b).max(directed_distance(b, a))
}
