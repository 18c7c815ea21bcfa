//! Converting between the f64 network and the core's Cao En blob.

use std::path::Path;

use neurosurf_core::blob::ModelKind;
use neurosurf_core::caoen::{Blending, CaoEnPayload};
use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};

use super::groups::order_for_groups;
use super::network::CaoEnNetwork;
use crate::blob;
use crate::error::{Error, Result};

/// Encodes `network` as a Cao En blob storing its words as `scalar` (`metadata` is opaque to
/// the core). Compact networks are stored with their keys in [`order_for_groups`]'s order.
///
/// # Errors
/// [`Error::InvalidInput`] for an invalid network, a word that cannot be stored (beyond ±1024
/// for Q16.16), or a scalar other than f32 / Q16.16.
pub fn to_blob(network: &CaoEnNetwork, scalar: ScalarKind, metadata: &[u8]) -> Result<Vec<u8>> {
    network.validate()?;
    let ordered;
    let network = if network.blending == Blending::Compact.code() {
        ordered = order_for_groups(network);
        &ordered
    } else {
        network
    };
    let limit = match scalar {
        ScalarKind::F32 => f64::from(f32::MAX),
        ScalarKind::Q16_16 => f64::from(<Q16 as Scalar>::MAX_PARAMETER),
        other => {
            return Err(Error::invalid(format!(
                "Cao En networks are stored as f32 or q16.16, not {}",
                other.name()
            )));
        }
    };
    let encode = |what: &str, values: &mut dyn Iterator<Item = f64>| -> Result<Vec<u8>> {
        let mut out = Vec::new();
        for (index, value) in values.enumerate() {
            let word = scalar
                .encode(value)
                .filter(|_| value.abs() <= limit)
                .ok_or_else(|| {
                    let advice = match what {
                        "target" => {
                            "the targets are too far from the origin: store the network as \
                             f32, or scale or move the target mesh within the limit"
                        }
                        "sharpness" => "store the network as f32, or fit with a lower sharpness",
                        _ => "store the network as f32",
                    };
                    Error::invalid(format!(
                        "{what} word {index} = {value} cannot be stored as {} (limit ±{limit}): \
                         {advice}",
                        scalar.name()
                    ))
                })?;
            out.extend_from_slice(&word);
        }
        Ok(out)
    };
    let weights = encode("weight", &mut network.weights.iter().flatten().copied())?;
    let targets = encode("target", &mut network.targets.iter().flatten().copied())?;
    let sharpness = encode("sharpness", &mut network.sharpness.iter().copied())?;
    let payload = CaoEnPayload {
        domain: network.domain,
        blending: network.blending,
        normalized: network.normalized,
        source_dimension: network.source_dimension() as u8,
        target_dimension: network.target_dimension() as u8,
        weights: &weights,
        targets: &targets,
        sharpness: &sharpness,
        metadata,
    };
    blob::encode(ModelKind::CaoEn, scalar, &payload)
}

/// Reads a Cao En blob back into an f64 network (words widened exactly) and its metadata.
/// `path` only names the source in errors.
///
/// # Errors
/// [`Error::Blob`] when the core rejects the blob.
pub fn from_blob(bytes: &[u8], path: &Path) -> Result<(CaoEnNetwork, Vec<u8>, ScalarKind)> {
    let blob_error = |source| Error::Blob {
        path: path.to_path_buf(),
        source,
    };
    let (header, payload) = CaoEnPayload::from_blob(bytes).map_err(blob_error)?;
    // Validate with the core itself (f32 accepts every blob Q16.16 accepts).
    neurosurf_core::caoen::CaoEnModel::<f32, { neurosurf_core::caoen::MAX_KEY_POINTS }>::from_payload(
        &payload,
        header.scalar,
    )
    .map_err(blob_error)?;
    let word = |chunk: &[u8]| -> f64 {
        let bytes: [u8; 4] = chunk.try_into().unwrap_or([0; 4]);
        match header.scalar {
            ScalarKind::F32 => f64::from(f32::from_le_bytes(bytes)),
            _ => f64::from(i32::from_le_bytes(bytes)) / 65_536.0,
        }
    };
    let rows = |bytes: &[u8], width: usize| -> Vec<Vec<f64>> {
        bytes
            .chunks_exact(4 * width)
            .map(|row| row.chunks_exact(4).map(word).collect())
            .collect()
    };
    let network = CaoEnNetwork {
        domain: payload.domain,
        blending: payload.blending,
        normalized: payload.normalized,
        weights: rows(payload.weights, usize::from(payload.source_dimension)),
        targets: rows(payload.targets, usize::from(payload.target_dimension)),
        sharpness: payload.sharpness.chunks_exact(4).map(word).collect(),
    };
    Ok((network, payload.metadata.to_vec(), header.scalar))
}

/// A Cao En blob read back into the trainer.
#[derive(Clone, Debug)]
pub struct DecodedCaoEn {
    /// The network, words widened to `f64` exactly.
    pub network: CaoEnNetwork,
    /// The blob's metadata (opaque bytes).
    pub metadata: Vec<u8>,
    /// How the words were stored.
    pub stored_as: ScalarKind,
}

impl crate::evaluate::HostModel for DecodedCaoEn {
    const KIND: ModelKind = ModelKind::CaoEn;
    const OUTPUT: crate::evaluate::Output = crate::evaluate::Output::Geometry;

    fn from_blob(bytes: &[u8], path: &Path) -> Result<Self> {
        let (network, metadata, stored_as) = from_blob(bytes, path)?;
        Ok(DecodedCaoEn {
            network,
            metadata,
            stored_as,
        })
    }

    fn stored_as(&self) -> ScalarKind {
        self.stored_as
    }

    fn parameter_count(&self) -> usize {
        let n = &self.network;
        n.key_count() * (n.source_dimension() + n.target_dimension() + 1)
    }

    fn query_arity(&self) -> usize {
        self.network.source_dimension()
    }

    fn geometry(&self, p: &[f64]) -> Option<crate::evaluate::Geometry> {
        let m = self.network.source_dimension();
        let x: Vec<f64> = (0..m).map(|k| p.get(k).copied().unwrap_or(0.0)).collect();
        Some(crate::evaluate::Geometry {
            output: self.network.position(&x),
            direction: self.network.normal(&x).unwrap_or([0.0; 3]),
        })
    }

    fn geometry_columns(&self) -> Option<Vec<String>> {
        let (m, p) = (
            self.network.source_dimension(),
            self.network.target_dimension(),
        );
        let mut columns: Vec<String> = (1..=m).map(|i| format!("s{i}")).collect();
        if p == 3 {
            columns.extend(crate::evaluate::columns(&["x", "y", "z"]));
        } else {
            columns.extend((1..=p).map(|i| format!("y{i}")));
        }
        columns.extend(crate::evaluate::columns(&["nx", "ny", "nz"]));
        Some(columns)
    }
}
