//! Network topology search, §5.2: grow the hidden layers and neurons until the test error
//! converges, then keep the best configuration.
//!
//! For n_L = 1 … [`TopologyOptions::max_layers`] hidden layers (each of n_N neurons), n_N grows
//! from 1; each configuration is trained by Levenberg–Marquardt until the validation error
//! converges ([`super::train`] with [`TopologyOptions::search_train`], best of
//! [`TopologyOptions::restarts`] starts by validation error) and its test error P_T recorded.
//! n_N stops growing when P_T has not improved by more than [`TopologyOptions::tolerance`]
//! (relative) for [`TopologyOptions::patience`] consecutive steps, when it is below
//! [`TopologyOptions::floor`] (an exact fit), or at [`TopologyOptions::max_neurons`].
//!
//! **The deepest layer grows to the cap** unless it fits exactly: on a noisy scan P_T is
//! mostly the noise, so it stalls for a few steps while larger networks still come closer to
//! the surface. Stopping there picked a 2 × 8 or 2 × 9 network on some samples and 2 × 12 on
//! others of the same surface, and the refined fits differed by up to 2× in RMS from the
//! true surface. On seven surfaces (a horn, a saddle, a bump, an open cylinder, a
//! paraboloid, two wavy sheets; 1 500 points, noise 0.2 % of the diagonal, 6 seeds each)
//! growing to the cap lowered the RMS to the true surface by 7 % (geometric mean), and the
//! worst ratio between two fits of the same points, one less 2 % of them, from 1.74 to 1.56;
//! it trains 5 % more candidates and takes about 15 % longer. Only with enough points: at
//! least [`VALUES_PER_WEIGHT`] coordinates per weight of the largest network. A small patch
//! around a hole keeps the patience rule, since a larger network is freer across the hole.
//!
//! **Warm starts** ([`TopologyOptions::grow`]): the paper's step 5 adds a neuron and trains
//! again without saying from where. Here n_N = 1 starts from random weights and every later
//! n_N from the trained n_N − 1 network with one neuron added per layer, computing the same
//! function ([`super::growth`]); the starts differ in the new neurons' weights. Training thus
//! continues along the chain instead of repeating itself, so each configuration needs a
//! short LM run (at most 30 steps, against up to 100 from random weights). Together with
//! candidates on 1 000 instead of 2 000 points, this took the bunny's 10 000-point fit from
//! 14.5 s to 3.4 s on one core, with a better fit (relative RMS 8.4·10⁻³ against 8.8·10⁻³;
//! `README.md`, Table 2).
//!
//! The paper reports "the configuration with the best P_T"; test errors within `tolerance`
//! of the best (or below `floor`) are treated as ties and the tie with the fewest weights
//! wins, so a plane is not given a big network for a 10⁻¹² gain. Errors are normalized MSEs
//! (see [`super::SurfaceNetwork`]).
//!
//! The starts of a configuration train in parallel (rayon), and each LM step forms its normal
//! equations in parallel parts; the result does not depend on the number of threads.
//!
//! Large sets: candidates are trained on a stratified subsample of at most
//! [`TopologyOptions::max_search_points`] training points (the networks have at most a few
//! hundred weights). The chosen network is then refined on the whole training set with
//! [`TopologyOptions::train`] (also for small sets, whose candidates had the short
//! `search_train` runs).

use rayon::prelude::*;

use super::activation::Activation;
use super::growth::grow;
use super::network::SurfaceNetwork;
use super::split::Split;
use super::train::{Samples, TrainReport, TrainSettings, mean_square, randomize, train};

/// Training coordinates (3 per point) per weight of the largest network from which the
/// deepest layer grows to [`TopologyOptions::max_neurons`] (see the module docs).
pub const VALUES_PER_WEIGHT: usize = 10;

/// Weights of a network with `layers` hidden layers of `neurons` each, (u, v) → (x, y, z).
fn weights_of(layers: usize, neurons: usize) -> usize {
    let mut inputs = 2;
    let mut total = 0;
    for _ in 0..layers {
        total += neurons * (inputs + 1);
        inputs = neurons;
    }
    total + 3 * (inputs + 1)
}

/// Search settings.
#[derive(Copy, Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TopologyOptions {
    /// Hidden activation (tan-sig).
    pub activation: Activation,
    /// n_Lmax (2).
    pub max_layers: usize,
    /// Largest n_N tried (12).
    pub max_neurons: usize,
    /// Starts per configuration: random weights, or with `grow` random new neurons (2).
    pub restarts: usize,
    /// Relative P_T improvement that counts as progress (0.1).
    pub tolerance: f64,
    /// Non-improving steps before P_T counts as converged (2).
    pub patience: usize,
    /// P_T below this normalized MSE is an exact fit (10⁻⁶: an RMS of 0.1 % of the
    /// half-extent s_p per coordinate).
    pub floor: f64,
    /// Training points used per candidate (1 000).
    pub max_search_points: usize,
    /// Start n_N + 1 from the trained n_N network (true; see the module docs).
    pub grow: bool,
    /// LM settings of the candidates: at most 30 steps, stopping after 6 without a 0.1 %
    /// validation gain.
    pub search_train: TrainSettings,
    /// LM settings of the chosen network's refinement on all training points: at most 100
    /// steps, stopping after 6 without a 0.1 % validation gain. With 1 % the refinement
    /// stopped while the fit still improved by a few per cent every ten steps: on seven
    /// surfaces (1 500 points, noise 0.2 % of the diagonal, 6 seeds) 0.1 % lowers the RMS to
    /// the true surface by 16 %, and on the bunny's 10 000-point patch by 18 %, in about
    /// twice the fitting time there.
    pub train: TrainSettings,
    /// Seed of the initial weights.
    pub seed: u64,
}

impl Default for TopologyOptions {
    fn default() -> Self {
        TopologyOptions {
            activation: Activation::TanSig,
            max_layers: 2,
            max_neurons: 12,
            restarts: 2,
            tolerance: 0.1,
            patience: 2,
            floor: 1e-6,
            max_search_points: 1000,
            grow: true,
            search_train: TrainSettings {
                max_iterations: 30,
                max_fail: 6,
                min_gain: 1e-3,
                ..TrainSettings::default()
            },
            train: TrainSettings {
                min_gain: 1e-3,
                ..TrainSettings::default()
            },
            seed: 1,
        }
    }
}

impl TopologyOptions {
    /// The search without warm starts: every configuration from random weights, trained until
    /// the validation error converges (up to 100 LM steps, stopping after 6 without a 1 %
    /// validation gain; no refinement follows). Several
    /// times slower on large sets; hole filling uses it because its network must *extrapolate*
    /// into the hole, and networks grown along the chain bend more there (fandisk holes: the
    /// worst new vertex 0.054 from the surface against 0.020).
    pub fn from_random_starts() -> Self {
        let defaults = TopologyOptions::default();
        TopologyOptions {
            grow: false,
            search_train: TrainSettings::default(),
            train: TrainSettings::default(),
            ..defaults
        }
    }
}

/// One trained configuration.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Candidate {
    /// n_L.
    pub layers: usize,
    /// n_N per hidden layer.
    pub neurons: usize,
    /// Weights and biases.
    pub parameters: usize,
    /// Training MSE (normalized).
    pub training_mse: f64,
    /// Validation MSE (normalized).
    pub validation_mse: f64,
    /// Test MSE P_T (normalized).
    pub test_mse: f64,
    /// LM steps of the kept start.
    pub iterations: usize,
    /// LM trial steps of the kept start (accepted or not; see [`TrainReport::trials`]).
    pub trials: usize,
}

/// Every configuration tried and the one chosen.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct TopologySearch {
    /// In the order tried.
    pub candidates: Vec<Candidate>,
    /// Index of the chosen one in `candidates`.
    pub chosen: usize,
}

impl TopologySearch {
    /// The chosen configuration.
    pub fn best(&self) -> &Candidate {
        &self.candidates[self.chosen]
    }
}

/// Runs the search on normalized samples; `template` carries the normalization. `None` when no
/// configuration could be built.
pub(crate) fn search(
    template: &SurfaceNetwork,
    samples: &Samples,
    split: &Split,
    search_training: &[usize],
    options: &TopologyOptions,
) -> Option<(SurfaceNetwork, TopologySearch)> {
    let mut candidates = Vec::new();
    let mut networks = Vec::new();
    let mut seed = options.seed;
    let deepest_layers = options.max_layers.max(1);
    let to_the_cap = 3 * search_training.len()
        >= VALUES_PER_WEIGHT * weights_of(deepest_layers, options.max_neurons.max(1));
    for layers in 1..=deepest_layers {
        let mut best_pt = f64::INFINITY;
        let mut stale = 0;
        let mut previous: Option<SurfaceNetwork> = None;
        for neurons in 1..=options.max_neurons.max(1) {
            let hidden = vec![neurons; layers];
            // The starts are independent: train them in parallel (rayon) and keep the first
            // with the lowest validation error, as a sequential loop would.
            let seeds: Vec<u64> = (0..options.restarts.max(1))
                .map(|_| {
                    seed = seed.wrapping_add(0x9e37_79b9);
                    seed
                })
                .collect();
            let trained: Vec<(SurfaceNetwork, TrainReport)> = seeds
                .into_par_iter()
                .filter_map(|start| {
                    let mut net = match &previous {
                        Some(smaller) => grow(smaller, start),
                        None => {
                            let mut net = SurfaceNetwork::zeros(
                                &hidden,
                                options.activation,
                                template.input_center,
                                template.input_scale,
                                template.output_center,
                                template.output_scale,
                            )
                            .ok()?;
                            randomize(&mut net, start);
                            net
                        }
                    };
                    let report = train(
                        &mut net,
                        samples,
                        search_training,
                        &split.validation,
                        &options.search_train,
                    );
                    Some((net, report))
                })
                .collect();
            let kept = trained.into_iter().reduce(|kept, other| {
                if other.1.validation_mse < kept.1.validation_mse {
                    other
                } else {
                    kept
                }
            });
            let Some((net, report)) = kept else {
                continue;
            };
            let test_mse = mean_square(&net, samples, &split.test);
            candidates.push(Candidate {
                layers,
                neurons,
                parameters: net.parameter_count(),
                training_mse: report.training_mse,
                validation_mse: report.validation_mse,
                test_mse,
                iterations: report.iterations,
                trials: report.trials,
            });
            if options.grow {
                previous = Some(net.clone());
            }
            networks.push(net);
            if test_mse < best_pt * (1.0 - options.tolerance) && best_pt > options.floor {
                stale = 0;
            } else {
                stale += 1;
            }
            best_pt = best_pt.min(test_mse);
            let grows_on = to_the_cap && layers == deepest_layers;
            if (stale >= options.patience && !grows_on) || best_pt <= options.floor && stale > 0 {
                break;
            }
        }
    }
    let clamp = |e: f64| e.max(options.floor);
    let best = candidates
        .iter()
        .map(|c| clamp(c.test_mse))
        .fold(f64::INFINITY, f64::min);
    let chosen = candidates
        .iter()
        .enumerate()
        .filter(|(_, c)| clamp(c.test_mse) <= best * (1.0 + options.tolerance))
        .min_by_key(|(_, c)| c.parameters)
        .map(|(i, _)| i)
        .unwrap_or(0);
    if chosen >= networks.len() {
        return None;
    }
    let network = networks.swap_remove(chosen);
    Some((network, TopologySearch { candidates, chosen }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_of_counts_what_the_network_holds() {
        for layers in 1..=3 {
            for neurons in [1, 5, 12] {
                let network = SurfaceNetwork::zeros(
                    &vec![neurons; layers],
                    Activation::TanSig,
                    [0.0; 2],
                    [1.0; 2],
                    [0.0; 3],
                    1.0,
                )
                .unwrap();
                assert_eq!(weights_of(layers, neurons), network.parameter_count());
            }
        }
    }
}
