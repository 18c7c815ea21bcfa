//! The postcard payloads of curve and surface blobs: what the trainer writes and the loaders
//! read (the framing is [`crate::blob`]'s).

use serde::{Deserialize, Serialize};

use crate::blob::{self, BlobHeader, ModelKind};
use crate::error::BlobError;
use crate::frame::FramePayload;
use crate::scalar::ScalarKind;

/// The payload of a [`ModelKind::Curve`] blob.
///
/// ```
/// use neurosurf_core::blob::ModelKind;
/// use neurosurf_core::curve::CurvePayload;
/// use neurosurf_core::frame::IDENTITY_PAYLOAD;
/// use neurosurf_core::scalar::ScalarKind;
/// # fn main() -> Result<(), neurosurf_core::BlobError> {
/// let points = [[0.0, 0.0, 0.0], [1.0, 2.0, 0.0], [2.0, 2.0, 0.0], [3.0, 0.0, 0.0]];
/// let control: Vec<u8> =
///     points.iter().flatten().flat_map(|&c| ScalarKind::F32.encode(c).unwrap()).collect();
/// let payload = CurvePayload {
///     dimension: 2, closed: false, degree: 3, frame: IDENTITY_PAYLOAD, control: &control,
///     metadata: b"fit",
/// };
/// let mut out = [0_u8; 128];
/// let len = payload.write(ScalarKind::F32, &mut out)?;
/// let (header, decoded) = CurvePayload::from_blob(&out[..len])?;
/// assert_eq!((header.model, header.scalar), (ModelKind::Curve, ScalarKind::F32));
/// assert_eq!(decoded, payload);
/// # Ok(())
/// # }
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct CurvePayload<'a> {
    /// 2 or 3. A 2-D curve stores z = 0 for every control point.
    pub dimension: u8,
    /// Whether the control points wrap around (n segments) or not (n − degree segments).
    pub closed: bool,
    /// The polynomial degree p, 2 to 5 ([`MIN_DEGREE`](super::MIN_DEGREE) to
    /// [`MAX_DEGREE`](super::MAX_DEGREE)); version 3 blobs, which have no such field, are
    /// cubic.
    pub degree: u8,
    /// Where the control points' coordinates sit among the user's ([`crate::frame`]); a 2-D
    /// curve's has z = 0.
    #[serde(borrow)]
    pub frame: FramePayload<'a>,
    /// x, y, z of P₀ … P₍ₙ₋₁₎: 12 bytes per point, 4 little-endian bytes per coordinate in the
    /// blob's scalar kind.
    #[serde(borrow)]
    pub control: &'a [u8],
    /// Opaque to the core (the trainer stores its fitting summary here).
    #[serde(borrow)]
    pub metadata: &'a [u8],
}

/// The payload of a [`ModelKind::SplineSurface`] blob.
///
/// ```
/// use neurosurf_core::curve::SurfacePayload;
/// use neurosurf_core::scalar::ScalarKind;
/// # fn main() -> Result<(), neurosurf_core::BlobError> {
/// // A 4 × 4 patch of the plane z = x·y, rows of constant v.
/// let mut control = Vec::new();
/// for v in 0..4 {
///     for u in 0..4 {
///         let (x, y) = (f64::from(u), f64::from(v));
///         for c in [x, y, x * y] {
///             control.extend_from_slice(&ScalarKind::Q16_16.encode(c).unwrap());
///         }
///     }
/// }
/// let payload = SurfacePayload {
///     closed_u: false, closed_v: false, degree_u: 3, degree_v: 3, count_u: 4, count_v: 4,
///     frame: neurosurf_core::frame::IDENTITY_PAYLOAD, control: &control, metadata: &[],
/// };
/// let mut out = vec![0_u8; 256];
/// let len = payload.write(ScalarKind::Q16_16, &mut out)?;
/// assert_eq!(SurfacePayload::from_blob(&out[..len])?.1, payload);
/// # Ok(())
/// # }
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct SurfacePayload<'a> {
    /// Whether the u direction (along a row) wraps around.
    pub closed_u: bool,
    /// Whether the v direction (across rows) wraps around.
    pub closed_v: bool,
    /// The polynomial degree along u, 2 to 5 (version 3 blobs: 3).
    pub degree_u: u8,
    /// The polynomial degree along v, as `degree_u`.
    pub degree_v: u8,
    /// Control points per row (u direction), ≥ 4.
    pub count_u: u16,
    /// Rows (v direction), ≥ 4.
    pub count_v: u16,
    /// Where the control points' coordinates sit among the user's ([`crate::frame`]).
    #[serde(borrow)]
    pub frame: FramePayload<'a>,
    /// x, y, z of P[v·count_u + u], 12 bytes per point as in [`CurvePayload::control`].
    #[serde(borrow)]
    pub control: &'a [u8],
    /// Opaque to the core.
    #[serde(borrow)]
    pub metadata: &'a [u8],
}

impl<'a> CurvePayload<'a> {
    /// Checks a blob's framing and kind and decodes its payload, without validating the
    /// curve.
    ///
    /// # Errors
    /// Framing errors of [`blob::parse`], [`BlobError::WrongModelKind`],
    /// [`BlobError::MalformedPayload`].
    pub fn from_blob(bytes: &'a [u8]) -> Result<(BlobHeader, Self), BlobError> {
        let (header, payload) = blob::parse_kind(bytes, ModelKind::Curve)?;
        let payload = if header.version == 3 {
            let old: CurveV3<'a> = blob::decode_payload(payload)?;
            CurvePayload {
                dimension: old.dimension,
                closed: old.closed,
                degree: 3,
                frame: old.frame,
                control: old.control,
                metadata: old.metadata,
            }
        } else {
            blob::decode_payload(payload)?
        };
        Ok((header, payload))
    }

    /// Frames this payload as a [`ModelKind::Curve`] blob in `out`, whose `control` is stored
    /// as `scalar`; returns the blob's length.
    ///
    /// # Errors
    /// As [`blob::write`].
    pub fn write(&self, scalar: ScalarKind, out: &mut [u8]) -> Result<usize, BlobError> {
        blob::write(ModelKind::Curve, scalar, self, out)
    }
}

impl<'a> SurfacePayload<'a> {
    /// Checks a blob's framing and kind and decodes its payload, without validating the
    /// surface.
    ///
    /// # Errors
    /// Framing errors of [`blob::parse`], [`BlobError::WrongModelKind`],
    /// [`BlobError::MalformedPayload`].
    pub fn from_blob(bytes: &'a [u8]) -> Result<(BlobHeader, Self), BlobError> {
        let (header, payload) = blob::parse_kind(bytes, ModelKind::SplineSurface)?;
        let payload = if header.version == 3 {
            let old: SurfaceV3<'a> = blob::decode_payload(payload)?;
            SurfacePayload {
                closed_u: old.closed_u,
                closed_v: old.closed_v,
                degree_u: 3,
                degree_v: 3,
                count_u: old.count_u,
                count_v: old.count_v,
                frame: old.frame,
                control: old.control,
                metadata: old.metadata,
            }
        } else {
            blob::decode_payload(payload)?
        };
        Ok((header, payload))
    }

    /// Frames this payload as a [`ModelKind::SplineSurface`] blob in `out`, whose `control`
    /// is stored as `scalar`; returns the blob's length.
    ///
    /// # Errors
    /// As [`blob::write`].
    pub fn write(&self, scalar: ScalarKind, out: &mut [u8]) -> Result<usize, BlobError> {
        blob::write(ModelKind::SplineSurface, scalar, self, out)
    }
}

/// A version 3 curve payload: no degree (cubic).
#[derive(Deserialize)]
struct CurveV3<'a> {
    dimension: u8,
    closed: bool,
    #[serde(borrow)]
    frame: FramePayload<'a>,
    #[serde(borrow)]
    control: &'a [u8],
    #[serde(borrow)]
    metadata: &'a [u8],
}

/// A version 3 surface payload: no degrees (cubic).
#[derive(Deserialize)]
struct SurfaceV3<'a> {
    closed_u: bool,
    closed_v: bool,
    count_u: u16,
    count_v: u16,
    #[serde(borrow)]
    frame: FramePayload<'a>,
    #[serde(borrow)]
    control: &'a [u8],
    #[serde(borrow)]
    metadata: &'a [u8],
}
