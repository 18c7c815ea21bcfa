//! Growing a trained network by one neuron per hidden layer without changing its function:
//! the warm start of the §5.2 search's next configuration.
//!
//! The paper's step 5 adds a neuron and trains again, without saying from where. Training
//! n_N + 1 neurons from fresh random weights repeats all the work that found the n_N-neuron
//! fit; starting from that fit with one neuron added lets a short LM run continue it (see
//! [`super::topology`] and `README.md`, Table 2).
//!
//! The new neuron of each hidden layer gets random incoming weights (U(−1, 1), as
//! [`super::train::randomize`]) from every neuron below it, the new one included. The
//! weights from a new neuron into the *old* neurons of the next layer are 0, and so are the
//! output weights of the last hidden layer's new neuron, so no new neuron reaches the output
//! and the grown network computes exactly what the old one did. LM then moves those zero
//! weights first: their Jacobian columns are the new neurons' activations, which are not
//! zero.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::network::{Layer, SurfaceNetwork};

/// `network` with one more neuron in every hidden layer, computing the same function (see
/// the module docs); `seed` picks the new neurons' incoming weights.
pub fn grow(network: &SurfaceNetwork, seed: u64) -> SurfaceNetwork {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let last = network.layers.len() - 1;
    let mut layers = Vec::with_capacity(network.layers.len());
    for (li, l) in network.layers.iter().enumerate() {
        // The layer below grew by one neuron (except below the first layer: the inputs).
        let inputs = if li == 0 { l.inputs } else { l.inputs + 1 };
        let outputs = if li == last { l.outputs } else { l.outputs + 1 };
        let mut weights = Vec::with_capacity(inputs * outputs);
        let mut biases = l.biases.clone();
        for o in 0..l.outputs {
            weights.extend_from_slice(&l.weights[o * l.inputs..(o + 1) * l.inputs]);
            if inputs > l.inputs {
                weights.push(0.0);
            }
        }
        if outputs > l.outputs {
            weights.extend((0..inputs).map(|_| 2.0 * rng.random::<f64>() - 1.0));
            biases.push(2.0 * rng.random::<f64>() - 1.0);
        }
        layers.push(Layer {
            inputs,
            outputs,
            weights,
            biases,
        });
    }
    SurfaceNetwork {
        layers,
        ..network.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parametric::activation::Activation;
    use crate::parametric::train::random_network;

    #[test]
    fn a_grown_network_computes_the_same_function() {
        for hidden in [vec![1], vec![4], vec![3, 3], vec![2, 5, 4]] {
            let net = random_network(&hidden, Activation::TanSig, 7);
            let grown = grow(&net, 11);
            let sizes: Vec<usize> = hidden.iter().map(|n| n + 1).collect();
            assert_eq!(grown.hidden_sizes(), sizes);
            assert_eq!(
                grown.parameter_count(),
                grown
                    .layers
                    .iter()
                    .map(Layer::parameter_count)
                    .sum::<usize>()
            );
            for l in &grown.layers {
                assert_eq!(l.weights.len(), l.inputs * l.outputs);
                assert_eq!(l.biases.len(), l.outputs);
            }
            // New incoming weights are not all zero, or LM could not move the neuron.
            assert!(
                grown.layers[0].weights[2 * hidden[0]..]
                    .iter()
                    .any(|w| *w != 0.0)
            );
            for k in 0..50 {
                let x = [(k as f64 * 0.37).sin(), (k as f64 * 0.71).cos()];
                assert_eq!(
                    grown.forward_normalized(x),
                    net.forward_normalized(x),
                    "{hidden:?}"
                );
            }
        }
    }
}
