//! A network laid out for the training passes: every layer's weights transposed, so a layer
//! is a sum of scaled columns (independent multiply–adds across its outputs, which vectorize)
//! instead of one dot product per neuron (a chain of dependent additions). A 2 × 12 tan-sig
//! network's forward pass takes 0.43–0.58× the reference's time (about 250–390 ns against
//! 470–680 ns), half of it the 24 `exp` calls; `forward_pass_timing` prints the table (an
//! inlined polynomial eˣ was tried: slower than glibc's FMA path). The forward and
//! Jacobian passes of LM use it; the f64 reference evaluation stays in [`SurfaceNetwork`].
//!
//! Values differ from [`SurfaceNetwork::forward_normalized`] only by rounding (the sums run in
//! another order): the unit test checks 10⁻¹³.

use super::activation::Activation;
use super::network::SurfaceNetwork;

/// One layer: `columns[i * outputs + o]` is the weight from input i to output o.
#[derive(Clone, Debug)]
struct PackedLayer {
    inputs: usize,
    outputs: usize,
    columns: Vec<f64>,
    biases: Vec<f64>,
}

/// A [`SurfaceNetwork`]'s weights in training layout (see the module docs).
#[derive(Clone, Debug)]
pub struct PackedNetwork {
    activation: Activation,
    layers: Vec<PackedLayer>,
    width: usize,
}

/// Buffers of one forward pass.
#[derive(Clone, Debug, Default)]
pub struct ForwardScratch {
    x: Vec<f64>,
    z: Vec<f64>,
}

/// (σ(a), σ′(a)) with one `exp` (the formulas of [`Activation::value_and_derivative`]).
#[inline(always)]
pub fn activate(activation: Activation, a: f64) -> (f64, f64) {
    match activation {
        Activation::LogSig => {
            let s = 1.0 / (1.0 + (-a).exp());
            (s, s * (1.0 - s))
        }
        Activation::TanSig => {
            let s = 2.0 / (1.0 + (-a).exp()) - 1.0;
            (s, 0.5 * (1.0 - s * s))
        }
        Activation::RadBas => {
            let s = (-a * a).exp();
            (s, -2.0 * a * s)
        }
        Activation::TriBas => activation.value_and_derivative(a),
    }
}

impl PackedNetwork {
    /// `network` transposed.
    pub fn new(network: &SurfaceNetwork) -> Self {
        let layers: Vec<PackedLayer> = network
            .layers
            .iter()
            .map(|l| PackedLayer {
                inputs: l.inputs,
                outputs: l.outputs,
                columns: (0..l.inputs * l.outputs)
                    .map(|k| l.weights[(k % l.outputs) * l.inputs + k / l.outputs])
                    .collect(),
                biases: l.biases.clone(),
            })
            .collect();
        let width = layers
            .iter()
            .map(|l| l.inputs.max(l.outputs))
            .max()
            .unwrap_or(3);
        PackedNetwork {
            activation: network.activation,
            layers,
            width,
        }
    }

    /// z = W x + b of layer `l` into `z`.
    #[inline(always)]
    fn affine(l: &PackedLayer, x: &[f64], z: &mut [f64]) {
        z.copy_from_slice(&l.biases);
        for (column, &xi) in l.columns.chunks_exact(l.outputs).zip(x) {
            for (zo, &w) in z.iter_mut().zip(column) {
                *zo += w * xi;
            }
        }
    }

    /// The normalized output y at normalized input `x0`.
    pub fn forward(&self, x0: [f64; 2], scratch: &mut ForwardScratch) -> [f64; 3] {
        let ForwardScratch { x, z } = scratch;
        x.clear();
        x.extend_from_slice(&x0);
        z.resize(self.width, 0.0);
        let last = self.layers.len() - 1;
        for (li, l) in self.layers.iter().enumerate() {
            let out = &mut z[..l.outputs];
            Self::affine(l, &x[..l.inputs], out);
            if li < last {
                for v in out.iter_mut() {
                    *v = activate(self.activation, *v).0;
                }
            }
            x.resize(self.width, 0.0);
            x[..l.outputs].copy_from_slice(out);
        }
        [x[0], x[1], x[2]]
    }

    /// The normalized output, recording every layer's input in `activations[l]` (length
    /// `inputs`) and every hidden neuron's σ′ in `slopes[l]` (length `outputs`).
    pub fn forward_recording(
        &self,
        x0: [f64; 2],
        activations: &mut [Vec<f64>],
        slopes: &mut [Vec<f64>],
    ) -> [f64; 3] {
        activations[0].copy_from_slice(&x0);
        let last = self.layers.len() - 1;
        let mut output = [0.0; 3];
        for (li, l) in self.layers.iter().enumerate() {
            if li < last {
                let (below, above) = activations.split_at_mut(li + 1);
                let out = &mut above[0][..l.outputs];
                Self::affine(l, &below[li], out);
                for (v, s) in out.iter_mut().zip(slopes[li].iter_mut()) {
                    let (value, slope) = activate(self.activation, *v);
                    *v = value;
                    *s = slope;
                }
            } else {
                Self::affine(l, &activations[li], &mut output);
            }
        }
        output
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parametric::train::random_network;

    #[test]
    fn agrees_with_the_reference_forward_pass() {
        for activation in Activation::ALL {
            for hidden in [vec![1], vec![7], vec![5, 9], vec![3, 12, 4]] {
                let net = random_network(&hidden, activation, 3);
                let packed = PackedNetwork::new(&net);
                let mut scratch = ForwardScratch::default();
                let mut activations: Vec<Vec<f64>> =
                    net.layers.iter().map(|l| vec![0.0; l.inputs]).collect();
                let mut slopes: Vec<Vec<f64>> =
                    net.layers.iter().map(|l| vec![0.0; l.outputs]).collect();
                for k in 0..100 {
                    let x = [(k as f64 * 0.37).sin(), (k as f64 * 0.71).cos()];
                    let want = net.forward_normalized(x);
                    let got = packed.forward(x, &mut scratch);
                    let recorded = packed.forward_recording(x, &mut activations, &mut slopes);
                    for a in 0..3 {
                        assert!(
                            (got[a] - want[a]).abs() < 1e-13,
                            "{activation:?} {hidden:?}"
                        );
                        assert_eq!(recorded[a], got[a]);
                    }
                }
            }
        }
    }

    #[test]
    #[ignore = "timing run: cargo test --release -p neurosurf-trainer --lib parametric::packed::tests::forward_pass_timing -- --ignored --nocapture"]
    fn forward_pass_timing() {
        let net = random_network(&[12, 12], Activation::TanSig, 3);
        let inputs: Vec<[f64; 2]> = (0..100_000)
            .map(|k| [(k as f64 * 0.37).sin(), (k as f64 * 0.71).cos()])
            .collect();
        let per_point = |f: &mut dyn FnMut([f64; 2]) -> f64| {
            let start = std::time::Instant::now();
            let sum: f64 = inputs.iter().map(|&x| f(x)).sum();
            (
                start.elapsed().as_secs_f64() * 1e9 / inputs.len() as f64,
                sum,
            )
        };
        let (reference, a) = per_point(&mut |x| net.forward_normalized(x)[0]);
        let packed = PackedNetwork::new(&net);
        let mut scratch = ForwardScratch::default();
        let (fast, b) = per_point(&mut |x| packed.forward(x, &mut scratch)[0]);
        let (exps, c) = per_point(&mut |x| (0..24).map(|k| (x[0] * k as f64).exp()).sum());
        eprintln!("| 2 × 12 tan-sig, per point | ns | ratio |");
        eprintln!("| reference forward (baseline) | {reference:.0} | 1.00 |");
        eprintln!("| packed forward | {fast:.0} | {:.2} |", fast / reference);
        eprintln!(
            "| its 24 `exp` calls alone | {exps:.0} | {:.2} |",
            exps / reference
        );
        assert!((a - b).abs() < 1e-6 * a.abs().max(1.0) && c.is_finite());
    }
}
