//! The activation a(H) = 1.7159·tanh(2H/3) and its derivatives, in `f64` (the reference).

use neurosurf_core::scalar::{ACTIVATION_AMPLITUDE as AMPLITUDE, ACTIVATION_GAIN as GAIN};

/// a(H), a′(H) and a″(H) at once.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Activation {
    /// a(H).
    pub value: f64,
    /// a′(H) = 1.7159·(2/3)·(1 − tanh²).
    pub slope: f64,
    /// a″(H) = −2·(2/3)·tanh·a′(H).
    pub curvature: f64,
}

/// Evaluates the activation and its first two derivatives at `h`.
///
/// ```
/// let a = neurosurf_trainer::implicit::activation(1.0);
/// assert!((a.value - 1.7159 * (2.0_f64 / 3.0).tanh()).abs() < 1e-15);
/// ```
#[inline]
pub fn activation(h: f64) -> Activation {
    let t = (GAIN * h).tanh();
    let slope = AMPLITUDE * GAIN * (1.0 - t * t);
    Activation {
        value: AMPLITUDE * t,
        slope,
        curvature: -2.0 * GAIN * t * slope,
    }
}

#[cfg(test)]
mod tests {
    use super::activation;

    #[test]
    fn derivatives_match_finite_differences() {
        for i in -40..=40 {
            let h = f64::from(i) * 0.25;
            let e = 1e-5;
            let (lo, mid, hi) = (activation(h - e), activation(h), activation(h + e));
            assert!(
                ((hi.value - lo.value) / (2.0 * e) - mid.slope).abs() < 1e-9,
                "h = {h}"
            );
            assert!(
                ((hi.slope - lo.slope) / (2.0 * e) - mid.curvature).abs() < 1e-9,
                "h = {h}"
            );
        }
    }
}
