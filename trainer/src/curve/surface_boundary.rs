//! Whether scattered 3-D points have a boundary: a spline surface is one open patch, and a
//! map trained on a closed surface (a sphere, a closed scan) folds over it with no warning.
//!
//! A point lies on the boundary when its [`BOUNDARY_NEIGHBOURS`] nearest points, seen in
//! their best-fitting plane, leave a gap of more than [`BOUNDARY_GAP`] around it: inside a
//! surface they surround it, at an edge they lie on one side. Boundary points next to each
//! other form a boundary; an open patch of n points has one of about 3.5·√n points or more
//! (a square's perimeter over its spacing). A few points that noise or uneven sampling
//! flags inside a surface do not join into one.
//!
//! Measured on random points (500, 2 000 and 8 000; [`BOUNDARY_GAP`] = 130°): a wavy square
//! and a paraboloid disc have a largest boundary of 2.1–3.4·√n points, with noise of 2 % of
//! their size too; a sphere 0.08·√n or less, with noise of 1 % of its radius too.

use std::num::NonZeroUsize;

use kiddo::ImmutableKdTree;
use nalgebra::{Matrix3, SymmetricEigen, Vector3};

use super::groups::{join, nearest, root};

/// Nearest points that decide whether a point lies on the boundary.
pub const BOUNDARY_NEIGHBOURS: usize = 16;
/// The angle, in radians, that the neighbours must leave empty around a boundary point
/// (130°: a straight edge leaves 180°; 16 points spread at random around an inner point
/// leave more than 130° with probability about 2 %, and such points seldom join).
pub const BOUNDARY_GAP: f64 = 130.0 * std::f64::consts::PI / 180.0;
/// Points with a largest boundary below this many times √n have none: measured, an open
/// patch of n random points has one of at least 2·√n points, a sphere at most 0.1·√n.
pub const CLOSED_BELOW: f64 = 0.5;

/// The size of the largest boundary of `points`: the most boundary points that join through
/// each other's neighbours. 0 for too few points to tell (fewer than 4 neighbourhoods).
pub fn largest_boundary(points: &[[f64; 3]]) -> usize {
    boundaries(points).first().map_or(0, Vec::len)
}

/// The boundaries of `points`, largest first: each the indices of boundary points that join
/// through each other's neighbours. None for too few points to tell (fewer than 4
/// neighbourhoods).
pub fn boundaries(points: &[[f64; 3]]) -> Vec<Vec<usize>> {
    let n = points.len();
    if n < 4 * BOUNDARY_NEIGHBOURS {
        return Vec::new();
    }
    let Ok(tree) = ImmutableKdTree::<f64, 3>::new_from_slice(points) else {
        return Vec::new();
    };
    let count = NonZeroUsize::new(BOUNDARY_NEIGHBOURS + 1).unwrap_or(NonZeroUsize::MIN);
    let neighbours: Vec<Vec<usize>> = nearest(&tree, points, count)
        .into_iter()
        .map(|list| list.into_iter().map(|(j, _)| j).collect())
        .collect();
    let on_boundary: Vec<bool> = (0..n)
        .map(|i| angular_gap(points, i, &neighbours[i]) > BOUNDARY_GAP)
        .collect();
    // Boundary points that are each other's neighbours form one boundary.
    let mut parent: Vec<usize> = (0..n).collect();
    for i in (0..n).filter(|&i| on_boundary[i]) {
        for &j in neighbours[i].iter().filter(|&&j| on_boundary[j]) {
            join(&mut parent, i, j);
        }
    }
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); n];
    for i in (0..n).filter(|&i| on_boundary[i]) {
        let r = root(&mut parent, i);
        members[r].push(i);
    }
    let mut found: Vec<Vec<usize>> = members.into_iter().filter(|m| !m.is_empty()).collect();
    found.sort_by_key(|m| std::cmp::Reverse(m.len()));
    found
}

/// The largest angle around point `i` between consecutive `neighbours` (itself among them or
/// not), in the plane that fits them best; 0 where they span no plane.
fn angular_gap(points: &[[f64; 3]], i: usize, neighbours: &[usize]) -> f64 {
    let others: Vec<[f64; 3]> = neighbours
        .iter()
        .filter(|&&j| j != i)
        .map(|&j| points[j])
        .collect();
    gap_around(points[i], &others)
}

/// The largest angle around `centre` between consecutive `others`, in the plane through
/// `centre` that fits them best; 0 where they span no plane.
fn gap_around(centre: [f64; 3], others: &[[f64; 3]]) -> f64 {
    let centre = Vector3::from(centre);
    let others: Vec<Vector3<f64>> = others.iter().map(|&p| Vector3::from(p) - centre).collect();
    let mut scatter = Matrix3::zeros();
    for d in &others {
        scatter += d * d.transpose();
    }
    let eigen = SymmetricEigen::new(scatter);
    let mut order = [0, 1, 2];
    order.sort_by(|&a, &b| eigen.eigenvalues[b].total_cmp(&eigen.eigenvalues[a]));
    let (e1, e2) = (
        eigen.eigenvectors.column(order[0]).into_owned(),
        eigen.eigenvectors.column(order[1]).into_owned(),
    );
    let mut angles: Vec<f64> = others
        .iter()
        .filter(|d| d.norm() > 0.0)
        .map(|d| d.dot(&e2).atan2(d.dot(&e1)))
        .filter(|a| a.is_finite())
        .collect();
    if angles.len() < 3 {
        return 0.0;
    }
    angles.sort_by(f64::total_cmp);
    let wrap = angles[0] + std::f64::consts::TAU - angles[angles.len() - 1];
    angles.windows(2).map(|w| w[1] - w[0]).fold(wrap, f64::max)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// `n` points at random (u, v) ∈ [0, 1)² mapped by `at`.
    pub(crate) fn random(n: usize, seed: u64, at: impl Fn(f64, f64) -> [f64; 3]) -> Vec<[f64; 3]> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..n)
            .map(|_| at(rng.random::<f64>(), rng.random::<f64>()))
            .collect()
    }

    #[test]
    fn a_patch_has_one_boundary_and_a_sphere_none() {
        let tau = std::f64::consts::TAU;
        for (n, seed) in [(500, 1), (2_000, 2), (8_000, 3)] {
            let root = (n as f64).sqrt();
            let square = random(n, seed, |u, v| [u, v, 0.3 * (3.0 * u).sin() * v]);
            let ratio = |points: &[[f64; 3]]| largest_boundary(points) as f64 / root;
            assert!(ratio(&square) >= 1.5, "square {n}: {}", ratio(&square));
            let disc = random(n, seed, |u, v| {
                let r = u.sqrt();
                [r * (tau * v).cos(), r * (tau * v).sin(), 0.2 * r * r]
            });
            assert!(ratio(&disc) >= 1.5, "disc {n}: {}", ratio(&disc));
            let sphere = random(n, seed, |u, v| {
                let z = 2.0 * u - 1.0;
                let r = (1.0 - z * z).sqrt();
                [r * (tau * v).cos(), r * (tau * v).sin(), z]
            });
            assert!(ratio(&sphere) < 0.25, "sphere {n}: {}", ratio(&sphere));
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let noisy: Vec<[f64; 3]> = sphere
                .iter()
                .map(|p| p.map(|c| c * (1.0 + 0.02 * (rng.random::<f64>() - 0.5))))
                .collect();
            assert!(ratio(&noisy) < 0.25, "noisy sphere {n}: {}", ratio(&noisy));
        }
    }
}
