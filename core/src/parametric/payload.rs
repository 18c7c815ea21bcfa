//! The postcard payload of a surface-network blob: what the trainer writes and the loader
//! reads (the framing is [`crate::blob`]'s).

use serde::{Deserialize, Serialize};

use crate::blob::{self, BlobHeader, ModelKind};
use crate::error::BlobError;
use crate::frame::FramePayload;
use crate::scalar::ScalarKind;

/// The payload of a [`ModelKind::SurfaceNetwork`] blob (layout in [`crate::parametric`]).
///
/// ```
/// use neurosurf_core::blob::ModelKind;
/// use neurosurf_core::parametric::SurfaceNetworkPayload;
/// use neurosurf_core::scalar::ScalarKind;
/// # fn main() -> Result<(), neurosurf_core::BlobError> {
/// // One hidden neuron: 4 + (1·2 + 1) + (3·1 + 3) + 4 = 17 words.
/// let words: Vec<u8> = (0..17)
///     .flat_map(|i| ScalarKind::F32.encode(if i < 4 { 1.0 } else { 0.5 }).unwrap())
///     .collect();
/// let payload = SurfaceNetworkPayload {
///     activation: 1, hidden: &[1], frame: neurosurf_core::frame::IDENTITY_PAYLOAD,
///     parameters: &words, metadata: b"example",
/// };
/// let mut out = [0_u8; 128];
/// let len = payload.write(ScalarKind::F32, &mut out)?;
/// let (header, decoded) = SurfaceNetworkPayload::from_blob(&out[..len])?;
/// assert_eq!(header.model, ModelKind::SurfaceNetwork);
/// assert_eq!(decoded, payload);
/// # Ok(())
/// # }
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct SurfaceNetworkPayload<'a> {
    /// [`Activation::code`](super::Activation::code) of every hidden layer.
    pub activation: u8,
    /// Neurons of each hidden layer, one byte per layer (1 …
    /// [`MAX_HIDDEN_LAYERS`](super::MAX_HIDDEN_LAYERS) layers of 1 …
    /// [`MAX_NEURONS`](super::MAX_NEURONS)).
    #[serde(borrow)]
    pub hidden: &'a [u8],
    /// Where the output's coordinates sit among the user's ([`crate::frame`]): the position is
    /// the frame's `to_user` of y·s_p + c_p.
    #[serde(borrow)]
    pub frame: FramePayload<'a>,
    /// Every word, in the order of [`crate::parametric`]'s layout; 4 little-endian bytes per
    /// word in the blob's scalar kind.
    #[serde(borrow)]
    pub parameters: &'a [u8],
    /// Opaque to the core (the trainer stores its fit summary here).
    #[serde(borrow)]
    pub metadata: &'a [u8],
}

impl<'a> SurfaceNetworkPayload<'a> {
    /// Checks a blob's framing and kind and decodes its payload, without validating the
    /// network.
    ///
    /// # Errors
    /// Framing errors of [`blob::parse`], [`BlobError::WrongModelKind`],
    /// [`BlobError::MalformedPayload`].
    pub fn from_blob(bytes: &'a [u8]) -> Result<(BlobHeader, Self), BlobError> {
        blob::decode_kind(bytes, ModelKind::SurfaceNetwork)
    }

    /// Frames this payload as a [`ModelKind::SurfaceNetwork`] blob in `out`, whose words are
    /// stored as `scalar`; returns the blob's length.
    ///
    /// # Errors
    /// As [`blob::write`].
    pub fn write(&self, scalar: ScalarKind, out: &mut [u8]) -> Result<usize, BlobError> {
        blob::write(ModelKind::SurfaceNetwork, scalar, self, out)
    }
}
