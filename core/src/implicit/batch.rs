//! Batch evaluation: [`LANES`] points at a time in structure-of-arrays form, so every
//! multiply–accumulate of a weight runs over contiguous lanes (the parallel-hardware intent of
//! both Carcenac and Wyvill–Cao: one weight, many points) — for the scalars where that pays on
//! the machine (`Kernels::LANE_GROUP`, `Kernels::GRADIENT_LANE_GROUP`,
//! `Kernels::KERNEL_WIDTH_LANE_GROUP`): on 64-bit hosts always; on a Cortex-M4F never for
//! Q16.16 (eight 64-bit accumulators do not fit its register file), not for the `f32` field and
//! gradient at a width compiled as a constant (its eight-lane backward layers are zeroed and
//! copied in memory), and not for the `f32` field at N = 9 (eight lanes cost more estimated
//! cycles there): those batches run point by point. On x86-64 the `f32` batches at the
//! compiled widths take [`WIDE_LANES`] points at a time (four lane groups per neuron, so that
//! each weight serves four independent sums), and their last fewer than 32 points
//! [`LANES`] at a time.

use super::eval::{FieldGradient, ModuleView};
use super::model::ImplicitModel;
use super::width::SPECIALIZED as SPECIALIZED_WIDTHS;
use crate::dense::KERNEL_WIDTH;
use crate::error::LengthMismatch;
use crate::scalar::Scalar;

/// Points evaluated together by the batch functions (for scalars whose
/// `Kernels::LANE_GROUP`, `Kernels::GRADIENT_LANE_GROUP` or `Kernels::KERNEL_WIDTH_LANE_GROUP`
/// is 1: one at a time).
pub const LANES: usize = 8;

/// The wide lane group: four of [`LANES`] per neuron (`f32` on x86-64, see
/// `Kernels::GRADIENT_LANE_GROUP`).
pub(crate) const WIDE_LANES: usize = 4 * LANES;

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
    /// Φ at every point, [`LANES`] at a time (see `Kernels::LANE_GROUP`).
    ///
    /// # Errors
    /// [`LengthMismatch`] when the slices differ in length (nothing is written).
    pub fn field_batch(&self, points: &[[S; 3]], out: &mut [S]) -> Result<(), LengthMismatch> {
        check_lengths(points.len(), out.len())?;
        let group = if self.model.width == KERNEL_WIDTH {
            S::KERNEL_WIDTH_LANE_GROUP
        } else {
            S::LANE_GROUP
        };
        match group {
            1 => grouped::<S, S, 1>(points, out, |group| self.field_lanes(group)),
            // Guarded by constants, so that scalars without the wide group compile no test.
            WIDE_LANES if S::KERNEL_WIDTH_LANE_GROUP == WIDE_LANES => {
                let rest = grouped_wide(points, out, |group| self.field_lanes(group));
                grouped::<S, S, LANES>(rest.0, rest.1, |group| self.field_lanes(group));
            }
            _ => grouped::<S, S, LANES>(points, out, |group| self.field_lanes(group)),
        }
        Ok(())
    }

    /// Φ and ∇Φ at every point, [`LANES`] at a time (see `Kernels::GRADIENT_LANE_GROUP`).
    ///
    /// # Errors
    /// [`LengthMismatch`] when the slices differ in length (nothing is written).
    pub fn field_gradient_batch(
        &self,
        points: &[[S; 3]],
        out: &mut [FieldGradient<S>],
    ) -> Result<(), LengthMismatch> {
        check_lengths(points.len(), out.len())?;
        let group = if SPECIALIZED_WIDTHS.contains(&self.model.width) {
            S::GRADIENT_LANE_GROUP
        } else {
            S::LANE_GROUP
        };
        match group {
            1 => grouped::<S, _, 1>(points, out, |group| self.field_gradient_lanes(group)),
            WIDE_LANES if S::GRADIENT_LANE_GROUP == WIDE_LANES => {
                let rest = grouped_wide(points, out, |group| self.field_gradient_lanes(group));
                grouped::<S, _, LANES>(rest.0, rest.1, |group| self.field_gradient_lanes(group));
            }
            _ => grouped::<S, _, LANES>(points, out, |group| self.field_gradient_lanes(group)),
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

/// Evaluates `points` `G` at a time with `evaluate` (which computes every lane with the same
/// operations as a single point, so the grouping never changes a result) into `out`.
#[inline(always)]
fn grouped<S: Scalar, R: Copy, const G: usize>(
    points: &[[S; 3]],
    out: &mut [R],
    evaluate: impl Fn(&[[S; 3]; G]) -> [R; G],
) {
    for (chunk, out) in points.chunks(G).zip(out.chunks_mut(G)) {
        let results = evaluate(&pad(chunk));
        for (slot, &result) in out.iter_mut().zip(&results) {
            *slot = result;
        }
    }
}

/// Evaluates the whole [`WIDE_LANES`] groups of `points` with `evaluate` into `out`; returns
/// the points and outputs left (fewer than a wide group), for [`LANES`]-point groups: a short
/// batch is padded to eight points, not to 32.
#[inline(always)]
fn grouped_wide<'p, 'o, S: Scalar, R: Copy>(
    points: &'p [[S; 3]],
    out: &'o mut [R],
    evaluate: impl Fn(&[[S; 3]; WIDE_LANES]) -> [R; WIDE_LANES],
) -> (&'p [[S; 3]], &'o mut [R]) {
    let (groups, rest) = points.as_chunks::<WIDE_LANES>();
    let (out_groups, out_rest) = out.as_chunks_mut::<WIDE_LANES>();
    for (group, out) in groups.iter().zip(out_groups) {
        *out = evaluate(group);
    }
    (rest, out_rest)
}

/// A full group of lanes: the chunk's points, the last one repeated into unused lanes.
fn pad<S: Scalar, const G: usize>(chunk: &[[S; 3]]) -> [[S; 3]; G] {
    let last = chunk.last().copied().unwrap_or([S::ZERO; 3]);
    core::array::from_fn(|lane| chunk.get(lane).copied().unwrap_or(last))
}
