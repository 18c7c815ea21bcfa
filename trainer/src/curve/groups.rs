//! Separate groups of scattered points: curves that one chain would join by a bridge.
//!
//! Two points belong to one group when they are not more than [`GROUP_REACH`] times the
//! typical reach apart (the median distance from a point to the farthest of its
//! [`GROUP_NEIGHBOURS`] nearest), or when one is among the other's nearest and within
//! [`GROUP_REACH`] times the smaller of their own reaches (a sparsely sampled stretch); groups
//! are closed under that. A stray point far from the
//! others reaches far, but the points it would join do not. Along one curve a point's nearest neighbours
//! reach several spacings to either side, so gaps in the sampling of up to about that many
//! spacings stay within a group; a second curve farther away than that is a group of its
//! own.

use std::num::NonZeroUsize;

use kiddo::{ImmutableKdTree, SquaredEuclidean};

/// Nearest points each point is joined to…
pub const GROUP_NEIGHBOURS: usize = 10;
/// … when closer than this many times the median distance to the farthest of them, or the
/// smaller of the two points' own distances to their farthest (so that a stray point far from
/// everything is a group of its own).
pub const GROUP_REACH: f64 = 3.0;

/// The groups of `points` (indices), largest first; one group when there are too few points
/// to tell.
pub fn point_groups(points: &[[f64; 3]]) -> Vec<Vec<usize>> {
    let n = points.len();
    let everything = || vec![(0..n).collect::<Vec<usize>>()];
    if n <= GROUP_NEIGHBOURS + 1 {
        return everything();
    }
    let Ok(tree) = ImmutableKdTree::<f64, 3>::new_from_slice(points) else {
        return everything();
    };
    let count = NonZeroUsize::new(GROUP_NEIGHBOURS + 1).unwrap_or(NonZeroUsize::MIN);
    let mut parent: Vec<usize> = (0..n).collect();
    let neighbours = nearest(&tree, points, count);
    // A point's reach: the distance to the farthest of its nearest points.
    let reach: Vec<f64> = neighbours
        .iter()
        .map(|list| list.last().map_or(0.0, |f| f.1))
        .collect();
    let mut sorted = reach.clone();
    sorted.sort_by(f64::total_cmp);
    let typical = sorted[n / 2];
    for (i, list) in neighbours.iter().enumerate() {
        for &(j, d) in list {
            // Where both points are sparser than typical, their own reach counts: a stretch
            // sampled ten times more sparsely than the rest is still one curve with it.
            let longest = GROUP_REACH * typical.max(reach[i].min(reach[j]));
            if d > longest {
                continue;
            }
            join(&mut parent, i, j);
        }
        // Within the typical reach of each other: one group, also where a gap in the
        // sampling leaves each side's nearest points on that side.
        let radius = GROUP_REACH * typical;
        for f in tree
            .query(&points[i])
            .within::<SquaredEuclidean<f64>>(radius * radius)
            .unsorted()
            .execute()
            .iter()
        {
            join(&mut parent, i, f.item as usize);
        }
    }
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut slot = vec![usize::MAX; n];
    for i in 0..n {
        let r = root(&mut parent, i);
        if slot[r] == usize::MAX {
            slot[r] = groups.len();
            groups.push(Vec::new());
        }
        groups[slot[r]].push(i);
    }
    groups.sort_by(|a, b| b.len().cmp(&a.len()).then(a[0].cmp(&b[0])));
    groups
}

/// For each of `points`, its `count` nearest in `tree` (itself first) with their distances.
pub(crate) fn nearest(
    tree: &ImmutableKdTree<f64, 3>,
    points: &[[f64; 3]],
    count: NonZeroUsize,
) -> Vec<Vec<(usize, f64)>> {
    points
        .iter()
        .map(|p| {
            tree.query(p)
                .nearest_n::<SquaredEuclidean<f64>>(count)
                .execute()
                .iter()
                .map(|f| (f.item as usize, f.distance.sqrt()))
                .collect()
        })
        .collect()
}

/// The representative of `i`'s set in the union–find forest `parent` (paths halved).
pub(crate) fn root(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

/// Merges the sets of `i` and `j` in `parent`, the lower representative kept.
pub(crate) fn join(parent: &mut [usize], i: usize, j: usize) {
    let (a, b) = (root(parent, i), root(parent, j));
    if a != b {
        parent[a.max(b)] = a.min(b);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn circle(centre: f64, n: usize, offset: f64) -> Vec<[f64; 3]> {
        (0..n)
            .map(|i| {
                // Uneven spacing: gaps from 0.5 to 1.5 times the mean.
                let a = std::f64::consts::TAU * (i as f64 + offset * (i % 3) as f64) / n as f64;
                [centre + a.cos(), a.sin(), 0.0]
            })
            .collect()
    }

    #[test]
    fn two_circles_apart_are_two_groups_and_one_circle_is_one() {
        let mut points = circle(0.0, 200, 0.5);
        assert_eq!(point_groups(&points).len(), 1);
        points.extend(circle(3.0, 120, 0.3));
        let groups = point_groups(&points);
        assert_eq!(
            groups.iter().map(Vec::len).collect::<Vec<_>>(),
            vec![200, 120]
        );
        assert!(groups[1].iter().all(|&i| i >= 200));
        // A stray point far away is a group of one.
        points.push([10.0, 10.0, 0.0]);
        assert_eq!(point_groups(&points).len(), 3);
        assert_eq!(point_groups(&points[..5]).len(), 1);
    }

    #[test]
    fn a_sparse_stretch_and_a_gap_stay_in_their_curve() {
        // 200 points on one half of a circle, 20 on the other: one curve.
        let half = |from: f64, n: usize| {
            (0..n).map(move |i| {
                let a = std::f64::consts::PI * (from + i as f64 / n as f64);
                [a.cos(), a.sin(), 0.0]
            })
        };
        let step: Vec<[f64; 3]> = half(0.0, 200).chain(half(1.0, 20)).collect();
        assert_eq!(point_groups(&step).len(), 1);
        // 300 points with a gap of 12 spacings: the nearest ten of the points on either side
        // lie on their own side, but the gap is within the typical reach.
        let gapped: Vec<[f64; 3]> = (0..312)
            .filter(|i| !(100..112).contains(i))
            .map(|i| {
                let a = std::f64::consts::TAU * i as f64 / 312.0;
                [a.cos(), a.sin(), 0.0]
            })
            .collect();
        assert_eq!(point_groups(&gapped).len(), 1);
    }
}
