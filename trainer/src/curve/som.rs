//! The presentation loop the chain and the grid map share: random initial weights in the
//! points' bounding box, epochs of shuffled presentations, the exact winner on the moving
//! neuron grid, and a neighbourhood pull whose shape (a chain, a grid) the caller gives.

use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::error::{Error, Result};

use super::grid::NeuronGrid;
use super::points::CurvePoints;
use super::schedule::{Schedule, gaussian_table, radius_block};

/// A self-organizing map being trained: its neurons and their search grid.
pub(crate) struct Som {
    /// Weights, one per neuron.
    pub neurons: Vec<[f64; 3]>,
    /// The exact nearest-neuron grid, kept up to date with `neurons`.
    pub grid: NeuronGrid,
    /// Presentations made.
    pub presented: usize,
}

/// What the caller decides: which neurons a winner pulls, and when to stop early.
pub(crate) trait Neighbourhood {
    /// Farthest neighbourhood offset that is still a distinct neuron (the Gaussian table is
    /// cut there).
    fn reach_limit(&self) -> usize;
    /// Calls `pull(j, gain)` for every neuron j of winner `c`'s neighbourhood, with the
    /// Gaussian weights `table` (index = offset) and the learning rate `rate`.
    fn pull(&self, c: usize, rate: f64, table: &[f64], pull: impl FnMut(usize, f64));
    /// At the end of each epoch: whether training may stop here.
    fn converged(&mut self, _som: &Som, _total: usize) -> bool {
        false
    }
}

/// Trains `count` neurons on `points` for `schedule.total` presentations (fewer when
/// `shape` says it converged), seeded by `seed`, from the weights `initial` (`count` of them)
/// or random ones. `what` names the map in errors.
///
/// # Errors
/// [`Error::InvalidInput`] when a winner cannot be found (weights became non-finite).
pub(crate) fn train(
    points: &CurvePoints,
    count: usize,
    schedule: &Schedule,
    seed: u64,
    initial: Option<&[[f64; 3]]>,
    what: &str,
    shape: &mut impl Neighbourhood,
) -> Result<Som> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (lower, upper) = points.bounds();
    let neurons: Vec<[f64; 3]> = match initial {
        Some(initial) if initial.len() == count => initial.to_vec(),
        _ => (0..count)
            .map(|_| [0, 1, 2].map(|k| lower[k] + rng.random::<f64>() * (upper[k] - lower[k])))
            .collect(),
    };
    let grid = NeuronGrid::new(lower, upper, &neurons);
    let mut som = Som {
        neurons,
        grid,
        presented: 0,
    };
    let data = points.points();
    let total = schedule.total;
    let mut order: Vec<usize> = (0..data.len()).collect();
    let mut table = Vec::new();
    let block = radius_block(total);
    let limit = shape.reach_limit();
    while som.presented < total {
        order.shuffle(&mut rng);
        for &p in &order {
            let t = som.presented;
            if t == total {
                break;
            }
            if t.is_multiple_of(block) {
                gaussian_table(schedule.radius(t), limit, &mut table);
            }
            let x = data[p];
            let Some((c, _)) = som.grid.nearest(x, &som.neurons, None) else {
                return Err(Error::invalid(format!(
                    "no winner for input point {p}: the {what}'s weights became non-finite"
                )));
            };
            let Som { neurons, grid, .. } = &mut som;
            shape.pull(c, schedule.rate(t), &table, |j, gain| {
                let w = &mut neurons[j];
                for k in 0..3 {
                    w[k] += gain * (x[k] - w[k]);
                }
                grid.moved(j, *w);
            });
            som.presented += 1;
        }
        if som.presented < total && shape.converged(&som, total) {
            break;
        }
    }
    Ok(som)
}
