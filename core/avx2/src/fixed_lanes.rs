//! The AVX2 kernels for eight-lane Q16.16 batches: every product exact in a 64-bit lane, every
//! rounding, saturation and table lookup the core's portable Q16.16 code does, in its order.

#![allow(unsafe_code)]

use core::arch::x86_64::{
    __m256i, _mm256_abs_epi32, _mm256_add_epi32, _mm256_add_epi64, _mm256_and_si256,
    _mm256_blend_epi32, _mm256_blendv_epi8, _mm256_cmpeq_epi32, _mm256_cmpgt_epi32,
    _mm256_i32gather_epi32, _mm256_loadu_si256, _mm256_min_epu32, _mm256_mul_epi32,
    _mm256_mullo_epi32, _mm256_set1_epi32, _mm256_set1_epi64x, _mm256_setzero_si256,
    _mm256_slli_epi32, _mm256_slli_epi64, _mm256_srai_epi32, _mm256_srli_epi64,
    _mm256_storeu_si256, _mm256_sub_epi32,
};

use crate::lanes::{available, fits_transposed};

/// One Q16.16 neuron (or input) of eight points, as bits.
pub type FixedLanes = [i32; 8];

/// The core's Q16.16 activation table: `segments[last + k]` = [a(k·2^−bits), rise] for the
/// segment from k, both as Q16.16 bits; |H| from `last` segments on is saturated.
#[derive(Copy, Clone, Debug)]
pub struct FixedTable<'a> {
    /// The segments of both signs, `2·last + 1` of them.
    pub segments: &'a [[i32; 2]],
    /// Index of H = 0.
    pub last: usize,
    /// Bits of H below one segment (H's Q16.16 bits >> `fraction_bits` is the segment).
    pub fraction_bits: u32,
}

/// The Q16.16 chain rule through the activation: a′ = offset − round(square·round(a²)), as
/// the core's `slope_bits` (bits).
#[derive(Copy, Clone, Debug)]
pub struct FixedSlope {
    /// a′ at a = 0, bits.
    pub offset: i32,
    /// The factor of a², bits.
    pub square: i32,
}

#[inline(always)]
fn load(x: &FixedLanes) -> __m256i {
    // SAFETY: `x` is eight readable `i32`; the load has no alignment requirement.
    unsafe { _mm256_loadu_si256(x.as_ptr().cast()) }
}

#[inline(always)]
fn store(out: &mut FixedLanes, v: __m256i) {
    // SAFETY: `out` is eight writable `i32`; the store has no alignment requirement.
    unsafe { _mm256_storeu_si256(out.as_mut_ptr().cast(), v) }
}

/// Eight 64-bit sums as even lanes (points 0, 2, 4, 6) and odd lanes (1, 3, 5, 7).
#[derive(Copy, Clone)]
struct Wide {
    even: __m256i,
    odd: __m256i,
}

impl Wide {
    /// Each point's value `bits` times 2¹⁶ (the core's `to_acc`), from one value for all.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn splat_shifted(bits: i32) -> Wide {
        let v = _mm256_set1_epi64x(i64::from(bits) << 16);
        Wide { even: v, odd: v }
    }

    #[target_feature(enable = "avx2")]
    #[inline]
    fn zero() -> Wide {
        Wide {
            even: _mm256_setzero_si256(),
            odd: _mm256_setzero_si256(),
        }
    }

    /// `self += w·x` lane by lane, exact (`x_odd` is `x` shifted down by 32 bits).
    #[target_feature(enable = "avx2")]
    #[inline]
    fn mac(&mut self, w: __m256i, x: __m256i, x_odd: __m256i) {
        self.even = _mm256_add_epi64(self.even, _mm256_mul_epi32(x, w));
        self.odd = _mm256_add_epi64(self.odd, _mm256_mul_epi32(x_odd, w));
    }

    /// (self + 2¹⁵) in eight lanes: its bits 16..48 (`low`) and 32..64 (`high`).
    #[target_feature(enable = "avx2")]
    #[inline]
    fn rounded_words(self) -> (__m256i, __m256i) {
        let half = _mm256_set1_epi64x(1 << 15);
        let (even, odd) = (
            _mm256_add_epi64(self.even, half),
            _mm256_add_epi64(self.odd, half),
        );
        // Even points: their word in the low half of each 64-bit lane; odd points: the high.
        let low = _mm256_blend_epi32::<0b1010_1010>(
            _mm256_srli_epi64::<16>(even),
            _mm256_slli_epi64::<16>(odd),
        );
        let high = _mm256_blend_epi32::<0b1010_1010>(_mm256_srli_epi64::<32>(even), odd);
        (low, high)
    }

    /// The core's `from_acc`: round half up to Q16.16, saturated.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn rounded(self) -> __m256i {
        let (low, high) = self.rounded_words();
        // (acc + 2¹⁵) >> 16 fits i32 when bits 47..64 of acc + 2¹⁵ all equal bit 47.
        let fits = _mm256_cmpeq_epi32(_mm256_srai_epi32::<15>(high), _mm256_srai_epi32::<31>(low));
        let negative = _mm256_srai_epi32::<31>(high);
        let saturated = _mm256_blendv_epi8(
            _mm256_set1_epi32(i32::MAX),
            _mm256_set1_epi32(i32::MIN),
            negative,
        );
        _mm256_blendv_epi8(saturated, low, fits)
    }

    /// The core's `activation_from_acc` for Q16.16.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn activation(self, table: &FixedTable<'_>) -> __m256i {
        let (bits, high) = self.rounded_words();
        // |H| < 10 when the integer part (rounded down) lies in [−10, 10).
        let shifted = _mm256_add_epi32(high, _mm256_set1_epi32(10));
        let in_table =
            _mm256_cmpeq_epi32(_mm256_min_epu32(shifted, _mm256_set1_epi32(19)), shifted);
        let magnitude = _mm256_abs_epi32(bits);
        let last = table.last as i32;
        let index = _mm256_min_epu32(srl(magnitude, table.fraction_bits), _mm256_set1_epi32(last));
        let slot = _mm256_slli_epi32::<1>(_mm256_add_epi32(index, _mm256_set1_epi32(last)));
        let base = table.segments.as_ptr().cast::<i32>();
        // SAFETY: `slot` ≤ 2·(2·last) and `slot + 1` index the `2·(2·last + 1)` words of
        // `segments` (checked by the callers: `segments.len()` is `2·last + 1`).
        let (lower, rise) = unsafe {
            (
                _mm256_i32gather_epi32::<4>(base, slot),
                _mm256_i32gather_epi32::<4>(base.add(1), slot),
            )
        };
        let mask = _mm256_set1_epi32((1 << table.fraction_bits) - 1);
        let fraction = _mm256_and_si256(magnitude, mask);
        let step = _mm256_add_epi32(
            _mm256_mullo_epi32(rise, fraction),
            _mm256_set1_epi32(1 << (table.fraction_bits - 1)),
        );
        let value = _mm256_add_epi32(lower, sra(step, table.fraction_bits));
        let negative = _mm256_cmpgt_epi32(_mm256_setzero_si256(), bits);
        let value = _mm256_blendv_epi8(
            value,
            _mm256_sub_epi32(_mm256_setzero_si256(), value),
            negative,
        );
        let top = table.segments.get(2 * table.last).map_or(0, |s| s[0]);
        let limit = _mm256_blendv_epi8(
            _mm256_set1_epi32(top),
            _mm256_set1_epi32(-top),
            _mm256_srai_epi32::<31>(high),
        );
        _mm256_blendv_epi8(limit, value, in_table)
    }
}

/// `x >> bits`, logical, for a shift known only at run time (the table's layout).
#[target_feature(enable = "avx2")]
#[inline]
fn srl(x: __m256i, bits: u32) -> __m256i {
    core::arch::x86_64::_mm256_srlv_epi32(x, _mm256_set1_epi32(bits as i32))
}

/// `x >> bits`, arithmetic, for a shift known only at run time.
#[target_feature(enable = "avx2")]
#[inline]
fn sra(x: __m256i, bits: u32) -> __m256i {
    core::arch::x86_64::_mm256_srav_epi32(x, _mm256_set1_epi32(bits as i32))
}

/// round(x·y/2³²) lane by lane, ties up (the core's `high_word_rounded`).
#[target_feature(enable = "avx2")]
#[inline]
fn high_word_rounded(x: __m256i, y: __m256i) -> __m256i {
    let half = _mm256_set1_epi64x(1 << 31);
    let even = _mm256_add_epi64(_mm256_mul_epi32(x, y), half);
    let odd = _mm256_add_epi64(
        _mm256_mul_epi32(_mm256_srli_epi64::<32>(x), _mm256_srli_epi64::<32>(y)),
        half,
    );
    _mm256_blend_epi32::<0b1010_1010>(_mm256_srli_epi64::<32>(even), odd)
}

/// The forward layer in Q16.16 (see [`crate::forward`]): `out[j]` = the core's
/// `activation_from_acc` of `biases[j]`·2¹⁶ + Σᵢ `weights[j][i]`·xᵢ, x the concatenated
/// `inputs`. Returns `false` without writing when AVX2 is missing, the slices do not fit, or
/// `table` is not `2·last + 1` segments.
pub fn fixed_forward(
    weights: &[i32],
    biases: &[i32],
    inputs: [&[FixedLanes]; 3],
    table: &FixedTable<'_>,
    out: &mut [FixedLanes],
) -> bool {
    let count = inputs.iter().map(|part| part.len()).sum::<usize>();
    let rows = biases.len();
    if count == 0
        || Some(weights.len()) != rows.checked_mul(count)
        || out.len() < rows
        || Some(table.segments.len()) != table.last.checked_mul(2).and_then(|n| n.checked_add(1))
        || !(1..=16).contains(&table.fraction_bits)
        || !available()
    {
        return false;
    }
    // SAFETY: AVX2 is available and the table has its documented length (checked above).
    unsafe { fixed_forward_avx2(weights, count, biases, inputs, table, out) };
    true
}

#[target_feature(enable = "avx2")]
fn fixed_forward_avx2(
    weights: &[i32],
    count: usize,
    biases: &[i32],
    inputs: [&[FixedLanes]; 3],
    table: &FixedTable<'_>,
    out: &mut [FixedLanes],
) {
    for ((row, &bias), out) in weights.chunks_exact(count).zip(biases).zip(out.iter_mut()) {
        let mut acc = Wide::splat_shifted(bias);
        let mut weights = row.iter();
        for part in inputs {
            for (x, &w) in part.iter().zip(&mut weights) {
                let x = load(x);
                acc.mac(_mm256_set1_epi32(w), x, _mm256_srli_epi64::<32>(x));
            }
        }
        store(out, acc.activation(table));
    }
}

/// The transposed layer in Q16.16 (see [`crate::transposed`]): `out[c]` = the core's
/// `from_acc` of Σⱼ `weights[j][first + c]`·`g[j]`, summed from 0 over the rows in order;
/// with `slope`, then the core's `times_slope` with `outputs[c]`. Returns `false` when AVX2 is
/// missing, the slices do not fit, or (with `slope`) a lane is outside the chain rule's fast
/// range (|a| ≤ 2, |δ| < 2¹³): `out` is then unspecified and the portable loop must run.
pub fn fixed_transposed(
    weights: &[i32],
    count: usize,
    (first, columns): (usize, usize),
    g: &[FixedLanes],
    slope: Option<(&[FixedLanes], &FixedSlope)>,
    out: &mut [FixedLanes],
) -> bool {
    let fits = fits_transposed(weights, count, (first, columns), (g, 1), out.len())
        && slope.is_none_or(|(outputs, _)| outputs.len() >= columns);
    if !fits || !available() {
        return false;
    }
    // SAFETY: AVX2 is available (checked above).
    unsafe { fixed_transposed_avx2(weights, count, (first, columns), g, slope, out) }
}

#[target_feature(enable = "avx2")]
fn fixed_transposed_avx2(
    weights: &[i32],
    count: usize,
    (first, columns): (usize, usize),
    g: &[FixedLanes],
    slope: Option<(&[FixedLanes], &FixedSlope)>,
    out: &mut [FixedLanes],
) -> bool {
    let mut in_range = true;
    for (c, out) in out.iter_mut().take(columns).enumerate() {
        let mut acc = Wide::zero();
        for (row, g) in weights.chunks_exact(count).zip(g) {
            let w = row.get(first + c).copied().unwrap_or(0);
            let g = load(g);
            acc.mac(_mm256_set1_epi32(w), g, _mm256_srli_epi64::<32>(g));
        }
        let mut delta = acc.rounded();
        if let Some((outputs, slope)) = slope
            && let Some(a) = outputs.get(c)
        {
            let a = load(a);
            // |a| ≤ 2·2¹⁶ and |δ| < 2²⁹, as the core tests them (unsigned after an offset).
            let a_ok = le_unsigned(_mm256_add_epi32(a, _mm256_set1_epi32(2 << 16)), 4 << 16);
            let d_ok = le_unsigned(
                _mm256_add_epi32(delta, _mm256_set1_epi32(1 << 29)),
                (1 << 30) - 1,
            );
            in_range &= all(_mm256_and_si256(a_ok, d_ok));
            let scaled_a = _mm256_slli_epi32::<8>(a);
            let square = high_word_rounded(scaled_a, scaled_a);
            let slope_bits = _mm256_sub_epi32(
                _mm256_set1_epi32(slope.offset),
                high_word_rounded(_mm256_set1_epi32(slope.square << 16), square),
            );
            delta = high_word_rounded(
                _mm256_slli_epi32::<2>(delta),
                _mm256_slli_epi32::<14>(slope_bits),
            );
        }
        store(out, delta);
    }
    in_range
}

/// Lanes whose unsigned value is at most `limit`, as all-ones.
#[target_feature(enable = "avx2")]
#[inline]
fn le_unsigned(x: __m256i, limit: i32) -> __m256i {
    _mm256_cmpeq_epi32(_mm256_min_epu32(x, _mm256_set1_epi32(limit)), x)
}

/// Whether every lane of `mask` is all-ones.
#[target_feature(enable = "avx2")]
#[inline]
fn all(mask: __m256i) -> bool {
    core::arch::x86_64::_mm256_movemask_epi8(mask) == -1
}
