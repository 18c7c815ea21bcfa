//! The batch driver shared by the model families: slices of inputs in chunks of
//! [`LANES`](crate::implicit::LANES), the last chunk padded by repeating its last input, each
//! chunk through a structure-of-arrays kernel whose single-point form is the same code with
//! one lane.

use crate::error::LengthMismatch;
use crate::implicit::LANES;

/// Runs `kernel` over `inputs` [`LANES`] at a time and writes one result per input to `out`.
///
/// # Errors
/// [`LengthMismatch`] when the slices differ in length (nothing is written).
#[inline]
pub(crate) fn batch<T: Copy, R>(
    inputs: &[T],
    out: &mut [R],
    empty: T,
    mut kernel: impl FnMut(&[T; LANES]) -> [R; LANES],
) -> Result<(), LengthMismatch> {
    if inputs.len() != out.len() {
        return Err(LengthMismatch {
            inputs: inputs.len(),
            outputs: out.len(),
        });
    }
    for (chunk, out) in inputs.chunks(LANES).zip(out.chunks_mut(LANES)) {
        let last = chunk.last().copied().unwrap_or(empty);
        let lanes = core::array::from_fn(|lane| chunk.get(lane).copied().unwrap_or(last));
        for (slot, result) in out.iter_mut().zip(kernel(&lanes)) {
            *slot = result;
        }
    }
    Ok(())
}
