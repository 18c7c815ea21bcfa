//! The paper's punctual search (§6): Newton's method for Φ = 0 along the ray, inside the
//! smallest sphere containing a voxel.
//!
//! Newton on φ(t) = Φ(o + t·d), t ← t − φ/φ′ with φ′ = ∇Φ·d, inside the ray's segment
//! through the voxel's bounding sphere. φ is sampled at the entry, middle and exit of the
//! voxel's span; where two neighbours differ in sign Newton runs inside that bracket
//! (bisecting when a step leaves it), otherwise from the sample nearest to a zero by its
//! Newton step |φ/φ′|, preferring samples outside and heading in (φ < 0 < φ′). Trained fields saturate away from the surface (|Φ| → 1.7159, φ′ → 0),
//! where a single Newton run from the sphere's entry jumps out of the sphere; the samples
//! avoid that. A run fails when it leaves the sphere, meets φ′ = 0 or takes more than
//! [`MAX_ITERATIONS`] steps. A root counts for this voxel only if it lies in the voxel's own
//! span (so the octree's front-to-back walk returns the nearest hit). Nothing guarantees that
//! a crossing is found: [`super::guaranteed`] does.
//!
//! Accuracy: a reported root has a last Newton step below `tolerance` (in ray length), so it
//! is within about `tolerance` of a zero of Φ along the ray (quadratic convergence), up to the
//! field's own evaluation error divided by |φ′|.

use super::field::Field;
use super::region::Aabb;
use crate::curve::vector::{add, dot, norm, scale, sub};

/// Newton steps allowed per start.
pub const MAX_ITERATIONS: usize = 24;

/// The first root of Φ along the ray inside `voxel`'s span `[t_in, t_out]`, by Newton in the
/// voxel's bounding sphere (see the module docs). `direction` is unit.
pub fn newton_in_voxel<F: Field + ?Sized>(
    field: &F,
    origin: [f64; 3],
    direction: [f64; 3],
    voxel: &Aabb,
    span: [f64; 2],
    tolerance: f64,
) -> Option<f64> {
    let center = voxel.center();
    let radius = norm(voxel.half());
    let oc = sub(origin, center);
    let b = dot(oc, direction);
    let disc = b * b - (dot(oc, oc) - radius * radius);
    if disc < 0.0 {
        return None;
    }
    let root = disc.sqrt();
    let sphere = [(-b - root).max(0.0), -b + root];
    let inside = |t: f64| t >= span[0] - tolerance && t <= span[1] + tolerance;
    let sample = |t: f64| {
        let (value, gradient) = field.value_gradient(add(origin, scale(direction, t)));
        (t, value, dot(gradient, direction))
    };
    let samples = [span[0], 0.5 * (span[0] + span[1]), span[1]].map(sample);
    for pair in samples.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        if (a.1 < 0.0) != (b.1 < 0.0) {
            let start = if a.1.abs() <= b.1.abs() { a } else { b };
            let lo_negative = Some(a.1 < 0.0);
            return newton(
                field,
                origin,
                direction,
                start.0,
                [a.0, b.0],
                tolerance,
                lo_negative,
            )
            .filter(|&t| inside(t));
        }
    }
    // No sign change: the ray may graze the surface (two close crossings). Start from a
    // sample outside and heading in (φ < 0 < φ′) when there is one, so Newton meets the near
    // crossing first.
    let usable = |s: &&(f64, f64, f64)| s.2 != 0.0 && s.2.is_finite();
    let approaching = |s: &&(f64, f64, f64)| s.1 < 0.0 && s.2 > 0.0;
    let closest = |x: &&(f64, f64, f64), y: &&(f64, f64, f64)| {
        (x.1 / x.2).abs().total_cmp(&(y.1 / y.2).abs())
    };
    let nearest = samples
        .iter()
        .filter(usable)
        .filter(approaching)
        .min_by(closest)
        .or_else(|| samples.iter().filter(usable).min_by(closest))?;
    newton(field, origin, direction, nearest.0, sphere, tolerance, None).filter(|&t| inside(t))
}

/// Newton from `start` within `bounds`. With `lo_negative` (whether φ < 0 at `bounds[0]`),
/// φ changes sign over `bounds` and a step leaving the shrinking bracket bisects instead of
/// failing.
fn newton<F: Field + ?Sized>(
    field: &F,
    origin: [f64; 3],
    direction: [f64; 3],
    start: f64,
    bounds: [f64; 2],
    tolerance: f64,
    lo_negative: Option<bool>,
) -> Option<f64> {
    let [mut lo, mut hi] = bounds;
    let mut t = start;
    for _ in 0..MAX_ITERATIONS {
        let (value, gradient) = field.value_gradient(add(origin, scale(direction, t)));
        let slope = dot(gradient, direction);
        if !value.is_finite() {
            return None;
        }
        if let Some(negative) = lo_negative {
            // Keep the sign change inside [lo, hi].
            if (value < 0.0) == negative {
                lo = t;
            } else {
                hi = t;
            }
        }
        let step = value / slope;
        let next = t - step;
        if !(next >= lo && next <= hi) {
            lo_negative?;
            t = 0.5 * (lo + hi);
            if hi - lo < tolerance {
                return Some(t);
            }
            continue;
        }
        t = next;
        if step.abs() < tolerance {
            return Some(t);
        }
    }
    None
}
