//! Timing of the curve pipeline (Kohonen training + ordering + both fits).

use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::error::Result;

use super::pipeline::{CurveOptions, reconstruct_curve};
use super::samples::{SampleCurve, SampleOptions, sample_curve};

/// The point counts of the standard benchmark: the paper's 20, then 200 to 20 000 (beyond
/// 2 000 the chain learns from a sample of 2 000).
pub const BENCHMARK_SIZES: [usize; 5] = [20, 200, 2_000, 5_000, 20_000];

/// One benchmark measurement.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BenchmarkRow {
    /// Input points n.
    pub points: usize,
    /// Chain neurons m.
    pub neurons: usize,
    /// The points the chain learned from.
    pub trained_points: usize,
    /// Presentations the training made.
    pub iterations: usize,
    /// Wall-clock seconds for training + ordering + approximation + interpolation.
    pub seconds: f64,
}

/// Times [`reconstruct_curve`] with default options on a noisy ellipse sample
/// ([`SampleCurve::Ellipse`], closed) of each size in `sizes`, one run each, single
/// threaded. Sampling is not timed.
///
/// # Errors
/// As [`sample_curve`] and [`reconstruct_curve`] (e.g. a size below 4).
pub fn benchmark(sizes: &[usize], seed: u64) -> Result<Vec<BenchmarkRow>> {
    sizes
        .iter()
        .map(|&count| {
            let sample = sample_curve(
                SampleCurve::Ellipse,
                &SampleOptions {
                    count,
                    seed,
                    ..SampleOptions::default()
                },
            )?;
            let points = sample.curve_points()?;
            let options = CurveOptions::new(SampleCurve::Ellipse.topology(), seed);
            let start = Instant::now();
            let result = reconstruct_curve(&points, &options)?;
            let seconds = start.elapsed().as_secs_f64();
            Ok(BenchmarkRow {
                points: count,
                neurons: result.training.neurons,
                trained_points: result.training.trained_points,
                iterations: result.training.iterations,
                seconds,
            })
        })
        .collect()
}
