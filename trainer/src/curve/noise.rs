//! Noise across an ordered curve, and parameters that do not follow it.
//!
//! With noise wider than the point spacing an order zig-zags across the band of points, and
//! chord lengths along it grow with the zig-zag rather than with the curve: a least-squares
//! spline at those parameters snakes through the band. Averaging each point with its order
//! neighbours over about the band's width gives a polyline along the band's middle; chord
//! lengths along that polyline follow the curve.

use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

use super::fit::default_control_points;
use crate::error::Result;
use crate::fidelity::median;
use crate::geometry::vector::{distance, dot, sub};

/// Order neighbours on each side that the noise estimate fits a line to.
const NOISE_WINDOW: usize = 5;
/// The band counts as noisy when the noise across it exceeds the spacing along it times this:
/// the order then zig-zags.
const NOISY: f64 = 1.0;
/// Fewest points for which the noise is estimated: below it the windows span so much of the
/// curve that its bends pass for noise.
const MIN_BAND_POINTS: usize = 100;
/// The averaging window reaches this many noise deviations along the curve on each side (on
/// the sample curves at 1 % and 5 % noise, 4 fits closer than 2 or 3).
const BAND_REACH: f64 = 4.0;

/// How a noisy band was parametrized.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BandReport {
    /// The noise across the curve (a standard deviation), in the data's units.
    pub noise: f64,
    /// The spacing along the curve (the averaged polyline's length ÷ the points).
    pub spacing: f64,
    /// Order neighbours averaged on each side.
    pub window: usize,
    /// The control points chosen: about one per averaging window.
    pub control_points: usize,
}

/// Parameters for a noisy band and its report.
pub(crate) struct Band {
    pub(crate) parameters: Vec<f64>,
    pub(crate) control_points: usize,
    pub(crate) report: BandReport,
}

/// When the noise across `ordered` (at least [`MIN_BAND_POINTS`]) exceeds the spacing along it: chord-length
/// parameters along the order averaged over ±4 noise deviations, and one control point per
/// such window (fewer than the default). `None` for data that noise does not scramble.
pub(crate) fn band_parameters(
    ordered: &[[f64; 3]],
    dimension: usize,
    closed: bool,
) -> Option<Band> {
    let n = ordered.len();
    if n < MIN_BAND_POINTS {
        return None;
    }
    let noise = noise_across(ordered, dimension, closed, NOISE_WINDOW);
    let rough = moving_average(ordered, closed, NOISE_WINDOW);
    let spacing = polyline_length(&rough, closed) / n as f64;
    if noise.is_nan() || noise <= NOISY * spacing {
        return None;
    }
    let window = ((BAND_REACH * noise / spacing).ceil() as usize).clamp(1, n / 4);
    let parameters: Result<Vec<f64>> =
        super::fit::chord_length_parameters(&moving_average(ordered, closed, window), closed);
    let parameters = parameters.ok()?;
    let most = if closed { n } else { n + 2 };
    let control_points = (n / (2 * window + 1))
        .max(8)
        .min(default_control_points(n, closed))
        .min(most);
    Some(Band {
        parameters,
        control_points,
        report: BandReport {
            noise,
            spacing,
            window,
            control_points,
        },
    })
}

fn polyline_length(points: &[[f64; 3]], closed: bool) -> f64 {
    let n = points.len();
    (0..if closed { n } else { n - 1 })
        .map(|i| distance(points[i], points[(i + 1) % n]))
        .sum()
}

/// The order neighbours of point `i` within `w` of it (wrapping when closed).
fn window(n: usize, closed: bool, i: usize, w: usize) -> impl Iterator<Item = usize> {
    let w = w.min((n - 1) / 2);
    let (lo, hi) = if closed {
        (i + n - w, i + n + w)
    } else {
        let half = w.min(i).min(n - 1 - i);
        (i - half + n, i + half + n)
    };
    (lo..=hi).map(move |j| j % n)
}

/// The standard deviation of the noise across the curve: the median distance of each point
/// from the principal line of its 2w + 1 order neighbours, scaled for Gaussian noise in the
/// 1 (2-D) or 2 (3-D) directions across the curve.
pub(crate) fn noise_across(ordered: &[[f64; 3]], dimension: usize, closed: bool, w: usize) -> f64 {
    let n = ordered.len();
    let mut distances: Vec<f64> = (0..n)
        .map(|i| {
            let members: Vec<[f64; 3]> = window(n, closed, i, w).map(|j| ordered[j]).collect();
            let count = members.len() as f64;
            let mut centre = [0.0; 3];
            for p in &members {
                for k in 0..3 {
                    centre[k] += p[k] / count;
                }
            }
            let mut covariance = [[0.0; 3]; 3];
            for p in &members {
                let d = sub(*p, centre);
                for a in 0..3 {
                    for b in 0..3 {
                        covariance[a][b] += d[a] * d[b];
                    }
                }
            }
            // The principal direction by power iteration from the window's chord.
            let mut axis = sub(members[members.len() - 1], members[0]);
            for _ in 0..20 {
                let next = [0, 1, 2].map(|a| dot(covariance[a], axis));
                let norm = dot(next, next).sqrt();
                if !(norm > 0.0 && norm.is_finite()) {
                    break;
                }
                axis = next.map(|v| v / norm);
            }
            // Across the line, as a quadratic in the position along it: the curve's own
            // bend is not noise.
            let norm2 = dot(axis, axis).max(f64::MIN_POSITIVE);
            let split = |p: [f64; 3]| {
                let d = sub(p, centre);
                let t = dot(d, axis) / norm2.sqrt();
                (t, sub(d, axis.map(|v| v * dot(d, axis) / norm2)))
            };
            let mut normal = [[0.0; 3]; 3];
            let mut right = [[0.0; 3]; 3];
            for &p in &members {
                let (t, r) = split(p);
                let basis = [1.0, t, t * t];
                for a in 0..3 {
                    for b in 0..3 {
                        normal[a][b] += basis[a] * basis[b];
                    }
                    for k in 0..3 {
                        right[k][a] += basis[a] * r[k];
                    }
                }
            }
            let (t, r) = split(ordered[i]);
            let Some(fits) = right
                .iter()
                .map(|b| solve3(normal, *b))
                .collect::<Option<Vec<_>>>()
            else {
                return dot(r, r).sqrt();
            };
            let residual =
                [0, 1, 2].map(|k| r[k] - (fits[k][0] + fits[k][1] * t + fits[k][2] * t * t));
            // Three fitted coefficients take their share of the window's spread.
            let dof = (count / (count - 3.0).max(1.0)).sqrt();
            dot(residual, residual).sqrt() * dof
        })
        .collect();
    // Median of |N(0, σ)| is 0.674σ; of a 2-D Gaussian's radius, 1.177σ.
    let scale = if dimension == 2 { 0.6745 } else { 1.1774 };
    median(&mut distances) / scale
}

/// `ordered`, each point averaged with its order neighbours within `w`.
pub(crate) fn moving_average(ordered: &[[f64; 3]], closed: bool, w: usize) -> Vec<[f64; 3]> {
    let n = ordered.len();
    (0..n)
        .map(|i| {
            let mut sum = [0.0; 3];
            let mut count = 0.0;
            for j in window(n, closed, i, w) {
                for k in 0..3 {
                    sum[k] += ordered[j][k];
                }
                count += 1.0;
            }
            sum.map(|v| v / count)
        })
        .collect()
}

/// Solves the 3 × 3 system `a x = b`; `None` when it is singular.
fn solve3(a: [[f64; 3]; 3], b: [f64; 3]) -> Option<[f64; 3]> {
    let x = Matrix3::from_fn(|i, j| a[i][j])
        .lu()
        .solve(&Vector3::from(b))?;
    x.iter().all(|v| v.is_finite()).then(|| [x[0], x[1], x[2]])
}
