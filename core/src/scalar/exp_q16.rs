//! e^x in Q16.16 from integer operations only: deterministic on every target, no table.
//!
//! x·log₂e = k + f (k = ⌊·⌋, f ∈ [0, 1) in Q30, from one 32×32→64-bit product), 2^f =
//! e^{f·ln2} from its degree-8 Taylor polynomial in Q30 (truncation < 1.1·10⁻⁷ relative, each
//! Horner step rounded to 2⁻³⁰), then one rounding shift by 14 − k. Results below half an LSB
//! round to 0 (x < −11.8) and results beyond the range saturate to [`Q16::MAX`] (x ≥ 10.3972);
//! nothing overflows for any input.
//!
//! Accuracy: within 0.5 LSB + 2.5·10⁻⁷·e^x of the exact e^x at the Q16.16 input, and
//! monotone (measured over every input from −11.8 to 10.4 and a sweep of the rest in
//! `core/tests/caoen_scalar.rs`: at most 0.503 LSB for x ≤ 0).

use super::Q16;

/// log₂e in Q30 (1 549 082 005 < 2³¹).
const LOG2_E_Q30: i64 = 1_549_082_005;
/// ln 2 in Q30.
const LN2_Q30: i64 = 744_261_118;
/// 1/n! in Q30 for n = 0 … 8.
const INVERSE_FACTORIALS_Q30: [i64; 9] = [
    1 << 30,
    1 << 30,
    1 << 29,
    178_956_971,
    44_739_243,
    8_947_849,
    1_491_308,
    213_044,
    26_631,
];

/// `value · 2⁻shift`, rounded half up (shift ≥ 1).
#[inline(always)]
fn round_shift(value: i64, shift: u32) -> i64 {
    (value + (1 << (shift - 1))) >> shift
}

/// e^x, saturating (see the module documentation).
#[inline]
pub(crate) fn exp(x: Q16) -> Q16 {
    // Q16 · Q30 = Q46; |x bits| < 2³¹ so the product stays below 2⁶².
    let y = i64::from(x.to_bits()) * LOG2_E_Q30;
    let k = y >> 46;
    if k >= 15 {
        return Q16::MAX;
    }
    if k < -17 {
        return Q16::ZERO;
    }
    // f ∈ [0, 2³⁰), u = f·ln2 ∈ [0, 0.694) in Q30.
    let f = (y - (k << 46)) >> 16;
    let u = round_shift(f * LN2_Q30, 30);
    let mut p = 0_i64;
    for &c in INVERSE_FACTORIALS_Q30.iter().rev() {
        // p < 2³¹ and u < 2³⁰: the product stays below 2⁶¹.
        p = c + round_shift(p * u, 30);
    }
    // p = 2^f ∈ [2³⁰, 2³¹) in Q30; the result is p·2^k in Q16: shift right by 14 − k ∈ [0, 31].
    let shift = (14 - k) as u32;
    let bits = if shift == 0 { p } else { round_shift(p, shift) };
    Q16::from_bits(i32::try_from(bits).unwrap_or(i32::MAX))
}
