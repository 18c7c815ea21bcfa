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
use neurosurf_core::caoen::{Blending, Domain};

use super::network::{CaoEnNetwork, on_domain};
use crate::error::{Error, Result};

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
