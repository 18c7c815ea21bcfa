//! The activation of Carcenac's modules, a(H) = 1.7159·tanh(2H/3) (LeCun's scaled tanh), with
//! its derivatives as the backward pass needs them: computed from a = a(H), not from H.
//!
//! Accuracy against the exact a(H), over all inputs:
//! - `f32`: [`F32_ACTIVATION_MAX_ERROR`] (an exp-based form with plain `+ − × ÷`, the same
//!   bits on every target);
//! - Q16.16: [`Q16_ACTIVATION_MAX_ERROR`] (a 1 281-segment table with linear interpolation,
//!   measured exhaustively).
//!
//! ```
//! use neurosurf_core::implicit::Activation;
//! use neurosurf_core::scalar::{Q16, Scalar, F32_ACTIVATION_MAX_ERROR, Q16_ACTIVATION_MAX_ERROR};
//! let exact = 1.7159 * (2.0f64 / 3.0 * 0.8).tanh();
//! assert!((f64::from(f32::activation(0.8)) - exact).abs() <= F32_ACTIVATION_MAX_ERROR);
//! let fixed = Q16::activation(Q16::from_f32_saturating(0.8)).to_f64();
//! assert!((fixed - exact).abs() <= Q16_ACTIVATION_MAX_ERROR);
//! ```
//!
//! [`F32_ACTIVATION_MAX_ERROR`]: crate::scalar::F32_ACTIVATION_MAX_ERROR
//! [`Q16_ACTIVATION_MAX_ERROR`]: crate::scalar::Q16_ACTIVATION_MAX_ERROR

/// a(H), a′ and a″ in a scalar. Implemented for `f32` and [`crate::scalar::Q16`] only
/// (sealed), and required of every [`crate::scalar::Scalar`].
pub trait Activation: crate::scalar::sealed::Sealed + Sized {
    /// The activation a(H) = 1.7159·tanh(2H/3).
    fn activation(h: Self) -> Self;
    /// a′(H), computed from `a = a(H)`: a′ = (2/3)(1.7159 − a²/1.7159).
    fn activation_slope(a: Self) -> Self;
    /// `delta · a′(H)`, with a′ computed from `a = a(H)`: the chain rule through a neuron in
    /// the backward pass, exactly the scalar's saturating `delta · activation_slope(a)`, bit
    /// for bit (an implementation may fuse the two).
    fn times_slope(delta: Self, a: Self) -> Self;
    /// a″(H), computed from `a = a(H)` and `slope = a′(H)`: a″ = −(4/3)·a·a′/1.7159.
    fn activation_curvature(a: Self, slope: Self) -> Self;
}
