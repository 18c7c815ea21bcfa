//! Embedding and fitting a scanned patch without its outliers: [`find_outliers`] before
//! [`embed_points`] and [`fit_network`].

use std::time::Instant;

use super::embedding::{LleOptions, Parameterization, embed_points};
use super::fit::{SurfaceFit, fit_network, refine_without};
use super::fit_outliers::find_fit_outliers;
use super::outliers::{OutlierOptions, Outliers, find_outliers};
use super::topology::TopologyOptions;
use crate::error::{Error, Result};

/// A fit and the points it kept.
#[derive(Clone, Debug)]
pub struct RobustFit {
    /// Indices (into the input) of the points the final network was fitted to.
    pub kept: Vec<usize>,
    /// Their (u, v), in the order of `kept`.
    pub parameters: Vec<[f64; 2]>,
    /// Neighbours per point k of the embedding (`None` when parameters were given).
    pub neighbors: Option<usize>,
    /// How the points were parameterized (`None` when parameters were given).
    pub parameterization: Option<Parameterization>,
    /// Points left out before the embedding, in input order: off their neighbours' planes,
    /// or isolated.
    pub off_surface: Vec<usize>,
    /// Points left out after the first fit, in input order: their height off the network
    /// stands out from their neighbours' (`OutlierOptions::fit_deviations`); the network
    /// was refined without them.
    pub off_fit: Vec<usize>,
    /// The final fit.
    pub fit: SurfaceFit,
    /// Wall time of the outlier search and the embedding (s).
    pub embedding_seconds: f64,
    /// Wall time of the fits (s).
    pub fitting_seconds: f64,
}

/// Embeds `points` (unless `parameters` are given, one per point) and fits a network; with
/// `outliers`, without the points off the surface.
///
/// # Errors
/// Every error of [`find_outliers`], [`embed_points`] and [`fit_network`], and
/// [`Error::InvalidInput`] when `parameters` has another length than `points`.
pub fn fit_robustly(
    points: &[[f64; 3]],
    parameters: Option<&[[f64; 2]]>,
    embedding: &LleOptions,
    topology: &TopologyOptions,
    outliers: Option<&OutlierOptions>,
) -> Result<RobustFit> {
    if let Some(given) = parameters
        && given.len() != points.len()
    {
        return Err(Error::invalid(format!(
            "{} points but {} parameter pairs",
            points.len(),
            given.len()
        )));
    }
    let start = Instant::now();
    let first = match outliers {
        Some(options) => find_outliers(points, options)?,
        None => Outliers {
            kept: (0..points.len()).collect(),
            removed: Vec::new(),
        },
    };
    let kept = first.kept;
    let chosen: Vec<[f64; 3]> = kept.iter().map(|&i| points[i]).collect();
    let (uv, neighbors, parameterization) = match parameters {
        Some(given) => (
            kept.iter().map(|&i| given[i]).collect::<Vec<_>>(),
            None,
            None,
        ),
        None => {
            let e = embed_points(&chosen, embedding)?;
            (e.parameters, Some(e.neighbors), Some(e.parameterization))
        }
    };
    let embedding_seconds = start.elapsed().as_secs_f64();

    let start = Instant::now();
    let mut fit = fit_network(&chosen, &uv, topology)?;
    let mut kept = kept;
    let mut uv = uv;
    let mut left_out_of_fit = Vec::new();
    if let Some(options) = outliers {
        // Points near the surface but off it, which the search before the embedding could
        // not tell from a rough surface, stand out against the fitted network.
        let off_fit = find_fit_outliers(&fit.network, &chosen, &uv, options.fit_deviations);
        if !off_fit.is_empty() {
            fit = refine_without(&fit, &chosen, &uv, &topology.train, &off_fit);
            let mut out = vec![false; kept.len()];
            for &i in &off_fit {
                out[i] = true;
            }
            left_out_of_fit = off_fit.iter().map(|&i| kept[i]).collect();
            uv = (0..kept.len())
                .filter(|&i| !out[i])
                .map(|i| uv[i])
                .collect();
            kept = (0..kept.len())
                .filter(|&i| !out[i])
                .map(|i| kept[i])
                .collect();
        }
    }
    Ok(RobustFit {
        kept,
        parameters: uv,
        neighbors,
        parameterization,
        off_surface: first.removed,
        off_fit: left_out_of_fit,
        fit,
        embedding_seconds,
        fitting_seconds: start.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parametric::{SampleSurface, sample_surface};
    use rand::{Rng, SeedableRng};

    /// RMS vertical distance of the network at the kept points' (u, v) to z = 0.25 sin(2.5x)
    /// cos(2y), as a fraction of the diagonal (2.9).
    fn wavy_error(fit: &RobustFit) -> f64 {
        let squares: Vec<f64> = fit
            .parameters
            .iter()
            .map(|&[u, v]| {
                let p = fit.fit.network.evaluate(u, v).position;
                (p[2] - 0.25 * (2.5 * p[0]).sin() * (2.0 * p[1]).cos()).powi(2)
            })
            .collect();
        (squares.iter().sum::<f64>() / squares.len() as f64).sqrt() / 2.9
    }

    #[test]
    fn two_percent_outliers_cost_little_once_left_out() {
        let topology = TopologyOptions {
            max_neurons: 8,
            ..TopologyOptions::default()
        };
        let lle = LleOptions::default();
        let options = OutlierOptions::default();
        let run = |points: &[[f64; 3]], outliers| {
            wavy_error(&fit_robustly(points, None, &lle, &topology, outliers).unwrap())
        };
        // Every seed within 1.5× of the clean fit (measured 0.69–1.09); kept, the median
        // is over 2×.
        let (mut robust, mut plain) = (Vec::new(), Vec::new());
        for seed in 1..=5 {
            let clean = sample_surface(SampleSurface::Wavy, 1_500, 0.002, seed)
                .unwrap()
                .points;
            // 2 % more points, uniform in the bounding box grown by 10 % per side.
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            let (lo, hi) = crate::geometry::vector::bounds(&clean);
            let mut noisy = clean.clone();
            for _ in 0..30 {
                noisy.push([0, 1, 2].map(|k| {
                    let g = 0.1 * (hi[k] - lo[k]);
                    rng.random_range(lo[k] - g..hi[k] + g)
                }));
            }
            let reference = run(&clean, Some(&options));
            robust.push(run(&noisy, Some(&options)) / reference);
            plain.push(run(&noisy, None) / reference);
        }
        robust.sort_by(f64::total_cmp);
        plain.sort_by(f64::total_cmp);
        eprintln!("against the clean fit: left out {robust:.2?}, kept {plain:.2?}");
        assert!(robust[4] < 1.5, "{robust:?}");
        assert!(plain[2] > 2.0, "{plain:?}");
    }
}
