//! Evaluating a blob at many points in a chosen precision: the trainer's `f64` reference, or
//! the core in `f32` or Q16.16 — exactly what a microcontroller would compute.

mod parametric;
mod precision;
mod through_core;

use std::path::Path;

use neurosurf_core::blob::{self, ModelKind};
use neurosurf_core::scalar::ScalarKind;

use crate::caoen::{self, CaoEnNetwork};
use crate::curve::{DecodedCurve, DecodedSurface, curve_from_blob, surface_from_blob};
use crate::error::{Error, Result};
use through_core::core_outputs;

use crate::implicit::{self, DecodedImplicit};
use crate::parametric::{DecodedNetwork, network_from_blob};
use crate::rbf::RbfModel;
pub use parametric::{Geometry, geometry_columns};
pub use precision::Precision;

/// Φ and ∇Φ at one point, in `f64` whatever the precision it was computed in.
pub type Sample = (f64, [f64; 3]);

/// A model read from a blob file, ready to evaluate.
#[derive(Debug)]
pub enum LoadedModel {
    /// A modular implicit surface; `bytes` is the blob, for the core.
    Implicit {
        /// The blob.
        bytes: Vec<u8>,
        /// Its `f64` reading.
        decoded: Box<DecodedImplicit>,
    },
    /// The RBF baseline (host only).
    Rbf(RbfModel),
    /// A B-spline curve; `bytes` is the blob, for the core.
    Curve {
        /// The blob.
        bytes: Vec<u8>,
        /// Its `f64` reading.
        decoded: Box<DecodedCurve>,
    },
    /// A B-spline tensor-product surface; `bytes` is the blob, for the core.
    SplineSurface {
        /// The blob.
        bytes: Vec<u8>,
        /// Its `f64` reading.
        decoded: Box<DecodedSurface>,
    },
    /// A Cao En network; `bytes` is the blob, for the core.
    CaoEn {
        /// The blob.
        bytes: Vec<u8>,
        /// Its `f64` reading.
        decoded: Box<DecodedCaoEn>,
    },
    /// A parametric surface network (Yumer & Kara); `bytes` is the blob, for the core.
    SurfaceNetwork {
        /// The blob.
        bytes: Vec<u8>,
        /// Its `f64` reading.
        decoded: Box<DecodedNetwork>,
    },
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

impl LoadedModel {
    /// Reads and validates the blob at `path`.
    ///
    /// # Errors
    /// [`Error::Io`] if unreadable, [`Error::Blob`] / [`Error::Format`] if rejected.
    pub fn read(path: &Path) -> Result<Self> {
        let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        Self::from_bytes(bytes, path)
    }

    /// Validates a blob; `path` names it in errors.
    ///
    /// # Errors
    /// [`Error::Blob`] / [`Error::Format`] if rejected.
    pub fn from_bytes(bytes: Vec<u8>, path: &Path) -> Result<Self> {
        let (header, _) = blob::parse(&bytes).map_err(|source| Error::Blob {
            path: path.to_path_buf(),
            source,
        })?;
        match header.model {
            ModelKind::Implicit => {
                let decoded = implicit::from_blob(&bytes, path)?;
                Ok(LoadedModel::Implicit {
                    bytes,
                    decoded: Box::new(decoded),
                })
            }
            ModelKind::Rbf => Ok(LoadedModel::Rbf(RbfModel::from_blob(&bytes, path)?)),
            ModelKind::Curve => {
                let decoded = Box::new(curve_from_blob(&bytes, path)?);
                Ok(LoadedModel::Curve { bytes, decoded })
            }
            ModelKind::SplineSurface => {
                let decoded = Box::new(surface_from_blob(&bytes, path)?);
                Ok(LoadedModel::SplineSurface { bytes, decoded })
            }
            ModelKind::CaoEn => {
                let (network, metadata, stored_as) = caoen::from_blob(&bytes, path)?;
                let decoded = Box::new(DecodedCaoEn {
                    network,
                    metadata,
                    stored_as,
                });
                Ok(LoadedModel::CaoEn { bytes, decoded })
            }
            ModelKind::SurfaceNetwork => {
                let decoded = Box::new(network_from_blob(&bytes, path)?);
                Ok(LoadedModel::SurfaceNetwork { bytes, decoded })
            }
        }
    }

    /// The model kind.
    pub fn kind(&self) -> ModelKind {
        match self {
            LoadedModel::Implicit { .. } => ModelKind::Implicit,
            LoadedModel::Rbf(_) => ModelKind::Rbf,
            LoadedModel::Curve { .. } => ModelKind::Curve,
            LoadedModel::SplineSurface { .. } => ModelKind::SplineSurface,
            LoadedModel::CaoEn { .. } => ModelKind::CaoEn,
            LoadedModel::SurfaceNetwork { .. } => ModelKind::SurfaceNetwork,
        }
    }

    /// The scalar the parameters are stored in (`f64` for the RBF baseline).
    pub fn stored_as(&self) -> ScalarKind {
        match self {
            LoadedModel::Implicit { decoded, .. } => decoded.stored_as,
            LoadedModel::Rbf(_) => ScalarKind::F64,
            LoadedModel::Curve { decoded, .. } => decoded.stored_as,
            LoadedModel::SplineSurface { decoded, .. } => decoded.stored_as,
            LoadedModel::CaoEn { decoded, .. } => decoded.stored_as,
            LoadedModel::SurfaceNetwork { decoded, .. } => decoded.stored_as,
        }
    }

    /// The numbers the model stores: weights, biases and guards; control point coordinates;
    /// key points, their weights and targets.
    pub fn parameter_count(&self) -> usize {
        match self {
            LoadedModel::Implicit { decoded, .. } => decoded.network.params().len(),
            LoadedModel::Rbf(rbf) => rbf.parameter_count(),
            LoadedModel::Curve { decoded, .. } => decoded.curve.control.len() * 3,
            LoadedModel::SplineSurface { decoded, .. } => decoded.surface.control.len() * 3,
            LoadedModel::CaoEn { decoded, .. } => {
                let n = &decoded.network;
                n.key_count() * (n.source_dimension() + n.target_dimension() + 1)
            }
            LoadedModel::SurfaceNetwork { decoded, .. } => decoded.network.parameter_count(),
        }
    }

    /// The blob as read.
    pub fn bytes(&self) -> Option<&[u8]> {
        match self {
            LoadedModel::Implicit { bytes, .. }
            | LoadedModel::Curve { bytes, .. }
            | LoadedModel::SplineSurface { bytes, .. }
            | LoadedModel::CaoEn { bytes, .. }
            | LoadedModel::SurfaceNetwork { bytes, .. } => Some(bytes),
            LoadedModel::Rbf(_) => None,
        }
    }

    /// How many coordinates a query has: 3 (x, y, z) for fields, 1 (t) for curves, 2 (u, v)
    /// for spline surfaces and surface networks, the source dimension m for Cao En networks.
    pub fn query_arity(&self) -> usize {
        match self {
            LoadedModel::Curve { .. } => 1,
            LoadedModel::SplineSurface { .. } | LoadedModel::SurfaceNetwork { .. } => 2,
            LoadedModel::CaoEn { decoded, .. } => decoded.network.source_dimension(),
            _ => 3,
        }
    }

    /// Φ and ∇Φ at every point in `precision`.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when the model cannot be evaluated in that precision (an RBF
    /// outside `f64`; an implicit model whose parameters exceed Q16.16's range or the core's
    /// capacity).
    pub fn evaluate(&self, points: &[[f64; 3]], precision: Precision) -> Result<Vec<Sample>> {
        match (self, precision) {
            (LoadedModel::Implicit { decoded, .. }, Precision::F64) => {
                Ok(points.iter().map(|&p| decoded.network.eval(p)).collect())
            }
            (LoadedModel::Implicit { bytes, .. }, Precision::F32 | Precision::Q16) => {
                let points: Vec<Vec<f64>> = points.iter().map(|p| p.to_vec()).collect();
                Ok(
                    core_outputs(bytes, ModelKind::Implicit, precision, &points)?
                        .into_iter()
                        .map(|o| {
                            let at = |k: usize| o.derivative.get(k).copied().unwrap_or(0.0);
                            (
                                o.value.first().copied().unwrap_or(0.0),
                                [at(0), at(1), at(2)],
                            )
                        })
                        .collect(),
                )
            }
            (LoadedModel::Rbf(model), Precision::F64) => {
                Ok(points.iter().map(|&p| model.field_gradient(p)).collect())
            }
            (LoadedModel::Rbf(_), other) => Err(Error::invalid(format!(
                "the RBF baseline is a host-only model: it evaluates in f64, not {other}"
            ))),
            (
                LoadedModel::Curve { .. }
                | LoadedModel::SplineSurface { .. }
                | LoadedModel::CaoEn { .. }
                | LoadedModel::SurfaceNetwork { .. },
                _,
            ) => Err(Error::invalid(format!(
                "a {} has no field: evaluate its geometry",
                self.kind().name()
            ))),
        }
    }
}
