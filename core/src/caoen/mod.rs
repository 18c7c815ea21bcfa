//! Cao En surfaces (Wyvill, Cao & Trotman 1992): a two-layer network that maps the unit sphere
//! (or a torus, or a hypersphere) to a closed freeform surface.
//!
//! - [`CaoEnModel`]: loading and validation, [`eval`](CaoEnModel::eval) y(x),
//!   [`normal`](CaoEnModel::normal) (exact, trigonometry-free), [`project`](CaoEnModel::project)
//!   (axis or view plane), the convex [`implicit_value`](CaoEnModel::implicit_value) and
//!   [`ray_intersections`](CaoEnModel::ray_intersections) (entry and exit, for CSG), batches of
//!   [`LANES`](crate::implicit::LANES) points;
//! - [`CaoEnPayload`]: the blob payload (what the trainer writes).
//!
//! # The contract
//!
//! n key points, each with a weight wᵢ ∈ ℝᵐ (a point of the source sphere), a target
//! tᵢ ∈ ℝᵖ (column i of the shape matrix V) and a sharpness qᵢ. At a source point x:
//!
//! sᵢ = x·wᵢ,  kᵢ = Fᵢ(sᵢ)  (or kᵢ = Fᵢ(sᵢ) / Σⱼ Fⱼ(sⱼ) when normalized),  y = Σᵢ kᵢ·tᵢ,
//!
//! with F(s) = s^q for s > 0 and 0 otherwise ([`Blending::Power`], q whole, eq. 4; at the
//! kink s = 0 of q = 1, F′ is the mean of its one-sided slopes, 1/2, so keys of opposite
//! weights sum to a smooth s and a source point with a zero coordinate keeps its normal),
//! F(s) = e^{q(s−1)} ([`Blending::Exponential`], eq. 5) or F(s) = (1 + q(s − 1))³ where
//! positive and 0 otherwise ([`Blending::Compact`]: local support, the paper's §5 open
//! question). The normalized form is our reading of
//! the paper's rational form (eq. 6, printed as kᵢ = sᵢ/Σ F, which cannot give the described
//! effect): it makes y a convex combination of the targets, so the surface stays within their
//! convex hull, and with the six axis targets it approaches the octahedron as q grows (Fig. 3).
//!
//! Inputs: the caller gives the source point as a vector — a unit vector on the sphere, or
//! (cos θ, sin θ, cos φ, sin φ) on the torus — so the evaluator needs no trigonometry; a
//! normalized network with power blending gives y = 0 where no key point has sᵢ > 0.
//! Normals (eq. 8–13) come from the Jacobian of y, see [`CaoEnModel::normal`] and `normal.rs`.
//! Under compact blending a key point only reaches the cap s > 1 − 1/q around its weight. The
//! loader groups [`GROUP_KEYS`] consecutive keys and the evaluator skips a group when no lane
//! of the pass is within reach of any of its keys (bounded by the first key's cosine plus |x|
//! times the group's spread, with a margin that makes a skipped key one that would have given
//! exactly 0: skipping changes no bit). Keys stored near each other in the blob make compact
//! groups; the trainer orders them so. Then the cost per point follows the keys within reach,
//! not n.
//!
//! The paper's approximate-normal network — targets replaced by the normals at the key points —
//! is an ordinary model for this evaluator, built by the trainer.
//!
//! # Payload
//!
//! Blob framing as in [`crate::blob`], model kind [`ModelKind::CaoEn`](crate::blob::ModelKind)
//! (code 5), stored as [`ScalarKind::F32`](crate::scalar::ScalarKind) or
//! [`ScalarKind::Q16_16`](crate::scalar::ScalarKind):
//!
//! ```text
//! { domain: u8 (0 sphere, 1 torus), blending: u8 (0 power, 1 exponential, 2 compact),
//!   normalized: bool,
//!   source_dimension: u8 (m), target_dimension: u8 (p),
//!   weights: [u8] (w₁ … wₙ, m words each), targets: [u8] (t₁ … tₙ, p words each),
//!   sharpness: [u8] (q₁ … qₙ, one word each), metadata: [u8] }
//! ```
//!
//! 4 little-endian bytes per word in the blob's scalar kind; n is the number of sharpness
//! words (1 … [`MAX_KEY_POINTS`] and the model's capacity). m is 3 … [`MAX_SOURCE_DIMENSION`]
//! (exactly 4 for a torus), p is 1 … [`MAX_TARGET_DIMENSION`]; q ∈ [0, [`MAX_SHARPNESS`]],
//! whole for power blending; in Q16.16 every word is within ±1024. Either storage kind loads
//! into either scalar.
//!
//! # Accuracy and saturation
//!
//! Each sᵢ, each output and each Jacobian entry is one accumulation with one rounding;
//! blending values and the products F′ᵢ·wᵢ are clamped to ±[`MAX_PARAMETER`] (1024 in Q16.16,
//! which with |w|, |t| ≤ 1024 and n ≤ 1024 keeps every Q32.32 accumulator below 2⁶²; no clamp
//! in practice for `f32`). Exponential blending in Q16.16 uses the integer
//! [`exp`](crate::scalar::Scalar::exp): for unit x and w its argument q(s − 1) ∈ [−2q, 0]
//! cannot overflow for any q ≤ 64 (measured for q ≤ 16: within 0.5 LSB plus the argument's
//! rounding, `core/tests/caoen_scalar.rs`).
//!
//! Against an `f64` evaluation at unit source points, for random networks with unit weights,
//! targets in [−2, 2]³, n = 6 … 104, the three blendings and both forms (`core/tests/caoen.rs`;
//! asserted bound, measured worst in parentheses):
//!
//! - `f32`: positions within 2·10⁻⁶·(1 + max|y|) (7.7·10⁻⁷);
//! - Q16.16: positions within 128 LSB (62 LSB, power blending, n = 6, rational form at
//!   Σ F = 0.027; compact blending 31 LSB). The rational form divides by Σ F, a sum of values
//!   rounded to 2⁻¹⁶, so its error grows like 1/Σ F: this holds where Σ F ≥ 0.01 — choose q so
//!   that every source point is within reach of a key point;
//! - normals: the direction of N is ill-conditioned where the Jacobian is nearly rank 1 (a cusp
//!   of the surface), so the bound is on angle × strength, strength = |N|/max|J|² (1 for a
//!   conformal map): `f32` 10⁻⁴ rad (7.4·10⁻⁵), Q16.16 10⁻² rad (6.9·10⁻³) where
//!   max|J| > 0.05 and strength > 0.01, both where Σ F ≥ 0.01 in the rational form. Against
//!   finite differences: 4.1·10⁻⁴ rad.
//! - Compact blending amplifies the input's rounding by F′(1) = 3q at a key (exponential: q),
//!   so the same accuracy needs q three times smaller; the tests draw q ≤ 16/3 for it.
//!
//! [`MAX_PARAMETER`]: crate::scalar::Scalar::MAX_PARAMETER
//!
//! ```
//! use neurosurf_core::caoen::{CaoEnModel, CaoEnPayload};
//! use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};
//! # fn main() -> Result<(), neurosurf_core::BlobError> {
//! // The paper's Fig. 2 with q = 1: W = V = the six axis points. Then y = x, the unit sphere.
//! let axes = [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0],
//!             [0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]];
//! let words = |v: &[f64]| -> Vec<u8> { v.iter().flat_map(|&c| ScalarKind::Q16_16.encode(c).unwrap()).collect() };
//! let w = words(axes.as_flattened());
//! let q = words(&[1.0; 6]);
//! let payload = CaoEnPayload { domain: 0, blending: 0, normalized: false, source_dimension: 3,
//!     target_dimension: 3, weights: &w, targets: &w, sharpness: &q, metadata: &[] };
//! let mut blob = [0_u8; 256];
//! let len = payload.write(ScalarKind::Q16_16, &mut blob)?;
//!
//! let model = CaoEnModel::<f32>::from_blob(&blob[..len])?;
//! let x = [0.48, 0.6, -0.64];
//! let y: [f32; 3] = model.eval(&x);
//! assert_eq!(y, x);
//! let n = model.normal(&x).unwrap(); // the sphere's normal is x
//! assert!((0..3).all(|k| (n[k] - x[k]).abs() < 1e-6));
//! let fixed = CaoEnModel::<Q16>::from_blob(&blob[..len])?;
//! let z: [Q16; 3] = fixed.eval(&x.map(Q16::from_num));
//! assert!((z[2].to_f32() + 0.64).abs() < 1e-4);
//! # Ok(())
//! # }
//! ```

mod batch;
mod blending;
mod convex;
mod eval;
mod model;
mod normal;
mod payload;
mod project;

pub use blending::{Blending, Domain, MAX_SHARPNESS};
pub use convex::{
    BISECTION_STEPS, GOLDEN_STEPS, MAX_RAY_EVALUATIONS, RAY_SCAN_SAMPLES, Ray, RayHit,
};
pub use model::{
    CaoEnModel, DEFAULT_KEY_POINTS, GROUP_KEYS, MAX_KEY_POINTS, MAX_SOURCE_DIMENSION,
    MAX_TARGET_DIMENSION,
};
pub use normal::CaoEnPoint;
pub use payload::CaoEnPayload;
