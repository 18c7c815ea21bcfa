//! # neurosurf-core
//!
//! Evaluates neural freeform surface models on anything from a desktop to a Cortex-M4F:
//! `#![no_std]`, no allocator, no `unsafe`, no panics on any input. (On a Cortex-M4F, f32's
//! N = 9 layer products run as the inline assembly of the separate `neurosurf-m4f` crate.)
//!
//! - [`scalar`]: the one sealed number abstraction, implemented for `f32` and Q16.16
//!   ([`scalar::Q16`]) side by side;
//! - [`blob`]: the checked container format trained models travel in;
//! - [`implicit`]: Carcenac's modular implicit surfaces Φ(x) = 0 — field, gradient, normal;
//! - [`curve`]: uniform cubic B-spline curves and surfaces (Hoffmann & Várady) — position,
//!   tangent, partials, normal;
//! - [`caoen`]: Cao En surfaces (Wyvill, Cao & Trotman) — a two-layer network from a sphere,
//!   torus or hypersphere: position, exact normal, projections, convex implicit form and
//!   ray intersections;
//! - [`parametric`]: parametric surface networks (Yumer & Kara) — a multilayer perceptron
//!   (u, v) → (x, y, z): position, partials ∂/∂u and ∂/∂v, unit normal.
//!
//! Load a blob once (that validates everything), then evaluate without failure:
//!
//! ```
//! use neurosurf_core::{implicit::ImplicitModel, BlobError};
//! fn surface_normal(blob: &[u8], p: [f32; 3]) -> Result<Option<[f32; 3]>, BlobError> {
//!     let model = ImplicitModel::<f32>::from_blob(blob)?;
//!     Ok(model.normal(p))
//! }
//! assert!(surface_normal(b"not a blob", [0.0; 3]).is_err());
//! ```
#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
#![warn(missing_debug_implementations)]
// The library never panics; its tests may (a failing test is the point), so these lints stop
// at the library and the integration tests in `core/tests/` need no `allow` header.
#![cfg_attr(
    not(test),
    warn(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::indexing_slicing
    )
)]

mod arch;
pub mod blob;
pub mod caoen;
pub mod curve;
mod dense;
mod error;
pub mod frame;
pub mod implicit;
mod lanes;
mod math;
pub mod model;
pub mod parametric;
pub mod scalar;

pub use error::{BlobError, LengthMismatch, Quantity};

/// Every target kernel against its portable loop, for the simulator's kernel check
/// (`firmware-sim`); not part of the API.
#[doc(hidden)]
pub use arch::kernel_check;
