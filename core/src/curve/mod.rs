//! Uniform B-spline curves and tensor-product surfaces of degree 2 to 5: the curves Hoffmann
//! & Várady fit through a Kohonen chain's ordering of scattered points, and their
//! two-dimensional analogue.
//!
//! - [`BSplineCurve`]: position and tangent of a 2-D or 3-D curve, open or closed;
//! - [`BSplineSurface`]: position, partial derivatives and unit normal of a surface, open or
//!   closed in each direction;
//! - [`CurvePayload`], [`SurfacePayload`]: the blob payloads (what the trainer writes);
//! - batch evaluation of [`LANES`] parameters at a time, bit-identical to the single calls.
//!
//! # The contract
//!
//! A direction of degree p ([`MIN_DEGREE`] = 2 to [`MAX_DEGREE`] = 5) with n
//! control points is *closed* (n segments, indices wrap mod n) or *open* (n − p segments);
//! n ≥ p + 1 either way ([`MIN_CONTROL_POINTS`] = 4 for a cubic), and at most
//! [`MAX_SEGMENTS`] segments. A global parameter t ∈ [0, 1] maps to
//! s = t·segments, i = min(⌊s⌋, segments − 1), u = s − i; t outside [0, 1] is clamped and a
//! NaN t is taken as 0. Then
//!
//! C(t) = Σₖ Bₖ(u)·P₍ᵢ₊ₖ₎ (k = 0‥3), with B₀ = (1 − u)³/6, B₁ = (3u³ − 6u² + 4)/6,
//! B₂ = (−3u³ + 3u² + 3u + 1)/6, B₃ = u³/6,
//!
//! and dC/dt = segments·Σₖ Bₖ′(u)·P₍ᵢ₊ₖ₎. For degree p the sum runs over k = 0‥p with the
//! uniform B-spline basis on integer knots (the Cox–de Boor recurrence
//! N_k^d = ((u + d − k)·N_{k−1}^{d−1} + (k + 1 − u)·N_k^{d−1})/d, N₀⁰ = 1; B is N^p) and
//! the derivative weights N_{k−1}^{p−1} − N_k^{p−1}. A surface is the tensor product:
//! S(u, v) = Σⱼ Σₖ Bⱼ(v)·Bₖ(u)·P[(i_v + j)·count_u + (i_u + k)].
//!
//! # How it is computed
//!
//! The basis sums to 1 and its derivative to 0, so the core evaluates
//! C = P₍ᵢ₊₁₎ + Σ_{k≠1} Bₖ·(P₍ᵢ₊ₖ₎ − P₍ᵢ₊₁₎) (for surfaces, around P₍₁₁₎; for degree p ≠ 3
//! around P₍ᵢ₊⌊p/2⌋₎, for surfaces of other degrees around P at (⌊p_v/2⌋, ⌊p_u/2⌋), with
//! the recurrence's weights, each factor and sum rounded once and the
//! derivative's triangle started from `segments` so that its roundings are not scaled by it;
//! accuracy as stated in `core/tests/curve_degree.rs`): a constant control
//! polygon reproduces its constant exactly, in `f32` and in Q16.16, and errors scale with the
//! control polygon's local differences rather than its distance from the origin. Each output
//! coordinate is one accumulation ([`Scalar::to_acc`](crate::scalar::Scalar::to_acc),
//! [`mac`](crate::scalar::Scalar::mac), [`from_acc`](crate::scalar::Scalar::from_acc)) with one
//! rounding; the hot path has no division (1/6 is a constant), and fixed point saturates.
//! In Q16.16 the segment and local parameter come from the bits of s = t·segments, which is
//! exact; in `f32` from plain IEEE operations, so host and target agree bit for bit.
//!
//! Q16.16 details: control coordinates are limited to ±1024
//! ([`Scalar::MAX_PARAMETER`](crate::scalar::Scalar::MAX_PARAMETER)), so differences stay
//! within ±2048 and no accumulation comes near overflow (products below 2⁵⁹, at most 15 per
//! output); 1/6 rounds to 10923·2⁻¹⁶, and B₂'s linear coefficient is 1 − 3·(1/6 rounded) so
//! that the weights at u = 1 mirror those at u = 0 exactly. Surface normals are computed from
//! the partials of the local parameters (no segment factor) and never saturate.
//!
//! # Payloads
//!
//! Blob framing as in [`crate::blob`], model kind [`ModelKind::Curve`](crate::blob::ModelKind)
//! (code 3) or [`ModelKind::SplineSurface`](crate::blob::ModelKind) (code 4), stored as
//! [`ScalarKind::F32`](crate::scalar::ScalarKind) or
//! [`ScalarKind::Q16_16`](crate::scalar::ScalarKind). The postcard payloads are
//!
//! ```text
//! curve:   { dimension: u8, closed: bool, degree: u8, frame, control: [u8], metadata: [u8] }
//! surface: { closed_u: bool, closed_v: bool, degree_u: u8, degree_v: u8, count_u: u16,
//!            count_v: u16, frame, control: [u8], metadata: [u8] }
//! ```
//!
//! where `control` holds x, y, z of every control point (z = 0 for 2-D curves), 4
//! little-endian bytes per coordinate in the blob's scalar kind; surfaces store
//! P[v·count_u + u], rows of constant v. Either storage kind loads into either scalar.
//!
//! ```
//! use neurosurf_core::curve::{BSplineCurve, CurvePayload};
//! use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};
//! # fn main() -> Result<(), neurosurf_core::BlobError> {
//! // A closed square of control points, written as the trainer does.
//! let square = [[1.0, 1.0, 0.0], [-1.0, 1.0, 0.0], [-1.0, -1.0, 0.0], [1.0, -1.0, 0.0]];
//! let control: Vec<u8> = square.iter().flatten().flat_map(|&c| ScalarKind::Q16_16.encode(c).unwrap()).collect();
//! let payload = CurvePayload {
//!     dimension: 2, closed: true, degree: 3, frame: neurosurf_core::frame::IDENTITY_PAYLOAD,
//!     control: &control, metadata: &[],
//! };
//! let mut blob = [0_u8; 128];
//! let len = payload.write(ScalarKind::Q16_16, &mut blob)?;
//!
//! let curve = BSplineCurve::<f32>::from_blob(&blob[..len])?;
//! let fixed = BSplineCurve::<Q16>::from_blob(&blob[..len])?;
//! // C(0) = (P₀ + 4P₁ + P₂)/6 = (−2/3, 2/3, 0).
//! let p = curve.position(0.0);
//! assert!((p[0] + 2.0 / 3.0).abs() < 1e-6 && (p[1] - 2.0 / 3.0).abs() < 1e-6 && p[2] == 0.0);
//! let q = fixed.position(Q16::ZERO);
//! assert!((q[0].to_f32() + 2.0 / 3.0).abs() < 1e-4 && (q[1].to_f32() - 2.0 / 3.0).abs() < 1e-4);
//! # Ok(())
//! # }
//! ```

mod batch;
mod bspline_curve;
mod bspline_surface;
mod control;
mod direction;
mod payload;

pub use crate::implicit::LANES;
pub use bspline_curve::{BSplineCurve, CurvePoint, DEFAULT_CURVE_POINTS};
pub use bspline_surface::{BSplineSurface, DEFAULT_SURFACE_POINTS, SurfacePoint};
pub use direction::{MAX_DEGREE, MAX_SEGMENTS, MIN_CONTROL_POINTS, MIN_DEGREE};
pub use payload::{CurvePayload, SurfacePayload};
