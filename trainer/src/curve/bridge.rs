//! An open band's fit that bridges two arms: it runs across the empty mouth between their
//! tips, while its own ends meet where the band bends. The band is then cut at the bridge
//! and followed again from there.
//!
//! A hairpin's two arms run side by side; a fit that starts and ends at the bend joins the
//! arms' tips with a bridge across the mouth, and lies as close to the points as the right
//! fit (every point has a foot on it). What tells them apart is where the points are: along
//! the right fit every stretch has points within a noise deviation (fewer where the sampling
//! thins), while the straight gap between its ends crosses the mouth, where next to none lie.
//! Along the bridged fit it is the other way round: the bridge has next to no points, and
//! the gap between its ends is full of the bend's. Measured at σ = 5 % of the diagonal on a
//! hairpin whose arms are 6.3 deviations apart (1 000 points, 8 seeds): the weakest stretch
//! over the gap's weakest was 0.12–0.28 on bridged fits and 1.3 or more on right ones.
//!
//! A fit whose end ran on round a bend into the band's next turn (a helix's) is weak where
//! it crosses between the turns, but has no gap between its ends to bridge: it is also
//! trimmed to the longer side of its weakest stretch, and whichever of the three fits has
//! the strongest weakest stretch is kept. On the 2-turn helix at σ = 5 % (5 000 points, 8
//! seeds) the worst seed went from 15 % of the diagonal to 2.0 %.
//!
//! A fit may also cross the mouth and run on past it at both ends, so that the gap between
//! its ends lies in the mouth too: then the bridge is weak against the fit's own typical
//! stretch (its median support), and the band is cut there as well. A correct fit's weakest
//! stretch (its ends, a sparse part) is weak in the same way, but following it from a cut
//! there bridges its ends, which has fewer points still, and the cut is not kept.

use kiddo::{ImmutableKdTree, SquaredEuclidean};

use super::fit::ApproximationOptions;
use super::principal::{Followed, Polyline, fit_band_in_order, ordered_by_place};
use crate::error::Result;
use crate::geometry::vector::distance;

/// A path's support at a point: the band's points within this many noise deviations.
const SUPPORT_REACH: f64 = 1.0;

/// Samples per noise deviation along the fit and along the gap between its ends.
const SAMPLES_PER_NOISE: f64 = 2.0;

/// The support is averaged over this many noise deviations along a path, so that a single
/// sample's count (a few points) does not decide.
const SUPPORT_WINDOW: f64 = 2.0;

/// A fit is cut where its weakest stretch has less than this share of the support of the
/// gap between its ends at that gap's weakest: a bridge across an empty mouth has next to no
/// points, a bend full of them. Along a correct fit the weakest stretch (a sparse part of
/// the band) still has more points than the mouth its ends face across.
const WEAKER: f64 = 0.5;

/// A fit is also cut where its weakest stretch has less than this share of its typical
/// (median) support: on the hairpin (above) the bridges that also have their ends in the
/// mouth had 0–6 % of it.
pub(crate) const VOID: f64 = 0.25;

/// The weakest stretch along `path` (its vertices in order, `step` apart at most): the least
/// mean count of points within `reach` over a window of `window` vertices, the arc length
/// at that window's middle, and the median count at a vertex.
fn weakest(
    path: &[[f64; 3]],
    tree: &ImmutableKdTree<f64, 3>,
    reach: f64,
    window: usize,
) -> (f64, f64, f64) {
    let counts: Vec<f64> = path
        .iter()
        .map(|p| {
            tree.query(p)
                .within::<SquaredEuclidean<f64>>(reach * reach)
                .unsorted()
                .execute()
                .len() as f64
        })
        .collect();
    let mut along = Vec::with_capacity(path.len());
    let mut total = 0.0;
    along.push(0.0);
    for pair in path.windows(2) {
        total += distance(pair[0], pair[1]);
        along.push(total);
    }
    let window = window.clamp(1, counts.len().max(1));
    let mut sorted = counts.clone();
    sorted.sort_by(f64::total_cmp);
    let typical = sorted.get(sorted.len() / 2).copied().unwrap_or(0.0);
    let (mut least, mut middle) = (f64::INFINITY, 0.0);
    for start in 0..=counts.len().saturating_sub(window) {
        let mean = counts[start..start + window].iter().sum::<f64>() / window as f64;
        if mean < least {
            least = mean;
            middle = along[start + window / 2];
        }
    }
    (least, middle, typical)
}

/// `path` resampled `step` apart at most.
fn resampled(path: &[[f64; 3]], step: f64) -> Vec<[f64; 3]> {
    let mut out = Vec::with_capacity(path.len());
    for pair in path.windows(2) {
        let pieces = ((distance(pair[0], pair[1]) / step).ceil() as usize).max(1);
        for j in 0..pieces {
            let t = j as f64 / pieces as f64;
            out.push([0, 1, 2].map(|k| pair[0][k] + t * (pair[1][k] - pair[0][k])));
        }
    }
    out.extend(path.last());
    out
}

/// The support of `fit`'s weakest stretch over its median support (see [`cut_at_void`]),
/// or `None` when it cannot be measured.
pub(crate) fn weakest_share(ordered: &[[f64; 3]], fit: &Followed) -> Option<f64> {
    let noise = fit.noise;
    if !(noise > 0.0 && noise.is_finite()) {
        return None;
    }
    let tree = ImmutableKdTree::<f64, 3>::new_from_slice(ordered).ok()?;
    let step = noise / SAMPLES_PER_NOISE;
    let window = (SUPPORT_WINDOW * SAMPLES_PER_NOISE).round() as usize;
    let samples = ((fit.length / step).ceil() as usize).clamp(64, 100_000);
    let line = fit.approximation.curve.polyline(samples);
    let (least, _, typical) = weakest(&line, &tree, SUPPORT_REACH * noise, window);
    (typical > 0.0).then(|| least / typical)
}

/// `followed` (an open band's fit of `ordered`), or the band followed again from a cut at
/// its weakest stretch or from the longer side of it, when that stretch has less than
/// [`WEAKER`] times the support of the gap between its ends or [`VOID`] times its own
/// median (see the module documentation): of the three, the fit whose weakest stretch has
/// the most points.
///
/// # Errors
/// As [`fit_band_in_order`].
pub(crate) fn cut_at_void(
    ordered: &[[f64; 3]],
    dimension: usize,
    fixed: Option<usize>,
    options: &ApproximationOptions,
    followed: Followed,
) -> Result<Followed> {
    let noise = followed.noise;
    let Ok(tree) = ImmutableKdTree::<f64, 3>::new_from_slice(ordered) else {
        return Ok(followed);
    };
    if !(noise > 0.0 && noise.is_finite()) {
        return Ok(followed);
    }
    let step = noise / SAMPLES_PER_NOISE;
    let reach = SUPPORT_REACH * noise;
    let window = (SUPPORT_WINDOW * SAMPLES_PER_NOISE).round() as usize;
    let support = |fit: &Followed| {
        let curve = &fit.approximation.curve;
        let samples = ((fit.length / step).ceil() as usize).clamp(64, 100_000);
        let line = curve.polyline(samples);
        let inside = weakest(&line, &tree, reach, window);
        let ends = [line[0], line[line.len() - 1]];
        let between = weakest(&resampled(&ends, step), &tree, reach, window).0;
        (inside, between, line)
    };
    let ((inside, cut, typical), between, line) = support(&followed);
    if inside >= WEAKER * between && inside >= VOID * typical {
        return Ok(followed);
    }
    // Each point's place along the fit: its foot's arc length.
    let gap = distance(line[0], line[line.len() - 1]);
    let vertices = line.clone();
    let polyline = Polyline::new(line, false);
    let total = polyline.length();
    let place = |p: &[f64; 3]| polyline.foot(*p, 0.0).0.clamp(0.0, total);
    // The new order starts past the weak stretch, runs to the fit's end, across the gap
    // between its ends and on to the weak stretch.
    let mut keyed: Vec<(f64, usize)> = followed
        .order
        .iter()
        .map(|&i| {
            let s = place(&ordered[i]);
            (
                if s > cut {
                    s - cut
                } else {
                    total - cut + gap + s
                },
                i,
            )
        })
        .collect();
    keyed.sort_by(|a, b| a.0.total_cmp(&b.0));
    let order: Vec<usize> = keyed.iter().map(|k| k.1).collect();
    let (first, last) = (keyed[0].0, keyed[keyed.len() - 1].0);
    let span = (last - first).max(f64::MIN_POSITIVE);
    let places: Vec<f64> = keyed.iter().map(|k| (k.0 - first) / span).collect();
    // The band followed again from `order`, at `places` along a band `span` long.
    let refollow = |order: &[usize], places: Vec<f64>, span: f64| {
        fit_band_in_order(
            ordered,
            order,
            (dimension, false),
            (noise, places),
            fixed,
            span,
            options,
        )
    };
    let Ok(again) = refollow(&order, places, span) else {
        return Ok(followed);
    };
    let ((inside_again, _, _), _, _) = support(&again);
    let mut best = if inside_again > inside {
        (inside_again, again)
    } else {
        (inside, followed)
    };
    // Or the fit trimmed at the weak stretch: the points ordered by their feet on its longer
    // side alone. A fit whose end ran on round a bend into the next turn of a helix is weak
    // where it crosses between the turns, and has no gap between its ends to bridge.
    let mut along = 0.0;
    let mut side: Vec<[f64; 3]> = Vec::new();
    let keep_start = cut > 0.5 * total;
    for (j, v) in vertices.iter().enumerate() {
        if j > 0 {
            along += distance(vertices[j - 1], *v);
        }
        if (along <= cut) == keep_start {
            side.push(*v);
        }
    }
    if side.len() >= 2 {
        let piece = Polyline::new(side, false);
        let places: Vec<(f64, usize)> = best
            .1
            .order
            .iter()
            .map(|&i| (piece.foot(ordered[i], 0.0).0, i))
            .collect();
        if let Some((order, places, span)) = ordered_by_place(places)
            && let Ok(trimmed) = refollow(&order, places, span)
        {
            let ((inside_trimmed, _, _), _, _) = support(&trimmed);
            if inside_trimmed > best.0 {
                best = (inside_trimmed, trimmed);
            }
        }
    }
    Ok(best.1)
}
