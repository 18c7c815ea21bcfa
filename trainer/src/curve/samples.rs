//! Scattered test data on known curves, with the truth needed to score a reconstruction.
//!
//! A sample draws `count` points at stratified arc-length positions (one per stratum of
//! length L/count, jittered inside it), adds isotropic Gaussian noise (scaled to the
//! spacing L/count) and shuffles them. It
//! also returns each point's true parameter (its arc-length fraction before the noise) and a
//! dense polyline of the true curve for Hausdorff distances.

use std::f64::consts::{PI, TAU};

use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

use super::kohonen::Topology;
use super::points::{CurvePoints, MAX_POINTS, MIN_POINTS};
use crate::geometry::vector::{bounds, distance};

/// Vertices of the true-curve polyline (its chords deviate from the curve by < 1e-6 of its
/// size).
pub const TRUTH_VERTICES: usize = 8192;

/// The test curves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum SampleCurve {
    /// Closed, 2-D: the ellipse (cos θ, 0.6 sin θ).
    Ellipse,
    /// Open, 2-D: an Archimedean spiral of two turns, radius 0.25 → 1 (arms 0.375 apart).
    Spiral,
    /// Closed, 2-D: a Cassini oval just outside the lemniscate (a = 1, b² = 1 + 0.075²): a
    /// figure-eight that does not cross itself; its branches come within 0.15 of each other
    /// at the waist (the curve is 2.8 wide).
    Peanut,
    /// Closed, 3-D: the trefoil knot (sin t + 2 sin 2t, cos t − 2 cos 2t, −sin 3t).
    Trefoil,
}

impl SampleCurve {
    /// All curves.
    pub const ALL: [SampleCurve; 4] = [
        SampleCurve::Ellipse,
        SampleCurve::Spiral,
        SampleCurve::Peanut,
        SampleCurve::Trefoil,
    ];

    /// Whether the curve is closed.
    pub fn closed(self) -> bool {
        !matches!(self, SampleCurve::Spiral)
    }

    /// The chain topology that matches.
    pub fn topology(self) -> Topology {
        if self.closed() {
            Topology::Closed
        } else {
            Topology::Open
        }
    }

    /// 2 or 3.
    pub fn dimension(self) -> usize {
        if self == SampleCurve::Trefoil { 3 } else { 2 }
    }

    /// The curve at raw parameter s ∈ [0, 1] (not arc length).
    pub fn at(self, s: f64) -> [f64; 3] {
        match self {
            SampleCurve::Ellipse => [(TAU * s).cos(), 0.6 * (TAU * s).sin(), 0.0],
            SampleCurve::Spiral => {
                let r = 0.25 + 0.75 * s;
                let theta = 2.0 * TAU * s;
                [r * theta.cos(), r * theta.sin(), 0.0]
            }
            SampleCurve::Peanut => {
                let b2: f64 = 1.0 + 0.075 * 0.075;
                let theta = TAU * s;
                let (c2, s2) = ((2.0 * theta).cos(), (2.0 * theta).sin());
                let r = (c2 + (b2 * b2 - s2 * s2).sqrt()).sqrt();
                [r * theta.cos(), r * theta.sin(), 0.0]
            }
            SampleCurve::Trefoil => {
                let t = TAU * s;
                [
                    t.sin() + 2.0 * (2.0 * t).sin(),
                    t.cos() - 2.0 * (2.0 * t).cos(),
                    -(3.0 * t).sin(),
                ]
            }
        }
    }
}

/// Settings of [`sample_curve`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SampleOptions {
    /// Number of points (200).
    pub count: usize,
    /// Standard deviation of the noise per coordinate, × the mean spacing L/count of the
    /// points along the curve (0.1: noise well below the spacing, so the true order stays
    /// well defined at every count).
    pub noise: f64,
    /// Jitter of each point inside its arc-length stratum, 0 (evenly spaced) … 1 (uniform
    /// in the stratum) (0.5).
    pub jitter: f64,
    /// Seed (0).
    pub seed: u64,
}

impl Default for SampleOptions {
    fn default() -> Self {
        SampleOptions {
            count: 200,
            noise: 0.1,
            jitter: 0.5,
            seed: 0,
        }
    }
}

/// Scattered points on a known curve.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CurveSample {
    /// Which curve.
    pub curve: SampleCurve,
    /// The points, shuffled and noisy (z = 0 in 2-D).
    pub points: Vec<[f64; 3]>,
    /// Each point's true arc-length fraction in [0, 1] (before the noise).
    pub parameters: Vec<f64>,
    /// The true curve as a polyline of [`TRUTH_VERTICES`] vertices (+1 closing vertex
    /// equal to the first for a closed curve).
    pub truth: Vec<[f64; 3]>,
    /// The true curve's bounding-box diagonal: the unit for relative distances.
    pub size: f64,
}

impl CurveSample {
    /// The points, validated for the pipeline.
    ///
    /// # Errors
    /// As [`CurvePoints::new`] (e.g. two points closer than the duplicate tolerance).
    pub fn curve_points(&self) -> Result<CurvePoints> {
        CurvePoints::new(self.curve.dimension(), self.points.clone())
    }
}

/// Draws a sample of `curve`. Deterministic for a seed.
///
/// # Errors
/// [`Error::InvalidInput`] for a count outside [`MIN_POINTS`]..=[`MAX_POINTS`], or a noise
/// or jitter that is negative, non-finite or (jitter) above 1.
pub fn sample_curve(curve: SampleCurve, options: &SampleOptions) -> Result<CurveSample> {
    let n = options.count;
    if !(MIN_POINTS..=MAX_POINTS).contains(&n) {
        return Err(Error::invalid(format!(
            "a curve sample needs {MIN_POINTS}..={MAX_POINTS} points, got {n}"
        )));
    }
    if !(options.noise.is_finite() && options.noise >= 0.0) {
        return Err(Error::invalid(format!(
            "the sample noise must be finite and ≥ 0, got {}",
            options.noise
        )));
    }
    if !(0.0..=1.0).contains(&options.jitter) {
        return Err(Error::invalid(format!(
            "the sample jitter must lie in [0, 1], got {}",
            options.jitter
        )));
    }
    let closed = curve.closed();
    let mut truth: Vec<[f64; 3]> = (0..=TRUTH_VERTICES)
        .map(|k| curve.at(k as f64 / TRUTH_VERTICES as f64))
        .collect();
    let mut arc = vec![0.0; truth.len()];
    for k in 1..truth.len() {
        arc[k] = arc[k - 1] + distance(truth[k - 1], truth[k]);
    }
    let length = arc[truth.len() - 1];
    let (lower, upper) = bounds(&truth);
    let size = distance(lower, upper);
    if closed {
        // The closing vertex is exactly the first.
        truth[TRUTH_VERTICES] = truth[0];
    }

    let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
    let sigma = options.noise * length / n as f64;
    let dimension = curve.dimension();
    let mut samples: Vec<([f64; 3], f64)> = (0..n)
        .map(|k| {
            let jitter = options.jitter * (rng.random::<f64>() - 0.5);
            let fraction = if closed {
                (k as f64 + 0.5 + jitter) / n as f64
            } else {
                ((k as f64 + jitter) / (n - 1) as f64).clamp(0.0, 1.0)
            };
            let mut p = point_at_arc_length(curve, &arc, fraction * length);
            for c in p.iter_mut().take(dimension) {
                *c += sigma * gaussian(&mut rng);
            }
            (p, fraction)
        })
        .collect();
    samples.shuffle(&mut rng);
    let (points, parameters) = samples.into_iter().unzip();
    Ok(CurveSample {
        curve,
        points,
        parameters,
        truth,
        size,
    })
}

/// The curve point at arc length `target`: the raw parameter interpolated on the dense
/// arc-length table, then evaluated exactly.
fn point_at_arc_length(curve: SampleCurve, arc: &[f64], target: f64) -> [f64; 3] {
    let k = arc.partition_point(|&a| a < target).clamp(1, arc.len() - 1);
    let span = arc[k] - arc[k - 1];
    let local = if span > 0.0 {
        ((target - arc[k - 1]) / span).clamp(0.0, 1.0)
    } else {
        0.0
    };
    curve.at((k as f64 - 1.0 + local) / (arc.len() - 1) as f64)
}

/// A standard normal deviate (Box–Muller).
pub(crate) fn gaussian(rng: &mut ChaCha8Rng) -> f64 {
    let u1 = 1.0 - rng.random::<f64>(); // (0, 1]
    let u2 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (PI * 2.0 * u2).cos()
}
