//! The least-squares problem of one module: its control points' inputs and target gradients.

use super::jacobian::{InputJet, TrainedLayout, forward, jacobian_rows};
use super::lm::LeastSquares;

/// A module's training data: per control point, the module's inputs with their tangents
/// (derivatives with respect to world x), and the target gradient −s·n.
///
/// For a leaf the inputs are the normalized coordinates A(x − c) with tangents the columns of
/// A; for a node they are the last hidden layers of its (frozen) children.
#[derive(Clone, Debug, PartialEq)]
pub struct ModuleData {
    inputs: usize,
    values: Vec<f64>,
    tangents: Vec<f64>,
    targets: Vec<[f64; 3]>,
}

impl ModuleData {
    /// An empty data set for a module with `inputs` inputs.
    pub fn new(inputs: usize) -> Self {
        ModuleData {
            inputs,
            values: Vec::new(),
            tangents: Vec::new(),
            targets: Vec::new(),
        }
    }

    /// Adds one control point: input `values` (d), `tangents[k]` (d each), and the target
    /// gradient ∇Φ = −s·n.
    pub fn push(&mut self, values: &[f64], tangents: [&[f64]; 3], target_gradient: [f64; 3]) {
        debug_assert_eq!(values.len(), self.inputs);
        self.values.extend_from_slice(values);
        for t in tangents {
            debug_assert_eq!(t.len(), self.inputs);
            self.tangents.extend_from_slice(t);
        }
        self.targets.push(target_gradient);
    }

    /// Number of control points.
    pub fn len(&self) -> usize {
        self.targets.len()
    }

    /// Whether there are no control points.
    pub fn is_empty(&self) -> bool {
        self.targets.is_empty()
    }

    /// Inputs per point.
    pub fn inputs(&self) -> usize {
        self.inputs
    }

    /// The inputs of point `i`.
    pub fn input(&self, i: usize) -> InputJet<'_> {
        let d = self.inputs;
        let values = &self.values[i * d..(i + 1) * d];
        let t = &self.tangents[i * 3 * d..(i + 1) * 3 * d];
        InputJet {
            values,
            tangents: [&t[..d], &t[d..2 * d], &t[2 * d..]],
        }
    }
}

/// Residuals e = [Φ, γ(∂Φ/∂xₖ + s·nₖ)] of every control point of a module, as a
/// [`LeastSquares`] problem over the module's trained parameters.
#[derive(Clone, Debug)]
pub struct ModuleProblem<'a> {
    data: &'a ModuleData,
    layout: TrainedLayout,
    gamma: f64,
}

impl<'a> ModuleProblem<'a> {
    /// The problem of fitting a width-`width` module to `data` with gradient weight `gamma`.
    pub fn new(data: &'a ModuleData, width: usize, gamma: f64) -> Self {
        ModuleProblem {
            data,
            layout: TrainedLayout::new(data.inputs(), width),
            gamma,
        }
    }

    /// The trained-parameter layout.
    pub fn layout(&self) -> &TrainedLayout {
        &self.layout
    }

    fn point_residuals(&self, i: usize, tape_value: f64, gradient: [f64; 3], out: &mut [f64]) {
        let target = self.data.targets[i];
        out[0] = tape_value;
        for k in 0..3 {
            out[1 + k] = self.gamma * (gradient[k] - target[k]);
        }
    }
}

impl LeastSquares for ModuleProblem<'_> {
    fn parameter_count(&self) -> usize {
        self.layout.len
    }

    fn residual_count(&self) -> usize {
        4 * self.data.len()
    }

    fn residuals(&self, params: &[f64], residuals: &mut [f64]) {
        for (i, out) in residuals.chunks_exact_mut(4).enumerate() {
            let tape = forward(&self.layout, params, &self.data.input(i));
            self.point_residuals(i, tape.value, tape.gradient, out);
        }
    }

    fn jacobian(&self, params: &[f64], residuals: &mut [f64], jacobian: &mut [f64]) {
        let p = self.layout.len;
        let rows = jacobian.chunks_exact_mut(4 * p);
        for (i, (out, rows)) in residuals.chunks_exact_mut(4).zip(rows).enumerate() {
            let input = self.data.input(i);
            let tape = forward(&self.layout, params, &input);
            self.point_residuals(i, tape.value, tape.gradient, out);
            jacobian_rows(&self.layout, params, &input, &tape, self.gamma, rows);
        }
    }
}
