//! The scalar operations the Cao En blending needs, measured exhaustively: Q16.16 e^x over every
//! input (no overflow anywhere, the error the docs state), exponential blending in Q16.16 for q
//! up to 16 and beyond, and the quotient of accumulators used by the rational form.

use neurosurf_core::scalar::{Q16, Scalar};

const LSB: f64 = 1.0 / 65536.0;

/// Every Q16.16 input where e^x is representable and above half an LSB (and a sweep of the
/// rest): the result is within 0.5 LSB + 2.5·10⁻⁷·e^x of e^x (exactly 0 below
/// −11.8, saturated from 10.3972 on), and monotone.
#[test]
fn q16_exp_is_accurate_and_total_over_every_input() {
    let mut worst_low = 0.0_f64; // x ≤ 0, in LSB
    let mut worst_relative = 0.0_f64; // x > 0, error / (LSB + 2.5e-7·e^x)
    let mut previous = Q16::ZERO;
    let low = (-11.8 * 65536.0) as i32 - 1000;
    let high = (10.4 * 65536.0) as i32 + 1000;
    let sweep = (i32::MIN..low).step_by(4099).chain(low..=high);
    let sweep = sweep
        .chain((high + 1..=i32::MAX).step_by(4099))
        .chain([i32::MAX]);
    for bits in sweep {
        let x = Q16::from_bits(bits);
        let got = x.exp();
        assert!(got >= previous, "not monotone at {x}");
        previous = got;
        let exact = x.to_num::<f64>().exp();
        if exact >= 32768.0 - LSB {
            assert!(got >= Q16::from_num(32767.9), "{x}");
            continue;
        }
        let error = (got.to_num::<f64>() - exact).abs();
        if bits <= 0 {
            worst_low = worst_low.max(error / LSB);
        }
        let bound = 0.5 * LSB + 2.5e-7 * exact;
        worst_relative = worst_relative.max(error / bound);
    }
    println!("Q16 exp: worst {worst_low:.3} LSB for x ≤ 0, {worst_relative:.3} of the bound");
    assert!(worst_low <= 0.52 && worst_relative <= 1.0);
    assert_eq!(Q16::from_num(-11.8).exp(), Q16::ZERO);
    assert_eq!(Q16::ZERO.exp(), Q16::ONE);
    assert_eq!(Q16::MAX.exp(), Q16::MAX);
    assert_eq!(Q16::MIN.exp(), Q16::ZERO);
}

/// The exponential blending's argument q·(s − 1) for unit vectors and q ≤ 64, evaluated the
/// way the core does (rounded product, then exp): never saturates, never overflows, and for
/// q ≤ 16 stays within 0.5 LSB + q·|s − 1|·e^{q(s−1)}·2⁻¹⁶ (the rounding of the argument) of
/// the exact blending value.
#[test]
fn q16_exponential_blending_has_no_overflow_for_q_up_to_16() {
    let mut worst = 0.0_f64;
    for q_sixteenths in 0..=16 * 16 {
        let q = Q16::from_num(f64::from(q_sixteenths) / 16.0);
        for s_bits in (-65536..=65536).step_by(7) {
            let s = Q16::from_bits(s_bits);
            let argument = q.mul(s.sub(Q16::ONE));
            let value = argument.exp();
            assert!(value <= Q16::ONE, "q {q} s {s}: {value}");
            let exact = (q.to_num::<f64>() * (s.to_num::<f64>() - 1.0)).exp();
            let bound = 0.5 * LSB + 1.02 * exact * 0.5 * LSB + 2.5e-7 * exact;
            worst = worst.max((value.to_num::<f64>() - exact).abs() / bound);
        }
    }
    println!("exponential blending: worst error {worst:.3} of the bound");
    assert!(worst <= 1.0);
}

/// `quotient` rounds num/den once, to nearest, saturating; 0 for a zero denominator.
#[test]
fn quotient_of_accumulators() {
    let acc = |v: f64| Q16::from_num(v).to_acc();
    let sum = |values: &[f64]| {
        values.iter().fold(Q16::ZERO.to_acc(), |a, &v| {
            Q16::mac(a, Q16::from_num(v), Q16::ONE)
        })
    };
    assert_eq!(Q16::quotient(acc(1.0), sum(&[0.5, 0.25, 0.25])), Q16::ONE);
    assert_eq!(Q16::quotient(acc(-3.0), acc(2.0)), Q16::from_num(-1.5));
    assert_eq!(Q16::quotient(acc(1.0), acc(3.0)), Q16::from_bits(21845));
    assert_eq!(Q16::quotient(acc(2.0), acc(3.0)), Q16::from_bits(43691));
    assert_eq!(Q16::quotient(acc(-2.0), acc(3.0)), Q16::from_bits(-43691));
    assert_eq!(Q16::quotient(acc(5.0), 0), Q16::ZERO);
    assert_eq!(Q16::quotient(acc(1000.0), acc(0.001)), Q16::MAX);
    assert_eq!(Q16::quotient(acc(-1000.0), acc(0.001)), Q16::MIN);
    assert_eq!(Q16::quotient(i64::MAX, Q16::DELTA.to_acc()), Q16::MAX);
    assert_eq!(<f32 as Scalar>::quotient(1.0, 0.0), 0.0);
    assert_eq!(<f32 as Scalar>::quotient(1.0, 4.0), 0.25);
    // Exhaustive against exact rounding for small numerators and denominators.
    for n in -300_i64..=300 {
        for d in 1_i64..=40 {
            let got = Q16::quotient(n << 16, d << 32).to_bits();
            // n·2⁻¹⁶ / d, in Q16.16 bits.
            let exact = n as f64 / d as f64;
            assert!(
                (f64::from(got) - exact).abs() <= 0.5,
                "{n}/{d}: {got} vs {exact}"
            );
        }
    }
}
