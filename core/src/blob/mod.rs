//! The blob: a self-checking container for one trained model.
//!
//! # Format (version 4)
//!
//! | offset | size | field |
//! |---:|---:|---|
//! | 0 | 4 | magic `NSRF` |
//! | 4 | 2 | format version, `u16` little endian (currently 4) |
//! | 6 | 1 | model kind ([`ModelKind::code`]) |
//! | 7 | 1 | scalar kind of the stored parameters ([`ScalarKind::code`]) |
//! | 8 | 4 | payload length *n*, `u32` little endian |
//! | 12 | *n* | payload: one `postcard`-encoded struct, specific to the model kind |
//! | 12 + *n* | 4 | CRC-32 (IEEE) of bytes 0 .. 12 + *n*, `u32` little endian |
//!
//! Payloads keep bulk arrays (weights) as `postcard` byte strings of little-endian 4-byte
//! words in the blob's scalar kind, so a microcontroller decodes them in place without
//! allocating. Each payload ends with an opaque `metadata` byte string that the core skips
//! (the trainer keeps its training summary there).
//!
//! Decoding checks, in order: length, magic, version, declared length, CRC, model and scalar
//! kind; then the model's own loader validates shapes, capacities and every parameter. Any
//! byte string gets either a model or a [`BlobError`] — never a panic.
//!
//! # Versions
//!
//! The core writes [`FORMAT_VERSION`] and reads it and the versions back to
//! [`OLDEST_READABLE_VERSION`], each by its own layout; any other gets
//! [`BlobError::UnsupportedVersion`] (checked before the CRC), never a reinterpretation.
//!
//! - **4**: curve and spline-surface payloads carry their degree (curves: `degree`; surfaces:
//!   `degree_u`, `degree_v`), 2 to 5. Version 3 curves and surfaces read as cubic. The other
//!   kinds' payloads are unchanged.
//! - **3**: implicit, curve, spline-surface and surface-network payloads carry a
//!   [frame](crate::frame) (origin and power-of-two scale): implicit modules and guards, and
//!   curve and surface control points, are stored in the frame's coordinates, and a surface
//!   network's outputs are moved by it, so their parameters no longer depend on the data's
//!   units. Cao En and RBF payloads are unchanged.
//! - **2**: every implicit module starts with its normalization c, A — nodes included — and a
//!   node's a′ layer reads [b_left, b_right, A·(x − c)] (2N + 3 inputs; see
//!   [`crate::implicit::ModuleLayout`]). The other kinds' payloads are unchanged.
//! - **1**: implicit nodes stored no normalization and an a′ of 2N inputs (the children only).
//!   Retrain, or convert with a tool that chooses the nodes' normalization, to read such
//!   models.
//!
//! ```
//! use neurosurf_core::blob::{self, BlobError, ModelKind};
//! use neurosurf_core::scalar::ScalarKind;
//! let mut buffer = [0_u8; 64];
//! let len = blob::write(ModelKind::Implicit, ScalarKind::F32, &(7_u8, 9_u8), &mut buffer)?;
//! let (header, payload) = blob::parse(&buffer[..len])?;
//! assert_eq!(header.model, ModelKind::Implicit);
//! assert_eq!(payload, &[7, 9]);
//! buffer[13] ^= 1;
//! assert!(matches!(blob::parse(&buffer[..len]), Err(BlobError::CrcMismatch { .. })));
//! # Ok::<(), BlobError>(())
//! ```

mod crc32;
mod loader;
mod words;

pub use crc32::crc32;
pub(crate) use loader::loader_methods;
pub use words::stored_value;
pub(crate) use words::{check_storage, decode_word};

pub use crate::error::BlobError;
use crate::scalar::ScalarKind;

/// The four bytes every blob starts with.
pub const MAGIC: [u8; 4] = *b"NSRF";
/// The format version this core writes (see the module docs' version history).
pub const FORMAT_VERSION: u16 = 4;
/// The oldest format version this core still reads: version 3 blobs load unchanged, their
/// curves and surfaces as cubic.
pub const OLDEST_READABLE_VERSION: u16 = 3;
/// Bytes before the payload.
pub const HEADER_LEN: usize = 12;
/// Bytes after the payload (the CRC).
pub const TRAILER_LEN: usize = 4;

/// What a blob holds.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum ModelKind {
    /// Carcenac's modular implicit surface (a tree of MLP modules), see [`crate::implicit`].
    Implicit,
    /// The multiquadric RBF baseline (Carcenac §9); evaluated by the host trainer only.
    Rbf,
    /// A uniform cubic B-spline curve (Hoffmann & Várady), see [`crate::curve::BSplineCurve`].
    Curve,
    /// A uniform cubic B-spline tensor-product surface, see [`crate::curve::BSplineSurface`].
    SplineSurface,
    /// A Cao En surface (Wyvill, Cao & Trotman): a two-layer network mapping a sphere, torus or
    /// hypersphere to a surface, see [`crate::caoen::CaoEnModel`].
    CaoEn,
    /// A parametric surface network (Yumer & Kara): a multilayer perceptron (u, v) → (x, y, z),
    /// see [`crate::parametric::SurfaceNetworkModel`].
    SurfaceNetwork,
}

impl ModelKind {
    /// The byte that identifies this kind in a blob header.
    pub const fn code(self) -> u8 {
        match self {
            ModelKind::Implicit => 1,
            ModelKind::Rbf => 2,
            ModelKind::Curve => 3,
            ModelKind::SplineSurface => 4,
            ModelKind::CaoEn => 5,
            ModelKind::SurfaceNetwork => 6,
        }
    }

    /// The kind a header byte names, if this core knows it.
    pub const fn from_code(code: u8) -> Option<Self> {
        match code {
            1 => Some(ModelKind::Implicit),
            2 => Some(ModelKind::Rbf),
            3 => Some(ModelKind::Curve),
            4 => Some(ModelKind::SplineSurface),
            5 => Some(ModelKind::CaoEn),
            6 => Some(ModelKind::SurfaceNetwork),
            _ => None,
        }
    }

    /// A short lowercase name.
    pub const fn name(self) -> &'static str {
        match self {
            ModelKind::Implicit => "implicit",
            ModelKind::Rbf => "rbf",
            ModelKind::Curve => "curve",
            ModelKind::SplineSurface => "spline-surface",
            ModelKind::CaoEn => "cao-en",
            ModelKind::SurfaceNetwork => "surface-network",
        }
    }
}

/// The decoded fixed-size header of a blob.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct BlobHeader {
    /// Format version, [`OLDEST_READABLE_VERSION`] ..= [`FORMAT_VERSION`] once parsed.
    pub version: u16,
    /// Model kind.
    pub model: ModelKind,
    /// How parameters are stored.
    pub scalar: ScalarKind,
}

/// Checks a blob's framing and returns its header and payload.
///
/// # Errors
/// [`BlobError::Truncated`], [`BlobError::BadMagic`], [`BlobError::UnsupportedVersion`],
/// [`BlobError::TrailingBytes`], [`BlobError::CrcMismatch`],
/// [`BlobError::UnknownModelKind`], [`BlobError::UnknownScalarKind`].
pub fn parse(bytes: &[u8]) -> Result<(BlobHeader, &[u8]), BlobError> {
    let available = bytes.len();
    let truncated = |needed| BlobError::Truncated { needed, available };
    let magic: [u8; 4] = read_array(bytes, 0).ok_or(truncated(MAGIC.len()))?;
    if magic != MAGIC {
        return Err(BlobError::BadMagic { found: magic });
    }
    let fixed: [u8; HEADER_LEN] = read_array(bytes, 0).ok_or(truncated(HEADER_LEN))?;
    let [_, _, _, _, v0, v1, model_code, scalar_code, l0, l1, l2, l3] = fixed;
    let version = u16::from_le_bytes([v0, v1]);
    if !(OLDEST_READABLE_VERSION..=FORMAT_VERSION).contains(&version) {
        return Err(BlobError::UnsupportedVersion {
            found: version,
            supported: FORMAT_VERSION,
        });
    }
    let payload_len = u32::from_le_bytes([l0, l1, l2, l3]) as usize;
    let total = HEADER_LEN
        .saturating_add(payload_len)
        .saturating_add(TRAILER_LEN);
    if available < total {
        return Err(truncated(total));
    }
    if available > total {
        return Err(BlobError::TrailingBytes {
            count: available - total,
        });
    }
    let body = bytes
        .get(..HEADER_LEN + payload_len)
        .ok_or(truncated(total))?;
    let stored: [u8; 4] = read_array(bytes, HEADER_LEN + payload_len).ok_or(truncated(total))?;
    let stored = u32::from_le_bytes(stored);
    let computed = crc32(body);
    if stored != computed {
        return Err(BlobError::CrcMismatch { stored, computed });
    }
    let model =
        ModelKind::from_code(model_code).ok_or(BlobError::UnknownModelKind { code: model_code })?;
    let scalar = ScalarKind::from_code(scalar_code)
        .ok_or(BlobError::UnknownScalarKind { code: scalar_code })?;
    let payload = body.get(HEADER_LEN..).ok_or(truncated(total))?;
    Ok((
        BlobHeader {
            version,
            model,
            scalar,
        },
        payload,
    ))
}

/// Frames `payload` (postcard-encoded) as a blob in `out` and returns the blob's length.
///
/// # Errors
/// [`BlobError::BufferTooSmall`] when `out` cannot hold the blob (with the size it needs),
/// [`BlobError::MalformedPayload`] when serialization fails.
pub fn write<T: serde::Serialize + ?Sized>(
    model: ModelKind,
    scalar: ScalarKind,
    payload: &T,
    out: &mut [u8],
) -> Result<usize, BlobError> {
    let payload_len = postcard::serialize_with_flavor::<T, _, usize>(
        payload,
        postcard::ser_flavors::Size::default(),
    )
    .map_err(|_| BlobError::MalformedPayload)?;
    let total = HEADER_LEN + payload_len + TRAILER_LEN;
    let capacity = out.len();
    let too_small = BlobError::BufferTooSmall {
        needed: total,
        capacity,
    };
    let (header, rest) = out.split_at_mut_checked(HEADER_LEN).ok_or(too_small)?;
    let rest = rest.get_mut(..payload_len).ok_or(too_small)?;
    postcard::to_slice(payload, rest).map_err(|_| BlobError::MalformedPayload)?;
    let len_bytes = u32::try_from(payload_len)
        .map_err(|_| too_small)?
        .to_le_bytes();
    let version = FORMAT_VERSION.to_le_bytes();
    header.copy_from_slice(&[
        MAGIC[0],
        MAGIC[1],
        MAGIC[2],
        MAGIC[3],
        version[0],
        version[1],
        model.code(),
        scalar.code(),
        len_bytes[0],
        len_bytes[1],
        len_bytes[2],
        len_bytes[3],
    ]);
    let body_len = HEADER_LEN + payload_len;
    let body = out.get(..body_len).ok_or(too_small)?;
    let crc = crc32(body).to_le_bytes();
    out.get_mut(body_len..total)
        .ok_or(too_small)?
        .copy_from_slice(&crc);
    Ok(total)
}

/// Checks a blob's framing and that it holds a model of kind `expected`, then decodes its
/// payload (shared by every model kind's `Payload::from_blob`).
///
/// # Errors
/// Framing errors of [`parse`], [`BlobError::WrongModelKind`], [`BlobError::MalformedPayload`].
pub(crate) fn decode_kind<'a, T: serde::Deserialize<'a>>(
    bytes: &'a [u8],
    expected: ModelKind,
) -> Result<(BlobHeader, T), BlobError> {
    let (header, payload) = parse_kind(bytes, expected)?;
    Ok((header, decode_payload(payload)?))
}

/// [`parse`], then checks that the blob holds the `expected` kind of model.
pub(crate) fn parse_kind(
    bytes: &[u8],
    expected: ModelKind,
) -> Result<(BlobHeader, &[u8]), BlobError> {
    let (header, payload) = parse(bytes)?;
    if header.model != expected {
        return Err(BlobError::WrongModelKind {
            expected,
            found: header.model,
        });
    }
    Ok((header, payload))
}

/// Decodes a postcard payload that must be consumed exactly.
pub(crate) fn decode_payload<'a, T: serde::Deserialize<'a>>(
    payload: &'a [u8],
) -> Result<T, BlobError> {
    match postcard::take_from_bytes::<T>(payload) {
        Ok((value, [])) => Ok(value),
        Ok(_) | Err(_) => Err(BlobError::MalformedPayload),
    }
}

fn read_array<const N: usize>(bytes: &[u8], offset: usize) -> Option<[u8; N]> {
    bytes.get(offset..offset.checked_add(N)?)?.try_into().ok()
}
