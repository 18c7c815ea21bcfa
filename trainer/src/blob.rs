//! Writing blobs: every family's payload framed by the core's container (header, postcard
//! payload, CRC), so that what the trainer writes is exactly what the core reads.

use neurosurf_core::BlobError;
use neurosurf_core::blob::{self, ModelKind};
use neurosurf_core::scalar::ScalarKind;
use serde::Serialize;

use crate::error::{Error, Result};

/// Frames any serializable payload as a blob, sizing the buffer exactly.
///
/// # Errors
/// [`Error::InvalidInput`] if the payload does not serialize.
pub fn encode<T: Serialize + ?Sized>(
    model: ModelKind,
    scalar: ScalarKind,
    payload: &T,
) -> Result<Vec<u8>> {
    let needed = match blob::write(model, scalar, payload, &mut []) {
        Err(BlobError::BufferTooSmall { needed, .. }) => needed,
        Ok(len) => len,
        Err(e) => return Err(Error::invalid(format!("cannot encode the blob: {e}"))),
    };
    let mut out = vec![0; needed];
    let len = blob::write(model, scalar, payload, &mut out)
        .map_err(|e| Error::invalid(format!("cannot encode the blob: {e}")))?;
    out.truncate(len);
    Ok(out)
}
