//! Levenberg–Marquardt with weight decay, exactly as Carcenac §5.
//!
//! Minimizes E_sc = E_s + E_c with E_s = (1/2N_s)·Σe² over the N_s error terms and the weight
//! decay E_c. Each iteration forms A = JᵀJ/N_s + λ′I and B = −(Jᵀe/N_s + λ′V), solves
//! (A + μI)ΔV = B by Cholesky, and raises μ by θ until E_s decreases; after an accepted step μ
//! is lowered by θ. It stops when E_s ≤ threshold, at the iteration cap, or when μ exceeds
//! [`LmOptions::mu_max`] without finding a decrease (stalled).
//!
//! λ′ depends on [`DecayScale`]: the paper's formulas read literally (λ′ = λ beside the
//! normalized E_s) collapse every network to Φ ≡ 0 at Table 1's λ = 1.2·10⁻⁴ (measured on
//! the paper's torus); the default reads the decay per error term,
//! λ′ = λ/N_s, which trains.
//!
//! Each trial step v is corrected by geodesic acceleration (Transtrum & Sethna, "Improvements to
//! the Levenberg–Marquardt algorithm for nonlinear least-squares minimization", 2012) unless
//! [`LmOptions::acceleration`] is off: the residuals' second directional derivative r″ along v,
//! by a finite difference of one more residual evaluation, gives a = −(A + μI)⁻¹Jᵀr″/N_s with
//! the same factor, and the step v + a/2 follows the curvature of the residual manifold. It is
//! kept when 2‖a‖ ≤ α‖v‖ (α = 0.75); else the step is v alone. On Table 5's torus it halves
//! the iterations (576 points: 72 → 33, median of seeds 1–5, and a far narrower spread). It needs J
//! kept in f32 between the accumulation and the step ([`NormalEquations::keeping_rows`]);
//! a problem whose J would take more than 256 MiB runs without it.
//!
//! JᵀJ is accumulated a block of rows at a time ([`NormalEquations`]), so a problem can hand
//! over its Jacobian in pieces that stay in cache; A + μI is factored in place
//! ([`DampedSystem`]).

use super::kept_rows::KeptRows;
use super::normal_equations::{DampedSystem, NormalEquations};

/// A nonlinear least-squares problem: residuals e(V) and their Jacobian.
pub trait LeastSquares {
    /// Number of parameters V.
    fn parameter_count(&self) -> usize;
    /// Number of residuals.
    fn residual_count(&self) -> usize;
    /// N_s, the number of error terms E_s is the mean over (and the weight decay is scaled
    /// by); by default every residual. A problem with auxiliary residuals (constraints beside
    /// the paper's error terms) counts only the error terms, so that the auxiliary ones add to
    /// E_s without diluting it.
    fn error_terms(&self) -> usize {
        self.residual_count()
    }
    /// Writes e(V).
    fn residuals(&self, params: &[f64], residuals: &mut [f64]);
    /// Writes e(V) and J = ∂e/∂V (row-major, N_s × parameters).
    fn jacobian(&self, params: &[f64], residuals: &mut [f64], jacobian: &mut [f64]);
    /// Writes e(V) and accumulates JᵀJ and Jᵀe into `normal` (cleared by the caller).
    ///
    /// The default forms J with [`Self::jacobian`] and feeds its rows; a problem can instead
    /// hand its rows over a few at a time ([`NormalEquations::rows_mut`]) so J never exists
    /// whole and each block is multiplied while it is still in cache.
    fn normal_equations(
        &self,
        params: &[f64],
        residuals: &mut [f64],
        normal: &mut NormalEquations,
    ) {
        let p = self.parameter_count();
        let mut jacobian = vec![0.0; residuals.len() * p];
        self.jacobian(params, residuals, &mut jacobian);
        normal.add_jacobian(&jacobian, residuals);
    }
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
    /// Stop as stagnated when E_s fell by less than [`Self::stagnation_decrease`] (relative)
    /// over this many accepted iterations (10), unless [`Self::finish_on_course`]; 0 never
    /// stops so.
    pub stagnation_window: usize,
    /// The relative decrease of E_s over [`Self::stagnation_window`] iterations below which
    /// training has stagnated (0.02).
    pub stagnation_decrease: f64,
    /// Do not stop as stagnated while E_s, falling on at the window's rate, reaches the
    /// threshold within the iterations left: a slow last approach still converges (true).
    #[serde(default = "finish_on_course_default")]
    pub finish_on_course: bool,
    /// Correct each step by geodesic acceleration (true; see the module documentation).
    /// Not stored with the options (blob metadata keeps its layout, so blobs written before
    /// it existed still read); read back, it is the default.
    #[serde(skip, default = "acceleration_default")]
    pub acceleration: bool,
}

fn acceleration_default() -> bool {
    true
}

/// Step h of the finite difference r″ ≈ (2/h)·((r(V + h·v) − r(V))/h − J·v) (Transtrum &
/// Sethna's choice).
const ACCELERATION_PROBE: f64 = 0.1;

/// Largest 2‖a‖/‖v‖ for which the acceleration is kept (Transtrum & Sethna's α).
const ACCELERATION_RATIO: f64 = 0.75;

/// Most memory J may take in f32 for the acceleration to keep it.
const KEPT_ROWS_LIMIT: usize = 256 << 20;

fn finish_on_course_default() -> bool {
    true
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
            stagnation_window: 10,
            stagnation_decrease: 0.02,
            finish_on_course: true,
            acceleration: true,
        }
    }
}

/// E_s over the last stagnation window: where it was, where it is, and the iterations left.
struct Course {
    error: f64,
    before: f64,
    window: usize,
    remaining: usize,
}

impl Course {
    /// Whether E_s, falling on geometrically at the window's rate, reaches `threshold`
    /// within the iterations left.
    fn reaches(&self, threshold: f64) -> bool {
        if !(self.error < self.before && threshold > 0.0) {
            return false;
        }
        let windows = (threshold / self.error).ln() / (self.error / self.before).ln();
        windows * self.window as f64 <= self.remaining as f64
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
    /// E_s stopped falling: less than the stagnation decrease over the stagnation window.
    Stagnated,
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

/// The buffers of the geodesic acceleration.
struct Acceleration {
    /// The residuals at the current parameters.
    base: Vec<f64>,
    /// The residuals at V + h·v.
    probe: Vec<f64>,
    /// V + h·v.
    probe_params: Vec<f64>,
    /// The step v, and then the step taken (v + a/2 or v).
    velocity: Vec<f64>,
    /// Jᵀr″ and then −Jᵀr″/N_s.
    rhs: Vec<f64>,
}

impl Acceleration {
    fn new(residuals: usize, p: usize) -> Self {
        Acceleration {
            base: vec![0.0; residuals],
            probe: vec![0.0; residuals],
            probe_params: vec![0.0; p],
            velocity: vec![0.0; p],
            rhs: vec![0.0; p],
        }
    }

    /// Replaces the step v in `velocity` by v + a/2 when the acceleration a is small enough
    /// beside it (one residual evaluation).
    fn correct(
        &mut self,
        problem: &dyn LeastSquares,
        params: &[f64],
        kept: &KeptRows,
        system: &mut DampedSystem,
        scale: f64,
    ) {
        let h = ACCELERATION_PROBE;
        for ((t, &x), &v) in self.probe_params.iter_mut().zip(params).zip(&self.velocity) {
            *t = x + h * v;
        }
        problem.residuals(&self.probe_params, &mut self.probe);
        let (base, probe) = (&self.base, &self.probe);
        kept.transpose_along(
            &self.velocity,
            |i, along| (2.0 / h) * ((probe[i] - base[i]) / h - along),
            &mut self.rhs,
        );
        if !self.rhs.iter().all(|x| x.is_finite()) {
            return;
        }
        self.rhs.iter_mut().for_each(|x| *x *= -scale);
        let Some(a) = system.solve_again(&self.rhs) else {
            return;
        };
        let norm = |x: &[f64]| x.iter().map(|y| y * y).sum::<f64>().sqrt();
        if 2.0 * norm(a) <= ACCELERATION_RATIO * norm(&self.velocity) {
            for (v, &a) in self.velocity.iter_mut().zip(a) {
                *v += 0.5 * a;
            }
        }
    }
}

/// E_s = ½Σe² / N_s.
fn half_mean_square(residuals: &[f64], terms: usize) -> f64 {
    let sum: f64 = residuals.iter().map(|e| e * e).sum();
    0.5 * sum / terms.max(1) as f64
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
    let ns = problem.error_terms();
    let decay = match options.decay {
        DecayScale::PerTerm => options.lambda / ns.max(1) as f64,
        DecayScale::Normalized => options.lambda,
    };
    let scale = 1.0 / ns.max(1) as f64;
    let decay_energy = |v: &[f64]| 0.5 * decay * v.iter().map(|x| x * x).sum::<f64>();

    // Every buffer is allocated once (kept rows grow in the first iteration); an iteration
    // allocates only the acceleration's two short scratch rows.
    let mut residuals = vec![0.0; problem.residual_count()];
    let kept_bytes = residuals.len() * p.div_ceil(4) * 4 * size_of::<f32>();
    let accelerate = options.acceleration && kept_bytes <= KEPT_ROWS_LIMIT;
    let mut normal = NormalEquations::single_precision(p);
    if accelerate {
        normal = normal.keeping_rows();
    }
    let mut system = DampedSystem::new(p);
    let mut trial = vec![0.0; p];
    let mut acceleration = accelerate.then(|| Acceleration::new(residuals.len(), p));
    problem.residuals(params, &mut residuals);
    let mut evaluations = 1;
    let initial_error = half_mean_square(&residuals, ns);
    let mut error = initial_error;
    let mut mu = options.mu0;
    let mut iterations = 0;
    let mut stop = StopReason::Converged;

    // E_s after each of the last `stagnation_window` accepted iterations (a ring: slot
    // i mod window holds E_s after iteration i).
    let window = options.stagnation_window;
    let mut history = vec![error; window.max(1)];
    while error > options.threshold {
        if iterations >= options.max_iterations {
            stop = StopReason::IterationLimit;
            break;
        }
        if window > 0 && iterations >= window {
            let before = history[iterations % window];
            let course = Course {
                error,
                before,
                window,
                remaining: options.max_iterations - iterations,
            };
            if error > (1.0 - options.stagnation_decrease) * before
                && !(options.finish_on_course && course.reaches(options.threshold))
            {
                stop = StopReason::Stagnated;
                break;
            }
        }
        if window > 0 {
            // Read again `window` iterations from now.
            history[iterations % window] = error;
        }
        normal.clear();
        problem.normal_equations(params, &mut residuals, &mut normal);
        normal.finish();
        for i in 0..p {
            let row = system.lhs_row_mut(i);
            for j in i..p {
                row[j - i] = normal.gram(i, j) * scale;
            }
            row[0] += decay;
            // B = −(Jᵀe/N_s + λ′V).
            system.rhs_mut()[i] = -(normal.gradient(i) * scale + params[i] * decay);
        }
        if let Some(acceleration) = &mut acceleration {
            acceleration.base.copy_from_slice(&residuals);
        }
        let mut accepted = false;
        while mu <= options.mu_max {
            let Some(step) = system.solve(mu) else {
                mu *= options.theta;
                continue;
            };
            match (&mut acceleration, normal.kept_rows()) {
                (Some(acceleration), Some(kept)) if kept.is_complete() => {
                    acceleration.velocity.copy_from_slice(step);
                    evaluations += 1;
                    acceleration.correct(problem, params, kept, &mut system, scale);
                    for ((t, &x), &dx) in trial
                        .iter_mut()
                        .zip(params.iter())
                        .zip(&acceleration.velocity)
                    {
                        *t = x + dx;
                    }
                }
                _ => {
                    for ((t, &x), &dx) in trial.iter_mut().zip(params.iter()).zip(step.iter()) {
                        *t = x + dx;
                    }
                }
            }
            problem.residuals(&trial, &mut residuals);
            evaluations += 1;
            let trial_error = half_mean_square(&residuals, ns);
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

#[cfg(test)]
mod tests {
    use super::{Course, LeastSquares, LmOptions, StopReason, levenberg_marquardt};

    /// Rosenbrock's valley as least squares: e = (10·(y − x²), 1 − x), minimum 0 at (1, 1);
    /// its curved valley is where geodesic acceleration helps.
    struct Valley;

    impl LeastSquares for Valley {
        fn parameter_count(&self) -> usize {
            2
        }
        fn residual_count(&self) -> usize {
            2
        }
        fn residuals(&self, v: &[f64], e: &mut [f64]) {
            e[0] = 10.0 * (v[1] - v[0] * v[0]);
            e[1] = 1.0 - v[0];
        }
        fn jacobian(&self, v: &[f64], e: &mut [f64], j: &mut [f64]) {
            self.residuals(v, e);
            j.copy_from_slice(&[-20.0 * v[0], 10.0, -1.0, 0.0]);
        }
    }

    #[test]
    fn acceleration_reaches_the_valley_floor_in_fewer_iterations() {
        let run = |acceleration| {
            let options = LmOptions {
                lambda: 0.0,
                threshold: 1e-20,
                stagnation_window: 0,
                acceleration,
                ..LmOptions::default()
            };
            let mut v = [-1.2, 1.0];
            let report = levenberg_marquardt(&Valley, &mut v, &options, &mut |_, _| {});
            assert_eq!(report.stop, StopReason::Converged, "{report:?}");
            assert!(
                (v[0] - 1.0).abs() < 1e-9 && (v[1] - 1.0).abs() < 1e-9,
                "{v:?}"
            );
            report.iterations
        };
        let (plain, accelerated) = (run(false), run(true));
        eprintln!("valley: {plain} plain, {accelerated} accelerated iterations");
        assert!(accelerated < plain, "{accelerated} vs {plain}");
    }

    fn course(error: f64, before: f64, remaining: usize) -> Course {
        Course {
            error,
            before,
            window: 10,
            remaining,
        }
    }

    #[test]
    fn a_slow_last_approach_is_on_course_when_the_iterations_left_suffice() {
        // 1 % per 10 iterations from 1.2e-5: 1e-5 after 19 windows, 190 iterations.
        assert!(course(1.2e-5, 1.2e-5 / 0.99, 2000).reaches(1e-5));
        assert!(course(1.2e-5, 1.2e-5 / 0.99, 190).reaches(1e-5));
        assert!(!course(1.2e-5, 1.2e-5 / 0.99, 170).reaches(1e-5));
    }

    #[test]
    fn far_above_the_threshold_or_not_falling_is_off_course() {
        // 0.5 % per window from 3e-4 needs about 6 800 iterations.
        assert!(!course(3e-4, 3e-4 / 0.995, 2000).reaches(1e-5));
        assert!(!course(1.1e-5, 1.1e-5, 2000).reaches(1e-5));
        assert!(!course(1.1e-5, 1.0e-5, 2000).reaches(1e-5));
        assert!(!course(1.1e-5, 1.2e-5, 2000).reaches(0.0));
    }
}
