//! Evaluating a blob at many points in a chosen precision: the trainer's `f64` reference, or
//! the core in `f32` or Q16.16 — exactly what a microcontroller would compute.

mod host_model;
mod parametric;
mod precision;
mod through_core;

use std::path::Path;

use crate::error::{Error, Result};
use through_core::core_outputs;

pub(crate) use host_model::columns;
pub use host_model::{HostModel, LoadedModel, Output};
pub use parametric::Geometry;
pub(crate) use parametric::geometry;
pub use precision::Precision;

/// Φ and ∇Φ at one point, in `f64` whatever the precision it was computed in.
pub type Sample = (f64, [f64; 3]);

impl LoadedModel {
    /// Reads and validates the blob at `path`.
    ///
    /// # Errors
    /// [`Error::Io`] if unreadable, [`Error::Blob`] / [`Error::Format`] if rejected.
    pub fn read(path: &Path) -> Result<Self> {
        let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        Self::from_bytes(bytes, path)
    }

    /// The blob for the core to evaluate in `precision`.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the kind when it is host-only.
    fn for_core(&self, precision: Precision) -> Result<&[u8]> {
        self.bytes().ok_or_else(|| {
            Error::invalid(format!(
                "the {} model is host-only: it evaluates in f64, not {precision}",
                self.kind().name()
            ))
        })
    }

    /// Φ and ∇Φ at every point in `precision`.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when the model cannot be evaluated in that precision (an RBF
    /// outside `f64`; an implicit model whose parameters exceed Q16.16's range or the core's
    /// capacity).
    pub fn evaluate(&self, points: &[[f64; 3]], precision: Precision) -> Result<Vec<Sample>> {
        if self.output() != Output::Field {
            return Err(Error::invalid(format!(
                "a {} has no field: evaluate its geometry",
                self.kind().name()
            )));
        }
        if precision == Precision::F64 {
            return Ok(points
                .iter()
                .map(|&p| self.field_f64(p).unwrap_or((f64::NAN, [f64::NAN; 3])))
                .collect());
        }
        let bytes = self.for_core(precision)?;
        let points: Vec<Vec<f64>> = points.iter().map(|p| p.to_vec()).collect();
        Ok(core_outputs(bytes, self.kind(), precision, &points)?
            .into_iter()
            .map(|o| {
                let at = |k: usize| o.derivative.get(k).copied().unwrap_or(0.0);
                (
                    o.value.first().copied().unwrap_or(0.0),
                    [at(0), at(1), at(2)],
                )
            })
            .collect())
    }
}
