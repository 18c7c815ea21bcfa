//! The four hidden-layer activations of Yumer & Kara §5.1 (Eqs. 9–12) and their slopes, in any
//! [`Scalar`], from [`Scalar::exp`], one quotient and basic operations: the same bits on the
//! host and on the target.

use crate::scalar::Scalar;

/// A hidden-layer activation σ, with its blob code.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum Activation {
    /// Log-sig, Eq. 9: σ(a) = 1/(1 + e⁻ᵃ).
    LogSig,
    /// Tan-sig, Eq. 10: σ(a) = 2/(1 + e⁻ᵃ) − 1 (= tanh(a/2)).
    TanSig,
    /// Rad-bas, Eq. 11: σ(a) = e^(−a²).
    RadBas,
    /// Tri-bas, Eq. 12: σ(a) = 1 − |a| for |a| ≤ 1, else 0.
    TriBas,
}

impl Activation {
    /// The blob code: 0 log-sig, 1 tan-sig, 2 rad-bas, 3 tri-bas.
    pub const fn code(self) -> u8 {
        match self {
            Activation::LogSig => 0,
            Activation::TanSig => 1,
            Activation::RadBas => 2,
            Activation::TriBas => 3,
        }
    }

    /// The activation a blob code names.
    pub const fn from_code(code: u8) -> Option<Self> {
        match code {
            0 => Some(Activation::LogSig),
            1 => Some(Activation::TanSig),
            2 => Some(Activation::RadBas),
            3 => Some(Activation::TriBas),
            _ => None,
        }
    }

    /// The largest valid code.
    pub(crate) const LAST_CODE: u8 = 3;

    /// σ(a) and, when `SLOPE`, σ′(a) (else 0). Tri-bas takes the slope −sign(a) inside
    /// (−1, 1), 0 at a = 0 and outside, like the trainer.
    ///
    /// The sigmoids are evaluated from e = e^(−|a|) ∈ (0, 1], so nothing overflows for any
    /// input: log-sig = 1/(1 + e) for a ≥ 0 and e/(1 + e) below, tan-sig = ±(1 − e)/(1 + e);
    /// each is one rounded quotient. Their slopes come from the value: σ(1 − σ) and
    /// (1 − σ²)/2.
    #[inline(always)]
    pub(crate) fn apply<S: Scalar, const SLOPE: bool>(self, a: S) -> (S, S) {
        let half = S::from_f32_saturating(0.5);
        match self {
            Activation::LogSig | Activation::TanSig => {
                let negative = a < S::ZERO;
                let e = a.abs().neg().exp();
                let denominator = S::ONE.add(e).to_acc();
                let value = if self == Activation::LogSig {
                    let numerator = if negative { e } else { S::ONE };
                    S::quotient(numerator.to_acc(), denominator)
                } else {
                    let magnitude = S::quotient(S::ONE.sub(e).to_acc(), denominator);
                    if negative { magnitude.neg() } else { magnitude }
                };
                let slope = match (SLOPE, self) {
                    (false, _) => S::ZERO,
                    (true, Activation::LogSig) => value.mul(S::ONE.sub(value)),
                    (true, _) => half.mul(S::ONE.sub(value.mul(value))),
                };
                (value, slope)
            }
            Activation::RadBas => {
                let value = a.mul(a).neg().exp();
                let slope = if SLOPE {
                    a.add(a).mul(value).neg()
                } else {
                    S::ZERO
                };
                (value, slope)
            }
            Activation::TriBas => {
                let magnitude = a.abs();
                if magnitude < S::ONE {
                    let slope = if !SLOPE || a == S::ZERO {
                        S::ZERO
                    } else if a > S::ZERO {
                        S::ONE.neg()
                    } else {
                        S::ONE
                    };
                    (S::ONE.sub(magnitude), slope)
                } else {
                    // Also NaN: no slope, value 0 (NaN is not below 1).
                    (S::ZERO, S::ZERO)
                }
            }
        }
    }
}
