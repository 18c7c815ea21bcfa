//! Building a network from key and target points (paper §3: wᵢ on the sphere, V = the targets)
//! and fitting it so the surface passes through the targets.
//!
//! The paper's surface only passes *near* tᵢ. With the key points fixed, y(wⱼ) = Σᵢ kᵢ(wⱼ)·vᵢ
//! is linear in V, so passing *through* the targets is the n × n linear system K·V = T with
//! Kⱼᵢ = kᵢ(wⱼ) (one right-hand side per output). K is symmetric-like and diagonally dominant
//! for sharp blending; it is solved by an SVD least-squares solve (the minimum-norm V when
//! nearby keys make K singular), so it also serves more data points than keys.
//!
//! q per key point is chosen by [`fit_sharpness`]: a 1-D search over candidate q, one key at a
//! time, scored by the least-squares residual at extra sample points (the fitted V interpolates
//! the keys whatever q is, so only points between keys tell q's). A coordinate search is enough
//! here: each q only shapes its neighbourhood, and every trial is one linear solve.

use nalgebra::DMatrix;
use neurosurf_core::caoen::{Blending, Domain, MAX_SHARPNESS};

use super::network::{CaoEnNetwork, on_domain};
use crate::error::{Error, Result};
use crate::geometry::vector::inner;

/// The 26 unit directions of a cube's faces, edges and corners: the paper's key points.
pub fn cube_directions() -> Vec<Vec<f64>> {
    let mut keys = Vec::new();
    for i in -1_i32..=1 {
        for j in -1_i32..=1 {
            for k in -1_i32..=1 {
                if (i, j, k) != (0, 0, 0) {
                    let n = f64::from(i * i + j * j + k * k).sqrt();
                    keys.push(vec![f64::from(i) / n, f64::from(j) / n, f64::from(k) / n]);
                }
            }
        }
    }
    keys
}

/// The paper's construction: the key points (normalized onto the domain) as weights, the
/// targets as the shape matrix, one q for all.
///
/// # Errors
/// [`Error::InvalidInput`] for mismatched counts or an invalid network (see
/// [`CaoEnNetwork::validate`]).
pub fn from_key_points(
    domain: Domain,
    blending: Blending,
    normalized: bool,
    keys: &[Vec<f64>],
    targets: &[Vec<f64>],
    q: f64,
) -> Result<CaoEnNetwork> {
    if keys.len() != targets.len() {
        return Err(Error::invalid(format!(
            "{} key points but {} targets",
            keys.len(),
            targets.len()
        )));
    }
    let network = CaoEnNetwork {
        domain: domain.code(),
        blending: blending.code(),
        normalized,
        weights: keys.iter().map(|k| on_domain(domain.code(), k)).collect(),
        targets: targets.to_vec(),
        sharpness: vec![q; keys.len()],
    };
    network.validate()?;
    Ok(network)
}

/// Replaces V so that y(xⱼ) = yⱼ for the given source points in the least-squares sense (with
/// `points` = the key points and `values` = the targets: y passes through the targets).
///
/// # Errors
/// [`Error::InvalidInput`] for mismatched counts or dimensions, or when the solve fails.
pub fn fit_shape(
    network: &CaoEnNetwork,
    points: &[Vec<f64>],
    values: &[Vec<f64>],
) -> Result<CaoEnNetwork> {
    let (n, p) = (network.key_count(), network.target_dimension());
    if points.len() != values.len() || points.len() < n {
        return Err(Error::invalid(format!(
            "fitting {n} key points needs at least {n} points with values, got {} and {}",
            points.len(),
            values.len()
        )));
    }
    if values.iter().any(|v| v.len() != p) {
        return Err(Error::invalid("a value has the wrong dimension"));
    }
    let rows: Vec<Vec<f64>> = points.iter().map(|x| network.activations(x)).collect();
    let k = DMatrix::from_fn(points.len(), n, |j, i| rows[j][i]);
    let t = DMatrix::from_fn(points.len(), p, |j, g| values[j][g]);
    let svd = k.svd(true, true);
    let v = svd
        .solve(&t, 1e-12)
        .map_err(|e| Error::invalid(format!("least squares failed: {e}")))?;
    let mut fitted = network.clone();
    fitted.targets = (0..n)
        .map(|i| (0..p).map(|g| v[(i, g)]).collect())
        .collect();
    fitted.validate()?;
    Ok(fitted)
}

/// Root-mean-square distance between y(xⱼ) and yⱼ.
pub fn rms_error(network: &CaoEnNetwork, points: &[Vec<f64>], values: &[Vec<f64>]) -> f64 {
    let total: f64 = points
        .iter()
        .zip(values)
        .map(|(x, v)| {
            let y = network.position(x);
            y.iter().zip(v).map(|(a, b)| (a - b) * (a - b)).sum::<f64>()
        })
        .sum();
    (total / points.len().max(1) as f64).sqrt()
}

/// q per key point by coordinate search over `candidates` (two sweeps), V refitted by
/// [`fit_shape`] on `points`/`values` at every trial; returns the best network and its RMS
/// error on those points.
///
/// # Errors
/// As [`fit_shape`].
pub fn fit_sharpness(
    network: &CaoEnNetwork,
    points: &[Vec<f64>],
    values: &[Vec<f64>],
    candidates: &[f64],
) -> Result<(CaoEnNetwork, f64)> {
    let mut best = fit_shape(network, points, values)?;
    let mut best_error = rms_error(&best, points, values);
    for _sweep in 0..2 {
        for i in 0..network.key_count() {
            for &q in candidates {
                let mut trial = best.clone();
                trial.sharpness[i] = q;
                if trial.validate().is_err() {
                    continue;
                }
                let Ok(trial) = fit_shape(&trial, points, values) else {
                    continue;
                };
                let error = rms_error(&trial, points, values);
                if error < best_error {
                    (best, best_error) = (trial, error);
                }
            }
        }
    }
    Ok((best, best_error))
}

/// The sharpness values [`fit_auto`] tries: whole numbers (power blending takes no other),
/// spaced about 20 % apart up to the core's largest.
pub const AUTO_SHARPNESS: [f64; 19] = [
    1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 10.0, 12.0, 14.0, 16.0, 20.0, 24.0, 28.0, 32.0, 40.0,
    48.0, 64.0,
];

/// How a fit through the key points predicts them: the root-mean-square distance from each
/// target tᵢ to where the surface fitted through every *other* target puts it, y₋ᵢ(wᵢ).
///
/// Computed for all keys at once from the inverse of the key matrix K (Rippa 1999): with
/// C = K⁻¹T, the left-out error of key i is Cᵢ / (K⁻¹)ᵢᵢ. That is exact when leaving a key
/// out removes its column of K as well (unnormalized blending), and close to it for the
/// normalized form, whose other columns also change a little. `None` when K is singular.
pub fn leave_one_out(network: &CaoEnNetwork, targets: &[Vec<f64>]) -> Option<f64> {
    let n = network.key_count();
    if n < 2 || targets.len() != n {
        return None;
    }
    let p = network.target_dimension();
    let rows: Vec<Vec<f64>> = network
        .weights
        .iter()
        .map(|w| network.activations(w))
        .collect();
    let k = DMatrix::from_fn(n, n, |j, i| rows[j][i]);
    let inverse = k.try_inverse()?;
    let t = DMatrix::from_fn(n, p, |j, g| targets[j][g]);
    let c = &inverse * t;
    let mut total = 0.0;
    for i in 0..n {
        let d = inverse[(i, i)];
        for g in 0..p {
            let e = c[(i, g)] / d;
            total += e * e;
        }
    }
    let rms = (total / n as f64).sqrt();
    rms.is_finite().then_some(rms)
}

/// The factors α that [`fit_auto`] tries for q scaled by each key's spacing,
/// qᵢ = α / (wᵢ·wᵢ − the mean wᵢ·wⱼ of its three nearest keys), rounded and kept in 1 … 64.
pub const AUTO_SPACING: [f64; 12] = [
    0.1, 0.14, 0.2, 0.25, 0.3, 0.35, 0.42, 0.5, 0.7, 1.0, 1.4, 2.0,
];

/// For each key, 1 / (wᵢ·wᵢ − the mean of its three largest wᵢ·wⱼ): the sharpness at which
/// F falls to about e⁻¹ of its peak at its nearest neighbours (exactly so for exponential
/// blending on the sphere, where F = e^{q(s − 1)}).
fn spacing_scales(network: &CaoEnNetwork) -> Vec<f64> {
    let w = &network.weights;
    (0..w.len())
        .map(|i| {
            let own = inner(&w[i], &w[i]);
            let mut near: Vec<f64> = (0..w.len())
                .filter(|&j| j != i)
                .map(|j| inner(&w[i], &w[j]))
                .collect();
            near.sort_by(|a, b| b.total_cmp(a));
            let k = near.len().min(3);
            let mean = near[..k].iter().sum::<f64>() / k.max(1) as f64;
            1.0 / (own - mean).max(1e-6)
        })
        .collect()
}

/// The network through the targets at the key points (as [`fit_shape`]) with the q that
/// predicts left-out targets best ([`leave_one_out`]), among one q for every key
/// ([`AUTO_SHARPNESS`]) and q scaled by each key's spacing ([`AUTO_SPACING`]: sharper where
/// keys are dense, wider across gaps); returns it with that error.
///
/// Too small a q for the keys' spacing makes K nearly singular: the fit still passes through
/// every target, but swings far away between them (a star of 100 keys fitted with q = 4
/// strayed more than 200 times its diagonal from it). Too large a q leaves the surface
/// sagging between keys. Both predict a left-out target badly, so the left-out error finds
/// the q between, without knowing the shape.
///
/// # Errors
/// As [`fit_shape`]; [`Error::InvalidInput`] when no q gives a solvable key matrix.
pub fn fit_auto(network: &CaoEnNetwork, targets: &[Vec<f64>]) -> Result<(CaoEnNetwork, f64)> {
    let w = &network.weights;
    for i in 0..w.len() {
        if let Some(j) = (i + 1..w.len()).find(|&j| w[j] == w[i]) {
            return Err(Error::invalid(format!(
                "key points {} and {} (rows {} and {}) lie on the same direction of the domain, \
                 so the fit cannot tell their targets apart; remove one of them",
                i,
                j,
                i + 1,
                j + 1
            )));
        }
    }
    let scales = spacing_scales(network);
    let whole = |q: f64| q.round().clamp(1.0, MAX_SHARPNESS);
    let candidates = AUTO_SHARPNESS.iter().map(|&q| vec![q; scales.len()]).chain(
        AUTO_SPACING
            .iter()
            .map(|&alpha| scales.iter().map(|&b| whole(alpha * b)).collect()),
    );
    let mut best: Option<(Vec<f64>, f64)> = None;
    for sharpness in candidates {
        let mut trial = network.clone();
        trial.sharpness = sharpness;
        if trial.validate().is_err() {
            continue;
        }
        if let Some(error) = leave_one_out(&trial, targets)
            && best.as_ref().is_none_or(|(_, e)| error < *e)
        {
            best = Some((trial.sharpness, error));
        }
    }
    let Some((sharpness, error)) = best else {
        return Err(Error::invalid(
            "no sharpness makes the key matrix solvable: are two key points the same?",
        ));
    };
    let mut chosen = network.clone();
    chosen.sharpness = sharpness;
    let fitted = fit_shape(&chosen, &chosen.weights.clone(), targets)?;
    Ok((fitted, error))
}

/// How a fitted surface behaves between its key points, on dense samples of the whole source
/// domain (an icosphere of 2 562 vertices, a 160 × 80 torus grid, or 4 096 points of a
/// hypersphere), in the targets' units.
#[derive(Copy, Clone, Debug, PartialEq, serde::Serialize)]
pub struct BetweenKeys {
    /// The largest distance from a sample y(x) to the nearest target: below
    /// [`BetweenKeys::target_gap`] for a surface that follows the targets (0.7–0.9 of it on
    /// evenly spread stars), far above it for one that swings away between them.
    pub farthest_from_targets: f64,
    /// The largest distance from a target to its nearest other target: the gap the first
    /// figure is read against.
    pub target_gap: f64,
    /// The targets' bounding diagonal.
    pub diagonal: f64,
}

/// [`BetweenKeys`] of `network`, whose surface is meant to follow `targets`.
pub fn between_keys(network: &CaoEnNetwork, targets: &[Vec<f64>]) -> BetweenKeys {
    let nearest = |y: &[f64], skip: Option<usize>| {
        targets
            .iter()
            .enumerate()
            .filter(|&(j, _)| Some(j) != skip)
            .map(|(_, t)| t.iter().zip(y).map(|(a, b)| (a - b) * (a - b)).sum::<f64>())
            .fold(f64::INFINITY, f64::min)
            .sqrt()
    };
    let samples = super::morph::domain_samples(network, 4);
    let farthest_from_targets = samples
        .iter()
        .map(|x| nearest(&network.position(x), None))
        .fold(0.0, f64::max);
    let target_gap = (0..targets.len())
        .map(|i| nearest(&targets[i], Some(i)))
        .filter(|d| d.is_finite())
        .fold(0.0, f64::max);
    let p = targets.first().map_or(0, Vec::len);
    let diagonal = (0..p)
        .map(|g| {
            let (lo, hi) = targets
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), t| {
                    (l.min(t[g]), h.max(t[g]))
                });
            (hi - lo) * (hi - lo)
        })
        .sum::<f64>()
        .sqrt();
    BetweenKeys {
        farthest_from_targets,
        target_gap,
        diagonal,
    }
}
