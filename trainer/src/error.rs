//! The trainer's error type: every failure names the file or the input that is wrong.

use std::path::PathBuf;

use neurosurf_core::BlobError;

/// Anything that can go wrong while reading, training or writing.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// A file's content is malformed (unparseable PLY/OBJ/text, missing properties, …).
    #[error("{path}: {message}")]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong, with a line number where one is known.
        message: String,
    },
    /// A blob file was rejected.
    #[error("{path}: {source}")]
    Blob {
        /// The file.
        path: PathBuf,
        /// Why.
        source: BlobError,
    },
    /// The input data cannot be used (NaN, zero normals, too few points, degenerate
    /// features, inconsistent options, …).
    #[error("{0}")]
    InvalidInput(String),
}

impl Error {
    /// An [`Error::InvalidInput`] from anything printable.
    pub fn invalid(message: impl Into<String>) -> Self {
        Error::InvalidInput(message.into())
    }

    /// An [`Error::Io`] for `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }

    /// An [`Error::Format`] for `path`.
    pub fn format(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        Error::Format {
            path: path.into(),
            message: message.into(),
        }
    }
}

/// Result with the trainer's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
