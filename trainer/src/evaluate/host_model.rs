//! What the trainer reads from every kind of blob, and the one list of the kinds it reads.
//!
//! A model family implements [`HostModel`] for its decoded type, in its own folder, and adds
//! one line to the `loaded_models!` list at the bottom of this file: [`LoadedModel`] gets a
//! variant, and reading, `info`'s numbers and `f64` evaluation dispatch to it. The core's
//! registry (`neurosurf_core::model`) is the target's list.

use std::path::Path;

use neurosurf_core::blob::{self, ModelKind};
use neurosurf_core::scalar::ScalarKind;

use super::{Geometry, Sample};
use crate::caoen::DecodedCaoEn;
use crate::curve::{DecodedCurve, DecodedSurface};
use crate::error::{Error, Result};
use crate::implicit::DecodedImplicit;
use crate::parametric::DecodedNetwork;
use crate::rbf::RbfModel;

/// What a kind's blob evaluates to.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Output {
    /// A field Φ(x, y, z) and its gradient.
    Field,
    /// A position (or a Cao En network's outputs) and a direction at parameters.
    Geometry,
}

/// A blob kind as the trainer reads it: its `f64` reference and what `info`, `eval` and
/// `compare` ask of every kind.
pub trait HostModel: Sized {
    /// The blob kind it reads.
    const KIND: ModelKind;
    /// What it evaluates to.
    const OUTPUT: Output;
    /// Whether the core evaluates it (false for the host-only RBF baseline).
    const ON_TARGET: bool = true;

    /// Reads and checks a blob of [`Self::KIND`]; `path` names it in errors.
    ///
    /// # Errors
    /// [`Error::Blob`] / [`Error::Format`] when the blob is rejected.
    fn from_blob(bytes: &[u8], path: &Path) -> Result<Self>;

    /// The scalar the parameters are stored in.
    fn stored_as(&self) -> ScalarKind;

    /// The numbers the model stores: weights, biases and guards; control point coordinates;
    /// key points, their weights and targets.
    fn parameter_count(&self) -> usize;

    /// How many coordinates a query has: 3 for fields, 1 (t) for curves, 2 (u, v) for
    /// surfaces, the source dimension for Cao En networks.
    fn query_arity(&self) -> usize;

    /// Φ and ∇Φ at `x` in `f64`; `None` unless [`Self::OUTPUT`] is a field.
    fn field(&self, x: [f64; 3]) -> Option<Sample> {
        let _ = x;
        None
    }

    /// Output and direction at the parameters `p` in `f64`; `None` unless [`Self::OUTPUT`]
    /// is a geometry.
    fn geometry(&self, p: &[f64]) -> Option<Geometry> {
        let _ = p;
        None
    }

    /// The CSV columns of `neurosurf eval` for the geometry; `None` for a field.
    fn geometry_columns(&self) -> Option<Vec<String>> {
        None
    }
}

macro_rules! loaded_models {
    ($($(#[$doc:meta])* $variant:ident($decoded:ty),)*) => {
        /// A model read from a blob file, ready to evaluate: one variant per kind the trainer
        /// reads, each with the blob as read and its `f64` reading.
        #[derive(Debug)]
        pub enum LoadedModel {
            $(
                $(#[$doc])*
                $variant {
                    /// The blob as read.
                    bytes: Vec<u8>,
                    /// Its `f64` reading.
                    decoded: Box<$decoded>,
                },
            )*
        }

        impl LoadedModel {
            /// Validates a blob; `path` names it in errors.
            ///
            /// # Errors
            /// [`Error::Blob`] / [`Error::Format`] if rejected, [`Error::InvalidInput`] for a
            /// kind the core knows and the trainer does not read.
            pub fn from_bytes(bytes: Vec<u8>, path: &Path) -> Result<Self> {
                let (header, _) = blob::parse(&bytes).map_err(|source| Error::Blob {
                    path: path.to_path_buf(),
                    source,
                })?;
                $(
                    if header.model == <$decoded as HostModel>::KIND {
                        let decoded = Box::new(<$decoded as HostModel>::from_blob(&bytes, path)?);
                        return Ok(LoadedModel::$variant { bytes, decoded });
                    }
                )*
                Err(Error::invalid(format!(
                    "{}: the trainer does not read {} blobs",
                    path.display(),
                    header.model.name()
                )))
            }

            /// The model kind.
            pub fn kind(&self) -> ModelKind {
                match self {
                    $(LoadedModel::$variant { .. } => <$decoded as HostModel>::KIND,)*
                }
            }

            /// What the model evaluates to.
            pub fn output(&self) -> Output {
                match self {
                    $(LoadedModel::$variant { .. } => <$decoded as HostModel>::OUTPUT,)*
                }
            }

            /// The scalar the parameters are stored in (`f64` for the RBF baseline).
            pub fn stored_as(&self) -> ScalarKind {
                match self {
                    $(LoadedModel::$variant { decoded, .. } => <$decoded as HostModel>::stored_as(decoded),)*
                }
            }

            /// The numbers the model stores ([`HostModel::parameter_count`]).
            pub fn parameter_count(&self) -> usize {
                match self {
                    $(LoadedModel::$variant { decoded, .. } => <$decoded as HostModel>::parameter_count(decoded),)*
                }
            }

            /// How many coordinates a query has ([`HostModel::query_arity`]).
            pub fn query_arity(&self) -> usize {
                match self {
                    $(LoadedModel::$variant { decoded, .. } => <$decoded as HostModel>::query_arity(decoded),)*
                }
            }

            /// The blob, for the core; `None` for a host-only kind.
            pub fn bytes(&self) -> Option<&[u8]> {
                match self {
                    $(
                        LoadedModel::$variant { bytes, .. } => {
                            <$decoded as HostModel>::ON_TARGET.then_some(bytes.as_slice())
                        }
                    )*
                }
            }

            /// Φ and ∇Φ at `x` in `f64`; `None` for a geometry kind.
            pub(crate) fn field_f64(&self, x: [f64; 3]) -> Option<Sample> {
                match self {
                    $(LoadedModel::$variant { decoded, .. } => <$decoded as HostModel>::field(decoded, x),)*
                }
            }

            /// Output and direction at `p` in `f64`; `None` for a field kind.
            pub(crate) fn geometry_f64(&self, p: &[f64]) -> Option<Geometry> {
                match self {
                    $(LoadedModel::$variant { decoded, .. } => <$decoded as HostModel>::geometry(decoded, p),)*
                }
            }

            /// The CSV columns of `neurosurf eval` for a geometry kind, `None` for a field:
            /// `t,x,y,z,tx,ty,tz` for a curve, `u,v,x,y,z,nx,ny,nz` for a spline surface or a
            /// surface network, and for a Cao En network its source coordinates `s1…sm`, its
            /// outputs (`x,y,z` when p = 3, else `y1…yp`) and `nx,ny,nz`.
            pub fn geometry_columns(&self) -> Option<Vec<String>> {
                match self {
                    $(LoadedModel::$variant { decoded, .. } => <$decoded as HostModel>::geometry_columns(decoded),)*
                }
            }
        }
    };
}

loaded_models! {
    /// A modular implicit surface (Carcenac).
    Implicit(DecodedImplicit),
    /// The RBF baseline (host only).
    Rbf(RbfModel),
    /// A B-spline curve (Hoffmann & Várady).
    Curve(DecodedCurve),
    /// A B-spline tensor-product surface.
    SplineSurface(DecodedSurface),
    /// A Cao En network (Wyvill, Cao & Trotman).
    CaoEn(DecodedCaoEn),
    /// A parametric surface network (Yumer & Kara).
    SurfaceNetwork(DecodedNetwork),
}

/// Column names from string literals.
pub(crate) fn columns(list: &[&str]) -> Vec<String> {
    list.iter().map(|c| (*c).to_string()).collect()
}
