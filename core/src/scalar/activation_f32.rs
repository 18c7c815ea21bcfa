//! The activation a(H) = 1.7159·tanh(2H/3) in `f32`, gain and amplitude folded in: ~32
//! instructions on a Cortex-M4F (libm's tanhf alone takes ~150), no table, and on hosts no
//! branch: a loop over lanes vectorizes.
//!
//! a(H) = A·(2^u − 1)/(2^u + 1) with A = 1.7159 and u = H·(4/3)/ln 2 (so 2^u = e^{4H/3}), for
//! either sign of H: below saturation no absolute value and no sign to restore. 2^u = 2ⁿ·2^r
//! with n = u rounded to the nearest integer by adding 1.5·2²³ (which leaves n in the low
//! mantissa bits: no float-to-integer conversion) and |r| ≤ ½; 2^r by a degree-6 polynomial
//! (minimax for relative error on [−½, ½]: 2·10⁻⁹); 2ⁿ by adding n to the exponent field.
//! Only `+ − × ÷` and bit operations on plain `f32`, never fused: every IEEE-754 target
//! (x86-64 SSE, Cortex-M4F FPv4) computes the same bits, so host and target agree exactly. A
//! NaN input is returned as it is (it takes the saturated path). The function is odd only to
//! within its error (|a(H) + a(−H)| ≤ 2.4·10⁻⁷ measured; a(−0) = +0), and monotone only to
//! within it too (neighbouring inputs can step down by up to 3.6·10⁻⁷, near H ≈ 12.5): the
//! exhaustive, ignored test in `core/tests/activation.rs` measures both.
//!
//! Accuracy: absolute error below 3.0·10⁻⁷ over all `f32` (measured 2.855·10⁻⁷ on a sweep of
//! every seventh `f32` in [−16, 16], and in the tests below and in `core/tests/activation.rs`):
//! the roundings of 2^u ± 1, of the quotient and of the product (≈ 2 ulp of A at worst) plus the
//! rounding of 2^r, propagated. The sign-symmetric form this replaced (A − 2A/(2^|u| + 1), the
//! sign restored from H) measured 2.13·10⁻⁷ for ~7 more instructions per neuron. Relative
//! accuracy is not a goal — near 0 the result is within 3·10⁻⁷ of a(H), not within an ulp.

/// A = 1.7159.
pub(crate) const AMPLITUDE: f32 = super::ACTIVATION_AMPLITUDE as f32;
/// (4/3)/ln 2: u = H·U_PER_H.
pub(crate) const U_PER_H: f32 = (2.0 * super::ACTIVATION_GAIN * core::f64::consts::LOG2_E) as f32;
/// Beyond this |u|, a(H) is within 2.6·10⁻⁸ of ±A (2A/2^27), and ±A is returned.
pub(crate) const SATURATION: f32 = 27.0;
/// 1.5·2²³: for |u| ≤ 2²², `u + ROUNDER` is u rounded to the nearest integer n (ties to even),
/// stored as ROUNDER's bits + n; ROUNDER's low 22 bits are zero, so those bits shifted left by
/// 23 are n·2²³ (mod 2³²), the exponent increment of 2ⁿ.
pub(crate) const ROUNDER: f32 = 12_582_912.0;
/// 2^r ≈ 1 + r·(c₁ + r·(c₂ + … + r·c₆)) for |r| ≤ ½, coefficients c₁…c₆ minimax for relative
/// error (2.0·10⁻⁹); c₁ rounds to ln 2 in `f32`.
pub(crate) const POLYNOMIAL: [f32; 6] = [
    core::f32::consts::LN_2,
    0.240_226_48,
    0.055_503_327,
    0.009_618_427,
    0.001_339_884_2,
    0.000_153_565_21,
];

/// Whether [`activation`] computes both paths and selects (so loops over lanes vectorize:
/// SSE on x86-64, NEON on AArch64) rather than branching past the polynomial when saturated
/// (cheaper on a Cortex-M, which has no vector unit: measured +4 % instructions for the torus
/// field + gradient, +8 % for the head, with the select). Both give the same bits; the
/// simulator tests compare the target's branch with the host's select.
const SELECT: bool = !cfg!(target_arch = "arm");

/// a(H) = 1.7159·tanh(2H/3) to 3.0·10⁻⁷ absolute.
#[inline]
pub(crate) fn activation(h: f32) -> f32 {
    let u = h * U_PER_H;
    // NaN counts as saturated and leaves through `limit`, unchanged. Written as "not below" so
    // that it is one unordered comparison (`>= || is_nan` compiled to two on the M4F).
    let magnitude = f32::from_bits(u.to_bits() & 0x7fff_ffff);
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    let saturated = !(magnitude < SATURATION);
    if SELECT {
        // The polynomial sees u clamped to the saturation point, where it is in range.
        let below = unsaturated(if saturated { SATURATION } else { u });
        if saturated { limit(h) } else { below }
    } else if saturated {
        // Out of line: the common path then falls through to its store (measured −2
        // instructions per neuron on the M4F).
        cold_limit(h)
    } else {
        unsaturated(u)
    }
}

/// ±A with the sign of `h`; `h` itself when it is NaN.
#[inline(always)]
fn limit(h: f32) -> f32 {
    if h.is_nan() {
        h
    } else {
        f32::from_bits(AMPLITUDE.to_bits() | (h.to_bits() & 0x8000_0000))
    }
}

/// [`limit`], kept out of the hot path.
#[cold]
#[inline(never)]
fn cold_limit(h: f32) -> f32 {
    limit(h)
}

/// A·(2^u − 1)/(2^u + 1) for |u| ≤ [`SATURATION`].
#[inline(always)]
fn unsaturated(u: f32) -> f32 {
    let rounded = u + ROUNDER;
    // |u| ≤ 27: n = rounded − ROUNDER exactly, and r = u − n is exact (|r| ≤ ½).
    let r = u - (rounded - ROUNDER);
    // Horner from c₆ down.
    let [lower @ .., highest] = POLYNOMIAL;
    let p = 1.0 + r * lower.iter().rev().fold(highest, |acc, &c| c + r * acc);
    // p ∈ [0.7, 1.42] and |n| ≤ 27: adding n to the exponent stays in the normal range. (A NaN
    // never gets here: its payload bits, shifted up, could make a finite value.)
    let e = f32::from_bits(p.to_bits().wrapping_add(rounded.to_bits() << 23));
    (e - 1.0) / (e + 1.0) * AMPLITUDE
}

#[cfg(test)]
mod tests {
    use super::activation;

    fn exact(h: f32) -> f64 {
        super::super::ACTIVATION_AMPLITUDE
            * libm::tanh(super::super::ACTIVATION_GAIN * f64::from(h))
    }

    /// Every 61st `f32` from 0 up to past saturation (19 million inputs, all exponents), both
    /// signs, against f64 libm, and the largest difference between a(H) and −a(−H).
    #[test]
    fn absolute_error_below_3e_7_everywhere() {
        let mut worst = 0.0_f64;
        let mut asymmetry = 0.0_f32;
        let end = 16.0_f32.to_bits();
        let mut bits = 0_u32;
        while bits <= end {
            let h = f32::from_bits(bits);
            for h in [h, -h] {
                worst = worst.max((f64::from(activation(h)) - exact(h)).abs());
            }
            asymmetry = asymmetry.max((activation(h) + activation(-h)).abs());
            bits += 61;
        }
        assert!(worst < 3.0e-7, "worst {worst:e}");
        assert!(asymmetry <= 4.8e-7, "asymmetry {asymmetry:e}");
    }

    #[test]
    fn special_values() {
        let amplitude = super::AMPLITUDE;
        assert_eq!(activation(27.0 / super::U_PER_H), amplitude);
        assert_eq!(activation(-1e30), -amplitude);
        assert_eq!(activation(0.0).to_bits(), 0.0_f32.to_bits());
        // The odd symmetry holds only to within the error: a(−0) is +0.
        assert_eq!(activation(-0.0).to_bits(), 0.0_f32.to_bits());
        assert_eq!(activation(f32::INFINITY), amplitude);
        assert_eq!(activation(f32::NEG_INFINITY), -amplitude);
        assert_eq!(activation(1e30), amplitude);
        assert!(activation(f32::NAN).is_nan());
        // A NaN comes back as it went in, payload and sign (its low bits must never reach an
        // exponent).
        for bits in [
            0x7fc0_0001,
            0x7f80_0001,
            0xffc0_0001,
            0x7fc0_01ff,
            0x7fc0_0100,
        ] {
            assert_eq!(
                activation(f32::from_bits(bits)).to_bits(),
                bits,
                "{bits:#x}"
            );
        }
        assert_eq!(activation(f32::MIN_POSITIVE), 0.0);
    }
}
