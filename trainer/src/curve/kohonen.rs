//! The 1-D Kohonen chain of the paper: m ≥ n neurons over 2-D or 3-D points, open or closed.
//!
//! Each presentation of an input point x finds the winner c (the nearest neuron, Euclidean)
//! and moves every neuron j of its neighbourhood towards x:
//! wⱼ ← wⱼ + η(t) · h(|j − c|) · (x − wⱼ), with the paper's η(t) = η₀(1 − t/T) and a Gaussian
//! h(d) = exp(−d²/2σ(t)²) whose radius σ shrinks geometrically from σ₀ to σ_T (distance `d`
//! along the chain, cyclic for a ring). Points are presented in epochs, each a fresh random
//! permutation of the input (the paper cycles through them in input order).
//!
//! Complexity: T = max(epochs · n, min_iterations) presentations, each an exact
//! nearest-neuron query on a uniform grid that follows the moving neurons (a few cells and
//! neurons once the chain has formed) plus an update of ≤ 2⌈3σ(t)⌉ + 1 neurons; with the
//! geometric radius the mean update is about 6(σ₀ − σ_T)/ln(σ₀/σ_T) neurons, O(m / log m).
//! So O(n · m / log m) in all, memory O(n + m). Beyond
//! [`KohonenOptions::max_trained_points`] the chain learns from a random sample of that many
//! points, so training time stops growing with the input (`neurosurf curve bench`:
//! `docs/performance/curve.md`).

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

use super::convergence::{Convergence, check_chain, point_spacing};
use super::points::CurvePoints;
use super::schedule::{Schedule, check_settings};
use super::som;

/// Most neurons a chain may have.
pub const MAX_NEURONS: usize = 16_000_000;

/// Whether the chain has two ends (an open curve) or is a ring (a closed curve).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Topology {
    /// A chain with two free ends.
    Open,
    /// A ring: the last neuron neighbours the first.
    Closed,
}

/// Settings of [`train_chain`]. Lengths (ε, the line tolerance) are fractions of the
/// points' median nearest-neighbour distance, so they do not depend on the data's units.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct KohonenOptions {
    /// Open chain or ring (open).
    pub topology: Topology,
    /// Neurons per input point, m = ratio · n (4: the paper's 80 neurons for 20 points).
    pub neurons_per_point: usize,
    /// Passes over the input; T = epochs · n presentations (30).
    pub epochs: usize,
    /// Least T whatever n (20 000), so small inputs still get a full schedule.
    pub min_iterations: usize,
    /// η₀ of η(t) = η₀(1 − t/T) (0.6).
    pub initial_rate: f64,
    /// σ₀ as a fraction of m (0.05; at most half the ring or the whole chain is used).
    pub initial_radius: f64,
    /// σ_T in neurons (0.7: at the end a neighbour moves ~36 % as far as the winner).
    pub final_radius: f64,
    /// ε of the paper's convergence test, × the median nearest-neighbour distance (0.1).
    pub epsilon: f64,
    /// Tolerance of the strong test (a non-winning neuron's distance to the line through its
    /// two chain neighbours), × the median nearest-neighbour distance (0.1).
    pub line_tolerance: f64,
    /// Stop at the end of the first epoch after T/2 where both tests pass (true).
    pub early_stop: bool,
    /// Seed of the initial weights and the presentation order (0).
    pub seed: u64,
    /// Most points the chain is trained on (2 000): from larger inputs a random sample of
    /// this many, drawn with the seed. Training costs about n·m/log m, so a chain over every
    /// point of a large input would take minutes; the sample fixes the curve's course, and
    /// [`order_points`](super::order_points) places every point along it.
    #[serde(default = "default_trained_points")]
    pub max_trained_points: usize,
}

fn default_trained_points() -> usize {
    2_000
}

impl Default for KohonenOptions {
    fn default() -> Self {
        KohonenOptions {
            topology: Topology::Open,
            neurons_per_point: 4,
            epochs: 30,
            min_iterations: 20_000,
            initial_rate: 0.6,
            initial_radius: 0.05,
            final_radius: 0.7,
            epsilon: 0.1,
            line_tolerance: 0.1,
            early_stop: true,
            seed: 0,
            max_trained_points: default_trained_points(),
        }
    }
}

impl KohonenOptions {
    /// Options with the given topology and the defaults otherwise.
    pub fn with_topology(topology: Topology) -> Self {
        KohonenOptions {
            topology,
            ..Self::default()
        }
    }

    /// Checks every setting.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the offending setting.
    pub fn check(&self) -> Result<()> {
        if self.max_trained_points < super::points::MIN_POINTS {
            return Err(Error::invalid(format!(
                "the chain learns from at least {} points, but max_trained_points \
                 (--chain-points) is {}; give {} or more",
                super::points::MIN_POINTS,
                self.max_trained_points,
                super::points::MIN_POINTS
            )));
        }
        if self.neurons_per_point == 0 {
            return Err(Error::invalid(
                "Kohonen option neurons_per_point must be at least 1 (m ≥ n)",
            ));
        }
        check_settings(
            "Kohonen",
            self.epochs,
            self.initial_rate,
            &[
                ("initial_radius", self.initial_radius),
                ("final_radius", self.final_radius),
                ("epsilon", self.epsilon),
                ("line_tolerance", self.line_tolerance),
            ],
        )
    }

    /// m for `points` input points.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when m would exceed [`MAX_NEURONS`].
    pub fn neuron_count(&self, points: usize) -> Result<usize> {
        match points.checked_mul(self.neurons_per_point) {
            Some(m) if m <= MAX_NEURONS => Ok(m),
            _ => Err(Error::invalid(format!(
                "{points} points × {} neurons per point exceeds {MAX_NEURONS} neurons",
                self.neurons_per_point
            ))),
        }
    }
}

/// A trained chain: neuron weights in chain order.
#[derive(Clone, Debug, PartialEq)]
pub struct KohonenChain {
    /// Open chain or ring.
    pub topology: Topology,
    /// 2 or 3 (2-D neurons have z = 0).
    pub dimension: usize,
    /// The weights (output vectors) o₁ … oₘ, in chain order.
    pub neurons: Vec<[f64; 3]>,
}

/// What [`train_chain`] did.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrainingReport {
    /// m.
    pub neurons: usize,
    /// The points the chain learned from: all of them, or a sample of
    /// [`KohonenOptions::max_trained_points`].
    pub trained_points: usize,
    /// Presentations made (less than `scheduled_iterations` after an early stop).
    pub iterations: usize,
    /// T of the schedule.
    pub scheduled_iterations: usize,
    /// The median nearest-neighbour distance of the input, the unit of ε and the tolerance.
    pub spacing: f64,
    /// Both convergence tests on the final chain, in the data's units.
    pub convergence: Convergence,
}

/// Trains a chain on `points` (on a sample of them beyond
/// [`KohonenOptions::max_trained_points`]). Deterministic: the same points and options give bit-identical
/// weights.
///
/// # Errors
/// [`Error::InvalidInput`] for invalid options or too many neurons.
pub fn train_chain(
    points: &CurvePoints,
    options: &KohonenOptions,
) -> Result<(KohonenChain, TrainingReport)> {
    options.check()?;
    let sample = points.sample(options.max_trained_points, options.seed);
    let points = &sample;
    let n = points.len();
    let m = options.neuron_count(n)?;
    let closed = options.topology == Topology::Closed;
    let total = n
        .saturating_mul(options.epochs)
        .max(options.min_iterations)
        .max(1);
    let schedule = Schedule {
        total,
        initial_rate: options.initial_rate,
        initial_radius: (options.initial_radius * m as f64).max(options.final_radius),
        final_radius: options.final_radius,
    };
    let spacing = point_spacing(points);
    let epsilon = options.epsilon * spacing;
    let tolerance = options.line_tolerance * spacing;

    let mut chain = Chain {
        m,
        closed,
        early_stop: options.early_stop,
        data: points.points(),
        epsilon,
        tolerance,
        convergence: None,
    };
    let som = som::train(
        points,
        m,
        &schedule,
        options.seed,
        None,
        "chain",
        &mut chain,
    )?;
    let t = som.presented;
    let convergence = match chain.convergence {
        Some(c) => c,
        None => check_chain(
            chain.data,
            &som.neurons,
            &som.grid,
            closed,
            epsilon,
            tolerance,
        ),
    };
    let neurons = som.neurons;
    let report = TrainingReport {
        neurons: m,
        trained_points: n,
        iterations: t,
        scheduled_iterations: total,
        spacing,
        convergence,
    };
    let chain = KohonenChain {
        topology: options.topology,
        dimension: points.dimension(),
        neurons,
    };
    Ok((chain, report))
}

/// The chain's neighbourhood (offsets along it, cyclic for a ring) and its early stop: the
/// paper's two convergence tests, checked at the end of each epoch after half the schedule.
struct Chain<'a> {
    m: usize,
    closed: bool,
    early_stop: bool,
    data: &'a [[f64; 3]],
    epsilon: f64,
    tolerance: f64,
    convergence: Option<Convergence>,
}

impl som::Neighbourhood for Chain<'_> {
    fn reach_limit(&self) -> usize {
        if self.closed {
            (self.m - 1) / 2
        } else {
            self.m - 1
        }
    }

    fn pull(&self, c: usize, rate: f64, table: &[f64], mut pull: impl FnMut(usize, f64)) {
        let m = self.m;
        for (d, &h) in table.iter().enumerate() {
            let gain = rate * h;
            if d == 0 {
                pull(c, gain);
            } else if self.closed {
                pull((c + d) % m, gain);
                pull((c + m - d) % m, gain);
            } else {
                if c + d < m {
                    pull(c + d, gain);
                }
                if d <= c {
                    pull(c - d, gain);
                }
            }
        }
    }

    fn converged(&mut self, som: &som::Som, total: usize) -> bool {
        if !self.early_stop || 2 * som.presented < total {
            return false;
        }
        let check = check_chain(
            self.data,
            &som.neurons,
            &som.grid,
            self.closed,
            self.epsilon,
            self.tolerance,
        );
        let converged = check.converged();
        if converged {
            self.convergence = Some(check);
        }
        converged
    }
}
