//! The postcard payload of a Cao En blob: what the trainer writes and the loader reads (the
//! framing is [`crate::blob`]'s).

use serde::{Deserialize, Serialize};

use crate::blob::{self, BlobHeader, ModelKind};
use crate::error::BlobError;
use crate::scalar::ScalarKind;

/// The payload of a [`ModelKind::CaoEn`] blob (layout in [`crate::caoen`]).
///
/// ```
/// use neurosurf_core::blob::ModelKind;
/// use neurosurf_core::caoen::CaoEnPayload;
/// use neurosurf_core::scalar::ScalarKind;
/// # fn main() -> Result<(), neurosurf_core::BlobError> {
/// // Two key points on the unit sphere mapped to two targets: w₁ = t₁ = +z, w₂ = t₂ = −z.
/// let words = |values: &[f64]| -> Vec<u8> {
///     values.iter().flat_map(|&v| ScalarKind::F32.encode(v).unwrap()).collect()
/// };
/// let weights = words(&[0.0, 0.0, 1.0, 0.0, 0.0, -1.0]);
/// let sharpness = words(&[2.0, 2.0]);
/// let payload = CaoEnPayload {
///     domain: 0, blending: 0, normalized: false, source_dimension: 3, target_dimension: 3,
///     weights: &weights, targets: &weights, sharpness: &sharpness, metadata: b"example",
/// };
/// let mut out = [0_u8; 128];
/// let len = payload.write(ScalarKind::F32, &mut out)?;
/// let (header, decoded) = CaoEnPayload::from_blob(&out[..len])?;
/// assert_eq!((header.model, header.scalar), (ModelKind::CaoEn, ScalarKind::F32));
/// assert_eq!(decoded, payload);
/// # Ok(())
/// # }
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct CaoEnPayload<'a> {
    /// [`Domain::code`](super::Domain::code): 0 sphere or hypersphere, 1 torus.
    pub domain: u8,
    /// [`Blending::code`](super::Blending::code): 0 power s^q, 1 exponential e^{q(s−1)}, 2
    /// compact (1 + q(s − 1))³₊.
    pub blending: u8,
    /// Whether k is normalized, kᵢ = Fᵢ/Σⱼ Fⱼ (the rational form, paper eq. 6).
    pub normalized: bool,
    /// m: coordinates of a source point (3 … [`MAX_SOURCE_DIMENSION`](super::MAX_SOURCE_DIMENSION);
    /// 4 for a torus).
    pub source_dimension: u8,
    /// p: outputs (1 … [`MAX_TARGET_DIMENSION`](super::MAX_TARGET_DIMENSION)).
    pub target_dimension: u8,
    /// The blending matrix W, key point by key point: w₁ (m words), w₂, …; 4 little-endian
    /// bytes per word in the blob's scalar kind.
    #[serde(borrow)]
    pub weights: &'a [u8],
    /// The shape matrix V by columns, i.e. the target points t₁ (p words), t₂, ….
    #[serde(borrow)]
    pub targets: &'a [u8],
    /// q₁ … qₙ, one word per key point: its count defines n.
    #[serde(borrow)]
    pub sharpness: &'a [u8],
    /// Opaque to the core (the trainer stores its model summary here).
    #[serde(borrow)]
    pub metadata: &'a [u8],
}

impl<'a> CaoEnPayload<'a> {
    /// Checks a blob's framing and kind and decodes its payload, without validating the
    /// network.
    ///
    /// # Errors
    /// Framing errors of [`blob::parse`], [`BlobError::WrongModelKind`],
    /// [`BlobError::MalformedPayload`].
    pub fn from_blob(bytes: &'a [u8]) -> Result<(BlobHeader, Self), BlobError> {
        blob::decode_kind(bytes, ModelKind::CaoEn)
    }

    /// Frames this payload as a [`ModelKind::CaoEn`] blob in `out`, whose words are stored as
    /// `scalar`; returns the blob's length.
    ///
    /// # Errors
    /// As [`blob::write`].
    pub fn write(&self, scalar: ScalarKind, out: &mut [u8]) -> Result<usize, BlobError> {
        blob::write(ModelKind::CaoEn, scalar, self, out)
    }
}
