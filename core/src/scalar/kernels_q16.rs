//! Q16.16's target kernels: on a Cortex-M4F (bare-metal hard-float ARM, the `neurosurf-m4f`
//! targets), the width-9 layers run as the `neurosurf-m4f` assembly — the forward layers
//! (products, rounding and table lookup in one kernel each), the 9×9 and 1×9 transposes fused
//! with the chain rule on their sums, the 9×3 transpose, the chain rule alone through nine
//! neurons, and the input normalization (a leaf's input, a node's position) — with the same
//! bits as the portable loops; everywhere else there are none.

// The forward kernels hard-code the activation table's layout: 1 281 segments of two words,
// H = 0 at index 640, one segment per 2¹⁰ bits of H.
const _: () = {
    use super::activation_table::{FRACTION_BITS, LAST, SEGMENTS};
    assert!(FRACTION_BITS == 10 && LAST == 640 && SEGMENTS.len() == 1281);
};

/// Whether this build has the kernels.
pub(super) const AVAILABLE: bool = neurosurf_m4f::AVAILABLE;

use super::Q16;

/// `Wᵀ·g`, each output rounded as `from_acc`, when a kernel exists for `(OUT, IN)`.
#[inline(always)]
pub(super) fn transposed<const IN: usize, const OUT: usize>(
    w: &[[Q16; IN]; OUT],
    g: &[Q16; OUT],
) -> Option<[Q16; IN]> {
    #[cfg(all(target_arch = "arm", target_abi = "eabihf", target_os = "none"))]
    {
        use super::kernel_shapes::{resize, rows};
        use neurosurf_m4f as m4f;
        let w = w.as_flattened();
        return match (OUT, IN) {
            (9, 3) => resize(m4f::q16_transposed_9x3(rows(w)?, g.first_chunk()?)),
            _ => None,
        };
    }
    #[allow(unreachable_code)]
    {
        let _ = (w, g);
        None
    }
}

/// `δᵢ ← times_slope(δᵢ, aᵢ)` for the neurons in the kernel's fast range, when a kernel exists
/// for `N` neurons: `Some(mask)` of the neurons it left unchanged (outside that range), with
/// a′ = `offset` − `square`·a² in Q16.16 bits.
#[inline(always)]
pub(super) fn times_slope<const N: usize>(
    delta: &mut [Q16; N],
    a: &[Q16; N],
    offset: i32,
    square: i32,
) -> Option<u32> {
    #[cfg(all(target_arch = "arm", target_abi = "eabihf", target_os = "none"))]
    {
        let delta: &mut [Q16; 9] = delta.as_mut_slice().try_into().ok()?;
        let a: &[Q16; 9] = a.as_slice().try_into().ok()?;
        return Some(neurosurf_m4f::q16_times_slope_9(delta, a, offset, square));
    }
    #[allow(unreachable_code)]
    {
        let _ = (delta, a, offset, square);
        None
    }
}

/// A forward layer, `activation_from_acc(to_acc(bⱼ) + Σᵢ W[j][i]·xᵢ)` per output, when a kernel
/// exists for `(OUT, IN)`; `table` is the activation table's segments.
#[inline(always)]
pub(super) fn layer<const IN: usize, const OUT: usize>(
    w: &[[Q16; IN]; OUT],
    b: &[Q16; OUT],
    x: &[Q16; IN],
    table: &[[i32; 2]; 1281],
) -> Option<[Q16; OUT]> {
    #[cfg(all(target_arch = "arm", target_abi = "eabihf", target_os = "none"))]
    {
        use super::kernel_shapes::{resize, rows};
        use neurosurf_m4f as m4f;
        let w = w.as_flattened();
        return match (OUT, IN) {
            (9, 9) => resize(m4f::q16_layer_9x9(
                rows(w)?,
                b.first_chunk()?,
                x.first_chunk()?,
                table,
            )),
            (9, 3) => resize(m4f::q16_layer_9x3(
                rows(w)?,
                b.first_chunk()?,
                x.first_chunk()?,
                table,
            )),
            (1, 9) => resize([m4f::q16_layer_1x9(
                w.first_chunk()?,
                *b.first()?,
                x.first_chunk()?,
                table,
            )]),
            _ => None,
        };
    }
    #[allow(unreachable_code)]
    {
        let _ = (w, b, x, table);
        None
    }
}

/// `δᵢ = times_slope(from_acc(Σⱼ W[j][i]·gⱼ), aᵢ)` for the neurons in the kernel's fast range,
/// when a kernel exists for `(OUT, IN)`: `Some((δ, mask))`, where a set bit i of the mask means
/// output i is only `from_acc(…)`, still to be multiplied by the slope (see `times_slope`).
#[inline(always)]
pub(super) fn transposed_slope<const IN: usize, const OUT: usize>(
    w: &[[Q16; IN]; OUT],
    g: &[Q16; OUT],
    a: &[Q16; IN],
    offset: i32,
    square: i32,
) -> Option<([Q16; IN], u32)> {
    #[cfg(all(target_arch = "arm", target_abi = "eabihf", target_os = "none"))]
    {
        use super::kernel_shapes::{resize, rows};
        use neurosurf_m4f as m4f;
        let w = w.as_flattened();
        let a = a.first_chunk()?;
        let (out, slow) = match (OUT, IN) {
            (9, 9) => m4f::q16_transposed_slope_9x9(rows(w)?, g.first_chunk()?, a, offset, square),
            (1, 9) => {
                m4f::q16_transposed_slope_1x9(w.first_chunk()?, *g.first()?, a, offset, square)?
            }
            _ => return None,
        };
        return Some((resize(out)?, slow));
    }
    #[allow(unreachable_code)]
    {
        let _ = (w, g, a, offset, square);
        None
    }
}

/// A module's normalized position x′ = A·(x − c) (`normalization` = [c, A row by row]), as the
/// core's `normalized_input`, when a kernel exists.
#[inline(always)]
pub(super) fn normalize(normalization: &[Q16; 12], x: &[Q16; 3]) -> Option<[Q16; 3]> {
    #[cfg(all(target_arch = "arm", target_abi = "eabihf", target_os = "none"))]
    {
        return Some(neurosurf_m4f::q16_normalize(normalization, x));
    }
    #[allow(unreachable_code)]
    {
        let _ = (normalization, x);
        None
    }
}
