//! Φ and ∇Φ together in reverse mode: one forward pass that keeps each layer's outputs (a′ follows
//! from a),
//! then one transposed pass from the root's output down to every leaf's input.
//!
//! Carcenac §4 differentiates forward (three tangents per neuron: four times the multiply–
//! accumulates of Φ). Reverse mode needs about twice those of Φ, independent of the input
//! dimension. The pass down needs every module's slopes, which a tape would have to reserve for
//! the largest model; instead each module hands the rest of the evaluation to its parent as a
//! continuation ([`Above`]) and keeps its slopes in its own stack frame until the pass comes back
//! down through it. Stack use is therefore proportional to the model actually loaded (about
//! `4·MAX_WIDTH·L` scalars per module), and nothing is allocated or zeroed beyond that.

use super::eval::{FieldGradient, ModuleView, normalized_input};
use super::layout::{MAX_HEIGHT, MAX_WIDTH, ModuleKind, ModuleLayout, NORMALIZATION_LEN};
use super::model::ImplicitModel;
use crate::dense::{Layer, forward, through_activation, transposed};
use crate::scalar::Scalar;

/// ∇Φ summed over the leaves, per coordinate and lane, in the wide accumulator.
type Gradient<S, const L: usize> = [[<S as Scalar>::Acc; L]; 3];

/// The evaluation above a module: given the module's last hidden layer (b), it finishes the
/// forward pass, runs the transposed pass down to this module, and returns ∂Φ/∂b.
type Above<'f, S, const L: usize> = dyn FnMut(&[[S; L]], &mut Gradient<S, L>) -> Layer<S, L> + 'f;

impl<S: Scalar, const P: usize, const M: usize> ModuleView<'_, S, P, M> {
    /// Φ and ∇Φ at `L` points at once.
    #[inline]
    pub(crate) fn field_gradient_lanes<const L: usize>(
        &self,
        points: &[[S; 3]; L],
    ) -> [FieldGradient<S>; L] {
        let model = self.model;
        let width = model.width;
        let mut value = [S::ZERO; L];
        let mut gradient = [[S::ZERO.to_acc(); L]; 3];
        if let Some(entry) = model.modules.get(self.module) {
            let layout = ModuleLayout::new(entry.kind, width);
            let params = model.module_parameters(entry.offset, layout.len);
            let root = &mut |hidden: &[[S; L]], _: &mut Gradient<S, L>| {
                let mut out = [[S::ZERO; L]; 1];
                forward(params, &layout.output, (hidden, &[]), &mut out);
                [value] = out;
                let slope = [value.map(S::activation_slope)];
                // ∂Φ/∂bⱼ = a′(H)·wⱼ
                let mut delta = [[S::ZERO; L]; MAX_WIDTH];
                let below = delta.get_mut(..width).unwrap_or(&mut []);
                transposed(params, &layout.output, &slope, (below, &mut []));
                delta
            };
            model.reverse(self.module, points, MAX_HEIGHT, &mut gradient, root);
        }
        let [g0, g1, g2] = gradient.map(|lanes| lanes.map(S::from_acc));
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
    /// then the transposed pass back down, adding each leaf's share of ∇Φ to `gradient`.
    /// `budget` bounds the recursion (validated tree heights never exhaust it).
    fn reverse<const L: usize>(
        &self,
        index: usize,
        points: &[[S; 3]; L],
        budget: usize,
        gradient: &mut Gradient<S, L>,
        above: &mut Above<'_, S, L>,
    ) {
        let (Some(entry), Some(budget)) = (self.modules.get(index), budget.checked_sub(1)) else {
            return;
        };
        let width = self.width;
        let layout = ModuleLayout::new(entry.kind, width);
        let params = self.module_parameters(entry.offset, layout.len);
        match entry.kind {
            ModuleKind::Leaf => {
                let input = normalized_input(params, points);
                let mut delta_input = [[S::ZERO; L]; 3];
                let pass = Pass { params, layout };
                pass.run((&input, &[]), gradient, above, (&mut delta_input, &mut []));
                add_normalization_transpose(params, &delta_input, gradient);
            }
            ModuleKind::Node => {
                let right_child = index.saturating_sub(1);
                self.reverse(
                    entry.left,
                    points,
                    budget,
                    gradient,
                    &mut |left, gradient| {
                        let mut delta_left = [[S::ZERO; L]; MAX_WIDTH];
                        self.reverse(
                            right_child,
                            points,
                            budget,
                            gradient,
                            &mut |right, gradient| {
                                let mut delta_right = [[S::ZERO; L]; MAX_WIDTH];
                                let pass = Pass { params, layout };
                                let out = (
                                    delta_left.get_mut(..width).unwrap_or(&mut []),
                                    delta_right.get_mut(..width).unwrap_or(&mut []),
                                );
                                pass.run((left, right), gradient, &mut *above, out);
                                delta_right
                            },
                        );
                        delta_left
                    },
                );
            }
        }
    }
}

/// One module's two hidden layers, forward and back.
struct Pass<'p, S> {
    params: &'p [S],
    layout: ModuleLayout,
}

impl<S: Scalar> Pass<'_, S> {
    /// Forward through layers a and b on `inputs`, `above` for the rest, then ∂Φ/∂inputs into
    /// `out`.
    #[inline]
    fn run<const L: usize>(
        &self,
        inputs: (&[[S; L]], &[[S; L]]),
        gradient: &mut Gradient<S, L>,
        above: &mut Above<'_, S, L>,
        out: (&mut [[S; L]], &mut [[S; L]]),
    ) {
        let (params, layout, width) = (self.params, &self.layout, self.layout.width);
        let (mut a, mut b) = ([[S::ZERO; L]; MAX_WIDTH], [[S::ZERO; L]; MAX_WIDTH]);
        forward(params, &layout.hidden_a, inputs, &mut a);
        let a = a.get(..width).unwrap_or(&[]);
        forward(params, &layout.hidden_b, (a, &[]), &mut b);
        let b = b.get(..width).unwrap_or(&[]);
        let mut delta_b = above(b, gradient);
        through_activation(&mut delta_b, b);
        let mut delta_a = [[S::ZERO; L]; MAX_WIDTH];
        let delta_b = delta_b.get(..width).unwrap_or(&[]);
        let below = delta_a.get_mut(..width).unwrap_or(&mut []);
        transposed(params, &layout.hidden_b, delta_b, (below, &mut []));
        through_activation(&mut delta_a, a);
        transposed(params, &layout.hidden_a, &delta_a, out);
    }
}

/// ∇Φ += Aᵀ·∂Φ/∂x′ for a leaf whose input is x′ = A·(x − c).
#[inline]
fn add_normalization_transpose<S: Scalar, const L: usize>(
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
