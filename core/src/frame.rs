//! A model's frame: where the model's own coordinates sit among the user's.
//!
//! A model is trained on points moved to the origin and scaled to a size of a few units, so
//! that its parameters mean the same whatever the data's units, and so that fixed point can
//! hold them. The blob keeps that move and scale as a [`Frame`]: an origin o and a power of
//! two 2ˢ,
//!
//! x_model = (x − o) · 2ˢ,
//!
//! and the model applies it itself, so callers evaluate in their own units. A power of two
//! keeps the scaling exact in `f32` and a plain shift in Q16.16. Implicit models read points
//! (`to_model`); curves and surfaces store their control points in the frame and give
//! positions back in the user's units (`to_user`).
//!
//! Accuracy: the scaling adds no error in `f32`; the subtraction rounds once, as any `f32`
//! arithmetic on the caller's coordinates would. In Q16.16 the caller's coordinates carry
//! 2⁻¹⁶ of their own unit, so a shape only a few units across, or smaller, is resolved only
//! as finely as its coordinates are: scale such data before evaluating in Q16.16.
//!
//! ```
//! use neurosurf_core::frame::Frame;
//! let frame = Frame::<f32>::new([1000.0, -1000.0, 500.0], 3).unwrap();
//! assert_eq!(frame.to_model([1000.5, -1000.0, 500.25]), [4.0, 0.0, 2.0]);
//! assert_eq!(frame.to_user([4.0, 0.0, 2.0]), [1000.5, -1000.0, 500.25]);
//! assert_eq!(frame.gradient_to_user([1.0, 0.5, 0.0]), [8.0, 4.0, 0.0]);
//! ```

use serde::{Deserialize, Serialize};

use crate::blob::stored_value;
use crate::error::BlobError;
use crate::scalar::{Scalar, ScalarKind};

/// The largest |s| a frame may scale by (2⁶⁴ spans any shape `f32` can describe).
pub const MAX_FRAME_SHIFT: i8 = 64;
/// The largest |origin coordinate| a frame may hold in Q16.16 (in `f32` any finite one).
pub const MAX_Q16_ORIGIN: f32 = 32_767.0;

/// A frame as a blob stores it: the origin's three coordinates as 4-byte words in the blob's
/// scalar kind, and the shift s.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct FramePayload<'a> {
    /// o as three little-endian words of the blob's scalar kind (12 bytes).
    #[serde(borrow)]
    pub origin: &'a [u8],
    /// s: model coordinates are 2ˢ times the user's, once the origin is subtracted.
    pub shift: i8,
}

/// The identity frame's payload (origin 0, shift 0) in any 4-byte scalar kind.
pub const IDENTITY_PAYLOAD: FramePayload<'static> = FramePayload {
    origin: &[0; 12],
    shift: 0,
};

/// A validated frame: x_model = (x − origin)·2^shift (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame<S> {
    origin: [S; 3],
    shift: i8,
}

impl<S: Scalar> Frame<S> {
    /// The identity: model coordinates are the user's.
    pub const IDENTITY: Frame<S> = Frame {
        origin: [S::ZERO; 3],
        shift: 0,
    };

    /// A frame with origin `origin` and shift `shift`, `None` when a coordinate is not finite
    /// (or, in Q16.16, beyond ±[`MAX_Q16_ORIGIN`]), or |shift| > [`MAX_FRAME_SHIFT`].
    pub fn new(origin: [f32; 3], shift: i8) -> Option<Self> {
        let limit = match S::KIND {
            ScalarKind::Q16_16 => MAX_Q16_ORIGIN,
            _ => f32::MAX,
        };
        if shift.unsigned_abs() > MAX_FRAME_SHIFT.unsigned_abs()
            || origin.iter().any(|v| !v.is_finite() || v.abs() > limit)
        {
            return None;
        }
        Some(Frame {
            origin: origin.map(S::from_f32_saturating),
            shift,
        })
    }

    /// Decodes a stored frame whose words are of kind `stored`.
    ///
    /// # Errors
    /// [`BlobError::MalformedPayload`] when the origin is not three 4-byte words,
    /// [`BlobError::FrameOutOfRange`] when a coordinate is not finite (or, in Q16.16, beyond
    /// ±[`MAX_Q16_ORIGIN`]), or the shift beyond ±[`MAX_FRAME_SHIFT`].
    pub fn from_payload(payload: &FramePayload<'_>, stored: ScalarKind) -> Result<Self, BlobError> {
        if payload.origin.len() != 12 {
            return Err(BlobError::MalformedPayload);
        }
        let mut origin = [0.0_f32; 3];
        for (slot, word) in origin.iter_mut().zip(payload.origin.chunks_exact(4)) {
            // A Q16.16 word is exact in f64; f32 keeps 24 bits of it, as from_f32 would.
            *slot = stored_value(word, stored).map_or(f32::NAN, |v| v as f32);
        }
        Self::new(origin, payload.shift).ok_or(BlobError::FrameOutOfRange)
    }

    /// The origin o, in the user's units.
    pub fn origin(&self) -> [S; 3] {
        self.origin
    }

    /// The shift s.
    pub fn shift(&self) -> i8 {
        self.shift
    }

    /// A user's point in model coordinates: (x − o)·2ˢ, saturated in fixed point.
    #[inline]
    pub fn to_model(&self, point: [S; 3]) -> [S; 3] {
        let mut out = point;
        for (value, origin) in out.iter_mut().zip(self.origin) {
            *value = value.sub(origin).times_power_of_two(self.shift);
        }
        out
    }

    /// A model point in the user's units: o + x·2⁻ˢ, saturated in fixed point (the inverse of
    /// [`Frame::to_model`], up to rounding).
    #[inline]
    pub fn to_user(&self, point: [S; 3]) -> [S; 3] {
        let mut out = point;
        for (value, origin) in out.iter_mut().zip(self.origin) {
            *value = origin.add(value.times_power_of_two(self.shift.saturating_neg()));
        }
        out
    }

    /// A gradient taken in model coordinates, in the user's: ∇ · 2ˢ.
    #[inline]
    pub fn gradient_to_user(&self, gradient: [S; 3]) -> [S; 3] {
        gradient.map(|g| g.times_power_of_two(self.shift))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scalar::Q16;

    fn payload(origin: [f32; 3], shift: i8, kind: ScalarKind) -> ([u8; 12], i8) {
        let mut bytes = [0_u8; 12];
        for (chunk, v) in bytes.chunks_exact_mut(4).zip(origin) {
            let word = match kind {
                ScalarKind::F32 => v.to_le_bytes(),
                _ => kind.encode(f64::from(v)).unwrap(),
            };
            chunk.copy_from_slice(&word);
        }
        (bytes, shift)
    }

    #[test]
    fn both_scalars_map_points_like_f64() {
        let (origin, shift) = ([1000.0, -1000.0, 500.0], 7);
        let point = [1000.01_f32, -999.99, 500.002];
        let reference =
            [0, 1, 2].map(|k| (f64::from(point[k]) - f64::from(origin[k])) * f64::from(1 << 7));
        for kind in [ScalarKind::F32, ScalarKind::Q16_16] {
            let (bytes, shift) = payload(origin, shift, kind);
            let stored = FramePayload {
                origin: &bytes,
                shift,
            };
            let f = Frame::<f32>::from_payload(&stored, kind).unwrap();
            let q = Frame::<Q16>::from_payload(&stored, kind).unwrap();
            let fx = f.to_model(point);
            let qx = q.to_model(point.map(Q16::from_f32_saturating));
            for k in 0..3 {
                // f32: one rounding of the input and of the subtraction, ×2⁷.
                assert!((f64::from(fx[k]) - reference[k]).abs() < 2e-3);
                // Q16.16: the input's quantum 2⁻¹⁶, ×2⁷.
                assert!((qx[k].to_f64() - reference[k]).abs() < 2.0 * 128.0 / 65536.0);
            }
        }
    }

    #[test]
    fn shifts_round_and_saturate_in_fixed_point() {
        let frame = Frame::<Q16>::new([0.0; 3], -3).unwrap();
        assert_eq!(
            frame.to_model([Q16::from_bits(12), Q16::from_bits(11), Q16::from_bits(-12)]),
            [Q16::from_bits(2), Q16::from_bits(1), Q16::from_bits(-1)]
        );
        let frame = Frame::<Q16>::new([-30_000.0, 0.0, 0.0], 4).unwrap();
        assert_eq!(frame.to_model([Q16::from_num(30_000); 3])[0], Q16::MAX);
        assert_eq!(
            frame.gradient_to_user([Q16::from_num(-4096); 3])[2],
            Q16::MIN
        );
    }

    #[test]
    fn out_of_range_frames_are_refused() {
        for (origin, shift) in [([0.0, f32::NAN, 0.0], 0), ([0.0; 3], 65), ([0.0; 3], -65)] {
            let (bytes, shift) = payload(origin, shift, ScalarKind::F32);
            let stored = FramePayload {
                origin: &bytes,
                shift,
            };
            assert_eq!(
                Frame::<f32>::from_payload(&stored, ScalarKind::F32),
                Err(BlobError::FrameOutOfRange)
            );
        }
        // Far from the origin: f32 holds it, Q16.16 does not.
        let (bytes, shift) = payload([40_000.0, 0.0, 0.0], 0, ScalarKind::F32);
        let far = FramePayload {
            origin: &bytes,
            shift,
        };
        assert!(Frame::<f32>::from_payload(&far, ScalarKind::F32).is_ok());
        assert_eq!(
            Frame::<Q16>::from_payload(&far, ScalarKind::F32),
            Err(BlobError::FrameOutOfRange)
        );
        let short = FramePayload {
            origin: &[0; 8],
            shift: 0,
        };
        assert_eq!(
            Frame::<Q16>::from_payload(&short, ScalarKind::Q16_16),
            Err(BlobError::MalformedPayload)
        );
    }
}
