//! e^x for `f32` from IEEE basic operations only (shared with the fast tanh).
//!
//! e^y = 2ⁿ·e^r with n = round(y/ln 2) and |r| ≤ ln2/2 (Cody–Waite: ln 2 split in two so n·ln2
//! is exact), e^r from its degree-7 Taylor polynomial (truncation < 5·10⁻⁹ relative), and 2ⁿ
//! added to the exponent bits. Only `+ − × ÷`, conversions and bit operations, never fused:
//! every IEEE-754 target computes the same bits, so host and target agree exactly.
//!
//! Accuracy: relative error below 2.5·10⁻⁷ (≈ 2 ulp) on [−86, 88] (measured on a dense sweep in
//! the tests below); below −86 the result is flushed to 0 (e^−86 ≈ 4.4·10⁻³⁸, the subnormal
//! range is not produced), above 88 it is +∞, NaN gives NaN.

/// ln 2 rounded to 16 significant bits: n·LN2_HI is exact for |n| < 2⁸.
pub(crate) const LN2_HI: f32 = 0.693_145_75;
/// ln 2 − LN2_HI.
pub(crate) const LN2_LO: f32 = 1.428_606_8e-6;
/// 1/ln 2.
pub(crate) const INV_LN2: f32 = core::f32::consts::LOG2_E;
/// Above this, [`exp`] returns +∞ (e^88 ≈ 1.65·10³⁸ is the largest result it forms).
pub(crate) const OVERFLOW: f32 = 88.0;
/// Below this, [`exp`] returns 0.
pub(crate) const UNDERFLOW: f32 = -86.0;

/// e^r for |r| ≤ ln2/2 (degree-7 Taylor polynomial, Horner form).
#[inline(always)]
pub(crate) fn exp_reduced(r: f32) -> f32 {
    1.0 + r
        * (1.0
            + r * (0.5
                + r * (1.0 / 6.0
                    + r * (1.0 / 24.0
                        + r * (1.0 / 120.0 + r * (1.0 / 720.0 + r * (1.0 / 5040.0)))))))
}

/// p·2ⁿ by adding n to the exponent bits; p ∈ [0.7, 1.42] and the result must be normal.
#[inline(always)]
pub(crate) fn scale_by_power_of_two(p: f32, n: i32) -> f32 {
    f32::from_bits(p.to_bits().wrapping_add((n as u32) << 23))
}

/// e^x (see the module documentation for the accuracy and the special values).
#[inline]
pub(crate) fn exp(x: f32) -> f32 {
    if x.is_nan() {
        return x;
    }
    if x > OVERFLOW {
        return f32::INFINITY;
    }
    if x < UNDERFLOW {
        return 0.0;
    }
    // t ∈ [−124.6, 127.5]: truncation toward zero, corrected to a floor, rounds x/ln2.
    let t = x * INV_LN2 + 0.5;
    let mut n = t as i32;
    if n as f32 > t {
        n -= 1;
    }
    let nf = n as f32;
    let r = (x - nf * LN2_HI) - nf * LN2_LO;
    // n ∈ [−124, 127] and p ∈ [0.7, 1.42]: the biased exponent stays in [2, 254].
    scale_by_power_of_two(exp_reduced(r), n)
}

#[cfg(test)]
mod tests {
    use super::exp;

    /// Every 29th `f32` of [−86, 88] (both signs swept separately), against f64 libm.
    #[test]
    fn relative_error_below_2_5e_7() {
        let mut worst = 0.0_f64;
        for (start, end) in [(0.0_f32, 88.0_f32), (-0.0, -86.0)] {
            let (mut bits, last) = (start.to_bits(), end.to_bits());
            while bits <= last {
                let x = f32::from_bits(bits);
                let exact = libm::exp(f64::from(x));
                worst = worst.max(((f64::from(exp(x)) - exact) / exact).abs());
                bits += 29;
            }
        }
        assert!(worst < 2.5e-7, "worst relative error {worst:e}");
    }

    #[test]
    fn special_values() {
        assert_eq!(exp(0.0), 1.0);
        assert_eq!(exp(-0.0), 1.0);
        assert_eq!(exp(88.5), f32::INFINITY);
        assert_eq!(exp(f32::INFINITY), f32::INFINITY);
        assert_eq!(exp(-86.5), 0.0);
        assert_eq!(exp(f32::NEG_INFINITY), 0.0);
        assert!(exp(f32::NAN).is_nan());
        assert!(exp(88.0).is_finite() && exp(-86.0) > 0.0);
    }
}
