//! Noise across an ordered curve, and parameters that do not follow it.
//!
//! With noise wider than the point spacing an order zig-zags across the band of points, and
//! chord lengths along it grow with the zig-zag rather than with the curve: a least-squares
//! spline at those parameters snakes through the band. Smoothing each point with its order
//! neighbours (a local quadratic) over about the band's width gives a polyline along the
//! band's middle; chord lengths along that polyline follow the curve, and the points' spread
//! about it measures the noise. The fit then follows the band itself
//! ([`principal`](super::principal)).

use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

use super::fit::default_control_points;
use super::principal::Polyline;
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

/// The fewest noise deviations a band's control points lie apart along it. Closer control
/// points let a segment bend within the band, and ordering the points by their feet on the
/// fit locks such a bend in. On closed and open curves of our own at σ = 5 % of the
/// diagonal (1 000 points, 8 seeds), 6 deviations gave the least worst-case Hausdorff
/// distance of 4, 6 and 8 (within 0.3 % of the diagonal); 4 gave up to twice it.
const SEGMENT_NOISE: f64 = 6.0;
/// The fewest points per control point of a band: fewer let the fit follow the noise, more
/// leave out detail. At σ = 1 % (1 000 points), 30 gave a worst Hausdorff distance of
/// 0.42–0.65 % of the size on the sample ellipse and peanut (3 seeds) and 0.71–1.19 % on
/// curves of our own (8 seeds); 40 left the peanut's waist at 1.26 %, and 20 let smooth
/// curves follow the noise (up to 1.02 % where 40 gave 0.62 %).
const BAND_POINTS_PER_CONTROL: f64 = 30.0;

/// The control points of a band `length` long with noise `noise` across it: one per
/// [`SEGMENT_NOISE`] deviations and at most one per [`BAND_POINTS_PER_CONTROL`] points, at
/// least 8, at most the default for `n` points.
pub(crate) fn band_control_points(length: f64, noise: f64, n: usize, closed: bool) -> usize {
    let most = if closed { n } else { n + 2 };
    let count = (length / (SEGMENT_NOISE * noise))
        .min(n as f64 / BAND_POINTS_PER_CONTROL)
        .round();
    let count = if count.is_finite() { count as usize } else { 8 };
    count
        .max(8)
        .min(default_control_points(n, closed))
        .min(most)
}

/// The median of |N(0, σ)| over σ across a 2-D curve (0.674), or of a 2-D Gaussian's
/// radius across a 3-D one (1.177).
pub(crate) fn gaussian_median(dimension: usize) -> f64 {
    if dimension == 2 { 0.6745 } else { 1.1774 }
}

/// The `p`-quantile (0 < p < 1) of the distance of Gaussian noise of unit deviation from a
/// curve: of |N(0, 1)| across a 2-D curve, of a 2-D Gaussian's radius (Rayleigh) across a
/// 3-D one. The 2-D quantile is Abramowitz and Stegun's 26.2.23, within 4.5 × 10⁻⁴.
pub(crate) fn gaussian_quantile(p: f64, dimension: usize) -> f64 {
    let p = p.clamp(f64::MIN_POSITIVE, 1.0 - f64::EPSILON);
    if dimension != 2 {
        return (-2.0 * (1.0 - p).ln()).sqrt();
    }
    // The upper tail (1 − p)/2 of N(0, 1).
    let t = (-2.0 * ((1.0 - p) / 2.0).ln()).sqrt();
    t - (2.515_517 + 0.802_853 * t + 0.010_328 * t * t)
        / (1.0 + 1.432_788 * t + 0.189_269 * t * t + 0.001_308 * t * t * t)
}

/// How a noisy band was parametrized.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BandReport {
    /// The noise across the curve (a standard deviation), in the data's units: measured
    /// from the points' distances to the fit once it follows the band.
    pub noise: f64,
    /// The spacing along the curve: the fit's length ÷ the points.
    pub spacing: f64,
    /// Order neighbours the band's middle is smoothed over on each side.
    pub window: usize,
    /// The control points chosen: one per 6 noise deviations along the curve, at most one
    /// per 40 points.
    pub control_points: usize,
    /// Rounds of ordering the points by their feet on the fit and fitting again.
    #[serde(default)]
    pub rounds: usize,
}

/// Parameters for a noisy band and its report.
pub(crate) struct Band {
    pub(crate) parameters: Vec<f64>,
    pub(crate) report: BandReport,
}

/// When the noise across `ordered` (at least [`MIN_BAND_POINTS`]) exceeds the spacing along
/// it: the noise and spacing [`settle`] measures, chord-length parameters along the order
/// smoothed over ±[`BAND_REACH`] noise deviations, and [`band_control_points`] control
/// points in the report. `None` for data that noise does not scramble.
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
    let (noise, spacing, window) = settle(ordered, dimension, closed, noise, spacing);
    let parameters: Result<Vec<f64>> =
        super::fit::chord_length_parameters(&local_quadratic(ordered, closed, window), closed);
    let parameters = parameters.ok()?;
    let control_points = band_control_points(spacing * n as f64, noise, n, closed);
    Some(Band {
        parameters,
        report: BandReport {
            noise,
            spacing,
            window,
            control_points,
            rounds: 0,
        },
    })
}

/// The averaging window for noise `noise` at spacing `spacing` along the curve.
fn reach(noise: f64, spacing: f64, n: usize) -> usize {
    ((BAND_REACH * noise / spacing).ceil() as usize).clamp(1, (n / 4).max(1))
}

/// Each window of [`settle`]'s scan is this many times the last.
const SCAN_STEP: f64 = 1.25;

/// The noise, spacing and averaging window of a band, from a first `noise` and `spacing`.
///
/// The principal line of a few order neighbours sees a band many spacings wide as a blob
/// and underrates its noise (on an ellipse at σ = 5 % of the diagonal, by 3×). The spread of
/// the points about the band's middle does not, once the middle is smoothed over enough
/// order neighbours: over too few, a local quadratic follows the order's zig-zag across the
/// band and the spread is too small; over too many, it cannot follow the curve's bends and
/// the spread is too large; in between the spread stays about the same. The scan smooths
/// over windows growing by [`SCAN_STEP`] from the first estimate's down to 2 points and up
/// to a quarter of the points, and takes the spread where it changes least with the window
/// (the smallest log-log slope between neighbouring windows).
fn settle(
    ordered: &[[f64; 3]],
    dimension: usize,
    closed: bool,
    noise: f64,
    spacing: f64,
) -> (f64, f64, usize) {
    let n = ordered.len();
    let most = (n / 4).max(2);
    let mut scan: Vec<(usize, f64, f64)> = Vec::new();
    let mut window = 2usize;
    while window <= most {
        let middle = local_quadratic(ordered, closed, window);
        let length = polyline_length(&middle, closed) / n as f64;
        let spread = spread_about(ordered, &middle, closed, dimension);
        if spread.is_finite() && spread > 0.0 && length > 0.0 {
            scan.push((window, spread, length));
        }
        window = ((window as f64 * SCAN_STEP).ceil() as usize).max(window + 1);
    }
    let flattest = scan
        .windows(2)
        .map(|pair| {
            let slope = (pair[1].1 / pair[0].1).ln() / (pair[1].0 as f64 / pair[0].0 as f64).ln();
            (slope, pair[0])
        })
        .min_by(|a, b| a.0.total_cmp(&b.0));
    match flattest {
        Some((_, (_, noise, spacing))) => (noise, spacing, reach(noise, spacing, n)),
        None => (noise, spacing, reach(noise, spacing, n)),
    }
}

/// Most points whose distance [`spread_about`] measures (evenly spaced in the order).
const SPREAD_SAMPLES: usize = 2000;

/// The standard deviation of `ordered` about the polyline `middle`: each point's distance
/// from it (at most [`SPREAD_SAMPLES`] points, evenly spaced in the order), their median
/// scaled for Gaussian noise as in [`noise_across`].
fn spread_about(ordered: &[[f64; 3]], middle: &[[f64; 3]], closed: bool, dimension: usize) -> f64 {
    let n = ordered.len();
    let stride = n.div_ceil(SPREAD_SAMPLES).max(1);
    let mut line = middle.to_vec();
    if closed {
        line.push(middle[0]);
    }
    let line = Polyline::new(line, closed);
    let mut distances: Vec<f64> = (0..n)
        .step_by(stride)
        .map(|i| line.foot(ordered[i], 0.0).1)
        .collect();
    median(&mut distances) / gaussian_median(dimension)
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
    median(&mut distances) / gaussian_median(dimension)
}

/// `ordered`, each point replaced by the value at its place of a quadratic in the order
/// index fitted to its order neighbours within `w` (a Savitzky–Golay smoothing). A plain
/// average over a window that reaches around a bend cuts inside it, by about κL²/6 for a
/// window of half-length L at curvature κ; a quadratic follows a bend and averages the noise
/// almost as well (its variance is 9/4 of the average's).
///
/// Near an open curve's ends the window shrinks to stay centred on the point.
pub(crate) fn local_quadratic(ordered: &[[f64; 3]], closed: bool, w: usize) -> Vec<[f64; 3]> {
    let n = ordered.len();
    let w = w.min((n - 1) / 2);
    // Prefix sums of x_j, j·x_j and j²·x_j over the points, extended by w on either side
    // when closed (index j runs from −w).
    let offset = if closed { w } else { 0 };
    let len = n + 2 * offset;
    let at = |j: usize| ordered[(j + n - offset) % n];
    let mut sums = vec![[[0.0; 3]; 3]; len + 1];
    for j in 0..len {
        let x = at(j);
        let d = j as f64;
        for k in 0..3 {
            sums[j + 1][0][k] = sums[j][0][k] + x[k];
            sums[j + 1][1][k] = sums[j][1][k] + d * x[k];
            sums[j + 1][2][k] = sums[j][2][k] + d * d * x[k];
        }
    }
    (0..n)
        .map(|i| {
            let half = if closed { w } else { w.min(i).min(n - 1 - i) };
            if half == 0 {
                return ordered[i];
            }
            let centre = i + offset;
            let (lo, hi) = (centre - half, centre + half + 1);
            let h = half as f64;
            // Σd⁰, Σd², Σd⁴ over d = −h..h.
            let s0 = 2.0 * h + 1.0;
            let s2 = h * (h + 1.0) * (2.0 * h + 1.0) / 3.0;
            let s4 = h * (h + 1.0) * (2.0 * h + 1.0) * (3.0 * h * h + 3.0 * h - 1.0) / 15.0;
            let c = centre as f64;
            [0, 1, 2].map(|k| {
                let sum = sums[hi][0][k] - sums[lo][0][k];
                let first = sums[hi][1][k] - sums[lo][1][k];
                let second = sums[hi][2][k] - sums[lo][2][k];
                // Σ(j − c)²x_j from the prefix sums.
                let squares = second - 2.0 * c * first + c * c * sum;
                (s4 * sum - s2 * squares) / (s0 * s4 - s2 * s2)
            })
        })
        .collect()
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

#[cfg(test)]
mod tests {
    use super::{gaussian_median, gaussian_quantile};

    /// Quantiles of |N(0, 1)| and of the Rayleigh distribution (tables; exact for the
    /// Rayleigh's closed form), within the stated 4.5 × 10⁻⁴.
    #[test]
    fn gaussian_quantiles_match_their_tables() {
        let vectors = [
            (0.5, 2, 0.674_490),
            (0.9, 2, 1.644_854),
            (0.99, 2, 2.575_829),
            (0.1, 2, 0.125_661),
            (0.5, 3, 1.177_410),
            (0.9, 3, 2.145_966),
            (0.1, 3, 0.459_044),
        ];
        for (p, dimension, expected) in vectors {
            let got = gaussian_quantile(p, dimension);
            assert!((got - expected).abs() <= 4.5e-4, "{p} {dimension}: {got}");
        }
        for dimension in [2, 3] {
            let median = gaussian_quantile(0.5, dimension);
            assert!((median - gaussian_median(dimension)).abs() <= 4.5e-4);
        }
    }
}
