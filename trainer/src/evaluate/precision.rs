//! The arithmetic a model is evaluated in, as the command line names it.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// The arithmetic a model is evaluated in.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Precision {
    /// The trainer's reference: parameters widened to `f64`, evaluated in `f64`.
    F64,
    /// The core in IEEE binary32.
    F32,
    /// The core in Q16.16 fixed point.
    Q16,
}

impl Precision {
    /// Every precision, reference first.
    pub const ALL: [Precision; 3] = [Precision::F64, Precision::F32, Precision::Q16];

    /// The command-line name: `f64`, `f32`, `q16.16`.
    pub const fn name(self) -> &'static str {
        match self {
            Precision::F64 => "f64",
            Precision::F32 => "f32",
            Precision::Q16 => "q16.16",
        }
    }
}

impl fmt::Display for Precision {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Precision {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        match s.to_ascii_lowercase().as_str() {
            "f64" => Ok(Precision::F64),
            "f32" => Ok(Precision::F32),
            "q16.16" | "q16" | "i16f16" => Ok(Precision::Q16),
            _ => Err(Error::invalid(format!(
                "unknown scalar {s:?}: expected f64, f32 or q16.16"
            ))),
        }
    }
}
