//! The four activation functions of §5.1 (Eqs. 9–12) with their derivatives.

/// A hidden-layer activation σ.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Activation {
    /// Log-sig, Eq. 9: σ(a) = 1/(1 + e⁻ᵃ).
    LogSig,
    /// Tan-sig, Eq. 10: σ(a) = 2/(1 + e⁻ᵃ) − 1 (= tanh(a/2); the default, C^∞ surfaces).
    #[default]
    TanSig,
    /// Rad-bas, Eq. 11: σ(a) = e^(−a²).
    RadBas,
    /// Tri-bas, Eq. 12: σ(a) = 1 − |a| for |a| ≤ 1, else 0 (C⁰: piecewise-planar surfaces).
    TriBas,
}

impl Activation {
    /// All four, in the paper's order.
    pub const ALL: [Activation; 4] = [
        Activation::LogSig,
        Activation::TanSig,
        Activation::RadBas,
        Activation::TriBas,
    ];

    /// σ(a).
    pub fn value(self, a: f64) -> f64 {
        match self {
            Activation::LogSig => 1.0 / (1.0 + (-a).exp()),
            Activation::TanSig => 2.0 / (1.0 + (-a).exp()) - 1.0,
            Activation::RadBas => (-a * a).exp(),
            Activation::TriBas => (1.0 - a.abs()).max(0.0),
        }
    }

    /// σ′(a) (for tri-bas the one-sided slope −sign(a) inside (−1, 1), 0 outside and at 0).
    pub fn derivative(self, a: f64) -> f64 {
        self.value_and_derivative(a).1
    }

    /// (σ(a), σ′(a)) with one exponential for the sigmoids (the same values as [`Self::value`]
    /// and [`Self::derivative`]).
    pub fn value_and_derivative(self, a: f64) -> (f64, f64) {
        let s = self.value(a);
        let slope = match self {
            Activation::LogSig => s * (1.0 - s),
            Activation::TanSig => 0.5 * (1.0 - s * s),
            Activation::RadBas => -2.0 * a * (-a * a).exp(),
            Activation::TriBas => {
                if a.abs() < 1.0 && a != 0.0 {
                    -a.signum()
                } else {
                    0.0
                }
            }
        };
        (s, slope)
    }

    /// The paper's name.
    pub fn name(self) -> &'static str {
        match self {
            Activation::LogSig => "log-sig",
            Activation::TanSig => "tan-sig",
            Activation::RadBas => "rad-bas",
            Activation::TriBas => "tri-bas",
        }
    }
}
