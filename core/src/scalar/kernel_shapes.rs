//! Shape glue between the core's row-major parameter slices and the target kernels' fixed-size
//! arrays (`kernels_f32`, `kernels_q16`); only compiled where kernels exist.

/// The first `R` rows of `C` values of a row-major matrix.
#[inline(always)]
pub(super) fn rows<T, const C: usize, const R: usize>(flat: &[T]) -> Option<&[[T; C]; R]> {
    flat.as_chunks::<C>().0.first_chunk::<R>()
}

/// `a` as an array of length `B` (the caller's shape), when `A == B`.
#[inline(always)]
pub(super) fn resize<T: Copy, const A: usize, const B: usize>(a: [T; A]) -> Option<[T; B]> {
    <[T; B]>::try_from(a.as_slice()).ok()
}
