//! Outliers of a fitted patch: points whose height off the network stands out from their
//! neighbours' heights.
//!
//! [`find_outliers`](super::find_outliers) runs before the embedding and keeps points within
//! about a point spacing of their neighbours' planes: they cannot be told from a rough
//! surface there. Against the fitted network they can. A point's height is its signed
//! distance from the network along the normal at the foot of its perpendicular (found from
//! its (u, v) by a few Gauss–Newton steps); where the network misses
//! the surface, its neighbours in (u, v) miss it alike, so a point is measured by its height
//! less the median of its [`NEIGHBORS`] nearest neighbours' heights. It is an outlier when
//! that exceeds `deviations` robust deviations (1.4826 · MAD) of the same difference, over
//! the whole patch and over its [`SPREAD_NEIGHBORS`] nearest, and [`MIN_SPACINGS`] of the point spacing (the
//! median distance to the nearest neighbour). Without noise the differences are the
//! network's own error, which changes quickly in places (near a patch's border, mostly):
//! points there are not isolated, and their neighbours' spread keeps them.

use kiddo::{ImmutableKdTree, SquaredEuclidean};

use super::network::SurfaceNetwork;
use super::outliers::median;
use crate::geometry::vector::{cross, distance, dot, norm, sub};

/// Neighbours in (u, v) a point's height is compared with.
pub const NEIGHBORS: usize = 8;

/// Least difference from the neighbours' heights, in point spacings, that makes an outlier:
/// a network with a few points per weight follows such a point by a small part of that,
/// while a coarse network's own error may change by nearly that much between neighbours.
pub const MIN_SPACINGS: f64 = 0.25;

/// Neighbours in (u, v) whose spread of differences a point is also measured against.
pub const SPREAD_NEIGHBORS: usize = 32;

/// A point and its [`SPREAD_NEIGHBORS`] nearest.
const SPREAD_ASKED: std::num::NonZero<usize> =
    std::num::NonZero::new(SPREAD_NEIGHBORS + 1).unwrap();

/// Gauss–Newton steps from a point's (u, v) to the foot of its perpendicular on the network.
const FOOT_STEPS: usize = 3;

/// The signed distance of `p` from `network` along its normal at the foot of the
/// perpendicular, found from `uv`: the embedding places a point's (u, v) a little along the
/// surface, and on a curved patch the normal at `uv` itself would miss it by that much.
fn height(network: &SurfaceNetwork, p: [f64; 3], uv: [f64; 2]) -> f64 {
    let [mut u, mut v] = uv;
    for _ in 0..FOOT_STEPS {
        let at = network.evaluate(u, v);
        let r = sub(p, at.position);
        let (a, b, c) = (dot(at.du, at.du), dot(at.du, at.dv), dot(at.dv, at.dv));
        let determinant = a * c - b * b;
        if determinant.is_nan() || determinant <= 0.0 {
            break;
        }
        let (gu, gv) = (dot(at.du, r), dot(at.dv, r));
        u += (c * gu - b * gv) / determinant;
        v += (a * gv - b * gu) / determinant;
    }
    let at = network.evaluate(u, v);
    let normal = cross(at.du, at.dv);
    let length = norm(normal);
    if length > 0.0 && length.is_finite() {
        dot(sub(p, at.position), normal) / length
    } else {
        0.0
    }
}

/// Indices of the points (at their `parameters`) whose height off `network` stands out from
/// their neighbours' (see the module docs); none for `NEIGHBORS` points or fewer, or when
/// every height difference is alike.
pub fn find_fit_outliers(
    network: &SurfaceNetwork,
    points: &[[f64; 3]],
    parameters: &[[f64; 2]],
    deviations: f64,
) -> Vec<usize> {
    if points.len() != parameters.len() || points.len() <= NEIGHBORS {
        return Vec::new();
    }
    let heights: Vec<f64> = points
        .iter()
        .zip(parameters)
        .map(|(&p, &uv)| height(network, p, uv))
        .collect();
    // Neighbours in (u, v) scaled to the network's input box, so an elongated patch's
    // neighbours are not all along its long side.
    let scaled: Vec<[f64; 2]> = parameters
        .iter()
        .map(|&uv| network.normalize_input(uv[0], uv[1]))
        .collect();
    let Ok(tree) = ImmutableKdTree::<f64, 2>::new_from_slice(&scaled) else {
        return Vec::new();
    };
    // Each point's SPREAD_NEIGHBORS nearest in (u, v), nearest first; the first NEIGHBORS
    // of them give its neighbours' heights.
    let around: Vec<Vec<usize>> = scaled
        .iter()
        .enumerate()
        .map(|(i, uv)| {
            let mut found = tree
                .query(uv)
                .nearest_n::<SquaredEuclidean<f64>>(SPREAD_ASKED)
                .execute();
            found.sort_by(|a, b| a.distance.total_cmp(&b.distance));
            found
                .into_iter()
                .map(|n| n.item as usize)
                .filter(|&j| j != i)
                .collect()
        })
        .collect();
    let differences: Vec<f64> = around
        .iter()
        .enumerate()
        .map(|(i, list)| {
            let mut theirs: Vec<f64> = list.iter().take(NEIGHBORS).map(|&j| heights[j]).collect();
            heights[i] - median(&mut theirs)
        })
        .collect();
    let mut nearest: Vec<f64> = around
        .iter()
        .enumerate()
        .map(|(i, list)| {
            list.iter()
                .take(NEIGHBORS)
                .map(|&j| distance(points[i], points[j]))
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    let floor = MIN_SPACINGS * median(&mut nearest);
    let mut sorted = differences.clone();
    let middle = median(&mut sorted);
    let mut spread: Vec<f64> = differences.iter().map(|d| (d - middle).abs()).collect();
    let spread = 1.4826 * median(&mut spread);
    if spread.is_nan() || spread <= 0.0 {
        return Vec::new();
    }
    (0..points.len())
        .filter(|&i| {
            // Where the network's error changes quickly, the differences around are large
            // too: a point is measured by the larger of the patch's spread and theirs, over
            // enough points for a steady estimate.
            let mut theirs: Vec<f64> = around[i]
                .iter()
                .map(|&j| (differences[j] - middle).abs())
                .collect();
            let local = 1.4826 * median(&mut theirs);
            (differences[i] - middle).abs() > (deviations * spread.max(local)).max(floor)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parametric::{SampleSurface, TopologyOptions, fit_network, sample_surface};
    use rand::{Rng, SeedableRng};

    /// The wavy sheet's upward unit normal at (x, y).
    fn wavy_normal(x: f64, y: f64) -> [f64; 3] {
        let zx = 0.625 * (2.5 * x).cos() * (2.0 * y).cos();
        let zy = -0.5 * (2.5 * x).sin() * (2.0 * y).sin();
        let n = [-zx, -zy, 1.0];
        let l = norm(n);
        n.map(|c| c / l)
    }

    #[test]
    fn points_a_little_off_the_fit_stand_out_and_surface_points_do_not() {
        let topology = TopologyOptions {
            max_neurons: 8,
            ..TopologyOptions::default()
        };
        // Noise ±0.2 % of the diagonal (2.9), and none.
        for (noise, seed) in [(0.002, 1), (0.0, 2)] {
            let sample = sample_surface(SampleSurface::Wavy, 1_500, noise, seed).unwrap();
            let fit = fit_network(&sample.points, &sample.parameters, &topology).unwrap();
            let found = find_fit_outliers(&fit.network, &sample.points, &sample.parameters, 3.0);
            // A few surface points where the network's error changes fastest (1.2 % without
            // noise), no more.
            assert!(found.len() <= 30, "noise {noise}: {} flagged", found.len());
            // 20 points 0.02 off the surface (0.7 % of the diagonal, under half the 0.05
            // spacing, so `find_outliers` keeps them; 6 times the noise's deviation along
            // the normal): all stand out without noise, and at least 18 with it.
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            let (mut points, mut parameters) = (sample.points.clone(), sample.parameters.clone());
            for k in 0..20 {
                let (x, y) = (rng.random_range(-0.9..0.9), rng.random_range(-0.9..0.9));
                let side = if k % 2 == 0 { 0.02 } else { -0.02 };
                let p = SampleSurface::Wavy.position(x, y);
                let n = wavy_normal(x, y);
                points.push([0, 1, 2].map(|a| p[a] + side * n[a]));
                parameters.push([x, y]);
            }
            let found = find_fit_outliers(&fit.network, &points, &parameters, 3.0);
            let planted = found.iter().filter(|&&i| i >= 1_500).count();
            let least = if noise > 0.0 { 18 } else { 20 };
            assert!(planted >= least, "noise {noise}: {found:?}");
        }
    }
}
