//! A set of grid points and the distance from anywhere in the grid to its nearest member.

use super::*;

/// Members of a set of grid points, and a k-d tree over the members that a nearest-member
/// query can end on.
///
/// Only members with a grid neighbour outside the set go into the tree. From a query point
/// `q` inside the grid, a member with every neighbour in the set is never the only nearest
/// one unless `q` lies in a grid cell it is a corner of: along an axis where `q` is more than
/// half a spacing away, the neighbour one step toward `q` is nearer and is a member too. So
/// the nearest distance is the smaller of the tree's answer and the members among the eight
/// corners of `q`'s cell, the same value a tree over every member gives, bit for bit. The
/// large sets (everything far outside a shape) are mostly interior: the tree holds a thin
/// shell of them.
pub(super) struct GridSet {
    member: Vec<bool>,
    tree: Option<ImmutableKdTree<f64, 3>>,
}

impl GridSet {
    /// The grid points `i` with `keep(i)`.
    pub(super) fn new(grid: &Grid, keep: impl Fn(usize) -> bool + Sync) -> GridSet {
        let member: Vec<bool> = (0..grid.len()).into_par_iter().map(&keep).collect();
        let shell: Vec<[f64; 3]> = (0..grid.len())
            .into_par_iter()
            .filter(|&i| member[i] && grid.neighbours(i).any(|j| !member[j]))
            .map(|i| grid.point(i))
            .collect();
        let tree = (!shell.is_empty())
            .then(|| ImmutableKdTree::<f64, 3>::new_from_slice(&shell).ok())
            .flatten();
        GridSet { member, tree }
    }

    /// The distance from `q` (inside the grid's box) to the nearest member; infinite for an
    /// empty set.
    pub(super) fn nearest(&self, grid: &Grid, q: [f64; 3]) -> f64 {
        let shell = self.tree.as_ref().map_or(f64::INFINITY, |tree| {
            tree.query(&q)
                .nearest_one::<SquaredEuclidean<f64>>()
                .execute()
                .distance
        });
        let corner = grid
            .cell_corners(q)
            .filter(|&i| self.member[i])
            .map(|i| squared_distance(q, grid.point(i)))
            .fold(f64::INFINITY, f64::min);
        shell.min(corner).sqrt()
    }
}

/// The squared distance summed as the k-d tree sums it (axis by axis, from the first).
fn squared_distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    let mut sum = (a[0] - b[0]) * (a[0] - b[0]);
    sum += (a[1] - b[1]) * (a[1] - b[1]);
    sum += (a[2] - b[2]) * (a[2] - b[2]);
    sum
}
