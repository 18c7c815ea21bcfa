//! The fully connected layer with the scaled-tanh activation, forward and transposed: the hot
//! loops of every implicit module.
//!
//! Layers are fixed-size arrays `[[S; L]; N]`: `L` lanes hold independent points in
//! structure-of-arrays form (`L = 1` for single points) and `N` is a capacity of which the
//! layout's width is used. When the caller instantiates `N` with the model's exact width (see
//! [`crate::implicit`]'s width dispatch), every loop bound below is a compile-time constant: the
//! compiler unrolls the rows, keeps a layer's inputs in registers and drops all checks. The
//! kernels return their layers by value, computed neuron by neuron, so no buffer is zeroed
//! before it is written.

use crate::implicit::DenseLayout;
use crate::scalar::Scalar;

/// Evaluates the layer at `layout` inside `params` on the concatenation of `inputs.0` and
/// `inputs.1`: Hⱼ = bⱼ + Σᵢ Wⱼᵢ·xᵢ, output j = a(Hⱼ) for j below the layer's width (at most `OUT`).
///
/// Outputs beyond the layer's width, and all outputs when `params` is too short for the layout
/// or the inputs do not match it, are zero (the model loader rules both out).
#[inline(always)]
pub(crate) fn forward<S: Scalar, const L: usize, const OUT: usize>(
    params: &[S],
    layout: &DenseLayout,
    inputs: (&[[S; L]], &[[S; L]]),
) -> [[S; L]; OUT] {
    let (count, outputs) = (layout.inputs, layout.outputs);
    let (Some(weights), Some(biases)) = (
        params.get(layout.weights..layout.weights + count * outputs),
        params.get(layout.biases..layout.biases + outputs),
    ) else {
        return [[S::ZERO; L]; OUT];
    };
    if count == 0 || inputs.0.len() + inputs.1.len() != count {
        return [[S::ZERO; L]; OUT];
    }
    let split = inputs.0.len();
    let mut out = [[S::ZERO; L]; OUT];
    for ((out, row), &bias) in out.iter_mut().zip(weights.chunks_exact(count)).zip(biases) {
        let (first, second) = row.split_at_checked(split).unwrap_or((row, &[]));
        let mut acc = [bias.to_acc(); L];
        accumulate_row(&mut acc, first, inputs.0);
        accumulate_row(&mut acc, second, inputs.1);
        for (out, &acc) in out.iter_mut().zip(&acc) {
            *out = S::activation_from_acc(acc);
        }
    }
    out
}

/// `acc += Σᵢ row[i]·x[i]`.
#[inline(always)]
fn accumulate_row<S: Scalar, const L: usize>(acc: &mut [S::Acc; L], row: &[S], x: &[[S; L]]) {
    for (x, &w) in x.iter().zip(row) {
        for (s, &v) in acc.iter_mut().zip(x) {
            *s = S::mac(*s, w, v);
        }
    }
}

/// The transposed layer: δᵢ = Σⱼ Wⱼᵢ·gⱼ (the gradient of Σⱼ gⱼ·Hⱼ with respect to input i of
/// the layer at `layout`) for the `columns` inputs `first..first + columns` (`columns` ≤ `K`).
///
/// Slots from `columns` on, and all slots when the slices do not match the layout (never after
/// validation), are zero.
#[inline(always)]
pub(crate) fn transposed<S: Scalar, const L: usize, const K: usize>(
    params: &[S],
    layout: &DenseLayout,
    (first, columns): (usize, usize),
    g: &[[S; L]],
) -> [[S; L]; K] {
    let (count, outputs) = (layout.inputs, layout.outputs);
    let (Some(weights), Some(g)) = (
        params.get(layout.weights..layout.weights + count * outputs),
        g.get(..outputs),
    ) else {
        return [[S::ZERO; L]; K];
    };
    if count == 0 {
        return [[S::ZERO; L]; K];
    }
    let mut out = [[S::ZERO; L]; K];
    for (out, column) in out.iter_mut().zip(first..first + columns) {
        let mut acc = [S::ZERO.to_acc(); L];
        for (row, g) in weights.chunks_exact(count).zip(g) {
            if let Some(&w) = row.get(column) {
                for (s, &v) in acc.iter_mut().zip(g) {
                    *s = S::mac(*s, w, v);
                }
            }
        }
        for (out, &acc) in out.iter_mut().zip(&acc) {
            *out = S::from_acc(acc);
        }
    }
    out
}

/// `δ[j] ← δ[j]·a′(Hⱼ)` lane by lane, with a′ recovered from the layer's outputs a(Hⱼ): the
/// chain rule through the activation.
#[inline(always)]
pub(crate) fn through_activation<S: Scalar, const L: usize>(
    delta: &mut [[S; L]],
    outputs: &[[S; L]],
) {
    for (delta, output) in delta.iter_mut().zip(outputs) {
        for (d, &a) in delta.iter_mut().zip(output) {
            *d = d.mul(S::activation_slope(a));
        }
    }
}
