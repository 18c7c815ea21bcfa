//! B-spline curves through ordered points Q₀ … Q_{n−1}: a least-squares approximation and
//! an interpolation.
//!
//! Open curves carry phantom end control points, P₀ = 2P₁ − P₂ and P_{K−1} = 2P_{K−2} −
//! P_{K−3}: then C(0) = P₁ and C(1) = P_{K−2} (and C″ = 0 there, the natural end
//! condition), and both fits pin P₁ = Q₀ and P_{K−2} = Q_{n−1}, so the curve starts and ends
//! at the data ends.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

use super::basis::{cubic_basis, locate, uniform_basis};
use super::corners::{Corner, find_corners};
use neurosurf_core::curve::DEFAULT_CURVE_POINTS;

use super::least_squares::{Affine, NormalEquations};
use super::points::MIN_POINTS;
use super::spline::{BSplineCurve, MIN_CONTROL_POINTS, check_degree};
use super::tridiagonal::{solve_cyclic, solve_tridiagonal};
use crate::geometry::vector::distance;

/// Settings of [`approximate`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ApproximationOptions {
    /// K, the number of control points including an open curve's two phantoms; `None`:
    /// max(n/5, 8), at most n (closed) or n + 2 (open).
    pub control_points: Option<usize>,
    /// Weight λ of the second-difference penalty λ · Σ |P_{k−1} − 2P_k + P_{k+1}|², relative
    /// to the mean diagonal of the data term (1e-6: only keeps spans without data
    /// well-posed; raise it to smooth).
    pub smoothing: f64,
    /// When set (and [`Self::control_points`] is not), the fewest control points whose fit
    /// keeps every point within this distance of its place on the curve (data units).
    #[serde(default)]
    pub tolerance: Option<f64>,
    /// Keep the corners [`find_corners`] detects sharp: each falls on a knot where three
    /// control points coincide (on by default).
    #[serde(default = "keep_corners")]
    pub corners: bool,
    /// The polynomial degree, 2 to 5 (3 by default).
    #[serde(default = "cubic")]
    pub degree: usize,
    /// Where an open curve ends: at the first and last ordered point (the default), or where
    /// the least squares places them (for a band of noise, whose first and last points lie
    /// anywhere across it).
    #[serde(default)]
    pub ends: Ends,
}

/// Where an open curve's ends go.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Ends {
    /// C(0) = Q₀ and C(1) = Q_{n−1}.
    #[default]
    AtData,
    /// C(0) and C(1) are unknowns of the fit like any control point (the natural end
    /// condition, C″ = 0, stays: with the ends free as well, a few noisy points near an end
    /// swing the last segment).
    Fitted,
}

fn keep_corners() -> bool {
    true
}

fn cubic() -> usize {
    3
}

impl Default for ApproximationOptions {
    fn default() -> Self {
        ApproximationOptions {
            control_points: None,
            smoothing: 1e-6,
            tolerance: None,
            corners: true,
            degree: 3,
            ends: Ends::AtData,
        }
    }
}

/// A least-squares fit and how well it matches the data.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Approximation {
    /// The curve.
    pub curve: BSplineCurve,
    /// The chord-length parameter tⱼ ∈ [0, 1] of every data point.
    pub parameters: Vec<f64>,
    /// √(mean |C(tⱼ) − Qⱼ|²).
    pub rms_residual: f64,
    /// max |C(tⱼ) − Qⱼ|.
    pub max_residual: f64,
    /// The ordered points kept as sharp corners (indices, in order).
    #[serde(default)]
    pub corners: Vec<usize>,
    /// Where the curve has each of [`Self::corners`]: the arms' intersection, or where the
    /// fit placed it.
    #[serde(default)]
    pub corner_points: Vec<[f64; 3]>,
}

/// Chord-length parameters: t₀ = 0, tⱼ = Σ_{i<j} |Q_{i+1} − Q_i| / L with L the polygon's
/// length (closed: including the closing chord, so tⱼ < 1).
///
/// # Errors
/// [`Error::InvalidInput`] when the polygon has zero length.
pub fn chord_length_parameters(ordered: &[[f64; 3]], closed: bool) -> Result<Vec<f64>> {
    let mut t = Vec::with_capacity(ordered.len());
    let mut length = 0.0;
    for (j, &q) in ordered.iter().enumerate() {
        if j > 0 {
            length += distance(ordered[j - 1], q);
        }
        t.push(length);
    }
    if closed && let (Some(&first), Some(&last)) = (ordered.first(), ordered.last()) {
        length += distance(last, first);
    }
    if !(length > 0.0 && length.is_finite()) {
        return Err(Error::invalid(format!(
            "the ordered points' polygon has length {length}: no chord-length parameters"
        )));
    }
    Ok(t.into_iter().map(|l| l / length).collect())
}

/// The control points an approximation of `n` points gets by default: n/5, at least 8, at
/// most what the spline can have (n + 2 open, n closed) and what the core holds
/// ([`DEFAULT_CURVE_POINTS`]).
pub fn default_control_points(n: usize, closed: bool) -> usize {
    let most = if closed { n } else { n + 2 };
    (n / 5).max(8).min(most).min(DEFAULT_CURVE_POINTS)
}

/// Refuses, before any training, a curve the core could not hold: `control` control points
/// asked for with `--control`, or the n + 2 (open) or n (closed) of an interpolation through
/// `n` points.
///
/// # Errors
/// [`Error::InvalidInput`] naming the count, the core's limit and what to change.
pub fn check_curve_capacity(
    n: usize,
    closed: bool,
    control: Option<usize>,
    interpolate: bool,
) -> Result<()> {
    let limit = DEFAULT_CURVE_POINTS;
    if let Some(k) = control.filter(|&k| k > limit) {
        return Err(Error::invalid(format!(
            "--control {k}: the core holds at most {limit} control points; give --control \
             {limit} or fewer"
        )));
    }
    let through = if closed { n } else { n + 2 };
    if interpolate && through > limit {
        return Err(Error::invalid(format!(
            "--interpolate through {n} points needs {through} control points, but the core \
             holds at most {limit}; approximate instead (without --interpolate, --control \
             {limit} or fewer) or give at most {} points",
            if closed { limit } else { limit - 2 }
        )));
    }
    Ok(())
}

/// Steps on either side of a step that [`density_parameters`] averages into the local
/// spacing it divides that step by.
pub const DENSITY_WINDOW: usize = 16;

/// Parameters that follow the data's density: chord length measured in local spacings. Each
/// step |Q_{j+1} − Q_j| counts divided by the mean step over the [`DENSITY_WINDOW`] steps on
/// either side, so that evenly spaced points get chord-length parameters and every stretch
/// gets parameter range (and with uniform knots, control points) in proportion to its points:
/// a stretch sampled ten times more sparsely than the rest gets a tenth of the knots per unit
/// length instead of segments with one point or none, where a uniform spline swings freely.
///
/// # Errors
/// [`Error::InvalidInput`] where the polygon has no length.
pub fn density_parameters(ordered: &[[f64; 3]], closed: bool) -> Result<Vec<f64>> {
    let n = ordered.len();
    let steps: Vec<f64> = (0..if closed { n } else { n.saturating_sub(1) })
        .map(|j| distance(ordered[j], ordered[(j + 1) % n]))
        .collect();
    let m = steps.len();
    let total: f64 = steps.iter().sum();
    if !(total > 0.0 && total.is_finite()) {
        return Err(Error::invalid(format!(
            "the ordered points' polygon has length {total}: no parameters"
        )));
    }
    // Running sums give each window's mean in O(1).
    let mut prefix = vec![0.0; m + 1];
    for (j, &s) in steps.iter().enumerate() {
        prefix[j + 1] = prefix[j] + s;
    }
    let w = DENSITY_WINDOW.min(m.saturating_sub(1) / 2);
    let floor = 1e-9 * total / m as f64;
    let local = |j: usize| -> f64 {
        let sum = if closed {
            let (lo, hi) = (j as isize - w as isize, j + w + 1);
            let wrapped = |a: isize| -> f64 {
                let turns = a.div_euclid(m as isize) as f64;
                turns * total + prefix[a.rem_euclid(m as isize) as usize]
            };
            wrapped(hi as isize) - wrapped(lo)
        } else {
            let (lo, hi) = (j.saturating_sub(w), (j + w + 1).min(m));
            (prefix[hi] - prefix[lo]) * (2 * w + 1) as f64 / (hi - lo) as f64
        };
        (sum / (2 * w + 1) as f64).max(floor)
    };
    let increments: Vec<f64> = (0..m).map(|j| steps[j] / local(j)).collect();
    let length: f64 = increments.iter().sum();
    let mut t = Vec::with_capacity(n);
    let mut at = 0.0;
    for j in 0..n {
        t.push(at / length);
        if j < m {
            at += increments[j];
        }
    }
    Ok(t)
}

/// Least-squares approximation of `ordered` (dimension 2 or 3) by a uniform cubic B-spline
/// with K control points, at parameters that follow the data's density
/// ([`density_parameters`]).
/// Open: the ends are interpolated exactly (phantoms, see the module docs), the remaining
/// K − 4 control points minimize Σ |C(tⱼ) − Qⱼ|² + penalty. Closed: all K are free.
/// Cost O(n + K³).
///
/// # Errors
/// [`Error::InvalidInput`] for fewer than 4 or non-finite points, a bad dimension, K out of
/// range (open: 4 ≤ K ≤ n + 2; closed: 4 ≤ K ≤ n), a negative or non-finite smoothing, or
/// data that leaves the system singular.
pub fn approximate(
    ordered: &[[f64; 3]],
    dimension: usize,
    closed: bool,
    options: &ApproximationOptions,
) -> Result<Approximation> {
    check_ordered(ordered, dimension)?;
    check_degree(options.degree)?;
    let n = ordered.len();
    let (fewest, most) = control_range(n, closed, options.degree);
    let k = options
        .control_points
        .unwrap_or_else(|| default_control_points(n, closed).max(fewest));
    if !(fewest..=most).contains(&k) {
        return Err(Error::invalid(format!(
            "{k} control points requested for {n} {} points at degree {}: use {fewest}..={most}",
            if closed { "closed" } else { "open" },
            options.degree
        )));
    }
    if !(options.smoothing.is_finite() && options.smoothing >= 0.0) {
        return Err(Error::invalid(format!(
            "the smoothing weight must be finite and ≥ 0, got {}",
            options.smoothing
        )));
    }
    let parameters = density_parameters(ordered, closed)?;
    match (options.control_points, options.tolerance) {
        (None, Some(tolerance)) => {
            approximate_within(ordered, parameters, dimension, closed, tolerance, options)
        }
        _ => approximate_at(ordered, parameters, dimension, closed, k, options),
    }
}

/// [`approximate_at`] with the fewest control points K (between 8, or fewer points, and
/// the core's limit) whose fit has a largest residual within `tolerance`, by bisection over
/// K (the residual falls with K, though not strictly, so the K found meets the tolerance and
/// is the least within a few).
///
/// # Errors
/// [`Error::InvalidInput`] for a tolerance that is not positive and finite, or one that even
/// the most control points miss (naming the residual they reach).
pub(crate) fn approximate_within(
    ordered: &[[f64; 3]],
    parameters: Vec<f64>,
    dimension: usize,
    closed: bool,
    tolerance: f64,
    options: &ApproximationOptions,
) -> Result<Approximation> {
    if !(tolerance.is_finite() && tolerance > 0.0) {
        return Err(Error::invalid(format!(
            "--tolerance {tolerance}: give a positive distance in the points' units"
        )));
    }
    let n = ordered.len();
    let (least, most) = control_range(n, closed, options.degree);
    let most = most.min(DEFAULT_CURVE_POINTS);
    let fewest = least.max(8).min(most);
    // The corners depend on the points alone: found once for every K tried.
    let detected = detect(ordered, closed, options);
    let shape = (dimension, closed);
    let fit =
        |k: usize| fit_with_corners(ordered, parameters.clone(), shape, k, options, &detected);
    let meets = |a: &Approximation| a.max_residual <= tolerance;
    let best = match fit(most) {
        Ok(a) if meets(&a) => a,
        Ok(a) => {
            return Err(Error::invalid(format!(
                "--tolerance {tolerance:e}: even {most} control points leave a point {:.3e} \
                 from the curve; give a larger tolerance, or --interpolate to pass through \
                 every point",
                a.max_residual
            )));
        }
        Err(e) => return Err(e),
    };
    // The least K known to meet the tolerance, and one known not to (or below the range).
    let (mut low, mut high, mut found) = (fewest - 1, most, best);
    while high - low > 1 {
        let mid = low + (high - low) / 2;
        match fit(mid) {
            Ok(a) if meets(&a) => {
                high = mid;
                found = a;
            }
            _ => low = mid,
        }
    }
    Ok(found)
}

/// [`approximate`] with K = `k` at the given non-decreasing parameters in [0, 1].
///
/// With [`ApproximationOptions::corners`], each corner [`find_corners`] detects is kept
/// sharp (three coinciding control points at a knot), and the parameters then move to their
/// feet on the curve a few times. Residuals cannot decide whether a corner is real: a
/// rounded corner passes as close to the points as a sharp one when none lies at its tip,
/// so the decision is the detector's.
pub(crate) fn approximate_at(
    ordered: &[[f64; 3]],
    parameters: Vec<f64>,
    dimension: usize,
    closed: bool,
    k: usize,
    options: &ApproximationOptions,
) -> Result<Approximation> {
    let detected = detect(ordered, closed, options);
    fit_with_corners(
        ordered,
        parameters,
        (dimension, closed),
        k,
        options,
        &detected,
    )
}

/// The corners of `ordered` when `options` keeps corners, else none.
fn detect(ordered: &[[f64; 3]], closed: bool, options: &ApproximationOptions) -> Vec<Corner> {
    if options.corners {
        find_corners(ordered, closed)
    } else {
        Vec::new()
    }
}

/// [`approximate_at`] with the corners already `detected`.
fn fit_with_corners(
    ordered: &[[f64; 3]],
    parameters: Vec<f64>,
    (dimension, closed): (usize, bool),
    k: usize,
    options: &ApproximationOptions,
    detected: &[Corner],
) -> Result<Approximation> {
    let degree = options.degree;
    let segments = if closed { k } else { k - degree };
    let fit = |corners: &[KnotCorner], corrections: usize| {
        let shape = (dimension, closed, k);
        fit_at(
            ordered,
            parameters.clone(),
            shape,
            options,
            corners,
            corrections,
        )
    };
    let corners = corner_knots(detected, &parameters, segments, closed, degree);
    let smooth = fit(&[], 0)?;
    if corners.is_empty() {
        return Ok(smooth);
    }
    // A safety net, not the test: corners that leave the fit far worse than the smooth one
    // (or singular) were not corners the control points can hold.
    let sharp = match fit(&corners, PARAMETER_CORRECTIONS) {
        Ok(sharp) if sharp.rms_residual <= WORSE_WITH_CORNERS * smooth.rms_residual => sharp,
        _ => return Ok(smooth),
    };
    // A corner fits its own points better than a rounded one does; one that fits them worse
    // cuts across a bend that sparse points made look like two straight arms.
    let reach =
        (corrected_segments(degree) * ordered.len() as f64 / segments as f64).ceil() as usize;
    let near = |a: &Approximation, c: &KnotCorner| local_rms(a, ordered, c.index, reach, closed);
    let kept: Vec<KnotCorner> = corners
        .iter()
        .copied()
        .filter(|c| near(&sharp, c) <= near(&smooth, c))
        .collect();
    if kept.len() == corners.len() {
        return Ok(sharp);
    }
    if kept.is_empty() {
        return Ok(smooth);
    }
    match fit(&kept, PARAMETER_CORRECTIONS) {
        Ok(sharp) if sharp.rms_residual <= WORSE_WITH_CORNERS * smooth.rms_residual => Ok(sharp),
        _ => Ok(smooth),
    }
}

/// The root-mean-square distance of the points within `reach` places of `centre` in the order
/// from `fit`'s curve (from their feet on it, found from their parameters: how far along a
/// straight arm the curve places a point is not the fit's error).
fn local_rms(
    fit: &Approximation,
    ordered: &[[f64; 3]],
    centre: usize,
    reach: usize,
    closed: bool,
) -> f64 {
    let n = ordered.len();
    let reach = reach.min((n - 1) / 2);
    let indices: Vec<usize> = if closed {
        (0..=2 * reach)
            .map(|d| (centre + n - reach + d) % n)
            .collect()
    } else {
        (centre.saturating_sub(reach)..(centre + reach + 1).min(n)).collect()
    };
    let sum: f64 = indices
        .iter()
        .map(|&j| {
            let q = ordered[j];
            let foot = foot_parameter(&fit.curve, q, fit.parameters[j]);
            distance(fit.curve.point(foot), q).powi(2)
        })
        .sum();
    (sum / indices.len().max(1) as f64).sqrt()
}

/// A fit with corners is dropped when its RMS residual exceeds the smooth fit's this many
/// times.
const WORSE_WITH_CORNERS: f64 = 1.5;

/// A corner kept at a knot.
#[derive(Clone, Copy, Debug)]
struct KnotCorner {
    /// The ordered point at the corner.
    index: usize,
    /// The knot the curve has its corner at.
    knot: usize,
    /// Where the corner is, when its arms say so; else the fit places it.
    tip: Option<[f64; 3]>,
}

/// The fit of `ordered` at `parameters` with `shape` = (dimension, closed, K), the control
/// points at each of `corners` tied (at the corner's tip where it has one), and `corrections`
/// rounds of moving every parameter near a corner to its foot on the curve and solving again.
fn fit_at(
    ordered: &[[f64; 3]],
    parameters: Vec<f64>,
    (dimension, closed, k): (usize, bool, usize),
    options: &ApproximationOptions,
    corners: &[KnotCorner],
    corrections: usize,
) -> Result<Approximation> {
    let n = ordered.len();
    let degree = options.degree;
    let segments = if closed { k } else { k - degree };
    let mut parameters = move_to_knots(parameters, corners, segments, closed);
    let knots: Vec<usize> = corners.iter().map(|c| c.knot).collect();
    let layout = control_layout(k, closed, ordered, degree, options.ends);
    let (controls, unknowns) = tie_corners(layout, corners, degree);
    let solve = |parameters: &[f64]| -> Result<BSplineCurve> {
        let mut equations = NormalEquations::new(unknowns);
        for (&t, &q) in parameters.iter().zip(ordered) {
            let (i, u) = locate(t, segments);
            let b = if degree == 3 {
                let c = cubic_basis(u);
                [c[0], c[1], c[2], c[3], 0.0, 0.0]
            } else {
                uniform_basis(degree, u)
            };
            let row: Vec<(f64, &Affine)> = (0..=degree)
                .map(|a| (b[a], &controls[(i + a) % k]))
                .collect();
            equations.add_row(&row, q, 1.0);
        }
        let weight = options.smoothing * equations.mean_diagonal();
        let differences = if closed { 0..k } else { 1..k - 1 };
        // No bending penalty at a corner's tied control points.
        let at_corner = |c: usize| knots.iter().any(|&i| (c + k - i) % k < degree);
        for c in differences.filter(|&c| !at_corner(c)) {
            let row = [
                (1.0, &controls[(c + k - 1) % k]),
                (-2.0, &controls[c]),
                (1.0, &controls[(c + 1) % k]),
            ];
            equations.add_row(&row, [0.0; 3], weight);
        }
        let solution = equations.solve().ok_or_else(|| {
            Error::invalid(format!(
                "the least-squares system for {k} control points over {n} points is \
                 singular: use fewer control points or more smoothing"
            ))
        })?;
        Ok(BSplineCurve {
            dimension,
            closed,
            degree,
            control: controls.iter().map(|a| a.evaluate(&solution)).collect(),
        })
    };
    let mut curve = solve(&parameters)?;
    // Next to a corner the curve slows to a stop at its tip (three coinciding control
    // points), so parameters spread evenly along the data put points at the wrong places on
    // it: each point moves to its foot on the curve and the fit is solved again.
    // Only within a few segments of a corner: elsewhere evenly spread parameters are right,
    // and moving them lets the fit follow the noise.
    let reach = corrected_segments(degree) / segments as f64;
    let near_corner = |t: f64| {
        corners.iter().any(|c| {
            let d = (t - c.knot as f64 / segments as f64).abs();
            (if closed { d.min(1.0 - d) } else { d }) < reach
        })
    };
    for _ in 0..corrections {
        for (t, &q) in parameters.iter_mut().zip(ordered) {
            if near_corner(*t) {
                *t = foot_parameter(&curve, q, *t);
            }
        }
        curve = solve(&parameters)?;
    }
    let residuals: Vec<f64> = parameters
        .iter()
        .zip(ordered)
        .map(|(&t, &q)| distance(curve.point(t), q))
        .collect();
    let rms_residual = (residuals.iter().map(|r| r * r).sum::<f64>() / n as f64).sqrt();
    let max_residual = residuals.iter().copied().fold(0.0, f64::max);
    let corner_points = corners.iter().map(|c| curve.control[c.knot % k]).collect();
    Ok(Approximation {
        curve,
        parameters,
        rms_residual,
        max_residual,
        corners: corners.iter().map(|c| c.index).collect(),
        corner_points,
    })
}

/// Corners keep at least this many knots between them.
const MIN_KNOTS_APART: usize = 4;

/// Parameters within this many segments of a corner move to their feet on the curve.
const CORRECTED_SEGMENTS: f64 = 4.0;

/// [`CORRECTED_SEGMENTS`] for a cubic, one more segment per degree above it: a corner's tied
/// control points reach p segments.
fn corrected_segments(degree: usize) -> f64 {
    CORRECTED_SEGMENTS + degree.saturating_sub(3) as f64
}

/// Times the parameters of a fit with corners move to their feet on the curve.
const PARAMETER_CORRECTIONS: usize = 4;

/// The parameter of the point of `curve` nearest `q`: the nearest of samples an eighth of a
/// segment apart within a segment of `t` (the curve stops at a corner's tip, where a step
/// from the tip alone would not move), then Gauss–Newton steps of at most half a segment
/// each (a closed curve's parameter wraps).
fn foot_parameter(curve: &BSplineCurve, q: [f64; 3], t: f64) -> f64 {
    let most = 0.5 / curve.segments() as f64;
    let wrap = |t: f64| {
        if curve.closed {
            t.rem_euclid(1.0)
        } else {
            t.clamp(0.0, 1.0)
        }
    };
    let step = most / 4.0;
    let mut t = (-8..=8)
        .map(|j| wrap(t + j as f64 * step))
        .min_by(|&a, &b| distance(curve.point(a), q).total_cmp(&distance(curve.point(b), q)))
        .unwrap_or(t);
    for _ in 0..4 {
        let (c, d) = (curve.point(t), curve.tangent(t));
        let speed = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        if !(speed > 0.0 && speed.is_finite()) {
            break;
        }
        let along = (0..3).map(|a| (q[a] - c[a]) * d[a]).sum::<f64>() / speed;
        t = wrap(t + along.clamp(-most, most));
    }
    t
}

/// The knot each of `corners` is kept at, in order: the knot nearest its parameter, sharpest corners first, each at least [`MIN_KNOTS_APART`]
/// knots from the others (its three control points are its own, and at least one free one
/// lies between two corners) and, open, off the pinned ends (knots 2 ..=
/// segments − 2).
fn corner_knots(
    corners: &[Corner],
    parameters: &[f64],
    segments: usize,
    closed: bool,
    degree: usize,
) -> Vec<KnotCorner> {
    // Cubic: 4 knots apart and knots 2 ..= segments − 2; each degree above 3 one more.
    let apart_at_least = MIN_KNOTS_APART + degree.saturating_sub(3);
    let margin = 2 + degree.saturating_sub(3);
    let mut sharpest: Vec<Corner> = corners.to_vec();
    sharpest.sort_by(|a, b| b.turn.total_cmp(&a.turn));
    let apart = |a: usize, b: usize| {
        let d = a.abs_diff(b);
        if closed { d.min(segments - d) } else { d }
    };
    let mut kept: Vec<KnotCorner> = Vec::new();
    for corner in sharpest {
        let nearest = (parameters[corner.index] * segments as f64).round() as usize;
        let knot = if closed { nearest % segments } else { nearest };
        let allowed = closed || (margin..=segments.saturating_sub(margin)).contains(&knot);
        if allowed
            && kept
                .iter()
                .all(|other| apart(knot, other.knot) >= apart_at_least)
        {
            kept.push(KnotCorner {
                index: corner.index,
                knot,
                tip: corner.tip,
            });
        }
    }
    kept.sort_by_key(|c| c.knot);
    kept
}

/// `parameters` moved piecewise linearly so that each corner's point lands on its knot
/// (knot / `segments`); order is kept, and an open curve's ends stay at 0 and 1.
fn move_to_knots(
    parameters: Vec<f64>,
    corners: &[KnotCorner],
    segments: usize,
    closed: bool,
) -> Vec<f64> {
    if corners.is_empty() {
        return parameters;
    }
    // Anchors (from, to), increasing in both. Closed, a knot is taken a turn up or down to
    // lie within half a turn of its point (knot 0 for a point at 0.999 is 1).
    let mut anchors: Vec<(f64, f64)> = corners
        .iter()
        .map(|c| {
            let (from, to) = (parameters[c.index], c.knot as f64 / segments as f64);
            (from, if closed { to + (from - to).round() } else { to })
        })
        .collect();
    anchors.sort_by(|a, b| a.0.total_cmp(&b.0));
    if closed {
        // Wrap around: the last anchor before 0 and the first after 1.
        let (first, last) = (anchors[0], anchors[anchors.len() - 1]);
        anchors.insert(0, (last.0 - 1.0, last.1 - 1.0));
        anchors.push((first.0 + 1.0, first.1 + 1.0));
    } else {
        anchors.insert(0, (0.0, 0.0));
        anchors.push((1.0, 1.0));
    }
    parameters
        .iter()
        .map(|&t| {
            let j = anchors
                .windows(2)
                .position(|w| t <= w[1].0)
                .unwrap_or(anchors.len() - 2);
            let ((a, x), (b, y)) = (anchors[j], anchors[j + 1]);
            let moved = if b > a {
                x + (t - a) / (b - a) * (y - x)
            } else {
                x
            };
            if closed {
                moved.rem_euclid(1.0)
            } else {
                moved.clamp(0.0, 1.0)
            }
        })
        .collect()
}

/// `controls` with the `degree` control points at each corner's knot i (P_i … P_{i+p−1},
/// cyclically: the ones the curve depends on at the knot) made one, fixed at the corner's tip
/// where it has one, and the unknowns still in use numbered densely; returns them and their
/// count.
fn tie_corners(
    mut controls: Vec<Affine>,
    corners: &[KnotCorner],
    degree: usize,
) -> (Vec<Affine>, usize) {
    let k = controls.len();
    for corner in corners {
        let i = corner.knot;
        let tip = match corner.tip {
            Some(at) => Affine::fixed(at),
            None => controls[i % k].clone(),
        };
        for j in 0..degree {
            controls[(i + j) % k] = tip.clone();
        }
    }
    let mut used: Vec<usize> = controls
        .iter()
        .flat_map(|a| a.terms.iter().map(|t| t.0))
        .collect();
    used.sort_unstable();
    used.dedup();
    for a in &mut controls {
        for term in &mut a.terms {
            term.0 = used.binary_search(&term.0).unwrap_or(0);
        }
    }
    (controls, used.len())
}

/// The K control points as affine functions of the unknowns (see [`approximate`]).
fn control_layout(
    k: usize,
    closed: bool,
    ordered: &[[f64; 3]],
    degree: usize,
    ends: Ends,
) -> Vec<Affine> {
    if closed {
        return (0..k).map(Affine::unknown).collect();
    }
    // The curve's ends: the data's, or two more unknowns after the K that any layout uses.
    let [first, last] = match ends {
        Ends::AtData => [ordered[0], ordered[ordered.len() - 1]].map(Affine::fixed),
        Ends::Fitted => [k, k + 1].map(Affine::unknown),
    };
    if degree != 3 {
        return open_layout(k, [first, last], degree);
    }
    // P₁ = Q₀, P₂ … P_{K−3} unknowns 0 … K−5, P_{K−2} = Q_{n−1}.
    let mut inner = vec![first];
    inner.extend((0..k - 4).map(Affine::unknown));
    inner.push(last);
    let start = inner[0].combine(2.0, &inner[1], -1.0);
    let end = inner[k - 3].combine(2.0, &inner[k - 4], -1.0);
    let mut controls = vec![start];
    controls.extend(inner);
    controls.push(end);
    controls
}

/// [`control_layout`] of an open curve of degree p ≠ 3, the cubic's phantoms generalized.
/// At each end, with m = ⌊(p − 1)/2⌋, the control points before P_m continue the line
/// through P_m and P_{m+1} at equal steps (P_j = P_m + (m − j)·(P_m − P_{m+1})), and P_m
/// is what makes the curve start at its start point, C(0) = Σ N_j(0)·P_j = E₀ (solved for
/// P_m; its coefficient is at least 1/2 for p ≤ 5). The same mirrored at the other end.
/// For p = 3 this is the cubic's layout: P₀ = 2P₁ − P₂ and P₁ = E₀.
fn open_layout(k: usize, ends: [Affine; 2], degree: usize) -> Vec<Affine> {
    let m = (degree - 1) / 2;
    let weights = uniform_basis(degree, 0.0);
    // The unknowns: every control point that no end condition fixes (k ≥ p + m + 2, see
    // [`control_range`], so each end's condition reads unknowns only).
    let mut controls: Vec<Option<Affine>> = vec![None; k];
    for (f, slot) in controls[m + 1..k - m - 1].iter_mut().enumerate() {
        *slot = Some(Affine::unknown(f));
    }
    let zero = || Affine::fixed([0.0; 3]);
    // Start: index j of the weights is control point j; end: mirrored (j ↔ k − 1 − j),
    // where the weights at u = 1 of the last segment mirror those at u = 0.
    let [first, last] = ends;
    for (target, mirror) in [(first, false), (last, true)] {
        let at = |j: usize| if mirror { k - 1 - j } else { j };
        // C(0) = α·P_m + β·P_{m+1} + Σ_{j>m+1} N_j·P_j = Q.
        let mut alpha = weights[m];
        let mut beta = weights[m + 1];
        for j in 0..m {
            alpha += weights[j] * (1 + m - j) as f64;
            beta -= weights[j] * (m - j) as f64;
        }
        let next = controls[at(m + 1)].clone().unwrap_or_else(zero);
        let mut anchor = target.combine(1.0 / alpha, &next, -beta / alpha);
        for j in m + 2..=degree {
            let p = controls[at(j)].clone().unwrap_or_else(zero);
            anchor = anchor.combine(1.0, &p, -weights[j] / alpha);
        }
        for j in 0..m {
            let steps = (m - j) as f64;
            controls[at(j)] = Some(anchor.combine(1.0 + steps, &next, -steps));
        }
        controls[at(m)] = Some(anchor);
    }
    controls
        .into_iter()
        .map(|c| c.unwrap_or_else(zero))
        .collect()
}

/// The least and most control points K of a fit of n points at `degree`: closed, degree + 1
/// (at least 4) to n; open, 4 for a cubic and p + ⌊(p − 1)/2⌋ + 2 otherwise (the end
/// conditions of an open curve of another degree need one free point between them) to n + 2 for a cubic and
/// n + p − 1 otherwise.
pub fn control_range(n: usize, closed: bool, degree: usize) -> (usize, usize) {
    if closed {
        (MIN_CONTROL_POINTS.max(degree + 1), n)
    } else if degree == 3 {
        (MIN_CONTROL_POINTS, n + 2)
    } else {
        (
            MIN_CONTROL_POINTS.max(degree + (degree - 1) / 2 + 2),
            n + degree - 1,
        )
    }
}

/// The parameter at which [`interpolate`] passes through Qⱼ: j/(n − 1) open, j/n closed.
pub fn interpolation_parameter(j: usize, n: usize, closed: bool) -> f64 {
    let segments = if closed {
        n
    } else {
        n.saturating_sub(1).max(1)
    };
    j as f64 / segments as f64
}

/// The uniform cubic B-spline through every ordered point, Qⱼ = C(tⱼ) at the segment joints
/// tⱼ = [`interpolation_parameter`]: (P_j + 4P_{j+1} + P_{j+2})/6 = Qⱼ. Open: n + 2
/// control points with phantoms (natural ends), a tridiagonal system in P₂ … P_{n−1};
/// closed: n control points, a cyclic tridiagonal system. O(n). The curve passes through
/// every point to within a few ulp of the coordinates' magnitude (≤ 1e-12 for unit-sized
/// data).
///
/// # Errors
/// [`Error::InvalidInput`] for fewer than 4 or non-finite points or a bad dimension.
pub fn interpolate(ordered: &[[f64; 3]], dimension: usize, closed: bool) -> Result<BSplineCurve> {
    check_ordered(ordered, dimension)?;
    let n = ordered.len();
    let control = if closed {
        // R_j = P_{j+1}: R_{j−1} + 4R_j + R_{j+1} = 6Q_j, cyclic; then P_k = R_{k−1}.
        let rhs: Vec<[f64; 3]> = ordered.iter().map(|q| q.map(|c| 6.0 * c)).collect();
        let r = solve_cyclic(1.0, 4.0, 1.0, &rhs);
        (0..n).map(|k| r[(k + n - 1) % n]).collect()
    } else {
        // Unknowns P₂ … P_{n−1}; P₁ = Q₀, P_n = Q_{n−1}.
        let (first, last) = (ordered[0], ordered[n - 1]);
        let mut rhs: Vec<[f64; 3]> = ordered[1..n - 1]
            .iter()
            .map(|q| q.map(|c| 6.0 * c))
            .collect();
        let inner = rhs.len();
        for k in 0..3 {
            rhs[0][k] -= first[k];
            rhs[inner - 1][k] -= last[k];
        }
        let middle = solve_tridiagonal(1.0, 4.0, 1.0, &rhs);
        let mut control = Vec::with_capacity(n + 2);
        control.push([0, 1, 2].map(|k| 2.0 * first[k] - middle[0][k]));
        control.push(first);
        control.extend(middle.iter().copied());
        control.push(last);
        control.push([0, 1, 2].map(|k| 2.0 * last[k] - middle[inner - 1][k]));
        control
    };
    Ok(BSplineCurve {
        dimension,
        closed,
        degree: 3,
        control,
    })
}

/// Checks ordered fit input: ≥ 4 finite points of dimension 2 (z = 0) or 3.
fn check_ordered(ordered: &[[f64; 3]], dimension: usize) -> Result<()> {
    if dimension != 2 && dimension != 3 {
        return Err(Error::invalid(format!(
            "curve points must be 2-D or 3-D, got dimension {dimension}"
        )));
    }
    if ordered.len() < MIN_POINTS {
        return Err(Error::invalid(format!(
            "a B-spline fit needs at least {MIN_POINTS} points, got {}",
            ordered.len()
        )));
    }
    for (i, p) in ordered.iter().enumerate() {
        if p.iter().any(|c| !c.is_finite()) {
            return Err(Error::invalid(format!(
                "ordered point {i} has a non-finite coordinate {p:?}"
            )));
        }
        if dimension == 2 && p[2] != 0.0 {
            return Err(Error::invalid(format!(
                "ordered point {i} is 2-D but has z = {}",
                p[2]
            )));
        }
    }
    Ok(())
}
