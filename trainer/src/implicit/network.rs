//! The `f64` model of a whole module tree: parameters in the core's layout, and the reference
//! evaluation of Φ and ∇Φ (independent of the core's implementation).

use neurosurf_core::implicit::{
    GUARD_LEN, MAX_HEIGHT, MAX_WIDTH, ModuleKind, ModuleLayout, NORMALIZATION_LEN,
};

use super::jacobian::{HiddenJet, InputJet, MAX_INPUTS, Tape, TrainedLayout, forward};
use super::normalize::Normalization;
use super::tree::TreeSpec;
use crate::error::{Error, Result};

/// A modular implicit surface in `f64`: the trainer's working model and the reference the
/// core's `f32` and Q16.16 evaluations are measured against.
#[derive(Clone, Debug, PartialEq)]
pub struct ImplicitNetwork {
    width: usize,
    kinds: Vec<ModuleKind>,
    leaf_features: Vec<Option<u32>>,
    offsets: Vec<usize>,
    lefts: Vec<usize>,
    params: Vec<f64>,
    guards: Vec<Guard>,
}

/// A sign guard (see `neurosurf_core::implicit::guard`): adds
/// a·(1 − ρ²|x − c|²)³ to Φ inside the ball of radius 1/ρ around c.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Guard {
    /// The centre c.
    pub center: [f64; 3],
    /// The inverse radius ρ (> 0).
    pub inverse_radius: f64,
    /// The amplitude a: positive inside the surface, negative outside.
    pub amplitude: f64,
}

impl Guard {
    /// The guard's value and gradient at `x`, as the core computes them.
    pub fn eval(&self, x: [f64; 3]) -> (f64, [f64; 3]) {
        let d = [0, 1, 2].map(|k| (x[k] - self.center[k]) * self.inverse_radius);
        let t2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        if d.iter().any(|v| v.abs() >= 1.0) || t2 >= 1.0 {
            return (0.0, [0.0; 3]);
        }
        let u = 1.0 - t2;
        let s = -6.0 * self.amplitude * self.inverse_radius * u * u;
        (self.amplitude * u * u * u, d.map(|v| s * v))
    }

    /// This guard in the parameters the core stores: c, ρ, a.
    pub fn parameters(&self) -> [f64; GUARD_LEN] {
        let [x, y, z] = self.center;
        [x, y, z, self.inverse_radius, self.amplitude]
    }
}

impl ImplicitNetwork {
    /// A network of width `width` shaped like `tree`, all parameters 0.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for a width outside 1..=16 or a tree taller than the core
    /// evaluates.
    pub fn new(width: usize, tree: &TreeSpec) -> Result<Self> {
        let kinds = tree.post_order();
        let features = tree.post_order_features();
        let len = kinds.iter().map(|&k| ModuleLayout::new(k, width).len).sum();
        Self::from_parts(width, kinds, features, vec![0.0; len])
    }

    /// A network from its post-order module kinds, leaf features and parameters.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when the width, tree or parameter count is inconsistent.
    pub fn from_parts(
        width: usize,
        kinds: Vec<ModuleKind>,
        leaf_features: Vec<Option<u32>>,
        params: Vec<f64>,
    ) -> Result<Self> {
        if !(1..=MAX_WIDTH).contains(&width) {
            return Err(Error::invalid(format!(
                "hidden width {width} is outside 1..={MAX_WIDTH}"
            )));
        }
        if leaf_features.len() != kinds.len() {
            return Err(Error::invalid("leaf feature list does not match the tree"));
        }
        let mut offsets = Vec::with_capacity(kinds.len());
        let mut lefts = Vec::with_capacity(kinds.len());
        let mut heights: Vec<usize> = Vec::with_capacity(kinds.len());
        let mut pending: Vec<usize> = Vec::new();
        let mut offset = 0;
        for (i, &kind) in kinds.iter().enumerate() {
            offsets.push(offset);
            offset += ModuleLayout::new(kind, width).len;
            match kind {
                ModuleKind::Leaf => {
                    lefts.push(i);
                    heights.push(1);
                }
                ModuleKind::Node => {
                    let (Some(right), Some(left)) = (pending.pop(), pending.pop()) else {
                        return Err(Error::invalid(format!(
                            "module {i} is a node without two children"
                        )));
                    };
                    lefts.push(left);
                    heights.push(1 + heights[left].max(heights[right]));
                    if heights[i] > MAX_HEIGHT {
                        return Err(Error::invalid(format!(
                            "the tree is {} modules tall; the core evaluates at most {MAX_HEIGHT}",
                            heights[i]
                        )));
                    }
                }
            }
            pending.push(i);
        }
        if pending.len() != 1 {
            return Err(Error::invalid("the module list is not a single tree"));
        }
        if params.len() != offset {
            return Err(Error::invalid(format!(
                "{} parameters given, the tree needs {offset}",
                params.len()
            )));
        }
        Ok(ImplicitNetwork {
            width,
            kinds,
            leaf_features,
            offsets,
            lefts,
            params,
            guards: Vec::new(),
        })
    }

    /// Hidden width N.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Module kinds in post-order.
    pub fn kinds(&self) -> &[ModuleKind] {
        &self.kinds
    }

    /// For every module, its feature if it is a leaf.
    pub fn leaf_features(&self) -> &[Option<u32>] {
        &self.leaf_features
    }

    /// Number of modules.
    pub fn module_count(&self) -> usize {
        self.kinds.len()
    }

    /// Index of the root module.
    pub fn root(&self) -> usize {
        self.kinds.len() - 1
    }

    /// All parameters in the core's layout.
    pub fn params(&self) -> &[f64] {
        &self.params
    }

    /// The tree, rebuilt from the module list.
    pub fn tree(&self) -> TreeSpec {
        self.subtree_spec(self.root())
    }

    fn subtree_spec(&self, i: usize) -> TreeSpec {
        match self.children(i) {
            Some((l, r)) => TreeSpec::node(self.subtree_spec(l), self.subtree_spec(r)),
            None => TreeSpec::Leaf(self.leaf_features[i].unwrap_or(0)),
        }
    }

    /// (left, right) children of a node.
    pub fn children(&self, i: usize) -> Option<(usize, usize)> {
        (self.kinds[i] == ModuleKind::Node).then(|| (self.lefts[i], i - 1))
    }

    /// The model of the subtree rooted at module `i` alone: what the network had memorized
    /// when that module finished training (the paper's Fig. 6). Post-order keeps a subtree's
    /// modules and parameters contiguous, so this is a slice of the whole; `None` for an
    /// index out of range.
    pub fn subtree(&self, i: usize) -> Option<ImplicitNetwork> {
        if i >= self.module_count() {
            return None;
        }
        let first = self.subtree_leaves(i).first().copied().unwrap_or(i);
        let end = self.offsets[i] + self.layout(i).len;
        Self::from_parts(
            self.width,
            self.kinds[first..=i].to_vec(),
            self.leaf_features[first..=i].to_vec(),
            self.params[self.offsets[first]..end].to_vec(),
        )
        .ok()
    }

    /// Leaf modules of the subtree rooted at `i`, left to right.
    pub fn subtree_leaves(&self, i: usize) -> Vec<usize> {
        match self.children(i) {
            Some((l, r)) => {
                let mut out = self.subtree_leaves(l);
                out.extend(self.subtree_leaves(r));
                out
            }
            None => vec![i],
        }
    }

    /// The parameter layout of module `i`.
    pub fn layout(&self, i: usize) -> ModuleLayout {
        ModuleLayout::new(self.kinds[i], self.width)
    }

    /// The trained-parameter layout of module `i`.
    pub fn trained_layout(&self, i: usize) -> TrainedLayout {
        TrainedLayout::new(self.layout(i).hidden_a.inputs, self.width)
    }

    /// Module `i`'s trained parameters.
    pub fn trained_params(&self, i: usize) -> &[f64] {
        let layout = self.layout(i);
        let start = self.offsets[i] + layout.trainable_start;
        &self.params[start..self.offsets[i] + layout.len]
    }

    /// Module `i`'s trained parameters, mutable.
    pub fn trained_params_mut(&mut self, i: usize) -> &mut [f64] {
        let layout = self.layout(i);
        let start = self.offsets[i] + layout.trainable_start;
        &mut self.params[start..self.offsets[i] + layout.len]
    }

    /// Module `i`'s input normalization x′ = A·(x − c): a leaf's input, a node's last three
    /// inputs (every module stores one, blob format 2).
    pub fn normalization(&self, i: usize) -> Option<Normalization> {
        Some(Normalization::from_params(
            &self.params[self.offsets[i]..self.offsets[i] + NORMALIZATION_LEN],
        ))
    }

    /// Sets module `i`'s input normalization (a leaf's or a node's).
    pub fn set_normalization(&mut self, i: usize, normalization: &Normalization) {
        let o = self.offsets[i];
        self.params[o..o + NORMALIZATION_LEN].copy_from_slice(&normalization.to_params());
    }

    /// Module `i`'s inputs at world point `x`: values and world tangents, written into
    /// `values` and `tangents` (the returned jet borrows them).
    pub fn module_input<'a>(
        &self,
        i: usize,
        x: [f64; 3],
        values: &'a mut [f64; MAX_INPUTS],
        tangents: &'a mut [[f64; MAX_INPUTS]; 3],
    ) -> InputJet<'a> {
        let n = self.width;
        let d = match self.children(i) {
            None => {
                let norm = self.normalization(i).unwrap_or(Normalization {
                    center: [0.0; 3],
                    matrix: [[0.0; 3]; 3],
                });
                values[..3].copy_from_slice(&norm.apply(x));
                for (k, tangent) in tangents.iter_mut().enumerate() {
                    for c in 0..3 {
                        tangent[c] = norm.matrix[c][k];
                    }
                }
                3
            }
            Some((l, r)) => {
                for (half, child) in [l, r].into_iter().enumerate() {
                    let jet = self.last_hidden(child, x);
                    values[half * n..(half + 1) * n].copy_from_slice(&jet.values[..n]);
                    for k in 0..3 {
                        tangents[k][half * n..(half + 1) * n]
                            .copy_from_slice(&jet.tangents[k][..n]);
                    }
                }
                let norm = self.normalization(i).unwrap_or(Normalization {
                    center: [0.0; 3],
                    matrix: [[0.0; 3]; 3],
                });
                values[2 * n..2 * n + 3].copy_from_slice(&norm.apply(x));
                for (k, tangent) in tangents.iter_mut().enumerate() {
                    for c in 0..3 {
                        tangent[2 * n + c] = norm.matrix[c][k];
                    }
                }
                2 * n + 3
            }
        };
        let [t0, t1, t2] = tangents;
        InputJet {
            values: &values[..d],
            tangents: [&t0[..d], &t1[..d], &t2[..d]],
        }
    }

    fn tape(&self, i: usize, x: [f64; 3]) -> Tape {
        let mut values = [0.0; MAX_INPUTS];
        let mut tangents = [[0.0; MAX_INPUTS]; 3];
        let input = self.module_input(i, x, &mut values, &mut tangents);
        forward(&self.trained_layout(i), self.trained_params(i), &input)
    }

    /// The last hidden layer (b) of module `i` at `x`, with world tangents.
    pub fn last_hidden(&self, i: usize, x: [f64; 3]) -> HiddenJet {
        self.tape(i, x).last_hidden()
    }

    /// Φ and ∇Φ of module `i`'s subtree (through that module's own output layer).
    pub fn eval_module(&self, i: usize, x: [f64; 3]) -> (f64, [f64; 3]) {
        let tape = self.tape(i, x);
        (tape.value, tape.gradient)
    }

    /// Φ and ∇Φ of the whole model: the root's output plus every guard.
    pub fn eval(&self, x: [f64; 3]) -> (f64, [f64; 3]) {
        let (mut value, mut gradient) = self.eval_module(self.root(), x);
        for guard in &self.guards {
            let (v, g) = guard.eval(x);
            value += v;
            for k in 0..3 {
                gradient[k] += g[k];
            }
        }
        (value, gradient)
    }

    /// The sign guards added to the root's output.
    pub fn guards(&self) -> &[Guard] {
        &self.guards
    }

    /// This network with `guards` in place of its own.
    pub fn with_guards(mut self, guards: Vec<Guard>) -> Self {
        self.guards = guards;
        self
    }
}
