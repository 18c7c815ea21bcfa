//! The fully connected layer with the scaled-tanh activation, forward and transposed: the hot
//! loops of every implicit module.
//!
//! Layers are fixed-size arrays `[[S; L]; N]`: `L` lanes hold independent points in
//! structure-of-arrays form (`L = 1` for single points) and `N` is a capacity of which the
//! layout's width is used. When the caller instantiates `N` with the model's exact width (see
//! [`crate::implicit`]'s width dispatch), every loop bound below is a compile-time constant: the
//! compiler unrolls the rows, keeps a layer's inputs in registers and drops all checks. The
//! kernels return their layers by value, computed neuron by neuron, so no buffer is zeroed
//! before it is written (see `unwritten`).
//!
//! A scalar may bring target kernels for whole layers (`Kernels::layer_kernel`,
//! `Kernels::transposed_kernel`), for the chain rule through a layer
//! (`Kernels::times_slope_kernel`) and for both at once (`Kernels::transposed_slope_kernel`):
//! for single points whose layer shape one of them covers, the loops below hand the work to
//! it. Q16.16 on a Cortex-M4F has them for the N = 9 shapes (`neurosurf-m4f`); `f32` on x86-64
//! with AVX2 for the N = 9 layers with nine neurons and their transposes onto nine inputs, a
//! node's three-part layer a′ included (`neurosurf-avx2`'s single-point kernels). For a lane
//! group of [`LANES`] points, or several such groups per neuron, a scalar may bring lane
//! kernels (`Kernels::forward_lanes_kernel`, `Kernels::transposed_lanes_kernel`,
//! `Kernels::transposed_slope_lanes_kernel`): `f32` and Q16.16 on x86-64 with AVX2
//! (`neurosurf-avx2`; `f32` batches there run four groups per neuron). Every kernel computes the loops' exact bits,
//! so which path ran never shows in a result.

use crate::implicit::{DenseLayout, LANES};
use crate::scalar::Scalar;

/// Columns a blocked transposed layer accumulates together.
const BLOCK: usize = 4;

/// A layer's input in up to three parts, read one after the other (see [`forward`]): a
/// single-part input leaves the last two empty.
pub(crate) type LayerInputs<'a, S, const L: usize> = (&'a [[S; L]], &'a [[S; L]], &'a [[S; L]]);

/// Evaluates the layer at `layout` inside `params` on the concatenation of `inputs.0`,
/// `inputs.1` and `inputs.2` (a leaf's layer a: its normalized input alone; a node's layer a′:
/// its children's last hidden layers and its normalized position; every other layer: the
/// layer below alone): Hⱼ = bⱼ + Σᵢ Wⱼᵢ·xᵢ, summed part after part in input order, output
/// j = a(Hⱼ) for j below the layer's width (at most `OUT`).
///
/// Outputs beyond the layer's width are unspecified (callers slice the layer to its width); all
/// outputs are zero when `params` is too short for the layout or the inputs do not match it
/// (the model loader rules both out). Only single-part layers are offered to the scalar's
/// target kernels.
#[inline(always)]
pub(crate) fn forward<S: Scalar, const L: usize, const OUT: usize>(
    params: &[S],
    layout: &DenseLayout,
    inputs: LayerInputs<'_, S, L>,
) -> [[S; L]; OUT] {
    let (count, outputs) = (layout.inputs, layout.outputs);
    let (Some(weights), Some(biases)) = (
        params.get(layout.weights..layout.weights + count * outputs),
        params.get(layout.biases..layout.biases + outputs),
    ) else {
        return [[S::ZERO; L]; OUT];
    };
    if count == 0 || inputs.0.len() + inputs.1.len() + inputs.2.len() != count {
        return [[S::ZERO; L]; OUT];
    }
    if S::TARGET_KERNELS
        && L == 1
        && inputs.1.is_empty()
        && inputs.2.is_empty()
        && let Some(out) = forward_by_kernel(weights, biases, inputs.0)
    {
        return out;
    }
    if S::LANE_KERNELS && L.is_multiple_of(LANES) {
        let mut out = unwritten::<S, L, OUT>();
        let parts = [inputs.0, inputs.1, inputs.2].map(lanes);
        if S::forward_lanes_kernel(weights, biases, parts, L / LANES, lanes_mut(&mut out)) {
            return out;
        }
    }
    let (first, second) = (inputs.0.len(), inputs.1.len());
    let mut out = unwritten();
    for ((out, row), &bias) in out.iter_mut().zip(weights.chunks_exact(count)).zip(biases) {
        let (row_0, rest) = row.split_at_checked(first).unwrap_or((row, &[]));
        let (row_1, row_2) = rest.split_at_checked(second).unwrap_or((rest, &[]));
        let mut acc = [bias.to_acc(); L];
        accumulate_row(&mut acc, row_0, inputs.0);
        accumulate_row(&mut acc, row_1, inputs.1);
        accumulate_row(&mut acc, row_2, inputs.2);
        for (out, &acc) in out.iter_mut().zip(&acc) {
            *out = S::activation_from_acc(acc);
        }
    }
    out
}

/// The layer width the target kernels are written for (their shapes: 9×3, 9×9 and 1×9).
pub(crate) const KERNEL_WIDTH: usize = 9;

/// [`forward`] for one point through the scalar's target kernel, when it has one for the
/// layer's shape (`OUT` outputs, 3 or 9 inputs); `None` otherwise.
#[inline(always)]
fn forward_by_kernel<S: Scalar, const L: usize, const OUT: usize>(
    weights: &[S],
    biases: &[S],
    x: &[[S; L]],
) -> Option<[[S; L]; OUT]> {
    let layer = match x.len() {
        3 => layer_kernel::<S, 3, OUT>(weights, biases, x.as_flattened())?,
        9 => layer_kernel::<S, 9, OUT>(weights, biases, x.as_flattened())?,
        _ => return None,
    };
    let mut out = unwritten::<S, L, OUT>();
    fill(&mut out, layer).then_some(out)
}

/// [`forward`] for a node's layer a′ (three parts) in the field-and-gradient pass: for one
/// point through the scalar's target kernel where it has node kernels (see
/// `Kernels::NODE_KERNELS`). Kept out of [`forward`] and out of the field-only pass: in either
/// place its test, though constant on the Cortex-M4F, changed how the field evaluation
/// compiled there (1–7 % more instructions per evaluation, leaf-only models included).
#[inline(always)]
pub(crate) fn forward_node<S: Scalar, const L: usize, const OUT: usize>(
    params: &[S],
    layout: &DenseLayout,
    inputs: LayerInputs<'_, S, L>,
) -> [[S; L]; OUT] {
    if S::NODE_KERNELS
        && L == 1
        && let Some(weights) =
            params.get(layout.weights..layout.weights + layout.inputs * layout.outputs)
        && let Some(biases) = params.get(layout.biases..layout.biases + layout.outputs)
        && let Some(out) = node_forward_by_kernel(weights, biases, inputs)
    {
        return out;
    }
    forward(params, layout, inputs)
}

/// Inputs of a node's layer a′ at the kernels' width: both children's last hidden layers and
/// the node's normalized position.
const NODE_INPUTS: usize = 2 * KERNEL_WIDTH + 3;

/// [`forward`] for one point on a node's three-part input, joined, through the scalar's
/// target kernel (see `Kernels::NODE_KERNELS`); `None` unless it is a width-9 node's a′.
#[inline(always)]
fn node_forward_by_kernel<S: Scalar, const L: usize, const OUT: usize>(
    weights: &[S],
    biases: &[S],
    (left, right, position): LayerInputs<'_, S, L>,
) -> Option<[[S; L]; OUT]> {
    if left.len() + right.len() + position.len() != NODE_INPUTS {
        return None;
    }
    let mut x = [S::ZERO; NODE_INPUTS];
    let parts = left.iter().chain(right).chain(position);
    for (slot, input) in x.iter_mut().zip(parts) {
        *slot = *input.first()?;
    }
    let layer = layer_kernel::<S, NODE_INPUTS, OUT>(weights, biases, &x)?;
    let mut out = unwritten::<S, L, OUT>();
    fill(&mut out, layer).then_some(out)
}

/// `Kernels::layer_kernel` on slices of exactly the shape `(OUT, IN)`.
#[inline(always)]
fn layer_kernel<S: Scalar, const IN: usize, const OUT: usize>(
    weights: &[S],
    biases: &[S],
    x: &[S],
) -> Option<[S; OUT]> {
    let (rows, _) = weights.as_chunks::<IN>();
    if rows.len() != OUT || biases.len() != OUT || x.len() != IN {
        return None;
    }
    S::layer_kernel::<IN, OUT>(rows.first_chunk()?, biases.first_chunk()?, x.first_chunk()?)
}

/// [`transposed`] over all columns for one point through the scalar's target kernel, when it
/// has one for the layer's shape; `None` otherwise.
#[inline(always)]
fn transposed_by_kernel<S: Scalar, const L: usize, const K: usize>(
    weights: &[S],
    count: usize,
    g: &[[S; L]],
) -> Option<[[S; L]; K]> {
    let g = g.as_flattened();
    let mut out = unwritten::<S, L, K>();
    match (g.len(), count) {
        (9, 9) => fill(&mut out, transposed_kernel::<S, 9, 9>(weights, g)?),
        (9, 3) => fill(&mut out, transposed_kernel::<S, 3, 9>(weights, g)?),
        (1, 9) => fill(&mut out, transposed_kernel::<S, 9, 1>(weights, g)?),
        _ => return None,
    }
    .then_some(out)
}

/// `Kernels::transposed_kernel` on slices of exactly the shape `(OUT, IN)`.
#[inline(always)]
fn transposed_kernel<S: Scalar, const IN: usize, const OUT: usize>(
    weights: &[S],
    g: &[S],
) -> Option<[S; IN]> {
    let (rows, _) = weights.as_chunks::<IN>();
    if rows.len() != OUT || g.len() != OUT {
        return None;
    }
    S::transposed_kernel::<IN, OUT>(rows.first_chunk()?, g.first_chunk()?)
}

/// Writes `values` into the first slots of `out`; false when they do not fit.
#[inline(always)]
fn fill<S: Scalar, const L: usize, const IN: usize>(out: &mut [[S; L]], values: [S; IN]) -> bool {
    if IN > out.len() {
        return false;
    }
    for (out, value) in out.iter_mut().zip(values) {
        *out = [value; L];
    }
    true
}

/// A layer buffer whose slots below the width are all written before they are read, filled
/// with ones rather than zeros: on the Cortex-M4 a zero fill of more than eight words (N = 9)
/// becomes a call to `memset` (~40 instructions per layer, ~1/20 of a field and gradient),
/// whereas a fill with a non-zero pattern is plain stores, which the compiler drops as
/// overwritten.
#[inline(always)]
fn unwritten<S: Scalar, const L: usize, const N: usize>() -> [[S; L]; N] {
    [[S::ONE; L]; N]
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
/// Slots from `columns` on are unspecified; all slots are zero when the slices do not match the
/// layout (never after validation).
///
/// For single points (`L = 1`) at a run-time width (`EXACT` false), four columns are accumulated
/// at a time, so that each gⱼ is loaded once for four multiply–accumulates and the loop set-up
/// is shared; with the width compiled as a constant, or with eight lanes, the compiler does
/// better one column at a time (measured on the M4). Every column is summed in the same order
/// either way.
#[inline(always)]
pub(crate) fn transposed<S: Scalar, const L: usize, const K: usize, const EXACT: bool>(
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
    if S::TARGET_KERNELS
        && L == 1
        && first == 0
        && columns == count
        && let Some(out) = transposed_by_kernel(weights, count, g)
    {
        return out;
    }
    if S::LANE_KERNELS && L.is_multiple_of(LANES) {
        let mut out = unwritten::<S, L, K>();
        if S::transposed_lanes_kernel(
            weights,
            count,
            (first, columns),
            (lanes(g), L / LANES),
            lanes_mut(&mut out),
        ) {
            return out;
        }
    }
    let mut out = unwritten();
    let mut done = 0;
    if !EXACT && L == 1 {
        for block in out.chunks_exact_mut(BLOCK) {
            if done + BLOCK > columns {
                break;
            }
            let column = first + done;
            let mut acc = [[S::ZERO.to_acc(); L]; BLOCK];
            let [a0, a1, a2, a3] = &mut acc;
            for (row, g) in weights.chunks_exact(count).zip(g) {
                let Some(&[w0, w1, w2, w3]) = row.get(column..).and_then(<[S]>::first_chunk) else {
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
            for (out, acc) in block.iter_mut().zip(&acc) {
                for (out, &acc) in out.iter_mut().zip(acc) {
                    *out = S::from_acc(acc);
                }
            }
            done += BLOCK;
        }
    }
    for (out, column) in out.iter_mut().skip(done).zip(first + done..first + columns) {
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

/// [`transposed`] followed by [`through_activation`] with `outputs` (the layer whose inputs
/// the columns are): δᵢ = a′ᵢ·Σⱼ Wⱼᵢ·gⱼ, the gradient at the pre-activations of the layer
/// below. A scalar's `Kernels::transposed_slope_kernel` does both in one pass for one point
/// over all columns of the shapes it covers; the result is the same bit for bit.
#[inline(always)]
pub(crate) fn transposed_through_activation<
    S: Scalar,
    const L: usize,
    const K: usize,
    const EXACT: bool,
>(
    params: &[S],
    layout: &DenseLayout,
    (first, columns): (usize, usize),
    g: &[[S; L]],
    outputs: &[[S; L]],
) -> [[S; L]; K] {
    if S::TARGET_KERNELS
        && L == 1
        && first == 0
        && columns == layout.inputs
        && let Some(out) = transposed_slope_by_kernel(params, layout, g, outputs)
    {
        return out;
    }
    if S::NODE_KERNELS
        && L == 1
        && layout.inputs == NODE_INPUTS
        && columns == KERNEL_WIDTH
        && let Some(out) = node_transposed_slope_by_kernel(params, layout, first, g, outputs)
    {
        return out;
    }
    if S::LANE_KERNELS
        && L.is_multiple_of(LANES)
        && let Some(out) =
            transposed_slope_by_lane_kernel(params, layout, (first, columns), g, outputs)
    {
        return out;
    }
    let mut delta = transposed::<S, L, K, EXACT>(params, layout, (first, columns), g);
    through_activation(&mut delta, outputs);
    delta
}

/// [`transposed_through_activation`] over all columns for one point through the scalar's
/// target kernel, when it has one for the layer's shape; `None` otherwise.
#[inline(always)]
fn transposed_slope_by_kernel<S: Scalar, const L: usize, const K: usize>(
    params: &[S],
    layout: &DenseLayout,
    g: &[[S; L]],
    outputs: &[[S; L]],
) -> Option<[[S; L]; K]> {
    let (count, rows) = (layout.inputs, layout.outputs);
    let weights = params.get(layout.weights..layout.weights + count * rows)?;
    let (g, a) = (g.get(..rows)?.as_flattened(), outputs.as_flattened());
    let mut out = unwritten::<S, L, K>();
    match (rows, count) {
        (9, 9) => fill(&mut out, transposed_slope_kernel::<S, 9, 9>(weights, g, a)?),
        (1, 9) => fill(&mut out, transposed_slope_kernel::<S, 9, 1>(weights, g, a)?),
        _ => return None,
    }
    .then_some(out)
}

/// [`transposed_through_activation`] for one point onto one child's part (nine columns from
/// `first`) of a width-9 node's layer a′, through the scalar's target kernel (see
/// `Kernels::NODE_KERNELS`); `None` when it declines.
#[inline(always)]
fn node_transposed_slope_by_kernel<S: Scalar, const L: usize, const K: usize>(
    params: &[S],
    layout: &DenseLayout,
    first: usize,
    g: &[[S; L]],
    outputs: &[[S; L]],
) -> Option<[[S; L]; K]> {
    let weights = params.get(layout.weights..layout.weights + NODE_INPUTS * KERNEL_WIDTH)?;
    let (rows, _) = weights.as_chunks::<NODE_INPUTS>();
    let rows: &[[S; NODE_INPUTS]; KERNEL_WIDTH] = rows.try_into().ok()?;
    let g: &[S; KERNEL_WIDTH] = g.get(..layout.outputs)?.as_flattened().try_into().ok()?;
    let a: &[S; KERNEL_WIDTH] = outputs.as_flattened().try_into().ok()?;
    let delta = S::transposed_part_kernel(rows, first, g, Some(a))?;
    let mut out = unwritten::<S, L, K>();
    fill(&mut out, delta).then_some(out)
}

/// [`transposed_through_activation`] for a lane group through the scalar's lane kernel, when
/// it takes the shape; `None` otherwise.
#[inline(always)]
fn transposed_slope_by_lane_kernel<S: Scalar, const L: usize, const K: usize>(
    params: &[S],
    layout: &DenseLayout,
    columns: (usize, usize),
    g: &[[S; L]],
    outputs: &[[S; L]],
) -> Option<[[S; L]; K]> {
    let (count, rows) = (layout.inputs, layout.outputs);
    let weights = params.get(layout.weights..layout.weights + count * rows)?;
    let mut out = unwritten::<S, L, K>();
    S::transposed_slope_lanes_kernel(
        weights,
        count,
        columns,
        (lanes(g.get(..rows)?), L / LANES),
        lanes(outputs),
        lanes_mut(&mut out),
    )
    .then_some(out)
}

/// Lanes of `L` points as lane groups of [`LANES`]: neuron k's `L / LANES` groups side by
/// side (all of them when `L` is a multiple of `LANES`, the only case the lane kernels are
/// offered).
#[inline(always)]
fn lanes<S, const L: usize>(x: &[[S; L]]) -> &[[S; LANES]] {
    x.as_flattened().as_chunks::<LANES>().0
}

/// [`lanes`], writable.
#[inline(always)]
fn lanes_mut<S, const L: usize>(x: &mut [[S; L]]) -> &mut [[S; LANES]] {
    x.as_flattened_mut().as_chunks_mut::<LANES>().0
}

/// `Kernels::transposed_slope_kernel` on slices of exactly the shape `(OUT, IN)`.
#[inline(always)]
fn transposed_slope_kernel<S: Scalar, const IN: usize, const OUT: usize>(
    weights: &[S],
    g: &[S],
    a: &[S],
) -> Option<[S; IN]> {
    let (rows, _) = weights.as_chunks::<IN>();
    if rows.len() != OUT || g.len() != OUT || a.len() != IN {
        return None;
    }
    S::transposed_slope_kernel::<IN, OUT>(rows.first_chunk()?, g.first_chunk()?, a.first_chunk()?)
}

/// `δ[j] ← δ[j]·a′(Hⱼ)` lane by lane, with a′ recovered from the layer's outputs a(Hⱼ): the
/// chain rule through the activation.
#[inline(always)]
pub(crate) fn through_activation<S: Scalar, const L: usize>(
    delta: &mut [[S; L]],
    outputs: &[[S; L]],
) {
    if S::TARGET_KERNELS
        && L == 1
        && delta.len() == KERNEL_WIDTH
        && outputs.len() == KERNEL_WIDTH
        && let (Some(d), Some(a)) = (
            delta.as_flattened_mut().first_chunk_mut::<KERNEL_WIDTH>(),
            outputs.as_flattened().first_chunk::<KERNEL_WIDTH>(),
        )
        && S::times_slope_kernel(d, a)
    {
        return;
    }
    for (delta, output) in delta.iter_mut().zip(outputs) {
        for (d, &a) in delta.iter_mut().zip(output) {
            *d = S::times_slope(*d, a);
        }
    }
}
