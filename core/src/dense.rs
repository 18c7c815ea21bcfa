//! The fully connected layer with the scaled-tanh activation: the one hot loop of every
//! implicit module.

use crate::implicit::{DenseLayout, MAX_WIDTH};
use crate::jet::Jet;
use crate::scalar::Scalar;

/// A layer's neurons (the first `width` are meaningful).
pub(crate) type Layer<S, const L: usize, const D: usize> = [Jet<S, L, D>; MAX_WIDTH];

/// Evaluates the layer at `layout` inside `params` on the concatenation of `first` and
/// `second` into `out[..layout.outputs]`: Hⱼ = bⱼ + Σᵢ Wⱼᵢ·xᵢ, Oⱼ = a(Hⱼ), and tangents
/// ᵏGⱼ = a′(Hⱼ)·Σᵢ Wⱼᵢ·ᵏxᵢ.
///
/// Writes nothing when `params` is too short for the layout or `out` too small (the model
/// loader guarantees both, so that never happens after validation). No allocation, no copy
/// of a whole layer: the caller owns the buffers.
#[inline]
pub(crate) fn dense<S: Scalar, const L: usize, const D: usize>(
    params: &[S],
    layout: &DenseLayout,
    first: &[Jet<S, L, D>],
    second: &[Jet<S, L, D>],
    out: &mut [Jet<S, L, D>],
) {
    let (inputs, outputs) = (layout.inputs, layout.outputs);
    let (Some(weights), Some(biases), Some(out)) = (
        params.get(layout.weights..layout.weights + inputs * outputs),
        params.get(layout.biases..layout.biases + outputs),
        out.get_mut(..outputs),
    ) else {
        return;
    };
    if inputs == 0 {
        return;
    }
    for ((row, &bias), slot) in weights.chunks_exact(inputs).zip(biases).zip(out) {
        *slot = neuron(row, bias, first, second);
    }
}

/// One neuron: weighted sum of values and tangents, activation, chain rule.
#[inline(always)]
fn neuron<S: Scalar, const L: usize, const D: usize>(
    row: &[S],
    bias: S,
    first: &[Jet<S, L, D>],
    second: &[Jet<S, L, D>],
) -> Jet<S, L, D> {
    let mut value = [bias.to_acc(); L];
    let mut tangent = [[S::ZERO.to_acc(); L]; D];
    let (row_first, row_second) = row.split_at(first.len().min(row.len()));
    accumulate(&mut value, &mut tangent, row_first, first);
    accumulate(&mut value, &mut tangent, row_second, second);
    let mut out = Jet::ZERO;
    for (lane, acc) in value.iter().enumerate() {
        let a = S::activation(S::from_acc(*acc));
        let slope = S::activation_slope(a);
        if let Some(slot) = out.value.get_mut(lane) {
            *slot = a;
        }
        for (out_k, acc_k) in out.tangent.iter_mut().zip(&tangent) {
            if let (Some(slot), Some(t)) = (out_k.get_mut(lane), acc_k.get(lane)) {
                *slot = slope.mul(S::from_acc(*t));
            }
        }
    }
    out
}

/// `acc += Σᵢ wᵢ·xᵢ` over values and tangents, lane by lane.
#[inline(always)]
fn accumulate<S: Scalar, const L: usize, const D: usize>(
    value: &mut [S::Acc; L],
    tangent: &mut [[S::Acc; L]; D],
    weights: &[S],
    inputs: &[Jet<S, L, D>],
) {
    for (&w, x) in weights.iter().zip(inputs) {
        for (acc, &v) in value.iter_mut().zip(&x.value) {
            *acc = S::mac(*acc, w, v);
        }
        for (acc_k, x_k) in tangent.iter_mut().zip(&x.tangent) {
            for (acc, &t) in acc_k.iter_mut().zip(x_k) {
                *acc = S::mac(*acc, w, t);
            }
        }
    }
}
