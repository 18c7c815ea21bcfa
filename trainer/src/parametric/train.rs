//! Levenberg–Marquardt training of one [`SurfaceNetwork`] with early stopping on the
//! validation set (§5.2 step 3: "train until the validation performance converges").
//!
//! The residuals are the 3·N normalized coordinate errors y(xᵢ) − tᵢ of the training points.
//! J's rows come from one forward pass per four points ([`PackedNetwork::forward`], one AVX2
//! lane per point) and three backward passes per point; row k leaves out the other outputs'
//! weights, which it does not touch, and goes to output k's normal equations
//! ([`OutputNormalEquations`]), in [`PARTS`] parts of the training set that run in parallel.
//! The products run in f32 ([`crate::solve::NormalEquations::single_precision`], about
//! twice as fast: JᵀJ only steers the step, whose acceptance is decided by the f64 error); Jᵀe
//! and every error stay in f64. On the bunny's 10 000-point patch the f32 products alone gave
//! the same fit to three digits (relative RMS 8.37·10⁻³) in 0.79–0.89× the fitting time
//! (`README.md`, the list under Table 2). Each step solves
//! (JᵀJ + μI)Δ = −Jᵀe by the implicit trainer's blocked Cholesky ([`DampedSystem`]; the
//! networks have at most a few hundred weights); μ is divided by 10 after a step that lowers the training error and
//! multiplied by 10 otherwise (MATLAB's `trainlm`, which the paper used). After every
//! accepted step the validation error is measured; training stops after
//! [`TrainSettings::max_fail`] steps without a new best, and the best-validation weights are
//! kept.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::network::SurfaceNetwork;
use super::normal::OutputNormalEquations;
use super::packed::{LaneRecord, PackedNetwork, gather};
use crate::solve::{DampedSystem, LANES, Lanes};

/// Levenberg–Marquardt settings.
#[derive(Copy, Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TrainSettings {
    /// Iteration cap (accepted steps) (100).
    pub max_iterations: usize,
    /// Stop after this many accepted steps without a better validation error (6).
    pub max_fail: usize,
    /// Initial damping μ (10⁻³).
    pub mu0: f64,
    /// Give up when μ exceeds this (10¹⁰).
    pub mu_max: f64,
    /// Stop when the training MSE (normalized units) falls below this (10⁻¹⁴).
    pub goal: f64,
    /// Relative validation gain below which a step counts as a failure (10⁻²).
    pub min_gain: f64,
}

impl Default for TrainSettings {
    fn default() -> Self {
        TrainSettings {
            max_iterations: 100,
            max_fail: 6,
            mu0: 1e-3,
            mu_max: 1e10,
            goal: 1e-14,
            min_gain: 1e-2,
        }
    }
}

/// What one training run did; errors are mean squares per coordinate in normalized units
/// (divide by s_p² to undo, see [`SurfaceNetwork`]).
#[derive(Copy, Clone, Debug, PartialEq, serde::Serialize)]
pub struct TrainReport {
    /// Accepted LM steps.
    pub iterations: usize,
    /// Trial steps whose training error was evaluated, accepted or not (each a solve of the
    /// damped system and a pass over the training points).
    pub trials: usize,
    /// Training MSE of the kept weights.
    pub training_mse: f64,
    /// Validation MSE of the kept weights.
    pub validation_mse: f64,
}

/// Normalized training pairs.
#[derive(Clone, Debug)]
pub struct Samples {
    /// x⁰ of each point.
    pub inputs: Vec<[f64; 2]>,
    /// y targets of each point.
    pub targets: Vec<[f64; 3]>,
}

/// Random initial weights: U(−1, 1) for hidden layers (inputs lie in [−1, 1]), U(−0.5, 0.5)
/// for the output layer.
pub fn randomize(network: &mut SurfaceNetwork, seed: u64) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let last = network.layers.len() - 1;
    for (li, l) in network.layers.iter_mut().enumerate() {
        let scale = if li == last { 0.5 } else { 1.0 };
        for w in l.weights.iter_mut().chain(l.biases.iter_mut()) {
            *w = scale * (2.0 * rng.random::<f64>() - 1.0);
        }
    }
}

/// A network of the given hidden sizes with unit normalization and [`randomize`]d weights.
#[cfg(test)]
pub(crate) fn random_network(
    hidden: &[usize],
    activation: super::activation::Activation,
    seed: u64,
) -> SurfaceNetwork {
    let mut net = SurfaceNetwork::zeros(hidden, activation, [0.0; 2], [1.0; 2], [0.0; 3], 1.0)
        .expect("positive sizes");
    randomize(&mut net, seed);
    net
}

/// Mean squared coordinate error of `network` over the listed samples (0 for none).
pub fn mean_square(network: &SurfaceNetwork, samples: &Samples, indices: &[usize]) -> f64 {
    mean_square_packed(&PackedNetwork::new(network), samples, indices)
}

fn mean_square_packed(network: &PackedNetwork, samples: &Samples, indices: &[usize]) -> f64 {
    if indices.is_empty() {
        return 0.0;
    }
    let sum = network.squared_error_sum(
        &samples.inputs,
        &samples.targets,
        indices,
        &mut LaneRecord::default(),
    );
    sum / (3 * indices.len()) as f64
}

/// Fixed parts the training and evaluation sets are split into; the parts run in parallel
/// (rayon) and their sums are added in part order, so results do not depend on the number of
/// threads.
const PARTS: usize = 4;

/// [`mean_square`] over [`PARTS`] parts in parallel (the same value on any thread count).
pub fn mean_square_parallel(network: &SurfaceNetwork, samples: &Samples, indices: &[usize]) -> f64 {
    if indices.is_empty() {
        return 0.0;
    }
    let packed = PackedNetwork::new(network);
    let part = indices.len().div_ceil(PARTS);
    let sums: Vec<f64> = indices
        .par_chunks(part)
        .map(|chunk| mean_square_packed(&packed, samples, chunk) * chunk.len() as f64)
        .collect();
    sums.iter().sum::<f64>() / indices.len() as f64
}

/// One part's Jacobian rows and normal equations.
struct Part {
    normal: OutputNormalEquations,
    backprop: Backprop,
}

/// Trains `network` in place on `training`, stopping early on `validation` (see the module
/// docs). An empty validation set falls back to the training error.
pub fn train(
    network: &mut SurfaceNetwork,
    samples: &Samples,
    training: &[usize],
    validation: &[usize],
    settings: &TrainSettings,
) -> TrainReport {
    if training.is_empty() {
        return TrainReport {
            iterations: 0,
            trials: 0,
            training_mse: 0.0,
            validation_mse: mean_square(network, samples, validation),
        };
    }
    let p = network.parameter_count();
    let mut params = network.parameters();
    let chunks: Vec<&[usize]> = training
        .chunks(training.len().div_ceil(PARTS).max(1))
        .collect();
    let mut parts: Vec<Part> = chunks
        .iter()
        .map(|_| {
            let top = &network.layers[network.layers.len() - 1];
            Part {
                normal: OutputNormalEquations::new(p - top.parameter_count(), top.inputs),
                backprop: Backprop::new(network),
            }
        })
        .collect();
    let stride = parts[0].normal.stride();
    let mut system = DampedSystem::new(p);
    let validation = if validation.is_empty() {
        training
    } else {
        validation
    };
    let mut train_error = mean_square_parallel(network, samples, training);
    let mut best = (
        mean_square_parallel(network, samples, validation),
        params.clone(),
        train_error,
    );
    let mut mu = settings.mu0;
    let mut fails = 0;
    let mut iterations = 0;
    let mut trials = 0;
    let mut trial = network.clone();
    while iterations < settings.max_iterations
        && train_error > settings.goal
        && fails < settings.max_fail
    {
        let packed = PackedNetwork::new(network);
        parts
            .par_iter_mut()
            .zip(chunks.par_iter())
            .for_each(|(part, chunk)| {
                part.normal.clear();
                for points in chunk.chunks(part.normal.max_points()) {
                    let [(rows0, e0), (rows1, e1), (rows2, e2)] =
                        part.normal.rows_mut(points.len());
                    for (g, group) in points.chunks(LANES).enumerate() {
                        part.backprop
                            .record(&packed, gather(&samples.inputs, group));
                        for (lane, &i) in group.iter().enumerate() {
                            let c = g * LANES + lane;
                            let at = c * stride..(c + 1) * stride;
                            let mut residuals = [0.0; 3];
                            part.backprop.rows(
                                network,
                                lane,
                                samples.targets[i],
                                [
                                    &mut rows0[at.clone()],
                                    &mut rows1[at.clone()],
                                    &mut rows2[at],
                                ],
                                &mut residuals,
                            );
                            [e0[c], e1[c], e2[c]] = residuals;
                        }
                    }
                }
                part.normal.finish();
            });
        let sums: Vec<&OutputNormalEquations> = parts.iter().map(|part| &part.normal).collect();
        OutputNormalEquations::add_to(&sums, &mut system);
        let mut accepted = false;
        while mu <= settings.mu_max {
            let Some(step) = system.solve(mu) else {
                mu *= 10.0;
                continue;
            };
            let candidate: Vec<f64> = params.iter().zip(step).map(|(a, b)| a + b).collect();
            if trial.set_parameters(&candidate).is_err() {
                break;
            }
            let error = mean_square_parallel(&trial, samples, training);
            trials += 1;
            if error.is_finite() && error < train_error {
                params = candidate;
                std::mem::swap(network, &mut trial);
                train_error = error;
                mu = (mu / 10.0).max(1e-20);
                accepted = true;
                break;
            }
            mu *= 10.0;
        }
        if !accepted {
            break;
        }
        iterations += 1;
        let validation_error = mean_square_parallel(network, samples, validation);
        // A new best resets the count only when it is a real gain: a validation error that
        // creeps down by less than `min_gain` per step has converged.
        if validation_error < best.0 * (1.0 - settings.min_gain) {
            fails = 0;
        } else {
            fails += 1;
        }
        if validation_error < best.0 {
            best = (validation_error, params.clone(), train_error);
        }
    }
    // Keep the best-validation weights (the count always matches).
    let _ = network.set_parameters(&best.1);
    TrainReport {
        iterations,
        trials,
        training_mse: best.2,
        validation_mse: best.0,
    }
}

/// Per-layer buffers of the forward pass over [`LANES`] points and one point's backward
/// passes.
struct Backprop {
    /// The forward pass of the current group of points.
    record: LaneRecord,
    output: [Lanes; 3],
    /// One point's layer inputs and hidden slopes σ′(z), copied out of `record`.
    activations: Vec<Vec<f64>>,
    slopes: Vec<Vec<f64>>,
    offsets: Vec<usize>,
    /// ∂yₖ/∂(pre-activations) of the layer being visited, and of the one below it.
    delta: Vec<f64>,
    previous: Vec<f64>,
}

impl Backprop {
    fn new(network: &SurfaceNetwork) -> Self {
        let mut offsets = Vec::new();
        let mut at = 0;
        for l in &network.layers {
            offsets.push(at);
            at += l.parameter_count();
        }
        Backprop {
            record: LaneRecord::default(),
            output: [[0.0; LANES]; 3],
            activations: network.layers.iter().map(|l| vec![0.0; l.inputs]).collect(),
            slopes: network
                .layers
                .iter()
                .map(|l| vec![0.0; l.outputs])
                .collect(),
            offsets,
            delta: Vec::new(),
            previous: Vec::new(),
        }
    }

    /// Runs the forward pass of up to [`LANES`] points (see [`gather`]).
    fn record(&mut self, packed: &PackedNetwork, x0: [Lanes; 2]) {
        self.output = packed.forward(x0, &mut self.record);
    }

    /// Writes the three Jacobian rows of the recorded point in `lane` and its residuals
    /// yₖ − tₖ. Row k holds ∂yₖ/∂(hidden parameters), then ∂yₖ/∂(output k's weights) (the
    /// last hidden layer's values) and ∂yₖ/∂(output k's bias) = 1: the other outputs' columns
    /// are zero and left out (see [`OutputNormalEquations`]). Below the output layer
    /// `δ = W_out[k]` goes back through the layers; every entry is written, and the loops run
    /// over slices (no indexing), which vectorize.
    fn rows(
        &mut self,
        network: &SurfaceNetwork,
        lane: usize,
        target: [f64; 3],
        rows: [&mut [f64]; 3],
        residuals: &mut [f64; 3],
    ) {
        let last = network.layers.len() - 1;
        for (point, recorded) in self.activations.iter_mut().zip(&self.record.inputs) {
            for (v, r) in point.iter_mut().zip(recorded) {
                *v = r[lane];
            }
        }
        for (point, recorded) in self.slopes[..last].iter_mut().zip(&self.record.slopes) {
            for (v, r) in point.iter_mut().zip(recorded) {
                *v = r[lane];
            }
        }
        let output = self.output.map(|o| o[lane]);
        let top = &network.layers[last];
        let hidden = &self.activations[last];
        let below = self.offsets[last];
        for (k, row) in rows.into_iter().enumerate() {
            residuals[k] = output[k] - target[k];
            row[below..below + top.inputs].copy_from_slice(hidden);
            row[below + top.inputs] = 1.0;
            let delta = &mut self.delta;
            delta.clear();
            delta.extend_from_slice(&top.weights[k * top.inputs..(k + 1) * top.inputs]);
            for li in (0..last).rev() {
                let l = &network.layers[li];
                for (d, &slope) in delta.iter_mut().zip(&self.slopes[li]) {
                    *d *= slope;
                }
                let x = &self.activations[li];
                let (weights, biases) =
                    row[self.offsets[li]..][..l.parameter_count()].split_at_mut(l.weights.len());
                for ((w, &d), b) in weights
                    .chunks_exact_mut(l.inputs)
                    .zip(delta.iter())
                    .zip(biases.iter_mut())
                {
                    for (wi, &xi) in w.iter_mut().zip(x) {
                        *wi = d * xi;
                    }
                    *b = d;
                }
                if li > 0 {
                    let previous = &mut self.previous;
                    previous.clear();
                    previous.resize(l.inputs, 0.0);
                    for (weights_of, &d) in l.weights.chunks_exact(l.inputs).zip(delta.iter()) {
                        for (pv, &w) in previous.iter_mut().zip(weights_of) {
                            *pv += w * d;
                        }
                    }
                    std::mem::swap(delta, previous);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parametric::activation::Activation;

    /// The report counts every trial step: at least one per accepted step, and a rejected one
    /// costs a trial without a step.
    #[test]
    fn reports_count_trials_and_accepted_steps() {
        let inputs: Vec<[f64; 2]> = (0..60)
            .map(|i| [(i % 6) as f64 / 3.0 - 0.8, (i / 6) as f64 / 5.0 - 0.9])
            .collect();
        let targets = inputs
            .iter()
            .map(|&[u, v]| [u, v, 0.3 * (2.0 * u).sin() * v])
            .collect();
        let samples = Samples { inputs, targets };
        let mut net = random_network(&[4], Activation::TanSig, 3);
        let training: Vec<usize> = (0..50).collect();
        let validation: Vec<usize> = (50..60).collect();
        let report = train(
            &mut net,
            &samples,
            &training,
            &validation,
            &TrainSettings::default(),
        );
        assert!(report.iterations > 0, "{report:?}");
        assert!(report.trials >= report.iterations, "{report:?}");
        let empty = train(
            &mut net,
            &samples,
            &[],
            &validation,
            &TrainSettings::default(),
        );
        assert_eq!((empty.iterations, empty.trials), (0, 0));
    }

    /// Every Jacobian row, in each lane of a group of four, against central differences of the
    /// reference forward pass (the columns a compact row leaves out must have a zero
    /// derivative).
    #[test]
    fn jacobian_rows_match_central_differences() {
        let smooth = [Activation::LogSig, Activation::TanSig, Activation::RadBas];
        let inputs = [[0.9, 0.1], [-0.2, 0.5], [0.3, -0.6], [-0.7, -0.8]];
        let target = [0.1, 0.2, -0.3];
        for activation in smooth {
            for hidden in [vec![5], vec![4, 6], vec![3, 5, 4]] {
                let net = random_network(&hidden, activation, 11);
                let p = net.parameter_count();
                let n = *hidden.last().unwrap();
                let below = p - 3 * n - 3;
                let mut backprop = Backprop::new(&net);
                backprop.record(&PackedNetwork::new(&net), gather(&inputs, &[0, 1, 2, 3]));
                for (lane, &input) in inputs.iter().enumerate() {
                    let mut rows = [(); 3].map(|_| vec![f64::NAN; below + n + 1]);
                    let mut residuals = [0.0; 3];
                    let [r0, r1, r2] = &mut rows;
                    backprop.rows(&net, lane, target, [r0, r1, r2], &mut residuals);
                    let y = net.forward_normalized(input);
                    let params = net.parameters();
                    let mut shifted = net.clone();
                    let h = 1e-6;
                    for j in 0..p {
                        let mut at = |delta: f64| {
                            let mut v = params.clone();
                            v[j] += delta;
                            shifted.set_parameters(&v).unwrap();
                            shifted.forward_normalized(input)
                        };
                        let (plus, minus) = (at(h), at(-h));
                        for k in 0..3 {
                            let numeric = (plus[k] - minus[k]) / (2.0 * h);
                            // Compact column of parameter j in row k, if it has one.
                            let column = if j < below {
                                Some(j)
                            } else if (below + k * n..below + (k + 1) * n).contains(&j) {
                                Some(j - k * n)
                            } else if j == below + 3 * n + k {
                                Some(below + n)
                            } else {
                                None
                            };
                            let analytic = column.map_or(0.0, |c| rows[k][c]);
                            assert!(
                                (numeric - analytic).abs() < 1e-7 * (1.0 + numeric.abs()),
                                "{activation:?} {hidden:?} lane {lane}: ∂y{k}/∂θ{j} \
                                 {analytic} vs {numeric}"
                            );
                        }
                    }
                    for k in 0..3 {
                        assert!((residuals[k] - (y[k] - target[k])).abs() < 1e-13);
                    }
                }
            }
        }
    }
}
