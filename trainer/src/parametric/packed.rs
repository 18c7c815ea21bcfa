//! A network laid out for the training passes, evaluated [`LANES`] points at a time.
//!
//! Every layer's weights are transposed, so a layer is a sum of scaled columns, and each
//! multiply–add runs on [`LANES`] points at once (one AVX2 register); tan-sig and log-sig come
//! from the implicit trainer's vectorized [`tanh_lanes`] (σ_tan(a) = tanh(a/2),
//! σ_log(a) = (1 + tanh(a/2))/2) instead of one `exp` call per neuron and point. For a 2 × 12
//! tan-sig network this takes 0.32–0.48× the reference's time per point over five runs
//! (`forward_pass_timing` prints the table); the earlier one-point-at-a-time pass over the
//! transposed weights took 0.43–0.58×, half of it in `exp`. The trial, validation and Jacobian
//! passes of LM use it; the f64 reference evaluation stays in [`SurfaceNetwork`].
//!
//! Values differ from [`SurfaceNetwork::forward_normalized`] only by rounding (the sums run in
//! another order, tanh is within a few ulps of the `exp` formula): the unit test checks 10⁻¹³.

use super::activation::Activation;
use super::network::SurfaceNetwork;
use crate::solve::{LANES, Lanes, cpu_has_fma, tanh_lanes};

/// One layer: `columns[i * outputs + o]` is the weight from input i to output o.
#[derive(Clone, Debug)]
struct PackedLayer {
    outputs: usize,
    columns: Vec<f64>,
    biases: Vec<f64>,
}

/// A [`SurfaceNetwork`]'s weights in training layout (see the module docs).
#[derive(Clone, Debug)]
pub struct PackedNetwork {
    activation: Activation,
    layers: Vec<PackedLayer>,
    /// Whether the passes run the AVX2 + FMA build.
    fma: bool,
}

/// What a pass over [`LANES`] points records: every layer's input values and every hidden
/// neuron's slope σ′, one lane per point.
#[derive(Clone, Debug, Default)]
pub struct LaneRecord {
    /// `inputs[l][i]`: input i of layer l (layer 0: the points' (u, v)).
    pub inputs: Vec<Vec<Lanes>>,
    /// `slopes[l][o]`: σ′ of hidden neuron o of layer l.
    pub slopes: Vec<Vec<Lanes>>,
}

/// (σ(a), σ′(a)) with one `exp` (the formulas of [`Activation::value_and_derivative`]).
#[inline(always)]
fn activate(activation: Activation, a: f64) -> (f64, f64) {
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

/// (σ, σ′) on every lane: [`tanh_lanes`] for the sigmoids, [`activate`] per lane otherwise.
#[inline(always)]
fn activate_lanes<const FMA: bool>(activation: Activation, a: Lanes) -> (Lanes, Lanes) {
    match activation {
        Activation::TanSig => {
            let t = tanh_lanes::<FMA>(a.map(|v| 0.5 * v));
            (t, t.map(|t| 0.5 * (1.0 - t * t)))
        }
        Activation::LogSig => {
            let s = tanh_lanes::<FMA>(a.map(|v| 0.5 * v)).map(|t| 0.5 + 0.5 * t);
            (s, s.map(|s| s * (1.0 - s)))
        }
        _ => {
            let both = a.map(|v| activate(activation, v));
            (both.map(|b| b.0), both.map(|b| b.1))
        }
    }
}

impl PackedNetwork {
    /// `network` transposed.
    pub fn new(network: &SurfaceNetwork) -> Self {
        let layers: Vec<PackedLayer> = network
            .layers
            .iter()
            .map(|l| PackedLayer {
                outputs: l.outputs,
                columns: (0..l.inputs * l.outputs)
                    .map(|k| l.weights[(k % l.outputs) * l.inputs + k / l.outputs])
                    .collect(),
                biases: l.biases.clone(),
            })
            .collect();
        PackedNetwork {
            activation: network.activation,
            layers,
            fma: cpu_has_fma(),
        }
    }

    /// The normalized outputs y (per coordinate, one lane per point) at the points `x0`
    /// (per coordinate, one lane per point), recording the layers' inputs and slopes.
    pub fn forward(&self, x0: [Lanes; 2], record: &mut LaneRecord) -> [Lanes; 3] {
        #[cfg(target_arch = "x86_64")]
        if self.fma {
            // SAFETY: `fma` comes from `cpu_has_fma`: this CPU has AVX2 and FMA.
            return unsafe { self.forward_fma(x0, record) };
        }
        self.forward_impl::<false>(x0, record)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn forward_fma(&self, x0: [Lanes; 2], record: &mut LaneRecord) -> [Lanes; 3] {
        self.forward_impl::<true>(x0, record)
    }

    #[inline(always)]
    fn forward_impl<const FMA: bool>(&self, x0: [Lanes; 2], record: &mut LaneRecord) -> [Lanes; 3] {
        let LaneRecord { inputs, slopes } = record;
        inputs.resize(self.layers.len(), Vec::new());
        slopes.resize(self.layers.len(), Vec::new());
        inputs[0].clear();
        inputs[0].extend_from_slice(&x0);
        let last = self.layers.len() - 1;
        let mut output = [[0.0; LANES]; 3];
        for (li, layer) in self.layers.iter().enumerate() {
            let (below, above) = inputs.split_at_mut(li + 1);
            let x = &below[li];
            let out: &mut [Lanes] = if li < last {
                above[0].resize(layer.outputs, [0.0; LANES]);
                &mut above[0]
            } else {
                &mut output
            };
            for (zo, &b) in out.iter_mut().zip(&layer.biases) {
                *zo = [b; LANES];
            }
            for (column, xi) in layer.columns.chunks_exact(layer.outputs).zip(x) {
                for (zo, &w) in out.iter_mut().zip(column) {
                    for l in 0..LANES {
                        zo[l] += w * xi[l];
                    }
                }
            }
            if li < last {
                slopes[li].resize(layer.outputs, [0.0; LANES]);
                for (v, s) in out.iter_mut().zip(slopes[li].iter_mut()) {
                    (*v, *s) = activate_lanes::<FMA>(self.activation, *v);
                }
            }
        }
        output
    }

    /// Σ over `indices` of the squared coordinate errors |y(xᵢ) − tᵢ|², [`LANES`] points at a
    /// time. The lanes are added in a fixed order, so the sum depends only on `indices`.
    pub fn squared_error_sum(
        &self,
        inputs: &[[f64; 2]],
        targets: &[[f64; 3]],
        indices: &[usize],
        record: &mut LaneRecord,
    ) -> f64 {
        #[cfg(target_arch = "x86_64")]
        if self.fma {
            // SAFETY: `fma` comes from `cpu_has_fma`: this CPU has AVX2 and FMA.
            return unsafe { self.squared_error_sum_fma(inputs, targets, indices, record) };
        }
        self.squared_error_sum_impl::<false>(inputs, targets, indices, record)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn squared_error_sum_fma(
        &self,
        inputs: &[[f64; 2]],
        targets: &[[f64; 3]],
        indices: &[usize],
        record: &mut LaneRecord,
    ) -> f64 {
        self.squared_error_sum_impl::<true>(inputs, targets, indices, record)
    }

    #[inline(always)]
    fn squared_error_sum_impl<const FMA: bool>(
        &self,
        inputs: &[[f64; 2]],
        targets: &[[f64; 3]],
        indices: &[usize],
        record: &mut LaneRecord,
    ) -> f64 {
        let mut sums = [0.0; LANES];
        for group in indices.chunks(LANES) {
            let y = self.forward_impl::<FMA>(gather(inputs, group), record);
            for (l, &i) in group.iter().enumerate() {
                for a in 0..3 {
                    sums[l] += (y[a][l] - targets[i][a]).powi(2);
                }
            }
        }
        sums.iter().sum()
    }
}

/// The (u, v) of up to [`LANES`] points, one lane per point; a short group repeats its last
/// point in the spare lanes.
pub fn gather(inputs: &[[f64; 2]], group: &[usize]) -> [Lanes; 2] {
    std::array::from_fn(|a| std::array::from_fn(|l| inputs[group[l.min(group.len() - 1)]][a]))
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
                let mut record = LaneRecord::default();
                let inputs: Vec<[f64; 2]> = (0..101)
                    .map(|k| [(k as f64 * 0.37).sin(), (k as f64 * 0.71).cos()])
                    .collect();
                let indices: Vec<usize> = (0..inputs.len()).collect();
                let mut targets = Vec::new();
                for group in indices.chunks(LANES) {
                    let y = packed.forward(gather(&inputs, group), &mut record);
                    for (l, &i) in group.iter().enumerate() {
                        let want = net.forward_normalized(inputs[i]);
                        for a in 0..3 {
                            assert!(
                                (y[a][l] - want[a]).abs() < 1e-13,
                                "{activation:?} {hidden:?}"
                            );
                        }
                        // Slopes: σ′ of the recorded pre-activations' values.
                        let x = record.inputs[1][0][l];
                        let s = record.slopes[0][0][l];
                        let (value, slope) = activation.value_and_derivative(
                            net.layers[0].weights[0] * inputs[i][0]
                                + net.layers[0].weights[1] * inputs[i][1]
                                + net.layers[0].biases[0],
                        );
                        assert!((x - value).abs() < 1e-13 && (s - slope).abs() < 1e-13);
                        targets.push(want.map(|v| v + 0.25));
                    }
                }
                // Every point is 0.25 off in each coordinate: Σ = 3 · 0.25² per point.
                let sum = packed.squared_error_sum(&inputs, &targets, &indices, &mut record);
                assert!((sum - 0.1875 * inputs.len() as f64).abs() < 1e-10);
            }
        }
    }
}
