//! Parametric surface networks (Yumer & Kara 2012): a multilayer perceptron maps a parameter
//! point (u, v) to a surface point (x, y, z).
//!
//! - [`SurfaceNetworkModel`]: loading and validation, [`position`](SurfaceNetworkModel::position),
//!   [`eval`](SurfaceNetworkModel::eval) (position, ∂p/∂u, ∂p/∂v and the unit normal
//!   ∂p/∂u × ∂p/∂v), batches;
//! - [`SurfaceNetworkPayload`]: the blob payload (what the trainer writes).
//!
//! # The contract
//!
//! L hidden layers of n₁ … n_L neurons sharing one [`Activation`] σ, then a linear layer of
//! three outputs (n₀ = 2, n_{L+1} = 3):
//!
//! ```text
//! x⁰ = ((u − c_u)·g_u, (v − c_v)·g_v)            input normalization (g = 1/half-extent)
//! xˡ = σ(Wˡ xˡ⁻¹ + bˡ)                          l = 1 … L
//! y  = W^(L+1) x^L + b^(L+1)
//! p  = y·s_p + c_p                               one scale for the three coordinates
//! ```
//!
//! ∂p/∂u and ∂p/∂v are carried forward through every neuron (σ′ times the accumulated
//! tangent), so they are exact up to rounding: the trainer's `f64` reference computes the same
//! formula (`trainer/src/parametric/network.rs`).
//!
//! # Payload
//!
//! Blob framing as in [`crate::blob`], model kind
//! [`ModelKind::SurfaceNetwork`](crate::blob::ModelKind) (code 6), stored as `f32` or
//! Q16.16:
//!
//! ```text
//! { activation: u8 (0 log-sig, 1 tan-sig, 2 rad-bas, 3 tri-bas), hidden: [u8] (n₁ … n_L),
//!   frame: { origin: [u8] (3 words), shift: i8 },
//!   parameters: [u8] (words: c_u c_v g_u g_v, then per layer W row-major and b, then
//!   c_x c_y c_z s_p), metadata: [u8] }
//! ```
//!
//! The position is given in the user's units through the [frame](crate::frame): p = o +
//! (y·s_p + c_p)·2⁻ˢ. `f32` folds this into c_p and s_p at load; Q16.16 folds the origin and
//! applies 2⁻ˢ after the output layer, so that c_p and s_p keep their bits whatever the
//! data's units. The normal is taken before that scaling.
//!
//! 1 … [`MAX_HIDDEN_LAYERS`] hidden layers of 1 … [`MAX_NEURONS`] neurons; exactly
//! [`parameter_count`] words; g_u, g_v and s_p positive; in Q16.16 every word within ±1024.
//! Either storage kind loads into either scalar.
//!
//! # Accuracy
//!
//! Every neuron is one accumulation with one rounding; a sigmoid costs one [`Scalar::exp`]
//! and one rounded quotient. Against an `f64` evaluation of the same stored words, on random
//! networks of the sizes the trainer's search picks (1–2 hidden layers of 2–12 neurons, all
//! four activations, weights up to ±3, parameters in [−2, 2]², outputs of unit size;
//! `core/tests/parametric.rs`, asserted bound and measured worst in parentheses):
//!
//! - `f32`: positions within [`F32_POSITION_ERROR`] = 2·10⁻⁶ (1.2·10⁻⁶), partials within
//!   10⁻⁵ of 1 + their length (3.6·10⁻⁶);
//! - Q16.16: positions within [`Q16_POSITION_ERROR`] = 5·10⁻⁴ (2.8·10⁻⁴: 18 LSB, the rounding
//!   of each neuron amplified by weights up to 3 over 12 inputs), normals within 0.5°
//!   (0.24°) where both partials are at least 0.05 long and not nearly parallel.
//!
//! Positions scale with s_p: for a model of the points' size, the Q16.16 error is
//! 2.8·10⁻⁴·s_p plus half an LSB.
//!
//! [`Scalar::exp`]: crate::scalar::Scalar::exp
//!
//! ```
//! use neurosurf_core::parametric::{SurfaceNetworkModel, SurfaceNetworkPayload};
//! use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};
//! # fn main() -> Result<(), neurosurf_core::BlobError> {
//! // One tri-bas neuron h = σ(u) and the output (0, 0, 2h): a tent z = 2·(1 − |u|) drawn on
//! // the line x = y = 0 — degenerate as a surface, exact as an example.
//! let words: Vec<f64> = [
//!     vec![0.0, 0.0, 1.0, 1.0],            // c_u c_v g_u g_v
//!     vec![1.0, 0.0, 0.0],                 // hidden: W (1 × 2), b
//!     vec![0.0, 0.0, 1.0, 0.0, 0.0, 0.0],  // output: W (3 × 1), b
//!     vec![0.0, 0.0, 0.0, 2.0],            // c_p, s_p
//! ].concat();
//! let bytes: Vec<u8> = words.iter().flat_map(|&w| ScalarKind::F32.encode(w).unwrap()).collect();
//! let payload = SurfaceNetworkPayload {
//!     activation: 3, hidden: &[1], frame: neurosurf_core::frame::IDENTITY_PAYLOAD,
//!     parameters: &bytes, metadata: &[],
//! };
//! let mut blob = [0_u8; 256];
//! let len = payload.write(ScalarKind::F32, &mut blob)?;
//! let model = SurfaceNetworkModel::<f32>::from_blob(&blob[..len])?;
//! assert_eq!(model.position([0.25, 0.7]), [0.0, 0.0, 1.5]); // z = 2·(1 − 0.25)
//! let point = model.eval([0.25, 0.7]);
//! assert_eq!(point.du, [0.0, 0.0, -2.0]);
//! assert_eq!(point.normal, None); // ∂p/∂v = 0: no tangent plane
//! let fixed = SurfaceNetworkModel::<Q16>::from_blob(&blob[..len])?;
//! assert_eq!(fixed.position([Q16::from_num(0.25), Q16::ZERO])[2], Q16::from_num(1.5));
//! # Ok(())
//! # }
//! ```

mod activation;
mod eval;
mod model;
mod payload;

pub use activation::Activation;
pub use eval::SurfaceNetworkPoint;
pub use model::{
    DEFAULT_PARAMETERS, MAX_HIDDEN_LAYERS, MAX_NEURONS, NORMALIZATION_WORDS, SurfaceNetworkModel,
    parameter_count,
};
pub use payload::SurfaceNetworkPayload;

/// Largest absolute position error of `f32` evaluation against `f64`, for outputs of unit
/// size (scales with s_p): asserted by `core/tests/parametric.rs`.
pub const F32_POSITION_ERROR: f64 = 2.0e-6;
/// Largest absolute position error of Q16.16 evaluation against `f64`, for outputs of unit
/// size: asserted by `core/tests/parametric.rs` (a few LSB of 2⁻¹⁶ per layer).
pub const Q16_POSITION_ERROR: f64 = 5.0e-4;
