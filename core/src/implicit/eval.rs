//! Evaluation of Φ, ∇Φ and the unit normal: a recursive walk over the module tree.

use super::guard;
use super::layout::{MAX_HEIGHT, ModuleKind, ModuleLayout, NORMALIZATION_LEN};
use super::model::{ImplicitModel, ModuleEntry};
use super::width::{at_width, width};
use crate::dense::forward;
use crate::scalar::{Scalar, ScalarKind, normalize3};

/// Φ and ∇Φ at one point.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct FieldGradient<S> {
    /// Φ(x): 0 on the surface, > 0 inside, < 0 outside.
    pub value: S,
    /// ∇Φ(x) = (∂Φ/∂x₀, ∂Φ/∂x₁, ∂Φ/∂x₂); on the surface it is −s·n (s the trained slope).
    pub gradient: [S; 3],
}

impl<S: Scalar> FieldGradient<S> {
    /// The outward unit normal −∇Φ/|∇Φ|, `None` where the gradient vanishes.
    pub fn normal(&self) -> Option<[S; 3]> {
        normalize3(self.gradient.map(S::neg))
    }
}

/// One module of a model and the subtree below it, evaluated through that module's own
/// output layer. [`ImplicitModel::view`] gives the whole model (the root).
#[derive(Copy, Clone, Debug)]
pub struct ModuleView<'a, S: Scalar, const P: usize, const M: usize> {
    pub(crate) model: &'a ImplicitModel<S, P, M>,
    pub(crate) module: usize,
}

impl<S: Scalar, const P: usize, const M: usize> ImplicitModel<S, P, M> {
    /// The whole model.
    pub fn view(&self) -> ModuleView<'_, S, P, M> {
        ModuleView {
            model: self,
            module: self.root(),
        }
    }

    /// Module `index` (post-order) and its subtree: the surface learned up to that step.
    pub fn module(&self, index: usize) -> Option<ModuleView<'_, S, P, M>> {
        (index < self.modules.len()).then_some(ModuleView {
            model: self,
            module: index,
        })
    }

    /// Φ at `point`.
    ///
    /// Accuracy: `f32` within ~1e-6 of the `f64` reference for Carcenac-sized modules; Q16.16
    /// within ~1e-4 (activation error ≤ 1.25·2⁻¹⁵ per neuron, propagated).
    pub fn field(&self, point: [S; 3]) -> S {
        self.view().field(point)
    }

    /// Φ and ∇Φ at `point` (reverse mode: one forward pass, one transposed pass).
    pub fn field_gradient(&self, point: [S; 3]) -> FieldGradient<S> {
        self.view().field_gradient(point)
    }

    /// The outward unit normal −∇Φ/|∇Φ| at `point`, `None` where ∇Φ vanishes.
    pub fn normal(&self, point: [S; 3]) -> Option<[S; 3]> {
        self.view().normal(point)
    }
}

impl<S: Scalar, const P: usize, const M: usize> ModuleView<'_, S, P, M> {
    /// Index of the module this view evaluates.
    pub fn index(&self) -> usize {
        self.module
    }

    /// Φ at `point`.
    pub fn field(&self, point: [S; 3]) -> S {
        let [value] = self.field_lanes(&[point]);
        value
    }

    /// Φ and ∇Φ at `point`.
    pub fn field_gradient(&self, point: [S; 3]) -> FieldGradient<S> {
        let [result] = self.field_gradient_lanes(&[point]);
        result
    }

    /// The outward unit normal at `point`.
    pub fn normal(&self, point: [S; 3]) -> Option<[S; 3]> {
        self.field_gradient(point).normal()
    }

    /// Φ at `L` points at once.
    #[inline]
    pub(crate) fn field_lanes<const L: usize>(&self, points: &[[S; 3]; L]) -> [S; L] {
        at_width!(self.model.width, self.field_at::<L>(points))
    }

    /// The guards this view adds: the model's for the root, none for a subtree.
    #[inline]
    pub(crate) fn guards(&self) -> &[S] {
        if self.module == self.model.root() {
            self.model.guard_parameters()
        } else {
            &[]
        }
    }

    /// Φ at `L` points with layers of capacity `N` (see [`width`]).
    #[inline(always)]
    fn field_at<const L: usize, const N: usize, const EXACT: bool>(
        &self,
        points: &[[S; 3]; L],
    ) -> [S; L] {
        let model = self.model;
        let Some(entry) = model.modules.get(self.module) else {
            return [S::ZERO; L];
        };
        let width = width::<N, EXACT>(model.width);
        let layout = ModuleLayout::new(entry.kind, width);
        let params = model.module_parameters(entry.offset, layout.len);
        let last = model.last_hidden::<L, N, EXACT>(self.module, points, MAX_HEIGHT);
        let hidden = last.get(..width).unwrap_or(&[]);
        let [mut out] = forward::<S, L, 1>(params, &layout.output, (hidden, &[], &[]));
        let guards = self.guards();
        if !guards.is_empty() {
            guard::add_values(guards, points, &mut out, model.input_shift);
        }
        out
    }
}

impl<S: Scalar, const P: usize, const M: usize> ImplicitModel<S, P, M> {
    /// The parameters of the module starting at `offset` (empty if out of bounds, which
    /// validation rules out).
    pub(crate) fn module_parameters(&self, offset: usize, len: usize) -> &[S] {
        self.parameters.get(offset..offset + len).unwrap_or(&[])
    }

    /// The last hidden layer (b) of module `index`, recursing into children, with layers of
    /// capacity `N` (see [`width`]). `budget` bounds the recursion (validated tree heights
    /// never exhaust it).
    fn last_hidden<const L: usize, const N: usize, const EXACT: bool>(
        &self,
        index: usize,
        points: &[[S; 3]; L],
        budget: usize,
    ) -> [[S; L]; N] {
        let (Some(entry), Some(budget)) = (self.modules.get(index), budget.checked_sub(1)) else {
            return [[S::ZERO; L]; N];
        };
        let width = width::<N, EXACT>(self.width);
        // The layout is built from a constant kind in each arm, so that its shapes fold.
        let module = |kind| {
            let layout = ModuleLayout::new(kind, width);
            (layout, self.module_parameters(entry.offset, layout.len))
        };
        let (layout, params, hidden_a): (_, _, [[S; L]; N]) = match entry.kind {
            ModuleKind::Leaf => {
                let (layout, params) = module(ModuleKind::Leaf);
                let input = normalized_input(params, points, self.input_shift);
                (
                    layout,
                    params,
                    forward(params, &layout.hidden_a, (&input, &[], &[])),
                )
            }
            ModuleKind::Node => {
                let (layout, params) = module(ModuleKind::Node);
                let hidden_a = self.node_hidden_a::<L, N, EXACT>(index, entry, points, budget);
                (layout, params, hidden_a)
            }
        };
        let hidden_a = hidden_a.get(..width).unwrap_or(&[]);
        forward(params, &layout.hidden_b, (hidden_a, &[], &[]))
    }

    /// A node's layer a′ on [b of the left child, b of the right child, its normalized
    /// position x′]. Out of line (and in portable code: no kernel has its 2N + 3 inputs), so
    /// that [`Self::last_hidden`], which also runs every leaf, keeps the leaf's code as it was.
    #[inline(never)]
    fn node_hidden_a<const L: usize, const N: usize, const EXACT: bool>(
        &self,
        index: usize,
        entry: &ModuleEntry,
        points: &[[S; 3]; L],
        budget: usize,
    ) -> [[S; L]; N] {
        let width = width::<N, EXACT>(self.width);
        let layout = ModuleLayout::new(ModuleKind::Node, width);
        let params = self.module_parameters(entry.offset, layout.len);
        let left = self.last_hidden::<L, N, EXACT>(entry.left, points, budget);
        let right = self.last_hidden::<L, N, EXACT>(index.saturating_sub(1), points, budget);
        let position = normalized_input(params, points, self.input_shift);
        let inputs = (
            left.get(..width).unwrap_or(&[]),
            right.get(..width).unwrap_or(&[]),
            position.as_slice(),
        );
        forward(params, &layout.hidden_a, inputs)
    }
}

/// A module's normalized position x′ = A·(x − c)·2^`shift`, lane by lane: a leaf's input, and
/// the last three inputs of a node's layer a′ (both store c and A first, see
/// [`ModuleLayout`]). `shift` is what of the blob's frame the load could not fold into A
/// (see [`ImplicitModel::frame`]); 0 for every `f32` model.
#[inline]
pub(crate) fn normalized_input<S: Scalar, const L: usize>(
    params: &[S],
    points: &[[S; 3]; L],
    shift: i8,
) -> [[S; L]; 3] {
    let mut input = unscaled_input(params, points);
    // `f32` models always fold the frame at load: no run-time shift to compile.
    if S::KIND != ScalarKind::F32 && shift != 0 {
        scale_lanes(&mut input, shift);
    }
    input
}

/// Every value times 2^`shift`: out of line, so that models without a run-time shift keep
/// their code as it is.
#[inline(never)]
pub(crate) fn scale_lanes<S: Scalar, const L: usize>(values: &mut [[S; L]; 3], shift: i8) {
    for value in values.iter_mut().flatten() {
        *value = value.times_power_of_two(shift);
    }
}

#[inline]
fn unscaled_input<S: Scalar, const L: usize>(params: &[S], points: &[[S; 3]; L]) -> [[S; L]; 3] {
    let mut input = [[S::ZERO; L]; 3];
    let Some(normalization) = params.get(..NORMALIZATION_LEN) else {
        return input;
    };
    let (center, axes) = normalization.split_at(3);
    for (row, lanes) in axes.chunks_exact(3).zip(input.iter_mut()) {
        for (slot, point) in lanes.iter_mut().zip(points) {
            let mut acc = S::ZERO.to_acc();
            for ((&a, &x), &c) in row.iter().zip(point).zip(center) {
                acc = S::mac(acc, a, x.sub(c));
            }
            *slot = S::from_acc(acc);
        }
    }
    input
}
