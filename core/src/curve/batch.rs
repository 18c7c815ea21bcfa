//! Batch evaluation: [`LANES`] parameters at a time. Each batch computes every lane's segment
//! and basis weights together (structure of arrays), then gathers each lane's control points;
//! the single-point calls run the same code with one lane, so results are bit-identical.

use super::bspline_curve::{BSplineCurve, CurvePoint};
use super::bspline_surface::{BSplineSurface, SurfacePoint};
use crate::error::LengthMismatch;
use crate::implicit::LANES;
use crate::lanes;
use crate::scalar::Scalar;

impl<S: Scalar, const C: usize> BSplineCurve<S, C> {
    /// C(t) for every t of `t` into `out` (same length).
    ///
    /// ```
    /// # use neurosurf_core::curve::BSplineCurve;
    /// # fn demo(curve: &BSplineCurve<f32>) -> Result<(), neurosurf_core::LengthMismatch> {
    /// let t: Vec<f32> = (0..=100).map(|i| i as f32 / 100.0).collect();
    /// let mut points = vec![[0.0; 3]; t.len()];
    /// curve.position_batch(&t, &mut points)?;
    /// assert_eq!(points[37], curve.position(t[37]));
    /// # Ok(()) }
    /// # demo(&BSplineCurve::new()).unwrap();
    /// ```
    ///
    /// # Errors
    /// [`LengthMismatch`] when the slices differ in length (nothing is written).
    pub fn position_batch(&self, t: &[S], out: &mut [[S; 3]]) -> Result<(), LengthMismatch> {
        if self.is_cubic() {
            lanes::batch(t, out, S::ZERO, |t| {
                self.cubic_lanes::<LANES, false>(t)
                    .map(|point| point.position)
            })
        } else {
            lanes::batch(t, out, S::ZERO, |t| {
                self.any_degree_lanes::<LANES, false>(t)
                    .map(|point| point.position)
            })
        }
    }

    /// C(t) and dC/dt for every t of `t` into `out` (same length).
    ///
    /// # Errors
    /// [`LengthMismatch`] when the slices differ in length (nothing is written).
    pub fn eval_batch(&self, t: &[S], out: &mut [CurvePoint<S>]) -> Result<(), LengthMismatch> {
        if self.is_cubic() {
            lanes::batch(t, out, S::ZERO, |t| self.cubic_lanes::<LANES, true>(t))
        } else {
            lanes::batch(t, out, S::ZERO, |t| self.any_degree_lanes::<LANES, true>(t))
        }
    }
}

impl<S: Scalar, const C: usize> BSplineSurface<S, C> {
    /// S(u, v) for every `[u, v]` of `uv` into `out` (same length).
    ///
    /// # Errors
    /// [`LengthMismatch`] when the slices differ in length (nothing is written).
    pub fn position_batch(&self, uv: &[[S; 2]], out: &mut [[S; 3]]) -> Result<(), LengthMismatch> {
        if self.is_bicubic() {
            lanes::batch(uv, out, [S::ZERO; 2], |uv| {
                self.lanes::<LANES, false>(uv).map(|point| point.position)
            })
        } else {
            lanes::batch(uv, out, [S::ZERO; 2], |uv| {
                self.any_degree_lanes::<LANES, false>(uv)
                    .map(|point| point.position)
            })
        }
    }

    /// S(u, v), ∂S/∂u and ∂S/∂v for every `[u, v]` of `uv` into `out` (same length).
    ///
    /// # Errors
    /// [`LengthMismatch`] when the slices differ in length (nothing is written).
    pub fn eval_batch(
        &self,
        uv: &[[S; 2]],
        out: &mut [SurfacePoint<S>],
    ) -> Result<(), LengthMismatch> {
        if self.is_bicubic() {
            lanes::batch(uv, out, [S::ZERO; 2], |uv| self.lanes::<LANES, true>(uv))
        } else {
            lanes::batch(uv, out, [S::ZERO; 2], |uv| {
                self.any_degree_lanes::<LANES, true>(uv)
            })
        }
    }

    /// The unit normal for every `[u, v]` of `uv` into `out` (same length).
    ///
    /// # Errors
    /// [`LengthMismatch`] when the slices differ in length (nothing is written).
    pub fn normal_batch(
        &self,
        uv: &[[S; 2]],
        out: &mut [Option<[S; 3]>],
    ) -> Result<(), LengthMismatch> {
        if self.is_bicubic() {
            lanes::batch(uv, out, [S::ZERO; 2], |uv| self.normal_lanes::<LANES>(uv))
        } else {
            lanes::batch(uv, out, [S::ZERO; 2], |uv| {
                self.any_degree_normal::<LANES>(uv)
            })
        }
    }
}
