//! The single seam to floating-point library functions.
//!
//! Every transcendental the core needs is called here, by path, from `libm`: never through
//! method syntax (`x.tanh()`), which resolves to `std` on a host build and to another
//! implementation on the target, so host and target results would silently differ.

/// Square root for `f32` (libm: correctly rounded).
#[inline]
pub(crate) fn sqrtf(x: f32) -> f32 {
    libm::sqrtf(x)
}

/// |x| for `f32`.
#[inline]
pub(crate) fn fabsf(x: f32) -> f32 {
    libm::fabsf(x)
}

/// Square root for `f64` (libm: correctly rounded); load-time geometry only.
#[inline]
pub(crate) fn sqrt(x: f64) -> f64 {
    libm::sqrt(x)
}
