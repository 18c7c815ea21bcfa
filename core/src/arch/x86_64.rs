//! x86-64: the `neurosurf-avx2` kernels for eight-lane `f32` and Q16.16 batches, and for one
//! point's width-9 `f32` layers (its nine neurons side by side), which run when the processor
//! has AVX2 (detected at run time; otherwise they decline and the portable
//! loops run). Same bits either way: every lane computes the portable loop's operations in its
//! order (`f32`: unfused IEEE operations; Q16.16: exact 64-bit sums, the same roundings,
//! saturations and table lookups).

use neurosurf_avx2 as avx2;

use super::Lanes;
use crate::scalar::activation_f32::{AMPLITUDE, POLYNOMIAL, ROUNDER, SATURATION, U_PER_H};
use crate::scalar::Q16;
use crate::scalar::activation_table::{FRACTION_BITS, LAST, SEGMENTS};
use crate::scalar::float::{SLOPE_OFFSET, SLOPE_SQUARE};
use crate::scalar::q16::{SLOPE_OFFSET as Q16_SLOPE_OFFSET, SLOPE_SQUARE as Q16_SLOPE_SQUARE};

pub(super) use super::portable::{q16_layer, q16_times_slope, q16_transposed, q16_transposed_slope};

// The kernels' lane group is the core's.
const _: () = assert!(avx2::LANES == crate::implicit::LANES);

/// The `f32` lane kernels are compiled in, unless a comparison build turns them off with
/// `--cfg neurosurf_portable="f32_lanes"`.
pub(super) const F32_LANE_KERNELS: bool = !cfg!(neurosurf_portable = "f32_lanes");

/// Points per lane group of the `f32` field-and-gradient batches: the wide kernels' four
/// groups of eight per neuron. Four independent sums per weight hide the activation's latency
/// (its division), and the layer loops' set-up is paid once per 32 points.
pub(super) const F32_HOST_LANES: usize = avx2::WIDE_GROUPS * avx2::LANES;
const _: () = assert!(F32_HOST_LANES == crate::implicit::WIDE_LANES);

/// The core's `f32` activation constants (`scalar/activation_f32.rs`).
const ACTIVATION: avx2::Activation = avx2::Activation {
    u_per_h: U_PER_H,
    saturation: SATURATION,
    rounder: ROUNDER,
    polynomial: POLYNOMIAL,
    amplitude: AMPLITUDE,
};

/// The core's `f32` chain rule through the activation (`scalar/float.rs`).
const SLOPE: avx2::Slope = avx2::Slope {
    offset: SLOPE_OFFSET,
    square: SLOPE_SQUARE,
};

#[inline(always)]
pub(super) fn f32_forward_lanes(
    weights: &[f32],
    biases: &[f32],
    inputs: [&[Lanes]; 3],
    groups: usize,
    out: &mut [Lanes],
) -> bool {
    avx2::forward(weights, biases, inputs, groups, &ACTIVATION, out)
}

#[inline(always)]
pub(super) fn f32_transposed_lanes(
    weights: &[f32],
    count: usize,
    columns: (usize, usize),
    g: (&[Lanes], usize),
    out: &mut [Lanes],
) -> bool {
    avx2::transposed(weights, count, columns, g, out)
}

#[inline(always)]
pub(super) fn f32_transposed_slope_lanes(
    weights: &[f32],
    count: usize,
    columns: (usize, usize),
    g: (&[Lanes], usize),
    outputs: &[Lanes],
    out: &mut [Lanes],
) -> bool {
    avx2::transposed_slope(weights, count, columns, g, (outputs, &SLOPE), out)
}

/// The `f32` single-point kernels are compiled in, unless a comparison build turns them off
/// with `--cfg neurosurf_portable="f32_single"`.
pub(super) const F32_TARGET_KERNELS: bool = !cfg!(neurosurf_portable = "f32_single");

/// One point's forward layer, when it has nine neurons (any inputs).
#[inline(always)]
pub(super) fn f32_layer<const IN: usize, const OUT: usize>(
    w: &[[f32; IN]; OUT],
    b: &[f32; OUT],
    x: &[f32; IN],
) -> Option<[f32; OUT]> {
    if OUT != avx2::single::WIDTH {
        return None;
    }
    let out = avx2::single::layer(w.first_chunk()?, b.first_chunk()?, x, &ACTIVATION)?;
    out.as_slice().try_into().ok()
}

/// One point's transposed layer onto nine of its `COUNT` inputs from `first` on (any rows), and
/// with `a` the chain rule through their activations.
#[inline(always)]
pub(super) fn f32_transposed<const COUNT: usize, const OUT: usize, const COLUMNS: usize>(
    w: &[[f32; COUNT]; OUT],
    first: usize,
    g: &[f32; OUT],
    a: Option<&[f32; COLUMNS]>,
) -> Option<[f32; COLUMNS]> {
    if COLUMNS != avx2::single::WIDTH {
        return None;
    }
    let slope = match a {
        Some(a) => Some((a.as_slice().try_into().ok()?, &SLOPE)),
        None => None,
    };
    let out = avx2::single::transposed(w, first, g, slope)?;
    out.as_slice().try_into().ok()
}

/// The Q16.16 lane kernels are compiled in, unless a comparison build turns them off with
/// `--cfg neurosurf_portable="q16_lanes"`.
pub(super) const Q16_LANE_KERNELS: bool = !cfg!(neurosurf_portable = "q16_lanes");

/// The core's Q16.16 activation table (`scalar/activation_table.rs`).
const TABLE: avx2::FixedTable<'static> = avx2::FixedTable {
    segments: &SEGMENTS,
    last: LAST,
    fraction_bits: FRACTION_BITS,
};

#[inline(always)]
pub(super) fn q16_forward_lanes(
    weights: &[Q16],
    biases: &[Q16],
    inputs: [&[Lanes<Q16>]; 3],
    out: &mut [Lanes<Q16>],
) -> bool {
    avx2::fixed_forward(
        bytemuck::cast_slice(weights),
        bytemuck::cast_slice(biases),
        inputs.map(bytemuck::cast_slice),
        &TABLE,
        bytemuck::cast_slice_mut(out),
    )
}

/// The transposed layer, and with `outputs` the chain rule through their activations.
#[inline(always)]
pub(super) fn q16_transposed_lanes(
    weights: &[Q16],
    count: usize,
    columns: (usize, usize),
    g: &[Lanes<Q16>],
    outputs: Option<&[Lanes<Q16>]>,
    out: &mut [Lanes<Q16>],
) -> bool {
    const SLOPE: avx2::FixedSlope = avx2::FixedSlope {
        offset: Q16_SLOPE_OFFSET,
        square: Q16_SLOPE_SQUARE,
    };
    avx2::fixed_transposed(
        bytemuck::cast_slice(weights),
        count,
        columns,
        bytemuck::cast_slice(g),
        outputs.map(|a| (bytemuck::cast_slice(a), &SLOPE)),
        bytemuck::cast_slice_mut(out),
    )
}
