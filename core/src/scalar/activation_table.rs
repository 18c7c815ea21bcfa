//! Table of a(H) = 1.7159·tanh(2H/3) for Q16.16, built at compile time.
//!
//! 641 entries cover H ∈ [0, 10] in steps of 1/64 (a(10) is within 6·10⁻⁶ of the asymptote);
//! odd symmetry gives negative H. The table continues to H = 16 with copies of a(10), so that
//! an index masked to 10 bits needs no bounds check and every H below 16 interpolates to the
//! saturated value beyond 10 (two equal entries interpolate to themselves). Linear interpolation between entries has a worst-case error
//! of h²/8·max|a″| = 1.8·10⁻⁵; with the two roundings the total measures 3.07·10⁻⁵ (2.01 LSB,
//! exhaustively in the tests), bounded by `Q16_ACTIVATION_MAX_ERROR` = 1.25·2⁻¹⁵. The table is
//! computed by `const fn`s in `f64`, so there is no generated code to keep in sync.
//!
//! What is stored is [`SEGMENTS`]: each entry with its rise to the next, so that one 8-byte
//! read (`ldrd` on the M4) gives both and the interpolation needs no subtraction.

/// log2 of the number of table steps per unit of H.
pub(crate) const STEP_SHIFT: u32 = 6;
/// Q16.16 fraction bits below one table step.
pub(crate) const FRACTION_BITS: u32 = 16 - STEP_SHIFT;
/// Index of the last computed entry (H = 10).
pub(crate) const LAST: usize = 10 << STEP_SHIFT;
/// Bits of a table index: the entries below 2^`INDEX_BITS` cover H < 16.
pub(crate) const INDEX_BITS: u32 = 10;

/// a(i / 64) in Q16.16 for i = 0..=640, then a(10) up to i = 1024.
pub(crate) const TABLE: [i32; (1 << INDEX_BITS) + 1] = build();

/// `[a(i / 64), a((i + 1) / 64) − a(i / 64)]` in Q16.16 bits for i = 0..1024: [`TABLE`] as
/// segments, each entry with its rise to the next (exact: the entries lie below 2¹⁷).
pub(crate) static SEGMENTS: [[i32; 2]; 1 << INDEX_BITS] = segments();

#[allow(clippy::indexing_slicing)] // const evaluation: an out-of-bounds index is a compile error
const fn segments() -> [[i32; 2]; 1 << INDEX_BITS] {
    let mut segments = [[0_i32; 2]; 1 << INDEX_BITS];
    let mut i = 0;
    while i < segments.len() {
        segments[i] = [TABLE[i], TABLE[i + 1] - TABLE[i]];
        i += 1;
    }
    segments
}

#[allow(clippy::indexing_slicing)] // const evaluation: an out-of-bounds index is a compile error
const fn build() -> [i32; (1 << INDEX_BITS) + 1] {
    let mut table = [0_i32; (1 << INDEX_BITS) + 1];
    let mut i = 0;
    while i < table.len() {
        let step = if i < LAST { i } else { LAST };
        let h = step as f64 / (1 << STEP_SHIFT) as f64;
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
mod tests {
    #[test]
    fn const_tanh_matches_std() {
        for i in 0..2000 {
            let x = i as f64 * 0.01;
            assert!((super::tanh(x) - x.tanh()).abs() < 1e-15, "x = {x}");
        }
    }
}
