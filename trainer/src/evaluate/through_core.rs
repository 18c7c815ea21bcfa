//! Any blob through the core in `f32` or Q16.16, written once for every kind: the core's
//! [`model::visit`] picks the model type, [`Model::evaluate`] gives each point's value and
//! derivative as flat numbers (see [`Model::output_len`]).

use neurosurf_core::blob::ModelKind;
use neurosurf_core::model::{self, MAX_INPUTS, MAX_OUTPUTS, Model, ModelVisitor};
use neurosurf_core::scalar::{Scalar, ScalarKind};

use super::Precision;
use crate::error::{Error, Result};

/// What the core computes at one point, widened to `f64`: the value (Φ, or a position or the
/// p outputs of a Cao En network) and its derivative (∇Φ, a tangent or a unit normal).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct CoreOutput {
    pub value: Vec<f64>,
    pub derivative: Vec<f64>,
}

/// Loads `bytes` (a blob of `kind`) in the core in `precision` and evaluates every point of
/// `points` (its coordinates rounded to `f32`, then to the scalar, saturating; missing ones 0).
///
/// # Errors
/// [`Error::InvalidInput`] for `f64` or a kind the core does not evaluate, and naming the
/// core's reason when it refuses the blob in that precision.
pub(crate) fn core_outputs(
    bytes: &[u8],
    kind: ModelKind,
    precision: Precision,
    points: &[Vec<f64>],
) -> Result<Vec<CoreOutput>> {
    let scalar = match precision {
        Precision::F32 => ScalarKind::F32,
        Precision::Q16 => ScalarKind::Q16_16,
        Precision::F64 => {
            return Err(Error::invalid(
                "the core evaluates in f32 or q16.16, not f64",
            ));
        }
    };
    model::visit(kind, scalar, Run { bytes, points }).ok_or_else(|| {
        Error::invalid(format!("the core does not evaluate {} models", kind.name()))
    })?
}

struct Run<'a> {
    bytes: &'a [u8],
    points: &'a [Vec<f64>],
}

impl ModelVisitor for Run<'_> {
    type Output = Result<Vec<CoreOutput>>;

    fn visit<S: Scalar, M: Model<S>>(self) -> Self::Output {
        let mut model = Box::<M>::default();
        model.load_blob(self.bytes).map_err(|e| {
            Error::invalid(format!(
                "the core cannot load this {} in {}: {e}",
                M::KIND.name(),
                S::KIND.name()
            ))
        })?;
        let values = model.output_len(false);
        let all = model.output_len(true);
        Ok(self
            .points
            .iter()
            .map(|point| {
                let input: [S; MAX_INPUTS] = std::array::from_fn(|k| {
                    S::from_f32_saturating(point.get(k).copied().unwrap_or(0.0) as f32)
                });
                let mut out = [S::ZERO; MAX_OUTPUTS];
                model.evaluate(&input, true, &mut out);
                let widened: Vec<f64> = out[..all].iter().map(|v| v.to_f64()).collect();
                CoreOutput {
                    value: widened[..values].to_vec(),
                    derivative: widened[values..].to_vec(),
                }
            })
            .collect())
    }
}
