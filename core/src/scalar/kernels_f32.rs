//! `f32`'s target kernels: on a Cortex-M4F (hard-float ARM), the width-9 layer products run
//! as the `neurosurf-m4f` assembly (one `vldmia` per weight row, one non-fused `vmla` per
//! product: the same bits as `acc + w * x`); everywhere else there are none and the portable
//! loops run. The shapes are those of an N = 9 implicit leaf: 9×3, 9×9 and 1×9, forward and
//! transposed.

/// Whether this build has the kernels.
pub(super) const AVAILABLE: bool = neurosurf_m4f::AVAILABLE;

/// `b + W·x` when a kernel exists for `(OUT, IN)`.
#[inline(always)]
pub(super) fn affine<const IN: usize, const OUT: usize>(
    w: &[[f32; IN]; OUT],
    b: &[f32; OUT],
    x: &[f32; IN],
) -> Option<[f32; OUT]> {
    #[cfg(all(target_arch = "arm", target_abi = "eabihf", target_os = "none"))]
    {
        use super::kernel_shapes::{resize, rows};
        use neurosurf_m4f as m4f;
        let w = w.as_flattened();
        return match (OUT, IN) {
            (9, 9) => resize(m4f::affine_9x9(
                rows(w)?,
                b.first_chunk()?,
                x.first_chunk()?,
            )),
            (9, 3) => resize(m4f::affine_9x3(
                rows(w)?,
                b.first_chunk()?,
                x.first_chunk()?,
            )),
            (1, 9) => resize([m4f::affine_1x9(
                w.first_chunk()?,
                b.first()?,
                x.first_chunk()?,
            )]),
            _ => None,
        };
    }
    #[allow(unreachable_code)]
    {
        let _ = (w, b, x);
        None
    }
}

/// `Wᵀ·g` when a kernel exists for `(OUT, IN)`.
#[inline(always)]
pub(super) fn transposed<const IN: usize, const OUT: usize>(
    w: &[[f32; IN]; OUT],
    g: &[f32; OUT],
) -> Option<[f32; IN]> {
    #[cfg(all(target_arch = "arm", target_abi = "eabihf", target_os = "none"))]
    {
        use super::kernel_shapes::{resize, rows};
        use neurosurf_m4f as m4f;
        let w = w.as_flattened();
        return match (OUT, IN) {
            (9, 9) => resize(m4f::transposed_9x9(rows(w)?, g.first_chunk()?)),
            (9, 3) => resize(m4f::transposed_9x3(rows(w)?, g.first_chunk()?)),
            (1, 9) => resize(m4f::transposed_1x9(w.first_chunk()?, g.first()?)),
            _ => None,
        };
    }
    #[allow(unreachable_code)]
    {
        let _ = (w, g);
        None
    }
}
