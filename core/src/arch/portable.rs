//! No target kernels: every function says "use the portable loop". What every target but the
//! Cortex-M4F compiles (signatures as in `m4f.rs`).

use super::Lanes;
use crate::scalar::Q16;

#[inline(always)]
pub(super) fn q16_transposed<const IN: usize, const OUT: usize>(
    _: &[[Q16; IN]; OUT],
    _: &[Q16; OUT],
) -> Option<[Q16; IN]> {
    None
}

#[inline(always)]
pub(super) fn q16_times_slope<const N: usize>(
    _: &mut [Q16; N],
    _: &[Q16; N],
    _: i32,
    _: i32,
) -> Option<u32> {
    None
}

#[inline(always)]
pub(super) fn q16_layer<const IN: usize, const OUT: usize>(
    _: &[[Q16; IN]; OUT],
    _: &[Q16; OUT],
    _: &[Q16; IN],
    _: &[[i32; 2]; 1281],
) -> Option<[Q16; OUT]> {
    None
}

#[inline(always)]
pub(super) fn q16_transposed_slope<const IN: usize, const OUT: usize>(
    _: &[[Q16; IN]; OUT],
    _: &[Q16; OUT],
    _: &[Q16; IN],
    _: i32,
    _: i32,
) -> Option<([Q16; IN], u32)> {
    None
}

/// No `f32` single-point kernels.
pub(super) const F32_TARGET_KERNELS: bool = false;

#[inline(always)]
pub(super) fn f32_layer<const IN: usize, const OUT: usize>(
    _: &[[f32; IN]; OUT],
    _: &[f32; OUT],
    _: &[f32; IN],
) -> Option<[f32; OUT]> {
    None
}

#[inline(always)]
pub(super) fn f32_transposed<const COUNT: usize, const OUT: usize, const COLUMNS: usize>(
    _: &[[f32; COUNT]; OUT],
    _: usize,
    _: &[f32; OUT],
    _: Option<&[f32; COLUMNS]>,
) -> Option<[f32; COLUMNS]> {
    None
}

/// No `f32` lane kernels.
pub(super) const F32_LANE_KERNELS: bool = false;

/// Without lane kernels, one lane group per neuron.
pub(super) const F32_HOST_LANES: usize = crate::implicit::LANES;

#[inline(always)]
pub(super) fn f32_forward_lanes(
    _: &[f32],
    _: &[f32],
    _: [&[Lanes]; 3],
    _: usize,
    _: &mut [Lanes],
) -> bool {
    false
}

#[inline(always)]
pub(super) fn f32_transposed_lanes(
    _: &[f32],
    _: usize,
    _: (usize, usize),
    _: (&[Lanes], usize),
    _: &mut [Lanes],
) -> bool {
    false
}

#[inline(always)]
pub(super) fn f32_transposed_slope_lanes(
    _: &[f32],
    _: usize,
    _: (usize, usize),
    _: (&[Lanes], usize),
    _: &[Lanes],
    _: &mut [Lanes],
) -> bool {
    false
}

/// No Q16.16 lane kernels.
pub(super) const Q16_LANE_KERNELS: bool = false;

#[inline(always)]
pub(super) fn q16_forward_lanes(
    _: &[Q16],
    _: &[Q16],
    _: [&[Lanes<Q16>]; 3],
    _: &mut [Lanes<Q16>],
) -> bool {
    false
}

#[inline(always)]
pub(super) fn q16_transposed_lanes(
    _: &[Q16],
    _: usize,
    _: (usize, usize),
    _: &[Lanes<Q16>],
    _: Option<&[Lanes<Q16>]>,
    _: &mut [Lanes<Q16>],
) -> bool {
    false
}
