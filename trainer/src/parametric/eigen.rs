//! The few smallest eigenpairs of a sparse symmetric positive semi-definite matrix whose null
//! space is the constant vector (the LLE matrix M = (I − W)ᵀ(I − W), §4.3).
//!
//! Shift-and-invert subspace iteration: K = M + σI with σ = 10⁻¹²·tr(M)/n (raised by 100×
//! while the factorization breaks down) is factored once by
//! the sparse Cholesky of [`super::sparse`]; a block of `wanted + 4` vectors is repeatedly
//! multiplied by K⁻¹, kept orthogonal to the constant vector (the "free–free mode" the paper
//! discards), orthonormalized and rotated by a Rayleigh–Ritz step on M. Vector i converges at
//! the rate (λᵢ + σ)/(λ_b + σ), b the block size, which for a 2-D manifold is fast because M's
//! spectrum grows like the square of a Laplacian's. No dense n × n matrix is ever formed:
//! memory is the factor plus n·b numbers.
//!
//! Accuracy: stops when every wanted Ritz pair has ‖Mx − θx‖ ≤ 10⁻⁷·max(θ_b, 10⁻⁷·tr(M)/n)
//! (θ_b the largest Ritz value of the block; the floor keeps the test above the rounding of
//! M·x when the whole block is tiny, as for dense samples), which bounds the angle to the true
//! eigenvector by about that residual over the spectral gap; or when the wanted Ritz values
//! change by less than 10⁻¹² of that scale between iterations.

use crate::geometry::vector::inner;
use nalgebra::{DMatrix, SymmetricEigen};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::sparse::SymmetricMatrix;
use crate::error::{Error, Result};

/// Extra block vectors beyond the wanted ones (they speed convergence of the last wanted one).
const GUARD_VECTORS: usize = 4;
/// Iteration cap of the subspace iteration.
pub const MAX_EIGEN_ITERATIONS: usize = 300;
/// Relative residual at which a Ritz pair counts as converged.
const RESIDUAL_TOLERANCE: f64 = 1e-7;

/// Smallest eigenpairs, ascending, excluding the constant vector.
#[derive(Clone, Debug)]
pub struct Eigenpairs {
    /// Eigenvalues λ₂ ≤ λ₃ ≤ … of M.
    pub values: Vec<f64>,
    /// Unit eigenvectors, orthogonal to the constant vector, one `Vec` per eigenvalue.
    pub vectors: Vec<Vec<f64>>,
    /// Subspace iterations used.
    pub iterations: usize,
}

/// The `wanted` smallest eigenpairs of `m` orthogonal to the constant vector.
///
/// # Errors
/// [`Error::InvalidInput`] when n ≤ wanted + 1, when the shifted matrix cannot be factored, or
/// when the iteration does not converge within [`MAX_EIGEN_ITERATIONS`].
pub fn smallest_nonconstant(m: &SymmetricMatrix, wanted: usize) -> Result<Eigenpairs> {
    let n = m.order();
    if n <= wanted + 1 {
        return Err(Error::invalid(format!(
            "{n} points are too few for {wanted} embedding coordinates"
        )));
    }
    let block = (wanted + GUARD_VECTORS).min(n - 1);
    let trace = m.trace();
    if !(trace.is_finite() && trace > 0.0) {
        return Err(Error::invalid("the embedding matrix is zero or not finite"));
    }
    let mean_diagonal = trace / n as f64;
    // The shift must sit below λ₂ (dense samples have tiny LLE eigenvalues) but above the
    // rounding of M: try 10⁻¹²·tr(M)/n first and raise it when the factorization breaks down.
    let compressed = m.compress()?;
    let mut factor = None;
    for exponent in [-12, -10, -8, -6] {
        let sigma = 10f64.powi(exponent) * mean_diagonal;
        // M's diagonal is ≥ 1 everywhere (each point's own row of I − W).
        let shifted = compressed
            .with_diagonal_added(sigma)
            .ok_or_else(|| Error::invalid("the embedding matrix lacks a diagonal entry"))?;
        if let Ok(f) = shifted.cholesky() {
            factor = Some(f);
            break;
        }
    }
    let factor =
        factor.ok_or_else(|| Error::invalid("the shifted embedding matrix cannot be factored"))?;
    let m = compressed;
    let mut rng = ChaCha8Rng::seed_from_u64(0x5eed_e16e);

    let mut x: Vec<Vec<f64>> = (0..block)
        .map(|_| (0..n).map(|_| rng.random::<f64>() - 0.5).collect())
        .collect();
    orthonormalize(&mut x, &mut rng);
    let mut mx = vec![vec![0.0; n]; block];
    let mut previous = vec![f64::INFINITY; wanted];
    for iteration in 1..=MAX_EIGEN_ITERATIONS {
        factor.solve(&mut x);
        orthonormalize(&mut x, &mut rng);
        for (xi, yi) in x.iter().zip(mx.iter_mut()) {
            m.multiply(xi, yi);
        }
        let mut h = DMatrix::<f64>::zeros(block, block);
        for i in 0..block {
            for j in i..block {
                let v = inner(&x[i], &mx[j]);
                h[(i, j)] = v;
                h[(j, i)] = v;
            }
        }
        let eigen = SymmetricEigen::new(h);
        let mut order: Vec<usize> = (0..block).collect();
        order.sort_by(|&a, &b| eigen.eigenvalues[a].total_cmp(&eigen.eigenvalues[b]));
        let rotate = |vectors: &[Vec<f64>]| -> Vec<Vec<f64>> {
            order
                .iter()
                .map(|&c| {
                    let mut out = vec![0.0; n];
                    for (r, v) in vectors.iter().enumerate() {
                        let w = eigen.eigenvectors[(r, c)];
                        for (o, &vi) in out.iter_mut().zip(v.iter()) {
                            *o += w * vi;
                        }
                    }
                    out
                })
                .collect()
        };
        x = rotate(&x);
        mx = rotate(&mx);
        let theta: Vec<f64> = order.iter().map(|&c| eigen.eigenvalues[c]).collect();
        // Relative to the block's spread, but never below what rounding in M·x allows.
        let scale = theta[block - 1].abs().max(1e-7 * mean_diagonal);
        let converged = (0..wanted).all(|i| {
            let r: f64 = x[i]
                .iter()
                .zip(mx[i].iter())
                .map(|(&xv, &mv)| (mv - theta[i] * xv).powi(2))
                .sum::<f64>()
                .sqrt();
            r <= RESIDUAL_TOLERANCE * scale
        });
        let settled = (0..wanted).all(|i| (theta[i] - previous[i]).abs() <= 1e-12 * scale);
        previous.copy_from_slice(&theta[..wanted]);
        if converged || settled {
            return Ok(Eigenpairs {
                values: theta[..wanted].to_vec(),
                vectors: x.into_iter().take(wanted).collect(),
                iterations: iteration,
            });
        }
    }
    Err(Error::invalid(format!(
        "the sparse eigen solver did not converge in {MAX_EIGEN_ITERATIONS} iterations \
         (nearly repeated eigenvalues: the patch has no clear 2-D parameterization)"
    )))
}

/// Makes the vectors orthonormal and orthogonal to the constant vector (modified
/// Gram–Schmidt, twice); a vector that vanishes is replaced by a random one.
fn orthonormalize(vectors: &mut [Vec<f64>], rng: &mut ChaCha8Rng) {
    for i in 0..vectors.len() {
        for attempt in 0..3 {
            for _pass in 0..2 {
                let mean = vectors[i].iter().sum::<f64>() / vectors[i].len() as f64;
                vectors[i].iter_mut().for_each(|v| *v -= mean);
                for j in 0..i {
                    let (done, rest) = vectors.split_at_mut(i);
                    let d = inner(&done[j], &rest[0]);
                    for (v, &q) in rest[0].iter_mut().zip(done[j].iter()) {
                        *v -= d * q;
                    }
                }
            }
            let norm = inner(&vectors[i], &vectors[i]).sqrt();
            if norm > 1e-300 && norm.is_finite() {
                vectors[i].iter_mut().for_each(|v| *v /= norm);
                break;
            }
            let _ = attempt;
            for v in vectors[i].iter_mut() {
                *v = rng.random::<f64>() - 0.5;
            }
        }
    }
}
