//! Writing blobs: every family's payload framed by the core's container (header, postcard
//! payload, CRC), and loaded back through the core before it is written, so that no command
//! writes a blob the core refuses.

use std::path::Path;

use neurosurf_core::BlobError;
use neurosurf_core::blob::{self, ModelKind};
use neurosurf_core::frame::{FramePayload, MAX_FRAME_SHIFT, MAX_Q16_ORIGIN};
use neurosurf_core::model::{self, Model, ModelVisitor};
use neurosurf_core::scalar::{Scalar, ScalarKind};
use serde::Serialize;

use crate::error::{Error, Result};
use crate::io::write_atomic;

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

/// A frame as a blob stores it ([`neurosurf_core::frame`]): model = (x − origin)·2^shift,
/// the origin exactly as the blob's scalar holds it.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct StoredFrame {
    /// The origin, in the user's units, exactly as stored.
    pub origin: [f64; 3],
    /// The origin's three words in the blob's scalar.
    pub words: [u8; 12],
    /// Model coordinates are 2^shift times the user's.
    pub shift: i8,
}

impl StoredFrame {
    /// The frame centred at `center` (rounded to `scalar`) whose scale is the power of two
    /// nearest `scale` (model units per user unit; 1 when it is not a positive number).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the coordinate, the limit and the way out when Q16.16
    /// cannot hold the centre.
    pub fn new(center: [f64; 3], scale: f64, scalar: ScalarKind) -> Result<Self> {
        let shift = if scale.is_finite() && scale > 0.0 {
            let max = f64::from(MAX_FRAME_SHIFT);
            scale.log2().round().clamp(-max, max) as i8
        } else {
            0
        };
        let mut words = [0_u8; 12];
        let mut origin = [0.0; 3];
        for (k, (word, value)) in words.chunks_exact_mut(4).zip(&mut origin).enumerate() {
            let wanted = center[k];
            let in_range =
                scalar != ScalarKind::Q16_16 || wanted.abs() <= f64::from(MAX_Q16_ORIGIN);
            let stored = scalar
                .encode(wanted)
                .filter(|_| in_range)
                .ok_or_else(|| origin_error(k, wanted, scalar))?;
            word.copy_from_slice(&stored);
            *value = blob::stored_value(&stored, scalar).unwrap_or(0.0);
        }
        Ok(StoredFrame {
            origin,
            words,
            shift,
        })
    }

    /// The frame of a payload the core has validated, exactly.
    pub fn read(payload: &FramePayload<'_>, scalar: ScalarKind) -> Self {
        let mut words = [0_u8; 12];
        let mut origin = [0.0; 3];
        for ((word, value), stored) in words
            .chunks_exact_mut(4)
            .zip(&mut origin)
            .zip(payload.origin.chunks_exact(4))
        {
            word.copy_from_slice(stored);
            *value = blob::stored_value(stored, scalar).unwrap_or(0.0);
        }
        StoredFrame {
            origin,
            words,
            shift: payload.shift,
        }
    }

    /// As the payload stores it.
    pub fn payload(&self) -> FramePayload<'_> {
        FramePayload {
            origin: &self.words,
            shift: self.shift,
        }
    }

    /// A user's point in model coordinates.
    pub fn to_model(&self, x: [f64; 3]) -> [f64; 3] {
        let scale = f64::from(self.shift).exp2();
        [0, 1, 2].map(|k| (x[k] - self.origin[k]) * scale)
    }

    /// A model point in the user's units.
    pub fn to_user(&self, x: [f64; 3]) -> [f64; 3] {
        let scale = (-f64::from(self.shift)).exp2();
        [0, 1, 2].map(|k| self.origin[k] + x[k] * scale)
    }
}

/// Whether Q16.16 can hold a frame centred at `center`.
///
/// # Errors
/// [`Error::InvalidInput`] naming the coordinate, the limit and the way out.
pub fn check_q16_origin(center: [f64; 3], scalar: ScalarKind) -> Result<()> {
    if scalar != ScalarKind::Q16_16 {
        return Ok(());
    }
    match (0..3).find(|&k| center[k].abs() > f64::from(MAX_Q16_ORIGIN)) {
        Some(k) => Err(origin_error(k, center[k], scalar)),
        None => Ok(()),
    }
}

fn origin_error(axis: usize, value: f64, scalar: ScalarKind) -> Error {
    Error::invalid(format!(
        "the shape's centre {} = {value} cannot be stored as {} (limit ±{}): store the model \
         as f32, or move the points toward the origin before training",
        ["x", "y", "z"][axis],
        scalar.name(),
        MAX_Q16_ORIGIN
    ))
}

/// Loads `bytes` through the core in the scalar they are stored in (the RBF baseline, which
/// the core does not evaluate, through the trainer's own reader), as a user's firmware would.
///
/// # Errors
/// [`Error::Blob`] naming `path` and what the core refuses.
pub fn check_loads(bytes: &[u8], path: &Path) -> Result<()> {
    let rejected = |source| Error::Blob {
        path: path.to_path_buf(),
        source,
    };
    let (header, _) = blob::parse(bytes).map_err(rejected)?;
    if header.model == ModelKind::Rbf {
        return crate::rbf::RbfModel::from_blob(bytes, path).map(|_| ());
    }
    // Loaded in the scalar it is stored in; the core reads f64 parameters as f32.
    let scalar = match header.scalar {
        ScalarKind::Q16_16 => ScalarKind::Q16_16,
        _ => ScalarKind::F32,
    };
    match model::visit(header.model, scalar, Load(bytes)) {
        Some(loaded) => loaded.map_err(rejected),
        None => Err(Error::invalid(format!(
            "{}: the core does not load {} blobs",
            path.display(),
            header.model.name()
        ))),
    }
}

/// Loads a blob into the model type it names, boxed: some models are tens of kilobytes, held on
/// the heap here as a firmware holds them in a static.
struct Load<'a>(&'a [u8]);

impl ModelVisitor for Load<'_> {
    type Output = core::result::Result<(), BlobError>;
    fn visit<S: Scalar, M: Model<S>>(self) -> Self::Output {
        Box::<M>::default().load_blob(self.0)
    }
}

/// Writes `bytes` to `path` atomically once [`check_loads`] accepts them; nothing is written
/// (and an existing file is kept) otherwise.
///
/// # Errors
/// As [`check_loads`], and [`Error::Io`] when the file cannot be written.
pub fn write_checked(path: &Path, bytes: &[u8]) -> Result<()> {
    check_loads(bytes, path)?;
    write_atomic(path, bytes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::caoen::{from_key_points, to_blob};
    use neurosurf_core::caoen::{Blending, DEFAULT_KEY_POINTS, Domain};

    /// A sphere network with `n` key points spread over the sphere.
    fn sphere_blob(n: usize) -> Vec<u8> {
        let keys: Vec<Vec<f64>> = (0..n)
            .map(|i| {
                let t = i as f64 * 2.399_963;
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                let r = (1.0 - z * z).sqrt();
                vec![r * t.cos(), r * t.sin(), z]
            })
            .collect();
        let network =
            from_key_points(Domain::Sphere, Blending::Power, false, &keys, &keys, 4.0).unwrap();
        to_blob(&network, ScalarKind::F32, b"test").unwrap()
    }

    #[test]
    fn a_blob_at_the_core_limit_is_written_and_one_past_it_is_not() {
        let dir = tempfile::tempdir().unwrap();
        let at = dir.path().join("at.nsb");
        write_checked(&at, &sphere_blob(DEFAULT_KEY_POINTS)).unwrap();
        assert!(at.exists());
        let past = dir.path().join("past.nsb");
        std::fs::write(&past, b"kept").unwrap();
        let error = write_checked(&past, &sphere_blob(DEFAULT_KEY_POINTS + 1)).unwrap_err();
        assert!(error.to_string().contains("past.nsb"), "{error}");
        assert_eq!(std::fs::read(&past).unwrap(), b"kept");
    }

    #[test]
    fn a_corrupt_blob_is_not_written() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.nsb");
        let mut bytes = sphere_blob(12);
        let last = bytes.len() - 1;
        bytes[last] ^= 1;
        assert!(write_checked(&path, &bytes).is_err());
        assert!(!path.exists());
    }
}
