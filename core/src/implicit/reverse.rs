//! Φ and ∇Φ together in reverse mode: one forward pass that keeps each layer's outputs (a′ follows
//! from a),
//! then one transposed pass from the root's output down to every module's normalized position
//! x′ = A·(x − c): each leaf's input and each node's last three inputs, every one of which adds
//! Aᵀ·∂Φ/∂x′ to ∇Φ.
//!
//! Carcenac §4 differentiates forward (three tangents per neuron: four times the multiply–
//! accumulates of Φ). Reverse mode needs about twice those of Φ, independent of the input
//! dimension. The pass down needs every module's slopes, which a tape would have to reserve for
//! the largest model; instead each module hands the rest of the evaluation to its parent as a
//! continuation ([`Above`]) and keeps its slopes in its own stack frame until the pass comes back
//! down through it. Stack use is therefore proportional to the model actually loaded (about
//! `4·N·L` scalars per module, plus `3·L` for a node's position, N the layer capacity: the
//! width itself for the specialized widths, else `MAX_WIDTH`; see `width.rs`), and nothing is
//! allocated beyond that.

use super::eval::{FieldGradient, ModuleView, normalized_input, scale_lanes};
use super::guard;
use super::layout::{MAX_HEIGHT, ModuleKind, ModuleLayout, NORMALIZATION_LEN};
use super::model::ImplicitModel;
use super::width::{at_width, width};
use crate::dense::{LayerInputs, forward, forward_node, transposed, transposed_through_activation};
use crate::scalar::{Scalar, ScalarKind};

/// ∇Φ summed over the modules, per coordinate and lane, in the wide accumulator.
type Gradient<S, const L: usize> = [[<S as Scalar>::Acc; L]; 3];

/// The evaluation above a module: given the module's last hidden layer (b), it finishes the
/// forward pass, runs the transposed pass down to this module, and returns ∂Φ/∂H_b, the
/// gradient at b's pre-activations (the chain rule through b's activation included, so that
/// it can run on the transpose's sums while a kernel still holds them).
type Above<'f, S, const L: usize, const N: usize> =
    dyn FnMut(&[[S; L]; N], &mut Gradient<S, L>) -> [[S; L]; N] + 'f;

impl<S: Scalar, const P: usize, const M: usize> ModuleView<'_, S, P, M> {
    /// Φ and ∇Φ at `L` points at once.
    #[inline]
    pub(crate) fn field_gradient_lanes<const L: usize>(
        &self,
        points: &[[S; 3]; L],
    ) -> [FieldGradient<S>; L] {
        at_width!(self.model.width, self.field_gradient_at::<L>(points))
    }

    /// Φ and ∇Φ at `L` points with layers of capacity `N` (see [`width`]).
    #[inline(always)]
    fn field_gradient_at<const L: usize, const N: usize, const EXACT: bool>(
        &self,
        points: &[[S; 3]; L],
    ) -> [FieldGradient<S>; L] {
        let model = self.model;
        let mut value = [S::ZERO; L];
        let mut gradient = [[S::ZERO.to_acc(); L]; 3];
        if let Some(entry) = model.modules.get(self.module) {
            let root = &mut |hidden: &[[S; L]; N], _: &mut Gradient<S, L>| {
                // Built here, not captured: the shapes are then constants in this closure.
                let Pass {
                    params,
                    layout,
                    width,
                } = model.pass::<N, EXACT>(entry.offset, entry.kind);
                let hidden = hidden.get(..width).unwrap_or(&[]);
                let [out] = forward::<S, L, 1>(params, &layout.output, (hidden, &[], &[]));
                value = out;
                let mut slope = [out];
                for lanes in &mut slope {
                    for a in lanes {
                        *a = S::activation_slope(*a);
                    }
                }
                // ∂Φ/∂bⱼ = a′(H)·wⱼ, and through b's activation: ∂Φ/∂H_bⱼ = ∂Φ/∂bⱼ·b′ⱼ
                transposed_through_activation::<S, L, N, EXACT>(
                    params,
                    &layout.output,
                    (0, width),
                    &slope,
                    hidden,
                )
            };
            model.reverse::<L, N, EXACT>(self.module, points, MAX_HEIGHT, &mut gradient, root);
        }
        let mut gradient = gradient.map(|lanes| lanes.map(S::from_acc));
        let guards = self.guards();
        if !guards.is_empty() {
            guard::add_values_gradients(
                guards,
                points,
                &mut value,
                &mut gradient,
                model.input_shift,
            );
        }
        let [g0, g1, g2] = gradient;
        core::array::from_fn(|lane| {
            let at = |lanes: &[S; L]| lanes.get(lane).copied().unwrap_or(S::ZERO);
            FieldGradient {
                value: at(&value),
                gradient: [at(&g0), at(&g1), at(&g2)],
            }
        })
    }
}

impl<S: Scalar, const P: usize, const M: usize> ImplicitModel<S, P, M> {
    /// The forward pass through module `index` and its subtree, `above` for everything higher,
    /// then the transposed pass back down, adding each module's share of ∇Φ (through its
    /// normalized position) to `gradient`.
    /// Layers have capacity `N` (see [`width`]). `budget` bounds the recursion (validated tree
    /// heights never exhaust it).
    fn reverse<const L: usize, const N: usize, const EXACT: bool>(
        &self,
        index: usize,
        points: &[[S; 3]; L],
        budget: usize,
        gradient: &mut Gradient<S, L>,
        above: &mut Above<'_, S, L, N>,
    ) {
        let (Some(entry), Some(budget)) = (self.modules.get(index), budget.checked_sub(1)) else {
            return;
        };
        match entry.kind {
            ModuleKind::Leaf => {
                let pass = self.pass::<N, EXACT>(entry.offset, ModuleKind::Leaf);
                let input = normalized_input(pass.params, points, self.input_shift);
                let delta_a = pass.run::<L, N, EXACT, false>((&input, &[], &[]), gradient, above);
                let delta_a = delta_a.get(..pass.width).unwrap_or(&[]);
                let hidden_a = &pass.layout.hidden_a;
                let delta_input =
                    transposed::<S, L, 3, EXACT>(pass.params, hidden_a, (0, 3), delta_a);
                add_normalization_transpose(pass.params, &delta_input, gradient, self.input_shift);
            }
            ModuleKind::Node => {
                let right_child = index.saturating_sub(1);
                self.reverse::<L, N, EXACT>(
                    entry.left,
                    points,
                    budget,
                    gradient,
                    &mut |left, gradient| {
                        let mut delta_left = None;
                        self.reverse::<L, N, EXACT>(
                            right_child,
                            points,
                            budget,
                            gradient,
                            &mut |right, gradient| {
                                let pass = self.pass::<N, EXACT>(entry.offset, ModuleKind::Node);
                                let (params, width) = (pass.params, pass.width);
                                let (left, right) = (
                                    left.get(..width).unwrap_or(&[]),
                                    right.get(..width).unwrap_or(&[]),
                                );
                                let position = normalized_input(params, points, self.input_shift);
                                let delta_a = pass.run::<L, N, EXACT, true>(
                                    (left, right, &position),
                                    gradient,
                                    &mut *above,
                                );
                                let delta_a = delta_a.get(..width).unwrap_or(&[]);
                                let hidden_a = &pass.layout.hidden_a;
                                // The node's own share of ∇Φ, through its position inputs.
                                let delta_position = transposed::<S, L, 3, EXACT>(
                                    params,
                                    hidden_a,
                                    (2 * width, 3),
                                    delta_a,
                                );
                                add_normalization_transpose(
                                    params,
                                    &delta_position,
                                    gradient,
                                    self.input_shift,
                                );
                                // Each child's ∂Φ/∂H_b, through its activation.
                                delta_left = Some(transposed_through_activation::<S, L, N, EXACT>(
                                    params,
                                    hidden_a,
                                    (0, width),
                                    delta_a,
                                    left,
                                ));
                                transposed_through_activation::<S, L, N, EXACT>(
                                    params,
                                    hidden_a,
                                    (width, width),
                                    delta_a,
                                    right,
                                )
                            },
                        );
                        delta_left.unwrap_or([[S::ZERO; L]; N])
                    },
                );
            }
        }
    }

    /// The module whose parameters start at `offset`, with layers of capacity `N` (see
    /// [`width`]). Called where the pass runs, with a constant `kind` wherever the caller knows
    /// it, so that the layout's shapes are constants there (never captured by a closure).
    #[inline(always)]
    fn pass<const N: usize, const EXACT: bool>(
        &self,
        offset: usize,
        kind: ModuleKind,
    ) -> Pass<'_, S> {
        let width = width::<N, EXACT>(self.width);
        let layout = ModuleLayout::new(kind, width);
        Pass {
            params: self.module_parameters(offset, layout.len),
            layout,
            width,
        }
    }
}

/// One module's two hidden layers, forward and back.
struct Pass<'p, S> {
    params: &'p [S],
    layout: ModuleLayout,
    width: usize,
}

impl<S: Scalar> Pass<'_, S> {
    /// Forward through layers a and b on the concatenated `inputs` (see [`forward`]; a node's
    /// layer a′ when `NODE`, see [`forward_node`]), `above` for the rest, then back through b:
    /// returns ∂Φ/∂Hₐ, the gradient at layer a's pre-activations (its transpose gives
    /// ∂Φ/∂inputs).
    #[inline(always)]
    fn run<const L: usize, const N: usize, const EXACT: bool, const NODE: bool>(
        &self,
        inputs: LayerInputs<'_, S, L>,
        gradient: &mut Gradient<S, L>,
        above: &mut Above<'_, S, L, N>,
    ) -> [[S; L]; N] {
        let (params, layout, width) = (self.params, &self.layout, self.width);
        let a: [[S; L]; N] = if NODE {
            forward_node(params, &layout.hidden_a, inputs)
        } else {
            forward(params, &layout.hidden_a, inputs)
        };
        let a = a.get(..width).unwrap_or(&[]);
        let b: [[S; L]; N] = forward(params, &layout.hidden_b, (a, &[], &[]));
        let delta_b = above(&b, gradient);
        let delta_b = delta_b.get(..width).unwrap_or(&[]);
        transposed_through_activation::<S, L, N, EXACT>(
            params,
            &layout.hidden_b,
            (0, width),
            delta_b,
            a,
        )
    }
}

/// ∇Φ += 2^`shift`·Aᵀ·∂Φ/∂x′ for a module whose normalized position is x′ = A·(x − c)·2^`shift`
/// (a leaf's input, the last three inputs of a node; see [`normalized_input`]).
#[inline]
fn add_normalization_transpose<S: Scalar, const L: usize>(
    params: &[S],
    delta_input: &[[S; L]; 3],
    gradient: &mut Gradient<S, L>,
    shift: i8,
) {
    // `f32` models always fold the frame at load: no run-time shift to compile.
    if S::KIND != ScalarKind::F32 && shift != 0 {
        add_scaled_transpose(params, delta_input, gradient, shift);
    } else {
        add_transpose(params, delta_input, gradient);
    }
}

/// [`add_transpose`] of ∂Φ/∂x′·2^`shift`, out of line (see [`scale_lanes`]).
#[inline(never)]
fn add_scaled_transpose<S: Scalar, const L: usize>(
    params: &[S],
    delta_input: &[[S; L]; 3],
    gradient: &mut Gradient<S, L>,
    shift: i8,
) {
    let mut scaled = *delta_input;
    scale_lanes(&mut scaled, shift);
    add_transpose(params, &scaled, gradient);
}

#[inline]
fn add_transpose<S: Scalar, const L: usize>(
    params: &[S],
    delta_input: &[[S; L]; 3],
    gradient: &mut Gradient<S, L>,
) {
    let Some(axes) = params.get(3..NORMALIZATION_LEN) else {
        return;
    };
    for (row, delta) in axes.chunks_exact(3).zip(delta_input) {
        for (&a, coordinate) in row.iter().zip(gradient.iter_mut()) {
            for (acc, &d) in coordinate.iter_mut().zip(delta) {
                *acc = S::mac(*acc, a, d);
            }
        }
    }
}
