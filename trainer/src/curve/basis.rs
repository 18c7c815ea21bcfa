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
