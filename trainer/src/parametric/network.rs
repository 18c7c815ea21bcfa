//! The trained surface network, (u, v) → (x, y, z): the representation a core model will
//! evaluate, and its `f64` reference evaluation with analytic partials.
//!
//! # Forward formula
//!
//! With L hidden layers of sizes n₁ … n_L (all using one [`Activation`] σ), weights Wˡ
//! (nₗ × nₗ₋₁, row-major, n₀ = 2) and biases bˡ, and a linear output layer W^(L+1) (3 × n_L),
//! b^(L+1):
//!
//! ```text
//! x⁰ = ((u − c_u)/s_u, (v − c_v)/s_v)            input normalization
//! xˡ = σ(Wˡ xˡ⁻¹ + bˡ)                          l = 1 … L
//! y  = W^(L+1) x^L + b^(L+1)
//! p  = c_p + s_p · y                             output de-normalization (one scale s_p)
//! ```
//!
//! The input box [c − s, c + s] is the parameter bounding box, so training inputs lie in
//! [−1, 1]²; the output centre is the points' bounding-box centre and s_p half its largest
//! side, one scale for all three coordinates so a normalized error is a geometric error.
//! The output layer is linear, where Eq. 8 applies σ there too: a sigmoid output saturates
//! and cannot reach the extremes of the data (MATLAB's fitting networks, which the paper used,
//! also end in a linear layer).
//!
//! ∂p/∂u and ∂p/∂v are carried forward exactly (one tangent pair per neuron), so they are
//! exact up to rounding (the tests check them against central differences to 10⁻⁶).

use super::activation::Activation;
use crate::error::{Error, Result};

/// One dense layer: `weights` row-major `outputs × inputs`, then `biases`.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Layer {
    /// Inputs (columns).
    pub inputs: usize,
    /// Outputs (rows).
    pub outputs: usize,
    /// Row-major weights.
    pub weights: Vec<f64>,
    /// Biases.
    pub biases: Vec<f64>,
}

impl Layer {
    /// Weights plus biases.
    pub fn parameter_count(&self) -> usize {
        self.outputs * (self.inputs + 1)
    }
}

/// A trained map (u, v) → (x, y, z): see the module docs for the exact formula.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SurfaceNetwork {
    /// c_u, c_v.
    pub input_center: [f64; 2],
    /// s_u, s_v (> 0).
    pub input_scale: [f64; 2],
    /// c_p.
    pub output_center: [f64; 3],
    /// s_p (> 0).
    pub output_scale: f64,
    /// σ of every hidden layer.
    pub activation: Activation,
    /// Hidden layers, then the linear 3-output layer.
    pub layers: Vec<Layer>,
}

/// Position and first partials at one (u, v).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct SurfacePoint {
    /// p(u, v).
    pub position: [f64; 3],
    /// ∂p/∂u.
    pub du: [f64; 3],
    /// ∂p/∂v.
    pub dv: [f64; 3],
}

impl SurfacePoint {
    /// The unit normal ∂p/∂u × ∂p/∂v / |…| (zero where the partials are parallel).
    pub fn normal(&self) -> [f64; 3] {
        unit_cross(self.du, self.dv)
    }
}

/// a × b / |a × b| (zero when a and b are parallel).
pub fn unit_cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    let n = [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ];
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if len > 0.0 {
        n.map(|c| c / len)
    } else {
        [0.0; 3]
    }
}

impl SurfaceNetwork {
    /// A network with the given hidden sizes and all parameters zero.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for an empty or zero-sized hidden layer or non-positive scales.
    pub fn zeros(
        hidden: &[usize],
        activation: Activation,
        input_center: [f64; 2],
        input_scale: [f64; 2],
        output_center: [f64; 3],
        output_scale: f64,
    ) -> Result<Self> {
        if hidden.is_empty() || hidden.contains(&0) {
            return Err(Error::invalid(
                "a surface network needs hidden layers of ≥ 1 neuron",
            ));
        }
        if !(input_scale.iter().all(|s| *s > 0.0 && s.is_finite())
            && output_scale > 0.0
            && output_scale.is_finite())
        {
            return Err(Error::invalid(
                "network normalization scales must be positive",
            ));
        }
        let mut layers = Vec::new();
        let mut inputs = 2;
        for &outputs in hidden.iter().chain(std::iter::once(&3)) {
            layers.push(Layer {
                inputs,
                outputs,
                weights: vec![0.0; inputs * outputs],
                biases: vec![0.0; outputs],
            });
            inputs = outputs;
        }
        Ok(SurfaceNetwork {
            input_center,
            input_scale,
            output_center,
            output_scale,
            activation,
            layers,
        })
    }

    /// Hidden-layer sizes.
    pub fn hidden_sizes(&self) -> Vec<usize> {
        self.layers[..self.layers.len().saturating_sub(1)]
            .iter()
            .map(|l| l.outputs)
            .collect()
    }

    /// Number of weights and biases.
    pub fn parameter_count(&self) -> usize {
        self.layers.iter().map(Layer::parameter_count).sum()
    }

    /// All parameters, layer by layer (weights row-major, then biases).
    pub fn parameters(&self) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.parameter_count());
        for l in &self.layers {
            out.extend_from_slice(&l.weights);
            out.extend_from_slice(&l.biases);
        }
        out
    }

    /// Sets all parameters from the layout of [`Self::parameters`].
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when the count differs.
    pub fn set_parameters(&mut self, values: &[f64]) -> Result<()> {
        if values.len() != self.parameter_count() {
            return Err(Error::invalid(format!(
                "{} parameters given, the network has {}",
                values.len(),
                self.parameter_count()
            )));
        }
        let mut at = 0;
        for l in self.layers.iter_mut() {
            let w = l.weights.len();
            l.weights.copy_from_slice(&values[at..at + w]);
            at += w;
            let b = l.biases.len();
            l.biases.copy_from_slice(&values[at..at + b]);
            at += b;
        }
        Ok(())
    }

    /// Normalized inputs x⁰ of (u, v).
    pub fn normalize_input(&self, u: f64, v: f64) -> [f64; 2] {
        [
            (u - self.input_center[0]) / self.input_scale[0],
            (v - self.input_center[1]) / self.input_scale[1],
        ]
    }

    /// Normalized output y of a point.
    pub fn normalize_output(&self, p: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|a| (p[a] - self.output_center[a]) / self.output_scale)
    }

    /// The network's normalized output y for normalized input x⁰.
    pub fn forward_normalized(&self, x0: [f64; 2]) -> [f64; 3] {
        // The training loop calls this for every point of every trial step: keep the layers
        // on the stack when they fit (the same sums in the same order as the heap path).
        const STACK: usize = 64;
        if self.layers.iter().all(|l| l.outputs <= STACK) {
            let (mut x, mut next) = ([0.0; STACK], [0.0; STACK]);
            x[..2].copy_from_slice(&x0);
            let mut width = 2;
            let last = self.layers.len() - 1;
            for (li, l) in self.layers.iter().enumerate() {
                for (o, value) in next[..l.outputs].iter_mut().enumerate() {
                    let row = &l.weights[o * l.inputs..(o + 1) * l.inputs];
                    *value = l.biases[o]
                        + row
                            .iter()
                            .zip(&x[..width])
                            .map(|(w, xi)| w * xi)
                            .sum::<f64>();
                    if li < last {
                        *value = self.activation.value(*value);
                    }
                }
                std::mem::swap(&mut x, &mut next);
                width = l.outputs;
            }
            return [x[0], x[1], x[2]];
        }
        let mut x: Vec<f64> = x0.to_vec();
        let last = self.layers.len() - 1;
        for (li, l) in self.layers.iter().enumerate() {
            let mut next = l.biases.clone();
            for (o, value) in next.iter_mut().enumerate() {
                let row = &l.weights[o * l.inputs..(o + 1) * l.inputs];
                *value += row.iter().zip(&x).map(|(w, xi)| w * xi).sum::<f64>();
                if li < last {
                    *value = self.activation.value(*value);
                }
            }
            x = next;
        }
        [x[0], x[1], x[2]]
    }

    /// p(u, v).
    pub fn position(&self, u: f64, v: f64) -> [f64; 3] {
        let y = self.forward_normalized(self.normalize_input(u, v));
        std::array::from_fn(|a| self.output_center[a] + self.output_scale * y[a])
    }

    /// p(u, v), ∂p/∂u and ∂p/∂v (forward-mode tangents through every neuron).
    pub fn evaluate(&self, u: f64, v: f64) -> SurfacePoint {
        let x0 = self.normalize_input(u, v);
        let mut x = x0.to_vec();
        let mut du = vec![1.0 / self.input_scale[0], 0.0];
        let mut dv = vec![0.0, 1.0 / self.input_scale[1]];
        let last = self.layers.len() - 1;
        for (li, l) in self.layers.iter().enumerate() {
            let mut nx = l.biases.clone();
            let mut ndu = vec![0.0; l.outputs];
            let mut ndv = vec![0.0; l.outputs];
            for o in 0..l.outputs {
                let row = &l.weights[o * l.inputs..(o + 1) * l.inputs];
                for i in 0..l.inputs {
                    nx[o] += row[i] * x[i];
                    ndu[o] += row[i] * du[i];
                    ndv[o] += row[i] * dv[i];
                }
                if li < last {
                    let slope = self.activation.derivative(nx[o]);
                    nx[o] = self.activation.value(nx[o]);
                    ndu[o] *= slope;
                    ndv[o] *= slope;
                }
            }
            x = nx;
            du = ndu;
            dv = ndv;
        }
        let s = self.output_scale;
        SurfacePoint {
            position: std::array::from_fn(|a| self.output_center[a] + s * x[a]),
            du: std::array::from_fn(|a| s * du[a]),
            dv: std::array::from_fn(|a| s * dv[a]),
        }
    }
}
