//! The validated B-spline curve: loading and evaluation of position and tangent.

use heapless::Vec;

use super::control::{self, POINT_BYTES};
use super::direction::{Direction, MAX_ORDER};
use super::payload::CurvePayload;
use crate::blob::ModelKind;
use crate::error::{BlobError, Quantity};
use crate::scalar::{Scalar, ScalarKind};

/// Default control-point capacity of [`BSplineCurve`]: 512 points (6 KiB in `f32`), several
/// times the paper's 80-neuron chain.
pub const DEFAULT_CURVE_POINTS: usize = 512;

/// Position and tangent of a curve at one parameter.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct CurvePoint<S> {
    /// C(t).
    pub position: [S; 3],
    /// dC/dt (including the factor `segments`; saturated in Q16.16).
    pub tangent: [S; 3],
}

/// A uniform B-spline curve of degree 2 to 5, loaded from a blob and validated (see [`crate::curve`] for
/// the contract and the payload).
///
/// `C` is the control-point capacity reserved inline (no heap). Evaluation after a successful
/// load cannot fail: every parameter, including ±∞ and NaN, gives a point.
///
/// # Accuracy
///
/// Against an `f64` evaluation at the same parameter, with Δ the largest coordinate difference
/// between the segment's four control points and its second one, M their largest coordinate
/// magnitude, g the number of segments, ε = 2⁻²⁴ and LSB = 2⁻¹⁶ (bounds asserted by
/// `core/tests/curve.rs` on random open and closed curves of 1 to 43 segments with
/// coordinates up to ±500; the largest measured error over 5 × 1000 curves in parentheses):
///
/// - `f32`: position within 2.5·ε·(M + Δ) (1.6) when s = t·g is exact (any t on the Q16.16
///   grid for g < 256); otherwise the rounding of s adds up to 2·ε·g·Δ. Tangent within
///   3·ε·g·Δ (2.4).
/// - Q16.16 (s = t·g exact): position within 3 LSB·Δ + ½ LSB (2.1), tangent within
///   4.5 LSB·Δ + ½ LSB (3.4), whatever g; tangents saturate at ±32 768. For a curve in
///   [−1, 1]² that is at most 1.0·10⁻⁴ in position.
///
/// A constant control polygon gives its constant and a zero tangent exactly, in both scalars;
/// an open curve with phantom end points P₋₁ = 2P₀ − P₁, P₍ₙ₎ = 2P₍ₙ₋₁₎ − P₍ₙ₋₂₎ starts and
/// ends exactly at P₀ and P₍ₙ₋₁₎ in Q16.16 (within an ulp or two in `f32`).
///
/// ```
/// # use neurosurf_core::curve::{BSplineCurve, CurvePayload};
/// # use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};
/// # fn main() -> Result<(), neurosurf_core::BlobError> {
/// # let blob = example_blob();
/// let curve = BSplineCurve::<f32>::from_blob(&blob)?;
/// let fixed = BSplineCurve::<Q16>::from_blob(&blob)?; // same blob, other scalar
/// let p = curve.eval(0.3);
/// let q = fixed.eval(Q16::from_num(0.3));
/// assert!((p.position[0] - q.position[0].to_f32()).abs() < 1e-3);
/// assert_eq!(curve.segments(), 3);
/// # Ok(())
/// # }
/// # fn example_blob() -> Vec<u8> {
/// #     let points = [[0.0, 0.0, 0.0], [1.0, 2.0, 0.5], [2.0, 2.0, 0.0], [3.0, 0.0, 1.0], [4.0, 1.0, 0.0], [5.0, 0.0, 0.0]];
/// #     let control: Vec<u8> = points.iter().flatten().flat_map(|&c| ScalarKind::F32.encode(c).unwrap()).collect();
/// #     let payload = CurvePayload {
/// #         dimension: 3, closed: false, degree: 3, frame: neurosurf_core::frame::IDENTITY_PAYLOAD,
/// #         control: &control, metadata: &[] };
/// #     let mut out = vec![0_u8; 256];
/// #     let n = payload.write(ScalarKind::F32, &mut out).unwrap();
/// #     out.truncate(n);
/// #     out
/// # }
/// ```
#[derive(Clone, Debug)]
pub struct BSplineCurve<S: Scalar, const C: usize = DEFAULT_CURVE_POINTS> {
    pub(crate) dimension: u8,
    pub(crate) direction: Direction<S>,
    pub(crate) control: Vec<[S; 3], C>,
    pub(crate) stored_as: ScalarKind,
}

impl<S: Scalar, const C: usize> BSplineCurve<S, C> {
    /// An empty curve (no control points: every evaluation gives 0), to be filled by
    /// [`BSplineCurve::load`]. `const`, so firmware can keep a curve in a `static`.
    pub const fn new() -> Self {
        BSplineCurve {
            dimension: 0,
            direction: Direction::EMPTY,
            control: Vec::new(),
            stored_as: S::KIND,
        }
    }

    crate::blob::loader_methods!(
        CurvePayload,
        "curve",
        "Framing errors ([`crate::blob::parse`]); [`BlobError::WrongModelKind`] for \
         another kind of blob; [`BlobError::MalformedPayload`]; \
         [`BlobError::UnsupportedStorage`] for `f64` storage; \
         [`BlobError::ShapeMismatch`] for a dimension other than 2 or 3 (`Dimension`), a \
         control byte string that is not whole points (`Parameters`, in words), a degree \
         outside 2 to 5 (`Degree`), no more points than the degree (`ControlPoints`), or a \
         nonzero z in a 2-D curve (`Dimension`, \
         expected 2, found 3); [`BlobError::CapacityExceeded`] beyond \
         [`MAX_SEGMENTS`](super::MAX_SEGMENTS) segments (`Segments`) or `C` points \
         (`ControlPoints`); [`BlobError::NonFiniteParameter`] / \
         [`BlobError::ParameterOutOfRange`] (|x| > 1024 for Q16.16, in the frame's \
         coordinates) naming the first bad coordinate word; the frame's own errors \
         ([`crate::frame::Frame::from_payload`])."
    );

    fn fill(&mut self, payload: &CurvePayload<'_>, stored: ScalarKind) -> Result<(), BlobError> {
        self.clear();
        control::check_storage(ModelKind::Curve, stored)?;
        let dimension = payload.dimension;
        if !(2..=3).contains(&dimension) {
            return Err(BlobError::ShapeMismatch {
                what: Quantity::Dimension,
                expected: if dimension < 2 { 2 } else { 3 },
                found: usize::from(dimension),
            });
        }
        let bytes = payload.control.len();
        let count = bytes / POINT_BYTES;
        if !bytes.is_multiple_of(POINT_BYTES) {
            return Err(control::length_mismatch(count + 1, bytes));
        }
        let direction = Direction::new(count, payload.closed, usize::from(payload.degree))?;
        if count > C {
            return Err(control::over_capacity(count, C));
        }
        control::decode(&mut self.control, payload.control, stored, dimension == 2)?;
        control::fold_frame(&mut self.control, &payload.frame, stored, dimension == 2)?;
        self.dimension = dimension;
        self.direction = direction;
        self.stored_as = stored;
        Ok(())
    }

    /// 2 or 3 (0 for an empty curve).
    pub fn dimension(&self) -> usize {
        usize::from(self.dimension)
    }

    /// Whether the control points wrap around.
    pub fn is_closed(&self) -> bool {
        self.direction.closed
    }

    /// Number of control points n.
    pub fn control_count(&self) -> usize {
        self.control.len()
    }

    /// Number of polynomial segments: n when closed, n − degree when open.
    pub fn segments(&self) -> usize {
        self.direction.segments
    }

    /// The polynomial degree p, 2 to 5 (0 for an empty curve).
    pub fn degree(&self) -> usize {
        self.direction.degree
    }

    /// Control point `index`, if it exists.
    pub fn control_point(&self, index: usize) -> Option<[S; 3]> {
        self.control.get(index).copied()
    }

    /// The scalar kind the blob stored its control points in.
    pub fn stored_as(&self) -> ScalarKind {
        self.stored_as
    }

    /// Multiplications (scalar products and accumulator multiply–adds) of one evaluation:
    /// for a cubic curve 20 for [`BSplineCurve::position`], 34 for [`BSplineCurve::eval`]
    /// (position and tangent); for degree p otherwise 1 + 2p(p + 1) + 7p, plus
    /// 2p(p − 1) + 4(p − 1) + 3p for the tangent (quadratic: 27 and 41; quintic: 96 and 167).
    /// Independent of the number of control points.
    pub fn mac_count(&self, tangent: bool) -> usize {
        let p = self.direction.degree;
        if p == 3 || p == 0 {
            let position = Direction::<S>::VALUE_MULS + 9;
            return if tangent {
                position + Direction::<S>::SLOPE_MULS + 9
            } else {
                position
            };
        }
        let position = 1 + 2 * p * (p + 1) + 7 * p;
        if tangent {
            position + 2 * p * (p - 1) + 4 * (p - 1) + 3 * p
        } else {
            position
        }
    }

    /// C(t). t is clamped to [0, 1]; NaN counts as 0.
    pub fn position(&self, t: S) -> [S; 3] {
        if !self.is_cubic() {
            return self.any_degree_position(t);
        }
        let [point] = self.cubic_lanes::<1, false>(&[t]);
        point.position
    }

    /// dC/dt at t (including the factor `segments`).
    pub fn tangent(&self, t: S) -> [S; 3] {
        self.eval(t).tangent
    }

    /// C(t) and dC/dt.
    pub fn eval(&self, t: S) -> CurvePoint<S> {
        if !self.is_cubic() {
            return self.any_degree_point(t);
        }
        let [point] = self.cubic_lanes::<1, true>(&[t]);
        point
    }

    /// C(t) of a curve of degree p ≠ 3, out of line: the single-point calls then hold the
    /// cubic path alone.
    #[inline(never)]
    fn any_degree_position(&self, t: S) -> [S; 3] {
        let [point] = self.any_degree_lanes::<1, false>(&[t]);
        point.position
    }

    /// C(t) and dC/dt of a curve of degree p ≠ 3, out of line (see
    /// [`Self::any_degree_position`]).
    #[inline(never)]
    fn any_degree_point(&self, t: S) -> CurvePoint<S> {
        let [point] = self.any_degree_lanes::<1, true>(&[t]);
        point
    }

    /// Whether the curve is cubic: each entry point picks [`Self::cubic_lanes`] or
    /// [`Self::any_degree_lanes`] once, outside its loops, so that the cubic path compiles
    /// as it did before other degrees existed.
    #[inline(always)]
    pub(crate) fn is_cubic(&self) -> bool {
        self.direction.degree == 3
    }

    /// `L` parameters at once of a cubic curve: first every lane's segment and basis
    /// (structure of arrays), then every lane's four control points, four weights around the
    /// anchor P₁. The single-point calls are `L = 1`, so batches give the same bits.
    #[inline(always)]
    pub(crate) fn cubic_lanes<const L: usize, const TANGENT: bool>(
        &self,
        t: &[S; L],
    ) -> [CurvePoint<S>; L] {
        let direction = &self.direction;
        let mut first = [0_usize; L];
        let mut weights = [[S::ZERO; 4]; L];
        let mut slopes = [[S::ZERO; 4]; L];
        for (((&t, first), weights), slopes) in
            t.iter().zip(&mut first).zip(&mut weights).zip(&mut slopes)
        {
            let (i, u) = direction.locate(t);
            *first = i;
            *weights = direction.values(u);
            if TANGENT {
                *slopes = direction.slopes(u);
            }
        }
        let mut out = [CurvePoint::default(); L];
        for (((out, &first), weights), slopes) in
            out.iter_mut().zip(&first).zip(&weights).zip(&slopes)
        {
            let point = |k| self.point(first, k);
            let anchor = point(1);
            let differences = [0, 2, 3].map(|k| {
                let p = point(k);
                [0, 1, 2].map(|axis| at(&p, axis).sub(at(&anchor, axis)))
            });
            let [w0, _, w2, w3] = *weights;
            out.position = combine(anchor, [w0, w2, w3], &differences);
            if TANGENT {
                let [s0, _, s2, s3] = *slopes;
                out.tangent = combine([S::ZERO; 3], [s0, s2, s3], &differences);
            }
        }
        out
    }

    /// [`Self::cubic_lanes`] for a curve of degree p ≠ 3: the recurrence's p + 1 weights
    /// ([`Direction::any_degree`]) around the anchor P₍ₚ/₂₎, each coordinate one accumulation
    /// over k = 0 … p (the anchor skipped) with one rounding.
    #[inline]
    pub(crate) fn any_degree_lanes<const L: usize, const TANGENT: bool>(
        &self,
        t: &[S; L],
    ) -> [CurvePoint<S>; L] {
        let direction = &self.direction;
        let order = direction.degree + 1;
        let anchor = direction.degree / 2;
        let mut first = [0_usize; L];
        let mut weights = [([S::ZERO; MAX_ORDER], [S::ZERO; MAX_ORDER]); L];
        for ((&t, first), weights) in t.iter().zip(&mut first).zip(&mut weights) {
            let (i, u) = direction.locate(t);
            *first = i;
            *weights = direction.any_degree(u, TANGENT.then(|| direction.scale()));
        }
        let mut out = [CurvePoint::default(); L];
        for ((out, &first), (values, slopes)) in out.iter_mut().zip(&first).zip(&weights) {
            let start = self.point(first, anchor);
            let mut position = start.map(S::to_acc);
            let mut tangent = [S::ZERO.to_acc(); 3];
            for k in (0..order).filter(|&k| k != anchor) {
                let p = self.point(first, k);
                let value = values.get(k).copied().unwrap_or(S::ZERO);
                let slope = slopes.get(k).copied().unwrap_or(S::ZERO);
                for axis in 0..3 {
                    let difference = at(&p, axis).sub(at(&start, axis));
                    if let Some(acc) = position.get_mut(axis) {
                        *acc = S::mac(*acc, value, difference);
                    }
                    if TANGENT && let Some(acc) = tangent.get_mut(axis) {
                        *acc = S::mac(*acc, slope, difference);
                    }
                }
            }
            out.position = position.map(S::from_acc);
            if TANGENT {
                out.tangent = tangent.map(S::from_acc);
            }
        }
        out
    }

    /// Control point `k` of the segment starting at `first` (0 when out of range, which a
    /// validated curve never is).
    #[inline(always)]
    fn point(&self, first: usize, k: usize) -> [S; 3] {
        self.control
            .get(self.direction.index(first, k))
            .copied()
            .unwrap_or([S::ZERO; 3])
    }
}

impl<S: Scalar, const C: usize> Default for BSplineCurve<S, C> {
    fn default() -> Self {
        Self::new()
    }
}

/// `start + Σ weights[m]·differences[m]`, per coordinate, with one rounding.
#[inline]
fn combine<S: Scalar>(start: [S; 3], weights: [S; 3], differences: &[[S; 3]; 3]) -> [S; 3] {
    [0, 1, 2].map(|axis| {
        let mut acc = at(&start, axis).to_acc();
        for (&w, d) in weights.iter().zip(differences) {
            acc = S::mac(acc, w, at(d, axis));
        }
        S::from_acc(acc)
    })
}

/// `v[axis]` (always in bounds: axis < 3).
#[inline(always)]
pub(crate) fn at<S: Scalar>(v: &[S; 3], axis: usize) -> S {
    v.get(axis).copied().unwrap_or(S::ZERO)
}

impl<S: Scalar, const C: usize> crate::model::Model<S> for BSplineCurve<S, C> {
    const KIND: ModelKind = ModelKind::Curve;

    fn load_blob(&mut self, blob: &[u8]) -> Result<(), BlobError> {
        self.load(blob)
    }

    fn input_len(&self) -> usize {
        1
    }

    fn output_len(&self, full: bool) -> usize {
        if full { 6 } else { 3 }
    }

    fn evaluate(&self, input: &[S], full: bool, out: &mut [S]) {
        let [t] = crate::model::point(input);
        if full {
            let p = self.eval(t);
            crate::model::write(out, crate::model::pair(p.position, p.tangent));
        } else {
            crate::model::write(out, self.position(t));
        }
    }

    fn evaluate_batch(
        &self,
        inputs: &[[S; crate::model::MAX_INPUTS]],
        full: bool,
        out: &mut [[S; crate::model::MAX_OUTPUTS]],
    ) {
        let t = |input: &[S; crate::model::MAX_INPUTS]| crate::model::point::<S, 1>(input)[0];
        if full {
            crate::model::batch(
                inputs,
                out,
                t,
                |t, points| {
                    // Lengths agree by construction: nothing to report.
                    let _ = self.eval_batch(t, points);
                },
                |p: &CurvePoint<S>, out| {
                    crate::model::write(out, crate::model::pair(p.position, p.tangent));
                },
            );
        } else {
            crate::model::positions(inputs, out, t, |t, positions| {
                self.position_batch(t, positions)
            });
        }
    }

    fn mac_count(&self, full: bool) -> usize {
        BSplineCurve::mac_count(self, full)
    }

    fn describe(&self, f: &mut dyn core::fmt::Write) -> core::fmt::Result {
        write!(
            f,
            "{} control points, {}-D, degree {}, {}, {} segments",
            self.control_count(),
            self.dimension(),
            self.degree(),
            crate::model::open_or_closed(self.is_closed()),
            self.segments()
        )
    }
}
