//! Which control points each module trains on: its features' points, and beside them the
//! neighbouring features' points that lie within [`OVERLAP`] sample gaps of them.
//!
//! A leaf trained on its own feature alone is accurate up to the seam and extrapolates beyond
//! it, so the node that blends two leaves splices two fields that disagree there: on the
//! 1 500-point bunny without the band, the median normal error at vertices near a seam is
//! 6.5–7.0° against 5.2–5.4° inside the features. Leaves that also learn a band of their
//! neighbours' points agree across the seam, and the node blends two fields that are both right
//! there. The borrowed points weigh less ([`BORROWED_WEIGHT`]) so that they steer the leaf's
//! extrapolation without taking its capacity from its own feature.
//!
//! The band's width is measured in each point's own sample gap (the distance to its eighth
//! nearest neighbour, [`Oracle::gap`]), so it is the same number of sample rows at any density
//! and in any units.

use kiddo::{ImmutableKdTree, SquaredEuclidean};

use super::oracle::Oracle;

/// A point of another feature joins a feature when it lies within this many of its own sample
/// gaps of the feature's nearest point.
pub const OVERLAP: f64 = 1.0;

/// How much a borrowed point's residuals weigh beside the module's own points': enough to
/// pin the field across the seam, little enough to leave the module's capacity to its own
/// feature.
pub const BORROWED_WEIGHT: f64 = 0.3;

/// Each feature's training points: its `members`, then the other features' points within
/// [`OVERLAP`] gaps of them, in index order.
pub fn overlapping(
    members: &[Vec<usize>],
    positions: &[[f64; 3]],
    oracle: &Oracle,
) -> Vec<Vec<usize>> {
    members
        .iter()
        .enumerate()
        .map(|(f, own)| {
            let own_positions: Vec<[f64; 3]> = own.iter().map(|&p| positions[p]).collect();
            let Ok(tree) = ImmutableKdTree::<f64, 3>::new_from_slice(&own_positions) else {
                return own.clone();
            };
            let mut reach = own.clone();
            for (g, others) in members.iter().enumerate() {
                if g == f {
                    continue;
                }
                for &q in others {
                    let nearest = tree
                        .query(&positions[q])
                        .nearest_one::<SquaredEuclidean<f64>>()
                        .execute()
                        .distance
                        .sqrt();
                    if nearest <= OVERLAP * oracle.gap(q) {
                        reach.push(q);
                    }
                }
            }
            reach.sort_unstable();
            reach
        })
        .collect()
}

/// The training points of a module over `features`: their reaches one after the other, each
/// point once (where it first appears). Without a band this is the features' members in
/// feature order.
pub fn module_points(features: &[u32], reach: &[Vec<usize>]) -> Vec<usize> {
    let mut seen = std::collections::HashSet::new();
    features
        .iter()
        .filter_map(|&f| reach.get(f as usize))
        .flatten()
        .copied()
        .filter(|&p| seen.insert(p))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points on a line, 0.1 apart, split in two features at x = 1: each feature borrows the
    /// points of the other within one gap (the eighth neighbour is 0.4–0.8 away), and no more.
    #[test]
    fn a_feature_borrows_a_band_of_its_neighbours_points() {
        let positions: Vec<[f64; 3]> = (0..20)
            .map(|i| [0.1 * i as f64, 0.01 * (i % 3) as f64, 0.0])
            .collect();
        let normals = vec![[0.0, 0.0, 1.0]; positions.len()];
        let oracle = Oracle::new(&positions, &normals).expect("oracle");
        let members = vec![(0..10).collect::<Vec<_>>(), (10..20).collect()];
        let reach = overlapping(&members, &positions, &oracle);
        for (f, own) in members.iter().enumerate() {
            let borrowed: Vec<usize> = reach[f]
                .iter()
                .copied()
                .filter(|p| !own.contains(p))
                .collect();
            assert!(!borrowed.is_empty(), "feature {f} borrows nothing");
            for &q in &borrowed {
                let seam = if f == 0 { 9 } else { 10 };
                let d = (positions[q][0] - positions[seam][0]).abs();
                assert!(
                    d <= oracle.gap(q) + 0.02,
                    "point {q} is {d} beyond the seam"
                );
            }
            assert!(
                reach[f].len() < positions.len(),
                "feature {f} took every point"
            );
        }
        let mut both = module_points(&[0, 1], &reach);
        assert_eq!(
            both[..10],
            (0..10).collect::<Vec<_>>(),
            "feature 0's points first"
        );
        both.sort_unstable();
        assert_eq!(both, (0..20).collect::<Vec<_>>(), "every point once");
    }
}
