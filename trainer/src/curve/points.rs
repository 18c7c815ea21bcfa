//! The validated input of the curve pipeline: scattered 2-D or 3-D points.

use std::collections::HashMap;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::error::{Error, Result};

use crate::geometry::vector::{bounds, distance_squared};

/// Fewest points the curve pipeline accepts: one cubic B-spline segment needs four.
pub const MIN_POINTS: usize = 4;

/// Most points the curve pipeline accepts; more is almost certainly a mistake and would
/// exhaust memory (the chain has four neurons per point by default).
pub const MAX_POINTS: usize = 2_000_000;

/// Two points closer than this fraction of the bounding-box diagonal are duplicates.
pub const DUPLICATE_TOLERANCE: f64 = 1e-9;

/// Scattered points, checked once: at least [`MIN_POINTS`], finite, pairwise distinct, with a
/// bounding box of positive size. 2-D points are stored with z = 0.
#[derive(Clone, Debug, PartialEq)]
pub struct CurvePoints {
    dimension: usize,
    points: Vec<[f64; 3]>,
    lower: [f64; 3],
    upper: [f64; 3],
}

impl CurvePoints {
    /// Validates plane points.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] as [`CurvePoints::new`].
    pub fn from_2d(points: &[[f64; 2]]) -> Result<Self> {
        Self::new(2, points.iter().map(|p| [p[0], p[1], 0.0]).collect())
    }

    /// Validates space points.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] as [`CurvePoints::new`].
    pub fn from_3d(points: &[[f64; 3]]) -> Result<Self> {
        Self::new(3, points.to_vec())
    }

    /// Validates `points` of the given `dimension` (2: every z must be 0; or 3).
    ///
    /// Duplicate detection hashes the points into cells of the duplicate tolerance and
    /// compares neighbouring cells only: O(n) expected time.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the problem: a dimension other than 2 or 3, fewer than
    /// [`MIN_POINTS`] or more than [`MAX_POINTS`] points, a non-finite coordinate, a nonzero z
    /// in 2-D, all points at one place (zero extent), or two points closer than
    /// [`DUPLICATE_TOLERANCE`] × the bounding-box diagonal.
    pub fn new(dimension: usize, points: Vec<[f64; 3]>) -> Result<Self> {
        if dimension != 2 && dimension != 3 {
            return Err(Error::invalid(format!(
                "curve points must be 2-D or 3-D, got dimension {dimension}"
            )));
        }
        if points.len() < MIN_POINTS {
            return Err(Error::invalid(format!(
                "a curve needs at least {MIN_POINTS} points, got {}",
                points.len()
            )));
        }
        if points.len() > MAX_POINTS {
            return Err(Error::invalid(format!(
                "{} curve points given, at most {MAX_POINTS} are supported",
                points.len()
            )));
        }
        for (i, p) in points.iter().enumerate() {
            if p.iter().any(|c| !c.is_finite()) {
                return Err(Error::invalid(format!(
                    "curve point {i} has a non-finite coordinate {p:?}"
                )));
            }
            if dimension == 2 && p[2] != 0.0 {
                return Err(Error::invalid(format!(
                    "curve point {i} is 2-D but has z = {}",
                    p[2]
                )));
            }
        }
        let (lower, upper) = bounds(&points);
        let diagonal = distance_squared(lower, upper).sqrt();
        if !(diagonal > 0.0 && diagonal.is_finite()) {
            return Err(Error::invalid(format!(
                "the {} curve points have zero extent (all at {lower:?}) or an overflowing one",
                points.len()
            )));
        }
        if let Some((a, b)) = find_duplicate(&points, lower, DUPLICATE_TOLERANCE * diagonal) {
            return Err(Error::invalid(format!(
                "curve points {a} and {b} are duplicates ({:?} and {:?}, closer than {:e} of \
                 the bounding-box diagonal)",
                points[a], points[b], DUPLICATE_TOLERANCE
            )));
        }
        Ok(CurvePoints {
            dimension,
            points,
            lower,
            upper,
        })
    }

    /// `count` of the points, drawn without replacement (seeded by `seed`) and kept in input
    /// order; all of them when there are no more than `count`.
    pub fn sample(&self, count: usize, seed: u64) -> CurvePoints {
        if self.points.len() <= count.max(MIN_POINTS) {
            return self.clone();
        }
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut picked =
            rand::seq::index::sample(&mut rng, self.points.len(), count.max(MIN_POINTS)).into_vec();
        picked.sort_unstable();
        let points: Vec<[f64; 3]> = picked.into_iter().map(|i| self.points[i]).collect();
        let (lower, upper) = bounds(&points);
        CurvePoints {
            dimension: self.dimension,
            points,
            lower,
            upper,
        }
    }

    /// 2 or 3.
    pub fn dimension(&self) -> usize {
        self.dimension
    }

    /// The points, in input order (z = 0 in 2-D).
    pub fn points(&self) -> &[[f64; 3]] {
        &self.points
    }

    /// Number of points (at least [`MIN_POINTS`]).
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Always false: validation rejects empty sets (present for API symmetry).
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Lower and upper corners of the bounding box.
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        (self.lower, self.upper)
    }

    /// Length of the bounding-box diagonal (positive).
    pub fn diagonal(&self) -> f64 {
        distance_squared(self.lower, self.upper).sqrt()
    }
}

/// The first pair (by the later index) of points closer than `tolerance`, if any.
fn find_duplicate(points: &[[f64; 3]], lower: [f64; 3], tolerance: f64) -> Option<(usize, usize)> {
    let cell = |p: [f64; 3]| [0, 1, 2].map(|k| ((p[k] - lower[k]) / tolerance).floor() as i64);
    let tolerance2 = tolerance * tolerance;
    let mut cells: HashMap<[i64; 3], Vec<usize>> = HashMap::with_capacity(points.len());
    for (i, &p) in points.iter().enumerate() {
        let c = cell(p);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let key = [c[0] + dx, c[1] + dy, c[2] + dz];
                    if let Some(found) = cells.get(&key)
                        && let Some(&j) = found
                            .iter()
                            .find(|&&j| distance_squared(points[j], p) < tolerance2)
                    {
                        return Some((j, i));
                    }
                }
            }
        }
        cells.entry(c).or_default().push(i);
    }
    None
}
