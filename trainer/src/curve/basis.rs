//! The uniform cubic B-spline basis on one segment, u ∈ [0, 1].
//!
//! B₀ = (1 − u)³/6, B₁ = (3u³ − 6u² + 4)/6, B₂ = (−3u³ + 3u² + 3u + 1)/6, B₃ = u³/6.
//! They sum to 1 for every u; at a joint (u = 0) they are (1/6, 4/6, 1/6, 0). Mind the 3u
//! term of B₂: without it the four would sum to 1 − u/2 and the curve would not be the
//! uniform cubic B-spline (nor continuous at the joints).

/// The four basis values at `u`, in the order they weight P_i … P_{i+3}. Exact to a few ulp.
pub fn cubic_basis(u: f64) -> [f64; 4] {
    let u2 = u * u;
    let u3 = u2 * u;
    let v = 1.0 - u;
    [
        v * v * v / 6.0,
        (3.0 * u3 - 6.0 * u2 + 4.0) / 6.0,
        (-3.0 * u3 + 3.0 * u2 + 3.0 * u + 1.0) / 6.0,
        u3 / 6.0,
    ]
}

/// The derivatives d/du of [`cubic_basis`]: −(1 − u)²/2, (3u² − 4u)/2, (−3u² + 2u + 1)/2,
/// u²/2. They sum to 0 for every u.
pub fn cubic_basis_derivative(u: f64) -> [f64; 4] {
    let u2 = u * u;
    let v = 1.0 - u;
    [
        -0.5 * v * v,
        (3.0 * u2 - 4.0 * u) / 2.0,
        (-3.0 * u2 + 2.0 * u + 1.0) / 2.0,
        0.5 * u2,
    ]
}

/// Splits a global parameter t over `segments` uniform segments: s = t · segments,
/// i = min(⌊s⌋, segments − 1), u = s − i. t is clamped to [0, 1] first; a NaN t gives
/// segment 0 and a NaN u (so NaN results, never a panic). `segments` must be ≥ 1.
pub fn locate(t: f64, segments: usize) -> (usize, f64) {
    let s = t.clamp(0.0, 1.0) * segments as f64;
    // `as usize` saturates: NaN → 0.
    let i = (s.floor() as usize).min(segments - 1);
    (i, s - i as f64)
}

/// The basis functions of one segment of a uniform B-spline of degree `degree` (2 to 5) at
/// `u`, weighting P_i … P_{i+degree} (the rest 0): the Cox–de Boor recurrence on integer
/// knots, N_k^d = ((u + d − k)·N_{k−1}^{d−1} + (k + 1 − u)·N_k^{d−1})/d. They sum to 1. The
/// cubic case equals [`cubic_basis`] to a few ulp.
pub fn uniform_basis(degree: usize, u: f64) -> [f64; MAX_ORDER] {
    let mut basis = [0.0; MAX_ORDER];
    basis[0] = 1.0;
    for d in 1..=degree.min(MAX_ORDER - 1) {
        for k in (0..=d).rev() {
            let left = if k > 0 { basis[k - 1] } else { 0.0 };
            let rising = u + (d - k) as f64;
            let falling = (k + 1) as f64 - u;
            basis[k] = (rising * left + falling * basis[k]) / d as f64;
        }
    }
    basis
}

/// The derivatives d/du of [`uniform_basis`]: N_k′ = N_{k−1}^{p−1} − N_k^{p−1}. They sum to 0.
pub fn uniform_basis_derivative(degree: usize, u: f64) -> [f64; MAX_ORDER] {
    let lower = uniform_basis(degree.saturating_sub(1), u);
    let mut out = [0.0; MAX_ORDER];
    let mut previous = 0.0;
    for k in 0..=degree.min(MAX_ORDER - 1) {
        let b = if k < degree { lower[k] } else { 0.0 };
        out[k] = previous - b;
        previous = b;
    }
    out
}

/// The most basis functions of one segment: the core's highest degree (5) plus one.
pub const MAX_ORDER: usize = neurosurf_core::curve::MAX_DEGREE + 1;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_recurrence_gives_the_cubic_basis() {
        for step in 0..=20 {
            let u = f64::from(step) / 20.0;
            let b = uniform_basis(3, u);
            let d = uniform_basis_derivative(3, u);
            for k in 0..4 {
                assert!((b[k] - cubic_basis(u)[k]).abs() < 1e-15);
                assert!((d[k] - cubic_basis_derivative(u)[k]).abs() < 1e-15);
            }
            for degree in 2..=5 {
                let b = uniform_basis(degree, u);
                assert!((b.iter().sum::<f64>() - 1.0).abs() < 1e-15);
                assert!(
                    uniform_basis_derivative(degree, u)
                        .iter()
                        .sum::<f64>()
                        .abs()
                        < 1e-15
                );
                // Continuity at the joints: the weights at u = 1 are those at u = 0 shifted.
                let (start, end) = (uniform_basis(degree, 0.0), uniform_basis(degree, 1.0));
                for k in 0..degree {
                    assert!((end[k + 1] - start[k]).abs() < 1e-15);
                }
            }
        }
    }
}
