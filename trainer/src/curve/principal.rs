//! A noisy band followed by its own fit: each point moves to its foot on the curve, the
//! points are ordered by it, and the curve is fitted again (a principal curve, after Hastie
//! and Stuetzle).
//!
//! An order through a band many spacings wide zig-zags across it and may start or stop
//! inside it: its first and last points are wherever the chain's ends came to rest. A smooth
//! fit knows better where the band runs. Ordering the points by their feet on it repairs
//! the order, and measuring along it gives arc-length parameters. An open band's ends are
//! found from the points themselves: Gaussian noise of deviation σ carries about
//! ρσ/√(2π) ≈ 0.4ρσ points past a true end (ρ points per unit length), so the end lies that
//! many points in from the outermost foot.

use super::bridge::{VOID, weakest_share};
use super::fit::{Approximation, ApproximationOptions, approximate_at, control_range};
use super::noise::{band_control_points, gaussian_median, gaussian_quantile};
use super::path_graph::{dense_paths, neighbour_graph};
use super::skeleton::skeleton_order;
use crate::error::Result;
use crate::fidelity::median;
use crate::geometry::vector::{distance, dot, sub};
use kiddo::{ImmutableKdTree, SquaredEuclidean};

/// Most rounds of fitting and re-ordering.
const ROUNDS: usize = 6;
/// A round that changes the points' RMS distance from the curve by less than this fraction
/// ends the rounds.
const SETTLED: f64 = 0.005;
/// Vertices of the polyline the feet are found on (at least 64 per segment).
const FOOT_VERTICES: usize = 1024;
/// How far past an open curve's ends feet may lie, in noise deviations: far enough for the
/// noise. An extension stops short of this where another part of the curve comes nearer
/// than its own end ([`Polyline::clear_reaches`]).
const PAST_REACH: f64 = 4.0;
/// Steps along an open curve's extension at which [`Polyline::clear_reaches`] looks for
/// another part of the curve.
const CLEARANCE_STEPS: usize = 16;
/// Points past a true end per unit of ρσ: 1/√(2π).
const PAST_THE_END: f64 = 0.398_942_3;

/// A band's fit after the rounds, with the order it was fitted in.
pub(crate) struct Followed {
    /// Indices into the points as given, in their order along the curve.
    pub(crate) order: Vec<usize>,
    /// The fit of the points in `order`.
    pub(crate) approximation: Approximation,
    /// Rounds of feet, order and fit.
    pub(crate) rounds: usize,
    /// The noise across the band measured from the fit: the points' median distance from
    /// their feet, scaled for Gaussian noise as [`noise_across`](super::noise) is.
    pub(crate) noise: f64,
    /// The fitted curve's length.
    pub(crate) length: f64,
}

/// [`follow_either`] keeps the shorter of two fits unless the RMS distance of its points
/// exceeds this many times what Gaussian noise of the deviation their median gives would
/// have: then some points lie far off, in a part of the band that fit skipped.
const FARTHER: f64 = 1.5;

/// [`follow_either`] keeps the shorter of two fits only while it measures at most this many
/// times the longer's noise, and less when the longer is only a little longer
/// ([`folded_noise`]). A longer fit folded in two lays two strands along the band and
/// measures its noise from the nearer: two strands placed anywhere across Gaussian noise
/// bring the median distance down by at most 1.8 times across a 2-D curve (measured: strands
/// at ±0.6σ) and 1.3 times across a 3-D one. A shorter fit that measures more cannot be
/// blamed on a fold of the other: it misses the band. Across a 3-D curve the margin is
/// [`FOLDED_NOISE_3D`].
const FOLDED_NOISE: f64 = 2.0;

/// [`FOLDED_NOISE`] across a 3-D curve: on a helix at σ = 5 % (5 000 points) a fit that cut
/// across a turn measured 1.74 times the noise of the one along it.
const FOLDED_NOISE_3D: f64 = 1.5;

/// A longer fit more than this many times as long as the shorter scribbles through the band
/// (a fold doubles a fit's length): it measures less noise than the band has, so
/// [`FOLDED_NOISE`] does not speak against the shorter. On a cardioid at σ = 1 % of the
/// diagonal (5 000 points) the graph's start fitted one seed with a curve 20 times the
/// chain's length and 510 control points, measuring 0.28 times its noise.
const SCRIBBLED: f64 = 3.0;

/// [`fit_band`] from three starts, keeping the best fit: the chain's order at `band`'s
/// parameters, the order along the band through the graph of nearest points
/// ([`geodesic_order`] when open, [`ring_order`] when closed), and the order along the
/// tree of the band's cluster centres ([`skeleton_order`]). Each start can fail where
/// the others hold: a chain folds in a band many spacings wide (an end at rest inside it,
/// or a stretch that runs back), a graph path jumps a gap where the sampling thins, and the
/// tree of a band that thins out may leave its thin end as a side branch. Fits that run
/// where no points are lose first ([`without_voids`]): on a 2-turn helix at σ = 5 % (turns
/// 5.8 deviations apart, 1 000 and 5 000 points, 8 seeds) the first two starts cut across
/// a turn on 15 of 16 runs (14–22 % of the diagonal); now 2 of 16. On a trefoil knot at
/// σ = 3 % (strands 5.2 deviations apart, 1 000 points) 6 of 8 seeds were 8–14 % off; now
/// 2.
/// Closeness alone cannot choose: a curve that wanders through the band comes closer to
/// its points than the band's middle does, and a fold or a loop (and the extra control
/// points the lower noise it measures then asks for) brings it 5–35 % closer. So the
/// shorter curve wins unless its distances have a tail that noise does not explain
/// ([`FARTHER`]): a start that skipped part of the band, whose points then lie as far off
/// as that part is long. Nor does it win when it measures more than [`FOLDED_NOISE`] times
/// the other's noise: a curve that cuts across the band's turns (a stiff start that took
/// points of one arm of a spiral for the other's) puts so many points far off that the
/// median it measures its noise by grows with them, and its tail no longer shows. On a
/// 1.5-turn spiral at σ = 1 % (8 seeds) such a cut fitted one seed at 13 % of the diagonal,
/// measuring 5.7 times the graph start's noise; that start gives 1.5 %. A fit only a little
/// longer can have folded over only a little of the band, and so measures only a little
/// less noise for it ([`folded_noise`]): on an S at σ = 5 % whose ends come within 5.6
/// deviations of its middle stroke, a fit 0.7 % shorter that turned back at the end of a
/// bow measured 1.09 times the noise of the right one, and the margin of 2 let it win
/// (11.4 % of the diagonal where the right one is 4.2 %). With more than two fits, the
/// shortest that passes both tests against every longer one wins ([`choose`]).
///
/// # Errors
/// As [`approximate_at`].
pub(crate) fn follow_either(
    ordered: &[[f64; 3]],
    (dimension, closed): (usize, bool),
    (noise, parameters): (f64, Vec<f64>),
    fixed: Option<usize>,
    options: &ApproximationOptions,
) -> Result<Followed> {
    let shape = (dimension, closed);
    let chain = fit_band(ordered, shape, (noise, parameters), fixed, None, options)?;
    let mut fits = vec![chain];
    let around = if closed {
        ring_order(ordered)
    } else {
        geodesic_order(ordered)
    };
    // The graph's order runs along the band and cannot fold, so its fit need not start stiff.
    let in_order = |(order, places, length): (Vec<usize>, Vec<f64>, f64)| {
        fit_band_in_order(
            ordered,
            &order,
            shape,
            (noise, places),
            fixed,
            length,
            options,
        )
        .ok()
    };
    fits.extend(around.and_then(in_order));
    // The chain's fit measures the noise closer than the order's zig-zag does.
    let measured = fits[0].noise;
    fits.extend(skeleton_order(ordered, measured).and_then(in_order));
    let kept = choose(without_voids(ordered, fits), dimension);
    if closed {
        return Ok(kept);
    }
    super::bridge::cut_at_void(ordered, dimension, fixed, options, kept)
}

/// The `fits` whose weakest stretch has at least [`VOID`] times their median support, when
/// any has: a fit that runs where no points are (across the mouth of a 'C',
/// between two turns of a helix) is not the band's, whatever its closeness says. All of
/// them when none has (the band itself thins out somewhere).
fn without_voids(ordered: &[[f64; 3]], fits: Vec<Followed>) -> Vec<Followed> {
    let full: Vec<bool> = fits
        .iter()
        .map(|f| weakest_share(ordered, f).is_some_and(|share| share >= VOID))
        .collect();
    if !full.contains(&true) {
        return fits;
    }
    fits.into_iter()
        .zip(full)
        .filter_map(|(f, full)| full.then_some(f))
        .collect()
}

/// The shortest of `fits` (at least one) whose distances have no tail that noise does not
/// explain, and which measures at most [`folded_noise`] (at most [`FOLDED_NOISE`]) times
/// the noise of each longer fit that does not scribble ([`SCRIBBLED`]); the longest when
/// none does (see [`follow_either`]).
fn choose(mut fits: Vec<Followed>, dimension: usize) -> Followed {
    fits.sort_by(|a, b| a.length.total_cmp(&b.length));
    // Gaussian noise across a curve in d dimensions has an RMS of √(d − 1) deviations.
    let across = (dimension as f64 - 1.0).sqrt();
    let gaussian = |f: &Followed| f.approximation.rms_residual <= FARTHER * across * f.noise;
    let folded = if dimension == 3 {
        FOLDED_NOISE_3D
    } else {
        FOLDED_NOISE
    };
    let alike = |shorter: &Followed, longer: &Followed| {
        let share = (longer.length - shorter.length) / (2.0 * shorter.length);
        shorter.noise <= folded_noise(share, dimension).min(folded) * longer.noise
            || longer.length > SCRIBBLED * shorter.length
    };
    let pick = (0..fits.len())
        .find(|&i| gaussian(&fits[i]) && fits[i + 1..].iter().all(|l| alike(&fits[i], l)))
        .unwrap_or(fits.len() - 1);
    fits.swap_remove(pick)
}

/// How many times less noise a fit can measure than the band has when it folds back over
/// `share` of the band's length (a fold over a stretch lengthens the fit by twice that
/// stretch): at most as if the points of that share lay on the fit, which moves the median
/// distance down to the (½ − share)/(1 − share) quantile; and [`CONTROL_SLACK`] more.
/// Measured at σ = 5 % of the diagonal (16 curves, 1 000 and 5 000 points, 8 seeds), this
/// chose the best of the three fits wherever one was within 5.5 % of the diagonal, where a
/// fixed margin missed 4 (an S and a trefoil knot twice each); at σ = 1 % it chose the same
/// fits.
fn folded_noise(share: f64, dimension: usize) -> f64 {
    if share >= 0.5 {
        return f64::INFINITY;
    }
    let share = share.max(0.0);
    let quantile = gaussian_quantile((0.5 - share) / (1.0 - share), dimension);
    CONTROL_SLACK * gaussian_median(dimension) / quantile.max(f64::MIN_POSITIVE)
}

/// The noise two fits of a band measure may differ by this factor without a fold: the
/// cross-validated control counts differ between them, and more control points come
/// closer to the points.
const CONTROL_SLACK: f64 = 1.05;

/// [`fit_band`] of `ordered` taken in `order` (indices into it), at `places` along a band
/// `length` long; the fit's order is given back as indices into `ordered`.
///
/// # Errors
/// As [`fit_band`].
pub(crate) fn fit_band_in_order(
    ordered: &[[f64; 3]],
    order: &[usize],
    shape: (usize, bool),
    (noise, places): (f64, Vec<f64>),
    fixed: Option<usize>,
    length: f64,
    options: &ApproximationOptions,
) -> Result<Followed> {
    let points: Vec<[f64; 3]> = order.iter().map(|&i| ordered[i]).collect();
    let mut fit = fit_band(
        &points,
        shape,
        (noise, places),
        fixed,
        Some(length),
        options,
    )?;
    fit.order = fit.order.iter().map(|&i| order[i]).collect();
    Ok(fit)
}

/// Rounds of [`fit_band`] that re-count the control points from the noise and length the
/// last fit measured.
const RECOUNTS: usize = 3;

/// [`follow_band`] from `parameters` at the fewest control points [`band_control_points`]
/// allows (or `fixed` ones), then, unless fixed, again at the count it gives for the noise
/// and length that fit measured, until the count settles ([`RECOUNTS`] times at most).
///
/// The noise and length measured from a fit are better than the ones measured along the
/// order: the order's zig-zag across the band lengthens it and hides part of the noise. And
/// the stiffest curve starts: with more control points a first fit in a folded order keeps
/// the fold, measures the lower noise the fold leaves, and so asks for more control points.
/// An order that cannot fold (the graph's, whose places only grow along the band) starts
/// instead at the count its own `length` asks for: the stiffest curve cuts across a
/// spiral's turns, and the feet on it then mix the arms.
///
/// # Errors
/// As [`approximate_at`].
pub(crate) fn fit_band(
    ordered: &[[f64; 3]],
    (dimension, closed): (usize, bool),
    (noise, parameters): (f64, Vec<f64>),
    fixed: Option<usize>,
    length: Option<f64>,
    options: &ApproximationOptions,
) -> Result<Followed> {
    let shape = (dimension, closed);
    let n = ordered.len();
    let (least, most) = control_range(n, closed, options.degree);
    let stiffest = band_control_points(length.unwrap_or(0.0), noise, n, closed)
        .max(least)
        .min(most);
    let mut k = fixed.unwrap_or(stiffest);
    let first = approximate_at(ordered, parameters, dimension, closed, k, options)?;
    let mut followed = follow_band(ordered, shape, noise, options, first)?;
    if fixed.is_some() {
        return Ok(followed);
    }
    for _ in 0..RECOUNTS {
        let next = band_control_points(followed.length, followed.noise, n, closed)
            .max(least)
            .min(most);
        if next == k {
            break;
        }
        k = next;
        let order = followed.order;
        let points: Vec<[f64; 3]> = order.iter().map(|&i| ordered[i]).collect();
        let start = approximate_at(
            &points,
            followed.approximation.parameters,
            dimension,
            closed,
            k,
            options,
        )?;
        let mut again = follow_band(&points, shape, followed.noise, options, start)?;
        again.order = again.order.iter().map(|&i| order[i]).collect();
        again.rounds += followed.rounds;
        followed = again;
    }
    cross_validated(ordered, shape, options, followed, most)
}

/// `followed`'s points in its order, those past an open band's ends held back as its last
/// round held them back ([`hold_back_past_ends`]).
fn held_back(
    ordered: &[[f64; 3]],
    (dimension, closed): (usize, bool),
    followed: &Followed,
) -> Vec<[f64; 3]> {
    let mut points: Vec<[f64; 3]> = followed.order.iter().map(|&i| ordered[i]).collect();
    if !closed {
        let identity: Vec<usize> = (0..points.len()).collect();
        let reach = PAST_REACH * followed.noise;
        let feet = Feet::of(
            &followed.approximation,
            &points,
            (dimension, closed),
            &identity,
            reach,
        );
        let at: Vec<[f64; 3]> = feet.along.iter().map(|a| a.2).collect();
        hold_back_past_ends(&mut points, &followed.approximation.parameters, &at);
    }
    points
}

/// Folds of the cross-validation that chooses a band's control count: every fifth point
/// along the band is held out in turn.
const FOLDS: usize = 5;

/// Each control count tried is this many times the last.
const COUNT_STEP: f64 = 1.25;

/// The counts tried stop after this many in a row predict no better than the best so far.
const PATIENCE: usize = 2;

/// The fewest points per control point the cross-validation tries (of the points a fold
/// fits).
const FOLD_POINTS_PER_CONTROL: usize = 6;

/// The points one fold of the cross-validation fits, and the ones it holds out.
struct Fold {
    points: Vec<[f64; 3]>,
    parameters: Vec<f64>,
    held_out: Vec<usize>,
}

/// `followed` refitted at the control count, from its own upward (by [`COUNT_STEP`]), whose
/// fit at `followed`'s parameters predicts held-out points best ([`FOLDS`]-fold, mean
/// squared distance from each point to the curve at its parameter), at most `most`.
///
/// The count [`band_control_points`] gives is the stiffest that keeps a fit from bending
/// within the band as the points are re-ordered by their feet on it; detail narrower than a
/// few noise deviations (a ring's five wobbles at σ = 5 %) it smooths away. With the order
/// and parameters settled, more control points no longer move the order: held-out points
/// then say whether the extra freedom follows the curve or the noise. The fit is not
/// followed again at the new count (feet, order and fit), which would let its bends lock
/// in. Measured at σ = 5 % of the diagonal (1 000 and 5 000 points, 8 seeds,
/// `docs/performance/curve-bands.md`): the wobbly ring 6.3 → 3.1 %, the 10:1 density step
/// 6.5 → 3.5 %, a 3-D arc 5.2 → 3.9 % worst Hausdorff distance.
///
/// # Errors
/// As [`approximate_at`].
fn cross_validated(
    ordered: &[[f64; 3]],
    (dimension, closed): (usize, bool),
    options: &ApproximationOptions,
    followed: Followed,
    most: usize,
) -> Result<Followed> {
    let points = held_back(ordered, (dimension, closed), &followed);
    let parameters = &followed.approximation.parameters;
    let n = points.len();
    let stiff = followed.approximation.curve.control.len();
    let fitted = n - n / FOLDS;
    let cap = most.min(fitted / FOLD_POINTS_PER_CONTROL);
    let folds: Vec<Fold> = (0..FOLDS)
        .map(|fold| {
            let (kept, out): (Vec<usize>, Vec<usize>) = (0..n).partition(|i| i % FOLDS != fold);
            Fold {
                points: kept.iter().map(|&i| points[i]).collect(),
                parameters: kept.iter().map(|&i| parameters[i]).collect(),
                held_out: out,
            }
        })
        .collect();
    let predicts = |k: usize| -> Result<f64> {
        let mut squares = 0.0;
        for fold in &folds {
            let at = fold.parameters.clone();
            let fit = approximate_at(&fold.points, at, dimension, closed, k, options)?;
            for &i in &fold.held_out {
                let d = distance(fit.curve.point(parameters[i]), points[i]);
                squares += d * d;
            }
        }
        Ok(squares)
    };
    let (mut best, mut best_error) = (stiff, f64::INFINITY);
    let (mut k, mut worse) = (stiff, 0);
    while k <= cap && worse < PATIENCE {
        let error = predicts(k)?;
        if error < best_error {
            (best, best_error, worse) = (k, error, 0);
        } else {
            worse += 1;
        }
        k = ((k as f64 * COUNT_STEP).round() as usize).max(k + 1);
    }
    if best == stiff {
        return Ok(followed);
    }
    let fit = approximate_at(
        &points,
        followed.approximation.parameters.clone(),
        dimension,
        closed,
        best,
        options,
    )?;
    // The noise and length as the rounds measure them: from the points as given.
    let feet = Feet::of(
        &fit,
        ordered,
        (dimension, closed),
        &followed.order,
        PAST_REACH * followed.noise,
    );
    Ok(Followed {
        order: followed.order,
        approximation: fit,
        rounds: followed.rounds,
        noise: feet.noise,
        length: feet.length,
    })
}

/// Refits `first` (a fit of `ordered` with `options`) by rounds of feet, order and fit at
/// the same number of control points, until the points' distance from the curve settles.
/// `noise` is the deviation of the noise across the band.
///
/// The first round may leave the points farther from the curve than the start: a fit in a
/// zig-zag order follows part of the zig-zag, and so comes closer to the points than a
/// smooth curve through the band's middle.
///
/// # Errors
/// As [`approximate_at`].
pub(crate) fn follow_band(
    ordered: &[[f64; 3]],
    (dimension, closed): (usize, bool),
    noise: f64,
    options: &ApproximationOptions,
    first: Approximation,
) -> Result<Followed> {
    let n = ordered.len();
    let k = first.curve.control.len();
    let reach = PAST_REACH * noise;
    let order: Vec<usize> = (0..n).collect();
    let mut feet = Feet::of(&first, ordered, (dimension, closed), &order, reach);
    let mut latest = Followed {
        order,
        approximation: first,
        rounds: 0,
        noise: feet.noise,
        length: feet.length,
    };
    for round in 1..=ROUNDS {
        let (order, parameters) = feet.order_and_parameters(noise, closed);
        let mut points: Vec<[f64; 3]> = order.iter().map(|&i| ordered[i]).collect();
        if !closed {
            hold_back_past_ends(&mut points, &parameters, &feet.in_order());
        }
        let fit = approximate_at(&points, parameters, dimension, closed, k, options)?;
        let next = Feet::of(&fit, ordered, (dimension, closed), &order, reach);
        let settled = (next.rms - feet.rms).abs() <= SETTLED * feet.rms;
        latest = Followed {
            order,
            approximation: fit,
            rounds: round,
            noise: next.noise,
            length: next.length,
        };
        feet = next;
        if settled {
            break;
        }
    }
    Ok(latest)
}

/// Neighbours of each point in the graph [`geodesic_order`] measures along.
const GRAPH_NEIGHBOURS: usize = 10;

/// An open band's points ordered by their distance along the band from its far ends,
/// measured along the dense paths through the graph of nearest points ([`dense_paths`]):
/// the end a path from any point reaches farthest, the other end as far from that one, and
/// each point's place half its distance from the first end plus half the whole length less
/// its distance from the second. Across the band the places differ by about its width,
/// which the rounds of [`follow_band`] smooth out; along it they never run backwards, where
/// a chain's end can come to rest inside the band and fold it. Returns the order, each
/// ordered point's place as a parameter from 0 to 1, and the band's length; `None` when the
/// graph falls apart.
///
/// Plain shortest paths take the few points that noise carries into the mouth of a 'C' or
/// between two arms as stepping stones, and the farthest point from an end then lies
/// partway along the band. At σ = 5 % of the diagonal (1 000 points) a 3-D arc was fitted
/// 22 % of the diagonal off on one of 32 seeds that way (5.8 % with dense paths), and a
/// hairpin 10–21 % off on five of 8 seeds (three with dense paths).
pub(crate) fn geodesic_order(points: &[[f64; 3]]) -> Option<(Vec<usize>, Vec<f64>, f64)> {
    let graph = neighbour_graph(points, GRAPH_NEIGHBOURS)?;
    let farthest = |d: &[f64]| {
        d.iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map(|(i, _)| i)
    };
    let from_any = dense_paths(&graph, &[0]);
    if from_any.iter().any(|d| !d.is_finite()) {
        return None;
    }
    let start = farthest(&from_any)?;
    let from_start = dense_paths(&graph, &[start]);
    let end = farthest(&from_start)?;
    let from_end = dense_paths(&graph, &[end]);
    let length = from_start[end];
    // Finite: every path length was checked.
    ordered_by_place(
        (0..points.len())
            .map(|i| (0.5 * (from_start[i] + length - from_end[i]), i))
            .collect(),
    )
}

/// Points in the order of their `places` along an open band (place, point index): the
/// order, each ordered point's place scaled to 0 … 1, and the span of the places; `None`
/// when they all coincide (or there are none).
pub(crate) fn ordered_by_place(
    mut places: Vec<(f64, usize)>,
) -> Option<(Vec<usize>, Vec<f64>, f64)> {
    places.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (first, last) = (places.first()?.0, places.last()?.0);
    if last.partial_cmp(&first) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let (order, places) = places
        .into_iter()
        .map(|(s, i)| (i, (s - first) / (last - first)))
        .unzip();
    Some((order, places, last - first))
}

/// A closed band's points ordered around it, measured through the graph of nearest points
/// as [`geodesic_order`] measures an open one: from a point A, the path length to every
/// point is its distance around the ring in one direction or the other. A point C a quarter
/// of the way round tells the two apart: a point on C's side is as far from C as their
/// distances from A differ, one on the other side as far as they add up (through A or
/// through the point opposite A). Returns the order and each point's place around the ring
/// from 0 to 1, and the ring's length; `None` when the graph falls apart.
pub(crate) fn ring_order(points: &[[f64; 3]]) -> Option<(Vec<usize>, Vec<f64>, f64)> {
    let graph = neighbour_graph(points, GRAPH_NEIGHBOURS)?;
    let from_a = dense_paths(&graph, &[0]);
    if from_a.iter().any(|d| !d.is_finite()) {
        return None;
    }
    let half = from_a.iter().copied().fold(0.0, f64::max);
    if half <= 0.0 {
        return None;
    }
    let quarter = (0..points.len()).min_by(|&i, &j| {
        (from_a[i] - 0.5 * half)
            .abs()
            .total_cmp(&(from_a[j] - 0.5 * half).abs())
    })?;
    let from_c = dense_paths(&graph, &[quarter]);
    let c = from_a[quarter];
    let length = 2.0 * half;
    let mut places: Vec<(f64, usize)> = (0..points.len())
        .map(|i| {
            let a = from_a[i];
            let same = (a - c).abs();
            let other = (a + c).min(length - a - c);
            let place = if (from_c[i] - same).abs() <= (from_c[i] - other).abs() {
                a
            } else {
                length - a
            };
            (place.rem_euclid(length) / length, i)
        })
        .collect();
    places.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (order, places) = places
        .into_iter()
        .map(|(t, i)| (i, t.min(1.0 - f64::EPSILON)))
        .unzip();
    Some((order, places, length))
}

/// Where every point's foot lies along a fitted curve.
struct Feet {
    /// (arc length along the curve, extended past an open curve's ends; point index; foot).
    along: Vec<(f64, usize, [f64; 3])>,
    /// The curve's length.
    length: f64,
    /// √(mean squared distance of the points from their feet).
    rms: f64,
    /// The median distance of the points from their feet, scaled for Gaussian noise.
    noise: f64,
}

impl Feet {
    /// The feet in the order of [`Feet::order_and_parameters`]'s points.
    fn in_order(&self) -> Vec<[f64; 3]> {
        let mut along = self.along.clone();
        along.sort_by(|a, b| a.0.total_cmp(&b.0));
        along.into_iter().map(|a| a.2).collect()
    }

    /// The feet of `points` (indexed by `order`'s values) on `fit`'s curve, an open one
    /// extended by `reach` past each end.
    fn of(
        fit: &Approximation,
        points: &[[f64; 3]],
        (dimension, closed): (usize, bool),
        order: &[usize],
        reach: f64,
    ) -> Feet {
        let curve = &fit.curve;
        let samples = FOOT_VERTICES.max(64 * curve.segments());
        let line = Polyline::new(curve.polyline(samples), closed);
        let length = line.length();
        let reaches = line.clear_reaches(reach);
        let mut distances = Vec::with_capacity(order.len());
        let along = order
            .iter()
            .map(|&i| {
                let (s, d, at) = line.foot_within(points[i], reaches);
                distances.push(d);
                (s, i, at)
            })
            .collect();
        let squares: f64 = distances.iter().map(|d| d * d).sum();
        Feet {
            along,
            length,
            rms: (squares / order.len().max(1) as f64).sqrt(),
            noise: median(&mut distances) / gaussian_median(dimension),
        }
    }

    /// The points in order of their feet, and their parameters: chord lengths between
    /// consecutive feet over their sum (closed, the closing chord included), or between the
    /// ends the points imply (open, clamped).
    ///
    /// Chords between the feet rather than arc lengths along the curve: where the fit swings
    /// out between two points (a span without data, which only the light bending penalty
    /// holds), arc lengths would give the swing a stretch of parameters with no point in it,
    /// and the next fit would swing farther.
    fn order_and_parameters(&self, noise: f64, closed: bool) -> (Vec<usize>, Vec<f64>) {
        let mut along = self.along.clone();
        along.sort_by(|a, b| a.0.total_cmp(&b.0));
        let n = along.len();
        let order = along.iter().map(|a| a.1).collect();
        let mut chords = Vec::with_capacity(n);
        let mut total = 0.0;
        chords.push(0.0);
        for pair in along.windows(2) {
            total += distance(pair[0].2, pair[1].2);
            chords.push(total);
        }
        if closed {
            let length = (total + distance(along[n - 1].2, along[0].2)).max(f64::MIN_POSITIVE);
            let parameters = chords
                .iter()
                .map(|c| (c / length).clamp(0.0, 1.0 - f64::EPSILON))
                .collect();
            return (order, parameters);
        }
        let span = total.max(f64::MIN_POSITIVE);
        let past = ((PAST_THE_END * noise * n as f64 / span).round() as usize).min(n / 8);
        let (start, end) = (chords[past], chords[n - 1 - past]);
        let width = (end - start).max(f64::MIN_POSITIVE);
        let parameters = chords
            .iter()
            .map(|c| ((c - start) / width).clamp(0.0, 1.0))
            .collect();
        (order, parameters)
    }
}

/// Moves each point past an open band's end back onto the plane square to the band there:
/// the points given the end's parameter (0 or 1, see `order_and_parameters`) that lie
/// beyond the end's innermost foot, along the band's direction at the end (from that foot to
/// the foot as many points farther in). Those points lie past the true end by the noise
/// along the band; as they were, their mean pulled the fitted end outwards, by about a third
/// of the noise deviation. Moved, they still say where the end lies across the band.
/// Measured at σ = 5 % (1 000 points, 16 seeds): the worst Hausdorff distance of an open
/// sine 5.5 → 5.0 %, a 3-D arc 6.8 → 6.3 %, a widening hook 4.5 → 4.0 % of the size; the
/// means 3.9 → 3.3, 5.2 → 4.8 and 3.3 → 3.1 %.
fn hold_back_past_ends(points: &mut [[f64; 3]], parameters: &[f64], feet: &[[f64; 3]]) {
    let n = points.len().min(parameters.len()).min(feet.len());
    for (end, outward) in [(0.0, false), (1.0, true)] {
        let at_end: Vec<usize> = (0..n).filter(|&j| parameters[j] == end).collect();
        let (Some(&first), Some(&last)) = (at_end.first(), at_end.last()) else {
            continue;
        };
        if at_end.len() < 2 {
            continue;
        }
        // The innermost foot at the end, and one as many points farther in.
        let (anchor, inner) = if outward {
            (first, (2 * first + 1).saturating_sub(n))
        } else {
            (last, (2 * last + 1).min(n - 1))
        };
        let direction = sub(feet[anchor], feet[inner]);
        let length = dot(direction, direction).sqrt();
        if !(length > 0.0 && length.is_finite()) {
            continue;
        }
        let direction = direction.map(|c| c / length);
        for &j in &at_end {
            let beyond = dot(sub(points[j], feet[anchor]), direction);
            if beyond > 0.0 {
                for (p, d) in points[j].iter_mut().zip(direction) {
                    *p -= beyond * d;
                }
            }
        }
    }
}

/// A polyline with the arc length at each vertex and a tree of its vertices, for feet.
pub(crate) struct Polyline {
    line: Vec<[f64; 3]>,
    at: Vec<f64>,
    tree: Option<ImmutableKdTree<f64, 3>>,
    closed: bool,
}

impl Polyline {
    /// `line` (closed: its last vertex equals its first).
    pub(crate) fn new(line: Vec<[f64; 3]>, closed: bool) -> Polyline {
        let mut at = Vec::with_capacity(line.len());
        let mut length = 0.0;
        at.push(0.0);
        for pair in line.windows(2) {
            length += distance(pair[0], pair[1]);
            at.push(length);
        }
        let tree = ImmutableKdTree::new_from_slice(&line).ok();
        Polyline {
            line,
            at,
            tree,
            closed,
        }
    }

    /// The polyline's length.
    pub(crate) fn length(&self) -> f64 {
        self.at.last().copied().unwrap_or(0.0)
    }

    /// The arc length at the foot of `q`, the distance to it and the foot: on a segment
    /// next to the vertex nearest `q` (the segments are short), or, open, on the first or
    /// last segment extended straight by `reach` past the end.
    pub(crate) fn foot(&self, q: [f64; 3], reach: f64) -> (f64, f64, [f64; 3]) {
        self.foot_within(q, [reach, reach])
    }

    /// How far each end of an open polyline may be extended straight, up to `reach`: as far
    /// as its own end stays the nearest part of the line. An extension that ran on to where
    /// another part of the line is nearer (the other end of a 'C' across its mouth) would
    /// take that part's points for noise past this end, and the next fit would grow on into
    /// them. Measured at σ = 5 % of the diagonal on a 'C' of 330° (its mouth 3.7 deviations
    /// wide, 8 seeds, `docs/performance/curve-bands.md`): the worst Hausdorff distance went
    /// from 9.4 to 5.6 % (1 000 points) and from 9.4 to 2.7 % (5 000 points), where the
    /// fits' ends had grown across the mouth and on round the other arm.
    pub(crate) fn clear_reaches(&self, reach: f64) -> [f64; 2] {
        let n = self.line.len();
        let (Some(tree), false, true) = (&self.tree, self.closed, n >= 2) else {
            return [reach, reach];
        };
        let step = reach / CLEARANCE_STEPS as f64;
        let mut reaches = [reach, reach];
        for (end, (tip, inner)) in [(0, 1), (n - 1, n - 2)].into_iter().enumerate() {
            let direction = sub(self.line[tip], self.line[inner]);
            let norm = dot(direction, direction).sqrt();
            if norm.is_nan() || norm <= 0.0 {
                continue;
            }
            let at_tip = self.at[tip];
            for j in 1..=CLEARANCE_STEPS {
                let r = j as f64 * step;
                let p = [0, 1, 2].map(|k| self.line[tip][k] + r * direction[k] / norm);
                let nearest = tree
                    .query(&p)
                    .nearest_one::<SquaredEuclidean<f64>>()
                    .execute();
                let along = (self.at[nearest.item as usize] - at_tip).abs();
                let beside = nearest.distance.sqrt();
                // Nearer than the tip, and farther along the line than a bend near the
                // tip could bring a vertex.
                if beside < r && along > 2.0 * r + step {
                    reaches[end] = r - step;
                    break;
                }
            }
        }
        reaches
    }

    /// [`Polyline::foot`] with its own reach past each end (open): `[start, end]`.
    pub(crate) fn foot_within(&self, q: [f64; 3], reaches: [f64; 2]) -> (f64, f64, [f64; 3]) {
        let segments = self.line.len().saturating_sub(1);
        let mut best = (0.0, f64::INFINITY, q);
        if segments == 0 {
            return best;
        }
        let nearest = match &self.tree {
            Some(tree) => {
                tree.query(&q)
                    .nearest_one::<SquaredEuclidean<f64>>()
                    .execute()
                    .item as usize
            }
            None => 0,
        };
        let mut candidates = [
            nearest.saturating_sub(1),
            nearest.min(segments - 1),
            0,
            segments - 1,
        ];
        if self.closed && nearest == 0 {
            candidates[0] = segments - 1;
        }
        let ends = if self.closed { 2 } else { 4 };
        for &j in &candidates[..ends] {
            let (a, b) = (self.line[j], self.line[j + 1]);
            let ab = sub(b, a);
            let length2 = dot(ab, ab);
            let t = if length2 > 0.0 {
                dot(sub(q, a), ab) / length2
            } else {
                0.0
            };
            let first = j == 0 && !self.closed;
            let last = j == segments - 1 && !self.closed;
            let segment = length2.sqrt().max(f64::MIN_POSITIVE);
            let t = t.clamp(
                if first { -reaches[0] / segment } else { 0.0 },
                if last {
                    1.0 + reaches[1] / segment
                } else {
                    1.0
                },
            );
            let p = [0, 1, 2].map(|k| a[k] + t * ab[k]);
            let d = distance(q, p);
            if d < best.1 {
                best = (self.at[j] + t * (self.at[j + 1] - self.at[j]), d, p);
            }
        }
        best
    }
}
