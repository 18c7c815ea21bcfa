//! Points and their parameters → a trained [`SurfaceNetwork`] (§5): normalization, the
//! stratified split, the topology search and a final refinement on all training points.

use super::network::SurfaceNetwork;
use super::split::{Split, stratified_split};
use super::topology::{TopologyOptions, TopologySearch, search};
use super::train::{Samples, TrainSettings, mean_square, train};
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
    let samples = normalized(&template, points, parameters);
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
        network = refined(network, &samples, &split, &options.train);
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

/// `fit` refined (warm-started, with `settings`) without the points `left_out`,
/// which leave its training and validation sets; its errors are then those of the other
/// points, and its split indexes them in their order. `points` and `parameters` are those
/// `fit` was fitted to. The refined network is kept only when its validation error (without
/// `left_out`) is not worse.
pub(crate) fn refine_without(
    fit: &SurfaceFit,
    points: &[[f64; 3]],
    parameters: &[[f64; 2]],
    settings: &TrainSettings,
    left_out: &[usize],
) -> SurfaceFit {
    let started = std::time::Instant::now();
    let mut out = vec![false; points.len()];
    for &i in left_out {
        if let Some(flag) = out.get_mut(i) {
            *flag = true;
        }
    }
    let keep =
        |list: &[usize]| -> Vec<usize> { list.iter().copied().filter(|&i| !out[i]).collect() };
    let network = &fit.network;
    let samples = normalized(network, points, parameters);
    let split = Split {
        training: keep(&fit.split.training),
        validation: keep(&fit.split.validation),
        test: keep(&fit.split.test),
    };
    let network = refined(network.clone(), &samples, &split, settings);
    let kept = keep(&(0..points.len()).collect::<Vec<_>>());
    // The split, indexed by the kept points in their order.
    let mut rank = vec![usize::MAX; points.len()];
    for (r, &i) in kept.iter().enumerate() {
        rank[i] = r;
    }
    let split = Split {
        training: split.training.iter().map(|&i| rank[i]).collect(),
        validation: split.validation.iter().map(|&i| rank[i]).collect(),
        test: split.test.iter().map(|&i| rank[i]).collect(),
    };
    let rms_error =
        mean_square(&network, &samples, &kept).sqrt() * network.output_scale * 3f64.sqrt();
    let (lo, hi) = bounds(kept.iter().map(|&i| points[i].as_slice()), 3);
    let diagonal = (0..3).map(|a| (hi[a] - lo[a]).powi(2)).sum::<f64>().sqrt();
    SurfaceFit {
        network,
        search: fit.search.clone(),
        split,
        rms_error,
        relative_rms_error: rms_error / diagonal,
        search_seconds: fit.search_seconds,
        refinement_seconds: fit.refinement_seconds + started.elapsed().as_secs_f64(),
    }
}

/// `network` trained further on `split.training` with `settings`, or `network` itself when
/// that is not worse on `split.validation`.
fn refined(
    network: SurfaceNetwork,
    samples: &Samples,
    split: &Split,
    settings: &TrainSettings,
) -> SurfaceNetwork {
    let mut trained = network.clone();
    train(
        &mut trained,
        samples,
        &split.training,
        &split.validation,
        settings,
    );
    if mean_square(&trained, samples, &split.validation)
        <= mean_square(&network, samples, &split.validation)
    {
        trained
    } else {
        network
    }
}

/// `points` and `parameters` in `network`'s normalized units.
fn normalized(network: &SurfaceNetwork, points: &[[f64; 3]], parameters: &[[f64; 2]]) -> Samples {
    Samples {
        inputs: parameters
            .iter()
            .map(|p| network.normalize_input(p[0], p[1]))
            .collect(),
        targets: points
            .iter()
            .map(|&p| network.normalize_output(p))
            .collect(),
    }
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
