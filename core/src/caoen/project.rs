//! Projections with the same network (paper §8): y·z = Σᵢ kᵢ·(tᵢ·z), so replacing every
//! target tᵢ by its projections vᵢ_z = tᵢ·z (eq. 16) gives a network whose outputs are the
//! projected coordinates directly — one axis, a view plane (α, β), or any A axes.

use super::blending::clamp;
use super::model::{CaoEnModel, MAX_TARGET_DIMENSION};
use crate::scalar::Scalar;

impl<S: Scalar, const K: usize> CaoEnModel<S, K> {
    /// Replaces the targets by their projections onto `axes`: afterwards the network has
    /// A outputs, output a being y·axesₐ (eq. 14–16). Axis coordinates beyond p are ignored,
    /// missing ones count as 0. Each projected target is one accumulation with one rounding;
    /// in Q16.16 it saturates at ±1024 (the loader's bound, which keeps later evaluation
    /// overflow-free). A perspective view is a trainer matter: project the key points'
    /// targets to the screen there and store those (the paper's approximation).
    ///
    /// A must be 1 … [`MAX_TARGET_DIMENSION`] (checked at compile time).
    ///
    /// ```
    /// # use neurosurf_core::caoen::CaoEnModel;
    /// # fn demo(mut model: CaoEnModel<f32>) {
    /// let x = [0.0, 0.6, 0.8];
    /// let y: [f32; 3] = model.eval(&x);
    /// // A view plane spanned by α = (1, 0, 0) and β = (0, 0.6, −0.8).
    /// model.project(&[[1.0, 0.0, 0.0], [0.0, 0.6, -0.8]]);
    /// let screen: [f32; 2] = model.eval(&x);
    /// assert!((screen[1] - (0.6 * y[1] - 0.8 * y[2])).abs() < 1e-4);
    /// # }
    /// ```
    pub fn project<const D: usize, const A: usize>(&mut self, axes: &[[S; D]; A]) {
        const {
            assert!(
                A >= 1 && A <= MAX_TARGET_DIMENSION,
                "a Cao En projection needs 1 to MAX_TARGET_DIMENSION axes"
            );
        }
        let limit = S::from_f32_saturating(S::MAX_PARAMETER);
        let p = self.target_dimension();
        for key in &mut self.keys {
            let mut projected = [S::ZERO; MAX_TARGET_DIMENSION];
            for (out, axis) in projected.iter_mut().zip(axes) {
                let mut acc = S::ZERO.to_acc();
                for (&t, &z) in key.target.iter().zip(axis).take(p) {
                    acc = S::mac(acc, t, z);
                }
                *out = clamp(S::from_acc(acc), limit);
            }
            key.target = projected;
        }
        self.target_dimension = A as u8;
    }
}
