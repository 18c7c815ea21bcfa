//! Exact surface normals without trigonometry (paper §7, eqs. 8–13).
//!
//! The paper differentiates along θ and φ and removes the trigonometry with eq. 13, which still
//! divides by √(x₁² + x₂²) and fails at the poles. Here the tangent plane is handled without
//! any parameterization:
//!
//! - sphere (m = 3): for a right-handed orthonormal frame (e₁, e₂, x) at x,
//!   (J e₁) × (J e₂) = cof(J)·(e₁ × e₂) = cof(J)·x, and the cofactor matrix's columns are
//!   cross products of J's columns: N = x₁ (J₂ × J₃) + x₂ (J₃ × J₁) + x₃ (J₁ × J₂). No frame,
//!   no pole; for J = I it is x itself (outward);
//! - torus (m = 4, x = (cos θ, sin θ, cos φ, sin φ)): ∂x/∂θ = (−x₂, x₁, 0, 0) and
//!   ∂x/∂φ = (0, 0, −x₄, x₃), so N = (J ∂x/∂θ) × (J ∂x/∂φ) — outward for the standard torus.
//!
//! J is the network's Jacobian (eq. 12), scaled by the reciprocal of its largest entry before
//! the products so that nothing saturates in Q16.16 (the direction is unchanged).

use super::blending::Domain;
use super::eval::Jet;
use super::model::CaoEnModel;
use crate::scalar::{Scalar, normalize3};

/// Position and unit normal of a sphere or torus network at one source point.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct CaoEnPoint<S> {
    /// y (its first three coordinates).
    pub position: [S; 3],
    /// The unit normal; `None` where the surface is singular (the tangents are parallel or
    /// vanish) and for networks that do not define one (see [`CaoEnModel::normal`]).
    pub normal: Option<[S; 3]>,
}

impl<S: Scalar, const K: usize> CaoEnModel<S, K> {
    /// The unit normal at source point x (its first M coordinates; missing ones count as 0).
    ///
    /// Defined for p = 3 on the sphere (m = 3; x on the unit sphere) and on the torus; `None`
    /// for other networks (hyperspheres, projections) and at singular points. Cost: see
    /// [`CaoEnModel::mac_count`].
    ///
    /// ```
    /// # use neurosurf_core::caoen::CaoEnModel;
    /// # fn demo(model: &CaoEnModel<f32>) {
    /// let x = [0.0, 0.0, 1.0];
    /// if let Some(n) = model.normal(&x) {
    ///     assert!((n[0] * n[0] + n[1] * n[1] + n[2] * n[2] - 1.0).abs() < 1e-5);
    /// }
    /// # }
    /// ```
    pub fn normal<const M: usize>(&self, x: &[S; M]) -> Option<[S; 3]> {
        self.eval_normal(x).normal
    }

    /// Position and unit normal at source point x (see [`CaoEnModel::normal`]).
    pub fn eval_normal<const M: usize>(&self, x: &[S; M]) -> CaoEnPoint<S> {
        let [point] = self.normal_lanes::<1, M>(core::array::from_ref(x));
        point
    }

    /// `L` inputs at once.
    #[inline]
    pub(crate) fn normal_lanes<const L: usize, const M: usize>(
        &self,
        x: &[[S; M]; L],
    ) -> [CaoEnPoint<S>; L] {
        let jets = self.lanes::<L, M, 3, true>(x);
        let defined = self.target_dimension() == 3
            && matches!(
                (self.domain, self.source_dimension()),
                (Domain::Sphere, 3) | (Domain::Torus, 4)
            );
        let mut points = [CaoEnPoint::default(); L];
        for ((point, jet), x) in points.iter_mut().zip(&jets).zip(x) {
            point.position = jet.position;
            if defined {
                point.normal = match self.domain {
                    Domain::Torus => torus_normal(x, jet),
                    _ => sphere_normal(x, jet),
                };
            }
        }
        points
    }
}

/// Coordinate `i` of `v`, 0 beyond its end.
#[inline(always)]
fn at<S: Scalar, const N: usize>(v: &[S; N], i: usize) -> S {
    v.get(i).copied().unwrap_or(S::ZERO)
}

/// Column `h` of the Jacobian, times `scale`.
#[inline(always)]
fn column<S: Scalar, const M: usize>(jet: &Jet<S, M, 3>, h: usize, scale: S) -> [S; 3] {
    jet.jacobian.map(|row| at(&row, h).mul(scale))
}

/// 1/(largest |component|) of the vectors, `None` when all vanish.
fn inverse_magnitude<S: Scalar>(vectors: &[&[S]]) -> Option<S> {
    let mut largest = S::ZERO;
    for &c in vectors.iter().copied().flatten() {
        let c = c.abs();
        if c > largest {
            largest = c;
        }
    }
    largest.recip()
}

/// a × b, one rounding per component.
#[inline(always)]
fn cross<S: Scalar>(a: [S; 3], b: [S; 3]) -> [S; 3] {
    let term = |i: usize, j: usize| {
        let acc = S::mac(S::ZERO.to_acc(), at(&a, i), at(&b, j));
        S::from_acc(S::mac(acc, at(&a, j).neg(), at(&b, i)))
    };
    [term(1, 2), term(2, 0), term(0, 1)]
}

/// N = x₁ (J₂ × J₃) + x₂ (J₃ × J₁) + x₃ (J₁ × J₂), normalized.
fn sphere_normal<S: Scalar, const M: usize>(x: &[S; M], jet: &Jet<S, M, 3>) -> Option<[S; 3]> {
    let rows = jet.jacobian.each_ref().map(|row| row.as_slice());
    let scale = inverse_magnitude(&rows)?;
    let [c1, c2, c3] = [0, 1, 2].map(|h| column(jet, h, scale));
    let cofactor = [cross(c2, c3), cross(c3, c1), cross(c1, c2)];
    let n = [0, 1, 2].map(|k| {
        let mut acc = S::ZERO.to_acc();
        for (h, c) in cofactor.iter().enumerate() {
            acc = S::mac(acc, at(x, h), at(c, k));
        }
        S::from_acc(acc)
    });
    normalize3(n)
}

/// N = (J ∂x/∂θ) × (J ∂x/∂φ), normalized.
fn torus_normal<S: Scalar, const M: usize>(x: &[S; M], jet: &Jet<S, M, 3>) -> Option<[S; 3]> {
    let tangent = |cos: usize, sin: usize| {
        let (a, b) = (column(jet, cos, S::ONE), column(jet, sin, S::ONE));
        [0, 1, 2].map(|k| {
            let acc = S::mac(S::ZERO.to_acc(), at(x, sin).neg(), at(&a, k));
            S::from_acc(S::mac(acc, at(x, cos), at(&b, k)))
        })
    };
    let scaled = |v: [S; 3]| -> Option<[S; 3]> {
        let scale = inverse_magnitude(&[v.as_slice()])?;
        Some(v.map(|c| c.mul(scale)))
    };
    let theta = scaled(tangent(0, 1))?;
    let phi = scaled(tangent(2, 3))?;
    normalize3(cross(theta, phi))
}
