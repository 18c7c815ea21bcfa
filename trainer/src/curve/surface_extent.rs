//! How long and how wide a patch of scattered points is, measured along the patch: the map
//! and the control grid of [`super::fit_surface`] take their shape from it, so that a long
//! sheet gets a long map instead of a square one folded over it.
//!
//! Distances along the patch are shortest paths in the graph of each point's
//! [`EXTENT_NEIGHBOURS`] nearest points. Landmark MDS (de Silva & Tenenbaum 2004) unrolls the
//! patch into the plane: [`EXTENT_LANDMARKS`] landmarks picked farthest-first are placed by
//! classical MDS of their path lengths, every point by its path lengths to them. The two
//! principal spreads of the unrolled points give the patch's aspect: √(λ₁/λ₂), its length over
//! its width for a rectangle of uniform density, whatever its bending in space.
//!
//! Measured on random points (1 000, 3 000 and 8 000; the tests): a wavy strip of length 4.16
//! along its wave and width 1, 3.8–4.0; an S-sheet of length 3π and width 2 (4.7, bent
//! through 540°), 4.1–4.4; a saddle 1.01–1.05. Paths through neighbours cut across bends a
//! little, so bent patches measure somewhat short.

use std::num::NonZeroUsize;

use kiddo::ImmutableKdTree;
use nalgebra::{DMatrix, Matrix2, SymmetricEigen};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::path_graph::{neighbour_graph, shortest_paths};

/// Nearest points joined in the path graph.
pub const EXTENT_NEIGHBOURS: usize = 8;
/// Landmarks of the unrolling.
pub const EXTENT_LANDMARKS: usize = 32;
/// Most points the graph is built on: beyond it, a seeded random sample of this many.
pub const EXTENT_SAMPLE: usize = 2_000;

/// The aspect of the patch: its length over its width measured along it (≥ 1), or `None`
/// when it can't tell (fewer than 4 neighbourhoods of points, a graph that falls apart in
/// pieces, or points that unroll onto a line).
pub fn patch_aspect(points: &[[f64; 3]]) -> Option<f64> {
    unroll(points).map(|unrolled| unrolled.aspect)
}

/// A patch unrolled into the plane: a sample of its points and where each lands.
#[derive(Clone, Debug)]
pub struct Unrolled {
    /// Length over width along the patch (≥ 1).
    pub aspect: f64,
    /// The sample's points in space.
    sample: Vec<[f64; 3]>,
    /// Each sample point in the plane, in the frame of the smallest rectangle around them
    /// all: x along its long side, y along its short one.
    plane: Vec<[f64; 2]>,
}

/// Unrolls the patch (see the module's documentation); `None` as [`patch_aspect`].
pub fn unroll(points: &[[f64; 3]]) -> Option<Unrolled> {
    if points.len() < 4 * EXTENT_NEIGHBOURS {
        return None;
    }
    let sample: Vec<[f64; 3]> = if points.len() > EXTENT_SAMPLE {
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        rand::seq::index::sample(&mut rng, points.len(), EXTENT_SAMPLE)
            .into_iter()
            .map(|i| points[i])
            .collect()
    } else {
        points.to_vec()
    };
    let graph = neighbour_graph(&sample, EXTENT_NEIGHBOURS)?;
    let plane = unroll_graph(&graph, EXTENT_LANDMARKS)?;
    let spreads = principal_spreads(&plane)?;
    let aspect = (spreads[0] / spreads[1]).sqrt();
    if !aspect.is_finite() {
        return None;
    }
    Some(Unrolled {
        aspect: aspect.max(1.0),
        sample,
        plane: smallest_rectangle_frame(&plane),
    })
}

impl Unrolled {
    /// Starting weights for a `columns × rows` map (row by row): the map laid over the
    /// smallest rectangle around the unrolled points, its longer side along the rectangle's,
    /// each neuron at the mean of the [`EXTENT_NEIGHBOURS`] points unrolled nearest to it.
    pub fn initial_map(&self, columns: usize, rows: usize) -> Option<Vec<[f64; 3]>> {
        let tree = ImmutableKdTree::<f64, 2>::new_from_slice(&self.plane).ok()?;
        let count = NonZeroUsize::new(EXTENT_NEIGHBOURS)?;
        let low = [0, 1].map(|a| {
            self.plane
                .iter()
                .map(|p| p[a])
                .fold(f64::INFINITY, f64::min)
        });
        let high = [0, 1].map(|a| {
            self.plane
                .iter()
                .map(|p| p[a])
                .fold(f64::NEG_INFINITY, f64::max)
        });
        let at = |a: usize, k: usize, count: usize| {
            low[a] + (high[a] - low[a]) * k as f64 / (count - 1).max(1) as f64
        };
        let mut neurons = Vec::with_capacity(columns * rows);
        for row in 0..rows {
            for column in 0..columns {
                let place = if columns <= rows {
                    [at(0, row, rows), at(1, column, columns)]
                } else {
                    [at(0, column, columns), at(1, row, rows)]
                };
                let found = tree
                    .query(&place)
                    .nearest_n::<kiddo::SquaredEuclidean<f64>>(count)
                    .execute();
                let mut mean = [0.0; 3];
                for f in &found {
                    let p = self.sample[f.item as usize];
                    for k in 0..3 {
                        mean[k] += p[k] / found.len() as f64;
                    }
                }
                neurons.push(mean);
            }
        }
        Some(neurons)
    }
}

/// The index of the largest of `values`.
fn farthest(values: &[f64]) -> usize {
    values
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .map_or(0, |(i, _)| i)
}

/// Every point unrolled into the plane by landmark MDS, from `paths[l][i]`, the path length
/// from landmark l to point i; `None` when the landmarks span no plane.
fn landmark_mds(paths: &[Vec<f64>]) -> Option<Vec<[f64; 2]>> {
    let landmarks = paths.len();
    let n = paths.first()?.len();
    if landmarks < 3 {
        return None;
    }
    // The landmarks' own squared distances, each landmark being one of the points.
    let index: Vec<usize> = paths
        .iter()
        .map(|p| p.iter().position(|&d| d == 0.0).unwrap_or(0))
        .collect();
    let squared = DMatrix::from_fn(landmarks, landmarks, |a, b| paths[a][index[b]].powi(2));
    let mean: Vec<f64> = (0..landmarks).map(|b| squared.column(b).mean()).collect();
    let total = squared.mean();
    let centred = DMatrix::from_fn(landmarks, landmarks, |a, b| {
        -0.5 * (squared[(a, b)] - mean[a] - mean[b] + total)
    });
    let eigen = SymmetricEigen::new(centred);
    let mut order: Vec<usize> = (0..landmarks).collect();
    order.sort_by(|&a, &b| eigen.eigenvalues[b].total_cmp(&eigen.eigenvalues[a]));
    let axes: Vec<(f64, usize)> = order[..2]
        .iter()
        .map(|&k| (eigen.eigenvalues[k], k))
        .collect();
    if axes
        .iter()
        .any(|&(value, _)| value.is_nan() || value <= 0.0)
    {
        return None;
    }
    // Point i at −½ Σ_l vₖ[l]/√λₖ · (d²(l, i) − mean_l).
    let mut unrolled = vec![[0.0_f64; 2]; n];
    for (i, point) in unrolled.iter_mut().enumerate() {
        for (axis, &(value, k)) in axes.iter().enumerate() {
            let vector = eigen.eigenvectors.column(k);
            point[axis] = -0.5
                * (0..landmarks)
                    .map(|l| vector[l] / value.sqrt() * (paths[l][i].powi(2) - mean[l]))
                    .sum::<f64>();
        }
    }
    Some(unrolled)
}

/// The two principal variances of points in the plane, largest first; `None` when they lie
/// on a line.
fn principal_spreads(plane: &[[f64; 2]]) -> Option<[f64; 2]> {
    let n = plane.len() as f64;
    let centre = [0, 1].map(|a| plane.iter().map(|p| p[a]).sum::<f64>() / n);
    let mut covariance = Matrix2::<f64>::zeros();
    for p in plane {
        let d = [p[0] - centre[0], p[1] - centre[1]];
        for a in 0..2 {
            for b in 0..2 {
                covariance[(a, b)] += d[a] * d[b] / n;
            }
        }
    }
    let values = SymmetricEigen::new(covariance).eigenvalues;
    let (large, small) = (values[0].max(values[1]), values[0].min(values[1]));
    (small > 0.0).then_some([large, small])
}

/// `plane` turned into the frame of the smallest-area rectangle around it (searched in
/// half-degree steps), x along the rectangle's longer side.
fn smallest_rectangle_frame(plane: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let turned = |angle: f64| {
        let (sin, cos) = angle.sin_cos();
        move |p: &[f64; 2]| [cos * p[0] + sin * p[1], cos * p[1] - sin * p[0]]
    };
    let sides = |angle: f64| {
        let turn = turned(angle);
        let mut low = [f64::INFINITY; 2];
        let mut high = [f64::NEG_INFINITY; 2];
        for q in plane.iter().map(turn) {
            for a in 0..2 {
                low[a] = low[a].min(q[a]);
                high[a] = high[a].max(q[a]);
            }
        }
        [high[0] - low[0], high[1] - low[1]]
    };
    let steps = 180;
    let best = (0..steps)
        .map(|k| k as f64 * std::f64::consts::FRAC_PI_2 / steps as f64)
        .min_by(|&a, &b| {
            let (x, y) = (sides(a), sides(b));
            (x[0] * x[1]).total_cmp(&(y[0] * y[1]))
        })
        .unwrap_or(0.0);
    let [long, short] = sides(best);
    let angle = if long >= short {
        best
    } else {
        best + std::f64::consts::FRAC_PI_2
    };
    plane.iter().map(turned(angle)).collect()
}

/// Every point of `graph` (each point's neighbours with their distances, listed both ways)
/// unrolled into the plane by landmark MDS of path lengths through it, with `landmarks`
/// landmarks picked farthest-first; `None` when the graph falls apart in pieces or the
/// landmarks span no plane.
pub(crate) fn unroll_graph(graph: &[Vec<(usize, f64)>], landmarks: usize) -> Option<Vec<[f64; 2]>> {
    let n = graph.len();
    let from_zero = shortest_paths(graph, &[0]);
    if n == 0 || from_zero.iter().any(|d| !d.is_finite()) {
        return None;
    }
    // Farthest-first landmarks: each new one is the point farthest along the patch from
    // those chosen. The first is the farthest from point 0, an end of the patch.
    let mut nearest_landmark = vec![f64::INFINITY; n];
    let mut next = farthest(&from_zero);
    let mut paths: Vec<Vec<f64>> = Vec::with_capacity(landmarks);
    for _ in 0..landmarks.min(n) {
        let distances = shortest_paths(graph, &[next]);
        for (m, &d) in nearest_landmark.iter_mut().zip(&distances) {
            *m = m.min(d);
        }
        paths.push(distances);
        next = farthest(&nearest_landmark);
    }
    landmark_mds(&paths)
}

#[cfg(test)]
mod tests {
    use super::super::surface_boundary::tests::random;
    use super::*;

    #[test]
    fn the_aspect_is_measured_along_the_patch() {
        let pi = std::f64::consts::PI;
        for (n, seed) in [(1_000, 1), (3_000, 2), (8_000, 3)] {
            let strip = random(n, seed, |u, v| [4.0 * u, v, 0.2 * (8.0 * u).sin()]);
            let a = patch_aspect(&strip).unwrap();
            assert!((3.6..4.4).contains(&a), "strip {n}: {a}");
            // Length 3π, width 2, bent through 540°: its box is 2 × 2 × 4.
            let sheet = random(n, seed, |u, v| {
                let t = 3.0 * pi * (u - 0.5);
                [t.sin(), 2.0 * v, t.signum() * (t.cos() - 1.0)]
            });
            let a = patch_aspect(&sheet).unwrap();
            assert!((4.0..5.2).contains(&a), "S-sheet {n}: {a}");
            let saddle = random(n, seed, |u, v| {
                let (x, y) = (2.0 * u - 1.0, 2.0 * v - 1.0);
                [x, y, 0.5 * (x * x - y * y)]
            });
            let a = patch_aspect(&saddle).unwrap();
            assert!(a < 1.25, "saddle {n}: {a}");
        }
    }

    #[test]
    fn too_few_or_scattered_points_give_none() {
        assert_eq!(patch_aspect(&[[0.0; 3]; 10]), None);
        // Two far clusters: the graph falls apart.
        let mut two = random(200, 4, |u, v| [u, v, 0.0]);
        two.extend(random(200, 5, |u, v| [u + 100.0, v, 0.0]));
        assert_eq!(patch_aspect(&two), None);
    }
}
