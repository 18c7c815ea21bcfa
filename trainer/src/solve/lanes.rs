//! Four `f64` values side by side (one AVX2 register): the lane type every trainer kernel
//! uses, the fused or unfused multiply–add they are compiled with, the CPU check that picks
//! the AVX2 + FMA build, and tanh on every lane.

/// Control points the trainer pushes through a module together, one per SIMD lane (4 × f64: one AVX2
/// register).
pub const LANES: usize = 4;

/// One value per lane.
pub type Lanes = [f64; LANES];

/// Whether the CPU runs the AVX2 + FMA kernels.
pub fn cpu_has_fma() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// a·b + c, fused when the kernel is compiled for FMA.
#[inline(always)]
pub fn madd<const FMA: bool>(a: f64, b: f64, c: f64) -> f64 {
    if FMA { a.mul_add(b, c) } else { a * b + c }
}

/// tanh on every lane, from eᵘ − 1 with u = 2|y|: tanh|y| = (eᵘ − 1)/(eᵘ − 1 + 2).
///
/// Within a few ulps of `f64::tanh` (see the tests), without a call per value: u = k·ln 2 + r
/// with |r| ≤ ln 2/2, eʳ − 1 by its Taylor series to r¹³ (the next term is below 10⁻¹⁷·r),
/// eᵘ − 1 = 2ᵏ(eʳ − 1) + (2ᵏ − 1). For k = 0 (|y| < 0.17) that is the series itself, so
/// small arguments keep their relative accuracy. |y| > 20 gives ±1 (as tanh does to the last
/// bit), NaN stays NaN.
#[inline(always)]
pub fn tanh_lanes<const FMA: bool>(y: Lanes) -> Lanes {
    // 1.5·2⁵²: adding it rounds a small number to an integer held in the low mantissa bits.
    const ROUND: f64 = 6_755_399_441_055_744.0;
    // ln 2 to 21 bits, so k·LN2_HI is exact; and the rest.
    const LN2_HI: f64 = f64::from_bits(0x3fe6_2e42_0000_0000);
    const LN2_LO: f64 = 4.749_325_039_031_672_6e-7;
    // (eʳ − 1)/r = Σ rⁱ/(i + 1)!.
    const SERIES: [f64; 13] = [
        1.0,
        1.0 / 2.0,
        1.0 / 6.0,
        1.0 / 24.0,
        1.0 / 120.0,
        1.0 / 720.0,
        1.0 / 5_040.0,
        1.0 / 40_320.0,
        1.0 / 362_880.0,
        1.0 / 3_628_800.0,
        1.0 / 39_916_800.0,
        1.0 / 479_001_600.0,
        1.0 / 6_227_020_800.0,
    ];
    let mut out = [0.0; LANES];
    for l in 0..LANES {
        let u = 2.0 * y[l].abs();
        let u = if u > 40.0 { 40.0 } else { u };
        let shifted = madd::<FMA>(u, std::f64::consts::LOG2_E, ROUND);
        let k = shifted - ROUND;
        let r = madd::<FMA>(-k, LN2_LO, madd::<FMA>(-k, LN2_HI, u));
        let mut series = SERIES[12];
        for &c in SERIES[..12].iter().rev() {
            series = madd::<FMA>(series, r, c);
        }
        let expm1_r = r * series;
        // 2ᵏ from k's bits in `shifted`.
        let exponent = shifted
            .to_bits()
            .wrapping_sub(ROUND.to_bits())
            .wrapping_add(1023);
        let scale = f64::from_bits(exponent << 52);
        let expm1 = madd::<FMA>(scale, expm1_r, scale - 1.0);
        out[l] = (expm1 / (expm1 + 2.0)).copysign(y[l]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distance in units in the last place.
    fn ulps(a: f64, b: f64) -> u64 {
        if a == b {
            return 0;
        }
        let key = |x: f64| {
            let bits = x.to_bits() as i64;
            if bits < 0 { i64::MIN - bits } else { bits }
        };
        key(a).abs_diff(key(b))
    }

    fn worst_ulps<const FMA: bool>(ys: &[f64]) -> u64 {
        let mut worst = 0;
        for y in ys.chunks(LANES) {
            let mut lanes = [0.0; LANES];
            lanes[..y.len()].copy_from_slice(y);
            let t = tanh_lanes::<FMA>(lanes);
            for (l, &x) in y.iter().enumerate() {
                worst = worst.max(ulps(t[l], x.tanh()));
            }
        }
        worst
    }

    #[test]
    fn lane_tanh_is_within_a_few_ulps() {
        let mut ys: Vec<f64> = (-400_000..=400_000)
            .map(|i| f64::from(i) * 6.1e-5)
            .collect();
        ys.extend((-300..=10).map(|e| 2f64.powi(e) * 1.37));
        ys.extend((-300..=10).map(|e| -(2f64.powi(e) * 0.93)));
        ys.extend([
            0.0,
            -0.0,
            0.17328679513998632,
            19.99,
            20.01,
            40.0,
            1e300,
            f64::MAX,
        ]);
        let worst = worst_ulps::<false>(&ys);
        eprintln!("tanh_lanes: worst {worst} ulps");
        assert!(worst <= 4, "{worst}");
        if cpu_has_fma() {
            // The FMA build runs the same code with fused operations: check it under FMA.
            #[target_feature(enable = "avx2,fma")]
            fn fused(ys: &[f64]) -> u64 {
                worst_ulps::<true>(ys)
            }
            // SAFETY: the CPU has AVX2 and FMA.
            let worst = unsafe { fused(&ys) };
            eprintln!("tanh_lanes (FMA): worst {worst} ulps");
            assert!(worst <= 4, "{worst}");
        }
        let special = tanh_lanes::<false>([f64::NAN, f64::INFINITY, f64::NEG_INFINITY, -0.0]);
        assert!(special[0].is_nan());
        assert_eq!(special[1], 1.0);
        assert_eq!(special[2], -1.0);
        assert!(special[3] == 0.0 && special[3].is_sign_negative());
    }
}
