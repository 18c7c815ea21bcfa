//! Batch evaluation: [`LANES`] points at a time in structure-of-arrays form, so every
//! multiply–accumulate of a weight runs over contiguous lanes (the parallel-hardware intent of
//! both Carcenac and Wyvill–Cao: one weight, many points).

use super::eval::{FieldGradient, ModuleView};
use super::model::ImplicitModel;
use crate::error::LengthMismatch;
use crate::scalar::Scalar;

/// Points evaluated together by the batch functions.
pub const LANES: usize = 8;

impl<S: Scalar, const P: usize, const M: usize> ImplicitModel<S, P, M> {
    /// Φ at every point of `points` into `out` (same length).
    ///
    /// ```
    /// # use neurosurf_core::implicit::ImplicitModel;
    /// # fn demo(model: &ImplicitModel<f32>) -> Result<(), neurosurf_core::LengthMismatch> {
    /// let points = [[0.0, 0.0, 0.0]; 20];
    /// let mut phi = [0.0; 20];
    /// model.field_batch(&points, &mut phi)?;
    /// # Ok(()) }
    /// ```
    ///
    /// # Errors
    /// [`LengthMismatch`] when the slices differ in length (nothing is written).
    pub fn field_batch(&self, points: &[[S; 3]], out: &mut [S]) -> Result<(), LengthMismatch> {
        self.view().field_batch(points, out)
    }

    /// Φ and ∇Φ at every point of `points` into `out` (same length).
    ///
    /// # Errors
    /// [`LengthMismatch`] when the slices differ in length (nothing is written).
    pub fn field_gradient_batch(
        &self,
        points: &[[S; 3]],
        out: &mut [FieldGradient<S>],
    ) -> Result<(), LengthMismatch> {
        self.view().field_gradient_batch(points, out)
    }
}

impl<S: Scalar, const P: usize, const M: usize> ModuleView<'_, S, P, M> {
    /// Φ at every point, [`LANES`] at a time.
    ///
    /// # Errors
    /// [`LengthMismatch`] when the slices differ in length (nothing is written).
    pub fn field_batch(&self, points: &[[S; 3]], out: &mut [S]) -> Result<(), LengthMismatch> {
        check_lengths(points.len(), out.len())?;
        for (chunk, out) in points.chunks(LANES).zip(out.chunks_mut(LANES)) {
            let values = self.field_lanes(&pad(chunk));
            for (slot, &value) in out.iter_mut().zip(&values) {
                *slot = value;
            }
        }
        Ok(())
    }

    /// Φ and ∇Φ at every point, [`LANES`] at a time.
    ///
    /// # Errors
    /// [`LengthMismatch`] when the slices differ in length (nothing is written).
    pub fn field_gradient_batch(
        &self,
        points: &[[S; 3]],
        out: &mut [FieldGradient<S>],
    ) -> Result<(), LengthMismatch> {
        check_lengths(points.len(), out.len())?;
        for (chunk, out) in points.chunks(LANES).zip(out.chunks_mut(LANES)) {
            let results = self.field_gradient_lanes(&pad(chunk));
            for (slot, result) in out.iter_mut().zip(results) {
                *slot = result;
            }
        }
        Ok(())
    }
}

fn check_lengths(inputs: usize, outputs: usize) -> Result<(), LengthMismatch> {
    if inputs == outputs {
        Ok(())
    } else {
        Err(LengthMismatch { inputs, outputs })
    }
}

/// A full set of lanes: the chunk's points, the last one repeated into unused lanes.
fn pad<S: Scalar>(chunk: &[[S; 3]]) -> [[S; 3]; LANES] {
    let last = chunk.last().copied().unwrap_or([S::ZERO; 3]);
    core::array::from_fn(|lane| chunk.get(lane).copied().unwrap_or(last))
}
