//! The fully connected layer with the scaled-tanh activation, forward and transposed: the hot
//! loops of every implicit module.
//!
//! Both directions work on blocks of [`BLOCK`] rows (forward) or columns (transposed), so one
//! load of an input feeds four multiply–accumulates and the accumulators stay in registers.
//! `L` lanes hold independent points in structure-of-arrays form (`L = 1` for single points):
//! the innermost loops run over contiguous lanes and vectorize.

use crate::implicit::{DenseLayout, MAX_WIDTH};
use crate::scalar::Scalar;

/// One value per lane for each neuron of a layer (the first `width` are meaningful).
pub(crate) type Layer<S, const L: usize> = [[S; L]; MAX_WIDTH];

/// Rows (or columns) processed together.
const BLOCK: usize = 4;

/// Evaluates the layer at `layout` inside `params` on the concatenation of `inputs.0` and
/// `inputs.1`: Hⱼ = bⱼ + Σᵢ Wⱼᵢ·xᵢ, `values[j]` = a(Hⱼ).
///
/// Writes nothing when `params` is too short for the layout or the outputs too small (the
/// model loader guarantees both, so that never happens after validation).
#[inline(always)]
pub(crate) fn forward<S: Scalar, const L: usize>(
    params: &[S],
    layout: &DenseLayout,
    inputs: (&[[S; L]], &[[S; L]]),
    values: &mut [[S; L]],
) {
    let (count, outputs) = (layout.inputs, layout.outputs);
    let (Some(weights), Some(biases), Some(values)) = (
        params.get(layout.weights..layout.weights + count * outputs),
        params.get(layout.biases..layout.biases + outputs),
        values.get_mut(..outputs),
    ) else {
        return;
    };
    if count == 0 || inputs.0.len() + inputs.1.len() != count {
        return;
    }
    let split = inputs.0.len();
    for ((row, &bias), value) in weights.chunks_exact(count).zip(biases).zip(values) {
        let (first, second) = row.split_at(split.min(count));
        let mut acc = [bias.to_acc(); L];
        accumulate_row(&mut acc, first, inputs.0);
        if !second.is_empty() {
            accumulate_row(&mut acc, second, inputs.1);
        }
        for (out, acc) in value.iter_mut().zip(&acc) {
            *out = S::activation(S::from_acc(*acc));
        }
    }
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

/// The transposed layer: δᵢ = Σⱼ Wⱼᵢ·gⱼ for every input i of the layer at `layout`, into the
/// concatenation of `out.0` and `out.1` (the gradient of Σⱼ gⱼ·Hⱼ with respect to the inputs).
///
/// Writes nothing when the slices do not match the layout (never after validation).
#[inline(always)]
pub(crate) fn transposed<S: Scalar, const L: usize>(
    params: &[S],
    layout: &DenseLayout,
    g: &[[S; L]],
    out: (&mut [[S; L]], &mut [[S; L]]),
) {
    let (count, outputs) = (layout.inputs, layout.outputs);
    let (Some(weights), Some(g)) = (
        params.get(layout.weights..layout.weights + count * outputs),
        g.get(..outputs),
    ) else {
        return;
    };
    if count == 0 || out.0.len() + out.1.len() != count {
        return;
    }
    let mut slots = out.0.iter_mut().chain(out.1.iter_mut());
    let mut column = 0;
    while column + BLOCK <= count {
        let mut acc = [[S::ZERO.to_acc(); L]; BLOCK];
        let [a0, a1, a2, a3] = &mut acc;
        let tail = weights.get(column..).unwrap_or(&[]);
        for (row, g) in tail.chunks(count).zip(g) {
            let Some(&[w0, w1, w2, w3]) = row.first_chunk::<BLOCK>() else {
                break;
            };
            for ((((&v, s0), s1), s2), s3) in g
                .iter()
                .zip(a0.iter_mut())
                .zip(a1.iter_mut())
                .zip(a2.iter_mut())
                .zip(a3.iter_mut())
            {
                *s0 = S::mac(*s0, w0, v);
                *s1 = S::mac(*s1, w1, v);
                *s2 = S::mac(*s2, w2, v);
                *s3 = S::mac(*s3, w3, v);
            }
        }
        for acc in &acc {
            round_into(acc, slots.next());
        }
        column += BLOCK;
    }
    while column < count {
        let mut acc = [S::ZERO.to_acc(); L];
        let tail = weights.get(column..).unwrap_or(&[]);
        for (row, g) in tail.chunks(count).zip(g) {
            let Some(&w) = row.first() else {
                break;
            };
            for (s, &v) in acc.iter_mut().zip(g) {
                *s = S::mac(*s, w, v);
            }
        }
        round_into(&acc, slots.next());
        column += 1;
    }
}

#[inline(always)]
fn round_into<S: Scalar, const L: usize>(acc: &[S::Acc; L], slot: Option<&mut [S; L]>) {
    if let Some(slot) = slot {
        for (out, acc) in slot.iter_mut().zip(acc) {
            *out = S::from_acc(*acc);
        }
    }
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
