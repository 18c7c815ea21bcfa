//! The Cortex-M4F kernels (bare-metal hard-float ARM): the `neurosurf-m4f` assembly for the
//! width-9 layers of an N = 9 implicit module, each with exactly the bits of the portable loop
//! it replaces.
//!
//! Q16.16 only: the forward layers (products, rounding and the activation table's lookup in one
//! kernel each), the 9×9 and 1×9 transposes fused with the chain rule on their sums, the 9×3
//! transpose, and the chain rule alone through nine neurons. `f32` and the input normalization
//! have no kernel: by the simulator's cycle estimate the portable loops are faster there
//! (`docs/performance/kernels.md`).

use neurosurf_m4f as m4f;

pub(super) use super::portable::{
    F32_HOST_LANES, F32_LANE_KERNELS, F32_TARGET_KERNELS, Q16_LANE_KERNELS, f32_forward_lanes, f32_layer,
    f32_transposed, f32_transposed_lanes, f32_transposed_slope_lanes, q16_forward_lanes,
    q16_transposed_lanes,
};

use crate::scalar::Q16;

// Every kernel is in use unless a comparison build turns it off with
// `--cfg neurosurf_portable="<kernel>"` (`neurosurf sim-bench --kernel-comparison` does, to
// price the portable loop it replaces): the `cfg` attributes and `cfg!` tests below leave the
// default build's code as it would be without them.

// The forward kernels hard-code the activation table's layout: 1 281 segments of two words,
// H = 0 at index 640, one segment per 2¹⁰ bits of H.
const _: () = {
    use crate::scalar::activation_table::{FRACTION_BITS, LAST, SEGMENTS};
    assert!(FRACTION_BITS == 10 && LAST == 640 && SEGMENTS.len() == 1281);
};

/// `Wᵀ·g`, each output rounded as `from_acc`, when a kernel exists for `(OUT, IN)`.
#[inline(always)]
pub(super) fn q16_transposed<const IN: usize, const OUT: usize>(
    w: &[[Q16; IN]; OUT],
    g: &[Q16; OUT],
) -> Option<[Q16; IN]> {
    let w = w.as_flattened();
    match (OUT, IN) {
        #[cfg(not(neurosurf_portable = "q16_transposed_9x3"))]
        (9, 3) => resize(m4f::q16_transposed_9x3(rows(w)?, g.first_chunk()?)),
        _ => None,
    }
}

/// `δᵢ ← times_slope(δᵢ, aᵢ)` for the neurons in the kernel's fast range, when a kernel exists
/// for `N` neurons: `Some(mask)` of the neurons it left unchanged (outside that range), with
/// a′ = `offset` − `square`·a² in Q16.16 bits.
#[inline(always)]
pub(super) fn q16_times_slope<const N: usize>(
    delta: &mut [Q16; N],
    a: &[Q16; N],
    offset: i32,
    square: i32,
) -> Option<u32> {
    if cfg!(neurosurf_portable = "q16_times_slope_9") {
        return None;
    }
    let delta: &mut [Q16; 9] = delta.as_mut_slice().try_into().ok()?;
    let a: &[Q16; 9] = a.as_slice().try_into().ok()?;
    Some(m4f::q16_times_slope_9(delta, a, offset, square))
}

/// A forward layer, `activation_from_acc(to_acc(bⱼ) + Σᵢ W[j][i]·xᵢ)` per output, when a kernel
/// exists for `(OUT, IN)`; `table` is the activation table's segments.
#[inline(always)]
pub(super) fn q16_layer<const IN: usize, const OUT: usize>(
    w: &[[Q16; IN]; OUT],
    b: &[Q16; OUT],
    x: &[Q16; IN],
    table: &[[i32; 2]; 1281],
) -> Option<[Q16; OUT]> {
    let w = w.as_flattened();
    match (OUT, IN) {
        #[cfg(not(neurosurf_portable = "q16_layer_9x9"))]
        (9, 9) => resize(m4f::q16_layer_9x9(
            rows(w)?,
            b.first_chunk()?,
            x.first_chunk()?,
            table,
        )),
        #[cfg(not(neurosurf_portable = "q16_layer_9x3"))]
        (9, 3) => resize(m4f::q16_layer_9x3(
            rows(w)?,
            b.first_chunk()?,
            x.first_chunk()?,
            table,
        )),
        #[cfg(not(neurosurf_portable = "q16_layer_1x9"))]
        (1, 9) => resize([m4f::q16_layer_1x9(
            w.first_chunk()?,
            *b.first()?,
            x.first_chunk()?,
            table,
        )]),
        _ => None,
    }
}

/// `δᵢ = times_slope(from_acc(Σⱼ W[j][i]·gⱼ), aᵢ)` for the neurons in the kernel's fast range,
/// when a kernel exists for `(OUT, IN)`: `Some((δ, mask))`, where a set bit i of the mask means
/// output i is only `from_acc(…)`, still to be multiplied by the slope (see `times_slope`).
#[inline(always)]
pub(super) fn q16_transposed_slope<const IN: usize, const OUT: usize>(
    w: &[[Q16; IN]; OUT],
    g: &[Q16; OUT],
    a: &[Q16; IN],
    offset: i32,
    square: i32,
) -> Option<([Q16; IN], u32)> {
    let w = w.as_flattened();
    let a: &[Q16; 9] = a.first_chunk()?;
    let (out, slow): ([Q16; 9], u32) = match (OUT, IN) {
        #[cfg(not(neurosurf_portable = "q16_transposed_slope_9x9"))]
        (9, 9) => m4f::q16_transposed_slope_9x9(rows(w)?, g.first_chunk()?, a, offset, square),
        #[cfg(not(neurosurf_portable = "q16_transposed_slope_1x9"))]
        (1, 9) => {
            m4f::q16_transposed_slope_1x9(w.first_chunk()?, *g.first()?, a, offset, square)?
        }
        _ => return None,
    };
    Some((resize(out)?, slow))
}

/// The first `R` rows of `C` values of a row-major matrix.
#[inline(always)]
fn rows<T, const C: usize, const R: usize>(flat: &[T]) -> Option<&[[T; C]; R]> {
    flat.as_chunks::<C>().0.first_chunk::<R>()
}

/// `a` as an array of length `B` (the caller's shape), when `A == B`.
#[inline(always)]
fn resize<T: Copy, const A: usize, const B: usize>(a: [T; A]) -> Option<[T; B]> {
    <[T; B]>::try_from(a.as_slice()).ok()
}
