//! The paper's punctual search (§6): Newton's method for Φ = 0 along the ray inside each
//! voxel the octree walk reaches.
//!
//! φ(t) = Φ(o + t·d) is sampled at [`SAMPLES`] evenly spaced points of the ray's span through
//! the voxel, in one call of the core's batch API (values only). At the first pair of
//! neighbouring samples whose signs differ, Newton's method t ← t − φ/φ′ (φ′ = ∇Φ·d) starts
//! from the secant (regula falsi) point of the pair and stays inside the shrinking bracket,
//! bisecting when a step would leave it. Without a sign change the ray may graze the surface,
//! crossing it twice between two samples: where |φ| has a local minimum at an interior sample,
//! the parabola through it and its neighbours predicts the extremum of φ; if that extremum has
//! the other sign, φ is evaluated there, and a sign change brackets the near crossing.
//!
//! Departure from the paper, measured (`cargo bench -p neurosurf-trainer --bench render`): the
//! paper starts Newton from the entry of the voxel's bounding sphere. On trained fields, which
//! saturate away from the surface (|Φ| → 1.7159, φ′ → 0), such a run jumps out of the sphere
//! and the crossing is missed, and every voxel without a crossing costs a full failed run; the
//! batch of samples finds brackets at the cost of about one single-point evaluation per voxel.
//! Nothing guarantees that a crossing is found (two crossings between samples whose parabola
//! does not dip through zero are missed): [`super::guaranteed`] does.
//!
//! Accuracy: a reported root has a last Newton step, or a bracket, below `tolerance` (in ray
//! length), so it is within about `tolerance` of a zero of Φ along the ray, up to the field's
//! own evaluation error divided by |φ′|.

use super::field::Field;
use crate::geometry::vector::{add, dot, scale};

/// Newton steps allowed per bracket.
pub const MAX_ITERATIONS: usize = 24;
/// Samples of φ along the ray's span through a voxel: one batch of the core.
pub const SAMPLES: usize = neurosurf_core::implicit::LANES;

/// The first root of Φ along the ray inside a voxel's span `[t_in, t_out]` (see the module
/// docs), with ∇Φ from Newton's last step (within `tolerance` of the root, for shading).
/// `direction` is unit.
pub fn newton_in_voxel<F: Field + ?Sized>(
    field: &F,
    origin: [f64; 3],
    direction: [f64; 3],
    span: [f64; 2],
    tolerance: f64,
) -> Option<(f64, [f64; 3])> {
    let step = (span[1] - span[0]) / (SAMPLES - 1) as f64;
    let ts: [f64; SAMPLES] = std::array::from_fn(|i| span[0] + step * i as f64);
    let points = ts.map(|t| add(origin, scale(direction, t)));
    let mut phi = [f64::NAN; SAMPLES];
    field.values(&points, &mut phi);
    let at = |t: f64| field.value(add(origin, scale(direction, t)));
    for i in 0..SAMPLES - 1 {
        let (a, b) = (phi[i], phi[i + 1]);
        if !(a.is_finite() && b.is_finite()) {
            continue;
        }
        if (a < 0.0) != (b < 0.0) {
            return bracketed(
                field,
                origin,
                direction,
                [ts[i], ts[i + 1]],
                [a, b],
                tolerance,
            );
        }
        // A graze: |φ| smallest at sample i + 1 among its neighbours, and the parabola
        // through the three dips through zero.
        let Some(&c) = phi.get(i + 2) else { continue };
        if !(c.is_finite() && b.abs() <= a.abs() && b.abs() <= c.abs()) {
            continue;
        }
        let curvature = a - 2.0 * b + c;
        if curvature == 0.0 {
            continue;
        }
        let offset = 0.5 * (a - c) / curvature;
        let extremum = b - 0.125 * (a - c) * (a - c) / curvature;
        if (extremum < 0.0) == (b < 0.0) || offset.is_nan() || offset.abs() > 1.0 {
            continue;
        }
        let t_mid = ts[i + 1] + offset * step;
        let mid = at(t_mid);
        if mid.is_finite() && (mid < 0.0) != (a < 0.0) {
            let (lo, hi) = if t_mid > ts[i] {
                (ts[i], t_mid)
            } else {
                continue;
            };
            return bracketed(field, origin, direction, [lo, hi], [a, mid], tolerance);
        }
    }
    None
}

/// Newton inside `bracket`, where φ takes the values `ends` of opposite signs: started from
/// the secant point, a step leaving the shrinking bracket bisects instead. Returns the root
/// and the gradient last evaluated.
fn bracketed<F: Field + ?Sized>(
    field: &F,
    origin: [f64; 3],
    direction: [f64; 3],
    bracket: [f64; 2],
    ends: [f64; 2],
    tolerance: f64,
) -> Option<(f64, [f64; 3])> {
    let [mut lo, mut hi] = bracket;
    let lo_negative = ends[0] < 0.0;
    let secant = lo + (hi - lo) * ends[0] / (ends[0] - ends[1]);
    let mut t = if secant > lo && secant < hi {
        secant
    } else {
        0.5 * (lo + hi)
    };
    for _ in 0..MAX_ITERATIONS {
        let (value, gradient) = field.value_gradient(add(origin, scale(direction, t)));
        if !value.is_finite() {
            return None;
        }
        if (value < 0.0) == lo_negative {
            lo = t;
        } else {
            hi = t;
        }
        let step = value / dot(gradient, direction);
        let next = t - step;
        if next > lo && next < hi {
            t = next;
            if step.abs() < tolerance {
                return Some((t, gradient));
            }
        } else {
            t = 0.5 * (lo + hi);
            if hi - lo < tolerance {
                return Some((t, gradient));
            }
        }
    }
    None
}
