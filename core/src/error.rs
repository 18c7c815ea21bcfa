//! Error types. Small, `Copy`, with the data needed to say what is wrong.

use core::fmt;

use crate::blob::ModelKind;
use crate::scalar::ScalarKind;

/// A quantity a blob declares, named in shape and capacity errors.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Quantity {
    /// Neurons per hidden layer.
    Width,
    /// Modules in the tree.
    Modules,
    /// Stored parameters (weights, biases, normalizations).
    Parameters,
    /// Evaluation stack depth the tree needs.
    StackDepth,
    /// Spatial dimension of a curve (2 or 3).
    Dimension,
    /// Control points of a spline (in total, or along one parametric direction).
    ControlPoints,
    /// Polynomial segments of a spline along one parametric direction.
    Segments,
    /// Key points of a Cao En network (its hidden neurons).
    KeyPoints,
    /// Source dimension m of a Cao En network (the hypersphere or torus it maps from).
    SourceDimension,
    /// Target dimension p of a Cao En network (its outputs).
    TargetDimension,
    /// The code of a Cao En blending function (the valid maximum is reported as expected).
    Blending,
    /// The code of a Cao En source domain (the valid maximum is reported as expected).
    Domain,
    /// Hidden layers of a parametric surface network.
    Layers,
    /// The code of a parametric surface network's activation (the valid maximum is reported
    /// as expected).
    Activation,
    /// Sign guards of an implicit model.
    Guards,
    /// Polynomial degree of a spline along one parametric direction (2 to 5; the nearest
    /// valid degree is reported as expected).
    Degree,
}

impl fmt::Display for Quantity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Quantity::Width => "layer width",
            Quantity::Modules => "module count",
            Quantity::Parameters => "parameter count",
            Quantity::StackDepth => "evaluation stack depth",
            Quantity::Dimension => "dimension",
            Quantity::ControlPoints => "control point count",
            Quantity::Segments => "segment count",
            Quantity::KeyPoints => "key point count",
            Quantity::SourceDimension => "source dimension",
            Quantity::TargetDimension => "target dimension",
            Quantity::Blending => "blending function code",
            Quantity::Domain => "source domain code",
            Quantity::Layers => "hidden layer count",
            Quantity::Activation => "activation code",
            Quantity::Guards => "sign guard count",
            Quantity::Degree => "spline degree",
        })
    }
}

/// Why a byte string is not a usable model.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum BlobError {
    /// The bytes end before the blob does.
    Truncated {
        /// Bytes the blob needs.
        needed: usize,
        /// Bytes given.
        available: usize,
    },
    /// The first four bytes are not `NSRF`.
    BadMagic {
        /// The bytes found.
        found: [u8; 4],
    },
    /// A format version this core does not read.
    UnsupportedVersion {
        /// Version in the blob.
        found: u16,
        /// The newest version this core reads (it reads back to
        /// [`crate::blob::OLDEST_READABLE_VERSION`]).
        supported: u16,
    },
    /// More bytes follow the CRC than the header declares.
    TrailingBytes {
        /// How many.
        count: usize,
    },
    /// The checksum does not match: the blob is corrupt.
    CrcMismatch {
        /// CRC stored in the blob.
        stored: u32,
        /// CRC of the bytes.
        computed: u32,
    },
    /// The model kind byte names no known model.
    UnknownModelKind {
        /// The byte.
        code: u8,
    },
    /// The scalar kind byte names no known scalar.
    UnknownScalarKind {
        /// The byte.
        code: u8,
    },
    /// The model kind cannot be stored in this scalar kind (e.g. an implicit model in f64).
    UnsupportedStorage {
        /// The model kind.
        model: ModelKind,
        /// The scalar kind its parameters claim to be stored in.
        scalar: ScalarKind,
    },
    /// The blob holds another kind of model than the one asked for.
    WrongModelKind {
        /// Kind asked for.
        expected: ModelKind,
        /// Kind in the blob.
        found: ModelKind,
    },
    /// The payload does not decode as the model kind's structure.
    MalformedPayload,
    /// A declared dimension is invalid or disagrees with another.
    ShapeMismatch {
        /// What.
        what: Quantity,
        /// What the rest of the blob implies (or the valid maximum).
        expected: usize,
        /// What was found.
        found: usize,
    },
    /// A dimension exceeds what this build reserved (const generic capacity).
    CapacityExceeded {
        /// What.
        what: Quantity,
        /// What the blob needs.
        needed: usize,
        /// What the model type holds.
        capacity: usize,
    },
    /// The module tree is not a valid post-order binary tree.
    InvalidTree {
        /// Index of the first offending module.
        module: usize,
    },
    /// A parameter is NaN or infinite.
    NonFiniteParameter {
        /// Its index in the parameter array.
        index: usize,
    },
    /// A parameter is too large for the scalar the model is loaded in.
    ParameterOutOfRange {
        /// Its index in the parameter array.
        index: usize,
    },
    /// The model's frame (origin and power-of-two scale, [`crate::frame`]) is beyond what the
    /// scalar holds: an origin coordinate not finite or, in Q16.16, outside ±32 767; or a
    /// shift beyond ±64.
    FrameOutOfRange,
    /// Encoding only: the output buffer is too small.
    BufferTooSmall {
        /// Bytes needed.
        needed: usize,
        /// Bytes available.
        capacity: usize,
    },
}

impl fmt::Display for BlobError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            BlobError::Truncated { needed, available } => {
                write!(f, "blob truncated: needs {needed} bytes, got {available}")
            }
            BlobError::BadMagic { found } => {
                write!(
                    f,
                    "not a neurosurf blob: magic is {found:02x?}, expected \"NSRF\""
                )
            }
            BlobError::UnsupportedVersion { found, supported } => {
                write!(
                    f,
                    "blob format version {found} is not supported (this core reads versions {}..={supported})",
                    crate::blob::OLDEST_READABLE_VERSION
                )
            }
            BlobError::TrailingBytes { count } => {
                write!(f, "{count} unexpected bytes after the blob's checksum")
            }
            BlobError::CrcMismatch { stored, computed } => write!(
                f,
                "blob is corrupt: CRC-32 is {computed:#010x}, header says {stored:#010x}"
            ),
            BlobError::UnknownModelKind { code } => write!(f, "unknown model kind {code}"),
            BlobError::UnknownScalarKind { code } => write!(f, "unknown scalar kind {code}"),
            BlobError::UnsupportedStorage { model, scalar } => write!(
                f,
                "{} models cannot be stored as {}",
                model.name(),
                scalar.name()
            ),
            BlobError::WrongModelKind { expected, found } => write!(
                f,
                "blob holds a {} model, expected {}",
                found.name(),
                expected.name()
            ),
            BlobError::MalformedPayload => f.write_str("blob payload does not decode"),
            BlobError::ShapeMismatch {
                what,
                expected,
                found,
            } => {
                write!(f, "inconsistent {what}: expected {expected}, found {found}")
            }
            BlobError::CapacityExceeded {
                what,
                needed,
                capacity,
            } => write!(
                f,
                "{what} {needed} exceeds this build's capacity of {capacity}"
            ),
            BlobError::InvalidTree { module } => {
                write!(f, "module tree is invalid at module {module}")
            }
            BlobError::NonFiniteParameter { index } => {
                write!(f, "parameter {index} is not finite")
            }
            BlobError::ParameterOutOfRange { index } => {
                write!(f, "parameter {index} is out of range for the target scalar")
            }
            BlobError::FrameOutOfRange => f.write_str(
                "the model's frame is out of range: its origin must be finite (within ±32 767 \
                 for Q16.16) and its scale 2^s with |s| ≤ 64",
            ),
            BlobError::BufferTooSmall { needed, capacity } => {
                write!(
                    f,
                    "output buffer holds {capacity} bytes, blob needs {needed}"
                )
            }
        }
    }
}

impl core::error::Error for BlobError {}

/// Slices of different lengths were given to a batch evaluation.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct LengthMismatch {
    /// Number of input points.
    pub inputs: usize,
    /// Number of output slots.
    pub outputs: usize,
}

impl fmt::Display for LengthMismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} points but {} output slots",
            self.inputs, self.outputs
        )
    }
}

impl core::error::Error for LengthMismatch {}
