//! Levenberg–Marquardt with weight decay, exactly as Carcenac §5.
//!
//! Minimizes E_sc = E_s + E_c with E_s = (1/2N_s)·Σe² over the N_s error terms and the weight
//! decay E_c. Each iteration forms A = JᵀJ/N_s + λ′I and B = −(Jᵀe/N_s + λ′V), solves
//! (A + μI)ΔV = B by Cholesky, and raises μ by θ until E_s decreases; after an accepted step μ
//! is lowered by θ. It stops when E_s ≤ threshold, at the iteration cap, or when μ exceeds
//! [`LmOptions::mu_max`] without finding a decrease (stalled).
//!
//! λ′ depends on [`DecayScale`]: the paper's formulas read literally (λ′ = λ beside the
//! normalized E_s) collapse every network to Φ ≡ 0 at Table 1's λ = 1.2·10⁻⁴ (measured in
//! `shared/notes/carcenac-reproduction.md`); the default reads the decay per error term,
//! λ′ = λ/N_s, which trains.

use nalgebra::{Cholesky, DMatrix, DMatrixView, DVector};

/// A nonlinear least-squares problem: residuals e(V) and their Jacobian.
pub trait LeastSquares {
    /// Number of parameters V.
    fn parameter_count(&self) -> usize;
    /// Number of residuals N_s.
    fn residual_count(&self) -> usize;
    /// Writes e(V).
    fn residuals(&self, params: &[f64], residuals: &mut [f64]);
    /// Writes e(V) and J = ∂e/∂V (row-major, N_s × parameters).
    fn jacobian(&self, params: &[f64], residuals: &mut [f64], jacobian: &mut [f64]);
}

/// How the weight-decay coefficient λ enters the criterion.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum DecayScale {
    /// E_c = (λ/2N_s)·ΣV²: λ beside the un-normalized ½Σe² (trains at Table 1's λ).
    #[default]
    PerTerm,
    /// E_c = (λ/2)·ΣV²: the paper's formula read literally.
    Normalized,
}

/// Levenberg–Marquardt settings (defaults: Carcenac's Table 1).
#[derive(Copy, Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LmOptions {
    /// Weight decay λ (1.2·10⁻⁴).
    pub lambda: f64,
    /// How λ is scaled.
    pub decay: DecayScale,
    /// Initial damping μ₀ (10⁻⁴).
    pub mu0: f64,
    /// Damping ratio θ (2).
    pub theta: f64,
    /// Stop when E_s ≤ threshold (10⁻⁵).
    pub threshold: f64,
    /// Iteration cap.
    pub max_iterations: usize,
    /// Give up when μ grows past this without a decrease of E_s.
    pub mu_max: f64,
}

impl Default for LmOptions {
    fn default() -> Self {
        LmOptions {
            lambda: 1.2e-4,
            decay: DecayScale::PerTerm,
            mu0: 1e-4,
            theta: 2.0,
            threshold: 1e-5,
            max_iterations: 2000,
            mu_max: 1e12,
        }
    }
}

/// Why the iteration stopped.
#[derive(Copy, Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum StopReason {
    /// E_s reached the threshold.
    Converged,
    /// The iteration cap was reached first.
    IterationLimit,
    /// μ exceeded its cap without a decrease of E_s.
    Stalled,
}

/// What a run did.
#[derive(Copy, Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LmReport {
    /// Accepted iterations.
    pub iterations: usize,
    /// E_s before the first iteration.
    pub initial_error: f64,
    /// Final E_s.
    pub error: f64,
    /// Final E_s + E_c.
    pub criterion: f64,
    /// Why it stopped.
    pub stop: StopReason,
    /// Residual evaluations, including rejected trial steps.
    pub evaluations: usize,
}

/// Half the mean squared residual: E_s.
fn half_mean_square(residuals: &[f64]) -> f64 {
    let sum: f64 = residuals.iter().map(|e| e * e).sum();
    0.5 * sum / residuals.len().max(1) as f64
}

/// Runs Levenberg–Marquardt on `problem` from `params` (updated in place). `progress` is called
/// after every accepted iteration with (iteration, E_s).
pub fn levenberg_marquardt(
    problem: &dyn LeastSquares,
    params: &mut [f64],
    options: &LmOptions,
    progress: &mut dyn FnMut(usize, f64),
) -> LmReport {
    let p = problem.parameter_count();
    let ns = problem.residual_count();
    let decay = match options.decay {
        DecayScale::PerTerm => options.lambda / ns.max(1) as f64,
        DecayScale::Normalized => options.lambda,
    };
    let decay_energy = |v: &[f64]| 0.5 * decay * v.iter().map(|x| x * x).sum::<f64>();

    let mut residuals = vec![0.0; ns];
    let mut jacobian = vec![0.0; ns * p];
    let mut trial = vec![0.0; p];
    problem.residuals(params, &mut residuals);
    let mut evaluations = 1;
    let initial_error = half_mean_square(&residuals);
    let mut error = initial_error;
    let mut mu = options.mu0;
    let mut iterations = 0;
    let mut stop = StopReason::Converged;

    while error > options.threshold {
        if iterations >= options.max_iterations {
            stop = StopReason::IterationLimit;
            break;
        }
        problem.jacobian(params, &mut residuals, &mut jacobian);
        let (normal, gradient) = normal_equations(&jacobian, &residuals, ns, p);
        let v = DVector::from_column_slice(params);
        let b = -(gradient + &v * decay);
        let mut accepted = false;
        while mu <= options.mu_max {
            let mut system = normal.clone();
            for i in 0..p {
                system[(i, i)] += decay + mu;
            }
            let Some(cholesky) = Cholesky::new(system) else {
                mu *= options.theta;
                continue;
            };
            let step = cholesky.solve(&b);
            for ((t, &x), &dx) in trial.iter_mut().zip(params.iter()).zip(step.iter()) {
                *t = x + dx;
            }
            problem.residuals(&trial, &mut residuals);
            evaluations += 1;
            let trial_error = half_mean_square(&residuals);
            if trial_error.is_finite() && trial_error <= error {
                params.copy_from_slice(&trial);
                error = trial_error;
                accepted = true;
                break;
            }
            mu *= options.theta;
        }
        if !accepted {
            stop = StopReason::Stalled;
            // Leave the residuals consistent with the parameters we keep.
            problem.residuals(params, &mut residuals);
            break;
        }
        mu /= options.theta;
        iterations += 1;
        progress(iterations, error);
    }
    LmReport {
        iterations,
        initial_error,
        error,
        criterion: error + decay_energy(params),
        stop,
        evaluations,
    }
}

/// Column blocks for the symmetric product: only blocks on or below the diagonal are computed.
const SYMMETRIC_BLOCKS: usize = 4;

/// JᵀJ/N_s and Jᵀe/N_s for a row-major J, through nalgebra's GEMM (matrixmultiply).
///
/// JᵀJ is symmetric, so it is computed in column blocks, lower triangle only, and mirrored:
/// 10 of 16 block products, ~60 % of a full GEMM.
pub(crate) fn normal_equations(
    jacobian: &[f64],
    residuals: &[f64],
    ns: usize,
    p: usize,
) -> (DMatrix<f64>, DVector<f64>) {
    // Row-major J (ns × p) is column-major Jᵀ (p × ns).
    let jt = DMatrixView::from_slice(jacobian, p, ns);
    let j = DMatrixView::from_slice_with_strides(jacobian, ns, p, p, 1);
    let scale = 1.0 / ns.max(1) as f64;
    let mut normal = DMatrix::zeros(p, p);
    let bounds: Vec<usize> = (0..=SYMMETRIC_BLOCKS)
        .map(|b| b * p / SYMMETRIC_BLOCKS)
        .collect();
    for (bi, rows) in bounds.windows(2).enumerate() {
        for cols in bounds.windows(2).take(bi + 1) {
            let (r0, r1, c0, c1) = (rows[0], rows[1], cols[0], cols[1]);
            if r1 == r0 || c1 == c0 {
                continue;
            }
            let mut block = normal.view_mut((r0, c0), (r1 - r0, c1 - c0));
            block.gemm(scale, &jt.rows(r0, r1 - r0), &j.columns(c0, c1 - c0), 0.0);
        }
    }
    normal.fill_upper_triangle_with_lower_triangle();
    let e = DVector::from_column_slice(residuals);
    let gradient = (jt * e) * scale;
    (normal, gradient)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocked_normal_equations_equal_the_plain_product() {
        for (ns, p) in [(7, 3), (40, 13), (64, 136), (5, 1)] {
            let j: Vec<f64> = (0..ns * p)
                .map(|i| ((i * 7919) % 101) as f64 / 50.0 - 1.0)
                .collect();
            let e: Vec<f64> = (0..ns).map(|i| (i % 5) as f64 - 2.0).collect();
            let (normal, gradient) = normal_equations(&j, &e, ns, p);
            let jm = DMatrix::from_row_slice(ns, p, &j);
            let expected = jm.transpose() * &jm / ns as f64;
            let expected_g = jm.transpose() * DVector::from_column_slice(&e) / ns as f64;
            assert!((normal - expected).amax() < 1e-12, "{ns}x{p}");
            assert!((gradient - expected_g).amax() < 1e-12, "{ns}x{p}");
        }
    }
}
