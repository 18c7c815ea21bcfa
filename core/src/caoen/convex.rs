//! The implicit form of convex Cao En surfaces (paper §9) and ray intersection (§10.1).
//!
//! A convex polyhedron whose face planes have foot points tᵢ (perpendiculars from the origin)
//! is {x : maxᵢ x·wᵢ ≤ 1} with wᵢ = tᵢ/|tᵢ|² (eq. 17). A network with these weights, p = 1 and
//! every target 1 evaluates f(x) = Σᵢ F(x·wᵢ) at any point x of space (not just the sphere),
//! a smooth stand-in for the maximum: for power blending with q ≥ 1 or exponential blending
//! and non-negative targets, f is convex, so the solid {f ≤ s} (s > 1) is convex — a rounded
//! version of the polyhedron that approaches it as q grows — and a ray meets its boundary at
//! most twice. Both points are returned so the solid can take part in CSG.
//!
//! Ray marching: the paper bisects the range between two bounding-sphere intersections,
//! looking for an inside point by recursive subdivision. Here, with the same goal and a fixed
//! budget: f at [`RAY_SCAN_SAMPLES`] + 1 evenly spaced points; if none is inside, a
//! golden-section search of f's minimum around the lowest sample ([`GOLDEN_STEPS`], exact for
//! convex f — the paper's search can miss a thin chord); then [`BISECTION_STEPS`] bisections
//! from the first inside sample back to the entry and from the last one on to the exit. At
//! most [`MAX_RAY_EVALUATIONS`] evaluations, never a failure.

use super::model::CaoEnModel;
use crate::scalar::Scalar;

/// Evenly spaced intervals of the first scan along a ray.
pub const RAY_SCAN_SAMPLES: usize = 16;
/// Golden-section steps when no scan sample is inside (0.618⁴⁰ ≈ 4·10⁻⁹ of an interval).
pub const GOLDEN_STEPS: usize = 40;
/// Bisection steps per intersection (2⁻³² of a scan interval: below the resolution of both
/// scalars for any ray).
pub const BISECTION_STEPS: usize = 32;
/// Most evaluations of f for one ray.
pub const MAX_RAY_EVALUATIONS: usize =
    RAY_SCAN_SAMPLES + 1 + GOLDEN_STEPS + 2 + 2 * BISECTION_STEPS;

/// A ray segment x(t) = origin + t·direction for t ∈ [near, far] (typically the two
/// intersections with a bounding sphere).
#[derive(Copy, Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Ray<S, const M: usize> {
    /// The origin.
    pub origin: [S; M],
    /// The direction (any length: t is in its units).
    pub direction: [S; M],
    /// Start of the searched range.
    pub near: S,
    /// End of the searched range.
    pub far: S,
}

/// Where a ray is inside the solid: the parameters of its two boundary crossings.
#[derive(Copy, Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct RayHit<S> {
    /// The first inside parameter: `near` if the ray starts inside, else within one bisection
    /// step after the entry crossing.
    pub entry: S,
    /// The last inside parameter: `far` if the ray ends inside, else within one bisection
    /// step before the exit crossing.
    pub exit: S,
}

impl<S: Scalar, const K: usize> CaoEnModel<S, K> {
    /// The implicit function f(x) = y₁, the network's first output, at any point x of the
    /// source space (not only the sphere).
    ///
    /// ```
    /// # use neurosurf_core::caoen::CaoEnModel;
    /// # fn demo(model: &CaoEnModel<f32>) {
    /// let inside = model.implicit_value(&[0.1, 0.2, 0.0]) <= 1.5;
    /// assert_eq!(inside, model.is_inside(&[0.1, 0.2, 0.0], 1.5));
    /// # }
    /// ```
    pub fn implicit_value<const M: usize>(&self, x: &[S; M]) -> S {
        let [f] = self.eval::<M, 1>(x);
        f
    }

    /// Whether f(x) ≤ `level` (false for NaN).
    pub fn is_inside<const M: usize>(&self, x: &[S; M], level: S) -> bool {
        self.implicit_value(x) <= level
    }

    /// The two crossings of `ray` with the boundary f = `level`, `None` when the ray misses
    /// the solid within [near, far] (or near > far, or NaN).
    ///
    /// Exact (to [`BISECTION_STEPS`]) when f is convex along the ray (see [`crate::caoen`]'s
    /// implicit form); for other networks the entry and exit of the first and last inside
    /// scan samples. Where saturation (Q16.16, or the blending clamp at ±1024) flattens f over
    /// every scan sample, a thin solid can be missed.
    ///
    /// ```
    /// # use neurosurf_core::caoen::{CaoEnModel, Ray};
    /// # fn demo(model: &CaoEnModel<f32>) {
    /// let ray = Ray { origin: [-3.0, 0.1, 0.0], direction: [1.0, 0.0, 0.0], near: 0.0, far: 6.0 };
    /// if let Some(hit) = model.ray_intersections(&ray, 1.5) {
    ///     assert!(hit.entry <= hit.exit);
    /// }
    /// # }
    /// ```
    pub fn ray_intersections<const M: usize>(
        &self,
        ray: &Ray<S, M>,
        level: S,
    ) -> Option<RayHit<S>> {
        if ray
            .near
            .partial_cmp(&ray.far)
            .is_none_or(|o| o == core::cmp::Ordering::Greater)
        {
            return None;
        }
        let inside = |t: S| {
            let x = core::array::from_fn(|h| {
                let (o, d) = (at(&ray.origin, h), at(&ray.direction, h));
                o.add(t.mul(d))
            });
            let f = self.implicit_value::<M>(&x);
            (f <= level, f)
        };
        let span = ray.far.sub(ray.near);
        let sample = |i: usize| {
            if i >= RAY_SCAN_SAMPLES {
                ray.far
            } else {
                let fraction = S::from_f32_saturating(i as f32 / RAY_SCAN_SAMPLES as f32);
                ray.near.add(span.mul(fraction))
            }
        };
        // The scan: first and last inside sample, and the lowest sample.
        let mut first = None;
        let mut last = 0;
        let mut lowest = (0, None::<S>);
        for i in 0..=RAY_SCAN_SAMPLES {
            let (is_inside, f) = inside(sample(i));
            if is_inside {
                first.get_or_insert(i);
                last = i;
            }
            if lowest.1.is_none_or(|low| f < low) {
                lowest = (i, Some(f));
            }
        }
        let (entry_outside, entry_inside, exit_inside, exit_outside) = match first {
            Some(first) => (
                first.checked_sub(1).map(sample),
                sample(first),
                sample(last),
                (last < RAY_SCAN_SAMPLES).then(|| sample(last + 1)),
            ),
            None => {
                let (i, _) = lowest;
                let a = sample(i.saturating_sub(1));
                let b = sample((i + 1).min(RAY_SCAN_SAMPLES));
                let t = golden_inside(a, b, inside)?;
                (Some(a), t, t, Some(b))
            }
        };
        let entry = match entry_outside {
            Some(outside) => bisect(outside, entry_inside, |t| inside(t).0),
            None => entry_inside,
        };
        let exit = match exit_outside {
            Some(outside) => bisect(outside, exit_inside, |t| inside(t).0),
            None => exit_inside,
        };
        Some(RayHit { entry, exit })
    }
}

/// Coordinate `i` of `v`, 0 beyond its end.
#[inline(always)]
fn at<S: Scalar, const N: usize>(v: &[S; N], i: usize) -> S {
    v.get(i).copied().unwrap_or(S::ZERO)
}

/// Golden-section search of the minimum of f on [a, b], stopping at the first inside point.
fn golden_inside<S: Scalar>(mut a: S, mut b: S, f: impl Fn(S) -> (bool, S)) -> Option<S> {
    let ratio = S::from_f32_saturating(0.618_034);
    let mut c = b.sub(b.sub(a).mul(ratio));
    let mut d = a.add(b.sub(a).mul(ratio));
    let (mut c_inside, mut fc) = f(c);
    let (mut d_inside, mut fd) = f(d);
    for _ in 0..GOLDEN_STEPS {
        if c_inside {
            return Some(c);
        }
        if d_inside {
            return Some(d);
        }
        if fc <= fd {
            b = d;
            (d, fd) = (c, fc);
            c = b.sub(b.sub(a).mul(ratio));
            (c_inside, fc) = f(c);
            d_inside = false;
        } else {
            a = c;
            (c, fc) = (d, fd);
            d = a.add(b.sub(a).mul(ratio));
            (d_inside, fd) = f(d);
            c_inside = false;
        }
    }
    if c_inside {
        Some(c)
    } else if d_inside {
        Some(d)
    } else {
        None
    }
}

/// Bisection between an outside and an inside parameter; returns the last inside one.
fn bisect<S: Scalar>(mut outside: S, mut inside: S, is_inside: impl Fn(S) -> bool) -> S {
    let half = S::from_f32_saturating(0.5);
    for _ in 0..BISECTION_STEPS {
        let middle = outside.add(inside.sub(outside).mul(half));
        if is_inside(middle) {
            inside = middle;
        } else {
            outside = middle;
        }
    }
    inside
}
