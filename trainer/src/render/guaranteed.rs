//! The guaranteed search (beyond the paper): interval bounds of Φ and of its derivative along
//! the ray prune segments that cannot hold a crossing, so no sign change of Φ is ever missed.
//!
//! A segment [a, b] is processed front to back:
//! - 0 ∉ \[Φ\]([a, b]): no zero, dropped;
//! - 0 ∉ [φ′]([a, b]): φ is monotone, so it has a zero iff φ(a) and φ(b) differ in sign
//!   (or one is 0); the zero is then refined by regula falsi (Illinois), bisecting when the
//!   secant leaves the bracket;
//! - otherwise split at the midpoint, down to `min_length`, where a segment whose bounds
//!   still contain 0 is reported as a hit at its start (conservative: a tangency of width
//!   below `min_length` counts).
//!
//! Guarantee: every sign change of φ on the searched spans lies in a segment whose bound
//! contains 0, so it is never dropped; the first such segment in ray order yields the
//! nearest hit. This holds for the field the bounds enclose — the `f64` network, up to
//! [`super::interval::ROUNDING_MARGIN`].
//!
//! Accuracy: a refined root is within `tolerance` (ray length) of the bracketed zero.

use super::field::Field;
use super::interval::Interval;
use crate::geometry::vector::{add, scale};

/// The first zero of Φ along the ray in `span`, or `None` when the field has no interval
/// bounds or the span holds no zero (see the module docs). `direction` is unit.
pub fn first_root<F: Field + ?Sized>(
    field: &F,
    origin: [f64; 3],
    direction: [f64; 3],
    span: [f64; 2],
    min_length: f64,
    tolerance: f64,
) -> Option<f64> {
    let phi = |t: f64| field.value(add(origin, scale(direction, t)));
    let mut stack = vec![span];
    while let Some([a, b]) = stack.pop() {
        let (value, slope) = field.segment_bounds(origin, direction, Interval::new(a, b))?;
        if !value.contains_zero() {
            continue;
        }
        if !slope.contains_zero() {
            let (fa, fb) = (phi(a), phi(b));
            if fa == 0.0 {
                return Some(a);
            }
            if fa * fb <= 0.0 {
                return Some(refine(&phi, [a, b], [fa, fb], tolerance));
            }
            continue;
        }
        if b - a <= min_length {
            return Some(a);
        }
        let mid = 0.5 * (a + b);
        stack.push([mid, b]);
        stack.push([a, mid]);
    }
    None
}

/// Illinois regula falsi on a bracket with f(a)·f(b) ≤ 0: stops when the bracket is
/// `tolerance` narrow (Illinois shrinks it from both sides) and returns the last estimate.
fn refine(
    f: &dyn Fn(f64) -> f64,
    [mut a, mut b]: [f64; 2],
    [mut fa, mut fb]: [f64; 2],
    tolerance: f64,
) -> f64 {
    if fb == 0.0 {
        return b;
    }
    let mut side = 0;
    let mut estimate = 0.5 * (a + b);
    for _ in 0..100 {
        let secant = (a * fb - b * fa) / (fb - fa);
        // Bisection when the secant lands outside the bracket (rounding).
        let c = if secant > a && secant < b {
            secant
        } else {
            0.5 * (a + b)
        };
        estimate = c;
        let fc = f(c);
        if fc == 0.0 {
            return c;
        }
        if (fc < 0.0) == (fa < 0.0) {
            a = c;
            fa = fc;
            if side == -1 {
                fb *= 0.5;
            }
            side = -1;
        } else {
            b = c;
            fb = fc;
            if side == 1 {
                fa *= 0.5;
            }
            side = 1;
        }
        if b - a <= tolerance {
            return estimate;
        }
    }
    estimate
}
