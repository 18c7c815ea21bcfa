//! Test fixtures shared by the Cao En tests: key-point layouts and fitted shapes.

use neurosurf_core::caoen::{Blending, Domain};

use super::{CaoEnNetwork, fit_shape, from_key_points};

/// n points spread over the unit sphere (a Fibonacci lattice).
pub(crate) fn fibonacci(n: usize) -> Vec<Vec<f64>> {
    let golden = std::f64::consts::PI * (3.0 - 5.0_f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let (r, a) = ((1.0 - z * z).sqrt(), golden * i as f64);
            vec![r * a.cos(), r * a.sin(), z]
        })
        .collect()
}

/// The six axis points ±eₖ.
pub(crate) fn axes() -> Vec<Vec<f64>> {
    (0..6)
        .map(|i| {
            let mut k = vec![0.0; 3];
            k[i / 2] = if i % 2 == 0 { 1.0 } else { -1.0 };
            k
        })
        .collect()
}

/// A sphere network through `targets` at `keys` (V fitted), one q for all.
pub(crate) fn fitted(
    keys: &[Vec<f64>],
    targets: &[Vec<f64>],
    blending: Blending,
    normalized: bool,
    q: f64,
) -> CaoEnNetwork {
    let built = from_key_points(Domain::Sphere, blending, normalized, keys, targets, q)
        .unwrap_or_else(|e| panic!("{e}"));
    fit_shape(&built, keys, targets).unwrap_or_else(|e| panic!("{e}"))
}
