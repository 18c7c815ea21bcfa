//! Points and their parameters → a trained [`SurfaceNetwork`] (§5): normalization, the
//! stratified split, the topology search and a final refinement on all training points.

use super::network::SurfaceNetwork;
use super::split::{Split, stratified_split};
use super::topology::{TopologyOptions, TopologySearch, search};
use super::train::{Samples, mean_square, train};
use crate::error::{Error, Result};

/// Fewest points a network is fitted to (the split needs a few of each kind).
pub const MIN_FIT_POINTS: usize = 10;

/// A fitted surface network and how it was chosen.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SurfaceFit {
    /// The network.
    pub network: SurfaceNetwork,
    /// Every configuration tried.
    pub search: TopologySearch,
    /// The 85 / 10 / 5 split used.
    pub split: Split,
    /// RMS distance between the network and all points, in the points' units.
    pub rms_error: f64,
    /// The same as a fraction of the points' bounding-box diagonal.
    pub relative_rms_error: f64,
    /// Wall-clock seconds of the §5.2 search (timing only, not a result).
    pub search_seconds: f64,
    /// Wall-clock seconds of the final refinement on all training points (timing only).
    pub refinement_seconds: f64,
}

/// Fits (u, v) → p to `points` at `parameters` with the §5.2 topology search.
///
/// # Errors
/// [`Error::InvalidInput`] for different lengths, fewer than [`MIN_FIT_POINTS`] points,
/// non-finite values, or a degenerate parameter or point box.
pub fn fit_network(
    points: &[[f64; 3]],
    parameters: &[[f64; 2]],
    options: &TopologyOptions,
) -> Result<SurfaceFit> {
    super::check_capacity(options.max_layers, options.max_neurons)?;
    if points.len() != parameters.len() {
        return Err(Error::invalid(format!(
            "{} points but {} parameter pairs",
            points.len(),
            parameters.len()
        )));
    }
    if points.len() < MIN_FIT_POINTS {
        return Err(Error::invalid(format!(
            "{} points are too few to fit a network: at least {MIN_FIT_POINTS} are needed",
            points.len()
        )));
    }
    if points
        .iter()
        .flatten()
        .chain(parameters.iter().flatten())
        .any(|c| !c.is_finite())
    {
        return Err(Error::invalid("points and parameters must be finite"));
    }
    let (plo, phi) = bounds(parameters.iter().map(|p| p.as_slice()), 2);
    let (xlo, xhi) = bounds(points.iter().map(|p| p.as_slice()), 3);
    let input_scale = [0, 1].map(|a| 0.5 * (phi[a] - plo[a]));
    let half = (0..3).map(|a| 0.5 * (xhi[a] - xlo[a])).fold(0.0, f64::max);
    if input_scale.iter().any(|s| s.is_nan() || *s <= 0.0) || half.is_nan() || half <= 0.0 {
        return Err(Error::invalid("the parameters or the points span no area"));
    }
    let template = SurfaceNetwork::zeros(
        &[1],
        options.activation,
        [0, 1].map(|a| 0.5 * (phi[a] + plo[a])),
        input_scale,
        [0, 1, 2].map(|a| 0.5 * (xhi[a] + xlo[a])),
        half,
    )?;
    let samples = Samples {
        inputs: parameters
            .iter()
            .map(|p| template.normalize_input(p[0], p[1]))
            .collect(),
        targets: points
            .iter()
            .map(|&p| template.normalize_output(p))
            .collect(),
    };
    let split = stratified_split(parameters, options.seed);
    let search_training = subsample(&split.training, options.max_search_points);
    let started = std::time::Instant::now();
    let (mut network, search) = search(&template, &samples, &split, &search_training, options)
        .ok_or_else(|| Error::invalid("no network configuration could be trained"))?;
    // Refine on all training points with the full LM settings: the candidates saw a
    // subsample, or (small sets) a short run of `search_train`.
    let search_seconds = started.elapsed().as_secs_f64();
    let started = std::time::Instant::now();
    if search_training.len() < split.training.len() || options.search_train != options.train {
        let mut refined = network.clone();
        train(
            &mut refined,
            &samples,
            &split.training,
            &split.validation,
            &options.train,
        );
        let before = mean_square(&network, &samples, &split.validation);
        if mean_square(&refined, &samples, &split.validation) <= before {
            network = refined;
        }
    }
    let refinement_seconds = started.elapsed().as_secs_f64();
    let all: Vec<usize> = (0..points.len()).collect();
    let rms_error = mean_square(&network, &samples, &all).sqrt() * half * 3f64.sqrt();
    let diagonal = (0..3)
        .map(|a| (xhi[a] - xlo[a]).powi(2))
        .sum::<f64>()
        .sqrt();
    Ok(SurfaceFit {
        network,
        search,
        split,
        rms_error,
        relative_rms_error: rms_error / diagonal,
        search_seconds,
        refinement_seconds,
    })
}

/// Every `len/max`-th index (all of them when `max` covers the list); the training list is
/// in cell order, so a regular stride keeps the stratification.
fn subsample(indices: &[usize], max: usize) -> Vec<usize> {
    if max == 0 || indices.len() <= max {
        return indices.to_vec();
    }
    (0..max).map(|i| indices[i * indices.len() / max]).collect()
}

/// Per-axis minimum and maximum.
pub(crate) fn bounds<'a>(
    points: impl Iterator<Item = &'a [f64]>,
    dim: usize,
) -> (Vec<f64>, Vec<f64>) {
    let mut lo = vec![f64::INFINITY; dim];
    let mut hi = vec![f64::NEG_INFINITY; dim];
    for p in points {
        for a in 0..dim {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    (lo, hi)
}
