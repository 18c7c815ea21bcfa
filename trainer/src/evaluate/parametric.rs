//! Evaluating parametric models — curves, spline surfaces, Cao En networks and surface
//! networks: the output vector and a direction (a curve's tangent dC/dt, a surface's or Cao En
//! shape's unit normal)
//! at parameters, in `f64` (the trainer's reference) or through the core in `f32` or Q16.16.

use super::through_core::core_outputs;
use super::{LoadedModel, Output, Precision};
use crate::error::{Error, Result};

/// The outputs and direction at one parameter, in `f64` whatever the precision it was
/// computed in: a curve's C(t) and dC/dt, a surface's S(u, v) and unit normal, a Cao En
/// network's p outputs y and unit normal ((0, 0, 0) where the normal does not exist).
#[derive(Clone, Debug, PartialEq)]
pub struct Geometry {
    /// The position (3 coordinates; z = 0 for a 2-D curve) or a Cao En network's p outputs.
    pub output: Vec<f64>,
    /// Tangent or unit normal.
    pub direction: [f64; 3],
}

impl From<(Vec<f64>, [f64; 3])> for Geometry {
    fn from((output, direction): (Vec<f64>, [f64; 3])) -> Self {
        Geometry { output, direction }
    }
}

impl LoadedModel {
    /// Outputs and direction of a curve (t = `parameters[i][0]`), spline surface ((u, v) =
    /// the first two coordinates) or Cao En network (the source point: the first m
    /// coordinates) in `precision`. Parameters are first rounded to `f32`, which is what the
    /// core receives, so every precision sees the same inputs.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for field models, and when the core cannot load the blob in
    /// that precision.
    pub fn evaluate_geometry(
        &self,
        parameters: &[Vec<f64>],
        precision: Precision,
    ) -> Result<Vec<Geometry>> {
        let rounded: Vec<Vec<f64>> = parameters
            .iter()
            .map(|p| p.iter().map(|&c| f64::from(c as f32)).collect())
            .collect();
        if self.output() != Output::Geometry {
            return Err(Error::invalid(format!(
                "a {} model has a field, not a parametric geometry",
                self.kind().name()
            )));
        }
        if precision == Precision::F64 {
            return Ok(rounded
                .iter()
                .map(|p| {
                    self.geometry_f64(p).unwrap_or_else(|| Geometry {
                        output: Vec::new(),
                        direction: [0.0; 3],
                    })
                })
                .collect());
        }
        let bytes = self.for_core(precision)?;
        Ok(core_outputs(bytes, self.kind(), precision, &rounded)?
            .into_iter()
            .map(|o| Geometry {
                output: o.value,
                direction: std::array::from_fn(|k| o.derivative.get(k).copied().unwrap_or(0.0)),
            })
            .collect())
    }
}

/// A position and its direction as a [`Geometry`].
pub(crate) fn geometry(position: [f64; 3], direction: [f64; 3]) -> Geometry {
    Geometry {
        output: position.to_vec(),
        direction,
    }
}
