//! Stored parameter words, shared by the loaders of the 4-byte model kinds (curves, surfaces,
//! Cao En networks): which storage kinds they accept, and one word's decoding with the error
//! that names it.

use super::ModelKind;
use crate::error::BlobError;
use crate::scalar::{Scalar, ScalarKind};

/// Only 4-byte storage kinds (`f32`, Q16.16) hold these models.
///
/// # Errors
/// [`BlobError::UnsupportedStorage`] for any other kind.
pub(crate) fn check_storage(model: ModelKind, stored: ScalarKind) -> Result<(), BlobError> {
    if matches!(stored, ScalarKind::F32 | ScalarKind::Q16_16) {
        Ok(())
    } else {
        Err(BlobError::UnsupportedStorage {
            model,
            scalar: stored,
        })
    }
}

/// Decodes the stored word `word` (a 4-byte chunk; anything else is malformed), whose index in
/// the model's parameter numbering is `index`.
///
/// # Errors
/// [`BlobError::NonFiniteParameter`] for a NaN or infinite `f32` word,
/// [`BlobError::ParameterOutOfRange`] beyond [`Scalar::MAX_PARAMETER`],
/// [`BlobError::MalformedPayload`] for a chunk that is not 4 bytes.
pub(crate) fn decode_word<S: Scalar>(
    word: &[u8],
    stored: ScalarKind,
    index: usize,
) -> Result<S, BlobError> {
    let word: [u8; 4] = word.try_into().map_err(|_| BlobError::MalformedPayload)?;
    S::from_stored(word, stored).ok_or_else(|| {
        if stored == ScalarKind::F32 && !f32::from_le_bytes(word).is_finite() {
            BlobError::NonFiniteParameter { index }
        } else {
            BlobError::ParameterOutOfRange { index }
        }
    })
}

/// The exact value of a stored word as `f64` (`None` for a non-finite `f32` or a chunk that is
/// not 4 bytes): for range checks both scalars must agree on, made before conversion, and for
/// hosts reading a blob back.
///
/// ```
/// use neurosurf_core::blob::stored_value;
/// use neurosurf_core::scalar::ScalarKind;
/// assert_eq!(stored_value(&0x0001_8000_i32.to_le_bytes(), ScalarKind::Q16_16), Some(1.5));
/// assert_eq!(stored_value(&[0; 3], ScalarKind::F32), None);
/// ```
pub fn stored_value(word: &[u8], stored: ScalarKind) -> Option<f64> {
    let word: [u8; 4] = word.try_into().ok()?;
    let value = match stored {
        ScalarKind::F32 => f64::from(f32::from_le_bytes(word)),
        _ => f64::from(i32::from_le_bytes(word)) / 65_536.0,
    };
    value.is_finite().then_some(value)
}
