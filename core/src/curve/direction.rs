//! One parametric direction of a spline: where a global parameter falls (segment and local
//! parameter) and the uniform B-spline basis of its degree there.

use crate::error::{BlobError, Quantity};
use crate::scalar::{Scalar, ScalarKind};

/// Fewest control points along a cubic direction (open or closed): one segment's worth. A
/// direction of degree p needs p + 1.
pub const MIN_CONTROL_POINTS: usize = 4;

/// The lowest degree the core evaluates (quadratic).
pub const MIN_DEGREE: usize = 2;
/// The highest degree the core evaluates (quintic).
pub const MAX_DEGREE: usize = 5;
/// Basis functions of one segment at the highest degree: `MAX_DEGREE + 1`.
pub(crate) const MAX_ORDER: usize = MAX_DEGREE + 1;

/// Most segments along a direction: 32 767 = 2¹⁵ − 1.
///
/// The bound makes s = t·segments representable in Q16.16 for every t ∈ [0, 1]
/// (s ≤ 32 767 < 32 768; in bits t·2¹⁶·segments ≤ 2¹⁶·(2¹⁵ − 1) < 2³¹) and keeps the scaled
/// derivative weights segments·Bₖ′(u) (|·| ≤ 2/3·segments ≤ 21 845) unsaturated. Both scalars
/// apply it, so `f32` and Q16.16 accept the same shapes.
pub const MAX_SEGMENTS: usize = 32_767;

/// A validated direction with its constants in the evaluation scalar.
#[derive(Copy, Clone, Debug, PartialEq)]
pub(crate) struct Direction<S> {
    /// Control points along the direction.
    pub(crate) count: usize,
    /// Whether indices wrap around.
    pub(crate) closed: bool,
    /// Polynomial segments: `count` when closed, `count − degree` when open.
    pub(crate) segments: usize,
    /// The polynomial degree p ([`MIN_DEGREE`] ..= [`MAX_DEGREE`]; 0 when empty).
    pub(crate) degree: usize,
    /// 1/d rounded to `S`, for d = 1 ..= [`MAX_DEGREE`] (index d − 1): the recurrence's
    /// divisors (1/2 and 1/4 exact).
    inverses: [S; MAX_DEGREE],
    /// 0, 1, …, [`MAX_ORDER`] in `S` (exact): the recurrence's knot offsets.
    integers: [S; MAX_ORDER + 1],
    /// `segments` in `S` (exact).
    scale: S,
    /// `segments / 2` in `S` (exact): the factor of the scaled derivative weights.
    half_scale: S,
    /// 1/6 rounded to `S`.
    sixth: S,
    /// 1/2.
    half: S,
    /// 1 − 3·`sixth` (1/2 in f32, 1/2 − 2⁻¹⁶ in Q16.16): the linear coefficient of B₂.
    linear: S,
}

impl<S: Scalar> Direction<S> {
    /// No control points: every index is out of bounds, every weight 0.
    pub(crate) const EMPTY: Self = Direction {
        count: 0,
        closed: false,
        segments: 0,
        degree: 0,
        inverses: [S::ZERO; MAX_DEGREE],
        integers: [S::ZERO; MAX_ORDER + 1],
        scale: S::ZERO,
        half_scale: S::ZERO,
        sixth: S::ZERO,
        half: S::ZERO,
        linear: S::ZERO,
    };

    /// Checks `count` control points along a direction of degree `degree`.
    ///
    /// # Errors
    /// [`BlobError::ShapeMismatch`] (`Degree`, expected the nearest valid degree) for a
    /// degree outside [`MIN_DEGREE`] ..= [`MAX_DEGREE`], (`ControlPoints`, expected
    /// degree + 1) for fewer than degree + 1 points; [`BlobError::CapacityExceeded`]
    /// (`Segments`) beyond [`MAX_SEGMENTS`].
    pub(crate) fn new(count: usize, closed: bool, degree: usize) -> Result<Self, BlobError> {
        if !(MIN_DEGREE..=MAX_DEGREE).contains(&degree) {
            return Err(BlobError::ShapeMismatch {
                what: Quantity::Degree,
                expected: degree.clamp(MIN_DEGREE, MAX_DEGREE),
                found: degree,
            });
        }
        if count <= degree {
            return Err(BlobError::ShapeMismatch {
                what: Quantity::ControlPoints,
                expected: degree + 1,
                found: count,
            });
        }
        let segments = if closed { count } else { count - degree };
        if segments > MAX_SEGMENTS {
            return Err(BlobError::CapacityExceeded {
                what: Quantity::Segments,
                needed: segments,
                capacity: MAX_SEGMENTS,
            });
        }
        // All exact in f32 and Q16.16 (integers and halves below 2¹⁵), except 1/6, which
        // rounds to nearest (Q16.16: 10923·2⁻¹⁶).
        let g = segments as f32;
        let sixth = S::from_f32_saturating(1.0 / 6.0);
        Ok(Direction {
            count,
            closed,
            segments,
            degree,
            inverses: core::array::from_fn(|i| S::from_f32_saturating(1.0 / (i + 1) as f32)),
            integers: core::array::from_fn(|i| S::from_f32_saturating(i as f32)),
            scale: S::from_f32_saturating(g),
            half_scale: S::from_f32_saturating(g * 0.5),
            sixth,
            half: S::from_f32_saturating(0.5),
            linear: S::ONE.sub(sixth.add(sixth).add(sixth)),
        })
    }

    /// The segment i and local parameter u ∈ [0, 1] of a global parameter t (clamped to
    /// [0, 1]; NaN counts as 0).
    #[inline]
    pub(crate) fn locate(&self, t: S) -> (usize, S) {
        let t = if t > S::ONE {
            S::ONE
        } else if t >= S::ZERO {
            t
        } else {
            S::ZERO
        };
        // Exact in Q16.16 (an integer factor, no saturation by MAX_SEGMENTS); one rounding
        // in f32.
        let s = t.mul(self.scale);
        split(s, self.segments.saturating_sub(1))
    }

    /// Index of the `k`-th control point of the segment starting at `first` (k ≤ degree).
    ///
    /// Open directions never pass `count − 1` (first ≤ count − degree − 1); closed ones wrap
    /// at most once (first ≤ count − 1, count > degree), so one subtraction replaces the
    /// modulo.
    #[inline]
    pub(crate) fn index(&self, first: usize, k: usize) -> usize {
        let i = first + k;
        if i >= self.count { i - self.count } else { i }
    }

    /// B₀(u) … B₃(u).
    ///
    /// B₁ = 1 − B₀ − B₂ − B₃ exactly, so the four sum to exactly 1 (and a constant control
    /// polygon is reproduced exactly). B₂ = 1/6 + (1 − 3·1/6)·u + u²(1 − u)/2 with the rounded
    /// 1/6, so that the weights at u = 1 are the exact mirror image of those at u = 0
    /// ((1/6, 1 − 2/6, 1/6, 0) reversed): with phantom end points an open curve then
    /// interpolates both of its ends exactly in Q16.16.
    ///
    /// Q16.16: B₀, B₂, B₃ within 2.5 LSB of the exact basis at u (1/6 is 0.33 LSB off, the
    /// linear coefficient 1 LSB, then one rounding per product), B₁ within 6 LSB.
    #[inline]
    pub(crate) fn values(&self, u: S) -> [S; 4] {
        let v = S::ONE.sub(u);
        let b0 = self.sixth.mul(v).mul(v).mul(v);
        let b3 = self.sixth.mul(u).mul(u).mul(u);
        let u2v = u.mul(u).mul(v);
        let b2 = S::from_acc(S::mac(
            S::mac(self.sixth.to_acc(), self.linear, u),
            self.half,
            u2v,
        ));
        let b1 = S::ONE.sub(b0).sub(b2).sub(b3);
        [b0, b1, b2, b3]
    }

    /// segments·B₀′(u) … segments·B₃′(u): the weights of dC/dt.
    #[inline]
    pub(crate) fn slopes(&self, u: S) -> [S; 4] {
        scaled_slopes(u, self.half_scale)
    }

    /// B₀′(u) … B₃′(u): the weights of dC/du (for normals, which only need a direction and so
    /// avoid the large segment factor).
    #[inline]
    pub(crate) fn unit_slopes(&self, u: S) -> [S; 4] {
        scaled_slopes(u, self.half)
    }

    /// The `degree + 1` basis functions N₀(u) … N_p(u) of a segment (the rest 0) and, with
    /// `slope` = Some(h), h·N₀′(u) … h·N_p′(u), for a direction of any degree (the cubic
    /// one has its own [`Direction::values`] and [`Direction::slopes`], whose bits the
    /// cubic blobs keep).
    ///
    /// The values come from the triangle of the Cox–de Boor recurrence on integer knots
    /// ([`Direction::triangle`]); the derivative weights are differences of the degree p − 1
    /// basis, N_k′ = N_{k−1}^{p−1} − N_k^{p−1}, whose triangle starts from h instead of 1 so
    /// that its roundings are not multiplied by h. The evaluation uses the weights as
    /// differences from an anchor point (see [`crate::curve`]), so a constant control
    /// polygon is reproduced exactly whatever their rounding.
    #[inline]
    pub(crate) fn any_degree(&self, u: S, slope: Option<S>) -> ([S; MAX_ORDER], [S; MAX_ORDER]) {
        let values = self.triangle(u, self.degree, S::ONE);
        let mut slopes = [S::ZERO; MAX_ORDER];
        if let Some(h) = slope {
            let lower = self.triangle(u, self.degree.saturating_sub(1), h);
            let mut previous = S::ZERO;
            for (slope, &b) in slopes.iter_mut().zip(&lower).take(self.degree + 1) {
                *slope = previous.sub(b);
                previous = b;
            }
        }
        (values, slopes)
    }

    /// `start`·N_k^`top`(u) for k = 0 … `top` (the rest 0), by
    /// N_k^d = ((u + d − k)/d)·N_{k−1}^{d−1} plus ((k + 1 − u)/d)·N_k^{d−1}: each factor
    /// rounded once (both at most 1, so no partial result exceeds `start` and Q16.16 never
    /// saturates for |start| ≤ [`MAX_SEGMENTS`]), each sum accumulated with one rounding.
    #[inline]
    fn triangle(&self, u: S, top: usize, start: S) -> [S; MAX_ORDER] {
        let mut basis = [S::ZERO; MAX_ORDER];
        if let Some(first) = basis.first_mut() {
            *first = start;
        }
        let integer = |n: usize| self.integers.get(n).copied().unwrap_or(S::ZERO);
        for d in 1..=top.min(MAX_DEGREE) {
            let inverse = self.inverses.get(d - 1).copied().unwrap_or(S::ZERO);
            // In place from the top: N_k^d reads N_{k−1}^{d−1} and N_k^{d−1}, not yet
            // overwritten.
            for k in (0..=d).rev() {
                let left = match k.checked_sub(1) {
                    Some(j) => basis.get(j).copied().unwrap_or(S::ZERO),
                    None => S::ZERO,
                };
                let right = basis.get(k).copied().unwrap_or(S::ZERO);
                let rising = u.add(integer(d - k)).mul(inverse);
                let falling = integer(k + 1).sub(u).mul(inverse);
                let acc = S::mac(S::mac(S::ZERO.to_acc(), rising, left), falling, right);
                if let Some(b) = basis.get_mut(k) {
                    *b = S::from_acc(acc);
                }
            }
        }
        basis
    }

    /// `segments` in `S` (exact): the factor of dC/dt over dC/du.
    #[inline]
    pub(crate) fn scale(&self) -> S {
        self.scale
    }

    /// Multiplications of [`Direction::locate`] and [`Direction::values`].
    pub(crate) const VALUE_MULS: usize = 11;
    /// Multiplications of [`Direction::slopes`].
    pub(crate) const SLOPE_MULS: usize = 5;
}

/// 2h·Bₖ′(u): −h(1 − u)², h(3u² − 4u), h(1 + 3u)(1 − u), hu², with products ordered so that
/// every rounding error is scaled by at most 4 (multiplying by u ≤ 1 does not amplify).
#[inline]
fn scaled_slopes<S: Scalar>(u: S, h: S) -> [S; 4] {
    let v = S::ONE.sub(u);
    let hv = h.mul(v);
    let w0 = hv.mul(v).neg();
    let w3 = h.mul(u).mul(u);
    let w2 = hv.mul(S::ONE.add(u).add(u).add(u));
    let w1 = w0.add(w2).add(w3).neg();
    [w0, w1, w2, w3]
}

/// ⌊s⌋ clamped to `last`, and s minus it, for s ≥ 0 (a clamped t times the segment count).
///
/// Q16.16 from the bits (exact); `f32` by a truncating conversion (IEEE convertToInteger,
/// exact for s < 2²⁴) and an exact subtraction.
#[inline]
fn split<S: Scalar>(s: S, last: usize) -> (usize, S) {
    if S::KIND == ScalarKind::Q16_16 {
        let bits = i32::from_le_bytes(s.to_le_bytes()).max(0).unsigned_abs();
        let first = ((bits >> 16) as usize).min(last);
        // first ≤ bits >> 16 < 2¹⁵: no underflow, no overflow.
        let fraction = bits - ((first as u32) << 16);
        let u = S::from_stored(fraction.to_le_bytes(), ScalarKind::Q16_16).unwrap_or(S::ZERO);
        (first, u)
    } else {
        // `as` saturates (and maps NaN to 0): never panics.
        let first = (f32::from_le_bytes(s.to_le_bytes()) as usize).min(last);
        (first, s.sub(S::from_f32_saturating(first as f32)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scalar::Q16;

    #[test]
    fn constants_are_rounded_to_nearest() {
        let d = Direction::<Q16>::new(7, false, 3).unwrap();
        assert_eq!(d.sixth.to_bits(), 10923);
        assert_eq!(d.half.to_bits(), 1 << 15);
        assert_eq!(d.linear.to_bits(), (1 << 15) - 1);
        assert_eq!(d.scale, Q16::from_num(4));
        assert_eq!(d.half_scale, Q16::from_num(2));
        let d = Direction::<f32>::new(7, true, 3).unwrap();
        assert_eq!((d.sixth, d.linear), (1.0 / 6.0, 0.5));
        assert_eq!((d.scale, d.half_scale), (7.0, 3.5));
    }

    #[test]
    fn q16_split_is_exact() {
        let d = Direction::<Q16>::new(MAX_SEGMENTS, true, 3).unwrap();
        for bits in [
            0,
            1,
            2,
            12345,
            65535,
            65536,
            3 << 15,
            -1,
            i32::MIN,
            i32::MAX,
        ] {
            let t = Q16::from_bits(bits);
            let (i, u) = d.locate(t);
            let s = i64::from(bits.clamp(0, 1 << 16)) * MAX_SEGMENTS as i64;
            let i_exact = ((s >> 16) as usize).min(MAX_SEGMENTS - 1);
            assert_eq!(i, i_exact);
            assert_eq!(i64::from(u.to_bits()), s - ((i_exact as i64) << 16));
        }
    }

    #[test]
    fn end_weights_mirror_each_other() {
        let d = Direction::<Q16>::new(5, false, 3).unwrap();
        let [a0, a1, a2, a3] = d.values(Q16::ZERO);
        let [b0, b1, b2, b3] = d.values(Q16::ONE);
        assert_eq!([a0, a1, a2, a3], [b3, b2, b1, b0]);
        assert_eq!((a0, a3), (d.sixth, Q16::ZERO));
        let [a0, a1, a2, a3] = d.slopes(Q16::ZERO);
        let [b0, b1, b2, b3] = d.slopes(Q16::ONE);
        assert_eq!([a0, a1, a2, a3], [-b3, -b2, -b1, -b0]);
    }

    #[test]
    fn weights_sum_exactly_in_q16() {
        let d = Direction::<Q16>::new(5, false, 3).unwrap();
        for bits in (0..=65536).step_by(97) {
            let u = Q16::from_bits(bits);
            let b = d.values(u);
            assert_eq!(b.iter().map(|x| x.to_bits()).sum::<i32>(), 1 << 16);
            let w = d.slopes(u);
            assert_eq!(w.iter().map(|x| x.to_bits()).sum::<i32>(), 0);
        }
    }
}
