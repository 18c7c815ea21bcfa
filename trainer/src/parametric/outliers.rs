//! Outliers of a scanned patch: points off the surface that would pull the network out to
//! them, found before the embedding from each point's k nearest neighbours
//! (k = [`OutlierOptions::neighbors`]).
//!
//! A point is an outlier when it stands off the planes of its nearest neighbours by more than
//! [`OutlierOptions::height`] times their spread (or, on a noisy scan, more than the median
//! height plus [`OutlierOptions::deviations`] robust deviations), or when it is farther from
//! its neighbours than [`OutlierOptions::isolation`] times they are from theirs (a local
//! ratio, so a sparser region of the scan is not an outlier), or than
//! [`OutlierOptions::edge_isolation`] times when its neighbours all lie to one side of it (it
//! stands beyond the scan's edge, where the region the points cover would reach out to it in
//! a spike). Each plane is fitted to a
//! neighbour's own neighbours, the flattest of the plane of all of them and of those without
//! one, so an outlier tilts neither its own plane nor, much, its neighbours'. A point's height
//! is the median over the [`PLANES_ASKED`] flattest planes among its neighbours': those of
//! surface points, even when other outliers are nearer.
//!
//! Points off the surface by less than half the neighbourhood's spread (about one point
//! spacing) stay; their pull on the network is at most that. A cluster of outliers far from
//! the surface whose nearest neighbours are each other also stays (a 5 % cloud of outliers
//! filling the inside of a cylinder leaves a few).

use super::neighbors::nearest_neighbors;
use crate::error::Result;
use crate::geometry::vector::{cross, distance, dot, sub};

/// How many of its neighbours' planes (the flattest) a point is measured against, the median
/// of their verdicts.
pub const PLANES_ASKED: usize = 3;

/// Thresholds of [`find_outliers`].
#[derive(Copy, Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct OutlierOptions {
    /// Neighbours per point (10).
    pub neighbors: usize,
    /// Height off the neighbours' planes, in units of their RMS spread around their centroid,
    /// beyond which a point is an outlier (0.5), or the median height over the whole scan plus
    /// `deviations` robust deviations when that is larger (noisy scans).
    pub height: f64,
    /// Mean distance to the neighbours over the median of the neighbours' own, beyond which a
    /// point is isolated (3.0).
    pub isolation: f64,
    /// The same ratio for a point beyond the edge of the others: its neighbours, seen in
    /// their plane, leave a gap of more than a half-turn around it (2.5). Points on a scan's
    /// border sit at 1.2–1.6.
    pub edge_isolation: f64,
    /// Robust deviations (1.4826 · MAD) beyond the median height over the whole scan that
    /// still count as noise (6.0).
    pub deviations: f64,
    /// Robust deviations of a point's height off the fitted network, less its neighbours',
    /// beyond which it is left out and the network refined without it (3.0; see
    /// `fit_outliers`).
    pub fit_deviations: f64,
}

impl Default for OutlierOptions {
    fn default() -> Self {
        OutlierOptions {
            neighbors: 10,
            height: 0.5,
            isolation: 3.0,
            edge_isolation: 2.5,
            deviations: 6.0,
            fit_deviations: 3.0,
        }
    }
}

/// Which points [`find_outliers`] kept and which it removed (indices into its input).
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Outliers {
    /// Kept, in input order.
    pub kept: Vec<usize>,
    /// Removed, in input order.
    pub removed: Vec<usize>,
}

impl Outliers {
    fn from_flags(flags: &[bool]) -> Self {
        let (removed, kept): (Vec<usize>, Vec<usize>) = (0..flags.len()).partition(|&i| flags[i]);
        Outliers { kept, removed }
    }
}

/// The points off their neighbours' planes or isolated from them.
///
/// # Errors
/// Those of [`nearest_neighbors`]: too few points for k, coinciding points, k below 3.
pub fn find_outliers(points: &[[f64; 3]], options: &OutlierOptions) -> Result<Outliers> {
    let diagonal = {
        let (lo, hi) = crate::geometry::vector::bounds(points);
        distance(lo, hi)
    };
    let neighbors = nearest_neighbors(points, options.neighbors, diagonal)?;
    let reach: Vec<f64> = points
        .iter()
        .zip(&neighbors)
        .map(|(&p, list)| {
            list.iter().map(|&j| distance(p, points[j])).sum::<f64>() / list.len() as f64
        })
        .collect();
    // Each point's plane comes from its neighbours alone, so an outlier does not tilt its
    // own; a point is measured against the flattest planes among its neighbours', those of
    // surface points even where other outliers are nearer.
    let planes: Vec<Plane> = neighbors
        .iter()
        .map(|list| flattest_plane(&list.iter().map(|&j| points[j]).collect::<Vec<_>>()))
        .collect();
    let heights: Vec<f64> = points
        .iter()
        .zip(&neighbors)
        .map(|(&p, list)| {
            let mut flattest = list.clone();
            flattest.sort_unstable_by(|&a, &b| planes[a].flatness.total_cmp(&planes[b].flatness));
            let mut heights: Vec<f64> = flattest
                .iter()
                .take(PLANES_ASKED)
                .map(|&j| planes[j].height(p))
                .collect();
            median(&mut heights)
        })
        .collect();
    // Noise raises every height: the limit is the larger of the option and a robust bound
    // over the whole scan.
    let height_limit = options
        .height
        .max(robust_limit(&heights, options.deviations));
    let flags: Vec<bool> = (0..points.len())
        .map(|i| {
            let mut theirs: Vec<f64> = neighbors[i].iter().map(|&j| reach[j]).collect();
            let typical = median(&mut theirs);
            heights[i] > height_limit
                || reach[i] > options.isolation * typical
                || (reach[i] > options.edge_isolation * typical
                    && widest_gap(points[i], &neighbors[i], points, planes[i].normal)
                        > std::f64::consts::PI)
        })
        .collect();
    Ok(Outliers::from_flags(&flags))
}

/// The widest angle around `p` between two of its `neighbors`, seen along `normal`: more
/// than π when they all lie on one side of it.
fn widest_gap(p: [f64; 3], neighbors: &[usize], points: &[[f64; 3]], normal: [f64; 3]) -> f64 {
    let helper = if normal[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let first = cross(normal, helper);
    let second = cross(normal, first);
    let mut angles: Vec<f64> = neighbors
        .iter()
        .map(|&j| {
            let d = sub(points[j], p);
            dot(d, second).atan2(dot(d, first))
        })
        .collect();
    angles.sort_unstable_by(f64::total_cmp);
    let (Some(&lowest), Some(&highest)) = (angles.first(), angles.last()) else {
        return 0.0;
    };
    let wrap = lowest + std::f64::consts::TAU - highest;
    angles.windows(2).map(|w| w[1] - w[0]).fold(wrap, f64::max)
}

/// The median of `values` plus `deviations` robust deviations (1.4826 · MAD); infinite when
/// the deviation is 0 (all values alike: nothing stands out).
fn robust_limit(values: &[f64], deviations: f64) -> f64 {
    let mut sorted = values.to_vec();
    let middle = median(&mut sorted);
    let mut spread: Vec<f64> = values.iter().map(|r| (r - middle).abs()).collect();
    let spread = 1.4826 * median(&mut spread);
    if spread > 0.0 {
        middle + deviations * spread
    } else {
        f64::INFINITY
    }
}

/// A least-squares plane through a point's neighbours.
#[derive(Copy, Clone, Debug)]
pub(crate) struct Plane {
    pub(crate) center: [f64; 3],
    pub(crate) normal: [f64; 3],
    /// RMS distance of the points to their centroid.
    spread: f64,
    /// The covariance's smallest eigenvalue over its trace: 0 for points on a plane, 1/3 for
    /// an isotropic cloud.
    flatness: f64,
}

impl Plane {
    /// Least-squares plane of `points`.
    pub(crate) fn fit(points: &[[f64; 3]]) -> Plane {
        let n = points.len().max(1) as f64;
        let center = [0, 1, 2].map(|k| points.iter().map(|p| p[k]).sum::<f64>() / n);
        let covariance = nalgebra::Matrix3::from_fn(|r, c| {
            points
                .iter()
                .map(|p| (p[r] - center[r]) * (p[c] - center[c]))
                .sum::<f64>()
        });
        let trace = covariance.trace();
        let eigen = covariance.symmetric_eigen();
        let smallest = eigen.eigenvalues.imin();
        let v = eigen.eigenvectors.column(smallest);
        Plane {
            center,
            normal: [v[0], v[1], v[2]],
            spread: (trace / n).sqrt(),
            flatness: eigen.eigenvalues[smallest] / trace.max(f64::MIN_POSITIVE),
        }
    }

    /// How far `p` stands off the plane, in units of the spread.
    fn height(&self, p: [f64; 3]) -> f64 {
        dot(sub(p, self.center), self.normal).abs() / self.spread.max(f64::MIN_POSITIVE)
    }
}

/// The flattest of the least-squares planes of `points` and of `points` without one of them:
/// an outlier among a point's neighbours weighs as much as the spread of the others and can
/// turn the plane of all of them on its side, where it no longer stands out.
fn flattest_plane(points: &[[f64; 3]]) -> Plane {
    let mut best = Plane::fit(points);
    if points.len() <= 3 {
        return best;
    }
    for skip in 0..points.len() {
        let rest: Vec<[f64; 3]> = (0..points.len())
            .filter(|&i| i != skip)
            .map(|i| points[i])
            .collect();
        let candidate = Plane::fit(&rest);
        if candidate.flatness < best.flatness {
            best = candidate;
        }
    }
    best
}

/// The median of `values` (reordered); 0 for none.
pub(super) fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let middle = values.len() / 2;
    *values
        .select_nth_unstable_by(middle, |a, b| a.total_cmp(b))
        .1
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parametric::{SampleSurface, sample_surface};
    use rand::{Rng, SeedableRng};

    /// `count` points uniform in the points' bounding box grown by 10 % per side.
    fn box_outliers(points: &[[f64; 3]], count: usize, seed: u64) -> Vec<[f64; 3]> {
        let (lo, hi) = crate::geometry::vector::bounds(points);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        (0..count)
            .map(|_| {
                [0, 1, 2].map(|k| {
                    let g = 0.1 * (hi[k] - lo[k]);
                    rng.random_range(lo[k] - g..hi[k] + g)
                })
            })
            .collect()
    }

    fn wavy_height(p: [f64; 3]) -> f64 {
        (p[2] - 0.25 * (2.5 * p[0]).sin() * (2.0 * p[1]).cos()).abs()
    }

    #[test]
    fn off_surface_points_are_found_and_clean_scans_keep_every_point() {
        for seed in 1..=3 {
            let clean = sample_surface(SampleSurface::Wavy, 2_000, 0.002, seed)
                .unwrap()
                .points;
            let found = find_outliers(&clean, &OutlierOptions::default()).unwrap();
            assert!(found.removed.is_empty(), "seed {seed}: {:?}", found.removed);
            let mut points = clean.clone();
            let extra = box_outliers(&clean, 40, seed);
            points.extend(&extra);
            let found = find_outliers(&points, &OutlierOptions::default()).unwrap();
            // Every outlier more than 1.5 % of the diagonal (2.9) off the surface goes, and
            // no surface point.
            for (k, &p) in extra.iter().enumerate() {
                let removed = found.removed.contains(&(2_000 + k));
                assert!(
                    removed || wavy_height(p) < 0.043,
                    "seed {seed}: {p:?} stays"
                );
            }
            assert!(found.removed.iter().all(|&i| i >= 2_000), "seed {seed}");
        }
    }

    #[test]
    fn a_lone_point_beyond_the_edge_goes_and_the_edge_stays() {
        // On the surface's extension, 0.15 beyond its edge at x = 1 (about 3.5 point
        // spacings): no plane tells it from the surface, and the region the points cover
        // would reach out to it in a spike.
        for seed in 1..=3 {
            let mut points = sample_surface(SampleSurface::Wavy, 2_000, 0.0, seed)
                .unwrap()
                .points;
            let y = 0.3 * seed as f64 - 0.6;
            let x = 1.15;
            points.push([x, y, 0.25 * (2.5 * x).sin() * (2.0 * y).cos()]);
            let found = find_outliers(&points, &OutlierOptions::default()).unwrap();
            assert_eq!(found.removed, vec![2_000], "seed {seed}");
        }
    }

    #[test]
    fn a_sparser_half_is_not_an_outlier() {
        // The saddle z = xy, ten times sparser for x > 0.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut points = Vec::new();
        while points.len() < 2_200 {
            let (x, y): (f64, f64) = (rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
            if x < 0.0 || rng.random_range(0.0..1.0) < 0.1 {
                points.push([x, y, x * y]);
            }
        }
        let found = find_outliers(&points, &OutlierOptions::default()).unwrap();
        assert!(found.removed.is_empty(), "{:?}", found.removed);
    }
}
