//! Decoding and validation of stored control points, shared by curves and surfaces.

use heapless::Vec;

use crate::blob;
use crate::error::{BlobError, Quantity};
use crate::frame::{Frame, FramePayload};
use crate::scalar::{Scalar, ScalarKind};

/// Bytes per stored control point: x, y, z, 4 bytes each.
pub(crate) const POINT_BYTES: usize = 12;

pub(crate) use crate::blob::check_storage;

/// The shape error of a control byte string that does not hold exactly `expected` points
/// (counted in 4-byte words, like the implicit model's parameters).
pub(crate) fn length_mismatch(expected_points: usize, bytes: usize) -> BlobError {
    BlobError::ShapeMismatch {
        what: Quantity::Parameters,
        expected: expected_points.saturating_mul(3),
        found: bytes / 4,
    }
}

/// The capacity error for `needed` points in a model type holding `capacity`.
pub(crate) fn over_capacity(needed: usize, capacity: usize) -> BlobError {
    BlobError::CapacityExceeded {
        what: Quantity::ControlPoints,
        needed,
        capacity,
    }
}

/// Decodes every control point of `bytes` (a whole number of [`POINT_BYTES`], checked by the
/// caller, as is the capacity) into `out`.
///
/// # Errors
/// For `flat` (2-D) curves [`BlobError::ShapeMismatch`] (`Dimension`, expected 2, found 3) at
/// the first point whose stored z is not exactly 0 (±0 in f32); then
/// [`BlobError::NonFiniteParameter`] / [`BlobError::ParameterOutOfRange`] with the index of
/// the first bad word (3·point + coordinate).
pub(crate) fn decode<S: Scalar, const C: usize>(
    out: &mut Vec<[S; 3], C>,
    bytes: &[u8],
    stored: ScalarKind,
    flat: bool,
) -> Result<(), BlobError> {
    out.clear();
    for (point, chunk) in bytes.chunks_exact(POINT_BYTES).enumerate() {
        // The stored z, not its conversion: a tiny z would round to 0 in Q16.16 but not in f32,
        // and both scalars must reject the same blobs.
        if flat && !stored_zero(chunk.get(8..).unwrap_or(&[]), stored) {
            return Err(BlobError::ShapeMismatch {
                what: Quantity::Dimension,
                expected: 2,
                found: 3,
            });
        }
        let mut coordinates = [S::ZERO; 3];
        for (axis, (slot, word)) in coordinates
            .iter_mut()
            .zip(chunk.chunks_exact(4))
            .enumerate()
        {
            *slot = blob::decode_word(word, stored, 3 * point + axis)?;
        }
        out.push(coordinates)
            .map_err(|_| over_capacity(bytes.len() / POINT_BYTES, C))?;
    }
    Ok(())
}

/// Reads the stored frame and moves every control point from its coordinates into the
/// user's (see [`crate::frame`]): B-splines are affine invariant, so the curve or surface then
/// evaluates in the user's units at no cost per point. A 2-D (`flat`) curve's frame keeps
/// z = 0.
///
/// # Errors
/// As [`Frame::from_payload`]; [`BlobError::ShapeMismatch`] (`Dimension`, expected 2, found 3)
/// for a `flat` curve whose frame has a nonzero z.
pub(crate) fn fold_frame<S: Scalar>(
    points: &mut [[S; 3]],
    frame: &FramePayload<'_>,
    stored: ScalarKind,
    flat: bool,
) -> Result<(), BlobError> {
    if flat && !stored_zero(frame.origin.get(8..).unwrap_or(&[]), stored) {
        return Err(BlobError::ShapeMismatch {
            what: Quantity::Dimension,
            expected: 2,
            found: 3,
        });
    }
    let frame = Frame::<S>::from_payload(frame, stored)?;
    for point in points {
        *point = frame.to_user(*point);
    }
    Ok(())
}

/// Whether a stored word is exactly zero (either zero of f32).
fn stored_zero(word: &[u8], stored: ScalarKind) -> bool {
    let Ok(word) = <[u8; 4]>::try_from(word) else {
        return false;
    };
    match stored {
        ScalarKind::F32 => f32::from_le_bytes(word) == 0.0,
        _ => word == [0; 4],
    }
}
