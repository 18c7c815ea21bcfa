//! Batch evaluation: [`LANES`] source points per pass over the key points, bit-identical to
//! the single-point calls (for meshes and depth buffers: one network, many sphere points).

use super::model::CaoEnModel;
use super::normal::CaoEnPoint;
use crate::error::LengthMismatch;
use crate::implicit::LANES;
use crate::lanes;
use crate::scalar::Scalar;

impl<S: Scalar, const K: usize> CaoEnModel<S, K> {
    /// y at every source point of `x` into `out` (same length); see [`CaoEnModel::eval`].
    ///
    /// ```
    /// # use neurosurf_core::caoen::CaoEnModel;
    /// # fn demo(model: &CaoEnModel<f32>) -> Result<(), neurosurf_core::LengthMismatch> {
    /// let x: Vec<[f32; 3]> = (0..20).map(|i| {
    ///     let z = -1.0 + i as f32 / 10.0;
    ///     [(1.0 - z * z).max(0.0).sqrt(), 0.0, z]
    /// }).collect();
    /// let mut y = vec![[0.0; 3]; x.len()];
    /// model.eval_batch(&x, &mut y)?;
    /// assert_eq!(y[7], model.eval(&x[7]));
    /// # Ok(()) }
    /// # demo(&CaoEnModel::new()).unwrap();
    /// ```
    ///
    /// # Errors
    /// [`LengthMismatch`] when the slices differ in length (nothing is written).
    pub fn eval_batch<const M: usize, const P: usize>(
        &self,
        x: &[[S; M]],
        out: &mut [[S; P]],
    ) -> Result<(), LengthMismatch> {
        lanes::batch(x, out, [S::ZERO; M], |x| {
            self.lanes::<LANES, M, P, false>(x).map(|jet| jet.position)
        })
    }

    /// Position and unit normal at every source point of `x` into `out` (same length); see
    /// [`CaoEnModel::eval_normal`].
    ///
    /// # Errors
    /// [`LengthMismatch`] when the slices differ in length (nothing is written).
    pub fn eval_normal_batch<const M: usize>(
        &self,
        x: &[[S; M]],
        out: &mut [CaoEnPoint<S>],
    ) -> Result<(), LengthMismatch> {
        lanes::batch(x, out, [S::ZERO; M], |x| self.normal_lanes::<LANES, M>(x))
    }
}
