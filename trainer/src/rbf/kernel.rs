//! The multiquadric kernel φ(r) = √(r² + c²) and its gradient.

/// φ(|d|) = √(|d|² + c²) for a displacement `d` = x − centre.
///
/// Exact to a few ulps (one rounded sum of squares and a correctly rounded square root);
/// `c2 > 0` keeps it smooth and ≥ c everywhere.
#[inline]
pub fn multiquadric(d: [f64; 3], c2: f64) -> f64 {
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] + c2).sqrt()
}

/// φ(|d|) and its gradient with respect to x, d/φ (each component bounded by 1 in
/// magnitude), to a few ulps.
#[inline]
pub fn multiquadric_gradient(d: [f64; 3], c2: f64) -> (f64, [f64; 3]) {
    let phi = multiquadric(d, c2);
    let inv = 1.0 / phi;
    (phi, [d[0] * inv, d[1] * inv, d[2] * inv])
}
