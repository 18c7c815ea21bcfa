//! The one scalar abstraction every model is written against.
//!
//! [`Scalar`] is sealed and implemented side by side for [`f32`] and for Q16.16 fixed point
//! ([`Q16`] = `fixed::types::I16F16`), so a single test binary can evaluate the same model in
//! both and compare them with an `f64` reference. It provides exactly what the models need:
//! saturating arithmetic, a wide multiply–accumulate ([`Scalar::Acc`]), `sqrt`/`recip` for
//! normalization, `exp` and a quotient of accumulators for the Cao En blending functions, and
//! conversions. The implicit modules' activation a(H) = 1.7159·tanh(2H/3), with its first and
//! second derivatives, is [`crate::implicit::Activation`], which every scalar also implements.
//!
//! The hot loop of every network is `acc = mac(acc, weight, input)` followed by one
//! [`Scalar::from_acc`] per neuron: for `f32` that is a plain multiply–add; for Q16.16 it is a
//! 32×32→64-bit multiply–accumulate in Q32.32 with a single rounding and saturation at the end
//! (no division, no per-term rounding).
//!
//! ```
//! use neurosurf_core::implicit::Activation;
//! use neurosurf_core::scalar::{Q16, Scalar};
//! let h = 0.75_f32;
//! let float = <f32 as Activation>::activation(h);
//! let fixed = Q16::activation(Q16::from_f32_saturating(h)).to_f32();
//! assert!((float - fixed).abs() < 1.0 / 16384.0);
//! ```

pub(crate) mod activation_f32;
pub(crate) mod activation_table;
mod exp_f32;
mod exp_q16;
pub(crate) mod float;
pub(crate) mod q16;

pub use q16::Q16;

use core::fmt::Debug;

/// 1.7159, the amplitude of the activation a(H) = 1.7159·tanh(2H/3) (LeCun's choice, used by
/// Carcenac).
pub const ACTIVATION_AMPLITUDE: f64 = 1.7159;
/// 2/3, the input gain of the activation.
pub const ACTIVATION_GAIN: f64 = 2.0 / 3.0;

/// Largest absolute error of [`Q16`]'s activation against the exact a(H), over all inputs:
/// 1.25·2⁻¹⁵ ≈ 3.81·10⁻⁵. Measured exhaustively by the tests (`core/tests/activation.rs`, every
/// Q16.16 input in [−12, 12] plus the saturated tails): 3.067·10⁻⁵ = 2.01 LSB, at H = −0.86728
/// (interpolation error of the 1/64-step table plus the table's and the interpolation's
/// roundings). The design goal was 2⁻¹⁴.
pub const Q16_ACTIVATION_MAX_ERROR: f64 = 1.25 / 32768.0;

/// Largest absolute error of `f32`'s activation against the exact a(H): the fast activation's
/// 3.0·10⁻⁷ (measured 2.855·10⁻⁷ by `core/tests/activation.rs`) with a margin.
pub const F32_ACTIVATION_MAX_ERROR: f64 = 4.0e-7;

pub(crate) mod sealed {
    pub trait Sealed {}
    impl Sealed for f32 {}
    impl Sealed for super::Q16 {}
}

/// How parameters are stored in a blob, and which scalar a model is evaluated in.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum ScalarKind {
    /// IEEE-754 binary32, little endian.
    F32,
    /// Signed Q16.16 fixed point (`I16F16`), two's complement, little endian.
    Q16_16,
    /// IEEE-754 binary64, little endian: only host-side model kinds (the RBF baseline) store
    /// this; no core model loads it and no core [`Scalar`] evaluates in it.
    F64,
}

impl ScalarKind {
    /// The byte that identifies this kind in a blob header.
    pub const fn code(self) -> u8 {
        match self {
            ScalarKind::F32 => 1,
            ScalarKind::Q16_16 => 2,
            ScalarKind::F64 => 3,
        }
    }

    /// The kind a blob header byte names, if any.
    pub const fn from_code(code: u8) -> Option<Self> {
        match code {
            1 => Some(ScalarKind::F32),
            2 => Some(ScalarKind::Q16_16),
            3 => Some(ScalarKind::F64),
            _ => None,
        }
    }

    /// Bytes per stored parameter.
    pub const fn stored_bytes(self) -> usize {
        match self {
            ScalarKind::F32 | ScalarKind::Q16_16 => 4,
            ScalarKind::F64 => 8,
        }
    }

    /// A short lowercase name (`"f32"`, `"q16.16"`), as used on the command line.
    pub const fn name(self) -> &'static str {
        match self {
            ScalarKind::F32 => "f32",
            ScalarKind::Q16_16 => "q16.16",
            ScalarKind::F64 => "f64",
        }
    }

    /// Encodes one parameter for storage in this kind (round to nearest).
    ///
    /// Returns `None` when `value` is not finite or not representable (Q16.16 covers
    /// [−32768, 32768)), and for [`ScalarKind::F64`], whose 8-byte words host code writes
    /// itself.
    ///
    /// ```
    /// use neurosurf_core::scalar::ScalarKind;
    /// assert_eq!(ScalarKind::Q16_16.encode(1.5), Some(0x0001_8000_i32.to_le_bytes()));
    /// assert_eq!(ScalarKind::F32.encode(f64::NAN), None);
    /// ```
    pub fn encode(self, value: f64) -> Option<[u8; 4]> {
        if !value.is_finite() {
            return None;
        }
        match self {
            ScalarKind::F32 => {
                let narrowed = value as f32;
                narrowed.is_finite().then(|| narrowed.to_le_bytes())
            }
            ScalarKind::Q16_16 => Q16::checked_from_num(value).map(|q| q.to_bits().to_le_bytes()),
            ScalarKind::F64 => None,
        }
    }
}

/// A number type the models are evaluated in: `f32` or [`Q16`].
///
/// Sealed: the models rely on the documented accuracy and saturation behaviour of each
/// implementation. Every operation is total — none panics, none wraps; fixed-point
/// operations saturate at the ends of the range.
pub trait Scalar:
    Copy
    + Default
    + PartialEq
    + PartialOrd
    + Debug
    + sealed::Sealed
    + crate::implicit::Activation
    + crate::arch::Kernels
    + 'static
{
    /// Wide accumulator for dot products (`f32` for `f32`, Q32.32 in an `i64` for [`Q16`]).
    type Acc: Copy + Debug;

    /// The kind tag of this scalar.
    const KIND: ScalarKind;
    /// 0.
    const ZERO: Self;
    /// 1.
    const ONE: Self;
    /// Largest parameter magnitude a blob may hold for evaluation in this scalar; the loader
    /// rejects larger ones so that accumulators provably cannot overflow.
    const MAX_PARAMETER: f32;

    /// Converts a parameter, `None` if it is not finite or its magnitude exceeds
    /// [`Scalar::MAX_PARAMETER`].
    fn from_f32(value: f32) -> Option<Self>;
    /// Converts an input coordinate: NaN becomes 0, out-of-range values saturate.
    fn from_f32_saturating(value: f32) -> Self;
    /// Decodes one stored parameter of kind `stored`; `None` when it is not finite or beyond
    /// [`Scalar::MAX_PARAMETER`].
    fn from_stored(bytes: [u8; 4], stored: ScalarKind) -> Option<Self>;
    /// The raw little-endian bits in this scalar's own [`ScalarKind`] (`f32` bits, Q16.16
    /// bits): the exact value, for transport and bit-for-bit comparison.
    fn to_le_bytes(self) -> [u8; 4];
    /// The nearest `f32`.
    fn to_f32(self) -> f32;
    /// The exact value as `f64`.
    fn to_f64(self) -> f64;

    /// Saturating addition.
    fn add(self, other: Self) -> Self;
    /// Saturating subtraction.
    fn sub(self, other: Self) -> Self;
    /// Saturating multiplication (rounded to nearest in fixed point).
    fn mul(self, other: Self) -> Self;
    /// Saturating negation.
    fn neg(self) -> Self;
    /// Absolute value (saturating).
    fn abs(self) -> Self;

    /// Starts an accumulation at `self` (typically a bias).
    fn to_acc(self) -> Self::Acc;
    /// `acc + a·b` in the wide accumulator. Within the parameter bound the loader enforces,
    /// at most 64 terms of inputs bounded by the saturated range cannot overflow it.
    fn mac(acc: Self::Acc, a: Self, b: Self) -> Self::Acc;
    /// Rounds an accumulator back to the scalar, saturating.
    fn from_acc(acc: Self::Acc) -> Self;

    /// [`Activation::activation`](crate::implicit::Activation::activation)`(from_acc(acc))`,
    /// bit for bit: a neuron's epilogue, which an implementation may fuse.
    #[inline(always)]
    fn activation_from_acc(acc: Self::Acc) -> Self {
        Self::activation(Self::from_acc(acc))
    }

    /// `self · 2^exponent`, exact unless it leaves the scalar's range (`f32`: IEEE rounding at
    /// the ends; Q16.16: rounded to nearest, ties up, and saturated). `exponent` within
    /// ±[`MAX_FRAME_SHIFT`](crate::frame::MAX_FRAME_SHIFT).
    ///
    /// ```
    /// use neurosurf_core::scalar::{Q16, Scalar};
    /// assert_eq!(<f32 as Scalar>::times_power_of_two(3.0, -2), 0.75);
    /// assert_eq!(Q16::from_num(3).times_power_of_two(-2), Q16::from_num(0.75));
    /// assert_eq!(Q16::from_num(3).times_power_of_two(20), Q16::MAX);
    /// ```
    fn times_power_of_two(self, exponent: i8) -> Self;

    /// Square root; 0 for negative inputs.
    fn sqrt(self) -> Self;
    /// 1/x; `None` when x is 0 or the result is not representable.
    fn recip(self) -> Option<Self>;

    /// e^x, total and deterministic (integer or IEEE basic operations only, the same bits on
    /// every target).
    ///
    /// - `f32`: relative error below 2.5·10⁻⁷ on [−86, 88]; 0 below −86, +∞ above 88, NaN
    ///   for NaN.
    /// - Q16.16: within 0.5 LSB + 2.5·10⁻⁷·e^x; 0 below −11.8, saturated to the largest
    ///   value from 10.3972 on. Never overflows.
    ///
    /// ```
    /// use neurosurf_core::scalar::{Q16, Scalar};
    /// assert!((<f32 as Scalar>::exp(-1.0) - 0.367_879_44).abs() < 1e-7);
    /// let q = Q16::exp(Q16::from_num(-16));
    /// assert_eq!(q, Q16::ZERO); // e⁻¹⁶ ≈ 1.1·10⁻⁷ is below half an LSB
    /// assert_eq!(Q16::exp(Q16::from_num(11)), Q16::MAX);
    /// ```
    fn exp(self) -> Self;

    /// `numerator / denominator` of two accumulators (as [`Scalar::from_acc`] would round
    /// them), rounded to nearest and saturated; 0 when the denominator is 0.
    ///
    /// For Q16.16 the denominator must be a sum of Q16.16 values (a multiple of 2⁻¹⁶, as every
    /// accumulation of `mac(acc, x, ONE)` is); then the quotient is rounded once, exactly.
    fn quotient(numerator: Self::Acc, denominator: Self::Acc) -> Self;
}

/// Dot product of two equally long slices, starting from `init` (extra elements of the longer
/// slice are ignored).
#[inline]
pub fn dot<S: Scalar>(init: S, a: &[S], b: &[S]) -> S {
    let mut acc = init.to_acc();
    for (&x, &y) in a.iter().zip(b) {
        acc = S::mac(acc, x, y);
    }
    S::from_acc(acc)
}

/// Scales a 3-vector to unit length; `None` when its length is 0 (or underflows).
///
/// ```
/// use neurosurf_core::scalar::{normalize3, Q16, Scalar};
/// let n = normalize3([3.0_f32, 0.0, 4.0]).unwrap();
/// assert!((n[0] - 0.6).abs() < 1e-6 && (n[2] - 0.8).abs() < 1e-6);
/// let q = normalize3([Q16::from_num(3), Q16::ZERO, Q16::from_num(4)]).unwrap();
/// assert!((q[2].to_f32() - 0.8).abs() < 1e-4);
/// ```
pub fn normalize3<S: Scalar>(v: [S; 3]) -> Option<[S; 3]> {
    let [x, y, z] = v;
    // Scale down by the largest component first so squares stay in range for fixed point
    // and do not underflow for f32.
    let largest = x.abs().max_scalar(y.abs()).max_scalar(z.abs());
    let inv_largest = largest.recip()?;
    let (x, y, z) = (x.mul(inv_largest), y.mul(inv_largest), z.mul(inv_largest));
    let mut acc = S::ZERO.to_acc();
    acc = S::mac(acc, x, x);
    acc = S::mac(acc, y, y);
    acc = S::mac(acc, z, z);
    let inv_len = S::from_acc(acc).sqrt().recip()?;
    Some([x.mul(inv_len), y.mul(inv_len), z.mul(inv_len)])
}

/// Ordering helpers available on every scalar.
trait MaxScalar: Scalar {
    fn max_scalar(self, other: Self) -> Self {
        if other > self { other } else { self }
    }
}
impl<S: Scalar> MaxScalar for S {}
