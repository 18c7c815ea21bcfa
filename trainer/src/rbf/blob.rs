//! RBF models in blobs: model kind [`ModelKind::Rbf`], parameters stored as `f64`.
//!
//! The payload follows the core's convention (a `postcard` struct whose bulk array is a byte
//! string of little-endian words in the header's scalar kind, then opaque metadata):
//!
//! | field | type | content |
//! |---|---|---|
//! | `centers` | `u32` | number of centres m |
//! | `parameters` | bytes | 4m + 5 little-endian `f64`: c² (0: biharmonic), a₀, a₁, a₂, b, the centres (x, y, z each), the weights |
//! | `metadata` | bytes | opaque; empty (reserved for the trainer) |
//!
//! Values are stored bit-exactly, so a round trip reproduces the model exactly. Parameter
//! indices in [`BlobError::NonFiniteParameter`] count in that order (0 = c²). Readers skip
//! the metadata.

use std::path::Path;

use neurosurf_core::blob::{self, ModelKind};
use neurosurf_core::scalar::ScalarKind;
use neurosurf_core::{BlobError, Quantity};
use serde::{Deserialize, Serialize};

use super::model::{MAX_CENTERS, RbfModel};
use crate::blob::encode;
use crate::error::{Error, Result};

/// How RBF blobs store their parameters: IEEE binary64. The RBF is host-only, so nothing
/// forces 4-byte words, and `f64` keeps a loaded model bit-identical to the fit (constraint
/// residuals ~10⁻¹¹). In `f32`, rounding centres and weights (Σ|wᵢ| ≈ 3·10³ on the 576-point
/// test torus) would move the field by up to ~10⁻⁴, small next to the fit error but 10⁷ times
/// the residual.
pub const RBF_SCALAR: ScalarKind = ScalarKind::F64;

/// Bytes per stored value.
const WORD: usize = 8;

#[derive(Debug, Serialize, Deserialize)]
struct RbfPayload<'a> {
    centers: u32,
    #[serde(borrow)]
    parameters: &'a [u8],
    #[serde(borrow)]
    metadata: &'a [u8],
}

impl RbfModel {
    /// The model as a blob (empty metadata).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] only if the payload cannot be framed (more than 4 GiB — not
    /// reachable within [`MAX_CENTERS`]).
    pub fn to_blob(&self) -> Result<Vec<u8>> {
        let mut parameters = Vec::with_capacity(WORD * (4 * self.centers.len() + 5));
        let values = [
            self.c2,
            self.linear[0],
            self.linear[1],
            self.linear[2],
            self.constant,
        ];
        let values = values
            .into_iter()
            .chain(self.centers.iter().flatten().copied())
            .chain(self.weights.iter().copied());
        for value in values {
            parameters.extend_from_slice(&value.to_le_bytes());
        }
        let centers = u32::try_from(self.centers.len()).map_err(|_| {
            Error::invalid(format!(
                "{} RBF centres do not fit a blob",
                self.centers.len()
            ))
        })?;
        let payload = RbfPayload {
            centers,
            parameters: &parameters,
            metadata: &[],
        };
        encode(ModelKind::Rbf, RBF_SCALAR, &payload)
    }

    /// Decodes and validates an RBF blob; `path` only names the source in errors.
    ///
    /// # Errors
    /// [`Error::Blob`] for framing ([`blob::parse`]), another model kind
    /// ([`BlobError::WrongModelKind`]), storage other than [`RBF_SCALAR`]
    /// ([`BlobError::UnsupportedStorage`]), an undecodable payload
    /// ([`BlobError::MalformedPayload`]), a parameter byte count other than 8·(4m + 5)
    /// ([`BlobError::ShapeMismatch`]) and non-finite values
    /// ([`BlobError::NonFiniteParameter`]); [`Error::Format`] for no centres, more than
    /// [`MAX_CENTERS`], or c² < 0 (c² = 0 is the biharmonic kernel).
    pub fn from_blob(bytes: &[u8], path: &Path) -> Result<Self> {
        let rejected = |source| Error::Blob {
            path: path.to_path_buf(),
            source,
        };
        let (header, payload) = blob::parse(bytes).map_err(rejected)?;
        if header.model != ModelKind::Rbf {
            return Err(rejected(BlobError::WrongModelKind {
                expected: ModelKind::Rbf,
                found: header.model,
            }));
        }
        if header.scalar != RBF_SCALAR {
            return Err(rejected(BlobError::UnsupportedStorage {
                model: ModelKind::Rbf,
                scalar: header.scalar,
            }));
        }
        let payload: RbfPayload<'_> = match postcard::take_from_bytes(payload) {
            Ok((payload, [])) => payload,
            Ok(_) | Err(_) => return Err(rejected(BlobError::MalformedPayload)),
        };
        let m = payload.centers as usize;
        if m == 0 || m > MAX_CENTERS {
            return Err(Error::format(
                path,
                format!("an RBF model needs 1 to {MAX_CENTERS} centres, the blob declares {m}"),
            ));
        }
        let expected = 4 * m + 5;
        if payload.parameters.len() != WORD * expected {
            return Err(rejected(BlobError::ShapeMismatch {
                what: Quantity::Parameters,
                expected,
                found: payload.parameters.len() / WORD,
            }));
        }
        let mut values = Vec::with_capacity(expected);
        for (index, word) in payload.parameters.chunks_exact(WORD).enumerate() {
            let mut bytes = [0; WORD];
            bytes.copy_from_slice(word);
            let value = f64::from_le_bytes(bytes);
            if !value.is_finite() {
                return Err(rejected(BlobError::NonFiniteParameter { index }));
            }
            values.push(value);
        }
        let c2 = values[0];
        if c2 < 0.0 {
            return Err(Error::format(
                path,
                format!("the RBF's multiquadric c² must be at least 0, the blob has {c2}"),
            ));
        }
        let (centers, weights) = values[5..].split_at(3 * m);
        Ok(RbfModel::from_parts(
            centers
                .chunks_exact(3)
                .map(|c| [c[0], c[1], c[2]])
                .collect(),
            weights.to_vec(),
            [values[1], values[2], values[3]],
            values[4],
            c2,
        ))
    }
}

impl crate::evaluate::HostModel for RbfModel {
    const KIND: ModelKind = ModelKind::Rbf;
    const OUTPUT: crate::evaluate::Output = crate::evaluate::Output::Field;
    const ON_TARGET: bool = false;

    fn from_blob(bytes: &[u8], path: &Path) -> Result<Self> {
        RbfModel::from_blob(bytes, path)
    }

    fn stored_as(&self) -> ScalarKind {
        ScalarKind::F64
    }

    fn parameter_count(&self) -> usize {
        RbfModel::parameter_count(self)
    }

    fn query_arity(&self) -> usize {
        3
    }

    fn field(&self, x: [f64; 3]) -> Option<(f64, [f64; 3])> {
        Some(self.field_gradient(x))
    }
}
