//! Separate groups of scattered points: curves that one chain would join by a bridge.
//!
//! Two points belong to one group when one is among the other's [`GROUP_NEIGHBOURS`] nearest
//! points and not more than [`GROUP_REACH`] times the typical reach of those away, and groups
//! are closed under that. Along one curve a point's nearest neighbours
//! reach several spacings to either side, so gaps in the sampling of up to about that many
//! spacings stay within a group; a second curve farther away than that is a group of its
//! own.

use std::num::NonZeroUsize;

use kiddo::{ImmutableKdTree, SquaredEuclidean};

/// Nearest points each point is joined to…
pub const GROUP_NEIGHBOURS: usize = 10;
/// … when closer than this many times the median distance to the farthest of them (so that
/// a stray point far from everything is a group of its own).
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
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let neighbours: Vec<Vec<(usize, f64)>> = points
        .iter()
        .map(|p| {
            tree.query(p)
                .nearest_n::<SquaredEuclidean<f64>>(count)
                .execute()
                .iter()
                .map(|f| (f.item as usize, f.distance.sqrt()))
                .collect()
        })
        .collect();
    let mut reach: Vec<f64> = neighbours
        .iter()
        .map(|list| list.last().map_or(0.0, |f| f.1))
        .collect();
    reach.sort_by(f64::total_cmp);
    let longest = GROUP_REACH * reach[n / 2];
    for (i, list) in neighbours.iter().enumerate() {
        for &(j, d) in list {
            if d > longest {
                continue;
            }
            let (a, b) = (root(&mut parent, i), root(&mut parent, j));
            if a != b {
                parent[a.max(b)] = a.min(b);
            }
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
}
