//! [`Scalar`] for Q16.16 fixed point (`fixed::types::I16F16`).
//!
//! Designed for a Cortex-M4 without relying on its FPU: products are 32×32→64-bit
//! (`SMULL`/`SMLAL`), dot products accumulate in Q32.32 and are rounded once, the activation is
//! a 641-entry table of a(H) for H in [0, 10], stored as (value, rise) segments over both
//! signs, with linear interpolation (no division anywhere in a neuron). Every operation saturates at the ends of
//! the range instead of wrapping.

use super::activation_table::{FRACTION_BITS, LAST, SEGMENTS};
use super::{ACTIVATION_AMPLITUDE, ACTIVATION_GAIN, Scalar, ScalarKind};

/// Signed Q16.16 fixed point: range [−32768, 32768), resolution 2⁻¹⁶ ≈ 1.5·10⁻⁵.
pub type Q16 = fixed::types::I16F16;

const ONE_BITS: i64 = 1 << 16;
const HALF_BITS: i64 = 1 << 15;

const fn q(value: f64) -> i32 {
    (value * 65536.0 + 0.5) as i32
}
pub(crate) const SLOPE_OFFSET: i32 = q(ACTIVATION_GAIN * ACTIVATION_AMPLITUDE);
pub(crate) const SLOPE_SQUARE: i32 = q(ACTIVATION_GAIN / ACTIVATION_AMPLITUDE);
const CURVATURE: i32 = q(2.0 * ACTIVATION_GAIN / ACTIVATION_AMPLITUDE);

/// Saturates a Q16.16 value held in an `i64` to `i32` range: one comparison in the common
/// case (the value fits), which matters in every neuron's epilogue on a Cortex-M4.
#[inline(always)]
fn saturate(bits: i64) -> Q16 {
    let low = bits as i32;
    Q16::from_bits(if i64::from(low) == bits {
        low
    } else if bits < 0 {
        i32::MIN
    } else {
        i32::MAX
    })
}

/// Rounds a Q32.32 value to Q16.16 (round half up), saturating.
///
/// The add cannot overflow: accumulators stay below 2⁶² in magnitude (see
/// [`Scalar::MAX_PARAMETER`] for Q16: at most 2·16 products below 2⁵⁷ plus a bias), and a
/// product of two Q16.16 values is below 2⁶².
#[inline(always)]
fn round_q32(acc: i64) -> Q16 {
    saturate(acc.wrapping_add(HALF_BITS) >> 16)
}

/// round(x·y/2³²), ties up: the high word of a rounded 32×32→64-bit product (`smmulr` on
/// ARMv7E-M).
#[inline(always)]
fn high_word_rounded(x: i32, y: i32) -> i32 {
    ((i64::from(x) * i64::from(y) + (1 << 31)) >> 32) as i32
}

/// a′ = SLOPE_OFFSET − round(SLOPE_SQUARE·round(a²)) in bits, for |a| ≤ 2 (every activation
/// output: |a| ≤ 1.7159), where nothing can saturate: exactly the saturating
/// `SLOPE_OFFSET − SLOPE_SQUARE·(a·a)`.
///
/// Each round(x·y/2¹⁶) is the rounded high word of (x·2^k)·(y·2^(16−k)): one `smmulr` on the
/// M4 instead of a 64-bit product, rounding and shift. |a| ≤ 2 keeps a·2⁸ below 2²⁶; a² ≤ 4
/// in bits is below 2¹⁹, and SLOPE_SQUARE·2¹⁶ below 2³¹ (0.3885·2³²).
#[inline(always)]
fn slope_bits(a: i32) -> i32 {
    let scaled_a = a << 8;
    let square = high_word_rounded(scaled_a, scaled_a);
    SLOPE_OFFSET - high_word_rounded(SLOPE_SQUARE << 16, square)
}

/// a(H) for H = `bits`·2⁻¹⁶: the table entry below |H| interpolated linearly towards the next,
/// the sign restored (odd symmetry).
#[inline(always)]
fn activation_bits(bits: i32) -> i32 {
    let magnitude = bits.unsigned_abs();
    let value = if magnitude >= (LAST as u32) << FRACTION_BITS {
        saturated_activation()
    } else {
        interpolate(magnitude)
    };
    if bits < 0 { -value } else { value }
}

/// a(|H|) for |H| = `magnitude`·2⁻¹⁶ (callers pass |H| ≤ 10): the segment of the table's upper
/// half below |H| (its index clamped to the last, which is flat), interpolated and rounded.
#[inline(always)]
fn interpolate(magnitude: u32) -> i32 {
    let index = (magnitude >> FRACTION_BITS).min(LAST as u32) as usize;
    let [lower, rise] = SEGMENTS.get(LAST + index).copied().unwrap_or([0, 0]);
    let fraction = (magnitude & ((1 << FRACTION_BITS) - 1)) as i32;
    lower + ((rise * fraction + (1 << (FRACTION_BITS - 1))) >> FRACTION_BITS)
}

/// `delta[i] ← times_slope(delta[i], a[i])` for each bit i set in `slow`: what a chain-rule
/// kernel left outside its fast range, finished on the portable (saturating) path.
#[inline(always)]
pub(crate) fn finish_times_slope<const N: usize>(delta: &mut [Q16; N], a: &[Q16; N], slow: u32) {
    if slow != 0 {
        for (i, (d, &a)) in delta.iter_mut().zip(a).enumerate() {
            if slow.checked_shr(i as u32).unwrap_or(0) & 1 != 0 {
                *d = <Q16 as crate::implicit::Activation>::times_slope(*d, a);
            }
        }
    }
}

/// a(H) in bits for |H| ≥ 10, where the table has saturated.
#[inline(always)]
fn saturated_activation() -> i32 {
    SEGMENTS.get(2 * LAST).map_or(0, |&[value, _]| value)
}

impl Scalar for Q16 {
    type Acc = i64;

    const KIND: ScalarKind = ScalarKind::Q16_16;
    const ZERO: Self = Q16::ZERO;
    const ONE: Self = Q16::ONE;
    /// 1024: with |parameter| ≤ 2¹⁰ (2²⁶ in bits) and inputs below 2³¹ bits, each product is
    /// below 2⁵⁷, and a neuron's at most 2·16 inputs plus its bias stay below 2⁶².
    const MAX_PARAMETER: f32 = 1024.0;

    #[inline]
    fn from_f32(value: f32) -> Option<Self> {
        (value.is_finite() && value.abs() <= Self::MAX_PARAMETER).then(|| Q16::from_num(value))
    }
    #[inline]
    fn from_f32_saturating(value: f32) -> Self {
        if value.is_nan() {
            Q16::ZERO
        } else {
            Q16::saturating_from_num(value)
        }
    }
    #[inline]
    fn from_stored(bytes: [u8; 4], stored: ScalarKind) -> Option<Self> {
        match stored {
            ScalarKind::F32 => Self::from_f32(f32::from_le_bytes(bytes)),
            ScalarKind::Q16_16 => {
                let value = Q16::from_bits(i32::from_le_bytes(bytes));
                (value.to_bits().unsigned_abs() <= (Self::MAX_PARAMETER as u32) << 16)
                    .then_some(value)
            }
            ScalarKind::F64 => None,
        }
    }
    #[inline]
    fn to_le_bytes(self) -> [u8; 4] {
        self.to_bits().to_le_bytes()
    }
    #[inline]
    fn to_f32(self) -> f32 {
        self.to_num()
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self.to_num()
    }

    #[inline]
    fn add(self, other: Self) -> Self {
        self.saturating_add(other)
    }
    #[inline]
    fn sub(self, other: Self) -> Self {
        self.saturating_sub(other)
    }
    #[inline]
    fn mul(self, other: Self) -> Self {
        round_q32(i64::from(self.to_bits()) * i64::from(other.to_bits()))
    }
    #[inline]
    fn times_power_of_two(self, exponent: i8) -> Self {
        let bits = i64::from(self.to_bits());
        if exponent >= 0 {
            // Any non-zero value saturates by a shift of 32; 2³¹·2³² still fits an i64.
            saturate(bits << exponent.unsigned_abs().min(32))
        } else {
            let shift = exponent.unsigned_abs().min(40);
            saturate((bits + (1_i64 << (shift - 1))) >> shift)
        }
    }
    #[inline]
    fn neg(self) -> Self {
        self.saturating_neg()
    }
    #[inline]
    fn abs(self) -> Self {
        self.saturating_abs()
    }

    #[inline(always)]
    fn to_acc(self) -> i64 {
        // `i64::from(bits) << 16` as its two words (high = bits >> 16, low = bits << 16): the
        // M4 code then has one shift per word instead of four instructions for the 64-bit shift.
        let bits = self.to_bits();
        (i64::from(bits >> 16) << 32) | i64::from((bits << 16) as u32)
    }
    #[inline(always)]
    fn mac(acc: i64, a: Self, b: Self) -> i64 {
        // Bounded by MAX_PARAMETER (see there); wrapping_add keeps the M4 code to one SMLAL
        // and cannot actually wrap within that bound.
        acc.wrapping_add(i64::from(a.to_bits()) * i64::from(b.to_bits()))
    }
    #[inline(always)]
    fn from_acc(acc: i64) -> Self {
        round_q32(acc)
    }

    #[inline(always)]
    fn activation_from_acc(acc: i64) -> Self {
        // Exactly `activation(from_acc(acc))`: when the high word of the rounded accumulator
        // (the integer part of H, rounded down) lies in [−10, 10), H fits `i32` unsaturated;
        // otherwise |H| ≥ 10, where the table has saturated (index ≥ LAST) whatever the
        // rounding and saturation would have given.
        let rounded = acc.wrapping_add(HALF_BITS);
        let high = (rounded >> 32) as i32;
        Q16::from_bits(if (high as u32).wrapping_add(10) < 20 {
            // |H| ≤ 10: within the table, no second range check.
            let bits = (rounded >> 16) as i32;
            let value = interpolate(bits.unsigned_abs());
            if bits < 0 { -value } else { value }
        } else {
            let last = saturated_activation();
            if high < 0 { -last } else { last }
        })
    }

    #[inline]
    fn sqrt(self) -> Self {
        let bits = self.to_bits();
        if bits <= 0 {
            return Q16::ZERO;
        }
        // sqrt(b / 2¹⁶) · 2¹⁶ = sqrt(b · 2¹⁶)
        saturate(isqrt((bits as u64) << 16) as i64)
    }
    #[inline]
    fn recip(self) -> Option<Self> {
        let bits = i64::from(self.to_bits());
        if bits == 0 {
            return None;
        }
        // round(2³² / b), sign-aware
        let numerator = (ONE_BITS * ONE_BITS) + bits.abs() / 2;
        let magnitude = numerator / bits.abs();
        let value = if bits < 0 { -magnitude } else { magnitude };
        i32::try_from(value).ok().map(Q16::from_bits)
    }

    #[inline]
    fn exp(self) -> Self {
        super::exp_q16::exp(self)
    }
    #[inline]
    fn quotient(numerator: i64, denominator: i64) -> Self {
        // The denominator is a multiple of 2¹⁶ in Q32.32 (a sum of Q16.16 values), so
        // d = denominator / 2¹⁶ is exact and numerator / d is the quotient in Q16.16 bits.
        let d = denominator >> 16;
        if d == 0 {
            return Q16::ZERO;
        }
        let (q, r) = (numerator.wrapping_div(d), numerator.wrapping_rem(d));
        // Round half away from zero; |2r| < 2|d| ≤ 2⁴⁸ cannot overflow.
        let away = 2 * r.unsigned_abs() >= d.unsigned_abs();
        let q = if !away {
            q
        } else if (r < 0) == (d < 0) {
            q.saturating_add(1)
        } else {
            q.saturating_sub(1)
        };
        saturate(q)
    }
}

/// ⌊√n⌋ for a 64-bit integer, by the bit-by-bit method (no division, fixed 32 steps).
fn isqrt(n: u64) -> u64 {
    let mut remainder = n;
    let mut root = 0_u64;
    let mut bit = 1_u64 << 62;
    while bit > remainder {
        bit >>= 2;
    }
    while bit != 0 {
        if remainder >= root + bit {
            remainder -= root + bit;
            root = (root >> 1) + bit;
        } else {
            root >>= 1;
        }
        bit >>= 2;
    }
    root
}

impl crate::implicit::Activation for Q16 {
    #[inline]
    fn activation(h: Self) -> Self {
        Q16::from_bits(activation_bits(h.to_bits()))
    }
    #[inline]
    fn activation_slope(a: Self) -> Self {
        // For |a| ≤ 2 (every activation output: |a| ≤ 1.7159) nothing here can saturate, so
        // exact integer products give the saturating a·a, SLOPE_SQUARE·(a·a) and the
        // difference. Other inputs (not produced by `activation`) take the saturating path.
        let bits = i64::from(a.to_bits());
        if bits.unsigned_abs() > 2 << 16 {
            let square = a.mul(a);
            return Q16::from_bits(SLOPE_OFFSET).sub(Q16::from_bits(SLOPE_SQUARE).mul(square));
        }
        Q16::from_bits(slope_bits(bits as i32))
    }
    #[inline(always)]
    fn times_slope(delta: Self, a: Self) -> Self {
        // The common case as two rounded high words: for |a| ≤ 2 the slope is `slope_bits`
        // (|a′| ≤ 1.144, below 2¹⁷ in bits), and for |δ| < 2¹³ (2²⁹ in bits) the product
        // round(δ·a′/2¹⁶) is the rounded high word of (δ·2²)·(a′·2¹⁴), both factors below 2³¹,
        // and cannot saturate (|δ·a′| < 2¹⁴). The same bits as `mul`, which rounds
        // (δ·a′ + 2¹⁵)/2¹⁶ down: (δ·a′·2¹⁶ + 2³¹)/2³² is that quotient.
        let (delta_bits, a_bits) = (delta.to_bits(), a.to_bits());
        // |a| ≤ 2·2¹⁶ and |δ| < 2²⁹ as one add and one unsigned compare each.
        let a_in_range = a_bits.wrapping_add(2 << 16) as u32 <= 4 << 16;
        let delta_in_range = (delta_bits.wrapping_add(1 << 29) as u32) < 1 << 30;
        if a_in_range && delta_in_range {
            let slope = slope_bits(a_bits);
            return Q16::from_bits(high_word_rounded(delta_bits << 2, slope << 14));
        }
        delta.mul(Self::activation_slope(a))
    }
    #[inline]
    fn activation_curvature(a: Self, slope: Self) -> Self {
        Q16::from_bits(CURVATURE).mul(a).mul(slope).neg()
    }
}

#[cfg(test)]
mod tests {
    use super::{
        FRACTION_BITS, HALF_BITS, LAST, Q16, SLOPE_OFFSET, SLOPE_SQUARE, activation_bits, isqrt,
    };
    use crate::implicit::Activation;
    use crate::scalar::Scalar;
    use crate::scalar::activation_table::TABLE;

    /// The slope's `smmulr` form equals the 64-bit formula it replaced, for every a in [−2, 2].
    #[test]
    fn slope_by_high_words_equals_the_64_bit_formula() {
        for bits in -(2_i64 << 16)..=(2 << 16) {
            let square = (bits * bits + HALF_BITS) >> 16;
            let scaled = (i64::from(SLOPE_SQUARE) * square + HALF_BITS) >> 16;
            let expected = (i64::from(SLOPE_OFFSET) - scaled) as i32;
            let slope = Q16::activation_slope(Q16::from_bits(bits as i32));
            assert_eq!(slope.to_bits(), expected, "a bits {bits}");
        }
    }

    /// The segment lookup gives the bits of the checked 641-entry lookup it replaced, for every
    /// H below 32 in magnitude and at the ends of the range.
    #[test]
    #[allow(clippy::indexing_slicing)] // the reference as it was written, with its checks
    fn segment_lookup_equals_the_checked_one() {
        let checked = |bits: i32| -> i32 {
            let magnitude = bits.unsigned_abs();
            let index = (magnitude >> FRACTION_BITS) as usize;
            let table = &TABLE[..=LAST];
            let value = if index >= LAST {
                table[LAST]
            } else {
                let (lower, upper) = (table[index], table[index + 1]);
                let fraction = (magnitude & ((1 << FRACTION_BITS) - 1)) as i32;
                lower + (((upper - lower) * fraction + (1 << (FRACTION_BITS - 1))) >> FRACTION_BITS)
            };
            if bits < 0 { -value } else { value }
        };
        let extremes = [i32::MIN, i32::MIN + 1, i32::MAX, i32::MAX - 1];
        for bits in (-(1 << 21)..=(1 << 21)).chain(extremes) {
            assert_eq!(activation_bits(bits), checked(bits), "H bits {bits}");
        }
    }

    /// The accumulator built from two words equals the 64-bit shift.
    #[test]
    fn to_acc_is_the_value_shifted_into_q32_32() {
        let mut x = 0x2545_F491_4F6C_DD1D_u64;
        let spread = core::iter::repeat_with(|| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x as i32
        });
        let edges = [
            0,
            1,
            -1,
            i32::MAX,
            i32::MIN,
            0xFFFF,
            -0x10000,
            0x8000,
            -0x8000,
        ];
        for bits in edges
            .into_iter()
            .chain((-70_000..70_000).step_by(7))
            .chain(spread.take(100_000))
        {
            assert_eq!(
                Q16::from_bits(bits).to_acc(),
                i64::from(bits) << 16,
                "bits {bits}"
            );
        }
    }

    /// The fused backward step equals `delta.mul(activation_slope(a))` for every a in
    /// [−2.5, 2.5] (the fast path ends at 2) against deltas around every boundary it tests
    /// (|δ| = 2²⁹ in bits, 0, the i32 range) and spread over the range.
    #[test]
    fn times_slope_is_delta_times_the_slope() {
        let edge = 1_i32 << 29;
        let mut deltas = [0_i32; 82];
        let fixed = [
            0,
            1,
            -1,
            i32::MAX,
            i32::MIN,
            i32::MIN + 1,
            1 << 16,
            -(1 << 16),
        ];
        let edges = (-3..=3).flat_map(|d| [edge + d, -edge + d]);
        let mut x = 0x2545_F491_4F6C_DD1D_u64;
        let spread = core::iter::repeat_with(|| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x as i32) >> (x % 31)
        });
        for (slot, d) in deltas
            .iter_mut()
            .zip(fixed.into_iter().chain(edges).chain(spread))
        {
            *slot = d;
        }
        for a_bits in -(5_i32 << 15)..=(5 << 15) {
            let a = Q16::from_bits(a_bits);
            for &d in &deltas {
                let delta = Q16::from_bits(d);
                assert_eq!(
                    Q16::times_slope(delta, a),
                    delta.mul(Q16::activation_slope(a)),
                    "delta bits {d}, a bits {a_bits}"
                );
            }
        }
    }

    /// The fused epilogue equals rounding, saturating and then the activation, around every
    /// boundary it special-cases (|H| = 10, the i32 range) and on a sweep in between.
    #[test]
    fn activation_from_acc_is_activation_of_from_acc() {
        let check = |acc: i64| {
            assert_eq!(
                Q16::activation_from_acc(acc),
                Q16::activation(Q16::from_acc(acc)),
                "acc {acc}"
            );
        };
        for h in [0_i64, 10, 32768, 1 << 29] {
            for sign in [1, -1] {
                let centre = sign * (h << 32);
                (-70_000..70_000).for_each(|delta| check(centre + delta));
            }
        }
        [i64::MAX / 4, i64::MIN / 4, (1 << 47) - 1, -(1 << 47)]
            .into_iter()
            .for_each(check);
        let mut x = 0x9E37_79B9_7F4A_7C15_u64;
        for _ in 0..200_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            check((x as i64) >> (x % 40));
        }
    }

    #[test]
    fn isqrt_is_floor_sqrt() {
        for n in (0..100_000_u64).chain([u64::MAX, u64::MAX - 1, 1 << 62, (1 << 32) - 1]) {
            let r = isqrt(n);
            assert!(r * r <= n, "n = {n}");
            assert!(
                (r + 1).checked_mul(r + 1).is_none_or(|sq| sq > n),
                "n = {n}"
            );
        }
    }
}
