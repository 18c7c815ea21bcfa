//! The paper's planned extension: a 2-D Kohonen map, a grid of neurons over 3-D points.
//!
//! Training is the chain's with a grid neighbourhood: the winner c = (c_u, c_v) moves every
//! neuron (i, j) with |i − c_u|, |j − c_v| ≤ ⌈3σ⌉ by η(t)·h(i − c_u)·h(j − c_v)·(x − w), h the
//! Gaussian of the chain, η(t) = η₀(1 − t/T), σ shrinking geometrically. Winner queries use
//! the same exact moving-neuron grid as the chain. Cost per presentation: one query plus
//! (2⌈3σ⌉ + 1)² updates.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

use super::kohonen::MAX_NEURONS;
use super::points::CurvePoints;
use super::schedule::{Schedule, check_settings};
use super::som;

/// Settings of [`train_map`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct KohonenMapOptions {
    /// Neurons along u (12).
    pub columns: usize,
    /// Neurons along v (12).
    pub rows: usize,
    /// Passes over the input; T = epochs · n presentations (20).
    pub epochs: usize,
    /// Least T whatever n (20 000).
    pub min_iterations: usize,
    /// η₀ (0.6).
    pub initial_rate: f64,
    /// σ₀ as a fraction of max(columns, rows) (0.5).
    pub initial_radius: f64,
    /// σ_T in neurons (0.5).
    pub final_radius: f64,
    /// Seed of the initial weights and the presentation order (0).
    pub seed: u64,
}

impl Default for KohonenMapOptions {
    fn default() -> Self {
        KohonenMapOptions {
            columns: 12,
            rows: 12,
            epochs: 20,
            min_iterations: 20_000,
            initial_rate: 0.6,
            initial_radius: 0.5,
            final_radius: 0.5,
            seed: 0,
        }
    }
}

/// A trained grid: `neurons[row * columns + column]`.
#[derive(Clone, Debug, PartialEq)]
pub struct KohonenMap {
    /// Neurons along u.
    pub columns: usize,
    /// Neurons along v.
    pub rows: usize,
    /// The weights, row by row.
    pub neurons: Vec<[f64; 3]>,
}

impl KohonenMap {
    /// The weight of neuron (column, row); `None` outside the grid.
    pub fn at(&self, column: usize, row: usize) -> Option<[f64; 3]> {
        if column < self.columns && row < self.rows {
            self.neurons.get(row * self.columns + column).copied()
        } else {
            None
        }
    }
}

/// What [`train_map`] did.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MapReport {
    /// Presentations made (T).
    pub iterations: usize,
    /// Largest distance from an input point to its nearest neuron.
    pub worst_input_distance: f64,
    /// Mean distance from an input point to its nearest neuron.
    pub mean_input_distance: f64,
}

/// Trains a grid map on `points`. Deterministic for a seed.
///
/// # Errors
/// [`Error::InvalidInput`] for fewer than 2 neurons per direction, more than
/// [`MAX_NEURONS`], zero epochs, or a rate or radius out of range.
pub fn train_map(
    points: &CurvePoints,
    options: &KohonenMapOptions,
) -> Result<(KohonenMap, MapReport)> {
    train_map_from(points, options, None)
}

/// [`train_map`] from the weights `initial` (`columns × rows` of them, row by row) instead
/// of random ones.
///
/// # Errors
/// As [`train_map`].
pub fn train_map_from(
    points: &CurvePoints,
    options: &KohonenMapOptions,
    initial: Option<&[[f64; 3]]>,
) -> Result<(KohonenMap, MapReport)> {
    let (columns, rows) = (options.columns, options.rows);
    if columns < 2 || rows < 2 || columns.saturating_mul(rows) > MAX_NEURONS {
        return Err(Error::invalid(format!(
            "a Kohonen map needs 2..={MAX_NEURONS} neurons with at least 2 per direction, got \
             {columns} × {rows}"
        )));
    }
    check_settings(
        "Kohonen map",
        options.epochs,
        options.initial_rate,
        &[
            ("initial_radius", options.initial_radius),
            ("final_radius", options.final_radius),
        ],
    )?;
    let n = points.len();
    let total = n
        .saturating_mul(options.epochs)
        .max(options.min_iterations)
        .max(1);
    let schedule = Schedule {
        total,
        initial_rate: options.initial_rate,
        initial_radius: (options.initial_radius * columns.max(rows) as f64)
            .max(options.final_radius),
        final_radius: options.final_radius,
    };
    let som = som::train(
        points,
        columns * rows,
        &schedule,
        options.seed,
        initial,
        "map",
        &mut Grid { columns, rows },
    )?;
    let (neurons, grid, t) = (som.neurons, som.grid, som.presented);
    let data = points.points();
    let distances: Vec<f64> = data
        .iter()
        .map(|&x| {
            grid.nearest(x, &neurons, None)
                .map_or(f64::INFINITY, |(_, d)| d.sqrt())
        })
        .collect();
    let report = MapReport {
        iterations: t,
        worst_input_distance: distances.iter().copied().fold(0.0, f64::max),
        mean_input_distance: distances.iter().sum::<f64>() / n as f64,
    };
    Ok((
        KohonenMap {
            columns,
            rows,
            neurons,
        },
        report,
    ))
}

/// The map's neighbourhood: a square of offsets around the winner, weighted by the product of
/// the Gaussian along each direction.
struct Grid {
    columns: usize,
    rows: usize,
}

impl som::Neighbourhood for Grid {
    fn reach_limit(&self) -> usize {
        self.columns.max(self.rows)
    }

    fn pull(&self, c: usize, rate: f64, table: &[f64], mut pull: impl FnMut(usize, f64)) {
        let (columns, rows) = (self.columns, self.rows);
        let (cu, cv) = (c % columns, c / columns);
        let reach = table.len() - 1;
        for row in cv.saturating_sub(reach)..(cv + reach + 1).min(rows) {
            let hv = rate * table[row.abs_diff(cv)];
            for column in cu.saturating_sub(reach)..(cu + reach + 1).min(columns) {
                pull(row * columns + column, hv * table[column.abs_diff(cu)]);
            }
        }
    }
}
