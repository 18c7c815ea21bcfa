//! Whether two evaluations in the same scalar agree bit for bit (the host's core against the
//! target's), and by how many units in the last place they differ when they do not.

use neurosurf_core::scalar::ScalarKind;
use serde::Serialize;

use super::measured::Measured;
use crate::error::{Error, Result};

/// The agreement of two evaluations of the same points in the same scalar.
///
/// Values are the `f64` decodings of `f32` or Q16.16 results (exact), compared bit for bit:
/// every number of every point (Φ and ∇Φ, or position and direction).
#[derive(Copy, Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Agreement {
    /// Every value identical.
    pub bit_exact: bool,
    /// Values (4 per point) that differ.
    pub differing_values: usize,
    /// Largest distance in units of the last place of the scalar: `f32` ulps, or Q16.16 steps
    /// of 2⁻¹⁶.
    pub max_ulp: u64,
}

impl Agreement {
    /// Compares `a` and `b`, evaluated in `scalar`.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when the two lists differ in length.
    pub fn measure<T: Measured>(scalar: ScalarKind, a: &[T], b: &[T]) -> Result<Self> {
        if a.len() != b.len() {
            return Err(Error::invalid(format!(
                "cannot compare {} samples with {}",
                a.len(),
                b.len()
            )));
        }
        let mut agreement = Agreement {
            bit_exact: true,
            differing_values: 0,
            max_ulp: 0,
        };
        for (x, y) in a.iter().zip(b) {
            for (u, v) in x.words().zip(y.words()) {
                if u.to_bits() != v.to_bits() {
                    agreement.bit_exact = false;
                    agreement.differing_values += 1;
                    agreement.max_ulp = agreement.max_ulp.max(ulp_distance(scalar, u, v));
                }
            }
        }
        Ok(agreement)
    }
}

/// Units in the last place between two values of `scalar` (given as their exact `f64`
/// decodings): for `f32` (and `f64`), the number of representable values between them (+0 and
/// −0 are the same place; a NaN is far from everything); for Q16.16, |a − b| / 2⁻¹⁶.
pub fn ulp_distance(scalar: ScalarKind, a: f64, b: f64) -> u64 {
    match scalar {
        ScalarKind::Q16_16 => {
            let step = |x: f64| (x * 65536.0).round() as i64;
            step(a).abs_diff(step(b))
        }
        ScalarKind::F32 => {
            // Sign-magnitude bits to a monotonic integer line.
            let place = |x: f64| {
                let bits = (x as f32).to_bits();
                let magnitude = i64::from(bits & 0x7FFF_FFFF);
                if bits >> 31 == 1 {
                    -magnitude
                } else {
                    magnitude
                }
            };
            place(a).abs_diff(place(b))
        }
        _ => {
            let place = |x: f64| {
                let bits = x.to_bits();
                let magnitude = i128::from(bits & 0x7FFF_FFFF_FFFF_FFFF);
                if bits >> 63 == 1 {
                    -magnitude
                } else {
                    magnitude
                }
            };
            u64::try_from(place(a).abs_diff(place(b))).unwrap_or(u64::MAX)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn f32_ulps_count_representable_values() {
        let one = 1.0_f32;
        let next = f32::from_bits(one.to_bits() + 1);
        let f = |x: f32| f64::from(x);
        assert_eq!(ulp_distance(ScalarKind::F32, f(one), f(one)), 0);
        assert_eq!(ulp_distance(ScalarKind::F32, f(one), f(next)), 1);
        assert_eq!(ulp_distance(ScalarKind::F32, f(next), f(one)), 1);
        // Across zero: the smallest subnormals on either side are 2 apart, ±0 coincide.
        let tiny = f32::from_bits(1);
        assert_eq!(ulp_distance(ScalarKind::F32, f(tiny), f(-tiny)), 2);
        assert_eq!(ulp_distance(ScalarKind::F32, 0.0, -0.0), 0);
        assert!(ulp_distance(ScalarKind::F32, f64::NAN, 1.0) > 1 << 20);
    }

    #[test]
    fn q16_ulps_are_steps_of_two_to_the_minus_16() {
        let step = 1.0 / 65536.0;
        assert_eq!(ulp_distance(ScalarKind::Q16_16, 1.0, 1.0 + 3.0 * step), 3);
        assert_eq!(ulp_distance(ScalarKind::Q16_16, -step, step), 2);
    }

    #[test]
    fn agreement_counts_differing_values() {
        let a = vec![(1.0, [0.0, 0.5, -1.0]), (2.0, [1.0, 1.0, 1.0])];
        assert_eq!(
            Agreement::measure(ScalarKind::F32, &a, &a).unwrap(),
            Agreement {
                bit_exact: true,
                differing_values: 0,
                max_ulp: 0
            }
        );
        let mut b = a.clone();
        b[1].1[2] = f64::from(f32::from_bits(1.0_f32.to_bits() + 2));
        b[0].0 = f64::from(f32::from_bits(1.0_f32.to_bits() - 1));
        let agreement = Agreement::measure(ScalarKind::F32, &a, &b).unwrap();
        assert!(!agreement.bit_exact);
        assert_eq!((agreement.differing_values, agreement.max_ulp), (2, 2));
        assert!(Agreement::measure(ScalarKind::F32, &a, &b[..1]).is_err());
    }

    #[test]
    fn signed_zeros_differ_in_bits_but_not_in_ulps() {
        let a = vec![(0.0, [0.0; 3])];
        let b = vec![(-0.0, [0.0; 3])];
        let agreement = Agreement::measure(ScalarKind::F32, &a, &b).unwrap();
        assert!(!agreement.bit_exact);
        assert_eq!(agreement.max_ulp, 0);
    }
}
