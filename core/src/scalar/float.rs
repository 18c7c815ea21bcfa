//! [`Scalar`] for `f32`: IEEE arithmetic, a fast exp-based activation ([`super::activation_f32`]), `libm`
//! for sqrt.
//!
//! No fused multiply–add is used, so results are bit-identical on every IEEE-754 target
//! (x86-64 SSE, Cortex-M4F FPv4) given the same `libm`.

use super::{ACTIVATION_AMPLITUDE, ACTIVATION_GAIN, Q16, Scalar, ScalarKind};
use crate::math;

pub(crate) const SLOPE_OFFSET: f32 = (ACTIVATION_GAIN * ACTIVATION_AMPLITUDE) as f32;
pub(crate) const SLOPE_SQUARE: f32 = (ACTIVATION_GAIN / ACTIVATION_AMPLITUDE) as f32;
const CURVATURE: f32 = (2.0 * ACTIVATION_GAIN / ACTIVATION_AMPLITUDE) as f32;

impl Scalar for f32 {
    type Acc = f32;

    const KIND: ScalarKind = ScalarKind::F32;
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    const MAX_PARAMETER: f32 = f32::MAX;

    #[inline]
    fn from_f32(value: f32) -> Option<Self> {
        value.is_finite().then_some(value)
    }
    #[inline]
    fn from_f32_saturating(value: f32) -> Self {
        if value.is_nan() { 0.0 } else { value }
    }
    #[inline]
    fn from_stored(bytes: [u8; 4], stored: ScalarKind) -> Option<Self> {
        match stored {
            ScalarKind::F32 => Self::from_f32(f32::from_le_bytes(bytes)),
            ScalarKind::Q16_16 => Some(Q16::from_bits(i32::from_le_bytes(bytes)).to_num()),
            ScalarKind::F64 => None,
        }
    }
    #[inline]
    fn to_le_bytes(self) -> [u8; 4] {
        f32::to_le_bytes(self)
    }
    #[inline]
    fn to_f32(self) -> f32 {
        self
    }
    #[inline]
    fn to_f64(self) -> f64 {
        f64::from(self)
    }

    #[inline]
    fn add(self, other: Self) -> Self {
        self + other
    }
    #[inline]
    fn sub(self, other: Self) -> Self {
        self - other
    }
    #[inline]
    fn mul(self, other: Self) -> Self {
        self * other
    }
    #[inline]
    fn times_power_of_two(self, exponent: i8) -> Self {
        // 2^e is a normal f32 for e in [−126, 127]; frames stay within ±64.
        let biased = (127 + i32::from(exponent)).clamp(1, 254) as u32;
        self * f32::from_bits(biased << 23)
    }
    #[inline]
    fn neg(self) -> Self {
        -self
    }
    #[inline]
    fn abs(self) -> Self {
        math::fabsf(self)
    }

    #[inline]
    fn to_acc(self) -> f32 {
        self
    }
    #[inline(always)]
    fn mac(acc: f32, a: Self, b: Self) -> f32 {
        acc + a * b
    }
    #[inline(always)]
    fn from_acc(acc: f32) -> Self {
        acc
    }

    #[inline]
    fn sqrt(self) -> Self {
        if self > 0.0 { math::sqrtf(self) } else { 0.0 }
    }
    #[inline]
    fn recip(self) -> Option<Self> {
        let r = 1.0 / self;
        (self != 0.0 && r.is_finite()).then_some(r)
    }

    #[inline]
    fn exp(self) -> Self {
        super::exp_f32::exp(self)
    }
    #[inline]
    fn quotient(numerator: f32, denominator: f32) -> Self {
        if denominator == 0.0 {
            0.0
        } else {
            numerator / denominator
        }
    }
}

impl crate::implicit::Activation for f32 {
    #[inline]
    fn activation(h: Self) -> Self {
        super::activation_f32::activation(h)
    }
    #[inline]
    fn activation_slope(a: Self) -> Self {
        SLOPE_OFFSET - SLOPE_SQUARE * (a * a)
    }
    #[inline(always)]
    fn times_slope(delta: Self, a: Self) -> Self {
        delta * Self::activation_slope(a)
    }
    #[inline]
    fn activation_curvature(a: Self, slope: Self) -> Self {
        -CURVATURE * a * slope
    }
}
