//! The B-spline curve the core evaluates (a fixed contract), and its f64 reference
//! evaluation.
//!
//! The global parameter t ∈ [0, 1] covers the whole curve: s = t · segments,
//! i = min(⌊s⌋, segments − 1), u = s − i, and C(t) = Σₖ Bₖ(u) · P_{i+k} (k = 0..3, indices
//! mod n when closed) with the uniform cubic basis of [`cubic_basis`]. Closed curves have
//! `segments = n`, open ones `n − 3`.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

use super::basis::{
    MAX_ORDER, cubic_basis, cubic_basis_derivative, locate, uniform_basis, uniform_basis_derivative,
};
use neurosurf_core::curve::{MAX_DEGREE, MIN_DEGREE};

/// Fewest control points of a curve (open or closed) or of an open surface direction.
pub const MIN_CONTROL_POINTS: usize = 4;

/// A uniform B-spline curve of degree 2 to 5 (cubic by default). Closed: control points
/// wrap (segments = n). Open: segments = n − degree, and the fitter adds phantom end points
/// (P₋₁ = 2P₀ − P₁ style) so the curve starts/ends at the data ends.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BSplineCurve {
    /// 2 or 3 (2-D control points have z = 0).
    pub dimension: usize,
    /// Whether the control points wrap around.
    pub closed: bool,
    /// The polynomial degree p, 2 to 5.
    #[serde(default = "cubic")]
    pub degree: usize,
    /// The control points P₀ … P_{n−1}.
    pub control: Vec<[f64; 3]>,
}

impl BSplineCurve {
    /// Checks the curve: dimension 2 or 3, at least [`MIN_CONTROL_POINTS`] control points,
    /// all finite, z = 0 in 2-D.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the problem.
    pub fn validate(&self) -> Result<()> {
        if self.dimension != 2 && self.dimension != 3 {
            return Err(Error::invalid(format!(
                "a B-spline curve is 2-D or 3-D, got dimension {}",
                self.dimension
            )));
        }
        check_degree(self.degree)?;
        if self.control.len() <= self.degree {
            return Err(Error::invalid(format!(
                "a B-spline curve of degree {} needs at least {} control points, got {}",
                self.degree,
                self.degree + 1,
                self.control.len()
            )));
        }
        check_control(&self.control, self.dimension == 2)
    }

    /// Number of polynomial segments: n when closed, n − degree when open (0 if too few
    /// points).
    pub fn segments(&self) -> usize {
        if self.closed {
            self.control.len()
        } else {
            self.control.len().saturating_sub(self.degree)
        }
    }

    /// C(t), t clamped to [0, 1]. Exact to a few ulp of the control points' magnitude.
    /// Returns NaN coordinates when the curve has fewer than [`MIN_CONTROL_POINTS`] points.
    pub fn point(&self, t: f64) -> [f64; 3] {
        if self.degree == 3 {
            self.combine(t, |u| widen(cubic_basis(u)), 1.0)
        } else {
            let degree = self.degree;
            self.combine(t, |u| uniform_basis(degree, u), 1.0)
        }
    }

    /// dC/dt (includes the factor `segments` of s = t · segments), t clamped to [0, 1];
    /// NaN like [`BSplineCurve::point`].
    pub fn tangent(&self, t: f64) -> [f64; 3] {
        let factor = self.segments() as f64;
        if self.degree == 3 {
            self.combine(t, |u| widen(cubic_basis_derivative(u)), factor)
        } else {
            let degree = self.degree;
            self.combine(t, |u| uniform_basis_derivative(degree, u), factor)
        }
    }

    /// Σ weights(u)ₖ · P_{i+k} · factor.
    fn combine(&self, t: f64, weights: impl Fn(f64) -> [f64; MAX_ORDER], factor: f64) -> [f64; 3] {
        let n = self.control.len();
        if n <= self.degree || !(MIN_DEGREE..=MAX_DEGREE).contains(&self.degree) {
            return [f64::NAN; 3];
        }
        let (i, u) = locate(t, self.segments());
        let w = weights(u);
        let mut c = [0.0; 3];
        for (k, &wk) in w.iter().enumerate().take(self.degree + 1) {
            let p = self.control[(i + k) % n];
            for axis in 0..3 {
                c[axis] += wk * p[axis];
            }
        }
        c.map(|v| v * factor)
    }

    /// `samples + 1` points C(k / samples), k = 0..=samples (for a closed curve the last
    /// equals the first): a polyline for plots and distances.
    pub fn polyline(&self, samples: usize) -> Vec<[f64; 3]> {
        let samples = samples.max(1);
        (0..=samples)
            .map(|k| self.point(k as f64 / samples as f64))
            .collect()
    }
}

/// The default degree of curves (and of version 3 blobs).
fn cubic() -> usize {
    3
}

/// The four cubic weights in the array of any degree.
fn widen(w: [f64; 4]) -> [f64; MAX_ORDER] {
    let mut out = [0.0; MAX_ORDER];
    out[..4].copy_from_slice(&w);
    out
}

/// Checks a curve degree: 2 to 5, what the core evaluates.
///
/// # Errors
/// [`Error::InvalidInput`] naming the degree and the range.
pub fn check_degree(degree: usize) -> Result<()> {
    if (MIN_DEGREE..=MAX_DEGREE).contains(&degree) {
        Ok(())
    } else {
        Err(Error::invalid(format!(
            "degree {degree}: the core evaluates B-splines of degree {MIN_DEGREE} to \
             {MAX_DEGREE}; give --degree {MIN_DEGREE}..={MAX_DEGREE}"
        )))
    }
}

/// Tensor-product uniform B-spline surface of degree 2 to 5 along each direction (bicubic by
/// default); control[v * count_u + u]; each direction has more control points than its
/// degree, and at least 4.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BSplineSurface {
    /// Whether the u direction wraps around.
    pub closed_u: bool,
    /// Whether the v direction wraps around.
    pub closed_v: bool,
    /// The polynomial degree along u, 2 to 5.
    #[serde(default = "cubic")]
    pub degree_u: usize,
    /// The polynomial degree along v, 2 to 5.
    #[serde(default = "cubic")]
    pub degree_v: usize,
    /// Control points per row (along u).
    pub count_u: usize,
    /// Rows (along v).
    pub count_v: usize,
    /// The control grid, row by row: `control[v * count_u + u]`.
    pub control: Vec<[f64; 3]>,
}

impl BSplineSurface {
    /// Checks the surface: at least [`MIN_CONTROL_POINTS`] per direction, a control grid of
    /// `count_u · count_v` finite points.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the problem.
    pub fn validate(&self) -> Result<()> {
        check_degree(self.degree_u)?;
        check_degree(self.degree_v)?;
        if self.count_u < MIN_CONTROL_POINTS || self.count_v < MIN_CONTROL_POINTS {
            return Err(Error::invalid(format!(
                "a B-spline surface needs at least {MIN_CONTROL_POINTS} control points \
                 per direction, got {} × {}",
                self.count_u, self.count_v
            )));
        }
        if self.count_u <= self.degree_u || self.count_v <= self.degree_v {
            return Err(Error::invalid(format!(
                "a B-spline surface of degrees {} × {} needs more control points than its \
                 degree in each direction, got {} × {}",
                self.degree_u, self.degree_v, self.count_u, self.count_v
            )));
        }
        if Some(self.control.len()) != self.count_u.checked_mul(self.count_v) {
            return Err(Error::invalid(format!(
                "a {} × {} B-spline surface needs {} control points, got {}",
                self.count_u,
                self.count_v,
                self.count_u.saturating_mul(self.count_v),
                self.control.len()
            )));
        }
        check_control(&self.control, false)
    }

    /// Segments along u: `count_u` when closed, `count_u − degree_u` when open.
    pub fn segments_u(&self) -> usize {
        segments(self.count_u, self.closed_u, self.degree_u)
    }

    /// Segments along v: `count_v` when closed, `count_v − degree_v` when open.
    pub fn segments_v(&self) -> usize {
        segments(self.count_v, self.closed_v, self.degree_v)
    }

    /// S(u, v), both clamped to [0, 1]; NaN for a surface that fails
    /// [`BSplineSurface::validate`]'s counts. Exact to a few ulp.
    pub fn point(&self, u: f64, v: f64) -> [f64; 3] {
        self.combine(u, v, [false, false], 1.0)
    }

    /// (∂S/∂u, ∂S/∂v), including the factors `segments_u` and `segments_v`.
    pub fn partials(&self, u: f64, v: f64) -> ([f64; 3], [f64; 3]) {
        let du = self.combine(u, v, [true, false], self.segments_u() as f64);
        let dv = self.combine(u, v, [false, true], self.segments_v() as f64);
        (du, dv)
    }

    /// The basis weights of one direction of `degree` at `u`: values, or their derivative.
    fn weights(degree: usize, u: f64, derivative: bool) -> [f64; MAX_ORDER] {
        match (degree, derivative) {
            (3, false) => widen(cubic_basis(u)),
            (3, true) => widen(cubic_basis_derivative(u)),
            (_, false) => uniform_basis(degree, u),
            (_, true) => uniform_basis_derivative(degree, u),
        }
    }

    /// The unit normal ∂S/∂u × ∂S/∂v / |…|; `None` where the cross product vanishes or is
    /// not finite (a degenerate point).
    pub fn normal(&self, u: f64, v: f64) -> Option<[f64; 3]> {
        let (a, b) = self.partials(u, v);
        let n = crate::geometry::vector::cross(a, b);
        let length = crate::geometry::vector::norm(n);
        (length > 0.0 && length.is_finite()).then(|| n.map(|c| c / length))
    }

    /// Σ wv·wu·P times `factor`, with each direction's weights or their derivative as
    /// `derivative` says.
    fn combine(&self, u: f64, v: f64, derivative: [bool; 2], factor: f64) -> [f64; 3] {
        let (nu, nv) = (self.count_u, self.count_v);
        let degrees_valid = [self.degree_u, self.degree_v]
            .iter()
            .all(|d| (MIN_DEGREE..=MAX_DEGREE).contains(d));
        if nu < MIN_CONTROL_POINTS
            || nv < MIN_CONTROL_POINTS
            || !degrees_valid
            || nu <= self.degree_u
            || nv <= self.degree_v
            || Some(self.control.len()) != nu.checked_mul(nv)
        {
            return [f64::NAN; 3];
        }
        let (i, lu) = locate(u, self.segments_u());
        let (j, lv) = locate(v, self.segments_v());
        let wu = Self::weights(self.degree_u, lu, derivative[0]);
        let wv = Self::weights(self.degree_v, lv, derivative[1]);
        let mut c = [0.0; 3];
        for (b, &wb) in wv.iter().enumerate().take(self.degree_v + 1) {
            let row = (j + b) % nv;
            let mut r = [0.0; 3];
            for (a, &wa) in wu.iter().enumerate().take(self.degree_u + 1) {
                let p = self.control[row * nu + (i + a) % nu];
                for axis in 0..3 {
                    r[axis] += wa * p[axis];
                }
            }
            for axis in 0..3 {
                c[axis] += wb * r[axis];
            }
        }
        c.map(|x| x * factor)
    }
}

fn segments(count: usize, closed: bool, degree: usize) -> usize {
    if closed {
        count
    } else {
        count.saturating_sub(degree)
    }
}

fn check_control(control: &[[f64; 3]], planar: bool) -> Result<()> {
    for (i, p) in control.iter().enumerate() {
        if p.iter().any(|c| !c.is_finite()) {
            return Err(Error::invalid(format!(
                "control point {i} has a non-finite coordinate {p:?}"
            )));
        }
        if planar && p[2] != 0.0 {
            return Err(Error::invalid(format!(
                "control point {i} of a 2-D curve has z = {}",
                p[2]
            )));
        }
    }
    Ok(())
}
