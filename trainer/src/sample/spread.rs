//! Evenly spread subsets of random candidates: weighted sample elimination (Yuksel 2015,
//! "Sample Elimination for Generating Poisson Disk Sample Sets").
//!
//! Independent uniform samples clump and leave gaps: among 1 500 points on the Stanford bunny,
//! the widest gaps decide how far a surface fitted through them strays between points. Drawing
//! several times more candidates and removing, one at a time, the candidate most crowded by
//! its neighbours leaves points that keep a near-constant distance from each other (blue
//! noise), still area-uniform on average.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use kiddo::{ImmutableKdTree, SquaredEuclidean};

/// Candidates drawn per point kept.
pub const CANDIDATES_PER_POINT: usize = 4;

/// The most points spread evenly; a larger request is drawn at random. Elimination takes
/// about 3.4 s for 100 000 points on the bunny, 9.6 s for 200 000 and 68 s (and 0.5 GB)
/// for 10⁶ on this project's 2-core machine.
pub const MAX_EVEN_POINTS: usize = 200_000;

/// How a mesh sampler places its points.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Spread {
    /// Evenly: [`CANDIDATES_PER_POINT`] random candidates per point, thinned by weighted
    /// sample elimination to points that keep a near-constant distance from each other. Up
    /// to [`MAX_EVEN_POINTS`] points; more are drawn as [`Spread::Random`].
    #[default]
    Even,
    /// Independent area-uniform draws: clumps and gaps, as a scanner without a plan leaves.
    Random,
}

/// The cosine below which two candidates' normals are opposed: 120°.
const OPPOSED: f64 = -0.5;

/// Exponent α of the weight (1 − d / 2r)^α (Yuksel's value).
const ALPHA: i32 = 8;
/// Yuksel's β and γ: the distance below which crowding stops growing, as a share of r.
const BETA: f64 = 0.65;
const GAMMA: f64 = 1.5;

/// The indices of `count` of `candidates` (points on a surface of total `area`, with their
/// unit `normals`) spread as evenly as elimination makes them, in increasing order. Returns
/// every index when `count` is at least the number of candidates. Deterministic.
///
/// Two candidates crowd each other unless their normals are opposed (more than 120° apart):
/// across a thin part (an ear, a fin) the two sides are close in space but are different
/// surface, and counting them as neighbours would thin that part twice over. Across a sharp
/// edge (90°) they do crowd each other, or the edge would hold the points of both faces.
pub(super) fn spread_evenly(
    candidates: &[[f64; 3]],
    normals: &[[f64; 3]],
    count: usize,
    area: f64,
) -> Vec<usize> {
    let total = candidates.len();
    if count >= total {
        return (0..total).collect();
    }
    // The largest spacing `count` points can keep on `area` (hexagonal packing), and the
    // distance under which two candidates count as equally crowded.
    let r_max = (area / (2.0 * 3f64.sqrt() * count as f64)).sqrt();
    let r_min = r_max * (1.0 - (count as f64 / total as f64).powf(GAMMA)) * BETA;
    let reach = 2.0 * r_max;
    if !(reach > 0.0 && reach.is_finite()) {
        return (0..count).collect();
    }
    let weight = |d2: f64| {
        let d = d2.sqrt().max(r_min).min(reach);
        (1.0 - d / reach).powi(ALPHA)
    };
    let Ok(tree) = ImmutableKdTree::<f64, 3>::new_from_slice(candidates) else {
        return (0..count).collect();
    };
    let neighbours = |i: usize| {
        tree.query(&candidates[i])
            .within::<SquaredEuclidean<f64>>(reach * reach)
            .unsorted()
            .execute()
            .into_iter()
            .filter(move |n| {
                let j = n.item as usize;
                j != i && (0..3).map(|k| normals[i][k] * normals[j][k]).sum::<f64>() > OPPOSED
            })
    };
    let mut weights: Vec<f64> = (0..total)
        .map(|i| neighbours(i).map(|n| weight(n.distance)).sum())
        .collect();
    let mut heap: BinaryHeap<Crowding> = weights
        .iter()
        .enumerate()
        .map(|(index, &weight)| Crowding { weight, index })
        .collect();
    let mut alive = vec![true; total];
    let mut left = total;
    while left > count {
        let Some(Crowding { weight: w, index }) = heap.pop() else {
            break;
        };
        // Entries are pushed again when a weight drops; only the current one counts.
        if !alive[index] || w != weights[index] {
            continue;
        }
        alive[index] = false;
        left -= 1;
        for n in neighbours(index) {
            let j = n.item as usize;
            if alive[j] {
                weights[j] -= weight(n.distance);
                heap.push(Crowding {
                    weight: weights[j],
                    index: j,
                });
            }
        }
    }
    (0..total).filter(|&i| alive[i]).collect()
}

/// A heap entry: the most crowded candidate first, the lower index among equals.
struct Crowding {
    weight: f64,
    index: usize,
}

impl PartialEq for Crowding {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for Crowding {}

impl PartialOrd for Crowding {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Crowding {
    fn cmp(&self, other: &Self) -> Ordering {
        self.weight
            .total_cmp(&other.weight)
            .then(other.index.cmp(&self.index))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The closest pair's distance among `points`, by brute force.
    fn closest_pair(points: &[[f64; 3]]) -> f64 {
        let mut best = f64::INFINITY;
        for (i, p) in points.iter().enumerate() {
            for q in &points[i + 1..] {
                let d = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt();
                best = best.min(d);
            }
        }
        best
    }

    /// The largest distance from a point of a fine grid over the unit square to the nearest
    /// of `points`: the widest gap.
    fn widest_gap(points: &[[f64; 3]]) -> f64 {
        let mut worst: f64 = 0.0;
        for i in 0..=100 {
            for j in 0..=100 {
                let (x, y) = (i as f64 / 100.0, j as f64 / 100.0);
                let nearest = points
                    .iter()
                    .map(|p| ((p[0] - x).powi(2) + (p[1] - y).powi(2)).sqrt())
                    .fold(f64::INFINITY, f64::min);
                worst = worst.max(nearest);
            }
        }
        worst
    }

    #[test]
    fn the_kept_points_keep_their_distance_and_leave_no_wide_gap() {
        let count = 400;
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let square = |n: usize, rng: &mut ChaCha8Rng| -> Vec<[f64; 3]> {
            (0..n)
                .map(|_| [rng.random::<f64>(), rng.random::<f64>(), 0.0])
                .collect()
        };
        let random = square(count, &mut rng);
        let candidates = square(count * CANDIDATES_PER_POINT, &mut rng);
        let up = vec![[0.0, 0.0, 1.0]; candidates.len()];
        let kept = spread_evenly(&candidates, &up, count, 1.0);
        assert_eq!(kept.len(), count);
        assert!(kept.windows(2).all(|w| w[0] < w[1]));
        let even: Vec<[f64; 3]> = kept.iter().map(|&i| candidates[i]).collect();
        // Hexagonal packing of 400 points on the unit square keeps them 0.054 apart.
        let spacing = (2.0 / (3f64.sqrt() * count as f64)).sqrt();
        let (close_even, close_random) = (closest_pair(&even), closest_pair(&random));
        let (gap_even, gap_random) = (widest_gap(&even), widest_gap(&random));
        assert!(close_even > 0.6 * spacing, "{close_even} against {spacing}");
        assert!(close_random < 0.2 * spacing, "{close_random}");
        assert!(
            gap_even < 0.7 * gap_random,
            "{gap_even} against {gap_random}"
        );
    }

    #[test]
    fn a_thin_plate_keeps_its_share_on_both_sides() {
        // A plate 0.01 thick (a unit square facing up at z = 0.01 and one facing down at
        // z = 0: closer than the points' spacing) and, apart, a unit square alone. Area-uniform
        // points put two thirds on the plate; counting its two sides as one crowd would leave
        // it half.
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let (mut candidates, mut normals) = (Vec::new(), Vec::new());
        for i in 0..1800 {
            let (z, up) = match i % 3 {
                0 => (0.01, 1.0),
                1 => (0.0, -1.0),
                _ => (5.0, 1.0),
            };
            candidates.push([rng.random(), rng.random(), z]);
            normals.push([0.0, 0.0, up]);
        }
        let kept = spread_evenly(&candidates, &normals, 450, 3.0);
        let on_plate = kept.iter().filter(|&&i| candidates[i][2] < 1.0).count();
        assert!(
            (280..=320).contains(&on_plate),
            "{on_plate} of 450 on the plate"
        );
    }

    #[test]
    fn deterministic_and_whole_when_nothing_is_to_remove() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let candidates: Vec<[f64; 3]> = (0..800)
            .map(|_| [rng.random(), rng.random(), rng.random()])
            .collect();
        let up = vec![[0.0, 0.0, 1.0]; candidates.len()];
        assert_eq!(
            spread_evenly(&candidates, &up, 200, 3.0),
            spread_evenly(&candidates, &up, 200, 3.0)
        );
        assert_eq!(spread_evenly(&candidates, &up, 800, 3.0).len(), 800);
        assert_eq!(
            spread_evenly(&candidates[..5], &up[..5], 9, 3.0),
            vec![0, 1, 2, 3, 4]
        );
    }
}
