//! Accuracy of the activation a(H) = 1.7159·tanh(2H/3) and of its derivatives a′, a″ in both
//! scalars, against an `f64` reference.
//!
//! Q16.16 is checked exhaustively: every representable input in [−12, 12] (2⁻¹⁶ apart,
//! 1 572 865 values) plus a strided scan of the saturated tails out to the ends of the range.
//! `f32` is checked with proptest over H ∈ [−50, 50]. The derivative bounds live in
//! `common/mod.rs` (the evaluation tests' error analysis uses them too).

mod common;

use neurosurf_core::implicit::Activation;
use neurosurf_core::scalar::{
    ACTIVATION_AMPLITUDE, F32_ACTIVATION_MAX_ERROR, Q16, Q16_ACTIVATION_MAX_ERROR, Scalar,
};
use proptest::prelude::*;

use common::{
    F32_CURVATURE_MAX_ERROR, F32_SLOPE_MAX_ERROR, Q16_CURVATURE_MAX_ERROR, Q16_SLOPE_MAX_ERROR,
    activation as exact,
};

fn q16(bits: i32) -> Q16 {
    Q16::from_bits(bits)
}

#[derive(Default, Debug)]
struct MaxError {
    value: (f64, i32),
    slope: (f64, i32),
    curvature: (f64, i32),
}

impl MaxError {
    fn record(&mut self, bits: i32) {
        let h = q16(bits);
        let a = Q16::activation(h);
        let slope = Q16::activation_slope(a);
        let curvature = Q16::activation_curvature(a, slope);
        let (ev, es, ec) = exact(h.to_f64());
        for (slot, error) in [
            (&mut self.value, (a.to_f64() - ev).abs()),
            (&mut self.slope, (slope.to_f64() - es).abs()),
            (&mut self.curvature, (curvature.to_f64() - ec).abs()),
        ] {
            if error > slot.0 {
                *slot = (error, bits);
            }
        }
    }
}

const SCAN_LIMIT: i32 = 12 << 16;

/// The tails beyond ±12: a stride that is prime to 2¹⁶ (so every fractional position shows up)
/// plus the ends of the range.
fn tail_inputs() -> impl Iterator<Item = i32> {
    let positive = (SCAN_LIMIT..=i32::MAX).step_by(65_537 * 3);
    let edges = [
        SCAN_LIMIT + 1,
        (10 << 16) - 1,
        10 << 16,
        i32::MAX - 1,
        i32::MAX,
    ];
    positive
        .chain(edges)
        .flat_map(|b| [b, -b])
        .chain([i32::MIN, i32::MIN + 1])
}

#[test]
fn q16_activation_and_derivatives_exhaustive() {
    let mut max = MaxError::default();
    for bits in -SCAN_LIMIT..=SCAN_LIMIT {
        max.record(bits);
    }
    for bits in tail_inputs() {
        max.record(bits);
    }
    let lsb = 1.0 / 65536.0;
    println!(
        "Q16 max |error|: value {:.3e} ({:.3} LSB at H = {}), slope {:.3e} ({:.3} LSB at H = {}), \
         curvature {:.3e} ({:.3} LSB at H = {})",
        max.value.0,
        max.value.0 / lsb,
        q16(max.value.1),
        max.slope.0,
        max.slope.0 / lsb,
        q16(max.slope.1),
        max.curvature.0,
        max.curvature.0 / lsb,
        q16(max.curvature.1),
    );
    // The goal; the documented constant must be at most that.
    const { assert!(Q16_ACTIVATION_MAX_ERROR <= 1.0 / 16384.0) };
    assert!(
        max.value.0 <= Q16_ACTIVATION_MAX_ERROR,
        "value error {} at H = {} exceeds Q16_ACTIVATION_MAX_ERROR = {}",
        max.value.0,
        q16(max.value.1),
        Q16_ACTIVATION_MAX_ERROR
    );
    // The documented bound is tight: not loose by more than 2×.
    assert!(
        max.value.0 > Q16_ACTIVATION_MAX_ERROR / 2.0,
        "Q16_ACTIVATION_MAX_ERROR = {} is loose: measured {}",
        Q16_ACTIVATION_MAX_ERROR,
        max.value.0
    );
    assert!(
        max.slope.0 <= Q16_SLOPE_MAX_ERROR,
        "slope error {} at H = {}",
        max.slope.0,
        q16(max.slope.1)
    );
    // The derivative bounds are tight as well.
    assert!(max.slope.0 > Q16_SLOPE_MAX_ERROR / 2.0);
    assert!(max.curvature.0 > Q16_CURVATURE_MAX_ERROR / 2.0);
    assert!(
        max.curvature.0 <= Q16_CURVATURE_MAX_ERROR,
        "curvature error {} at H = {}",
        max.curvature.0,
        q16(max.curvature.1)
    );
}

#[test]
fn q16_activation_is_monotone_and_odd() {
    let mut previous = Q16::activation(q16(i32::MIN));
    // The saturated tails below −12 are constant (the table's last entry).
    for bits in tail_inputs().filter(|&b| b < -SCAN_LIMIT) {
        assert_eq!(Q16::activation(q16(bits)), previous, "H bits {bits}");
    }
    for bits in -SCAN_LIMIT..=SCAN_LIMIT {
        let a = Q16::activation(q16(bits));
        assert!(a >= previous, "a decreases at H bits {bits}");
        previous = a;
        // Odd symmetry holds exactly (the table is indexed by |H| and the sign reapplied).
        assert_eq!(
            Q16::activation(q16(-bits)).to_bits(),
            -a.to_bits(),
            "a(−H) ≠ −a(H) at H bits {bits}"
        );
    }
    for bits in tail_inputs().filter(|&b| b > SCAN_LIMIT) {
        assert_eq!(Q16::activation(q16(bits)), previous, "H bits {bits}");
    }
    // i32::MIN has no positive counterpart; it saturates like every other large negative input.
    assert_eq!(
        Q16::activation(q16(i32::MIN)).to_bits(),
        -Q16::activation(q16(i32::MAX)).to_bits()
    );
    // The range is strictly inside ±1.7159 and a(0) = 0.
    assert_eq!(Q16::activation(Q16::ZERO), Q16::ZERO);
    assert!(Q16::activation(q16(i32::MAX)).to_f64() < ACTIVATION_AMPLITUDE);
}

#[test]
fn q16_slope_and_curvature_have_the_right_sign() {
    for bits in (-SCAN_LIMIT..=SCAN_LIMIT).step_by(97) {
        let a = Q16::activation(q16(bits));
        let slope = Q16::activation_slope(a);
        let curvature = Q16::activation_curvature(a, slope);
        assert!(slope >= Q16::ZERO, "a′ < 0 at H bits {bits}");
        // a″ has the opposite sign of H (or is 0).
        assert!(
            curvature.to_bits().signum() * bits.signum() <= 0,
            "a″ has the wrong sign at H bits {bits}"
        );
    }
}

fn f32_errors(h: f32) -> (f64, f64, f64) {
    let a = <f32 as Activation>::activation(h);
    let slope = <f32 as Activation>::activation_slope(a);
    let curvature = <f32 as Activation>::activation_curvature(a, slope);
    let (ev, es, ec) = exact(f64::from(h));
    (
        (f64::from(a) - ev).abs(),
        (f64::from(slope) - es).abs(),
        (f64::from(curvature) - ec).abs(),
    )
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 20_000,
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn f32_activation_matches_f64(h in -50.0_f32..=50.0) {
        let (value, slope, curvature) = f32_errors(h);
        prop_assert!(value <= F32_ACTIVATION_MAX_ERROR, "a error {value} at H = {h}");
        prop_assert!(slope <= F32_SLOPE_MAX_ERROR, "a′ error {slope} at H = {h}");
        prop_assert!(curvature <= F32_CURVATURE_MAX_ERROR, "a″ error {curvature} at H = {h}");
    }
}

/// A dense deterministic scan complementing proptest, reporting the measured maxima.
#[test]
fn f32_activation_scan() {
    let mut max = (0.0_f64, 0.0_f64, 0.0_f64);
    let steps = 400_000;
    for i in 0..=steps {
        let h = -50.0 + 100.0 * f64::from(i) / f64::from(steps);
        let (v, s, c) = f32_errors(h as f32);
        max = (max.0.max(v), max.1.max(s), max.2.max(c));
    }
    // Around 0 where the relative precision of f32 matters most.
    for i in -100_000..=100_000 {
        let (v, s, c) = f32_errors(i as f32 * 1.0e-5);
        max = (max.0.max(v), max.1.max(s), max.2.max(c));
    }
    println!(
        "f32 max |error|: value {:.3e}, slope {:.3e}, curvature {:.3e}",
        max.0, max.1, max.2
    );
    assert!(max.0 <= F32_ACTIVATION_MAX_ERROR);
    assert!(max.1 <= F32_SLOPE_MAX_ERROR);
    assert!(max.2 <= F32_CURVATURE_MAX_ERROR);
    // f32 is odd to within twice its error (computed from the signed H, not from |H|).
    for i in 0..10_000 {
        let h = i as f32 * 0.0051;
        let sum = <f32 as Activation>::activation(-h) + <f32 as Activation>::activation(h);
        assert!(
            f64::from(sum.abs()) <= 2.0 * F32_ACTIVATION_MAX_ERROR,
            "a(−H) + a(H) = {sum} at H = {h}"
        );
    }
}

/// Every `f32` in [0, 16] (past saturation), in order: the f32 activation's largest error, its
/// largest step *down* between neighbouring inputs (it is monotone only to within its error)
/// and its largest |a(H) + a(−H)| (odd only to within it). About 1.1·10⁹ inputs, so ignored by
/// default: `cargo test --release -p neurosurf-core --test activation -- --ignored --nocapture`.
/// Measured: error 2.855·10⁻⁷, step down 3.6·10⁻⁷, asymmetry 2.4·10⁻⁷.
#[test]
#[ignore = "exhaustive over 1.1e9 inputs: run on demand"]
fn f32_activation_exhaustive_monotonicity_and_symmetry() {
    let (mut error, mut step_down, mut asymmetry) = (0.0_f64, 0.0_f32, 0.0_f32);
    let mut previous = <f32 as Activation>::activation(0.0);
    for bits in 0..=16.0_f32.to_bits() {
        let h = f32::from_bits(bits);
        let a = <f32 as Activation>::activation(h);
        error = error.max((f64::from(a) - exact(f64::from(h)).0).abs());
        step_down = step_down.max(previous - a);
        asymmetry = asymmetry.max((a + <f32 as Activation>::activation(-h)).abs());
        previous = a;
    }
    println!(
        "f32 over [0, 16]: error {error:.4e}, step down {step_down:.3e}, asymmetry {asymmetry:.3e}"
    );
    assert!(error <= F32_ACTIVATION_MAX_ERROR);
    assert!(f64::from(step_down) <= 2.0 * F32_ACTIVATION_MAX_ERROR);
    assert!(f64::from(asymmetry) <= 2.0 * F32_ACTIVATION_MAX_ERROR);
}
