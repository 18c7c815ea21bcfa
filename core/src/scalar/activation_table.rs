//! Table of a(H) = 1.7159·tanh(2H/3) for Q16.16, built at compile time.
//!
//! 641 entries cover H ∈ [0, 10] in steps of 1/64 (a(10) is within 6·10⁻⁶ of the asymptote,
//! and |H| ≥ 10 gives a(10)); odd symmetry gives negative H. Linear interpolation between
//! entries has a worst-case error
//! of h²/8·max|a″| = 1.8·10⁻⁵; with the two roundings the total measures 3.07·10⁻⁵ (2.01 LSB,
//! exhaustively in the tests), bounded by `Q16_ACTIVATION_MAX_ERROR` = 1.25·2⁻¹⁵. The table is
//! computed by `const fn`s in `f64`, so there is no generated code to keep in sync.
//!
//! What is stored is [`SEGMENTS`], over both signs: entry `LAST + k` is the value at H = k/64
//! (odd symmetry: a(−H) = −a(H)) and its rise to the next, for k = −640 … 640. One 8-byte read
//! (`ldrd` on the M4) gives both, and a kernel can index it with H's signed integer part
//! directly (see [`SEGMENTS`] for why that gives the symmetric interpolation's bits).

/// log2 of the number of table steps per unit of H.
pub(crate) const STEP_SHIFT: u32 = 6;
/// Q16.16 fraction bits below one table step.
pub(crate) const FRACTION_BITS: u32 = 16 - STEP_SHIFT;
/// Index of the last computed entry (H = 10).
pub(crate) const LAST: usize = 10 << STEP_SHIFT;

/// a(i / 64) in Q16.16 for i = 0..=640.
pub(crate) const TABLE: [i32; LAST + 1] = build();

/// `[a(k / 64), a((k + 1) / 64) − a(k / 64)]` in Q16.16 bits at index `LAST + k` for
/// k = −640 … 640: [`TABLE`] extended to negative H by odd symmetry, as segments, each entry
/// with its rise to the next (0 at k = 640, where the table has saturated; exact: the values
/// lie below 2¹⁷).
///
/// The portable code interpolates |H| in the upper half and restores the sign. A kernel may
/// instead take the segment below H itself (index `LAST + (H >> 10)`, fraction `H & 1023`)
/// and round with 2⁹ − 1 instead of 2⁹ when H < 0: for H = −(1024·i + f), 0 < f < 1024, that
/// segment starts at −T[i+1] with rise T[i+1] − T[i], and −T[i+1] + ((R·(1024 − f) + 511) >> 10)
/// = −T[i] + ((511 − R·f) >> 10) = −(T[i] + ((R·f + 512) >> 10)) — the same bits (at f = 0 both
/// give −T[i]). `tests::signed_segments_give_the_symmetric_bits` checks every H in [−10, 10].
pub(crate) static SEGMENTS: [[i32; 2]; 2 * LAST + 1] = segments();

#[allow(clippy::indexing_slicing)] // const evaluation: an out-of-bounds index is a compile error
const fn segments() -> [[i32; 2]; 2 * LAST + 1] {
    // a(k / 64) for any k: odd, flat from |k| = 640 on.
    const fn value(k: isize) -> i32 {
        let at = if k.unsigned_abs() < LAST {
            k.unsigned_abs()
        } else {
            LAST
        };
        if k < 0 { -TABLE[at] } else { TABLE[at] }
    }
    let mut segments = [[0_i32; 2]; 2 * LAST + 1];
    let mut i = 0;
    while i < segments.len() {
        let k = i as isize - LAST as isize;
        segments[i] = [value(k), value(k + 1) - value(k)];
        i += 1;
    }
    segments
}

#[allow(clippy::indexing_slicing)] // const evaluation: an out-of-bounds index is a compile error
const fn build() -> [i32; LAST + 1] {
    let mut table = [0_i32; LAST + 1];
    let mut i = 0;
    while i < table.len() {
        let h = i as f64 / (1 << STEP_SHIFT) as f64;
        let a = super::ACTIVATION_AMPLITUDE * tanh(super::ACTIVATION_GAIN * h);
        // a ≥ 0 here, so truncation after adding ½ rounds to nearest.
        table[i] = (a * 65536.0 + 0.5) as i32;
        i += 1;
    }
    table
}

/// tanh(x) for x ≥ 0, accurate to a few ulp of f64.
const fn tanh(x: f64) -> f64 {
    let e = exp_neg(2.0 * x);
    (1.0 - e) / (1.0 + e)
}

/// e^(−y) for y ≥ 0 by range reduction y = k·ln2 + r and a Taylor series of e^(−r).
const fn exp_neg(y: f64) -> f64 {
    let k = (y / core::f64::consts::LN_2) as i32;
    let r = y - k as f64 * core::f64::consts::LN_2;
    let mut term = 1.0;
    let mut sum = 1.0;
    let mut n = 1;
    while n < 30 {
        term = -term * r / n as f64;
        sum += term;
        n += 1;
    }
    let mut scaled = sum;
    let mut i = 0;
    while i < k {
        scaled *= 0.5;
        i += 1;
    }
    scaled
}

#[cfg(test)]
#[allow(clippy::indexing_slicing)]
mod tests {
    use super::{FRACTION_BITS, LAST, SEGMENTS};

    /// The kernels' signed lookup (see [`SEGMENTS`]) against the portable symmetric one.
    #[test]
    fn signed_segments_give_the_symmetric_bits() {
        let symmetric = |h: i32| {
            let u = h.unsigned_abs();
            let [lower, rise] = SEGMENTS[LAST + ((u >> FRACTION_BITS) as usize).min(LAST)];
            let value = lower + ((rise * (u & 1023) as i32 + 512) >> FRACTION_BITS);
            if h < 0 { -value } else { value }
        };
        let signed = |h: i32| {
            let [lower, rise] = SEGMENTS[(LAST as isize + (h >> FRACTION_BITS) as isize) as usize];
            lower + ((rise * (h & 1023) + 512 + (h >> 31)) >> FRACTION_BITS)
        };
        for h in -(10 << 16)..=(10 << 16) {
            assert_eq!(signed(h), symmetric(h), "H = {h} / 2^16");
        }
        assert_eq!(SEGMENTS[2 * LAST][1], 0);
        assert_eq!(SEGMENTS[0][0], -SEGMENTS[2 * LAST][0]);
    }

    #[test]
    fn const_tanh_matches_std() {
        for i in 0..2000 {
            let x = i as f64 * 0.01;
            assert!((super::tanh(x) - x.tanh()).abs() < 1e-15, "x = {x}");
        }
    }
}
